"""The generic figures of any result (`granplate plot RESULT`): one Figure per topic.

- energies: E_shock, E_granular (in space with its part KE_depth), E_plate, dissipation
  D_viscous + D_friction (+ D_plastic where contacts yielded) and their sum in J; the
  same as fractions of the energy put in; the energy-balance residual;
- body-stress: a 3D body's largest von Mises stress and ball average [MPa], max |u| [um];
- body-contact-forces: normal force of each granule on a 3D body [N];
- contact-forces: normal and tangential force at each plate contact [N];
- stress-strain: the plate's largest von Mises stress [MPa] and largest |eps_yy| [-];
- granule-speeds: |v| of each granule [m/s], three components in space (beyond
  MAX_LABELLED granules: the min-max envelope, the median and the fastest few, labelled);
- wall-forces: a run with drives or gravity: the normal force on each wall [N], each
  drive's force [N] and displacement [um].

`missing(name, ds)` says why a run cannot have a figure (no plate, no contacts, no
granules), None when it can; `figures(ds)` builds those it can. Time in ms throughout.

    >>> from granplate.figures import run
    >>> for name, fig in run.figures(ds).items():
    ...     save_figure(fig, "out", f"{ds.attrs['scenario_name']}-{name}")
"""

from __future__ import annotations

import functools

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from granplate.figures.common import new_figure, plot_curves, scenario_name, time_axis
from granplate.results import analysis as an
from granplate.results.dataset import dimension_spec, has_solid

#: Beyond this many granules the speeds are drawn as an envelope.
MAX_LABELLED = 8
#: Granules named on the envelope: the fastest few (largest peak speed).
FASTEST = 3
#: Plate contact forces that differ by less than this fraction of the panel's peak are
#: drawn as coinciding (symmetric contacts agree to round-off of the time loop, ~0.1%).
FORCE_COINCIDE = 0.01
#: An energy below this fraction of the energy put in counts as zero (round-off).
NEGLIGIBLE = 1e-9


def _t_ms(ds: xr.Dataset) -> np.ndarray:
    return an.times_ms(ds)


def _end_ms(ds: xr.Dataset) -> float:
    t = _t_ms(ds)
    return float(t[-1]) if len(t) and t[-1] > 0 else 1.0


def _caption(fig: Figure, ds: xr.Dataset, what: str) -> None:
    fig.suptitle(f"{scenario_name(ds)}: {what}", fontsize=11, x=0.01, ha="left")
    fig.supxlabel(
        f"run {scenario_name(ds)}, t_end = {_end_ms(ds):.4g} ms, scheme {ds.attrs.get('scheme', '?')}, "
        f"granplate {ds.attrs.get('granplate_version', '?')}",
        fontsize=7,
        color="0.35",
    )


def _finish(fig: Figure, ds: xr.Dataset, axes, what: str) -> Figure:
    """Stacked panels over the run's time: each a time axis [ms], the x label on the lowest
    only, and the caption (`_caption`); the figure."""
    for ax in axes:
        time_axis(ax, _end_ms(ds))
    for ax in axes[:-1]:
        ax.set_xlabel("")
    _caption(fig, ds, what)
    return fig


def reference_label(ds: xr.Dataset) -> str:
    """The name of the energy the fractions are of: E_shock for a run from rest, E_initial
    for a run without a load, else E_shock + E_initial (see `analysis.reference_energy`;
    E_shock the work the load put in)."""
    e0 = float(ds.attrs.get("E_initial", 0.0))
    es = float(an.load_work(ds["E_shock"].values)[0][-1]) if ds.sizes.get("time", 0) else 0.0
    total = abs(e0) + abs(es)
    if "E_gravity" in ds or "E_drive" in ds:  # gravity and the drives put energy in too
        return "E_in"
    if abs(e0) <= NEGLIGIBLE * total:
        return "E_shock"
    if abs(es) <= NEGLIGIBLE * total:
        return "E_initial"
    return "E_shock + E_initial"


