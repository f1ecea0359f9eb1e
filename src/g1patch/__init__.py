"""g1patch: quad meshes to smooth bicubic patch networks, with a continuity report that proves it.

::

    import g1patch
    surface = g1patch.smooth("mesh.obj")     # a path, (vertices, faces), a meshio.Mesh, a trimesh…
    print(surface.check())                   # G1 angles, gaps, folds, fairness
    surface.export("mesh.step")              # .npz .obj .ply .stl .step .iges .bpt, by suffix
    surface.render("zebra.png", mode="zebra")

``g1patch.read(path)`` opens a mesh (QuadMesh), a network file (.npz) or Bézier patches (.bpt,
PatchNetwork). The names here are loaded on first use (:mod:`g1patch.api` and the classes of the
deep modules), so ``import g1patch`` itself is fast; the deep modules stay importable as ever.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .display import register_painter

if TYPE_CHECKING:  # pragma: no cover
    from .api import Surface, as_mesh, as_network, check, export, read, smooth, view
    from .continuity import ContinuityReport
    from .errors import (
        BudgetError,
        FormatError,
        G1PatchError,
        InputError,
        MeshError,
        MissingDependencyError,
    )
    from .gregory import GregoryPatchSet
    from .mesh import QuadMesh, QuadTopology
    from .network import PatchNetwork
    from .patches import PatchSet

#: public name → the module that defines it (imported on first access, PEP 562)
_LAZY = {
    "read": "api",
    "smooth": "api",
    "fit": "api",
    "Surface": "api",
    "check": "api",
    "export": "api",
    "as_mesh": "api",
    "as_network": "api",
    "view": "api",
    "QuadMesh": "mesh",
    "QuadTopology": "mesh",
    "PatchNetwork": "network",
    "PatchSet": "patches",
    "GregoryPatchSet": "gregory",
    "ContinuityReport": "continuity",
    "G1PatchError": "errors",
    "InputError": "errors",
    "MeshError": "errors",
    "FormatError": "errors",
    "MissingDependencyError": "errors",
    "BudgetError": "errors",
}

__all__ = ["__version__", *_LAZY]


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("g1patch")
    except PackageNotFoundError:  # running from a source tree that is not installed
        return "0+unknown"


def __getattr__(name: str) -> Any:
    if name == "__version__":
        value: Any = _version()
    elif name in _LAZY:
        from importlib import import_module

        value = getattr(import_module(f".{_LAZY[name]}", __name__), name)
    else:
        raise AttributeError(f"module 'g1patch' has no attribute {name!r}")
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


def _paint_mesh(mesh: QuadMesh) -> bytes:
    from .api import mesh_png

    return mesh_png(mesh)


def _paint_network(network: PatchNetwork) -> bytes:
    from .api import network_png

    return network_png(network)


# Jupyter pictures of the deep modules' objects are drawn by render, a high layer: the objects ask
# g1patch.display, and the root (a shell, like the CLI) tells it who draws.
register_painter("mesh", _paint_mesh)
register_painter("network", _paint_network)
