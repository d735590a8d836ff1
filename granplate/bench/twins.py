"""`granplate bench --twins`: each paper case beside its 3D twin (docs/model.md section
8.1) under velocity Verlet (the presets' scheme) and under the implicit scheme, in one
process, timed alternately 2D / 3D / 3D implicit.

Per case: the thin-limit agreement (E_shock and the plate's peak share, 3D against 2D,
unrounded, against THIN_LIMIT's targets), the twin's energy residual and step, and the
cost of both: the run's wall time as its summary states it (`wall_time_s`: set-up and
time loop), the loop's CPU time, and the whole `simulate` call (the run and the result
Dataset: for a 3D body its stresses at every output time), each the median of `repeats`
runs after a 1 us warm-up run of each (the compiled loops loaded, the plate and the slab
read from the run store). The speed target is a twin's wall time at most SPEED_TARGET
times its 2D preset's (velocity Verlet's; the implicit twin's ratio is reported beside it).
"""

from __future__ import annotations

import json
import statistics
import sys
import time
import warnings

from granplate.bench import write_report

#: The thin-limit targets: |3D / 2D - 1| of E_shock and of the plate's peak share.
THIN_LIMIT = {"e_shock": 0.01, "ep_max_fraction": 0.02}
#: The target of a twin's wall time over its 2D preset's.
SPEED_TARGET = 3.0
#: Timed repeats per case and dimension (medians).
REPEATS = 3


def timed_run(s) -> dict:
    """One run of scenario s: its summary, the run's wall and loop CPU time [s] (run_info)
    and the whole simulate call's [s]."""
    import granplate as gp
    from granplate.errors import YieldWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", YieldWarning)
        t0 = time.perf_counter()
        ds = gp.simulate(s, progress=False)
        whole = time.perf_counter() - t0
    info = json.loads(ds.attrs.get("run_info", "{}"))
    return {
        "summary": gp.summary(ds),
        "wall_s": float(info.get("wall_time_s", whole)),
        "loop_cpu_s": float(info.get("loop_cpu_s", float("nan"))),
        "simulate_s": whole,
        "n_steps": int(info.get("n_steps", 0)),
        "dt_s": float(s.time.dt_max),
    }


#: The schemes that drive the 3D twin's elastic solid: the presets' own ("verlet") and
#: "implicit" (docs/model.md section 6.7), each row's "3d" and "3d_implicit" columns.
TWIN_SCHEMES = {"3d": "verlet", "3d_implicit": "implicit"}


def bench_case(name: str, t_end: float | None = None, repeats: int = REPEATS) -> dict:
    """The row of preset `name` and its twin "3d-NAME" under each of TWIN_SCHEMES (module
    docstring)."""
    import granplate as gp

    plane = gp.preset(name)
    if t_end is not None:
        plane = gp.with_changes(plane, {"time.t_end": float(t_end)})
    runs_of = {"2d": plane}
    for col, scheme in TWIN_SCHEMES.items():
        changes = {"solver.scheme": scheme} | ({} if t_end is None else {"time.t_end": float(t_end)})
        runs_of[col] = gp.with_changes(gp.preset("3d-" + name), changes)
    for s in runs_of.values():  # warm-up: kernels loaded, plate and slab from the run store
        timed_run(gp.with_changes(s, {"time.t_end": 1e-6}))
    runs = {d: [] for d in runs_of}
    for _ in range(max(int(repeats), 1)):
        for d, s in runs_of.items():
            runs[d].append(timed_run(s))
    med = {
        d: {k: statistics.median(r[k] for r in rs) for k in ("wall_s", "loop_cpu_s", "simulate_s")}
        for d, rs in runs.items()
    }
    a = runs["2d"][-1]["summary"]
    row = {"case": name, "t_end_s": float(runs_of["3d"].time.t_end), "e_shock_2d_j": a["e_shock"]}
    row["ep_max_fraction_2d"] = a["ep_max_fraction"]
    for d in TWIN_SCHEMES:
        b = runs[d][-1]["summary"]
        tail = "" if d == "3d" else "_implicit"
        diff = {m: (b[m] / a[m] - 1.0 if a[m] else float("nan")) for m in THIN_LIMIT}
        row[f"e_shock_{d}_j"] = b["e_shock"]
        row[f"e_shock{tail}_rel_diff"] = diff["e_shock"]
        row[f"ep_max_fraction_{d}"] = b["ep_max_fraction"]
        row[f"ep_max_fraction{tail}_rel_diff"] = diff["ep_max_fraction"]
        row[f"energy_residual_{d}"] = b["energy_residual_max"]
        row[f"n_steps_{d}"] = runs[d][-1]["n_steps"]
        row[f"within_thin_limit{tail}"] = all(abs(diff[m]) <= tol for m, tol in THIN_LIMIT.items())
    row["dt_3d_s"] = runs["3d"][-1]["dt_s"]
    row["repeats"] = len(runs["2d"])
    for d in runs:
        row[f"wall_{d}_s"] = med[d]["wall_s"]
        row[f"loop_cpu_{d}_s"] = med[d]["loop_cpu_s"]
        row[f"simulate_{d}_s"] = med[d]["simulate_s"]
    row["wall_ratio"] = med["3d"]["wall_s"] / med["2d"]["wall_s"]
    row["wall_ratio_implicit"] = med["3d_implicit"]["wall_s"] / med["2d"]["wall_s"]
    row["simulate_ratio"] = med["3d"]["simulate_s"] / med["2d"]["simulate_s"]
    row["within_speed_target"] = row["wall_ratio"] <= SPEED_TARGET
    return row


