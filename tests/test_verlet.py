"""The velocity-Verlet scheme of the granules (solver.scheme = "verlet", docs/model.md
section 6.5): LAMMPS's algorithm to round-off, second order with damping and friction, its
energy balance, the plastic law and the loop's guards under it, and its refusals."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from granplate.errors import ScenarioError, SimulationError, YieldWarning
from granplate.results.run import simulate
from granplate.setup.geometry import resolve
from granplate.setup.scenario import Contact, Granule, LatticeLayout, Load, Scenario, Solver, TimeSettings
from granplate.setup.validate import validate
from granplate.verification import lammps as L

needs_lammps = pytest.mark.skipif(bool(L.unavailable()), reason=L.unavailable() or "lammps available")


def with_step(s: Scenario, scheme: str, dt: float) -> Scenario:
    """Scenario s with `scheme` at the fixed step dt [s]."""
    return dataclasses.replace(
        s,
        solver=dataclasses.replace(s.solver, scheme=scheme),
        time=dataclasses.replace(s.time, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt)),
    )


def quiet_run(s: Scenario):
    """simulate(s), the yield-onset warning of elastic runs silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", YieldWarning)
        return simulate(s, progress=False)


def oblique_pair(
    t_end: float = 2e-5, normal_law: str = "hertz", speed: float = 1.0, mu: float = 0.05, alpha_n: float = 0.05
) -> Scenario:
    """Two 1 mm steel spheres touching at t = 0, line of centres at 0.3 rad, meeting at
    ~1.25 speed [m/s] and sliding ~0.66 m/s, with spins; damped (alpha_n), friction mu."""
    d, phi = 2e-3, 0.3
    gs = (
        Granule(x=0.0, y=0.0, radius=1e-3, material="steel", label="a", vx=0.5 * speed, vy=0.5 * speed, omega=300.0),
        Granule(
            x=d * np.cos(phi),
            y=d * np.sin(phi),
            radius=1e-3,
            material="steel",
            label="b",
            vx=-0.5 * speed,
            vy=-0.5 * speed,
            omega=-100.0,
        ),
    )
    out = t_end / 4
    return Scenario(
        name="oblique-pair",
        granules=gs,
        plate=None,
        load=Load(kind="none"),
        contact=Contact(mu=mu, alpha_n=alpha_n, pairs=(), normal_law=normal_law),
        time=TimeSettings(t_end=t_end, output_interval=out, field_interval=out),
        solver=Solver(energy_tol=1e-3),
    )


def pressed_pair(t_end: float = 4e-6, mu: float = 0.05, count: int = 2) -> Scenario:
    """`count` 1 mm steel spheres in a row, touching at t = 0 (line of centres at 0.3 rad)
    with no normal speed, each sliding past the next at 1 m/s with spins (mu 0.05: in gross
    slip throughout); the first pushed into the rest by the half-sine line load (q0 2e4 N/m,
    10 us); damped (alpha_n 0.05), friction mu. Until t_end [s] the contacts stay closed
    and loaded: the motion is smooth."""
    d, phi = 2e-3, 0.3
    nx, ny = np.cos(phi), np.sin(phi)
    gs = tuple(
        Granule(
            x=k * d * nx,
            y=k * d * ny,
            radius=1e-3,
            material="steel",
            label="abc"[k],
            vx=-0.5 * sign * ny,
            vy=0.5 * sign * nx,
            omega=spin,
        )
        for k, sign, spin in ((0, 1.0, 300.0), (1, -1.0, -100.0), (2, 1.0, 50.0))[:count]
    )
    out = t_end / 4
    return Scenario(
        name="pressed-pair",
        granules=gs,
        plate=None,
        load=Load(kind="line", target="granules", q0=2e4, duration=1e-5, length=0.1, y0=-0.05, granules=("a",)),
        contact=Contact(mu=mu, alpha_n=0.05, pairs=()),
        time=TimeSettings(t_end=t_end, output_interval=out, field_interval=out),
        solver=Solver(energy_tol=1e-3),
    )


