"""Mindlin's tangential law in the plane (dimension = 2, docs/model.md section 3.16) held
against truth: LAMMPS's pair granular `tangential mindlin_rescale` in `dimension 2` run
side by side at the same step (an oblique pair with a spin, and a short window of the
990-granule frictional packing: velocities to 1e-6), the closed forms of a sticking
contact's tangential vibration (Mindlin's stiffness 8 G* a, the sphere's mass ratio 7/2) and
of an impact in gross sliding (tangential impulse = mu x normal impulse), and eq. (11) at
every output to second order in the step."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

from granplate.errors import ScenarioError
from granplate.physics.mindlin import tangential_compliance
from granplate.setup.materials import LIBRARY
from granplate.setup.scenario import Contact, Granule, Gravity, Load, Scenario, Solver, TimeSettings, Wall
from granplate.setup.validate import validate
from granplate.verification import lammps as L
from granplate.verification.base import simulate

needs_lammps = pytest.mark.skipif(bool(L.unavailable()), reason=L.unavailable() or "lammps available")

R = 1e-3
STEEL = LIBRARY["steel"]
MASS = 4.0 / 3.0 * math.pi * R**3 * STEEL.rho


def _time(dt: float, t_end: float, n_out: int) -> TimeSettings:
    out = t_end / n_out
    return TimeSettings(
        t_end=t_end, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt), output_interval=out, field_interval=out
    )


def run(s: Scenario):
    with warnings.catch_warnings():  # the elastic law is compared, whatever the pressure
        warnings.simplefilter("ignore")
        return simulate(s)


def on_floor(
    vx: float, vy: float = 0.0, y0: float | None = None, g: float = 1000.0, dt: float = 5e-8, t_end=8e-5, n_out=80
):
    """A steel disc-plane sphere (R = 1 mm) on a steel floor y = 0 (gravity g [m/s^2], at its
    static overlap unless y0 [m] is given), launched at (vx, vy) [m/s] without spin, mu =
    0.3, undamped, Mindlin's law under Verlet at dt [s]. Returns (scenario, static overlap)."""
    d0 = (MASS * g / (4.0 / 3.0 * STEEL.E / (1.0 - STEEL.nu**2) * math.sqrt(R))) ** (2.0 / 3.0) if g else 0.0
    s = Scenario(
        name="mindlin-floor-plane",
        dimension=2,
        granules=(Granule(x=0.0, y=R - d0 if y0 is None else y0, radius=R, material="steel", vx=vx, vy=vy),),
        walls=(Wall(normal=(0.0, -1.0), offset=0.0, material="steel"),),
        load=Load(kind="none"),
        gravity=Gravity(g=(0.0, -g)) if g else None,
        contact=Contact(mu=0.3, alpha_n=0.0, pairs=(), tangential_law="mindlin", overlap_start=1e-3),
        time=_time(dt, t_end, n_out),
        solver=Solver(scheme="verlet"),
    )
    return s, d0


def test_sticking_contact_vibrates_at_mindlins_frequency_in_the_plane():
    """A sphere resting on a floor, nudged along it far below slip: its contact point's
    velocity v_x + R omega is v0 cos(w_t t), w_t^2 = 7/2 k_t / m with k_t = 8 G* a (as in
    space: the plane's tangent carries the same law), to 1e-3 of v0 at every output."""
    v0 = 1e-3
    s, d0 = on_floor(v0)
    ds = run(s)
    k_t = 8.0 / tangential_compliance(STEEL.E, STEEL.nu) * math.sqrt(R * d0)
    w_t = math.sqrt(3.5 * k_t / MASS)
    t = ds.time.values
    v_contact = ds["vx"].values[:, 0] + R * ds["omega"].values[:, 0]  # the floor's normal is -y: t = +x
    assert np.abs(v_contact - v0 * np.cos(w_t * t)).max() < 1e-3 * v0
    assert w_t * t[-1] > 2.0 * math.pi


def test_gross_sliding_impact_takes_mu_times_the_normal_impulse_in_the_plane():
    """A grazing impact on a floor (v_t / v_n = 5 > 7 mu: slides throughout): the tangential
    impulse is mu times the normal one, and the spin R |omega| = 5/2 mu dv_n, to round-off."""
    v_n, v_t, mu = 0.2, 1.0, 0.3
    s, _ = on_floor(v_t, -v_n, y0=R + 1e-8, g=0.0, dt=1e-9, t_end=2e-5, n_out=4)
    ds = run(s)
    dvn = float(ds["vy"].values[-1, 0] + v_n)
    dvt = float(v_t - ds["vx"].values[-1, 0])
    assert dvn == pytest.approx(2.0 * v_n, rel=1e-3)  # the elastic rebound: the contact ended
    assert dvt == pytest.approx(mu * dvn, rel=1e-9)
    assert -R * float(ds["omega"].values[-1, 0]) == pytest.approx(2.5 * mu * dvn, rel=1e-9)


