"""`granplate bench --solid --coupled`: what a coupled run of the 3D solid costs, and which
cut-off (plate.max_frequency) its contact forces need.

The protector (`protector`): a free FCC stack of steel spheres (setup.layouts, kind "fcc",
R = 5 mm, CELLS conventional cells: 3 cells, six lattice planes along x, 300 spheres, no
walls) pressed on the xmin face of a 5 x 100 x 100 mm steel plate (hex20, clamped on its
four edges ymin, ymax, zmin, zmax) by a half-sine force along +x on the first plane
(load.kind = "force"), 1 ms, velocity Verlet at a fixed step (solver.scheme = "verlet",
granular_friction = "split"). The sphere drop (`sphere_drop`): one such sphere at
DROP_SPEED onto the plate's centre, without load.

Each row runs in a fresh subprocess (bench.scaling.run_in_subprocess): set-up is
`build_model` (the solid's build, with its modes and residual compliance; "uncached" in an
empty run store, the first repeat's; "cached" the same build again from the store), loop
and steps from the run's attributes. The tables: the cost of one coupled step on the
protector; its growth with the dofs (MESHES), the modes (FREQUENCIES), the spheres in
touch (SIZES) and the step (DTS); the cut-off tables of the protector and of a 5 mm and a
2 mm sphere's drop (CUTOFFS against REFERENCE_CUTOFF): the plate's peak energy share
max E_plate / E_in and the peak contact force on the body, each against the reference's.
"""

from __future__ import annotations

import math
import statistics
import sys

from granplate.bench import write_report

#: The spheres [m], their FCC cells (along x, y, z: 300 spheres) and the plate [m].
RADIUS = 0.005
CELLS = (3, 5, 5)
PLATE_THICKNESS = 0.005
PLATE_SPAN = 0.1
PLATE_CLAMPS = ("ymin", "ymax", "zmin", "zmax")
#: The plate's mesh of the cost table (elements along x, y, z: through the thickness first).
MESH = (2, 20, 20)
#: The half-sine force on the first plane [N] and its duration [s]; simulated time [s].
FORCE = 500.0
DURATION = 1.0e-4
T_END = 1.0e-3
#: The fixed step [s] (time.dt_max = dt_initial) and output interval [s] of the protector
#: (1e-6 s breaks the energy balance's tolerance 1e-4 on the loaded plane's pairs, at 13 us),
#: and the steps of the step table.
DT = 5.0e-7
DTS: tuple[float, ...] = (1.0e-7, 2.0e-7, 5.0e-7, 1.0e-6)
OUTPUT_INTERVAL = 1.0e-6
#: The cut-off of the cost table [Hz] (100 kHz, as `bench --solid`'s plate; the default,
#: setup.scenario.SOLID_MAX_FREQUENCY, is 150 kHz: the modes table has both).
MAX_FREQUENCY = 1.0e5
#: Growth with the dofs, the modes and the spheres in touch.
MESHES: tuple[tuple[int, int, int], ...] = ((1, 10, 10), (2, 20, 20), (2, 40, 40))
FREQUENCIES: tuple[float, ...] = (5.0e4, 1.0e5, 1.5e5, 2.0e5)
SIZES: tuple[tuple[int, int, int], ...] = ((3, 1, 1), (3, 3, 3), (3, 5, 5))
#: The cut-off table: the cut-offs measured [Hz] against a much higher one.
CUTOFFS: tuple[float, ...] = (2.5e4, 5.0e4, 1.0e5, 1.5e5, 2.0e5)
REFERENCE_CUTOFF = 3.0e5
#: The sphere drop: impact speed [m/s], its step [s], simulated time [s] and output interval [s].
DROP_SPEED = 1.0
DROP_DT = 5.0e-8
DROP_T_END = 1.0e-4
DROP_OUTPUT = 1.0e-7
#: The small sphere's drop: its radius [m], step [s] and simulated time [s] (a contact
#: about 2.5 times shorter).
SMALL_RADIUS = 0.002
SMALL_DT = 2.0e-8
SMALL_T_END = 5.0e-5
#: The tolerance of the chosen cut-off: both measures within 1% of the reference's.
WITHIN = 0.01


