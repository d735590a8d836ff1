"""`granplate bench --solid --coupled --profile`: where the body's contact pass
(solver.body.contact_forces) spends a coupled step, timed sub-pass by sub-pass on the
protector (bench.solid_coupled) at its largest total contact force on the plate.

The protector is run once (its modes and residual from the run store); its granules'
state and modal coordinates at that output time are fed to compiled drivers that call
each sub-pass `calls` times: the whole pass, the bounding-box test, the closest point
(`locate`: solid.surface.slide_closest), the surface motion at the points, the force
spread onto the modes, the residual matrix between the contacts in touch and its
Gauss-Seidel solve. CPU time per call [us].
"""

from __future__ import annotations

import sys
import time

import numpy as np
from granplate.jit import njit

from granplate.solver import body as B
from granplate.bench import write_report

#: Calls per sub-pass timed (after one call that compiles it).
CALLS = 200
#: The sub-passes, in the order of the table.
PASSES = ("contact_forces", "near_box", "locate", "surface_motion", "spread", "residual_matrix", "solve_static")
#: (solver.body's surface motion: normal_motion and surface_velocity)


@njit
def _near(b, y, radius, n):
    c = 0
    for _ in range(n):
        for i in range(y.shape[0]):
            if B.near_box(b, y[i, 0], y[i, 1], y[i, 2], B.REACH * radius[i]):
                c += 1
    return c


@njit(refcount=True)
def _locate(b, y, radius, n):
    nfn = b.face_nodes.shape[1]
    out = np.empty(9)
    N = np.empty(nfn)
    dN = np.empty((nfn, 2))
    p = np.empty(3)
    for _ in range(n):
        for i in range(y.shape[0]):
            if B.near_box(b, y[i, 0], y[i, 1], y[i, 2], B.REACH * radius[i]):
                p[0] = y[i, 0]
                p[1] = y[i, 1]
                p[2] = y[i, 2]
                B.locate(b, 0, i, p, out, N, dN)


@njit
def _motion(b, act, q, qd, n):
    s = 0.0
    for _ in range(n):
        for i in act:
            s += B.normal_motion(b, 0, i, q) + B.surface_velocity(b, 0, i, qd)[0]
    return s


@njit(refcount=True)
def _spread(b, act, nm, n):
    out = np.zeros(nm)
    for _ in range(n):
        for i in act:
            B.spread(b, 0, i, 1.0, 0.0, 0.0, out, 1.0)
    return out[0]


@njit(refcount=True)
def _residual(b, act, n):
    n_act = act.shape[0]
    counts = np.zeros(max(n_act, 1), np.int64)
    n_s = b.resid.shape[0]
    rmat = np.zeros((n_act, n_act))
    for _ in range(n):
        upos = np.full(n_s, -1, np.int64)
        ulist = np.empty(n_s, np.int64)
        for k in range(n_act):
            counts[k] = B.residual_rows(b, 0, act[k], k)
        n_u = B.touched_dofs(b, n_act, counts, upos, ulist)
        rows = np.empty((n_act, n_u))
        B.residual_matrix(b, n_act, counts, upos, ulist, n_u, rows, rmat)
    return rmat


@njit
def _solve(b, act, delta0, rmat, n):
    for k in range(act.shape[0]):
        b.active[k] = act[k]
    e = 0.0
    for _ in range(n):
        e += B.solve_static(b, 0, act.shape[0], delta0, rmat, True)
    return e


@njit
def _whole(y, q, qd, b, radius, mass, acc, fd, n):
    for _ in range(n):
        B.contact_forces(y, q, qd, b, 0, radius, mass, True, acc, fd, True)


def _cpu_us(fn, args, calls: int) -> float:
    """CPU time per call [us] of fn(*args, calls) after one call (which compiles it)."""
    fn(*args, 1)
    t0 = time.process_time()
    fn(*args, calls)
    return 1e6 * (time.process_time() - t0) / calls


