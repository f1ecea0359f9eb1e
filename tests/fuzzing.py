"""Adversarial inputs for the command line: generated meshes and files, and the promises they test.

A *case* is one seed: :func:`make_case` writes either a mesh file (OBJ, PLY or OFF, from a small
valid mesh with random topology edits, coordinate edits, tags and byte-level damage) or a network
file (a valid ``.npz`` with one member mutated, or the file damaged), and :func:`run_case` drives it
through ``build → check → export → render`` in this process (``g1patch.cli.main``), recording per
command the exit code, stderr, escaped exceptions and leftover files. :func:`problems` names every
broken promise: an exit code other than 0/1/2, a traceback, more than one stderr line on exit 2, an
output or temporary file left after a failure (exit 2; exit 1, a measure that fell short, writes
its output by design), a NaN or infinity in a JSON report, a command slower than
:data:`TIME_CAP`.

Used by ``tests/test_fuzz.py`` (a few hundred cases in CI) and ``benchmarks/fuzz.py`` (10,000).
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import time
import traceback
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

#: seconds any one command of a case may take
TIME_CAP = 60.0
MESH_FORMATS = (".obj", ".ply", ".off")


@dataclass
class Outcome:
    """One command of a case: arguments, exit code, stderr, an escaped exception, leftovers,
    time."""

    argv: list[str]
    code: int | None
    stdout: str
    stderr: str
    exception: str | None
    leftovers: list[str]
    seconds: float


@dataclass
class Case:
    seed: int
    kind: str  # "mesh" or "network"
    path: Path
    edits: list[str] = field(default_factory=list)


# -- meshes ---------------------------------------------------------------------------------------


def _base_mesh(rng: np.random.Generator) -> tuple[np.ndarray, list[list[int]]]:
    """A small valid mesh: a cube, a grid, a torus, a fan, or a box with n-gon caps."""
    from g1patch import shapes

    choice = rng.integers(5)
    if choice == 0:
        mesh = shapes.cube()
    elif choice == 1:
        mesh = shapes.grid(int(rng.integers(1, 4)), int(rng.integers(1, 4)))
    elif choice == 2:
        mesh = shapes.torus(int(rng.integers(3, 7)), int(rng.integers(3, 5)))
    elif choice == 3:
        mesh = shapes.fan(int(rng.integers(3, 9)))
    else:
        sides = int(rng.integers(3, 9))
        angle = np.linspace(0, 2 * np.pi, sides, endpoint=False)
        ring = np.stack([np.cos(angle), np.sin(angle)], axis=1)
        vertices = np.concatenate(
            [np.column_stack([ring, np.zeros(sides)]), np.column_stack([ring, np.ones(sides)])]
        )
        faces = [[i, (i + 1) % sides, sides + (i + 1) % sides, sides + i] for i in range(sides)]
        faces += [list(range(sides))[::-1], list(range(sides, 2 * sides))]
        return vertices, faces
    return mesh.vertices.copy(), mesh.faces.tolist()


def _edit_mesh(
    rng: np.random.Generator, vertices: np.ndarray, faces: list[list[int]], edits: list[str]
) -> tuple[np.ndarray, list[list[int]], list[str]]:
    """Random topology and coordinate edits, and OpenSubdiv tags (some of them invalid)."""
    tags: list[str] = []
    nv = len(vertices)
    for _ in range(int(rng.integers(0, 4))):
        kind = int(rng.integers(18))
        f = int(rng.integers(len(faces))) if faces else 0
        if kind == 0 and faces:
            faces[f] = faces[f][::-1]
            edits.append(f"flip face {f}")
        elif kind == 1 and faces:
            faces.append(list(faces[f]))
            edits.append(f"duplicate face {f}")
        elif kind == 2 and len(faces) > 1:
            faces.pop(f)
            edits.append(f"delete face {f}")
        elif kind == 3 and faces and all(0 <= i < len(vertices) for i in faces[f][:2]):
            a, b = faces[f][0], faces[f][1]
            vertices = np.vstack([vertices, vertices[[a, b]].mean(axis=0) + rng.normal(size=3)])
            faces.append([a, b, len(vertices) - 1])
            edits.append(f"third face on edge ({a}, {b})")
        elif kind == 4 and faces:
            faces[f] = faces[f] + [faces[f][0]]
            edits.append(f"repeat a vertex in face {f}")
        elif kind == 5 and faces:
            faces[f][0] = nv + int(rng.integers(1, 5))
            edits.append(f"out-of-range index in face {f}")
        elif kind == 6 and faces:
            faces[f][0] = -int(rng.integers(1, 3))
            edits.append(f"negative index in face {f}")
        elif kind == 7:
            vertices[int(rng.integers(len(vertices))), int(rng.integers(3))] = rng.choice(
                [np.nan, np.inf, -np.inf]
            )
            edits.append("non-finite coordinate")
        elif kind == 8:
            vertices = vertices * rng.choice([1e300, 1e-300, 1e150, 1e-150])
            edits.append("extreme scale")
        elif kind == 9:
            vertices = vertices + rng.choice([1e12, -1e15])
            edits.append("far translation")
        elif kind == 10 and faces and all(0 <= i < len(vertices) for i in faces[f][:2]):
            vertices[faces[f][1]] = vertices[faces[f][0]]
            edits.append(f"collapse an edge of face {f}")
        elif kind == 11:
            vertices = vertices + rng.normal(scale=0.3, size=vertices.shape)
            edits.append("noise")
        elif kind == 12 and faces:
            a, b = faces[f][0], faces[f][1]
            tags.append(
                f"t crease 2/1/0 {a} {b} {rng.choice(['10', '2.5', '0.3', '-1', 'nan', '1e308'])}"
            )
            edits.append("crease tag")
        elif kind == 13:
            tags.append(f"t crease 2/1/0 0 {int(rng.integers(nv + 3))} 10")
            edits.append("crease tag on a possible non-edge")
        elif kind == 14:
            tags.append(
                f"t corner 1/1/0 {int(rng.integers(-2, nv + 3))} {rng.choice(['10', '3', 'inf'])}"
            )
            edits.append("corner tag")
        elif kind == 15 and faces:
            tags.append(f"t hole 1/0/0 {int(rng.integers(-1, len(faces) + 2))}")
            edits.append("hole tag")
        elif kind == 16:
            tags.append(f"t interpolateboundary 1/0/0 {int(rng.integers(-1, 5))}")
            edits.append("boundary tag")
        elif kind == 17:
            vertices = np.vstack([vertices, rng.normal(size=(int(rng.integers(1, 4)), 3))])
            edits.append("unused vertices")
    return vertices, faces, tags


def _mesh_text(suffix: str, vertices: np.ndarray, faces: list[list[int]], tags: list[str]) -> bytes:
    """The mesh as OBJ (1-based, tags at the end), ASCII PLY or OFF text."""

    def number(x: float) -> str:
        return repr(float(x))

    if suffix == ".obj":
        lines = [f"v {' '.join(map(number, v))}" for v in vertices]
        lines += ["f " + " ".join(str(i + 1 if i >= 0 else i) for i in face) for face in faces]
        lines += tags
    elif suffix == ".off":
        lines = ["OFF", f"{len(vertices)} {len(faces)} 0"]
        lines += [" ".join(map(number, v)) for v in vertices]
        lines += [f"{len(face)} " + " ".join(map(str, face)) for face in faces]
    else:
        lines = [
            "ply",
            "format ascii 1.0",
            f"element vertex {len(vertices)}",
            "property float x",
            "property float y",
            "property float z",
            f"element face {len(faces)}",
            "property list uchar int vertex_indices",
            "end_header",
        ]
        lines += [" ".join(map(number, v)) for v in vertices]
        lines += [f"{len(face)} " + " ".join(map(str, face)) for face in faces]
    return ("\n".join(lines) + "\n").encode()


def _damage_bytes(rng: np.random.Generator, data: bytes, edits: list[str]) -> bytes:
    """Byte-level damage, sometimes: truncation, flipped bytes, garbage or dropped lines."""
    kind = int(rng.integers(8))
    if kind == 0 and data:
        cut = int(rng.integers(len(data)))
        edits.append(f"truncated at byte {cut}")
        return data[:cut]
    if kind == 1 and data:
        buffer = bytearray(data)
        for _ in range(int(rng.integers(1, 6))):
            buffer[int(rng.integers(len(buffer)))] = int(rng.integers(256))
        edits.append("flipped bytes")
        return bytes(buffer)
    if kind == 2:
        lines = data.split(b"\n")
        lines.insert(
            int(rng.integers(len(lines) + 1)),
            rng.choice([b"f 1 2", b"v 1 2", b"v a b c", b"\x00\xff", b"f 1/2/3/4 x"]),
        )
        edits.append("garbage line")
        return b"\n".join(lines)
    if kind == 3:
        lines = data.split(b"\n")
        lines.pop(int(rng.integers(len(lines))))
        edits.append("dropped line")
        return b"\n".join(lines)
    return data


# -- networks -------------------------------------------------------------------------------------


def _network_bytes(rng: np.random.Generator, directory: Path, edits: list[str]) -> bytes:
    """A valid network file of a small mesh, then one member mutated or the file damaged."""
    from g1patch import shapes
    from g1patch.build import build_network
    from g1patch.io.network_file import save_network

    mesh = [shapes.cube, lambda: shapes.grid(2, 2), lambda: shapes.torus(4, 3)][
        int(rng.integers(3))
    ]()
    method = str(rng.choice(["gregory", "split4", "corner"]))
    clean = directory / "clean.npz"
    save_network(clean, build_network(mesh, method))  # type: ignore[arg-type]
    data = clean.read_bytes()
    clean.unlink()
    if rng.random() < 0.3:
        return _damage_bytes(rng, data, edits)
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    name = str(rng.choice(sorted(members)))
    array = np.load(io.BytesIO(members[name]), allow_pickle=False)
    kind = int(rng.integers(9))
    if kind == 0:
        del members[name]
        edits.append(f"member {name} removed")
    elif kind == 8:
        members["junk.npy"] = members[name]
        edits.append("junk member added")
    else:
        array = _mutated(rng, name, array, kind, edits)
        buffer = io.BytesIO()
        np.save(buffer, array, allow_pickle=False)
        members[name] = buffer.getvalue()
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as archive:
        for member, content in members.items():
            archive.writestr(member, content)
    return out.getvalue()


def _mutated(
    rng: np.random.Generator, name: str, array: np.ndarray, kind: int, edits: list[str]
) -> np.ndarray:
    """One member's array changed one way (kind 1–7): a bad index, a bad float, a row short, bools
    as 2s, another dtype, a replaced header, another shape (unchanged where the kind does not
    apply)."""
    if kind == 1 and array.dtype.kind in "iu" and array.size:
        array = array.astype(np.int64)
        array.flat[int(rng.integers(array.size))] = int(rng.choice([-5, 10**6, 2**40]))
        edits.append(f"{name}: index out of range")
    elif kind == 2 and array.dtype.kind == "f" and array.size:
        array = array.copy()
        array.flat[int(rng.integers(array.size))] = rng.choice([np.nan, np.inf, 1e308, -1e200])
        edits.append(f"{name}: bad float")
    elif kind == 3 and array.ndim and len(array):
        array = array[:-1]
        edits.append(f"{name}: one row short")
    elif kind == 4 and array.dtype.kind == "b":
        array = array.astype(np.int8) * 2
        edits.append(f"{name}: bool as int8 2")
    elif kind == 5 and array.dtype.kind in "iubf":
        array = array.astype(np.float32) if array.dtype.kind in "iub" else array.astype(np.int64)
        edits.append(f"{name}: dtype changed")
    elif kind == 6 and array.dtype.kind == "U":
        array = np.array(
            rng.choice(
                ['{"format": "g1patch-network", "version": 99}', "{not json", '{"version": 3}']
            )
        )
        edits.append(f"{name}: header replaced")
    elif kind == 7:
        array = (
            array.reshape(-1)
            if array.ndim > 1
            else array.reshape(1, -1)
            if array.ndim == 1
            else np.array([array])
        )
        edits.append(f"{name}: reshaped")
    return array


def make_case(seed: int, directory: Path) -> Case:
    """Write case ``seed`` into ``directory`` (a fresh, empty one) and say what was done."""
    rng = np.random.default_rng(seed)
    edits: list[str] = []
    if rng.random() < 0.7:
        suffix = str(rng.choice(MESH_FORMATS))
        vertices, faces = _base_mesh(rng)
        vertices, faces, tags = _edit_mesh(rng, vertices, faces, edits)
        data = _mesh_text(suffix, vertices, faces, tags if suffix == ".obj" else [])
        if rng.random() < 0.3:
            data = _damage_bytes(rng, data, edits)
        path = directory / f"input{suffix}"
        path.write_bytes(data)
        return Case(seed, "mesh", path, edits)
    path = directory / "input.npz"
    path.write_bytes(_network_bytes(rng, directory, edits))
    return Case(seed, "network", path, edits)


# -- running and judging
# ------------------------------------------------------------------------------


def _run(argv: list[str], directory: Path) -> Outcome:
    """``g1patch.cli.main(argv)`` with stdout and stderr captured; files created in ``directory`` by
    a failing command are its leftovers."""
    from g1patch.cli import main

    before = set(directory.iterdir())
    stdout, stderr = io.StringIO(), io.StringIO()
    exception = None
    code: int | None = None
    start = time.perf_counter()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        try:
            code = main(argv)
        except SystemExit as exit_:  # argparse
            code = exit_.code if isinstance(exit_.code, int) else 2
        except BaseException:  # noqa: BLE001 - every escaped exception is a finding
            exception = traceback.format_exc()
    seconds = time.perf_counter() - start
    created = sorted(str(p.name) for p in set(directory.iterdir()) - before)
    # exit 1 is a measurement that fell short (a build's distance to the limit above its
    # tolerance): the output is written all the same, as the command line promises
    leftovers = created if code not in (0, 1) else [name for name in created if "tmp" in name]
    return Outcome(argv, code, stdout.getvalue(), stderr.getvalue(), exception, leftovers, seconds)


def run_case(
    case: Case, rng_seed: int | None = None, render: bool = True, cad: bool = False
) -> list[Outcome]:
    """Drive the case through the commands that apply (module docstring)."""
    rng = np.random.default_rng(case.seed if rng_seed is None else rng_seed)
    directory = case.path.parent
    outcomes = []
    network = case.path
    if case.kind == "mesh":
        network = directory / "built.npz"
        options = [
            ["--method", str(rng.choice(["gregory", "split4", "corner"]))],
            ["--shape", str(rng.choice(["interpolate", "limit", "legacy"]))],
        ]
        argv = ["build", str(case.path), "-o", str(network), "-q"] + [
            x for option in options if rng.random() < 0.5 for x in option
        ]
        if rng.random() < 0.2:
            argv += ["--sharp-angle", "30"]
        if rng.random() < 0.2:
            argv += ["--strict"]
        outcomes.append(_run(argv, directory))
        if outcomes[-1].code not in (0, 1):
            return outcomes
    outcomes.append(_run(["check", str(network), "--json", "-q"], directory))
    outcomes.append(
        _run(["export", str(network), "-o", str(directory / "out.obj"), "-q"], directory)
    )
    if cad:
        outcomes.append(
            _run(["export", str(network), "-o", str(directory / "out.step"), "-q"], directory)
        )
    if render:
        outcomes.append(
            _run(
                [
                    "render",
                    str(network),
                    "-o",
                    str(directory / "out.png"),
                    "--size",
                    "96",
                    "96",
                    "-q",
                ],
                directory,
            )
        )
    return outcomes


def _has_nan(text: str) -> bool:
    try:
        value = json.loads(text)
    except ValueError:
        return "NaN" in text or "Infinity" in text

    def walk(item: object) -> bool:
        if isinstance(item, float):
            return not math.isfinite(item)
        if isinstance(item, dict):
            return any(walk(v) for v in item.values())
        if isinstance(item, list):
            return any(walk(v) for v in item)
        return False

    return walk(value) or "NaN" in text or "Infinity" in text


def problems(case: Case, outcomes: list[Outcome]) -> list[str]:
    """Every broken promise of the case's commands (module docstring), as one-line descriptions."""
    found = []
    for outcome in outcomes:
        edits = ", ".join(case.edits) or "clean"
        what = f"seed {case.seed} ({case.kind}: {edits}): {' '.join(outcome.argv[:1])}"
        if outcome.exception is not None:
            found.append(f"{what}: traceback: {outcome.exception.strip().splitlines()[-1]}")
            continue
        if outcome.code not in (0, 1, 2):
            found.append(f"{what}: exit {outcome.code}")
        lines = [line for line in outcome.stderr.splitlines() if line.strip()]
        if outcome.code == 2 and (len(lines) != 1 or not lines[0].startswith("g1patch: error: ")):
            found.append(f"{what}: exit 2 with stderr {outcome.stderr!r}")
        if "Traceback" in outcome.stderr:
            found.append(f"{what}: traceback on stderr")
        if outcome.leftovers:
            found.append(f"{what}: left {outcome.leftovers}")
        if outcome.argv[0] == "check" and outcome.code in (0, 1) and _has_nan(outcome.stdout):
            found.append(f"{what}: NaN or infinity in the report")
        if outcome.seconds > TIME_CAP:
            found.append(f"{what}: took {outcome.seconds:.0f} s")
    return found
