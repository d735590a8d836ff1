"""Convergence studies of the coupled runs (slow: `granplate verify --full`).

For the PTFE and the steel R2 = R1 presets, the plate's peak and final share of E_shock
and the maximum von Mises stress (its point peak and its disc average) are recomputed with every step halved (time.dt_max and
solver.lambda_target, twice), the iteration tolerance halved (twice), the element size
halved (at a fixed rigid-layer width) and with other rigid-layer widths. Observed orders
come from three levels, p = log2 |Q1 - Q2| / |Q2 - Q3|; the error bar of the default
setting is its difference to the next finer level (and a Richardson estimate where the
order is meaningful).

Runs are expensive (5-150 s each), so their summaries are kept in the run store
(`granplate.store`, kind "verification") and in DIR/validation-runs.json, both keyed by
the store's key of the scenario, the end time and the package version: a second `--full`
run only computes what changed (like pystencils' parameter studies).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .base import Case, CaseResult, Check, Context, new_figure

#: Presets studied (the PTFE and the steel R2 = R1 cases).
PRESETS: tuple[str, ...] = ("ptfe-r05", "steel-r1")
#: (summary key, label, unit, scale to the unit).
QUANTITIES: tuple[tuple[str, str, str, float], ...] = (
    ("ep_max_fraction", "plate energy, peak / E_shock", "-", 1.0),
    ("ep_final_fraction", "plate energy, final / E_shock", "-", 1.0),
    ("max_von_mises", "max von Mises stress", "MPa", 1e-6),
    ("max_von_mises_disc", "max von Mises stress, disc average", "MPa", 1e-6),
)
#: Quantities whose mesh studies are not checked: the point peak of a singular stress has
#: no mesh limit (its disc average, the next quantity, is the one checked; the tables keep both).
NO_MESH_LIMIT: tuple[str, ...] = ("max_von_mises",)
#: Relative accuracy asked of the default settings.
TARGET = 0.01
TARGET_WHY = (
    "the paper quotes these figures to two significant digits at most ('a little over "
    "50%', 'about 10%', '~80 MPa'); a numerical error below 1% of the value leaves them "
    "unchanged."
)


@dataclass(frozen=True)
class Study:
    """Levels (label, dotted-path changes) from coarse to fine (each step halves the
    parameter when `refinement`); `default`: index of the default setting or None."""

    name: str
    levels: tuple[tuple[str, dict], ...]
    default: int | None
    refinement: bool = True
    check: bool = False


W_DEFAULT = 0.0025
#: The studies run the paper scheme, which takes the dense basis only ("auto" would give
#: 8 x 80 the truncated one; docs/model.md section 4.5).
STUDIES: tuple[Study, ...] = (
    Study(
        "time step (time.dt_max and solver.lambda_target halved)",
        (
            ("40 ns, lambda 0.5 (default)", {}),
            ("20 ns, lambda 0.25", {"time.dt_max": 2e-8, "time.dt_initial": 2e-8, "solver.lambda_target": 0.25}),
            ("10 ns, lambda 0.125", {"time.dt_max": 1e-8, "time.dt_initial": 1e-8, "solver.lambda_target": 0.125}),
        ),
        0,
        check=True,
    ),
    Study(
        "iteration tolerance (solver.iteration_rtol and _atol halved)",
        (
            ("1e-9, 1e-10 N (default)", {}),
            ("5e-10, 5e-11 N", {"solver.iteration_rtol": 5e-10, "solver.iteration_atol": 5e-11}),
            ("2.5e-10, 2.5e-11 N", {"solver.iteration_rtol": 2.5e-10, "solver.iteration_atol": 2.5e-11}),
        ),
        0,
        check=True,
    ),
    Study(
        "element size, default rigid layer w = 2.5 mm",
        (
            ("4 x 40 (default)", {}),
            ("8 x 80", {"plate.nx": 8, "plate.ny": 80, "plate.rigid_layer_width": W_DEFAULT, "plate.modes": "all"}),
        ),
        0,
        check=True,
    ),
    Study(
        "element size at a fixed rigid layer w = 5 mm (three levels)",
        (
            ("2 x 20", {"plate.nx": 2, "plate.ny": 20, "plate.rigid_layer_width": 0.005}),
            ("4 x 40", {"plate.rigid_layer_width": 0.005}),
            ("8 x 80", {"plate.nx": 8, "plate.ny": 80, "plate.rigid_layer_width": 0.005, "plate.modes": "all"}),
        ),
        None,
    ),
    Study(
        "rigid-layer width on the 4 x 40 mesh (a model parameter, not a discretisation)",
        (
            ("w -> 0 (driving node only)", {"plate.rigid_layer_width": 1e-4}),
            ("w = 2.5 mm (default)", {}),
            ("w = 5 mm", {"plate.rigid_layer_width": 0.005}),
        ),
        1,
        refinement=False,
    ),
)


#: The run store's kind of the study runs' summaries, and their format version.
RUN_KIND = "verification"
RUN_FORMAT = 1


def run_payload(scenario, t_end: float | None = None) -> dict:
    """A study run's identity: the scenario's TOML and the end time [s] (None: the scenario's)."""
    from granplate.setup.io import dumps

    return {"scenario_toml": dumps(scenario), "t_end": None if t_end is None else repr(float(t_end))}


def cache_key(scenario, t_end: float | None = None) -> str:
    """The run store's key of a study run (scenario, end time, package version)."""
    from granplate import store

    return store.key(RUN_KIND, run_payload(scenario, t_end), RUN_FORMAT)


def load_run_cache(path: Path) -> dict:
    """The run cache stored at path ({} when absent or unreadable)."""
    try:
        cache = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    return cache if isinstance(cache, dict) else {}


def save_run_cache(path: Path, cache: dict) -> None:
    """Write the run cache atomically (sorted, indented: it is committed next to the page)."""
    from granplate import store

    text = json.dumps(cache, indent=1, sort_keys=True) + "\n"
    store.atomic_write(path, lambda tmp: tmp.write_text(text))


def _vm_location(ds) -> list[float]:
    """(x - x0, y) [m] of the element with the largest von Mises stress in the snapshots."""
    from granplate.results.analysis import peak_stress_location

    return list(peak_stress_location(ds)[1:])


def run_summary(scenario) -> dict:
    """Summary of a full run of `scenario` (a Scenario or its TOML text): gp.summary, the
    largest |energy residual| and the location of the largest von Mises stress."""
    from granplate.results.run import simulate as run
    from granplate.results.dataset import summary
    from granplate.setup.io import loads

    ds = run(loads(scenario) if isinstance(scenario, str) else scenario, progress=False)
    summ = summary(ds)
    summ["energy_residual_max"] = float(np.max(np.abs(ds.energy_residual_max.values)))
    summ["vm_location"] = _vm_location(ds)
    return summ


def keep_run(ctx: Context, scenario, summ: dict, in_store: bool = False) -> None:
    """Keep a study run's summary in the run store (unless in_store: read from there) and
    in the page's run cache."""
    from granplate import store

    if not in_store:
        store.save_json(RUN_KIND, run_payload(scenario), RUN_FORMAT, summ)
    if ctx.run_cache is not None:
        ctx.run_cache[cache_key(scenario)] = summ
        if ctx.out is not None:
            save_run_cache(ctx.out / "validation-runs.json", ctx.run_cache)


def stored_run(ctx: Context, scenario) -> dict | None:
    """A study run's summary from the page's run cache, else the run store (kept in the
    run cache then); None: not run yet."""
    from granplate import store

    if ctx.run_cache is not None and (key := cache_key(scenario)) in ctx.run_cache:
        return ctx.run_cache[key]
    summ = store.load_json(RUN_KIND, run_payload(scenario), RUN_FORMAT)
    if summ is not None:
        keep_run(ctx, scenario, summ, in_store=True)
    return summ


def study_run(ctx: Context, scenario) -> dict:
    """Summary of a full run of `scenario`: from the page's run cache, else the run store,
    else computed here (and kept in both)."""
    summ = stored_run(ctx, scenario)
    if summ is None:
        summ = run_summary(scenario)
        keep_run(ctx, scenario, summ)
    return summ


def study_scenarios() -> list:
    """Every run of the studies: (preset, study, scenario), level by level."""
    from granplate.setup.presets import preset
    from granplate.setup.io import with_changes

    out = []
    for name in PRESETS:
        base = with_changes(preset(name), {"solver.scheme": "paper"})  # the studies vary its step
        for study in STUDIES:
            out += [(name, study, with_changes(base, ch) if ch else base) for _, ch in study.levels]
    return out


def _order(q: list[float]) -> float:
    d1, d2 = q[0] - q[1], q[1] - q[2]
    if d1 == 0.0 or d2 == 0.0:
        return math.nan
    return math.log(abs(d1) / abs(d2), 2)


def _fmt(v: float, unit: str, scale: float) -> str:
    v = v * scale
    if unit == "MPa":
        return f"{v:.2f}"
    return f"{v:.5g}"


def study_tables(results: dict, preset: str) -> str:
    """Markdown tables of every study for one preset."""
    out = [f"#### {preset}"]
    for study in STUDIES:
        runs = results[(preset, study.name)]
        head = (
            "| "
            + study.name
            + " | "
            + " | ".join(f"{lab} [{u}]" for _, lab, u, _ in QUANTITIES)
            + " | steps | wall [s] |"
        )
        out += ["", head, "|---" * (len(QUANTITIES) + 3) + "|"]
        for (label, _), summ in zip(study.levels, runs):
            vals = " | ".join(_fmt(summ[k], u, sc) for k, _, u, sc in QUANTITIES)
            out.append(f"| {label} | {vals} | {summ['n_steps']} | {summ['wall_time_s']:.1f} |")
        if study.refinement and len(runs) == 3:
            orders = []
            for k, _, u, sc in QUANTITIES:
                q = [r[k] for r in runs]
                p = _order(q)
                if max(abs(q[0] - q[1]), abs(q[1] - q[2])) <= 1e-8 * abs(q[0]):
                    orders.append("changes < 1e-8: round-off level")
                elif math.isfinite(p) and 0.5 < p < 8 and (q[0] - q[1]) * (q[1] - q[2]) > 0:
                    extrap = q[2] + (q[2] - q[1]) / (2**p - 1)
                    orders.append(f"p = {p:.2f}, Richardson limit {_fmt(extrap, u, sc)}")
                else:
                    orders.append(f"p = {p:.2f}: not in the asymptotic range" if math.isfinite(p) else "p: n/a")
            out.append("| observed order | " + " | ".join(orders) + " | | |")
        if study.default is not None and study.refinement and len(runs) > study.default + 1:
            d, f = runs[study.default], runs[study.default + 1]
            bars = []
            for k, _, u, sc in QUANTITIES:
                rel = abs(f[k] - d[k]) / abs(d[k]) if d[k] else math.nan
                bars.append(f"+-{abs(f[k] - d[k]) * sc:.2e}{'' if u == '-' else ' ' + u} ({rel * 100:.2g}%)")
            out.append("| error bar of the default (vs next level) | " + " | ".join(bars) + " | | |")
        if not study.refinement:
            spreads = []
            for k, _, u, sc in QUANTITIES:
                q = np.array([r[k] for r in runs])
                base = q[study.default]
                spreads.append(f"{(q.min() / base - 1) * 100:+.1f}% .. {(q.max() / base - 1) * 100:+.1f}%")
            out.append("| spread around the default | " + " | ".join(spreads) + " | | |")
    return "\n".join(out)


def _disc_lines(results: dict) -> list[str]:
    """Per preset: the point peak and the disc average [MPa] on the w = 5 mm meshes."""
    study = STUDIES[3]
    lines = []
    for name in PRESETS:
        runs = results[(name, study.name)]
        point = ", ".join(f"{r['max_von_mises'] / 1e6:.1f}" for r in runs)
        disc = ", ".join(f"{r['max_von_mises_disc'] / 1e6:.2f}" for r in runs)
        lines.append(
            f"{name} on {', '.join(lab for lab, _ in study.levels)} (w = 5 mm): disc average "
            f"{disc} MPa, point peak {point} MPa"
        )
    return lines


def coupled_convergence(ctx: Context) -> CaseResult:
    """The studies above for both presets, with checks on the default settings."""
    results: dict = {}
    for name, study, scenario in study_scenarios():
        results.setdefault((name, study.name), []).append(study_run(ctx, scenario))
    checks = []
    for name in PRESETS:
        for study in STUDIES:
            if not study.check:
                continue
            runs = results[(name, study.name)]
            d, f = runs[study.default], runs[study.default + 1]
            for k, lab, u, sc in QUANTITIES:
                if k in NO_MESH_LIMIT and study.name.startswith("element size"):
                    continue
                checks.append(
                    Check(
                        f"{lab}, {name}: default vs {study.levels[study.default + 1][0]} ({study.name.split(' (')[0]})",
                        u,
                        f[k] * sc,
                        "the same run with the parameter halved",
                        d[k] * sc,
                        TARGET,
                        TARGET_WHY,
                    )
                )
    tables = [study_tables(results, name) for name in PRESETS]
    loc_lines = []
    for name in PRESETS:
        for study, w in zip(STUDIES[2:4], ("w = 2.5 mm", "w = 5 mm")):
            for (label, _), summ in zip(study.levels, results[(name, study.name)]):
                x, y = summ.get("vm_location", [math.nan, math.nan])
                loc_lines.append(
                    f"{name}, {label} ({w}): "
                    f"{summ['max_von_mises'] / 1e6:.1f} MPa, element at x - x0 = "
                    f"{x * 1e3:.2f} mm, y = {y * 1e3:.2f} mm"
                )
    desc = (
        "Full 2 ms runs of `ptfe-r05` and `steel-r1` with one numerical parameter changed at a "
        "time (results cached in `validation-runs.json`). The step study halves time.dt_max "
        "and solver.lambda_target together, so that every step halves (the eq. (8) step "
        "control sets most steps below dt_max); the mesh is refined at a fixed physical "
        "rigid-layer width, since the default width is one element edge and would shrink "
        "with the mesh. Checks ask that halving a parameter changes each figure by less "
        "than 1%."
    )
    notes = [
        "Time step and iteration tolerance are converged far beyond the paper's precision: "
        "halving the step changes each figure by less than 1e-4 of its value, halving "
        "the iteration tolerance by less than 1e-8.",
        "The mesh is not converged for the stress: the maximum von Mises stress grows under "
        "refinement instead of converging, because it sits in the element next to the end of a "
        "rigid layer (a rigid flat punch on an elastic edge: stress ~ r^(-1/2)) or, on the "
        "coarsest mesh, next to a corner where a clamped edge meets the free left edge; a point "
        "value of a singular stress has no mesh limit, and the reported maximum is a property of "
        "the mesh (and of sampling at the Gauss points). Locations of the maximum (from the "
        "plate snapshots): " + "; ".join(loc_lines) + ". Its mesh studies are therefore reported, "
        "not checked: there is no limit to check against.",
        "The disc average of the stress (discs of plate.stress_radius, 2.5 mm by default, a "
        "quarter of the plate's width, the same on every mesh; docs/model.md section 4.4) "
        "converges where the point peak grows: " + "; ".join(_disc_lines(results)) + ". It is "
        "the stress the mesh studies check; at the default rigid-layer width its error bar "
        "(above) is beyond the 1% asked, and those checks fail.",
        "The peak plate-energy share of the steel packing is mesh-converged (0.6% at the default "
        "w, 0.05% at w = 5 mm). For PTFE it converges at a fixed w = 5 mm with order about 2, but "
        "the default 4 x 40 mesh is 10-20% below the refined value: that is its error bar. The "
        "final share at 2 ms (after many reflections in the plate) is not mesh-converged for "
        "either preset.",
        "The rigid-layer width is a model parameter (docs/model.md section 4), not a discretisation: "
        "it changes the PTFE peak share from -42% to +61% around the default, the steel one by "
        "only 1%.",
    ]
    unique = {id(s): s for runs in results.values() for s in runs}
    total = sum(s["wall_time_s"] for s in unique.values())
    notes.append(
        f"The {len(unique)} distinct runs took {total:.0f} s of wall time when computed "
        "(a second `--full` takes them from validation-runs.json)."
    )
    res = CaseResult.of(desc, checks, plot={"results": results}, notes=notes, tables=tables)
    return res


def draw_coupled_convergence(p: dict):
    """The figure of coupled_convergence, from its numbers."""
    results = p["results"]
    fig, axes = new_figure(ncols=len(QUANTITIES), width=3.6, height=3.6)
    mesh_study = STUDIES[3]
    for ax, (k, lab, u, sc) in zip(axes[0], QUANTITIES):
        for name, marker in zip(PRESETS, ("o", "s")):
            runs = results[(name, mesh_study.name)]
            ref = runs[1][k]
            ax.plot([5.0, 2.5, 1.25], [r[k] / ref for r in runs], marker + "-", label=f"{name}, w = 5 mm")
            dflt = results[(name, STUDIES[2].name)]
            ax.plot(
                [2.5, 1.25], [r[k] / dflt[0][k] for r in dflt], marker + "--", mfc="none", label=f"{name}, w = 2.5 mm"
            )
        ax.set_xscale("log")
        ax.minorticks_off()
        ax.set_xticks([1.25, 2.5, 5.0], ["1.25", "2.5", "5"])
        ax.set_xlabel("element size [mm]")
        ax.set_ylabel("value / value on the 4 x 40 mesh [-]")
        ax.set_title(lab, fontsize=9)
        ax.legend(fontsize=6)
    return fig


CASES: tuple[Case, ...] = (
    Case(
        "coupled-convergence",
        "coupled",
        "Coupled runs: convergence and error bars of the default settings",
        coupled_convergence,
        draw=draw_coupled_convergence,
        slow=True,
    ),
)
