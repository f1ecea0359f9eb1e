"""``g1patch fit``: time, memory and distance against the scan's size and the layout's (issue 33).

Table 1, scans of growing size: triangulated tori (``shapes.torus_quads``, R 2, r 0.7, each quad
cut in two; ``--triangles`` of them, about) fitted at the default tolerance (1e-3 of the
diagonal): wall time of ``g1patch.fit`` (the Instant Meshes child process included), tracemalloc
peak of this process (the child's memory is its own), cage quads, layouts tried, and the two-way
maximum distance, of the diagonal. The baseline measured in the same run is the tool before the
fit existed: ``smooth`` of the same triangles as a cage (every triangle split into three quads,
interpolated); the ratio is the fit's time over it.

Table 2, distance against the layout's size on one scan (``--faces`` sweep) and on the shared
Spot triangles (a coarse tessellation: its facets are up to 3e-3 of the diagonal from any smooth
surface through its vertices, so the surface → scan figure stays above that).

Table 3 (not with ``--quick``), local refinement: a sphere scan with a narrow bump fitted at
``--tolerance 2e-3`` with the layout refined where it is off, against the baseline of the same
run with that switched off (every off layout remade finer): quads, time, distance.

Table 4 (not with ``--quick``), the cage's sparse solve: a 100 k-triangle torus fitted on one
layout of the largest ``--faces`` with SuperLU told the system is symmetric, against the same fit
with SuperLU's default ordering and pivoting in the same run.

Table 5 (not with ``--quick``), generated scans a user brings, fitted at ``--tolerance 2e-3``
as ``g1patch fit`` does (no face count): a height field with three round holes, a ragged rim and
noise (a range scan), a low-poly ellipsoid (796 triangles: a layout face holds few vertices, its
facets are sampled), and a noisy sphere scan; whether each is within the tolerance, its quads,
layouts, two-way distance and folds.

Run:  .venv/bin/python benchmarks/bench_fit.py [--triangles N ...] [--faces N ...] [--quick]
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from pathlib import Path

import harness
import numpy as np

import g1patch
from g1patch import shapes
from g1patch.io.meshfile import write_triangles

record = harness.recorder("bench_fit")
Array = np.ndarray  # a float or int array


def torus_scan(folder: Path, triangles: int) -> Path:
    """A triangulated torus of about ``triangles`` triangles (minor rings = major / 2)."""
    minor = max(4, int(round((triangles / 4) ** 0.5)))
    mesh = shapes.torus_quads(2 * minor, minor, 2.0, 0.7)
    cells = np.concatenate([mesh.faces[:, [0, 1, 2]], mesh.faces[:, [0, 2, 3]]])
    path = folder / f"torus_{len(cells)}.obj"
    write_triangles(path, mesh.vertices, cells)
    return path


def row(label: str, path: Path, **options: object) -> g1patch.api.FitResult:
    """One fit, timed and traced (two runs: the traced one's peak, the untraced one's time)."""
    seconds, result = harness.timed(lambda: g1patch.fit(path, **options))  # type: ignore[arg-type]
    peak = harness.peak(lambda: g1patch.fit(path, **options))  # type: ignore[arg-type]
    report = result.report
    print(
        f"  {label:<28} {seconds:6.1f} s {peak / 1e6:7.0f} MB  {report.faces:7,} quads "
        f"({report.rounds} layouts)  scan→surface {report.to_surface[0] / report.diagonal:.1e}"
        f"  surface→scan {report.to_scan[0] / report.diagonal:.1e}"
    )
    record(f"{label}: time", seconds, "s", "remesher child process included")
    record(f"{label}: peak", peak / 1e6, "MB", "tracemalloc, this process")
    record(f"{label}: quads", report.faces, "")
    record(f"{label}: two-way max", report.worst, "of diagonal", f"{report.rounds} layouts")
    return result


def table_sizes(folder: Path, sizes: Sequence[int]) -> None:
    print("fit against the scan's size (torus scans, default tolerance 1e-3):")
    for triangles in sizes:
        path = torus_scan(folder, triangles)
        label = f"torus {triangles:,} triangles"
        result = row(label, path)
        if triangles <= 40_000:  # the baseline: the triangles as a cage, interpolated
            g1patch.smooth(path, method="gregory")  # kernels loaded
            baseline, surface = harness.timed(
                lambda path=path: g1patch.smooth(path, method="gregory")
            )
            ratio = result.report.seconds / baseline
            print(
                f"  {'  as a cage (baseline)':<28} {baseline:6.1f} s {surface.n_patches:,} "
                f"patches; the fit takes {ratio:.1f}× its time, {result.report.patches:,} patches"
            )
            record(f"{label}: fit / build as a cage", ratio, "×", "time")
            record(f"{label}: build as a cage", baseline, "s", f"{surface.n_patches} patches")


def table_faces(folder: Path, faces: Sequence[int], spot: bool) -> None:
    print("distance against the layout's size:")
    path = torus_scan(folder, 40_000)
    for count in faces:
        row(f"torus 40k, {count:,} quads asked", path, faces=count)
    shared = harness.SHARED / "spot_triangulated.obj"
    if spot and shared.exists():
        for count in faces:
            row(f"Spot triangles, {count:,} quads", shared, faces=count)


def bump_scan(folder: Path) -> Path:
    """A unit sphere scan with a narrow bump at a pole (``shapes.bump_sphere_scan``: 60,000
    points, height 0.4, width 0.1 rad)."""
    path = folder / "bump.obj"
    write_triangles(path, *shapes.bump_sphere_scan())
    return path


def table_local(folder: Path) -> None:
    """Table 3: the layout refined where it is off against made finer everywhere (the baseline,
    the same fit with local refinement switched off, in the same run)."""
    import g1patch.fitting

    print("local refinement (a bump on a sphere, --tolerance 2e-3):")
    path = bump_scan(folder)
    local = row("bump, refined locally", path, tolerance=2e-3)
    share = g1patch.fitting.LOCAL_SHARE
    g1patch.fitting.LOCAL_SHARE = 0.0  # every off layout remade finer
    try:
        finer = row("bump, finer layouts (baseline)", path, tolerance=2e-3)
    finally:
        g1patch.fitting.LOCAL_SHARE = share
    record("bump: quads, local / finer layouts", local.report.faces / finer.report.faces, "×")


def table_solver(folder: Path, faces: int) -> None:
    """Table 4: the cage solved with SuperLU told the normal equations are symmetric
    (``solve.SYMMETRIC_LU``) against the baseline of the same run with SuperLU's defaults (a
    column ordering of A alone, partial pivoting): the same fit, one layout of ``faces`` quads."""
    from g1patch.fitting import solve

    print(f"the cage's sparse solve (torus 100k, {faces:,} quads asked):")
    path = torus_scan(folder, 100_000)
    symmetric = row("symmetric LU", path, faces=faces)
    options = solve.SYMMETRIC_LU
    solve.SYMMETRIC_LU = {}
    try:
        general = row("default LU (baseline)", path, faces=faces)
    finally:
        solve.SYMMETRIC_LU = options
    ratio = symmetric.report.seconds / general.report.seconds
    print(f"  the symmetric solve takes {ratio:.2f}× the fit time of the default one")
    record("torus 100k: fit time, symmetric / default LU", ratio, "×", f"{faces} quads asked")


def holed_sheet(cells: int = 160, noise: float = 5e-4, seed: int = 0) -> tuple[Array, Array]:
    """A range-scan-like sheet: the height field ``z = 0.1 sin(2πx) cos(πy)`` over the unit
    square in ``cells`` × ``cells`` squares (two triangles each), without the triangles whose
    centroid is inside three round holes (radius 0.06–0.1) or within a random 0–0.0125 (two
    cells) of the square's sides (a ragged rim), its points moved by normal noise of σ ``noise``
    in z."""
    random = np.random.default_rng(seed)
    x = np.linspace(0.0, 1.0, cells + 1)
    u, v = np.meshgrid(x, x, indexing="ij")
    z = 0.1 * np.sin(2 * np.pi * u) * np.cos(np.pi * v) + random.normal(0.0, noise, u.shape)
    points = np.stack([u, v, z], -1).reshape(-1, 3)
    corner = (np.arange(cells)[:, None] * (cells + 1) + np.arange(cells)).ravel()
    triangles = np.concatenate(
        [
            np.stack([corner, corner + cells + 1, corner + cells + 2], 1),
            np.stack([corner, corner + cells + 2, corner + 1], 1),
        ]
    )
    centre = points[triangles].mean(axis=1)[:, :2]
    holes = np.array([[0.3, 0.3, 0.1], [0.7, 0.35, 0.06], [0.5, 0.72, 0.08]])
    inside = (np.linalg.norm(centre[:, None] - holes[:, :2], axis=2) < holes[:, 2]).any(axis=1)
    border = np.minimum(centre, 1.0 - centre).min(axis=1)
    ragged = border < random.uniform(0.0, 0.0125, len(triangles))
    return points, triangles[~inside & ~ragged]


def sphere_scan(
    points: int, axes: Sequence[float], noise: float, seed: int = 0
) -> tuple[Array, Array]:
    """An ellipsoid of semi-axes ``axes`` through ``points`` Fibonacci points of the unit sphere
    (``shapes.bump_sphere_scan`` without its bump), moved radially by normal noise of σ
    ``noise``."""
    unit, triangles = shapes.bump_sphere_scan(points, height=0.0)
    radius = 1.0 + np.random.default_rng(seed).normal(0.0, noise, len(unit))
    return unit * radius[:, None] * np.asarray(axes), triangles


def table_suite(folder: Path) -> None:
    """Table 5: generated scans at ``--tolerance 2e-3``, each as ``g1patch fit`` fits it."""
    print("generated scans (--tolerance 2e-3):")
    scans = {
        "holed sheet, ragged rim, noise": holed_sheet(),
        "low-poly ellipsoid": sphere_scan(400, (1.0, 0.7, 0.5), 0.0),
        "noisy sphere": sphere_scan(40_000, (1.0, 1.0, 1.0), 2e-4),
    }
    for label, (points, triangles) in scans.items():
        path = folder / f"{label.split(',')[0].replace(' ', '_')}.obj"
        write_triangles(path, points, triangles)
        result = row(label, path, tolerance=2e-3)
        report = result.report
        print(f"  {'':<28} {'within' if report.met else 'NOT within'}, {report.folds} folds")
        record(f"{label}: folds", report.folds, "", "within" if report.met else "not within")


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "triangles": ([10_000, 100_000, 1_000_000], "scan sizes, triangles"),
    "faces": ([500, 2_000, 8_000], "layout sizes of table 2, quads"),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"triangles": [10_000], "faces": [500]}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    with tempfile.TemporaryDirectory(prefix="bench-fit.") as folder:
        table_sizes(Path(folder), args.triangles)
        table_faces(Path(folder), args.faces, spot=not args.quick)
        if not args.quick:
            table_local(Path(folder))
            table_solver(Path(folder), max(args.faces))
            table_suite(Path(folder))


if __name__ == "__main__":
    main()
