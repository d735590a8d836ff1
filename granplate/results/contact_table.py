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
    COEF_KS,
    COEF_MU,
    COEF_TLAW,
    contact_arm,
    friction_magnitude,
    pair_overlap,
    pair_rates,
    wall_overlap,
    wall_rates,
)
from granplate.model.dimension import of_state
from granplate.physics.laws import normal_law_force
from granplate.physics.space import pair_contact_3d, wall_overlap_3d
from granplate.setup.law_registry import MINDLIN
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


def wall_links(y, radius, granule, geo, vn, coef, dmax, rate, arm_shrink, clip, out) -> None:
    """Overlap, normal and friction force of each granule `granule[k]` against the wall of
    row geo[k] ([n..., offset where the wall is], unit outward normal) moving at vn[k] [m/s]
    along it, into out (nw, 3); out[k, OVERLAP] <= 0 where apart. dmax, rate: each
    contact's largest overlap so far [m] and rate factor [-]."""
    kin = np.zeros((len(granule), 3))
    KINEMATICS[of_state(y.shape[1]).name][1](y, radius, granule, geo, vn, arm_shrink, kin)
    link_forces(kin, coef, dmax, rate, clip, out)


@njit(cache=True)
def tangential_magnitude(n: float, vt: float, c) -> float:
    """|F_t| [N] of a contact of coefficient row c at normal force n [N] and slip rate vt
    [m/s]: the tanh law's (eq. 5); NaN for a Mindlin contact (COEF_TLAW), whose force
    follows from its tangential history, not from the state."""
    if c[COEF_TLAW] == MINDLIN:
        return math.nan
    return abs(friction_magnitude(n, vt, c[COEF_MU], c[COEF_KS]))


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
    model.neighbours.contact_pairs with no gap): the reference `in_touch` keeps to."""
    from granplate.model.contacts import centre_coordinates
    from granplate.model.neighbours import contact_pairs

    x, yy, z = centre_coordinates(y, of_state(y.shape[1]).n)
    return np.asarray(contact_pairs(x, yy, radius, 0.0, z), np.int64).reshape(-1, 2)


def reaching(y: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """(nc, 2) sorted pairs i < j at state y that may touch by any rounding of their
    distance (model.neighbours.reaching_pairs: one compiled cell-grid pass)."""
    from granplate.model.neighbours import reaching_pairs

    return reaching_pairs(y[:, : of_state(y.shape[1]).n], radius)


def in_touch(y: np.ndarray, radius: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """The mask of `pairs` (sorted, i < j) that `touching_pairs` returns at state y: the
    same test (model.neighbours.contacts_among with no gap), on these pairs alone."""
    from granplate.model.contacts import centre_coordinates
    from granplate.model.neighbours import contacts_among

    x, yy, z = centre_coordinates(y, of_state(y.shape[1]).n)
    return contacts_among(pairs, x, yy, radius, 0.0, z)


def touching_walls(y: np.ndarray, radius: np.ndarray, walls: WallMotion, o: int) -> np.ndarray:
    """(nw, 2) [granule, wall] of the granules reaching each wall at output o (overlap >= 0)."""
    d = walls.normal.shape[1]
    if not len(walls.normal):
        return np.zeros((0, 2), np.int64)
    reach = y[:, :d] @ walls.normal.T + radius[:, None] - walls.offset[o][None, :]
    i, w = np.nonzero(reach >= 0.0)
    return np.column_stack([i, w]).astype(np.int64).reshape(-1, 2)


class History:
    """Each contact's largest overlap so far and rate factor at an output time (module
    docstring), from the run's final histories (peaks) and the overlaps seen at the output
    times passed so far (`see`). Contacts are keyed granule * width + (partner + n_walls + 1)."""

    def __init__(self, peaks, n_granules: int, n_walls: int):
        self.width = n_granules + n_walls + 2
        self.n_walls = n_walls
        self.seen_key = np.zeros(0, np.int64)
        self.seen_max = np.zeros(0)
        if peaks is None or not len(peaks.granule):
            self.key, self.peak, self.when, self.rate = (np.zeros(0, np.int64), np.zeros(0), np.zeros(0), np.zeros(0))
            return
        key = self.keys(peaks.granule, peaks.partner)
        order = np.argsort(key, kind="stable")
        self.key, self.peak, self.when = key[order], np.asarray(peaks.delta_max)[order], np.asarray(peaks.time)[order]
        rate = np.zeros(len(key)) if peaks.rate is None else np.asarray(peaks.rate, float)
        self.rate = rate[order]

    def keys(self, granule: np.ndarray, partner: np.ndarray) -> np.ndarray:
        return np.asarray(granule, np.int64) * self.width + (np.asarray(partner, np.int64) + self.n_walls + 1)

    def see(self, key: np.ndarray, delta: np.ndarray) -> None:
        """Take the overlaps delta [m] of the contacts `key` at one output time into the
        largest seen so far."""
        on = delta > 0.0
        if not on.any():
            return
        keys = np.concatenate([self.seen_key, key[on]])
        values = np.concatenate([self.seen_max, delta[on]])
        self.seen_key, inverse = np.unique(keys, return_inverse=True)
        self.seen_max = np.full(len(self.seen_key), -np.inf)
        np.maximum.at(self.seen_max, inverse, values)

    def at(self, key: np.ndarray, t: float, coef: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(largest overlap so far [m], rate factor [-]) of the contacts `key` at time t [s]
        (coef: their coefficient rows: the rate factor is the loop's, 0, until the largest
        overlap passes the rate-free yield overlap)."""
        dmax = np.zeros(len(key))
        if len(self.seen_key):
            k = np.clip(np.searchsorted(self.seen_key, key), 0, len(self.seen_key) - 1)
            hit = self.seen_key[k] == key
            dmax[hit] = self.seen_max[k[hit]]
        rate = np.zeros(len(key))
        if len(self.key):
            k = np.clip(np.searchsorted(self.key, key), 0, len(self.key) - 1)
            hit = self.key[k] == key
            done = hit & (self.when[k] <= t * (1.0 + 1e-12))
            dmax[done] = np.maximum(dmax[done], self.peak[k[done]])
            rate[hit] = self.rate[k[hit]]
        yielded = dmax > np.asarray(coef, float).reshape(len(key), -1)[:, COEF_DY] if len(key) else np.zeros(0, bool)
        return dmax, np.where(yielded, rate, 0.0)