def has_plastic_work(ds: xr.Dataset) -> bool:
    """Whether contacts yielded in the run (`plastic_work` is not None)."""
    return plastic_work(ds) is not None


def plastic_work(ds: xr.Dataset) -> np.ndarray | None:
    """D_plastic [J] over time when some contact yielded in the run (None under Hertz's
    law, where it is zero throughout)."""
    if "D_plastic" not in ds or not np.any(ds["D_plastic"].values != 0.0):
        return None
    return ds["D_plastic"].values


def energy_curves(ds: xr.Dataset) -> dict[str, tuple[str, np.ndarray]]:
    """key -> (legend label, energy [J] over time) of the energy figure: E_shock when the
    load does work, E_initial (a constant) when the run starts with some, and with both
    E_initial + E_shock, the line the balance closes on (eq. 11), E_granular with granules
    (in space also its part KE_depth, the translation along z), E_plate with a plate or a 3D elastic body, the dissipation D = D_viscous + D_friction
    (+ D_plastic, also drawn alone, when contacts yielded), and the sum of those stored
    and dissipated."""
    out = {}
    e_shock = ds["E_shock"].values
    e0 = float(ds.attrs.get("E_initial", 0.0))
    scale = max(float(np.abs(e_shock).max()), abs(e0))
    loaded = float(np.abs(e_shock).max()) > NEGLIGIBLE * scale
    if loaded:
        out["shock"] = ("$E_{shock}$, work of the load", e_shock)
    if abs(e0) > NEGLIGIBLE * scale:  # the energy present at t = 0 (initial velocities)
        out["initial"] = ("$E_{initial}$, energy at t = 0", np.full(len(e_shock), e0))
        if loaded:  # what E_p + E_g + D closes on (eq. 11)
            out["input"] = ("$E_{initial} + E_{shock}$, the energy in (the balance closes on it)", e0 + e_shock)
    if "E_gravity" in ds or "E_drive" in ds:  # their work, and the line the balance closes on (eq. 11)
        for name, label in (
            ("E_gravity", "$E_{gravity}$, work of gravity"),
            ("E_drive", "$E_{drive}$, work of the drives"),
        ):
            if name in ds:
                out[name.lower()[2:]] = (label, ds[name].values)
        out["input"] = ("$E_{in}$, the energy in (the balance closes on it)", e0 + e_shock + an.body_force_work(ds))
    parts = []
    if an.has_granules(ds):
        out["granular"] = ("$E_{granular}$", ds["E_granular"].values)
        parts.append(("E_{granular}", ds["E_granular"].values))
    if an.has_elastic_energy(ds):
        body = "" if an.has_plate(ds) else ", the elastic body"
        out["plate"] = ("$E_{plate}$" + body, ds["E_plate"].values)
        parts.append(("E_{plate}", ds["E_plate"].values))
    for name in dimension_spec(ds).depth_energies:  # in space: the kinetic energy along z, a part of E_granular
        if name in ds:
            out["depth"] = ("$KE_{depth}$, translation along z (part of $E_{granular}$)", ds[name].values)
    dissipated = ds["D_viscous"].values + ds["D_friction"].values
    if plastic_work(ds) is not None:
        dissipated = dissipated + ds["D_plastic"].values
        out["plastic"] = ("$D_{plastic}$, plastic work of the contacts (part of D)", ds["D_plastic"].values)
        out["dissipated"] = ("$D = D_{viscous} + D_{friction} + D_{plastic}$", dissipated)
    else:
        out["dissipated"] = ("$D = D_{viscous} + D_{friction}$", dissipated)
    parts.append(("D", dissipated))
    out["total"] = ("$" + " + ".join(name for name, _ in parts) + "$", sum(v for _, v in parts))
    return out


