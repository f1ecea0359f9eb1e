"""Budgets: a build's size and peak memory known before it starts (:func:`estimate_build`), and a
build above the memory budget or the network file's patch limit refused with the estimate."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import pytest

from g1patch import shapes
from g1patch.build import build_network, estimate_build
from g1patch.cli import main
from g1patch.errors import BudgetError
from g1patch.mesh import QuadMesh, Tag


def _tent() -> QuadMesh:
    """A 3 × 3 grid with a semi-sharp crease of sharpness 2 (the limit shapes refine twice)."""
    grid = shapes.grid(3, 3)
    row = [4 * 1 + i for i in range(4)]
    pairs = tuple(v for a, b in zip(row, row[1:], strict=False) for v in (a, b))
    return QuadMesh(grid.vertices, grid.topology, (Tag("crease", pairs, (2.0,)),))


@pytest.mark.parametrize("method", ["gregory", "split4", "corner"])
@pytest.mark.parametrize(("shape", "refine"), [("interpolate", 1), ("limit", 0)])
def test_the_estimate_counts_what_the_build_makes(method: str, shape: str, refine: int) -> None:
    """Without a tolerance (a Gregory limit build with one refines locally: fewer patches)."""
    mesh = _tent()
    estimate = estimate_build(mesh, method, shape, refine)
    network = build_network(mesh, method, shape, refine=refine, tolerance=None)
    assert estimate.patches == network.n_patches
    assert estimate.steps == (refine if shape == "interpolate" else 2)
    if method == "gregory" and shape == "limit":
        local = build_network(mesh, method, shape)
        assert local.n_patches < estimate.patches
        assert estimate_build(mesh, method, shape, semi_sharp_first=False).steps == 0


@pytest.mark.parametrize("method", ["gregory", "split4", "corner"])
def test_the_memory_estimate_bounds_the_peak(method: str) -> None:
    """tracemalloc's peak of a 20k-quad build (after the same build compiled the kernels) is below
    the estimate, and the estimate less than 1.5 times it: a budget that neither lets a build
    through that exhausts memory nor refuses one that fits."""
    mesh = shapes.large_torus(20_000)
    build_network(mesh, method, "interpolate", refine=1)  # kernels compiled or loaded: not traced
    _assert_the_estimate_bounds_the_peak(mesh, method)


def _assert_the_estimate_bounds_the_peak(mesh: QuadMesh, method: str) -> None:
    """``estimate_build`` of a once-refined interpolating build is within [1, 1.5)× its traced
    peak."""
    tracemalloc.start()
    try:
        build_network(mesh, method, "interpolate", refine=1)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    estimate = estimate_build(mesh, method, "interpolate", refine=1).bytes
    assert peak <= estimate < 1.5 * peak, (peak, estimate)


@pytest.mark.slow
@pytest.mark.parametrize("method", ["gregory", "split4"])
def test_without_a_kernel_cache_the_estimate_bounds_the_numpy_peak(
    method: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Where numba cannot cache (a read-only install) the NumPy path runs, which holds more (the
    gregory build 2.6× the kernels' peak): the estimate takes that path's figures, still within
    1.5× of the peak."""
    from g1patch import kernels

    monkeypatch.setattr(kernels, "kernels_cached", lambda: False)
    mesh = shapes.large_torus(20_000)
    _assert_the_estimate_bounds_the_peak(mesh, method)


def test_a_build_above_the_budget_is_refused_before_it_starts() -> None:
    with pytest.raises(BudgetError, match=r"8,388,608 gregory patches after 9 Catmull–Clark steps"):
        build_network(shapes.torus(8, 4, 1.0, 0.25), "gregory", refine=9, max_memory=10**9)


def test_the_command_line_names_the_file_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cage = tmp_path / "cage.obj"
    cage.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    out = tmp_path / "out.npz"
    assert main(["build", str(cage), "-o", str(out), "--refine", "12"]) == 2
    assert "more than a network file holds" in capsys.readouterr().err
    code = main(["build", str(cage), "-o", str(out), "--refine", "6", "--max-memory", "1M"])
    line = capsys.readouterr().err.strip()
    assert code == 2 and line.startswith(f"g1patch: error: {cage}: ") and "1 MB" in line
    assert not out.exists()
