"""`granplate bench --plastic`: what the elastic-plastic normal laws (docs/model.md
sections 3.6 and 3.10) cost in the time loop, against Hertz's law on the same scenario.

Cases: the 990-granule hexagonal packing of `bench --friction` (1 mm steel spheres, its
first column launched at 1 m/s, mu = 0.099: granule-granule and granule-wall contacts
dominate), and the presets ptfe-r05 and steel-r1 (plate contacts, both schemes' paths),
each with contact.normal_law = "hertz", "thornton" and "johnson" (its materials given a
rate coefficient, JOHNSON_RATE, so that the rate factor is computed). The laws take different paths
(a yielding contact rebounds slower, so the step count differs), so the figure compared
is the loop's CPU time per step, the median of REPEATS runs, each after a 1 us warm-up run
(the compiled loop loaded), timed alternately law after law in this process. The
target is at most PLASTIC_COST_TARGET times Hertz's per step.

A packing that yields compacts: more of its contacts are in touch at a time than under
Hertz's law (flattened contacts stay closed), so its loop does more per step. The
`kernel` rows compare the laws on identical work: the granular forces (granular_rhs, the
normal force and friction of every listed contact, then the split friction pass) on one
state, the packing's at t_end under the plastic law, every contact's history set 5%
above its overlap (all on their unloading curves, the plastic law's general branch), with
the Hertz coefficients and with the plastic ones: us per evaluation, median of
KERNEL_CALLS.
"""

from __future__ import annotations

import statistics
import sys
import warnings

from granplate.bench import write_report

#: Timed repeats per case and law (medians), the simulated time of the presets [s], and
#: the target ratio of the plastic law's loop time per step to Hertz's.
REPEATS = 3
PRESET_T_END = 5e-4
PLASTIC_COST_TARGET = 1.2
LAWS = ("hertz", "thornton", "johnson")
PLASTIC_LAWS = LAWS[1:]
#: the rate coefficient and reference rate [1/s] every material gets under "johnson" here
JOHNSON_RATE = (0.02, 1e-3)
KERNEL_CALLS = 200


def cases(t_end: float | None = None) -> list[tuple[str, object]]:
    """(case, scenario) of the table; t_end overrides every run's [s]."""
    import granplate as gp
    from granplate.bench.friction import packing_scenario

    packing = packing_scenario(0.099, "split", t_end)
    t = PRESET_T_END if t_end is None else float(t_end)
    out = [(f"packing {len(packing.granules)}, mu 0.099", packing)]
    for name in ("ptfe-r05", "steel-r1"):
        for scheme in ("paper", "implicit"):
            out.append(
                (
                    f"{name}, {scheme}",
                    gp.with_changes(
                        gp.preset(name),
                        {
                            "solver.scheme": scheme,
                            "time.t_end": t,
                            "time.output_interval": min(1e-6, t),
                            "time.field_interval": min(2e-5, t),
                        },
                    ),
                )
            )
    return out


def timed(s) -> dict:
    """Loop CPU seconds, steps and the plastic share of one run (after a warm-up)."""
    import granplate as gp
    from granplate.errors import YieldWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", YieldWarning)
        warnings.simplefilter("ignore", RuntimeWarning)  # overlaps beyond overlap_warn
        gp.simulate(
            gp.with_changes(s, {"time.t_end": 1e-6, "time.output_interval": 1e-6, "time.field_interval": 1e-6}),
            summary_only=True,
            progress=False,
        )
        ds = gp.simulate(s, summary_only=True, progress=False)
    summ = gp.summary(ds)
    return {
        "loop_cpu_s": float(ds.attrs["loop_cpu_s"]),
        "n_steps": int(ds.attrs["n_steps"]),
        "plastic_fraction": summ["plastic_fraction"],
        "yield_onset_ratio": summ["yield_onset_ratio"],
    }


def bench_case(case: str, s, repeats: int = REPEATS) -> dict:
    """Every law on one scenario, alternately `repeats` times: median loop CPU time per step
    [us] of each and their ratios to Hertz's ("ratio": the larger)."""

    runs: dict[str, list[dict]] = {law: [] for law in LAWS}
    for _ in range(repeats):
        for law in LAWS:
            runs[law].append(timed(with_law(s, law)))
    row: dict = {"case": case, "t_end_s": float(s.time.t_end)}
    for law in LAWS:
        per = [1e6 * r["loop_cpu_s"] / max(r["n_steps"], 1) for r in runs[law]]
        row[law] = {
            "us_per_step": statistics.median(per),
            "n_steps": runs[law][-1]["n_steps"],
            "plastic_fraction": runs[law][-1]["plastic_fraction"],
            "yield_onset_ratio": runs[law][-1]["yield_onset_ratio"],
        }
    for law in PLASTIC_LAWS:
        row[f"ratio_{law}"] = row[law]["us_per_step"] / row["hertz"]["us_per_step"]
    row["ratio"] = max(row[f"ratio_{law}"] for law in PLASTIC_LAWS)
    return row


def with_law(s, law: str):
    """s under normal law `law` (under "johnson", every material given JOHNSON_RATE)."""
    import dataclasses

    import granplate as gp

    s = gp.with_changes(s, {"contact.normal_law": law})
    if law != "johnson":
        return s
    c, ref = JOHNSON_RATE
    return dataclasses.replace(
        s, materials={k: dataclasses.replace(m, C=c, rate_ref=ref) for k, m in s.materials.items()}
    )


