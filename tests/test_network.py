"""PatchNetwork's lists of edges (:mod:`g1patch.network`)."""

from __future__ import annotations

import numpy as np
import pytest

from g1patch import shapes
from g1patch.build import build_network
from g1patch.network import PatchNetwork
from g1patch.patches import PatchSet


def _first_sides(network: PatchNetwork) -> list[tuple[int, int]]:
    """Each shared edge's side (patch, edge) that comes first, (patch, edge) < its neighbour's, by a
    loop."""
    return [
        (p, e)
        for p in range(network.n_patches)
        for e in range(4)
        if network.neighbor[p, e] >= 0
        and (p, e) < (network.neighbor[p, e], network.neighbor_edge[p, e])
    ]


def _self_adjacent() -> PatchNetwork:
    """Patch 0's edges 1 and 3 glued to each other (a one-patch cylinder), its edge 2 to patch 1's
    edge 0."""
    neighbor = np.array([[-1, 0, 1, 0], [0, -1, -1, -1]])
    neighbor_edge = np.array([[-1, 3, 0, 1], [2, -1, -1, -1]])
    four = np.zeros((2, 4), dtype=bool)
    return PatchNetwork(
        PatchSet(np.zeros((2, 4, 4, 3))),
        np.zeros((2, 4), dtype=np.int64),
        np.arange(8).reshape(2, 4),
        four,
        neighbor,
        neighbor_edge,
        four,
        np.zeros(8, dtype=bool),
    )


@pytest.mark.parametrize(
    "network",
    [_self_adjacent(), build_network(shapes.fan(5, 2)), build_network(shapes.grid(3, 2), "split4")],
    ids=["self-adjacent", "fan", "split4 grid"],
)
def test_shared_edges_lists_each_shared_edge_once_by_its_first_side(network: PatchNetwork) -> None:
    patch, edge = network.shared_edges()
    assert list(zip(patch.tolist(), edge.tolist(), strict=True)) == _first_sides(network)
    assert 2 * len(patch) == int((network.neighbor >= 0).sum())
