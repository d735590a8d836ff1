"""Verification of precompressed chains (docs/model.md sections 3.12-3.13): the case
`precompressed-chain` (the static state against statics: every contact carries F0, its
overlap (F0/A)^(2/3); under gravity F0 plus the weight above; the linear modes against the
chain's closed forms) and the case `solitary-wave-speed` (Nesterenko's solitary wave in a
precompressed chain: its speed against the closed form in the amplitude ratio F_m / F0, over
more than a decade)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .base import Case, CaseResult, Check, Context, new_figure

#: the chain: steel spheres of radius R [m], the precompression F0 [N]
RADIUS = 0.005
F0 = 10.0
#: the solitary waves' chain length and the striker speeds [m/s] that launch them
WAVE_COUNT = 160
STRIKER_SPEEDS = (0.1, 0.2, 0.4, 0.8, 1.5)
#: the contacts (by index from the struck end) over which a wave's speed and amplitude are measured
MEASURED = range(25, 65)
SPEED_RTOL = 0.015


def chain_scenario(count: int, gravity: bool = False, dimer_ratio: float = 1.0):
    """A 3D chain of `count` steel spheres (R = RADIUS) along x between the walls xmin and
    xmax, pressed by F0 from xmax, undamped and frictionless (gravity along -x if asked)."""
    import granplate as gp

    g = "[gravity]\ng = [-9.81, 0.0, 0.0]\n" if gravity else ""
    return gp.loads(f"""
