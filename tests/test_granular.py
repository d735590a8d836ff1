"""The granules' step with friction split off (solver.granular): the friction half steps
book exactly the kinetic energy they remove, a sphere striking a wall with spin leaves
it rolling as the impulse balance demands, a sphere squeezed between two walls loses all
its kinetic energy to friction with the balance exact to round-off, and in a packing
friction no longer sets the step."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from granplate.model.arrays import build_model
from granplate.results.run import simulate
from granplate.setup.geometry import resolve
from granplate.setup.materials import LIBRARY, sphere_mass
from granplate.setup.scenario import (
    Contact,
    Granule,
    LatticeLayout,
    Load,
    Scenario,
    Solver,
    TimeSettings,
    Wall,
)
from granplate.physics.contact import COEF_A, hertz_elastic
from granplate.solver.granular import friction_flow, kinetic_energies, slip_relaxation_rate

R = 0.01


def single(
    granule: Granule, walls, t_end: float, friction: str, scheme: str = "implicit", mu: float = 0.5, out: float = 1e-5
) -> Scenario:
    """One steel sphere among rigid walls, no load."""
    return Scenario(
        name="friction",
        granules=(granule,),
        walls=tuple(walls),
        load=Load(kind="none"),
        contact=Contact(mu=mu, pairs=()),
        time=TimeSettings(t_end=t_end, dt_initial=1e-8, dt_max=4e-8, output_interval=out, field_interval=out),
        solver=Solver(scheme=scheme, granular_friction=friction),
    )


def packing(
    mu: float, friction: str = "split", cols: int = 4, rows: int = 6, t_end: float = 2e-5, implicit_dt_max: float = 1e-6
) -> Scenario:
    """A hexagonal packing of 1 mm steel spheres in its walls, column 1 launched at 1 m/s."""
    s = resolve(
        Scenario(
            name="packing",
            layout=LatticeLayout(kind="hexagonal", columns=cols, rows=rows, radius=1e-3),
            load=Load(kind="none"),
            contact=Contact(mu=mu),
            time=TimeSettings(
                t_end=t_end, dt_initial=1e-8, dt_max=4e-8, output_interval=t_end / 4, field_interval=t_end / 4
            ),
            solver=Solver(granular_friction=friction, implicit_dt_max=implicit_dt_max),
        )
    )
    left = min(g.x - g.radius for g in s.granules)
    return dataclasses.replace(
        s,
        granules=tuple(dataclasses.replace(g, vx=1.0) if abs(g.x - g.radius - left) < 1e-9 else g for g in s.granules),
    )


def test_friction_half_step_books_the_kinetic_energy_it_removes():
    """friction_flow changes velocities and spins only, every contact's slip decays, and the
    dissipation it returns is the kinetic energy lost (to round-off), >= 0, for steps from
    mild to far beyond RK4's limit, in either contact order."""
    model = build_model(packing(0.3))
    g, cfg = model.granular, model.config
    rng = np.random.default_rng(7)
    y0 = model.initial_state.copy()
    y0[:, :2] += rng.normal(scale=2e-5, size=(len(y0), 2))  # overlaps: normal forces at every contact
    y0[:, 3:5] = rng.normal(scale=0.5, size=(len(y0), 2))
    y0[:, 5] = rng.normal(scale=300.0, size=len(y0))
    ke0 = sum(kinetic_energies(y0, g.mass, g.inertia))
    for dt in (1e-10, 1e-8, 1e-6):
        for forward in (True, False):
            y = y0.copy()
            work = friction_flow(y, dt, g, cfg, forward)
            assert np.array_equal(y[:, :3], y0[:, :3])
            assert work > 0.0
            assert ke0 - sum(kinetic_energies(y, g.mass, g.inertia)) == pytest.approx(work, rel=1e-10)


