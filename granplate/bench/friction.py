"""`granplate bench --friction`: what friction at the granule contacts costs in steps.

Two cases, each run with solver.granular_friction = "split" (the default) and "rk4"
(friction inside RK4, the step bounded by its stiffness), and the packing also without
friction: a 990-granule hexagonal packing of 1 mm steel spheres (20 columns of 50 and
49), its first column launched at 1 m/s, 0.1 ms; and ptfe-r05 under q0 = 1e7 N/m
(granules reach ~36 m/s, overlaps up to ~0.4 R: contact.overlap_stop 0.5), 2 ms with
"split" and 0.2 ms with "rk4", which needs ~1e-9 s steps there. Each run is timed after a
1 us warm-up run of the same scenario (the compiled loop loaded), in this process.

Then, where LAMMPS is installed (granplate.verification.lammps.run_granular), the packing
with mu = 0.099 side by side with LAMMPS (pair_style granular: the same Hertz law and
damping, Mindlin's tangential law with the same mu; velocity Verlet at LAMMPS_DT):
granplate's "split" run, granplate's "verlet" run (solver.scheme = "verlet", velocity
Verlet at VERLET_DT: the step whose error is about LAMMPS's) and LAMMPS's, alternately
REPEATS times each, their median loop
times (wall, and CPU time of this process: on a shared machine what each code used), steps, cost per contact and step (the listed contacts at t = 0, the same count for
both), and each one's error against its own converged run (granplate: the "rk4" row, whose
own error is ~3e-5 m/s; LAMMPS: its step / LAMMPS_REF_DIVISOR): the largest |v - v_ref|
over the granules' velocity components at t_end [m/s]. Last, the same law in both codes
(`mindlin_comparison`): the packing undamped under Mindlin's law (contact.tangential_law =
"mindlin") in granplate's Verlet scheme and LAMMPS's `tangential mindlin_rescale`, both at
LAMMPS_DT: loop times, each one's error against its own run at LAMMPS_DT /
LAMMPS_REF_DIVISOR, and how far the two runs' velocities differ.
"""

from __future__ import annotations

import dataclasses
import sys
import time

from granplate.bench import write_report

#: The packing: columns x rows of radius [m], the struck column's speed [m/s], t_end [s].
PACKING = {"columns": 20, "rows": 50, "radius": 1e-3, "v0": 1.0, "t_end": 1e-4}
#: ptfe-r05 under a strong shock: q0 [N/m], overlap_stop, t_end [s] per treatment.
STRONG = {"q0": 1e7, "overlap_stop": 0.5, "t_end": {"split": 2e-3, "rk4": 2e-4}}
#: LAMMPS's step on the packing [s], its converged reference's step divisor, and how many
#: times each code's run is timed (alternately; medians).
LAMMPS_DT = 1e-7
LAMMPS_REF_DIVISOR = 16
#: granplate's "verlet" step on the packing [s]: its error against the converged run is
#: about LAMMPS's at LAMMPS_DT (1.6e-3 against 1.86e-3 m/s; docs/benchmarks.md).
VERLET_DT = LAMMPS_DT / 6
REPEATS = 3


def packing_scenario(mu: float, friction: str, t_end: float | None = None):
    """The hexagonal packing of PACKING with friction coefficient mu and treatment `friction`."""
    from granplate.setup.geometry import resolve
    from granplate.setup.scenario import Contact, LatticeLayout, Load, Scenario, Solver, TimeSettings

    t_end = PACKING["t_end"] if t_end is None else float(t_end)
    s = resolve(
        Scenario(
            name="friction-packing",
            layout=LatticeLayout(
                kind="hexagonal", columns=PACKING["columns"], rows=PACKING["rows"], radius=PACKING["radius"]
            ),
            load=Load(kind="none"),
            contact=Contact(mu=mu),
            time=TimeSettings(
                t_end=t_end, dt_initial=1e-8, dt_max=4e-8, output_interval=t_end / 10, field_interval=t_end / 10
            ),
            solver=Solver(granular_friction=friction),
        )
    )
    left = min(g.x - g.radius for g in s.granules)
    return dataclasses.replace(
        s,
        granules=tuple(
            dataclasses.replace(g, vx=PACKING["v0"]) if abs(g.x - g.radius - left) < 1e-9 else g for g in s.granules
        ),
    )


