"""Static precompression ([precompression], granplate.model.static): the truth is statics.
A chain pressed by F0 between two walls carries F0 at every contact, its overlaps
(F0 / A)^(2/3); under gravity each contact carries F0 plus the weight above it; the run
starts at rest in that state (nothing moves, eq. (11) holds from the stored energy, which
is E_initial); bad input is refused naming the field, a minimisation that does not converge
stops with its residual."""

from __future__ import annotations

import numpy as np
import pytest

import granplate as gp
from granplate.errors import ScenarioError, SimulationError
from granplate.model.arrays import build_model
from granplate.physics.contact import COEF_A
from granplate.setup.validate import validate

CHAIN = """
name = "pressed-chain"
dimension = {dimension}
[layout]
kind = "chain"
count = 6
radius = 0.005
material = "steel"
[precompression]
target = "wall {wall}"
force = {force}
[time]
t_end = 2e-5
dt_initial = 1e-8
dt_max = 1e-8
output_interval = 1e-6
field_interval = 1e-6
[solver]
scheme = "verlet"
"""


def chain(dimension=3, force=10.0, wall="xmax", extra=""):
    return gp.loads(CHAIN.format(dimension=dimension, force=force, wall=wall) + extra)


def _pair_overlaps(model):
    g, d = model.granular, model.granular.wall_geo.shape[1] - 1
    x = model.initial_state[:, :d]
    i, j = g.pair_ij[:, 0], g.pair_ij[:, 1]
    return g.radius[i] + g.radius[j] - np.linalg.norm(x[i] - x[j], axis=1), g.pair_coef[:, COEF_A]


@pytest.mark.parametrize("dimension, wall", [(3, "xmax"), (2, "right")])
def test_every_contact_of_a_pressed_chain_carries_the_force(dimension, wall):
    """Every pair's overlap is (F0 / A)^(2/3) to the minimiser's tolerance (relative 1e-8 on the
    forces: 1e-8 x 2/3 on the overlaps), and both walls receive F0 at t = 0 and at t_end."""
    if dimension == 2:
        discs = "".join(
            f'[[granules]]\nx = {0.005 + 0.01 * k!r}\ny = 0.005\nradius = 0.005\nmaterial = "steel"\n' for k in range(6)
        )
        walls = (
            '[[walls]]\nlabel = "left"\nnormal = [-1.0, 0.0]\noffset = 0.0\n'
            '[[walls]]\nlabel = "right"\nnormal = [1.0, 0.0]\noffset = 0.06\n[load]\nkind = "none"\n'
        )
        text = CHAIN.format(dimension=2, force=10.0, wall=wall)
        head, _, tail = text.partition("[precompression]")
        layout_free = head.split("[layout]")[0]
        s = gp.loads(layout_free + discs + walls + "[precompression]" + tail)
    else:
        s = chain(dimension, 10.0, wall)
    model = build_model(s)
    delta, a = _pair_overlaps(model)
    on = delta > 0
    assert on.sum() == 5
    np.testing.assert_allclose(delta[on], (10.0 / a[on]) ** (2.0 / 3.0), rtol=1e-8)
    ds = gp.simulate(s, progress=False)
    np.testing.assert_allclose(ds["wall_force"].values, 10.0, rtol=1e-7)
    aw = model.granular.wall_coef[:, COEF_A]
    stored = np.sum(0.4 * a[on] * delta[on] ** 2.5) + np.sum(0.4 * aw * (10.0 / aw) ** (5.0 / 3.0))
    assert ds.attrs["E_initial"] == pytest.approx(float(stored), rel=1e-7)


def test_under_gravity_each_contact_carries_the_weight_above_it():
    """A vertical chain (gravity along -x) pressed from the top by F0: the contact under the k-th
    granule from the top carries F0 + k m g, the floor F0 + N m g."""
    g = 9.81
    s = chain(extra=f"[gravity]\ng = [{-g}, 0.0, 0.0]\n")
    model = build_model(s)
    delta, a = _pair_overlaps(model)
    m = float(model.granular.mass[0])
    forces = np.sort(a * np.maximum(delta, 0.0) ** 1.5)
    np.testing.assert_allclose(forces, 10.0 + m * g * np.arange(1, 6), rtol=1e-7)
    ds = gp.simulate(s, progress=False)
    floor = ds["wall_force"].sel(wall="xmin").values[0]
    assert floor == pytest.approx(10.0 + 6 * m * g, rel=1e-7)


def test_the_pressed_chain_stays_at_rest_and_balances_its_energy():
    """Started from its static state with nothing else put in, the chain stays where it is (to
    round-off of the residual force) and eq. (11) holds: E_g stays E_initial."""
    s = chain()
    ds = gp.simulate(s, progress=False)
    x = ds["x"].values
    assert np.max(np.abs(x - x[0])) <= 1e-12
    e = ds["E_granular"].values
    np.testing.assert_allclose(e, ds.attrs["E_initial"], rtol=1e-9)


