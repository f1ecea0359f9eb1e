"""What is checked before anything reaches OpenCASCADE, and after sewing.

OCC segfaults (it does not raise) on some inputs that look harmless, so every input is checked
first (the bounds and rules are in :mod:`g1patch.io.cad`): coordinates finite and at most
:data:`MAX_COORDINATE`, a positive bounding box, clamped cubic knot vectors, no face smaller than
OCC can sew (:data:`MIN_FACE_EXTENT`, :data:`MIN_FACE_SEWING`). Each violation is an
:class:`InputError` naming the output file and the patch; a face the sewing dropped anyway is an
:class:`OpenCascadeError`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import InputError
from ...frame import Frame
from ...patches import PatchSet
from .bspline import BSplineFit
from .opencascade import OpenCascadeError

#: largest |coordinate| (world units) handed to OpenCASCADE: the network file's bound
MAX_COORDINATE = 1e30
#: smallest extent (control-net bounding-box diagonal, model units) of a face handed to
#: OpenCASCADE: 100 × its fixed ``Precision::Confusion()`` (1e-7); smaller faces are sewn away
MIN_FACE_EXTENT = 1e-5
#: smallest extent of a face relative to the sewing tolerance (which would sew it away)
MIN_FACE_SEWING = 10.0


def _bound_message(value: float) -> str:
    what = (
        "is not a number"
        if np.isnan(value)
        else "is infinite"
        if np.isinf(value)
        else f"reaches magnitude {abs(value):.3g}"
    )
    limit = f"finite coordinates of magnitude at most {MAX_COORDINATE:g}"
    return f"{what}; OpenCASCADE export needs {limit}"


def _check_patch_coordinates(target: Path, patches: object) -> None:
    """Polynomial and Gregory patches: world coordinates finite and within :data:`MAX_COORDINATE`
    (``|c| + s·max|x|`` with a frame, in Python floats: no overflow warning); other patches are
    checked on their fitted poles."""
    data = patches.control if isinstance(patches, PatchSet) else getattr(patches, "points", None)
    if not isinstance(data, np.ndarray) or data.dtype.kind != "f" or not data.size:
        return
    low, high = float(data.min()), float(data.max())
    largest = max(-low, high) if low == low and high == high else float("nan")
    frame = getattr(patches, "frame", None)
    if isinstance(frame, Frame):
        largest = float(np.abs(frame.centre).max()) + frame.scale * largest
    if not largest <= MAX_COORDINATE:
        raise InputError(
            f"{target}: cannot export: the largest of the patches' coordinates "
            f"{_bound_message(largest)}"
        )


def _check_diagonal(target: Path, diagonal: float) -> None:
    if not (np.isfinite(diagonal) and diagonal > 0):
        what = "0: all patch corners coincide" if diagonal == 0 else f"{diagonal!r}"
        raise InputError(
            f"{target}: cannot export: the bounding-box diagonal of the patch corners is {what}"
        )


def _check_knots(target: Path, name: str, knots: NDArray[np.float64], poles: int) -> None:
    """A clamped cubic knot vector for ``poles`` poles, as ``Geom_BSplineSurface`` takes it."""
    knots = np.asarray(knots, dtype=np.float64)
    problem = None
    if knots.ndim != 1 or len(knots) != poles + 4:
        problem = f"has {knots.size} knots for {poles} poles (needs poles + 4)"
    elif not np.isfinite(knots).all():
        problem = "is not finite"
    elif np.any(np.diff(knots) < 0):
        problem = "decreases"
    else:
        values, counts = np.unique(knots, return_counts=True)
        span = values[-1] - values[0]
        if len(values) < 2 or not span > 0:
            problem = "spans nothing"
        elif counts[0] != 4 or counts[-1] != 4:
            problem = (
                f"has end multiplicities {counts[0]} and {counts[-1]} (a clamped cubic needs 4)"
            )
        elif len(counts) > 2 and counts[1:-1].max() > 3:
            problem = (
                f"has an interior knot of multiplicity {counts[1:-1].max()} (at most 3 for cubics)"
            )
        elif np.diff(values).min() < 1e-12 * span:
            problem = f"has a span of {np.diff(values).min():.3g}, below 1e-12 of its range"
    if problem is not None:
        raise InputError(f"{target}: cannot export: the B-spline knot vector in {name} {problem}")


def _check_fit(target: Path, fit: BSplineFit, sewing_tolerance: float) -> None:
    """The poles and knots handed to ``Geom_BSplineSurface``: finite, bounded, clamped cubic knots,
    no face smaller than OCC can sew (:mod:`g1patch.io.cad`)."""
    control = np.asarray(fit.control)
    if control.ndim != 4 or control.shape[-1] != 3 or not control.shape[0]:
        raise InputError(
            f"{target}: cannot export: expected control nets (N, nu, nv, 3), got {control.shape}"
        )
    low, high = float(control.min()), float(control.max())
    if not (low >= -MAX_COORDINATE and high <= MAX_COORDINATE):
        bad = np.argwhere(~(np.abs(control) <= MAX_COORDINATE))[0]
        raise InputError(
            f"{target}: cannot export: patch {bad[0]}: a B-spline pole "
            f"{_bound_message(float(control[tuple(bad)]))}"
        )
    _check_knots(target, "u", fit.knots_u, control.shape[1])
    _check_knots(target, "v", fit.knots_v, control.shape[2])
    if not (np.isfinite(sewing_tolerance) and sewing_tolerance > 0):
        raise InputError(f"{target}: cannot export: the sewing tolerance is {sewing_tolerance!r}")
    extent = np.linalg.norm(control.max(axis=(1, 2)) - control.min(axis=(1, 2)), axis=-1)
    smallest = max(MIN_FACE_EXTENT, MIN_FACE_SEWING * sewing_tolerance)
    small = np.flatnonzero(extent < smallest)
    if small.size:
        first = int(small[0])
        others = f" (and {small.size - 1} more)" if small.size > 1 else ""
        raise InputError(
            f"{target}: cannot export: patch {first}{others} spans {extent[first]:.3g} (its "
            "control net's diagonal), "
            f"below {smallest:.3g}, the least OpenCASCADE can sew (100 × its fixed precision "
            "1e-7, at least "
            f"10 × the sewing tolerance): a degenerate or too small patch"
        )


def _check_sewn(target: Path, faces: Sequence[Any]) -> None:
    """Every input face has a sewn face: OCC segfaults evaluating the null face of one it
    dropped."""
    dropped = [n for n, face in enumerate(faces) if face.IsNull()]
    if dropped:
        raise OpenCascadeError(
            f"{target}: OpenCASCADE's sewing dropped the face of patch {dropped[0]}"
            f"{f' (and {len(dropped) - 1} more)' if len(dropped) > 1 else ''}: a degenerate face"
        )