def strong_scenario(friction: str, t_end: float | None = None):
    """ptfe-r05 under STRONG's shock with treatment `friction`."""
    import granplate as gp

    t_end = STRONG["t_end"][friction] if t_end is None else float(t_end)
    return gp.with_changes(
        gp.preset("ptfe-r05"),
        {
            "load.q0": STRONG["q0"],
            "contact.overlap_stop": STRONG["overlap_stop"],
            "solver.granular_friction": friction,
            "time.t_end": t_end,
            "time.output_interval": min(1e-6, t_end),
            "time.field_interval": min(2e-5, t_end),
        },
    )


def verlet_scenario(t_end: float | None = None):
    """The packing with mu = 0.099 under solver.scheme = "verlet" at the fixed step VERLET_DT."""
    s = packing_scenario(0.099, "split", t_end)
    return dataclasses.replace(
        s,
        solver=dataclasses.replace(s.solver, scheme="verlet"),
        time=dataclasses.replace(s.time, dt_initial=VERLET_DT, dt_max=VERLET_DT),
    )


#: The Mindlin run's energy tolerance: at LAMMPS_DT the packing's residual of eq. (11) is
#: Verlet's own, 3.2e-4 of the energy in (undamped), above the default 1e-4.
MINDLIN_ENERGY_TOL = 1e-3


def mindlin_scenario(
    t_end: float | None = None, dt: float = LAMMPS_DT, alpha_n: float | None = None, damping: str | None = None
):
    """The packing with mu = 0.099 under Mindlin's law (contact.tangential_law = "mindlin",
    LAMMPS's torque arms), solver.scheme = "verlet" at the fixed step dt [s] (LAMMPS's);
    alpha_n: eq. (3)'s damping (None: the packing's); damping: solver.verlet_damping (None:
    the default, the predicted velocities)."""
    s = packing_scenario(0.099, "split", t_end)
    contact = dataclasses.replace(s.contact, tangential_law="mindlin", torque_arm="lammps")
    if alpha_n is not None:
        contact = dataclasses.replace(contact, alpha_n=alpha_n)
    return dataclasses.replace(
        s,
        contact=contact,
        solver=dataclasses.replace(s.solver, scheme="verlet", energy_tol=MINDLIN_ENERGY_TOL, verlet_damping=damping),
        time=dataclasses.replace(s.time, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt)),
    )


def cases(t_end: float | None = None) -> list[tuple[str, str, object]]:
    """(case, treatment, scenario) of the table; t_end overrides every run's [s]."""
    free = packing_scenario(0.0, "split", t_end)
    n = len(free.granules)
    return [
        (f"packing {n}, mu 0", "-", free),
        (f"packing {n}, mu 0.099", "split", packing_scenario(0.099, "split", t_end)),
        (f"packing {n}, mu 0.099", "rk4", packing_scenario(0.099, "rk4", t_end)),
        ("ptfe-r05, q0 1e7", "split", strong_scenario("split", t_end)),
        ("ptfe-r05, q0 1e7", "rk4", strong_scenario("rk4", t_end)),
    ]


def timed_run(s):
    """(dataset, wall time [s]) of one run of `s` after a 1 us warm-up run (the compiled
    loop loaded); overlap warnings silenced."""
    import warnings

    import granplate as gp

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # overlaps beyond overlap_warn
        gp.simulate(
            gp.with_changes(s, {"time.t_end": 1e-6, "time.output_interval": 1e-6, "time.field_interval": 1e-6}),
            progress=False,
        )
        t0 = time.perf_counter()
        ds = gp.simulate(s, progress=False)
        return ds, time.perf_counter() - t0


def final_velocities(ds) -> dict:
    """vx, vy [m/s] of every granule at the run's last output."""
    return {"vx": ds.vx.values[-1].copy(), "vy": ds.vy.values[-1].copy()}


def velocity_error(v: dict, ref: dict) -> float:
    """The largest |v - v_ref| over the granules' velocity components [m/s]."""
    import numpy as np

    return float(max(np.abs(np.asarray(v["vx"]) - ref["vx"]).max(), np.abs(np.asarray(v["vy"]) - ref["vy"]).max()))