def links_at(model, y: np.ndarray, o: int, walls: WallMotion, history: History, t: float, known: dict) -> Links:
    """The contacts in touch at state y, output o (time t [s]), with their forces; known:
    the pairs' coefficient rows met so far (model.arrays.cached_pair_coefficients)."""
    from granplate.model.arrays import cached_pair_coefficients, wall_arrays

    s, mats, g, cfg = model.scenario, list(model.materials), model.granular, model.config
    r = np.asarray(g.radius, float)
    cand = reaching(y, r)  # kept: those of `touching_pairs` that overlap, in its order
    kin = np.zeros((len(cand), 3))
    KINEMATICS[of_state(y.shape[1]).name][0](y, r, cand, cfg.arm_shrink, kin)
    on = np.flatnonzero(kin[:, DELTA] > 0.0)
    on = on[in_touch(y, r, cand[on])]
    pairs, kin = cand[on], kin[on]
    coef = cached_pair_coefficients(s, mats, g, pairs, known)
    dmax, rate = history.at(history.keys(pairs[:, 0], pairs[:, 1]), t, coef)
    pv = np.zeros((len(pairs), 3))
    link_forces(kin, coef, dmax, rate, cfg.clip, pv)
    wc = touching_walls(y, r, walls, o)
    _, wcoef = wall_arrays(s, mats, r, g.mass, wc, model.walls)
    w = wc[:, 1]
    geo = (
        np.column_stack([walls.normal[w], walls.offset[o, w]]) if len(wc) else np.zeros((0, walls.normal.shape[1] + 1))
    )
    dmax, rate = history.at(history.keys(wc[:, 0], -1 - w), t, wcoef)
    wv = np.zeros((len(wc), 3))
    wall_links(
        y,
        r,
        np.ascontiguousarray(wc[:, 0]),
        geo,
        walls.speed[o, w].copy(),
        wcoef,
        dmax,
        rate,
        cfg.arm_shrink,
        cfg.clip,
        wv,
    )
    on_p, on_w = pv[:, OVERLAP] > 0.0, wv[:, OVERLAP] > 0.0
    return Links(
        granule=np.concatenate([pairs[on_p, 0], wc[on_w, 0]]),
        partner=np.concatenate([pairs[on_p, 1], -1 - wc[on_w, 1]]),
        values=np.concatenate([pv[on_p], wv[on_w]]),
    )


def overlaps_at(model, y: np.ndarray, o: int, walls: WallMotion, history: History) -> None:
    """The overlaps of the contacts touching at output o taken into `history` (no forces)."""
    r = np.asarray(model.granular.radius, float)
    d = walls.normal.shape[1]
    cand = reaching(y, r)
    delta = r[cand[:, 0]] + r[cand[:, 1]] - np.linalg.norm(y[cand[:, 1], :d] - y[cand[:, 0], :d], axis=1)
    on = np.flatnonzero(delta > 0.0)
    on = on[in_touch(y, r, cand[on])]
    history.see(history.keys(cand[on, 0], cand[on, 1]), delta[on])
    wc = touching_walls(y, r, walls, o)
    i, w = wc[:, 0], wc[:, 1]
    delta = np.sum(y[i, :d] * walls.normal[w], axis=1) + r[i] - walls.offset[o, w]
    history.see(history.keys(i, -1 - w), delta)