def protector(
    cells=CELLS,
    mesh=MESH,
    max_frequency: float = MAX_FREQUENCY,
    dt: float = DT,
    t_end: float = T_END,
    output_interval: float = OUTPUT_INTERVAL,
    element: str = "hex20",
):
    """The protector scenario (module docstring): `cells` FCC cells of steel spheres of
    RADIUS, the plate's face xmin against the last plane's surfaces, centred on the stack in
    y and z; `mesh` the plate's elements (x, y, z), `max_frequency` [Hz] its cut-off; fixed
    step dt [s]."""
    from granplate.setup.geometry import layout_packing
    from granplate.setup.scenario import Load, Scenario, Solid, Solver, SpaceLattice

    packing = layout_packing(SpaceLattice(kind="fcc", cells=tuple(cells), radius=RADIUS, walls=()))
    granules = packing.granules
    x_face = max(g.x + g.radius for g in granules)
    cy = 0.5 * (min(g.y for g in granules) + max(g.y for g in granules))
    cz = 0.5 * (min(g.z for g in granules) + max(g.z for g in granules))
    plate = Solid(
        size=(PLATE_THICKNESS, PLATE_SPAN, PLATE_SPAN),
        elements=tuple(mesh),
        origin=(x_face, cy - 0.5 * PLATE_SPAN, cz - 0.5 * PLATE_SPAN),
        material="steel",
        element=element,
        clamped=PLATE_CLAMPS,
        max_frequency=max_frequency,
    )
    load = Load(
        kind="force", force=FORCE, duration=DURATION, direction=(1.0, 0.0, 0.0), granules=tuple(packing.column1)
    )
    name = "protector-" + "x".join(str(c) for c in cells)
    return Scenario(
        name=name,
        dimension=3,
        granules=granules,
        plate=plate,
        load=load,
        time=_fixed_step(t_end, dt, output_interval),
        solver=Solver(scheme="verlet", granular_friction="split"),
    )


def sphere_drop(
    mesh=MESH,
    max_frequency: float = MAX_FREQUENCY,
    dt: float = DROP_DT,
    t_end: float = DROP_T_END,
    output_interval: float = DROP_OUTPUT,
    radius: float = RADIUS,
):
    """One steel sphere of `radius` [m] at DROP_SPEED along +x, touching the centre of the
    protector's plate (same mesh and clamps) at t = 0, no load."""
    from granplate.setup.scenario import Granule, Load, Scenario, Solid, Solver

    plate = Solid(
        size=(PLATE_THICKNESS, PLATE_SPAN, PLATE_SPAN),
        elements=tuple(mesh),
        origin=(radius, -0.5 * PLATE_SPAN, -0.5 * PLATE_SPAN),
        material="steel",
        clamped=PLATE_CLAMPS,
        max_frequency=max_frequency,
    )
    ball = Granule(0.0, 0.0, radius, "steel", label="ball", z=0.0, vx=DROP_SPEED, omega=(0.0, 0.0, 0.0))
    return Scenario(
        name="sphere-drop",
        dimension=3,
        granules=(ball,),
        plate=plate,
        load=Load(kind="none"),
        time=_fixed_step(t_end, dt, output_interval),
        solver=Solver(scheme="verlet", granular_friction="split"),
    )


def _fixed_step(t_end: float, dt: float, output_interval: float):
    """TimeSettings of a fixed step dt [s] (dt_initial = dt_max = dt)."""
    from granplate.setup.scenario import TimeSettings

    return TimeSettings(
        t_end=t_end,
        dt_initial=dt,
        dt_max=dt,
        dt_min=min(1e-13, dt),
        output_interval=output_interval,
        field_interval=max(output_interval, t_end / 20.0),
    )


