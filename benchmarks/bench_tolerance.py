"""The limit shapes' tolerance: Catmull–Clark steps, patches, time and memory per tolerance.

``build_network(mesh, method, "limit", tolerance=t)`` on the shared meshes (and on
``shapes.genus2()`` refined, a cage of valences 3–5 that needs no shared data), for t in
``--tolerances`` and both exact methods. Columns: the steps the tolerance loop added, the
patches, the distance reached (``g1patch.fidelity.limit_distance``: exact limit samples projected
on the network, of the diagonal; ``*`` where the loop stopped short: six steps at most, or the
memory budget), the hanging edges, the wall time of the build (measure included) and its
tracemalloc peak. Gregory networks refine only where they are off the limit or touch a
semi-sharp crease (hanging edges between levels); split4 refines globally, 4× the patches a
step. The distance halves per step around extraordinary vertices.

Run:  .venv/bin/python benchmarks/bench_tolerance.py [--tolerances T ...] [--meshes NAME ...]
      [--quick]
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from functools import partial

import harness

from g1patch import shapes
from g1patch.build import build_network
from g1patch.io.meshfile import read_mesh
from g1patch.memory import tune_for_large_arrays
from g1patch.mesh import QuadMesh
from g1patch.subdivision import refine

record = harness.recorder("bench_tolerance")

OPTIONS: dict[str, harness.Option] = {
    "tolerances": ([1e-2, 3e-3, 1e-3, 3e-4, 1e-4], "tolerances, of the diagonal"),
    "meshes": (
        [
            "catmark_cube",
            "catmark_xord_interior",
            "catmark_xord_boundary",
            "catmark_dart_edgecorner",
            "catmark_torus_creases0",
            "catmark_tent_creases1",
            "spot_quadrangulated",
        ],
        "shared meshes",
    ),
}
QUICK = {"tolerances": [1e-2, 1e-3], "meshes": ["catmark_xord_boundary"]}
METHODS = ("gregory", "split4")


def cages(names: Sequence[str]) -> list[tuple[str, QuadMesh]]:
    found = [("genus2 refined 2×", refine(shapes.genus2(), 2))]
    for name in names:
        path = harness.SHARED / f"{name}.obj"
        if path.is_file():
            found.append((name, read_mesh(path)))
        else:
            print(f"{name}: skipped, not found at {path}")
    return found


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    tune_for_large_arrays()
    logging.disable(logging.INFO)
    print(harness.machine_line() + "\n")
    build_network(shapes.genus2(), "split4", "limit")  # warm-up: numba loads its kernels
    build_network(shapes.genus2(), "gregory", "limit")
    header = f"{'cage':<26}{'method':<9}{'tolerance':>10}{'steps':>6}{'patches':>10}"
    print(header + f"{'hanging':>9}{'distance':>12}{'build s':>9}{'peak MB':>9}")
    for name, mesh in cages(args.meshes):
        for method in METHODS:
            for tolerance in args.tolerances:
                build = partial(build_network, mesh, method, "limit", tolerance=tolerance)
                seconds, network = harness.timed(build)
                peak = harness.peak(build)
                provenance = network.provenance
                distance = float(provenance["limit_distance"])
                short = "*" if "tolerance_stop" in provenance else " "
                steps = int(provenance["tolerance_steps"])
                hanging = len(network.hanging) if network.hanging is not None else 0
                print(
                    f"{name:<26}{method:<9}{tolerance:>10.0e}{steps:>6}{network.n_patches:>10,}"
                    f"{hanging:>9,}{distance:>11.2e}{short}{seconds:>9.2f}{peak / 1e6:>9.0f}"
                )
                label = f"{name} {method} tolerance {tolerance:g}"
                record(f"{label} steps", steps, "")
                record(f"{label} patches", network.n_patches, "")
                record(f"{label} hanging edges", hanging, "")
                record(f"{label} distance", distance, "of diagonal", short.strip() and "stopped")
                record(f"{label} build", seconds, "s")
                record(f"{label} peak", peak / 1e6, "MB", "tracemalloc")


if __name__ == "__main__":
    main()