@pytest.mark.parametrize("scheme", ["implicit", "paper"])
def test_sphere_striking_a_wall_with_spin_leaves_rolling(scheme):
    """A steel sphere hits the left wall at 1 m/s with tangential speed 0.5 m/s and spin;
    friction stops the slip during the impact, so the wall's tangential impulse is
    P = v_t0 / (1/m + R^2/I) (the model's I = 2/5 m R^2: v_y = 5/7 v_y0 + 2/7 R omega_0),
    the same with steps far beyond RK4's friction limit as in closed form, in fewer steps
    than RK4 on the friction (5x fewer where the step is free: "implicit")."""
    vy0, w0 = 0.5, -30.0
    ball = Granule(x=R + 1e-5, y=0.0, radius=R, material="steel", label="s", vx=-1.0, vy=vy0, omega=w0)
    wall = Wall(normal=(-1.0, 0.0), offset=0.0, label="left")
    runs = {f: simulate(single(ball, [wall], 1.2e-4, f, scheme), progress=False) for f in ("split", "rk4")}
    model = build_model(single(ball, [wall], 1.2e-4, "split", scheme))
    m, inertia = model.granular.mass[0], model.granular.inertia[0]
    assert m == pytest.approx(sphere_mass(R, LIBRARY["steel"].rho)) and inertia == pytest.approx(0.4 * m * R * R)
    vt0 = -vy0 + R * w0  # slip rate on the left wall, t = (0, -1)
    p = vt0 / (1.0 / m + R * R / inertia)
    ds = runs["split"]
    assert ds.vx.values[-1, 0] > 0.9  # bounced off
    assert ds.vy.values[-1, 0] == pytest.approx(vy0 + p / m, rel=1e-5)
    assert ds.omega.values[-1, 0] == pytest.approx(w0 - p * R / inertia, rel=1e-5)
    assert float(np.max(np.abs(ds.energy_residual.values))) < 1e-6
    assert np.all(np.diff(ds.D_friction.values) >= 0.0) and ds.D_friction.values[-1] > 0.0
    assert (5 if scheme == "implicit" else 1) * ds.attrs["n_steps"] < runs["rk4"].attrs["n_steps"]


def test_squeezed_sphere_loses_its_kinetic_energy_to_friction_exactly():
    """A sphere pressed between two parallel walls (equal overlaps, no normal motion), sliding
    and spinning: friction stops it, so D_friction ends at the initial kinetic energy, and
    since the friction work is booked as the kinetic energy it removes, the balance holds to
    round-off at every output although each step is > 50 times RK4's friction limit.
    (A scenario cannot start overlapped: the model of a sphere touching both walls gets a
    radius 50 um larger, so that it starts pressed by both.)"""
    ball = Granule(x=R, y=0.0, radius=R, material="steel", label="s", vy=0.3, omega=50.0)
    walls = [Wall(normal=(-1.0, 0.0), offset=0.0, label="left"), Wall(normal=(1.0, 0.0), offset=2 * R, label="right")]
    s = single(ball, walls, 2e-4, "split", mu=0.2, out=2e-5)
    model = build_model(s)
    model.granular.radius[0] = R + 5e-5
    ds = simulate(s, model=model, progress=False)
    m, inertia = model.granular.mass[0], model.granular.inertia[0]
    ke0 = 0.5 * m * 0.3**2 + 0.5 * inertia * 50.0**2
    assert abs(ds.vy.values[-1, 0]) < 1e-9 and abs(R * ds.omega.values[-1, 0]) < 1e-9
    assert ds.D_friction.values[-1] == pytest.approx(ke0, rel=1e-9)
    assert np.all(np.diff(ds.D_friction.values) >= 0.0)
    assert float(np.max(np.abs(ds.energy_residual.values))) < 1e-12
    g = model.granular  # RK4 on this friction would need t_end x its stick relaxation rate steps
    rate = slip_relaxation_rate(
        hertz_elastic(5e-5, g.wall_coef[0, COEF_A]),
        0.0,
        g.wall_coef[0],
        1.0 / m + g.radius[0] ** 2 / inertia,
    )
    assert 50 * ds.attrs["n_steps"] < 2e-4 * rate


def test_friction_no_longer_sets_the_step_in_a_packing():
    """A hexagonal packing struck by its first column: with friction split off it takes at
    most 1.5x the steps of the frictionless run (RK4 on the friction takes > 2x), and its
    final velocities and friction work agree with a run of 16x smaller steps."""
    steps = {}
    runs = {}
    for key, mu, friction, dt_max in [
        ("frictionless", 0.0, "split", 1e-6),
        ("split", 0.099, "split", 1e-6),
        ("rk4", 0.099, "rk4", 1e-6),
        ("fine", 0.099, "split", 5e-6 / 2**11),
    ]:
        runs[key] = simulate(packing(mu, friction, implicit_dt_max=dt_max), progress=False)
        steps[key] = runs[key].attrs["n_steps"]
    assert steps["split"] <= 1.5 * steps["frictionless"]
    assert steps["rk4"] > 2.0 * steps["frictionless"]
    assert steps["fine"] > 8 * steps["split"]
    ds, ref = runs["split"], runs["fine"]
    for v in ("vx", "vy"):  # [m/s], the struck column at 1 m/s (measured: 2e-4)
        np.testing.assert_allclose(ds[v].values[-1], ref[v].values[-1], atol=5e-4)
    np.testing.assert_allclose(ds.omega.values[-1] * 1e-3, ref.omega.values[-1] * 1e-3, atol=2e-3)  # R omega (8e-4)
    assert ds.D_friction.values[-1] == pytest.approx(ref.D_friction.values[-1], rel=1e-4)  # (3e-5)


