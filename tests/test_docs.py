"""The documentation: ``mkdocs build --strict`` succeeds (no warning: a broken link, a missing
picture or a docstring mkdocstrings cannot read fails it), and its pictures are small and used."""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: the largest picture committed to docs/images
MAX_PICTURE_BYTES = 150_000
#: modules the build needs (the ``docs`` extra)
DOCS_MODULES = ("mkdocs", "material", "mkdocstrings", "mkdocstrings_handlers.python")


@pytest.mark.slow
def test_the_docs_build_without_warnings(tmp_path: Path) -> None:
    for module in DOCS_MODULES:
        try:
            found = importlib.util.find_spec(module) is not None
        except ModuleNotFoundError:
            found = False
        if not found:
            pytest.skip(f"{module} is not installed: the docs build needs pip install -e '.[docs]'")
    site = tmp_path / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    result = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert result.returncode == 0, (
        f"mkdocs build --strict failed:\n{result.stdout}\n{result.stderr}"
    )
    assert "WARNING" not in result.stderr, result.stderr
    render_page = (site / "api" / "render" / "index.html").read_text(encoding="utf-8")
    assert 'id="g1patch.render.auto_camera"' in render_page, (
        "the API reference documents auto_camera"
    )
    assert ":func:" not in render_page, "Sphinx roles are shown as code (docs/griffe_roles.py)"
    for page in ("build", "check", "export", "render", "view", "demo", "batch", "fit"):
        assert (site / "guide" / page / "index.html").is_file(), f"no guide page for {page}"


def test_the_pictures_are_small_and_every_one_is_shown() -> None:
    pictures = sorted((DOCS / "images").glob("*.png"))
    assert pictures, "docs/images holds the pictures made by docs/make_pictures.py"
    for picture in pictures:
        assert picture.stat().st_size <= MAX_PICTURE_BYTES, (
            f"{picture.name}: {picture.stat().st_size} bytes"
        )
    pages = [*DOCS.rglob("*.md"), ROOT / "README.md"]
    shown = {
        Path(m).name
        for page in pages
        for m in re.findall(r"\]\(([^)]+\.png)\)", page.read_text(encoding="utf-8"))
    }
    assert {p.name for p in pictures} <= shown, (
        f"pictures no page shows: {sorted({p.name for p in pictures} - shown)}"
    )
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    for name in ("cube_three_ways_zebra.png", "spot_zebra.png"):
        assert f"docs/images/{name}" in readme, f"the README shows {name}"
        assert (DOCS / "images" / name).is_file()
