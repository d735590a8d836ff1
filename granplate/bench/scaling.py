"""`granplate bench --scaling`: how the granular loop's cost grows with the number of
granules, with and without friction, and (where LAMMPS is installed) LAMMPS's time to the
same accuracy on the same frictionless packing.

The packing (granplate.verification.lammps.launched_hexagon): a free hexagonal packing of
steel spheres, R = 1 mm, no walls, no plate, no load, whose first column is launched at
1 m/s into the rest; dynamic detection, the default (implicit) scheme unless asked, run to
a short t_end (default 20 us: the wave crosses ~15 granules, every contact of its path
closes and reopens).

Each (size, mu) runs in a fresh subprocess: a tiny warm-up run (numba cache load), then
`build_model` (set-up time) and `simulate` (loop time, steps), then the peak resident
memory (ru_maxrss). Accuracy (frictionless rows): the largest |v - v_ref| over the
granules at t_end, divided by the launch speed, where v_ref is the paper scheme (RK4) at a
fixed step of REFERENCE_DT, run in the same process after the memory is read. LAMMPS
(another fresh subprocess) runs the same packing at steps LAMMPS_DT_START, halved until
its error against the same v_ref is at most ours; its row is the first step that reaches it.
"""

from __future__ import annotations

import json
import shutil
import math
import os
import subprocess
import sys
import tempfile
import time

from granplate.bench.harness import parse_pairs
from granplate.bench import write_report

#: Packings (columns, rows) of the table: 10, 100, 1,008, 2,996 and 9,950 granules.
SIZES: tuple[tuple[int, int], ...] = ((4, 3), (8, 13), (32, 32), (56, 54), (100, 100))
#: Friction coefficients of the rows: frictionless (compared with LAMMPS) and the default.
FRICTIONS: tuple[float, ...] = (0.0, 0.099)
#: Launch speed [m/s], radius [m], default simulated time [s].
SPEED = 1.0
RADIUS = 1e-3
T_END = 2e-5
#: The reference: RK4 (paper scheme) at this fixed step [s] (t_c / 1000 at 1 m/s).
REFERENCE_DT = 2.5e-9
#: LAMMPS's first step [s] (the paper scheme's dt_max) and the most halvings tried.
LAMMPS_DT_START = 4e-8
LAMMPS_HALVINGS = 6
#: Relative slack under which LAMMPS's error counts as equal to ours: the same velocity
#: Verlet at the same step (solver.scheme = "verlet") reaches the same error up to
#: round-off (measured: 2e-14 relative), which must not cost LAMMPS a halving.
ACCURACY_SLACK = 1e-9


def as_accurate(error: float, target: float) -> bool:
    """Whether an error is at most the target's, up to ACCURACY_SLACK of it (round-off)."""
    return error <= target * (1.0 + ACCURACY_SLACK)


def granule_count(columns: int, rows: int) -> int:
    """Granules of a hexagonal packing: odd columns hold `rows`, even ones rows - 1."""
    return (columns + 1) // 2 * rows + columns // 2 * (rows - 1)


def _warm_up() -> None:
    """Load the compiled kernels of every scheme from the numba cache (a 1 us run each)."""
    from granplate.results.run import simulate
    from granplate.verification.lammps import launched_hexagon

    for scheme in ("implicit", "paper", "verlet"):
        dt = 4e-8 if scheme in ("paper", "verlet") else None
        simulate(launched_hexagon(2, 2, radius=RADIUS, t_end=1e-6, scheme=scheme, dt=dt), progress=False)


def _max_error(vx, vy, ref: dict) -> float:
    """max |v - v_ref| / SPEED over the granules at t_end."""
    import numpy as np

    return float(max(np.abs(np.asarray(vx) - ref["vx"]).max(), np.abs(np.asarray(vy) - ref["vy"]).max()) / SPEED)


def _ours_worker(spec: dict) -> dict:
    """Runs in a fresh subprocess: one (size, mu) of granplate; the reference when mu = 0."""
    import resource

    import numpy as np

    from granplate.model.arrays import build_model
    from granplate.results.run import simulate
    from granplate.verification.lammps import launched_hexagon

    _warm_up()
    s = launched_hexagon(
        spec["columns"],
        spec["rows"],
        radius=RADIUS,
        speed=SPEED,
        mu=spec["mu"],
        t_end=spec["t_end"],
        scheme=spec["scheme"],
    )
    t0 = time.perf_counter()
    model = build_model(s)
    setup = time.perf_counter() - t0
    ds = simulate(s, model=model, progress=False)
    out = {
        "granules": len(s.granules),
        "contacts": int(len(model.pairs)),
        "setup_s": setup,
        "n_steps": int(ds.attrs["n_steps"]),
        "loop_s": float(ds.attrs["loop_time_s"]),
        "rss_peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "energy_residual": float(np.abs(ds.energy_residual.values).max()),
    }
    if spec["mu"] == 0.0:
        ref = simulate(
            launched_hexagon(
                spec["columns"],
                spec["rows"],
                radius=RADIUS,
                speed=SPEED,
                t_end=spec["t_end"],
                scheme="paper",
                dt=REFERENCE_DT,
            ),
            progress=False,
        )
        out["reference"] = {"vx": ref.vx.values[-1].tolist(), "vy": ref.vy.values[-1].tolist()}
        out["error"] = _max_error(
            ds.vx.values[-1], ds.vy.values[-1], {k: np.array(v) for k, v in out["reference"].items()}
        )
    return out


