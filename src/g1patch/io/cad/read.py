"""Reading STEP and IGES files back with OCC's readers (:func:`read_cad_faces`), and the G1 angles
a CAD user's system sees in such a file (:func:`file_g1_angles`)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...errors import FormatError
from ...network import PatchNetwork
from .bspline import split4_quad_faces
from .measure import G1_SAMPLES, _face_normals, _occ_g1_angles
from .opencascade import (
    CAD_FORMATS,
    CadFormat,
    PathLike,
    _faces_of,
    _format_of,
    _occ,
    _occ_failures,
    _quiet,
)


class CadFace:
    """One face of a read shape: evaluate its surface (``BRepAdaptor_Surface``) at (u, v)."""

    def __init__(self, occ: SimpleNamespace, face: Any) -> None:
        self._occ = occ
        self.face = face
        self.surface = occ.BRepAdaptor_Surface(face, False)
        #: (u_min, u_max, v_min, v_max) of the underlying surface (not trimmed to the face)
        self.bounds = (
            self.surface.FirstUParameter(),
            self.surface.LastUParameter(),
            self.surface.FirstVParameter(),
            self.surface.LastVParameter(),
        )

    def evaluate(self, uv: ArrayLike) -> NDArray[np.float64]:
        """Points ``S(u, v)`` for ``uv`` of shape (K, 2), returned (K, 3)."""
        value = self.surface.Value
        params = np.asarray(uv, dtype=np.float64).reshape(-1, 2).tolist()
        return np.array([value(u, v).Coord() for u, v in params], dtype=np.float64).reshape(-1, 3)

    def normals(self, uv: ArrayLike) -> NDArray[np.float64]:
        """Unit normals ``±(S_u × S_v)/|…|`` (outwards for a face of an oriented solid), (K, 3)."""
        normals = _face_normals(
            self._occ, self.face, np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        )
        length = np.linalg.norm(normals, axis=-1, keepdims=True)
        return np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)

    def poles(self) -> NDArray[np.float64] | None:
        """The control net ``(nu, nv, 3)`` of a B-spline or Bézier surface, else None."""
        kind = self.surface.GetType()
        types = self._occ.GeomAbs_SurfaceType
        if kind == types.GeomAbs_BSplineSurface:
            surface = self.surface.BSpline()
        elif kind == types.GeomAbs_BezierSurface:
            surface = self.surface.Bezier()
        else:
            return None
        return np.array(
            [
                [surface.Pole(i, j).Coord() for j in range(1, surface.NbVPoles() + 1)]
                for i in range(1, surface.NbUPoles() + 1)
            ]
        )


class CadModel(NamedTuple):
    """A shape read from a CAD file and an evaluator per face (in ``TopExp_Explorer`` order)."""

    shape: Any
    faces: list[CadFace]


def read_cad_faces(path: PathLike) -> CadModel:
    """Read a STEP or IGES file (by extension) with OCC's readers into a shape and face
    evaluators."""
    source = Path(path)
    kind = _format_of(source, None)
    occ = _occ()
    if not source.is_file():
        raise FormatError(source, "no such file")
    with _occ_failures(source, ["reading the file"]), _quiet(occ):
        reader = occ.STEPControl_Reader() if kind == "step" else occ.IGESControl_Reader()
        status = reader.ReadFile(str(source))
        if status != occ.IFSelect_ReturnStatus.IFSelect_RetDone:
            raise FormatError(
                source, f"OpenCASCADE cannot read it as {kind.upper()} ({status.name})"
            )
        reader.TransferRoots()
        shape = reader.OneShape()
        faces = [CadFace(occ, face) for face in _faces_of(occ, shape) if not face.IsNull()]
    if not faces:
        raise FormatError(source, f"the {kind.upper()} file holds no faces")
    return CadModel(shape, faces)


def _read_as(path: PathLike, kind: CadFormat) -> CadModel:
    """:func:`read_cad_faces` of a file whose extension must be one of ``kind``."""
    if _format_of(Path(path), None) != kind:
        what = {"step": "a STEP", "iges": "an IGES"}[kind]
        raise FormatError(
            path,
            f"expected {what} file ({', '.join(CAD_FORMATS[kind])}), got {Path(path).suffix!r}",
        )
    return read_cad_faces(path)


def read_step_faces(path: PathLike) -> CadModel:
    """Read a STEP file (``STEPControl_Reader``): the shape and one evaluator per face."""
    return _read_as(path, "step")


def read_iges_faces(path: PathLike) -> CadModel:
    """Read an IGES file (``IGESControl_Reader``): the shape and one evaluator per face."""
    return _read_as(path, "iges")


def file_g1_angles(
    path: PathLike, network: PatchNetwork, samples: int = G1_SAMPLES
) -> NDArray[np.float64]:
    """(E, samples) angles (degrees) between the OCC normals of a *read-back* CAD file's faces
    along every shared edge of ``network``, the network that was written (for a Gregory network
    exported by split4, its :func:`~g1patch.construct.polynomial.split4_of_gregory`): what a CAD
    user's system sees. Faces are matched to patches (or split4 quads) by their middle points
    (nearest, each face once); seams are included (``network.seam`` tells them apart)."""
    return _model_g1_angles(read_cad_faces(path), network, samples, path)


def _model_g1_angles(
    model: CadModel, network: PatchNetwork, samples: int, path: PathLike | None = None
) -> NDArray[np.float64]:
    """:func:`file_g1_angles` of a model already read (``path`` names it in an error)."""
    from scipy.spatial import cKDTree

    quads = split4_quad_faces(network) is not None
    middles = np.concatenate(
        [
            face.evaluate(
                np.array(
                    [
                        [
                            0.5 * (face.bounds[0] + face.bounds[1]),
                            0.5 * (face.bounds[2] + face.bounds[3]),
                        ]
                    ]
                )
            )
            for face in model.faces
        ]
    )
    centres = (
        network.patches.evaluate(np.array([[1.0, 1.0]]))[::4, 0]
        if quads
        else network.patches.evaluate(np.array([[0.5, 0.5]]))[:, 0]
    )
    distance, order = cKDTree(middles).query(centres)
    if len(model.faces) != len(centres) or len(set(order.tolist())) != len(centres):
        raise FormatError(
            path or "the CAD model",
            f"its {len(model.faces)} faces do not match the network's {len(centres)} "
            f"{'quads' if quads else 'patches'} one to one",
        )
    faces = [model.faces[i].face for i in order.tolist()]
    return _occ_g1_angles(_occ(), faces, network, samples, None, quads)
