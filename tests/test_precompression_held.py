"""A held precompression (`precompression.mode = "held"`, docs/model.md section 3.12): the
target wall becomes a piston that keeps pushing with the force F0. Truths: statics (started
from the static state with nothing else put in, nothing moves and the wall keeps F0);
Newton's second law for the wall (its mean force over a run is F0 less its momentum over the
run's length, M v(T) / T, which stays small, while a frozen wall's mean force grows with the
energy a striker puts in); eq. (11) at every step; "frozen" stays the default."""

from __future__ import annotations

import numpy as np
import pytest

import granplate as gp
from granplate.model.arrays import build_model

F0 = 10.0
R = 0.005

CHAIN = """
name = "held-chain"
dimension = 3
[[walls]]
label = "floor"
normal = [-1.0, 0.0, 0.0]
offset = 0.0
[[walls]]
label = "top"
normal = [1.0, 0.0, 0.0]
offset = 0.05
{granules}
[precompression]
target = "wall top"
force = {force}
mode = "{mode}"
[contact]
mu = 0.0
alpha_n = 0.0
[time]
t_end = {t_end}
dt_initial = 2e-8
dt_max = 2e-8
output_interval = 2e-7
field_interval = 2e-7
[solver]
scheme = "verlet"
"""


def chain(mode: str, t_end: float = 2e-5, striker: float = 0.0) -> gp.Scenario:
    """Five steel spheres in a row between a floor and the top wall, pressed by F0 from the top;
    the bottom one moving up at `striker` [m/s] at t = 0."""
    beads = "".join(
        f'[[granules]]\nlabel = "b{k}"\nx = {R + 2 * R * k!r}\ny = 0.0\nz = 0.0\nradius = {R}\nmaterial = "steel"\n'
        + (f"vx = {striker!r}\n" if k == 0 and striker else "")
        for k in range(5)
    )
    return gp.loads(CHAIN.format(granules=beads, force=F0, mode=mode, t_end=t_end))


def test_a_held_chain_stays_at_rest_holding_its_force():
    """From its static state, with no shock, the held wall and the beads stay where they are
    (to the static state's residual), the wall's contact carries F0 and its drive's force is
    F0 at every output time; eq. (11) holds (E_granular stays E_initial); the frozen run is
    the same chain."""
    held = gp.simulate(chain("held"), progress=False)
    x = held.x.values
    assert np.max(np.abs(x - x[0])) <= 1e-12
    assert np.max(np.abs(held.drive_displacement.sel(drive="wall top").values)) <= 1e-12
    np.testing.assert_allclose(held.wall_force.sel(wall="top").values, F0, rtol=1e-7)
    np.testing.assert_allclose(held.drive_force.sel(drive="wall top").values, F0)
    np.testing.assert_allclose(held.E_granular.values, held.attrs["E_initial"], rtol=1e-9)
    frozen = gp.simulate(chain("frozen"), progress=False)
    np.testing.assert_array_equal(frozen.x.values[0], x[0])
    assert "drive" not in frozen.coords


def test_the_held_wall_keeps_its_mean_force_where_a_frozen_one_does_not():
    """The bottom bead struck up at 0.2 m/s, 0.3 ms of the chain ringing: the held wall's
    mean force (trapezoid over the outputs) is F0 less M v(T) / T, its momentum over the run
    (Newton's second law for the wall, v(T) from its recorded displacement), within the
    quadrature's error; the frozen wall's mean force is well above F0 (the striker's energy
    presses on a wall that cannot yield); eq. (11) holds in both."""
    t_end = 3e-4
    held = gp.simulate(chain("held", t_end, 0.2), progress=False)
    frozen = gp.simulate(chain("frozen", t_end, 0.2), progress=False)
    mass = float(build_model(chain("held", t_end, 0.2)).granular.mass.sum())  # the default: the granules' total
    t = held.time.values
    s = held.drive_displacement.sel(drive="wall top").values
    v_end = (s[-1] - s[-2]) / (t[-1] - t[-2])
    mean_held = np.trapezoid(held.wall_force.sel(wall="top").values, t) / t[-1]
    mean_frozen = np.trapezoid(frozen.wall_force.sel(wall="top").values, t) / t[-1]
    assert abs(mass * v_end / t[-1]) > 0.01 * F0  # the wall moved
    assert mean_held == pytest.approx(F0 - mass * v_end / t[-1], rel=1e-3)
    assert mean_frozen > 1.5 * F0
    for ds in (held, frozen):
        assert float(np.abs(ds.energy_residual_max).max()) < 1e-4


def test_rebuilt_contact_lists_keep_the_wall_at_its_static_offset():
    """The contact lists rebuilt during a run (contact.detection = "dynamic") see the target
    wall where the static state left it, frozen or held, not where the scenario put it."""
    from granplate.solver.driver import ContactLists

    for mode in ("frozen", "held"):
        model = build_model(chain(mode))
        lists = ContactLists(model)
        before = model.granular.wall_geo[:, -1].copy()
        assert before[model.granular.wall_w == 1][0] < 0.05  # pressed in from the scenario's 0.05 m
        lists.refresh(model.initial_state)
        np.testing.assert_array_equal(lists.g.wall_geo[:, -1], before)


def test_held_mode_round_trips_and_frozen_is_written_as_before():
    """`mode = "held"` and its `mass` survive TOML writing and reading; a frozen
    precompression is written without a mass key (its text as before the held mode)."""
    held = gp.with_changes(chain("held"), {"precompression.mass": 0.5})
    assert gp.loads(gp.dumps(held)) == held and "mass = 0.5" in gp.dumps(held)
    assert "mass" not in gp.dumps(chain("frozen"))
