"""Rhino's ``.3dm`` through OpenNURBS (``rhino3dm``, the extra ``rhino``): the same exact bicubic
B-spline faces as the STEP file (:func:`~g1patch.io.cad.export.cad_surfaces`: one per patch, or
one per quad of a split4 network, the same count), each an untrimmed NURBS surface named
``'face N'`` as in STEP. A network with face groups (:attr:`~g1patch.network.PatchNetwork.groups`)
gets one layer per group, named after it and in its colour (black without one), and the faces of a
group are named ``'NAME N'``, on its layer, coloured by the layer; faces without a group stay
``'face N'`` on a layer ``'Default'``. OpenNURBS stores a degree-3 knot vector without its two
outer knots (``cv + order − 2`` values), so ``[0, 0, 0, 0, ½, ½, 1, 1, 1, 1]`` is written
``[0, 0, 0, ½, ½, 1, 1, 1]``. rhino3dm is imported only here; without it
:class:`MissingDependencyError` names the extra before anything is written.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from ...errors import MissingDependencyError
from ...mesh.groups import FaceGroups
from ...network import PatchNetwork
from ...patches import PatchSet
from ..atomic import atomic_path
from .export import _as_network, cad_surfaces
from .guards import _check_patch_coordinates
from .method import DEVIATION_RTOL, CadMethod
from .opencascade import PathLike

__all__ = ["RhinoResult", "export_3dm"]

#: the OpenNURBS archive version written (Rhino 8 reads 2–8)
ARCHIVE_VERSION = 8


@dataclass(frozen=True)
class RhinoResult:
    """What :func:`export_3dm` wrote: ``faces`` surfaces by ``method`` (and its note), their largest
    distance to the network (model units and relative to the diagonal), the file's size."""

    path: Path
    faces: int
    method: str
    method_note: str
    deviation: float
    relative_deviation: float
    file_bytes: int

    def to_dict(self) -> dict[str, Any]:
        """The figures, JSON-ready (the path as text)."""
        return {**asdict(self), "path": str(self.path)}

    def summary(self) -> str:
        """One line: the file, its faces, the method and the deviation."""
        note = f" ({self.method_note})" if self.method_note else ""
        return (
            f"wrote {self.faces} NURBS faces ({self.method}{note}) -> {self.path}; "
            f"{self.relative_deviation:.2e} of the diagonal from the surface"
        )


def _rhino3dm() -> ModuleType:
    try:
        import rhino3dm
    except ImportError:
        raise MissingDependencyError("rhino3dm", "rhino", "writing .3dm") from None
    return rhino3dm


def export_3dm(
    path: PathLike,
    network: PatchNetwork | PatchSet,
    *,
    method: CadMethod = "auto",
    max_deviation: float = DEVIATION_RTOL,
    fit_tolerance: float | None = None,
) -> RhinoResult:
    """Write ``network`` as a Rhino ``.3dm`` file of B-spline faces (options as for
    :func:`~g1patch.io.cad.export_cad`), atomically. One Python call per control point: rhino3dm
    takes no arrays (Spot's 2,928 faces: well under a second)."""
    target = Path(path)
    rhino = _rhino3dm()
    _check_patch_coordinates(
        target, network.patches if isinstance(network, PatchNetwork) else network
    )
    surfaces = cad_surfaces(
        target,
        _as_network(network),
        method=method,
        max_deviation=max_deviation,
        fit_tolerance=fit_tolerance,
    )
    model = rhino.File3dm()
    nets, knots = surfaces.nets(), surfaces.knots()
    layer_of = _group_layers(rhino, model, surfaces.groups)
    for index, (net, (knots_u, knots_v)) in enumerate(zip(nets, knots, strict=True)):
        count_u, count_v = net.shape[:2]
        surface = rhino.NurbsSurface.Create(3, False, 4, 4, count_u, count_v)
        for (i, j), (x, y, z) in zip(
            ((i, j) for i in range(count_u) for j in range(count_v)),
            net.reshape(-1, 3).tolist(),
            strict=True,
        ):
            surface.Points[i, j] = rhino.Point4d(x, y, z, 1.0)
        for k, value in enumerate(knots_u[1:-1].tolist()):
            surface.KnotsU[k] = value
        for k, value in enumerate(knots_v[1:-1].tolist()):
            surface.KnotsV[k] = value
        attributes = rhino.ObjectAttributes()
        attributes.Name = f"face {index}"
        if layer_of is not None:
            attributes.Name = surfaces.groups.label(index, "face")  # type: ignore[union-attr]
            attributes.LayerIndex = layer_of[index]
            attributes.ColorSource = rhino.ObjectColorSource.ColorFromLayer
        model.Objects.AddSurface(surface, attributes)
    with atomic_path(target) as temporary:
        if not model.Write(str(temporary), ARCHIVE_VERSION):
            raise OSError(f"rhino3dm could not write {target}")
        file_bytes = temporary.stat().st_size
    diagonal = surfaces.diagonal or 1.0
    return RhinoResult(
        target,
        len(nets),
        surfaces.method,
        surfaces.method_note,
        surfaces.deviation,
        surfaces.deviation / diagonal,
        file_bytes,
    )


def _group_layers(rhino: ModuleType, model: Any, groups: FaceGroups | None) -> list[int] | None:
    """One layer per group of ``groups`` (per face), named after it and in its colour (sRGB bytes;
    black without), and ``'Default'`` first where some face has no group: each face's layer
    index. None without groups."""
    if groups is None:
        return None
    layers = []
    if (groups.ids < 0).any():
        layers.append(("Default", (0, 0, 0, 255)))
    for name, colour in zip(groups.names, groups.colours.tolist(), strict=True):
        rgb = (0, 0, 0) if np.isnan(colour).any() else tuple(round(255 * c) for c in colour)
        layers.append((name, (*rgb, 255)))
    for name, colour in layers:
        layer = rhino.Layer()
        layer.Name, layer.Color = name, colour
        model.Layers.Add(layer)
    first = 1 if (groups.ids < 0).any() else 0
    return np.where(groups.ids >= 0, groups.ids + first, 0).tolist()
