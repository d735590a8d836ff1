"""Verification under gravity: the case `gravity-bounce`, a sphere dropped on a rigid floor
(docs/model.md sections 3 and 3.11): free fall against the parabola, the bounce's apex against
an independent scipy integration of the damped Hertz contact with gravity (eqs. 2-3), and
against Hertz impact's restitution e(alpha) without gravity in the contact, e^2 h0; the energy
balance of eq. (11) with the work of gravity."""

from __future__ import annotations

import math

import numpy as np

from .base import Case, CaseResult, Check, Context, load_case_scenario, new_figure

#: drop height [m] of the ball's lowest point above the floor, and the steps the case runs at [s]
DROP = 0.02
STEPS = (4e-7, 2e-7)


def bounce_scenario(drop: float = DROP, step: float = STEPS[-1], t_end: float | None = None):
    """The case's scenario: the ball's lowest point `drop` [m] above the floor, velocity Verlet
    at `step` [s], to t_end [s] (default: the fall, the bounce and the rise to the apex of a
    perfectly elastic bounce, plus a tenth)."""
    s = load_case_scenario("gravity-bounce")
    g = -s.gravity.g[1]
    r = s.granules[0].radius
    end = 2.2 * math.sqrt(2.0 * drop / g) if t_end is None else t_end
    return load_case_scenario(
        "gravity-bounce",
        {
            "granules[0].y": r + drop,
            "time.t_end": end,
            "time.dt_initial": step,
            "time.dt_max": step,
        },
    )


def reference_bounce(s) -> dict:
    """The bounce of scenario s integrated independently (scipy DOP853, rtol 1e-12): free fall
    in closed form to the floor, then m delta'' = m g - N, N = max(A delta^1.5 + c delta^(1/4)
    delta', 0) (eqs. 2-3 against a rigid wall: E* = E / (1 - nu^2), R* = R, m* = m, c = alpha_n
    sqrt(m A)) until the ball leaves the floor; then the rise to its apex in closed form.
    Returns the impact and rebound speeds [m/s], the contact time [s] and the apex [m] of the
    ball's centre."""
    from scipy.integrate import solve_ivp

    from granplate.physics.contact import hertz_coefficient
    from granplate.setup.materials import effective_modulus

    b = s.granules[0]
    mat = s.material(b.material)
    g = -s.gravity.g[1]
    m = mat.rho * 4.0 / 3.0 * math.pi * b.radius**3
    a = hertz_coefficient(effective_modulus(mat, None), b.radius)
    c = s.contact.alpha_n * math.sqrt(m * a)
    v_in = math.sqrt(2.0 * g * (b.y - b.radius))

    def rhs(_t, z):
        d, v = z
        n = max(a * d**1.5 + c * d**0.25 * v, 0.0) if d > 0.0 else 0.0
        return [v, g - n / m]

    def left(_t, z):
        return z[0]

    left.terminal, left.direction = True, -1
    sol = solve_ivp(rhs, (0.0, 1.0), [0.0, v_in], method="DOP853", rtol=1e-12, atol=1e-18, events=left)
    v_out = -float(sol.y_events[0][0][1])
    return {
        "v_in": v_in,
        "v_out": v_out,
        "t_c": float(sol.t_events[0][0]),
        "apex": b.radius + v_out**2 / (2.0 * g),
        "e": v_out / v_in,
    }


def measured_bounce(ds, s) -> dict:
    """The loop's bounce: its apex after the impact [m], the free fall's largest departure
    from the parabola before the impact [m], the energy residual of eq. (11)."""
    t, y = ds["time"].values, ds["y"].values[:, 0]
    b, g = s.granules[0], -s.gravity.g[1]
    t_hit = math.sqrt(2.0 * (b.y - b.radius) / g)
    falling = t < 0.95 * t_hit
    parabola = b.y - 0.5 * g * t[falling] ** 2
    k = int(np.argmin(y))
    return {
        "apex": float(np.max(y[k:])),
        "fall_error": float(np.max(np.abs(y[falling] - parabola))),
        "residual": float(np.max(np.abs(ds["energy_residual"].values))) if "energy_residual" in ds else math.nan,
        "t": t,
        "y": y,
    }


