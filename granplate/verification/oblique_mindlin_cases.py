"""Mindlin friction on the whole oblique-impact curve (case `mindlin-oblique-curve`): a steel
sphere meets a rigid floor at a fixed normal speed and a range of tangential speeds
(Thornton et al. 2011's test of a constant normal and a varying tangential speed; Maw,
Barber & Fawcett's and Di Renzo & Di Maio's normalised angles, oblique_mindlin.py) under
contact.tangential_law = "mindlin" and the scheme "verlet"; its rebound (Psi2, the
tangential restitution, the spin) against the independent integration of the same law
(`reference_impact`), against the gross-sliding line in closed form, and against LAMMPS's
`mindlin_rescale` at the same step (where lammps is installed).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from granplate.setup.materials import LIBRARY

from .base import Case, CaseResult, Check, Context, new_figure, simulate
from .oblique_mindlin import (
    REFERENCE_SOURCE,
    SPIN_FACTOR,
    Rebound,
    normalised_angle,
    reference_impact,
    sliding_line,
    sliding_threshold,
    stiffness_ratio,
)

#: The set-up: a steel sphere of radius RADIUS [m] (diameter 2 mm), the normal speed V_N
#: [m/s], friction MU, the step STEP [s] (the contact lasts 7.4 us: 3,700 steps), the gap
#: GAP [m] it starts from.
RADIUS = 1e-3
V_N = 0.2
MU = 0.3
STEP = 2e-9
GAP = 1e-8
MATERIAL = "steel"

#: The normalised incidence angles Psi1 of the curve: sticking at touch below 2/3, the
#: reversal between, gross sliding from 7 kappa - 1/3 = 5.43 (nu = 0.3) on.
PSI1 = (0.1, 0.3, 0.5, 0.8, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0, 5.25, 5.6, 6.0, 7.0, 8.0, 10.0)

#: Psi1 run by LAMMPS beside granplate (in each regime) and the agreement asked of it.
LAMMPS_PSI1 = (0.5, 2.0, 4.0, 6.0)
LAMMPS_TOL = 1e-6


def tangential_speed(psi1: float, nu: float, mu: float = MU, v_n: float = V_N) -> float:
    """The contact point's incident tangential speed v_c1 [m/s] of Psi1 (eq. O1)."""
    return psi1 * mu * v_n / stiffness_ratio(nu)


def impact_scenario(psi1: float, dt: float = STEP, arm: str = "lammps"):
    """The sphere GAP above the floor z = 0 moving at (v_c1(psi1), 0, -V_N) without spin,
    undamped Hertz, Mindlin's law with MU, the scheme "verlet" at the fixed step dt [s], to
    the end of the contact and a little after (contact.torque_arm = arm; at a wall every arm
    but "contact_point" is R)."""
    from granplate.setup.scenario import Contact, Granule, Load, Scenario, Solver, TimeSettings, Wall

    mat = LIBRARY[MATERIAL]
    v_t = tangential_speed(psi1, mat.nu)
    t_c = reference_impact(V_N, v_t, RADIUS, mat.E, mat.nu, mat.rho, MU).t_c
    n_steps = int(math.ceil((GAP / V_N + 1.1 * t_c) / dt / 4.0)) * 4
    t_end = n_steps * dt
    return Scenario(
        name=f"mindlin-oblique-{psi1:g}",
        dimension=3,
        granules=(
            Granule(
                x=0.0,
                y=0.0,
                z=RADIUS + GAP,
                radius=RADIUS,
                material=MATERIAL,
                label="a",
                vx=v_t,
                vz=-V_N,
                omega=(0.0, 0.0, 0.0),
            ),
        ),
        walls=(Wall(normal=(0.0, 0.0, -1.0), offset=0.0, material=MATERIAL),),
        load=Load(kind="none"),
        contact=Contact(mu=MU, alpha_n=0.0, pairs=(), tangential_law="mindlin", torque_arm=arm),
        time=TimeSettings(
            t_end=t_end,
            dt_initial=dt,
            dt_max=dt,
            dt_min=min(1e-13, dt),
            output_interval=t_end / 4,
            field_interval=t_end,
        ),
        solver=Solver(scheme="verlet"),
    )


