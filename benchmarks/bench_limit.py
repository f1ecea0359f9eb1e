"""Catmull–Clark limit mode: distance to OpenSubdiv's limit, G1, folds, fairness, build cost.

And the limit build at scale.

Table 1, per shared mesh with a reference (``../shared/data/reference/NAME.limit.npz``, OpenSubdiv's
limit: cage refined ``levels`` times, points on the limit; skipped when absent), rows
``build_network(mesh, method, shape, refine=r)`` for shape ``limit`` with r = 0, 1, 2 and
``limit-interpolate`` with r = 0, methods gregory and split4. Columns, distances relative to the
reference's bounding-box diagonal:

* ``S→R max / mean``: our surface's samples (:data:`SAMPLE_STEPS` grid steps per cage face, 8 on
  Spot) to the reference's triangles, exact point–triangle distances (``compare.mesh_distance``).
  It includes the reference's own faceting where samples fall between its vertices (Spot's level 3
  reference: ~2e-4 at 16 steps; at 8 the samples sit at its vertices' parameters);
* ``R→S max / mean``: the reference's points (on the limit surface) to our surface, approximately:
  point-to-plane at the nearest of dense samples (:data:`DENSE_STEPS` steps per cage face, 32 on
  Spot; :func:`distance_to_samples`);
* ``G1 °``: the largest G1 angle on edges and at corners, and ``folds`` (``continuity.check``, its
  samples per patch edge 33, 17, 9 for refine 0, 1, 2: the same spacing along a cage edge);
* ``p99×``: our p99 normal turn over the reference's on grids of the reference's step
  (``compare.compare_fairness``; for refine r the reference is read as ``levels − r`` steps per
  face of the refined network, so the step is the same). DESIGN §5 bars: ≤ 1.1 limit, ≤ 1.5
  interpolating;
* ``corner``: the largest distance of a patch corner from the point the network passes through
  (the limit point for ``limit``, the mesh vertex for ``limit-interpolate``), of the diagonal;
* ``build s``: one ``build_network`` call (the first build of a run also compiles numba kernels:
  a warm-up build precedes the table).

``limit-interpolate`` passes through the mesh's vertices, so its distance to the limit of the mesh
as a cage is the difference between the two surfaces, not an error. Its cage solve is reported below
the table (solver, condition estimate, residual).

Table 2, at scale (``--no-scale`` skips it): ``build_network(cage, "gregory", shape)`` for ``limit``
and for ``interpolate`` on the same cage in the same run, time (the best of ``--repeat`` untraced
builds) and tracemalloc peak (one more, traced build), and their ratio: on
``shapes.large_torus(--quads)`` (all regular: the limit targets are the B-spline's, no fit), and on
``shapes.genus2()`` refined ``--xv-levels`` times (interior valences 3, 4, 5: 50 · 4^L quads; the
default 7 is 819,200 quads). The limit fit refines only the neighbourhood of the faces it fits
(those at the extraordinary vertices, 24 of them here at every level), ``FIT_LEVELS = 3`` times,
so that cost stays the same as the cage grows. The load average is printed with each row (the
times are only comparable within a run; the ratios hold). The numba kernels' one-time compile is
not in the figures: warm-up builds of both sizes' paths precede the tables.

``--quick`` runs table 1 on the cube alone, with fewer samples, and table 2 on small cages.

Run:  .venv/bin/python benchmarks/bench_limit.py [--quads N] [--xv-levels L] [--repeat R]
      [--meshes NAME ...] [--no-scale] [--quick]
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence
from functools import partial

import harness
import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from g1patch import compare, shapes
from g1patch.build import build_network
from g1patch.continuity import check
from g1patch.io.meshfile import read_mesh
from g1patch.memory import tune_for_large_arrays
from g1patch.mesh import QuadMesh
from g1patch.network import PatchNetwork
from g1patch.subdivision import refine
from g1patch.targets.limit_interpolate import interpolating_cage

FloatArray = NDArray[np.float64]
record = harness.recorder("bench_limit")

#: (shape, refine) rows of table 1, each built by both methods
ROWS = (("limit", 0), ("limit", 1), ("limit", 2), ("limit-interpolate", 0))
METHODS = ("gregory", "split4")
#: grid steps per cage face of the samples measured against the reference, and at most this
#: many samples per mesh (the step is halved until they fit; exact distances cost ~40 µs each)
SAMPLE_STEPS = 16
SAMPLE_BUDGET = 250_000
#: the same for the dense samples the reference points are measured against
DENSE_STEPS = 64
DENSE_BUDGET = 4_000_000


def network_steps(
    cage_faces: int, cage_steps: int, refinements: int, split4: bool, budget: int
) -> int:
    """Grid steps per network face for ``cage_steps`` per cage face after ``refinements`` steps,
    halved until ``cage_faces · (steps + 1)² ≤ budget``; at least 1, or 2 for split4 (even)."""
    steps = cage_steps
    while steps > 2 and cage_faces * (steps + 1) ** 2 > budget:
        steps //= 2
    return max(steps >> refinements, 2 if split4 else 1)


def distance_to_samples(points: FloatArray, samples: FloatArray, normals: FloatArray) -> FloatArray:
    """Approximate distance from ``points`` to a surface sampled on grids ``(N, S, S, 3)`` with
    unit normals.

    With q the nearest sample (k-d tree), ``δ = p − q``, n its normal and h half the largest grid
    cell diagonal (the farthest a surface point lies, tangentially, from its nearest sample):
    ``d = √((n·δ)² + max(0, |δ − (n·δ) n| − h)²)``: point-to-plane near the surface (error
    ~ h²κ/2), the Euclidean excess beyond its reach (past an open boundary)."""
    diagonals = np.concatenate(
        [
            np.linalg.norm(samples[:, 1:, 1:] - samples[:, :-1, :-1], axis=-1).ravel(),
            np.linalg.norm(samples[:, 1:, :-1] - samples[:, :-1, 1:], axis=-1).ravel(),
        ]
    )
    reach = 0.5 * float(diagonals.max())
    flat, flat_normals = samples.reshape(-1, 3), normals.reshape(-1, 3)
    nearest = cKDTree(flat).query(points, workers=-1)[1]
    delta = points - flat[nearest]
    normal_part = np.einsum("pd,pd->p", delta, flat_normals[nearest])
    tangential = np.linalg.norm(delta - normal_part[:, None] * flat_normals[nearest], axis=1)
    return np.sqrt(normal_part**2 + np.maximum(tangential - reach, 0.0) ** 2)


def distances(
    network: PatchNetwork,
    reference: compare.Reference,
    cage_faces: int,
    refinements: int,
    budgets: tuple[int, int],
) -> tuple[float, float, float, float]:
    """(max, mean) of samples → reference (exact, ``mesh_distance``) and of reference points →
    our surface (:func:`distance_to_samples`), of the reference's diagonal."""
    split4 = network.provenance.get("method") == "split4"
    diagonal = reference.bounding_box_diagonal
    steps = network_steps(cage_faces, SAMPLE_STEPS, refinements, split4, budgets[0])
    samples, _ = compare.surface_samples(network, compare.patch_samples(network, steps))
    to_reference = (
        compare.mesh_distance(samples.reshape(-1, 3), reference.points, reference.faces) / diagonal
    )
    steps = network_steps(cage_faces, DENSE_STEPS, refinements, split4, budgets[1])
    dense, normals = compare.surface_samples(network, compare.patch_samples(network, steps))
    to_ours = distance_to_samples(reference.points, dense, normals) / diagonal
    return (
        float(to_reference.max()),
        float(to_reference.mean()),
        float(to_ours.max()),
        float(to_ours.mean()),
    )


