"""Shared fixtures: the external test meshes in ../shared/data beside the repository."""

from __future__ import annotations

from pathlib import Path

import pytest

SHARED_DATA = Path(__file__).parents[1].parent / "shared" / "data"


@pytest.fixture
def shared_data() -> Path:
    """The directory ``../shared/data`` (relative to the repository); skips the test where it is
    absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(
            f"external test data not found: expected the directory {SHARED_DATA} (../shared/data "
            "beside the repository)"
        )
    return SHARED_DATA
