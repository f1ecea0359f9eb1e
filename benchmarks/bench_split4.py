"""Construction speed and memory of the 2×2-split bicubic network (split4), against Gregory.

Workload: an irregular ~1 M-quad mesh: a 16 × 16 torus with three quads collapsed along a
diagonal (valences 3, 5, 6 next to 4), refined by ``mesh.subdivide`` (linear positions) until
it has at least ``--quads`` quads (default 1,000,000 → 1,036,288); its topology is built before
anything is timed. In the same run:

* build: ``build_split4_network(mesh)`` and ``build_gregory_network(mesh)`` (tangents "arc",
  fan normals to PatchNetwork); median of ``--repeats`` runs after one untimed build of each
  (``first s``), which loads the kernels and faults the build's memory in: on this VM fresh
  memory is first touched at ~0.2-2 GB/s, and without it the first build (split4's) paid that
  for both; ratio split4 / Gregory. From ``split4.KERNEL_FACES`` faces the split4 build runs
  numba kernels; ``--numpy`` also times one build on its NumPy reference path (kernels off), in
  the same run;
* build peak: the tracemalloc peak of one more build over the memory held before it, per quad
  (DESIGN §5 bar: 1 KB; issue 13: 2 KB). The split4 network alone is ~2.3 KB per quad: its
  controls 4 × 16 × 3 doubles = 1.5 KB, four (4, 4) int64 connectivity arrays per quad 0.5 KB,
  points and normals at vertices, midpoints and centres 0.2 KB;
* with ``--check``: ``continuity.check`` of the split4 network (4 sub-patches per quad).

Load averages (1, 5, 15 min) are printed before and after: the machine is shared, compare
ratios. Issue 13's targets: split4 build ≤ 6 s and ≤ 2 KB per quad at 1 M quads.

Run:  .venv/bin/python benchmarks/bench_split4.py [--quads N] [--repeats R] [--numpy] [--check]
      [--quick]
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Sequence
from functools import partial

import harness
import numpy as np

from g1patch import shapes
from g1patch.build import build_gregory_network, build_split4_network
from g1patch.construct.split4 import threshold as split4
from g1patch.continuity import check
from g1patch.memory import tune_for_large_arrays
from g1patch.mesh import QuadMesh, subdivide
from g1patch.network import PatchNetwork

record = harness.recorder("bench_split4")
BUILDERS: dict[str, Callable[[QuadMesh], PatchNetwork]] = {
    "split4": build_split4_network,
    "gregory": build_gregory_network,
}


def irregular_mesh(quads: int) -> QuadMesh:
    """A torus with three diagonal collapses (two corners of a quad merged), subdivided to at
    least ``quads``."""
    base = shapes.torus(16, 16, r=0.4)
    faces, vertices = base.faces.copy(), base.vertices.copy()
    keep = np.ones(len(faces), dtype=bool)
    for f in (17, 100, 183):  # far apart: each makes one valence-6 and two valence-3 vertices
        a, c = faces[f, 0], faces[f, 2]
        vertices[a] = 0.5 * (vertices[a] + vertices[c])
        faces[faces == c] = a
        keep[f] = False
    mesh = QuadMesh.from_arrays(vertices, faces[keep])
    while mesh.topology.n_faces < quads:
        mesh = subdivide(mesh)
    return mesh


def numpy_path(mesh: QuadMesh, kernel_seconds: float) -> None:
    """One split4 build with its kernels off (the NumPy reference path)."""
    kernel_faces, split4.KERNEL_FACES = split4.KERNEL_FACES, mesh.n_faces + 1
    try:
        seconds = harness.timed(lambda: build_split4_network(mesh))[0]
    finally:
        split4.KERNEL_FACES = kernel_faces
    print(
        f"split4 NumPy path (kernels off) {seconds:.2f} s: kernels "
        f"{seconds / kernel_seconds:.1f}x faster"
    )
    record("split4 NumPy path build", seconds, "s", "kernels off, one run")
    record("split4 kernels speed-up", seconds / kernel_seconds, "×")


def check_split4(mesh: QuadMesh) -> None:
    """``continuity.check`` of the split4 network, timed."""
    network = build_split4_network(mesh)
    seconds, report = harness.timed(lambda: check(network))
    print(
        f"check split4: {seconds:.1f} s, max G1 {report.max_edge_angle_deg:.2e}°, corners "
        f"{report.max_corner_angle_deg:.2e}°, G0 {report.max_g0_gap:.1e}, vertex deviation "
        f"{report.max_vertex_deviation:.1e}, folds {report.folds}"
    )
    record("split4 check", seconds, "s")
    record("split4 max G1 angle on edges", report.max_edge_angle_deg, "°")
    record("split4 max G1 angle at corners", report.max_corner_angle_deg, "°")
    record("split4 folds", report.folds, "")


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "quads": (1_000_000, "quads of the mesh, at least"),
    "repeats": (3, "timed builds, the median"),
    "numpy": (False, "also time one split4 build on the NumPy path (kernels off)"),
    "check": (False, "also run continuity.check on the split4 network"),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"quads": 20_000, "repeats": 1}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    tune_for_large_arrays()  # as the command line does (g1patch.memory)

    mesh = irregular_mesh(args.quads)
    topology = mesh.topology
    interior = ~topology.is_boundary_vertex
    valences = np.unique(topology.valence[interior], return_counts=True)
    print(harness.machine_line())
    print(
        f"mesh: {topology.n_faces:,} quads, {topology.n_vertices:,} vertices; interior valences "
        + ", ".join(f"{v}×{c}" for v, c in zip(*valences, strict=True))
    )
    record("quads", topology.n_faces, "quads", f"irregular torus subdivided to ≥ {args.quads}")

    print(f"load average before: {harness.loads()}")
    times: dict[str, float] = {}
    for name, builder in BUILDERS.items():
        build = partial(builder, mesh)
        first = harness.timed(build)[0]
        runs = harness.runs(build, args.repeats)[0]
        times[name] = statistics.median(runs)
        _, peak, network = harness.traced(build)
        print(
            f"{name:8s} build {times[name]:6.2f} s (median of {args.repeats}; runs "
            + ", ".join(f"{r:.2f}" for r in runs)
            + f"; first {first:.2f})  peak {peak / 2**20:7.0f} MiB = "
            f"{peak / topology.n_faces:6.0f} B/quad  patches {network.n_patches:,}"
        )
        note = f"median of {args.repeats}, runs {min(runs):.2f}–{max(runs):.2f}"
        record(f"{name} build", times[name], "s", note)
        record(f"{name} first build", first, "s", "untimed for the median")
        record(f"{name} build peak per quad", peak / topology.n_faces, "B/quad", "tracemalloc")
        record(f"{name} patches", network.n_patches, "")
        del network
    ratio = times["split4"] / times["gregory"]
    print(f"ratio split4 / gregory: {ratio:.2f}")
    record("split4 / gregory build time", ratio, "×")
    if args.numpy:
        numpy_path(mesh, times["split4"])
    print(f"load average after: {harness.loads()}")
    if args.check:
        check_split4(mesh)
    process = harness.process_peak()
    print(f"process peak (ru_maxrss): {process / 2**20:.0f} MiB")
    record("process peak", process / 1e6, "MB", "ru_maxrss")


if __name__ == "__main__":
    main()
