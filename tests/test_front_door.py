"""One front door (issue 29): the command line builds through the public API, so ``g1patch build``
and ``g1patch.smooth`` give bit-identical networks for every shape × method, and every command
that reads a surface reads what the API reads (``.npz`` and ``.bpt`` alike)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import g1patch
from g1patch.cli import main
from g1patch.construct import ASSEMBLIES
from g1patch.targets import SHAPES

CAGES = (
    "catmark_cube",
    "catmark_torus_creases0",
    "catmark_xord_boundary",
    "catmark_dart_edgecorner",
)


def _arrays(network: g1patch.PatchNetwork) -> dict[str, object]:
    """Every array of the network, its patches' stored points and frame included."""
    patches = network.patches
    stored = patches.points if isinstance(patches, g1patch.GregoryPatchSet) else patches.control
    names = ("corner_ids", "edge_ids", "neighbor", "neighbor_edge", "vertices", "vertex_normals")
    arrays: dict[str, object] = {name: getattr(network, name) for name in names}
    frame = getattr(patches, "frame", None)
    arrays.update(patches=stored, seam=network.seam, frame=None if frame is None else repr(frame))
    return arrays


@pytest.mark.parametrize("cage", CAGES)
@pytest.mark.parametrize("shape", tuple(SHAPES))
@pytest.mark.parametrize("method", tuple(ASSEMBLIES))
def test_cli_and_api_build_the_same_network(
    shared_data: Path, tmp_path: Path, cage: str, shape: str, method: str
) -> None:
    mesh = shared_data / f"{cage}.obj"
    out = tmp_path / "cli.npz"
    assert (
        main(["build", str(mesh), "-o", str(out), "--shape", shape, "--method", method, "-q"]) == 0
    )
    from_cli = g1patch.read(out)
    from_api = g1patch.smooth(mesh, shape, method).network
    assert isinstance(from_cli, g1patch.PatchNetwork)
    cli_arrays = _arrays(from_cli)
    for name, value in _arrays(from_api).items():
        np.testing.assert_array_equal(cli_arrays[name], value, err_msg=name)  # type: ignore[arg-type]
    assert from_cli.provenance == from_api.provenance


def test_export_reads_bezier_patches_as_check_and_render_do(
    shared_data: Path, tmp_path: Path
) -> None:
    teapot = shared_data / "teapot.bpt"
    assert main(["check", str(teapot), "-q"]) == 0
    assert main(["export", str(teapot), "-o", str(tmp_path / "teapot.obj"), "-q"]) == 0
    assert main(["export", str(teapot), "-o", str(tmp_path / "teapot.bpt"), "-q"]) == 0
    again = g1patch.read(tmp_path / "teapot.bpt")
    assert isinstance(again, g1patch.PatchNetwork) and again.n_patches == 32


def test_every_door_has_the_same_default_method_split4() -> None:
    """The default is the polynomial assembly, so the CAD file of a default build is the surface
    itself; the API, the batch, the build and the command line agree on it."""
    import inspect

    from g1patch.batch.jobs import BuildOptions
    from g1patch.build import build_network
    from g1patch.cli.parser import build_parser
    from g1patch.construct import DEFAULT_METHOD

    assert DEFAULT_METHOD == "split4"
    for function in (g1patch.smooth, build_network):
        assert inspect.signature(function).parameters["method"].default == DEFAULT_METHOD
    assert BuildOptions().method == DEFAULT_METHOD
    arguments = build_parser().parse_args(["build", "cube.obj", "-o", "cube.npz"])
    assert arguments.method == DEFAULT_METHOD


def test_every_door_has_the_same_default_tolerance() -> None:
    """The limit shapes' distance bound (issue 30): the API, the build, the batch and the command
    line agree on 1e-3 of the diagonal."""
    import inspect

    from g1patch.batch.jobs import BuildOptions
    from g1patch.build import DEFAULT_TOLERANCE, build_network
    from g1patch.cli.parser import build_parser

    assert DEFAULT_TOLERANCE == 1e-3
    for function in (g1patch.smooth, build_network):
        assert inspect.signature(function).parameters["tolerance"].default == DEFAULT_TOLERANCE
    assert BuildOptions().tolerance == DEFAULT_TOLERANCE
    for argv in (["build", "cube.obj", "-o", "cube.npz"], ["batch", "cube.obj", "--out", "o"]):
        assert build_parser().parse_args(argv).tolerance == DEFAULT_TOLERANCE


def test_every_fit_door_has_the_same_sharp_angle() -> None:
    """The fit keeps a CAD part's edges by default (issue 33): the API, the fit and the command
    line agree on the angle, and 'off' turns it off."""
    import inspect

    from g1patch.cli.parser import build_parser
    from g1patch.fitting import FIT_SHARP_ANGLE, fit_network

    for function in (g1patch.fit, fit_network):
        assert inspect.signature(function).parameters["sharp_angle"].default == FIT_SHARP_ANGLE
    arguments = build_parser().parse_args(["fit", "scan.stl", "-o", "part.step"])
    assert arguments.sharp_angle == FIT_SHARP_ANGLE
    off = build_parser().parse_args(["fit", "scan.stl", "-o", "a.step", "--sharp-angle", "off"])
    assert off.sharp_angle is None