def rebound_of(v_n2: float, v_t2: float, omega2: float, psi1: float) -> Rebound:
    """The Rebound of final velocities v_n2 (away from the floor), v_t2 [m/s] and spin
    omega2 = omega_y [rad/s] of the impact at Psi1 (contact time left NaN)."""
    nu = LIBRARY[MATERIAL].nu
    v_c1 = tangential_speed(psi1, nu)
    v_c2 = v_t2 - RADIUS * omega2
    return Rebound(v_n2, v_t2, omega2, v_c2, normalised_angle(v_c2, V_N, MU, nu), -v_c2 / v_c1, math.nan)


def granplate_impact(psi1: float, dt: float = STEP) -> Rebound:
    """granplate's rebound at Psi1 with the step dt [s]."""
    with warnings.catch_warnings():  # the elastic law is compared, whatever the pressure
        warnings.simplefilter("ignore")
        ds = simulate(impact_scenario(psi1, dt))
    last = ds.isel(time=-1, granule=0)
    return rebound_of(float(last["vz"]), float(last["vx"]), float(last["omega_y"]), psi1)


def lammps_impact(psi1: float, dt: float = STEP) -> Rebound:
    """LAMMPS's rebound at Psi1 (`pair granular`'s `fix wall/gran` with hertz/material and
    `tangential mindlin_rescale`, velocity Verlet, the same step and end time)."""
    from .lammps import run_hertz_3d

    s = impact_scenario(psi1, dt)
    lm = run_hertz_3d(s, dt, s.time.t_end)
    return rebound_of(float(lm["vz"][-1][0]), float(lm["vx"][-1][0]), float(lm["wy"][-1][0]), psi1)


def reference_of(psi1: float) -> Rebound:
    """The independent integration's rebound at Psi1."""
    mat = LIBRARY[MATERIAL]
    return reference_impact(V_N, tangential_speed(psi1, mat.nu), RADIUS, mat.E, mat.nu, mat.rho, MU)


def speed_difference(a: Rebound, b: Rebound) -> float:
    """The largest difference of the rebound's v_n2, v_t2 and R omega2, over V_N [-]."""
    return max(abs(a.v_n2 - b.v_n2), abs(a.v_t2 - b.v_t2), RADIUS * abs(a.omega2 - b.omega2)) / V_N


#: Psi1 of the equal-sphere impacts: against the flat's curve (torque_arm "radius") and,
#: with LAMMPS's arms, against LAMMPS.
PAIR_PSI1 = (1.0, 2.5, 4.0, 7.0)
PAIR_LAMMPS_PSI1 = (2.5,)


def pair_scenario(psi1: float, dt: float = STEP, arm: str = "radius"):
    """Two equal spheres meeting along z at the relative normal speed V_N and the relative
    tangential speed v_c1(psi1) along x (each half of it, opposite; no spin), GAP apart; as
    `impact_scenario` otherwise. Relative to each other they are a sphere of mass sqrt(2) m
    on a rigid flat (E* and R* halved, k_t scaled alike) but for their line of centres,
    which turns as they slide past each other."""
    import dataclasses

    from granplate.setup.scenario import Granule

    s = impact_scenario(psi1, dt, arm)
    g = s.granules[0]
    top = dataclasses.replace(g, z=RADIUS + GAP / 2, vx=g.vx / 2, vz=-V_N / 2, label="a")
    low = Granule(
        x=0.0,
        y=0.0,
        z=-(RADIUS + GAP / 2),
        radius=RADIUS,
        material=MATERIAL,
        label="b",
        vx=-g.vx / 2,
        vz=V_N / 2,
        omega=(0.0, 0.0, 0.0),
    )
    t_end = s.time.t_end * 1.25  # the contact lasts 2^(1/5) times the flat's
    n = int(math.ceil(t_end / dt / 4.0)) * 4
    t_end = n * dt
    time = dataclasses.replace(s.time, t_end=t_end, output_interval=t_end / 4, field_interval=t_end)
    return dataclasses.replace(s, name=f"mindlin-pair-{psi1:g}", granules=(top, low), walls=(), time=time)


