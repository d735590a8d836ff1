"""The report's stress checks sample von Mises through the plate's own recovery: at the
Gauss points it equals what the simulator stored, and a linear displacement field (a
uniform strain, exact in Q8) gives the closed-form plane-stress stress at every node."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.paper import checks as ck
from granplate.results.dataset import scenario_of

from short_results import short_results


@pytest.fixture(scope="module")
def steel():
    return short_results()["steel-r1"]


def test_gauss_sampling_is_the_simulators_stress(steel):
    """Gauss-point sampling reproduces plate_von_mises (the solver's own max per element)."""
    ours = ck.stress_series(steel, "gauss")
    stored = steel["plate_von_mises"].values.max(axis=1)
    assert ours.shape == stored.shape and stored.max() > 0
    np.testing.assert_allclose(ours, stored, rtol=1e-12)


def test_uniform_strain_gives_closed_form_stress_at_the_nodes(steel):
    """u = (a x, b y + c x): eps = (a, b, c); sigma from the plane-stress law, eq. (12)."""
    a, b, c = 2e-4, -1e-4, 3e-4
    x, y = steel["node_x"].values, steel["node_y"].values
    n_t = steel.sizes["field_time"]
    ds = steel.copy()
    ds["plate_ux"] = (("field_time", "node"), np.tile(a * x, (n_t, 1)))
    ds["plate_uy"] = (("field_time", "node"), np.tile(b * y + c * x, (n_t, 1)))
    s = scenario_of(ds)
    m = s.material(s.plate.material)
    E, nu = float(m.E), float(m.nu)
    sxx, syy, sxy = E / (1 - nu**2) * (a + nu * b), E / (1 - nu**2) * (nu * a + b), E / (2 * (1 + nu)) * c
    exact = np.sqrt(sxx**2 - sxx * syy + syy**2 + 3 * sxy**2)
    for where in ck.SAMPLING:
        np.testing.assert_allclose(ck.stress_series(ds, where), exact, rtol=1e-9)


def test_unknown_sampling_is_refused(steel):
    with pytest.raises(ValueError, match="nodes"):
        ck.stress_series(steel, "centroids")
