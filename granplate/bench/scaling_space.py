"""`granplate bench --scaling --dimension 3`: the granule-scaling table in space, how the 3D
granular loop's cost grows with the number of spheres, with and without friction, and
(where LAMMPS is installed) LAMMPS's time to the same accuracy on the same frictionless
packing (granplate.verification.lammps.run_hertz_3d).

The packing (`launched_fcc`): a free face-centred cubic packing (setup.layouts, kind
"fcc", NX x NY x NZ conventional cells of 4 sites, 2 NX lattice planes normal to x) of
steel spheres, R = 1 mm, nearest neighbours touching, no walls, no plate, no load, whose
first lattice plane is launched at 1 m/s in +x into the rest; undamped, dynamic
detection, the default (implicit) scheme unless asked (any name of
model.inputs.SCHEME_NAMES), run to a short t_end (default 20 us).

Each (size, mu) runs in a fresh subprocess as the plane's rows do (bench.scaling): a tiny
warm-up run, `build_model` (set-up), `simulate` (loop, steps), the peak resident memory,
then (frictionless rows) the reference, RK4 (the paper scheme) at REFERENCE_DT, and the
error max |v - v_ref| / SPEED over the spheres' three velocity components at t_end. LAMMPS
(another fresh subprocess) runs the same packing at steps from LAMMPS_DT_START, halved until
its error against the same v_ref is at most ours. The rows with friction under a law LAMMPS
has, under velocity Verlet (Mindlin's, `same_law`), are one algorithm in both codes: LAMMPS
runs them at our step and law, and the row says how far apart the two codes' velocities end.
So do the frictionless rows of more than REFERENCE_MAX_SPHERES spheres under velocity
Verlet, which have no reference to halve LAMMPS's step against (`lammps_at_our_step`).
"""

from __future__ import annotations

import dataclasses
import math
import sys

from granplate.bench.scaling import (
    FRICTIONS,
    LAMMPS_DT_START,
    LAMMPS_HALVINGS,
    RADIUS,
    REFERENCE_DT,
    SPEED,
    T_END,
    as_accurate,
    format_or_dash,
    per_contact_step_us,
    run_in_subprocess,
)
from granplate.bench import write_report

#: FCC packings (cells along x, y, z) of the table: 12, 108, 1,008, 2,916 and 10,192 spheres.
SIZES: tuple[tuple[int, int, int], ...] = ((3, 1, 1), (3, 3, 3), (6, 6, 7), (9, 9, 9), (14, 14, 13))
#: Sites per conventional FCC cell.
FCC_SITES = 4
#: Rows of more spheres than this run without the reference (RK4 at REFERENCE_DT), so
#: without an error, and keep the outputs at t = 0 and t_end alone: what they time is the
#: loop's cost per contact-step and the memory a million spheres take. Under velocity
#: Verlet LAMMPS runs them at our step (`lammps_at_our_step`): one algorithm, so one accuracy.
REFERENCE_MAX_SPHERES = 100_000


def sphere_count(cells: tuple[int, int, int]) -> int:
    """Spheres of an FCC packing of `cells` conventional cells: 4 nx ny nz."""
    return FCC_SITES * cells[0] * cells[1] * cells[2]


