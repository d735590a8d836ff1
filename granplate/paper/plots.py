"""The paper's figures (section 3 and Appendix A), drawn from result Datasets.

One function per figure, each `fig_N(datasets...) -> matplotlib Figure`, drawing only
the numbers in the datasets it is given (through `granplate.analysis`), with units on
every axis and a caption line naming the runs. `FIGURES` says which presets each figure
takes; `save_figure` writes a PNG and a PDF.

    >>> from granplate.paper import plots
    >>> fig = plots.fig_3(gp.read("bare-plate.nc"), gp.read("steel-r1.nc"))
    >>> plots.save_figure(fig, "out", "fig3")

Figures are built with `matplotlib.figure.Figure` on the Agg canvas (no pyplot, no
global state, no display needed). Every plotted line / image carries a `gid` naming
what it shows (e.g. "energy:plate", "vx:3", "vx:column1"), which the tests use to check
that a figure shows its dataset's own numbers.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass
from typing import Callable

import numpy as np
import xarray as xr
from matplotlib.colors import Normalize
from matplotlib.figure import Figure

from granplate.figures.common import PNG_DPI, save_figure  # noqa: F401 - part of this module's interface
from granplate.figures.common import new_figure as _new_figure
from granplate.paper import plastic as _plastic
from granplate.paper import space as _space
from granplate.results import analysis as an
from granplate.setup.presets import PLANE_PRESETS

#: The granules whose velocities the paper plots (Figs. 4e-f, 5c).
VELOCITY_GRANULES = ("3", "8", "C")

#: The plate contacts of Fig. A.1.
LAMBDA_CONTACTS = ("A", "B", "C")

#: Line colours, fixed per quantity so the figures read alike.
COLOURS = {
    "granular": "tab:blue",
    "plate": "tab:red",
    "sum": "tab:purple",
    "total": "black",
    "horizontal": "tab:blue",
    "vertical": "tab:orange",
    "rotational": "tab:green",
    "3": "tab:blue",
    "8": "tab:orange",
    "C": "tab:green",
}
STYLES = {"total": "--", "sum": "-."}
#: Two curves of a panel coincide when they differ by less than this fraction of its
#: largest value: far below a pixel (the vy of granules 3 and C, zero by symmetry, is
#: 1e-9 of granule 8's in the runs: the solver's round-off and tolerances).
COINCIDE = 1e-6
#: Markers of a curve drawn over an identical one (so that both stay visible).
MARKERS = ("o", "s", "^", "v", "D")


@dataclass(frozen=True)
class FigureSpec:
    """A paper figure: its drawing function, the presets it takes (in order), its title
    and what it needs of every result it is given (keys of REQUIREMENTS)."""

    function: Callable[..., Figure]
    presets: tuple[str, ...]
    title: str
    needs: tuple[str, ...] = ("plate",)


# --------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------
def _name(ds: xr.Dataset) -> str:
    return str(ds.attrs.get("scenario_name", "result"))


def _t_end_ms(ds: xr.Dataset) -> float:
    return float(ds["time"].values[-1]) * 1e3


def _normal_law(ds: xr.Dataset) -> str:
    """The run's contact.normal_law, in words ("Hertz contacts", "Thornton contacts")."""
    from granplate.results.dataset import scenario_of

    try:
        law = scenario_of(ds).contact.normal_law
    except Exception:  # noqa: BLE001 - a result without its scenario: the law is unknown
        return "contact law unknown"
    return f"{str(law).capitalize()} contacts"


def run_labels(datasets) -> list[str]:
    """Each run's label in a caption: its name and t_end, and its contact law where two runs
    share a name (a preset and its twin with yielding contacts)."""
    names = [_name(d) for d in datasets]
    return [
        f"{n} ({_normal_law(d) + ', ' if names.count(n) > 1 else ''}t_end = {_t_end_ms(d):.3g} ms)"
        for n, d in zip(names, datasets)
    ]


