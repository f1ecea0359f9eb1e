"""``g1patch batch`` on Dask: an embedded LocalCluster, a shared one by address, a scheduler started
apart; good files converted, a broken one reported and the others untouched by it, re-runs
skipped."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from g1patch import shapes
from g1patch.batch import FAILED, BuildOptions, Job, convert
from g1patch.batch.jobs import recipe
from g1patch.cli import main
from g1patch.io.atomic import TEMPORARY_PREFIX
from g1patch.io.meshfile import write_quads

#: an OBJ whose face names a vertex the file does not have
BROKEN_OBJ = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 9\n"


def needs_dask() -> None:
    pytest.importorskip(
        "distributed", reason="dask.distributed is not installed: pip install 'g1patch[batch]'"
    )


@pytest.fixture(scope="module")
def scheduler() -> Iterator[str]:
    """The address of one LocalCluster of 2 workers on 127.0.0.1, shared by the tests here. Its
    workers are threads of this process (no process starts: the embedded cluster's worker
    processes are tested through the command itself)."""
    needs_dask()
    from distributed import LocalCluster

    with LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=False,
        protocol="tcp",
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        yield cluster.scheduler_address


@pytest.fixture
def meshes(tmp_path: Path) -> Path:
    """A folder of generated meshes (a cube, a torus, an open grid as PLY) and a broken OBJ."""
    folder = tmp_path / "meshes"
    folder.mkdir()
    for name, mesh in (
        ("cube.obj", shapes.cube()),
        ("torus.obj", shapes.torus(6, 4)),
        ("grid.ply", shapes.grid(3, 2)),
    ):
        write_quads(folder / name, mesh.vertices, mesh.faces)
    (folder / "broken.obj").write_text(BROKEN_OBJ)
    return folder


def summary(out: Path) -> dict[str, dict]:
    return {
        record["name"]: record for record in json.loads((out / "summary.json").read_text())["files"]
    }


def table_rows(stdout: str) -> dict[str, str]:
    return {line.split()[0]: line for line in stdout.splitlines()[1:-1]}


def assert_one_line_error(record: dict, name: str) -> None:
    assert record["status"] == FAILED and record["outputs"] == []
    assert name in record["error"] and "vertex" in record["error"] and "\n" not in record["error"]


@pytest.mark.slow
def test_embedded_cluster_converts_generated_meshes_and_reports_the_broken_one(
    meshes: Path, tmp_path: Path
) -> None:
    """The command as a user runs it: its own LocalCluster (one worker process: each costs an
    interpreter, g1patch and its kernels), two formats per file."""
    needs_dask()
    out = tmp_path / "out"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "g1patch.cli",
            "batch",
            meshes,
            "--out",
            out,
            "--workers",
            "1",
            "--formats",
            "npz,obj",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 1, result.stderr
    records = summary(out)
    assert sorted(records) == ["broken.obj", "cube.obj", "grid.ply", "torus.obj"]
    for name in ("cube.obj", "grid.ply", "torus.obj"):
        record = records[name]
        assert record["status"] == "built" and record["error"] is None
        assert record["max_g1_angle_deg"] <= 1e-9 and record["folds"] == 0
        assert set(record["times"]) == {"read", "build", "check", "export", "total"}
        assert set(record["times"]["export"]) == {"npz", "obj"}
        stem = Path(name).stem
        assert record["outputs"] == [str(out / f"{stem}.npz"), str(out / f"{stem}.obj")]
    assert_one_line_error(records["broken.obj"], "broken.obj")
    rows = table_rows(result.stdout)
    assert records["broken.obj"]["error"] in rows["broken.obj"] and "failed" in rows["broken.obj"]
    assert result.stdout.splitlines()[-1] == "4 files: 3 built, 0 skipped, 1 failed"
    assert "1 of 4 files failed: broken.obj" in result.stderr and "Traceback" not in result.stderr
    assert not list(out.glob("broken.*")) and not list(out.glob(f"{TEMPORARY_PREFIX}*"))

    import g1patch

    assert g1patch.check(out / "torus.npz").max_edge_angle_deg <= 1e-9


@pytest.mark.slow
def test_shared_meshes_with_a_broken_file_then_a_rerun_skips_them(
    scheduler: str, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    broken = tmp_path / "broken.obj"
    broken.write_text(BROKEN_OBJ)
    out = tmp_path / "out"
    command = [
        "batch",
        str(shared_data),
        str(broken),
        "--out",
        str(out),
        "--scheduler",
        scheduler,
        "-q",
    ]
    good = sorted(path.name for path in shared_data.glob("*.obj"))
    assert len(good) >= 9

    assert main(command) == 1
    first = capsys.readouterr()
    records = summary(out)
    assert sorted(records) == sorted(
        [*good, "broken.obj"]
    )  # teapot.bpt is not a mesh: left out of the folder
    for name in good:
        assert records[name]["status"] == "built", records[name]["error"]
        assert records[name]["max_g1_angle_deg"] <= 1e-9 and records[name]["folds"] == 0
        assert (out / f"{Path(name).stem}.npz").is_file()
    assert (
        records["catmark_cube_creases2.obj"]["seams"] > 0
    )  # the file's crease tags are kept as seams
    assert_one_line_error(records["broken.obj"], str(broken))
    assert records["broken.obj"]["error"] in table_rows(first.out)["broken.obj"]

    assert (
        main(command) == 1
    )  # the broken file is tried again and fails again; the others are up to date
    second = capsys.readouterr()
    rows = table_rows(second.out)
    again = summary(out)
    for name in good:
        assert (
            again[name]["status"] == "skipped"
            and "skipped" in rows[name]
            and "up to date: same input and options" in rows[name]
        )
        assert (
            again[name]["max_g1_angle_deg"] == records[name]["max_g1_angle_deg"]
        )  # the figures carried over
    assert_one_line_error(again["broken.obj"], str(broken))
    assert (
        second.out.splitlines()[-1]
        == f"{len(good) + 1} files: 0 built, {len(good)} skipped, 1 failed"
    )


def test_rerun_rebuilds_changed_inputs_and_changed_options(
    scheduler: str, meshes: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (meshes / "broken.obj").unlink()
    out = tmp_path / "out"
    command = ["batch", str(meshes), "--out", str(out), "--scheduler", scheduler, "-q"]
    assert main(command) == 0
    assert main(command) == 0
    assert {r["status"] for r in summary(out).values()} == {"skipped"}

    later = time.time() + 5  # touched: the same bytes, a later time
    os.utime(meshes / "torus.obj", (later, later))
    with (meshes / "cube.obj").open("a") as edited:  # edited: other bytes
        edited.write("# edited\n")
    assert main(command) == 0
    assert {name: r["status"] for name, r in summary(out).items()} == {
        "cube.obj": "built",
        "grid.ply": "skipped",
        "torus.obj": "skipped",
    }
    assert (
        main([*command, "--method", "gregory"]) == 0
    )  # other options: the old outputs are not reused
    records = summary(out)
    assert {r["status"] for r in records.values()} == {"built"} and {
        r["method"] for r in records.values()
    } == {"gregory"}
    capsys.readouterr()


@pytest.mark.slow
def test_scheduler_started_separately(
    meshes: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``dask scheduler`` and ``dask worker`` as their own processes on 127.0.0.1, joined by
    address."""
    needs_dask()
    (meshes / "broken.obj").unlink()
    dask_cli = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    scheduler_file = tmp_path / "scheduler.json"
    logs = (tmp_path / "scheduler.log").open("w")
    processes = [
        subprocess.Popen(
            [
                *dask_cli,
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                str(scheduler_file),
            ],
            stdout=logs,
            stderr=logs,
        )
    ]
    try:
        deadline = time.monotonic() + 60
        while not scheduler_file.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        processes.append(
            subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "distributed.cli.dask_worker",
                    address,
                    "--nthreads",
                    "1",
                    "--no-nanny",
                    "--no-dashboard",
                    "--host",
                    "127.0.0.1",
                ],
                stdout=logs,
                stderr=logs,
            )
        )
        out = tmp_path / "out"
        assert main(["batch", str(meshes), "--out", str(out), "--scheduler", address]) == 0, (
            capsys.readouterr().err
        )
        assert {r["status"] for r in summary(out).values()} == {"built"}
        assert json.loads((out / "summary.json").read_text())["scheduler"] == address
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=15)
            except subprocess.TimeoutExpired:  # a worker still closing gracefully
                process.kill()
                process.wait()
        logs.close()


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.mark.slow
def test_unreachable_scheduler_is_a_usage_error(
    meshes: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    needs_dask()
    import dask

    address = f"tcp://127.0.0.1:{_free_port()}"
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        assert (
            main(
                [
                    "batch",
                    str(meshes / "cube.obj"),
                    "--out",
                    str(tmp_path / "out"),
                    "--scheduler",
                    address,
                ]
            )
            == 2
        )
    error = capsys.readouterr().err
    assert (
        error.startswith(f"g1patch: error: --scheduler {address}: cannot connect")
        and error.count("\n") == 1
    )


@pytest.mark.parametrize(
    "case",
    [
        "missing",
        "not a mesh",
        "empty folder",
        "format",
        "no format",
        "bpt of gregory",
        "workers",
        "workers and scheduler",
        "same name",
        "overwrites input",
        "sharp angle",
        "refine",
    ],
)
def test_usage_errors_exit_2_before_any_work(
    case: str, meshes: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    cube = str(meshes / "cube.obj")
    (tmp_path / "empty").mkdir()
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "cube.ply").write_text("ply\n")
    (tmp_path / "notes.txt").write_text("hello\n")
    arguments, named = {
        "missing": ([str(tmp_path / "nothing.obj")], "nothing.obj: no such file or folder"),
        "not a mesh": ([str(tmp_path / "notes.txt")], "notes.txt: not a mesh file"),
        "empty folder": ([str(tmp_path / "empty")], "empty: a folder with no mesh files"),
        "format": ([cube, "--formats", "npz,xyz"], "unknown format 'xyz'"),
        "no format": ([cube, "--formats", " , "], "--formats: give at least one of npz, obj"),
        "bpt of gregory": ([cube, "--formats", "bpt", "--method", "gregory"], "--method split4"),
        "workers": (
            [cube, "--workers", "0"],
            "--workers: expected a number of worker processes ≥ 1, got 0",
        ),
        "workers and scheduler": (
            [cube, "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"],
            "not allowed with",
        ),
        "same name": ([cube, str(tmp_path / "other")], "would both write"),
        "overwrites input": (
            [str(meshes), "--formats", "obj", "--out", str(meshes)],
            "would overwrite the input",
        ),
        "sharp angle": (
            [cube, "--sharp-angle", "200"],
            "--sharp-angle: expected degrees between 0 and 180",
        ),
        "refine": (
            [cube, "--refine", "-1"],
            "refine: expected a number of Catmull–Clark steps ≥ 0",
        ),
    }[case]
    assert (
        exit_code(["batch", *arguments, *([] if "--out" in arguments else ["--out", str(out)])])
        == 2
    )
    error = capsys.readouterr().err
    assert named in error.splitlines()[-1] and "Traceback" not in error
    assert (
        case == "workers and scheduler" or error.count("\n") == 1
    )  # argparse adds its usage lines
    assert not out.exists() and not list(meshes.glob("*.npz"))


def exit_code(argv: list[str]) -> int:
    """``main(argv)``, argparse's exits included."""
    try:
        return main(argv)
    except SystemExit as exit_:
        return int(exit_.code or 0)


def test_missing_dask_names_the_extra(
    meshes: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed → ImportError
    assert main(["batch", str(meshes / "cube.obj"), "--out", str(tmp_path / "out")]) == 2
    assert "pip install 'g1patch[batch]'" in capsys.readouterr().err


def test_import_g1patch_and_its_cli_import_no_dask() -> None:
    code = (
        "import sys, g1patch, g1patch.cli, g1patch.batch; "
        "print(sorted({'dask', 'distributed'} & set(sys.modules)))"
    )
    assert (
        subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True
        ).stdout.strip()
        == "[]"
    )


def test_help_has_examples(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["batch", "--help"])
    assert exit_.value.code == 0 and "g1patch batch meshes/ --out out" in capsys.readouterr().out


def test_convert_returns_a_record_and_never_raises(meshes: Path, tmp_path: Path) -> None:
    """The task itself, without a cluster: a built file's figures, a broken file's one-line error,
    an unwritable output's OS error."""
    options = BuildOptions(shape="limit")
    good = convert(Job(str(meshes / "cube.obj"), (str(tmp_path / "cube.npz"),), options))
    assert good["status"] == "built" and good["shape"] == "limit" and good["patches"] == 4 * 6
    assert 0 < good["limit_distance"] <= good["tolerance"] == 1e-3  # the cube: 4.8e-4 (split4)
    assert (tmp_path / "cube.npz").is_file()
    assert_one_line_error(
        convert(Job(str(meshes / "broken.obj"), (str(tmp_path / "b.npz"),), options)), "broken.obj"
    )
    unwritable = convert(
        Job(str(meshes / "cube.obj"), (str(tmp_path / "no" / "such" / "cube.npz"),), options)
    )
    assert unwritable["status"] == FAILED and "No such file or directory" in unwritable["error"]
    assert unwritable["patches"] == 4 * 6 and unwritable["times"]["check"] > 0  # how far it got


def test_interrupt_writes_the_summary_so_far(
    meshes: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C during a batch: the records done are kept, the others marked cancelled, and it is
    raised again."""
    import g1patch.batch.run as batch

    def run(
        jobs: list[Job], scheduler: object, workers: object, progress: object, done: dict
    ) -> None:
        done[jobs[0].source] = convert(jobs[0])
        raise KeyboardInterrupt

    monkeypatch.setattr(batch, "_run", run)
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        batch.run_batch([meshes], out)
    statuses = {name: record["status"] for name, record in summary(out).items()}
    assert statuses == {
        "broken.obj": "failed",
        "cube.obj": "cancelled",
        "grid.ply": "cancelled",
        "torus.obj": "cancelled",
    }


def test_cad_exports_record_what_opencascade_measured(meshes: Path, tmp_path: Path) -> None:
    pytest.importorskip(
        "OCP", reason="STEP export needs cadquery-ocp-novtk: pip install 'g1patch[cad]'"
    )
    from g1patch.batch.jobs import json_ready

    record = convert(Job(str(meshes / "cube.obj"), (str(tmp_path / "cube.step"),), BuildOptions()))
    assert record["status"] == "built", record["error"]
    step = record["cad"]["step"]
    assert (
        step["faces"] == 6
        and step["max_g1_angle_deg"] <= 1e-9
        and step["path"] == str(tmp_path / "cube.step")
    )
    json.dumps(json_ready(record), allow_nan=False)  # summary.json holds it as it is
    assert json_ready({"a": float("nan"), "b": (1, float("inf"))}) == {"a": None, "b": [1, None]}


def test_embedded_workers_are_set_up_like_the_command_line(monkeypatch: pytest.MonkeyPatch) -> None:
    """The embedded cluster's workers ignore SIGINT and keep freed memory (g1patch.memory)."""
    pytest.importorskip(
        "distributed", reason="dask.distributed is not installed: pip install 'g1patch[batch]'"
    )
    import signal

    from g1patch.batch import run as batch

    calls: list[object] = []
    monkeypatch.setattr(batch, "tune_for_large_arrays", lambda: calls.append("tuned"))
    monkeypatch.setattr(signal, "signal", lambda *arguments: calls.append(arguments))
    batch._embedded_worker_setup().setup(worker=None)
    assert calls == [(signal.SIGINT, signal.SIG_IGN), "tuned"]


def test_the_workers_read_with_the_input_size_cap(meshes: Path, tmp_path: Path) -> None:
    """--max-input-size reaches the task: a file above it fails alone (a batch's way), one line
    naming it and the cap, nothing written; the cap is no part of an output's recipe."""
    capped = BuildOptions(max_input_size=10)
    record = convert(Job(str(meshes / "cube.obj"), (str(tmp_path / "cube.npz"),), capped))
    assert record["status"] == FAILED and record["outputs"] == []
    assert "cube.obj" in record["error"] and "input size cap of 10 bytes" in record["error"]
    assert "\n" not in record["error"] and not (tmp_path / "cube.npz").exists()
    assert recipe(capped, ["npz"], "x") == recipe(BuildOptions(), ["npz"], "x")