def _lammps_worker(spec: dict) -> dict:
    """Runs in a fresh subprocess: LAMMPS on the frictionless packing, steps halved from
    LAMMPS_DT_START until its error is at most spec["error"]."""
    import resource

    import numpy as np

    from granplate.verification import lammps as L

    if L.unavailable():
        return {"skipped": L.unavailable()}
    s = L.launched_hexagon(spec["columns"], spec["rows"], radius=RADIUS, speed=SPEED, t_end=spec["t_end"])
    ref = {k: np.array(v) for k, v in spec["reference"].items()}
    L.run_hertz(L.launched_hexagon(2, 2, radius=RADIUS, t_end=1e-7), 1e-8, 1e-7)  # load the library once
    tried = []
    dt = LAMMPS_DT_START
    for _ in range(LAMMPS_HALVINGS + 1):
        res = L.run_hertz(s, dt, spec["t_end"])
        err = _max_error(res["vx"][-1], res["vy"][-1], ref)
        tried.append(
            {
                "dt_s": dt,
                "n_steps": res["n_steps"],
                "setup_s": res["setup_time_s"],
                "loop_s": res["loop_time_s"],
                "error": err,
            }
        )
        if as_accurate(err, spec["error"]):
            break
        dt /= 2.0
    return {
        **tried[-1],
        "reached": as_accurate(tried[-1]["error"], spec["error"]),
        "tried": tried,
        "rss_peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }


def run_in_subprocess(module: str, worker: str, spec: dict, processes: int = 1) -> dict:
    """Run `worker` (a function of granplate.bench.`module`) on `spec` in a fresh Python
    process (processes > 1: that many MPI processes by the environment's `mpirun`, each
    running the worker, rank 0's result kept); its result, or {"failed": the last line of
    its error}."""
    if processes > 1:
        mpirun = shutil.which("mpirun", path=os.path.dirname(sys.executable)) or shutil.which("mpirun")
        if mpirun is None:
            return {"skipped": "no mpirun beside this Python or on the PATH (pip install mpich)"}
        code = (
            f"import os, json; from granplate.bench import {module}; r = {module}.{worker}("
            "json.loads(open(os.environ['GRANPLATE_BENCH_SPEC']).read())); "
            "print('@@RESULT ' + json.dumps(r)) if os.environ.get('PMI_RANK', '0') == '0' else None"
        )
        with tempfile.TemporaryDirectory() as folder:  # every rank reads the spec from one file
            path = os.path.join(folder, "spec.json")
            with open(path, "w") as f:
                json.dump(spec, f)
            env = dict(os.environ, GRANPLATE_BENCH_SPEC=path)
            p = subprocess.run(
                [mpirun, "-np", str(processes), sys.executable, "-c", code], capture_output=True, text=True, env=env
            )
    else:
        code = (
            f"import sys, json; from granplate.bench import {module}; "
            f"print('@@RESULT ' + json.dumps({module}.{worker}(json.loads(sys.stdin.read()))))"
        )
        p = subprocess.run(
            [sys.executable, "-c", code], input=json.dumps(spec), capture_output=True, text=True, env=dict(os.environ)
        )
    for line in p.stdout.splitlines():
        if line.startswith("@@RESULT "):
            return json.loads(line[len("@@RESULT ") :])
    return {"failed": f"rc {p.returncode}: {(p.stderr.strip().splitlines() or [''])[-1]}"}


def per_contact_step_us(loop_s: float, n_steps: int, contacts: int) -> float:
    """1e6 loop_s / (n_steps contacts) [us]: the loop's cost per listed contact and step."""
    return 1e6 * loop_s / (n_steps * contacts) if n_steps and contacts else math.nan


def run_scaling(
    sizes=SIZES, frictions=FRICTIONS, t_end: float = T_END, scheme: str = "implicit", lammps: bool = True, log=print
) -> list[dict]:
    """The table's rows: one per (size, mu), each measured in fresh subprocesses."""
    rows = []
    for columns, rows_ in sizes:
        for mu in frictions:
            log(f"scaling: {granule_count(columns, rows_)} granules, mu = {mu:g} ...")
            spec = {"columns": columns, "rows": rows_, "mu": mu, "t_end": t_end, "scheme": scheme}
            row = {
                "dimension": 2,
                "columns": columns,
                "rows": rows_,
                "mu": mu,
                "scheme": scheme,
                "t_end_s": t_end,
                **run_in_subprocess("scaling", "_ours_worker", spec),
            }
            if "failed" not in row:
                row["us_per_step"] = 1e6 * row["loop_s"] / row["n_steps"]
                row["us_per_contact_step"] = per_contact_step_us(row["loop_s"], row["n_steps"], row["contacts"])
            if lammps and mu == 0.0 and "error" in row:
                log(f"scaling: {row['granules']} granules, LAMMPS ...")
                lm = run_in_subprocess(
                    "scaling", "_lammps_worker", {**spec, "error": row["error"], "reference": row["reference"]}
                )
                if "loop_s" in lm:
                    lm["us_per_contact_step"] = per_contact_step_us(lm["loop_s"], lm["n_steps"], row["contacts"])
                row["lammps"] = lm
            row.pop("reference", None)
            rows.append(row)
    return rows


def format_or_dash(v, fmt: str) -> str:
    """format(v, fmt), or '-' for None and NaN."""
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, fmt)