def test_strong_shock_takes_the_steps_of_the_frictionless_run():
    """ptfe-r05 under q0 = 1e7 N/m (granules at tens of m/s, |N| ~ 1e4 N): with friction
    split off at the granule contacts and held at the plate contacts, friction does not
    bound the step (<= 1.5x the frictionless run's steps; RK4's limit on it needed ~1e-9 s
    steps, 10x more), and D_friction >= 0 grows with the energy balance kept."""
    import warnings

    from granplate.setup.io import with_changes
    from granplate.setup.presets import preset

    base = {
        "load.q0": 1e7,
        "time.t_end": 1.6e-4,
        "time.field_interval": 2e-5,
        "contact.overlap_stop": 0.5,
        "solver.granular_friction": "split",
    }
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # overlaps beyond contact.overlap_warn
        ds = simulate(with_changes(preset("ptfe-r05"), base), progress=False)
        free = simulate(with_changes(preset("ptfe-r05"), {**base, "contact.mu": 0.0}), progress=False)
    assert ds.attrs["n_steps"] <= 1.5 * free.attrs["n_steps"]
    assert np.all(np.diff(ds.D_friction.values) >= 0.0) and ds.D_friction.values[-1] > 0.0
    assert float(np.max(np.abs(ds.energy_residual.values))) < 1e-4


def test_a_run_set_by_rk4_friction_is_told_to_split_it(monkeypatch):
    """With solver.granular_friction = "rk4" a packing whose steps RK4's stability on the
    friction cuts (> 2x the frictionless steps, above) counts the steps taken at that bound
    (about a third here) and warns, naming the setting that lifts it; split off, no step is
    at a friction bound."""
    from granplate.solver import driver

    monkeypatch.setattr(driver, "FRICTION_BOUND_MIN_STEPS", 10)
    monkeypatch.setattr(driver, "FRICTION_BOUND_SHARE", 0.25)
    with pytest.warns(RuntimeWarning, match='solver.granular_friction = "split"'):
        ds = simulate(packing(0.099, "rk4"), progress=False)
    assert ds.attrs["n_friction_bound"] > driver.FRICTION_BOUND_SHARE * ds.attrs["n_steps"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        split = simulate(packing(0.099, "split"), progress=False)
    assert split.attrs["n_friction_bound"] == 0


@pytest.mark.parametrize("split", [False, True])
def test_force_sums_name_the_stored_energy_and_the_largest_overlap(split):
    """granular_rhs's ForceSums on a sphere pressed into a wall and into a second sphere:
    e_pot is eq. (9)'s 2/5 A delta^(5/2) summed over both contacts, ovl the larger overlap
    over the radius with its granule and partner (granule 1, then wall 0: -1), and with the
    friction split off no friction power, no torque and no slip relaxation rate."""
    from granplate.solver.granular import granular_rhs

    a = Granule(x=R + 1e-5, y=0.0, radius=R, material="steel", label="a")
    b = Granule(x=3 * R + 2e-5, y=0.0, radius=R, material="steel", label="b")
    s = dataclasses.replace(
        single(a, [Wall(normal=(-1.0, 0.0), offset=0.0, label="left")], 1e-5, "split"), granules=(a, b)
    )
    model = build_model(s)
    g, cfg = model.granular, model.config
    assert g.pair_ij.shape[0] == 1 and g.wall_i.tolist() == [0]
    z = np.zeros(0)
    for wall_d, pair_d, who in ((2e-6, 5e-6, (0, 1)), (8e-6, 5e-6, (0, -1))):
        y = model.initial_state.copy()
        y[0, 0] = R - wall_d
        y[1, 0] = y[0, 0] + 2 * R - pair_d
        y[:, 4] = (0.2, -0.1)  # sliding: friction at both contacts
        dy = np.zeros_like(y)
        sums = granular_rhs(0.0, y, z, z, g, cfg, dy, z, z, z, False, z, split)
        stored = 0.4 * (g.pair_coef[0, COEF_A] * pair_d**2.5 + g.wall_coef[0, COEF_A] * wall_d**2.5)
        assert sums.e_pot == pytest.approx(stored, rel=1e-9)
        assert sums.ovl == pytest.approx(max(wall_d, pair_d) / R, rel=1e-9)
        assert (sums.ovl_i, sums.ovl_j) == who and isinstance(sums.ovl_i, int)
        if split:
            assert sums.p_fric == 0.0 and sums.rate == 0.0 and np.all(dy[:, 5] == 0.0)
        else:
            assert sums.p_fric > 0.0 and sums.rate > 0.0 and np.all(dy[:, 5] != 0.0)
