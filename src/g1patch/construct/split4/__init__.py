"""Exact G1 with polynomial patches only: the 2×2-split bicubic network (polynomial-g1.md).

Every quad f is split at its edge midpoints M and its centre C into four bicubic Bézier
sub-patches; sub-patch ``4 f + k`` sits at corner k. Inside the quad the four pieces join C1,
so each quad is one bicubic B-spline patch with knots ``[0,0,0,0,½,½,1,1,1,1]`` in u and v
(:func:`bspline_nets`). On every refined edge (half mesh edge V–M or seam M–C) from S to E with
sub-patches P, Q on either side the symmetric G1 form

    D_P(t) + D_Q(t) = Φ(t) c'(t),   Φ(0) = λ_S,  Φ(1) = −λ_E                          (G1)

holds, λ being the star coefficient of the end vertex for that edge (``t_left + t_right = λ t``).
In Bézier coefficients (``δ_k`` cross row − curve point, ``d_k`` curve differences) it is

    δP_0 + δQ_0 = λ_S d_0,   δP_1 + δQ_1 = (2 Φ0 d_1 + Φ1 d_0)/3,   and the mirror at E,

so G1 is a star plus a twist system at every refined vertex:

* original vertex v: a star ``t_{j−1} + t_{j+1} = λ_j t_j`` per slot (λ_j = 2 c_j), half-edge points
  ``P1 = v + T/6``; twists ``F_{j−1} + F_j = R_j`` with
  ``R_j = 2 P1_j + (2 λ_j (P2_j − P1_j) − m_j (P1_j − v))/3``, ``m_j = λ(M_j → v)``. Where that
  twist system has compatibility conditions (even valence: valence 4 and ≥ 6 below) the star is
  regular (one λ_v); on the boundary and at odd valence any fan whose sectors have equal areas
  will do (the re-assembly of a Gregory network takes the nearest to its fan,
  :func:`.stars._equal_area_fans`; a build the regular star);
* midpoint M of edge X → Y: sheared star ``t_L + t_R = μ t_X`` (μ = λ(M → X), λ(M → Y) = −μ),
  compatible iff ``D (5 μ + c_X − c_Y) = 2 μ (P1 − P5)`` for ``D = P2 − P4``
  (:func:`.reference._edge_curves`);
* centre C: a plain cross (λ = 0), so every seam is C1.

Even-valence twist cycles are singular: at valence 4 they need equal λ from opposite ring
edges, so μ is carried along grid lines (:func:`.chains._chain_shears`); at even valence ≥ 6 they
need ``Σ_j (−1)^j P2_j = Σ_j (−1)^j m_j t_j / (6 λ_v)``, met by moving whole midpoints
(:func:`.systems._even_vertex_shifts`). Every twist is the minimum-norm change of its target
(below) that solves its vertex system (a pseudo-inverse per system size; a mesh vertex's ring
relative to the vertex: near k ≈ n/2 the cycle's eigenvalues 1 + ω^k are small and the
pseudo-inverse amplifies its right-hand side's rounding ~n/π, which is then of the ring's size,
not of the model's). Work is done in centred, unit-scaled coordinates and mapped back.

Shape: the assembly moves the targets only as far as G1 requires (DESIGN §1). Each face's targets
are one bicubic (corners, slot tangents, :attr:`~g1patch.targets.Targets.corner_interior`,
:func:`.nets.target_nets`), subdivided at ½ into a 7×7 net (or a ``guide`` net instead). The free
choices take that net's *detail over what its boundary predicts*, added to what the split curves
predict (:data:`.nets._QUANTITIES`): the centre ``ΣM/2 − ΣV/4 + (C° − ΣM°/2 + ΣV/4)``, the cross
arms over ``(M_k − M_{k+2})/6``, the seam tangents at M over ``C − M`` (their star gap ``t_L + t_R
− μ t_X`` split equally), and every twist target the parallelogram of its three neighbours plus the
net's twist offset. So where the star, the shear or an even-valence shift moves a curve point, the
interior moves with it and keeps the targets' shape; where the split curves are the targets' own (a
C1 bicubic B-spline with μ = 0: a regular torus under ``limit``) the targets are reproduced, the
min-norm twist changes vanish and each quad is one bicubic. The star length safeguard stays
everywhere: a star longer than it allows (B-spline tangents on a strongly graded cage, a 1 : 4 box)
is shrunk, and a face with a shrunk corner takes the net's detail scaled by the smallest factor (its
curves are that much shorter than the net's).

From :data:`.threshold.KERNEL_FACES` faces on, the stars, the grid-line shears, the assembly and
the network's connectivity run in numba kernels (:func:`.compiled._compiled_patches`: the curves
edge by edge, the net's quantities and the centre face by face, the midpoint stars and twists edge
by edge, the ring twists vertex by vertex, the centre twists face by face, each writing straight
into the controls; ranges side by side, :func:`~g1patch.kernels.in_chunks`), so a large build makes
no (4F, ·, 3) temporaries. The NumPy code is the reference
(:func:`.reference._reference_patches`): the same formulas, batched; the two agree to rounding
(tests/test_split4_kernels.py: points within 16 ε · max|x|).

The pipeline, one module a step (each imports only the ones above it):

* :mod:`.threshold`: from how many faces the kernels run;
* :mod:`.nets`: the 7×7 macro net of a quad, the targets' bicubic, what the free choices take over;
* :mod:`.stars`: the stars at the mesh vertices (regular, rim, equal-sector fans; the safeguard);
* :mod:`.chains`: the shears along grid lines;
* :mod:`.systems`: the G1 systems and their minimum-norm solutions, the even-valence shifts;
* :mod:`.reference` and :mod:`.compiled`: the sub-patches, in NumPy and in numba kernels;
* :mod:`.assembly`: :func:`split4_patches`, the stars, the shears, then either of the two;
* :mod:`.network`: the sub-patches' connectivity and the network, from targets or from parts.
"""

from __future__ import annotations

from .assembly import Split4Parts, split4_patches
from .chains import _chain_shears as _chain_shears
from .nets import _HALVE as _HALVE
from .nets import BSPLINE_KNOTS, bspline_nets, macro_nets, target_nets
from .network import _split4_network as _split4_network
from .network import (
    split4_network_from_parts,
    split4_network_from_points,
    split4_network_from_targets,
    split4_provenance,
)
from .stars import STAR_LENGTH_LIMIT, FanWalk, SplitStar, edge_end_cosines, fan_walk, split4_star

__all__ = [
    "BSPLINE_KNOTS",
    "STAR_LENGTH_LIMIT",
    "FanWalk",
    "Split4Parts",
    "SplitStar",
    "bspline_nets",
    "edge_end_cosines",
    "fan_walk",
    "macro_nets",
    "split4_network_from_parts",
    "split4_network_from_points",
    "split4_network_from_targets",
    "split4_patches",
    "split4_provenance",
    "split4_star",
    "target_nets",
]
