"""The verification suite's fast cases in space (the 3D granules and the elastic solid):
each passes against its independent reference (tests/test_verification.py holds the rest)."""

from __future__ import annotations

import pytest
from test_verification import SPACE_CASES, assert_case_passes

from granplate.verification.base import Context


@pytest.fixture(scope="module")
def ctx(tmp_path_factory) -> Context:
    return Context(out=tmp_path_factory.mktemp("verify-space"))


@pytest.mark.parametrize("name", SPACE_CASES)
def test_fast_case_in_space(name, ctx):
    """Each fast case in space runs, draws its figure and passes every check (but the known failures)."""
    assert_case_passes(name, ctx)
