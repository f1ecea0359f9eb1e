"""Quad layouts of dense triangle meshes: Instant Meshes (Jakob et al. 2015, field-aligned
remeshing) through its maintained nanobind binding ``pynanoinstantmeshes``.

The remesher runs in a child process (:func:`quad_layout`): a crash inside native code becomes
a clear :class:`~g1patch.errors.ConstructionError`, its progress chatter on stdout stays out of
ours, and a hang ends at ``timeout``. It runs deterministically (``deterministic=True``: the
same input gives the same layout, bit for bit). Its raw output is quad-dominant; it returns the
pure-quad mesh of one regular split of that (about 4 quads per requested vertex), which is the
cage the fit solves for. On some inputs that output has coincident vertices and degenerate quads
(a corner repeated, zero area); :func:`clean_layout` merges and drops them before the cage is
built.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import ConstructionError, InputError, MissingDependencyError
from ..mesh.validate import DEGENERATE_AREA_TOLERANCE

__all__ = ["LAYOUT_TIMEOUT", "clean_layout", "quad_layout"]

#: seconds the remesher may take before it is stopped
LAYOUT_TIMEOUT = 600.0

#: the child: read the triangles, remesh, write the quads (stdout is the remesher's chatter)
_CHILD = """
import sys
import numpy as np
import pynanoinstantmeshes
given = np.load(sys.argv[1])
vertices, quads = pynanoinstantmeshes.remesh(
    given["points"].astype(np.float32),
    given["triangles"].astype(np.uint32),
    int(given["vertex_count"]),
    deterministic=True,
)
np.savez(sys.argv[2], vertices=np.asarray(vertices, dtype=np.float64),
         quads=np.asarray(quads, dtype=np.int64))
"""


def _check_remesher() -> None:
    """:class:`MissingDependencyError` naming the extra to install when the binding is absent."""
    import importlib.util

    if importlib.util.find_spec("pynanoinstantmeshes") is None:
        raise MissingDependencyError(
            "pynanoinstantmeshes", "fit", "a quad layout (Instant Meshes; or pass one: --layout)"
        )


def quad_layout(
    points: NDArray[np.float64],
    triangles: NDArray[np.int64],
    faces: int,
    *,
    timeout: float = LAYOUT_TIMEOUT,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A pure-quad layout of about ``faces`` quads over the triangles (``points`` (V, 3),
    ``triangles`` (T, 3)), by Instant Meshes in a child process: ``(vertices, quads)``.

    The remesher is asked for ``faces / 4`` vertices (its quad-dominant result is split once
    into quads, four per face), then cleaned (:func:`clean_layout`). Raises
    :class:`ConstructionError` when it fails, crashes, times out or returns no usable quads."""
    if isinstance(faces, bool) or not isinstance(faces, (int, np.integer)) or faces < 16:
        raise InputError(f"faces: expected a number of quads ≥ 16, got {faces!r}")
    _check_remesher()
    with tempfile.TemporaryDirectory(prefix="g1patch-layout-") as folder:
        given, taken = Path(folder) / "given.npz", Path(folder) / "taken.npz"
        np.savez(given, points=points, triangles=triangles, vertex_count=max(int(faces) // 4, 4))
        environment = {**os.environ, "OMP_NUM_THREADS": os.environ.get("OMP_NUM_THREADS", "1")}
        try:
            result = subprocess.run(
                [sys.executable, "-c", _CHILD, str(given), str(taken)],
                capture_output=True,
                text=True,
                timeout=timeout,
                env=environment,
                check=False,
            )
        except subprocess.TimeoutExpired:
            raise ConstructionError(
                f"the quad remesher (Instant Meshes) did not finish in {timeout:g} s"
            ) from None
        if result.returncode != 0 or not taken.exists():
            last = (result.stderr.strip().splitlines() or [f"exit status {result.returncode}"])[-1]
            raise ConstructionError(f"the quad remesher (Instant Meshes) failed: {last[:200]}")
        with np.load(taken) as made:
            vertices, quads = made["vertices"], made["quads"]
    if quads.ndim != 2 or quads.shape[1] != 4 or not len(quads):
        raise ConstructionError("the quad remesher (Instant Meshes) returned no quads")
    vertices, quads = clean_layout(vertices, quads)
    if not len(quads):
        raise ConstructionError("the quad remesher (Instant Meshes) returned only degenerate quads")
    return vertices, quads


def clean_layout(
    vertices: NDArray[np.float64], quads: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The layout with coincident vertices merged and the quads dropped that a cage cannot have:
    a corner repeated, zero area (``|d1 × d2| ≤ tol · max(|d1|², |d2|²)``, d1 and d2 the
    diagonals, as :mod:`~g1patch.mesh.validate` refuses) or an edge shared by more than two
    quads (every quad at such an edge). Unused vertices stay (the mesh drops them)."""
    merged, inverse = np.unique(vertices, axis=0, return_inverse=True)
    quads = inverse.reshape(-1)[quads]
    ordered = np.sort(quads, axis=1)
    repeated = (ordered[:, 1:] == ordered[:, :-1]).any(axis=1)
    corners = merged[quads]
    d1, d2 = corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1]
    size = np.maximum((d1 * d1).sum(1), (d2 * d2).sum(1))
    flat = np.linalg.norm(np.cross(d1, d2), axis=1) <= DEGENERATE_AREA_TOLERANCE * size
    quads = quads[~(repeated | flat)]
    sides = np.stack([quads, np.roll(quads, -1, axis=1)], axis=-1)
    key = sides.min(axis=-1) * len(merged) + sides.max(axis=-1)
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    crowded = (counts[inverse] > 2).reshape(key.shape).any(axis=1)
    return merged, quads[~crowded]
