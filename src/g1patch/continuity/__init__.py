"""How smooth is a patch network? G0 gaps and G1 angles on every shared edge and corner, folds,
fairness.

For every interior edge shared by patches L and R the edge is sampled at K ≥ 33 parameters,
both ends included, from both sides; exact first derivatives give the normals
``n = p_u × p_v`` and the G1 angle is ``atan2(|n_L × n_R|, n_L · n_R)`` (accurate near 0, where
arccos floors at ~1e-6°). The G0 gap is ``|p_L − p_R|``, reported relative to the bounding-box
diagonal. Corners: the angle between the normals of every pair of patches meeting at a point
within one sector (:meth:`PatchNetwork.corner_sectors`: the patches a walk around the point
reaches without crossing a seam).

**Seams** (``network.seam``: edges sharp on purpose) are only meant to be G0. They are measured
like every shared edge but reported apart: their number, their largest G0 gap and the range
(min, max over all their samples) of the angle between the two sides' normals. They never count
as G1 failures or folds; a G0 gap above :data:`SEAM_G0_RTOL` on a seam still fails the check.

On a ``G × G`` grid of every patch (``G = fold_samples``, both borders included):

* degenerate normals: ``|p_u × p_v| ≤ degenerate_rtol · diag²`` (collapsed edges);
* degenerate patches: every grid sample's normal degenerate (no area), or more than one collapsed
  edge (one is an intended triangular patch, as the teapot's poles); they fail the check;
* folds (intrinsic, DESIGN §4): a patch is folded where two neighbouring samples (along u or v)
  have normals more than 90° apart (``n_a · n_b < 0``), or where a sample of a corner's grid cell
  has its normal against the normal at that corner; both patches of a shared edge are folded
  where their normals at one point of the edge are more than 90° apart (G1 angle > 90°: the
  surface turns back across the edge), unless the edge is a seam. Degenerate normals are skipped;
* fairness: the normal turn ``θ = 2 asin(|n̂_a − n̂_b| / 2)`` between neighbouring samples (median,
  p99, max over all pairs of all patches) and the thin-plate energy
  ``∫∫ |p_uu|² + 2|p_uv|² + |p_vv|² du dv = ∫∫ |∇p_u|² + |∇p_v|² du dv`` (``p_uv = p_vu``), summed
  over the patches and divided by diag².

**Evaluation.** From :data:`KERNEL_PATCHES` patches on (``compiled=None``, the default; ``True``
always) numba kernels do the work, compiled on first use and cached on disk (see "Compiled
kernels" below): one parallel pass over the shared edges (both
sides of each), one over the corner sectors and one over the patches' grids, several patches at a
time. ``compiled=False`` runs the NumPy reference, block by block. The two agree exactly on
counts, folds, their locations, the turn figures, and within a few ULP on angles, gaps and energy
(tests/test_check_kernels.py states and tests the bounds).

Everything is measured in the patches' local coordinates (``patches.local()`` when the patch set
has a frame; a frame-free set whose corners' box is far from size 1 or from the origin, as a
``.bpt`` 1e-25 or 1e25 in size, in the frame of that box, :func:`g1patch.network.unit_frame`):
angles do not depend on the frame, gaps and deviations are relative to the diagonal, so the
figures are the same wherever the model sits and whatever its size.

**Modules.** :mod:`.checker` runs the check (:func:`check`) and :mod:`.report` holds its result
(:class:`ContinuityReport`); :mod:`.edges` measures shared edges and corners, :mod:`.grid` the
grid of every patch (degenerate normals, folds, fairness: :func:`fairness`), :mod:`.folds` says
which patches fold and where (:func:`folded_patches`); :mod:`.sampling`, :mod:`.vectors` and
:mod:`.turns` are what they build on. :mod:`.jit` compiles the numba kernels of
:mod:`.edge_kernels`, :mod:`.corner_kernels` and :mod:`.grid_kernels`.
"""

# the public names; the documented constants (``X as X``: re-exported; to change one, as a test
# does, set it in its module); the private names that render and the viewer import from here
from .checker import check
from .edges import _edge_measures as _edge_measures
from .edges import _hanging_measures as _hanging_measures
from .folds import folded_patches, folds_and_bend
from .grid import DEGENERATE_RTOL as DEGENERATE_RTOL
from .grid import EXACT_TURN_CANDIDATES as EXACT_TURN_CANDIDATES
from .grid import FOLD_SAMPLES as FOLD_SAMPLES
from .grid import MAX_FOLD_LOCATIONS as MAX_FOLD_LOCATIONS
from .grid import TENSOR_TURN_ATOL as TENSOR_TURN_ATOL
from .grid import fairness
from .jit import KERNEL_PATCHES as KERNEL_PATCHES
from .report import EXACT_G1_DEG, SEAM_G0_RTOL, ContinuityReport, format_reports
from .sampling import _blocks as _blocks
from .sampling import _box as _box
from .sampling import _diagonal as _diagonal
from .sampling import _local as _local
from .vectors import _cross3 as _cross3
from .vectors import _norm3 as _norm3
from .vectors import _planar as _planar
from .vectors import angle_between

__all__ = [
    "EXACT_G1_DEG",
    "SEAM_G0_RTOL",
    "ContinuityReport",
    "check",
    "fairness",
    "folded_patches",
    "folds_and_bend",
    "angle_between",
    "format_reports",
]