def final_state(ds) -> np.ndarray:
    """Velocities and spin [m/s, rad/s * R] of every granule at the last output."""
    r = ds.radius.values if "radius" in ds else 1e-3
    return np.concatenate([ds.vx.values[-1], ds.vy.values[-1], ds.omega.values[-1] * r])


def small_packing(mu: float, t_end: float = 2e-5) -> Scenario:
    """A 6 x 8 hexagonal packing between walls, damped (the default alpha_n), friction mu,
    its first column launched at 1 m/s."""
    s = resolve(
        Scenario(
            name="small-packing",
            layout=LatticeLayout(kind="hexagonal", columns=6, rows=8, radius=1e-3),
            load=Load(kind="none"),
            contact=Contact(mu=mu),
            time=TimeSettings(t_end=t_end, output_interval=t_end / 5, field_interval=t_end / 5),
        )
    )
    left = min(g.x - g.radius for g in s.granules)
    return dataclasses.replace(
        s,
        granules=tuple(dataclasses.replace(g, vx=1.0) if abs(g.x - g.radius - left) < 1e-9 else g for g in s.granules),
    )


@needs_lammps
def test_frictionless_packing_is_lammps_to_round_off():
    """A launched 3 x 3 packing, undamped and frictionless: verlet and LAMMPS at the same
    step agree to round-off (every output, largest |dv| below 1e-12 of v0; measured ~4e-14)."""
    dt = 4e-9
    s = L.launched_hexagon(3, 3, t_end=1e-5, scheme="verlet", dt=dt)
    ds = quiet_run(s)
    lm = L.run_hertz(s, dt, 1e-5, every=int(round(s.time.output_interval / dt)))
    assert np.abs(ds.vx.values[-1]).max() > 0.1  # the wave crossed the packing
    dv = max(np.abs(lm["vx"] - ds.vx.values).max(), np.abs(lm["vy"] - ds.vy.values).max())
    dx = max(np.abs(lm["x"] - ds.x.values).max(), np.abs(lm["y"] - ds.y.values).max())
    assert dv < 1e-12 and dx < 1e-12 * 1e-3


@needs_lammps
@pytest.mark.parametrize("case", ["fcc", "gas"])
def test_frictionless_space_is_lammps_to_round_off(case):
    """In space, a launched FCC block and a gas in a box (walls): verlet and LAMMPS at the
    same step agree to round-off (largest |dv| below 1e-10 of the speed)."""
    dt = 4e-9 if case == "fcc" else 1e-8
    s = L.fcc_block(1, t_end=1e-5, dt=dt) if case == "fcc" else L.gas_in_box((2, 2, 2), t_end=2e-4, dt=dt)
    s = with_step(s, "verlet", dt)
    ds = quiet_run(s)
    lm = L.run_hertz_3d(s, dt, s.time.t_end, every=int(round(s.time.output_interval / dt)))
    moved = max(np.abs(lm[k][-1] - lm[k][0]).max() for k in ("vx", "vy", "vz"))
    dv = max(np.abs(lm[k] - ds[k].values).max() for k in ("vx", "vy", "vz"))
    assert moved > 0.1 and dv < 1e-10


@pytest.mark.parametrize("count", [2, 3])
def test_second_order_with_damping_and_friction(count):
    """A pair (and a row of three, whose middle sphere's two contacts each friction pass
    relaxes one after the other, in alternating order) pressed together by a load while
    sliding, damped, with friction (the contacts closed and loaded throughout): the error
    of verlet's velocities and spins against a converged paper-scheme run falls 4x per
    halving of the step (order 2.00 +- 0.1)."""
    s = pressed_pair(count=count)
    ref = quiet_run(with_step(s, "paper", 2.5e-9))
    assert float(ref.D_friction.values[-1]) > 0.0 and float(ref.D_viscous.values[-1]) > 0.0
    errors = [
        np.abs(final_state(quiet_run(with_step(s, "verlet", dt))) - final_state(ref)).max()
        for dt in (1e-7, 5e-8, 2.5e-8)
    ]
    assert errors[0] > 1e-5  # a step that the motion resolves, not round-off
    assert np.log2(np.array(errors[:-1]) / np.array(errors[1:])) == pytest.approx([2.0, 2.0], abs=0.1)


