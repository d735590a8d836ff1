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
    np.testing.assert_allclose(stress_series(every, "gauss").max(), float(every["max_von_mises"].max()),
                               rtol=1e-9)


def test_mass_is_the_sum_of_the_granules_masses(runs):
    _, sparse = runs
    r1, rho = 0.01, 7850.0
    assert D.metrics(sparse)["granular_mass"] == pytest.approx(14 * 4 / 3 * np.pi * r1 ** 3 * rho, rel=1e-12)