def profile_contacts(spec: dict, calls: int = CALLS) -> dict:
    """The sub-passes' CPU time per call [us] (keys PASSES + "_us") on the protector of
    `spec` (bench.solid_coupled.spec_of), with the counts: granules near the body, in
    touch, modes, residual dofs, and the run's CPU time per step."""
    import warnings

    from granplate.bench import solid_coupled as C
    from granplate.errors import YieldWarning
    from granplate.model.arrays import build_model
    from granplate.model.inputs import GEO_DELTA, GEO_TOUCH, new_body_state
    from granplate.results.run import simulate

    warnings.simplefilter("ignore", YieldWarning)
    s = C.scenario_of(spec)
    model = build_model(s)
    ds = simulate(s, model=model, progress=False)
    k = int(np.argmax(ds.body_contact_normal_force.values.sum(axis=1)))
    cols = ("x", "y", "z", "vx", "vy", "vz", "omega_x", "omega_y", "omega_z")
    y = np.ascontiguousarray(np.stack([ds[c].values[k] for c in cols], axis=1))
    q = np.ascontiguousarray(ds.body_q.values[k])
    qd = np.ascontiguousarray(ds.body_qd.values[k])
    b = new_body_state(model.body)
    radius = np.ascontiguousarray(model.granular.radius)
    mass = np.ascontiguousarray(model.granular.mass)
    acc = np.zeros_like(y)
    fd = np.zeros_like(y)
    B.contact_forces(y, q, qd, b, 0, radius, mass, True, acc, fd, True)  # the faces seeded at this state
    act = np.array([i for i in range(len(y)) if b.geo[0, i, GEO_TOUCH] != 0.0], np.int64)
    delta0 = np.array([b.geo[0, i, GEO_DELTA] for i in act]) + 1e-7
    out = {
        "n_near": int(_near(b, y, radius, 1)),
        "n_touch": int(len(act)),
        "n_modes": int(q.size),
        "n_resid": int(b.resid.shape[0]),
        "n_dofs": int(len(model.solid.dofs)),
        "step_cpu_us": 1e6 * float(ds.attrs["loop_cpu_s"]) / int(ds.attrs["n_steps"]),
    }
    runs = {
        "contact_forces": (_whole, (y, q, qd, b, radius, mass, acc, fd)),
        "near_box": (_near, (b, y, radius)),
        "locate": (_locate, (b, y, radius)),
        "surface_motion": (_motion, (b, act, q, qd)),
        "spread": (_spread, (b, act, q.size)),
        "residual_matrix": (_residual, (b, act)),
        "solve_static": (_solve, (b, act, delta0, _residual(b, act, 1))),
    }
    for name in PASSES:
        fn, args = runs[name]
        out[name + "_us"] = _cpu_us(fn, args, calls)
    return out


def format_profile(rows: list[dict]) -> str:
    """The profile table as Markdown: one row per mesh."""
    head = (
        "| mesh | free dofs | residual dofs | in touch | "
        + " | ".join(f"{p} [us]" for p in PASSES)
        + " | whole step [us] |"
    )
    lines = [head, "|" + " ---: |" * (head.count("|") - 1)]
    for r in rows:
        mesh = " x ".join(str(n) for n in r["mesh"])
        lines.append(
            f"| {mesh} | {r['n_dofs']:,} | {r['n_resid']:,} | {r['n_touch']} | "
            + " | ".join(f"{r[p + '_us']:,.0f}" for p in PASSES)
            + f" | {r['step_cpu_us']:,.0f} |"
        )
    return "\n".join(lines)


def _worker(spec: dict) -> dict:
    """Runs in a fresh subprocess: one mesh's profile."""
    return {"mesh": spec["mesh"], **profile_contacts(spec)}


def main(args) -> int:
    """`granplate bench --solid --coupled --profile [--json FILE]`: the profile on each mesh of
    bench.solid_coupled.MESHES (1 ms of the protector each, a fresh process each)."""
    from granplate.bench import solid_coupled as C
    from granplate.bench.scaling import run_in_subprocess

    rows = []
    for mesh in C.MESHES:
        print(f"contact pass profile: mesh {mesh} ...", file=sys.stderr)
        rows.append(run_in_subprocess("solid_profile", "_worker", C.spec_of(mesh=mesh)))
    good = [r for r in rows if "failed" not in r]
    print(format_profile(good))
    for r in rows:
        if "failed" in r:
            print(f"failed: {r['failed']}")
    write_report(args, rows)
    return 1 if len(good) < len(rows) else 0
