"""Mindlin's tangential law at a granule's contact on the elastic solid in space
(contact.tangential_law = "mindlin", docs/model.md sections 3.9 and 3.16) held against
truth: the sticking vibration's closed form w_t^2 = 7/2 k_t / m on a stiff block, the
gross-sliding impulse (tangential = mu x normal, R w = 5/2 mu dv_n), the rigid wall's
Mindlin run as the block's modulus grows, eq. (11) at every output to second order in the
step, a bitwise restart, and the plane's plate still refused."""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import granplate as gp
from granplate.model.inputs import GEO_DELTA, GEO_N, HIST_XI
from granplate.physics.mindlin import tangential_compliance
from granplate.results.restart import restart_state
from granplate.results.run import simulate
from granplate.setup.materials import LIBRARY

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"
R = 0.002  # the sphere's radius [m]
TOP = 0.01  # the block's top face z [m]
STEEL = LIBRARY["steel"]
MASS = 4.0 / 3.0 * math.pi * R**3 * STEEL.rho


def scenario(
    vx: float = 0.0,
    vz: float = 0.0,
    wy: float = 0.0,
    z: float = TOP + R + 1e-8,
    block_e: float | None = 200e9,
    force: float = 0.0,
    dt: float = 1e-8,
    t_end: float = 3e-5,
    n_out: int = 6,
    mu: float = 0.3,
    alpha_n: float = 0.0,
    x_t: float = 0.0,
) -> gp.Scenario:
    """A steel sphere (R = 2 mm) above the top face of a clamped 20 x 20 x 10 mm block of
    Young's modulus block_e [Pa] (steel's nu and density; 3 x 3 x 2 hex20, a point patch,
    modes to 150 kHz), or of a rigid steel floor there (block_e None), off the face's
    nodes; launched at (vx, 0, vz) [m/s] with spin (0, wy, 0) [rad/s], optionally pressed
    by a constant force [N] along -z; Mindlin's law (damping alpha_n, tangential x_t: none by
    default), velocity Verlet at dt [s]."""
    out = t_end / n_out
    body = (
        '[[walls]]\nnormal = [0.0, 0.0, -1.0]\noffset = -0.01\nmaterial = "steel"\n'
        if block_e is None
        else f"[materials.block]\nE = {block_e!r}\nnu = 0.3\nrho = 7850.0\n"
        '[plate]\nsize = [0.02, 0.02, 0.01]\nelements = [3, 3, 2]\nmaterial = "block"\nclamped = ["zmin"]\n'
        "patch_radius = 0.0\nmax_frequency = 1.5e5\n"
    )
    drive = (
        '[[drives]]\ntarget = "granule ball"\nkind = "force"\nprofile = "constant"\n'
        f"direction = [0.0, 0.0, -1.0]\nvalue = {force!r}\n"
        if force
        else ""
    )
    return gp.loads(
        f"""name = "mindlin-on-a-block"
dimension = 3
[[granules]]
label = "ball"
x = 0.0103
y = 0.0096
z = {z!r}
radius = {R!r}  # radius 2 mm, diameter 4 mm
material = "steel"
vx = {vx!r}
vz = {vz!r}
omega = [0.0, {wy!r}, 0.0]
{body}
[load]
kind = "none"
[contact]
mu = {mu!r}
alpha_n = {alpha_n!r}
pairs = []
tangential_law = "mindlin"
tangential_damping = {x_t!r}
overlap_start = 1e-3
[time]
t_end = {t_end!r}
dt_max = {dt!r}
dt_initial = {dt!r}
output_interval = {out!r}
field_interval = {t_end!r}
[solver]
scheme = "verlet"
{drive}"""
    )


def run(s: gp.Scenario, **kw):
    with warnings.catch_warnings():  # the elastic law is compared, whatever the pressure
        warnings.simplefilter("ignore")
        return simulate(s, **kw)


