"""The top-level API: ``g1patch.read``, ``g1patch.smooth`` and the :class:`Surface` they lead to.

One import does the whole job, in the style of ``trimesh.load`` and ``meshio.read``::

    import g1patch
    surface = g1patch.smooth("mesh.obj")            # or (vertices, faces), a meshio.Mesh, a trimesh
    print(surface.check())                          # the continuity report
    surface.export("mesh.step")                     # by suffix: .npz .obj .ply .stl .step …
    surface.render("zebra.png", mode="zebra")

A :class:`Surface` is a thin wrapper around the :class:`~g1patch.network.PatchNetwork` it holds
(``surface.network``), so everything in the deep modules keeps working on that. Heavy modules
(SciPy, numba, matplotlib, OpenCASCADE) are imported only by the call that needs them, so
``import g1patch`` stays fast.
"""

from __future__ import annotations

import logging
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from .display import PREVIEW_SIZE, describe, picture
from .errors import FormatError, InputError

if TYPE_CHECKING:  # pragma: no cover
    from .continuity import ContinuityReport
    from .fitting import FitReport, Scan
    from .gregory import GregoryPatchSet
    from .io.cad import ExportResult, RhinoResult
    from .mesh import QuadMesh, Tag
    from .mesh.groups import FaceGroups
    from .network import PatchNetwork
    from .patches import PatchSet

__all__ = [
    "MESH_SUFFIXES",
    "NETWORK_SUFFIXES",
    "EXPORT_SUFFIXES",
    "FitResult",
    "Surface",
    "as_mesh",
    "as_network",
    "check",
    "export",
    "fit",
    "read",
    "smooth",
    "view",
]

logger = logging.getLogger(__name__)

PathLike = str | os.PathLike[str]

#: files :func:`read` and :func:`smooth` open as meshes
MESH_SUFFIXES = (".obj", ".ply", ".off", ".stl")
#: files :func:`read` opens as networks: g1patch's network file and Newell's Bézier patches
NETWORK_SUFFIXES = (".npz", ".bpt")
TRIANGLE_SUFFIXES = (".obj", ".ply", ".stl")
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs")
#: what :meth:`Surface.export` writes, by suffix
#: Rhino's NURBS file (the extra ``rhino``)
RHINO_SUFFIX = ".3dm"
EXPORT_SUFFIXES = (".npz", *TRIANGLE_SUFFIXES, *CAD_SUFFIXES, RHINO_SUFFIX, ".bpt")

_SOURCES = (
    "a mesh file path (.obj, .ply, .off, .stl), a (vertices, faces) pair of arrays or lists, a "
    "meshio.Mesh, "
    "an object with vertices and faces (trimesh), a pyvista.PolyData or a QuadMesh"
)


def _png_via_file(draw: Any) -> bytes:
    with tempfile.TemporaryDirectory(prefix="g1patch-png-") as folder:
        path = Path(folder) / "picture.png"
        draw(path)
        return path.read_bytes()


def network_png(
    network: PatchNetwork, size: tuple[int, int] = PREVIEW_SIZE, **options: Any
) -> bytes:
    """The PNG bytes of :func:`g1patch.render.render` of ``network``."""
    from .render import render

    return _png_via_file(lambda path: render(path, network, size=size, **options))


def mesh_png(mesh: QuadMesh, size: tuple[int, int] = PREVIEW_SIZE) -> bytes:
    """The PNG bytes of a quad mesh drawn flat-shaded (each quad as two triangles with its own
    normal)."""
    from .render import render_surfaces
    from .tessellate import TriangleMesh

    triangles = mesh.faces[:, [0, 1, 2, 0, 2, 3]].reshape(-1, 3)
    points = mesh.vertices[triangles].reshape(-1, 3)
    corner = mesh.vertices[mesh.faces]
    normal = np.cross(
        corner[:, 2] - corner[:, 0], corner[:, 3] - corner[:, 1]
    )  # the quad's diagonals
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)
    normals = np.repeat(normal, 6, axis=0)
    flat = TriangleMesh(points, normals, np.arange(len(points), dtype=np.int64).reshape(-1, 3))
    return _png_via_file(lambda path: render_surfaces(path, [flat], [None], size=size))  # type: ignore[list-item]


# ------------------------------------------------------------------------------- inputs


def _check_path(name: str, path: object) -> Path:
    if isinstance(path, (str, os.PathLike)):
        return Path(path)
    raise InputError(f"{name}: expected a file name (str or pathlib.Path), got {describe(path)}")