def yields(model) -> bool:
    """Whether any contact of the run may follow a yielding law (its history matters): a
    law other than Hertz's between two of its granules' materials or a granule's and a wall's."""
    s = model.scenario
    names = sorted({m.name for m in model.materials})
    others = names + sorted({w.material for w in model.walls})
    return any(s.contact.law_for_pair(a, b) != "hertz" for a in names for b in others)


def contact_table(model, out, n: int, peaks, steps: int) -> tuple[dict[str, xr.DataArray], dict]:
    """The contact table's variables and its coordinate `link_table_time` over the first n
    output rows of `out` (solver.state.Output), every `steps` rows (run_checks.contact_steps;
    0: none, an empty dict each); peaks: the run's ContactPeaks (None: none known).

    A run whose contacts all follow Hertz's law (no history) is tabled in blocks of output
    times at once (`elastic_links`); a run with a yielding law time by time, each contact's
    largest overlap carried from the times before (`links_at`)."""
    t = np.asarray(out.t[:n], float)
    rows = table_rows(n, steps, t, model.scenario.time.t_end, model.scenario.time.output_interval)
    if not len(rows):
        return {}, {}
    walls = wall_motion(model, out, n)
    if not yields(model):
        return table_variables(*elastic_links(model, out, rows, walls), t[rows])
    history = History(peaks, model.n_granules, len(model.walls))
    wanted = set(rows.tolist())
    tables: list[Links] = []
    known: dict = {}
    for o in range(int(rows[-1]) + 1):
        y = np.ascontiguousarray(out.y[o], dtype=float)
        if o in wanted:
            links = links_at(model, y, o, walls, history, float(t[o]), known)
            tables.append(links)
            keys = history.keys(links.granule, links.partner)
            history.see(keys, links.values[:, OVERLAP])
        else:
            overlaps_at(model, y, o, walls, history)
    counts = np.array([len(x.granule) for x in tables], np.int64)
    joined = Links(*(np.concatenate([getattr(x, f) for x in tables]) for f in Links._fields))
    return table_variables(counts, joined, t[rows])


#: the most (output time, candidate contact) rows `elastic_links` treats at once
BLOCK_ROWS = 1_000_000


def block_candidates(ys: np.ndarray, r: np.ndarray) -> np.ndarray | None:
    """(nc, 2) sorted pairs i < j that may touch at any of the states ys (nb, ng, columns)
    (model.neighbours.reaching_pairs at the first state, its reach widened by twice the
    largest displacement D from it); None where D exceeds half the smallest radius (a block
    of fewer times is cheaper) or is not finite."""
    from granplate.model.neighbours import SEARCH_MARGIN, reaching_pairs

    d = of_state(ys.shape[2]).n
    p0 = ys[0, :, :d]
    disp = float(np.sqrt(np.max(np.sum((ys[:, :, :d] - p0) ** 2, axis=2)))) if len(ys) > 1 else 0.0
    r_min = float(r.min()) if len(r) else 0.0
    if not math.isfinite(disp) or (disp > 0.5 * r_min and len(ys) > 1):
        return None
    return reaching_pairs(p0, r, 1.0 + SEARCH_MARGIN + disp / r_min if disp > 0.0 else 1.0 + SEARCH_MARGIN)


def elastic_links(model, out, rows: np.ndarray, walls: WallMotion) -> tuple[np.ndarray, Links]:
    """The contacts in touch at the output rows `rows` of a run without contact history
    (every law Hertz's), with their forces, as `links_at` gives them time by time: the
    number of contacts at each row and the rows' contacts in time order (at each time the
    pairs, sorted, then the wall contacts). Output times are taken in blocks of at most
    BLOCK_ROWS candidate rows, over which no granule moves more than half the smallest
    radius: one candidate search per block, the kinematics and laws of all its rows in one
    compiled call each."""
    r = np.asarray(model.granular.radius, float)
    ng = len(r)
    parts: list[tuple[np.ndarray, Links, int]] = []
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
        parts.append(block_links(model, ys, rows[start : start + nb], cand, walls, known))
        start += nb
    counts = np.concatenate([np.bincount(p[0], minlength=p[2]) for p in parts]).astype(np.int64)
    joined = Links(*(np.concatenate([getattr(p[1], f) for p in parts]) for f in Links._fields))
    return counts, joined


