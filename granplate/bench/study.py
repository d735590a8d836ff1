"""`granplate bench --study`: the throughput of a design study on the Dask engine.

A sweep of a ptfe-r05-like study (the preset's 2 ms, the load and the friction coefficient
varied: one plate for all designs) runs through `granplate.study.sweep` exactly as
`granplate sweep` runs it, into a temporary folder (every design is computed). Reported:
the core-seconds per design all included (cluster start, warm-up, scheduling, set-up,
loop, summary: wall time x workers / designs), the loop's share of it and the overhead
(everything but the loop) as a fraction of the loop, the median of each part of a
design's time on its worker (and its CPU time, which a busy machine does not inflate),
and the extrapolation to 10,000 designs on 2 cores.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

#: Designs of the default study benchmark.
DEFAULT_DESIGNS = 200
#: The design count the report extrapolates to, and on how many cores.
EXTRAPOLATE_DESIGNS = 10_000
EXTRAPOLATE_CORES = 2
#: The target for those designs on those cores [h].
TARGET_HOURS = 1.0
#: Friction coefficients of the benchmarked study (the load has DEFAULT_DESIGNS / 10 values).
MU_VALUES = (0.05, 0.08, 0.099, 0.12, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4)


def bench_study(n_designs: int, t_end: float | None = None) -> dict:
    """The benchmarked study: ptfe-r05 (t_end [s] when given), load.q0 over [2e4, 8e4] N/m x
    contact.mu over MU_VALUES, its first n_designs designs (load varies slowest)."""
    from granplate.study.spec import parse_study

    n_q0 = max(1, -(-n_designs // len(MU_VALUES)))
    spec = {
        "base": "ptfe-r05",
        "parameters": {"load.q0": {"range": [2e4, 8e4], "num": n_q0}, "contact.mu": list(MU_VALUES)},
    }
    if t_end is not None:
        spec["set"] = {"time.t_end": float(t_end)}
    return parse_study(spec)


def run(
    n_designs: int = DEFAULT_DESIGNS,
    workers: int | None = None,
    scheduler: str | None = None,
    t_end: float | None = None,
    log=print,
) -> dict:
    """Sweep the benchmarked study's first n_designs designs; the JSON-ready report."""
    from granplate.results import engine
    from granplate.study import design as D
    from granplate.study.sweep import sweep

    study = bench_study(n_designs, t_end)
    n_workers = workers or engine.available_cores()
    with tempfile.TemporaryDirectory(prefix="granplate-bench-study-") as tmp:
        out = Path(tmp)
        log(
            f"study benchmark: {n_designs} designs of ptfe-r05 on "
            f"{'the cluster at ' + scheduler if scheduler else f'{n_workers} local workers'} ..."
        )
        t0 = time.perf_counter()
        with engine.dask_client(n_workers, scheduler) as client:
            t_cluster = time.perf_counter() - t0
            n_workers = len(client.scheduler_info(n_workers=-1)["workers"]) or n_workers
            report = sweep(study, out, client=client, limit=n_designs, progress=False)
        wall = time.perf_counter() - t0
        records = [
            r for r in (D.read_record(out, p.stem) for p in sorted((out / D.DESIGNS).glob("*.json"))) if r is not None
        ]
    ok = [r for r in records if r["status"] == "ok"]
    if not ok:
        raise RuntimeError(f"study benchmark: no design succeeded ({report.lost[:1] or records[:1]})")
    elapsed = [r["elapsed_s"] for r in ok]
    loop = [r["timings"]["loop_s"] for r in ok]
    setup = [r["timings"]["setup_s"] for r in ok]
    first = [r["timings"].get("first_call_s", 0.0) for r in ok]
    after = [r["timings"].get("summary_s", e - s_ - lp) for r, e, s_, lp in zip(ok, elapsed, setup, loop)]
    n = len(records)
    store_s = report.store_s / max(report.n_computed, 1)
    parts = {
        "setup": statistics.median(s_ + f for s_, f in zip(setup, first)),
        "loop": statistics.median(loop),
        "summary": statistics.median(after),
        "store": store_s,
    }
    per_design = wall * n_workers / n  # core-seconds, all included
    steady = (report.elapsed_s - report.warm_up_s) * n_workers / n
    mean_loop = statistics.fmean(loop)
    cpu = [r["timings"]["cpu_s"] for r in ok]
    loop_cpu = [r["timings"].get("loop_cpu_s", 0.0) for r in ok]
    cpu_per_design = statistics.fmean(c + store_s for c in cpu)  # core-s of the designs' own work
    return {
        "designs": n,
        "designs_ok": len(ok),
        "workers": n_workers,
        "t_end_s": study.scenario(0).time.t_end,
        "wall_time_s": wall,
        "cluster_start_s": t_cluster,
        "warm_up_s": report.warm_up_s,
        "s_per_design_core": per_design,
        "s_per_design_core_steady": steady,
        "loop_s_mean": mean_loop,
        "loop_s_median": statistics.median(loop),
        "setup_s_median": statistics.median(setup),
        "task_s_median": statistics.median(elapsed),
        "task_cpu_s_median": statistics.median(r["timings"]["cpu_s"] for r in ok),
        "loop_vs_task_median": statistics.median(lp / e for lp, e in zip(loop, elapsed)),
        "after_loop_s_median": statistics.median(after),
        "loop_share": mean_loop / per_design,
        "overhead_vs_loop": (per_design - mean_loop) / mean_loop,
        "overhead_vs_loop_steady": (steady - mean_loop) / mean_loop,
        "extrapolated_hours": EXTRAPOLATE_DESIGNS * per_design / EXTRAPOLATE_CORES / 3600.0,
        "extrapolated_designs": EXTRAPOLATE_DESIGNS,
        "extrapolated_cores": EXTRAPOLATE_CORES,
        "n_steps_median": statistics.median(r["summary"]["n_steps"] for r in ok),
        "breakdown_s_median": parts,
        "outside_loop_vs_loop_median": statistics.median(
            (s_ + f + a + store_s) / lp for s_, f, a, lp in zip(setup, first, after, loop) if lp > 0
        ),
        "task_cpu_s_mean": statistics.fmean(cpu),
        "loop_cpu_s_median": statistics.median(loop_cpu),
        "outside_loop_cpu_vs_loop_median": statistics.median(
            (c - lc + store_s) / lc for c, lc in zip(cpu, loop_cpu) if lc > 0
        ),
        "loop_cpu_s_mean": statistics.fmean(loop_cpu),
        "cpu_s_per_design": cpu_per_design,
        "extrapolated_hours_cpu": EXTRAPOLATE_DESIGNS * cpu_per_design / EXTRAPOLATE_CORES / 3600.0,
        "extrapolated_hours_steady": (t_cluster + report.warm_up_s + EXTRAPOLATE_DESIGNS * steady / EXTRAPOLATE_CORES)
        / 3600.0,
        "extrapolated_hours_loop": EXTRAPOLATE_DESIGNS * statistics.fmean(loop_cpu) / EXTRAPOLATE_CORES / 3600.0,
        "core_s_per_design_target": TARGET_HOURS * 3600.0 * EXTRAPOLATE_CORES / EXTRAPOLATE_DESIGNS,
    }