def read(
    path: PathLike,
    *,
    split: bool = True,
    sharp_angle: float | None = None,
    strict: bool | None = None,
    max_input_size: int | None = None,
) -> QuadMesh | PatchNetwork:
    """Open a file by its suffix: a mesh (``.obj`` with OpenSubdiv tags, ``.ply``, ``.off``,
    ``.stl``) as a :class:`~g1patch.mesh.QuadMesh` (options as for
    :func:`g1patch.io.meshfile.read_mesh`), a network file (``.npz``, written by ``g1patch
    build`` or :meth:`Surface.export`) or Newell's Bézier patches (``.bpt``, their shared edges
    matched) as a :class:`~g1patch.network.PatchNetwork`. A bad file raises
    :class:`FormatError` naming it. ``max_input_size`` (bytes): refuse a larger mesh or ``.bpt``
    file before reading it (default: 2 GB for a mesh, 1 GiB for a ``.bpt``); only regular files
    are read."""
    target = _check_path("path", path)
    suffix = target.suffix.lower()
    if suffix in MESH_SUFFIXES:
        from .io.meshfile import read_mesh

        return read_mesh(
            target,
            split=split,
            sharp_angle=sharp_angle,
            strict=strict,
            max_input_size=max_input_size,
        )
    if suffix == ".npz":
        from .io.network_file import load_network

        return load_network(target)
    if suffix == ".bpt":
        from .io.bpt import read_bpt
        from .network import network_from_patch_points

        patches = read_bpt(target) if max_input_size is None else read_bpt(target, max_input_size)
        return network_from_patch_points(patches, source=str(target))
    raise FormatError(
        target,
        f"unsupported extension {target.suffix or '(none)'!r}; g1patch.read opens meshes "
        f"({', '.join(MESH_SUFFIXES)}), network files (.npz) and Bézier patches (.bpt)",
    )


def _sharp_tags(vertices: Any, faces: Any, degrees: float | None) -> tuple[Tag, ...]:
    """The ``sharp_angle`` tags of polygons given as arrays (none when the polygons are not usable:
    the mesh checks then name what is wrong)."""
    if degrees is None:
        return ()
    from .mesh import _as_polygons
    from .sharpen import sharp_angle_tags

    corners, sizes = _as_polygons(faces)
    points = np.asarray(vertices, dtype=np.float64)
    if (
        points.ndim != 2
        or points.shape[1] != 3
        or not sizes.size
        or not corners.size
        or corners.min() < 0
        or corners.max() >= len(points)
        or not np.isfinite(points).all()
        or sizes.min() < 3
    ):
        return ()
    return sharp_angle_tags(points, corners, sizes, degrees)


def _planar_to_space(vertices: Any) -> Any:
    """(n, 2) points as (n, 3) with z = 0 (meshio and trimesh keep 2-D meshes so); others
    unchanged."""
    array = np.asarray(vertices)
    if array.ndim == 2 and array.shape[1] == 2 and array.dtype != object:
        return np.column_stack([array, np.zeros(len(array))])
    return vertices


def _from_arrays(
    vertices: Any,
    faces: Any,
    source: str | None,
    *,
    split: bool,
    sharp_angle: float | None,
    strict: bool | None,
) -> QuadMesh:
    from .mesh import QuadMesh

    vertices = _planar_to_space(vertices)
    tags = _sharp_tags(vertices, faces, sharp_angle)
    return QuadMesh.from_arrays(
        vertices, faces, split=split, source=source, tags=tags, strict=strict
    )


#: meshio cell types of surfaces (polygon blocks are "polygon", in older files "polygonN")
_MESHIO_SURFACES = ("triangle", "quad")


def _meshio_faces(mesh: Any) -> Any:
    """The faces of a meshio.Mesh's triangle, quad and polygon blocks, in block order: one (F, n)
    array when all have n corners, else a list of index arrays. Points, lines and vertex cells are
    left out; volume and higher-order cells raise :class:`InputError` naming the block."""
    blocks = []
    skipped = []
    for index, block in enumerate(mesh.cells):
        kind = str(getattr(block, "type", "?"))
        data = getattr(block, "data", None)
        if kind in _MESHIO_SURFACES or kind.startswith("polygon"):
            if isinstance(data, np.ndarray) and data.ndim == 2:
                blocks.append(data.astype(np.int64, copy=False))
            else:  # polygon blocks of mixed sizes come as a list of arrays
                blocks.extend(
                    np.atleast_2d(np.asarray(face, dtype=np.int64))
                    for face in (data if data is not None else ())
                )
        elif kind == "vertex" or kind.startswith("line"):
            skipped.append(kind)
        else:
            raise InputError(
                f"meshio.Mesh: cell block {index} holds {kind!r} cells; g1patch smooths surfaces "
                "made of "
                "linear triangle, quad and polygon cells (give the corner points only, without "
                "mid-edge nodes, "
                "and the boundary of a volume mesh)"
            )
    if skipped:
        logger.info(
            "meshio.Mesh: left out the %s cells (not faces)", ", ".join(sorted(set(skipped)))
        )
    if not blocks:
        raise InputError(
            "meshio.Mesh: has no triangle, quad or polygon cells: there is no surface to smooth"
        )
    if len({block.shape[1] for block in blocks}) == 1:
        return np.concatenate(blocks)
    return [row for block in blocks for row in block]


