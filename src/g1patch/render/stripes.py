"""Zebra stripes: the reflection-line phase of a normal (:func:`stripe_phase`) and what the
zebra picture shows across every shared edge (:func:`stripe_jumps`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..continuity import DEGENERATE_RTOL
from ..errors import InputError, check_choice
from ..network import PatchNetwork, edge_parameters
from .camera import AUTO, DEFAULT_VIEW, UP_AXES, _Camera, _camera, _check_view
from .checks import _check_network

#: black/white stripe pairs per full turn of the reflected direction about the stripe axis
DEFAULT_STRIPES = 12


def _check_stripes(stripes: object) -> int:
    if (
        isinstance(stripes, bool)
        or not isinstance(stripes, (int, np.integer))
        or not 1 <= stripes <= 1000
    ):
        raise InputError(f"stripes: expected an integer from 1 to 1000, got {stripes!r}")
    return int(stripes)


def stripe_phase(
    normals: NDArray[np.float64],
    view: tuple[float, float] = DEFAULT_VIEW,
    stripes: int = DEFAULT_STRIPES,
    up: str = "z",
) -> NDArray[np.float64]:
    """Zebra stripe phase φ (radians) at unit ``normals`` (…, 3); white where ``sin φ ≥ 0``.

    ``r = d − 2 (d·n) n`` with d the viewing direction of ``view``; ``φ = stripes · atan2(r·b,
    r·a)`` about the stripe axis (see the module docstring). A function of the normal alone.
    """
    view, stripes, up = (
        _check_view(view, auto=False),
        _check_stripes(stripes),
        check_choice("up", up, UP_AXES),
    )
    camera = _Camera.from_view(view, up)
    return _phase(np.asarray(normals, dtype=np.float64), camera, stripes)


def _phase(normals: NDArray[np.float64], camera: _Camera, stripes: int) -> NDArray[np.float64]:
    d = -camera.eye
    reflected = d - 2.0 * (normals @ d)[..., None] * normals
    a, b = camera.stripe_frame()
    return stripes * np.arctan2(reflected @ b, reflected @ a)


def stripe_jumps(
    network: PatchNetwork,
    *,
    view: tuple[float, float] | str = AUTO,
    stripes: int = DEFAULT_STRIPES,
    samples: int = 33,
    up: str = AUTO,
) -> NDArray[np.float64]:
    """Per shared edge, the largest jump of the zebra stripe phase across it, in stripe periods.

    Edges in the order of :meth:`PatchNetwork.shared_edges` (the first rows of a
    ContinuityReport's edge arrays; a feature-adaptive network's hanging links follow there and
    are not measured here). Both sides are sampled at ``samples`` parameters (ends included) with
    their exact normals, as :func:`g1patch.continuity.check` does; the difference of the reflected
    directions' angle about the stripe axis (wrapped to (−π, π]) times ``stripes`` / 2π is the
    jump. 0 on an exactly G1 edge (up to rounding); about ``stripes · 2 θ / 360°`` on a crease of
    θ degrees whose normals turn about the stripe axis. Degenerate normals are left out. The camera
    is :func:`render`'s: ``view`` and ``up`` ``"auto"`` choose it as the picture does
    (:func:`auto_camera`).
    """
    _check_network(network)
    view, stripes, up = (
        _check_view(view),
        _check_stripes(stripes),
        check_choice("up", up, (AUTO, *UP_AXES)),
    )
    if not isinstance(samples, (int, np.integer)) or isinstance(samples, bool) or samples < 2:
        raise InputError(f"samples: expected an integer ≥ 2, got {samples!r}")
    camera = _camera(view, up, [network])
    patches = network.patches
    count = len(patches)
    t = np.linspace(0.0, 1.0, int(samples))
    uv = edge_parameters(np.arange(4)[:, None], t[None, :]).reshape(-1, 2)
    normals = np.cross(patches.evaluate(uv, 1, 0), patches.evaluate(uv, 0, 1)).reshape(
        count, 4, samples, 3
    )
    length = np.linalg.norm(normals, axis=-1)
    diagonal = network.bounding_box_diagonal() or 1.0
    usable = length > DEGENERATE_RTOL * diagonal**2
    normals = normals / np.where(usable, length, 1.0)[..., None]

    left_patch, left_edge = network.shared_edges()
    right_patch = network.neighbor[left_patch, left_edge]
    right_edge = network.neighbor_edge[left_patch, left_edge]
    same = network.same_direction[left_patch, left_edge]
    order = np.where(same[:, None], np.arange(samples), np.arange(samples)[::-1])
    left = normals[left_patch, left_edge]
    right = normals[right_patch[:, None], right_edge[:, None], order]
    right = np.where(same[:, None, None], -right, right)
    valid = usable[left_patch, left_edge] & usable[right_patch[:, None], right_edge[:, None], order]
    difference = (_phase(left, camera, 1) - _phase(right, camera, 1) + np.pi) % (
        2.0 * np.pi
    ) - np.pi
    jumps = np.where(valid, np.abs(difference) * stripes / (2.0 * np.pi), 0.0)
    return jumps.max(axis=1) if len(jumps) else np.zeros(0)
