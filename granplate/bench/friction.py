"""`granplate bench --friction`: what friction at the granule contacts costs in steps.

Two cases, each run with solver.granular_friction = "split" (the default) and "rk4"
(friction inside RK4, the step bounded by its stiffness), and the packing also without
friction: a 990-granule hexagonal packing of 1 mm steel spheres (20 columns of 50 and
49), its first column launched at 1 m/s, 0.1 ms; and ptfe-r05 under q0 = 1e7 N/m
(granules reach ~36 m/s, overlaps up to ~0.4 R: contact.overlap_stop 0.5), 2 ms with
"split" and 0.2 ms with "rk4", which needs ~1e-9 s steps there. Each run is timed after a
1 us warm-up run of the same scenario (the compiled loop loaded), in this process.
"""
from __future__ import annotations

import dataclasses
import json
import sys
import time

#: The packing: columns x rows of radius [m], the struck column's speed [m/s], t_end [s].
PACKING = {"columns": 20, "rows": 50, "radius": 1e-3, "v0": 1.0, "t_end": 1e-4}
#: ptfe-r05 under a strong shock: q0 [N/m], overlap_stop, t_end [s] per treatment.
STRONG = {"q0": 1e7, "overlap_stop": 0.5, "t_end": {"split": 2e-3, "rk4": 2e-4}}


def packing_scenario(mu: float, friction: str, t_end: float | None = None):
    """The hexagonal packing of PACKING with friction coefficient mu and treatment `friction`."""
    from granplate.setup.geometry import resolve
    from granplate.setup.scenario import Contact, LatticeLayout, Load, Scenario, Solver, TimeSettings

    t_end = PACKING["t_end"] if t_end is None else float(t_end)
    s = resolve(Scenario(
        name="friction-packing",
        layout=LatticeLayout(kind="hexagonal", columns=PACKING["columns"], rows=PACKING["rows"],
                             radius=PACKING["radius"]),
        load=Load(kind="none"), contact=Contact(mu=mu),
        time=TimeSettings(t_end=t_end, dt_initial=1e-8, dt_max=4e-8, output_interval=t_end / 10,
                          field_interval=t_end / 10),
        solver=Solver(granular_friction=friction)))
    left = min(g.x - g.radius for g in s.granules)
    return dataclasses.replace(s, granules=tuple(
        dataclasses.replace(g, vx=PACKING["v0"]) if abs(g.x - g.radius - left) < 1e-9 else g
        for g in s.granules))


def strong_scenario(friction: str, t_end: float | None = None):
    """ptfe-r05 under STRONG's shock with treatment `friction`."""
    import granplate as gp

    t_end = STRONG["t_end"][friction] if t_end is None else float(t_end)
    return gp.with_changes(gp.preset("ptfe-r05"), {
        "load.q0": STRONG["q0"], "contact.overlap_stop": STRONG["overlap_stop"],
        "solver.granular_friction": friction, "time.t_end": t_end,
        "time.output_interval": min(1e-6, t_end), "time.field_interval": min(2e-5, t_end)})


def cases(t_end: float | None = None) -> list[tuple[str, str, object]]:
    """(case, treatment, scenario) of the table; t_end overrides every run's [s]."""
    free = packing_scenario(0.0, "split", t_end)
    n = len(free.granules)
    return [(f"packing {n}, mu 0", "-", free),
            (f"packing {n}, mu 0.099", "split", packing_scenario(0.099, "split", t_end)),
            (f"packing {n}, mu 0.099", "rk4", packing_scenario(0.099, "rk4", t_end)),
            ("ptfe-r05, q0 1e7", "split", strong_scenario("split", t_end)),
            ("ptfe-r05, q0 1e7", "rk4", strong_scenario("rk4", t_end))]


def bench_run(case: str, friction: str, s) -> dict:
    """Steps, wall time and friction work of one run (after a 1 us warm-up)."""
    import warnings

    import granplate as gp

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # overlaps beyond overlap_warn
        gp.simulate(gp.with_changes(s, {"time.t_end": 1e-6, "time.output_interval": 1e-6,
                                        "time.field_interval": 1e-6}), progress=False)
        t0 = time.perf_counter()
        ds = gp.simulate(s, progress=False)
        wall = time.perf_counter() - t0
    return {"case": case, "friction": friction, "t_end_s": float(s.time.t_end),
            "n_steps": int(ds.attrs["n_steps"]), "wall_s": wall,
            "steps_per_ms": int(ds.attrs["n_steps"]) / (1e3 * float(s.time.t_end)),
            "d_friction_J": float(ds.D_friction.values[-1]),
            "energy_residual_max": float(abs(ds.energy_residual.values).max())}


def format_friction_table(rows: list[dict]) -> str:
    """The rows as a plain-text table."""
    head = f"{'case':<24} {'friction':<8} {'t_end [s]':>9} {'steps':>9} {'steps/ms':>10} {'wall [s]':>9} {'D_fric [J]':>11}"
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r['case']:<24} {r['friction']:<8} {r['t_end_s']:>9.2g} {r['n_steps']:>9d} "
                     f"{r['steps_per_ms']:>10.3g} {r['wall_s']:>9.2f} {r['d_friction_J']:>11.4e}")
    return "\n".join(lines)


def main(args) -> int:
    """`granplate bench --friction [--t-end T] [--json FILE]`."""
    rows = []
    for case, friction, s in cases(getattr(args, "t_end", None)):
        print(f"{case} ({friction}) ...", file=sys.stderr, flush=True)
        rows.append(bench_run(case, friction, s))
    print(format_friction_table(rows))
    if getattr(args, "json", None):
        with open(args.json, "w") as fh:
            fh.write(json.dumps(rows, indent=2) + "\n")
        print(f"json: {args.json}")
    return 0