@pytest.mark.parametrize("x", [0.0103, 0.02 * 2.0 / 3.0 - 1e-9])
def test_sticking_contact_on_a_stiff_block_vibrates_at_mindlins_frequency(x):
    """A sphere pressed on a block (E = 10x steel's) by 1 N at its static Hertz overlap,
    nudged along the face far below slip: its contact point's velocity is v0 cos(w_t t),
    w_t^2 = 7/2 k_t / m, k_t = 8 G* a with G* of both bodies, to 1e-3 of v0 at every output
    over two periods (measured 1.9e-4: the block's own compliance at the point, which on a
    steel block makes it 1.7e-2); the same where the contact crosses from one face to the
    next (1 nm from the edge; measured 3.3e-4): the history goes with the contact."""
    e_b, force, v0 = 2e12, 1.0, 1e-3
    e_star = 1.0 / ((1.0 - STEEL.nu**2) / STEEL.E + (1.0 - 0.3**2) / e_b)
    d0 = (force / (4.0 / 3.0 * e_star * math.sqrt(R))) ** (2.0 / 3.0)
    s = scenario(vx=v0, z=TOP + R - d0, block_e=e_b, force=force, dt=2e-8, t_end=5e-5, n_out=100)
    ds = run(dataclasses.replace(s, granules=(dataclasses.replace(s.granules[0], x=x),)))
    faces = set(ds["body_contact_face"].values[:, 0].tolist())
    assert len(faces) == (1 if x == 0.0103 else 2) and -1 not in faces  # the edge case crosses it
    k_t = 8.0 / (tangential_compliance(STEEL.E, STEEL.nu) + tangential_compliance(e_b, 0.3)) * math.sqrt(R * d0)
    w_t = math.sqrt(3.5 * k_t / MASS)
    t = ds.time.values
    v_contact = ds["vx"].values[:, 0] - R * ds["omega_y"].values[:, 0]
    assert np.abs(v_contact - v0 * np.cos(w_t * t)).max() < 1e-3 * v0
    assert w_t * t[-1] > 4.0 * math.pi  # two periods
    assert float(ds["body_contact_normal_force"].values.min()) > 0.99 * force  # in touch throughout


def test_the_tangential_force_is_mindlins_spring_on_the_slip_against_the_surface():
    """One contact pass on a sphere pressed 1 um into a steel block, sliding at 0.3 m/s over
    a surface moving with random modal rates: the force on the granule is -8 G* a v_s h
    (G* of both bodies, v_s the slip against the surface's motion at the contact, sticking
    far below mu |N|; a from the overlap left by the residual compliance), its torque R n x F_t, and the force on the block's modes is its
    reaction: its power at any modal rates is -F_t . (the surface's velocity there)."""
    from granplate.model import build_model
    from granplate.model.inputs import new_body_state
    from granplate.solver import body as B
    from granplate.solver.body_mindlin import mindlin_forces

    m = build_model(scenario(vx=0.3, z=TOP + R - 1e-6))
    g, b = m.granular, new_body_state(m.body)
    y = m.initial_state.copy()
    nm = b.phi.shape[1]
    acc = np.zeros_like(y)
    B.contact_forces(y, np.zeros(nm), np.zeros(nm), b, 0, g.radius, g.mass, m.config.clip, acc, np.zeros_like(y), True)
    f0, a0 = b.fmodal[0].copy(), acc.copy()
    vq = np.random.default_rng(1).normal(size=nm) * 1e-2
    h = 1e-8
    mindlin_forces(y, vq, b, 0, 0, h, g.radius, g.mass, g.inertia, 0.0, acc)
    force = (acc - a0)[0, 3:6] * g.mass[0]
    torque = (acc - a0)[0, 6:9] * g.inertia[0]
    v_surf = np.array(B.surface_velocity(b, 0, 0, vq))
    slip = np.array([0.3, 0.0, 0.0]) - v_surf
    slip[2] = 0.0  # the face's normal is z
    delta = float(b.geo[0, 0, GEO_DELTA])  # the overlap, the residual compliance's share taken off
    assert 0.99e-6 < delta < 1e-6
    k_t = 8.0 / (2.0 * tangential_compliance(STEEL.E, STEEL.nu)) * math.sqrt(R * delta)
    np.testing.assert_allclose(force, -k_t * slip * h, rtol=1e-6, atol=1e-12 * np.abs(force).max())
    np.testing.assert_allclose(torque, R * np.cross([0.0, 0.0, -1.0], force), rtol=1e-6, atol=1e-15)
    assert float((b.fmodal[0] - f0) @ vq) == pytest.approx(-float(force @ v_surf), rel=1e-9)
    assert np.abs(v_surf).max() > 1e-4 and np.abs(force).max() < 0.1 * 0.3 * float(b.geo[0, 0, GEO_N])