def bench_run(case: str, friction: str, s) -> dict:
    """Steps, wall time and friction work of one run (after a 1 us warm-up); the final
    velocities under the key "final" (not part of the table or the JSON)."""
    ds, wall = timed_run(s)
    return {
        "case": case,
        "friction": friction,
        "t_end_s": float(s.time.t_end),
        "n_steps": int(ds.attrs["n_steps"]),
        "wall_s": wall,
        "steps_per_ms": int(ds.attrs["n_steps"]) / (1e3 * float(s.time.t_end)),
        "d_friction_J": float(ds.D_friction.values[-1]),
        "energy_residual_max": float(abs(ds.energy_residual.values).max()),
        "final": final_velocities(ds),
    }


def listed_contacts(s) -> int:
    """Granule-granule and granule-wall contacts listed at t = 0 (the count both codes'
    cost per contact and step divides by)."""
    from granplate.model.arrays import build_model

    g = build_model(s).granular
    return int(g.pair_ij.shape[0] + g.wall_i.shape[0])


def per_contact_step_us(loop_s: float, n_steps: int, contacts: int) -> float:
    """1e6 loop_s / (n_steps contacts) [us]."""
    return 1e6 * loop_s / (n_steps * contacts)


def code_row(
    code: str, law: str, runs: list[tuple[float, float]], n_steps: int, t_end: float, error: float, contacts: int
) -> dict:
    """One code's row of the side-by-side table from its (loop wall, loop CPU) times [s]."""
    import statistics

    walls, cpus = [r[0] for r in runs], [r[1] for r in runs]
    row = {
        "code": code,
        "law": law,
        "dt_s": t_end / n_steps,
        "n_steps": n_steps,
        "loop_s": statistics.median(walls),
        "loop_s_all": walls,
        "loop_cpu_s": statistics.median(cpus),
        "loop_cpu_s_all": cpus,
        "error_m_s": error,
    }
    row["us_per_contact_step"] = per_contact_step_us(row["loop_s"], n_steps, contacts)
    row["cpu_us_per_contact_step"] = per_contact_step_us(row["loop_cpu_s"], n_steps, contacts)
    return row


def lammps_comparison(t_end: float | None, reference: dict, log=print) -> dict:
    """The packing with mu = 0.099: granplate ("split" and "verlet") and LAMMPS side by side
    (see the module's docstring); `reference`: granplate's converged final velocities (the
    "rk4" row). Returns {"skipped": why} where LAMMPS is not installed."""
    from granplate.verification import lammps as L

    if L.unavailable():
        return {"skipped": L.unavailable()}
    s = packing_scenario(0.099, "split", t_end)
    sv = verlet_scenario(t_end)
    t = float(s.time.t_end)
    contacts = listed_contacts(s)
    log(f"LAMMPS reference, dt {LAMMPS_DT / LAMMPS_REF_DIVISOR:g} s ...")
    lref = L.run_granular(s, LAMMPS_DT / LAMMPS_REF_DIVISOR, t)
    ours, verlet, theirs = [], [], []
    for k in range(REPEATS):
        log(f"granplate (split, verlet) and LAMMPS, side by side ({k + 1} of {REPEATS}) ...")
        ds, _ = timed_run(s)
        ours.append((float(ds.attrs["loop_time_s"]), float(ds.attrs["loop_cpu_s"])))
        dv, _ = timed_run(sv)
        verlet.append((float(dv.attrs["loop_time_s"]), float(dv.attrs["loop_cpu_s"])))
        lm = L.run_granular(s, LAMMPS_DT, t)
        theirs.append((lm["loop_time_s"], lm["loop_cpu_s"]))
    rows = {
        "granplate": code_row(
            "granplate",
            "tanh (eq. 5), split",
            ours,
            int(ds.attrs["n_steps"]),
            t,
            velocity_error(final_velocities(ds), reference),
            contacts,
        ),
        "verlet": code_row(
            "granplate",
            "tanh (eq. 5), verlet",
            verlet,
            int(dv.attrs["n_steps"]),
            t,
            velocity_error(final_velocities(dv), reference),
            contacts,
        ),
        "lammps": code_row("LAMMPS", "Mindlin", theirs, int(lm["n_steps"]), t, velocity_error(lm, lref), contacts),
    }
    ratio = {
        f"{key}{name}": rows[r][field] / rows["lammps"][field]
        for r, key in (("granplate", ""), ("verlet", "verlet_"))
        for name, field in (("loop_ratio", "loop_s"), ("cpu_ratio", "loop_cpu_s"))
    }
    return {"contacts": contacts, "t_end_s": t, **rows, **ratio}