name = "precompressed-chain"
dimension = 3
{g}[layout]
kind = "chain"
count = {count}
radius = {RADIUS!r}
material = "steel"
dimer_ratio = {dimer_ratio!r}
[precompression]
target = "wall xmax"
force = {F0!r}
[contact]
alpha_n = 0.0
mu = 0.0
[solver]
scheme = "verlet"
""")


def nesterenko_speed(c0: float, force_ratio: float) -> float:
    """The speed [m/s] of Nesterenko's solitary wave in a chain precompressed to the linear sound
    speed c0 [m/s], of peak force F_m = force_ratio F0 (Nesterenko, Dynamics of Heterogeneous
    Materials, 2001, section 1.2; Sen et al., Phys. Rep. 462, 21 (2008)):
    V_s = c0 sqrt(4/15 (3 + 2 xi^(5/2) - 5 xi)) / (xi - 1), xi = (F_m / F0)^(2/3) the overlap
    ratio (-> c0 as F_m -> F0)."""
    xi = force_ratio ** (2.0 / 3.0)
    return c0 * math.sqrt(4.0 / 15.0 * (3.0 + 2.0 * xi**2.5 - 5.0 * xi)) / (xi - 1.0)


def chain_constants(model) -> dict:
    """A pressed chain's pair coefficient A [N/m^1.5], contact stiffness k = (3/2) A^(2/3)
    F0^(1/3) [N/m], sphere mass m [kg] and linear sound speed c0 = 2R sqrt(k/m) [m/s]."""
    from granplate.physics.contact import COEF_A

    a = float(model.granular.pair_coef[0, COEF_A])
    k = 1.5 * a ** (2.0 / 3.0) * F0 ** (1.0 / 3.0)
    m = float(model.granular.mass[0])
    return {"A": a, "k": k, "m": m, "c0": 2.0 * RADIUS * math.sqrt(k / m)}


def solitary_wave(speed: float, count: int = WAVE_COUNT, step: float = 5e-8) -> dict:
    """A chain of `count` pressed by F0, its first sphere struck into it at `speed` [m/s]
    (velocity Verlet at `step` [s], at most the output interval 5e-7 s): the
    measured peak force F_m (mean over MEASURED contacts) and the speed of the peak (a least-
    squares line through its arrival times, each the parabola through the largest sample),
    before any reflection from the far wall returns; the contact forces from the positions
    (A delta^(3/2), undamped)."""
    from granplate.model.arrays import build_model
    from granplate.results.run import simulate
    from granplate.setup.geometry import resolve

    s = resolve(chain_scenario(count))
    struck = dataclasses.replace(s.granules[0], vx=speed)
    c = chain_constants(build_model(s))
    t_end = 5e-7 * math.ceil(0.75 * count * 2.0 * RADIUS / c["c0"] / 5e-7)  # the slowest wave reaches 3/4 of it
    s = dataclasses.replace(
        s,
        granules=(struck, *s.granules[1:]),
        time=dataclasses.replace(
            s.time, t_end=t_end, dt_initial=step, dt_max=step, output_interval=5e-7, field_interval=t_end
        ),
    )
    import warnings

    from granplate.errors import YieldWarning

    with warnings.catch_warnings():  # the struck end passes Hertz's yield onset: the case is the elastic law's
        warnings.simplefilter("ignore", YieldWarning)
        ds = simulate(s, progress=False)
    x, t = ds["x"].values, ds["time"].values
    force = c["A"] * np.maximum(2.0 * RADIUS - np.diff(x, axis=1), 0.0) ** 1.5
    times, peaks, where = [], [], []
    for k in MEASURED:
        j = int(np.argmax(force[:, k]))
        if 0 < j < len(t) - 1:
            y0, y1, y2 = force[j - 1, k], force[j, k], force[j + 1, k]
            shift = 0.5 * (y0 - y2) / (y0 - 2.0 * y1 + y2)
            times.append(t[j] + shift * (t[1] - t[0]))
            peaks.append(y1 - 0.25 * (y0 - y2) * shift)
            where.append(0.5 * (x[0, k] + x[0, k + 1]))
    v = float(np.polyfit(times, where, 1)[0])
    fm = float(np.mean(peaks))
    return {
        "striker": speed,
        "ratio": fm / F0,
        "spread": float(np.std(peaks) / fm),
        "speed": v,
        "theory": nesterenko_speed(c["c0"], fm / F0),
        "c0": c["c0"],
    }


def static_checks() -> tuple[list[Check], dict]:
    """The static state and the modes of pressed chains against statics and closed forms."""
    from granplate.model.arrays import build_model
    from granplate.results.modes import chain_band_edges, linear_modes

    m = build_model(chain_scenario(30))
    c = chain_constants(m)
    x = m.initial_state[:, 0]
    overlaps = 2.0 * RADIUS - np.diff(x)
    dev = float(np.max(np.abs(overlaps / (F0 / c["A"]) ** (2.0 / 3.0) - 1.0)))
    heavy = build_model(chain_scenario(30, gravity=True))
    xg = heavy.initial_state[:, 0]
    fg = c["A"] * np.maximum(2.0 * RADIUS - np.diff(xg), 0.0) ** 1.5
    weight = c["m"] * 9.81 * np.arange(29, 0, -1)  # above the contact between k and k + 1 (gravity along -x)
    dev_g = float(np.max(np.abs(fg / (F0 + weight) - 1.0)))
    f = linear_modes(m).frequencies
    fc = chain_band_edges(c["k"], c["m"])["cutoff"]
    dimer = build_model(chain_scenario(40, dimer_ratio=0.7))
    from granplate.physics.contact import COEF_A

    kd = 1.5 * float(dimer.granular.pair_coef[0, COEF_A]) ** (2.0 / 3.0) * F0 ** (1.0 / 3.0)
    edges = chain_band_edges(kd, float(dimer.granular.mass[0]), float(dimer.granular.mass[1]))
    fd = linear_modes(dimer).frequencies
    fd = fd[fd > 0.0]
    in_gap = int(
        np.count_nonzero((fd > edges["acoustic_top"] * (1 + 1e-9)) & (fd < edges["optical_bottom"] * (1 - 1e-9)))
    )
    checks = [
        Check(
            "overlaps of a chain of 30 pressed by F0 = 10 N, largest |delta / (F0/A)^(2/3) - 1|",
            "-",
            0.0,
            "statics: every contact carries F0 (eq. 2)",
            dev,
            1e-8,
            "the minimiser's tolerance on the forces (1e-8 x F0), two thirds of it on the overlaps",
            kind="max",
        ),
        Check(
            "the same chain standing under gravity: largest |N / (F0 + weight above) - 1|",
            "-",
            0.0,
            "statics: each contact carries F0 and the weight of the spheres above it",
            dev_g,
            1e-7,
            "the minimiser's tolerance 1e-8 x F0 on forces of 10-13 N",
            kind="max",
        ),
        Check(
            "the chain's highest frequency against the cut-off f_c = (1/pi) sqrt(k/m)",
            "Hz",
            fc,
            "the monatomic chain's band edge, k = (3/2) A^(2/3) F0^(1/3); between walls twice as stiff "
            "as a pair, the staggered mode sits exactly at it",
            float(f.max()),
            1e-9,
            "the eigensolver's round-off",
        ),
        Check(
            "a dimer chain (radii 1 : 0.7): modes inside its gap",
            "-",
            0.0,
            "the closed-form band edges sqrt(2k/m1)/(2 pi) and sqrt(2k/m2)/(2 pi): no bulk mode between",
            in_gap,
            1.0,
            "at most one surface mode, localised at an end wall, may fall in the gap",
            kind="max",
        ),
    ]
    return checks, {"f": f.tolist(), "fc": fc, "fd": fd.tolist(), "edges": edges}


def precompressed_chain(ctx: Context) -> CaseResult:
    """The static state and the linear modes of pressed chains."""
    checks, plot = static_checks()
    desc = (
        "Chains of steel spheres (R = 5 mm) between two walls, pressed by F0 = 10 N from one "
        "([precompression], docs/model.md section 3.12): the static state's overlaps against (F0/A)^(2/3); "
        "the chain standing on a floor under gravity, each contact's force against F0 plus the weight "
        "above it; the linear modes about the static state (`granplate modes`, section 3.13) against the "
        "monatomic chain's cut-off and a dimer chain's band gap."
    )
    return CaseResult.of(desc, checks, plot=plot)


def solitary_wave_speed(ctx: Context) -> CaseResult:
    """Nesterenko's solitary waves at five amplitudes."""
    rows = [solitary_wave(v) for v in STRIKER_SPEEDS]
    checks = [
        Check(
            f"solitary wave speed at F_m / F0 = {r['ratio']:.3g}",
            "m/s",
            r["theory"],
            "Nesterenko's V_s(F_m / F0) (nesterenko_speed)",
            r["speed"],
            SPEED_RTOL,
            "the closed form is the long-wave (continuum) limit of the discrete chain: 1.5% covers its "
            "error from weak waves (F_m / F0 near 1, wide and slow to form) to strong ones",
        )
        for r in rows
    ]
    ratios = [r["ratio"] for r in rows]
    checks.append(
        Check(
            "the amplitude ratios span a decade: max / min of F_m / F0",
            "-",
            10.0,
            "the case's design",
            max(ratios) / min(ratios),
            10.0,
            "Nesterenko's closed form is to be held over at least a decade of amplitudes, from nearly "
            "linear waves to strongly nonlinear ones",
            kind="min",
        )
    )
    table = "\n".join(
        [
            "| striker [m/s] | F_m / F0 | spread of F_m | speed [m/s] | Nesterenko [m/s] | ratio |",
            "|---|---|---|---|---|---|",
        ]
        + [
            f"| {r['striker']:g} | {r['ratio']:.3f} | {r['spread']:.1e} | {r['speed']:.2f} | {r['theory']:.2f} | "
            f"{r['speed'] / r['theory']:.4f} |"
            for r in rows
        ]
    )
    desc = (
        f"A chain of {WAVE_COUNT} steel spheres (R = 5 mm) pressed by F0 = 10 N between walls (linear sound "
        f"speed c0 = {rows[0]['c0']:.1f} m/s), undamped and frictionless, struck at one end at "
        f"{', '.join(f'{v:g}' for v in STRIKER_SPEEDS)} m/s; each wave's peak force F_m and speed measured "
        f"over contacts {MEASURED.start}-{MEASURED.stop - 1} before any reflection returns, against "
        "Nesterenko's closed form V_s(F_m / F0). The law is Hertz's (elastic) throughout, as the closed "
        "form's: the strongest waves press steel past its yield onset, which the case leaves aside."
    )
    return CaseResult.of(desc, checks, tables=[table], plot={"rows": rows})