def _vtk_faces(flat: Any) -> Any:
    """VTK's padded cell array ``[n0, i…, n1, j…, …]`` (pyvista's ``PolyData.faces``) as
    polygons."""
    cells = np.asarray(flat, dtype=np.int64).ravel()
    faces = []
    position = 0
    while position < len(cells):
        size = int(cells[position])
        if size < 1 or position + 1 + size > len(cells):
            raise InputError(
                f"faces: not a VTK cell array (a cell of {size} points at entry {position} of "
                f"{len(cells)})"
            )
        faces.append(cells[position + 1 : position + 1 + size])
        position += 1 + size
    sizes = {len(face) for face in faces}
    return np.stack(faces) if len(sizes) == 1 else faces


def as_mesh(
    source: Any,
    *,
    split: bool = True,
    sharp_angle: float | None = None,
    strict: bool | None = None,
    max_input_size: int | None = None,
) -> QuadMesh:
    """A validated :class:`~g1patch.mesh.QuadMesh` of anything :func:`smooth` accepts.

    ``source``: a mesh file path (str or path-like: ``.obj``, ``.ply``, ``.off``, ``.stl``); a
    ``(vertices, faces)`` pair (arrays or lists; faces an (F, n) array or a list of index lists of
    any sizes; 2-D points get z = 0); a ``meshio.Mesh`` (its triangle, quad and polygon blocks);
    any object with ``vertices`` and ``faces`` (``trimesh.Trimesh``); an object with ``points``
    and a VTK cell array ``faces`` (``pyvista.PolyData``); or a QuadMesh (returned as it is, with
    ``sharp_angle`` tags added). Non-quad faces are split (one smooth Catmull–Clark step) unless
    ``split`` is False; ``sharp_angle``, ``strict`` and ``max_input_size`` (a file's) as for
    :func:`g1patch.io.meshfile.read_mesh`. Anything else raises :class:`InputError` naming what was
    passed.
    """
    from .mesh import QuadMesh

    if isinstance(source, QuadMesh):
        if sharp_angle is None:
            return source
        tags = _sharp_tags(source.vertices, source.faces, sharp_angle)
        return QuadMesh(
            source.vertices,
            source.topology,
            source.tags + tags,
            source.source,
            source.repairs,
            uv=source.uv,
            groups=source.groups,
        )
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        suffix = path.suffix.lower()
        if suffix in NETWORK_SUFFIXES:
            raise InputError(
                f"{path}: is a {'network' if suffix == '.npz' else 'Bézier patch'} file, already "
                "a surface, "
                "not a mesh to smooth; open it with g1patch.read(path) or "
                "g1patch.Surface(g1patch.read(path))"
            )
        from .io.meshfile import read_mesh

        return read_mesh(
            path,
            split=split,
            sharp_angle=sharp_angle,
            strict=strict,
            max_input_size=max_input_size,
        )
    if isinstance(source, (tuple, list)) and len(source) == 2:
        vertices, faces = source
        return _from_arrays(
            vertices, faces, None, split=split, sharp_angle=sharp_angle, strict=strict
        )
    if (
        hasattr(source, "points") and hasattr(source, "cells") and not hasattr(source, "faces")
    ):  # meshio.Mesh
        return _from_arrays(
            source.points,
            _meshio_faces(source),
            None,
            split=split,
            sharp_angle=sharp_angle,
            strict=strict,
        )
    if hasattr(source, "vertices") and hasattr(source, "faces"):  # trimesh.Trimesh and the like
        return _from_arrays(
            np.asarray(source.vertices),
            _face_list(source.faces),
            None,
            split=split,
            sharp_angle=sharp_angle,
            strict=strict,
        )
    if hasattr(source, "points") and hasattr(
        source, "faces"
    ):  # pyvista.PolyData: faces a VTK cell array
        faces = source.faces
        faces = _vtk_faces(faces) if np.ndim(faces) == 1 else _face_list(faces)
        return _from_arrays(
            np.asarray(source.points),
            faces,
            None,
            split=split,
            sharp_angle=sharp_angle,
            strict=strict,
        )
    if isinstance(source, _surface_types()):
        raise InputError(
            f"smooth: got a {type(source).__name__}, already a surface, not a mesh; use "
            f"g1patch.Surface({type(source).__name__.lower()}) to check, export or render it"
        )
    raise InputError(f"smooth: cannot make a mesh of {describe(source)}; expected {_SOURCES}")


