"""Verification: a striker on a chain of spheres, against Nesterenko's solitary wave and
an independent 1-D Hertz chain integrated by scipy's `solve_ivp` (DOP853)."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from .base import (
    Case,
    CaseResult,
    Check,
    Context,
    load_case_scenario,
    loglog_slope,
    new_figure,
    parabolic_peak,
    simulate,
    step_changes,
)
from .granular import _material, sphere_mass

CHAIN_WINDOW = (8, 20)  # beads (striker = 0) where the solitary wave is measured


def _chain_measure(
    t: np.ndarray, vx: np.ndarray, x: np.ndarray | None, radius: float, window: tuple[int, int] = CHAIN_WINDOW
) -> dict:
    """Speed [beads / time unit], mean peak velocity and mean peak overlap over the window."""
    idx = np.arange(window[0], window[1] + 1)
    tp = np.empty(len(idx))
    vm = np.empty(len(idx))
    for k, i in enumerate(idx):
        tp[k], vm[k] = parabolic_peak(t, vx[:, i])
    out = {"beads_per_time": 1.0 / float(np.polyfit(idx, tp, 1)[0]), "v_max": float(vm.mean()), "peak_times": tp}
    if x is not None:
        dm = np.empty(len(idx))
        for k, i in enumerate(idx):
            _, dm[k] = parabolic_peak(t, 2.0 * radius - (x[:, i + 1] - x[:, i]))
        out["delta_max"] = float(dm.mean())
    return out


def chain_reference(n: int, window: tuple[int, int] = CHAIN_WINDOW) -> dict:
    """The discrete Hertz chain in units m = A = v0 = 1 (scipy DOP853, rtol 1e-12).

    m u_i'' = A [(u_{i-1} - u_i)_+^(3/2) - (u_i - u_{i+1})_+^(3/2)], striker u_0' = v0.
    Returns the wave speed [beads per time unit] and v_max / v0 over the window.
    """

    def rhs(_t, z):
        u, v = z[:n], z[n:]
        d = np.clip(u[:-1] - u[1:], 0.0, None)
        f = d * np.sqrt(d)
        a = np.zeros(n)
        a[:-1] -= f
        a[1:] += f
        return np.concatenate([v, a])

    z0 = np.zeros(2 * n)
    z0[n] = 1.0
    t_end = 1.7 * (window[1] + 2)
    t = np.arange(0.0, t_end, 0.01)
    sol = solve_ivp(rhs, (0.0, t_end), z0, method="DOP853", rtol=1e-12, atol=1e-14, t_eval=t)
    meas = _chain_measure(sol.t, sol.y[n:].T, None, 0.0, window)
    return {"beads_per_time": meas["beads_per_time"], "v_ratio": meas["v_max"]}


def solitary_wave_runs(speeds, radius, a_spacing, m, base, A, ref, n):
    """The chain struck at each striker speed v0 [m/s] (steps scaled to the chain's time unit, the run as
    long as the wave takes to cross it): each run's solitary wave as measured (`_chain_measure`)."""
    res = {}
    for v0 in speeds:
        T = (m / (A * math.sqrt(v0))) ** 0.4  # time unit of the normalised chain
        v_guess = a_spacing * ref["beads_per_time"] / T
        h = base.time.dt_max
        out = h * max(1, round(T / 100 / h))
        changes = {"granules[0].vx": v0}
        changes.update(step_changes(h, 1.05 * n * a_spacing / v_guess, out=out))
        s = load_case_scenario("striker-chain", changes)
        ds = simulate(s)
        meas = _chain_measure(ds.time.values, ds.vx.values, ds.x.values, radius)
        V = meas["beads_per_time"] * a_spacing
        res[v0] = {
            "V": V,
            "v_max": meas["v_max"],
            "delta_max": meas["delta_max"],
            "F_max": A * meas["delta_max"] ** 1.5,
            "T": T,
            "ds": ds,
            "V_ref": a_spacing * ref["beads_per_time"] / T,
        }
    return res


def striker_chain_checks(v_lw, r1, ref, speeds, res):
    """The checks of `striker_chain`: the solitary wave's speed at 1 m/s against the long-wave limit and
    the discrete reference, the peak particle velocity over the striker's, and the exponents of the wave
    speed against the peak force (1/6) and peak particle velocity (1/5) over 0.1-10 m/s. Returns (the
    checks, the peak forces, wave speeds and peak particle velocities per striker speed)."""
    checks = [
        Check(
            "solitary-wave speed V_s, striker 1 m/s",
            "m/s",
            v_lw,
            "Nesterenko (2001), long-wave: V_s = (16/25)^(1/5) c0^(4/5) v_m^(1/5), v_m ours",
            r1["V"],
            0.02,
            "2%, the discrete wave is known to run about 1% slower than the "
            "long-wave (continuum) compacton of the same amplitude; the independent discrete "
            "solution below gives that offset exactly.",
        ),
        Check(
            "solitary-wave speed V_s, striker 1 m/s",
            "m/s",
            r1["V_ref"],
            "independent discrete chain (scipy DOP853, rtol 1e-12)",
            r1["V"],
            1e-6,
            "peak times and values are parabola-interpolated from samples every T/100 (error "
            "~(T/100 / pulse width)^3 ~ 1e-7) and RK4 at h = 10 ns ~ T/2500 is accurate to "
            "~1e-8: 1e-6 bounds both.",
        ),
        Check(
            "peak particle velocity / striker velocity",
            "-",
            ref["v_ratio"],
            "independent discrete chain (scipy DOP853, rtol 1e-12)",
            r1["v_max"] / 1.0,
            1e-6,
            "as above.",
        ),
    ]
    F = np.array([res[v]["F_max"] for v in speeds])
    V = np.array([res[v]["V"] for v in speeds])
    vm = np.array([res[v]["v_max"] for v in speeds])
    checks.append(
        Check(
            "exponent of V_s against peak contact force, 0.1-10 m/s",
            "-",
            1.0 / 6.0,
            "Nesterenko: V_s ~ F_m^(1/6) (Hertz law, no precompression)",
            loglog_slope(F, V),
            1e-6,
            "the Hertz chain is exactly self-similar, so only the numerical errors of "
            "V_s and F_m (<= 1e-7 each at every speed, as above; h/T goes from 1/4000 to "
            "1/1600 at the fixed h = 10 ns) enter the slope, divided by ln(F ratio) ~ 14: "
            "1e-6 bounds them.",
            kind="abs",
        )
    )
    checks.append(
        Check(
            "exponent of V_s against peak particle velocity, 0.1-10 m/s",
            "-",
            0.2,
            "Nesterenko: V_s ~ v_m^(1/5)",
            loglog_slope(vm, V),
            1e-6,
            "as above.",
            kind="abs",
        )
    )
    return checks, F, V, vm