def pair_relative(vx, vz, wy) -> tuple[float, float]:
    """(relative normal speed apart [m/s], Psi2) of the pair's final velocities (a, b)."""
    v_c2 = (vx[0] - vx[1]) - RADIUS * (wy[0] + wy[1])
    return float(vz[0] - vz[1]), normalised_angle(float(v_c2), V_N, MU, LIBRARY[MATERIAL].nu)


def pair_impact(psi1: float, arm: str = "radius", dt: float = STEP) -> dict:
    """granplate's pair at Psi1: the final vx, vz, omega_y (a, b), the relative v_n2, Psi2."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        last = simulate(pair_scenario(psi1, dt, arm)).isel(time=-1)
    out = {k: last[k].values.astype(float) for k in ("vx", "vz", "omega_y")}
    out["v_n2"], out["psi2"] = pair_relative(out["vx"], out["vz"], out["omega_y"])
    return out


def lammps_pair(psi1: float, dt: float = STEP) -> dict:
    """LAMMPS's pair (`pair granular` hertz/material + mindlin_rescale) at Psi1, as `pair_impact`."""
    from .lammps import run_hertz_3d

    s = pair_scenario(psi1, dt, "lammps")
    lm = run_hertz_3d(s, dt, s.time.t_end)
    out = {"vx": lm["vx"][-1], "vz": lm["vz"][-1], "omega_y": lm["wy"][-1]}
    out["v_n2"], out["psi2"] = pair_relative(out["vx"], out["vz"], out["omega_y"])
    return out


def pair_difference(a: dict, b: dict) -> float:
    """The largest difference of the two spheres' vx, vz and R omega_y, over V_N [-]."""
    worst = max(float(np.abs(a[k] - b[k]).max()) for k in ("vx", "vz"))
    return max(worst, RADIUS * float(np.abs(a["omega_y"] - b["omega_y"]).max())) / V_N


def _pair_checks(ref_of, with_lammps: bool) -> tuple[list, dict, str]:
    """The equal spheres: LAMMPS's pair at the same step (a check), and their Psi2 beside
    the flat's curve (a note: the line of centres turns by about v_c t_c / (2 R) while they
    slide past each other, which the flat's fixed normal does not)."""
    runs = {p: pair_impact(p) for p in PAIR_PSI1}
    checks = []
    for p in PAIR_LAMMPS_PSI1 if with_lammps else ():
        diff = pair_difference(pair_impact(p, "lammps"), lammps_pair(p))
        checks.append(
            Check(
                f"equal spheres vs LAMMPS, Psi1 = {p:g}, speeds and R omega, max diff / v_n",
                "-",
                0.0,
                "LAMMPS pair granular hertz/material + tangential mindlin_rescale, velocity Verlet (same step)",
                diff,
                LAMMPS_TOL,
                'the same law, step and arms (contact.torque_arm = "lammps"): round-off',
                "max",
            )
        )
    gaps = ", ".join(f"Psi1 = {p:g}: {r['psi2'] - ref_of(p).psi2:+.1e}" for p, r in runs.items())
    note = (
        "Two equal spheres (relative speeds as the flat's, each sphere half of them; contact.torque_arm = "
        '"radius"): in the normalised angles their problem is the flat\'s but for the line of centres, which '
        f"turns as they slide past each other; Psi2 - the flat's curve: {gaps}, growing with the slide."
    )
    return checks, {"pair_psi1": list(runs), "pair": [r["psi2"] for r in runs.values()]}, note


def regime(psi1: float) -> str:
    """The name of Psi1's range on the curve (steel, nu = 0.3)."""
    if psi1 >= sliding_threshold(LIBRARY[MATERIAL].nu):
        return "gross sliding"
    return "stick at touch" if psi1 < 2.0 / 3.0 else "stick-slip"


