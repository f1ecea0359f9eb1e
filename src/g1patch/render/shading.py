"""Colours of the shaded and zebra modes: the lights, lit colours at the sample points, and
the zebra stripes' whiteness."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .camera import _Camera

_SURFACE_COLOUR = np.array([0.60, 0.72, 0.88])
_STRIPE_DARK = 0.05


def _lights(
    camera: _Camera,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Key light (upper left, in front), fill light (right), and the highlight's half vector."""
    key = -0.45 * camera.right + 0.60 * camera.up + 0.66 * camera.eye
    fill = 0.70 * camera.right - 0.15 * camera.up + 0.70 * camera.eye
    key, fill = key / np.linalg.norm(key), fill / np.linalg.norm(fill)
    half = key + camera.eye
    return key, fill, half / np.linalg.norm(half)


def _diffuse(
    normals: NDArray[np.float64], camera: _Camera
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Diffuse light in [0, 1] (ambient + key + fill) and the highlight, for normals facing the
    viewer."""
    key, fill, half = _lights(camera)
    diffuse = (
        0.42 + 0.48 * np.clip(normals @ key, 0.0, 1.0) + 0.18 * np.clip(normals @ fill, 0.0, 1.0)
    )
    highlight = np.clip(normals @ half, 0.0, 1.0) ** 40
    return np.clip(diffuse, 0.0, 1.0), highlight


def _shaded_colours(
    normals: NDArray[np.float64], camera: _Camera, base: NDArray[np.float64], gloss: float
) -> NDArray[np.float64]:
    """RGB (…, 3) of ``base`` lit at unit ``normals`` (…, 3) that face the viewer."""
    diffuse, highlight = _diffuse(normals, camera)
    rgb = diffuse[..., None] * base + gloss * highlight[..., None]
    return np.clip(rgb, 0.0, 1.0)


def _zebra_values(phase: NDArray[np.float64], triangles: NDArray[np.int64]) -> NDArray[np.float64]:
    """Whiteness in [0, 1] of the stripes at every point, from its phase (P,).

    The step ``sin φ ≥ 0`` is softened to a ramp about one triangle wide (``sin φ / s`` clipped,
    s the phase change across the point's triangles), so that the linear colour interpolation
    inside the triangles draws a sharp, antialiased stripe edge along the interpolated contour.
    Where the stripes are finer than the triangles (near the poles of the stripe axis) the
    stripes fade to grey instead of aliasing into moiré.
    """
    corner = phase[triangles]
    corner = (
        corner[:, :1] + (corner - corner[:, :1] + np.pi) % (2.0 * np.pi) - np.pi
    )  # unwrapped about corner 0
    spread = np.zeros(len(phase))
    np.maximum.at(
        spread, triangles.reshape(-1), np.repeat(corner.max(axis=1) - corner.min(axis=1), 3)
    )
    softness = np.clip(0.5 * spread, 0.02, 1.0)
    value = np.clip(0.5 + 0.5 * np.sin(phase) / softness, 0.0, 1.0)
    blur = np.clip((spread - 0.5 * np.pi) / np.pi, 0.0, 1.0)
    return (1.0 - blur) * value + 0.5 * blur