#: (colour, line style, width) per curve: E_shock (or E_initial + E_shock) wide and light,
#: so that the sum drawn over it (equal up to the residual, panel c) leaves both visible.
ENERGY_STYLE = {
    "shock": ("0.7", "-", 4.0),
    "initial": ("0.3", ":", 1.3),
    "input": ("0.7", "-", 4.0),
    "granular": ("tab:blue", "-", 1.3),
    "plate": ("tab:red", "-", 1.3),
    "dissipated": ("tab:green", "-", 1.3),
    "total": ("tab:purple", "--", 1.3),
    "depth": ("tab:cyan", ":", 1.3),
    "gravity": ("tab:brown", ":", 1.3),
    "drive": ("tab:orange", ":", 1.3),
    "plastic": ("tab:olive", ":", 1.3),
}


def fig_energies(ds: xr.Dataset) -> Figure:
    """Energies in J (a), as fractions of the energy put in (b), balance residual (c)."""
    fig = new_figure(9.0, 8.0)
    a, b, c = fig.subplots(3, 1, sharex=True, height_ratios=(1.0, 1.0, 0.6))
    t = _t_ms(ds)
    ref = an.reference_energy(ds)
    curves = energy_curves(ds)
    for key, (label, e) in curves.items():
        colour, ls, lw = ENERGY_STYLE[key]
        if key == "shock" and "input" in curves:  # the wide light line is then the input's
            colour, ls, lw = "0.4", "--", 1.0
        a.plot(t, e, color=colour, ls=ls, lw=lw, label=label, gid=f"energy:{key}")
        b.plot(t, e / ref, color=colour, ls=ls, lw=lw, label=label, gid=f"fraction:{key}")
    a.set_ylabel("energy [J]")
    a.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    a.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    a.set_title("(a) energies", loc="left", fontsize=10)
    b.set_ylabel(f"energy / {reference_label(ds)} [-]")
    taken = float(an.load_work(ds["E_shock"].values)[1][-1]) if ds.sizes.get("time", 0) else 0.0
    what = (
        f"{reference_label(ds)} = {ref:.4g} J"
        if taken <= NEGLIGIBLE * ref
        else f"the energy put in, {reference_label(ds)} = {ref:.4g} J (E_shock: the work the load put in; "
        f"it took {taken:.3g} J back)"
    )
    b.set_title(f"(b) fractions of {what}", loc="left", fontsize=10 if taken <= NEGLIGIBLE * ref else 8)
    c.plot(t, ds["energy_residual"].values, color="0.2", lw=1.0, gid="energy:residual")
    c.set_ylabel("residual [-]")
    c.set_title(
        "(c) energy-balance residual (eq. 11): (E_p + E_g + D - E_shock - E_initial) / E_in", loc="left", fontsize=9
    )
    c.ticklabel_format(axis="y", style="sci", scilimits=(-2, 2))
    return _finish(fig, ds, (a, b, c), "energies")


def fig_contact_forces(ds: xr.Dataset) -> Figure:
    """Normal (a) and tangential (b) force at each plate contact [N]; a contact whose force
    stays within FORCE_COINCIDE of the panel's peak of an earlier one's is drawn dashed
    with markers over it, its legend entry naming that contact."""
    fig = new_figure(9.0, 6.0)
    a, b = fig.subplots(2, 1, sharex=True)
    t = _t_ms(ds)
    labels = [str(c) for c in ds["contact"].values]
    fn, ft = ds["contact_normal_force"].values, ds["contact_tangential_force"].values
    plot_curves(
        a,
        t,
        [(f"contact {lab}", fn[:, k], f"normal:{lab}") for k, lab in enumerate(labels)],
        rtol=FORCE_COINCIDE,
        lw=1.2,
    )
    plot_curves(
        b,
        t,
        [(f"contact {lab}", ft[:, k], f"tangential:{lab}") for k, lab in enumerate(labels)],
        rtol=FORCE_COINCIDE,
        lw=1.2,
    )
    a.set_ylabel("normal force [N]")
    a.set_title("(a) normal force on the plate (+x)", loc="left", fontsize=10)
    b.set_ylabel("tangential force [N]")
    b.set_title("(b) friction force on the plate (+y)", loc="left", fontsize=10)
    a.legend(
        fontsize=8,
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        frameon=False,
        title="contact: the granule\ntouching the plate",
        title_fontsize=8,
    )
    return _finish(fig, ds, (a, b), "plate contact forces")


