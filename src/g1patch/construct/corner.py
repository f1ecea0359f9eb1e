"""The paper's construction: one bicubic Hermite patch per quad, G1 at every corner.

Skala's eq. (13): all patches sharing a corner get tangents orthogonal to one vertex normal n,

    n^T p_u^i = 0,   n^T p_v^i = 0      for every patch i at the corner,

so their tangent planes agree there. Corner tangents are the mesh edges projected onto the
tangent plane, ``T_{A→w} = d − (n·d) n`` with ``d = x_w − x_A``, rescaled to a chosen length.
Shared boundary curves are built from the same data on both sides, so they are identical.
Along edges the cross-boundary tangents of the two patches differ: the surface creases there.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import NDArray

from ..errors import check_choice
from ..mesh import QuadMesh
from ..network import PatchNetwork, network_from_mesh
from ..patches import PatchSet, hs_twists
from ..targets.local import (
    NORMALS,
    NormalRule,
    TangentRule,
    corner_tangents,
    fan_normals,
    least_squares_normals,
)

if TYPE_CHECKING:
    from ..targets import Targets

__all__ = ["TWISTS", "TwistRule", "assemble_corner", "build_corner_network"]

TwistRule = Literal["zero", "bilinear", "coons"]
TWISTS: tuple[TwistRule, ...] = ("zero", "bilinear", "coons")


def _hermite_corners(
    x: NDArray[np.float64], to_next: NDArray[np.float64], to_prev: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Hermite control (F, 4, 4, 3) with the corner points ``x`` (F, 4, 3) and tangents set by the
    table of :func:`build_corner_network` from ``T(k → k+1)``, ``T(k → k−1)``; zero twists."""
    control = np.zeros((len(x), 4, 4, 3))
    control[:, 0, 0], control[:, 1, 0], control[:, 1, 1], control[:, 0, 1] = (
        x[:, 0],
        x[:, 1],
        x[:, 2],
        x[:, 3],
    )
    control[:, 2, 0], control[:, 0, 2] = to_next[:, 0], to_prev[:, 0]  # corner (0,0)
    control[:, 3, 0], control[:, 1, 2] = -to_prev[:, 1], to_next[:, 1]  # corner (1,0)
    control[:, 3, 1], control[:, 1, 3] = -to_next[:, 2], -to_prev[:, 2]  # corner (1,1)
    control[:, 2, 1], control[:, 0, 3] = to_prev[:, 3], -to_next[:, 3]  # corner (0,1)
    return control


def build_corner_network(
    mesh: QuadMesh,
    *,
    tangents: TangentRule = "arc",
    twist: TwistRule = "bilinear",
    normals: NormalRule = "fan",
) -> PatchNetwork:
    """One Hermite patch per quad with the corner conditions of eq. (13), as a PatchNetwork.

    Face corners c0..c3 (CCW), ``T(i→j)`` the corner tangent from c_i towards c_j:

        p_u(0,0) =  T(0→1)   p_v(0,0) =  T(0→3)
        p_u(1,0) = −T(1→0)   p_v(1,0) =  T(1→2)
        p_u(1,1) = −T(2→3)   p_v(1,1) = −T(2→1)
        p_u(0,1) =  T(3→2)   p_v(0,1) = −T(3→0)

    Twists: ``zero``; ``bilinear`` ``x0 − x1 + x2 − x3`` at every corner; ``coons`` the S-/HS rule.
    """
    check_choice("twist", twist, TWISTS)
    check_choice("normals", normals, NORMALS)
    vertex_normals = fan_normals(mesh) if normals == "fan" else least_squares_normals(mesh)
    faces = mesh.faces
    x = mesh.vertices[faces]  # (F, 4, 3)
    n = vertex_normals[faces]
    next_edges = np.stack([faces, np.roll(faces, -1, axis=1)], axis=-1)
    prev_edges = np.stack([faces, np.roll(faces, 1, axis=1)], axis=-1)
    to_next = corner_tangents(x, np.roll(x, -1, axis=1), n, tangents, next_edges)  # T(k → k+1)
    to_prev = corner_tangents(x, np.roll(x, 1, axis=1), n, tangents, prev_edges)  # T(k → k−1)

    control = _hermite_corners(x, to_next, to_prev)
    if twist == "bilinear":
        control[:, 2:, 2:] = (x[:, 0] - x[:, 1] + x[:, 2] - x[:, 3])[:, None, None]
    elif twist == "coons":
        control[:, 2:, 2:] = hs_twists(control)
    provenance = {"method": "corner", "tangents": tangents, "twist": twist, "normals": normals}
    if mesh.source:
        provenance["source"] = str(mesh.source)
    return network_from_mesh(
        mesh.topology, PatchSet(control, "hermite"), mesh.vertices, fan_normals(mesh), provenance
    )


def assemble_corner(targets: Targets) -> PatchSet:
    """The paper's patches from any targets: one Hermite patch per quad, G1 at corners only.

    Corner tangents are the target tangents (⊥ the target normal, eq. 13); the twist at corner k
    is read off the interior target ``Ft = A + (t_AB + t_AD)/3 + w/9`` as ``w = 9 (Ft − A) − 3 (t_AB
    + t_AD)``, in the corner's own frame (u along A → B, v along A → D), which is ``±p_uv`` (+ at
    corners 0 and 2, − at 1 and 3, where one axis runs backwards).
    """
    from ..targets import halfedge_slots
    from .gregory import tangent_plane_tangents

    topology = targets.topology
    count = topology.n_faces
    t = tangent_plane_tangents(targets)
    slot_out, slot_in = halfedge_slots(topology)
    prev = topology.prev(np.arange(4 * count))
    to_next = t[slot_out].reshape(count, 4, 3)  # T(k → k+1)
    to_prev = t[slot_in[prev]].reshape(count, 4, 3)  # T(k → k−1)
    x = targets.positions[topology.faces]
    w = 9.0 * (targets.corner_interior - x) - 3.0 * (to_next + to_prev)
    control = _hermite_corners(x, to_next, to_prev)
    control[:, 2, 2], control[:, 3, 2], control[:, 3, 3], control[:, 2, 3] = (
        w[:, 0],
        -w[:, 1],
        w[:, 2],
        -w[:, 3],
    )
    return PatchSet(control, "hermite")
