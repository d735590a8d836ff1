"""Gravity and the drives of a scenario as the loop's arrays (model.inputs.Granular's
gravity, drive_* and wall_* fields; docs/model.md section 3.11), and the initial
velocities a displacement or velocity drive prescribes.
"""

from __future__ import annotations

import numpy as np

from granplate.model.inputs import N_DRIVE
from granplate.physics.drives import KIND_FORCE, PROFILE_CONSTANT, drive_motion
from granplate.physics.profiles import N_PAR, PAR_MASS, PAR_VALUE, TAB_I, TAB_T, TAB_V
from granplate.setup.drive_profiles import DRIVE_PROFILES, PAR_FIELDS
from granplate.setup.scenario import DRIVE_KINDS, Scenario


def drive_targets(s: Scenario) -> np.ndarray:
    """(nD,) int: each drive's granule index i >= 0, or -1 - w for wall w (the resolved
    scenario's order; validation has checked every target)."""
    labels = [g.label or str(i + 1) for i, g in enumerate(s.granules)]
    walls = [w.label for w in s.walls]
    out = []
    for d in s.drives:
        kind, label = d.target.split(None, 1)
        out.append(labels.index(label.strip()) if kind == "granule" else -1 - walls.index(label.strip()))
    return np.array(out, np.int64)


def drive_table(times, values) -> np.ndarray:
    """(n, 3) the table's times, values and the integral of the values from t = 0 at each
    time (the value held at values[0] before times[0]; the trapezoidal rule between)."""
    t = np.asarray(times, float)
    v = np.asarray(values, float)
    tab = np.zeros((len(t), 3))
    tab[:, TAB_T], tab[:, TAB_V] = t, v
    if len(t):
        tab[0, TAB_I] = v[0] * t[0]
        tab[1:, TAB_I] = tab[0, TAB_I] + np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))
    return tab


def drive_fields(s: Scenario, centres: np.ndarray) -> dict:
    """The Granular fields of gravity and the drives of the resolved scenario s, with the
    granules' centres (ng, d) at t = 0 [m] (empty arrays: none)."""
    d = s.dimension
    nd = len(s.drives)
    n_walls = len(s.walls)
    target = drive_targets(s) if nd else np.zeros(0, np.int64)
    length = max([max(len(x.times), 1) for x in s.drives], default=1)
    par = np.zeros((nd, N_PAR))
    tab = np.zeros((nd, length, 3))
    tlen = np.zeros(nd, np.int64)
    direction = np.zeros((nd, d))
    x0 = np.zeros((nd, d))
    for k, dr in enumerate(s.drives):
        par[k, : len(PAR_FIELDS)] = [getattr(dr, name) for name in PAR_FIELDS]
        par[k, PAR_MASS] = dr.mass
        rows = drive_table(dr.times, dr.values)
        tab[k, : len(rows)] = rows
        tlen[k] = len(rows)
        direction[k] = np.asarray(dr.direction, float) / np.linalg.norm(dr.direction)
        if target[k] >= 0:
            x0[k] = centres[target[k]]
    wall_drive = np.full(n_walls, -1, np.int64)
    for k in np.flatnonzero(target < 0):
        wall_drive[-1 - target[k]] = k
    return dict(
        gravity=np.asarray(s.gravity.g, float) if s.gravity is not None else np.zeros(0),
        drive_target=target,
        drive_kind=np.array([DRIVE_KINDS.index(x.kind) for x in s.drives], np.int64),
        drive_prof=np.array([DRIVE_PROFILES.index(x.profile) for x in s.drives], np.int64),
        drive_dir=direction,
        drive_par=par,
        drive_tab=tab,
        drive_tlen=tlen,
        drive_x0=x0,
        drive_now=np.zeros((nd, N_DRIVE)),
        wall_drive=wall_drive if (target < 0).any() else np.zeros(0, np.int64),
        wall_load=np.zeros(n_walls),
    )


def with_piston(g, wall: int, direction: np.ndarray, force: float, mass: float):
    """The granular arrays g (model.inputs.Granular or Granular3) with one more drive: wall
    `wall` (its index in the scenario) made a piston of `mass` [kg] pushed along the unit
    `direction` by the constant `force` [N], at rest where g's wall rows put it (the held
    wall of a precompression, docs/model.md section 3.12)."""
    nd, d = g.drive_dir.shape[0], len(direction)
    par = np.zeros((1, N_PAR))
    par[0, PAR_VALUE], par[0, PAR_MASS] = force, mass
    tab = np.zeros((nd + 1, g.drive_tab.shape[1], 3))
    tab[:nd] = g.drive_tab
    n_walls = len(g.wall_load)
    wall_drive = g.wall_drive.copy() if len(g.wall_drive) else np.full(n_walls, -1, np.int64)
    wall_drive[wall] = nd
    return g._replace(
        drive_target=np.append(g.drive_target, -1 - wall).astype(np.int64),
        drive_kind=np.append(g.drive_kind, KIND_FORCE).astype(np.int64),
        drive_prof=np.append(g.drive_prof, PROFILE_CONSTANT).astype(np.int64),
        drive_dir=np.vstack([g.drive_dir.reshape(nd, d), np.asarray(direction, float)[None, :]]),
        drive_par=np.vstack([g.drive_par, par]),
        drive_tab=tab,
        drive_tlen=np.append(g.drive_tlen, 1).astype(np.int64),
        drive_x0=np.vstack([g.drive_x0.reshape(nd, d), np.zeros((1, d))]),
        drive_now=np.vstack([g.drive_now, np.zeros((1, N_DRIVE))]),
        wall_drive=wall_drive,
    )


def drive_names(s: Scenario) -> list[str]:
    """The names of the drives of the resolved scenario s in the loop's order (the Dataset's
    `drive` axis): each [[drives]] entry's, then a held precompression's wall (its target,
    "wall LABEL")."""
    names = [d.name for d in s.drives]
    p = s.precompression
    if p is not None and p.mode == "held":
        names.append(p.target)
    return names


def driven_initial_state(y0: np.ndarray, fields: dict) -> np.ndarray:
    """y0 (ng, nc) with each granule under a displacement or velocity drive given the
    prescribed velocity at t = 0 along the drive's direction (the other components kept)."""
    y0 = y0.copy()
    d = fields["drive_dir"].shape[1]
    for k, i in enumerate(fields["drive_target"]):
        if i < 0 or fields["drive_kind"][k] == KIND_FORCE:
            continue
        _, v, _ = drive_motion(
            0.0,
            fields["drive_kind"][k],
            fields["drive_prof"][k],
            fields["drive_par"][k],
            fields["drive_tab"][k],
            fields["drive_tlen"][k],
        )
        e = fields["drive_dir"][k]
        vel = y0[i, 3 : 3 + d]
        y0[i, 3 : 3 + d] = vel + (v - float(vel @ e)) * e
    return y0