def scenario_of(spec: dict):
    """The scenario a row's spec names: {"case": "protector" | "drop", "mesh", "max_frequency",
    "dt", "t_end", "cells" (the protector's), "radius" (the drop's)}."""
    keys = {
        k: (tuple(v) if isinstance(v, list) else v)
        for k, v in spec.items()
        if k in ("mesh", "max_frequency", "dt", "t_end", "cells", "radius")
    }
    if spec.get("case", "protector") == "drop":
        keys.pop("cells", None)
        return sphere_drop(**keys)
    keys.pop("radius", None)
    return protector(**keys)


def run_measures(ds) -> dict:
    """What a run's Dataset says: steps, loop [s], the plate's peak energy share max E_plate /
    E_in (E_in = E_shock at t_end + E_initial), the peak contact force on the body [N] (at the
    output times), the most contacts in touch at once, the largest |energy residual|."""
    import numpy as np

    e_in = float(ds.E_shock.values[-1]) + float(ds.attrs.get("E_initial", 0.0))
    normal = ds.body_contact_normal_force.values
    return {
        "n_steps": int(ds.attrs["n_steps"]),
        "loop_s": float(ds.attrs["loop_time_s"]),
        "loop_cpu_s": float(ds.attrs["loop_cpu_s"]),
        "n_modes": int(ds.sizes.get("mode", 0)),
        "plate_share": float(ds.E_plate.values.max() / e_in) if e_in > 0.0 else math.nan,
        "peak_force_n": float(normal.max()) if normal.size else 0.0,
        "in_touch": int((normal > 0.0).sum(axis=1).max()) if normal.size else 0,
        "energy_residual": float(np.abs(ds.energy_residual_max.values).max()),
        "e_in_j": e_in,
    }


def _worker(spec: dict) -> dict:
    """Runs in a fresh subprocess (run store GRANPLATE_CACHE as given): build_model timed
    twice (the first uncached when the store is empty), then the run."""
    import resource
    import time
    import warnings

    from granplate.errors import YieldWarning
    from granplate.model.arrays import build_model
    from granplate.results.run import simulate

    warnings.simplefilter("ignore", YieldWarning)
    s = scenario_of(spec)
    t0 = time.perf_counter()
    build_model(s)
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    model = build_model(s)
    again = time.perf_counter() - t0
    ds = simulate(s, model=model, progress=False)
    dofs = int(len(model.solid.dofs)) if model.solid is not None else None
    return {
        "granules": len(s.granules),
        "setup_first_s": first,
        "setup_cached_s": again,
        "n_dofs": dofs,
        "rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        **run_measures(ds),
    }


def run_row(spec: dict, fresh: bool = False) -> dict:
    """One row in a fresh subprocess; fresh: with an empty run store (its first build is
    the set-up uncached, `setup_uncached_s`)."""
    import os
    import tempfile

    from granplate.bench.scaling import run_in_subprocess

    if not fresh:
        return {**spec, **run_in_subprocess("solid_coupled", "_worker", spec)}
    old = os.environ.get("GRANPLATE_CACHE")
    with tempfile.TemporaryDirectory(prefix="granplate-coupled-bench-") as cache:
        os.environ["GRANPLATE_CACHE"] = cache
        try:
            row = {**spec, **run_in_subprocess("solid_coupled", "_worker", spec)}
        finally:
            if old is None:
                os.environ.pop("GRANPLATE_CACHE", None)
            else:
                os.environ["GRANPLATE_CACHE"] = old
    if "setup_first_s" in row:
        row["setup_uncached_s"] = row["setup_first_s"]
    return row


def us_per_step(row: dict, key: str = "loop_s") -> float:
    """The loop's cost of one coupled step [us]: wall clock (loop_s) or CPU (loop_cpu_s)."""
    return 1e6 * row[key] / row["n_steps"] if row.get("n_steps") else math.nan


def relative_change(value: float, reference: float) -> float:
    """(value - reference) / |reference| (nan when the reference is 0)."""
    return (value - reference) / abs(reference) if reference else math.nan


