"""Construction speed and memory of the 2×2-split bicubic network (split4), against Gregory.

Workload: an irregular ~1 M-quad mesh: a 16 × 16 torus with three quads collapsed along a
diagonal (valences 3, 5, 6 next to 4), refined by ``mesh.subdivide`` (linear positions) until
it has at least ``--quads`` quads (default 1,000,000 → 1,036,288); its topology is built before
anything is timed. In the same run:

* build: ``build_split4_network(mesh)`` and ``build_gregory_network(mesh)`` (tangents "arc",
  fan normals to PatchNetwork); median of ``--repeats`` runs after one untimed build of each
  (``first s``), which loads the kernels and faults the build's memory in: on this VM fresh memory
  is first touched at ~0.2-2 GB/s, and without it the first build (split4's) paid that for both;
  ratio split4 / Gregory. From ``split4.KERNEL_FACES`` faces the split4 build runs numba kernels;
  ``--numpy`` also times one build on its NumPy reference path (kernels off), in the same run;
* build peak: the tracemalloc peak of one more build over the memory held before it, per quad
  (DESIGN §5 bar: 1 KB; issue 13: 2 KB). The split4 network alone is ~2.3 KB per quad: its
  controls 4 × 16 × 3 doubles = 1.5 KB, four (4, 4) int64 connectivity arrays per quad 0.5 KB,
  points and normals at vertices, midpoints and centres 0.2 KB;
* with ``--check``: ``continuity.check`` of the split4 network (4 sub-patches per quad).

Load averages (1, 5, 15 min) are printed before and after: the machine is shared, compare ratios.
Issue 13's targets: split4 build ≤ 6 s and ≤ 2 KB per quad at 1 M quads.

Run:  .venv/bin/python benchmarks/bench_split4.py [--quads N] [--repeats R] [--numpy] [--check]
"""

from __future__ import annotations

import argparse
import functools
import os
import platform
import resource
import statistics
from collections.abc import Callable

import numpy as np
from bench_build import timed, traced  # the same timing and tracing helpers, from beside this file

from g1patch import shapes
from g1patch.build import build_gregory_network, build_split4_network
from g1patch.construct import split4
from g1patch.continuity import check
from g1patch.memory import tune_for_large_arrays
from g1patch.mesh import QuadMesh, subdivide
from g1patch.network import PatchNetwork

BUILDERS: dict[str, Callable[[QuadMesh], PatchNetwork]] = {
    "split4": build_split4_network,
    "gregory": build_gregory_network,
}


def irregular_mesh(quads: int) -> QuadMesh:
    """A torus with three diagonal collapses (two corners of a quad merged), subdivided to ≥ ``quads``."""
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quads", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--numpy",
        action="store_true",
        help="also time one split4 build on the NumPy path (kernels off)",
    )
    parser.add_argument(
        "--check", action="store_true", help="also run continuity.check on the split4 network"
    )
    args = parser.parse_args()
    tune_for_large_arrays()  # as the command line does (g1patch.memory)

    mesh = irregular_mesh(args.quads)
    topology = mesh.topology
    interior = ~topology.is_boundary_vertex
    valences = np.unique(topology.valence[interior], return_counts=True)
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    )
    print(
        f"mesh: {topology.n_faces:,} quads, {topology.n_vertices:,} vertices; interior valences "
        + ", ".join(f"{v}×{c}" for v, c in zip(*valences, strict=True))
    )

    print("load average before: " + ", ".join(f"{x:.2f}" for x in os.getloadavg()))
    times: dict[str, float] = {}
    for name, builder in BUILDERS.items():
        build = functools.partial(builder, mesh)
        first = timed(build)[0]
        runs = [timed(build)[0] for _ in range(args.repeats)]
        times[name] = statistics.median(runs)
        _, peak, network = traced(build)
        print(
            f"{name:8s} build {times[name]:6.2f} s (median of {args.repeats}; runs "
            + ", ".join(f"{r:.2f}" for r in runs)
            + f"; first {first:.2f})  peak {peak / 2**20:7.0f} MiB = "
            f"{peak / topology.n_faces:6.0f} B/quad  patches {network.n_patches:,}"
        )
        del network
    print(f"ratio split4 / gregory: {times['split4'] / times['gregory']:.2f}")
    if args.numpy:
        kernel_faces, split4.KERNEL_FACES = split4.KERNEL_FACES, topology.n_faces + 1
        try:
            seconds = timed(lambda: build_split4_network(mesh))[0]
        finally:
            split4.KERNEL_FACES = kernel_faces
        print(
            f"split4 NumPy path (kernels off) {seconds:.2f} s: kernels {seconds / times['split4']:.1f}x faster"
        )
    print("load average after: " + ", ".join(f"{x:.2f}" for x in os.getloadavg()))

    if args.check:
        network = build_split4_network(mesh)
        seconds, report = timed(lambda: check(network))
        print(
            f"check split4: {seconds:.1f} s, max G1 {report.max_edge_angle_deg:.2e}°, corners "
            f"{report.max_corner_angle_deg:.2e}°, G0 {report.max_g0_gap:.1e}, vertex deviation "
            f"{report.max_vertex_deviation:.1e}, folds {report.folds}"
        )
    print(
        f"process peak (ru_maxrss): {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**10:.0f} MiB"
    )


if __name__ == "__main__":
    main()