def format_scaling_table(rows: list[dict]) -> str:
    """The scaling table as Markdown (LAMMPS columns on the frictionless rows)."""
    lines = [
        "| granules | contacts | mu | set-up [s] | steps | loop [s] | us/step | us/(contact step) "
        "| peak [MiB] | error | LAMMPS dt [s] | LAMMPS steps | LAMMPS loop [s] | LAMMPS us/(contact step) "
        "| LAMMPS error |",
        "|" + " ---: |" * 15,
    ]
    for r in rows:
        if "failed" in r:
            lines.append(f"| {granule_count(r['columns'], r['rows']):,} | | {r['mu']:g} | {r['failed']} |" + " |" * 11)
            continue
        lm = r.get("lammps") or {}
        if "skipped" in lm or not lm:
            lcols = ["-"] * 5
        elif "failed" in lm:
            lcols = [lm["failed"]] + ["-"] * 4
        else:
            lcols = [
                format_or_dash(lm["dt_s"], ".2e") + ("" if lm["reached"] else " (not reached)"),
                f"{lm['n_steps']:,}",
                format_or_dash(lm["loop_s"], ".3g"),
                format_or_dash(lm["us_per_contact_step"], ".3f"),
                format_or_dash(lm["error"], ".1e"),
            ]
        lines.append(
            f"| {r['granules']:,} | {r['contacts']:,} | {r['mu']:g} | {r['setup_s']:.3f} | {r['n_steps']:,} "
            f"| {r['loop_s']:.3g} | {r['us_per_step']:.1f} | {r['us_per_contact_step']:.3f} "
            f"| {r['rss_peak_mib']:.0f} | {format_or_dash(r.get('error'), '.1e')} | " + " | ".join(lcols) + " |"
        )
    return "\n".join(lines)


def parse_sizes(text: str) -> list[tuple[int, int]]:
    """'4x3,32x32' -> [(4, 3), (32, 32)] (columns x rows; ValueError naming the bad item)."""
    return parse_pairs(text, "--sizes", "COLUMNSxROWS", "32x32", min_second=2)


def check_scheme(name: str) -> str | None:
    """The error line for a --scheme that is not a registered scheme, or None."""
    from granplate.model.inputs import SCHEME_NAMES

    if name not in SCHEME_NAMES:
        return f"--scheme {name!r}: allowed {', '.join(SCHEME_NAMES)}"
    return None


def main(args) -> int:
    """`granplate bench --scaling [--dimension 2|3] [--sizes 4x3,32x32] [--t-end T] [--scheme S]
    [--no-lammps] [--json FILE]` (--dimension 3: bench.scaling_space, sizes NXxNYxNZ)."""
    t_end = T_END if getattr(args, "t_end", None) is None else float(args.t_end)
    if not t_end > 0.0:
        print(f"granplate: error: --t-end {t_end}: must be > 0 [s]", file=sys.stderr)
        return 2
    scheme = getattr(args, "scheme", None) or "implicit"
    if check_scheme(scheme):
        print(f"granplate: error: {check_scheme(scheme)}", file=sys.stderr)
        return 2
    from granplate.model.dimension import of_number

    dimension = getattr(args, "dimension", None) or 2
    try:
        dim = of_number(dimension)
    except ValueError:
        print(f"granplate: error: --dimension {dimension}: allowed 2 (the plane) or 3 (space)", file=sys.stderr)
        return 2
    return int(SCALINGS[dim.name](args, t_end, scheme))


def plane_main(args, t_end: float, scheme: str) -> int:
    """The plane's scaling table (`main`, --dimension 2): a launched hexagonal packing per size."""
    try:
        sizes = parse_sizes(args.sizes) if getattr(args, "sizes", None) else SIZES
    except ValueError as err:
        print(f"granplate: error: {err}", file=sys.stderr)
        return 2
    rows = run_scaling(sizes, t_end=t_end, scheme=scheme, lammps=not getattr(args, "no_lammps", False))
    print()
    print(format_scaling_table(rows))
    write_report(args, rows)
    return 1 if any("failed" in r or "failed" in (r.get("lammps") or {}) for r in rows) else 0


def _space_main(args, t_end: float, scheme: str) -> int:
    from granplate.bench import scaling_space

    return int(scaling_space.main(args, t_end, scheme))


#: the scaling table by the dimension's name (model.dimension): the plane's, or space's
#: (bench.scaling_space)
SCALINGS = {"plane": plane_main, "space": _space_main}
