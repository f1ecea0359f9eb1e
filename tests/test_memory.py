"""The command line's process settings for large arrays (:mod:`g1patch.memory`)."""

from __future__ import annotations

import ctypes
import os
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from g1patch import cli, memory

GLIBC = platform.system() == "Linux" and platform.libc_ver()[0] == "glibc"


class _MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in (
        "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks", "keepcost")]


def _mapped_blocks() -> int:
    """glibc's count of blocks served by their own ``mmap`` (``mallinfo2().hblks``)."""
    function = ctypes.CDLL(None).mallinfo2
    function.restype = _MallInfo2
    return int(function().hblks)


@pytest.mark.skipif(not GLIBC or not hasattr(ctypes.CDLL(None), "mallinfo2"), reason="needs glibc ≥ 2.33 (mallinfo2)")
def test_kept_memory_serves_large_arrays_from_the_heap_and_defaults_map_them() -> None:
    try:
        assert memory.keep_freed_memory()
        before = _mapped_blocks()
        kept = np.ones(2**23)  # 64 MiB: above glibc's largest mmap threshold
        assert _mapped_blocks() == before
        assert memory.keep_freed_memory(False)
        mapped = np.ones(2**23)
        assert _mapped_blocks() == before + 1
        del kept, mapped
    finally:
        memory.keep_freed_memory(False)


def test_other_c_libraries_are_left_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(platform, "libc_ver", lambda: ("musl", "1.2"))
    assert memory.keep_freed_memory() is False


def test_the_command_line_tunes_its_process(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[bool] = []
    monkeypatch.setattr(cli, "tune_for_large_arrays", lambda: calls.append(True))
    with pytest.raises(SystemExit):
        cli.main(["--version"])
    assert calls == [True]


@pytest.mark.skipif(not GLIBC or not hasattr(ctypes.CDLL(None), "mallinfo2"), reason="needs glibc ≥ 2.33 (mallinfo2)")
def test_a_child_started_with_the_environment_keeps_large_arrays_in_the_heap() -> None:
    code = (
        "import ctypes, sys, numpy as np; sys.path.insert(0, sys.argv[1]); from test_memory import _mapped_blocks; "
        "before = _mapped_blocks(); a = np.ones(2**23); print(_mapped_blocks() - before)"
    )

    def mapped_in_child(environment: dict[str, str]) -> str:
        return subprocess.run([sys.executable, "-c", code, str(Path(__file__).parent)], capture_output=True, text=True,
                              check=True, env={**os.environ, **environment}).stdout.strip()

    assert mapped_in_child(memory.TUNED_ENVIRONMENT) == "0"
    assert mapped_in_child({}) == "1"
