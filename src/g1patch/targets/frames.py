"""Vertex normals and second fundamental forms for surfaces that interpolate a quad mesh's vertices.

**Start.** The area-weighted fan normal ``N_A = normalize(Σ d_i × d_{i+1})`` over consecutive
ring edges ``d_i = x_i − A`` (:func:`g1patch.targets.local.fan_normals`).

**Ring repair.** ``N`` is *valid* at A when the ring edges projected on its plane go once around
it counter-clockwise: every ``N·(d_i × d_{i+1}) > 0`` (the sign of the projected pair's 2-D cross
product, since ``N·(a × b)`` ignores the components along N) and the turning angles
``atan2(N·(d_i × d_{i+1}), (P d_i)·(P d_{i+1}))`` sum to 2π (to less than 2π on a boundary
vertex, whose open fan has no pair between the last and the first neighbour). Where the fan
normal is invalid we try ``normalize(Σ u_i × u_{i+1})`` with unit edge directions ``u_i``, then
the max–min normal ``argmax_{|N|=1} min_i N·ĉ_i`` of the unit corner normals ``ĉ_i`` (the
direction of the point of their convex hull nearest the origin, by Gilbert's algorithm); the
first valid one is used and ``repaired`` set. If neither is valid the fan normal stays.

**Circle-aware fit** (shape-quality.md §3.1). In the frame (e1, e2, N) at A, each point p of the
face 2-ring has coordinates (x, y, z) of p − A, r² = x² + y². A circle through A tangent to the
plane, of curvature k in the direction x̂ = (x, y)/r, satisfies x̂-section ``r² + z² = 2z/k``, i.e.
``z = ½ k (r² + z²) = ½ (1 + z²/r²) k r²``; with ``k r² = (x, y) H (x, y)ᵀ`` the fit is linear:

    z = g1 x + g2 y + ½ (1 + z²/r²)(h11 x² + 2 h12 xy + h22 y²)
        + (c1 x³ + 3c2 x²y + 3c3 xy² + c4 y³)/6

by weighted least squares, ``w = exp(−r²/(2 h̄²))``, h̄² the mean squared projected length of the
ring edges; the cubic only with ≥ 12 points, else the face 1-ring without it. Then
``N ← normalize(N − g1 e1 − g2 e2)``, 3 times, a vertex stopping early once its slope ``|g|`` <
``STOP`` = 1e-14 (the further refits would move N by about that: at 1 M torus quads the slopes
are ≤ 9e-10, 6e-15, 3e-16, so 2 fits). On a sphere of radius ρ (outward normal n, frame
normal N with n = (a, b, c) in the frame) ``|q + ρn|² = ρ²`` gives exactly
``z = −(a/c) x − (b/c) y − (r² + z²)/(2ρc)``: the model holds with C = 0, so one step is exact at
any resolution (the cube's corners included). Elsewhere N is O(h³) and H O(h²).

**Shape operator.** ``S = −P E H Eᵀ P`` (E = [e1 e2] of the last fit, P = I − N Nᵀ): S = dN, so the
unit sphere with outward normals has S = I − N Nᵀ and principal curvatures are positive on convex
parts. Note the sign: a parametric surface has ``N·X_ab = −aᵀ S b``.

**Reliability switch.** The fit is used (``fitted``) only at interior vertices (a boundary
vertex sees its surface from one side only, and its fitted normal tilted 10–20° off the fan
normal on OpenSubdiv's boundary fans and folded the surface there) and only where all of these
hold; elsewhere the
(repaired) fan normal stays and S comes from the same circle fit with N fixed (3 unknowns h, face
1-ring), which is exact for spheres too when N is exact:

* ``RESIDUAL``: weighted RMS fit residual ≤ 0.05 h̄. Measured (ellipsoid = cube_sphere scaled by
  (1, 0.7, 0.5); tori R = 2, r = 0.7 and R = 1, r = 0.25): 96-quad ellipsoid ≤ 0.054 (98 % pass;
  fit error ≤ 1.2° against the fan's 5.5°), 24×12 tori ≤ 0.050 (pass); 24-quad ellipsoid ≥ 0.059
  and 12×6 tori ≥ 0.11 are rejected: there the fit is off by 4–6° while the (symmetric) fan
  normal is exact. With 8 % noise the 24-quad ellipsoid is rejected (fit 2–4× worse than the
  fan), the 96-quad one passes at 72–88 %; a 0.08 bar let 12–15 % of the coarse noisy vertices in
  and raised their worst error from 3.9° to 5.5°.
* ``MAX_TILT``: the fitted normal within 25° of the start normal. Largest tilt measured: 6° on the
  smooth 96-quad ellipsoid, 9° (96 quads) and 14° (24 quads) with 8 % noise.
* the fitted normal is valid (ring goes once around CCW) and every ring edge is less than
  ``MAX_STEEPNESS`` = 60° from its plane (the diagnosis: quads with a steeper edge fold 27 % of
  the time).
* ``MIN_PIVOT``: each of the 5 unknowns g, h is determined: sin² of the angle of its column to
  the span of *all* the other columns, ``1 / (G_jj (G⁻¹)_jj)`` of the scaled normal equations
  G, is ≥ 1e-3. The hub of a split n-gon fails it: its 2-ring lies on one circle r = ρ, where
  ``x r² = x³ + xy²`` makes the slope column a combination of cubic ones, and the fit tilted a
  1000-gon's centre normal by 20° (the fan normal is exact there). Measured on the meshes above
  and the shared ones, no other vertex changes (a test against the earlier, sequential pivot
  rejected nothing). In the pivot-dropping Cholesky of the normal equations, cubic columns whose
  pivot (sin² of the angle to the earlier columns) is below 1e-10 are dropped (coefficient 0).

**Evaluation.** The fits run in a numba kernel
(:func:`~g1patch.targets.frame_kernels._fit_kernel`, compiled on first use and cached on disk;
numba is imported only then): every vertex goes through the one-vertex sequence of operations,
:data:`~g1patch.targets.frame_kernels.LANES` vertices side by side so that the inner loops
vectorise, with the neighbourhoods in scipy's order, so the sums are the same; the ring checks and
fan normals are kernels too. The NumPy reference (``vertex_frames(mesh, compiled=False)``,
:mod:`g1patch.targets.frame_fit`) sorts the vertices by neighbourhood size and fits padded blocks;
the two agree to rounding (normals within 256 ε, S within 2¹⁴ ε of its largest entry, the same
masks: tests/test_frames.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..kernels import in_chunks, jit_kernel, use_kernels
from ..mesh import QuadMesh
from .frame_fit import CUBIC_POINTS, _face_rings, _Fit, _fit_all, _Ring
from .frame_kernels import LANES, _fit_kernel, _ring_kernel, _rows_kernel, _symmetric_kernel
from .local import fan_normals

__all__ = ["VertexFrames", "vertex_frames", "RESIDUAL", "MAX_TILT", "MAX_STEEPNESS", "MIN_PIVOT"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

RESIDUAL = 0.05  #: largest weighted RMS fit residual, in units of h̄
MAX_TILT = 25.0  #: largest angle (degrees) between fitted and start normal
MAX_STEEPNESS = 60.0  #: largest angle (degrees) between a ring edge and the tangent plane
MIN_PIVOT = 1e-3  #: smallest determination (sin² to the other columns) of the g, h unknowns


@dataclass(frozen=True)
class VertexFrames:
    """Per-vertex unit normals, shape operators S (``II(a, b) = aᵀ S b``, ``S N = 0``) and flags."""

    normals: FloatArray  # (V, 3) unit
    shape_operator: FloatArray  # (V, 3, 3) symmetric
    fitted: BoolArray  # (V,) the circle-aware fit was trusted and used
    repaired: BoolArray  # (V,) the start normal was replaced so that the ring goes once around it


def _ring_checks(
    mesh: QuadMesh, normals: FloatArray, vertices: IntArray
) -> tuple[BoolArray, FloatArray]:
    """:func:`_ring_kernel`: validity and steepness of ``normals`` at ``vertices``."""
    topo = mesh.topology
    valid = np.empty(vertices.size, dtype=bool)
    steepness = np.empty(vertices.size)
    jit_kernel(_ring_kernel)(
        mesh.vertices,
        topo.neighbor_offsets,
        topo.neighbors,
        topo.face_count,
        topo.is_boundary_vertex,
        normals,
        vertices,
        valid,
        steepness,
    )
    return valid, steepness


def _face_ring_rows(mesh: QuadMesh) -> tuple[IntArray, NDArray[np.int32]]:
    """The rows of ``I Iᵀ`` as CSR (offsets, int32 points), by :func:`_rows_kernel`."""
    topo = mesh.topology
    offsets = np.zeros(mesh.n_vertices + 1, dtype=np.int64)
    kernel = jit_kernel(_rows_kernel)
    in_chunks(
        lambda lo, hi: kernel(
            topo.faces,
            topo.ring_offsets,
            topo.ring_halfedges,
            offsets,
            np.empty(0, dtype=np.int32),
            False,
            lo,
            hi,
        ),
        mesh.n_vertices,
    )
    np.cumsum(offsets, out=offsets)
    points = np.empty(int(offsets[-1]), dtype=np.int32)
    in_chunks(
        lambda lo, hi: kernel(
            topo.faces, topo.ring_offsets, topo.ring_halfedges, offsets, points, True, lo, hi
        ),
        mesh.n_vertices,
    )
    return offsets, points


def _fit_compiled(
    mesh: QuadMesh,
    rows: tuple[IntArray, NDArray[np.int32]],
    vertices: IntArray,
    n: FloatArray,
    tilt: bool,
) -> _Fit:
    """:func:`_fit_kernel` of ``vertices`` (row i for ``vertices[i]``) with start normals ``n`` (V,
    3), in ranges of rows side by side (:func:`~g1patch.kernels.in_chunks`)."""
    topo = mesh.topology
    out = _Fit.empty(vertices.size)
    kernel = jit_kernel(_fit_kernel)
    in_chunks(
        lambda lo, hi: kernel(
            mesh.vertices,
            rows[0],
            rows[1],
            topo.neighbor_offsets,
            topo.neighbors,
            vertices[lo:hi],
            n,
            tilt,
            LANES,
            out.normals[lo:hi],
            out.shape_operator[lo:hi],
            out.residual[lo:hi],
            out.pivot[lo:hi],
        ),
        vertices.size,
    )
    return out


def vertex_frames(mesh: QuadMesh, *, compiled: bool = True) -> VertexFrames:
    """Unit normals and shape operators at the vertices of ``mesh``: repaired fan normal,
    circle-aware fit where trusted, else the fan normal with the fixed-normal circle fit of S
    (module doc).

    ``compiled`` runs the fits and ring checks in numba kernels (:func:`_fit_kernel`,
    :func:`_ring_kernel`); ``False`` runs the NumPy reference (the same to rounding,
    tests/test_frames.py).
    """
    compiled = use_kernels(compiled)  # NumPy where kernels cannot be cached
    nv = mesh.n_vertices
    everything = np.arange(nv)
    ring = None if compiled else _Ring.of(mesh)
    start = fan_normals(mesh, compiled=compiled)
    repaired = np.zeros(nv, dtype=bool)
    bad = np.flatnonzero(
        ~(_ring_checks(mesh, start, everything)[0] if ring is None else ring.valid(start))
    )
    if bad.size:
        ring = ring or _Ring.of(mesh)
        start, done = ring.repair(start, bad)
        repaired[bad[done]] = True

    with np.errstate(invalid="ignore", divide="ignore"):
        if compiled:
            rows = _face_ring_rows(mesh)
            fit = _fit_compiled(mesh, rows, everything, start, True)
            normals, shape_operator, residual, pivot = (
                fit.normals,
                fit.shape_operator,
                fit.residual,
                fit.pivot,
            )
        else:
            assert ring is not None  # the reference made it above
            one, two = _face_rings(mesh)
            normals = np.empty((nv, 3))
            shape_operator = np.empty((nv, 3, 3))
            residual = np.empty(nv)
            pivot = np.empty(nv)
            large = two.sizes >= CUBIC_POINTS
            for hood, cubic in ((two, True), (one, False)):
                vertices = np.flatnonzero(large == cubic)
                fit = _fit_all(mesh, ring, hood, vertices, start, cubic, True)
                normals[vertices], shape_operator[vertices], residual[vertices], pivot[vertices] = (
                    fit.normals,
                    fit.shape_operator,
                    fit.residual,
                    fit.pivot,
                )
        fitted = (
            ~mesh.topology.is_boundary_vertex  # a one-sided neighbourhood extrapolates the normal
            & np.isfinite(normals).all(axis=1)
            & np.isfinite(shape_operator).all(axis=(1, 2))
            & (residual <= RESIDUAL)
            & (pivot >= MIN_PIVOT)
            & (np.einsum("vd,vd->v", normals, start) >= np.cos(np.radians(MAX_TILT)))
        )
        if compiled:
            candidates = np.flatnonzero(fitted)
            valid, steepness = _ring_checks(mesh, normals, candidates)
            fitted[candidates] = valid & (steepness <= np.sin(np.radians(MAX_STEEPNESS)))
        else:
            assert ring is not None
            fitted &= ring.steepness(normals) <= np.sin(np.radians(MAX_STEEPNESS))
            fitted &= ring.valid(np.where(fitted[:, None], normals, start))
        rest = np.flatnonzero(~fitted)
        normals[rest] = start[rest]
        if rest.size:
            if compiled:
                held = _fit_compiled(mesh, rows, rest, start, False)
            else:
                assert ring is not None
                held = _fit_all(mesh, ring, one, rest, start, False, False)
            shape_operator[rest] = np.nan_to_num(held.shape_operator)
    if compiled:
        jit_kernel(_symmetric_kernel)(shape_operator)
    else:
        shape_operator = 0.5 * (shape_operator + shape_operator.transpose(0, 2, 1))
    return VertexFrames(normals, shape_operator, fitted, repaired)
