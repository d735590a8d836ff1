"""Optimisation constraints: a bound below a design's mass (the closed form of its
granules' masses) makes that design infeasible, above it feasible; Optuna's
constraints_func sees the same verdict, the Pareto front keeps only feasible trials and
pareto.csv and the report list the excluded better trial as infeasible; mistakes in a
[constraints] table are named before anything runs."""

from __future__ import annotations

import csv
import math

import pytest

import granplate as gp
from granplate.errors import ScenarioError
from granplate.study import design as D
from granplate.study.constraints import Bound, is_feasible, parse_constraints, violations
from granplate.study.optimize import (
    PARETO_CSV,
    TRIALS_CSV,
    feasible_text,
    open_study,
    parse_optimization,
    tell,
    write_outputs,
)

#: The paper's packing: 10 heavy granules of R1 and 4 intruders of R2 = ratio R1 (spheres).
R1 = 0.01


def packing_mass(ratio: float, intruder_rho: float, heavy_rho: float = 7850.0) -> float:
    """Mass [kg] of the paper's 14 granules: 4/3 pi R^3 rho each."""
    sphere = lambda r, rho: 4.0 / 3.0 * math.pi * r**3 * rho  # noqa: E731
    return 10 * sphere(R1, heavy_rho) + 4 * sphere(ratio * R1, intruder_rho)


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    """The records of two short designs of ptfe-r05: steel and PTFE intruders."""
    folder = tmp_path_factory.mktemp("records")
    out = {}
    for material in ("steel", "ptfe"):
        s = gp.with_changes(gp.load_scenario("ptfe-r05"), {"time.t_end": 2e-6, "layout.intruder_material": material})
        text = gp.dumps(s)
        key = D.design_key(text)
        outcome = D.run_design(text)
        assert outcome["status"] == "ok"
        out[material] = D.make_record(key, {"layout.intruder_material": material}, text, outcome)
        D.write_record(folder, out[material])
    return out


def test_mass_metric_is_the_closed_form_and_bounds_around_it_decide_feasibility(records):
    steel = records["steel"]["summary"]["granular_mass"]
    assert steel == pytest.approx(packing_mass(0.5, 7850.0), rel=1e-12)
    assert records["ptfe"]["summary"]["granular_mass"] == pytest.approx(packing_mass(0.5, 2150.0), rel=1e-12)
    below = parse_constraints({"granular_mass": {"max": 0.99 * steel}}, D.metric_units())
    above = parse_constraints({"granular_mass": {"max": 1.01 * steel}}, D.metric_units())
    band = parse_constraints({"granular_mass": {"min": 1.01 * steel, "max": 2 * steel}}, D.metric_units())
    summary = records["steel"]["summary"]
    assert is_feasible(violations(below, summary)) is False
    assert is_feasible(violations(above, summary)) is True
    assert is_feasible(violations(band, summary)) is False
    # the violation is relative to the bound: (m - max) / max
    assert violations(below, summary) == [pytest.approx(1 / 0.99 - 1, rel=1e-12)]
    # a design without the metric violates its bound (no plate: no stress)
    stress = (Bound("max_von_mises", high=1e9),)
    assert is_feasible(violations(stress, {"max_von_mises": None})) is False