def _face_list(faces: Any) -> Any:
    """Faces as an array when they are one (a trimesh's TrackedArray included), else as given."""
    return faces if isinstance(faces, (list, tuple)) else np.asarray(faces)


def _surface_types() -> tuple[type, ...]:
    from .gregory import GregoryPatchSet
    from .network import PatchNetwork
    from .patches import PatchSet

    return (Surface, PatchNetwork, PatchSet, GregoryPatchSet)


def as_network(surface: Any, name: str = "surface") -> PatchNetwork:
    """The :class:`~g1patch.network.PatchNetwork` of a Surface, a network (itself), a
    :class:`~g1patch.patches.PatchSet` or a :class:`~g1patch.gregory.GregoryPatchSet` (their
    shared edges found by matching boundary control points,
    :func:`~g1patch.network.network_of`), or a ``.npz`` / ``.bpt`` file name.
    Anything else raises :class:`InputError` naming it."""
    from .network import network_of

    if isinstance(surface, Surface):
        return surface.network
    if isinstance(surface, _surface_types()):
        return network_of(surface, name)  # type: ignore[arg-type]
    if isinstance(surface, (str, os.PathLike)):
        return _read_network(Path(surface))
    raise InputError(
        f"{name}: expected a Surface, PatchNetwork, PatchSet, GregoryPatchSet or a network "
        f"file (.npz, .bpt), got {describe(surface)}"
    )


#: what the commands that take a surface read instead of a mesh
NETWORK_EXPECTED = (
    "check, export, render and view read a network file (.npz) written by g1patch build, "
    "or Bézier patches (.bpt)"
)


def _read_network(path: Path) -> PatchNetwork:
    """The network of a ``.npz`` or ``.bpt`` file; anything else, a missing file included, is one
    :class:`FormatError` saying what was expected instead (and, for a mesh, how to make one)."""
    suffix = path.suffix.lower()
    if suffix == ".bpt":
        return read(path)  # type: ignore[return-value]
    if suffix == ".npz":
        from .io.network_file import load_network

        return load_network(path, expects=NETWORK_EXPECTED)
    if not path.exists():
        raise FormatError(path, "no such file")
    from .io.network_file import describe_file

    what = describe_file(path, b"")
    hint = (
        f" (make a network from it: g1patch build {path} -o {path.with_suffix('.npz')})"
        if suffix in MESH_SUFFIXES
        else ""
    )
    raise FormatError(path, f"not a network or patch file but {what}; {NETWORK_EXPECTED}{hint}")


# ------------------------------------------------------------------------------- the surface


