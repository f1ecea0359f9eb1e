"""The command line, run as a user runs it: subprocesses, exit codes, output files."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from environment import own_lines

MALFORMED = Path(__file__).parent / "data" / "malformed"
MALFORMED_BPT = Path(__file__).parent / "data" / "malformed_bpt"
REPORT_KEYS = {
    "max_edge_angle_deg",
    "mean_edge_angle_deg",
    "max_corner_angle_deg",
    "max_g0_gap",
    "degenerate_normals",
    "folds",
    "patches",
    "shared_edges",
}


# every test here runs the command line in a subprocess (~0.5 s each)
pytestmark = pytest.mark.slow


def g1patch(*args: str | Path, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "g1patch.cli", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )


@pytest.fixture(scope="module")
def cube_obj(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from g1patch import shapes
    from g1patch.io.meshfile import write_quads

    path = tmp_path_factory.mktemp("mesh") / "cube.obj"
    mesh = shapes.cube()
    write_quads(path, mesh.vertices, mesh.faces)
    return path


@pytest.mark.parametrize("command", ["build", "check", "export", "render", "demo"])
def test_every_command_has_help_with_examples(command: str) -> None:
    result = g1patch(command, "--help")
    assert result.returncode == 0
    assert "example" in result.stdout and f"g1patch {command}" in result.stdout


def test_version_and_top_level_help() -> None:
    from g1patch import __version__

    assert g1patch("--version").stdout.strip() == f"g1patch {__version__}"
    result = g1patch("--help")
    assert result.returncode == 0 and all(
        c in result.stdout for c in ("build", "check", "export", "render", "demo")
    )


def test_default_build_is_exactly_g1(tmp_path: Path, cube_obj: Path) -> None:
    network = tmp_path / "cube.npz"
    assert g1patch("build", cube_obj, "-o", network, "--quiet").returncode == 0
    result = g1patch("check", network, "--max-angle", "1e-9", "--json")
    assert result.returncode == 0
    assert json.loads(result.stdout)["max_edge_angle_deg"] <= 1e-9


def test_build_with_check_writes_the_same_file_and_prints_the_check(
    tmp_path: Path, cube_obj: Path
) -> None:
    """``build --check``: the file written while the check runs is the one ``build`` writes, and the
    report printed after the build line is the one ``check`` prints for that file."""
    alone, checked = tmp_path / "alone.npz", tmp_path / "checked.npz"
    assert g1patch("build", cube_obj, "-o", alone, "-q").returncode == 0
    result = g1patch("build", cube_obj, "-o", checked, "-q", "--check")
    assert result.returncode == 0, result.stderr
    assert checked.read_bytes() == alone.read_bytes()
    built, *report = result.stdout.splitlines()
    assert built.startswith("built 24 split4 patches")
    assert (
        report == g1patch("check", checked, "-q").stdout.splitlines()[1:]
    )  # after the file's name


def test_build_says_how_many_patches_fold_where_and_what_to_try(
    tmp_path: Path, cube_obj: Path
) -> None:
    """The build line counts the folded patches (the check's grid test: the same count as
    ``check``); with folds, one warning line names the first one's place and the options that
    avoid them (the noisy coarse torus folds when interpolated, its limit does not)."""
    import numpy as np

    from g1patch import shapes
    from g1patch.io.meshfile import write_quads

    clean = g1patch("build", cube_obj, "-o", tmp_path / "cube.npz", "-q")
    assert clean.stdout.rstrip().endswith("no folds") and not own_lines(clean.stderr)
    torus = shapes.torus(8, 4)
    noisy = torus.vertices + np.random.default_rng(3).normal(0.0, 0.12, torus.vertices.shape)
    write_quads(tmp_path / "noisy.obj", noisy, torus.faces)
    network = tmp_path / "noisy.npz"
    result = g1patch("build", tmp_path / "noisy.obj", "-o", network, "-q")
    assert result.returncode == 0, result.stderr
    folds = json.loads(g1patch("check", network, "--json").stdout)["folds"]
    assert folds > 0 and f", {folds} folded patches" in result.stdout
    (warning,) = own_lines(result.stderr)
    assert warning.startswith(f"g1patch: warning: {network}: {folds} patches fold (the first is ")
    assert "--shape limit" in warning and "--refine 1" in warning
    limit = g1patch("build", tmp_path / "noisy.obj", "-o", network, "-q", "--shape", "limit")
    assert limit.stdout.splitlines()[0].endswith("no folds") and not own_lines(limit.stderr)


def test_build_check_export(tmp_path: Path, cube_obj: Path) -> None:
    network = tmp_path / "cube.npz"
    result = g1patch(
        "build",
        cube_obj,
        "-o",
        network,
        "--method",
        "corner",
        "--tangents",
        "chord",
        "--twist",
        "coons",
    )
    assert result.returncode == 0, result.stderr
    assert network.exists()

    result = g1patch("check", network, "--json")
    assert result.returncode == 0
    report = json.loads(result.stdout)
    assert REPORT_KEYS <= set(report)
    assert report["patches"] == 6 and report["shared_edges"] == 12
    assert report["max_corner_angle_deg"] <= 1e-9

    assert g1patch("check", network).returncode == 0
    failed = g1patch("check", network, "--max-angle", "1e-9")
    assert failed.returncode == 1  # the corner construction creases along edges
    assert g1patch("check", network, "--max-angle", "90").returncode == 0

    for suffix in ("obj", "ply", "stl", "bpt"):
        output = tmp_path / f"surface.{suffix}"
        result = g1patch("export", network, "-o", output, "--resolution", "5")
        assert result.returncode == 0, result.stderr
        assert output.stat().st_size > 0
    assert g1patch("check", tmp_path / "surface.bpt", "--max-angle", "1e-9").returncode == 1


def test_step_export_reports_its_accuracy(tmp_path: Path, cube_obj: Path) -> None:
    pytest.importorskip("OCP", reason="STEP export needs the 'cad' extra (cadquery-ocp-novtk)")
    for method, kind in (
        ("corner", "exact B-spline faces,"),
        ("gregory", "exact B-spline faces of the split4 re-assembly"),
    ):
        network = tmp_path / f"{method}.npz"
        assert g1patch("build", cube_obj, "-o", network, "--method", method).returncode == 0
        result = g1patch("export", network, "-o", tmp_path / f"{method}.step")
        assert result.returncode == 0, result.stderr
        assert kind in result.stdout and "max deviation from the network's surface" in result.stdout
        assert (
            "closed solid" in result.stdout
            and "measured on OpenCASCADE's surfaces" in result.stdout
        )


@pytest.mark.parametrize("mode", [(), ("--zebra",), ("--deviation",)])
def test_render_writes_a_png_of_the_requested_size(
    tmp_path: Path, cube_obj: Path, mode: tuple[str, ...]
) -> None:
    import matplotlib.image

    network = tmp_path / "cube.npz"
    assert g1patch("build", cube_obj, "-o", network).returncode == 0
    picture = tmp_path / "cube.png"
    result = g1patch("render", network, "-o", picture, "--size", "320", "200", *mode)
    assert result.returncode == 0, result.stderr
    assert matplotlib.image.imread(picture).shape[:2] == (200, 320)


def test_check_reads_patch_files(shared_data: Path) -> None:
    result = g1patch("check", shared_data / "teapot.bpt", "--json")
    assert result.returncode == 0
    report = json.loads(result.stdout)
    assert (report["patches"], report["shared_edges"], report["collapsed_patch_edges"]) == (
        32,
        52,
        8,
    )


#: the demo's four cubes
METHODS_SHOWN = ("corner", "gregory", "split4", "limit")


def test_demo_writes_its_files(tmp_path: Path) -> None:
    result = g1patch("demo", "--out", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    assert (
        "max G1 angle at corners" in result.stdout
        and "Gregory" in result.stdout
        and "split4" in result.stdout
    )
    for name in ("cube_corner.obj", "cube_gregory.obj", "cube_split4.obj", "cube_limit.obj"):
        assert (tmp_path / "out" / name).stat().st_size > 0
    # four constructions, four surfaces (the Gregory cube was once built by the default method)
    surfaces = {(tmp_path / "out" / f"cube_{name}.obj").read_bytes() for name in METHODS_SHOWN}
    assert len(surfaces) == len(METHODS_SHOWN)
    for name in ("cube_zebra.png", "cube_deviation.png"):
        assert (tmp_path / "out" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def assert_clean_failure(result: subprocess.CompletedProcess[str], output: Path) -> None:
    assert result.returncode == 2, (result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("g1patch: error: "), result.stderr
    assert "Traceback" not in result.stderr
    assert not output.exists()
    from g1patch.io.atomic import TEMPORARY_PREFIX

    assert not list(output.parent.glob(f"{TEMPORARY_PREFIX}*")), "a temporary file was left behind"


@pytest.mark.parametrize("bad", sorted(p.name for p in MALFORMED.iterdir()))
def test_malformed_meshes_fail_cleanly(tmp_path: Path, bad: str) -> None:
    output = tmp_path / "out.npz"
    result = g1patch("build", MALFORMED / bad, "-o", output, "--no-split", "--strict")
    assert_clean_failure(result, output)
    assert bad in result.stderr  # the message names the file


@pytest.mark.parametrize("bad", sorted(p.name for p in MALFORMED_BPT.iterdir()))
def test_malformed_patch_files_fail_cleanly(tmp_path: Path, bad: str) -> None:
    result = g1patch("check", MALFORMED_BPT / bad)
    assert result.returncode == 2 and bad in result.stderr and "Traceback" not in result.stderr


def test_user_mistakes_fail_cleanly(tmp_path: Path, cube_obj: Path) -> None:
    network = tmp_path / "n.npz"
    assert g1patch("build", cube_obj, "-o", network).returncode == 0
    cases = [
        (("build", tmp_path / "missing.obj", "-o", tmp_path / "a.npz"), tmp_path / "a.npz"),
        (("build", cube_obj, "-o", tmp_path / "a.obj"), tmp_path / "a.obj"),
        (("export", network, "-o", tmp_path / "s.xyz"), tmp_path / "s.xyz"),
        (("export", network, "-o", tmp_path / "s.obj", "--resolution", "1"), tmp_path / "s.obj"),
        (("export", tmp_path / "missing.npz", "-o", tmp_path / "s.obj"), tmp_path / "s.obj"),
        (("check", cube_obj), tmp_path / "unused"),
        (("render", network, "-o", tmp_path / "p.jpg"), tmp_path / "p.jpg"),
        (("render", network, "-o", tmp_path / "p.png", "--size", "0", "10"), tmp_path / "p.png"),
    ]
    for args, output in cases:
        assert_clean_failure(g1patch(*args), output)


def test_usage_errors_exit_2() -> None:
    assert g1patch().returncode == 2
    assert g1patch("build").returncode == 2
    assert g1patch("build", "x.obj", "-o", "y.npz", "--twist", "wobbly").returncode == 2
