"""Benchmark harness for granplate: speed and accuracy of every coupling scheme.

For each case (a paper preset, possibly shortened) and each scheme in
``granplate.validate.SCHEMES`` it runs the simulation in a fresh worker subprocess
(one warm-up call so the numba cache is loaded, then ``repeats`` timed calls), and
compares the key metrics with a converged reference run of the same case, kept in the
run store (`granplate.store`, kind ``bench-reference``) keyed by the reference scenario's TOML. It also
measures the compile / cache-load time once per scheme in a fresh subprocess.

Run it as ``granplate bench [--quick] [--json FILE] [--cases A,B] [--repeats N]`` or
``python -m granplate.bench.harness ...``. The JSON keys are documented in
``docs/benchmarks.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time

from granplate.bench import write_report


#: The run store's kind of the converged reference summaries, and their format version.
REFERENCE_KIND = "bench-reference"
REFERENCE_FORMAT = 1


#: Key metrics compared with the converged reference (keys of granplate.summary).
METRICS = ("e_shock", "ep_max_fraction", "ep_final_fraction", "max_von_mises", "max_eps_yy")

#: Quick mode: a subset of presets, shortened.
QUICK_CASES = ("bare-plate", "ptfe-r05", "steel-r1")
QUICK_T_END = 5e-4
QUICK_REPEATS = 1
FULL_REPEATS = 3
#: The tiny run used for warm-up and for the compile / cache-load measurement.
TINY_CASE = "steel-r1"
TINY_T_END = 1e-6

SCHEMA_VERSION = 1


# --------------------------------------------------------------------------- scenarios


def case_scenario(case: str, scheme: str, t_end: float | None):
    """The benchmarked scenario: preset `case`, scheme `scheme`, t_end (None: preset's)."""
    import granplate as gp

    s = gp.preset(case)
    changes: dict[str, object] = {"solver.scheme": scheme}
    if t_end is not None:
        changes["time.t_end"] = float(t_end)
        if s.time.output_interval > t_end:
            changes["time.output_interval"] = float(t_end)
            changes["time.field_interval"] = float(t_end)
        elif s.time.field_interval > t_end:
            changes["time.field_interval"] = s.time.output_interval
    return gp.with_changes(s, changes)


def reference_scenario(case: str, t_end: float | None):
    """The converged reference: paper scheme, dt_max / 4, lambda_target 0.25, rtol / 100."""
    import granplate as gp

    s = case_scenario(case, "paper", t_end)
    dt_max = s.time.dt_max / 4.0
    return gp.with_changes(
        s,
        {
            "time.dt_max": dt_max,
            "time.dt_initial": min(s.time.dt_initial, dt_max),
            "solver.lambda_target": 0.25,
            "solver.iteration_rtol": min(s.solver.iteration_rtol / 100.0, 1e-11),
        },
    )


def reference_payload(s) -> dict:
    """The reference run's identity in the run store: its scenario's TOML (every material)."""
    from granplate.setup.io import dumps

    return {"scenario_toml": dumps(s, all_materials=True)}


def reference_summary(case: str, t_end: float | None, log=print) -> dict:
    """Summary of the reference run, from the run store or computed (and stored)."""
    import granplate as gp
    from granplate import store

    s = reference_scenario(case, t_end)
    payload = reference_payload(s)
    summ = store.load_json(REFERENCE_KIND, payload, REFERENCE_FORMAT, label=case)
    if summ is not None:
        return summ
    log(
        f"  reference run for {case} (t_end {s.time.t_end:g} s), kept in the run store "
        f"({store.cache_directory() / REFERENCE_KIND}) ..."
    )
    ds = gp.simulate(s, progress=False)
    summ = gp.summary(ds)
    summ["n_iterations"] = int(ds.attrs.get("n_iterations", 0)) if "n_iterations" in ds.attrs else None
    store.save_json(REFERENCE_KIND, payload, REFERENCE_FORMAT, summ, label=case)
    return summ


# --------------------------------------------------------------------------- worker


def _run_info(ds) -> dict:
    info = json.loads(ds.attrs.get("run_info", "{}"))
    for k in (
        "wall_time_s",
        "setup_time_s",
        "first_call_time_s",
        "loop_time_s",
        "n_steps",
        "n_iterations",
        "n_retries",
    ):
        if k in ds.attrs:
            info[k] = ds.attrs[k]
    return info


def _worker(spec: dict) -> dict:
    """Runs in a fresh subprocess: warm-up, then `repeats` timed runs of one case."""
    import resource

    t0 = time.perf_counter()
    import granplate as gp
    import numpy as np

    t_import = time.perf_counter() - t0

    if spec["kind"] == "compile":
        s = case_scenario(TINY_CASE, spec["scheme"], TINY_T_END)
        t1 = time.perf_counter()
        ds = gp.simulate(s, progress=False)
        first = time.perf_counter() - t1
        kernel_first = float(ds.attrs.get("first_call_time_s", float("nan")))
        setup_first = float(ds.attrs.get("setup_time_s", float("nan")))
        again, kernel_again = [], []
        for _ in range(3):
            t1 = time.perf_counter()
            ds = gp.simulate(s, progress=False)
            again.append(time.perf_counter() - t1)
            kernel_again.append(float(ds.attrs.get("first_call_time_s", float("nan"))))
        return {
            "import_time_s": t_import,
            "first_call_s": first,
            "repeat_call_s": min(again),
            "compile_time_s": first - min(again),
            "kernel_load_time_s": kernel_first - min(kernel_again),
            "setup_first_call_s": setup_first,
        }

    # warm-up: a tiny run of the same case loads (or compiles) the kernels
    gp.simulate(case_scenario(spec["case"], spec["scheme"], TINY_T_END), progress=False)
    rss_warm = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    s = case_scenario(spec["case"], spec["scheme"], spec["t_end"])
    runs = []
    summ = None
    for _ in range(spec["repeats"]):
        t1 = time.perf_counter()
        ds = gp.simulate(s, progress=False)
        wall = time.perf_counter() - t1
        info = _run_info(ds)
        dts = np.asarray(ds.dt_min.values, dtype=float)[1:] if "dt_min" in ds else np.array([])
        dts = dts[np.isfinite(dts) & (dts > 0)]  # the t = 0 record carries no step
        dt_min = float(dts.min()) if dts.size else float("nan")
        runs.append(
            {
                "wall_s": wall,
                "loop_s": float(info.get("loop_time_s", wall)),
                "setup_s": float(info.get("setup_time_s", 0.0)),
                "n_steps": int(info.get("n_steps", 0)),
                "n_iterations": int(info.get("n_iterations", 0)),
                "n_retries": int(info.get("n_retries", 0)),
                "dt_min": dt_min,
                "t_end": float(ds.time[-1]),
            }
        )
        summ = gp.summary(ds)
        del ds
    rss_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {"runs": runs, "summary": summ, "rss_warm_kib": rss_warm, "rss_peak_kib": rss_peak}


def _spawn(spec: dict) -> dict:
    code = (
        "import sys, json; "
        "from granplate.bench.harness import _worker; "
        "print('@@RESULT ' + json.dumps(_worker(json.loads(sys.stdin.read()))))"
    )
    p = subprocess.run([sys.executable, "-c", code], input=json.dumps(spec), capture_output=True, text=True)
    for line in p.stdout.splitlines():
        if line.startswith("@@RESULT "):
            return json.loads(line[len("@@RESULT ") :])
    raise RuntimeError(f"benchmark worker failed ({spec}): rc {p.returncode}\n{p.stderr[-3000:]}")


# --------------------------------------------------------------------------- harness


def _rel_error(x: float, ref: float) -> float:
    if ref == 0.0:
        return abs(x)
    return abs(x - ref) / abs(ref)


def bench_case(case: str, scheme: str, t_end: float | None, repeats: int, ref: dict) -> dict:
    """One (case, scheme) record of the JSON 'results' list."""
    w = _spawn({"kind": "case", "case": case, "scheme": scheme, "t_end": t_end, "repeats": repeats})
    runs = w["runs"]
    med = statistics.median(r["wall_s"] for r in runs)
    r0 = runs[0]  # steps/iterations are deterministic across repeats
    n = max(r0["n_steps"], 1)
    t_sim = r0["t_end"]
    summ = w["summary"]
    errors = {m: _rel_error(summ[m], ref[m]) for m in METRICS}
    return {
        "case": case,
        "scheme": scheme,
        "t_end_s": t_sim,
        "repeats": len(runs),
        "wall_time_s": med,
        "wall_times_s": [r["wall_s"] for r in runs],
        "loop_time_s": statistics.median(r["loop_s"] for r in runs),
        "setup_time_s": statistics.median(r["setup_s"] for r in runs),
        "n_steps": r0["n_steps"],
        "n_iterations": r0["n_iterations"],
        "n_retries": r0["n_retries"],
        "dt_mean_s": t_sim / n,
        "dt_min_s": r0["dt_min"],
        "us_per_step": 1e6 * statistics.median(r["loop_s"] for r in runs) / n,
        "iterations_per_step": r0["n_iterations"] / n,
        "metrics": {m: summ[m] for m in METRICS},
        "reference": {m: ref[m] for m in METRICS},
        "rel_error": errors,
        "max_rel_error": max(errors.values()),
        "reference_n_steps": ref.get("n_steps"),
        "peak_rss_mib": w["rss_peak_kib"] / 1024.0,
        "warm_rss_mib": w["rss_warm_kib"] / 1024.0,
    }


def schemes() -> tuple[str, ...]:
    """The schemes the presets (each with a plate) run under: every one but those of the
    granules alone (setup.validate.GRANULAR_SCHEMES)."""
    from granplate.setup.validate import GRANULAR_SCHEMES, SCHEMES

    return tuple(s for s in SCHEMES if s not in GRANULAR_SCHEMES)


def run(quick: bool = False, cases=None, repeats: int | None = None, t_end: float | None = None, log=print) -> dict:
    """Run the benchmark and return the JSON-ready report."""
    import granplate as gp

    t_start = time.perf_counter()
    if cases is None:
        cases = list(QUICK_CASES) if quick else gp.preset_names()
    twins = [c for c in cases if c in gp.preset_names(include_3d=True) and c not in gp.preset_names()]
    if twins:
        raise ValueError(
            f"case(s) {', '.join(twins)}: 3D twins, which this benchmark of the plane's plate schemes "
            f"({', '.join(schemes())}) does not run; `granplate bench --twins` times each twin under "
            f"velocity Verlet and the implicit scheme beside its 2D case"
        )
    unknown = [c for c in cases if c not in gp.preset_names()]
    if unknown:
        raise ValueError(f"unknown case(s) {', '.join(unknown)}; presets are: " + ", ".join(gp.preset_names()))
    if repeats is None:
        repeats = QUICK_REPEATS if quick else FULL_REPEATS
    if t_end is None and quick:
        t_end = QUICK_T_END
    sch = schemes()
    compile_info = {}
    for scheme in sch:
        log(f"compile / cache-load time, scheme {scheme} ...")
        compile_info[scheme] = _spawn({"kind": "compile", "scheme": scheme})
    results = []
    for case in cases:
        ref = reference_summary(case, t_end, log=log)
        for scheme in sch:
            log(f"{case} / {scheme} ({repeats} repeat(s)) ...")
            rec = bench_case(case, scheme, t_end, repeats, ref)
            results.append(rec)
            log("  " + _row(rec))
    return {
        "schema_version": SCHEMA_VERSION,
        "mode": "quick" if quick else "full",
        "t_end_override_s": t_end,
        "schemes": list(sch),
        "cases": list(cases),
        "metrics": list(METRICS),
        "machine": {
            "platform": platform.platform(),
            "python": platform.python_version(),
            "processor": platform.processor() or platform.machine(),
            "cpu_count": os.cpu_count(),
        },
        "compile": compile_info,
        "results": results,
        "total_time_s": time.perf_counter() - t_start,
    }


# --------------------------------------------------------------------------- output

HEADER = (
    f"{'case':18s} {'scheme':7s} {'wall s':>8s} {'steps':>9s} {'dt mean':>9s} {'dt min':>9s} "
    f"{'us/step':>8s} {'it/step':>7s} {'err E_sh':>9s} {'err Epmx':>9s} {'err Epfn':>9s} "
    f"{'err vM':>9s} {'err eyy':>9s} {'RSS MiB':>8s}"
)


def _row(r: dict) -> str:
    e = r["rel_error"]
    return (
        f"{r['case']:18s} {r['scheme']:7s} {r['wall_time_s']:8.3f} {r['n_steps']:9d} "
        f"{r['dt_mean_s']:9.2e} {r['dt_min_s']:9.2e} {r['us_per_step']:8.2f} "
        f"{r['iterations_per_step']:7.2f} {e['e_shock']:9.2e} {e['ep_max_fraction']:9.2e} "
        f"{e['ep_final_fraction']:9.2e} {e['max_von_mises']:9.2e} {e['max_eps_yy']:9.2e} "
        f"{r['peak_rss_mib']:8.1f}"
    )


def format_table(report: dict) -> str:
    lines = [HEADER, "-" * len(HEADER)]
    lines += [_row(r) for r in report["results"]]
    for scheme, c in report["compile"].items():
        lines.append(
            f"compile/cache-load ({scheme}): {c['compile_time_s']:.3f} s "
            f"(first call {c['first_call_s']:.3f} s, repeat {c['repeat_call_s']:.4f} s, "
            f"kernels alone {c['kernel_load_time_s']:.3f} s, import {c['import_time_s']:.2f} s)"
        )
    lines.append(f"total benchmark time: {report['total_time_s']:.1f} s ({report['mode']} mode)")
    return "\n".join(lines)


def main(args) -> int:
    """Entry point for `granplate bench` (args from granplate.bench)."""
    cases = [c.strip() for c in args.cases.split(",") if c.strip()] if getattr(args, "cases", None) else None
    if args.repeats is not None and args.repeats < 1:
        print("granplate: error: --repeats must be >= 1", file=sys.stderr)
        return 2
    try:
        report = run(quick=args.quick, cases=cases, repeats=args.repeats, t_end=getattr(args, "t_end", None))
    except ValueError as err:
        print(f"granplate: error: {err}", file=sys.stderr)
        return 2
    print()
    print(format_table(report))
    write_report(args, report)
    return 0


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--quick", action="store_true", help=f"a subset ({', '.join(QUICK_CASES)}) at t_end {QUICK_T_END:g} s, 1 repeat"
    )
    p.add_argument("--json", metavar="FILE", help="write the report as JSON to FILE")
    p.add_argument("--cases", help="comma-separated presets (default: all; quick: a subset)")
    p.add_argument(
        "--repeats",
        type=int,
        default=None,
        help=f"timed repeats per case, median reported (default {FULL_REPEATS}, quick {QUICK_REPEATS})",
    )
    p.add_argument("--t-end", dest="t_end", type=float, default=None, help=argparse.SUPPRESS)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(prog="python -m granplate.bench.harness")
    add_arguments(ap)
    sys.exit(main(ap.parse_args()))


def parse_pairs(text: str, flag: str, form: str, example: str, min_second: int = 1) -> list[tuple[int, int]]:
    """'4x40,8x80' -> [(4, 40), (8, 80)]: a bench option's comma-separated AxB items, each
    A >= 1 and B >= min_second (ValueError naming the option, the bad item and the form)."""
    out = []
    for item in text.split(","):
        parts = item.strip().lower().split("x")
        if len(parts) != 2 or not all(p.strip().isdigit() and int(p) >= 1 for p in parts) or int(parts[1]) < min_second:
            rows = f" ({form.split('x')[1]} >= {min_second})" if min_second > 1 else ""
            raise ValueError(f"{flag} item {item!r}: allowed {form} with integers >= 1{rows}, e.g. {example}")
        out.append((int(parts[0]), int(parts[1])))
    return out