class Surface:
    """A smooth surface: a :class:`~g1patch.network.PatchNetwork` (``.network``) with the mesh it
    was made from (``.mesh``, None for patch files), and the few things one does with it.

    Make one with :func:`smooth`, or wrap a network, a PatchSet or a GregoryPatchSet:
    ``Surface(network)``. The network stays a plain PatchNetwork, so the deep modules
    (:mod:`g1patch.continuity`, :mod:`g1patch.tessellate`, :mod:`g1patch.render`,
    :mod:`g1patch.io`) take ``surface.network`` as ever.
    """

    __slots__ = ("network", "mesh", "_report")

    def __init__(
        self,
        network: PatchNetwork | PatchSet | GregoryPatchSet | Surface,
        mesh: QuadMesh | None = None,
    ) -> None:
        if isinstance(network, Surface):
            mesh = network.mesh if mesh is None else mesh
        self.network: PatchNetwork = as_network(network, "network")
        from .mesh import QuadMesh

        if mesh is not None and not isinstance(mesh, QuadMesh):
            raise InputError(f"mesh: expected a QuadMesh or None, got {describe(mesh)}")
        self.mesh: QuadMesh | None = mesh
        self._report: ContinuityReport | None = None

    # -- what it is ------------------------------------------------------------------------

    @property
    def patches(self) -> PatchSet | GregoryPatchSet:
        return self.network.patches  # type: ignore[return-value]

    @property
    def n_patches(self) -> int:
        return self.network.n_patches

    @property
    def uv(self) -> np.ndarray | None:
        """Texture coordinates (P, 4, 2) at each patch's corners, from the mesh's ``vt``
        (:attr:`PatchNetwork.uv`); None without."""
        return self.network.uv

    @property
    def groups(self) -> FaceGroups | None:
        """Each patch's named group, from the mesh's materials or groups
        (:attr:`PatchNetwork.groups`); None without."""
        return self.network.groups

    @property
    def provenance(self) -> dict[str, str]:
        """How it was made: method, shape, refine, repairs, source…
        (:attr:`PatchNetwork.provenance`)."""
        return self.network.provenance

    @property
    def method(self) -> str:
        """``gregory``, ``split4`` or ``corner``; ``file`` for patches nobody here built."""
        return self.provenance.get("method", "file")

    @property
    def shape(self) -> str | None:
        """The shape rule (``interpolate``, ``limit``, …), None for patch files."""
        return self.provenance.get("shape")

    @property
    def repairs(self) -> tuple[str, ...]:
        """What was repaired in the input mesh (empty if nothing)."""
        return self.mesh.repairs if self.mesh is not None else ()

    @property
    def bounding_box(self) -> tuple[np.ndarray, np.ndarray]:
        """(lowest, highest) corner of the box around the surface, sampled at 3 × 3 points a patch
        (corners, edge midpoints, centre; :meth:`~g1patch.patches.PatchSet.box`)."""
        return self.network.patches.box()

    def __repr__(self) -> str:
        repaired = ("repaired",) if self.repairs else ()  # what: .repairs
        return self.network.describe("Surface", repaired)

    def _repr_png_(self) -> bytes | None:
        return picture("network", self.network, self.n_patches)

    # -- what one does with it -------------------------------------------------------------

    def folded_patches(self) -> np.ndarray:
        """The indices of the patches that fold in themselves, by the check's grid test
        (:func:`g1patch.continuity.folded_patches` on its ``FOLD_SAMPLES`` grid), at a fraction of
        the full :meth:`check`'s cost; the check's ``folds`` also counts patches that fold across
        an edge (a G1 angle above 90°, which an exactly G1 network never has)."""
        from .continuity import folded_patches
        from .continuity.grid import FOLD_SAMPLES

        return np.flatnonzero(folded_patches(self.network.patches, FOLD_SAMPLES))

    def check(self, **options: Any) -> ContinuityReport:
        """The :class:`~g1patch.continuity.ContinuityReport` (G0 gaps, G1 angles, folds,
        fairness): :func:`g1patch.continuity.check` with ``options`` (``samples``,
        ``fold_samples``, ``progress``…). The default report is computed once and kept."""
        import inspect

        from .continuity import check as measure

        known = set(inspect.signature(measure).parameters) - {"network"}
        unknown = sorted(set(options) - known)
        if unknown:
            raise InputError(
                f"check: unknown option {unknown[0]!r}; expected one of {', '.join(sorted(known))} "
                "(a verdict's max_angle goes to the report's is_g1 or passes)"
            )
        if options:
            return measure(self.network, **options)
        if self._report is None:
            self._report = measure(self.network)
        return self._report

    def tessellate(
        self, resolution: int | None = None, *, force: bool = False
    ) -> tuple[np.ndarray, np.ndarray]:
        """``(points (P, 3), triangles (T, 3))``: every patch sampled on a ``resolution²`` grid,
        welded along shared edges (:func:`g1patch.tessellate.tessellate`; None: about 2 M
        triangles at most, 17 samples a side for small networks; ``force`` allows more than 20
        M)."""
        from .tessellate import tessellate

        mesh = tessellate(self.network, resolution, force=force)
        return mesh.points, mesh.triangles

    def export(self, path: PathLike, **options: Any) -> Any:
        """Write the surface to ``path``, the format chosen by its suffix:

        * ``.npz``: the network file (``g1patch check/render/export`` read it; :func:`read` too);
          ``background=True`` writes it on a thread of its own and returns a future whose
          ``result()`` waits for it (:func:`g1patch.io.network_file.save_network_in_background`);
        * ``.obj``, ``.ply``, ``.stl``: triangles of :meth:`tessellate` (options ``resolution``,
          ``force``: an explicit resolution above 20 M triangles needs it), with the surface's
          texture coordinates where it has them (OBJ ``vt``, PLY ``s``, ``t``) and, in OBJ, its
          face groups (``g``/``usemtl`` per group);
        * ``.step``/``.stp``, ``.iges``/``.igs``: a B-rep, one B-spline face per patch (split4:
          per quad), exact for polynomial patches; a Gregory network by ``method`` (``auto``:
          its split4 re-assembly, exact G1 in CAD; ``fit``: fitted within ``fit_tolerance``, model
          units, default 1e-6 × the bbox diagonal); ``max_deviation`` (the re-assembly's bound,
          relative to the diagonal, default 1e-3); also ``progress``, ``g1_samples``, ``verify``
          (STEP of a split4 network, written directly: OpenCASCADE reads it back to check it,
          default up to 10,000 faces) (:func:`g1patch.io.cad.export_cad`, needs ``pip install
          'g1patch[cad]'``);
        * ``.3dm``: Rhino's file, the same B-spline faces as STEP's (options ``method``,
          ``max_deviation``, ``fit_tolerance``; :func:`g1patch.io.cad.export_3dm`, needs ``pip
          install 'g1patch[rhino]'``); returns a :class:`~g1patch.io.cad.RhinoResult`;
        * ``.bpt``: Newell's Bézier patches (polynomial networks only: corner, split4, files).

        Returns the path written, or for STEP/IGES the
        :class:`~g1patch.io.cad.ExportResult` (faces, solid, file size, deviation from this
        surface, the G1 angles OpenCASCADE measures; its ``path``). The file appears complete or
        not at all; an unknown suffix or an option the format does not take raises
        :class:`InputError`/:class:`FormatError`.
        """
        target = _check_path("path", path)
        suffix = target.suffix.lower()
        if suffix not in EXPORT_SUFFIXES:
            raise FormatError(
                target,
                f"unsupported extension {target.suffix or '(none)'!r}; expected one of "
                f"{', '.join(EXPORT_SUFFIXES)}",
            )
        if suffix in CAD_SUFFIXES:
            _check_options(
                target,
                options,
                ("fit_tolerance", "progress", "g1_samples", "method", "max_deviation", "verify"),
            )
            from .io.cad import export_cad

            return export_cad(target, self.network, **options)
        if suffix == RHINO_SUFFIX:
            _check_options(target, options, ("fit_tolerance", "method", "max_deviation"))
            from .io.cad import export_3dm

            return export_3dm(target, self.network, **options)
        if suffix in TRIANGLE_SUFFIXES:
            _check_options(target, options, ("resolution", "force"))
            from .io.meshfile import write_triangles
            from .tessellate import check_file_size

            resolution, force = options.get("resolution"), bool(options.get("force", False))
            if resolution is not None:
                check_file_size(
                    self.n_patches, resolution, suffix, force, textured=self.uv is not None
                )
            from .tessellate import tessellate

            mesh = tessellate(self.network, resolution, force=force)
            write_triangles(
                target,
                mesh.points,
                mesh.triangles,
                uv=mesh.uv,
                uv_triangles=mesh.uv_triangles,
                groups=mesh.groups,
            )
            return target
        if suffix == ".npz":
            _check_options(target, options, ("background",))
            from .io.network_file import save_network, save_network_in_background

            if options.get("background"):
                return save_network_in_background(target, self.network)
            save_network(target, self.network)
            return target
        _check_options(target, options, ())
        from .io.bpt import write_bpt
        from .patches import PatchSet

        if not isinstance(self.network.patches, PatchSet):
            raise FormatError(
                target,
                ".bpt holds polynomial Bézier patches; this surface's patches are rational "
                "Gregory patches (export to .step, or smooth with method='split4')",
            )
        write_bpt(target, self.network.patches)
        return target

    def render(
        self,
        path: PathLike | None = None,
        mode: str = "shaded",
        *,
        view: tuple[float, float] | str = "auto",
        up: str = "auto",
        **options: Any,
    ) -> Path | bytes:
        """A PNG of the surface: ``mode`` ``"shaded"``, ``"zebra"`` (reflection lines, they
        break where it creases), ``"deviation"`` (every patch edge coloured by its G1 angle) or
        ``"distance"`` (coloured by the distance to ``scan=(points, triangles)``);
        ``view`` = (elevation, azimuth) and the ``up`` axis default to ``"auto"``: chosen from the
        surface (:func:`g1patch.render.auto_camera`); ``options`` as for
        :func:`g1patch.render.render` (``size``, ``zoom``, ``title``…). Written to ``path``
        (returned), or returned as PNG bytes when ``path`` is None."""
        from .render import render

        options.update(view=view, up=up)
        if mode == "deviation" and "report" not in options and self._report is not None:
            options["report"] = self._report
        if path is None:
            return _png_via_file(lambda file: render(file, self.network, mode=mode, **options))  # type: ignore[arg-type]
        target = _check_path("path", path)
        render(target, self.network, mode=mode, **options)  # type: ignore[arg-type]
        return target

    def view(
        self,
        path: PathLike | None = None,
        *,
        resolution: int | None = None,
        force: bool = False,
        title: str | None = None,
        up: str = "auto",
        view: tuple[float, float] | str = "auto",
        scan: tuple[Any, Any] | None = None,
    ) -> Path | str:
        """An interactive viewer: one self-contained HTML page (orbit, zoom, pan; shaded, zebra and
        G1-deviation modes; seams as lines; the continuity summary), written to ``path``
        (``.html``, returned) or returned as a string when ``path`` is None. ``resolution``:
        samples per patch side (None: about 2 M triangles at most); a page of more needs ``force``.
        ``up``, ``view``: the first camera, as for :meth:`render` (``"auto"``: from the data).
        ``scan``: ``(points, triangles)`` of a scan the surface was fitted to: a mode colouring
        the surface by its distance to it. :func:`g1patch.viewer.view_html` makes the page;
        opening it needs no network."""
        from .viewer import view_html, write_view

        options: dict[str, Any] = {
            "resolution": resolution,
            "force": force,
            "title": title,
            "up": up,
            "view": view,
            "scan": scan,
        }
        if path is None:
            return view_html(self.network, report=self.check(), **options)
        return write_view(_check_path("path", path), self.network, report=self.check(), **options)