def shared_row(
    name: str,
    mesh: QuadMesh,
    reference: compare.Reference,
    row: tuple[str, int, str],
    budgets: tuple[int, int],
) -> None:
    """One row of table 1: one mesh, shape, refinement and method."""
    shape, refinements, method = row
    build = partial(  # at the given refinement: the tolerance loop is bench_tolerance's
        build_network,
        mesh,
        method,
        shape,  # type: ignore[arg-type]
        refine=refinements,
        tolerance=None,
    )
    seconds, network = harness.timed(build)
    report = check(network, samples=max(9, 33 >> refinements))  # the same spacing on a cage edge
    levels = reference.levels - refinements
    ratio = compare.compare_fairness(
        network, dataclasses.replace(reference, levels=levels)
    ).p99_ratio
    s_max, s_mean, r_max, r_mean = distances(network, reference, mesh.n_faces, refinements, budgets)
    g1 = max(report.max_edge_angle_deg, report.max_corner_angle_deg)
    corner = report.max_vertex_deviation
    print(
        f"{name:<22}{shape:<18}{refinements:>2} {method:<8}{s_max:>9.2e}{s_mean:>9.2e}"
        f"{r_max:>9.2e}{r_mean:>9.2e}{g1:>9.1e}{report.folds:>6}{ratio:>7.3f}{corner:>9.1e}"
        f"{seconds:>8.2f}"
    )
    label = f"{name} {shape} r{refinements} {method}"
    record(f"{label} S→R max", s_max, "of diagonal")
    record(f"{label} R→S max", r_max, "of diagonal")
    record(f"{label} max G1 angle", g1, "°")
    record(f"{label} folds", report.folds, "")
    record(f"{label} p99 turn / limit", ratio, "×", "bar ≤ 1.1 limit, ≤ 1.5 interpolating")
    record(f"{label} build", seconds, "s", "one build")


