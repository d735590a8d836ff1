"""`granplate bench --pour`: how long a poured packing takes to settle in space.

Millimetre steel spheres (radii uniform in [1, 1.3] mm, seed 3), the container of the
layout's defaults, gravity 9.81 m/s^2, Mindlin's friction mu = 0.5 while settling, dropped
one at a time (`[layout] drop = "sequential"`, docs/model.md section 3.14) and settled at
the real stiffness by the ramped settling's kernel, on `--threads` threads (default: all
cores). Each row: the deposition's wall time, the settling's wall and CPU time (the
deposition included), the simulated time and steps, what it reached (kinetic energy over
gravity's work, the largest residual force over a weight) and whether it settled within
TARGET_S (the target for 10,000 spheres on a 2-core machine). The packing is settled
afresh (not read from the run store). The compiled kernels are loaded by a 20-sphere
settling first.
"""

from __future__ import annotations

import sys
import time

from granplate.bench import write_report

#: Sphere counts of the table (--sizes), the wall-time target [s].
SIZES = (1000, 10000)
TARGET_S = 600.0
#: The warm-up settling's sphere count.
WARM_UP = 20


def pour_scenario(count: int, threads: int | None):
    """The poured layout of the module docstring, `count` spheres."""
    from granplate.setup.scenario import Contact, Gravity, PouredLayout, Scenario, Solver

    lay = PouredLayout(
        count=count, radius_range=(0.001, 0.0013), seed=3, settle_friction=0.5, drop="sequential", settle_time=2.0
    )
    return Scenario(
        name=f"pour-{count}",
        dimension=3,
        layout=lay,
        gravity=Gravity((0.0, 0.0, -9.81)),
        contact=Contact(pairs=()),
        solver=Solver(threads=threads),
    )


def row(count: int, threads: int | None, progress: bool = False) -> dict:
    """One row of the table (module docstring)."""
    from granplate.results import ramped
    from granplate.setup import deposition, pouring
    from granplate.setup.threads import loop_threads

    s = pour_scenario(count, threads)
    lay = s.layout
    t0 = time.perf_counter()
    axis, sign = pouring.floor_axis(pouring.pour_gravity(s, lay))
    deposition.deposit(pouring.poured_radii(lay), pouring.container_size(lay, 3), axis, sign, lay.seed)
    deposit_s = time.perf_counter() - t0
    pouring.clear_dropped()
    _, out = ramped.settle_ramped(s, lay, progress=progress)
    return {
        "spheres": count,
        "threads": loop_threads(threads, count, "verlet"),
        "deposition_s": deposit_s,
        "wall_s": out.wall_s,
        "cpu_s": out.cpu_s,
        "simulated_s": out.t,
        "steps": out.steps,
        "kinetic": out.kinetic,
        "residual": out.residual,
        "settled": out.settled,
        "within_target": bool(out.settled and out.wall_s <= TARGET_S),
    }


def format_table(rows: list[dict]) -> str:
    """The rows as a text table."""
    head = "spheres  threads  deposition [s]  wall [s]  CPU [s]  simulated [s]    steps  kinetic   residual  settled"
    lines = [head]
    for r in rows:
        lines.append(
            f"{r['spheres']:7d}  {r['threads']:7d}  {r['deposition_s']:14.2f}  {r['wall_s']:8.1f}  {r['cpu_s']:7.1f}  "
            f"{r['simulated_s']:13.4g}  {r['steps']:7d}  {r['kinetic']:.2g}  {r['residual']:9.2g}  {r['settled']}"
        )
    return "\n".join(lines)


def main(args) -> int:
    """`granplate bench --pour [--sizes N,...] [--threads K] [--json F]`."""
    try:
        sizes = tuple(int(v) for v in args.sizes.split(",")) if getattr(args, "sizes", None) else SIZES
        threads = getattr(args, "threads", None)
        threads = None if threads is None else int(threads)
    except ValueError:
        print(f"granplate: error: --sizes {args.sizes!r} / --threads {args.threads!r}: integers >= 1", file=sys.stderr)
        return 2
    if any(n < 1 for n in sizes) or (threads is not None and threads < 1):
        print("granplate: error: --sizes and --threads must be integers >= 1", file=sys.stderr)
        return 2
    row(WARM_UP, threads)
    rows = []
    for n in sizes:
        rows.append(row(n, threads, progress=True))
        print(format_table(rows[-1:]), file=sys.stderr)
    print(format_table(rows))
    write_report(args, {"target_s": TARGET_S, "rows": rows})
    return 0
