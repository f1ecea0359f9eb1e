"""Batch provenance (issue 32): every output records the options and the input bytes it was made
from, a re-run goes by those records and never by ``summary.json``, and a batch never reports a
result it did not make with the options it was given."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

import pytest
import test_batch
from test_batch import summary

import g1patch
from g1patch.batch import (
    FAILED,
    RECORDS_FOLDER,
    BuildOptions,
    Job,
    convert,
    folder_lock,
    record_path,
)
from g1patch.batch import run as batch_run
from g1patch.batch.provenance import LOCK_NAME
from g1patch.cli import main
from g1patch.io.atomic import TEMPORARY_PREFIX

NAMES = ("cube.obj", "grid.ply", "torus.obj")
#: the batch tests' fixtures: a LocalCluster of 2 worker threads, the generated meshes
scheduler, meshes = test_batch.scheduler, test_batch.meshes


@pytest.fixture
def inputs(meshes: Path) -> Path:
    """The batch tests' generated meshes without the broken one."""
    (meshes / "broken.obj").unlink()
    return meshes


def batch(inputs: Path, out: Path, scheduler: str, *options: str) -> dict[str, dict]:
    """``g1patch batch`` of the meshes into ``out`` as npz and obj: the summary's records by name,
    checked against every output's own record."""
    command = ["batch", str(inputs), "--out", str(out), "--scheduler", scheduler, "-q"]
    assert main([*command, "--formats", "npz,obj", *options]) == 0
    assert_records_match(out)
    return summary(out)


def assert_records_match(out: Path) -> None:
    """The summary's options are each output's recorded recipe; its input hash is the input's
    present SHA-256; the output is the file the record was written with; no temporary left."""
    written = json.loads((out / "summary.json").read_text())
    options = written["options"]
    assert options["formats"] == written["formats"] and options["g1patch"] == g1patch.__version__
    for record in written["files"]:
        source = Path(record["input"])
        digest = hashlib.sha256(source.read_bytes()).hexdigest()
        assert record["sha256"] == digest
        made_by = set(BuildOptions.__dataclass_fields__) - {"max_input_size"}  # how read, not made
        assert all(record[key] == options[key] for key in made_by)
        for output in record["outputs"]:
            own = json.loads(record_path(output).read_text())
            assert own["recipe"] == options, output
            assert own["input"] == {"path": str(source), "sha256": digest}
            stat = os.stat(output)
            assert own["file"] == {"size": stat.st_size, "mtime_ns": stat.st_mtime_ns}
    assert not list(out.rglob(f"{TEMPORARY_PREFIX}*"))


def statuses(records: dict[str, dict]) -> dict[str, str]:
    return {name: record["status"] for name, record in records.items()}


@pytest.mark.parametrize("summary_is", ["deleted", "garbage", "lying"])
def test_a_lost_or_false_summary_and_other_options_rebuild_everything(
    summary_is: str,
    inputs: Path,
    tmp_path: Path,
    scheduler: str,
) -> None:
    """The reported bug: with summary.json gone, unreadable or claiming the new options, a re-run
    with other options rebuilt nothing and relabelled the old outputs as made with them."""
    out = tmp_path / "out"
    first = batch(inputs, out, scheduler)
    assert set(statuses(first).values()) == {"built"}
    assert {
        g1patch.read(out / f"{Path(name).stem}.npz").provenance["method"] for name in NAMES
    } == {"split4"}
    path = out / "summary.json"
    if summary_is == "deleted":
        path.unlink()
    elif summary_is == "garbage":
        path.write_bytes(b'{"files": [\x00\xff not json')
    else:  # the summary says the outputs were made with gregory (the options asked next)
        text = json.loads(path.read_text())
        for record in text["files"]:
            record["method"] = "gregory"
        text["options"]["method"] = "gregory"
        path.write_text(json.dumps(text))

    again = batch(inputs, out, scheduler, "--method", "gregory")
    assert statuses(again) == dict.fromkeys(NAMES, "built")
    assert {record["method"] for record in again.values()} == {"gregory"}
    for name in NAMES:  # the files themselves say so, not only their records
        assert g1patch.read(out / f"{Path(name).stem}.npz").provenance["method"] == "gregory"


def test_an_input_edited_in_place_with_its_time_put_back_is_rebuilt(
    inputs: Path,
    tmp_path: Path,
    scheduler: str,
) -> None:
    """Times are no evidence: the same size and modification time, other bytes; and the same bytes
    touched later are not rebuilt."""
    out = tmp_path / "out"
    first = batch(inputs, out, scheduler)
    cube, torus = inputs / "cube.obj", inputs / "torus.obj"
    before = cube.stat()
    text = cube.read_text()
    edited = text.replace("v 1.0 1.0 1.0", "v 1.0 1.0 1.5")
    assert edited != text and len(edited) == len(text)
    cube.write_text(edited)
    os.utime(cube, ns=(before.st_atime_ns, before.st_mtime_ns))
    assert (cube.stat().st_size, cube.stat().st_mtime_ns) == (before.st_size, before.st_mtime_ns)
    later = torus.stat().st_mtime_ns + 10**10
    os.utime(torus, ns=(later, later))

    again = batch(inputs, out, scheduler)
    assert statuses(again) == {"cube.obj": "built", "grid.ply": "skipped", "torus.obj": "skipped"}
    assert again["cube.obj"]["sha256"] != first["cube.obj"]["sha256"]
    assert again["torus.obj"]["max_g1_angle_deg"] == first["torus.obj"]["max_g1_angle_deg"]