def _check_options(target: Path, options: dict[str, Any], allowed: Sequence[str]) -> None:
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        takes = f"takes only {', '.join(allowed)}" if allowed else "takes no options"
        raise InputError(
            f"export to {target.suffix.lower()}: unknown option {', '.join(map(repr, unknown))} "
            f"(this format {takes})"
        )


# ------------------------------------------------------------------------------- functions


def smooth(
    source: Any,
    shape: str = "interpolate",
    method: str = "split4",
    *,
    refine: int = 0,
    sharp_angle: float | None = None,
    strict: bool | None = None,
    split: bool = True,
    tangents: str = "arc",
    twist: str = "bilinear",
    normals: str = "fan",
    max_memory: int | None = None,
    max_patches: int | None = None,
    max_input_size: int | None = None,
    tolerance: float | None = 1e-3,
) -> Surface:
    """The smooth surface of a mesh: exactly G1 bicubic patches
    (:func:`g1patch.build.build_network`).

    ``source``: a mesh file path, a ``(vertices, faces)`` pair, a ``meshio.Mesh``, a trimesh, a
    pyvista PolyData or a QuadMesh (:func:`as_mesh`). ``shape``: ``interpolate`` (through the
    vertices, the default), ``limit`` (the Catmull–Clark limit of the mesh as a cage),
    ``limit-interpolate`` or ``legacy``. ``method``: ``split4`` (exact G1, polynomial: exact in
    STEP, the default), ``gregory`` (exact G1, rational: the fairest, fitted in STEP) or
    ``corner`` (the paper's, G1 at corners only). ``refine``: Catmull–Clark steps first.
    ``sharp_angle`` (degrees): keep edges whose faces turn by more than that sharp. ``strict``:
    refuse a mesh that needs repair instead of repairing it. ``split``: split non-quad faces (else
    they raise). ``tangents``: the legacy shape's;
    ``twist`` and ``normals``: the paper's construction's (``corner`` with ``legacy``).
    ``max_memory`` (bytes; default half the RAM) and ``max_patches``: a build estimated above
    either is refused before it starts (:class:`~g1patch.errors.BudgetError`).
    ``max_input_size`` (bytes; default 2 GB): a larger mesh file is refused before it is read.
    ``tolerance`` (limit shapes): the largest distance from the exact Catmull–Clark limit, of the
    bounding-box diagonal; the cage is refined until it holds (the surface's provenance says the
    distance reached; None: not measured).
    """
    from .build import build_network
    from .construct import METHODS
    from .errors import BudgetError, ConstructionError, check_choice, named_errors
    from .targets import SHAPES

    check_choice("shape", shape, tuple(SHAPES))  # before a large file is read
    check_choice("method", method, METHODS)
    mesh = as_mesh(
        source, split=split, sharp_angle=sharp_angle, strict=strict, max_input_size=max_input_size
    )
    with named_errors(mesh.source, (ConstructionError, BudgetError)):  # the file it cannot build
        network = build_network(
            mesh,
            method,
            shape,
            tangents=tangents,  # type: ignore[arg-type]
            twist=twist,  # type: ignore[arg-type]
            normals=normals,  # type: ignore[arg-type]
            refine=refine,
            max_memory=max_memory,
            max_patches=max_patches,
            tolerance=tolerance,
        )
    return Surface(network, mesh)