def chosen_cutoff(rows: list[dict], reference: dict, within: float = WITHIN) -> float | None:
    """The lowest cut-off [Hz] whose peak energy share and peak contact force are both
    within `within` (relative) of the reference's, and stay so at every higher cut-off of
    `rows`; None when none is."""
    ok = [
        r["max_frequency"]
        for r in rows
        if abs(relative_change(r["plate_share"], reference["plate_share"])) <= within
        and abs(relative_change(r["peak_force_n"], reference["peak_force_n"])) <= within
    ]
    fine = sorted(f for f in ok if all(g in ok for g in (r["max_frequency"] for r in rows) if g >= f))
    return fine[0] if fine else None


def _cell(x, fmt: str) -> str:
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, fmt)


def _mesh(row: dict) -> str:
    return " x ".join(str(n) for n in row.get("mesh", MESH))


def format_cost(rows: list[dict]) -> str:
    """The cost table as Markdown: one row per run."""
    head = (
        "| case | spheres | mesh | free dofs | modes | cut-off [Hz] | dt [s] | set-up uncached [s] "
        "| set-up cached [s] | steps | loop [s] | us/step | CPU us/step | in touch | energy residual |"
    )
    lines = [head, "|" + " ---: |" * (head.count("|") - 1)]
    for r in rows:
        if "failed" in r:
            lines.append(f"| {r.get('case', 'protector')} | | {_mesh(r)} | {r['failed'][:200]} |" + " |" * 11)
            continue
        uncached = r.get("setup_uncached_s")
        lines.append(
            f"| {r.get('case', 'protector')} | {r['granules']:,} | {_mesh(r)} | {_cell(r['n_dofs'], ',')} "
            f"| {r['n_modes']} | {r['max_frequency']:.3g} | {r['dt']:.2g} | {_cell(uncached, '.1f')} "
            f"| {r['setup_cached_s']:.2f} | {r['n_steps']:,} | {r['loop_s']:.1f} "
            f"| {us_per_step(r):.0f} | {us_per_step(r, 'loop_cpu_s'):.0f} | {r['in_touch']} "
            f"| {r['energy_residual']:.1e} |"
        )
    return "\n".join(lines)


def format_cutoffs(rows: list[dict], reference: dict) -> str:
    """The cut-off table as Markdown: each cut-off's modes, peak energy share and peak
    contact force, each against the reference's."""
    lines = [
        "| case | cut-off [Hz] | modes | plate's peak share | vs reference | peak force [N] | vs reference | us/step |",
        "|" + " ---: |" * 8,
    ]
    for r in [*rows, reference]:
        if "failed" in r:
            lines.append(f"| {r.get('case')} | {r['max_frequency']:.3g} | {r['failed']} |" + " |" * 5)
            continue
        ds = relative_change(r["plate_share"], reference["plate_share"])
        df = relative_change(r["peak_force_n"], reference["peak_force_n"])
        lines.append(
            f"| {r.get('case')} | {r['max_frequency']:.3g} | {r['n_modes']} | {100 * r['plate_share']:.3f}% "
            f"| {100 * ds:+.2f}% | {r['peak_force_n']:.2f} | {100 * df:+.2f}% | {us_per_step(r):.0f} |"
        )
    return "\n".join(lines)


def median_row(rows: list[dict]) -> dict:
    """One row from repeats of the same run: each timing the median (the set-up uncached
    the first's, the only one in an empty store), the rest the first's."""
    if len(rows) == 1 or any("failed" in r for r in rows):
        return rows[0]
    out = dict(rows[0])
    for k in ("setup_cached_s", "loop_s", "loop_cpu_s"):
        out[k] = statistics.median(r[k] for r in rows)
    out["repeats"] = len(rows)
    return out


def spec_of(case: str = "protector", **kw) -> dict:
    """A row's spec with the defaults of its case."""
    base = {"case": case, "mesh": list(MESH), "max_frequency": MAX_FREQUENCY}
    if case == "drop":
        base.update(dt=DROP_DT, t_end=DROP_T_END)
    else:
        base.update(dt=DT, t_end=T_END, cells=list(CELLS))
    base.update({k: (list(v) if isinstance(v, tuple) else v) for k, v in kw.items()})
    return base


