"""How objects describe themselves: short phrases for reprs and error messages, and the hook
through which Jupyter pictures are drawn.

A leaf module, so that every layer may describe what it holds without reaching up to
:mod:`g1patch.api`; NumPy is imported by the functions that use it, since the package root
registers the painters here at ``import g1patch``, which must stay light.

Pictures need :mod:`g1patch.render`, which sits high above the objects that show them, so the
objects ask :func:`picture` and the package root registers the painters
(:func:`register_painter`): the low layers never import the high ones.
"""

from __future__ import annotations

import logging
import reprlib
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

logger = logging.getLogger(__name__)

#: pixels of the pictures Jupyter shows (``_repr_png_``)
PREVIEW_SIZE = (400, 400)
#: networks (or meshes, in faces) larger than this are not drawn automatically in Jupyter: the
#: text repr is shown instead, and :meth:`g1patch.Surface.render` draws them on request
PREVIEW_MAX_PATCHES = 20_000
#: samples per patch side of the box in reprs: corners, edge midpoints and the centre, where a
#: patch of a smooth surface bulges most
BOX_SAMPLES = 3
_BLOCK = 1 << 16


def describe(value: object) -> str:
    """A short phrase naming ``value`` for an error message: its type and a repr of at most ~60
    characters (arrays by shape and dtype, never their contents)."""
    import numpy as np

    kind = type(value)
    module = kind.__module__
    name = (
        kind.__qualname__ if module == "builtins" else f"{module.split('.')[0]}.{kind.__qualname__}"
    )
    if isinstance(value, np.ndarray):
        return f"a numpy.ndarray of shape {value.shape} and dtype {value.dtype}"
    short = reprlib.Repr()
    short.maxstring, short.maxother, short.maxlist, short.maxtuple, short.maxdict = 40, 40, 4, 4, 3
    try:
        text = short.repr(value)
    except Exception:  # a repr that fails says nothing useful
        text = "…"
    if len(text) > 60:
        text = text[:59] + "…"
    article = "an" if name[:1].lower() in "aeiou" else "a"
    return f"{article} {name} ({text})"


def _number(value: float) -> str:
    return f"{float(value) + 0.0:.4g}"  # + 0.0: no "-0"


def bbox_text(low: Any, high: Any) -> str:
    """``"bbox (-1, -1, -1)…(1, 1, 1)"``, 4 significant digits."""
    import numpy as np

    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    if low.shape != (3,) or not (np.isfinite(low).all() and np.isfinite(high).all()):
        return "bbox empty"
    return f"bbox ({', '.join(map(_number, low))})…({', '.join(map(_number, high))})"


def patch_set_repr(name: str, count: int, what: str, box: Callable[[], tuple[Any, Any]]) -> str:
    """``<name 6 what, bbox (-1, -1, -1)…(1, 1, 1)>``: ``box()`` is the box of the surface sampled
    at :data:`BOX_SAMPLES` ² points a patch (world coordinates), left out of an empty set; never the
    arrays."""
    text = f", {bbox_text(*box())}" if count else ""
    return f"<{name} {count} {what}{text}>"


def short_source(source: object) -> str:
    """The file name of a source path, at most 40 characters."""
    name = Path(str(source)).name or str(source)
    return name if len(name) <= 40 else name[:39] + "…"


def patch_kind(patches: object) -> str:
    """``"gregory"`` for Gregory patches, the form (``"bezier"``, ``"hermite"``, ``"bspline"``)
    for bicubics."""
    return getattr(patches, "kind", None) or str(getattr(patches, "form", type(patches).__name__))


def sampled_box(
    weights: np.ndarray, points: np.ndarray, to_world: Callable[[np.ndarray], np.ndarray] | None
) -> tuple[np.ndarray, np.ndarray]:
    """(lowest, highest) corner of the points ``weights @ points[n]`` of every patch n: one
    batched product a block of patches at a time, without copies, so a million patches take well
    under a second. ``weights`` (S, K), ``points`` (N, K, 3); ``to_world`` maps the corners out of
    the patches' working frame (x ↦ c + s x with s > 0 keeps the order of every coordinate)."""
    import numpy as np

    low, high = np.full(3, np.inf), np.full(3, -np.inf)
    for start in range(0, len(points), _BLOCK):
        sampled = np.matmul(weights, points[start : start + _BLOCK]).reshape(-1, 3)
        low, high = np.minimum(low, sampled.min(axis=0)), np.maximum(high, sampled.max(axis=0))
    if to_world is not None and len(points):
        low, high = to_world(low), to_world(high)
    return low, high


# ------------------------------------------------------------------------------- pictures

#: kind ("mesh", "network") → a function drawing such an object as PNG bytes
_PAINTERS: dict[str, Callable[[Any], bytes]] = {}


def register_painter(kind: str, paint: Callable[[Any], bytes]) -> None:
    """Make :func:`picture` draw objects of ``kind`` with ``paint`` (the package root registers
    :mod:`g1patch.render`'s painters)."""
    _PAINTERS[kind] = paint


def picture(kind: str, value: object, count: int) -> bytes | None:
    """The PNG of ``value`` for Jupyter's ``_repr_png_``: None (the text repr is shown instead)
    above :data:`PREVIEW_MAX_PATCHES` items, when no painter is registered, or when the picture
    cannot be made (no matplotlib, an empty or degenerate surface): a display hook must not
    raise."""
    from .errors import G1PatchError

    paint = _PAINTERS.get(kind)
    if paint is None or count > PREVIEW_MAX_PATCHES:
        return None
    try:
        return paint(value)
    except (G1PatchError, OSError, ValueError, ArithmeticError, RuntimeError):
        logger.info("no picture: drawing failed", exc_info=True)
        return None