class FitResult(NamedTuple):
    """What :func:`fit` returns: the fitted ``surface``, its ``report``
    (:class:`g1patch.fitting.FitReport`: two-way distances to the scan, faces, rounds, time) and
    the ``scan`` it was fitted to (:class:`g1patch.fitting.Scan`)."""

    surface: Surface
    report: FitReport
    scan: Scan

    def view(self, path: PathLike | None = None, **options: Any) -> Path | str:
        """:meth:`Surface.view` with the distance-to-the-scan mode."""
        return self.surface.view(path, scan=(self.scan.points, self.scan.triangles), **options)

    def render(self, path: PathLike | None = None, **options: Any) -> Path | bytes:
        """:meth:`Surface.render` in the distance mode: the surface coloured by its distance to
        the scan (of the scan's diagonal), with its colour bar."""
        scan = (self.scan.points, self.scan.triangles)
        return self.surface.render(path, "distance", scan=scan, **options)


def fit(
    source: Any,
    *,
    tolerance: float = 1e-3,
    faces: int | None = None,
    layout: Any = None,
    method: str = "split4",
    max_input_size: int | None = None,
    sharp_angle: float | None = 60.0,
) -> FitResult:
    """An exact-G1 surface fitted to a dense triangle mesh (a scan; :mod:`g1patch.fitting`).

    ``source``: a mesh file (OBJ, PLY, OFF, STL) or anything :func:`as_mesh` takes, its
    triangles (or polygons) the scan. A quad layout (Instant Meshes, or ``layout``: your own
    quad mesh near the scan, anything :func:`as_mesh` takes) gives the cage's topology; its
    positions are solved so that the Catmull–Clark limit passes nearest the scan's points; the
    limit is assembled exactly G1 by ``method`` (``split4``: polynomial, so STEP holds the
    fitted surface itself).
    ``tolerance``: two-way distance, of the bounding-box diagonal (99.9 % of the scan's points
    within it of the surface, every surface point within it of the scan); the layout is refined
    where it is off, or made finer, until it holds (at most four layouts) unless ``faces`` or
    ``layout`` fix it; the report says whether it was met. ``sharp_angle`` (degrees; None:
    off): scan edges whose triangles turn by more than that are features, kept as creases (STEP
    edges)."""
    from .construct import METHODS
    from .errors import ConstructionError, check_choice, named_errors
    from .fitting import fit_network, scan_of

    check_choice("method", method, METHODS)
    if isinstance(source, (str, os.PathLike)):  # a file: its triangles as they are, not split
        scan = read_scan(_check_path("source", source), max_input_size)
    else:
        scan = scan_of(as_mesh(source))
    quads = None if layout is None else _fit_layout(layout, max_input_size)
    with named_errors(scan.source, (ConstructionError,)):
        network, report = fit_network(
            scan,
            tolerance=tolerance,
            faces=faces,
            layout=quads,
            method=method,
            sharp_angle=sharp_angle,
        )
    return FitResult(Surface(network), report, scan)


