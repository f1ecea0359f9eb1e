"""Kernels run in ranges side by side (g1patch.kernels.in_chunks) give the one-range result, bit for
bit."""

from __future__ import annotations

import numpy as np
import pytest

from g1patch import kernels, shapes
from g1patch.build import build_network


def test_ranges_cover_the_items_in_order(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(kernels, "CHUNK_ITEMS", 3)
    monkeypatch.setattr(kernels, "workers", lambda: 4)
    assert kernels.in_chunks(lambda lo, hi: (lo, hi), 13) == [(0, 3), (3, 6), (6, 9), (9, 13)]
    assert kernels.in_chunks(lambda lo, hi: (lo, hi), 5) == [
        (0, 5)
    ]  # fewer than two ranges' worth: one call
    assert kernels.in_chunks(lambda lo, hi: (lo, hi), 0) == [(0, 0)]


@pytest.mark.parametrize("shape", ["interpolate", "limit"])
def test_a_build_in_ranges_is_the_build_in_one(monkeypatch: pytest.MonkeyPatch, shape: str) -> None:
    """The frame fit, the interior targets and the Gregory assembly each write every item's result
    in its own place: cut into many ranges on threads, the patches are the same bits."""
    rng = np.random.default_rng(7)
    mesh = shapes.torus(24, 12)
    mesh = mesh.with_vertices(mesh.vertices + rng.normal(scale=0.01, size=mesh.vertices.shape))
    whole = build_network(mesh, "gregory", shape=shape)
    monkeypatch.setattr(kernels, "CHUNK_ITEMS", 7)
    monkeypatch.setattr(kernels, "workers", lambda: 5)
    ranged = build_network(mesh, "gregory", shape=shape)
    np.testing.assert_array_equal(ranged.patches.points, whole.patches.points)