def format_table(rows: list[dict]) -> str:
    """The table as Markdown: agreement, then cost."""
    head = (
        "| case | E_shock 2D / 3D [J] | diff | peak share 2D / 3D | diff | residual 3D | dt 3D [us] | "
        "wall 2D / 3D [s] | ratio | simulate 2D / 3D [s] | ratio |"
    )
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in rows:
        lines.append(
            f"| {r['case']} | {r['e_shock_2d_j']:.4e} / {r['e_shock_3d_j']:.4e} | {100 * r['e_shock_rel_diff']:+.2f}% | "
            f"{r['ep_max_fraction_2d']:.4g} / {r['ep_max_fraction_3d']:.4g} | {100 * r['ep_max_fraction_rel_diff']:+.2f}% | "
            f"{r['energy_residual_3d']:.1e} | {1e6 * r['dt_3d_s']:.1f} | "
            f"{r['wall_2d_s']:.2f} / {r['wall_3d_s']:.2f} | {r['wall_ratio']:.2f} | "
            f"{r['simulate_2d_s']:.2f} / {r['simulate_3d_s']:.2f} | {r['simulate_ratio']:.2f} |"
        )
    lines += ["", "The same twins on the implicit scheme (3D against 2D; wall time beside velocity Verlet's):", ""]
    head = (
        "| case | E_shock 3D implicit [J] | diff | peak share 3D implicit | diff | residual | steps | "
        "wall 3D implicit / verlet [s] | loop CPU implicit / verlet [s] | ratio to 2D |"
    )
    lines += [head, "|" + "---|" * (head.count("|") - 1)]
    for r in rows:
        lines.append(
            f"| {r['case']} | {r['e_shock_3d_implicit_j']:.4e} | {100 * r['e_shock_implicit_rel_diff']:+.3f}% | "
            f"{r['ep_max_fraction_3d_implicit']:.4g} | {100 * r['ep_max_fraction_implicit_rel_diff']:+.2f}% | "
            f"{r['energy_residual_3d_implicit']:.1e} | {r['n_steps_3d_implicit']} | "
            f"{r['wall_3d_implicit_s']:.2f} / {r['wall_3d_s']:.2f} | "
            f"{r['loop_cpu_3d_implicit_s']:.2f} / {r['loop_cpu_3d_s']:.2f} | {r['wall_ratio_implicit']:.2f} |"
        )
    ok = sum(r["within_thin_limit"] for r in rows)
    ok_i = sum(r["within_thin_limit_implicit"] for r in rows)
    fast = sum(r["within_speed_target"] for r in rows)
    lines.append("")
    lines.append(
        f"thin limit (E_shock within {100 * THIN_LIMIT['e_shock']:g}%, peak share within "
        f"{100 * THIN_LIMIT['ep_max_fraction']:g}%): {ok} of {len(rows)} cases; wall time at most "
        f"{SPEED_TARGET:g}x the 2D preset's: {fast} of {len(rows)}; the implicit twins within the thin limit: "
        f"{ok_i} of {len(rows)}"
    )
    return "\n".join(lines)


def main(args) -> int:
    """`granplate bench --twins [--cases A,B] [--t-end T] [--repeats N] [--json FILE]`."""
    import granplate as gp

    names = gp.preset_names()
    cases = names if not args.cases else [c.strip() for c in args.cases.split(",") if c.strip()]
    unknown = [c for c in cases if c not in names]
    if unknown:
        print(
            f"granplate: error: --cases {','.join(unknown)}: unknown; the paper's cases are: " + ", ".join(names),
            file=sys.stderr,
        )
        return 2
    if args.t_end is not None and not args.t_end > 0.0:
        print(f"granplate: error: --t-end {args.t_end}: must be > 0 [s]", file=sys.stderr)
        return 2
    if args.repeats is not None and args.repeats < 1:
        print(f"granplate: error: --repeats {args.repeats}: must be >= 1", file=sys.stderr)
        return 2
    rows = []
    for name in cases:
        print(f"twins: {name} and 3d-{name} ...", file=sys.stderr)
        rows.append(bench_case(name, args.t_end, args.repeats or REPEATS))
    print(format_table(rows))
    write_report(args, rows)
    return 0
