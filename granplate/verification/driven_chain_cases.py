"""Verification of harmonically driven precompressed chains: the case `driven-chain`.

A chain of bearing-steel beads (diameter 9.525 mm, 3/8 inch) between two walls, pressed by
F0 = 10 N from the far wall ([precompression]), its near wall shaken harmonically by a
displacement drive of 1e-10 m (1e-4 of the static overlap: the linear regime). The far
wall's force (`wall_force`) and the beads' positions, measured at the drive's frequency
once the start's transient has died down (a Hann-weighted projection over the record's last
window, `chain_response.lock_in`), are compared with the linear solution written from the
equations in `chain_response` (the chain's tangent stiffness and damping about the static
overlaps, eq. L1, solved at the drive's frequency): below the cut-off the transmitted
amplitude against the finite chain's steady state; above it the beads' amplitudes decay by
the transfer matrix's ratio per bead (the evanescent wave) and the far wall receives almost
nothing. A dimer chain (radii 1 : 0.7) does the same across its band gap.
"""

from __future__ import annotations

import math

import numpy as np

from .base import Case, CaseResult, Check, Context, new_figure
from .chain_response import (
    LinearChain,
    bloch_ratio,
    linear_chain,
    linear_history,
    lock_in,
    steady_displacements,
    transmission,
)

#: the beads: bearing steel, radius [m] (diameter 9.525 mm), the precompression [N]
MATERIAL = "bearing_steel"
RADIUS = 0.0047625
F0 = 10.0
#: eq. (3)'s damping: modal damping ratios from 0.004 (a chain of 20's lowest mode) to 0.06 (the cut-off)
ALPHA_N = 0.1
#: the drive's amplitude [m] (1e-4 of the static overlap 1.2 um), the step and output interval [s]
AMPLITUDE = 1e-10
STEP = 2e-7
OUTPUT = 1e-6
#: the transmitted amplitude in the pass band against the linear steady state (relative)
PASS_RTOL = 1e-3
#: the evanescent decay ratio per bead (or cell) against the transfer matrix's (relative)
DECAY_RTOL = 2e-3
#: above the cut-off (or in the gap) the far wall's amplitude over the drive's k_0 a at most
STOP_FRACTION = 1e-3
#: the far wall's whole force history against the linear response from rest (largest departure / largest value)
HISTORY_TOL = 2e-3
#: the beads (1-based, from the driven wall) over which an evanescent decay is measured
DECAY_BEADS = 5


def driven_scenario(count: int, frequency: float, t_end: float, dimer_ratio: float = 1.0):
    """A 3D chain of `count` beads along x between the walls xmin and xmax, pressed by F0 from
    xmax, the wall xmin driven into it by AMPLITUDE sin(2 pi frequency t) [m]; frictionless,
    damped by ALPHA_N; velocity Verlet at STEP to t_end [s]."""
    import granplate as gp

    return gp.loads(f"""
name = "driven-chain"
dimension = 3
[layout]
kind = "chain"
count = {count}
radius = {RADIUS!r}
material = "{MATERIAL}"
wall_material = "{MATERIAL}"
dimer_ratio = {dimer_ratio!r}
[precompression]
target = "wall xmax"
force = {F0!r}
[[drives]]
target = "wall xmin"
kind = "displacement"
direction = [1.0, 0.0, 0.0]
profile = "harmonic"
amplitude = {AMPLITUDE!r}
frequency = {frequency!r}
label = "shaker"
[contact]
alpha_n = {ALPHA_N!r}
mu = 0.0
[time]
t_end = {t_end!r}
dt_initial = {STEP!r}
dt_max = {STEP!r}
output_interval = {OUTPUT!r}
field_interval = {t_end!r}
[solver]
scheme = "verlet"
""")


def chain_model(count: int, dimer_ratio: float = 1.0) -> LinearChain:
    """The chain linearised about its static state from the closed forms alone: masses
    4/3 pi R^3 rho, Hertz coefficients A = 4/3 E* sqrt(R*) (eqs. 3-4; a wall is rigid, R* = R),
    every contact carrying F0 (chain_response eq. L1)."""
    from granplate.setup.materials import LIBRARY

    mat = LIBRARY[MATERIAL]
    e_one = mat.E / (1.0 - mat.nu**2)  # a sphere against a rigid wall; two spheres: E* = e_one / 2
    radii = np.array([RADIUS * (dimer_ratio if k % 2 else 1.0) for k in range(count)])
    masses = 4.0 / 3.0 * math.pi * radii**3 * mat.rho
    r_pair = radii[:-1] * radii[1:] / (radii[:-1] + radii[1:])
    pair_a = 4.0 / 3.0 * (e_one / 2.0) * np.sqrt(r_pair)
    wall_a = (4.0 / 3.0 * e_one * math.sqrt(radii[0]), 4.0 / 3.0 * e_one * math.sqrt(radii[-1]))
    return linear_chain(masses, pair_a, wall_a, ALPHA_N, F0)


