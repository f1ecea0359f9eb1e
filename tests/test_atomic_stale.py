"""No litter (issue 32, part 6): a temporary of an atomic write left by a SIGKILLed writer is
removed by the next atomic write into its folder; a live writer's temporary never is."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from g1patch.io import atomic
from g1patch.io.atomic import TEMPORARY_PREFIX, atomic_path, remove_stale_temporaries

pytestmark = pytest.mark.skipif(os.name != "posix", reason="PIDs and signals of POSIX")

#: a writer that creates its temporary, writes part of it, says so and waits to be killed
_WRITER = """
import sys, time
from g1patch.io.atomic import atomic_path
with atomic_path(sys.argv[1]) as temporary:
    temporary.write_bytes(b"half a file")
    print(temporary, flush=True)
    time.sleep(600)
"""


def temporaries(folder: Path) -> list[Path]:
    return sorted(folder.glob(f"{TEMPORARY_PREFIX}*"))


def start_writer(target: Path) -> tuple[subprocess.Popen[str], Path]:
    """A writer process stopped mid-write, and its temporary."""
    writer = subprocess.Popen(
        [sys.executable, "-c", _WRITER, str(target)], stdout=subprocess.PIPE, text=True
    )
    assert writer.stdout is not None
    temporary = Path(writer.stdout.readline().strip())
    assert temporary.exists() and temporary.parent == target.parent
    return writer, temporary


def test_a_killed_writers_temporary_is_removed_by_the_next_write(tmp_path: Path) -> None:
    writer, temporary = start_writer(tmp_path / "out.npz")
    assert f"-{writer.pid}-" in temporary.name
    writer.send_signal(signal.SIGKILL)
    writer.wait(timeout=30)
    assert temporaries(tmp_path) == [temporary]  # SIGKILL: no clean-up of its own
    with atomic_path(tmp_path / "other.obj") as path:
        path.write_text("v 0 0 0\n")
    assert temporaries(tmp_path) == [] and (tmp_path / "other.obj").read_text() == "v 0 0 0\n"


def test_a_live_writers_temporary_is_kept(tmp_path: Path) -> None:
    writer, temporary = start_writer(tmp_path / "out.npz")
    try:
        with atomic_path(tmp_path / "out.npz") as path:  # a second writer of the same target
            path.write_bytes(b"whole")
        assert remove_stale_temporaries(tmp_path, force=True) == []
        assert temporaries(tmp_path) == [temporary]
    finally:
        writer.kill()
        writer.wait(timeout=30)
    assert (tmp_path / "out.npz").read_bytes() == b"whole"
    assert remove_stale_temporaries(tmp_path, force=True) == [temporary]


def test_a_reused_pid_does_not_keep_an_older_temporary(tmp_path: Path) -> None:
    """The PID in the name runs (this process), but it started after the file was written."""
    host, pid = atomic._host(), os.getpid()
    old = tmp_path / f"{TEMPORARY_PREFIX}a.npz.{host}-{pid}-0123abcd.npz"
    fresh = tmp_path / f"{TEMPORARY_PREFIX}b.npz.{host}-{pid}-0123abcd.npz"
    foreign = tmp_path / f"{TEMPORARY_PREFIX}c.npz.00000000-{pid}-0123abcd.npz"  # another host
    unmarked = tmp_path / f"{TEMPORARY_PREFIX}d.npz.0123abcd.npz"  # the old naming: no writer
    for path in (old, fresh, foreign, unmarked):
        path.write_bytes(b"x")
    boot = atomic._boot_time()
    if boot is None:
        pytest.skip("needs /proc")
    for path in (old, foreign, unmarked):  # before the boot: before this process started
        os.utime(path, (boot - 60, boot - 60))
    assert remove_stale_temporaries(tmp_path, force=True) == [old]
    assert temporaries(tmp_path) == sorted([fresh, foreign, unmarked])


def test_a_folder_is_swept_once_a_minute(tmp_path: Path) -> None:
    writer, temporary = start_writer(tmp_path / "out.npz")
    writer.kill()
    writer.wait(timeout=30)
    assert remove_stale_temporaries(tmp_path) == [temporary]
    temporary.write_bytes(b"again")  # a second leftover within the minute: left for later
    assert remove_stale_temporaries(tmp_path) == []
    assert remove_stale_temporaries(tmp_path, force=True) == [temporary]


def test_temporary_names_record_the_writer(tmp_path: Path) -> None:
    with atomic_path(tmp_path / "mesh.tar.gz") as path:
        match = atomic._WRITER.search(path.name)
        assert path.name.startswith(f"{TEMPORARY_PREFIX}mesh.tar.gz.") and path.suffix == ".gz"
        assert match is not None and int(match["pid"]) == os.getpid()
        path.write_bytes(b"")