def table_shared(meshes: Sequence[str], budgets: tuple[int, int]) -> None:
    """Table 1 (module docstring)."""
    header = (
        f"{'mesh':<22}{'shape':<18}{'r':>2} {'method':<8}{'S→R max':>9}{'mean':>9}"
        f"{'R→S max':>9}{'mean':>9}{'G1 °':>9}{'folds':>6}{'p99×':>7}{'corner':>9}{'build s':>8}"
    )
    print(header)
    print("-" * len(header))
    solves = []
    for name in meshes:
        obj = harness.SHARED / f"{name}.obj"
        mesh = read_mesh(obj)
        reference = compare.load_reference(compare.reference_path(obj))
        for shape, refinements in ROWS:
            for method in METHODS:
                shared_row(name, mesh, reference, (shape, refinements, method), budgets)
        solution = interpolating_cage(mesh)
        solves.append(
            f"{name}: {solution.solver}, condition ≈ {solution.condition:.1e}, relative "
            f"residual {solution.residual:.1e}"
        )
        print()
    print("limit-interpolate cage solves (L C = V):")
    for line in solves:
        print(f"  {line}")


def scale_row(label: str, key: str, mesh: QuadMesh, repeat: int) -> None:
    """Table 2 rows for one cage: limit and interpolate, the best of ``repeat`` times and the
    peak, and limit / interpolate."""
    figures = {}
    for shape in ("limit", "interpolate"):
        build = partial(build_network, mesh, "gregory", shape, tolerance=None)  # type: ignore[arg-type]
        seconds = harness.best(build, repeat)
        load = harness.load_average()[0]
        peak = harness.peak(build)
        figures[shape] = (seconds, peak)
        print(
            f"{label:<34}{mesh.n_faces:>10,}  {shape:<12}{seconds:>8.2f}{peak / 1e6:>9.0f}"
            f"{peak / mesh.n_faces:>8.0f}{load:>6.1f}"
        )
        record(f"{key} {shape} build", seconds, "s", f"{mesh.n_faces:,} quads, best of {repeat}")
        record(f"{key} {shape} build peak per quad", peak / mesh.n_faces, "B/quad")
    (limit_s, limit_peak), (base_s, base_peak) = figures["limit"], figures["interpolate"]
    print(f"{'':<34}{'':>10}  {'ratio':<12}{limit_s / base_s:>8.2f}{limit_peak / base_peak:>9.2f}")
    record(f"{key} limit / interpolate build time", limit_s / base_s, "×")
    record(f"{key} limit / interpolate build peak", limit_peak / base_peak, "×")


def table_scale(quads: int, xv_levels: int, repeat: int) -> None:
    """Table 2 (module docstring)."""
    header = (
        f"{'cage':<34}{'quads':>10}  {'shape':<12}{'build s':>8}{'peak MB':>9}{'B/quad':>8}"
        f"{'load':>6}"
    )
    print(header)
    print("-" * len(header))
    regular = shapes.large_torus(quads)
    scale_row(f"large_torus({quads:,}) (regular)", "regular", regular, repeat)
    record("regular quads", regular.n_faces, "quads", f"large_torus({quads})")
    del regular
    irregular = refine(shapes.genus2(), xv_levels)
    scale_row(f"genus2 refined {xv_levels}× (valence 3/5)", "genus2", irregular, repeat)
    record("genus2 quads", irregular.n_faces, "quads", f"genus2 refined {xv_levels}×")


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "quads": (1_000_000, "quads of the regular torus in table 2"),
    "xv_levels": (7, "refinements of genus2 in table 2 (7: 819,200 quads)"),
    "repeat": (3, "untraced builds per row of table 2, the best"),
    "meshes": (list(harness.SHARED_MESHES), "shared meshes of table 1"),
    "sample_budget": (SAMPLE_BUDGET, "samples measured against the reference, at most"),
    "dense_budget": (DENSE_BUDGET, "dense samples the reference is measured against, at most"),
    "no_scale": (False, "skip table 2"),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {
    "meshes": ["catmark_cube"],
    "sample_budget": 20_000,
    "dense_budget": 200_000,
    "quads": 20_000,
    "xv_levels": 3,
    "repeat": 1,
}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    tune_for_large_arrays()  # as the command line does (g1patch.memory)
    logging.disable(logging.INFO)
    print(harness.machine_line() + "\n")
    # warm-up: numba loads (or compiles) its kernels once per process, above their thresholds too
    warm = refine(shapes.genus2(), 5)
    for mesh in (shapes.genus2(), warm):
        build_network(mesh, "gregory", "limit")
        build_network(mesh, "gregory", "interpolate")
    build_network(shapes.genus2(), "split4", "limit")
    if harness.SHARED.is_dir():
        table_shared(args.meshes, (args.sample_budget, args.dense_budget))
    else:
        print(f"table 1 skipped: shared data not found at {harness.SHARED}")
    if not args.no_scale:
        print()
        table_scale(args.quads, args.xv_levels, args.repeat)
    process = harness.process_peak()
    print(f"\nprocess peak (ru_maxrss) {process / 1e6:.0f} MB")
    record("process peak", process / 1e6, "MB", "ru_maxrss")


if __name__ == "__main__":
    main()
