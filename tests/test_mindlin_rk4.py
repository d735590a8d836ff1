"""Mindlin's tangential law (contact.tangential_law = "mindlin") under the RK4 schemes
("paper", "implicit"; docs/model.md section 3.16, "Under RK4") held against truth: the
sticking contact's tangential vibration w_t^2 = 7/2 k_t / m (fourth order in the step), an
impact in gross sliding (tangential impulse = mu x normal impulse, R w = 5/2 mu dv_n),
eq. (11) at every output, agreement with a fine-step Verlet run, in space and in the plane,
and the plane's plate still refused."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

import granplate as gp

from granplate.physics.mindlin import tangential_compliance
from granplate.setup.materials import LIBRARY
from granplate.setup.scenario import Contact, Granule, Load, Scenario, Solver, TimeSettings, Wall
from granplate.verification import lammps as L
from granplate.verification.base import simulate

R = 1e-3
STEEL = LIBRARY["steel"]
MASS = 4.0 / 3.0 * math.pi * R**3 * STEEL.rho


def run(s: Scenario, scheme: str):
    with warnings.catch_warnings():  # the elastic law is compared, whatever the pressure
        warnings.simplefilter("ignore")
        return simulate(dataclasses.replace(s, solver=Solver(scheme=scheme)))


def _time(dt: float, t_end: float, n_out: int) -> TimeSettings:
    out = t_end / n_out
    return TimeSettings(
        t_end=t_end, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt), output_interval=out, field_interval=out
    )


def _sticking_error(scheme: str, dt: float) -> float:
    """The resting sphere nudged along its floor (far below slip): the largest departure of
    its contact point's velocity from v0 cos(w_t t), w_t^2 = 7/2 k_t / m, over v0."""
    v0 = 1e-3
    s, d0 = L.mindlin_floor(vx=v0, vy=0.0, t_end=8e-5, n_out=80, dt=dt)
    ds = run(s, scheme)
    w_t = math.sqrt(3.5 * 8.0 / tangential_compliance(STEEL.E, STEEL.nu) * math.sqrt(R * d0) / MASS)
    t = ds.time.values
    assert w_t * t[-1] > 2.0 * math.pi  # more than one period
    v_contact = ds["vx"].values[:, 0] - R * ds["omega_y"].values[:, 0]
    return float(np.abs(v_contact - v0 * np.cos(w_t * t)).max() / v0)


def test_sticking_contact_vibrates_at_mindlins_frequency_to_fourth_order():
    """Paper's scheme in space: the nudged resting sphere's contact point follows v0 cos(w_t
    t), w_t^2 = 7/2 k_t / m, within 2e-6 of v0 at h w_t = 0.043 (measured 9.4e-7), and the
    departure falls ~16x as the step halves (the elastic displacement is RK4's unknown)."""
    e1 = _sticking_error("paper", 1e-7)
    e2 = _sticking_error("paper", 5e-8)
    assert e1 < 2e-6
    assert 10.0 < e1 / e2 < 24.0


def test_sticking_contact_vibrates_at_mindlins_frequency_under_the_implicit_scheme():
    """The implicit scheme (its own step control) holds the sticking vibration to 1e-5 of
    v0 (measured 2.3e-6)."""
    assert _sticking_error("implicit", 1e-7) < 1e-5


def grazing(dimension: int, dt: float = 1e-9) -> Scenario:
    """A sphere (R = 1 mm, steel) meeting a steel floor at v_n = 0.2 m/s with v_t = 1 m/s
    (v_t / v_n = 5 > 7 mu: it slides throughout), mu = 0.3, undamped, Mindlin's law."""
    v_n, v_t = 0.2, 1.0
    if dimension == 3:
        g = Granule(x=0.0, y=0.0, z=R + 1e-8, radius=R, material="steel", vx=v_t, vz=-v_n, omega=(0.0, 0.0, 0.0))
        wall = Wall(normal=(0.0, 0.0, -1.0), offset=0.0, material="steel")
    else:
        g = Granule(x=0.0, y=R + 1e-8, radius=R, material="steel", vx=v_t, vy=-v_n)
        wall = Wall(normal=(0.0, -1.0), offset=0.0, material="steel")
    return Scenario(
        name="grazing",
        dimension=dimension,
        granules=(g,),
        walls=(wall,),
        load=Load(kind="none"),
        contact=Contact(mu=0.3, alpha_n=0.0, pairs=(), tangential_law="mindlin"),
        time=_time(dt, 2e-5, 4),
    )


