"""`granplate bench --startup`: how long a run takes from its process's start to its first
step, and the memory it holds then, as the number of spheres grows and by how the granules
are given ([[granules]] tables in the TOML, or a granules_file: CSV, NPZ, netCDF).

The packing (`boxed_fcc`): a face-centred cubic block of touching steel spheres (R = 1 mm,
NX x NY x NZ conventional cells of 4 sites, setup.layouts kind "fcc") in a box of six walls
touching it, frictionless, undamped, whose first lattice plane is launched at 1 m/s in +x;
velocity Verlet at a fixed step, dynamic detection: the set-up of the loop at its
simplest, so that what is timed is the set-up itself. The scenario is written (resolved,
every sphere and wall explicit) once per size and format; each repeat then runs it in a
fresh process as `granplate run` does (the same imports), up to the first step: the
process's start is timed by the parent, the first step by the loop's stop poll, which
the driver calls just before its first step (`solver.driver.run`'s should_stop), and the
run ends there. Reported per row (medians over the repeats): the process's start to its
imports done, the scenario read and validated, the model built, the loop's arrays and
compiled code ready, the total to the first step and the process's CPU time to it (user
and system: what the wall time would be on a machine no other process shares); the peak
resident memory, and bytes per sphere (the peak above the two-sphere row's, per sphere).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

#: Rows of the default table: (cells, format). 2 spheres in tables (the baseline), 10,192 as
#: tables and as each file format.
DEFAULT_ROWS: tuple[tuple[tuple[int, int, int] | None, str], ...] = (
    (None, "toml"),
    ((14, 14, 13), "toml"),
    ((14, 14, 13), "csv"),
    ((14, 14, 13), "npz"),
    ((14, 14, 13), "nc"),
)
#: Formats a row may take: the TOML's own tables, or a granules_file of that extension.
FORMATS: tuple[str, ...] = ("toml", "csv", "npz", "nc")
#: Sphere radius [m], launch speed [m/s], fixed step [s] and simulated time [s].
RADIUS, SPEED, DT, T_END = 1e-3, 1.0, 1e-8, 1e-6
#: Repeats per row (the median is reported).
REPEATS = 3


def boxed_fcc(cells: tuple[int, int, int] | None):
    """The scenario of a row: the launched FCC block of `cells` in its box (resolved), or
    for None two touching spheres in a box, the first launched (the baseline)."""
    import dataclasses

    from granplate.setup.geometry import box_walls, layout_packing, resolve
    from granplate.setup.scenario import Box, Contact, Granule, Load, Scenario, Solver, SpaceLattice, TimeSettings

    time_settings = TimeSettings(
        t_end=T_END, dt_initial=DT, dt_max=DT, dt_min=DT, output_interval=T_END / 10, field_interval=T_END / 10
    )
    common = dict(
        dimension=3,
        plate=None,
        load=Load(kind="none"),
        time=time_settings,
        contact=Contact(mu=0.0, alpha_n=0.0, pairs=(), detection="dynamic"),
        solver=Solver(scheme="verlet"),
    )
    if cells is None:
        granules = (
            Granule(RADIUS, RADIUS, RADIUS, "steel", "a", vx=SPEED, omega=(0.0, 0.0, 0.0), z=RADIUS),
            Granule(3 * RADIUS, RADIUS, RADIUS, "steel", "b", omega=(0.0, 0.0, 0.0), z=RADIUS),
        )
        box = Box((0.0, 0.0, 0.0), (4 * RADIUS, 2 * RADIUS, 2 * RADIUS))
        return resolve(Scenario(name="two-spheres", granules=granules, walls=box_walls(box), **common))
    packing = layout_packing(SpaceLattice(kind="fcc", cells=tuple(cells), radius=RADIUS))
    first = set(packing.column1)
    granules = tuple(dataclasses.replace(g, vx=SPEED) if g.label in first else g for g in packing.granules)
    name = "fcc-box-" + "x".join(str(c) for c in cells)
    return resolve(Scenario(name=name, granules=granules, walls=packing.walls, **common))


def write_scenario(s, folder: str, fmt: str) -> tuple[str, int]:
    """Write `s` into `folder` as TOML tables (fmt "toml") or TOML with a granules_file of
    extension fmt; the TOML's path and the bytes written (the TOML and its file)."""
    from granplate.setup.io import dumps, dumps_with_granules_file

    path = os.path.join(folder, f"{s.name}-{fmt}.toml")
    table = os.path.join(folder, f"{s.name}.{fmt}")
    text = dumps(s) if fmt == "toml" else dumps_with_granules_file(s, table, folder)
    with open(path, "w") as f:
        f.write(text)
    return path, os.path.getsize(path) + (os.path.getsize(table) if fmt != "toml" else 0)


#: The child process: what `granplate run FILE` does up to the first step, each stage timed.
CHILD = """
import time, json, resource, sys
t0, c0 = time.time(), time.process_time()
from granplate import cli
cli.keep_dask_out()
from granplate.results.run import simulate
from granplate.setup.io import load_scenario
from granplate.model.arrays import build_model
from granplate.solver import driver
t1 = time.time()
s = load_scenario(sys.argv[1])
t2 = time.time()
model = build_model(s)
t3 = time.time()
first = []
def at_first_step():
    first.append(time.time())
    first.append(time.process_time())
    return True
driver.run(model, should_stop=at_first_step, interruptible=False)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print("@@RESULT " + json.dumps({"t0": t0, "imported": t1, "read": t2, "built": t3, "first_step": first[0], "cpu_s": first[1] - c0,
                                "peak_bytes": peak, "spheres": len(model.labels), "pairs": len(model.granular.pair_ij)}))
"""