def _caption(fig: Figure, text: str, *datasets: xr.Dataset) -> None:
    """A caption line under the panels: what is shown, and which runs it comes from."""
    runs = ", ".join(run_labels(datasets))
    version = datasets[0].attrs.get("granplate_version", "?") if datasets else "?"
    full = f"{text}  Runs: {runs}; granplate {version}."
    width = int(fig.get_figwidth() * 15)
    fig.supxlabel(textwrap.fill(full, width), fontsize=8, ha="center")
    fig._granplate_caption = full  # for tests and the report


def caption_of(fig: Figure) -> str:
    """The caption text given to a figure (empty if none)."""
    return getattr(fig, "_granplate_caption", "")


def _label(ax, text: str) -> None:
    ax.set_title(text, loc="left", fontsize=10)


def _time_axis(ax, ds: xr.Dataset) -> None:
    ax.set_xlabel("time [ms]")
    ax.set_xlim(0.0, _t_end_ms(ds))
    ax.grid(True, lw=0.3, alpha=0.5)


def energy_panel(ax, ds: xr.Dataset, legend: bool = True) -> None:
    """Normalised energies E_g, E_p, E_g + E_p, E_g + E_p + D vs time (Figs. 3c, 4a-b, 5a, 8)."""
    t = an.times_ms(ds)
    e = an.normalised_energies(ds)
    for key, label in an.ENERGY_CURVES.items():
        ax.plot(t, e[key], color=COLOURS[key], ls=STYLES.get(key, "-"), lw=1.2, label=label, gid=f"energy:{key}")
    ax.set_ylabel("energy / $E_{shock}$ [-]")
    ax.set_ylim(-0.02, 1.08)
    _time_axis(ax, ds)
    if legend:
        ax.legend(fontsize=7, loc="center right", framealpha=0.8)


def kinetic_panel(ax, ds: xr.Dataset, legend: bool = True) -> None:
    """Granular kinetic energy split into horizontal, vertical and rotational parts [mJ]."""
    t = an.times_ms(ds)
    for key, arr in an.kinetic_split(ds).items():
        ax.plot(t, arr * 1e3, color=COLOURS[key], lw=1.0, label=an.KINETIC_PARTS[key], gid=f"kinetic:{key}")
    ax.set_ylabel("kinetic energy [mJ]")
    _time_axis(ax, ds)
    if legend:
        ax.legend(fontsize=7, loc="upper right", framealpha=0.8)