def mindlin_curve(ctx: Context) -> CaseResult:
    """The curve Psi2(Psi1) of granplate against the independent integration, the sliding
    line and LAMMPS; the step halved at three angles (convergence)."""
    from . import lammps

    nu = LIBRARY[MATERIAL].nu
    ours = [granplate_impact(p) for p in PSI1]
    ref = [reference_of(p) for p in PSI1]
    checks = _reference_checks(ours, ref) + _sliding_checks(ours, nu)
    half = {p: granplate_impact(p, STEP / 2) for p in (1.0, 4.0, 8.0)}
    conv = {
        p: (abs(ours[PSI1.index(p)].psi2 - ref[PSI1.index(p)].psi2), abs(h.psi2 - ref[PSI1.index(p)].psi2))
        for p, h in half.items()
    }
    ratio = min(c / max(f, 1e-15) for c, f in conv.values() if c > 1e-9)
    checks.append(
        Check(
            "Psi2 error ratio, step 2 ns vs 1 ns (smallest over Psi1 = 1, 4)",
            "-",
            2.0,
            REFERENCE_SOURCE,
            ratio,
            1.8,
            "at least first order: the stick-slip switch falls inside a step",
            kind="min",
        )
    )
    side = [] if lammps.unavailable() else [(p, lammps_impact(p)) for p in LAMMPS_PSI1]
    for p, lm in side:
        checks.append(
            Check(
                f"rebound speeds vs LAMMPS, Psi1 = {p:g} ({regime(p)}), max diff / v_n",
                "-",
                0.0,
                "LAMMPS fix wall/gran hertz/material + tangential mindlin_rescale, velocity Verlet (same step)",
                speed_difference(ours[PSI1.index(p)], lm),
                LAMMPS_TOL,
                "the same law, step and integrator: the codes differ by round-off",
                kind="max",
            )
        )
    pair_checks, pair_plot, pair_note = _pair_checks(reference_of, bool(side))
    checks += pair_checks
    curve = reference_curve()
    notes = _notes(nu, conv, bool(side), curve) + [pair_note]
    plot = {
        "psi1": list(PSI1),
        "ours": [r.psi2 for r in ours],
        "ref": [r.psi2 for r in ref],
        "lammps_psi1": [p for p, _ in side],
        "lammps": [r.psi2 for _, r in side],
        "nu": nu,
        "curve": curve,
        **pair_plot,
    }
    return CaseResult.of(_description(nu), checks, notes=notes, tables=[_table(ours, ref)], plot=plot)


def _reference_checks(ours: list, ref: list) -> list:
    """Psi2 and the rebound speeds against the independent integration, per regime."""
    checks = []
    for name in ("stick at touch", "stick-slip", "gross sliding"):
        idx = [k for k, p in enumerate(PSI1) if regime(p) == name]
        worst = max(abs(ours[k].psi2 - ref[k].psi2) for k in idx)
        speeds = max(speed_difference(ours[k], ref[k]) for k in idx)
        span = f"Psi1 {PSI1[idx[0]]:g}-{PSI1[idx[-1]]:g}"
        why = (
            "velocity Verlet at 2 ns (3,700 steps a contact), first order where stick and slip switch "
            "(measured: at most 1.7e-4 in Psi2, 4.3e-5 in the speeds, halving with the step)"
        )
        checks.append(Check(f"Psi2, {name} ({span}), max |diff|", "-", 0.0, REFERENCE_SOURCE, worst, 5e-4, why, "max"))
        checks.append(
            Check(
                f"rebound speeds, {name} ({span}), max diff / v_n", "-", 0.0, REFERENCE_SOURCE, speeds, 1e-4, why, "max"
            )
        )
    return checks