def fig_stress_strain(ds: xr.Dataset) -> Figure:
    """The plate's largest von Mises stress [MPa] (a) and largest |eps_yy| [-] (b)."""
    fig = new_figure(7.5, 6.0)
    a, b = fig.subplots(2, 1, sharex=True)
    t = _t_ms(ds)
    a.plot(t, ds["max_von_mises"].values / 1e6, color="tab:red", lw=1.3, gid="max_von_mises")
    a.set_ylabel("max von Mises [MPa]")
    a.set_title("(a) largest von Mises stress over the plate (eq. 12)", loc="left", fontsize=10)
    b.plot(t, ds["max_eps_yy"].values, color="tab:blue", lw=1.3, gid="max_eps_yy")
    b.set_ylabel("max |eps_yy| [-]")
    b.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    b.set_title("(b) largest |eps_yy| over the plate", loc="left", fontsize=10)
    return _finish(fig, ds, (a, b), "plate stress and strain")


def granule_speeds(ds: xr.Dataset) -> np.ndarray:
    """|v| = sqrt(vx^2 + vy^2 (+ vz^2 in space)) [m/s], shape (time, granule)."""
    return functools.reduce(np.hypot, (ds[k].values for k in dimension_spec(ds).velocities))


def fig_granule_speeds(ds: xr.Dataset) -> Figure:
    """Speed of each granule [m/s]; many granules: envelope, median and the fastest."""
    fig = new_figure(9.0, 4.5)
    ax = fig.add_subplot()
    t = _t_ms(ds)
    v = granule_speeds(ds)
    labels = [str(g) for g in ds["granule"].values]
    if len(labels) <= MAX_LABELLED:
        plot_curves(ax, t, [(f"granule {lab}", v[:, k], f"speed:{lab}") for k, lab in enumerate(labels)], lw=1.2)
        ax.set_title("speed of each granule", loc="left", fontsize=10)
    else:
        ax.fill_between(
            t,
            v.min(axis=1),
            v.max(axis=1),
            color="0.8",
            label=f"all {len(labels)} granules: min to max",
            gid="speed:envelope",
        )
        ax.plot(t, np.median(v, axis=1), color="0.3", lw=1.0, ls="--", label="median", gid="speed:median")
        fastest = np.argsort(-v.max(axis=0), kind="stable")[:FASTEST]
        plot_curves(ax, t, [(f"granule {labels[k]}", v[:, k], f"speed:{labels[k]}") for k in fastest], lw=1.2)
        ax.set_title(f"granule speeds: envelope and the {FASTEST} fastest granules", loc="left", fontsize=10)
    ax.set_ylabel("speed |v| [m/s]")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return _finish(fig, ds, (ax,), "granule speeds")


