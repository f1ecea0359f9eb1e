"""What a batch does to each file: the build options, the formats, one task (:class:`Job`), the
recipe an output records, and the record of one file."""

from __future__ import annotations

import importlib.util
import json
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..api import CAD_SUFFIXES, EXPORT_SUFFIXES, RHINO_SUFFIX, TRIANGLE_SUFFIXES
from ..errors import InputError, MissingDependencyError, check_choice

#: the formats ``--formats`` takes: the suffixes :meth:`Surface.export` writes, without the dot
FORMATS = tuple(suffix[1:] for suffix in EXPORT_SUFFIXES)
#: record statuses: converted now, up to date from an earlier run, failed, never run (interrupted)
BUILT, SKIPPED, FAILED, CANCELLED = "built", "skipped", "failed", "cancelled"
STATUSES = (BUILT, SKIPPED, FAILED, CANCELLED)


@dataclass(frozen=True)
class BuildOptions:
    """The options of ``g1patch build`` a batch applies to every file (see
    :func:`g1patch.smooth`)."""

    method: str = "split4"
    shape: str = "interpolate"
    refine: int = 0
    sharp_angle: float | None = None
    strict: bool = False
    #: limit shapes: the largest distance from the exact Catmull–Clark limit, of the diagonal
    tolerance: float = 1e-3
    #: the input size cap (bytes; None: the readers' default): how a file is read, not what is
    #: made of it, so no part of an output's recipe
    max_input_size: int | None = None

    def __post_init__(self) -> None:
        from ..construct import METHODS
        from ..targets import SHAPES

        check_choice("method", self.method, METHODS)
        check_choice("shape", self.shape, tuple(SHAPES))
        if isinstance(self.refine, bool) or not isinstance(self.refine, int) or self.refine < 0:
            raise InputError(
                f"refine: expected a number of Catmull–Clark steps ≥ 0, got {self.refine!r}"
            )
        from ..build import check_tolerance

        check_tolerance(self.tolerance)
        if self.sharp_angle is not None and not (
            math.isfinite(self.sharp_angle) and 0 < self.sharp_angle < 180
        ):
            raise InputError(
                f"sharp angle: expected degrees between 0 and 180, got {self.sharp_angle!r}"
            )


@dataclass(frozen=True)
class Job:
    """One task: the input mesh and the files to write from it (absolute paths, ``<stem>.<format>``
    in the batch's order of formats). ``version``: the g1patch the batch runs, which the worker
    must run too (None: not checked)."""

    source: str
    outputs: tuple[str, ...]
    options: BuildOptions
    version: str | None = None

    @property
    def formats(self) -> tuple[str, ...]:
        return tuple(Path(output).suffix[1:].lower() for output in self.outputs)


def parse_formats(text: str | Sequence[str]) -> tuple[str, ...]:
    """``"npz,step,obj"`` (or a sequence of names) as ``("npz", "step", "obj")``: lower case,
    without dots, each once; an unknown one, or none, raises :class:`InputError` listing
    :data:`FORMATS`."""
    names = [name for name in (text.split(",") if isinstance(text, str) else text) if name.strip()]
    if not names:
        raise InputError(f"--formats: give at least one of {', '.join(FORMATS)}")
    formats: list[str] = []
    for name in names:
        cleaned = name.strip().lower().lstrip(".")
        if cleaned not in FORMATS:
            raise InputError(
                f"--formats: unknown format {name.strip()!r}; expected a comma-separated list of "
                f"{', '.join(FORMATS)}"
            )
        if cleaned not in formats:
            formats.append(cleaned)
    return tuple(formats)


def check_formats(formats: Sequence[str], options: BuildOptions) -> None:
    """Refuse, before any work, what every file would fail on: .bpt of rational patches, CAD without
    OCP, .3dm without rhino3dm."""
    if "bpt" in formats and options.method == "gregory":
        raise InputError(
            "--formats bpt: .bpt holds polynomial Bézier patches and gregory patches are rational; "
            "use --method split4 (or corner), or export .step instead"
        )
    if (
        any(f".{name}" in CAD_SUFFIXES for name in formats)
        and importlib.util.find_spec("OCP") is None
    ):
        raise MissingDependencyError("cadquery-ocp-novtk", "cad", "STEP/IGES export")
    if RHINO_SUFFIX[1:] in formats and importlib.util.find_spec("rhino3dm") is None:
        raise MissingDependencyError("rhino3dm", "rhino", ".3dm export")


def export_options(name: str) -> dict[str, Any]:
    """The keyword options a batch gives :meth:`Surface.export` for format ``name``: every one that
    changes the file, spelled out (None: the export's own choice, e.g. the resolution by patch
    count), so that an output's record names them."""
    if f".{name}" in TRIANGLE_SUFFIXES:
        return {"resolution": None}
    if f".{name}" in (*CAD_SUFFIXES, RHINO_SUFFIX):
        from ..io.cad.method import DEVIATION_RTOL

        return {"method": "auto", "max_deviation": DEVIATION_RTOL, "fit_tolerance": None}
    return {}


def recipe(options: BuildOptions, formats: Sequence[str], version: str) -> dict[str, Any]:
    """Everything an output of a batch is made from but its input: the build options, the formats
    and each one's export options, and the g1patch version (JSON-ready). Two outputs made with
    equal recipes from the same input bytes are the same file."""
    return {
        **{key: value for key, value in asdict(options).items() if key != "max_input_size"},
        "formats": list(formats),
        "export": {name: export_options(name) for name in formats},
        "g1patch": version,
    }


def blank_record(job: Job, status: str = CANCELLED) -> dict[str, Any]:
    """A record with the job's identity and options and no figures yet."""
    return {
        "input": job.source,
        "name": Path(job.source).name,
        "status": status,
        **asdict(job.options),
        "sha256": None,
        "patches": None,
        "max_g1_angle_deg": None,
        "max_edge_angle_deg": None,
        "max_corner_angle_deg": None,
        "folds": None,
        "repairs": [],
        "seams": None,
        "fallback_vertices": None,
        "relaxed_vertices": None,
        "limit_distance": None,
        "times": {},
        "outputs": [],
        "cad": {},
        "error": None,
        "note": None,
    }


def json_ready(value: Any) -> Any:
    """``value`` with NaN and infinities as None (JSON has neither), NumPy scalars as Python's, and
    anything else JSON lacks as its str."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, dict):
        return {str(key): json_ready(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(item) for item in value]
    if isinstance(value, bool) or value is None or isinstance(value, (int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return str(value)


def json_text(value: Any) -> str:
    """``value`` as the indented JSON text of a g1patch record file."""
    return json.dumps(json_ready(value), indent=1, allow_nan=False) + "\n"
