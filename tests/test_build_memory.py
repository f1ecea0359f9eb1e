"""The build frees what the network does not keep before it makes the network's arrays (DESIGN §6).

The targets (tangents, twists, corner normals: ~460 B a quad) and split4's stars were still held
while the connectivity was built, which set both builds' peaks (Gregory 1044 -> 972 B a quad,
split4 3040 -> 2696 at 250k quads). Here: no targets array is alive once the network's arrays are
made."""

from __future__ import annotations

import gc
import weakref
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import g1patch.build as build_module
import g1patch.construct.one_per_face as one_per_face_module
import g1patch.construct.split4.network as split4_module
from g1patch import shapes
from g1patch.targets import Targets


def _watching(
    monkeypatch: pytest.MonkeyPatch, module: Any, name: str, seen: list[weakref.ref[np.ndarray]]
) -> None:
    """Wrap ``module.name`` (returns Targets) so that weak references to its results' arrays land in
    ``seen``."""
    original: Callable[..., Targets] = getattr(module, name)

    def watched(*args: Any, **kwargs: Any) -> Targets:
        targets = original(*args, **kwargs)
        seen.extend(
            weakref.ref(getattr(targets, field))
            for field in ("tangents", "interior", "corner_normals")
        )
        return targets

    monkeypatch.setattr(module, name, watched)


def _asserting_freed(
    monkeypatch: pytest.MonkeyPatch,
    module: Any,
    name: str,
    seen: list[weakref.ref[np.ndarray]],
    calls: list[str],
) -> None:
    """Wrap ``module.name`` (makes the network's arrays) to assert that every array in ``seen`` is
    gone."""
    original = getattr(module, name)

    def checked(*args: Any, **kwargs: Any) -> Any:
        gc.collect()
        alive = [ref for ref in seen if ref() is not None]
        assert seen and not alive, (
            f"{len(alive)} of {len(seen)} targets arrays still alive when {name} runs"
        )
        calls.append(name)
        return original(*args, **kwargs)

    monkeypatch.setattr(module, name, checked)


@pytest.mark.parametrize("method", ["gregory", "split4", "corner"])
def test_the_targets_are_freed_before_the_network_is_made(
    monkeypatch: pytest.MonkeyPatch, method: str
) -> None:
    seen: list[weakref.ref[np.ndarray]] = []
    calls: list[str] = []
    _watching(monkeypatch, build_module, "shape_targets", seen)
    _watching(monkeypatch, build_module, "retreat", seen)
    if method == "split4":
        _asserting_freed(monkeypatch, split4_module, "_split4_network", seen, calls)
    else:
        _asserting_freed(monkeypatch, one_per_face_module, "network_from_mesh", seen, calls)
    network = build_module.build_network(shapes.noisy_sphere(2), method)  # type: ignore[arg-type]
    assert calls and network.n_patches > 0