def _fit_layout(layout: Any, max_input_size: int | None) -> QuadMesh:
    """A given layout as the cage's quad mesh, all quads: a file's quads cleaned as the
    remesher's are (:func:`g1patch.fitting.layout.clean_layout`: coincident vertices merged,
    degenerate and over-shared quads dropped), its own tags (creases, corners) kept; anything
    else as :func:`as_mesh` takes it."""
    from .fitting.layout import clean_layout
    from .io.meshfile import read_tagged_polygons
    from .mesh import QuadMesh

    if isinstance(layout, (str, os.PathLike)):
        path = _check_path("layout", layout)
        points, corners, sizes, tags = read_tagged_polygons(path, max_input_size=max_input_size)
        if (sizes != 4).any():
            raise InputError(f"{path}: a layout must be all quads")
        vertices, faces, tags = clean_layout(points, corners.reshape(-1, 4), tags)
        if not len(faces):
            raise InputError(f"{path}: the layout has no quad of nonzero area")
        return QuadMesh.from_arrays(vertices, faces, source=str(path), tags=tags)
    quads = as_mesh(layout, max_input_size=max_input_size)
    if quads.cage is not None:
        raise InputError(f"{quads.source or 'layout'}: a layout must be all quads")
    return quads


def read_scan(path: PathLike, max_input_size: int | None = None) -> Scan:
    """A mesh file's polygons as they are (no splitting, no repair) fanned into triangles: what
    :func:`fit` fits and ``render --distance`` measures against."""
    from .fitting import scan_from_polygons
    from .io.meshfile import read_polygons

    return scan_from_polygons(*read_polygons(path, max_input_size=max_input_size), str(path))


def check(surface: Any, **options: Any) -> ContinuityReport:
    """The continuity report of a Surface, PatchNetwork, PatchSet, GregoryPatchSet or network file
    (``.npz``, ``.bpt``); ``options`` as for :func:`g1patch.continuity.check`."""
    from .continuity import check as measure

    if isinstance(surface, Surface):
        return surface.check(**options)
    return measure(as_network(surface), **options)


def export(surface: Any, path: PathLike, **options: Any) -> Path | ExportResult | RhinoResult:
    """:meth:`Surface.export` of a Surface, PatchNetwork, PatchSet, GregoryPatchSet or network
    file."""
    wrapped = surface if isinstance(surface, Surface) else Surface(as_network(surface))
    return wrapped.export(path, **options)


def view(surface: Any, path: PathLike | None = None, **options: Any) -> Path | str:
    """:meth:`Surface.view` of a Surface, PatchNetwork, PatchSet, GregoryPatchSet or network
    file."""
    wrapped = surface if isinstance(surface, Surface) else Surface(as_network(surface))
    return wrapped.view(path, **options)
