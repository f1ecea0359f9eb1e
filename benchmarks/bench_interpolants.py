"""How much any fair surface through a cage's vertices turns, against its Catmull–Clark limit.

Issues 9 and 10 ask an interpolating surface (``interpolate``, ``limit-interpolate``) for a p99
normal turn at most 1.5× that of the Catmull–Clark limit of the same mesh taken as a cage. This
benchmark measures that ratio, and the median's, for every interpolating construction at hand, on
every shared mesh with a reference (``../shared/data/reference/NAME.limit.npz``) and no crease tags:

* ``interpolate``: the default shape rules (:mod:`g1patch.targets.interpolate`);
* ``limit-interpolate``: Halstead–Kass–DeRose's square solve, the cage whose limit points are the
  vertices (:mod:`g1patch.targets.limit_interpolate`);
* ``faired L``: HKD's fair variant, written here: the cage refined once is free, the limit points
  of the original vertices are held at the mesh's vertices (``A C₁ = V``, rows of the refined
  cage's limit stencil), and ``‖D S C₁‖²`` is minimised, D the umbrella Laplacian (the boundary's
  own second difference on boundary vertices) of that cage refined L more times (S: those L
  Catmull–Clark steps, exact columns by linearity). One KKT solve; the network is the ``limit``
  shape of the faired cage (4 patches per face).

All built with the Gregory assembly. Columns: the network's median / p99 / max normal turn over
the reference's on grids of the same step (``compare.compare_fairness``), the largest distance of
a mesh vertex from the point the surface passes through for it (of the diagonal; 0 by
construction for the first two, the KKT solve's residual for the faired ones), and the folds.
Bars: p99 ≤ 1.5× (issues 9, 10). A construction whose median is already 1.5× the limit's can meet
the p99 bar only by turning more evenly than the limit itself. ``--quick``: the cube alone.

Run:  .venv/bin/python benchmarks/bench_interpolants.py [--meshes NAME ...] [--quick]
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import harness
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

from g1patch import compare
from g1patch.build import build_network
from g1patch.continuity import check
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh
from g1patch.network import PatchNetwork
from g1patch.subdivision import catmull_clark_points, limit_matrix, limit_points, refine

record = harness.recorder("bench_interpolants")
#: extra Catmull–Clark steps of the faired cage the fairness energy is measured on
FAIRED_LEVELS = (0, 1, 2)
#: largest refined cage the dense-by-columns step operator S is formed for
MAX_FAIRED_VERTICES = 5_000


def umbrella(mesh: QuadMesh) -> sp.csr_matrix:
    """``(L x)_v = mean of v's neighbours − x_v``; on a boundary vertex over its two boundary
    neighbours only."""
    topology = mesh.topology
    a, b = topology.edges.T
    along, boundary = topology.is_boundary_edge, topology.is_boundary_vertex
    use = np.concatenate(
        [~boundary[a] | along, ~boundary[b] | along]
    )  # a boundary vertex: its boundary edges only
    rows, columns = np.concatenate([a, b])[use], np.concatenate([b, a])[use]
    adjacency = sp.csr_matrix((np.ones(rows.size), (rows, columns)), shape=(mesh.n_vertices,) * 2)
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    return sp.diags(1.0 / degree) @ adjacency - sp.identity(mesh.n_vertices)


def step_operator(cage: QuadMesh, levels: int) -> sp.csr_matrix:
    """S with ``refine(cage, levels).vertices == S @ cage.vertices``: Catmull–Clark is linear in
    the positions, so column i is the refined positions' change when vertex i moves (one step at
    a time)."""
    matrix = sp.identity(cage.n_vertices, format="csr")
    mesh = cage
    for _ in range(levels):
        base = catmull_clark_points(mesh)[:, 0]
        columns = []
        for i in range(mesh.n_vertices):
            moved = mesh.vertices.copy()
            moved[i, 0] += 1.0
            change = catmull_clark_points(mesh.with_vertices(moved))[:, 0] - base
            change[np.abs(change) < 1e-14] = 0.0
            columns.append(sp.csc_matrix(change[:, None]))
        matrix = sp.hstack(columns).tocsr() @ matrix
        mesh = refine(mesh)
    return matrix


def faired_cage(mesh: QuadMesh, levels: int) -> QuadMesh:
    """The once-refined cage whose limit passes through ``mesh``'s vertices with the least
    ``‖D S C₁‖²`` (module docstring), by one KKT solve."""
    cage = refine(mesh)
    count = cage.n_vertices
    held = limit_matrix(cage)[: mesh.n_vertices]  # refinement keeps the vertices first, in order
    energy = umbrella(refine(cage, levels) if levels else cage) @ step_operator(cage, levels)
    kkt = sp.bmat([[energy.T @ energy, held.T], [held, None]]).tocsc()
    solution = spsolve(kkt, np.vstack([np.zeros((count, 3)), mesh.vertices]))
    return cage.with_vertices(solution[:count])


def row(
    mesh: str,
    name: str,
    network: PatchNetwork,
    reference: compare.Reference,
    refined: int,
    vertex_error: float,
) -> str:
    """One table row: the turn ratios on grids of the reference's step, the vertex error, the
    folds; recorded too."""
    fairness = compare.compare_fairness(
        network, dataclasses.replace(reference, levels=reference.levels - refined)
    )
    ratio = {
        key: fairness.network[key] / fairness.reference[key] for key in ("median", "p99", "max")
    }
    folds = check(network).folds
    for key, value in ratio.items():
        record(f"{mesh} {name} {key} turn / limit", value, "×", "bar ≤ 1.5" if key == "p99" else "")
    record(f"{mesh} {name} vertex error", vertex_error, "of diagonal")
    record(f"{mesh} {name} folds", folds, "")
    return (
        f"  {name:22s} {ratio['median']:7.2f} {ratio['p99']:7.2f} {ratio['max']:7.2f} "
        f"{vertex_error:10.1e} {folds:6d}"
    )


def one_mesh(name: str, mesh: QuadMesh, reference: compare.Reference) -> None:
    """The table of one mesh: every construction through its vertices."""
    print(
        f"{name} ({mesh.n_faces} faces)\n  {'construction':22s} {'median':>7s} {'p99':>7s} "
        f"{'max':>7s} {'vertex':>10s} {'folds':>6s}"
    )
    for shape in ("interpolate", "limit-interpolate"):
        print(row(name, shape, build_network(mesh, shape=shape), reference, 0, 0.0))
    for levels in FAIRED_LEVELS:
        if levels and refine(mesh).n_vertices > MAX_FAIRED_VERTICES:
            continue  # S by columns: one Catmull–Clark step per cage vertex
        cage = faired_cage(mesh, levels)
        moved = limit_points(cage)[: mesh.n_vertices] - mesh.vertices
        error = float(np.linalg.norm(moved, axis=1).max()) / mesh.bounding_box_diagonal
        network = build_network(cage, shape="limit")
        print(row(name, f"faired {levels}", network, reference, 1, error))


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {"meshes": (list(harness.SHARED_MESHES), "shared meshes")}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"meshes": ["catmark_cube"]}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    print(
        "median / p99 / max normal turn over the Catmull–Clark limit's; vertex = largest "
        "distance of a mesh vertex from the point the surface passes through for it, of the "
        "diagonal (bar for the p99: ≤ 1.5)"
    )
    for name in args.meshes:
        path = harness.SHARED / f"{name}.obj"
        reference_path = harness.SHARED / "reference" / f"{name}.limit.npz"
        if not (path.exists() and reference_path.exists()):
            print(f"{name}: skipped ({harness.SHARED} has no such mesh or reference)")
            continue
        one_mesh(name, read_mesh(path), compare.load_reference(reference_path))


if __name__ == "__main__":
    main()