def time_row(path: str) -> dict:
    """One fresh process running the TOML at `path` to its first step: the stages' times
    from the process's start [s], the peak memory [bytes]."""
    start = time.time()
    p = subprocess.run([sys.executable, "-c", CHILD, path], capture_output=True, text=True, env=dict(os.environ))
    for line in p.stdout.splitlines():
        if line.startswith("@@RESULT "):
            r = json.loads(line[len("@@RESULT ") :])
            return {
                "spheres": r["spheres"],
                "pairs": r["pairs"],
                "peak_bytes": r["peak_bytes"],
                "import_s": r["imported"] - start,
                "read_s": r["read"] - r["imported"],
                "build_s": r["built"] - r["read"],
                "loop_start_s": r["first_step"] - r["built"],
                "first_step_s": r["first_step"] - start,
                "cpu_s": r["cpu_s"],
            }
    return {"failed": f"rc {p.returncode}: {(p.stderr.strip().splitlines() or [''])[-1]}"}


def run_startup(rows=DEFAULT_ROWS, repeats: int = REPEATS, log=print) -> list[dict]:
    """The table's rows: each (cells, format) written once, then timed `repeats` times in
    fresh processes (medians)."""
    out = []
    with tempfile.TemporaryDirectory() as folder:
        scenarios = {}
        for cells, fmt in rows:
            if cells not in scenarios:
                scenarios[cells] = boxed_fcc(cells)
            s = scenarios[cells]
            path, size = write_scenario(s, folder, fmt)
            log(f"start-up: {len(s.granules):,} spheres from {fmt} ...")
            runs = [time_row(path) for _ in range(repeats)]
            failed = [r for r in runs if "failed" in r]
            row = {
                "cells": list(cells) if cells else None,
                "format": fmt,
                "spheres": len(s.granules),
                "file_bytes": size,
                "repeats": repeats,
            }
            if failed:
                row["failed"] = failed[0]["failed"]
            else:
                for k in ("import_s", "read_s", "build_s", "loop_start_s", "first_step_s", "cpu_s", "peak_bytes"):
                    row[k] = statistics.median(r[k] for r in runs)
                row["pairs"] = runs[0]["pairs"]
            out.append(row)
    base = next((r for r in out if r["cells"] is None and "failed" not in r), None)
    for r in out:
        if base is not None and "failed" not in r and r is not base:
            r["beyond_two_s"] = r["first_step_s"] - base["first_step_s"]
            r["bytes_per_sphere"] = (r["peak_bytes"] - base["peak_bytes"]) / r["spheres"]
    return out


def format_startup_table(rows: list[dict]) -> str:
    """The start-up table as Markdown."""
    lines = [
        "| spheres | given as | file [MB] | imports [s] | read + validate [s] | model [s] | loop ready [s] "
        "| to first step [s] | its CPU time [s] | beyond 2 spheres [s] | peak [MiB] | bytes per sphere |",
        "|" + " ---: |" * 12,
    ]
    for r in rows:
        given = "[[granules]]" if r["format"] == "toml" else f"granules_file .{r['format']}"
        if "failed" in r:
            lines.append(f"| {r['spheres']:,} | {given} | | {r['failed']} |" + " |" * 8)
            continue
        extra = (
            f"{r['beyond_two_s']:.2f} | {r['peak_bytes'] / 2**20:.0f} | {r['bytes_per_sphere']:.0f}"
            if "beyond_two_s" in r
            else f"- | {r['peak_bytes'] / 2**20:.0f} | -"
        )
        lines.append(
            f"| {r['spheres']:,} | {given} | {r['file_bytes'] / 1e6:.2f} | {r['import_s']:.2f} "
            f"| {r['read_s']:.2f} | {r['build_s']:.2f} | {r['loop_start_s']:.2f} | {r['first_step_s']:.2f} "
            f"| {r['cpu_s']:.2f} "
            f"| {extra} |"
        )
    return "\n".join(lines)


def parse_rows(sizes: str | None, formats: str | None) -> list:
    """--sizes NXxNYxNZ,... and --formats toml,csv,...: the baseline row (two spheres in
    tables) and every size in every format (ValueError naming a bad item)."""
    from granplate.bench.scaling_space import parse_cells

    cells = parse_cells(sizes) if sizes else [(14, 14, 13)]
    fmts = [f.strip() for f in (formats or ",".join(FORMATS)).split(",")]
    for f in fmts:
        if f not in FORMATS:
            raise ValueError(f"--formats item {f!r}: allowed " + ", ".join(FORMATS))
    return [(None, "toml")] + [(c, f) for c in cells for f in fmts]


def main(args) -> int:
    """`granplate bench --startup [--sizes 14x14x13,63x63x63] [--formats npz] [--repeats N] [--json F]`."""
    from granplate.bench import write_report

    try:
        rows = parse_rows(getattr(args, "sizes", None), getattr(args, "formats", None))
    except ValueError as err:
        print(f"granplate: error: {err}", file=sys.stderr)
        return 2
    repeats = args.repeats if getattr(args, "repeats", None) else REPEATS
    if repeats < 1:
        print(f"granplate: error: --repeats = {repeats}: must be >= 1", file=sys.stderr)
        return 2
    table = run_startup(rows, repeats, log=lambda line: print(line, file=sys.stderr))
    print()
    print(format_startup_table(table))
    write_report(args, table)
    return 1 if any("failed" in r for r in table) else 0
