"""The numba kernels of the smooth vertices' limit stencils (:mod:`g1patch.subdivision.stencils`):
the same terms added in the same order as the NumPy code, so the same floats. Compiled by
:func:`~g1patch.kernels.jit_kernel` on first use.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


def _positions_kernel(
    x: FloatArray,
    faces: IntArray,
    ring_offsets: IntArray,
    ring_halfedges: IntArray,
    smooth: BoolArray,
    points: FloatArray,
) -> None:
    """``points[v] = (n² V + 4ΣE_i + ΣD_i)/(n(n + 5))`` at the smooth vertices, the sums in
    half-edge order as :func:`_segment_sum` adds them (the ring sorted), so the values are the
    reference's."""
    order = np.empty(max(1, int(np.max(ring_offsets[1:] - ring_offsets[:-1]))), dtype=np.int64)
    for v in range(smooth.size):
        if not smooth[v]:
            continue
        r0 = ring_offsets[v]
        k = ring_offsets[v + 1] - r0
        for i in range(k):  # insertion sort: rings are short
            h = ring_halfedges[r0 + i]
            j = i
            while j > 0 and order[j - 1] > h:
                order[j] = order[j - 1]
                j -= 1
            order[j] = h
        n0 = n1 = n2 = o0 = o1 = o2 = 0.0
        for i in range(k):
            h = order[i]
            f, c = h >> 2, h & 3
            e, d = faces[f, (c + 1) & 3], faces[f, (c + 2) & 3]
            n0 += x[e, 0]
            n1 += x[e, 1]
            n2 += x[e, 2]
            o0 += x[d, 0]
            o1 += x[d, 1]
            o2 += x[d, 2]
        n = float(k)
        scale = n * (n + 5.0)
        points[v, 0] = (n * n * x[v, 0] + 4.0 * n0 + o0) / scale
        points[v, 1] = (n * n * x[v, 1] + 4.0 * n1 + o1) / scale
        points[v, 2] = (n * n * x[v, 2] + 4.0 * n2 + o2) / scale


def _stars_kernel(
    x: FloatArray,
    faces: IntArray,
    ring_offsets: IntArray,
    ring_halfedges: IntArray,
    offsets: IntArray,
    smooth: BoolArray,
    start_of: IntArray,
    weights: FloatArray,
    rotation: FloatArray,
    a: FloatArray,
    b: FloatArray,
    tangents: FloatArray,
) -> None:
    """At each smooth vertex the stars ``A = Σ w_E,i E_i + w_D,i D_i`` (``weights[0:2]``), B
    (``weights[2:4]``), in ring order as :func:`_segment_sum` adds them, and slot j's tangent
    ``cos φ_j A + sin φ_j B`` (``rotation``); the tables' row for valence n, entry i, is
    ``start_of[n] + i``."""
    for v in range(smooth.size):
        if not smooth[v]:
            continue
        r0 = ring_offsets[v]
        k = ring_offsets[v + 1] - r0
        base = start_of[k]
        a0 = a1 = a2 = b0 = b1 = b2 = 0.0
        for i in range(k):
            h = ring_halfedges[r0 + i]
            f, c = h >> 2, h & 3
            e, d = faces[f, (c + 1) & 3], faces[f, (c + 2) & 3]
            ea, da, eb, db = (
                weights[0, base + i],
                weights[1, base + i],
                weights[2, base + i],
                weights[3, base + i],
            )
            a0 += ea * x[e, 0] + da * x[d, 0]
            a1 += ea * x[e, 1] + da * x[d, 1]
            a2 += ea * x[e, 2] + da * x[d, 2]
            b0 += eb * x[e, 0] + db * x[d, 0]
            b1 += eb * x[e, 1] + db * x[d, 1]
            b2 += eb * x[e, 2] + db * x[d, 2]
        a[v, 0], a[v, 1], a[v, 2] = a0, a1, a2
        b[v, 0], b[v, 1], b[v, 2] = b0, b1, b2
        s0 = offsets[v]
        for j in range(k):
            cj, sj = rotation[0, base + j], rotation[1, base + j]
            tangents[s0 + j, 0] = cj * a0 + sj * b0
            tangents[s0 + j, 1] = cj * a1 + sj * b1
            tangents[s0 + j, 2] = cj * a2 + sj * b2