@pytest.mark.parametrize("dimension, scheme", [(3, "paper"), (3, "implicit"), (2, "paper")])
def test_gross_sliding_impact_takes_mu_times_the_normal_impulse(dimension, scheme):
    """The grazing impact slides throughout: every RK4 stage caps the force at mu |N|, so the
    tangential impulse is mu times the normal one and R |w| = 5/2 mu dv_n, to 1e-9."""
    mu, v_n, v_t = 0.3, 0.2, 1.0
    ds = run(grazing(dimension), scheme)
    vn_col, spin = ("vz", "omega_y") if dimension == 3 else ("vy", "omega")
    dvn = float(ds[vn_col].values[-1, 0] + v_n)
    dvt = float(v_t - ds["vx"].values[-1, 0])
    assert dvn == pytest.approx(2.0 * v_n, rel=1e-3)  # the elastic rebound: the contact ended
    assert dvt == pytest.approx(mu * dvn, rel=1e-9)
    assert R * abs(float(ds[spin].values[-1, 0])) == pytest.approx(2.5 * mu * dvn, rel=1e-9)


@pytest.mark.parametrize("dimension", [3, 2])
def test_energy_balance_and_agreement_with_verlet(dimension):
    """The oblique pair (it sticks, then slides) under the paper's scheme: eq. (11) holds at
    every output with the springs' energy in E_g and the slip work in D_friction (residual
    under 2e-8 of the energy in, falling >= 4x as the step halves); its velocities agree
    with Verlet's at the same step to 1e-4 of the impact speed (both converge to the same
    law: measured 2.8e-5 apart from a fine-step Verlet run alike, at 8 ns), and
    D_friction ends positive."""
    make = L.mindlin_pair if dimension == 3 else L.mindlin_pair_plane
    keys = ("vx", "vy", "vz") if dimension == 3 else ("vx", "vy", "omega")
    worst = []
    for dt in (8e-9, 4e-9):
        ds = run(make(dt=dt, arm="radius"), "paper")
        worst.append(float(np.abs(ds["energy_residual"].values).max()))
        assert ds["D_friction"].values[-1] > 0.0
    assert worst[0] < 2e-8 and worst[0] / worst[1] > 4.0
    ref = run(make(dt=4e-9, arm="radius"), "verlet")
    scale = 0.2 if dimension == 3 else 0.2 / R
    for k in keys:
        s = scale if k == "omega" else 0.2
        assert float(np.abs(ds[k].values - ref[k].values).max()) < 1e-4 * s, k


def test_the_papers_preset_runs_under_mindlin_on_both_plate_schemes():
    """steel-r1 (the paper's packing on its plate, mu 0.1) under Mindlin's law at every
    contact, the plate's included, over 0.2 ms (the wave reaches and loads the plate): the
    paper and implicit schemes agree on E_shock, the plate's peak energy share and the
    friction work within 1e-3, and eq. (11) holds in both."""
    from granplate.setup.presets import preset

    s = preset("steel-r1")
    s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, tangential_law="mindlin"))
    runs = {
        k: gp.simulate(gp.with_changes(s, {"solver.scheme": k}), t_end=2e-4, progress=False)
        for k in ("paper", "implicit")
    }
    a, b = (gp.summary(runs[k]) for k in ("paper", "implicit"))
    for k in ("e_shock", "ep_max_fraction"):
        assert b[k] == pytest.approx(a[k], rel=1e-3), k
    fa, fb = (float(runs[k]["D_friction"].values[-1]) for k in ("paper", "implicit"))
    assert fa > 0.0 and fb == pytest.approx(fa, rel=1e-3)
    assert a["energy_residual_max"] < 1e-4 and b["energy_residual_max"] < 1e-4
