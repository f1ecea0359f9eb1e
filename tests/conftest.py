"""Shared fixtures and settings: the external test meshes in ../shared/data beside the repository
(one helper for every test that reads them), and Hypothesis's profile in CI."""

from __future__ import annotations

import os
from collections.abc import Generator
from pathlib import Path

import pytest
from hypothesis import settings

SHARED_DATA = Path(__file__).parents[1].parent / "shared" / "data"
#: CI services set the environment variable CI (GitHub Actions, GitLab, Travis, ...)
IN_CI = "CI" in os.environ
#: every skip for want of the external data says this (the report hook below recognises it)
DATA_SKIP = "external test data not found"

# In CI the same examples on every run (derandomize) and no example database: a stale database
# must never choose what runs. No deadline either: a shared runner's timing is not the code's.
# Locally Hypothesis's defaults: fresh random examples, failures replayed from .hypothesis/.
settings.register_profile("g1patch-ci", derandomize=True, database=None, deadline=None)
if IN_CI:
    settings.load_profile("g1patch-ci")


def shared_data_path(*parts: str) -> Path:
    """``../shared/data`` beside the repository, or ``parts`` inside it, for every test that
    reads the external data (through the fixture ``shared_data`` or, in Hypothesis tests, called
    directly). Where the directory is absent the test skips, all with one reason naming it (CI has
    it); a skip while the directory is there (a file missing) fails in CI, see below."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"{DATA_SKIP}: no directory {SHARED_DATA} (../shared/data beside the repo)")
    path = SHARED_DATA.joinpath(*parts)
    if not path.exists():
        pytest.skip(f"{DATA_SKIP}: {SHARED_DATA} has no {Path(*parts)}")
    return path


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The directory ``../shared/data`` (relative to the repository); see ``shared_data_path``."""
    return shared_data_path()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    """A data test's skip is reported from here, so ``-rs`` folds them into one line naming the
    directory; in CI with ../shared/data present it is a failure (it would hide the tests the data
    exist for)."""
    report = yield
    if report.skipped and isinstance(report.longrepr, tuple) and DATA_SKIP in report.longrepr[2]:
        reason = report.longrepr[2].removeprefix("Skipped: ")
        if IN_CI and SHARED_DATA.is_dir():
            report.outcome = "failed"
            report.longrepr = f"CI and {SHARED_DATA} is there, yet the test skipped: {reason}"
        else:
            report.longrepr = (__file__, None, reason)
    return report