def band_edges(chain: LinearChain) -> dict[str, float]:
    """The bulk band edges [Hz] of the chain's pairs (`results.modes.chain_band_edges`, the closed
    forms): the monatomic cut-off (1/pi) sqrt(k/m), or the dimer's acoustic top
    sqrt(2k/m_heavy) / (2 pi) and optical bottom sqrt(2k/m_light) / (2 pi) (Herbold et al. 2009)."""
    from granplate.results.modes import chain_band_edges

    m = chain.masses
    if np.allclose(m, m[0]):
        return chain_band_edges(float(chain.stiffness[1]), float(m[0]))
    edges = chain_band_edges(float(chain.stiffness[1]), float(m[0]), float(m[1]))
    return {"acoustic_top": edges["acoustic_top"], "optical_bottom": edges["optical_bottom"]}


def driven_response(count: int, frequency: float, settle: float, window: float, dimer_ratio: float = 1.0) -> dict:
    """Run the chain driven at `frequency` [Hz] for settle + window [s] and measure, over the
    last `window`, the amplitudes at the drive's frequency of the far wall's force change
    [N] and of every bead's displacement [m]; beside them the linear steady state's, and the
    same measure of the exact linear response from rest (the transient the window still
    holds)."""
    from granplate.results.run import simulate

    chain = chain_model(count, dimer_ratio)
    omega = 2.0 * math.pi * frequency
    t_end = OUTPUT * math.ceil((settle + window) / OUTPUT)
    ds = simulate(driven_scenario(count, frequency, t_end, dimer_ratio), progress=False)  # bearing steel: elastic
    t = ds["time"].values
    late = t >= t[-1] - window
    force = ds["wall_force"].sel(wall="xmax").values - F0
    x = ds["x"].values
    beads = np.array([lock_in(t[late], x[late, i] - x[0, i], omega) for i in range(count)])
    linear_force, _ = linear_history(chain, omega, AMPLITUDE, t)
    return {
        "frequency": frequency,
        "far": lock_in(t[late], force[late], omega),
        "far_linear": abs(transmission(chain, omega)) * AMPLITUDE,
        "far_linear_window": lock_in(t[late], linear_force[late], omega),
        "beads": beads.tolist(),
        "beads_linear": (np.abs(steady_displacements(chain, omega)) * AMPLITUDE).tolist(),
        "drive_force": float(chain.stiffness[0]) * AMPLITUDE,
        "history": float(np.max(np.abs(force - linear_force)) / np.max(np.abs(linear_force))),
    }


def cell_decay(amplitudes, cell: int) -> float:
    """The mean ratio per cell of `cell` beads of the amplitudes over the first DECAY_BEADS
    cells: (|u_(1 + cell n)| / |u_1|)^(1/n)."""
    n = DECAY_BEADS - 1
    return float((amplitudes[cell * n] / amplitudes[0]) ** (1.0 / n))


def pass_check(row: dict, label: str) -> Check:
    """The transmitted amplitude in a pass band against the linear response from rest, measured
    over the same window (the steady state |T| a plus what is left of the start's transient)."""
    return Check(
        f"{label}: far wall's force amplitude at {row['frequency']:.0f} Hz",
        "N",
        row["far_linear_window"],
        "the exact linear response from rest of the chain's stiffness and damping at the static overlaps "
        "(chain_response.linear_history: the steady state |T(omega)| a and the modes' free decay), measured alike",
        row["far"],
        PASS_RTOL,
        "velocity Verlet's phase error (omega h)^2 / 24 (below 2e-5 at h = 0.2 us) shifts each mode; between "
        "resonances the response moves by that shift over the drive's relative distance to the nearest mode (a "
        "few percent here): up to about 1e-3 (measured 1e-5 to 2.3e-4, four times less at half the step); the "
        "response's nonlinear part is of order a / delta0 = 1e-4",
    )