@pytest.mark.parametrize(
    "change, field",
    [
        ({"precompression.target": "wall top"}, "precompression.target"),
        ({"precompression.target": "granule c1"}, "precompression.target"),
        ({"precompression.force": 0.0}, "precompression.force"),
        ({"precompression.force": float("nan")}, "precompression.force"),
        ({"precompression.mode": "servo"}, "precompression.mode"),
        ({"precompression.mode": "held", "precompression.mass": -1.0}, "precompression.mass"),
        ({"precompression.mode": "held", "precompression.mass": float("inf")}, "precompression.mass"),
        ({"precompression.mass": 1.0}, "precompression.mass"),
        ({"precompression.tolerance": 1.0}, "precompression.tolerance"),
        ({"precompression.max_iterations": 0}, "precompression.max_iterations"),
        ({"contact.normal_law": "thornton"}, "precompression.target"),
    ],
)
def test_bad_precompression_is_refused_by_name(change, field):
    """Each bad [precompression] is refused before anything runs, naming its field."""
    with pytest.raises(ScenarioError) as e:
        validate(gp.with_changes(chain(), change))
    assert e.value.field == field


def test_a_wall_far_from_the_packing_is_refused():
    """A precompression with nowhere to go: no granule within a radius of the target wall."""
    s = gp.loads(
        """
name = "far"
dimension = 3
[[granules]]
x = 0.0
y = 0.0
z = 0.0
radius = 0.005
material = "steel"
[[walls]]
label = "far"
normal = [1.0, 0.0, 0.0]
offset = 0.5
[precompression]
target = "wall far"
force = 1.0
"""
    )
    with pytest.raises(ScenarioError, match="nowhere to go"):
        validate(s)


def test_a_minimisation_that_does_not_converge_says_its_residual():
    """One step of the minimiser cannot reach a residual of 1e-14: a SimulationError gives the
    residual reached and what to change, and keeps the state reached."""
    s = gp.with_changes(chain(), {"precompression.max_iterations": 1, "precompression.tolerance": 1e-14})
    with pytest.raises(SimulationError, match="max_iterations") as e:
        build_model(s)
    assert e.value.result.residual > 1e-14


def test_the_struck_chain_example_runs_and_records_its_floor():
    """docs/examples/struck-chain.toml (20 beads on a floor under gravity, 10 N from the top, the
    top bead struck): the floor carries 10 N plus the chain's weight at t = 0, and more once the
    wave arrives; the sensor bead b10 reads 10 N plus the weight of the 10 beads above it and
    half its own, and more as the wave passes; eq. (11) holds to solver.energy_tol; the summary's shares above 1 stay within
    the largest energy put in (gravity lends energy to the struck bead and takes it back)."""
    from pathlib import Path

    from granplate.results.dataset import summary
    from granplate.setup.io import load_scenario

    s = load_scenario(str(Path(__file__).resolve().parents[1] / "docs" / "examples" / "struck-chain.toml"))
    ds = gp.simulate(s, progress=False)
    m = float(build_model(s).granular.mass.sum())
    floor = ds["wall_force"].sel(wall="floor").values
    assert floor[0] == pytest.approx(10.0 + m * 9.81, rel=1e-7)
    assert floor.max() > 2.0 * floor[0]
    mid = ds["sensor_force"].sel(sensor="b10").values  # the 11th bead from the top, sampled at 10 MHz
    assert mid[0] == pytest.approx(10.0 + 10.5 * m / 20 * 9.81, rel=1e-7)
    assert mid.max() > 2.0 * mid[0] and ds.sizes["sensor_time"] == 4001
    assert float(np.max(np.abs(ds["energy_residual"].values))) <= s.solver.energy_tol
    sm = summary(ds)
    assert sm["eg_max_fraction"] <= sm["e_in_max"] / sm["e_in"] + 1e-6


def _spheres(xs, extra=""):
    body = "".join(f'[[granules]]\nx = {x!r}\ny = {y!r}\nz = 0.0\nradius = 0.005\nmaterial = "steel"\n' for x, y in xs)
    return gp.loads('name = "paths"\ndimension = 3\n' + body + extra)


WALLS = """
[[walls]]
label = "floor"
normal = [-1.0, 0.0, 0.0]
offset = 0.0
[[walls]]
label = "top"
normal = [1.0, 0.0, 0.0]
offset = 0.02
[precompression]
target = "wall top"
force = 10.0
"""


def test_a_force_with_no_path_to_a_support_is_refused():
    """Two spheres pressed by the top wall and touching nothing else: the force has no path to
    a support, refused naming precompression.target before minimising."""
    s = _spheres([(0.015, 0.0), (0.005, 0.0)], WALLS.replace("offset = 0.0\n", "offset = 0.05\n", 1))
    with pytest.raises(ScenarioError, match="no path to a support") as e:
        build_model(s)
    assert e.value.field == "precompression.target"


def test_granules_that_would_fall_are_refused():
    """Under gravity, a sphere beside the pressed chain resting on nothing would fall through:
    refused naming gravity.g."""
    s = _spheres([(0.005, 0.0), (0.015, 0.0), (0.009, 0.05)], WALLS + "[gravity]\ng = [-9.81, 0.0, 0.0]\n")
    with pytest.raises(ScenarioError, match="fall through") as e:
        build_model(s)
    assert e.value.field == "gravity.g"
