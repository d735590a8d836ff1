"""Each criterion passes where its rule holds and fails where it does not (including at
its edges and on NaN), and writes the rule it applies as text; a Check carries the
verdict, and the verification kinds map to the same criteria."""

from __future__ import annotations

import math

import pytest

from granplate.results.criteria import (
    Above,
    AllOf,
    AtLeast,
    AtMost,
    AtMostSetting,
    Below,
    Between,
    Check,
    Increasing,
    Item,
    ReportedOnly,
    Within,
    criterion_of_kind,
)


def test_within_relative_to_the_paper_or_a_given_value():
    c = Within(0.02)
    assert c.holds(1.0199, 1.0) and c.holds(0.9801, 1.0) and not c.holds(1.021, 1.0)
    assert not c.holds(math.nan, 1.0)
    assert c.text() == "within 2% of the paper's value"
    assert Within(0.05, of=1.0, name="ratio").holds(1.04) and not Within(0.05, of=1.0).holds(1.06)
    assert Within(0.05, of=1.0, name="ratio").text() == "ratio within 5% of 1"
    assert Within(0.1, absolute=True).holds(0.55, 0.5) and not Within(0.1, absolute=True).holds(0.65, 0.5)


def test_bounds_strict_and_inclusive():
    assert Below(0.5).holds(0.49) and not Below(0.5).holds(0.5)
    assert AtMost(0.5).holds(0.5) and not AtMost(0.5).holds(0.51)
    assert Above(10).holds(10.5) and not Above(10).holds(10)
    assert AtLeast(1.0).holds(1.0) and not AtLeast(1.0).holds(0.99)
    assert not Below(0.5).holds(math.nan) and not Above(0.5).holds(math.inf)
    assert Below(0.5, "PTFE / steel").text() == "PTFE / steel < 0.5"
    assert Above(10, "bare / with-granules").text() == "bare / with-granules > 10"
    assert Below(0.05, "plate peak share", percent=True).text() == "plate peak share < 5%"


def test_between_closed_and_half_open():
    c = Between(0.45, 0.60, percent=True, name="share")
    assert c.holds(0.45) and c.holds(0.60) and not c.holds(0.44) and not c.holds(0.61)
    assert c.text() == "share in [45%, 60%]"
    h = Between(0.7, 1.0, upper_open=True, name="ratio")
    assert h.holds(0.7) and not h.holds(1.0) and h.text() == "ratio in [0.7, 1)"


def test_increasing_with_never():
    assert Increasing().holds((1, 2, 3)) and not Increasing().holds((1, 1, 3)) and not Increasing().holds((3, 2))
    n = Increasing(nan_is_never=True)
    assert n.holds((1.0, math.nan)) and not n.holds((math.nan, 1.0)) and not n.holds((math.nan, math.nan))
    assert Increasing(name="peak shares").text() == "peak shares: strictly increasing"
    assert "'never'" in n.text()


def test_combinations_reported_and_settings():
    c = AllOf((Item(1, Above(0.5, "b")), Increasing(name="a, b")))
    assert c.holds((0.3, 0.6)) and not c.holds((0.7, 0.6)) and not c.holds((0.1, 0.4))
    assert c.text() == "b > 0.5 and a, b: strictly increasing"
    assert ReportedOnly().holds(1.0) is None and ReportedOnly().text() == "reported, not judged"
    s = AtMostSetting("solver.energy_tol", "max residual")
    assert s.holds(1e-5, 1e-4) and not s.holds(2e-4, 1e-4)
    assert s.text(1e-4) == "max residual <= solver.energy_tol = 0.0001"


def test_check_verdicts():
    """holds: None when not judged or not measured; passed is True only when it holds."""
    assert Check("q", "-", 1.0, "s", 1.01, Within(0.02)).holds is True
    assert Check("q", "-", 1.0, "s", 1.01, Within(0.02), judged=False).holds is None
    assert Check("q", "-", 1.0, "s", None, Within(0.02)).holds is None
    c = Check("q", "-", 1.0, "s", 2.0, Within(0.02), "why")
    assert c.holds is False and not c.passed and c.rule == "within 2% of the paper's value (why)"
    assert c.error == pytest.approx(1.0)


@pytest.mark.parametrize(
    "kind, tol, ours, ok",
    [
        ("rel", 1e-3, 2.002, True),
        ("rel", 1e-3, 2.01, False),
        ("abs", 0.03, 2.02, True),
        ("max", 1e-10, 1e-12, True),
        ("max", 1e-10, 1e-9, False),
        ("min", 1.0, 1.7, True),
        ("min", 1.0, 0.5, False),
    ],
)
def test_verification_kinds(kind, tol, ours, ok):
    c = Check("q", "-", 2.0, "s", ours, criterion_of_kind(kind, tol))
    assert c.passed is ok and c.kind == kind and c.tolerance == tol
    with pytest.raises(ValueError, match="rel, abs, max, min"):
        criterion_of_kind("other", tol)
