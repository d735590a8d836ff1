"""The verification case `plastic-impact` (yielding impacts simulated by the time loop):
it passes and draws its figure, and its checks fail when the truth or the loop is wrong."""

from __future__ import annotations

import math

import numpy as np
import pytest

from granplate import verification as V
from granplate.verification import plastic_cases as P
from granplate.verification.base import Context, run_case
from granplate.verification.plastic import thornton_restitution


@pytest.fixture(scope="module")
def context(tmp_path_factory) -> Context:
    return Context(out=tmp_path_factory.mktemp("plastic"))


@pytest.fixture(scope="module")
def result(context):
    return run_case(V.get_case("plastic-impact"), context)


@pytest.fixture(scope="module")
def pair_runs():
    """Two sphere-on-sphere impacts (2 and 10 v_y), measured: ({(kind, ratio): measure}, consts)."""
    runs, consts = {}, {}
    for ratio in (2.0, 10.0):
        ds, v, c = P.run_impact("pair", ratio)
        runs["pair", ratio], consts["pair"] = P.measure(ds, "pair", v, c), c
    return runs, consts


def by_quantity(checks, start: str):
    return [c for c in checks if c.quantity.startswith(start)]


def test_case_passes_and_draws_its_figure(result, context):
    """plastic-impact runs every impact through the loop and passes: restitution against
    P12 at 1.5-100 v_y on a wall and on a sphere far inside its 1% (within 1e-6), the
    Y -> infinity run bitwise Hertz's; each check says why and where its truth comes from,
    and the figure is drawn (the suite's only run of this case: tests/test_verification.py
    leaves it to this file)."""
    assert result.crashed is None, result.crashed
    assert result.passed, [(c.quantity, c.ours, c.reference) for c in result.checks if not c.passed]
    assert all(c.why and c.source for c in result.checks)
    assert result.figure and (context.figure_dir / result.figure).is_file()
    rest = by_quantity(result.checks, "restitution, ")
    assert len(rest) == 2 * len(P.RATIOS)
    assert max(c.error for c in rest) < 1e-6
    assert any("bitwise those of the Hertz run" in n for n in result.notes)
    assert by_quantity(result.checks, "max |x (thornton")[0].ours == 0.0


def test_restitution_checks_fail_with_a_wrong_closed_form(pair_runs):
    """P12 passes; P12 read at the speed ratio of the wrong yield velocity (v_y of the
    sphere's mass m instead of m* = m/2, P11: the ratio off by sqrt 2) fails every check,
    as does the elastic e = 1."""
    runs, _ = pair_runs
    assert all(c.passed for c in P.restitution_checks(runs))
    wrong_mass = P.restitution_checks(runs, lambda r: thornton_restitution(r * math.sqrt(2.0)))
    assert not any(c.passed for c in wrong_mass)
    assert not any(c.passed for c in P.restitution_checks(runs, lambda r: 1.0))


def test_loop_checks_fail_on_a_tampered_loop(pair_runs):
    """The loop checks pass on the simulated loops; an unloading that starts 1% below the
    loading force fails continuity, the force at the turn, the law and the area; a
    separation three output intervals late fails closure at delta_p (P7)."""
    runs, consts = pair_runs
    assert all(c.passed for c in P.loop_checks(runs, consts))
    m = dict(runs["pair", 10.0])
    k = m["turn"]
    m["force"] = np.concatenate([m["force"][:k], 0.99 * m["force"][k:]])
    m["force_after"] *= 0.99
    failing = [c.quantity for c in P.loop_checks({("pair", 10.0): m}, consts) if not c.passed]
    for start in (
        "loop area / D_plastic",
        "loop area / (1/2 m* v^2",
        "unloading continuous at delta_max",
        "force at the turn",
        "measured force vs the law",
    ):
        assert any(q.startswith(start) for q in failing), start
    m = dict(runs["pair", 10.0])
    lo, hi = m["separation"]
    m["separation"] = (lo - 3 * (hi - lo), hi - 3 * (hi - lo))
    closure = by_quantity(P.loop_checks({("pair", 10.0): m}, consts), "loop closes")
    assert closure and not closure[0].passed
