"""The result's contact table: every granule-granule and granule-wall contact in touch at
the table's output times (time.contact_interval), with its overlap, normal force and
friction force, computed from the recorded states by the loop's own contact laws.

Each row of the table (dimension `link`) is one contact at one time: `link_time` [s], the
granule `link_granule` and its partner `link_partner` (a granule index, or -1 - w for
wall w of the `wall` axis), `link_overlap` delta [m], `link_normal_force` |N| [N] and
`link_tangential_force` |F_t| [N]; the coordinate `link_table_time` lists the times the
table covers (a time with no contact in touch has no rows). docs/output.md.

How each force is found, at the recorded state (positions and velocities) of that time:

- the overlap and its rate with the loop's kinematics (physics.contact in the plane,
  physics.space and solver.granular3d in space), a driven wall where its drive put it
  (its recorded displacement) moving at its drive's speed (the prescribed motion's, or a
  piston's from its recorded displacements by central differences);
- the normal force by the contact's normal law (physics.laws.normal_law_force: Hertz,
  Thornton's or "johnson"), with the coefficient rows the loop builds
  (model.arrays.pair_coefficients, wall_arrays) and the contact's history: its largest
  overlap so far is the largest of its overlap now, its overlaps at the earlier output
  times (every output time, for a run with a yielding law), and the run's final largest
  overlap once the time it was reached has passed (solver.driver.ContactPeaks); its rate
  factor the run's final one once it has yielded. The largest overlap is exact after the
  contact's last loading and while it loads monotonically; between two loadings it is
  the largest sampled at the output times (a lower bound);
- the friction force |mu N tanh(k_s v_t)| (eq. 5) at the recorded slip rate, the law the
  loop integrates (under solver.granular_friction = "split" it applies it in exact half
  steps, so the force over a step is this law's along the slip's relaxation); under
  Mindlin's law (contact.tangential_law = "mindlin") the friction force depends on the
  contact's tangential history, which the recorded state does not hold: NaN.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import xarray as xr
from granplate.jit import njit

from granplate.physics.contact import (
    COEF_DY,
    N_COEF,
    contact_arm,
    pair_overlap,
    pair_rates,
    wall_overlap,
    wall_rates,
)
from granplate.model.dimension import of_state
from granplate.physics.laws import keeps_history, normal_law_force, tangential_friction
from granplate.physics.space import pair_contact_3d, wall_overlap_3d
from granplate.solver.granular3d import pair_slip, wall_slip

#: name -> (units, description) of the table's variables (docs/output.md)
LINK_VARIABLES: dict[str, tuple[str, str]] = {
    "link_time": ("s", "output time of each row of the contact table (one contact in touch at one time)"),
    "link_granule": ("1", "the contact's granule (index on the granule axis)"),
    "link_partner": (
        "1",
        "its partner: a granule index j > link_granule, or -1 - w for wall w (index on the wall axis)",
    ),
    "link_overlap": ("m", "the contact's overlap delta > 0"),
    "link_normal_force": ("N", "the normal force |N| of the contact's normal law, damping included (eqs. 2-4)"),
    "link_tangential_force": (
        "N",
        "the magnitude of the friction force mu |N| |tanh(k_s v_t)| (eq. 5); NaN under Mindlin's law",
    ),
}

#: the table's columns in the kernels' output rows
OVERLAP, NORMAL, TANGENTIAL = 0, 1, 2


class Links(NamedTuple):
    """The contacts in touch at one time: granule (n,), partner (n,) (granule j or -1 - w),
    values (n, 3): overlap [m], normal force [N], friction force [N]."""

    granule: np.ndarray
    partner: np.ndarray
    values: np.ndarray


#: columns of the kinematics rows: the overlap delta [m], its rate [m/s] (less a wall's
#: speed along its normal) and the slip speed |v_t| [m/s] (0 where apart)
DELTA, RATE, SLIP = 0, 1, 2


@njit(entry=True, cache=True)
def pair_kinematics_plane(y, radius, pairs, arm_shrink, kin):
    """Overlap, its rate and the slip speed of each pair (i, j) of `pairs` at the plane's
    state y (6 columns) into kin (np, 3), with the loop's kinematics (physics.contact)."""
    for p in range(pairs.shape[0]):
        i = pairs[p, 0]
        j = pairs[p, 1]
        ri = radius[i]
        rj = radius[j]
        delta, nx, nz = pair_overlap(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj)
        kin[p, DELTA] = delta
        kin[p, RATE] = 0.0
        kin[p, SLIP] = 0.0
        if delta > 0.0:
            ai = contact_arm(ri, delta, 0.5 * arm_shrink)
            aj = contact_arm(rj, delta, 0.5 * arm_shrink)
            ddot, vt = pair_rates(y[i, 3], y[i, 4], y[i, 5], y[j, 3], y[j, 4], y[j, 5], nx, nz, ai, aj)
            kin[p, RATE] = ddot
            kin[p, SLIP] = vt


