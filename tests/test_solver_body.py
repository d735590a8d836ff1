"""The granules' contacts on an elastic body in space (solver/body.py): Hertz's law at a
known overlap, the residual compliance in series solved exactly, the forces as the exact
gradient of the contact's potential (finite differences), the modes' projection as the
work-conjugate of the surface motion, the exact free vibration of the modes, friction
booked as the kinetic energy it removes, and a coupled run's energy balance converging as
h^2."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import brentq

from granplate.model import build_model
from granplate.model.inputs import new_body_state
from granplate.physics.contact import COEF_A
from granplate.setup import io as scenario_io
from granplate.solver import body as B

DROP = """
name = "drop"
dimension = 3
[[granules]]
label = "ball"
x = 0.0103
y = 0.0096
z = 0.01201
radius = 0.002
material = "steel"
vz = -1.0
vx = 0.3
omega = [0.0, 200.0, 0.0]
[plate]
size = [0.02, 0.02, 0.01]
elements = [3, 3, 2]
material = "steel"
clamped = ["zmin"]
patch_radius = 0.0
max_frequency = 1.5e5
[load]
kind = "none"
[contact]
mu = 0.3
[time]
t_end = 2.4e-5
dt_max = 2e-8
output_interval = 2e-7
field_interval = 2.4e-5
[solver]
scheme = "verlet"
granular_friction = "split"
"""


@pytest.fixture(scope="module")
def model():
    return build_model(scenario_io.loads(DROP))


@pytest.fixture(scope="module", params=[0.0, 0.006])
def any_patch(request):
    """The model with a point patch and with a disc patch of radius 6 mm (across face edges)."""
    return build_model(scenario_io.loads(DROP.replace("patch_radius = 0.0", f"patch_radius = {request.param}")))


def forces(m, y, q, b=None):
    """(acc * m [N] on the granules (ng, 9), the contacts' energy, the residual's [J], b)."""
    b = new_body_state(m.body) if b is None else b
    acc = np.zeros_like(y)
    fd = np.zeros_like(y)
    e_pot, _, _, e_static, _, _ = B.contact_forces(
        y, q, np.zeros_like(q), b, 0, m.granular.radius, m.granular.mass, False, acc, fd, False
    )
    return acc, e_pot, e_static, b


def state(m, overlap):
    """The granule at rest with its centre `overlap` [m] closer to the top face than R."""
    y = m.initial_state.copy()
    y[0, 2] = 0.01 + m.granular.radius[0] - overlap
    y[0, 3:] = 0.0
    return y


def test_hertz_force_at_a_known_overlap_with_the_residual_in_series(model):
    """With the modes at rest: delta + r F(delta) = delta0 with r = w^T R w of the residual
    (R, w from the solid), F Hertz's A delta^1.5, the force along the face's normal."""
    m = model
    y = state(m, 2e-6)
    acc, e_pot, e_static, b = forces(m, y, np.zeros(m.solid.n_modes))
    delta0 = m.granular.radius[0] - (y[0, 2] - 0.01)
    n = b.count[0, 0]  # a point patch: the closest point's face nodes
    w = b.weights[0, 0, :n]
    sidx = b.node_resid[b.entry[0, 0, :n], 2]
    r = float(w[sidx >= 0] @ m.solid.resid[np.ix_(sidx[sidx >= 0], sidx[sidx >= 0])] @ w[sidx >= 0])
    assert r > 0.0
    a = m.body.coef[0, COEF_A]
    delta = brentq(lambda d: d + r * a * d**1.5 - delta0, 0.0, delta0, xtol=1e-20)
    assert acc[0, 5] == pytest.approx(a * delta**1.5, rel=1e-11)
    # along the surface only the residual's pull as its weights move (tested below), tiny here
    assert abs(acc[0, 3]) < 1e-6 * acc[0, 5] and abs(acc[0, 4]) < 1e-6 * acc[0, 5]
    assert e_static == pytest.approx(0.5 * r * (a * delta**1.5) ** 2, rel=1e-10)
    assert e_pot == pytest.approx(0.4 * a * delta**2.5, rel=1e-10)


def test_forces_are_the_gradient_of_the_contact_potential(any_patch):
    """On a deformed body (modes displaced) the granule's force is -dPi/dx of Pi = E_Hertz +
    1/2 N^T R N (central differences in x, y, z to 1e-5), the tilt and the residual's moving
    weights included (a point patch and a disc patch); without them the tangential force
    would be zero."""
    m = any_patch
    rng = np.random.default_rng(3)
    q = rng.normal(size=m.solid.n_modes) * 5e-7 / np.maximum(1.0, np.arange(m.solid.n_modes))
    y = state(m, 1.5e-6)  # the modes' displacement (a fraction of the overlap) keeps the contact closed
    acc, _, _, _ = forces(m, y, q)
    assert acc[0, 5] > 0.0
    grad = []
    for c in range(3):
        h = 2e-9
        e = []
        for s in (1, -1):
            yy = y.copy()
            yy[0, c] += s * h
            _, ep, es, _ = forces(m, yy, q)
            e.append(ep + es)
        grad.append((e[0] - e[1]) / (2 * h))
    grad = np.array(grad)
    assert np.abs(acc[0, 3:5]).max() > 1e-4 * abs(acc[0, 5])  # a real tangential force
    np.testing.assert_allclose(acc[0, 3:6], -grad, rtol=1e-5, atol=1e-6 * abs(acc[0, 5]))


def test_modal_force_is_the_work_conjugate_of_the_overlap(any_patch):
    """Phi^T F on the modes equals -dPi/dq (central differences in two modes' coordinates),
    for a point patch and a disc patch."""
    m = any_patch
    q = np.zeros(m.solid.n_modes)
    y = state(m, 1.5e-6)
    _, _, _, b = forces(m, y, q)
    fm = b.fmodal[0].copy()
    for k in (0, 3):
        h = 1e-9
        e = []
        for s in (1, -1):
            qq = q.copy()
            qq[k] += s * h
            _, ep, es, _ = forces(m, y, qq)
            e.append(ep + es)
        assert fm[k] == pytest.approx(-(e[0] - e[1]) / (2 * h), rel=1e-5, abs=1e-8 * np.abs(fm).max())


def test_disc_patch_weights_average_the_shape_functions(any_patch):
    """A patch's weights sum to 1: a radius-0 patch is the point's face nodes (whose weights
    reproduce the point), a disc patch every surface node within its radius, weights >= 0."""
    m = any_patch
    y = state(m, 1e-6)
    _, _, _, b = forces(m, y, np.zeros(m.solid.n_modes))
    n = b.count[0, 0]
    w = b.weights[0, 0, :n]
    x = b.node_xyz[b.entry[0, 0, :n]]
    assert w.sum() == pytest.approx(1.0, abs=1e-12)
    if m.body.patch[0] == 0.0:  # the face's shape functions reproduce the point
        np.testing.assert_allclose(w @ x[:, :2], y[0, :2], atol=1e-12)
        assert n == b.face_nodes.shape[1]
    else:  # every node within the radius, none beyond, none weighted negatively
        assert np.all(w >= 0.0)
        d = np.linalg.norm(b.node_xyz - np.array([y[0, 0], y[0, 1], 0.01]), axis=1)
        assert set(b.entry[0, 0, :n]) == set(np.flatnonzero(d < m.body.patch[0]))


def test_modes_turn_exactly():
    """turn() is the exact free vibration: q(h) = q0 cos + qd0 sin / omega, and a rigid mode drifts."""
    q = np.array([1e-3, 2e-3])
    qd = np.array([0.5, -1.0])
    om = np.array([0.0, 3e4])
    h = 7e-5
    q1, qd1 = q.copy(), qd.copy()
    B.turn(q1, qd1, om, h)
    assert q1[0] == pytest.approx(q[0] + h * qd[0])
    assert q1[1] == pytest.approx(q[1] * np.cos(om[1] * h) + qd[1] * np.sin(om[1] * h) / om[1], rel=1e-13)
    assert qd1[1] == pytest.approx(-q[1] * om[1] * np.sin(om[1] * h) + qd[1] * np.cos(om[1] * h), rel=1e-13)


def test_friction_books_the_kinetic_energy_it_removes(model):
    """One friction pass on a sliding, spinning granule: the work booked equals the kinetic
    energy lost by the granule and the modes, and the slip speed drops."""
    m = model
    y = state(m, 2e-6)
    y[0, 3] = 0.3
    y[0, 7] = 200.0
    q = np.zeros(m.solid.n_modes)
    _, _, _, b = forces(m, y, q)
    qd = np.zeros(m.solid.n_modes)
    mass, inertia = m.granular.mass[0], m.granular.inertia[0]

    def ke(y, qd):
        return 0.5 * mass * (y[0, 3:6] ** 2).sum() + 0.5 * inertia * (y[0, 6:9] ** 2).sum() + 0.5 * (qd**2).sum()

    before = ke(y, qd)
    slip0 = y[0, 3] - m.granular.radius[0] * y[0, 7]
    work = B.friction_flow(y, qd, 1e-6, b, 0, m.granular.radius, m.granular.mass, m.granular.inertia, 0.0, True)
    assert work > 0.0
    assert before - ke(y, qd) == pytest.approx(work, rel=1e-10)
    assert abs(y[0, 3] - m.granular.radius[0] * y[0, 7]) < abs(slip0)


def test_coupled_run_energy_balance_converges_as_h_squared():
    """An oblique, spinning sphere with friction bouncing on a clamped block: the run's
    largest energy residual falls about fourfold when the step halves, and stays below 1e-5
    (with a disc patch too)."""
    import granplate as gp

    s = scenario_io.loads(DROP)
    res = []
    for dt in (2e-8, 1e-8):
        ds = gp.simulate(
            dataclasses.replace(s, time=dataclasses.replace(s.time, dt_max=dt, dt_initial=dt)), progress=False
        )
        assert ds.attrs["status"] == "ok"
        assert float(ds.body_contact_normal_force.max()) > 10.0  # it did hit
        res.append(float(np.abs(ds.energy_residual).max()))
    assert res[0] < 1e-5
    assert 3.0 < res[0] / res[1] < 5.0
    disc = scenario_io.loads(DROP.replace("patch_radius = 0.0", "patch_radius = 0.006"))
    ds = gp.simulate(disc, progress=False)
    assert float(np.abs(ds.energy_residual).max()) < 1e-5 and float(ds.body_contact_normal_force.max()) > 10.0


def test_patch_loads_spread_each_force_whole():
    """The nodal forces of a recorded contact force over its disc patch sum to that force,
    on the dofs of the patch's nodes only (a point patch's loads are solid.loads')."""
    m = build_model(scenario_io.loads(DROP.replace("patch_radius = 0.0", "patch_radius = 0.006")))
    b = new_body_state(m.body)
    face = np.array([[m.body.face[0, 0]]])
    xi = np.array([[[0.1, -0.2]]])
    force = np.array([[[0.0, 0.0, -12.5]]])
    room = 3 * b.entry.shape[2]
    t, col, val = np.empty(room, np.int64), np.empty(room, np.int64), np.empty(room)
    k = B.patch_loads(b, face, xi, force, t, col, val)
    assert k > 3 and val[:k].sum() == pytest.approx(-12.5, rel=1e-12)
    nodes = set(b.entry[0, 0, : b.count[0, 0]])
    rows = {int(b.node_rows[n, 2]) for n in nodes}
    assert set(col[:k][val[:k] != 0.0].tolist()) <= rows


def test_summary_only_equals_the_full_result_with_a_body():
    """A coupled run's summary from the summary-only Dataset (what a study stores) equals the
    full Dataset's, the body's keys included."""
    import granplate as gp

    s = scenario_io.loads(DROP.replace("patch_radius = 0.0", "patch_radius = 0.006"))
    full = gp.summary(gp.simulate(s, progress=False))
    brief = gp.summary(gp.simulate(s, progress=False, summary_only=True))
    for key in (
        "ep_max_fraction",
        "eg_max_fraction",
        "max_von_mises",
        "max_von_mises_ball",
        "max_displacement",
        "energy_residual_max",
        "max_contact_pressure",
    ):
        assert brief[key] == pytest.approx(full[key], rel=1e-12), key
    assert full["ep_max_fraction"] > 0.0 and full["units"]["max_von_mises_ball"] == "Pa"
