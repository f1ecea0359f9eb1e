"""Fuzzing the command line in CI: hypothesis draws case seeds, :mod:`fuzzing` writes the hostile
meshes and network files and judges what every command did (exit 0/1/2 only, one stderr line on
2, no traceback, nothing left behind on failure, no NaN in a report). ``benchmarks/fuzz.py`` runs
the same cases by the ten thousand."""

from __future__ import annotations

import tempfile
from pathlib import Path

import fuzzing
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

#: cases per CI run (the issue asks for at least 500)
CI_CASES = 500


@pytest.mark.slow
@settings(
    max_examples=CI_CASES, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck)
)
@given(st.integers(min_value=0, max_value=2**32 - 1))
def test_hostile_inputs_keep_the_command_line_promises(seed: int) -> None:
    with tempfile.TemporaryDirectory() as directory:
        case = fuzzing.make_case(seed, Path(directory))
        found = fuzzing.problems(case, fuzzing.run_case(case, render=seed % 8 == 0))
    assert not found, "\n".join(found)


@pytest.mark.parametrize("seed", [1623, 7417])
def test_cases_the_ten_thousand_found(seed: int) -> None:
    """split4 on a tagged mesh it then refused printed its crease warning before the error: two
    lines on a failure (benchmarks/fuzz.py, 10,000 cases); the warning now follows a built
    network."""
    with tempfile.TemporaryDirectory() as directory:
        case = fuzzing.make_case(seed, Path(directory))
        found = fuzzing.problems(case, fuzzing.run_case(case, render=False))
    assert not found, "\n".join(found)