def test_gross_sliding_on_the_block_takes_mu_times_the_normal_impulse():
    """An impact on a steel block at a grazing angle (v_t / v_n = 5 > 7 mu: slides
    throughout): the tangential impulse is mu times the normal one and the spin R w =
    5/2 mu dv_n, to 1e-6 (measured 7e-8: the deformed surface's tilt, which pulls the
    granule along the face without a torque), the block taking part of the rebound."""
    v_n, v_t, mu = 0.2, 1.0, 0.3
    ds = run(scenario(vx=v_t, vz=-v_n, mu=mu))
    assert float(ds["body_contact_normal_force"].values[-1].max()) == 0.0  # the contact ended
    dvn = float(ds["vz"].values[-1, 0] + v_n)
    dvt = float(v_t - ds["vx"].values[-1, 0])
    assert dvn == pytest.approx(2.0 * v_n, rel=1e-4)  # nearly elastic: the block's modes took 1e-5
    assert dvt == pytest.approx(mu * dvn, rel=1e-6)
    assert R * float(ds["omega_y"].values[-1, 0]) == pytest.approx(2.5 * mu * dvn, rel=1e-6)


def test_a_stiffening_block_approaches_the_rigid_floors_run():
    """An oblique impact in Mindlin's partial-slip regime (v_t / v_n = 1/4) on blocks of
    growing modulus: the rebound (v_x, v_z, R w_y) approaches the same impact on a rigid
    floor (the granule's compliance alone) as 1/E of the block, within 1e-4 of v_n at 50x
    steel's modulus (measured: 4.6e-4, 1.0e-4, 5.2e-5 at 5x, 25x, 50x)."""
    kw = {"vx": 0.05, "vz": -0.2}
    floor = run(scenario(block_e=None, **kw))

    def rebound(ds):
        return np.array([ds["vx"].values[-1, 0], ds["vz"].values[-1, 0], R * ds["omega_y"].values[-1, 0]])

    ref = rebound(floor)
    assert 0.0 < ref[2] < ref[0] < 0.05  # it rolls off slower than it came
    moduli = (1e12, 1e13)
    gaps = [float(np.abs(rebound(run(scenario(block_e=e, **kw))) - ref).max()) / 0.2 for e in moduli]
    assert gaps[1] < 1e-4
    assert 6.0 < gaps[0] / gaps[1] < 14.0  # as 1 / E (10)


@pytest.mark.parametrize("alpha_n, x_t", [(0.0, 0.0), (0.2, 1.0)])
def test_energy_balance_holds_to_second_order_in_the_step(alpha_n, x_t):
    """Eq. (11), E_p + E_g + D = E_in at every output, with the springs' energy in E_g and
    the slip's work in D_friction, for a sphere sliding across a steel block, undamped and
    with normal and tangential damping (the latter's work in D_friction too): the largest
    residual (relative to the energy in) falls 4x as the step halves (Verlet's own error; 1.2e-7
    without friction), under 3e-7 at 10 ns (measured 1.7e-7 undamped, 1.3e-7 damped, while
    D_friction takes 0.18-0.19 of the energy in); D_friction converged to 1e-4."""
    worst, lost = [], []
    for dt in (1e-8, 5e-9):
        ds = run(scenario(vx=0.3, vz=-0.2, dt=dt, n_out=30, alpha_n=alpha_n, x_t=x_t))
        worst.append(float(np.abs(ds["energy_residual"].values).max()))
        lost.append(float(ds["D_friction"].values[-1]))
        e_in = float(ds.attrs["E_initial"])
    assert worst[0] < 3e-7
    assert 3.5 < worst[0] / worst[1] < 4.5
    assert lost[1] == pytest.approx(lost[0], rel=1e-4) and lost[0] > 0.1 * e_in


def test_restart_mid_contact_equals_the_straight_run_bitwise():
    """An oblique spinning sphere on the block, restarted from a stored state while its
    contact sticks and slides (non-zero tangential history): every output from there and
    the loop's body state (modes, histories) equal the straight run's bitwise."""
    s = scenario(vx=0.05, vz=-0.2, wy=100.0, t_end=3e-5, n_out=30)
    straight = run(s)
    first = run(s, t_end=1.3e-5)
    assert np.abs(restart_state(first)["b.hist"][0, HIST_XI : HIST_XI + 3]).max() > 0.0  # in touch, loaded
    rest = run(s, start_from=first)
    n = rest.sizes["time"]
    for name in ("x", "z", "vx", "vz", "omega_y", "E_granular", "E_plate", "D_friction", "energy_residual"):
        np.testing.assert_array_equal(rest[name].values, straight[name].values[-n:], err_msg=name)
    s0, s1 = restart_state(straight), restart_state(rest)
    for key in ("st.q", "st.qd", "b.hist"):
        np.testing.assert_array_equal(s1[key], s0[key], err_msg=key)
    assert float(straight["D_friction"].values[-1]) > 0.0
