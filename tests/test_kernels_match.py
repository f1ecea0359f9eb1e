"""The numba kernels of the default build against the NumPy code they replace (kept as the
reference).

Each kernel does the same arithmetic in the same order one vertex, slot, face or edge at a time,
so the two agree to rounding: ≤ 1e-12 relative to each array's largest entry (measured: equal,
or a few ε), and every flag and mask is the same. The meshes: closed and open, valences 3–24,
boundary fans, creases, and vertex noise that makes the fans irregular (the k-h fit of the
assembly, the fan safeguard and the fold guard's risk test all take part).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from exactness import height, perturbed

from g1patch import shapes
from g1patch.construct.gregory import assemble_gregory, tangent_plane_tangents
from g1patch.mesh import QuadMesh
from g1patch.targets.interpolate import interpolate_targets
from g1patch.targets.local import fan_normals

RTOL = 1e-12

MESHES: dict[str, Callable[[], QuadMesh]] = {
    "torus": lambda: shapes.torus(24, 12),
    "noisy torus": lambda: perturbed(shapes.torus(16, 8), 0.05, 1),
    "noisy sphere": lambda: shapes.noisy_sphere(2),
    "cube": shapes.cube,
    "grid": lambda: perturbed(shapes.grid(6, 5, height=height), 0.05, 2),
    "fan 12": lambda: perturbed(shapes.fan(12, 2), 0.05, 3),
    "fan 24": lambda: shapes.fan(24, 1),
    "boundary fan": lambda: perturbed(shapes.boundary_fan(5), 0.05, 4),
    "flat fan": lambda: shapes.flat_fan(17),
    "genus 2": shapes.genus2,
    "filleted box": shapes.filleted_box,
    "slotted block": shapes.slotted_block,
}


def assert_close(fast: np.ndarray, reference: np.ndarray) -> None:
    assert fast.shape == reference.shape and fast.dtype == reference.dtype
    if fast.dtype == bool or fast.dtype.kind == "i":
        np.testing.assert_array_equal(fast, reference)
        return
    scale = max(float(np.abs(reference).max(initial=0.0)), np.finfo(np.float64).tiny)
    assert np.abs(fast - reference).max(initial=0.0) <= RTOL * scale


@pytest.fixture(params=list(MESHES), scope="module")
def mesh(request: pytest.FixtureRequest) -> QuadMesh:
    return MESHES[request.param]()


def test_fan_normals(mesh: QuadMesh) -> None:
    assert_close(fan_normals(mesh), fan_normals(mesh, compiled=False))


def test_assembly(mesh: QuadMesh) -> None:
    targets = interpolate_targets(mesh)
    assert_close(tangent_plane_tangents(targets), tangent_plane_tangents(targets, compiled=False))
    assert_close(assemble_gregory(targets).points, assemble_gregory(targets, compiled=False).points)


def test_assembly_of_a_random_fan_takes_the_kh_fit() -> None:
    """Targets far from C1 (random fans and twists): nearly every edge takes the k-h fit."""
    mesh = perturbed(shapes.torus(12, 6), 0.05, 7)
    targets = interpolate_targets(mesh)
    rng = np.random.default_rng(8)
    scale = rng.uniform(0.7, 1.4, len(targets.tangents))[:, None]
    interior = targets.interior + rng.normal(0.0, 0.01, targets.interior.shape)
    shaken = targets.with_changes(tangents=targets.tangents * scale, interior=interior)
    assert_close(assemble_gregory(shaken).points, assemble_gregory(shaken, compiled=False).points)


def test_targets_kernels(mesh: QuadMesh) -> None:
    """Projected tangents, their turn along smooth mesh lines, fan validity (on the raw fans, valid
    or not), interior targets with and without the shape operator, and the coarse-face turn."""
    from g1patch.kernels import jit_kernel
    from g1patch.targets import fans, interior, interpolate
    from g1patch.targets.frames import vertex_frames

    frames = vertex_frames(mesh)
    topology, n = mesh.topology, frames.normals
    fast, reference = (
        interpolate._projected_tangents(mesh, n),
        interpolate._projected_tangents(mesh, n, compiled=False),
    )
    for a, b in zip(fast, reference, strict=True):
        assert_close(a, b)
    raw = fast[0]
    lines = interpolate._along_smooth_lines(mesh, n, raw, compiled=False)
    assert_close(interpolate._along_smooth_lines(mesh, n, raw), lines)
    in_place = raw.copy()
    assert interpolate._along_smooth_lines(mesh, n, in_place, out=in_place) is in_place
    assert_close(in_place, lines)
    twisted = raw * np.where(np.arange(len(raw)) % 3 == 0, -1.0, 1.0)[:, None]  # folded fans fail
    for t in (raw, twisted):
        assert_close(
            fans._valid_fans(topology, n, t),
            fans._valid_fans(topology, n, t, compiled=False),
        )
    for s in (frames.shape_operator, None):
        assert_close(
            interpolate._interior_targets(topology, mesh.vertices, raw, n, s),
            interpolate._interior_targets(topology, mesh.vertices, raw, n, s, compiled=False),
        )
    corner_normals = n[topology.faces]
    turn = np.empty(mesh.n_faces)
    jit_kernel(interior._turn_kernel)(corner_normals, turn)
    cosine = np.einsum("fkd,fkd->fk", corner_normals, np.roll(corner_normals, -1, axis=1))
    assert_close(turn, np.arccos(np.clip(cosine, -1.0, 1.0)).max(axis=1))


def test_slot_tables(mesh: QuadMesh) -> None:
    from g1patch.targets import halfedge_slots
    from g1patch.targets.local import slot_tables

    for a, b in zip(slot_tables(mesh.topology), halfedge_slots(mesh.topology), strict=True):
        assert_close(a.astype(np.int64), b)


def test_faces_at_risk(mesh: QuadMesh) -> None:
    """The fold guard's risk test picks the same faces (also with fallbacks and shaken tangents)."""
    from g1patch.build import _faces_at_risk

    targets = interpolate_targets(mesh)
    rng = np.random.default_rng(9)
    shaken = targets.with_changes(
        tangents=targets.tangents * rng.uniform(0.4, 1.8, len(targets.tangents))[:, None],
        fallback=rng.random(mesh.n_vertices) < 0.05,
    )
    for t in (targets, shaken):
        assert_close(_faces_at_risk(t), _faces_at_risk(t, compiled=False))


def test_numpy_twins_of_the_uncached_path(mesh: QuadMesh, monkeypatch: pytest.MonkeyPatch) -> None:
    """Where kernels cannot be cached, the slot tables, the in-plane tangents and the coarse-face
    turn come from NumPy twins: the same values."""
    from g1patch.targets import interior, local
    from g1patch.targets.frames import vertex_frames

    topology, n = mesh.topology, vertex_frames(mesh).normals
    raw = np.random.default_rng(10).normal(size=(int(topology.neighbor_offsets[-1]), 3))
    corner_normals = n[topology.faces]
    compiled = (
        local.slot_tables(topology),
        local.in_vertex_planes(raw, n, topology.neighbor_offsets),
        interior.edge_turns(corner_normals),
    )
    for module in (local, interior):
        monkeypatch.setattr(module, "use_kernels", lambda wanted: False)
    twins = (
        local.slot_tables(topology),
        local.in_vertex_planes(raw, n, topology.neighbor_offsets),
        interior.edge_turns(corner_normals),
    )
    for fast, reference in zip(compiled[0], twins[0], strict=True):
        assert_close(fast, reference)
    assert_close(compiled[1], twins[1])
    assert_close(compiled[2], twins[2])
