"""The default shape on artist cages (issue 31, item 1): folds against the Catmull–Clark limit's,
the 99th-percentile normal turn against the faired limit-interpolating surface's, and build time.

The cages in ``benchmarks/cages`` were made by a box-modelling script for this purpose (a cow, a
troll, a quadruped, a bird, a car and the same with support loops, pawns of valence 8–16, slabs,
spikes, n-gons, jittered boxes: coarse, unequal edges, thin parts). For each cage and method:

* ``default``: ``build`` as a user runs it (interpolate), its folds (``check``), its p99 turn,
  the vertices it gives the faired surface's targets (``faired_vertices``) and those it moves
  off to mend a fold (``relaxed_vertices``), and its build time;
* ``limit``: the Catmull–Clark limit's folds (the default tolerance);
* ``limit-interpolate`` at one patch per face (no tolerance steps), the same patches as the
  default, so their p99 turns compare: the bar is ``default ≤ 1.1 × limit-interpolate``.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path

import harness

from g1patch.build import build_network
from g1patch.continuity import check
from g1patch.io.meshfile import read_mesh

record = harness.recorder("bench_cages")
CAGES = Path(__file__).resolve().parent / "cages"
METHODS = ("split4", "gregory")

#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "cages": (sorted(path.stem for path in CAGES.glob("*.obj")), "cages in benchmarks/cages")
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"cages": ["coarsearm", "lshape"]}


def one_cage(name: str) -> None:
    """One table row per method."""
    mesh = read_mesh(CAGES / f"{name}.obj")
    for method in METHODS:
        start = time.perf_counter()
        default = build_network(mesh, method)
        seconds = time.perf_counter() - start
        ours = check(default)
        faired = check(build_network(mesh, method, "limit-interpolate", tolerance=None))
        limit = check(build_network(mesh, method, "limit"))
        ratio = ours.turn_p99_deg / faired.turn_p99_deg
        provenance = default.provenance
        moved = int(provenance.get("relaxed_vertices", "0"))
        shaped = int(provenance.get("faired_vertices", "0"))
        key = f"{name} {method}"
        record(f"{key} default folds", ours.folds, "", f"limit: {limit.folds}")
        record(f"{key} limit folds", limit.folds, "")
        record(f"{key} p99 turn / limit-interpolate", ratio, "×", "bar ≤ 1.1")
        record(f"{key} faired vertices", shaped, "")
        record(f"{key} relaxed vertices", moved, "")
        record(f"{key} build", seconds, "s")
        print(
            f"{name:11s} {method:8s} {mesh.n_faces:6d} {ours.folds:6d} {limit.folds:6d} "
            f"{ratio:7.2f} {shaped:7d} {moved:7d} {seconds:7.2f}"
        )


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    print(
        f"{'cage':11s} {'method':8s} {'faces':>6s} {'folds':>6s} {'limit':>6s} {'p99/LI':>7s} "
        f"{'faired':>7s} {'moved':>7s} {'build s':>7s}"
    )
    for name in args.cages:
        one_cage(name)


if __name__ == "__main__":
    main()
