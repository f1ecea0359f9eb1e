"""Pictures a person can judge: shaded surfaces rendered with matplotlib (Agg, off-screen)."""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from .errors import InputError, MissingDependencyError
from .io.atomic import atomic_path
from .tessellate import TriangleMesh

__all__ = ["render_surfaces"]

_LIGHT = np.array([0.4, -0.5, 0.77])


def _shade(mesh: TriangleMesh) -> NDArray[np.float64]:
    """Lambert shading of each triangle with a fixed light, as RGBA colours."""
    normals = mesh.normals[mesh.triangles].mean(axis=1)
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    intensity = 0.25 + 0.75 * np.clip(normals @ (_LIGHT / np.linalg.norm(_LIGHT)), 0.0, 1.0)
    base = np.array([0.55, 0.68, 0.85])
    colours = np.empty((len(mesh.triangles), 4))
    colours[:, :3] = intensity[:, None] * base
    colours[:, 3] = 1.0
    return colours


def render_surfaces(
    path: str | os.PathLike[str],
    meshes: Sequence[TriangleMesh],
    titles: Sequence[str],
    *,
    size: tuple[int, int] = (1200, 600),
) -> None:
    """Write a PNG with the shaded ``meshes`` side by side, each under its title."""
    if len(meshes) != len(titles) or not meshes:
        raise InputError(f"titles: expected one title per mesh ({len(meshes)}), got {len(titles)}")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    except ImportError:
        raise MissingDependencyError("matplotlib", "viz", "rendering pictures") from None
    dpi = 100
    figure = plt.figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    try:
        for column, (mesh, title) in enumerate(zip(meshes, titles), start=1):
            axes = figure.add_subplot(1, len(meshes), column, projection="3d")
            triangles = mesh.points[mesh.triangles]
            axes.add_collection3d(Poly3DCollection(triangles, facecolors=_shade(mesh), edgecolors="none", linewidths=0, antialiased=False))
            low, high = mesh.points.min(axis=0), mesh.points.max(axis=0)
            centre, radius = (low + high) / 2, (high - low).max() / 2
            for setter, middle in zip((axes.set_xlim, axes.set_ylim, axes.set_zlim), centre):
                setter(middle - radius, middle + radius)
            axes.set_box_aspect((1, 1, 1), zoom=1.3)
            axes.view_init(elev=25, azim=-60)
            axes.set_axis_off()
            axes.set_title(title)
        with atomic_path(path) as temporary:
            figure.savefig(temporary, format="png", dpi=dpi)
    finally:
        plt.close(figure)