def test_infeasible_trial_is_left_off_the_front_and_reported(records, tmp_path):
    steel, ptfe = (records[m]["summary"]["granular_mass"] for m in ("steel", "ptfe"))
    doc = {
        "base": "ptfe-r05",
        "set": {"time.t_end": 2e-6},
        "parameters": {"layout.intruder_material": ["steel", "ptfe"]},
        "objectives": {"granular_mass": "minimize"},
        "constraints": {"granular_mass": {"min": (steel + ptfe) / 2}},
    }
    opt = parse_optimization(doc)
    study = open_study(opt, tmp_path, seed=0)
    for material in ("steel", "ptfe"):
        study.enqueue_trial({"layout.intruder_material": material})
        trial = study.ask(opt.space)
        assert tell(study, opt, trial, records[material])
    steel_t, ptfe_t = study.get_trials(deepcopy=False)
    # Optuna's own record of the constraints (its constraints_func) says the same
    assert [feasible_text(steel_t), feasible_text(ptfe_t)] == ["yes", "no"]
    from optuna.study._constrained_optimization import _get_feasible_trials

    assert _get_feasible_trials([steel_t, ptfe_t]) == [steel_t]
    # the lighter PTFE design is better but infeasible: the best is the steel one
    assert [t.number for t in study.best_trials] == [steel_t.number]
    write_outputs(study, opt, tmp_path)
    pareto = list(csv.DictReader(open(tmp_path / PARETO_CSV)))
    assert [(r["layout.intruder_material"], r["feasible"]) for r in pareto] == [("steel", "yes"), ("ptfe", "no")]
    trials = list(csv.DictReader(open(tmp_path / TRIALS_CSV)))
    assert [r["feasible"] for r in trials] == ["yes", "no"]
    # the report's table reads the same verdicts back
    from granplate.study.outcome import read_outcome

    (tmp_path / "study.toml").write_text(
        'base = "ptfe-r05"\n[objectives]\n"granular_mass" = "minimize"\n'
        f'[constraints]\n"granular_mass" = {{min = {(steel + ptfe) / 2!r}}}\n'
    )
    out = read_outcome(tmp_path)
    assert out.kind == "optimization" and [r.feasible for r in out.rows] == [True, False]
    # ... and its page: the front is the feasible trial, the other one marked infeasible
    from granplate.study.report import FIGURES, write_report

    page = write_report(tmp_path).read_text()
    markdown = (tmp_path / "report.md").read_text()
    assert "1 infeasible (constraints)" in markdown and "On the front: trial 0." in markdown
    assert "2 trials: 2 done, 0 failed, 0 left (1 infeasible)" in page
    assert (tmp_path / FIGURES / "pareto-front.png").is_file()


def test_trials_table_while_the_search_runs_counts_the_trials_left(records, tmp_path):
    """Truth: trials.csv written during the search (`write_progress`) lists the trials so
    far and one waiting row per trial to come, which the report's page counts as left."""
    from granplate.study.optimize import write_progress
    from granplate.study.explorer import counts
    from granplate.study.outcome import read_outcome

    doc = {
        "base": "ptfe-r05",
        "set": {"time.t_end": 2e-6},
        "parameters": {"layout.intruder_material": ["steel", "ptfe"]},
        "objectives": {"granular_mass": "minimize"},
    }
    opt = parse_optimization(doc)
    study = open_study(opt, tmp_path, seed=0)
    for material in ("steel", "ptfe"):
        study.enqueue_trial({"layout.intruder_material": material})
        assert tell(study, opt, study.ask(opt.space), records[material])
    study.ask(opt.space)  # a third trial, running
    write_progress(study, opt, tmp_path, trials=5)
    rows = list(csv.DictReader(open(tmp_path / TRIALS_CSV)))
    assert [r["state"] for r in rows] == ["COMPLETE", "COMPLETE", "RUNNING", "WAITING", "WAITING"]
    (tmp_path / "study.toml").write_text('base = "ptfe-r05"\n[objectives]\n"granular_mass" = "minimize"\n')
    c = counts(read_outcome(tmp_path, live=True))
    assert (c["total"], c["done"], c["failed"], c["left"]) == (5, 2, 0, 3)


@pytest.mark.parametrize(
    "table, field, words",
    [
        ({"mass": {"max": 1.0}}, "constraints.mass", "unknown metric"),
        ({"granular_mass": {"maximum": 1.0}}, "constraints.granular_mass.maximum", "allowed: min, max"),
        ({"granular_mass": {"min": 2.0, "max": 1.0}}, "constraints.granular_mass.max", "must be >= min"),
        ({"granular_mass": {"max": "heavy"}}, "constraints.granular_mass.max", "finite number"),
        ({"granular_mass": {}}, "constraints.granular_mass", "{max = b}"),
        ([1.0], "constraints", "table"),
    ],
)
def test_constraint_mistakes_name_the_field_and_what_is_allowed(table, field, words):
    with pytest.raises(ScenarioError) as err:
        parse_constraints(table, D.metric_units())
    assert err.value.field == field and words in str(err.value)


def test_optimize_refuses_a_bad_constraint_before_running():
    doc = {
        "base": "ptfe-r05",
        "parameters": {"load.q0": [1e3, 2e3]},
        "objectives": {"ep_max_fraction": "minimize"},
        "constraints": {"granular_mass": {"max": -math.inf}},
    }
    with pytest.raises(ScenarioError) as err:
        parse_optimization(doc)
    assert err.value.field == "constraints.granular_mass.max"
