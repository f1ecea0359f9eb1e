"""Patch files (.bpt) and network files (.npz): round trips and clear errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from g1patch import shapes
from g1patch.construct.corner import build_corner_network
from g1patch.continuity import check
from g1patch.errors import FormatError
from g1patch.io.bpt import read_bpt, write_bpt
from g1patch.io.network_file import load_network, save_network, save_network_in_background
from g1patch.patches import PatchSet

MALFORMED_BPT = Path(__file__).parent / "data" / "malformed_bpt"


def test_teapot_reads_as_32_bezier_patches(shared_data: Path) -> None:
    patches = read_bpt(shared_data / "teapot.bpt")
    assert patches.form == "bezier" and patches.control.shape == (32, 4, 4, 3)
    # first point of the rim in Newell's data, bounding box from the data README
    np.testing.assert_array_equal(patches.control[0, 0, 0], [1.4, 0.0, 2.4])
    flat = patches.control.reshape(-1, 3)
    np.testing.assert_array_equal(flat.min(axis=0), [-3.0, -2.0, 0.0])
    np.testing.assert_array_equal(flat.max(axis=0), [3.525, 2.0, 3.15])


def test_bpt_round_trip_is_exact(tmp_path: Path) -> None:
    patches = PatchSet(np.random.default_rng(1).normal(size=(5, 4, 4, 3)), "bezier")
    write_bpt(tmp_path / "p.bpt", patches)
    np.testing.assert_array_equal(read_bpt(tmp_path / "p.bpt").control, patches.control)


@pytest.mark.parametrize(
    "name,message",
    [
        ("truncated.bpt", r"truncated\.bpt:3: truncated: 2 patches need 35"),
        ("bad_count.bpt", r"bad_count\.bpt:1: expected a positive patch count"),
        ("bad_degree.bpt", r"bad_degree\.bpt:\d+: .*"),
        ("bad_number.bpt", r"bad_number\.bpt:10: patch 1: expected three finite numbers"),
        ("nan.bpt", r"nan\.bpt:18: patch 1: expected three finite numbers"),
        ("empty.bpt", r"empty\.bpt: empty file"),
        ("binary.bpt", r"binary\.bpt: not a text file"),
    ],
)
def test_malformed_bpt_files_name_file_and_line(name: str, message: str) -> None:
    with pytest.raises(FormatError, match=message):
        read_bpt(MALFORMED_BPT / name)


def test_network_round_trip_keeps_the_report(tmp_path: Path) -> None:
    network = build_corner_network(shapes.torus(6, 4), tangents="chord", twist="coons")
    save_network(tmp_path / "n.npz", network)
    loaded = load_network(tmp_path / "n.npz")
    np.testing.assert_array_equal(loaded.patches.control, network.patches.control)
    assert loaded.patches.form == "hermite"
    assert loaded.provenance == network.provenance
    for name in (
        "corner_ids",
        "edge_ids",
        "edge_reversed",
        "neighbor",
        "neighbor_edge",
        "vertices",
        "vertex_normals",
    ):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(network, name))
    assert check(loaded).to_dict() == check(network).to_dict()


def test_saving_in_background_writes_the_same_file(tmp_path: Path) -> None:
    network = build_corner_network(shapes.cube())
    save_network(tmp_path / "now.npz", network)
    saving = save_network_in_background(tmp_path / "later.npz", network)
    assert saving.result() is None
    assert (tmp_path / "later.npz").read_bytes() == (tmp_path / "now.npz").read_bytes()


def test_saving_in_background_refuses_at_once_and_writes_nothing(tmp_path: Path) -> None:
    network = build_corner_network(shapes.cube())
    with pytest.raises(FormatError, match="must end in .npz"):
        save_network_in_background(tmp_path / "n.obj", network)
    assert not list(tmp_path.iterdir())


def test_saving_in_background_raises_what_writing_raised_from_its_result(tmp_path: Path) -> None:
    target = tmp_path / "missing" / "n.npz"
    saving = save_network_in_background(target, build_corner_network(shapes.cube()))
    with pytest.raises(FileNotFoundError) as raised:
        saving.result()
    assert raised.value.filename == str(target)


def test_network_file_errors(tmp_path: Path) -> None:
    with pytest.raises(FormatError, match="no such file"):
        load_network(tmp_path / "missing.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(FormatError, match="not a g1patch network file"):
        load_network(tmp_path / "junk.npz")
    np.savez(tmp_path / "other.npz", a=np.zeros(3))
    with pytest.raises(FormatError, match="no header"):
        load_network(tmp_path / "other.npz")
    with pytest.raises(FormatError, match=r"must end in \.npz"):
        save_network(tmp_path / "n.obj", build_corner_network(shapes.cube()))
    assert not (tmp_path / "n.obj").exists()


def test_a_newer_format_version_is_refused(tmp_path: Path) -> None:
    import json

    save_network(tmp_path / "n.npz", build_corner_network(shapes.cube()))
    with np.load(tmp_path / "n.npz") as data:
        contents = {name: data[name] for name in data.files}
    header = json.loads(str(contents["header"]))
    header["version"] = 99
    contents["header"] = np.array(json.dumps(header))
    np.savez(tmp_path / "v99.npz", **contents)
    with pytest.raises(FormatError, match="version 99 is not supported"):
        load_network(tmp_path / "v99.npz")


def test_gregory_network_round_trip(tmp_path: Path) -> None:
    from g1patch.build import build_gregory_network

    network = build_gregory_network(shapes.torus(6, 4))
    save_network(tmp_path / "g.npz", network)
    loaded = load_network(tmp_path / "g.npz")
    assert type(loaded.patches) is type(network.patches)
    np.testing.assert_array_equal(loaded.patches.points, network.patches.points)
    assert check(loaded).to_dict() == check(network).to_dict()