@njit(entry=True, cache=True)
def pair_kinematics_space(y, radius, pairs, arm_shrink, kin):
    """`pair_kinematics_plane` at space's state y (9 columns), with the loop's kinematics
    in space (physics.space, solver.granular3d)."""
    for p in range(pairs.shape[0]):
        i = pairs[p, 0]
        j = pairs[p, 1]
        ri = radius[i]
        rj = radius[j]
        delta, nx, ny, nz = pair_contact_3d(y[i, 0], y[i, 1], y[i, 2], ri, y[j, 0], y[j, 1], y[j, 2], rj)
        kin[p, DELTA] = delta
        kin[p, RATE] = 0.0
        kin[p, SLIP] = 0.0
        if delta > 0.0:
            ai = contact_arm(ri, delta, 0.5 * arm_shrink)
            aj = contact_arm(rj, delta, 0.5 * arm_shrink)
            ddot, sx, sy, sz = pair_slip(y, i, j, nx, ny, nz, ai, aj)
            kin[p, RATE] = ddot
            kin[p, SLIP] = math.sqrt(sx * sx + sy * sy + sz * sz)


@njit(entry=True, cache=True)
def wall_kinematics_plane(y, radius, granule, geo, vn, arm_shrink, kin):
    """Overlap, its rate less the wall's speed vn[k] [m/s] along its normal, and the slip
    speed of each granule `granule[k]` against the wall of row geo[k] ([n..., offset where
    the wall is], unit outward normal) at the plane's state y into kin (nw, 3)."""
    for k in range(granule.shape[0]):
        i = granule[k]
        ri = radius[i]
        nx, nz = geo[k, 0], geo[k, 1]
        delta = wall_overlap(y[i, 0], y[i, 1], ri, nx, nz, geo[k, 2])
        kin[k, DELTA] = delta
        kin[k, RATE] = 0.0
        kin[k, SLIP] = 0.0
        if delta > 0.0:
            a = contact_arm(ri, delta, arm_shrink)
            ddot, vt = wall_rates(y[i, 3], y[i, 4], y[i, 5], nx, nz, a)
            kin[k, RATE] = ddot - vn[k]
            kin[k, SLIP] = vt


@njit(entry=True, cache=True)
def wall_kinematics_space(y, radius, granule, geo, vn, arm_shrink, kin):
    """`wall_kinematics_plane` at space's state y (9 columns)."""
    for k in range(granule.shape[0]):
        i = granule[k]
        ri = radius[i]
        nx, ny, nz = geo[k, 0], geo[k, 1], geo[k, 2]
        delta = wall_overlap_3d(y[i, 0], y[i, 1], y[i, 2], ri, nx, ny, nz, geo[k, 3])
        kin[k, DELTA] = delta
        kin[k, RATE] = 0.0
        kin[k, SLIP] = 0.0
        if delta > 0.0:
            a = contact_arm(ri, delta, arm_shrink)
            ddot, sx, sy, sz = wall_slip(y, i, nx, ny, nz, a)
            kin[k, RATE] = ddot - vn[k]
            kin[k, SLIP] = math.sqrt(sx * sx + sy * sy + sz * sz)


#: the contacts' kinematics by the dimension's name (model.dimension): (pairs, walls)
KINEMATICS = {
    "plane": (pair_kinematics_plane, wall_kinematics_plane),
    "space": (pair_kinematics_space, wall_kinematics_space),
}