def launched_fcc(
    cells: tuple[int, int, int],
    radius: float = RADIUS,
    speed: float = SPEED,
    mu: float = 0.0,
    t_end: float = T_END,
    scheme: str = "implicit",
    dt: float | None = None,
    outputs: int = 20,
    law: str = "tanh",
):
    """A free FCC packing of touching steel spheres (radius [m], `cells` conventional cells,
    no walls, no plate, no load) whose first lattice plane (x smallest) moves at `speed`
    [m/s] in +x. Undamped, friction mu under the tangential law `law` (contact.tangential_law;
    under velocity Verlet a law LAMMPS has, with its torque arms: `torque_arm`),
    dynamic detection; `scheme` with its own step, or with dt [s] the fixed step dt
    (dt_initial = dt_max = dt); `outputs` output intervals."""
    from granplate.setup.geometry import layout_packing
    from granplate.setup.scenario import Contact, Load, Scenario, Solver, SpaceLattice, TimeSettings

    packing = layout_packing(SpaceLattice(kind="fcc", cells=tuple(cells), radius=radius, walls=()))
    first = set(packing.column1)
    granules = tuple(dataclasses.replace(g, vx=speed) if g.label in first else g for g in packing.granules)
    out = t_end / outputs
    time_settings = TimeSettings(t_end=t_end, output_interval=out, field_interval=out)
    if dt is not None:
        time_settings = dataclasses.replace(time_settings, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt))
    name = "fcc-" + "x".join(str(c) for c in cells)
    return Scenario(
        name=name,
        dimension=3,
        granules=granules,
        plate=None,
        load=Load(kind="none"),
        contact=Contact(
            mu=mu, alpha_n=0.0, pairs=(), detection="dynamic", tangential_law=law, torque_arm=torque_arm(law, scheme)
        ),
        time=time_settings,
        solver=Solver(scheme=scheme),
    )


def torque_arm(law: str, scheme: str) -> str:
    """contact.torque_arm of the packing: "lammps" (LAMMPS's arms, R - delta / 2) where
    LAMMPS runs the same tangential law under the same integrator (`same_law`), so that the
    two codes' runs are one algorithm; else the default."""
    return "lammps" if same_law(law, scheme) else "radius"


def same_law(law: str, scheme: str) -> bool:
    """Whether LAMMPS runs the frictional rows' law (a law with history it has: Mindlin's)
    under granplate's integrator (velocity Verlet, `scheme`)."""
    from granplate.verification.lammps import LAMMPS_TANGENTIAL

    return scheme == "verlet" and law in LAMMPS_TANGENTIAL


def lammps_at_our_step(mu: float, law: str, scheme: str, big: bool) -> bool:
    """Whether LAMMPS runs a row at granplate's own step (and the row keeps its velocities
    at t_end to compare): the rows with friction under a law LAMMPS has under our
    integrator (`same_law`), and, under velocity Verlet, the frictionless rows too big for
    the reference (`big`: above REFERENCE_MAX_SPHERES), where no step-halving to a
    reference's error can be done: velocity Verlet at one step is one algorithm in both codes."""
    if mu > 0.0:
        return same_law(law, scheme)
    return big and scheme == "verlet"


def outputs_on_steps(t_end: float, dt: float, outputs: int) -> int:
    """The most output intervals, at most `outputs`, that each hold a whole number of steps
    dt [s] to t_end [s]: granplate cuts a step to land on an output time, which LAMMPS run
    at one fixed step does not, so a row that LAMMPS runs at our step takes these."""
    n = max(1, round(t_end / dt))
    return max(k for k in range(1, max(1, outputs) + 1) if n % k == 0)


def _warm_up(scheme: str) -> None:
    """Load the compiled 3D kernels of `scheme` and of the reference's paper scheme (1 us runs)."""
    from granplate.results.run import simulate

    for name, dt in ((scheme, None), ("paper", 4e-8)):
        simulate(launched_fcc((1, 1, 1), t_end=1e-6, scheme=name, dt=dt), progress=False)


def max_error_3d(v: tuple, ref: dict) -> float:
    """max |v - v_ref| / SPEED over the spheres' vx, vy, vz at t_end (v: the three arrays)."""
    import numpy as np

    return float(max(np.abs(np.asarray(vc) - np.asarray(ref[k])).max() for vc, k in zip(v, ("vx", "vy", "vz"))) / SPEED)


