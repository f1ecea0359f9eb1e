"""The command line's process settings for large arrays (:mod:`g1patch.memory`)."""

from __future__ import annotations

import ctypes
import os
import subprocess
import sys
from pathlib import Path

import pytest

from g1patch import cli, memory

GLIBC = memory._glibc()


class _MallInfo2(ctypes.Structure):
    _fields_ = [
        (name, ctypes.c_size_t)
        for name in (
            "arena",
            "ordblks",
            "smblks",
            "hblks",
            "hblkhd",
            "usmblks",
            "fsmblks",
            "uordblks",
            "fordblks",
            "keepcost",
        )
    ]


def _mapped_blocks() -> int:
    """glibc's count of blocks served by their own ``mmap`` (``mallinfo2().hblks``)."""
    function = ctypes.CDLL(None).mallinfo2
    function.restype = _MallInfo2
    return int(function().hblks)


NEEDS_MALLINFO2 = pytest.mark.skipif(
    not GLIBC or not hasattr(ctypes.CDLL(None), "mallinfo2"),
    reason="needs glibc ≥ 2.33 (mallinfo2)",
)


def _in_child(code: str, environment: dict[str, str] | None = None) -> str:
    """``code``'s standard output in a fresh interpreter (its allocator untouched by earlier tests),
    with this folder importable and ``environment`` added."""
    here = str(Path(__file__).parent)
    prologue = (
        f"import sys; sys.path.insert(0, {here!r}); import numpy as np; "
        "from test_memory import _mapped_blocks; "
    )
    return subprocess.run(
        [sys.executable, "-c", prologue + code],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, **(environment or {})},
    ).stdout.strip()


@NEEDS_MALLINFO2
def test_kept_memory_serves_large_arrays_from_the_heap_and_defaults_map_them() -> None:
    code = (
        "from g1patch import memory; before = _mapped_blocks(); assert memory.keep_freed_memory(); "
        "kept = np.ones(2**23); print(_mapped_blocks() - before); assert "
        "memory.keep_freed_memory(False); "
        # 64 and 128 MiB: above every mmap threshold
        "mapped = np.ones(2**24); print(_mapped_blocks() - before)"
    )
    assert _in_child(code).split() == ["0", "1"]


def test_other_c_libraries_are_left_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(os, "confstr", lambda name: None)  # musl: no GNU libc version
    assert memory.keep_freed_memory() is False


def test_the_command_line_tunes_its_process(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[bool] = []
    monkeypatch.setattr(cli, "tune_for_large_arrays", lambda: calls.append(True))
    with pytest.raises(SystemExit):
        cli.main(["--version"])
    assert calls == [True]


@NEEDS_MALLINFO2
def test_a_child_started_with_the_environment_keeps_large_arrays_in_the_heap() -> None:
    code = "before = _mapped_blocks(); a = np.ones(2**23); print(_mapped_blocks() - before)"
    assert _in_child(code, memory.TUNED_ENVIRONMENT) == "0"
    assert _in_child(code) == "1"


_ADVICE = (
    "advise = (np._core if hasattr(np, '_core') else np.core).multiarray._set_madvise_hugepage; "
)


def test_tuning_leaves_numpys_huge_page_advice_as_numpy_sets_it() -> None:
    """The command line's settings keep 2 MiB pages for large arrays (5–10× faster first touch on
    the development VM, DESIGN §6); ``without_huge_page_advice`` still turns them off."""
    code = _ADVICE + (
        "default = advise(True); advise(default); from g1patch import memory; "
        "memory.tune_for_large_arrays(); "
        "print(advise(default) == default); memory.without_huge_page_advice(); "
        "print(advise(default))"
    )
    assert _in_child(code).split() == ["True", "False"]
