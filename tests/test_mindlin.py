"""Mindlin's tangential law (contact.tangential_law = "mindlin", docs/model.md section 3.16)
held against truth: LAMMPS's pair granular `tangential mindlin_rescale` run side by side
(the same law, step and integrator: positions and velocities to 1e-6), the closed forms of
an impact in gross sliding (tangential impulse = mu x normal impulse) and of a sticking
contact's tangential vibration (Mindlin's stiffness 8 G* a with the sphere's mass ratio
7/2), eq. (11) at every output to second order in the step, and its refusals."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

from granplate.errors import ScenarioError
from granplate.model.arrays import carried_history
from granplate.model.inputs import HIST_A, HIST_XI, N_HIST
from granplate.physics.mindlin import tangential_compliance
from granplate.setup.materials import LIBRARY
from granplate.setup.scenario import (
    Contact,
    Granule,
    Load,
    Scenario,
    Solver,
    TimeSettings,
    Wall,
)
from granplate.setup.validate import validate
from granplate.verification import lammps as L
from granplate.verification.base import simulate

needs_lammps = pytest.mark.skipif(bool(L.unavailable()), reason=L.unavailable() or "lammps available")

R = 1e-3
STEEL = LIBRARY["steel"]
MASS = 4.0 / 3.0 * math.pi * R**3 * STEEL.rho


def _time(dt: float, t_end: float, n_out: int = 20) -> TimeSettings:
    out = t_end / n_out
    return TimeSettings(
        t_end=t_end, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt), output_interval=out, field_interval=out
    )


oblique_pair = L.mindlin_pair  # two free spheres meeting obliquely: they stick, then slide
resting_sphere = L.mindlin_floor  # a sphere on a floor under gravity, launched along it


def run(s: Scenario):
    with warnings.catch_warnings():  # the elastic law is compared, whatever the pressure
        warnings.simplefilter("ignore")
        return simulate(s)


def _agreement(ds, lm, keys) -> float:
    """Largest difference over every output and granule, relative to the largest value of
    that quantity (or of the speeds, for a velocity component that stays near zero)."""
    worst = 0.0
    for k in keys:
        scale = max(np.abs(lm[k]).max(), *(np.abs(lm[c]).max() for c in keys if c[0] == k[0]))
        worst = max(worst, float(np.abs(ds[k].values - lm[k]).max() / scale))
    return worst


@needs_lammps
def test_oblique_pair_agrees_with_lammps_step_for_step():
    """LAMMPS's pair granular hertz/material + tangential mindlin_rescale, velocity Verlet at
    the same step, LAMMPS's arms (contact.torque_arm = "lammps"): the two codes' positions
    and velocities agree to 1e-6 (measured: 1e-13) at every output."""
    s = oblique_pair()
    ds = run(s)
    lm = L.run_hertz_3d(s, 2e-9, s.time.t_end, every=int(round(s.time.output_interval / 2e-9)))
    assert _agreement(ds, lm, ("x", "y", "z")) < 1e-6
    assert _agreement(ds, lm, ("vx", "vy", "vz")) < 1e-6
    assert np.abs(lm["vy"][-1] - lm["vy"][0]).max() > 0.01  # friction did act


@needs_lammps
def test_sphere_sliding_on_a_wall_agrees_with_lammps():
    """A sphere pressed on a floor by gravity, launched along it: it slides, then rolls on
    its sticking contact; against fix wall/gran with the same model: 1e-6 (measured 1e-14)."""
    s, _ = resting_sphere()
    ds = run(s)
    lm = L.run_hertz_3d(s, 5e-8, s.time.t_end, every=int(round(s.time.output_interval / 5e-8)))
    assert _agreement(ds, lm, ("x", "y")) < 1e-6
    assert _agreement(ds, lm, ("vx", "vy", "vz")) < 1e-6
    assert lm["vx"][-1][0] < 0.8 * 0.1  # it turned from sliding to rolling (5/7 of its speed)


@needs_lammps
@pytest.mark.parametrize("case", ["pair", "floor"])
def test_damped_runs_agree_with_lammps_tsuji_at_the_half_step(case):
    """The oblique pair and the sphere on a floor with eq. (3)'s damping (alpha_n = 0.2) and
    solver.verlet_damping = "half_step" (granplate's force pass at the half step's
    velocities, as LAMMPS's): against LAMMPS's `damping tsuji` at the restitution whose
    alpha is ours, 1e-6 in positions and velocities (measured 4e-14 and 1e-14)."""
    s = L.mindlin_pair(alpha_n=L.MINDLIN_ALPHA) if case == "pair" else L.mindlin_floor(alpha_n=L.MINDLIN_ALPHA)[0]
    assert s.solver.verlet_damping == "half_step"
    dt = L.MINDLIN_PAIR_STEP if case == "pair" else L.MINDLIN_FLOOR_STEP
    res = L.side_by_side(s, dt)
    assert res["dx"] < 1e-6 and res["dv"] < 1e-6


def test_gross_sliding_impact_takes_mu_times_the_normal_impulse():
    """An impact on a floor at a grazing angle (v_t / v_n = 5 > 7 mu: slides throughout):
    the tangential impulse is mu times the normal one, and the spin R w = 5/2 mu dv_n, to
    round-off (the capped force is mu |N| at every force pass)."""
    v_n, v_t, mu = 0.2, 1.0, 0.3
    s = Scenario(
        name="grazing",
        dimension=3,
        granules=(
            Granule(x=0.0, y=0.0, z=R + 1e-8, radius=R, material="steel", vx=v_t, vz=-v_n, omega=(0.0, 0.0, 0.0)),
        ),
        walls=(Wall(normal=(0.0, 0.0, -1.0), offset=0.0, material="steel"),),
        load=Load(kind="none"),
        contact=Contact(mu=mu, alpha_n=0.0, pairs=(), tangential_law="mindlin"),
        time=_time(1e-9, 2e-5, 4),
        solver=Solver(scheme="verlet"),
    )
    ds = run(s)
    dvn = float(ds["vz"].values[-1, 0] + v_n)
    dvt = float(v_t - ds["vx"].values[-1, 0])
    assert dvn == pytest.approx(2.0 * v_n, rel=1e-3)  # the elastic rebound: the contact ended
    assert dvt == pytest.approx(mu * dvn, rel=1e-9)
    assert R * float(ds["omega_y"].values[-1, 0]) == pytest.approx(2.5 * mu * dvn, rel=1e-9)


def test_sticking_contact_vibrates_at_mindlins_frequency():
    """A sphere resting on a floor, nudged along it (far below slip): its contact point's
    velocity is v0 cos(w_t t) with w_t^2 = 8 G* a (1/m + R^2/I) = 7/2 k_t / m (Mindlin's
    sticking stiffness, Di Renzo & Di Maio's tangential-to-normal frequency ratio
    sqrt(7 (1 - nu) / (2 - nu)) for a rigid floor), to 1e-3 of v0 at every output."""
    v0 = 1e-3
    s, d0 = resting_sphere(vx=v0, vy=0.0, t_end=8e-5, n_out=80)
    ds = run(s)
    k_t = 8.0 / tangential_compliance(STEEL.E, STEEL.nu) * math.sqrt(R * d0)
    w_t = math.sqrt(3.5 * k_t / MASS)
    t = ds.time.values
    v_contact = ds["vx"].values[:, 0] - R * ds["omega_y"].values[:, 0]
    assert np.abs(v_contact - v0 * np.cos(w_t * t)).max() < 1e-3 * v0
    assert w_t * t[-1] > 2.0 * math.pi  # more than one period
    k_n = 1.5 * 4.0 / 3.0 * STEEL.E / (1.0 - STEEL.nu**2) * math.sqrt(R) * math.sqrt(d0)
    ratio = w_t / math.sqrt(k_n / MASS)
    assert ratio == pytest.approx(math.sqrt(7.0 * (1.0 - STEEL.nu) / (2.0 - STEEL.nu)), rel=1e-12)


def test_damped_sticking_contact_rings_down_as_a_damped_oscillator():
    """The nudged resting sphere with tangential damping x_t = 1 on alpha_n = 0.5: the
    contact point is a damped oscillator of mass 2m/7, stiffness 8 G* a and damping
    eta_t = x_t c delta^(1/4): v0 e^(-zeta w t) (cos w_d t - zeta w / w_d sin w_d t). The
    damping reads the half step's slip (as LAMMPS's), so the departure is first order in
    the step: it halves with the step, and is under 3e-3 of v0 at every output at 25 ns."""
    v0 = 1e-3
    errors = []
    for dt in (5e-8, 2.5e-8):
        s, d0 = resting_sphere(vx=v0, vy=0.0, dt=dt, t_end=8e-5, n_out=80)
        s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, alpha_n=0.5, tangential_damping=1.0))
        ds = run(s)
        a_hertz = 4.0 / 3.0 * STEEL.E / (1.0 - STEEL.nu**2) * math.sqrt(R)
        eta = 1.0 * 0.5 * math.sqrt(MASS * a_hertz) * d0**0.25
        m_t = MASS / 3.5
        w = math.sqrt(8.0 / tangential_compliance(STEEL.E, STEEL.nu) * math.sqrt(R * d0) / m_t)
        zeta = eta / (2.0 * m_t * w)
        wd = w * math.sqrt(1.0 - zeta**2)
        t = ds.time.values
        exact = v0 * np.exp(-zeta * w * t) * (np.cos(wd * t) - zeta * w / wd * np.sin(wd * t))
        v_contact = ds["vx"].values[:, 0] - R * ds["omega_y"].values[:, 0]
        assert 0.05 < zeta < 0.9  # damped, not overdamped
        errors.append(float(np.abs(v_contact - exact).max()))
    assert errors[1] < 3e-3 * v0
    assert 1.6 < errors[0] / errors[1] < 2.4


@pytest.mark.parametrize("alpha_n, x_t", [(0.0, 0.0), (0.2, 1.0)])
def test_energy_balance_holds_to_second_order_in_the_step(alpha_n, x_t):
    """Eq. (11), E_p + E_g + D = E_in at every output, with the spring's energy in E_g and
    the slip's (and the tangential damping's) work in D_friction, undamped and damped: the
    largest residual falls 4x as the step halves (Verlet's
    own error), and is under 1e-6 of the energy in. D_friction ends positive: the impact
    lost energy, though while the contact radius grows it is signed (the stiffening spring
    takes energy at fixed xi, eq. M6)."""
    worst = []
    for dt in (4e-9, 2e-9):
        s = oblique_pair(dt=dt, arm="radius")
        ds = run(
            dataclasses.replace(s, contact=dataclasses.replace(s.contact, alpha_n=alpha_n, tangential_damping=x_t))
        )
        worst.append(float(np.abs(ds["energy_residual"].values).max()))
        d = ds["D_friction"].values
        assert d[-1] > 0.0 and (d.min() < 0.0 or x_t > 0.0)
    assert worst[1] < 1e-6
    assert 3.0 < worst[0] / worst[1] < 5.0


def test_a_mindlin_history_is_carried_across_list_rebuilds():
    """carried_history keeps a contact's tangential displacement when its list is rebuilt,
    even with no largest overlap recorded, and a contact the new list lacks waits in the store."""
    old_keys = np.array([[0, 1], [1, 2]])
    hist = np.zeros((2, N_HIST))
    hist[0, HIST_XI : HIST_XI + 3] = (1e-9, -2e-9, 0.0)
    hist[0, HIST_A] = 1e-5
    store: dict = {}
    out = carried_history(old_keys, hist, np.array([[0, 1], [0, 2]]), store)
    assert np.array_equal(out[0], hist[0]) and not out[1].any()
    hist[1, HIST_XI] = 3e-9
    store.clear()
    carried_history(old_keys, hist, np.array([[0, 2]]), store)
    assert (1, 2) in store and store[(1, 2)][HIST_XI] == 3e-9


@pytest.mark.parametrize(
    "change, field, match",
    [
        ({"scheme": "paper"}, "contact.torque_arm", "solver.scheme = 'verlet' only"),
        ({"law": "coulomb"}, "contact.tangential_law", "mindlin"),
        ({"arm": True}, "contact.torque_arm", "tangential_law = 'mindlin'"),
        ({"nu": 0.7}, "materials.steel.nu", r"\(-1, 0.5"),
        ({"damping": -1.0}, "contact.tangential_damping", "must be"),
        ({"damping": 0.5, "law": "tanh"}, "contact.tangential_damping", "Mindlin's"),
        ({"verlet_damping": "lammps"}, "solver.verlet_damping", "half_step"),
        ({"verlet_damping": "half_step", "scheme": "paper"}, "solver.verlet_damping", "verlet"),
    ],
)
def test_unsupported_combinations_are_refused_naming_the_field(change, field, match):
    """LAMMPS's torque arms under another scheme than Verlet, an unknown law, the
    LAMMPS arms with the tanh law, a material without a usable Poisson ratio, an unknown
    solver.verlet_damping and "half_step" under another scheme are refused before the run,
    naming the field and what is allowed."""
    s = oblique_pair()
    if "scheme" in change:
        s = dataclasses.replace(s, solver=Solver(scheme="paper"), contact=dataclasses.replace(s.contact))
    if "verlet_damping" in change:
        s = dataclasses.replace(s, solver=dataclasses.replace(s.solver, verlet_damping=change["verlet_damping"]))
        if "scheme" in change:
            s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, torque_arm="radius"))
    if "law" in change:
        law = change["law"]
        s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, tangential_law=law, torque_arm="radius"))
    if "damping" in change:
        s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, tangential_damping=change["damping"]))
    if "arm" in change:
        s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, tangential_law="tanh"))
    if "nu" in change:
        s = dataclasses.replace(s, materials={**s.materials, "steel": dataclasses.replace(STEEL, nu=0.7)})
    with pytest.raises(ScenarioError, match=match) as err:
        validate(s)
    assert field in str(err.value)


def test_threads_agree_with_the_serial_loop_to_round_off():
    """A struck FCC packing of 48 spheres against a wall under Mindlin's law, damped, on 2
    threads (the normal forces in blocks, Mindlin's contacts after them): positions,
    velocities and energies are the serial run's within 1e-12 of their scale, and friction acted."""
    from granplate.bench.scaling_space import launched_fcc

    s = launched_fcc((3, 2, 2), mu=0.3, t_end=12e-6, scheme="verlet")
    floor = Wall(normal=(1.0, 0.0, 0.0), offset=float(max(g.x + g.radius for g in s.granules)), label="floor")
    contact = dataclasses.replace(s.contact, alpha_n=0.3, tangential_law="mindlin")
    runs = [
        run(dataclasses.replace(s, walls=(floor,), contact=contact, solver=dataclasses.replace(s.solver, threads=n)))
        for n in (1, 2)
    ]
    assert runs[1].attrs["threads"] == 2
    for name in ("x", "y", "z", "vx", "vy", "vz", "omega_x", "E_granular", "D_friction"):
        a, b = runs[0][name].values, runs[1][name].values
        assert np.abs(a - b).max() <= 1e-12 * max(np.abs(a).max(), 1e-30), name
    assert np.abs(runs[0]["omega_y"].values).max() > 0.0 and runs[0]["D_friction"].values[-1] > 0.0


def test_restart_carries_the_tangential_history():
    """A sphere rolling on its sticking contact (non-zero xi) restarted from a stored state
    mid-run equals the straight run bitwise at every output from there: the history
    columns travel with the restart state."""
    s, _ = resting_sphere()
    s = dataclasses.replace(s, time=dataclasses.replace(s.time, restart_interval=5e-5))
    ds = run(s)
    rest = run_from(s, ds, 1e-4)
    n = rest.sizes["time"]
    for name in ("x", "y", "vx", "vy", "omega_x", "omega_y", "E_granular", "D_friction", "energy_residual"):
        np.testing.assert_array_equal(rest[name].values[1:], ds[name].values[-n + 1 :], err_msg=name)


def run_from(s: Scenario, ds, t: float):
    from granplate.results.run import simulate as simulate_from

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate_from(s, start_from=ds, start_time=t)


def test_contact_table_leaves_mindlins_friction_unknown_and_keeps_the_normal_force():
    """The result's contact table cannot rebuild Mindlin's friction from a recorded state
    (it depends on the contact's history): NaN, never the tanh law's value; the normal force
    of the sphere on its floor is still the one the floor received (wall_force)."""
    s, _ = resting_sphere(vx=1e-3, vy=0.0, t_end=2e-5, n_out=10)
    ds = run(s)
    assert ds.sizes["link"] > 0
    assert np.isnan(ds["link_tangential_force"].values).all()
    at = np.searchsorted(ds.time.values, ds["link_time"].values)
    wall = -1 - ds["link_partner"].values
    np.testing.assert_allclose(ds["link_normal_force"].values, np.abs(ds["wall_force"].values[at, wall]), rtol=1e-9)