def gravity_bounce(ctx: Context) -> CaseResult:
    """The ball dropped at two steps, against the references."""
    from granplate.results.run import simulate
    from granplate.verification.granular import impact_ode

    runs = []
    for h in STEPS:
        s = bounce_scenario(step=h)
        runs.append((h, s, measured_bounce(simulate(s, progress=False), s)))
    s, fine = runs[-1][1], runs[-1][2]
    ref = reference_bounce(s)
    e0 = impact_ode(s.contact.alpha_n)[0]
    h0, r = s.granules[0].y - s.granules[0].radius, s.granules[0].radius
    errs = [abs(m["apex"] - ref["apex"]) for _, _, m in runs]
    checks = [
        Check(
            "free fall: largest departure from y0 - g t^2 / 2",
            "m",
            0.0,
            "the parabola (velocity Verlet is exact under a constant force)",
            max(m["fall_error"] for _, _, m in runs),
            1e-12,
            "round-off alone: a constant force makes velocity Verlet's step exact.",
            kind="max",
        ),
        Check(
            f"apex after the bounce, h = {STEPS[-1]:g} s",
            "m",
            ref["apex"],
            "scipy DOP853 of the damped Hertz contact with gravity (reference_bounce)",
            fine["apex"],
            1e-4,
            "relative; the step's error on the rebound speed, which halves at least as h halves (the next check).",
        ),
        Check(
            "apex error ratio, h halved",
            "-",
            1.0,
            "convergence: the error at h / 2 at most that at h",
            errs[1] / errs[0] if errs[0] > 0 else 0.0,
            1.0,
            "the damping term's delta^(1/4) limits the order near the contact's onset; the error "
            "must fall as the step is halved.",
            kind="max",
        ),
        Check(
            "rebound height / drop height against e(alpha)^2 (no gravity during the contact)",
            "-",
            e0**2,
            "Hertz's damped impact, e of the normalised impact ODE (verification.granular.impact_ode)",
            (fine["apex"] - r) / h0,
            1e-3,
            f"relative; gravity acts during the contact (t_c = {ref['t_c']:.3g} s, g t_c / v = "
            f"{9.81 * ref['t_c'] / ref['v_in']:.1e}), which the closed form leaves out.",
        ),
    ]
    if not math.isnan(fine["residual"]):
        checks.append(
            Check(
                "energy balance with gravity, eq. (11): max |residual| / E_in",
                "-",
                0.0,
                "E_g + D = E_in + E_gravity at every output time",
                fine["residual"],
                s.solver.energy_tol,
                "solver.energy_tol",
                kind="max",
            )
        )
    desc = (
        f"A steel sphere (R = {r * 1e3:g} mm, E = 200 GPa, nu = 0.3) dropped from {h0 * 1e3:g} mm onto a "
        f"rigid steel floor under g = 9.81 m/s^2, damped Hertz contact alpha_n = {s.contact.alpha_n:g}, "
        f"velocity Verlet at h = {STEPS[0]:g} and {STEPS[-1]:g} s (`gravity-bounce.toml`). The free fall "
        "must follow the parabola; the apex after the bounce must match an independent integration of "
        "the contact with gravity, and Hertz's damped restitution e(alpha)^2 h0 to the size of gravity's "
        "effect during the contact."
    )
    plot = {"t": fine["t"].tolist(), "y": fine["y"].tolist(), "apex": ref["apex"], "r": r}
    notes = [
        f"Reference: impact at {ref['v_in']:.6f} m/s, rebound at {ref['v_out']:.6f} m/s (e = {ref['e']:.6f}; "
        f"without gravity in the contact e = {e0:.6f}), contact {ref['t_c'] * 1e6:.2f} us; apex errors at the two "
        f"steps {errs[0]:.2e} m and {errs[1]:.2e} m."
    ]
    return CaseResult.of(desc, checks, notes=notes, plot=plot)


def draw_gravity_bounce(p: dict):
    """The ball's height over time and the reference apex."""
    fig, axes = new_figure(width=6.4, height=3.6)
    ax = axes[0, 0]
    ax.plot(np.asarray(p["t"]) * 1e3, (np.asarray(p["y"]) - p["r"]) * 1e3, lw=1.2, label="granplate")
    ax.axhline((p["apex"] - p["r"]) * 1e3, color="0.4", ls=":", label="reference apex")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("height of the lowest point [mm]")
    ax.legend(fontsize=8)
    return fig


CASES: tuple[Case, ...] = (
    Case(
        "gravity-bounce",
        "granular",
        "A ball dropped on a floor under gravity: free fall and damped bounce",
        gravity_bounce,
        slow=True,
        draw=draw_gravity_bounce,
    ),
)