def striker_chain(ctx: Context) -> CaseResult:
    """Solitary wave in a chain of steel spheres: speed, amplitude, scaling."""
    base = load_case_scenario("striker-chain")
    n = len(base.granules)
    g = base.granules[0]
    mat = _material(base, g.material)
    radius, a_spacing = g.radius, 2.0 * g.radius
    m = sphere_mass(radius, mat.rho)
    A = 4.0 / 3.0 * (mat.E / (2.0 * (1.0 - mat.nu**2))) * math.sqrt(radius / 2.0)
    c = math.sqrt(2.0 * mat.E / (math.pi * mat.rho * (1.0 - mat.nu**2)))  # Nesterenko's c0
    ref = chain_reference(n)
    speeds = (0.1, 1.0, 10.0)
    res = solitary_wave_runs(speeds, radius, a_spacing, m, base, A, ref, n)
    r1 = res[1.0]
    v_lw = (16.0 / 25.0) ** 0.2 * c**0.8 * r1["v_max"] ** 0.2
    checks, F, V, vm = striker_chain_checks(v_lw, r1, ref, speeds, res)
    offset = r1["V_ref"] / v_lw - 1.0

    desc = (
        "A steel striker (R = 10 mm) hits a chain of 24 touching steel spheres without "
        "precompression and without damping (`striker-chain.toml`, h = 10 ns). A single "
        "solitary wave forms within a few beads; its speed is fitted from the times of "
        f"peak velocity of beads {CHAIN_WINDOW[0]}-{CHAIN_WINDOW[1]}. Long-wave theory "
        "(Nesterenko 2001, Dynamics of Heterogeneous Materials, ch. 1): with c0^2 = "
        "2E/(pi rho (1 - nu^2)), V_s = (2/sqrt 5) c0 xi_m^(1/4) = (16/25)^(1/5) c0^(4/5) "
        "v_m^(1/5), xi_m the peak strain and v_m the peak particle velocity, so V_s ~ "
        "F_m^(1/6). An independent scipy integration of the 1-D chain gives the exact "
        "discrete speed and amplitude."
    )
    notes = [
        f"Discreteness offset (independent discrete solution vs long-wave theory at the same "
        f"v_m): {offset * 100:+.2f}%; granplate vs long-wave: {(r1['V'] / v_lw - 1) * 100:+.2f}%.",
        f"Peak particle velocity {ref['v_ratio']:.4f} of the striker's (equal masses): the "
        "striker hands most of its momentum to one wave and rebounds slowly.",
    ]
    return CaseResult.of(desc, checks, notes=notes, plot={"ds": r1["ds"], "F": F, "V": V, "vm": vm, "c": c})


def draw_striker_chain(p: dict):
    """Bead velocities at 1 m/s (a); V_s against F_m over the three strikers, with slope
    1/6 and long-wave theory (b)."""
    ds, F, V, vm, c = p["ds"], p["F"], p["V"], p["vm"], p["c"]
    fig, axes = new_figure(ncols=2)
    ax = axes[0, 0]
    for i in (1, 4, 8, 12, 16, 20):
        ax.plot(ds.time.values * 1e3, ds.vx.values[:, i], lw=1, label=f"bead {i}")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("bead velocity v_x [m/s]")
    ax.set_title("striker 1 m/s on 24 steel beads")
    ax.legend(fontsize=7)
    ax = axes[0, 1]
    ax.loglog(F, V, "o", label="granplate, striker 0.1 / 1 / 10 m/s")
    ff = np.geomspace(F.min() / 1.5, F.max() * 1.5, 20)
    ax.loglog(ff, V[1] * (ff / F[1]) ** (1 / 6), "--", label="slope 1/6")
    ax.loglog(F, [(16 / 25) ** 0.2 * c**0.8 * v**0.2 for v in vm], "s", mfc="none", label="long-wave theory (same v_m)")
    ax.set_xlabel("peak contact force F_m [N]")
    ax.set_ylabel("solitary-wave speed V_s [m/s]")
    ax.legend(fontsize=7)
    return fig


CASES: tuple[Case, ...] = (
    Case(
        "striker-chain",
        "granular",
        "Striker on a chain: Nesterenko's solitary wave",
        striker_chain,
        draw=draw_striker_chain,
    ),
)
