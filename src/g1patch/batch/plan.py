"""What a batch has to do: its inputs, their outputs, and which of them are up to date."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..api import MESH_SUFFIXES, PathLike
from ..errors import InputError
from . import provenance
from .jobs import SKIPPED, BuildOptions, Job, blank_record, recipe

#: the note of a skipped file
SKIP_NOTE = "up to date: same input and options"


def collect_inputs(paths: Sequence[PathLike]) -> list[Path]:
    """The mesh files to convert, absolute, each once, in the order given: files as they are,
    folders by the mesh files directly inside them (``.obj .ply .off .stl``, hidden ones left out,
    sorted). A missing path, a file of another kind or a folder without meshes raises
    :class:`InputError`."""
    found: dict[Path, None] = {}
    for given in paths:
        path = Path(given)
        if path.is_dir():
            inside = sorted(
                child
                for child in path.iterdir()
                if child.suffix.lower() in MESH_SUFFIXES
                and not child.name.startswith(".")
                and child.is_file()
            )
            if not inside:
                raise InputError(
                    f"{path}: a folder with no mesh files ({', '.join(MESH_SUFFIXES)}) directly "
                    "inside it"
                )
            found.update(dict.fromkeys(child.resolve() for child in inside))
        elif path.is_file():
            if path.suffix.lower() not in MESH_SUFFIXES:
                raise InputError(
                    f"{path}: not a mesh file; batch converts {', '.join(MESH_SUFFIXES)} files "
                    "(and the folders holding them)"
                )
            found[path.resolve()] = None
        else:
            raise InputError(f"{path}: no such file or folder")
    if not found:
        raise InputError("no inputs: give mesh files or folders holding them")
    return list(found)


def _outputs(
    sources: Sequence[Path], out: Path, formats: Sequence[str]
) -> dict[Path, tuple[Path, ...]]:
    """``OUT/<stem>.<format>`` per source; two sources writing one file, or an output that is an
    input, raise :class:`InputError` naming both."""
    writer: dict[Path, Path] = {}
    result = {}
    for source in sources:
        targets = tuple(out / f"{source.stem}.{name}" for name in formats)
        for target in targets:
            if target in writer:
                raise InputError(
                    f"{writer[target]} and {source} would both write {target}; rename one, or "
                    "batch them into different --out folders"
                )
            writer[target] = source
        result[source] = targets
    inputs = set(sources)
    for target, source in writer.items():
        if target in inputs:
            raise InputError(
                f"{source}: its output {target} would overwrite the input {target}; choose "
                "another --out folder or other --formats"
            )
    return result


def jobs_for(
    sources: Sequence[Path], out: Path, formats: Sequence[str], options: BuildOptions
) -> list[Job]:
    """One job per source, writing ``OUT/<stem>.<format>`` of each format; two sources writing one
    file, or an output that is an input, raise :class:`InputError`. Reads nothing in ``out``."""
    from .. import __version__

    return [
        Job(str(source), tuple(map(str, targets)), options, __version__)
        for source, targets in _outputs(sources, out, formats).items()
    ]


def plan(
    every: Sequence[Job], formats: Sequence[str], options: BuildOptions
) -> tuple[list[Job], dict[str, dict[str, Any]]]:
    """(jobs to run, records of the files skipped, by input path). A file is skipped when every
    output has a record (:mod:`~g1patch.batch.provenance`) saying it was made with these options,
    formats and g1patch version from the input's present bytes; its figures come from there.
    ``summary.json`` is not read: it is a report, not the truth."""
    from .. import __version__

    done = provenance.up_to_date(every, recipe(options, formats, __version__))
    jobs, skipped = [], {}
    for job in every:
        if job.source in done:
            record = {**blank_record(job), **done[job.source]}
            record.update(status=SKIPPED, outputs=list(job.outputs), error=None, note=SKIP_NOTE)
            skipped[job.source] = record
        else:
            jobs.append(job)
    return jobs, skipped