@njit(entry=True, cache=True)
def link_forces(kin, coef, dmax, rate, clip, out):
    """Overlap, normal and friction force of each contact of kinematics row kin[k] (`DELTA`,
    `RATE`, `SLIP`) and coefficient row coef[k] into out (n, 3), by its normal law
    (physics.laws) and `tangential_magnitude`; out[k, OVERLAP] <= 0 where apart.
    dmax, rate: each contact's largest overlap so far [m] and rate factor [-]."""
    for k in range(kin.shape[0]):
        delta = kin[k, DELTA]
        out[k, OVERLAP] = delta
        out[k, NORMAL] = 0.0
        out[k, TANGENTIAL] = 0.0
        if delta <= 0.0:
            continue
        c = coef[k]
        n = normal_law_force(delta, kin[k, RATE], c, max(dmax[k], delta), rate[k], clip)
        out[k, NORMAL] = n
        out[k, TANGENTIAL] = tangential_magnitude(n, kin[k, SLIP], c)


@njit(cache=True)
def tangential_magnitude(n: float, vt: float, c) -> float:
    """|F_t| [N] of a contact of coefficient row c at normal force n [N] and slip rate vt
    [m/s]: its rate law's (eq. 5 for the tanh law); NaN under a law with history (Mindlin's),
    whose force follows from its tangential history, not from the state."""
    if keeps_history(c):
        return math.nan
    return abs(tangential_friction(n, vt, c))


def table_rows(n: int, steps: int, times: np.ndarray, t_end: float, dt_out: float) -> np.ndarray:
    """The output rows (of n, at `times` [s]) the table covers: the output times k steps
    dt_out of the whole run (a restarted run's first row being a later one), and the last
    when the run reached t_end (as the plate snapshots); none for steps 0."""
    if steps <= 0 or n == 0:
        return np.zeros(0, np.int64)
    first = int(round(float(times[0]) / dt_out))
    idx = np.arange((-first) % steps, n, steps, dtype=np.int64)
    if (not len(idx) or idx[-1] != n - 1) and np.isclose(times[n - 1], t_end):
        idx = np.append(idx, n - 1)
    return idx


class WallMotion(NamedTuple):
    """The walls at every output time: unit outward normals (n_walls, d), offsets (no,
    n_walls) [m] and speeds along the normal (no, n_walls) [m/s]."""

    normal: np.ndarray
    offset: np.ndarray
    speed: np.ndarray


def wall_motion(model, out, n: int) -> WallMotion:
    """Where the walls of `model` (Model.walls, where the run starts) are at the n output
    times of `out`: a driven wall shifted by its drive's recorded displacement along its
    direction, moving at its prescribed speed (a piston: the central differences of its
    displacements)."""
    from granplate.physics.drives import drive_motion
    from granplate.solver.drives import is_piston

    walls, g = model.walls, model.granular
    d = model.config.dimension
    normal = np.array([np.asarray(w.normal, float) / np.linalg.norm(w.normal) for w in walls]).reshape(-1, d)
    offset = np.tile(np.array([float(w.offset) for w in walls]), (n, 1))
    speed = np.zeros_like(offset)
    t = np.asarray(out.t[:n], float)
    for w, k in enumerate(np.asarray(g.wall_drive, np.int64).tolist()):
        if k < 0:
            continue
        ne = float(normal[w] @ np.asarray(g.drive_dir[k], float))
        s = np.asarray(out.drive[:n, k, 1], float)
        offset[:, w] += s * ne
        if is_piston(g, k):
            v = np.gradient(s, t) if n > 1 else np.zeros(n)
        else:
            args = (g.drive_kind[k], g.drive_prof[k], g.drive_par[k], g.drive_tab[k], g.drive_tlen[k])
            v = np.array([drive_motion(float(tk), *args)[1] for tk in t])
        speed[:, w] = v * ne
    return WallMotion(normal, offset, speed)


