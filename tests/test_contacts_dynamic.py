"""Contacts that form and open during a run (docs/model.md section 1.3), against Hertz's
closed forms, an independent integrator and the energy balance; and every way two bodies
could interpenetrate silently stops the run instead."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from granplate.errors import SimulationError
from granplate.model.arrays import build_model, pair_coefficients
from granplate.model.contacts import contact_lists
from granplate.model.neighbours import brute_force_pairs, verlet_pairs
from granplate.results.run import simulate
from granplate.setup.materials import LIBRARY, effective_modulus, sphere_mass
from granplate.setup.presets import preset
from granplate.setup.scenario import Contact, Granule, Load, Plate, Scenario, TimeSettings, Wall
from granplate.verification.granular import hertz_reference, impact_ode

STEEL = LIBRARY["steel"]
R = 0.01
M = sphere_mass(R, STEEL.rho)


def scenario(granules, walls=(), t_end=1e-3, dt=1e-8, out=1e-7, plate=None, **contact) -> Scenario:
    """Granules and walls, no load; contact settings as given (no material-pair overrides)."""
    contact.setdefault("pairs", ())
    return Scenario(
        name="contacts",
        granules=tuple(granules),
        walls=tuple(walls),
        plate=plate,
        load=Load(kind="none"),
        contact=Contact(**contact),
        time=TimeSettings(t_end=t_end, dt_initial=dt, dt_max=dt, output_interval=out, field_interval=out),
    )


def crossings(t, f):
    """Times where f changes sign (linear interpolation between samples)."""
    k = np.flatnonzero(np.sign(f[1:]) != np.sign(f[:-1]))
    return t[k] + (t[k + 1] - t[k]) * f[k] / (f[k] - f[k + 1])


def head_on(gap: float, v: float, alpha_n: float, t_end: float, **contact) -> Scenario:
    """Two steel spheres of radius R, `gap` [m] apart, flying at each other at v [m/s] each."""
    return scenario(
        [
            Granule(x=0.0, y=0.0, radius=R, material="steel", label="left", vx=v),
            Granule(x=2 * R + gap, y=0.0, radius=R, material="steel", label="right", vx=-v),
        ],
        t_end=t_end,
        alpha_n=alpha_n,
        **contact,
    )


def test_verlet_list_holds_the_fixed_pairs_and_is_exact():
    """The Verlet list is every pair within (R_i + R_j)(1 + skin) (the double loop's),
    sorted, and contains the fixed topology's pairs, so the touching pairs keep their order."""
    rng = np.random.default_rng(3)
    x, y = rng.uniform(0, 0.1, 60), rng.uniform(0, 0.1, 60)
    r = rng.uniform(0.004, 0.008, 60)
    got = verlet_pairs(x, y, r, 0.1)
    want = [
        (i, j)
        for i in range(60)
        for j in range(i + 1, 60)
        if math.hypot(x[j] - x[i], y[j] - y[i]) <= (r[i] + r[j]) * 1.1
    ]
    assert got.tolist() == [list(p) for p in want]
    fixed = {tuple(p) for p in brute_force_pairs(x, y, r, 0.05).tolist()}
    assert fixed <= {tuple(p) for p in got.tolist()}


def test_head_on_from_a_gap_matches_hertz():
    """The docs example with a 1 mm gap: the spheres meet at gap / (2 v), stay in touch
    for Hertz's contact time, and leave at the restitution of the damped-impact ODE."""
    v, gap, alpha = 1.0, 1e-3, 6.313e-3
    ds = simulate(head_on(gap, v, alpha, 1.2e-3), progress=False)
    t = ds.time.values
    overlap = 2 * R - (ds.x.values[:, 1] - ds.x.values[:, 0])
    t_in, t_out = crossings(t, overlap)
    a = hertz_reference(M / 2, effective_modulus(STEEL, STEEL), R / 2, 2 * v)["A"]
    length = (M / 2 * (2 * v) ** 2 / a) ** 0.4  # the ODE's scales: delta = length x, t = length / (2 v) s
    e, s_end, sol = impact_ode(alpha)  # ends when the force vanishes; the spheres then fly off at e
    assert t_in == pytest.approx(gap / (2 * v), rel=1e-6)
    assert t_out - t_in == pytest.approx((s_end + sol.y[0, -1] / e) * length / (2 * v), rel=1e-4)
    assert ds.vx.values[-1] == pytest.approx([-e * v, e * v], rel=1e-5)
    assert abs(ds.energy_residual).max() < 1e-7
    assert ds.D_viscous.values[-1] == pytest.approx(M * v * v * (1 - e * e), rel=1e-4)


def test_fixed_topology_stops_at_the_unlisted_overlap():
    """contact.detection = "fixed": the pair is 5% of R apart or more at t = 0, so it is no
    contact; when the spheres meet the run stops naming both, keeping the result so far."""
    with pytest.raises(SimulationError, match="granule 'left'.*granule 'right' interpenetrate") as err:
        simulate(head_on(1e-3, 1.0, 0.0, 1.2e-3, detection="fixed"), progress=False)
    assert "contact.detection" in str(err.value)
    res = err.value.result
    assert res is not None and res.time.values[-1] > 4.9e-4


def test_oblique_impact_restitution_and_friction_bound():
    """A sphere hits a resting one off-centre (no damping, mu = 0.3): the normal relative
    speed is restored (e_n = 1) and the tangential impulse is at most mu times the normal
    one; no damping and frictionless gives no tangential impulse at all."""
    b, v = 0.6 * 2 * R, 5.0  # impact parameter [m], speed [m/s]
    for mu in (0.3, 0.0):
        s = scenario(
            [
                Granule(x=0.0, y=0.0, radius=R, material="steel", label="a", vx=v),
                Granule(x=0.0165, y=b, radius=R, material="steel", label="b"),
            ],
            t_end=3e-4,
            mu=mu,
            alpha_n=0.0,
        )
        ds = simulate(s, progress=False)
        x, y = ds.x.values, ds.y.values
        dist = np.hypot(x[:, 1] - x[:, 0], y[:, 1] - y[:, 0])
        k = int(np.argmin(dist))  # the deepest overlap: the normal of the impact
        assert dist[k] < 2 * R and dist[-1] > 2 * R
        n = np.array([x[k, 1] - x[k, 0], y[k, 1] - y[k, 0]]) / dist[k]
        tvec = np.array([-n[1], n[0]])
        dp = M * np.array([ds.vx.values[-1, 1], ds.vy.values[-1, 1]])  # impulse on b (at rest)
        jn, jt = dp @ n, dp @ tvec
        vrel0 = np.array([-v, 0.0]) @ n
        vrel1 = np.array([ds.vx.values[-1, 1] - ds.vx.values[-1, 0], ds.vy.values[-1, 1] - ds.vy.values[-1, 0]]) @ n
        assert vrel1 == pytest.approx(-vrel0, rel=2e-3)
        if mu == 0.0:  # the impulse along the line of centres (measured at the deepest sample)
            assert abs(jt) < 1e-5 * jn
        else:
            assert 0.1 * mu * jn < abs(jt) <= mu * jn  # friction acted, within Coulomb's bound
        assert abs(ds.energy_residual).max() < 1e-7


def test_bouncing_between_two_walls_has_the_hertz_period():
    """A sphere between two walls (no damping, no friction) returns with the period of its
    free flight plus two Hertz sphere-on-wall contact times; neither wall touches at t = 0."""
    v, free = 10.0, 0.5e-3
    L = 2 * R + free
    s = scenario(
        [Granule(x=L / 2, y=0.0, radius=R, material="steel", label="s", vx=v)],
        walls=[Wall(normal=(-1.0, 0.0), offset=0.0, label="left"), Wall(normal=(1.0, 0.0), offset=L, label="right")],
        t_end=3.2e-4,
        alpha_n=0.0,
        mu=0.0,
    )
    assert len(build_model(s).granular.wall_i) == 2  # in the Verlet list, not touching
    ds = simulate(s, progress=False)
    t = ds.time.values
    x = ds.x.values[:, 0] - L / 2
    up = [tc for tc in crossings(t, x) if np.interp(tc, t, ds.vx.values[:, 0]) > 0]
    t_c = hertz_reference(M, effective_modulus(STEEL, None), R, v)["t_c"]
    assert len(up) >= 2
    assert up[1] - up[0] == pytest.approx(2 * free / v + 2 * t_c, rel=1e-4)
    assert abs(ds.energy_residual).max() < 1e-7


def _reference_rhs(m, r, coef):
    """Frictionless Hertz + damping (eqs. 2-3) on every pair, written here from the
    equations: N = A d^1.5 + c d^0.25 d', never pulling."""
    n = len(m)

    def rhs(_t, z):
        pos = z[: 2 * n].reshape(n, 2)
        vel = z[2 * n :].reshape(n, 2)
        acc = np.zeros((n, 2))
        for (i, j), (a, c) in coef.items():
            d = pos[j] - pos[i]
            dist = math.hypot(*d)
            delta = r[i] + r[j] - dist
            if delta <= 0:
                continue
            nv = d / dist
            ddot = -(vel[j] - vel[i]) @ nv
            f = max(a * delta**1.5 + c * delta**0.25 * ddot, 0.0)
            acc[i] -= f * nv / m[i]
            acc[j] += f * nv / m[j]
        return np.concatenate([vel.ravel(), acc.ravel()])

    return rhs


def test_loose_packing_against_an_independent_integrator():
    """Five granules of two sizes with gaps (none touching at t = 0), frictionless and
    damped: positions and velocities equal scipy's DOP853 on the same equations."""
    gs = [
        Granule(x=0.0, y=0.0, radius=R, material="steel", label="1", vx=5.0),
        Granule(x=0.0195, y=0.002, radius=0.008, material="steel", label="2"),
        Granule(x=0.0205, y=-0.0155, radius=0.006, material="steel", label="3", vy=2.0),
        Granule(x=0.038, y=-0.003, radius=R, material="steel", label="4", vy=0.3),
        Granule(x=0.034, y=0.0185, radius=0.007, material="steel", label="5", vx=-3.0, vy=-2.0),
    ]
    s = scenario(gs, t_end=1e-3, mu=0.0, alpha_n=0.05)
    m_ = build_model(s)
    assert len(m_.pairs) == 0  # loose: nothing within neighbour_gap at t = 0
    ds = simulate(s, progress=False)
    g = m_.granular
    everyone = np.array([(i, j) for i in range(5) for j in range(i + 1, 5)])
    coef = pair_coefficients(m_.scenario, list(m_.materials), g.radius, g.mass, everyone)
    rhs = _reference_rhs(g.mass, g.radius, {(i, j): (c[0], c[1]) for (i, j), c in zip(everyone.tolist(), coef)})
    y0 = m_.initial_state
    z0 = np.concatenate([y0[:, :2].ravel(), y0[:, 3:5].ravel()])
    sol = solve_ivp(rhs, (0.0, 1e-3), z0, method="DOP853", rtol=1e-11, atol=1e-14, t_eval=[1e-3])
    pos = sol.y[:10, -1].reshape(5, 2)
    vel = sol.y[10:, -1].reshape(5, 2)
    r = g.radius
    dist = np.hypot(ds.x.values[:, 3] - ds.x.values[:, 1], ds.y.values[:, 3] - ds.y.values[:, 1])
    assert (dist < r[1] + r[3]).any()  # 1 hits 2, which then hits 4
    assert ds.D_viscous.values[-1] > 0.05 * ds.E_granular.values[0]
    np.testing.assert_allclose(np.column_stack([ds.x.values[-1], ds.y.values[-1]]), pos, atol=1e-8)
    np.testing.assert_allclose(np.column_stack([ds.vx.values[-1], ds.vy.values[-1]]), vel, atol=2e-5)
    assert abs(ds.energy_residual).max() < 1e-7


def test_huge_shock_stops_on_the_overlap_limit():
    """ptfe-r05 under q0 = 5e8 N/m (the largest validation allows, E_steel x 2.5 mm): the
    overlaps exceed contact.overlap_stop within the first steps; the run stops naming the
    contact instead of tunnelling."""
    s = preset("ptfe-r05")
    s = replace(s, load=replace(s.load, q0=5e8))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        with pytest.raises(
            SimulationError,
            match=r"granule '\w+' .* and granule '\w+' overlap by .*"
            r"beyond contact.overlap_stop = 0.2",
        ) as err:
            simulate(s, t_end=2e-5, progress=False)
    assert err.value.result is not None


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_granule_through_a_wall_stops_the_run():
    """A sphere thrown at a wall far too fast for Hertz's small-overlap assumption stops
    the run naming the wall; a huge step that jumps past the wall stops it too."""
    s = scenario(
        [Granule(x=0.0, y=0.0, radius=R, material="steel", label="s", vx=400.0)],
        walls=[Wall(normal=(1.0, 0.0), offset=0.02, label="right")],
        t_end=1e-4,
        mu=0.0,
    )
    with pytest.raises(SimulationError, match=r"granule 's' .* and wall 0 .* overlap by"):
        simulate(s, progress=False)
    fast = replace(s, time=replace(s.time, dt_initial=1e-4, dt_max=1e-4, output_interval=1e-4, field_interval=1e-4))
    with pytest.raises(SimulationError, match=r"granule 's'.*(wall 0|moved)"):
        simulate(fast, progress=False)


def test_overlap_beyond_the_warning_fraction_warns_once_per_contact():
    """An impact whose peak overlap exceeds contact.overlap_warn of R warns once, naming the pair."""
    s = head_on(1e-4, 1.0, 0.0, 3e-4, overlap_warn=1e-3)
    with pytest.warns(RuntimeWarning, match="granule 'left' and granule 'right'") as rec:
        simulate(s, progress=False)
    assert len([w for w in rec if "overlap" in str(w.message)]) == 1


def test_granule_reaching_the_plate_without_a_plate_contact_stops_the_run():
    """With the fixed topology plate contacts are those at t = 0: a granule 1 mm from the
    plate (beyond neighbour_gap R) that flies into it stops the run, naming it, the time
    and the place (with dynamic detection it gets a patch contact: test_patch_contacts.py)."""
    plate = Plate(x0=0.03, y0=0.0, height=0.1, ny=40)
    s = scenario(
        [Granule(x=0.03 - R - 1e-3, y=0.05, radius=R, material="steel", label="g", vx=2.0)],
        t_end=1e-3,
        dt=1e-7,
        out=1e-6,
        plate=plate,
        detection="fixed",
    )
    with pytest.raises(
        SimulationError,
        match=r"granule 'g' \(at x = .* y = 0.05 m\) reached the plate's face "
        r"at t = 5.0\d*e-04 s",
    ) as err:
        simulate(s, progress=False)
    assert err.value.result.time.values[-1] == pytest.approx(5e-4, abs=2e-6)


def test_contact_lists_modes():
    """dynamic lists include a pair 1 mm apart and a wall 1 mm away (skin 0.1 of 2 R and R);
    fixed lists do not (neighbour_gap 0.05 R = 0.5 mm)."""
    x, y, r = np.array([0.0, 0.021]), np.array([0.0, 0.0]), np.array([R, R])
    walls = (Wall(normal=(-1.0, 0.0), offset=R + 1e-3),)  # {x = -(R + 1 mm)}
    p, w = contact_lists(Contact(), walls, x, y, r)
    assert p.tolist() == [[0, 1]] and w.tolist() == [[0, 0]]
    p, w = contact_lists(Contact(detection="fixed"), walls, x, y, r)
    assert p.shape == (0, 2) and w.shape == (0, 2)


def test_paper_preset_is_bitwise_the_same_under_both_detections():
    """steel-r1's contacts are those at t = 0: the Verlet list adds only pairs that never
    touch, summed in the same order, so every output is bitwise that of the fixed topology."""
    runs = [
        simulate(
            replace(preset("steel-r1"), contact=replace(preset("steel-r1").contact, detection=d)),
            t_end=5e-5,
            progress=False,
        )
        for d in ("fixed", "dynamic")
    ]
    for name in ("x", "y", "vx", "vy", "omega", "E_granular", "E_plate", "D_viscous", "D_friction"):
        np.testing.assert_array_equal(runs[0][name].values, runs[1][name].values, err_msg=name)


@pytest.mark.parametrize(
    "field, value, words",
    [
        ("detection", "sometimes", "must be one of 'dynamic', 'fixed'"),
        ("skin", 0.0, "must be > 0"),
        ("skin", 1.5, "at most 1"),
        ("overlap_warn", -0.1, "must be > 0"),
        ("overlap_stop", 0.01, "must lie in [contact.overlap_warn = 0.05, 1)"),
        ("overlap_stop", 1.0, "must lie in"),
    ],
)
def test_contact_detection_fields_are_checked(field, value, words):
    """Each new contact field is range-checked, the message naming it."""
    from granplate.errors import ScenarioError
    from granplate.setup.validate import validate

    s = head_on(1e-3, 1.0, 0.0, 1e-4, **{field: value})
    with pytest.raises(ScenarioError, match=re_escape(f"contact.{field}")) as err:
        validate(s)
    assert words in str(err.value)


def re_escape(text: str) -> str:
    import re

    return re.escape(text)
