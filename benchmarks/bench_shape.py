"""Shape quality: accuracy and its order on smooth shapes; folds and fairness on real meshes.

Methods (rows), all built by ``g1patch.build.build_network(mesh, method, shape)``:

* ``default``  gregory, shape "interpolate" (the new default targets);
* ``split4``   split4, shape "interpolate";
* ``corner``   corner (the paper: G1 at corners only), shape "interpolate";
* ``legacy``   gregory, shape "legacy" (the previous default), the baseline.

With ``--legacy`` every method uses shape "legacy". Without ``g1patch.build`` (older trees) every
method is built by ``g1patch.cli.build_network(mesh, method)``, which is the legacy shape.

Table 1, refinement families (``g1patch.shapes``; h halves from one level to the next):
sphere_quads 0..4 (6…1536 quads, radial distance from the unit sphere), ellipsoid_quads 1..4,
torus_quads 12×6 … 96×48 (R = 2, r = 0.7), icosa_ellipsoid 0..2 (60…960 quads), each against the
exact surface (closest points from ``shapes.*_project``) on 20 grid steps per face
(``compare.patch_samples``): max distance, its order ``log2(e_prev / e)``, max normal error (°)
and its order, folds and max G1 angle (``continuity.check``). DESIGN §5 bar: order ≈ 4 (position),
≥ 3 (normal).

Table 2, the shared meshes (``../shared/data``; skipped with a message when absent): folds, max
G1 angle (edges and corners), p99 normal turn between neighbouring samples, the same for the
Catmull–Clark limit (``reference/NAME.limit.npz``, sampled at the same step:
``compare.compare_fairness``) and their ratio (DESIGN §5 bar: ≤ 1.5 interpolating), and the max
distance of the surface (4 grid steps per face) from that limit, relative to the bounding-box
diagonal.

``--quick`` keeps the meshes of table 1 up to 400 quads and table 2's cube and torus.

Run:  .venv/bin/python benchmarks/bench_shape.py [--legacy] [--no-shared] [--max-quads N]
      [--meshes NAME ...] [--quick]
"""

from __future__ import annotations

import importlib.util
import math
from collections.abc import Callable, Sequence
from functools import partial

import harness

from g1patch import compare, shapes
from g1patch.continuity import check
from g1patch.errors import G1PatchError
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh
from g1patch.network import PatchNetwork

Builder = Callable[[QuadMesh], PatchNetwork]
Measure = Callable[[PatchNetwork, int], compare.Deviation]

record = harness.recorder("bench_shape")
#: grid steps per mesh face for the distances to the exact surfaces (21 × 21 samples per face)
FAMILY_STEPS = 20
#: grid steps per mesh face for the distance to the Catmull–Clark limit
LIMIT_STEPS = 4
ELLIPSOID_AXES = (1.0, 0.7, 0.5)


def builders(legacy: bool) -> tuple[dict[str, Builder], str]:
    """The methods to compare, and a line saying which builder makes them."""
    if importlib.util.find_spec("g1patch.build") is None:
        from g1patch.cli import build_network as cli_build  # type: ignore[attr-defined]

        old: dict[str, Builder] = {
            f"{method}·legacy": partial(cli_build, method=method)
            for method in ("gregory", "split4", "corner")
        }
        return old, (
            "builder: g1patch.cli.build_network (g1patch.build not found; legacy shape for every "
            "method)"
        )
    from g1patch.build import build_network

    rows: dict[str, Builder]
    if legacy:
        rows = {
            f"{method}·legacy": partial(build_network, method=method, shape="legacy")
            for method in ("gregory", "split4", "corner")
        }
        return rows, (
            "builder: g1patch.build.build_network, shape 'legacy' for every method (--legacy)"
        )
    rows = {
        "default": partial(build_network, method="gregory", shape="interpolate"),
        "split4": partial(build_network, method="split4", shape="interpolate"),
        "corner": partial(build_network, method="corner", shape="interpolate"),
        "legacy": partial(build_network, method="gregory", shape="legacy"),
    }
    return rows, (
        "builder: g1patch.build.build_network (default = gregory/interpolate, legacy = "
        "gregory/legacy)"
    )


def order(previous: float | None, current: float) -> float | None:
    """``log2(previous / current)``; None at the first level or when either is zero."""
    if previous is None or previous <= 0 or current <= 0:
        return None
    return math.log2(previous / current)


def shown(value: float | None) -> str:
    """An order as text, '-' for None."""
    return "-" if value is None else f"{value:.2f}"


def family_table(
    family: str,
    title: str,
    meshes: Sequence[tuple[str, QuadMesh]],
    measure: Measure,
    methods: dict[str, Builder],
) -> None:
    """One refinement family against its exact surface (table 1)."""
    print(f"\n{family} {title}")
    print(
        f"{'method':<16}{'level':>8}{'quads':>7}{'max dist':>11}{'order':>7}{'normal°':>10}"
        f"{'order':>7}{'folds':>7}{'max G1°':>10}"
    )
    for name, build in methods.items():
        last_distance = last_normal = None
        for label, mesh in meshes:
            try:
                network = build(mesh)
            except G1PatchError as error:
                print(f"{name:<16}{label:>8}{mesh.n_faces:>7}  refused: {error}")
                last_distance = last_normal = None
                continue
            found = measure(network, compare.patch_samples(network, FAMILY_STEPS))
            report = check(network)
            g1 = max(report.max_edge_angle_deg, report.max_corner_angle_deg)
            distance, normal = found.max_distance, found.max_normal_error_deg
            distance_order, normal_order = (
                order(last_distance, distance),
                order(last_normal, normal),
            )
            print(
                f"{name:<16}{label:>8}{mesh.n_faces:>7}{distance:>11.2e}{shown(distance_order):>7}"
                f"{normal:>10.3g}{shown(normal_order):>7}{report.folds:>7}{g1:>10.1e}"
            )
            key = f"{family} {label} {name}"
            record(f"{key} max distance", distance, "", f"{mesh.n_faces} quads")
            record(f"{key} distance order", distance_order, "", "DESIGN bar ≈ 4")
            record(f"{key} max normal error", normal, "°")
            record(f"{key} normal order", normal_order, "", "DESIGN bar ≥ 3")
            record(f"{key} folds", report.folds, "")
            record(f"{key} max G1 angle", g1, "°")
            last_distance, last_normal = distance, normal