def mindlin_comparison(t_end: float | None, log=print) -> dict:
    """The packing with mu = 0.099, undamped, under Mindlin's law in granplate
    (`mindlin_scenario`) and in LAMMPS (`tangential mindlin_rescale`), both at LAMMPS_DT:
    the same law, integrator and step (eq. 3's damping left out of the timed runs: granplate's
    Verlet damping reads the velocity predicted at the step's end by default, LAMMPS's the
    half step's). Alternately REPEATS times each: median loop times, and each code's error
    against its own run at LAMMPS_DT / LAMMPS_REF_DIVISOR; `agreement`: the largest
    |v_granplate - v_LAMMPS| at t_end over the largest |v| [-]; `damped_agreement`: the same
    of the packing with its damping (LAMMPS's `damping tsuji`) and granplate's force pass at
    the half step's velocities (solver.verlet_damping = "half_step"). Returns {"skipped":
    why} where LAMMPS is not installed."""
    from granplate.verification import lammps as L

    if L.unavailable():
        return {"skipped": L.unavailable()}
    s = mindlin_scenario(t_end, alpha_n=0.0)
    t = float(s.time.t_end)
    contacts = listed_contacts(s)
    fine = LAMMPS_DT / LAMMPS_REF_DIVISOR
    log(f"Mindlin references, dt {fine:g} s ...")
    ours_ref = final_velocities(timed_run(mindlin_scenario(t_end, dt=fine, alpha_n=0.0))[0])
    lammps_ref = L.run_granular(s, fine, t)
    ours, theirs = [], []
    for k in range(REPEATS):
        log(f"granplate and LAMMPS under Mindlin's law, side by side ({k + 1} of {REPEATS}) ...")
        ds, _ = timed_run(s)
        ours.append((float(ds.attrs["loop_time_s"]), float(ds.attrs["loop_cpu_s"])))
        lm = L.run_granular(s, LAMMPS_DT, t)
        theirs.append((lm["loop_time_s"], lm["loop_cpu_s"]))
    v = final_velocities(ds)
    scale = max(float(abs(lm["vx"]).max()), float(abs(lm["vy"]).max()))
    log("the same, damped (eq. 3 against damping tsuji, the half step's velocities in both) ...")
    damped = mindlin_scenario(t_end, damping="half_step")
    lm_d = L.run_granular(damped, LAMMPS_DT, t)
    scale_d = max(float(abs(lm_d["vx"]).max()), float(abs(lm_d["vy"]).max()))
    damped_agreement = velocity_error(final_velocities(timed_run(damped)[0]), lm_d) / scale_d
    rows = {
        "granplate": code_row(
            "granplate", "Mindlin, verlet", ours, int(ds.attrs["n_steps"]), t, velocity_error(v, ours_ref), contacts
        ),
        "lammps": code_row(
            "LAMMPS", "mindlin_rescale", theirs, int(lm["n_steps"]), t, velocity_error(lm, lammps_ref), contacts
        ),
    }
    return {
        "contacts": contacts,
        "t_end_s": t,
        **rows,
        "agreement": velocity_error(v, lm) / scale,
        "damped_agreement": damped_agreement,
        "loop_ratio": rows["granplate"]["loop_s"] / rows["lammps"]["loop_s"],
        "cpu_ratio": rows["granplate"]["loop_cpu_s"] / rows["lammps"]["loop_cpu_s"],
    }


def format_mindlin_table(cmp: dict) -> str:
    """The Mindlin side-by-side comparison as a plain-text table (or why it was left out)."""
    if "skipped" in cmp:
        return f"Mindlin comparison skipped: {cmp['skipped']}"
    head = (
        f"{'code':<10} {'friction law':<20} {'dt [s]':>9} {'steps':>7} {'loop [s]':>9} "
        f"{'us/(contact step)':>17} {'CPU [s]':>8} {'CPU us/(c. step)':>16} {'error [m/s]':>11}"
    )
    lines = [
        f"packing with mu 0.099, undamped, Mindlin's law in both codes ({cmp['contacts']} listed contacts, "
        f"t_end {cmp['t_end_s']:g} s, median of {len(cmp['granplate']['loop_s_all'])} alternate runs each)",
        head,
        "-" * len(head),
    ]
    for r in (cmp["granplate"], cmp["lammps"]):
        lines.append(
            f"{r['code']:<10} {r['law']:<20} {r['dt_s']:>9.3g} {r['n_steps']:>7d} {r['loop_s']:>9.3f} "
            f"{r['us_per_contact_step']:>17.3f} {r['loop_cpu_s']:>8.3f} {r['cpu_us_per_contact_step']:>16.3f} "
            f"{r['error_m_s']:>11.2e}"
        )
    lines.append(
        f"loop time granplate / LAMMPS: {cmp['loop_ratio']:.2f} (wall), {cmp['cpu_ratio']:.2f} (CPU); "
        f"velocities at t_end, granplate against LAMMPS: {cmp['agreement']:.1e} of the largest; damped "
        f'(alpha_n of the packing, damping tsuji, solver.verlet_damping = "half_step"): {cmp["damped_agreement"]:.1e}'
    )
    return "\n".join(lines)