def run_all(quick: bool = False, repeats: int = 1, log=print) -> dict:
    """Every table's rows; the cost tables' timings the median of `repeats` runs (the
    cut-off tables' once: their measures are deterministic). quick: a smoke run of 0.1 ms
    without the finest mesh, the highest cut-offs and the step table, and the 5 mm drop's
    cut-off table only, against 100 kHz."""
    t_end = T_END / 10.0 if quick else T_END
    meshes = MESHES[:-1] if quick else MESHES
    frequencies = tuple(f for f in FREQUENCIES if f < MAX_FREQUENCY) if quick else FREQUENCIES
    report: dict = {}

    def row(spec):
        log(f"coupled solid: {spec} x {repeats} ...")
        return median_row([run_row(spec, fresh=k == 0) for k in range(repeats)])

    report["cost"] = [row(spec_of(t_end=t_end))]
    report["dofs"] = [row(spec_of(mesh=m, t_end=t_end)) for m in meshes if tuple(m) != MESH]
    report["modes"] = [row(spec_of(max_frequency=f, t_end=t_end)) for f in frequencies if f != MAX_FREQUENCY]
    report["spheres"] = [row(spec_of(cells=c, t_end=t_end)) for c in SIZES if tuple(c) != CELLS]
    report["steps"] = [] if quick else [row(spec_of(dt=dt, t_end=t_end)) for dt in DTS if dt != DT]
    if quick:
        report["cutoff_drop"] = cutoff_table("drop", {}, CUTOFFS[:2], MAX_FREQUENCY, log=log)
        return report
    cases = {
        "drop": ("drop", {}),
        "drop_small": ("drop", {"radius": SMALL_RADIUS, "dt": SMALL_DT, "t_end": SMALL_T_END}),
        "protector": ("protector", {"t_end": t_end}),
    }
    for key, (case, kw) in cases.items():
        report[f"cutoff_{key}"] = cutoff_table(case, kw, log=log)
    return report


def cutoff_table(case: str, kw: dict, cutoffs=CUTOFFS, reference: float = REFERENCE_CUTOFF, log=print) -> dict:
    """The cut-off table of one case (spec keywords kw): its rows, the reference's and the
    chosen cut-off (`chosen_cutoff`)."""
    log(f"coupled solid: cut-offs of the {case} {kw} ...")
    rows = [run_row(spec_of(case, max_frequency=f, **kw)) for f in cutoffs]
    ref = run_row(spec_of(case, max_frequency=reference, **kw))
    return {
        "rows": rows,
        "reference": ref,
        "chosen": None if "failed" in ref else chosen_cutoff([r for r in rows if "failed" not in r], ref),
    }


def print_report(report: dict) -> None:
    """The tables of `run_all`'s report."""
    cost = [*report["cost"], *report["dofs"], *report["modes"], *report["spheres"], *report.get("steps", [])]
    print("\ncoupled cost\n")
    print(format_cost(cost))
    for key in ("cutoff_drop", "cutoff_drop_small", "cutoff_protector"):
        if key in report:
            c = report[key]
            print(f"\n{key}\n")
            print(format_cutoffs(c["rows"], c["reference"]))
            print(f"\nchosen cut-off: {_cell(c['chosen'], '.3g')} Hz")


def main(args) -> int:
    """`granplate bench --solid --coupled [--quick] [--repeats N] [--json FILE]` (the JSON:
    run_all's report, each table a list of rows, each cut-off table its rows, reference and
    chosen cut-off)."""
    repeats = getattr(args, "repeats", None) or 1
    report = run_all(
        quick=getattr(args, "quick", False), repeats=repeats, log=lambda line: print(line, file=sys.stderr)
    )
    print_report(report)
    write_report(args, report)
    return 0