def velocity_panel(ax, ds: xr.Dataset, component: str, labels=VELOCITY_GRANULES, legend: bool = True) -> None:
    """Velocity component ("vx" or "vy") of the given granules [m/s] vs time.

    A curve equal to one drawn before it, within COINCIDE of the panel's largest value
    (granules 3 and C move only horizontally, their vy is 0 by symmetry), is drawn
    dashed with markers on top of it, and its legend entry says which curve it equals.
    """
    t = an.times_ms(ds)
    curves = {lab: np.asarray(ds[component].values[:, an.granule_index(ds, lab)]) for lab in labels}
    tiny = COINCIDE * max((float(np.max(np.abs(y))) for y in curves.values()), default=0.0)
    drawn: dict[str, np.ndarray] = {}
    lines: dict[str, object] = {}
    for k, (lab, y) in enumerate(curves.items()):
        same = next((other for other, prev in drawn.items() if np.max(np.abs(prev - y)) <= tiny), None)
        label, style = f"granule {lab}", {"ls": "-"}
        if same is not None:
            label += f" (= granule {same}{', both ~0' if np.max(np.abs(y)) <= tiny else ''})"
            style = {
                "ls": (0, (4, 3)),
                "marker": MARKERS[k % len(MARKERS)],
                "ms": 3.5,
                "markevery": max(1, len(t) // 15),
                "zorder": 3,
            }
        (line,) = ax.plot(t, y, color=COLOURS.get(lab), lw=0.9, label=label, gid=f"{component}:{lab}", **style)
        if same is not None:
            lines[same].set_linewidth(2.4)  # the curve underneath shows around the dashes
        drawn[lab], lines[lab] = y, line
    word = "horizontal" if component == "vx" else "vertical"
    ax.set_ylabel(f"{word} velocity [m/s]")
    _time_axis(ax, ds)
    if legend:
        ax.legend(fontsize=7, loc="upper right", framealpha=0.8, ncols=len(labels))


def von_mises_panel(ax, ds: xr.Dataset) -> None:
    """Maximum von Mises stress in the plate [MPa] vs time."""
    ax.plot(an.times_ms(ds), ds["max_von_mises"].values / 1e6, color="tab:red", lw=0.9, gid="max_von_mises")
    ax.set_ylabel("max von Mises stress [MPa]")
    _time_axis(ax, ds)


# --------------------------------------------------------------------------------------
# The figures
# --------------------------------------------------------------------------------------
def fig_3(bare: xr.Dataset, granular: xr.Dataset) -> Figure:
    """Fig. 3: max von Mises stress (a) bare plate, (b) with granules; (c) energies."""
    fig = _new_figure(10.0, 7.0)
    ax = fig.subplot_mosaic("ab;cc")
    von_mises_panel(ax["a"], bare)
    _label(ax["a"], f"(a) no granules ({_name(bare)})")
    von_mises_panel(ax["b"], granular)
    _label(ax["b"], f"(b) with granules ({_name(granular)})")
    energy_panel(ax["c"], granular)
    _label(ax["c"], f"(c) normalised energies ({_name(granular)})")
    _caption(
        fig,
        "Fig. 3. Maximum von Mises stress in the plate, shock on the bare plate (a) and on "
        "the granular medium (b); (c) energies of the granular medium, the plate, their sum and "
        "the sum with dissipation D, over the shock energy E_shock.",
        bare,
        granular,
    )
    return fig


def fig_4(same_size: xr.Dataset, small: xr.Dataset) -> Figure:
    """Fig. 4: R2 = R1 (left) vs R2 = 0.5 R1 (right): energies, kinetic split, velocities."""
    fig = _new_figure(11.0, 12.0)
    ax = fig.subplot_mosaic([["a", "b"], ["c", "d"], ["e", "f"], ["g", "h"]])
    for ds, (a, c, e, g) in ((same_size, "aceg"), (small, "bdfh")):
        tag = _name(ds)
        energy_panel(ax[a], ds)
        _label(ax[a], f"({a}) normalised energies, {tag}")
        kinetic_panel(ax[c], ds)
        _label(ax[c], f"({c}) granular kinetic energy, {tag}")
        velocity_panel(ax[e], ds, "vx")
        _label(ax[e], f"({e}) horizontal velocities, {tag}")
        velocity_panel(ax[g], ds, "vy")
        _label(ax[g], f"({g}) vertical velocities, {tag}")
    for row in (("c", "d"), ("e", "f"), ("g", "h")):
        _share_y(ax[row[0]], ax[row[1]])
    _caption(
        fig,
        "Fig. 4. Two intruder sizes, R2 = R1 (left) and R2 = 0.5 R1 (right): (a, b) energies "
        "over E_shock; (c, d) kinetic energy of the granular medium, horizontal / vertical / "
        "rotational; (e, f) horizontal and (g, h) vertical velocities of granules 3, 8 and C (the "
        "paper's panels e-f). A curve equal to another (3 and C: no vertical motion, by symmetry) "
        "is dashed with markers.",
        same_size,
        small,
    )
    return fig


def _share_y(a, b) -> None:
    lo = min(a.get_ylim()[0], b.get_ylim()[0])
    hi = max(a.get_ylim()[1], b.get_ylim()[1])
    a.set_ylim(lo, hi)
    b.set_ylim(lo, hi)


def fig_5(ptfe: xr.Dataset) -> Figure:
    """Fig. 5: PTFE intruders: energies, kinetic split, velocities of granules 3, 8, C."""
    fig = _new_figure(11.0, 7.5)
    ax = fig.subplot_mosaic([["a", "b"], ["c", "d"]])
    tag = _name(ptfe)
    energy_panel(ax["a"], ptfe)
    _label(ax["a"], f"(a) normalised energies, {tag}")
    kinetic_panel(ax["b"], ptfe)
    _label(ax["b"], f"(b) granular kinetic energy, {tag}")
    velocity_panel(ax["c"], ptfe, "vx")
    _label(ax["c"], "(c) horizontal velocities")
    velocity_panel(ax["d"], ptfe, "vy")
    _label(ax["d"], "(d) vertical velocities")
    _caption(
        fig,
        "Fig. 5. PTFE intruders, R2 = 0.5 R1: (a) energies over E_shock; (b) kinetic energy "
        "of the granular medium, horizontal / vertical / rotational; (c) horizontal and (d) vertical "
        "velocities of granules 3, 8 and C (the paper's panel c). A curve equal to another (3 and C: no "
        "vertical motion, by symmetry) is dashed with markers.",
        ptfe,
    )
    return fig


def space_time_parts(ds: xr.Dataset) -> list[tuple[str, list[str], np.ndarray, np.ndarray]]:
    """The four parts of a Fig. 6 map: (name, tick labels, positions, vx (time, position)).

    Columns 1, 2, 3 of the packing (granules top to bottom, as in the paper's numbering)
    and the plate's symmetry line (positions: x from the plate's left edge [mm]).
    """
    parts = []
    for k, col in enumerate(an.columns(ds), start=1):
        idx = [an.granule_index(ds, lab) for lab in col]
        parts.append((f"column {k}", col, np.arange(len(col), dtype=float), ds["vx"].values[:, idx]))
    xs = np.asarray(ds["x_symmetry"].values, float)
    parts.append(("plate, y = H/2", [], (xs - xs.min()) * 1e3, np.asarray(ds["plate_vx_symmetry"].values)))
    return parts


def fig_6(steel: xr.Dataset, ptfe: xr.Dataset) -> Figure:
    """Fig. 6: space-time maps of horizontal velocity, columns 1-3 and the plate."""
    fig = _new_figure(12.0, 9.5)
    rows = fig.subfigures(2, 1)
    for sub, ds, letter in zip(rows, (steel, ptfe), "ab"):
        parts = space_time_parts(ds)
        widths = [max(len(p[2]), 3) if p[1] else 3 for p in parts]
        axes = sub.subplots(1, len(parts), sharey=True, gridspec_kw={"width_ratios": widths})
        vmax = max(float(np.max(np.abs(p[3]))) for p in parts) or 1.0
        norm = Normalize(-vmax, vmax)
        t = an.times_ms(ds)
        mesh = None
        for c, (ax, (name, ticks, pos, vx)) in enumerate(zip(axes, parts)):
            mesh = ax.pcolormesh(pos, t, vx, shading="nearest", cmap="RdBu_r", norm=norm, rasterized=True)
            mesh.set_gid(f"vx:column{c + 1}" if ticks else "vx:plate")
            if ticks:
                ax.set_xticks(pos, ticks)
                ax.set_xlabel("granule [-]")
            else:
                ax.set_xlabel("x from plate edge [mm]")
            ax.set_title(name, fontsize=9)
            ax.set_ylim(0.0, t[-1])
        axes[0].set_ylabel("time [ms]")
        sub.colorbar(mesh, ax=list(axes), label="horizontal velocity [m/s]", shrink=0.95, pad=0.01)
        sub.suptitle(f"({letter}) {_name(ds)}", x=0.02, ha="left", fontsize=10)
    _caption(
        fig,
        "Fig. 6. Horizontal velocity over time of every granule (columns 1, 2, 3; granules top "
        "to bottom) and along the plate's symmetry line y = H/2: (a) steel intruders, (b) PTFE "
        "intruders, both R2 = 0.5 R1; one colour scale per row.",
        steel,
        ptfe,
    )
    return fig


def fig_7(steel: xr.Dataset, ptfe: xr.Dataset) -> Figure:
    """Fig. 7: maximum |eps_yy| in the plate vs time, (a) steel (b) PTFE intruders."""
    fig = _new_figure(10.0, 3.8)
    axes = fig.subplots(1, 2, sharey=True)
    for ax, ds, letter in zip(axes, (steel, ptfe), "ab"):
        ax.plot(an.times_ms(ds), ds["max_eps_yy"].values * 1e6, color="tab:red", lw=0.9, gid="max_eps_yy")
        _time_axis(ax, ds)
        _label(ax, f"({letter}) {_name(ds)}")
    axes[0].set_ylabel(r"max $|\varepsilon_{yy}|$ in the plate [$10^{-6}$]")
    _caption(
        fig,
        "Fig. 7. Maximum vertical strain |eps_yy| in the plate (microstrain), (a) steel "
        "intruders, (b) PTFE intruders, both R2 = 0.5 R1; same vertical scale.",
        steel,
        ptfe,
    )
    return fig


def fig_8(weak: xr.Dataset, moderate: xr.Dataset, strong: xr.Dataset) -> Figure:
    """Fig. 8: normalised energies at three shock intensities (PTFE intruders)."""
    fig = _new_figure(13.0, 4.0)
    axes = fig.subplots(1, 3, sharey=True)
    cases = (weak, moderate, strong)
    ep_top = max(float(an.normalised_energies(ds)["plate"].max()) for ds in cases) * 1.15 or 1.0
    for ax, ds, letter, word in zip(axes, cases, "abc", ("weak", "moderate", "strong")):
        energy_panel(ax, ds, legend=False)
        q0 = _q0(ds)
        _label(ax, f"({letter}) {word}: q0 = {q0 / 1e3:g} kN/m")
        inset = ax.inset_axes([0.33, 0.2, 0.62, 0.36])
        inset.plot(
            an.times_ms(ds),
            an.normalised_energies(ds)["plate"],
            color=COLOURS["plate"],
            lw=1.0,
            gid="energy-zoom:plate",
        )
        inset.set_ylim(0.0, ep_top)
        inset.set_xlim(0.0, _t_end_ms(ds))
        inset.set_title("plate $E_p$ / $E_{shock}$ [-], zoom", fontsize=7)
        inset.set_xlabel("time [ms]", fontsize=7, labelpad=1)
        inset.tick_params(labelsize=6)
        inset.grid(True, lw=0.3, alpha=0.5)
    for ax in axes[1:]:
        ax.set_ylabel("")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside upper center", ncols=len(labels), fontsize=8)
    _caption(
        fig,
        "Fig. 8. Energies over E_shock for PTFE intruders (R2 = 0.5 R1) under (a) weak, "
        "(b) moderate and (c) strong shocks.",
        weak,
        moderate,
        strong,
    )
    return fig


def _scenario(ds: xr.Dataset):
    from granplate.results.dataset import scenario_of

    return scenario_of(ds)


def _q0(ds: xr.Dataset) -> float:
    """The shock amplitude q0 [N/m] of the run."""
    return float(_scenario(ds).load.q0)


def _lambda_target(ds: xr.Dataset) -> float:
    """The local-map modulus the run's step control aimed for [-]."""
    return float(_scenario(ds).solver.lambda_target)


def fig_A1(steel: xr.Dataset) -> Figure:
    """Fig. A.1: modulus of the frictional local map's eigenvalue (eq. 8) at contacts A, B, C."""
    fig = _new_figure(10.0, 6.5)
    axes = fig.subplots(len(LAMBDA_CONTACTS), 1, sharex=True)
    contacts = [str(c) for c in steel["contact"].values]
    target = _lambda_target(steel)
    paper = _scenario(steel).solver.scheme == "paper"
    top = max(1.1, 1.05 * float(steel["local_map_modulus"].max()))
    t = an.times_ms(steel)
    for ax, lab, letter in zip(axes, LAMBDA_CONTACTS, "abc"):
        k = contacts.index(lab)
        ax.plot(t, steel["local_map_modulus"].values[:, k], color="tab:blue", lw=0.8, gid=f"lambda:{lab}")
        ax.axhline(1.0, color="tab:red", lw=0.8, ls="--", label="stability limit |λ| = 1")
        if paper:
            ax.axhline(target, color="grey", lw=0.8, ls=":", label=f"step-control target {target:g}")
            ax.set_ylim(0.0, 1.1)
        else:  # the implicit scheme's Newton does not need |lambda| < 1
            ax.set_yscale("log")
            ax.set_ylim(1e-4, top)
        ax.set_ylabel(r"$|\lambda|$ [-]")
        ax.grid(True, lw=0.3, alpha=0.5)
        _label(ax, f"({letter}) contact {lab}")
    axes[0].legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("time [ms]")
    axes[-1].set_xlim(0.0, t[-1])
    _caption(
        fig,
        "Fig. A.1. Largest modulus (per output interval) of the eigenvalue of the frictional "
        "local map, eq. (8), at the plate contacts of granules A, B and C; below 1 the paper's "
        "fixed-point iteration converges"
        + (
            "; the adaptive time step holds it near the target."
            if paper
            else ". This run used the implicit scheme (Newton), which needs "
            "no such bound: its steps give |λ| >> 1; run with "
            'solver.scheme = "paper" for the paper\'s figure.'
        ),
        steel,
    )
    return fig


def fig_yielding(elastic: xr.Dataset, plastic: xr.Dataset, measured: xr.Dataset | None = None) -> Figure:
    """The plate's energy E_p [mJ] over time with elastic (Hertz) and yielding (Thornton;
    and the law "johnson" where `measured` is given) contacts (a), and where the shock
    energy goes in each: E_g and D_plastic [mJ] (b)."""
    fig = _new_figure(10.0, 4.2)
    ax = fig.subplot_mosaic("ab")
    runs = [("elastic", elastic, "-"), ("thornton", plastic, "--")]
    if measured is not None:
        runs.append(("johnson", measured, ":"))
    for tag, ds, ls in runs:
        for key, var, colour in (("a", "E_plate", "plate"), ("b", "E_granular", "granular")):
            ax[key].plot(
                an.times_ms(ds),
                np.asarray(ds[var].values) * 1e3,
                color=COLOURS[colour],
                ls=ls,
                lw=1.2,
                label=f"${'E_p' if key == 'a' else 'E_g'}$, {tag} contacts",
                gid=f"{colour}:{tag}",
            )
    for tag, ds, ls in runs[1:]:
        ax["b"].plot(
            an.times_ms(ds),
            np.asarray(ds["D_plastic"].values) * 1e3,
            color="tab:brown",
            ls=ls,
            lw=1.2,
            label=f"$D_{{plastic}}$, {tag} contacts",
            gid=f"plastic:{tag}",
        )
    for key, text in (("a", "(a) plate energy"), ("b", "(b) granular energy and plastic work")):
        _time_axis(ax[key], elastic)
        ax[key].set_ylabel("energy [mJ]")
        ax[key].legend(fontsize=7, loc="best", framealpha=0.8)
        _label(ax[key], f"{text}, {_name(elastic)}")
    third = ' and the law "johnson" (contact.normal_law = "johnson", dotted)' if measured is not None else ""
    _caption(
        fig,
        "The plate's energy (a) and the granular energy with the plastic work (b), elastic "
        '(Hertz, solid) and yielding contacts: Thornton\'s law (contact.normal_law = "thornton", dashed)'
        f"{third}; the later runs are the first's twins with yielding contacts.",
        *(ds for _, ds, _ in runs),
    )
    return fig


def fig_3d(*datasets: xr.Dataset) -> Figure:
    """The plate's share of the shock energy E_p / E_shock [-] over time [ms], each case in
    2D (solid) and in 3D (its twin, dashed), one panel per case: the first half of
    `datasets` are the 2D results, the second half their 3D twins in the same order."""
    n = len(datasets) // 2
    if n == 0 or len(datasets) != 2 * n:
        raise ValueError(f"fig_3d takes the 2D results and their 3D twins, as many of each; got {len(datasets)}")
    plane, space = datasets[:n], datasets[n:]
    ncols = min(3, n)
    nrows = -(-n // ncols)
    fig = _new_figure(4.2 * ncols, 3.0 * nrows + 0.9)
    axes = np.atleast_1d(fig.subplots(nrows, ncols, squeeze=False).ravel())
    for k, (ax, a, b) in enumerate(zip(axes, plane, space)):
        name = _name(a)
        for tag, ds, ls, colour in (("2d", a, "-", COLOURS["plate"]), ("3d", b, "--", "black")):
            ax.plot(
                an.times_ms(ds),
                an.normalised_energies(ds)["plate"],
                color=colour,
                ls=ls,
                lw=1.2,
                label=f"{tag.upper()}",
                gid=f"plate:{tag}:{name}",
            )
        ax.set_ylabel("$E_p$ / $E_{shock}$ [-]")
        _time_axis(ax, a)
        _label(ax, f"({'abcdefghijklmnopqrstuvwxyz'[k % 26]}) {name}")
        ax.legend(fontsize=7, loc="best", framealpha=0.8)
    for ax in axes[n:]:
        ax.set_visible(False)
    _caption(
        fig,
        "The plate's energy over the shock energy put in, each case in 2D (plane stress, implicit "
        "scheme; solid) and its 3D twin (a hex20 slab, velocity Verlet; dashed), docs/model.md section 8.1.",
        *datasets,
    )
    return fig


#: What a figure may need of a result: a test of the Dataset and its words.
REQUIREMENTS: dict[str, tuple[Callable[[xr.Dataset], bool], str]] = {
    "plate": (an.has_plate, "a plate"),
    "velocity granules": (
        lambda ds: (
            an.has_granules(ds) and all(lab in {str(g) for g in ds["granule"].values} for lab in VELOCITY_GRANULES)
        ),
        "granules " + ", ".join(VELOCITY_GRANULES[:-1]) + " and " + VELOCITY_GRANULES[-1],
    ),
    "columns and symmetry line": (
        lambda ds: an.has_granules(ds) and ds.sizes.get("x_symmetry", 0) > 0,
        "granules and the plate's symmetry line",
    ),
    "lambda contacts": (
        lambda ds: (
            "contact" in ds.dims and all(lab in {str(c) for c in ds["contact"].values} for lab in LAMBDA_CONTACTS)
        ),
        "plate contacts " + ", ".join(LAMBDA_CONTACTS[:-1]) + " and " + LAMBDA_CONTACTS[-1],
    ),
}

_GRANULAR = ("plate", "velocity granules")

#: Figure name -> function and the presets it takes (docs/model.md section 8).
FIGURES: dict[str, FigureSpec] = {
    "3": FigureSpec(fig_3, ("bare-plate", "steel-r1"), "von Mises stress and energies, bare plate vs granules"),
    "4": FigureSpec(fig_4, ("steel-r1", "steel-r05"), "two intruder sizes", _GRANULAR),
    "5": FigureSpec(fig_5, ("ptfe-r05",), "PTFE intruders", _GRANULAR),
    "6": FigureSpec(
        fig_6,
        ("steel-r05", "ptfe-r05"),
        "space-time maps of horizontal velocity",
        ("plate", "columns and symmetry line"),
    ),
    "7": FigureSpec(fig_7, ("steel-r05", "ptfe-r05"), "maximum eps_yy in the plate"),
    "8": FigureSpec(fig_8, ("ptfe-r05-weak", "ptfe-r05-moderate", "ptfe-r05"), "three shock intensities"),
    "A1": FigureSpec(
        fig_A1, ("steel-r1",), "local-map eigenvalue modulus at contacts A, B, C", ("plate", "lambda contacts")
    ),
}


#: Figures of the report that are not the paper's: key -> spec ("yielding": the PTFE
#: headline case with elastic and yielding contacts, granplate.paper.plastic).
EXTRA_FIGURES: dict[str, FigureSpec] = {
    _plastic.FIGURE_KEY: FigureSpec(
        fig_yielding,
        (
            _plastic.FIGURE_CASE,
            _plastic.twin_name(_plastic.FIGURE_CASE),
            _plastic.twin_name(_plastic.FIGURE_CASE, _plastic.MEASURED_LAW),
        ),
        "plate energy with elastic and yielding contacts (PTFE intruders)",
    ),
}


#: The figure of the report's section "The paper in 3D" (`granplate reproduce --3d`,
#: granplate.paper.space): every preset, then its 3D twin, in preset order.
SPACE_FIGURES: dict[str, FigureSpec] = {
    _space.FIGURE_KEY: FigureSpec(
        fig_3d, (*PLANE_PRESETS, *(_space.twin_name(n) for n in PLANE_PRESETS)), "the plate's energy share in 2D and 3D"
    ),
}


def report_figures(plastic: bool = True, space: bool = False) -> dict[str, FigureSpec]:
    """The figures `granplate reproduce` draws: the paper's, with `plastic` the yielding
    contacts' (EXTRA_FIGURES), with `space` the 3D twins' (SPACE_FIGURES)."""
    return {**FIGURES, **(EXTRA_FIGURES if plastic else {}), **(SPACE_FIGURES if space else {})}


def figure_spec(key: str) -> FigureSpec:
    """The spec of a paper figure (FIGURES) or of another figure of the report
    (EXTRA_FIGURES, SPACE_FIGURES)."""
    return {**FIGURES, **EXTRA_FIGURES, **SPACE_FIGURES}[key]


def check_inputs(key: str, datasets: list[xr.Dataset]) -> None:
    """Raise ScenarioError (one line: the figure, what it needs, what the result lacks)
    when a result cannot make figure `key` (e.g. a custom scenario without granule 3)."""
    from granplate.errors import ScenarioError

    spec = FIGURES[key]
    for ds in datasets:
        lacking = [REQUIREMENTS[n][1] for n in spec.needs if not REQUIREMENTS[n][0](ds)]
        if lacking:
            raise ScenarioError(
                "--figure",
                key,
                f"figure {key} ({spec.title}) needs results with "
                f"{' and '.join(lacking)}, as the paper's {', '.join(spec.presets)} have; "
                f"result '{_name(ds)}' has not",
            )


def figure_key(name: str) -> str:
    """Normalise a figure name ("3", "fig3", "Fig. 3", "A.1", "a1") to a FIGURES key.

    Raises KeyError listing the names when there is no such figure.
    """
    key = str(name).strip().lower().replace("figure", "").replace("fig", "").replace(".", "")
    key = key.replace("_", "").replace(" ", "").upper()
    if key not in FIGURES:
        raise KeyError(name)
    return key


def figure_stem(key: str) -> str:
    """File stem of a figure: fig3, figA1; fig-yielding, fig-3d for the report's own figures."""
    return f"fig{key}" if key in FIGURES else f"fig-{key}"