def kernel_case(t_end: float | None = None) -> dict:
    """The granular forces on one state of the packing under both laws (module docstring):
    us per evaluation of granular_rhs plus the two friction half steps, contacts in touch."""
    import time

    import numpy as np

    import granplate as gp
    from granplate.bench.friction import packing_scenario
    from granplate.errors import YieldWarning
    from granplate.model.arrays import build_model, granular_with_contacts
    from granplate.model.contacts import contact_lists
    from granplate.model.inputs import HIST_MAX, HIST_RATE
    from granplate.physics.contact import COEF_DY, COEF_NLAW, pair_overlap
    from granplate.setup.law_registry import HERTZ
    from granplate.solver.granular import friction_flow, granular_rhs

    s = gp.with_changes(packing_scenario(0.099, "split", t_end), {"contact.normal_law": "thornton"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", YieldWarning)
        ds = gp.simulate(s, progress=False)
    model = build_model(s)
    y = np.zeros((len(model.labels), 6))
    for c, name in enumerate(("x", "y", "theta", "vx", "vy", "omega")):
        y[:, c] = ds[name].values[-1]
    pairs, wc = contact_lists(s.contact, s.walls, y[:, 0], y[:, 1], model.granular.radius)
    g = granular_with_contacts(model, model.granular, pairs, wc)
    r = g.radius
    touch = 0
    for p, (i, j) in enumerate(g.pair_ij):
        d = pair_overlap(y[i, 0], y[i, 1], r[i], y[j, 0], y[j, 1], r[j])[0]
        g.pair_hist[p, HIST_MAX] = 1.05 * max(d, 0.0)
        touch += d > 0.0
    elastic = g._replace(pair_coef=g.pair_coef.copy(), wall_coef=g.wall_coef.copy())
    for coef in (elastic.pair_coef, elastic.wall_coef):  # Hertz's law: its id, a yield overlap never reached
        coef[:, COEF_NLAW], coef[:, COEF_DY] = HERTZ, np.inf
    jm = build_model(with_law(s, "johnson"))
    johnson = granular_with_contacts(jm, jm.granular, pairs, wc)
    johnson = johnson._replace(pair_hist=g.pair_hist.copy(), wall_hist=g.wall_hist.copy())
    johnson.pair_hist[:, HIST_RATE] = 1.3  # yield strengths fixed at 1.3 Y
    johnson.wall_hist[:, HIST_RATE] = 1.3
    cfg = model.config
    ng = len(r)
    dy, ys = np.zeros((ng, 6)), np.zeros((ng, 6))
    e0 = np.zeros(0)
    out = {}
    for law, gg in (("hertz", elastic), ("thornton", g), ("johnson", johnson)):
        times = []
        for _ in range(KERNEL_CALLS):
            ys[:] = y
            t0 = time.perf_counter()
            granular_rhs(0.0, ys, e0, e0, gg, cfg, dy, e0, e0, e0, False, e0, True)
            friction_flow(ys, 1e-9, gg, cfg, True)
            times.append(time.perf_counter() - t0)
        out[law] = 1e6 * statistics.median(times)
    return {
        "case": f"kernel: packing state, {touch} of {len(g.pair_ij)} listed pairs in touch",
        "hertz_us": out["hertz"],
        "thornton_us": out["thornton"],
        "johnson_us": out["johnson"],
        "ratio": out["thornton"] / out["hertz"],
        "ratio_johnson": out["johnson"] / out["hertz"],
    }


def run(t_end: float | None = None, repeats: int = REPEATS, log=print) -> dict:
    """The table of every case (see the module's docstring)."""
    rows = []
    for case, s in cases(t_end):
        log(f"bench --plastic: {case} ...")
        rows.append(bench_case(case, s, repeats))
    log("bench --plastic: kernel on one packing state ...")
    kernel = kernel_case(t_end)
    return {
        "repeats": repeats,
        "target_ratio": PLASTIC_COST_TARGET,
        "rows": rows,
        "kernel": kernel,
        "largest_ratio": max(r["ratio"] for r in rows),
    }


def format_report(report: dict) -> str:
    """The table as text."""
    lines = [
        f"{'case':28s} {'hertz us/step':>14s} {'thornton':>9s} {'ratio':>6s} {'johnson':>8s} {'ratio':>6s}"
        f" {'steps H':>8s} {'steps T':>8s} {'steps J':>8s} {'D_plastic/E_in T':>17s} {'J':>7s}"
    ]
    for r in report["rows"]:
        h, t, j = r["hertz"], r["thornton"], r["johnson"]
        lines.append(
            f"{r['case']:28s} {h['us_per_step']:14.2f} {t['us_per_step']:9.2f} {r['ratio_thornton']:6.3f}"
            f" {j['us_per_step']:8.2f} {r['ratio_johnson']:6.3f} {h['n_steps']:8d} {t['n_steps']:8d}"
            f" {j['n_steps']:8d} {t['plastic_fraction'] or 0.0:17.4f} {j['plastic_fraction'] or 0.0:7.4f}"
        )
    lines.append(
        f"largest ratio {report['largest_ratio']:.3f} (target <= {report['target_ratio']:g}); "
        f"loop CPU time per step, median of {report['repeats']} runs"
    )
    k = report["kernel"]
    lines.append(
        f"{k['case']}: hertz {k['hertz_us']:.1f} us, thornton {k['thornton_us']:.1f} us "
        f"(ratio {k['ratio']:.3f}), johnson {k['johnson_us']:.1f} us (ratio {k['ratio_johnson']:.3f}) per "
        f"evaluation (median of {KERNEL_CALLS})"
    )
    return "\n".join(lines)


def main(args) -> int:
    repeats = args.repeats or REPEATS
    if repeats < 1:
        print(f"granplate: error: --repeats = {repeats}: must be >= 1", file=sys.stderr)
        return 2
    report = run(args.t_end, repeats, log=lambda line: print(line, file=sys.stderr))
    print(format_report(report))
    write_report(args, report)
    return 0
