"""How a network reaches CAD (``exact``, ``split4`` or ``fit``), and the split4 re-assembly of a
Gregory network within a distance of its surface (:func:`_split4_within`)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any, Literal

import numpy as np

from ...errors import ConstructionError, InputError, MeshError, check_choice
from ...network import PatchNetwork
from ...patches import PatchSet

CadMethod = Literal["auto", "split4", "fit"]
#: how a rational (Gregory) network reaches CAD: ``split4`` its targets re-assembled polynomially
#: (exact G1 in CAD, :mod:`g1patch.construct.polynomial`), ``fit`` its patches fitted one by one
#: (close, kinked), ``auto`` split4, or fit where split4 cannot re-assemble the network
CAD_METHODS: tuple[CadMethod, ...] = ("auto", "split4", "fit")
#: default largest distance of a split4 re-assembly from its Gregory surface, relative to the
#: bounding-box diagonal: above it each patch is re-assembled as n × n cells (n from
#: :data:`REFINE_STEPS`; :func:`~g1patch.construct.polynomial.split4_of_gregory`)
DEVIATION_RTOL = 1e-3
#: the cuts of a patch the re-assembly tries, in order (the distance falls about as 1/n), and the
#: most quads a cut may make
REFINE_STEPS = (1, 2, 3, 4, 6, 8)
REFINE_QUADS = 20_000
#: Gregory patches whose interior pairs agree to this share of the model's size are bicubics
BICUBIC_RTOL = 1e-12


def _bicubic(patches: Any) -> bool:
    """Whether Gregory patches are bicubics already (every pair ``Fn_k = Fp_k``, to
    :data:`BICUBIC_RTOL`)."""
    from ...gregory import GregoryPatchSet

    if not isinstance(patches, GregoryPatchSet):
        return False
    points = patches.points
    extent = float(np.abs(points).max())
    return bool(np.abs(points[:, 12::2] - points[:, 13::2]).max() <= BICUBIC_RTOL * extent)


def _as_bicubics(patches: Any) -> PatchSet:
    """Gregory patches that are bicubics (:func:`_bicubic`) as Bézier patches: the same surface,
    exactly."""
    return PatchSet(patches.to_bezier_control(), "bezier").with_frame(patches.frame)


def _cad_method(target: Path, network: PatchNetwork, method: CadMethod) -> str:
    """What ``method`` means for ``network``: ``exact``, ``split4`` or ``fit``."""
    from ...gregory import GregoryPatchSet

    check_choice("method", method, CAD_METHODS)
    if isinstance(network.patches, PatchSet):
        return "exact"
    if method == "fit" or not isinstance(network.patches, GregoryPatchSet):
        if method == "split4":
            raise InputError(
                f"{target}: method 'split4' re-assembles Gregory networks; these patches are "
                f"{type(network.patches).__name__} (use method 'fit')"
            )
        return "fit"
    if network.hanging is not None and len(network.hanging):
        if method == "split4":
            raise InputError(
                f"{target}: method 'split4' re-assembles conforming Gregory networks; this one is "
                f"refined locally ({len(network.hanging)} hanging edges): use method 'fit', or "
                "build with --method split4 for an exact polynomial CAD file"
            )
        return "fit"
    return "split4"


def _split4_within(
    network: PatchNetwork,
    max_deviation: float,
    diagonal: float,
    fallback: bool,
    lap: Callable[[str], None],
) -> tuple[PatchNetwork, float, int, str] | str:
    """The split4 re-assembly of a Gregory network
    (:func:`~g1patch.construct.polynomial.split4_of_gregory`) with n = 1, 2, 3, …
    (:data:`REFINE_STEPS`) cells per patch side until its distance to the Gregory surface is at most
    ``max_deviation × diagonal`` (split4's stars differ from the Gregory fans near the vertices,
    over a cell's size), or a cut would make more than :data:`REFINE_QUADS` quads: ``(network,
    deviation, n, note)``. A cut that folds more sub-patches than n = 1 (small cells of a coarse
    cage can) is not taken; of those tried the closest one that does not, and the note says when it
    is above the bound. A network split4 cannot re-assemble raises, or with ``fallback`` returns the
    note for a fit (where only its cells cannot be, the fewer cells are kept)."""
    from ...construct.polynomial import split4_of_gregory, surface_deviation
    from ...continuity import folded_patches

    tried: list[
        tuple[bool, float, int, PatchNetwork]
    ] = []  # (folds more than n = 1, deviation, n, result)
    base_folds, allowed = 0, max_deviation * diagonal
    for refine in REFINE_STEPS:
        if refine > 1 and refine * refine * network.n_patches > REFINE_QUADS:
            break
        try:
            converted = split4_of_gregory(network, refine=refine)
        except (ConstructionError, MeshError) as error:
            if tried:  # the cells failed where the whole patches did not: keep those
                break
            if not fallback:
                raise
            return f"split4 could not re-assemble it ({error}): fitted"
        lap("split4")
        deviation = surface_deviation(network, converted)[1]
        folds = int(folded_patches(converted.patches).sum())
        base_folds = folds if refine == 1 else base_folds
        lap("deviation")
        tried.append((folds > base_folds, deviation, refine, converted))
        if deviation <= allowed and not tried[-1][0]:
            break
    _, deviation, refine, converted = min(tried, key=lambda attempt: attempt[:2])
    note = (
        ""
        if deviation <= allowed
        else (
            f"the re-assembly stays {deviation / diagonal:.2e} of the diagonal from the Gregory "
            "surface, above "
            f"--max-deviation {max_deviation:g}, at {refine} × {refine} cells per patch"
            + (" (finer cells folded)" if any(attempt[0] for attempt in tried) else "")
        )
    )
    return converted, deviation, refine, note