def median_run(runs: list) -> tuple:
    """The run of median loop time among `runs` (tuples whose first item is the loop time
    [s]; of an even count the faster of the middle two)."""
    return sorted(runs, key=lambda r: r[0])[(len(runs) - 1) // 2]


def _ours_worker(spec: dict) -> dict:
    """Runs in a fresh subprocess: one (size, mu) of granplate; the reference when mu = 0
    (unless spec["reference"] is "skip"). The time the loop spends on its contact lists
    (`ContactLists.refresh`: the rebuilds the loop asks for, Python on one thread) is measured apart, so that the steps' own cost per contact-step can be read."""
    import os
    import resource
    import time
    import warnings

    import numpy as np

    from granplate.errors import YieldWarning
    from granplate.model.arrays import build_model
    from granplate.results.run import simulate
    from granplate.solver import run_contacts

    warnings.simplefilter("ignore", YieldWarning)  # Hertz's law is timed, elastic whatever the pressure
    skip = spec.get("reference") == "skip"
    _warm_up(spec["scheme"])
    cells = tuple(spec["cells"])
    law = spec.get("law", "tanh") if spec["mu"] > 0.0 else "tanh"
    outputs = spec.get("outputs", 20)
    s = launched_fcc(cells, mu=spec["mu"], t_end=spec["t_end"], scheme=spec["scheme"], outputs=outputs, law=law)
    at_our_step = lammps_at_our_step(spec["mu"], law, spec["scheme"], skip)
    if at_our_step:  # (LAMMPS at one fixed step cuts none to land on an output time)
        out = spec["t_end"] / outputs_on_steps(spec["t_end"], s.time.dt_max, outputs)
        s = dataclasses.replace(s, time=dataclasses.replace(s.time, output_interval=out, field_interval=out))
    s = dataclasses.replace(s, solver=dataclasses.replace(s.solver, threads=spec.get("threads")))
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # [KiB]: the imports and compiled kernels
    t0, c0 = time.perf_counter(), time.process_time()
    model = build_model(s)
    setup, setup_cpu = time.perf_counter() - t0, time.process_time() - c0
    lists_s = [0.0, 0.0]  # wall, CPU [s]
    refresh = run_contacts.ContactLists.refresh

    def timed_refresh(self, y):
        t, c = time.perf_counter(), time.process_time()
        try:
            return refresh(self, y)
        finally:
            lists_s[0] += time.perf_counter() - t
            lists_s[1] += time.process_time() - c

    run_contacts.ContactLists.refresh = timed_refresh  # type: ignore[method-assign]
    runs = []
    for _ in range(spec.get("repeats", 1)):  # the same run again: its median is reported
        lists_s[:] = [0.0, 0.0]
        t1, c1 = time.perf_counter(), time.process_time()
        ds = simulate(s, model=model, progress=False)
        run_s, run_cpu_s = time.perf_counter() - t1, time.process_time() - c1
        runs.append((float(ds.attrs["loop_time_s"]), ds, run_s, run_cpu_s, list(lists_s)))
    run_contacts.ContactLists.refresh = refresh  # type: ignore[method-assign]
    loop_s, ds, run_s, run_cpu_s, lists_s = median_run(runs)
    out = {
        "granules": len(s.granules),
        "contacts": int(len(model.pairs)),
        "setup_s": setup,
        "setup_cpu_s": setup_cpu,
        "n_steps": int(ds.attrs["n_steps"]),
        "loop_s": loop_s,
        "loop_cpu_s": float(ds.attrs["loop_cpu_s"]),
        "lists_s": lists_s[0],
        "lists_cpu_s": lists_s[1],
        "steps_s": loop_s - lists_s[0],
        "steps_cpu_s": float(ds.attrs["loop_cpu_s"]) - lists_s[1],
        "end_s": run_s - loop_s - float(ds.attrs["first_call_time_s"]),
        "run_s": run_s,
        "run_cpu_s": run_cpu_s,
        "rss_peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "bytes_per_sphere": (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) * 1024.0 / len(s.granules),
        "load_average": load,
        "energy_residual": float(np.abs(ds.energy_residual.values).max()),
        "threads": int(ds.attrs.get("threads", 1)),
        "loop_s_runs": [r[0] for r in runs],
    }
    if at_our_step:  # LAMMPS runs this step and law
        out["final"] = {k: ds[k].values[-1].tolist() for k in ("vx", "vy", "vz")}
        out["dt_s"] = float(s.time.dt_max)
    if spec["mu"] == 0.0 and not skip:
        if spec.get("reference") is None:
            ref = simulate(launched_fcc(cells, t_end=spec["t_end"], scheme="paper", dt=REFERENCE_DT), progress=False)
            out["reference"] = {k: ref[k].values[-1].tolist() for k in ("vx", "vy", "vz")}
        else:
            out["reference"] = spec["reference"]
        out["error"] = max_error_3d(tuple(ds[k].values[-1] for k in ("vx", "vy", "vz")), out["reference"])
    return out


def _lammps_worker(spec: dict) -> dict:
    """Runs in a fresh subprocess: LAMMPS (run_hertz_3d) on the frictionless packing, steps
    halved from LAMMPS_DT_START until its error is at most spec["error"]."""
    import resource
    import time

    from granplate.verification import lammps as L

    if L.unavailable():
        return {"skipped": L.unavailable()}
    s = launched_fcc(tuple(spec["cells"]), t_end=spec["t_end"])
    L.run_hertz_3d(launched_fcc((1, 1, 1), t_end=1e-7), 1e-8, 1e-7)  # load the library once
    tried = []
    dt = LAMMPS_DT_START
    for _ in range(LAMMPS_HALVINGS + 1):
        c0 = time.process_time()
        res = L.run_hertz_3d(s, dt, spec["t_end"])
        cpu = time.process_time() - c0
        err = max_error_3d(tuple(res[k][-1] for k in ("vx", "vy", "vz")), spec["reference"])
        tried.append(
            {
                "dt_s": dt,
                "n_steps": res["n_steps"],
                "setup_s": res["setup_time_s"],
                "loop_s": res["loop_time_s"],
                "cpu_s": cpu,
                "error": err,
            }
        )
        if as_accurate(err, spec["error"]):
            break
        dt /= 2.0
    last = tried[-1]
    runs = [(last["loop_s"], last)]
    for _ in range(spec.get("repeats", 1) - 1):  # the accurate step again: its median is reported
        c0 = time.process_time()
        res = L.run_hertz_3d(s, last["dt_s"], spec["t_end"])
        runs.append((res["loop_time_s"], {**last, "loop_s": res["loop_time_s"], "cpu_s": time.process_time() - c0}))
    tried[-1] = median_run(runs)[1]
    return {
        **tried[-1],
        "loop_s_runs": [r[0] for r in runs],
        "reached": as_accurate(tried[-1]["error"], spec["error"]),
        "tried": tried,
        "rss_peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }


def _lammps_same_law_worker(spec: dict) -> dict:
    """Runs in a fresh subprocess (on the row's MPI processes): LAMMPS (run_hertz_3d) on the
    frictional packing under the same tangential law and torque arms at granplate's own
    step (spec["dt_s"]): the same algorithm, so the same accuracy; `agreement`: the largest
    |v - v_granplate| at t_end over the launch speed (spec["final"]: granplate's velocities)."""
    import resource
    import time

    from granplate.verification import lammps as L

    if L.unavailable():
        return {"skipped": L.unavailable()}
    s = launched_fcc(tuple(spec["cells"]), mu=spec["mu"], t_end=spec["t_end"], scheme=spec["scheme"], law=spec["law"])
    L.run_hertz_3d(launched_fcc((1, 1, 1), t_end=1e-7), 1e-8, 1e-7)  # load the library once
    runs = []
    for _ in range(spec.get("repeats", 1)):  # its median is reported
        c0 = time.process_time()
        res = L.run_hertz_3d(s, spec["dt_s"], spec["t_end"])
        runs.append((res["loop_time_s"], res, time.process_time() - c0))
    _, res, cpu = median_run(runs)
    return {
        "loop_s_runs": [r[0] for r in runs],
        "dt_s": spec["dt_s"],
        "n_steps": res["n_steps"],
        "setup_s": res["setup_time_s"],
        "loop_s": res["loop_time_s"],
        "cpu_s": cpu,
        "error": None,
        "agreement": max_error_3d(tuple(res[k][-1] for k in ("vx", "vy", "vz")), spec["final"]),
        "reached": True,
        "rss_peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }


def run_scaling_space(
    sizes=SIZES,
    frictions=FRICTIONS,
    t_end: float = T_END,
    scheme: str = "implicit",
    lammps: bool = True,
    log=print,
    threads: tuple[int, ...] = (1,),
    law: str = "tanh",
    repeats: int = 1,
) -> list[dict]:
    """The 3D table's rows: one per (size, mu, thread count), each measured in fresh
    subprocesses, the rows with friction under the tangential law `law`
    (contact.tangential_law); `speedup` is the loop's time on one thread over this row's. LAMMPS runs
    the frictionless rows, and those of a law it has under velocity Verlet (`same_law`), on
    as many MPI processes as the row has threads (`mpirun -np N`, its shrink-wrapped box cut
    into N domains). Each run is timed `repeats` times in its process (granplate's after
    its first run, LAMMPS's at the step it keeps), the median reported."""
    rows = []
    for cells in sizes:
        for mu in frictions:
            reference, one_thread = None, None
            for n in threads:
                log(f"scaling in space: {sphere_count(cells)} spheres, mu = {mu:g}, {n} thread(s) ...")
                row = _space_row(cells, mu, t_end, scheme, n, reference, lammps, log, law, repeats)
                reference = row.pop("reference", reference)
                if n == 1 and "loop_s" in row:
                    one_thread = row["loop_s"]
                if one_thread is not None and "loop_s" in row:
                    row["speedup"] = one_thread / row["loop_s"]
                rows.append(row)
    return rows


def _space_row(
    cells, mu: float, t_end: float, scheme: str, n: int, reference, lammps: bool, log, law: str = "tanh", repeats=1
) -> dict:
    """One row of the 3D table: granplate on n threads (friction under `law`) and
    (frictionless, `lammps`) LAMMPS on n MPI processes to the same accuracy."""
    big = sphere_count(cells) > REFERENCE_MAX_SPHERES
    spec = {
        "cells": list(cells),
        "mu": mu,
        "t_end": t_end,
        "scheme": scheme,
        "threads": n,
        "reference": "skip" if big else reference,
        "outputs": 1 if big else 20,
        "law": law,
        "repeats": repeats,
    }
    row = {
        "dimension": 3,
        "cells": list(cells),
        "mu": mu,
        "law": law if mu > 0.0 else "-",
        "scheme": scheme,
        "t_end_s": t_end,
        "repeats": repeats,
        **run_in_subprocess("scaling_space", "_ours_worker", spec),
    }
    row["threads"] = n
    if "failed" not in row:
        row["us_per_step"] = 1e6 * row["loop_s"] / row["n_steps"]
        row["us_per_contact_step"] = per_contact_step_us(row["loop_s"], row["n_steps"], row["contacts"])
        row["cpu_us_per_contact_step"] = per_contact_step_us(row["loop_cpu_s"], row["n_steps"], row["contacts"])
        row["steps_us_per_contact_step"] = per_contact_step_us(row["steps_s"], row["n_steps"], row["contacts"])
        row["steps_cpu_us_per_contact_step"] = per_contact_step_us(row["steps_cpu_s"], row["n_steps"], row["contacts"])
    lm = None
    if lammps and mu == 0.0 and "error" in row:
        log(f"scaling in space: {row['granules']} spheres, LAMMPS on {n} process(es) ...")
        lm = run_in_subprocess(
            "scaling_space", "_lammps_worker", {**spec, "error": row["error"], "reference": row["reference"]}, n
        )
    elif lammps and "final" in row:
        log(f"scaling in space: {row['granules']} spheres, LAMMPS at our step and law on {n} process(es) ...")
        same = {**spec, "dt_s": row["dt_s"], "final": row.pop("final")}
        lm = run_in_subprocess("scaling_space", "_lammps_same_law_worker", same, n)
    row.pop("final", None)
    if lm is not None:
        if "loop_s" in lm:
            lm["us_per_contact_step"] = per_contact_step_us(lm["loop_s"], lm["n_steps"], row["contacts"])
            lm["cpu_us_per_contact_step"] = per_contact_step_us(lm["cpu_s"], lm["n_steps"], row["contacts"])
        lm["processes"] = n
        row["lammps"] = lm
    return row


def format_space_table(rows: list[dict]) -> str:
    """The 3D scaling table as Markdown (LAMMPS columns on the frictionless rows, and on the
    frictional rows whose law LAMMPS runs at our step: `same_law`)."""
    lines = [
        "| spheres | cells | contacts | mu | threads | set-up [s] | steps | loop [s] | speed-up | us/step "
        "| us/(contact step) | CPU us/(contact step) | peak [MiB] | error | LAMMPS dt [s] | LAMMPS steps "
        "| LAMMPS loop [s] | LAMMPS us/(contact step) | LAMMPS CPU us/(contact step) | LAMMPS error "
        "| lists [s] | steps' us/(contact step) | steps' CPU us/(contact step) | result [s] | bytes/sphere | load |",
        "|" + " ---: |" * 26,
    ]
    for r in rows:
        cells = "x".join(str(c) for c in r["cells"])
        if "failed" in r:
            lines.append(
                f"| {sphere_count(r['cells']):,} | {cells} | | {mu_law(r)} | {r.get('threads', 1)} | {r['failed']} |"
                + " |" * 20
            )
            continue
        lm = r.get("lammps") or {}
        if "skipped" in lm or not lm:
            lcols = ["-"] * 6
        elif "failed" in lm:
            lcols = [lm["failed"]] + ["-"] * 5
        else:
            lcols = [
                format_or_dash(lm["dt_s"], ".2e") + ("" if lm["reached"] else " (not reached)"),
                f"{lm['n_steps']:,}",
                format_or_dash(lm["loop_s"], ".3g"),
                format_or_dash(lm["us_per_contact_step"], ".3f"),
                format_or_dash(lm["cpu_us_per_contact_step"], ".3f"),
                lammps_error(lm),
            ]
        lines.append(
            f"| {r['granules']:,} | {cells} | {r['contacts']:,} | {mu_law(r)} | {r.get('threads', 1)} "
            f"| {r['setup_s']:.3f} | {r['n_steps']:,} | {r['loop_s']:.3g} | {format_or_dash(r.get('speedup'), '.2f')} "
            f"| {r['us_per_step']:.1f} "
            f"| {r['us_per_contact_step']:.3f} | {r['cpu_us_per_contact_step']:.3f} "
            f"| {r['rss_peak_mib']:.0f} | {format_or_dash(r.get('error'), '.1e')} | "
            + " | ".join(lcols)
            + " | "
            + " | ".join(_more_columns(r))
            + " |"
        )
    return "\n".join(lines)


def lammps_error(lm: dict) -> str:
    """The LAMMPS error column: its error against the reference, or, run at granplate's
    step under the same law, how far its velocities are from granplate's (over the launch
    speed)."""
    if lm.get("agreement") is not None:
        return f"same step and law: {lm['agreement']:.1e} from ours"
    return format_or_dash(lm["error"], ".1e")


def _more_columns(r: dict) -> list[str]:
    """A row's last columns: its contact lists' time [s], its steps' own cost per
    contact-step [us], the result's making after the loop [s], bytes per sphere at the
    peak, the load average at its start ("-" where a row has none)."""
    return [
        format_or_dash(r.get("lists_s"), ".3g"),
        format_or_dash(r.get("steps_us_per_contact_step"), ".3f"),
        format_or_dash(r.get("steps_cpu_us_per_contact_step"), ".3f"),
        format_or_dash(r.get("end_s"), ".3g"),
        format_or_dash(r.get("bytes_per_sphere"), ".0f"),
        format_or_dash(r.get("load_average"), ".1f"),
    ]


def mu_law(row: dict) -> str:
    """The mu column: mu, and its tangential law where it is not the default tanh."""
    law = row.get("law", "-")
    return f"{row['mu']:g}" + (f" ({law})" if law not in ("-", "tanh") else "")


def parse_cells(text: str) -> list[tuple[int, int, int]]:
    """'3x3x3,6x6x7' -> [(3, 3, 3), (6, 6, 7)] (FCC cells along x, y, z; ValueError naming
    the bad item and the allowed form)."""
    out = []
    for item in text.split(","):
        parts = item.strip().lower().split("x")
        if len(parts) != 3 or not all(p.strip().isdigit() and int(p) >= 1 for p in parts):
            raise ValueError(
                f"--sizes item {item!r}: allowed NXxNYxNZ (FCC cells along x, y, z) with integers >= 1, e.g. 6x6x7"
            )
        out.append((int(parts[0]), int(parts[1]), int(parts[2])))
    return out


def parse_threads(text: str | None, scheme: str) -> tuple[int, ...]:
    """'1,2' -> (1, 2) (ValueError naming the bad item and the range); None: 1 and every
    core for a threaded scheme (setup.threads.THREADED_SCHEMES), else 1 alone."""
    from granplate.setup.threads import THREADED_SCHEMES, available_threads

    n = available_threads()
    if text is None:
        return (1, n) if scheme in THREADED_SCHEMES and n > 1 else (1,)
    out = []
    for item in text.split(","):
        if not item.strip().isdigit() or not 1 <= int(item) <= n:
            raise ValueError(
                f"--threads item {item!r}: allowed integers from 1 to {n} (this machine's cores), e.g. 1,{n}"
            )
        out.append(int(item))
    return tuple(out)


def parse_frictions(text: str | None) -> tuple[float, ...]:
    """'0,0.5' -> (0.0, 0.5) (ValueError naming the bad item and the range); None: FRICTIONS."""
    if text is None:
        return FRICTIONS
    out = []
    for item in text.split(","):
        try:
            mu = float(item)
        except ValueError:
            mu = math.nan
        if not 0.0 <= mu <= 1e3:
            raise ValueError(f"--mu item {item!r}: allowed numbers from 0 to 1000 (friction coefficients), e.g. 0,0.5")
        out.append(mu)
    return tuple(out)


def main(args, t_end: float, scheme: str) -> int:
    """`granplate bench --scaling --dimension 3 [--sizes 3x3x3,6x6x7] ...` (t_end and scheme
    checked by bench.scaling.main)."""
    try:
        sizes = parse_cells(args.sizes) if getattr(args, "sizes", None) else SIZES
    except ValueError as err:
        print(f"granplate: error: {err}", file=sys.stderr)
        return 2
    try:
        threads = parse_threads(getattr(args, "threads", None), scheme)
    except ValueError as err:
        print(f"granplate: error: {err}", file=sys.stderr)
        return 2
    try:
        frictions = parse_frictions(getattr(args, "mu", None))
    except ValueError as err:
        print(f"granplate: error: {err}", file=sys.stderr)
        return 2
    law = getattr(args, "friction_law", None) or "tanh"
    repeats = getattr(args, "repeats", None)
    repeats = 1 if repeats is None else repeats
    if repeats < 1:
        print(f"granplate: error: --repeats {repeats}: allowed integers from 1", file=sys.stderr)
        return 2
    if law != "tanh" and scheme != "verlet":
        print(f"granplate: error: --friction-law {law}: runs under --scheme verlet only", file=sys.stderr)
        return 2
    rows = run_scaling_space(
        sizes,
        frictions=frictions,
        t_end=t_end,
        scheme=scheme,
        lammps=not getattr(args, "no_lammps", False),
        threads=threads,
        law=law,
        repeats=repeats,
    )
    print()
    print(format_space_table(rows))
    write_report(args, rows)
    return 1 if any("failed" in r or "failed" in (r.get("lammps") or {}) for r in rows) else 0
