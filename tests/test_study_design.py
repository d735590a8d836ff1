"""A design's extra metrics: the protector's mass, and the nodal stress only for a run that
keeps the plate fields at every output (else no value, never a maximum over a sparser
sampling), equal then to the largest nodal von Mises of the stored displacements."""

from __future__ import annotations

import numpy as np
import pytest

import granplate as gp
from granplate.paper.checks import stress_series
from granplate.study import design as D


@pytest.fixture(scope="module")
def runs():
    s = gp.load_scenario("steel-r1")
    every = gp.simulate(gp.with_changes(s, {"time.field_interval": 1e-6}), t_end=2e-5, progress=False)
    sparse = gp.simulate(s, t_end=2e-5, progress=False)
    return every, sparse


def test_nodal_stress_only_with_fields_at_every_output(runs):
    every, sparse = runs
    m = D.metrics(every)
    assert m["max_von_mises_nodes"] == float(stress_series(every, "nodes").max()) > 0
    assert m["units"]["max_von_mises_nodes"] == "Pa"
    assert D.metrics(sparse)["max_von_mises_nodes"] is None
    # the Gauss points of the same displacements give the simulator's own maximum
    np.testing.assert_allclose(stress_series(every, "gauss").max(), float(every["max_von_mises"].max()), rtol=1e-9)


def test_a_design_with_fields_at_every_output_gets_its_nodal_stress(runs):
    """Truth: run_design of a design keeping its plate fields at every output (and not
    asked for its whole result) reports the nodal stress of the full result's displacements."""
    every, _ = runs
    s = gp.with_changes(gp.load_scenario("steel-r1"), {"time.field_interval": 1e-6, "time.t_end": 2e-5})
    rec = D.run_design(gp.dumps(s))
    assert rec["status"] == "ok" and rec["result"] is None
    assert rec["summary"]["max_von_mises_nodes"] == D.metrics(every)["max_von_mises_nodes"]


def test_mass_is_the_sum_of_the_granules_masses(runs):
    _, sparse = runs
    r1, rho = 0.01, 7850.0
    assert D.metrics(sparse)["granular_mass"] == pytest.approx(14 * 4 / 3 * np.pi * r1**3 * rho, rel=1e-12)


def test_a_continuous_radius_is_valid_and_a_geometric_failure_names_the_granule_and_the_field():
    """A trial with radii off the mesh's node spacing validates (patch contacts at t = 0); a
    geometric refusal that remains reaches the trial's status naming the granule's label and
    the layout field the study varies, not a contact index or plate.ny."""
    from pathlib import Path

    from granplate.setup.validate import validate

    base = gp.load_scenario(str(Path(__file__).parents[1] / "docs" / "studies" / "two-layer-base.toml"))
    trial = gp.with_changes(base, {"layout.column_radii": (0.0093, 0.0071)})
    validate(trial)
    refused = gp.with_changes(trial, {"plate.n_modes": 30})
    status = D.run_design(gp.dumps(refused))["status"]
    assert status.startswith("ScenarioError: scenario field 'plate.n_modes' = 30: granule 'c2r")
    assert "layout.column_radii" in status and "contact 0" not in status and "plate.ny" not in status


def test_a_design_keeps_its_warnings_and_prints_none():
    """Truth: a design whose run warns (overlaps beyond a tiny contact.overlap_warn) returns
    the warning as one line in its outcome, once however often it was raised, and none
    escapes the task (a worker would print it); a run that does not warn keeps none."""
    import warnings

    s = gp.with_changes(gp.load_scenario("ptfe-r05"), {"time.t_end": 1e-5})
    with warnings.catch_warnings(record=True) as leaked:
        warnings.simplefilter("always")
        noisy = D.run_design(gp.dumps(gp.with_changes(s, {"contact.overlap_warn": 1e-6})))
        quiet = D.run_design(gp.dumps(s))
    assert leaked == []
    assert noisy["status"] == quiet["status"] == "ok"
    assert len(noisy["warnings"]) == 1 and noisy["warnings"][0].startswith("RuntimeWarning: ptfe-r05: ")
    assert "contact.overlap_warn" in noisy["warnings"][0] and "\n" not in noisy["warnings"][0]
    assert quiet["warnings"] == []
    assert D.make_record("k", {}, "", noisy)["warnings"] == noisy["warnings"]
