"""Options checked at the door: every count, angle, size and tolerance of a command is checked
before any file is read, and a bad one is refused with one line naming the option, the value and
the range (:class:`~g1patch.errors.InputError`, exit 2). Where the library checks the same value
(after reading the input, e.g. the memory bound of ``check --samples``), it refuses it too."""

from __future__ import annotations

import argparse
import math
from typing import Any

from ..errors import InputError
from ..kernels import workers as cores

#: the most quads ``fit --faces`` asks of the remesher (its fit takes ~2 kB a quad and more per
#: scan point: a few GB at this bound)
MAX_FIT_FACES = 1_000_000


def _count(option: str, value: Any, least: int, what: str = "an integer") -> None:
    if value is not None and value < least:
        raise InputError(f"{option}: expected {what} ≥ {least}, got {value}")


def _number(option: str, value: Any, low: float, high: float, *, low_open: bool) -> None:
    """A finite ``value`` in ``(low, high]`` (``low_open``) or ``[low, high]``; None passes."""
    if value is None:
        return
    above = value > low if low_open else value >= low
    if not (math.isfinite(value) and above and value <= high):
        bounds = (
            f"{'>' if low_open else '≥'} {low:g}"
            if math.isinf(high)
            else f"in {'(' if low_open else '['}{low:g}, {high:g}]"
        )
        raise InputError(f"{option}: expected a finite number {bounds}, got {value}")


def check_options(args: argparse.Namespace) -> list[str]:
    """Refuse (:class:`InputError`) the first option of ``args`` out of its range; cap
    ``batch --workers`` to the cores. Returns the notes to print (one line each)."""
    notes = []
    command = args.command
    if command in ("build", "batch"):
        _count("--refine", args.refine, 0, "a number of Catmull–Clark steps")
        angle = args.sharp_angle
        if angle is not None and not (math.isfinite(angle) and 0.0 < angle < 180.0):
            raise InputError(f"--sharp-angle: expected degrees between 0 and 180, got {angle}")
    if command == "fit":
        _number("--tolerance", args.tolerance, 0.0, 0.5, low_open=True)
        _count("--faces", args.faces, 16, "a number of quads")
        if args.faces is not None and args.faces > MAX_FIT_FACES:
            raise InputError(
                f"--faces: expected a number of quads ≤ {MAX_FIT_FACES:,}, got {args.faces:,}"
            )
    if command == "check":
        _count("--samples", args.samples, 2, "a number of samples per edge")
        _number("--max-angle", args.max_angle, 0.0, 180.0, low_open=False)
    if command in ("export", "view"):
        _count("--resolution", args.resolution, 2, "a number of samples per patch side")
    if command == "export":
        _number("--fit-tolerance", args.fit_tolerance, 0.0, math.inf, low_open=True)
        _number("--max-deviation", args.max_deviation, 0.0, math.inf, low_open=True)
    if command == "render":
        from ..render.checks import _SIZE_RANGE

        low, high = _SIZE_RANGE
        if not all(low <= side <= high for side in args.size):
            raise InputError(
                f"--size: expected two numbers of pixels from {low} to {high}, got "
                f"{' '.join(str(side) for side in args.size)}"
            )
        _number("--zoom", args.zoom, 0.0, math.inf, low_open=True)
    if command == "batch" and args.workers is not None:
        _count("--workers", args.workers, 1, "a number of worker processes")
        available = cores()
        if args.workers > available:
            notes.append(
                f"g1patch: note: --workers {args.workers} is more than the {available} cores of "
                f"this machine; using {available}"
            )
            args.workers = available
    return notes
