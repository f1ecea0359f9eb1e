"""A split4 network's quads written as a STEP AP214 B-rep directly, without building it in
OpenCASCADE first (:func:`write_quad_step`).

OCC's route (faces, sewing, solids, its writer, then :func:`~g1patch.io.cad.step_text.
compact_step`) costs ~4 ms and ~190 kB of memory per face: a 32,768-quad torus takes 149 s and
4.9 GB, so a million quads cannot be written at all. A split4 network already knows its B-rep:
each quad is one B-spline face (:func:`~g1patch.io.cad.bspline.split4_quad_faces`), its sides are
the mesh edges and its corners the mesh vertices, so the shared topology that sewing searches for
is read off the network's ids. The file holds, per quad, ``B_SPLINE_SURFACE_WITH_KNOTS`` (its
poles), ``FACE_BOUND``/``EDGE_LOOP`` of four ``ORIENTED_EDGE``; per mesh edge one ``EDGE_CURVE``
whose ``B_SPLINE_CURVE_WITH_KNOTS`` is the boundary row of the first quad that has it; per mesh
vertex one ``VERTEX_POINT``; a pole shared by neighbouring quads (equal within
:data:`~g1patch.io.cad.step_text.STEP_MATCH_RTOL` of the model's size, as OCC's compacted files
share them) is one ``CARTESIAN_POINT``. Each connected component whose every edge has two faces is
a ``MANIFOLD_SOLID_BREP`` turned outwards (the sign of its volume, by the divergence theorem over
the quads' control corners and centres), the others an ``OPEN_SHELL`` in a
``SHELL_BASED_SURFACE_MODEL``. Coordinates have :data:`~g1patch.io.cad.step_text.STEP_DIGITS`
significant digits, as in OCC's compacted files. OpenCASCADE reads the result as the same
B-rep its own writer made (tests/test_step_write.py: valid, solid, same faces, G1 angles).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ...network import PatchNetwork
from .bspline import QuadFaces
from .step_text import STEP_MATCH_RTOL, _step_reals

__all__ = ["QuadBrep", "quad_brep", "write_quad_step"]

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]

#: values formatted at once (bounds the format string to ~100 MB)
_CHUNK = 1 << 22


class QuadBrep(NamedTuple):
    """The B-rep of a split4 network's quads (:func:`quad_brep`). Per quad (in quad order) its
    ``net`` as point ids ``grids[size][row]`` (``size`` 4 or 6 poles a side, ``row`` its row in
    that group), its ``corners`` (vertex ids), ``sides`` (edge ids) and whether each side runs
    along its edge's curve (``forward``); per edge the quad side ``4 q + k`` whose row is its curve
    (``owner``, the first that has it) and the curve's point ids (``edge_rows``, padded
    with −1 after ``edge_length``); ``points`` the distinct poles; per quad its ``component`` and
    per component whether it is ``closed``; per quad whether its face is ``reversed`` (a closed
    component turned inside out: the face's normal is the surface's negated, its loop runs the
    other way), so every face points out of its solid."""

    points: FloatArray
    size: IntArray
    row: IntArray
    grids: dict[int, IntArray]
    corners: IntArray
    sides: IntArray
    forward: NDArray[np.bool_]
    owner: IntArray
    edge_rows: IntArray
    edge_length: IntArray
    component: IntArray
    closed: NDArray[np.bool_]
    reversed: NDArray[np.bool_]

    @property
    def free_edges(self) -> int:
        """Edges of one face (boundaries and holes)."""
        return int((np.bincount(self.sides.ravel(), minlength=len(self.edge_rows)) == 1).sum())


#: pole rows of side k of a net with ``s`` poles a side, from corner k to corner k + 1 (corners
#: (0, 0), (s−1, 0), (s−1, s−1), (0, s−1); the first index runs with u)
def _side_index(s: int) -> tuple[IntArray, IntArray]:
    r, last = np.arange(s), s - 1
    zeros, lasts = np.zeros(s, dtype=np.int64), np.full(s, last)
    return (
        np.stack([r, lasts, r[::-1], zeros]),
        np.stack([zeros, r, lasts, r[::-1]]),
    )


def _components(sides: IntArray, n_edges: int) -> tuple[int, IntArray, NDArray[np.bool_]]:
    """Connected components of quads across shared edges, and which are closed (every edge of
    theirs has two quads)."""
    n_quads = sides.shape[0]
    faces = np.repeat(np.arange(n_quads), 4)
    incidence = coo_matrix(
        (np.ones(faces.size), (sides.ravel(), faces)), shape=(n_edges, n_quads)
    ).tocsr()
    count, component = connected_components(incidence.T @ incidence, directed=False)
    shared = np.bincount(sides.ravel(), minlength=n_edges) == 2
    open_quad = ~shared[sides].all(axis=1)
    closed = np.bincount(component[open_quad], minlength=count) == 0
    return count, component.astype(np.int64), closed


def _signed_volumes(
    nets: dict[int, FloatArray], which: dict[int, IntArray], component: IntArray, count: int
) -> FloatArray:
    """Per component ``Σ (a × b)·c / 6`` over the triangles from each net's centre pole ``c`` to
    its corner pairs ``(a, b)`` in side order: the closed control polyhedron's volume, whose sign
    is the surface's orientation."""
    volume = np.zeros(count)
    for s, net in nets.items():
        last = s - 1
        corner = net[:, [0, last, last, 0], [0, 0, last, last]]
        centre = net[:, s // 2, s // 2]
        part = np.einsum("fkd,fd->f", np.cross(corner, np.roll(corner, -1, axis=1)), centre) / 6
        volume += np.bincount(component[which[s]], weights=part, minlength=count)
    return volume


def quad_brep(quads: QuadFaces, network: PatchNetwork) -> QuadBrep | None:
    """The B-rep of the quads of ``network`` (``quads``: its :func:`split4_quad_faces`), or None
    when a quad's side has one vertex at both ends (sewing must decide there)."""
    n_quads = len(quads.single)
    first = 4 * np.arange(n_quads)[:, None] + np.arange(4)[None]
    corners = network.corner_ids[first, np.arange(4)[None]]
    if (corners == np.roll(corners, -1, axis=1)).any():
        return None
    _, sides = np.unique(network.edge_ids[first, np.arange(4)[None]] >> 1, return_inverse=True)
    sides = sides.reshape(n_quads, 4).astype(np.int64)
    n_edges = int(sides.max()) + 1
    count, component, closed = _components(sides, n_edges)

    size = np.where(quads.single, 4, 6)
    which = {4: np.flatnonzero(quads.single), 6: np.flatnonzero(~quads.single)}
    nets = {4: quads.bezier.control, 6: quads.two_span.control}
    nets = {s: net for s, net in nets.items() if len(net)}
    inside_out = (_signed_volumes(nets, which, component, count) < 0) & closed

    # point ids: the poles of the 4×4 quads, then those of the 6×6 ones
    row = np.empty(n_quads, dtype=np.int64)
    grids: dict[int, IntArray] = {}
    side_rows = np.full((n_quads, 4, 6), -1, dtype=np.int64)
    offset = 0
    for s, net in nets.items():
        row[which[s]] = np.arange(len(net))
        grids[s] = offset + np.arange(net.size // 3).reshape(-1, s, s)
        offset += net.size // 3
        i, j = _side_index(s)
        side_rows[which[s], :, :s] = grids[s][:, i, j]
    points = np.concatenate([net.reshape(-1, 3) for net in nets.values()])

    flat = sides.ravel()
    owner = np.empty(n_edges, dtype=np.int64)
    owner[flat[::-1]] = np.arange(flat.size)[::-1]  # the first quad side that has the edge
    forward = corners == corners.ravel()[owner[sides]]
    edge_rows = side_rows.reshape(-1, 6)[owner]
    edge_length = size[owner // 4]

    # a side's poles equal to its edge's row (reversed where it runs backwards) become that
    # row's points; corners follow through the sides that meet there
    theirs = edge_rows[flat]
    length = edge_length[flat]
    backwards = ~forward.ravel()
    reversed_rows = np.take_along_axis(
        theirs, np.clip(length[:, None] - 1 - np.arange(6)[None], 0, 5), axis=1
    )
    theirs = np.where(backwards[:, None], reversed_rows, theirs)
    mine = side_rows.reshape(-1, 6)
    valid = np.arange(6)[None] < length[:, None]
    same_size = size[np.arange(flat.size) // 4] == length
    candidate = same_size & (owner[flat] != np.arange(flat.size))
    scale = max(float(np.abs(points).max()), 1.0) if len(points) else 1.0
    gap = np.zeros(flat.size)
    for pole in range(6):  # pole by pole: (4F, 3) temporaries, not (4F, 6, 3)
        at = valid[:, pole]
        gap[at] = np.maximum(
            gap[at], np.abs(points[mine[at, pole]] - points[theirs[at, pole]]).max(axis=1)
        )
    take = candidate & (gap <= STEP_MATCH_RTOL * scale)
    alias = np.arange(len(points))
    alias[mine[take][valid[take]]] = theirs[take][valid[take]]
    while True:
        deeper = alias[alias]
        if np.array_equal(deeper, alias):
            break
        alias = deeper
    root = alias == np.arange(len(points))  # every alias is a root now: number them densely
    alias = (np.cumsum(root) - 1)[alias]
    grids = {s: alias[grid] for s, grid in grids.items()}
    edge_rows = np.where(edge_rows >= 0, alias[np.maximum(edge_rows, 0)], -1)
    return QuadBrep(
        points[root],
        size,
        row,
        grids,
        corners,
        sides,
        forward,
        owner,
        edge_rows,
        edge_length,
        component,
        closed,
        inside_out[component],
    )


_HEADER = """ISO-10303-21;
HEADER;
FILE_DESCRIPTION(('g1patch exact B-spline faces'),'2;1');
FILE_NAME('{name}','{stamp}',(''),(''),'g1patch','g1patch','');
FILE_SCHEMA(('AUTOMOTIVE_DESIGN {{ 1 0 10303 214 1 1 1 1 }}'));
ENDSEC;
DATA;
"""

#: the product, its context and units (millimetres, as OCC writes by default): entities 1–16,
#: the shape representation's items and context filled in by :func:`_product`
_PRODUCT = (
    "#1=APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2000,#2)"
    ";\n"
    "#2=APPLICATION_CONTEXT('core data for automotive mechanical design processes');\n"
    "#3=SHAPE_DEFINITION_REPRESENTATION(#4,#{representation});\n"
    "#4=PRODUCT_DEFINITION_SHAPE('','',#5);\n"
    "#5=PRODUCT_DEFINITION('design','',#6,#9);\n"
    "#6=PRODUCT_DEFINITION_FORMATION('','',#7);\n"
    "#7=PRODUCT('{name}','{name}','',(#8));\n"
    "#8=PRODUCT_CONTEXT('',#2,'mechanical');\n"
    "#9=PRODUCT_DEFINITION_CONTEXT('part definition',#2,'design');\n"
    "#10=PRODUCT_RELATED_PRODUCT_CATEGORY('part',$,(#7));\n"
    "#11=( GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#15)) GLO"
    "BAL_UNIT_ASSIGNED_CONTEXT((#12,#13,#14)) REPRESENTATION_CONTEXT('Context #1','3D Context"
    " with UNIT and UNCERTAINTY') );\n"
    "#12=( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );\n"
    "#13=( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) );\n"
    "#14=( NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT() );\n"
    "#15=UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE({uncertainty}),#12,'distance_accuracy_v"
    "alue','confusion accuracy');\n"
    "#16=AXIS2_PLACEMENT_3D('',#17,#18,#19);\n"
    "#17=CARTESIAN_POINT('',(0.,0.,0.));\n"
    "#18=DIRECTION('',(0.,0.,1.));\n"
    "#19=DIRECTION('',(1.,0.,0.));\n"
)
_FIRST_FREE = 20
#: an oriented edge's sense in a reversed face's loop
_OTHER = {".T.": ".F.", ".F.": ".T."}

#: knot multiplicities and values of the curves and the surfaces with 4 (one span) and 6 (two
#: spans, a double knot at ½) poles a side
_KNOTS = {4: "(4,4),(0.,1.)", 6: "(4,2,4),(0.,0.5,1.)"}
_SURFACE_KNOTS = {4: "(4,4),(4,4),(0.,1.),(0.,1.)", 6: "(4,2,4),(4,2,4),(0.,0.5,1.),(0.,0.5,1.)"}


def _real_lines(points: FloatArray, first: int) -> Iterator[str]:
    """``CARTESIAN_POINT`` entities ``first, first + 1, …`` of ``points``, formatted in chunks."""
    flat = points.reshape(-1)
    step = _CHUNK - _CHUNK % 3
    for start in range(0, flat.size, step):
        reals = [text.decode() for text in _step_reals(flat[start : start + step])]
        base = first + start // 3
        yield "".join(
            f"#{base + n}=CARTESIAN_POINT('',({x},{y},{z}));\n"
            for n, (x, y, z) in enumerate(zip(reals[0::3], reals[1::3], reals[2::3], strict=True))
        )


def write_quad_step(
    path: Path,
    brep: QuadBrep,
    names: list[str] | None,
    colours: FloatArray | None,
    uncertainty: float,
    title: str,
    stamp: str,
) -> None:
    """Write ``brep`` (:func:`quad_brep`) as STEP AP214 to ``path``: faces named ``names`` (else
    ``'face n'``), coloured by the rows of ``colours`` (F, 3) sRGB that are not NaN, the model's
    ``uncertainty`` (model units) as its confusion accuracy; ``title`` and ``stamp`` for the
    header. See the module docstring for the entities."""
    n_quads = len(brep.corners)
    n_edges = len(brep.edge_rows)
    n_points = len(brep.points)
    p0 = _FIRST_FREE  # point n is entity p0 + n
    v0 = p0 + n_points  # vertex of mesh corner id c: v0 + vertex_index[c]
    corner_ids = np.unique(brep.corners)
    vertex_index = np.full(int(corner_ids.max()) + 1, -1, dtype=np.int64)
    vertex_index[corner_ids] = np.arange(corner_ids.size)
    owner = brep.owner
    start_corner = brep.corners.ravel()[owner]
    end_corner = np.roll(brep.corners, -1, axis=1).ravel()[owner]
    first_end = np.empty(corner_ids.size, dtype=np.int64)  # a point for each vertex: an edge end
    last = brep.edge_rows[np.arange(n_edges), brep.edge_length - 1]
    ends = np.concatenate([vertex_index[start_corner], vertex_index[end_corner]])
    end_points = np.concatenate([brep.edge_rows[:, 0], last])
    first_end[ends[::-1]] = end_points[::-1]
    c0 = v0 + corner_ids.size  # curve of edge e: c0 + 2e, its EDGE_CURVE c0 + 2e + 1
    f0 = c0 + 2 * n_edges  # quad q: f0 + 9q … (4 oriented edges, loop, bound, surface, face)
    s0 = f0 + 9 * n_quads  # shells, solids, the representation, then colours

    order = np.argsort(brep.component, kind="stable")
    count = int(brep.component.max()) + 1 if n_quads else 0
    solids = bool(brep.closed.all()) and count > 0
    shell_id = s0 + np.arange(count)
    representation = s0 + count + (count if solids else 1)
    with open(path, "w", encoding="ascii", newline="\n") as out:
        out.write(_HEADER.format(name=title, stamp=stamp))
        out.write(
            _PRODUCT.format(
                representation=representation,
                name=title,
                uncertainty=_step_reals(np.array([uncertainty]))[0].decode(),
            )
        )
        for chunk in _real_lines(brep.points, p0):
            out.write(chunk)
        out.write(
            "".join(
                f"#{v0 + n}=VERTEX_POINT('',#{p0 + p});\n" for n, p in enumerate(first_end.tolist())
            )
        )
        rows = brep.edge_rows + p0
        for e, (length, start, end) in enumerate(
            zip(brep.edge_length.tolist(), start_corner.tolist(), end_corner.tolist(), strict=True)
        ):
            poles = ",".join(f"#{i}" for i in rows[e, :length].tolist())
            out.write(
                f"#{c0 + 2 * e}=B_SPLINE_CURVE_WITH_KNOTS('',3,({poles}),.UNSPECIFIED.,.F.,.F.,"
                f"{_KNOTS[length]},.UNSPECIFIED.);\n"
                f"#{c0 + 2 * e + 1}=EDGE_CURVE('',#{v0 + vertex_index[start]},"
                f"#{v0 + vertex_index[end]},#{c0 + 2 * e},.T.);\n"
            )
        sense = np.where(brep.forward, ".T.", ".F.")
        for q in range(n_quads):
            s = int(brep.size[q])
            grid = brep.grids[s][brep.row[q]] + p0
            base = f0 + 9 * q
            surface = ",".join(f"({','.join(f'#{i}' for i in line)})" for line in grid.tolist())
            name = names[q] if names is not None else f"face {q}"
            edges = brep.sides[q].tolist()
            turned = bool(brep.reversed[q])
            out.write(
                "".join(
                    f"#{base + n}=ORIENTED_EDGE('',*,*,#{c0 + 2 * edges[k] + 1},"
                    f"{_OTHER[sense[q, k]] if turned else sense[q, k]});\n"
                    for n, k in enumerate((3, 2, 1, 0) if turned else range(4))
                )
                + f"#{base + 4}=EDGE_LOOP('',(#{base},#{base + 1},#{base + 2},#{base + 3}));\n"
                f"#{base + 5}=FACE_BOUND('',#{base + 4},.T.);\n"
                f"#{base + 6}=B_SPLINE_SURFACE_WITH_KNOTS('',3,3,({surface}),.UNSPECIFIED.,"
                f".F.,.F.,.F.,{_SURFACE_KNOTS[s]},.UNSPECIFIED.);\n"
                f"#{base + 7}=ADVANCED_FACE('{name}',(#{base + 5}),#{base + 6},"
                f"{'.F.' if turned else '.T.'});\n"
            )
        members = np.split(
            f0 + 9 * order + 7, np.cumsum(np.bincount(brep.component, minlength=count))[:-1]
        )
        for c, faces in enumerate(members):
            kind = "CLOSED_SHELL" if brep.closed[c] else "OPEN_SHELL"
            out.write(f"#{shell_id[c]}={kind}('',({','.join(f'#{i}' for i in faces.tolist())}));\n")
        if solids:
            items = s0 + count + np.arange(count)
            out.write(
                "".join(
                    f"#{items[c]}=MANIFOLD_SOLID_BREP('',#{shell_id[c]});\n" for c in range(count)
                )
            )
            out.write(
                f"#{representation}=ADVANCED_BREP_SHAPE_REPRESENTATION('',(#16,"
                f"{','.join(f'#{i}' for i in items.tolist())}),#11);\n"
            )
        else:
            model = s0 + count
            out.write(
                f"#{model}=SHELL_BASED_SURFACE_MODEL('',"
                f"({','.join(f'#{i}' for i in shell_id.tolist())}));\n"
                f"#{representation}=MANIFOLD_SURFACE_SHAPE_REPRESENTATION('',(#16,#{model}),#11);\n"
            )
        if colours is not None:
            _write_colours(out, colours, f0 + 9 * np.arange(n_quads) + 7, representation + 1)
        out.write("ENDSEC;\nEND-ISO-10303-21;\n")


def _write_colours(out: Any, colours: FloatArray, faces: IntArray, first: int) -> None:
    """AP214 styled items: one presentation style per distinct colour, a ``STYLED_ITEM`` per
    coloured face, gathered in a ``MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION``."""
    coloured = np.flatnonzero(~np.isnan(colours).any(axis=1))
    if not coloured.size:
        return
    palette, which = np.unique(colours[coloured], axis=0, return_inverse=True)
    style = first + 7 * np.arange(len(palette)) + 6
    lines = []
    for n, rgb in enumerate(palette.tolist()):
        b = first + 7 * n
        r, g, bl = (text.decode() for text in _step_reals(np.array(rgb)))
        lines.append(
            f"#{b}=COLOUR_RGB('',{r},{g},{bl});\n"
            f"#{b + 1}=FILL_AREA_STYLE_COLOUR('',#{b});\n"
            f"#{b + 2}=FILL_AREA_STYLE('',(#{b + 1}));\n"
            f"#{b + 3}=SURFACE_STYLE_FILL_AREA(#{b + 2});\n"
            f"#{b + 4}=SURFACE_SIDE_STYLE('',(#{b + 3}));\n"
            f"#{b + 5}=SURFACE_STYLE_USAGE(.BOTH.,#{b + 4});\n"
            f"#{b + 6}=PRESENTATION_STYLE_ASSIGNMENT((#{b + 5}));\n"
        )
    item0 = first + 7 * len(palette)
    items = item0 + np.arange(coloured.size)
    lines.extend(
        f"#{i}=STYLED_ITEM('color',(#{s}),#{f});\n"
        for i, s, f in zip(
            items.tolist(), style[which.ravel()].tolist(), faces[coloured].tolist(), strict=True
        )
    )
    lines.append(
        f"#{item0 + coloured.size}=MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION('',"
        f"({','.join(f'#{i}' for i in items.tolist())}),#11);\n"
    )
    out.write("".join(lines))
