"""Options checked at the door (issue 32, part 4): a count, angle, size or tolerance out of range
is refused before any file is read, with one line naming the option, the value and the range, and
exit 2; the library refuses the same values with InputError."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from g1patch import shapes
from g1patch.api import Surface
from g1patch.cli import main
from g1patch.cli.options import cores
from g1patch.construct.corner import build_corner_network
from g1patch.continuity import check, sampling
from g1patch.errors import InputError
from g1patch.io.network_file import save_network


def run(argv: list[str]) -> int:
    """``main(argv)``, argparse's exits included."""
    try:
        return main(argv)
    except SystemExit as exit_:
        return int(exit_.code or 0)


@pytest.fixture(scope="module")
def cube_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("net") / "cube.npz"
    save_network(path, build_corner_network(shapes.cube()))
    return path


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (
            ["check", "{net}", "--max-angle", "nan"],
            "--max-angle: expected a finite number in [0, 180], got nan",
        ),
        (
            ["check", "{net}", "--max-angle", "-1"],
            "--max-angle: expected a finite number in [0, 180]",
        ),
        (["check", "{net}", "--max-angle", "inf"], "--max-angle: expected a finite number"),
        (
            ["check", "{net}", "--samples", "1"],
            "--samples: expected a number of samples per edge ≥ 2, got 1",
        ),
        (["export", "{net}", "-o", "{out}.obj", "--resolution", "1"], "--resolution: expected"),
        (["view", "{net}", "-o", "{out}.html", "--resolution", "0"], "--resolution: expected"),
        (
            ["export", "{net}", "-o", "{out}.step", "--max-deviation", "nan"],
            "--max-deviation: expected a finite number > 0",
        ),
        (
            ["export", "{net}", "-o", "{out}.step", "--fit-tolerance", "0"],
            "--fit-tolerance: expected a finite number > 0, got 0.0",
        ),
        (
            ["render", "{net}", "-o", "{out}.png", "--size", "100000", "100"],
            "--size: expected two numbers of pixels from 32 to 8192, got 100000 100",
        ),
        (
            ["render", "{net}", "-o", "{out}.png", "--zoom", "nan"],
            "--zoom: expected a finite number > 0",
        ),
        (
            ["render", "{net}", "-o", "{out}.png", "--view", "nan", "0"],
            "view: expected finite angles",
        ),
        (["demo", "--out", "{out}", "--view", "0", "inf"], "view: expected finite angles"),
        (
            ["build", "{missing}", "-o", "{out}.npz", "--refine", "-1"],
            "--refine: expected a number of Catmull–Clark steps ≥ 0, got -1",
        ),
        (
            ["build", "{missing}", "-o", "{out}.npz", "--sharp-angle", "nan"],
            "--sharp-angle: expected degrees between 0 and 180, got nan",
        ),
        (
            ["batch", "{missing}", "--out", "{out}", "--sharp-angle", "180"],
            "--sharp-angle: expected degrees between 0 and 180, got 180.0",
        ),
        (
            ["batch", "{missing}", "--out", "{out}", "--workers", "0"],
            "--workers: expected a number of worker processes ≥ 1, got 0",
        ),
    ],
)
def test_bad_options_exit_2_with_one_line(
    argv: list[str], named: str, cube_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    fields = {"net": cube_file, "out": out, "missing": tmp_path / "missing.obj"}
    assert run([a.format(**fields) for a in argv]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and named in error and "Traceback" not in error
    assert not list(tmp_path.iterdir())  # nothing read (the missing mesh), nothing written


def test_workers_capped_to_the_cores_with_a_note(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import argparse

    from g1patch.cli.options import check_options

    args = argparse.Namespace(command="batch", refine=0, sharp_angle=None, workers=100_000)
    (note,) = check_options(args)
    assert args.workers == cores()
    assert f"--workers 100000 is more than the {cores()} cores" in note


def test_library_refuses_the_same_values() -> None:
    network = build_corner_network(shapes.cube())
    report = check(network)
    for angle in (math.nan, math.inf, -1.0, 181.0):
        with pytest.raises(InputError, match="max_angle: expected a finite number of degrees"):
            report.is_g1(angle)
        with pytest.raises(InputError, match="max_angle"):
            report.passes(angle)
    assert report.passes(1e-9) == report.is_g1(0.0)  # 0 and 180 are in range
    with pytest.raises(InputError, match="samples: expected 2 to .* samples per edge"):
        check(network, samples=1_000_000_000)
    with pytest.raises(InputError, match="fold_samples: expected 2 to"):
        check(network, fold_samples=10_000_000)
    with pytest.raises(InputError, match="samples: expected an integer ≥ 2"):
        check(network, samples=1)
    with pytest.raises(InputError, match="unknown option 'max_angle'"):
        Surface(network).check(max_angle=math.nan)


def test_samples_bound_follows_the_memory_budget(monkeypatch: pytest.MonkeyPatch) -> None:
    network = build_corner_network(shapes.cube())  # 12 shared edges
    monkeypatch.setattr(sampling, "memory_budget", lambda: 12 * 100 * sampling.SAMPLE_BYTES)
    check(network, samples=100, fold_samples=8)
    with pytest.raises(InputError, match="expected 2 to 100 samples per edge"):
        check(network, samples=101, fold_samples=8)


def test_memory_budget_is_the_builds() -> None:
    from g1patch.build import memory_budget

    assert sampling.memory_budget is memory_budget  # one budget, in g1patch.memory