def touching_pairs(y: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """(np, 2) sorted pairs i < j whose surfaces touch or overlap at state y (a k-d tree,
    model.neighbours.contact_pairs with no gap): the reference of the table's touch test."""
    from granplate.model.contacts import centre_coordinates
    from granplate.model.neighbours import contact_pairs

    x, yy, z = centre_coordinates(y, of_state(y.shape[1]).n)
    return np.asarray(contact_pairs(x, yy, radius, 0.0, z), np.int64).reshape(-1, 2)


def reaching(y: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """(nc, 2) sorted pairs i < j at state y that may touch by any rounding of their
    distance (model.neighbours.reaching_pairs: one compiled cell-grid pass)."""
    from granplate.model.neighbours import reaching_pairs

    return reaching_pairs(y[:, : of_state(y.shape[1]).n], radius)


def yields(model) -> bool:
    """Whether any contact of the run may follow a yielding law (its history matters): a
    law other than Hertz's between two of its granules' materials or a granule's and a wall's."""
    s = model.scenario
    names = sorted({m.name for m in model.materials})
    others = names + sorted({w.material for w in model.walls})
    return any(s.contact.law_for_pair(a, b) != "hertz" for a in names for b in others)


class Seen(NamedTuple):
    """The contacts in touch at some output rows, one row each, sorted by output row, then
    pairs (granule, partner) before walls (granule, wall): `time` the output row, `granule`,
    `partner` (granule j, or -1 - w), `delta` the overlap [m], `table` whether the row is a
    table time, and at table times `kin` (n, 3) the kinematics (DELTA, RATE, SLIP) and `coef`
    (n, N_COEF) the coefficient row (zeros elsewhere)."""

    time: np.ndarray
    granule: np.ndarray
    partner: np.ndarray
    delta: np.ndarray
    table: np.ndarray
    kin: np.ndarray
    coef: np.ndarray


def contact_table(model, out, n: int, peaks, steps: int) -> tuple[dict[str, xr.DataArray], dict]:
    """The contact table's variables and its coordinate `link_table_time` over the first n
    output rows of `out` (solver.state.Output), every `steps` rows (run_checks.contact_steps;
    0: none, an empty dict each); peaks: the run's ContactPeaks (None: none known).

    The output rows are taken in blocks (`seen_in_blocks`): a run whose contacts all follow
    Hertz's law needs its table times alone; a run with a yielding law every output time up
    to the last table time, whose overlaps give each contact's largest overlap at the table
    times (`largest_overlaps`)."""
    t = np.asarray(out.t[:n], float)
    rows = table_rows(n, steps, t, model.scenario.time.t_end, model.scenario.time.output_interval)
    if not len(rows):
        return {}, {}
    walls = wall_motion(model, out, n)
    plastic = yields(model)
    seen_rows = np.arange(int(rows[-1]) + 1, dtype=np.int64) if plastic else rows
    table = np.zeros(len(seen_rows), bool)
    table[np.searchsorted(seen_rows, rows)] = True
    seen = seen_in_blocks(model, out, seen_rows, table, walls)
    on = np.flatnonzero(seen.table)
    if plastic:
        dmax, rate = largest_overlaps(seen, t, peaks, model.n_granules, len(model.walls))
        dmax, rate = dmax[on], rate[on]
    else:
        dmax = rate = np.zeros(len(on))
    values = np.zeros((len(on), 3))
    link_forces(
        np.ascontiguousarray(seen.kin[on]), np.ascontiguousarray(seen.coef[on]), dmax, rate, model.config.clip, values
    )
    links = Links(granule=seen.granule[on], partner=seen.partner[on], values=values)
    counts = np.bincount(np.searchsorted(rows, seen.time[on]), minlength=len(rows)).astype(np.int64)
    return table_variables(counts, links, t[rows])


def contact_keys(granule: np.ndarray, partner: np.ndarray, n_granules: int, n_walls: int) -> np.ndarray:
    """One integer per contact: granule * (n_granules + n_walls + 2) + (partner + n_walls + 1)."""
    width = n_granules + n_walls + 2
    return np.asarray(granule, np.int64) * width + (np.asarray(partner, np.int64) + n_walls + 1)


@njit(entry=True, cache=True)
def earlier_maxima(first: np.ndarray, values: np.ndarray) -> np.ndarray:
    """out[k] = the largest of values[g..k-1] over the run of rows g..k-1 that row k's group
    began with (first[g] True), 0 where none: each contact's largest overlap at the output
    times before, its rows in time order."""
    out = np.zeros(values.shape[0])
    top = 0.0
    for k in range(values.shape[0]):
        if first[k]:
            top = 0.0
        out[k] = top
        if values[k] > top:
            top = values[k]
    return out


def largest_overlaps(seen: Seen, t: np.ndarray, peaks, n_granules: int, n_walls: int) -> tuple[np.ndarray, np.ndarray]:
    """Each seen row's contact's largest overlap so far [m] and rate factor [-] (module
    docstring): the largest of its overlaps at the output times before, and the run's final
    largest overlap (peaks: solver.driver.ContactPeaks) once the time it was reached has
    passed; the run's final rate factor once that largest overlap passes the rate-free yield
    overlap COEF_DY, else 0 (the loop's value while unset)."""
    key = contact_keys(seen.granule, seen.partner, n_granules, n_walls)
    order = np.lexsort((seen.time, key))
    first = np.ones(len(key), bool)
    first[1:] = key[order][1:] != key[order][:-1]
    dmax = np.empty(len(key))
    dmax[order] = earlier_maxima(first, np.ascontiguousarray(seen.delta[order]))
    rate = np.zeros(len(key))
    if peaks is not None and len(peaks.granule) and len(key):
        pk = contact_keys(peaks.granule, peaks.partner, n_granules, n_walls)
        by = np.argsort(pk, kind="stable")
        pk, peak, when = pk[by], np.asarray(peaks.delta_max, float)[by], np.asarray(peaks.time, float)[by]
        prate = (np.zeros(len(pk)) if peaks.rate is None else np.asarray(peaks.rate, float))[by]
        k = np.clip(np.searchsorted(pk, key), 0, len(pk) - 1)
        hit = pk[k] == key
        done = hit & (when[k] <= t[seen.time] * (1.0 + 1e-12))
        dmax[done] = np.maximum(dmax[done], peak[k[done]])
        rate[hit] = prate[k[hit]]
    yielded = dmax > seen.coef[:, COEF_DY]
    return dmax, np.where(yielded & seen.table, rate, 0.0)


#: the most (output time, candidate contact) rows `seen_in_blocks` treats at once
BLOCK_ROWS = 1_000_000


def block_candidates(ys: np.ndarray, r: np.ndarray) -> np.ndarray | None:
    """(nc, 2) sorted pairs i < j that may touch at any of the states ys (nb, ng, columns)
    (model.neighbours.reaching_pairs at the first state, its reach widened by twice the
    largest displacement D from it); None where D exceeds half the smallest radius (a block
    of fewer times is cheaper) or is not finite."""
    from granplate.model.neighbours import SEARCH_MARGIN, reaching_pairs

    if ys.shape[1] < 2:
        return np.zeros((0, 2), np.int64)
    d = of_state(ys.shape[2]).n
    p0 = ys[0, :, :d]
    disp = float(np.sqrt(np.max(np.sum((ys[:, :, :d] - p0) ** 2, axis=2)))) if len(ys) > 1 else 0.0
    r_min = float(r.min()) if len(r) else 0.0
    if not math.isfinite(disp) or (disp > 0.5 * r_min and len(ys) > 1):
        return None
    return reaching_pairs(p0, r, 1.0 + SEARCH_MARGIN + disp / r_min if disp > 0.0 else 1.0 + SEARCH_MARGIN)


def seen_in_blocks(model, out, rows: np.ndarray, table: np.ndarray, walls: WallMotion) -> Seen:
    """The contacts in touch at the output rows `rows` of `out` (`Seen`; table[k]: whether
    rows[k] is a table time), in blocks of output rows of at most BLOCK_ROWS candidate rows
    over which no granule moves more than half the smallest radius: one candidate search per
    block, the kinematics of all its rows in one compiled call (`block_seen`)."""
    r = np.asarray(model.granular.radius, float)
    ng = len(r)
    parts: list[Seen] = []
    known: dict = {}
    start = 0
    while start < len(rows):
        nb = min(len(rows) - start, max(1, BLOCK_ROWS // max(ng, 1)))
        while True:
            ys = np.ascontiguousarray(out.y[rows[start : start + nb]], dtype=float)
            cand = block_candidates(ys, r)
            if nb == 1 or (cand is not None and len(cand) * nb <= BLOCK_ROWS):
                break
            nb = max(1, nb // 2)
        if cand is None:
            cand = reaching(ys[0], r)
        parts.append(block_seen(model, ys, rows[start : start + nb], table[start : start + nb], cand, walls, known))
        start += nb
    return Seen(*(np.concatenate([getattr(p, f) for p in parts]) for f in Seen._fields))


def block_seen(
    model, ys, rows: np.ndarray, table: np.ndarray, cand: np.ndarray, walls: WallMotion, known: dict
) -> Seen:
    """`Seen` of the states ys (nb, ng, columns) at the output rows `rows` from the candidate
    pairs `cand`: the states laid end to end as nb * ng granules, so that the kinematics and
    the touch test run once over every (time, pair) and (time, wall) row. At a table time
    the overlap is the kinematics' (physics.contact, physics.space); between, the distance's
    (pairs: R_i + R_j - |x_j - x_i|; walls: x . n + R - offset), as the loop's own histories
    see it."""
    from granplate.model.contacts import centre_coordinates
    from granplate.model.neighbours import contacts_among

    cfg = model.config
    nb, ng, c = ys.shape
    d = of_state(c).n
    r = np.asarray(model.granular.radius, float)
    flat = ys.reshape(nb * ng, c)
    r_flat = np.tile(r, nb)
    base = (np.arange(nb, dtype=np.int64) * ng)[:, None]
    pairs = np.column_stack([(base + cand[:, 0]).ravel(), (base + cand[:, 1]).ravel()]).reshape(-1, 2)
    pair_kin, wall_kin = KINEMATICS[of_state(c).name]
    kin = np.zeros((len(pairs), 3))
    at_table = table[pairs[:, 0] // ng]
    sub = np.zeros((int(at_table.sum()), 3))
    pair_kin(flat, r_flat, np.ascontiguousarray(pairs[at_table]), cfg.arm_shrink, sub)
    kin[at_table] = sub
    between = ~at_table
    if between.any():
        i, j = pairs[between, 0], pairs[between, 1]
        kin[between, DELTA] = r_flat[i] + r_flat[j] - np.linalg.norm(flat[j, :d] - flat[i, :d], axis=1)
    on = np.flatnonzero(kin[:, DELTA] > 0.0)
    x, yy, z = centre_coordinates(flat, d)
    on = on[contacts_among(pairs[on], x, yy, r_flat, 0.0, z)]
    pt, pi, pj = pairs[on, 0] // ng, pairs[on, 0] % ng, pairs[on, 1] % ng
    tab = table[pt]
    pair_coef = None if len(tab) and tab.all() else np.zeros((len(on), N_COEF))
    if tab.any():
        codes = pi[tab] * ng + pj[tab]
        if np.all(codes[1:] > codes[:-1]):  # (one table time, its pairs in order: each its own row)
            code, inverse = codes, None
        else:
            code, inverse = np.unique(codes, return_inverse=True)
        rows_ = cached_rows(model, np.column_stack([code // ng, code % ng]), known)
        rows_ = rows_ if inverse is None else np.take(rows_, np.asarray(inverse, np.int64).ravel(), axis=0)
        if pair_coef is None:
            pair_coef = rows_
        else:
            pair_coef[tab] = rows_
    wt, wi, ww, wkin, wall_coef = block_walls(model, flat, rows, table, walls, r_flat, ng, wall_kin)
    keep = wkin[:, DELTA] > 0.0
    wt, wi, ww, wkin, wall_coef = wt[keep], wi[keep], ww[keep], wkin[keep], wall_coef[keep]
    time = np.concatenate([pt, wt])
    kind = np.concatenate([np.zeros(len(pt), np.int64), np.ones(len(wt), np.int64)])
    gran = np.concatenate([pi, wi])
    other = np.concatenate([pj, ww])  # the partner granule, or the wall's index
    order = np.lexsort((other, gran, kind, time))
    met_in_order = len(wt) == 0 and bool(np.all(order[1:] > order[:-1]))  # (pairs alone, as met: no copies)
    if met_in_order:
        order = slice(None)
    all_kin = np.concatenate([kin[on], wkin])[order]
    return Seen(
        time=rows[time[order]],
        granule=gran[order],
        partner=np.concatenate([pj, -1 - ww])[order],
        delta=all_kin[:, DELTA].copy(),
        table=table[time[order]],
        kin=all_kin,
        coef=pair_coef if met_in_order else np.concatenate([pair_coef, wall_coef])[order],
    )


def block_walls(model, flat, rows, table, walls: WallMotion, r_flat, ng: int, wall_kin):
    """(time in the block, granule, wall, kinematics (n, 3), coefficient rows) of the granules
    reaching each wall (x . n + R - offset >= 0) at the block's states `flat` (nb * ng rows);
    the kinematics' at table times (the wall where its drive put it, moving at its speed),
    the overlap x . n + R - offset between; coefficient rows at table times (zeros between)."""
    from granplate.model.arrays import wall_arrays

    nb = len(rows)
    nw = len(walls.normal)
    d = walls.normal.shape[1]
    if not nw:
        e = np.zeros(0, np.int64)
        return e, e, e, np.zeros((0, 3)), np.zeros((0, N_COEF))
    r = r_flat[:ng]
    reach = (flat[:, :d] @ walls.normal.T).reshape(nb, ng, nw) + r[None, :, None] - walls.offset[rows][:, None, :]
    wt, wi, ww = np.nonzero(reach >= 0.0)
    o = rows[wt]
    tab = table[wt]
    kin = np.zeros((len(wt), 3))
    geo = np.column_stack([walls.normal[ww[tab]], walls.offset[o[tab], ww[tab]]]).reshape(-1, d + 1)
    sub = np.zeros((int(tab.sum()), 3))
    wall_kin(
        flat,
        r_flat,
        np.ascontiguousarray(wt[tab] * ng + wi[tab]),
        geo,
        walls.speed[o[tab], ww[tab]].copy(),
        model.config.arm_shrink,
        sub,
    )
    kin[tab] = sub
    if (~tab).any():
        i, w, gi = wi[~tab], ww[~tab], wt[~tab] * ng + wi[~tab]
        kin[~tab, DELTA] = np.sum(flat[gi, :d] * walls.normal[w], axis=1) + r[i] - walls.offset[o[~tab], w]
    coef = np.zeros((len(wt), N_COEF))
    if tab.any():
        key, inverse = np.unique(wi[tab] * nw + ww[tab], return_inverse=True)
        g = model.granular
        _, rows_ = wall_arrays(
            model.scenario, list(model.materials), r, g.mass, np.column_stack([key // nw, key % nw]), model.walls
        )
        coef[tab] = rows_[np.asarray(inverse, np.int64).ravel()]
    return wt, wi, ww, kin, coef


def cached_rows(model, pairs: np.ndarray, known: dict) -> np.ndarray:
    """model.relists.cached_pair_coefficients of the distinct sorted pairs (n, 2)."""
    from granplate.model.arrays import cached_pair_coefficients

    g = model.granular
    return cached_pair_coefficients(
        model.scenario, list(model.materials), g, np.asarray(pairs, np.int64).reshape(-1, 2), known
    )


def table_variables(counts: np.ndarray, links: Links, times: np.ndarray) -> tuple[dict[str, xr.DataArray], dict]:
    """The Dataset variables of the table at `times` [s], counts[k] contacts at times[k], the
    rows `links` in time order (module docstring)."""
    values = np.asarray(links.values, float).reshape(-1, 3)

    def var(name: str, data) -> xr.DataArray:
        units, desc = LINK_VARIABLES[name]
        return xr.DataArray(data, dims=("link",), attrs={"units": units, "long_name": desc})

    data = {
        "link_time": var("link_time", np.repeat(times, counts)),
        "link_granule": var("link_granule", np.asarray(links.granule).astype(np.int32)),
        "link_partner": var("link_partner", np.asarray(links.partner).astype(np.int32)),
        "link_overlap": var("link_overlap", values[:, OVERLAP].copy()),
        "link_normal_force": var("link_normal_force", values[:, NORMAL].copy()),
        "link_tangential_force": var("link_tangential_force", values[:, TANGENTIAL].copy()),
    }
    coords = {
        "link_table_time": (
            "link_table_time",
            np.asarray(times, float).copy(),
            {"units": "s", "long_name": "the output times the contact table covers (time.contact_interval)"},
        )
    }
    return data, coords


def links_of(ds: xr.Dataset, t: float) -> Links | None:
    """The contact table's rows at time t [s] of a result (None: the result has no table at
    that time, or none at all)."""
    if "link_table_time" not in ds.coords or "link_time" not in ds:
        return None
    tt = np.asarray(ds["link_table_time"].values, float)
    if not len(tt) or not np.isclose(tt, t, rtol=1e-12, atol=0.0).any():
        return None
    on = np.asarray(ds["link_time"].values, float) == tt[np.argmin(np.abs(tt - t))]
    values = np.column_stack([ds[f"link_{k}"].values[on] for k in ("overlap", "normal_force", "tangential_force")])
    return Links(
        granule=np.asarray(ds["link_granule"].values[on], np.int64),
        partner=np.asarray(ds["link_partner"].values[on], np.int64),
        values=np.asarray(values, float).reshape(-1, 3),
    )