@pytest.mark.parametrize(
    "change", ["output deleted", "output edited", "record deleted", "record garbage", "formats"]
)
def test_an_output_without_a_true_record_is_rebuilt(
    change: str,
    inputs: Path,
    tmp_path: Path,
    scheduler: str,
) -> None:
    """A missing output, one changed since its record, a missing or unreadable record, or other
    formats asked: the file is built again, every output of it, and the others skipped."""
    out = tmp_path / "out"
    batch(inputs, out, scheduler)
    output = out / "cube.obj"
    formats: tuple[str, ...] = ()
    if change == "output deleted":
        output.unlink()
    elif change == "output edited":
        with output.open("a") as stream:
            stream.write("# by hand\n")
    elif change == "record deleted":
        record_path(output).unlink()
    elif change == "record garbage":
        record_path(output).write_text("[1, 2")
    else:
        formats = ("--formats", "obj,npz")

    again = batch(inputs, out, scheduler, *formats)
    expected = "built" if change == "formats" else "skipped"
    assert statuses(again) == {"cube.obj": "built", "grid.ply": expected, "torus.obj": expected}
    assert output.is_file() and str(output) in again["cube.obj"]["outputs"]


def test_an_unchanged_rerun_skips_everything_and_starts_no_cluster(
    inputs: Path,
    tmp_path: Path,
    scheduler: str,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Up to date by the records alone (summary.json deleted too): no task, no cluster, the figures
    of the build reported again."""
    out = tmp_path / "out"
    first = batch(inputs, out, scheduler, "--shape", "limit")
    (out / "summary.json").unlink()

    def no_cluster(*arguments: Any) -> Any:
        raise AssertionError("a cluster was started with nothing to do")

    monkeypatch.setattr(batch_run, "_client", no_cluster)
    records = batch_run.run_batch(
        [inputs], out, formats="npz,obj", options=BuildOptions(shape="limit")
    )
    assert [record["status"] for record in records] == ["skipped"] * 3
    assert_records_match(out)
    again = summary(out)
    for name in NAMES:
        for key in ("patches", "max_g1_angle_deg", "folds", "seams", "sha256", "outputs"):
            assert again[name][key] == first[name][key], (name, key)
    assert sorted(path.name for path in (out / RECORDS_FOLDER).iterdir()) == sorted(
        [LOCK_NAME]
        + [f"{Path(name).stem}.{suffix}.json" for name in NAMES for suffix in ("npz", "obj")]
    )


def test_a_second_batch_into_the_same_folder_is_refused(
    inputs: Path,
    tmp_path: Path,
    scheduler: str,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Two batches writing one folder would interleave outputs and records (one's record naming
    the other's file): while one holds the folder, another exits 2 before reading or writing."""
    out = tmp_path / "out"
    command = ["batch", str(inputs), "--out", str(out), "--scheduler", scheduler, "-q"]
    with folder_lock(out):
        assert main([*command, "--method", "split4"]) == 2
    error = capsys.readouterr().err.strip()
    assert error.endswith(
        f"out: another batch (PID {os.getpid()}) is writing into this folder; wait for it to end "
        "or choose another --out folder"
    )
    assert sorted(path.name for path in out.rglob("*")) == [RECORDS_FOLDER, LOCK_NAME]
    assert main(command) == 0  # released, whatever the holder did
    assert_records_match(out)


def test_a_record_of_an_output_with_a_long_name_is_kept(
    inputs: Path, tmp_path: Path, scheduler: str
) -> None:
    """An output name of 251 to 255 bytes has no room for ``.json``: its record's name is
    shortened by a hash, and the output is built and skipped like any other."""
    source = inputs / f"{'x' * 250}.obj"
    (inputs / "cube.obj").rename(source)
    out = tmp_path / "out"
    output = out / f"{source.stem}.npz"
    assert len(os.fsencode(output.name)) == 254
    for status in ("built", "skipped"):
        records = batch_run.run_batch([source], out, formats="npz", scheduler=scheduler)
        assert [record["status"] for record in records] == [status]
        assert_records_match(out)
    assert len(os.fsencode(record_path(output).name)) == 200 + 1 + 16 + 5


def test_a_worker_of_another_version_refuses_the_job(inputs: Path, tmp_path: Path) -> None:
    output = tmp_path / "cube.npz"
    record = convert(Job(str(inputs / "cube.obj"), (str(output),), BuildOptions(), "0.0.0"))
    assert record["status"] == FAILED and "install the same version" in record["error"]
    assert not output.exists() and not record_path(output).exists()


def test_an_input_changed_while_it_is_read_is_refused(
    inputs: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The hash a record names is of the bytes that were read: a file written to between the hash
    and the end of the read fails its task (the next run builds it)."""
    source = inputs / "cube.obj"
    read = g1patch.read

    def read_while_written(*arguments: Any, **options: Any) -> Any:
        with source.open("a") as stream:
            stream.write("# meanwhile\n")
        return read(*arguments, **options)

    monkeypatch.setattr(g1patch, "read", read_while_written)
    output = tmp_path / "cube.npz"
    record = convert(Job(str(source), (str(output),), BuildOptions()))
    assert record["status"] == FAILED and record["error"].endswith(
        "cube.obj: changed while it was read; run the batch again"
    )
    assert not output.exists() and not record_path(output).exists()
