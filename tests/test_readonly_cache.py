"""A read-only install (issue 32, part 2): where numba has no writable cache directory (the
package's ``__pycache__``, ``NUMBA_CACHE_DIR``, the user's cache), the commands run the NumPy code
with one warning instead of ending in a traceback.

The package is copied to a read-only folder (``PYTHONPATH``), and ``HOME`` and ``NUMBA_CACHE_DIR``
are read-only too. As root, permissions bind only without ``CAP_DAC_OVERRIDE``: the command then
runs under ``setpriv`` with that capability dropped."""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

import g1patch
from g1patch import kernels, shapes
from g1patch.io.meshfile import write_quads

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(sys.platform != "linux", reason="permissions and setpriv of Linux"),
]

WARNING = "g1patch: warning: numba has no writable cache directory"


def read_only(path: Path) -> None:
    """``path`` and everything below it: readable, not writable."""
    for folder, _, files in os.walk(path):
        for name in files:
            os.chmod(os.path.join(folder, name), 0o444)
        os.chmod(folder, 0o555)


@pytest.fixture(scope="module")
def install(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """A read-only copy of the package, without compiled caches, and read-only HOME and cache."""
    root = tmp_path_factory.mktemp("readonly")
    shutil.copytree(
        Path(g1patch.__file__).parent,
        root / "site" / "g1patch",
        ignore=shutil.ignore_patterns("__pycache__"),
    )
    for name in ("home", "cache"):
        (root / name).mkdir()
    (root / "matplotlib").mkdir()  # matplotlib's own complaint about HOME is not ours
    yield root
    for folder, _, _ in os.walk(root):
        os.chmod(folder, 0o755)


def g1patch_read_only(install: Path, *args: str | Path) -> subprocess.CompletedProcess[str]:
    for name in ("site", "home", "cache"):
        read_only(install / name)
    prefix: list[str] = []
    if os.geteuid() == 0:
        if shutil.which("setpriv") is None:
            pytest.skip("root without setpriv: permissions do not bind")
        prefix = ["setpriv", "--bounding-set", "-dac_override,-dac_read_search,-fowner", "--"]
    environment = {
        **os.environ,
        "PYTHONPATH": str(install / "site"),
        "HOME": str(install / "home"),
        "NUMBA_CACHE_DIR": str(install / "cache"),
        "MPLCONFIGDIR": str(install / "matplotlib"),
        "PYTHONDONTWRITEBYTECODE": "1",
    }
    return subprocess.run(
        [*prefix, sys.executable, "-m", "g1patch.cli", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=600,
        env=environment,
        cwd=install,
    )


def assert_one_warning(result: subprocess.CompletedProcess[str]) -> None:
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    assert result.stderr.count(WARNING) == 1, result.stderr


def test_build_and_demo_fall_back_to_numpy_with_one_warning(install: Path, tmp_path: Path) -> None:
    mesh = tmp_path / "sphere.obj"
    cube = shapes.cube_sphere(2)
    write_quads(mesh, cube.vertices, cube.faces)
    os.chmod(tmp_path, stat.S_IRWXU | stat.S_IRWXG | stat.S_IRWXO)
    built = g1patch_read_only(install, "build", mesh, "-o", tmp_path / "sphere.npz", "--check")
    assert_one_warning(built)
    assert (tmp_path / "sphere.npz").exists() and "G1" in built.stdout
    demo = g1patch_read_only(install, "demo", "--out", tmp_path / "demo")
    assert_one_warning(demo)
    assert (tmp_path / "demo" / "cube_zebra.png").exists()
    assert not list((install / "site").rglob("*.nbi")) and not list((install / "cache").iterdir())


def test_a_writable_cache_needs_no_warning(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """With a writable cache directory (``NUMBA_CACHE_DIR``, numba's ``config.CACHE_DIR``) the
    kernels run, and nothing is said (whether this process's own cache is writable or not)."""
    import numba

    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    kernels.kernels_cached.cache_clear()
    try:
        assert kernels.kernels_cached()
        assert kernels.use_kernels(True) and not kernels.use_kernels(False)
        assert "no writable cache" not in caplog.text
    finally:
        monkeypatch.undo()
        kernels.kernels_cached.cache_clear()


def test_no_kernel_is_compiled_where_none_can_be_cached(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """With no cache (``kernels_cached`` False) every stage takes its NumPy twin: reading a large
    OBJ, every shape × method, the check. numba's ``njit`` fails if anything compiles (an
    in-memory compile costs seconds per kernel per command)."""
    import numba

    from g1patch.construct import METHODS
    from g1patch.targets import SHAPES

    monkeypatch.setattr(kernels, "kernels_cached", lambda: False)
    monkeypatch.setattr(kernels, "jit_kernel", kernels.jit_kernel.__wrapped__)

    def refuse(*args: object, **options: object) -> None:
        raise AssertionError("a kernel was compiled")

    monkeypatch.setattr(numba, "njit", refuse)
    cube = shapes.cube_sphere(5)
    path = tmp_path / "sphere.obj"
    write_quads(path, cube.vertices, cube.faces)
    padding = b"#" * (2 << 20) + b"\n"  # past the readers' kernel threshold
    path.write_bytes(padding + path.read_bytes())
    assert g1patch.read(path).faces.shape == cube.faces.shape
    small = shapes.cube_sphere(1)
    for shape in SHAPES:
        for method in METHODS:
            report = g1patch.smooth(small, shape=shape, method=method).check()
            assert report.is_g1(1e-6) or method in ("corner", "legacy"), (shape, method)
