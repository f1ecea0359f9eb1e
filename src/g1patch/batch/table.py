"""The records of a batch as a text table."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from .jobs import CANCELLED, FAILED, SKIPPED, STATUSES


def _cell(value: Any, form: str) -> str:
    return "-" if value is None else format(value, form)


def summary_table(records: Sequence[dict[str, Any]]) -> str:
    """The records as a text table: one row per file, the note (an error, a repair, why it was
    skipped) last, then a line of counts."""
    header = (
        "file",
        "status",
        "method",
        "shape",
        "patches",
        "max G1°",
        "folds",
        "repairs",
        "seams",
        "time s",
        "note",
    )
    rows = [header]
    for r in records:
        total = r["times"].get("total") if r["status"] != SKIPPED else None
        note = r["error"] if r["status"] == FAILED else r.get("note") or ""
        rows.append(
            (
                r["name"],
                r["status"],
                r["method"],
                r["shape"],
                _cell(r["patches"], "d"),
                _cell(r["max_g1_angle_deg"], ".2e"),
                _cell(r["folds"], "d"),
                str(len(r["repairs"])),
                _cell(r["seams"], "d"),
                _cell(total, ".2f"),
                note,
            )
        )
    widths = [max(len(row[column]) for row in rows) for column in range(len(header) - 1)]
    lines = [
        "  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=False))
        + "  "
        + row[-1]
        for row in rows
    ]
    counts = {status: sum(r["status"] == status for r in records) for status in STATUSES}
    tally = ", ".join(
        f"{count} {status}" for status, count in counts.items() if count or status != CANCELLED
    )
    lines.append(f"{len(records)} file{'s' if len(records) != 1 else ''}: {tally}")
    return "\n".join(line.rstrip() for line in lines)