def test_impact_from_a_finite_speed_is_order_five_quarters():
    """An oblique damped impact from touch at 1.25 m/s: the damping c delta^(1/4) d(delta)/dt
    (eq. 3) is not smooth at the contact's onset, so the error falls as h^(5/4) (for every
    fixed-step scheme); verlet's is measured at order 1.27 +- 0.15 against the paper scheme."""
    s = oblique_pair()
    ref = final_state(quiet_run(with_step(s, "paper", 2.5e-9)))
    errors = [np.abs(final_state(quiet_run(with_step(s, "verlet", dt))) - ref).max() for dt in (5e-8, 2.5e-8, 1.25e-8)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert orders == pytest.approx([1.25, 1.25], abs=0.2)


def test_energy_balance_with_friction_and_walls():
    """A damped, frictional packing between walls: eq. (11)'s residual stays within
    energy_tol at every step, friction and damping dissipate, and the residual (Verlet's
    own energy error) falls ~4x when the step halves."""
    s = small_packing(0.099)
    res = []
    for dt in (4e-8, 2e-8):
        ds = quiet_run(with_step(s, "verlet", dt))
        assert float(ds.D_friction.values[-1]) > 0.0 and float(ds.D_viscous.values[-1]) > 0.0
        res.append(float(np.abs(ds.energy_residual.values).max()))
    assert max(res) < s.solver.energy_tol
    assert np.log2(res[0] / res[1]) == pytest.approx(2.0, abs=0.4)


def test_plastic_law_under_verlet():
    """A yielding oblique impact (Thornton's law, its histories): verlet's end velocities
    and plastic work agree with a converged paper-scheme run (second-order error)."""
    s = oblique_pair(normal_law="thornton", speed=3.0)
    ref = quiet_run(with_step(s, "paper", 2.5e-9))
    ds = quiet_run(with_step(s, "verlet", 2.5e-8))
    w_p = float(ref.D_plastic.values[-1])
    assert w_p > 1e-6  # it yields
    assert float(ds.D_plastic.values[-1]) == pytest.approx(w_p, rel=1e-3)
    assert np.abs(final_state(ds) - final_state(ref)).max() < 1e-3


def test_guards_hold_under_verlet():
    """The loop's guards under verlet: the contact list is rebuilt as the wave runs, and an
    overlap beyond contact.overlap_stop stops the run with a message naming the contact."""
    ds = quiet_run(L.launched_hexagon(6, 4, speed=5.0, mu=0.099, t_end=4e-5, scheme="verlet", dt=2e-8))
    assert int(ds.attrs["n_rebuilds"]) > 0
    s = oblique_pair()
    s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, overlap_warn=1e-3, overlap_stop=1e-3))
    with pytest.raises(SimulationError, match="overlap"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the overlap warning before the stop
        quiet_run(with_step(s, "verlet", 2e-8))


def test_refusals_name_the_field():
    """A scenario with the plane's plate, or with the friction inside the step, is refused
    under verlet in one line naming the field (and, for the plate, why), before anything runs."""
    import granplate as gp

    why = r"'solver\.scheme' = 'verlet': velocity Verlet does not drive the plane's plate: .*its modes"
    with pytest.raises(ScenarioError, match=why + r'.*"implicit" or "paper"') as err:
        validate(gp.with_changes(gp.preset("steel-r1"), {"solver.scheme": "verlet"}))
    assert "\n" not in str(err.value)
    s = dataclasses.replace(oblique_pair(), solver=Solver(scheme="verlet", granular_friction="rk4"))
    with pytest.raises(ScenarioError, match=r"solver\.granular_friction"):
        validate(s)