def format_friction_table(rows: list[dict]) -> str:
    """The rows as a plain-text table."""
    head = f"{'case':<24} {'friction':<8} {'t_end [s]':>9} {'steps':>9} {'steps/ms':>10} {'wall [s]':>9} {'D_fric [J]':>11}"
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r['case']:<24} {r['friction']:<8} {r['t_end_s']:>9.2g} {r['n_steps']:>9d} "
            f"{r['steps_per_ms']:>10.3g} {r['wall_s']:>9.2f} {r['d_friction_J']:>11.4e}"
        )
    return "\n".join(lines)


def format_lammps_table(cmp: dict) -> str:
    """The side-by-side comparison as a plain-text table (or why it was left out)."""
    if "skipped" in cmp:
        return f"LAMMPS comparison skipped: {cmp['skipped']}"
    head = (
        f"{'code':<10} {'friction law':<20} {'dt [s]':>9} {'steps':>7} {'loop [s]':>9} "
        f"{'us/(contact step)':>17} {'CPU [s]':>8} {'CPU us/(c. step)':>16} {'error [m/s]':>11}"
    )
    lines = [
        f"packing with mu 0.099 side by side ({cmp['contacts']} listed contacts, t_end {cmp['t_end_s']:g} s, "
        f"median of {len(cmp['granplate']['loop_s_all'])} alternate runs each)",
        head,
        "-" * len(head),
    ]
    for r in (cmp["granplate"], cmp["verlet"], cmp["lammps"]):
        lines.append(
            f"{r['code']:<10} {r['law']:<20} {r['dt_s']:>9.3g} {r['n_steps']:>7d} {r['loop_s']:>9.3f} "
            f"{r['us_per_contact_step']:>17.3f} {r['loop_cpu_s']:>8.3f} {r['cpu_us_per_contact_step']:>16.3f} "
            f"{r['error_m_s']:>11.2e}"
        )
    lines.append(
        f"loop time granplate / LAMMPS: {cmp['loop_ratio']:.2f} (wall), {cmp['cpu_ratio']:.2f} (CPU); "
        f"verlet / LAMMPS: {cmp['verlet_loop_ratio']:.2f} (wall), {cmp['verlet_cpu_ratio']:.2f} (CPU)"
    )
    return "\n".join(lines)


def main(args) -> int:
    """`granplate bench --friction [--t-end T] [--no-lammps] [--json FILE]`."""
    rows = []
    t_end = getattr(args, "t_end", None)
    for case, friction, s in cases(t_end):
        print(f"{case} ({friction}) ...", file=sys.stderr, flush=True)
        rows.append(bench_run(case, friction, s))
    print(format_friction_table(rows))
    if getattr(args, "no_lammps", False):
        cmp = {"skipped": "--no-lammps"}
    else:
        reference = next(r["final"] for r in rows if r["case"].endswith("mu 0.099") and r["friction"] == "rk4")
        cmp = lammps_comparison(t_end, reference, log=lambda m: print(m, file=sys.stderr, flush=True))
    print()
    print(format_lammps_table(cmp))
    if getattr(args, "no_lammps", False):
        mindlin = {"skipped": "--no-lammps"}
    else:
        mindlin = mindlin_comparison(t_end, log=lambda m: print(m, file=sys.stderr, flush=True))
    print()
    print(format_mindlin_table(mindlin))
    for r in rows:
        r.pop("final")
    write_report(args, {"rows": rows, "lammps": cmp, "mindlin": mindlin})
    return 0