def stop_checks(row: dict, label: str, chain: LinearChain, cell: int) -> list[Check]:
    """Above the cut-off (or in the gap): the beads' decay per cell against the transfer matrix's
    ratio, and the far wall's amplitude against a fraction of the drive's force k_0 a."""
    omega = 2.0 * math.pi * row["frequency"]
    z = complex(chain.stiffness[1] + 1j * omega * chain.dashpot[1])
    lam = abs(bloch_ratio(chain.masses[:cell], z, omega))
    return [
        Check(
            f"{label}: decay of the bead amplitudes per {'bead' if cell == 1 else 'cell'} at {row['frequency']:.0f} Hz",
            "-",
            lam,
            "|lambda| of the infinite chain's transfer matrix over one cell, lambda + 1/lambda its trace "
            "(chain_response.bloch_ratio)",
            cell_decay(row["beads"], cell),
            DECAY_RTOL,
            f"the first {DECAY_BEADS} cells, far from the far wall (whose reflection adds |lambda|^(2(N - n)) "
            "relative, below 2e-4 there) and the finite chain's end at the drive (one bead's ratio departs from "
            "the infinite chain's by the same order); Verlet's phase error and the linear regime as in the pass band",
        ),
        Check(
            f"{label}: far wall's force amplitude / k_0 a at {row['frequency']:.0f} Hz",
            "-",
            0.0,
            f"the evanescent wave: the linear solution gives {row['far_linear'] / row['drive_force']:.1e}",
            row["far"] / row["drive_force"],
            STOP_FRACTION,
            "in the pass band this ratio is 0.1-1; the force record resolves k_N ulp(x_N) = 3e-10 N, 1e-4 of k_0 a",
            kind="max",
        ),
    ]


def driven_checks(
    count: int,
    below: tuple[float, ...],
    above: tuple[float, ...],
    settle: float,
    window: float,
    dimer: tuple[float, ...] = (),
    dimer_count: int = 0,
) -> tuple[list[Check], dict]:
    """The monatomic chain of `count` driven at the fractions `below` and `above` of its cut-off,
    and (if `dimer` is given: fractions of the way from the acoustic top to the optical bottom,
    negative below the gap) the dimer chain of `dimer_count` (radii 1 : 0.7), each run for
    settle + window [s]."""
    chain = chain_model(count)
    fc = band_edges(chain)["cutoff"]
    rows = {"mono": [], "dimer": []}
    checks: list[Check] = []
    for r in below:
        row = driven_response(count, r * fc, settle, window)
        rows["mono"].append(row)
        checks.append(pass_check(row, f"chain of {count}, {r:g} f_c"))
    for r in above:
        row = driven_response(count, r * fc, settle, window)
        rows["mono"].append(row)
        checks += stop_checks(row, f"chain of {count}, {r:g} f_c", chain, 1)
    edges: dict[str, float] = {}
    if dimer:
        dchain = chain_model(dimer_count, 0.7)
        edges = band_edges(dchain)
        lo, hi = edges["acoustic_top"], edges["optical_bottom"]
        for r in dimer:
            f = lo * (1.0 + r) if r < 0 else lo + r * (hi - lo)
            row = driven_response(dimer_count, f, settle, window, 0.7)
            rows["dimer"].append(row)
            label = f"dimer chain of {dimer_count}, " + ("acoustic band" if r < 0 else "gap")
            checks += [pass_check(row, label)] if r < 0 else stop_checks(row, label, dchain, 2)
    every = rows["mono"] + rows["dimer"]
    checks.append(
        Check(
            "the far wall's force over each whole run against the linear response from rest: largest departure "
            "over its largest value, every run",
            "-",
            0.0,
            "chain_response.linear_history (the steady state and the modes' free decay from rest)",
            max(r["history"] for r in every),
            HISTORY_TOL,
            "Verlet's phase error on the modes the abrupt start rings, largest near the cut-off (measured 8e-4 at "
            "h = 0.2 us, 3e-4 at half the step), Hertz's second harmonic (of order a / delta0 = 1e-4) and the force "
            "record's resolution (3e-10 N) against the smallest records (1e-6 N above the cut-off)",
            kind="max",
        )
    )
    # the far wall's force resolves one ulp of the last bead's position times its contact's stiffness
    floor = float(np.spacing(2.0 * RADIUS * count) * chain.stiffness[-1] / chain.stiffness[0] / AMPLITUDE)
    return checks, {"rows": rows, "fc": fc, "edges": edges, "count": count, "dimer_count": dimer_count, "floor": floor}


def spectrum(chain: LinearChain, fmax: float, n: int = 600) -> dict:
    """|T(omega)| / k_0 [-] of the linear chain on n frequencies up to fmax [Hz] (the figure's curve)."""
    f = np.linspace(fmax / n, fmax, n)
    return {"f": f.tolist(), "T": [abs(transmission(chain, 2.0 * math.pi * x)) / chain.stiffness[0] for x in f]}