def _sliding_checks(ours: list, nu: float) -> list:
    """Psi2 = Psi1 - 7 kappa and R omega2 = 5 mu v_n above the threshold, to round-off."""
    idx = [k for k, p in enumerate(PSI1) if regime(p) == "gross sliding"]
    line = max(abs(ours[k].psi2 - float(sliding_line(PSI1[k], nu))) for k in idx)
    spin = max(abs(RADIUS * ours[k].omega2 / ((SPIN_FACTOR - 1.0) * 2.0 * MU * V_N) - 1.0) for k in idx)
    source = "gross sliding: tangential impulse = mu x normal impulse (closed form)"
    why = "the capped force is mu |N| at every force pass: only the normal impulse's step error (measured 1e-9) enters"
    return [
        Check(
            f"Psi2 - (Psi1 - 7 kappa), Psi1 >= {sliding_threshold(nu):.3f}, max",
            "-",
            0.0,
            source,
            line,
            1e-7,
            why,
            "max",
        ),
        Check("R omega2 / (5 mu v_n) - 1 in gross sliding, max", "-", 0.0, source, spin, 1e-7, why, "max"),
    ]


def reference_curve(n: int = 100) -> dict:
    """The independent integration's Psi2 on n Psi1 from 0.05 to 10, with where it crosses
    zero and its minimum (Psi1, Psi2), refined on the grid by a parabola."""
    grid = np.linspace(0.05, 10.0, n)
    psi2 = np.array([reference_of(float(p)).psi2 for p in grid])
    k = int(np.argmin(psi2))
    y0, y1, y2 = psi2[k - 1 : k + 2]
    shift = 0.5 * (y0 - y2) / (y0 - 2.0 * y1 + y2)
    h = grid[1] - grid[0]
    up = int(np.flatnonzero((psi2[:-1] > 0.0) & (psi2[1:] <= 0.0))[0])
    zero = grid[up] + h * psi2[up] / (psi2[up] - psi2[up + 1])
    return {
        "psi1": grid.tolist(),
        "psi2": psi2.tolist(),
        "zero": float(zero),
        "min_psi1": float(grid[k] + shift * h),
        "min_psi2": float(y1 - 0.25 * (y0 - y2) * shift),
        "stick_limit": reference_of(0.01).psi2 / 0.01,
    }


def _description(nu: float) -> str:
    kappa = stiffness_ratio(nu)
    return (
        "A steel sphere (R = 1 mm, E = 200 GPa, nu = 0.3, no spin) meets a rigid floor at the normal speed "
        f"v_n = {V_N:g} m/s and {len(PSI1)} tangential speeds (Thornton et al. 2011's test of a constant normal "
        'and a varying tangential speed), mu = 0.3, undamped Hertz, contact.tangential_law = "mindlin" '
        '(docs/model.md section 3.16), the scheme "verlet" at 2 ns (the contact lasts 7.4 us). Its rebound in '
        "Maw, Barber & Fawcett's and Di Renzo & Di Maio's normalised angles, Psi = 2 (1 - nu) / (mu (2 - nu)) "
        "v_c / v_n (v_c: the contact point's tangential speed; Psi2 over the incident v_n), against: the "
        "independent integration of the same continuous law (`oblique_mindlin.reference_impact`); the "
        f"gross-sliding line Psi2 = Psi1 - 7 kappa (kappa = 2 (1 - nu)/(2 - nu) = {kappa:.4f}) from Psi1 >= "
        f"7 kappa - 1/3 = {sliding_threshold(nu):.4f}, derived for this law in docs/model.md section 3.16; "
        "and LAMMPS's `fix wall/gran granular hertz/material ... tangential mindlin_rescale` at the same step. "
        "Sources: N. Maw, J. R. Barber, J. N. Fawcett, Wear 38 (1976) 101-114 and J. Lubr. Technol. 103 (1981) "
        "74-80; A. Di Renzo, F. P. Di Maio, Chem. Eng. Sci. 59 (2004) 525-541 and 60 (2005) 1303-1312; "
        "C. Thornton, S. J. Cummins, P. W. Cleary, Powder Technol. 210 (2011) 189-197."
    )