def block_links(model, ys: np.ndarray, rows: np.ndarray, cand: np.ndarray, walls: WallMotion, known: dict):
    """(row of each contact in touch (index into rows), their Links, len(rows)) at the states
    ys (nb, ng, columns) of the output rows `rows`, from the candidate pairs `cand`: the
    states are laid end to end as nb * ng granules, so that the kinematics, the touch test
    and the laws run once over every (time, pair) and (time, wall) row."""
    from granplate.model.arrays import wall_arrays
    from granplate.model.contacts import centre_coordinates
    from granplate.model.neighbours import contacts_among

    s, mats, g, cfg = model.scenario, list(model.materials), model.granular, model.config
    nb, ng, c = ys.shape
    d = of_state(c).n
    r = np.asarray(g.radius, float)
    flat = ys.reshape(nb * ng, c)
    r_flat = np.tile(r, nb)
    base = (np.arange(nb, dtype=np.int64) * ng)[:, None]
    pairs = np.column_stack([(base + cand[:, 0]).ravel(), (base + cand[:, 1]).ravel()]).reshape(-1, 2)
    pair_kin, wall_kin = KINEMATICS[of_state(c).name]
    kin = np.zeros((len(pairs), 3))
    pair_kin(flat, r_flat, pairs, cfg.arm_shrink, kin)
    on = np.flatnonzero(kin[:, DELTA] > 0.0)
    x, yy, z = centre_coordinates(flat, d)
    on = on[contacts_among(pairs[on], x, yy, r_flat, 0.0, z)]
    pt, pi, pj = pairs[on, 0] // ng, pairs[on, 0] % ng, pairs[on, 1] % ng
    code, inverse = np.unique(pi * ng + pj, return_inverse=True)
    coef = cached_rows(s, mats, g, np.column_stack([code // ng, code % ng]), known)[inverse.ravel()]
    pv = np.zeros((len(on), 3))
    link_forces(np.ascontiguousarray(kin[on]), coef, np.zeros(len(on)), np.zeros(len(on)), cfg.clip, pv)
    # granules reaching each wall (overlap >= 0), as `touching_walls` at each time
    if len(walls.normal):
        reach = (flat[:, :d] @ walls.normal.T).reshape(nb, ng, -1) + r[None, :, None] - walls.offset[rows][:, None, :]
        wt, wi, ww = np.nonzero(reach >= 0.0)
    else:
        wt = wi = ww = np.zeros(0, np.int64)
    wkey, winv = np.unique(wi * len(walls.normal) + ww, return_inverse=True) if len(wi) else (np.zeros(0, np.int64), wi)
    nw = max(len(walls.normal), 1)
    _, wcoef = wall_arrays(s, mats, r, g.mass, np.column_stack([wkey // nw, wkey % nw]), model.walls)
    wcoef = wcoef[np.asarray(winv, np.int64).ravel()] if len(wi) else wcoef
    geo = np.column_stack([walls.normal[ww], walls.offset[rows[wt], ww]]) if len(wi) else np.zeros((0, d + 1))
    wkin = np.zeros((len(wi), 3))
    wall_kin(
        flat, r_flat, np.ascontiguousarray(wt * ng + wi), geo, walls.speed[rows[wt], ww].copy(), cfg.arm_shrink, wkin
    )
    wv = np.zeros((len(wi), 3))
    link_forces(wkin, wcoef, np.zeros(len(wi)), np.zeros(len(wi)), cfg.clip, wv)
    keep_p, keep_w = pv[:, OVERLAP] > 0.0, wv[:, OVERLAP] > 0.0
    t_all = np.concatenate([pt[keep_p], wt[keep_w]])
    kind = np.concatenate([np.zeros(int(keep_p.sum()), np.int64), np.ones(int(keep_w.sum()), np.int64)])
    gran = np.concatenate([pi[keep_p], wi[keep_w]])
    other = np.concatenate([pj[keep_p], ww[keep_w]])  # the partner granule, or the wall's index
    order = np.lexsort((other, gran, kind, t_all))
    partner = np.concatenate([pj[keep_p], -1 - ww[keep_w]])
    values = np.concatenate([pv[keep_p], wv[keep_w]])[order]
    return t_all[order], Links(granule=gran[order], partner=partner[order], values=values), nb


def cached_rows(s, mats, g, pairs: np.ndarray, known: dict) -> np.ndarray:
    """model.relists.cached_pair_coefficients of the distinct sorted pairs (n, 2)."""
    from granplate.model.arrays import cached_pair_coefficients

    return cached_pair_coefficients(s, mats, g, np.asarray(pairs, np.int64).reshape(-1, 2), known)


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
