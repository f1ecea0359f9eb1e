"""STEP text after OCC wrote it: :func:`compact_step` shares equal points and writes the poles
with :data:`STEP_DIGITS` significant digits (bytes in, bytes out; no OpenCASCADE here)."""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .bspline import BSplineFit, QuadFaces

_ENTITY_END = re.compile(rb";[ \t\r]*\n(?=#\d)")
_REFERENCE = re.compile(rb"#(\d+)")
#: a face named ``'face N'`` or ``'GROUP N'`` (group names hold no quote: ``_step_text``)
_NAMED_FACE = re.compile(rb"ADVANCED_FACE\('[^']*? (\d+)',\([^)]*\),#(\d+),")
_POLE_GRID = re.compile(rb"B_SPLINE_SURFACE_WITH_KNOTS\('[^']*',\d+,\d+,\(\((.*?)\)\),")
_BLANKS = re.compile(rb"\n[ \t\r\n\f\v]*")
#: significant digits of the coordinates :func:`compact_step` writes (OCC's writer: 12)
STEP_DIGITS = 15


def _step_reals(values: NDArray[np.float64]) -> list[bytes]:
    """STEP reals with :data:`STEP_DIGITS` significant digits, each with its decimal point (``1.``,
    ``1.E+20``)."""
    texts = (f"%.{STEP_DIGITS}G," * values.size % tuple(values.tolist())).encode().split(b",")[:-1]
    return [
        text if b"." in text else text.replace(b"E", b".E") if b"E" in text else text + b"."
        for text in texts
    ]


# : a file's 12-digit pole and the exact one agree to this share of the model's size
# (:func:`compact_step`)
STEP_MATCH_RTOL = 1e-10


def _face_nets(faces: BSplineFit | QuadFaces) -> list[NDArray[np.float64]]:
    """The world control net of every face, in face order (split4 quads: 4×4 single-span or 6×6)."""
    if isinstance(faces, BSplineFit):
        return list(faces.control)
    single, two = iter(faces.bezier.control), iter(faces.two_span.control)
    return [next(single) if one else next(two) for one in faces.single.tolist()]


def compact_step(
    path: Path, nets: Sequence[NDArray[np.float64]] = (), tolerance: float = 0.0
) -> None:
    """Rewrite a STEP file written by OCC: equal ``CARTESIAN_POINT`` entities become one, surface
    poles get :data:`STEP_DIGITS` digits, entities are numbered densely, without line breaks.

    OCC's writer gives every surface pole, every edge curve's pole and every vertex its own point
    entity, so a pole on a mesh edge is written once per face, once per edge curve and once per
    vertex: points with the same text (blanks removed) become the first of them. OCC writes 12
    significant digits, which leaves OCC's normals across Spot's small faces 7e-8° apart on reading
    back: the poles of face ``'face N'`` or ``'GROUP N'`` (its ``B_SPLINE_SURFACE_WITH_KNOTS``) are
    written from ``nets[N]`` (world poles, (nu, nv, 3)) with 15, where the file's value agrees
    with it within ``tolerance`` (so a point is only ever made more precise). The same B-rep; a
    split4 network's file is a third smaller.
    """
    text = path.read_bytes()
    start = text.index(b"\nDATA;") + len(b"\nDATA;")
    end = text.index(b"\nENDSEC;", start)
    # one pass each over the whole section: entity ends marked, line breaks removed, split
    entities = _BLANKS.sub(b"", _ENTITY_END.sub(b"\0", text[start:end].strip())).split(b"\0")
    entities[-1] = entities[-1].rstrip(b";")
    heads = [entity.partition(b"=") for entity in entities]
    bodies = {name.strip()[1:]: body.strip() for name, _, body in heads}
    first: dict[bytes, bytes] = {}
    # point number → the number of the first equal point
    canonical = {
        number: first.setdefault(body, number)
        for number, body in bodies.items()
        if body.startswith(b"CARTESIAN_POINT(")
    }
    points: list[bytes] = []  # every surface pole of a named face, as its canonical point …
    poles: list[NDArray[np.float64]] = []  # … and the exact net it belongs to
    for face, surface in _NAMED_FACE.findall(
        b"".join(body for body in bodies.values() if b"ADVANCED_FACE" in body)
    ):
        grid = _POLE_GRID.match(bodies.get(surface, b""))
        if grid is None or int(face) >= len(nets):
            continue
        rows = [_REFERENCE.findall(row) for row in grid.group(1).split(b"),(")]
        net = nets[int(face)]
        if [len(row) for row in rows] != [net.shape[1]] * net.shape[0]:
            continue
        points.extend(canonical[number] for row in rows for number in row)
        poles.append(np.asarray(net, dtype=np.float64).reshape(-1, 3))
    exact: dict[bytes, bytes] = {}
    if points:
        distinct = list(dict.fromkeys(points))
        where = {point: n for n, point in enumerate(distinct)}
        written = np.array(
            b",".join(bodies[point].split(b"(")[-1].rstrip(b")") for point in distinct).split(b","),
            dtype=np.float64,
        ).reshape(len(distinct), 3)
        pole = np.concatenate(poles)
        close = np.abs(written[[where[point] for point in points]] - pole).max(axis=1) <= tolerance
        chosen = {
            points[k]: k for k in np.flatnonzero(close).tolist()
        }  # the last matching pole of each point
        reals = _step_reals(pole[list(chosen.values())].reshape(-1))
        exact = {
            point: b"CARTESIAN_POINT('',(" + b",".join(reals[3 * n : 3 * n + 3]) + b"))"
            for n, point in enumerate(chosen)
        }
    kept = [
        (number, exact.get(number, body))
        for number, body in bodies.items()
        if canonical.get(number, number) == number
    ]
    renumber = {number: str(n).encode() for n, (number, _) in enumerate(kept, start=1)}
    renumber.update({number: renumber[point] for number, point in canonical.items()})
    parts = _REFERENCE.split(
        b"".join(b"#" + number + b"=" + body + b";\n" for number, body in kept)
    )
    parts[1::2] = [
        b"#" + renumber[number] for number in parts[1::2]
    ]  # every reference (and entity number) renumbered
    data = b"".join(parts)
    path.write_bytes(text[:start] + b"\n" + data.rstrip(b"\n") + text[end:])