def fig_body_stress(ds: xr.Dataset) -> Figure:
    """The 3D body's largest von Mises stress and its ball average [MPa] (a) and its
    largest displacement [um] (b), against time [ms]; a summary-only run's skipped blocks
    of times (NaN) are gaps."""
    fig = new_figure(7.5, 6.0)
    a, b = fig.subplots(2, 1, sharex=True)
    t = _t_ms(ds)
    a.plot(
        t, ds["max_von_mises"].values / 1e6, color="tab:red", lw=1.3, label="largest over the body", gid="max_von_mises"
    )
    if "max_von_mises_ball" in ds:
        radius = ds["max_von_mises_ball"].attrs.get("ball_radius")
        ball = f" (radius {float(radius) * 1e3:.3g} mm)" if radius is not None else ""
        a.plot(
            t,
            ds["max_von_mises_ball"].values / 1e6,
            color="tab:orange",
            lw=1.1,
            ls="--",
            label=f"largest ball average{ball}",
            gid="max_von_mises_ball",
        )
    a.set_ylabel("von Mises stress [MPa]")
    a.set_title("(a) largest von Mises stress in the body", loc="left", fontsize=10)
    a.legend(fontsize=8, frameon=False)
    b.plot(t, ds["max_displacement"].values * 1e6, color="tab:blue", lw=1.3, gid="max_displacement")
    b.set_ylabel("largest |u| [um]")
    b.set_title("(b) largest displacement of the body", loc="left", fontsize=10)
    return _finish(fig, ds, (a, b), "body stress and displacement")


def body_touching(ds: xr.Dataset) -> list[int]:
    """Indices of the granules whose normal force on the 3D body is nonzero at some output
    time, the largest peak force first."""
    fn = np.nan_to_num(ds["body_contact_normal_force"].values)
    touching = [k for k in range(fn.shape[1]) if np.any(fn[:, k] != 0.0)]
    return sorted(touching, key=lambda k: -float(np.max(np.abs(fn[:, k]))))


def fig_body_contact_forces(ds: xr.Dataset) -> Figure:
    """Normal force [N] of each granule touching the 3D body against time [ms]; beyond
    MAX_LABELLED touching granules: their min-max envelope and the FASTEST largest."""
    fig = new_figure(9.0, 4.5)
    ax = fig.add_subplot()
    t = _t_ms(ds)
    fn = np.nan_to_num(ds["body_contact_normal_force"].values)
    labels = [str(g) for g in ds["granule"].values]
    touching = body_touching(ds)
    if len(touching) <= MAX_LABELLED:
        shown = touching
        which = "the granule" if len(touching) == 1 else f"each of the {len(touching)} granules"
        ax.set_title(f"normal force of {which} touching the body", loc="left", fontsize=10)
    else:
        ax.fill_between(
            t,
            fn[:, touching].min(axis=1),
            fn[:, touching].max(axis=1),
            color="0.8",
            label=f"all {len(touching)} touching granules: min to max",
            gid="body-normal:envelope",
        )
        shown = touching[:FASTEST]
        ax.set_title(
            f"normal force on the body: envelope of the {len(touching)} touching granules and the {FASTEST} largest",
            loc="left",
            fontsize=10,
        )
    plot_curves(
        ax,
        t,
        [(f"granule {labels[k]}", fn[:, k], f"body-normal:{labels[k]}") for k in shown],
        rtol=FORCE_COINCIDE,
        lw=1.2,
    )
    ax.set_ylabel("normal force on the body [N]")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return _finish(fig, ds, (ax,), "body contact forces")


def fig_wall_forces(ds: xr.Dataset) -> Figure:
    """The normal force each wall receives (a) [N]; with drives, the force each applies
    along its direction (b) [N] and its displacement (c) [um] (docs/model.md section 3.11)."""
    drives = "drive_force" in ds
    walls = "wall_force" in ds
    n = int(walls) + 2 * int(drives)
    fig = new_figure(9.0, 2.6 * n + 0.8)
    axes = list(np.atleast_1d(fig.subplots(n, 1, sharex=True)))
    t = _t_ms(ds)
    k = 0
    if walls:
        ax = axes[k]
        for j, lab in enumerate(ds["wall"].values):
            ax.plot(t, ds["wall_force"].values[:, j], lw=1.2, label=str(lab))
        ax.set_ylabel("wall force [N]")
        ax.set_title(f"({'abc'[k]}) normal force on each wall (compression > 0)", loc="left", fontsize=10)
        ax.legend(
            fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, title="wall", title_fontsize=8
        )
        k += 1
    if drives:
        for j, lab in enumerate(ds["drive"].values):
            axes[k].plot(t, ds["drive_force"].values[:, j], lw=1.2, label=str(lab))
            axes[k + 1].plot(t, 1e6 * ds["drive_displacement"].values[:, j], lw=1.2, label=str(lab))
        axes[k].set_ylabel("drive force [N]")
        axes[k].set_title(f"({'abc'[k]}) force each drive applies along its direction", loc="left", fontsize=10)
        axes[k + 1].set_ylabel("displacement [um]")
        axes[k + 1].set_title(f"({'abc'[k + 1]}) displacement along the drive's direction", loc="left", fontsize=10)
        axes[k].legend(
            fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, title="drive", title_fontsize=8
        )
    return _finish(fig, ds, axes, "wall and drive forces")