def test_energy_balance_holds_to_second_order_in_the_step_in_the_plane():
    """Eq. (11) at every output of the oblique pair (it sticks, then slides), with the
    spring's energy in E_g and the slip's work in D_friction: the largest residual falls
    4x as the step halves (Verlet's own error) and is under 1e-6 of the energy in."""
    worst = []
    for dt in (4e-9, 2e-9):
        ds = run(L.mindlin_pair_plane(dt=dt, arm="radius"))
        worst.append(float(np.abs(ds["energy_residual"].values).max()))
        assert ds["D_friction"].values[-1] > 0.0
    assert worst[1] < 1e-6
    assert 3.0 < worst[0] / worst[1] < 5.0


def _worst(ds, lm, keys) -> float:
    scale = max(float(np.abs(lm[k]).max()) for k in keys)
    return max(float(np.abs(ds[k].values - lm[k]).max()) for k in keys) / scale


@needs_lammps
def test_oblique_pair_agrees_with_lammps_in_the_plane():
    """LAMMPS's pair granular hertz/material + tangential mindlin_rescale in `dimension 2`,
    velocity Verlet at the same step, LAMMPS's arms: positions, velocities and spins agree to
    1e-6 (measured: 5e-14) at every output, and friction did act."""
    s = L.mindlin_pair_plane()
    ds = run(s)
    lm = L.run_granular(s, L.MINDLIN_PAIR_STEP, s.time.t_end, every=int(round(s.time.output_interval / 2e-9)))
    assert _worst(ds, lm, ("x", "y")) < 1e-6
    assert _worst(ds, lm, ("vx", "vy")) < 1e-6
    assert _worst(ds, lm, ("omega",)) < 1e-6
    assert np.abs(lm["vy"][-1] - lm["vy"][0]).max() > 0.01


@needs_lammps
def test_frictional_packing_agrees_with_lammps_at_its_step():
    """The 990-granule frictional packing (granplate.bench.friction, mu = 0.099, undamped)
    under Mindlin's law at LAMMPS's step, 10 us (100 steps): every granule's velocity agrees
    with LAMMPS's mindlin_rescale run to 1e-6 of the largest (measured 2e-11; 1.9e-10 over
    the benchmark's 100 us)."""
    from granplate.bench.friction import LAMMPS_DT, mindlin_scenario

    s = mindlin_scenario(1e-5, alpha_n=0.0)
    ds = run(s)
    lm = L.run_granular(s, LAMMPS_DT, s.time.t_end)
    v = np.concatenate([ds.vx.values[-1], ds.vy.values[-1]])
    ref = np.concatenate([lm["vx"], lm["vy"]])
    assert np.abs(v - ref).max() < 1e-6 * np.abs(ref).max()
    assert np.abs(ds.omega.values[-1]).max() > 1.0  # friction turned the granules


@needs_lammps
def test_damped_frictional_packing_agrees_with_lammps_tsuji_at_the_half_step():
    """The same packing with its damping (alpha_n = 6.3e-3) and solver.verlet_damping =
    "half_step" (the force pass at the half step's velocities, as LAMMPS's): every velocity
    agrees with LAMMPS's `damping tsuji` run to 1e-6 of the largest (measured 2e-12 after
    10 us), where the default predicted velocities leave them 3e-4 apart."""
    from granplate.bench.friction import LAMMPS_DT, mindlin_scenario

    ref, v = {}, {}
    for damping in ("half_step", "predicted"):
        s = mindlin_scenario(1e-5, damping=damping)
        assert s.contact.alpha_n > 0.0
        ds = run(s)
        lm = L.run_granular(s, LAMMPS_DT, s.time.t_end)
        v[damping] = np.concatenate([ds.vx.values[-1], ds.vy.values[-1]])
        ref[damping] = np.concatenate([lm["vx"], lm["vy"]])
    scale = np.abs(ref["half_step"]).max()
    assert np.abs(v["half_step"] - ref["half_step"]).max() < 1e-6 * scale
    assert np.abs(v["predicted"] - ref["predicted"]).max() > 1e-5 * scale  # the option is what agrees


def test_the_plane_runs_mindlin_under_every_scheme_but_lammps_arms_under_verlet_alone():
    """The plane validates under Verlet and under the paper's scheme with the radius as
    the arm; LAMMPS's arms under the paper's scheme are refused naming contact.torque_arm
    and the scheme they run under."""
    s = L.mindlin_pair_plane()
    validate(s)
    validate(dataclasses.replace(L.mindlin_pair_plane(arm="radius"), solver=Solver(scheme="paper")))
    with pytest.raises(ScenarioError, match="solver.scheme = 'verlet' only") as err:
        validate(dataclasses.replace(s, solver=Solver(scheme="paper")))
    assert "contact.torque_arm" in str(err.value)