def format_report(r: dict) -> str:
    """The study benchmark as text."""
    b = r["breakdown_s_median"]
    return "\n".join(
        [
            f"study: {r['designs']} designs ({r['designs_ok']} ok) of ptfe-r05, t_end {r['t_end_s']:g} s, "
            f"{r['workers']} workers, {r['wall_time_s']:.1f} s wall (cluster start {r['cluster_start_s']:.1f} s, "
            f"warm-up {r['warm_up_s']:.1f} s)",
            f"per design, all included: {r['s_per_design_core']:.3f} core-s "
            f"(steady state {r['s_per_design_core_steady']:.3f} core-s)",
            f"on its worker (medians): task {r['task_s_median']:.3f} s = set-up {r['setup_s_median']:.3f} s + loop "
            f"{r['loop_s_median']:.3f} s + summary {r['after_loop_s_median']:.3f} s; {r['n_steps_median']:.0f} steps",
            f"task CPU time {r['task_cpu_s_median']:.3f} s (median; wall above includes waiting for a core "
            f"on a busy machine); loop / task {100 * r['loop_vs_task_median']:.0f}% (median)",
            f"loop share {100 * r['loop_share']:.0f}%, overhead {100 * r['overhead_vs_loop']:.0f}% of the loop "
            f"(steady state {100 * r['overhead_vs_loop_steady']:.0f}%)",
            f"per design on its worker (medians): set-up {b['setup']:.4f} s, loop {b['loop']:.4f} s, "
            f"summary {b['summary']:.4f} s, store {b['store']:.4f} s (mean): outside the loop "
            f"{100 * r['outside_loop_vs_loop_median']:.0f}% of the loop (median over the designs)",
            f"CPU time of a design's task: loop {r['loop_cpu_s_median']:.3f} s (median), outside the loop "
            f"(set-up, summary, store) {100 * r['outside_loop_cpu_vs_loop_median']:.0f}% of the loop's "
            f"(median over the designs); {r['cpu_s_per_design']:.3f} core-s per design (mean)",
            f"{r['extrapolated_designs']} designs on {r['extrapolated_cores']} cores: "
            f"{r['extrapolated_hours']:.2f} h at this run's rate all included, {r['extrapolated_hours_steady']:.2f} h "
            f"with the cluster start and warm-up once and the steady rate after, {r['extrapolated_hours_cpu']:.2f} h "
            f"at the tasks' CPU time, {r['extrapolated_hours_loop']:.2f} h for the time loops alone "
            f"(loop CPU {r['loop_cpu_s_mean']:.3f} s a design, mean; target {TARGET_HOURS:g} h: "
            f"{r['core_s_per_design_target']:.2f} core-s per design)",
        ]
    )