def _notes(nu: float, conv: dict, with_lammps: bool, curve: dict) -> list[str]:
    orders = ", ".join(f"Psi1 = {p:g}: {c:.2e} -> {f:.2e}" for p, (c, f) in conv.items())
    notes = [
        f"Step halved (2 ns -> 1 ns), |Psi2 - reference|: {orders} (first order where stick and slip switch; "
        "LAMMPS, run the same way, agrees with granplate to round-off, so the error is the shared scheme's).",
        f"The curve of this law (independent integration): Psi2 = {curve['stick_limit']:.4f} Psi1 as Psi1 -> 0 "
        f"(e_t = -v_c2 / v_c1 -> {-curve['stick_limit']:.4f}: the contact point does not reverse), Psi2 < 0 from "
        f"Psi1 = {curve['zero']:.3f}, a minimum Psi2 = {curve['min_psi2']:.3f} at Psi1 = {curve['min_psi1']:.2f}, "
        f"the sliding line from Psi1 = {sliding_threshold(nu):.4f} (where Psi2 = -1/3).",
        "Against Maw, Barber & Fawcett (Mindlin-Deresiewicz partial slip): they find Psi2 < 0 at low Psi1 (1981, "
        "a thin diametral slice) and "
        "gross slip over a wider range than rigid-body theory's; this law reproduces the reversal and the "
        "widened sliding range but not the small-Psi1 end, where its spring (no micro-slip, stiffness 8 G* a "
        "up to the cap, the displacement rescaled with a while unloading) returns the contact point forward. "
        "docs/model.md section 3.16 says how the laws differ; no published value is compared.",
    ]
    if not with_lammps:
        notes.append("LAMMPS is not installed here (pip install granplate[lammps]): its checks were not run.")
    return notes


def _table(ours: list, ref: list) -> str:
    rows = [
        "| Psi1 | regime | Psi2 reference | Psi2 granplate | diff | e_t | R omega2 / v_n | v_n2 / v_n |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for p, o, r in zip(PSI1, ours, ref):
        rows.append(
            f"| {p:g} | {regime(p)} | {r.psi2:+.6f} | {o.psi2:+.6f} | {o.psi2 - r.psi2:+.1e} | {o.e_t:+.5f} | "
            f"{RADIUS * o.omega2 / V_N:.6f} | {o.v_n2 / V_N:.8f} |"
        )
    return "\n".join(rows)


def draw_mindlin_curve(p: dict):
    """Psi2 against Psi1: the reference line, granplate, LAMMPS, the sliding line."""
    fig, axes = new_figure(width=6.4, height=4.4)
    ax = axes[0, 0]
    curve = p["curve"]
    nu = p["nu"]
    ax.plot(curve["psi1"], curve["psi2"], "k-", lw=2.5, alpha=0.3, label="independent integration")
    ax.plot(p["psi1"], p["ours"], "C0o", ms=5, mfc="none", label="granplate (verlet, 2 ns)")
    ax.plot(p["pair_psi1"], p["pair"], "C1s", ms=5, mfc="none", label="granplate, two equal spheres (normal turns)")
    if p["lammps_psi1"]:
        ax.plot(p["lammps_psi1"], p["lammps"], "C3x", ms=8, label="LAMMPS mindlin_rescale (2 ns)")
    x = np.array([sliding_threshold(nu) - 2.0, 10.0])
    ax.plot(x, sliding_line(x, nu), "C2--", lw=1, label="gross sliding: Psi2 = Psi1 - 7 kappa")
    ax.axvline(sliding_threshold(nu), color="C2", lw=0.6, ls=":")
    ax.axhline(0.0, color="0.5", lw=0.5)
    ax.set_xlabel("Psi1 = 2(1-nu)/(mu(2-nu)) v_c1 / v_n  [-]")
    ax.set_ylabel("Psi2 = 2(1-nu)/(mu(2-nu)) v_c2 / v_n  [-]")
    ax.set_title("Oblique impacts under Mindlin friction (steel, nu = 0.3, mu = 0.3)", fontsize=9)
    ax.legend(fontsize=8)
    return fig


CASES: tuple[Case, ...] = (
    Case(
        "mindlin-oblique-curve",
        "space",
        "Mindlin friction on the whole oblique-impact curve: Psi2(Psi1) vs an independent integration, LAMMPS",
        mindlin_curve,
        draw=draw_mindlin_curve,
    ),
)
