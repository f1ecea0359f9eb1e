"""``g1patch batch``: many meshes converted on a Dask cluster, one task per file, with a summary.

Each input mesh is one task (:func:`convert`): :func:`g1patch.read` → :func:`g1patch.smooth` →
:meth:`~g1patch.api.Surface.check` → :meth:`~g1patch.api.Surface.export` of every format asked,
to ``OUT/<stem>.<format>`` (atomic, as every g1patch write: a file appears whole or not at all).
A task never raises: it returns one record (a JSON-ready dict) with the file's figures, or its
error in one line, so a failing file stops no other. :func:`run_batch` writes the records to
``OUT/summary.json`` and :func:`summary_table` prints them.

The cluster is an embedded :class:`distributed.LocalCluster` of worker processes on 127.0.0.1
(one thread each; as many as the cores, at most one per file to convert), or an existing one by
its scheduler's address. Workers read the inputs and write the outputs by absolute path, so they
must see the same file system as the caller, and run the same g1patch version.

Every output carries a record of what it was made from, ``OUT/.g1patch/<output name>.json``
(:mod:`~g1patch.batch.provenance`): the build options (method, shape, refine, sharp angle,
strict), the formats and their export options, the g1patch version, and the SHA-256 of the
input's bytes. Re-running skips a file only when every output's record says it was made that way
from the input as it is now (its figures then come from the record; its status is ``skipped``);
any output whose record is missing, unreadable or different is rebuilt, with the file's other
outputs. ``summary.json`` is a report of the run, never read back. When nothing is left to
convert, no cluster is started. One batch at a time writes into a folder (a lock in
``.g1patch``): a second one is refused, since its outputs and records would interleave.
Modules: :mod:`.jobs` (options, recipe, records), :mod:`.plan`, :mod:`.provenance`, :mod:`.task`
(one file), :mod:`.run` (the cluster), :mod:`.table`.

dask.distributed is the ``batch`` extra (``pip install 'g1patch[batch]'``), imported only when a
batch runs: ``import g1patch.batch`` needs no Dask.
"""

from __future__ import annotations

from .jobs import (
    BUILT,
    CANCELLED,
    FAILED,
    FORMATS,
    SKIPPED,
    BuildOptions,
    Job,
    parse_formats,
    recipe,
)
from .plan import collect_inputs, jobs_for, plan
from .provenance import RECORDS_FOLDER, folder_lock, record_path
from .run import SUMMARY_NAME, run_batch
from .table import summary_table
from .task import convert

__all__ = [
    "BUILT",
    "CANCELLED",
    "FAILED",
    "FORMATS",
    "RECORDS_FOLDER",
    "SKIPPED",
    "SUMMARY_NAME",
    "BuildOptions",
    "Job",
    "collect_inputs",
    "convert",
    "folder_lock",
    "jobs_for",
    "parse_formats",
    "plan",
    "recipe",
    "record_path",
    "run_batch",
    "summary_table",
]