def fig_sensor_forces(ds: xr.Dataset) -> Figure:
    """Each sensor's reading [N] (`sensor_force`: half the sum of the normal contact forces
    on its granule, docs/model.md section 3.15) on the sensors' own time axis [ms]."""
    fig = new_figure(9.0, 3.4)
    ax = fig.subplots(1, 1)
    t = 1e3 * ds["sensor_time"].values
    for j, lab in enumerate(ds["sensor"].values):
        ax.plot(t, ds["sensor_force"].values[:, j], lw=1.0, label=str(lab))
    ax.set_ylabel("sensor force [N]")
    ax.set_title("each sensor's reading: the mean of the forces on a chain bead's two faces", loc="left", fontsize=10)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, title="sensor", title_fontsize=8)
    return _finish(fig, ds, (ax,), "sensor forces")


FIGURES = {
    "energies": fig_energies,
    "contact-forces": fig_contact_forces,
    "stress-strain": fig_stress_strain,
    "body-stress": fig_body_stress,
    "body-contact-forces": fig_body_contact_forces,
    "granule-speeds": fig_granule_speeds,
    "wall-forces": fig_wall_forces,
    "sensor-forces": fig_sensor_forces,
}


def missing(name: str, ds: xr.Dataset) -> str | None:
    """Why the result cannot have figure `name` ("no plate", ...), None when it can."""
    if ds.sizes.get("time", 0) == 0:
        return "the run has no output times"
    if name == "contact-forces" and has_solid(ds):
        see = ": see body-contact-forces" if missing("body-contact-forces", ds) is None else ""
        return "the run's elastic body is a 3D solid" + see
    if name == "contact-forces" and (ds.sizes.get("contact", 0) == 0 or "contact_normal_force" not in ds):
        return "the run has no plate contacts"
    if name == "stress-strain" and has_solid(ds):
        return "eps_yy is a 2D plate strain; a 3D body has body-stress"
    if name == "stress-strain" and not ("max_von_mises" in ds and an.has_plate(ds)):
        return "the run has no plate"
    if name in ("body-stress", "body-contact-forces") and not has_solid(ds):
        return "the run has no 3D elastic body"
    if name == "body-contact-forces" and not an.has_granules(ds):
        return "the run has no granules"
    if name == "body-contact-forces" and ("body_contact_normal_force" not in ds or not body_touching(ds)):
        return "no granule touched the body"
    if name == "granule-speeds" and not an.has_granules(ds):
        return "the run has no granules"
    if name == "wall-forces" and "drive_force" not in ds and "E_gravity" not in ds:
        return "the run has no drives or gravity (its walls' forces are the Dataset's wall_force)"
    if name == "wall-forces" and "wall_force" not in ds and "drive_force" not in ds:
        return "the run has no walls or drives"
    if name == "sensor-forces" and ds.sizes.get("sensor_time", 0) == 0:
        return "the run has no [[sensors]]"
    return None


def figures(ds: xr.Dataset) -> dict[str, Figure]:
    """The generic figures the result can have, by name (FIGURES order)."""
    return {name: fn(ds) for name, fn in FIGURES.items() if missing(name, ds) is None}