def families(methods: dict[str, Builder], max_quads: int) -> None:
    """Table 1 (module docstring), meshes of at most ``max_quads`` quads."""

    def small(meshes: list[tuple[str, QuadMesh]]) -> list[tuple[str, QuadMesh]]:
        return [(label, mesh) for label, mesh in meshes if mesh.n_faces <= max_quads]

    to_ellipsoid = partial(compare.distance_to_ellipsoid, axes=ELLIPSOID_AXES)
    family_table(
        "sphere_quads",
        "(cube split 2×2 and projected each time) — radial distance from the unit sphere",
        small([(str(level), shapes.sphere_quads(level)) for level in range(5)]),
        lambda network, samples: compare.distance_to_sphere(network, samples=samples),
        methods,
    )
    family_table(
        "ellipsoid_quads",
        f"axes {ELLIPSOID_AXES} — distance from the ellipsoid",
        small([(str(n), shapes.ellipsoid_quads(n, ELLIPSOID_AXES)) for n in range(1, 5)]),
        lambda network, samples: to_ellipsoid(network, samples=samples),
        methods,
    )
    family_table(
        "torus_quads",
        "R = 2, r = 0.7 — distance from the torus",
        small([(f"{n}×{n // 2}", shapes.torus_quads(n, n // 2)) for n in (12, 24, 48, 96)]),
        lambda network, samples: compare.distance_to_torus(network, 2.0, 0.7, samples=samples),
        methods,
    )
    family_table(
        "icosa_ellipsoid",
        f"(icosahedron → 3 quads per triangle), axes {ELLIPSOID_AXES} — distance from the "
        "ellipsoid",
        small([(str(n), shapes.icosa_ellipsoid(n, ELLIPSOID_AXES)) for n in range(3)]),
        lambda network, samples: to_ellipsoid(network, samples=samples),
        methods,
    )


def shared_row(name: str, method: str, network: PatchNetwork, reference: compare.Reference) -> None:
    """One row of table 2."""
    report = check(network)
    fairness = compare.compare_fairness(network, reference)
    positions, _ = compare.surface_samples(network, compare.patch_samples(network, LIMIT_STEPS))
    distance = (
        compare.mesh_distance(positions, reference.points, reference.faces).max()
        / reference.bounding_box_diagonal
    )
    g1 = max(report.max_edge_angle_deg, report.max_corner_angle_deg)
    ours, limit = fairness.network["p99"], fairness.reference["p99"]
    print(
        f"{name:<24}{method:<16}{network.n_patches:>8}{report.folds:>7}{g1:>10.1e}{ours:>11.2f}"
        f"{limit:>9.2f}{fairness.p99_ratio:>7.2f}{distance:>10.1e}"
    )
    key = f"{name} {method}"
    record(f"{key} folds", report.folds, "")
    record(f"{key} max G1 angle", g1, "°")
    record(f"{key} p99 turn", ours, "°", f"Catmull–Clark limit {limit:.2f}°")
    record(f"{key} p99 turn / limit", fairness.p99_ratio, "×", "bar ≤ 1.5 interpolating")
    record(f"{key} distance to limit", distance, "of diagonal")


def shared_meshes(methods: dict[str, Builder], meshes: Sequence[str]) -> None:
    """Table 2 (module docstring)."""
    print(
        "\nshared meshes — fairness against the Catmull–Clark limit (bar: p99 ratio ≤ 1.5 "
        "interpolating)"
    )
    if not harness.SHARED.is_dir():
        print(f"skipped: {harness.SHARED} not found (../shared/data beside the repository)")
        return
    print(
        f"{'mesh':<24}{'method':<16}{'patches':>8}{'folds':>7}{'max G1°':>10}{'p99 turn°':>11}"
        f"{'CC p99°':>9}{'ratio':>7}{'dist CC':>10}"
    )
    for name in meshes:
        path = harness.SHARED / f"{name}.obj"
        reference_file = compare.reference_path(path)
        if not path.is_file() or not reference_file.is_file():
            print(f"{name:<24}skipped: {path.name} or {reference_file.name} not found")
            continue
        mesh, reference = read_mesh(path), compare.load_reference(reference_file)
        for method, build in methods.items():
            try:
                network = build(mesh)
            except G1PatchError as error:
                print(f"{name:<24}{method:<16}  refused: {error}")
                continue
            shared_row(name, method, network, reference)


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "legacy": (False, "build every method with the legacy (previous default) shape"),
    "no_shared": (False, "skip the shared meshes"),
    "max_quads": (10**9, "largest mesh of table 1"),
    "meshes": (list(harness.SHARED_MESHES), "shared meshes of table 2"),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"max_quads": 400, "meshes": ["catmark_cube", "catmark_torus"]}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    methods, note = builders(args.legacy)
    print(note)
    seconds, _ = harness.timed(lambda: families(methods, args.max_quads))
    if not args.no_shared:
        seconds += harness.timed(lambda: shared_meshes(methods, args.meshes))[0]
    print(f"\n{seconds:.0f} s")


if __name__ == "__main__":
    main()
