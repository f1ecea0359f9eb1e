"""split4's assembly, the front door: the stars, the shears along grid lines, then the sub-patches
by the NumPy reference (:mod:`~g1patch.construct.split4.reference`) or the numba passes
(:mod:`~g1patch.construct.split4.compiled`), from
:data:`~g1patch.construct.split4.threshold.KERNEL_FACES` faces on.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...errors import InputError
from ...patches import PatchSet
from ...targets import Targets
from .chains import _chain_shears
from .compiled import _compiled_patches
from .reference import SplitInputs, _reference_patches
from .stars import SplitStar, edge_end_cosines, split4_star
from .threshold import use_kernels

__all__ = ["Split4Parts", "split4_patches"]

FloatArray = NDArray[np.float64]

#: what :func:`split4_patches` returns: sub-patches, edge-midpoint and centre positions, their
#: normals, the stars
Split4Parts = tuple[PatchSet, FloatArray, FloatArray, SplitStar]


def split4_patches(
    targets: Targets,
    corners: FloatArray,
    centre: FloatArray,
    scale: float,
    guide: FloatArray | None = None,
    star: SplitStar | None = None,
    *,
    compiled: bool | None = None,
) -> Split4Parts:
    """The 4 F Bézier sub-patches (sub-patch ``4 f + k`` at corner k of face f), and the positions
    and unit surface normals of the edge midpoints and face centres, each stacked as (E + F, 3).
    The normal at M is ``t_L × t_X`` (⊥ the curve and seam tangents of its star); at C it is ``(b_0
    − b_2) × (b_1 − b_3)``, the cross of the centre's star. Also returns the star
    (:func:`split4_star`: which vertices were refitted or shrunk).

    ``targets`` are in local coordinates ``(x − centre) / scale``; the sub-patches are mapped
    back and their corners at mesh vertices set to ``corners`` (the input positions, (V, 3))
    exactly.

    ``guide`` (F, 7, 7, 3), local coordinates: a macro net per face
    (:func:`~g1patch.construct.split4.nets.macro_nets`) whose interior the split should follow
    instead of the targets' bicubic, e.g. a fit of another surface
    (:mod:`g1patch.construct.polynomial`): its detail over its own boundary is taken
    (:mod:`g1patch.construct.split4`, "Shape"), and the min-norm G1 corrections move it only as far
    as G1 requires. ``star``: the vertex stars to use instead of :func:`split4_star`'s (regular per
    vertex, each ``c_v`` its angle step's cosine). ``compiled``: by the numba kernels
    (:func:`~g1patch.construct.split4.compiled._compiled_patches`, item by item into the controls,
    ranges side by side), else the NumPy reference
    (:func:`~g1patch.construct.split4.reference._reference_patches`); default from
    :data:`~g1patch.construct.split4.threshold.KERNEL_FACES` faces on. The two agree to rounding
    (tests/test_split4_kernels.py).
    """
    if guide is not None and np.shape(guide) != (targets.topology.n_faces, 7, 7, 3):
        raise InputError(
            f"guide: expected shape ({targets.topology.n_faces}, 7, 7, 3), got {np.shape(guide)}"
        )
    topology = targets.topology
    compiled = use_kernels(topology.n_faces, compiled)
    stars = split4_star(targets, compiled=compiled) if star is None else star
    ends = edge_end_cosines(topology, stars.cosine)  # (E, 2): c at X and at Y
    mu = _chain_shears(topology, ends, compiled=compiled)
    assemble = _compiled_patches if compiled else _reference_patches
    control, extra, extra_normals = assemble(
        SplitInputs(targets, guide, stars, ends, mu, corners, centre, scale)
    )
    return PatchSet(control.reshape(-1, 4, 4, 3)), extra, extra_normals, stars
