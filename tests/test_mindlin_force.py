"""Mindlin's law in its force form (contact.tangential_law = "mindlin_force",
physics.mindlin_force), a tangential law added as one module and one registry line. Truth:
LAMMPS's `tangential mindlin_rescale/force` step for step; the displacement form where the
contact radius holds still (the two forms then agree); the closed-form integral of the
incremental stiffness while the contact loads; eq. (11) in a run."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

from granplate.physics import laws
from granplate.physics.contact import COEF_KT, COEF_MUT, COEF_TLAW, N_COEF
from granplate.setup.law_registry import MINDLIN, TANGENTIAL_LAW_IDS
from granplate.verification import lammps as L
from granplate.verification.base import simulate

needs_lammps = pytest.mark.skipif(bool(L.unavailable()), reason=L.unavailable() or "lammps available")

FORCE = TANGENTIAL_LAW_IDS["mindlin_force"]
K8G = 8.0 * 40e9  # 8 G* [Pa]
R_STAR = 0.5e-3  # [m]


def row(law: int, mu: float = 0.3) -> np.ndarray:
    """A coefficient row of tangential law `law` with 8 G* = K8G and mu."""
    c = np.zeros(N_COEF)
    c[COEF_TLAW], c[COEF_KT], c[COEF_MUT] = law, K8G, mu
    return c


def stepped(law: int, deltas, v: float, dt: float, n_abs: float = 1e3):
    """The tangential force on the first body after stepping the law of id `law` over the
    overlaps `deltas` [m] (one per step of dt [s]) at the constant slip speed v [m/s] along y,
    the normal along x; its history carried as the passes carry it."""
    c = row(law)
    h = np.zeros(3)
    a_old = 0.0
    f = (0.0, 0.0, 0.0)
    for delta in deltas:
        a = math.sqrt(R_STAR * delta)
        fx, fy, fz, hx, hy, hz, _, _ = laws.tangential_step(
            *h, a, a_old, c, delta, 1.0, 0.0, 0.0, 0.0, v, 0.0, dt, n_abs, *f
        )
        h, a_old, f = np.array([hx, hy, hz]), a, (fx, fy, fz)
    return f[1]


def test_equals_the_displacement_form_at_a_constant_contact_radius():
    """Stuck at a constant overlap, both forms give F = -k_t v t (k_t = 8 G* a), to round-off."""
    deltas = np.full(200, 1e-6)
    a = math.sqrt(R_STAR * 1e-6)
    want = -K8G * a * 1e-4 * 200 * 1e-9
    assert stepped(FORCE, deltas, 1e-4, 1e-9) == pytest.approx(want, rel=1e-12)
    assert stepped(MINDLIN, deltas, 1e-4, 1e-9) == pytest.approx(want, rel=1e-12)


def test_loading_contact_integrates_the_incremental_stiffness():
    """Stuck while the overlap grows linearly, delta = delta0 + r t: the force form gives
    -8 G* v int sqrt(R* delta) dt (closed form, to the step's order), the displacement form
    -8 G* sqrt(R* delta) v t: at delta = 21 delta0 the force form's is 0.69 of it, as the two
    closed forms say."""
    d0, rate, dt, n = 1e-7, 1.0, 1e-9, 2000  # delta ends at 2.1e-6 = 21 delta0
    deltas = d0 + rate * dt * np.arange(1, n + 1)
    v = 1e-4
    closed = -K8G * v * math.sqrt(R_STAR) * (2.0 / 3.0) * (deltas[-1] ** 1.5 - d0**1.5) / rate
    got = stepped(FORCE, deltas, v, dt)
    assert got == pytest.approx(closed, rel=2e-3)
    disp = stepped(MINDLIN, deltas, v, dt)
    assert disp == pytest.approx(-K8G * math.sqrt(R_STAR * deltas[-1]) * v * n * dt, rel=1e-12)
    ratio = (2.0 / 3.0) * (deltas[-1] ** 1.5 - d0**1.5) / (math.sqrt(deltas[-1]) * (deltas[-1] - d0))
    assert got / disp == pytest.approx(ratio, rel=2e-3) and ratio < 0.7  # the incremental law is the softer


def oblique(law: str, **kw):
    """lammps.mindlin_pair (two spheres meeting obliquely: they stick, then slide) under `law`."""
    s = L.mindlin_pair(**kw)
    return dataclasses.replace(s, contact=dataclasses.replace(s.contact, tangential_law=law))


def run(s):
    with warnings.catch_warnings():  # the elastic law is compared, whatever the pressure
        warnings.simplefilter("ignore")
        return simulate(s)


@needs_lammps
def test_oblique_pair_agrees_with_lammps_mindlin_rescale_force():
    """LAMMPS's pair granular hertz/material + tangential mindlin_rescale/force, velocity
    Verlet at the same step, LAMMPS's arms: positions and velocities agree to 1e-6 at every
    output, and differ from the displacement form's run (the two laws are not the same)."""
    s = oblique("mindlin_force")
    ds = run(s)
    every = int(round(s.time.output_interval / L.MINDLIN_PAIR_STEP))
    lm = L.run_hertz_3d(s, L.MINDLIN_PAIR_STEP, s.time.t_end, every=every)
    for keys in (("x", "y", "z"), ("vx", "vy", "vz")):
        scale = max(np.abs(lm[k]).max() for k in keys)
        assert max(float(np.abs(ds[k].values - lm[k]).max()) for k in keys) < 1e-6 * scale, keys
    other = run(oblique("mindlin"))
    assert float(np.abs(ds["vy"].values - other["vy"].values).max()) > 1e-4 * 0.2


def test_energy_balance_holds_to_second_order_in_the_step():
    """The oblique pair under the force form (velocity Verlet): eq. (11) holds at every output,
    the spring's energy |F_e|^2 / (2 k_t) in E_g and the slip's work in D_friction: the largest
    residual (relative to the energy in) falls about 4x as the step halves and is under 1e-6."""
    worst = []
    for dt in (4e-9, 2e-9):
        ds = run(oblique("mindlin_force", dt=dt, arm="radius"))
        worst.append(float(np.abs(ds["energy_residual"].values).max()))
        assert ds["D_friction"].values[-1] > 0.0
    assert worst[1] < 1e-6
    assert 3.0 < worst[0] / worst[1] < 5.0
