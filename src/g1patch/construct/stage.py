"""The assembly stage's contract: what an assembly is, and what it hands the network.

An assembly turns any valid :class:`~g1patch.targets.Targets` (in the centred, unit-scaled
coordinates of a :class:`~g1patch.frame.Frame`) into patches that are exactly G1 — or, for the
paper's construction, G1 at corners only — moving the targets only as far as G1 requires
(DESIGN §1). The build (:func:`g1patch.build.build_network`) runs it in three calls:

1. ``assemble(targets) → A``, whatever the assembly makes (its patches, or its patches and more);
   the fold guard tests ``patches_of(A)``, ``patches_per_face`` patches a face;
2. ``keep(A, targets, provenance) → (Kept, provenance)``: only what the network needs, so that the
   targets (~460 B a quad) are freed before the network's arrays are made (DESIGN §6);
3. ``network(kept, parts) → PatchNetwork``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..frame import Frame
from ..mesh import QuadMesh
from ..network import Patches, PatchNetwork
from ..targets import Targets


@dataclass(frozen=True)
class NetworkParts:
    """What every network is made of besides the assembly's own output: the mesh the targets were
    taken on (its topology and features), the ``surface`` mesh (the points the surface passes
    through, world coordinates), the working ``frame`` and the ``provenance``."""

    mesh: QuadMesh
    surface: QuadMesh
    frame: Frame
    provenance: dict[str, str]


@dataclass(frozen=True)
class Assembly:
    """One registered assembly (:data:`g1patch.construct.ASSEMBLIES`)."""

    #: the ``--method`` name
    name: str
    #: one line for ``--help``
    summary: str
    assemble: Callable[[Targets], Any]
    patches_per_face: int
    patches_of: Callable[[Any], Patches]
    keep: Callable[[Any, Targets, dict[str, str]], tuple[Any, dict[str, str]]]
    network: Callable[[Any, NetworkParts], PatchNetwork]
    #: the build's peak allocation per face, bytes: ~10 % above tracemalloc's (200k quads, either
    #: shape), an upper bound for the memory budget of :func:`g1patch.build.estimate_build`
    peak_bytes_per_face: int
    #: the same where the NumPy code runs instead of the kernels (no writable numba cache:
    #: :func:`g1patch.kernels.use_kernels`), measured the same way
    numpy_peak_bytes_per_face: int