def response_table(plot: dict) -> str:
    """One row per run: the far wall's amplitude measured, the linear response from rest measured
    alike, the linear steady state, and the largest departure of the whole force history."""
    lines = [
        "| chain | drive [Hz] | far wall, granplate [N] | linear from rest [N] | linear steady state [N] "
        "| history departure |",
        "|---|---|---|---|---|---|",
    ]
    for key, name in (("mono", f"{plot['count']} beads"), ("dimer", f"dimer, {plot['dimer_count']}")):
        lines += [
            f"| {name} | {r['frequency']:.0f} | {r['far']:.4e} | {r['far_linear_window']:.4e} | "
            f"{r['far_linear']:.4e} | {r['history']:.1e} |"
            for r in plot["rows"][key]
        ]
    return "\n".join(lines)


def driven_chain(ctx: Context) -> CaseResult:
    """A chain of 20 and a dimer chain of 20, driven below and above their band edges."""
    checks, plot = driven_checks(20, (0.3, 0.55, 0.8), (1.2, 1.5), 10e-3, 4e-3, dimer=(-0.5, 0.5), dimer_count=20)
    plot["mono_curve"] = spectrum(chain_model(20), 1.7 * plot["fc"])
    plot["dimer_curve"] = spectrum(chain_model(20, 0.7), 1.3 * plot["edges"]["optical_bottom"])
    notes = [
        f"Cut-off f_c = {plot['fc']:.0f} Hz; the dimer's gap {plot['edges']['acoustic_top']:.0f}-"
        f"{plot['edges']['optical_bottom']:.0f} Hz. The history departure is the largest difference between the "
        "far wall's force and the exact linear response from rest over the whole run, over the latter's largest "
        "value (the nonlinear second harmonic and the step's phase error)."
    ]
    desc = (
        "A chain of 20 bearing-steel beads (diameter 9.525 mm) between two walls, pressed by F0 = 10 N "
        "([precompression]), damped lightly (alpha_n = 0.1), its near wall driven by a harmonic displacement of "
        "1e-10 m (1e-4 of the static overlap) at 0.3, 0.55 and 0.8 of the cut-off f_c = (1/pi) sqrt(k/m) and at "
        "1.2 and 1.5 f_c, run 14 ms (velocity Verlet, h = 0.2 us); the far wall's force and the beads' positions "
        "measured at the drive's frequency over the last 4 ms (a Hann-weighted projection). Below f_c the "
        "transmitted force amplitude is compared with the linear response of the chain's tangent stiffness "
        "k = (3/2) A^(2/3) F0^(1/3) and damping at the static overlaps (the steady state by a direct solve at the "
        "drive's frequency, plus the free decay of its modes from rest, written apart from the time loop), "
        "measured alike; above it the beads' amplitudes must fall by the transfer matrix's ratio per bead and "
        "the far wall receive almost nothing. A dimer chain of 20 (radii 1 : 0.7) likewise, driven in its "
        "acoustic band and in its gap (the ratio per cell of two beads)."
    )
    return CaseResult.of(desc, checks, notes=notes, tables=[response_table(plot)], plot=plot)


def draw_driven_chain(p: dict):
    """The transmission |T| / k_0 of both chains against frequency, the measured points on it."""
    fig, axes = new_figure(ncols=2, width=4.4, height=3.6)
    for ax, key, curve in ((axes[0, 0], "mono", "mono_curve"), (axes[0, 1], "dimer", "dimer_curve")):
        c = p[curve]
        ax.semilogy(np.asarray(c["f"]) / 1e3, c["T"], "-", color="0.4", lw=1, label="linear steady state")
        rows = p["rows"][key]
        ax.semilogy(
            [r["frequency"] / 1e3 for r in rows],
            [max(r["far"], 1e-30) / r["drive_force"] for r in rows],
            "o",
            label="granplate",
        )
        ax.axhline(p["floor"], color="0.6", ls="--", lw=0.8, label="the force record's resolution")
        ax.set_xlabel("drive frequency [kHz]")
        ax.set_ylabel("|F_far| / (k_0 a) [-]")
    axes[0, 0].axvline(p["fc"] / 1e3, color="0.4", ls=":", lw=0.8)
    for v in p["edges"].values():
        axes[0, 1].axvline(v / 1e3, color="0.4", ls=":", lw=0.8)
    axes[0, 0].set_title(f"chain of {p['count']}", fontsize=9)
    axes[0, 1].set_title(f"dimer chain of {p['dimer_count']} (1 : 0.7)", fontsize=9)
    axes[0, 0].legend(fontsize=8)
    return fig


CASES: tuple[Case, ...] = (
    Case(
        "driven-chain",
        "granular",
        "A harmonically driven precompressed chain: the transmitted amplitude below and above the cut-off, "
        "against the linear transfer-matrix solution at small amplitude",
        driven_chain,
        slow=True,
        draw=draw_driven_chain,
    ),
)