def draw_solitary_wave_speed(p: dict):
    """The measured speeds over c0 against Nesterenko's curve, by F_m / F0."""
    fig, axes = new_figure(width=6.0, height=3.8)
    ax = axes[0, 0]
    rows = p["rows"]
    c0 = rows[0]["c0"]
    fr = np.geomspace(1.05, max(r["ratio"] for r in rows) * 1.2, 200)
    ax.plot(fr, [nesterenko_speed(c0, f) / c0 for f in fr], "-", color="0.4", label="Nesterenko")
    ax.plot([r["ratio"] for r in rows], [r["speed"] / c0 for r in rows], "o", label="granplate")
    ax.set_xscale("log")
    ax.set_xlabel("F_m / F0 [-]")
    ax.set_ylabel("V_s / c0 [-]")
    ax.legend(fontsize=8)
    return fig


def draw_precompressed_chain(p: dict):
    """The chain's frequencies with its cut-off, the dimer's with its band edges [kHz]."""
    fig, axes = new_figure(ncols=2, width=4.4, height=3.6)
    a, b = axes[0, 0], axes[0, 1]
    f = np.asarray(p["f"])
    a.plot(np.arange(1, len(f) + 1), f / 1e3, ".", ms=4)
    a.axhline(p["fc"] / 1e3, color="0.4", ls=":", label="cut-off f_c")
    b.plot(np.arange(1, len(p["fd"]) + 1), np.asarray(p["fd"]) / 1e3, ".", ms=4)
    for name, val in p["edges"].items():
        b.axhline(val / 1e3, color="0.4", ls=":", lw=0.8)
    for ax, title in ((a, "monatomic chain of 30"), (b, "dimer chain of 40 (1 : 0.7)")):
        ax.set_xlabel("mode number")
        ax.set_ylabel("frequency [kHz]")
        ax.set_title(title, fontsize=9)
    a.legend(fontsize=8)
    return fig


CASES: tuple[Case, ...] = (
    Case(
        "precompressed-chain",
        "granular",
        "A precompressed chain: its static state and linear modes against statics and the band edges",
        precompressed_chain,
        draw=draw_precompressed_chain,
    ),
    Case(
        "solitary-wave-speed",
        "granular",
        "Nesterenko's solitary wave in a precompressed chain: speed against amplitude",
        solitary_wave_speed,
        slow=True,
        draw=draw_solitary_wave_speed,
    ),
)
