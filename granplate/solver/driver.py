"""Run the compiled loop on a model: allocate the state once, call `loop.advance` in
chunks (each bounded by output times and by a step budget calibrated to a wall-time
target, so progress shows and a stop request is honoured within about a second, even
when the steps have collapsed), and return a plain record of the output buffers.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import signal
import threading
import time
import warnings
from contextlib import contextmanager
from typing import Callable, NamedTuple

import numpy as np

from granplate.model.arrays import Model, granular_with_contacts, granular_with_patch_contacts
from granplate.model.inputs import DR_REF, DR_S, HIST_MAX, HIST_RATE, HIST_TIME, no_history
from granplate.model.contacts import Missed, centre_coordinates, contact_lists, missed_contacts, wall_planes
from granplate.model.neighbours import verlet_pairs, verlet_walls
from granplate.physics.contact import plate_overlap
from granplate.solver import loop, snapshot, state as S
from granplate.solver.compiling import compile_calls, compile_seconds, describe_seconds, machine_slowdown
from granplate.plate.face import patch_weights
from granplate.solver.interface import set_face_weights
from granplate.solver.ladder import level_for
from granplate.solver.schemes import scheme
from granplate.setup.run_checks import restart_steps
from granplate.setup.sensor_checks import n_sensor_samples, sensor_granules, sensor_interval

#: wall-time target of one compiled chunk [s], and the step budget of the first one.
CHUNK_SECONDS = 0.15
FIRST_BUDGET = 64

log = logging.getLogger(__name__)
#: step attempts without the clock moving after which a run is stopped (every retry
#: goes one ladder level deeper, so a run that still advances never needs more)
STALL_ATTEMPTS = 2 * S.N_LEVELS
#: status of a run stopped by a signal (SIGINT, SIGTERM) or a stop request.
INTERRUPTED = -1
INTERRUPTED_STATUS = "interrupted by the user"


class ContactPeaks(NamedTuple):
    """Every contact that touched during a run, with its largest overlap (the elastic-
    plastic law's history, docs/model.md section 3.6; the largest Hertz peak pressure
    follows from it): those in the loop's lists at the end and those that left them."""

    granule: np.ndarray  # (n,) int64: the contact's granule
    partner: np.ndarray  # (n,) int64: granule j, wall -1 - w, or state.PARTNER_PLATE
    delta_max: np.ndarray  # (n,) [m]: the largest overlap
    time: np.ndarray  # (n,) [s]: when it was reached
    rate: np.ndarray | None = None  # (n,) [-]: the rate factor that fixed its yield strength (law "johnson"; 0: unset)


def contact_peaks(g, stores: tuple[dict, dict], body=None) -> ContactPeaks:
    """The ContactPeaks of the lists of g (pairs, walls, plate contacts), of the histories
    off the lists (stores: pairs by (i, j), walls by (i, wall)) and of each granule's
    contact on an elastic body in space (body: BodyArrays, partner PARTNER_PLATE)."""
    parts = [(g.pair_ij[:, 0], g.pair_ij[:, 1], g.pair_hist)]
    if body is not None:
        parts.append((np.arange(len(body.hist)), np.full(len(body.hist), S.PARTNER_PLATE), body.hist))
    parts.append((g.wall_i, -1 - g.wall_w, g.wall_hist))
    parts.append((g.pc_i, np.full(len(g.pc_i), S.PARTNER_PLATE), g.pc_hist))
    for store, sign in ((stores[0], 1), (stores[1], -1)):
        if store:
            k = np.array(list(store), np.int64).reshape(-1, 2)
            parts.append((k[:, 0], k[:, 1] if sign > 0 else -1 - k[:, 1], np.array(list(store.values()))))
    granule = np.concatenate([np.asarray(a, np.int64) for a, _, _ in parts])
    partner = np.concatenate([np.asarray(b, np.int64) for _, b, _ in parts])
    peak = np.concatenate([_column(h, len(a), HIST_MAX) for a, _, h in parts])
    when = np.concatenate([_column(h, len(a), HIST_TIME) for a, _, h in parts])
    rate = np.concatenate([_column(h, len(a), HIST_RATE) for a, _, h in parts])
    on = peak > 0.0
    return ContactPeaks(granule=granule[on], partner=partner[on], delta_max=peak[on], time=when[on], rate=rate[on])


def _column(h, n: int, c: int) -> np.ndarray:
    """Column c of n history rows h (none: an empty column)."""
    return np.asarray(h, float).reshape(n, -1)[:, c] if n else np.zeros(0)


class ContactChanges(NamedTuple):
    """How a run's contacts changed: the patch contacts on the plate's face (docs/model.md
    section 3.5), those of the granules touching the face between nodes at t = 0 (time 0)
    then those formed during the run, in the order they follow the model's rigid layers on
    the output's contact axis, and the contact lists' rebuilds."""

    granule: np.ndarray  # (n_formed,) int64: the granule of each patch contact formed
    time: np.ndarray  # (n_formed,) [s]: when it formed (its granule within contact.skin R of the face)
    y: np.ndarray  # (n_formed,) [m]: the height on the face where it formed (its granule's y then)
    n_rebuilds: int  # contact-list rebuilds (detection = "dynamic": a granule moved skin R_min / 2)
    peaks: ContactPeaks | None = None  # every contact's largest overlap


class RunRecord(NamedTuple):
    """What the loop leaves: the output buffers, how many rows are valid, the status
    code (state.OK, an error code, or INTERRUPTED), its message ("ok" or why the run
    stopped), the timings and counters (info), and how the contacts changed (contacts:
    the patch contacts formed, which extend the output's contact axis, and the list
    rebuilds)."""

    out: S.Output
    n_valid: int
    status: int
    message: str
    info: dict
    contacts: ContactChanges
    body: object = None  # the run's elastic body in space (model.inputs.BodyArrays, its last contact state) or None
    snapshot: dict | None = None  # the loop's state at the end (solver.snapshot.capture), for a restart
    earlier: tuple = ()  # its states at the earlier restart times (time.restart_interval), in time order


def output_times(t_end: float, dt_out: float) -> np.ndarray:
    """Output times 0, dt_out, 2 dt_out, ..., ending exactly at t_end [s]."""
    n = int(math.ceil(t_end / dt_out - 1e-9))
    t = np.arange(n + 1) * dt_out
    t[-1] = t_end
    return t


#: a sensor's sample time within this fraction of the sensor interval of an output time
#: is that output time (one step lands on both).
SNAP_RTOL = 1e-9


def sensor_times(t_first: float, t_end: float, interval: float, times: np.ndarray) -> np.ndarray:
    """The sensors' sample times k * interval in [t_first, t_end] [s] (docs/model.md
    section 3.15), each within SNAP_RTOL intervals of an output time (`times`) taken as
    that output time, so that the steps land on both at once."""
    k = np.arange(n_sensor_samples(t_end, interval))
    ts = k * interval
    j = np.clip(np.searchsorted(times, ts), 1, len(times) - 1) if len(times) > 1 else np.zeros(len(ts), int)
    for cand in (j - 1, j):
        near = np.abs(times[cand] - ts) <= SNAP_RTOL * interval
        ts = np.where(near, times[cand], ts)
    ts = np.unique(np.minimum(ts, t_end))  # (one step lands on each: none twice)
    return ts[ts >= t_first - SNAP_RTOL * interval]


def sensor_setup(model: Model, times: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(the sample times from the run's first output time on, each sensor's granule) of
    the model's [[sensors]], or (None, None) without sensors."""
    s = model.scenario
    if not s.sensors:
        return None, None
    ts = sensor_times(float(times[0]), float(model.config.t_end), sensor_interval(s), times)
    return ts, np.asarray(sensor_granules(s), np.int64)


def status_message(status: int, model: Model, st: S.State) -> str:
    """Why the run stopped, naming the quantities, the limits and what to change."""
    e = st.err
    cfg = model.config
    t = e[S.ERR_T]
    if status == INTERRUPTED:
        return f"{INTERRUPTED_STATUS} at t = {st.clock[S.T_NOW]:.6e} s."
    if status == S.ERR_NOCONV and int(e[S.ERR_ITER]) == 0:
        return (
            f"the time step cannot move the clock on at t = {t:.6e} s (step {e[S.ERR_H]:.3e} s, "
            f"time.dt_min = {cfg.dt_min:.3e} s): the step control has collapsed. Raise time.dt_min "
            f"or solver.error_tol."
        )
    if status == S.ERR_NOCONV:
        k = int(e[S.ERR_CONTACT])
        where = f"plate contact '{model.contact_labels[k]}'" if 0 <= k < len(model.contact_labels) else "the interface"
        return (
            f"the interface-force iteration cannot go on at t = {t:.6e} s: {where} has "
            f"|N| = {e[S.ERR_N]:.4g} N, slip rate {e[S.ERR_VT]:.4g} m/s, local-map modulus "
            f"|lambda| = {e[S.ERR_LAM]:.3g} (eq. 8) with step {e[S.ERR_H]:.3e} s after "
            f"{int(e[S.ERR_ITER])} iterations, and the step may not go below time.dt_min = "
            f"{cfg.dt_min:.3e} s. Lower solver.lambda_target, raise solver.max_iterations or "
            f"lower time.dt_min."
        )
    if status == S.ERR_ENERGY:
        return (
            f"energy balance broken at t = {t:.6e} s: residual (E_p + E_g + D - E_in)/E_in = "
            f"{e[S.ERR_RESID]:.3e} exceeds solver.energy_tol = {cfg.energy_tol:.1e} "
            f"(step {e[S.ERR_H]:.3e} s). Lower time.dt_max or solver.lambda_target."
        )
    if status in (S.ERR_OVERLAP, S.ERR_MISSED, S.ERR_PLATE_REACH, S.ERR_JUMP):
        return contact_message(status, model, st)
    if status == S.ERR_NAN:
        return f"the state became non-finite (NaN/inf) at t = {t:.6e} s (step {e[S.ERR_H]:.3e} s)."
    return f"output buffer exhausted at t = {t:.6e} s (internal error, status {status})."


def partner_name(model: Model, partner: int) -> str:
    """'granule X', 'wall w (x, y)' or 'the plate' from a partner code (state.PARTNER_PLATE)."""
    if partner == S.PARTNER_PLATE:
        return "the plate"
    if partner < 0:
        w = -1 - partner
        return f"wall {w} (normal {tuple(model.scenario.walls[w].normal)}, offset {model.scenario.walls[w].offset:g} m)"
    return f"granule '{model.labels[partner]}'"


def contact_message(status: int, model: Model, st: S.State) -> str:
    """Why the contact watch stopped the run (solver/contacts.py, model/contacts.py)."""
    e = st.err
    c = model.scenario.contact
    cfg = model.config
    t = e[S.ERR_T]
    i = int(e[S.ERR_CONTACT])
    who = f"granule '{model.labels[i]}'"
    other = partner_name(model, int(e[S.ERR_ITER]))
    where = "(at " + ", ".join(f"{name} = {v:.6g} m" for name, v in zip("xyz", st.y[i, : cfg.dimension])) + ")"
    if status == S.ERR_OVERLAP:
        return (
            f"{who} {where} and {other} overlap by {e[S.ERR_N]:.4g} m at t = {t:.6e} s, "
            f"{e[S.ERR_RESID]:.3g} of the smaller radius, beyond contact.overlap_stop = "
            f"{c.overlap_stop:g}: Hertz's law assumes small overlaps. Lower the load or "
            f"time.dt_max, or stiffen the contact."
        )
    if status == S.ERR_MISSED:
        how = (
            'it is not one of the fixed contacts (contact.detection = "fixed"); use detection = "dynamic"'
            if c.detection == "fixed"
            else "the contact formed unseen within one step: lower time.dt_max or raise contact.skin"
        )
        return (
            f"{who} {where} and {other} interpenetrate by {e[S.ERR_N]:.4g} m at t = {t:.6e} s "
            f"and no contact accounts for it: {how}."
        )
    if status == S.ERR_PLATE_REACH:
        if cfg.face_skin > 0.0:
            why = (
                "it came from farther than contact.skin R within one step, so its patch contact "
                "formed unseen: lower time.dt_max or raise contact.skin"
            )
        elif c.detection == "fixed":
            why = (
                f'with contact.detection = "fixed" plate contacts are those at t = 0 (within '
                f'contact.neighbour_gap = {c.neighbour_gap:g} R of the plate); use detection = "dynamic"'
            )
        else:
            why = (
                "contacts forming on the plate's face need every mode or the truncated basis' "
                'static correction; use plate.n_modes = 0 (with plate.modes = "all"), or '
                'plate.modes = "truncated" (a dense basis cut to plate.n_modes keeps plate '
                "contacts to those at t = 0)"
            )
        return (
            f"{who} {where} reached the plate's face at t = {t:.6e} s (overlap "
            f"{e[S.ERR_N]:.4g} m) but has no plate contact: {why}."
        )
    return (
        f"{who} {where} moved {e[S.ERR_N]:.4g} m ({e[S.ERR_RESID]:.3g} radii) in one step at "
        f"t = {t:.6e} s: contacts may have been passed through. Lower time.dt_max."
    )


def overlap_warnings(model: Model, w: S.Work) -> list[str]:
    """One line per granule whose largest contact overlap exceeded contact.overlap_warn
    (of the smaller radius), with that contact's partner: Hertz's law assumes small overlaps."""
    lim = model.scenario.contact.overlap_warn
    out = []
    seen = set()
    for i in np.flatnonzero(w.ovl > lim):
        j = int(w.ovl_with[i])
        key = (min(i, j), max(i, j)) if j >= 0 else (int(i), j)
        if key in seen:
            continue
        seen.add(key)
        out.append(
            f"granule '{model.labels[i]}' and {partner_name(model, j)}: overlap "
            f"{w.ovl[i]:.3g} of the smaller radius (contact.overlap_warn = {lim:g})"
        )
    return out


def wall_offsets_now(g, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """The walls' offsets [m] with each driven wall moved as far as the last force pass
    put it (its displacement along its direction, projected on its normal)."""
    out = offsets.copy()
    for w, k in enumerate(g.wall_drive):
        if k >= 0:
            out[w] += g.drive_now[k, DR_S] * float(normals[w] @ g.drive_dir[k])
    return out


class ContactLists:
    """The loop's contact lists during a run: rebuilt (detection = "dynamic") or checked
    (fixed) from the granules' positions, between compiled chunks (model/contacts.py),
    and how they changed (`changes`)."""

    def __init__(self, model: Model):
        self.model = model
        g = model.granular
        # this run's own histories (the loop updates them in place)
        self.g = g._replace(
            pair_hist=no_history(len(g.pair_ij)),
            wall_hist=no_history(len(g.wall_i)),
            pc_hist=no_history(len(g.pc_i)),
            drive_now=g.drive_now.copy(),
            wall_load=g.wall_load.copy(),
        )
        self.known: dict = {}
        self.stores: tuple[dict, dict] = ({}, {})  # histories of the pairs and wall contacts off the lists
        self.planes = wall_planes(model.walls, model.config.dimension)
        self.n_rebuilds = 0  # rebuilds the loop asked for (REBUILD, dynamic detection)
        self.formed: list[tuple[int, float, float]] = []  # patch contacts: (granule, t [s], y [m])

    def changes(self, body=None) -> ContactChanges:
        """The patch contacts formed so far and the rebuilds, as a ContactChanges (with the
        contacts on an elastic body in space, model.inputs.BodyArrays, among the peaks)."""
        i, t, y = zip(*self.formed) if self.formed else ((), (), ())
        return ContactChanges(
            granule=np.array(i, np.int64),
            time=np.array(t, float),
            y=np.array(y, float),
            n_rebuilds=self.n_rebuilds,
            peaks=contact_peaks(self.g, self.stores, body),
        )

    def refresh(self, y: np.ndarray) -> Missed | None:
        """Rebuild (dynamic) or check (fixed) the lists at positions y[:, :2]; returns the
        worst overlap no contact of the current list accounts for, or None."""
        m, g = self.model, self.g
        x, yy, z = centre_coordinates(y, m.config.dimension)
        r = g.radius
        c = m.scenario.contact
        fixed = c.detection == "fixed"
        normals, offsets = self.planes
        walls = m.walls
        if len(g.wall_drive):  # driven walls where they are now (docs/model.md section 3.11)
            offsets = wall_offsets_now(g, normals, offsets)
            walls = tuple(dataclasses.replace(wall, offset=float(o)) for wall, o in zip(walls, offsets))
            g.drive_now[:, DR_REF] = g.drive_now[:, DR_S]
        if fixed:
            cand_p, cand_w = verlet_pairs(x, yy, r, 0.0, z), verlet_walls(x, yy, r, normals, offsets, 0.0, z)
        else:
            cand_p, cand_w = contact_lists(c, walls, x, yy, r, z)
        cur_w = np.column_stack([g.wall_i, g.wall_w]).astype(np.int64)
        missed = missed_contacts(g.pair_ij, cur_w, cand_p, cand_w, normals, offsets, x, yy, r, z)
        if not fixed:
            self.g = granular_with_contacts(m, g, cand_p, cand_w, self.known, self.stores)
        return missed[0] if missed else None


class LoopArrays:
    """The arrays one run advances, replaced as a whole when a patch contact is added
    (their contact dimension grows): the plate's modal arrays (p: its contact rows are
    this run's own), the state, the shared and the scheme's scratch and the outputs."""

    def __init__(self, model: Model, times: np.ndarray, nk: int):
        g, p, cfg = model.granular, model.plate_arrays, model.config
        ng, nm = model.n_granules, len(p.omega2)
        nc = S.STATE_COLUMNS[cfg.dimension]
        self.p = p._replace(phi_d=p.phi_d.copy(), resid=p.resid.copy()) if cfg.face_skin > 0.0 else p
        self.st = S.new_state(ng, nm, nk, nc)
        self.w = S.new_work(ng, nm, nk, len(p.face_y), nc)
        if cfg.face_skin > 0.0 and p.resid_face.shape[0] > 0:  # the rigid layers' face weights: their node
            for k, y_k in enumerate(model.plate.contact_y[:nk]):
                first, last = patch_weights(p.face_y, float(y_k), 0.0, self.w.wface)
                set_face_weights(k, first, last, self.w)
        self.sw = scheme(cfg.scheme).new_scratch(ng, nm, nk, body=model.body, threads=cfg.threads)
        ts, gs = sensor_setup(model, times)
        self.out = S.new_output(times, ng, nm, nk, nc, len(g.wall_load), len(g.drive_target), ts, gs)
        self.scheme = cfg.scheme
        self.sw_threads = cfg.threads

    def grow(self, nk_new: int) -> None:
        """Room for nk_new plate contacts: every array reallocated with the old values
        kept (contacts keep their indices; the new ones start at zero) and the per-level
        matrices marked stale."""
        st, w = self.st, self.w
        ng, nm = st.y.shape[0], st.q.shape[0]
        nc = st.y.shape[1]
        self.st = _copied(st, S.new_state(ng, nm, nk_new, nc))
        self.w = _copied(w, S.new_work(ng, nm, nk_new, len(w.wface), nc))
        self.sw = _copied(self.sw, scheme(self.scheme).new_scratch(ng, nm, nk_new, threads=self.sw_threads))
        self.out = _copied(
            self.out,
            S.new_output(
                self.out.target,
                ng,
                nm,
                nk_new,
                nc,
                self.out.wall_force.shape[1],
                self.out.drive.shape[1],
                self.out.sensor_target,
                self.out.sensor_granule,
            ),
        )
        phi_d = np.zeros((2 * nk_new, nm))
        phi_d[: self.p.phi_d.shape[0]] = self.p.phi_d
        self.p = self.p._replace(phi_d=phi_d)
        if self.p.resid_face.shape[0] > 0:  # a truncated basis: the new contacts' static rows start at zero
            resid = np.zeros((2 * nk_new, 2 * nk_new))
            n = self.p.resid.shape[0]
            resid[:n, :n] = self.p.resid
            self.p = self.p._replace(resid=resid)
        self.w.g_ok[:] = 0
        self.st.clock[S.CUSTOM_H] = -1.0


def _copied(old: tuple, new: tuple) -> tuple:
    """`new` (a named tuple of arrays) with each array's leading block taken from `old`'s."""
    for a, b in zip(old, new):
        b[tuple(slice(0, min(m, n)) for m, n in zip(a.shape, b.shape))] = a[
            tuple(slice(0, min(m, n)) for m, n in zip(a.shape, b.shape))
        ]
    return new


def near_face(model: Model, y: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Granules without a plate contact (free != 0) whose centre lies within the plate's
    height and whose surface is within contact.skin R of its undeformed face (docs/model.md
    section 3.5), ascending."""
    cfg, r = model.config, model.granular.radius
    inside = (cfg.plate_ylo < y[:, 1]) & (y[:, 1] < cfg.plate_yhi) & (free != 0)
    near = plate_overlap(y[:, 0], r * (1.0 + cfg.face_skin), cfg.plate_x0) > 0.0
    return np.flatnonzero(inside & near).astype(np.int64)


def add_patch_contacts(model: Model, lists: "ContactLists", arr: LoopArrays) -> int:
    """Give every granule near the face without a plate contact a patch contact
    centred at its height (docs/model.md section 3.5); returns how many were added."""
    return attach_patches(model, lists, arr, near_face(model, arr.st.y, arr.w.plate_free))


def attach_patches(model: Model, lists: "ContactLists", arr: LoopArrays, new: np.ndarray) -> int:
    """Give each granule of `new` (ascending) a patch contact centred at its height: the
    one path of every patch contact, those formed during the run (NEW_PLATE) and those of
    the granules touching the face between nodes at t = 0 (before the first step); returns
    how many were added."""
    new = np.asarray(new, np.int64)
    if len(new) == 0:
        return 0
    nk = len(lists.g.pc_i)
    lists.g = granular_with_patch_contacts(model, lists.g, new)
    arr.grow(nk + len(new))
    for k, i in enumerate(new, start=nk):
        loop.place_contact(arr.sw, k, float(arr.st.y[i, 1]), arr.st, arr.p, model.config, arr.w)
        lists.formed.append((int(i), float(arr.st.clock[S.T_NOW]), float(arr.st.y[i, 1])))
        arr.st.slip[k] = arr.st.y[i, 4] + model.granular.radius[i] * arr.st.y[i, 5] - arr.st.v[2 * k + 1]
    arr.w.plate_free[new] = 0
    return len(new)


@contextmanager
def stop_on_signals():
    """Yield a function telling whether SIGINT or SIGTERM arrived meanwhile; the
    previous handlers are restored afterwards. Outside the main thread no handler is
    installed (signals cannot be caught there) and the function always says no."""
    flag = {"stop": False}
    if threading.current_thread() is not threading.main_thread():
        yield lambda: False
        return

    def handler(signum, frame):
        flag["stop"] = True

    old = {sig: signal.signal(sig, handler) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield lambda: flag["stop"]
    finally:
        for sig, h in old.items():
            signal.signal(sig, h)


def next_budget(budget: int, attempts: int, seconds: float) -> int:
    """Step budget of the next chunk so that it lasts about CHUNK_SECONDS."""
    if seconds <= 0.0 or attempts <= 0:
        return min(budget * 2, 1 << 24)
    per = seconds / attempts
    return int(min(max(CHUNK_SECONDS / per, 1), 1 << 24))


def set_reference(w: S.Work, st: S.State, dimension: int) -> None:
    """Keep the granules' centres (their first `dimension` state columns) as the contact
    list's reference (the contact watch measures how far each has moved since)."""
    w.yref[:, :dimension] = st.y[:, :dimension]


def _refresh(lists: ContactLists, st: S.State, w: S.Work) -> int:
    """Rebuild or check the contact lists at the current state: OK or ERR_MISSED (st.err filled)."""
    miss = lists.refresh(st.y)
    set_reference(w, st, lists.model.config.dimension)
    if miss is None:
        return S.OK
    st.err[S.ERR_T] = st.clock[S.T_NOW]
    st.err[S.ERR_CONTACT] = miss.i
    st.err[S.ERR_ITER] = miss.partner
    st.err[S.ERR_N] = miss.overlap
    return S.ERR_MISSED


#: A run whose step RK4's stability on the granule friction cuts (solver.granular_friction
#: = "rk4") on more than FRICTION_BOUND_SHARE of FRICTION_BOUND_MIN_STEPS or more steps
#: is told how to lift that bound.
FRICTION_BOUND_SHARE = 0.5
FRICTION_BOUND_MIN_STEPS = 5000
FRICTION_BOUND_HINT = (
    "{name}: friction at granule contacts, integrated inside RK4 (solver.granular_friction = "
    '"rk4", the presets\' setting), sets the step on most steps so far (t = {t:.4g} s): the run '
    'is slow for stability, not accuracy. solver.granular_friction = "split" integrates that '
    "friction exactly at any step, but its splitting error is outside the step control: check a "
    "result against a run with solver.implicit_dt_max halved (docs/model.md section 6.4)."
)


def friction_bound(count: np.ndarray) -> bool:
    """Whether granule friction inside RK4 has set most steps of a long enough run."""
    steps = int(count[S.C_STEPS])
    return steps >= FRICTION_BOUND_MIN_STEPS and count[S.C_FRICTION_BOUND] > FRICTION_BOUND_SHARE * steps


def stalled(st: S.State) -> int:
    """ERR_NOCONV for a run whose clock no longer moves (st.err filled: time, last step)."""
    st.err[:] = 0.0
    st.err[S.ERR_T] = st.clock[S.T_NOW]
    st.err[S.ERR_H] = st.clock[S.H_LAST]
    st.err[S.ERR_CONTACT] = -1.0
    return S.ERR_NOCONV


def restart_indices(n_times: int, first: int, every: int) -> np.ndarray:
    """The output rows (of n_times, the first being output time number `first` of the whole
    run) at which the loop's state is stored for a restart, every `every` output times
    (time.restart_interval; 0: none), the last row left out (its state is the run's end)."""
    if every <= 0:
        return np.zeros(0, np.int64)
    o = np.arange(1, n_times - 1, dtype=np.int64)
    return o[(first + o) % every == 0]


def chunk_stops(n_times: int, also: np.ndarray) -> np.ndarray:
    """The output rows the compiled chunks stop at: up to 200 spread over the run, and
    every row of `also` (where the loop's state is captured)."""
    n_chunks = min(200, n_times - 1)
    spread = np.linspace(1, n_times - 1, n_chunks).round().astype(np.int64) if n_chunks else np.zeros(0, np.int64)
    return np.union1d(spread, also).astype(np.int64)


def _loop_chunks(times, model, arr: LoopArrays, should_stop, on_progress, lists, captures=None, first=0) -> int:
    """Call the compiled loop chunk by chunk until the end, an error or a stop request;
    between chunks the contact lists are rebuilt when the loop asks (REBUILD), patch
    contacts added (NEW_PLATE) and, with fixed contacts, the lists checked after every
    chunk. captures: a list to which the loop's state (solver.snapshot.capture) is
    appended at every output time of `restart_indices` (times[0] being the run's output
    time number `first`)."""
    cfg = model.config
    fixed = model.scenario.contact.detection == "fixed"
    keep = restart_indices(len(times), first, restart_steps(model.scenario.time)) if captures is not None else []
    stops = chunk_stops(len(times), np.asarray(keep, np.int64))
    budget = FIRST_BUDGET
    warned = False
    idle = 0  # step attempts since the clock last moved
    for o_stop in stops:
        status = S.PAUSED
        while status == S.PAUSED:
            if should_stop():
                return INTERRUPTED
            st = arr.st
            before = st.count[S.C_OUT]
            n0 = st.count[S.C_STEPS] + st.count[S.C_RETRIES]
            t_before = st.clock[S.T_NOW]
            t0 = time.perf_counter()
            status = loop.advance(float(times[o_stop]), budget, lists.g, arr.p, cfg, st, arr.w, arr.sw, arr.out)
            attempts = int(st.count[S.C_STEPS] + st.count[S.C_RETRIES] - n0)
            budget = next_budget(budget, attempts, time.perf_counter() - t0)
            idle = idle + max(attempts, 1) if st.clock[S.T_NOW] <= t_before else 0
            if status == S.PAUSED and idle > STALL_ATTEMPTS:
                return stalled(st)
            on_progress(int(st.count[S.C_OUT] - before))
            if not warned and friction_bound(st.count):
                warned = True
                warnings.warn(
                    FRICTION_BOUND_HINT.format(name=model.scenario.name, t=st.clock[S.T_NOW]),
                    RuntimeWarning,
                    stacklevel=4,
                )
            if status in (S.REBUILD, S.NEW_PLATE) and cfg.face_skin > 0.0:
                add_patch_contacts(model, lists, arr)
            if status == S.REBUILD and not fixed:
                lists.n_rebuilds += 1
            if status == S.REBUILD or (fixed and status in (S.OK, S.PAUSED)):
                checked = _refresh(lists, arr.st, arr.w)
                if checked != S.OK:
                    return checked
            if status in (S.REBUILD, S.NEW_PLATE):
                status = S.PAUSED
        if status != S.OK:
            return status
        if o_stop in keep:
            captures.append(snapshot.capture(arr, lists))
    return _refresh(lists, arr.st, arr.w)


def type_fingerprint(a) -> tuple | type:
    """What numba's type of the argument `a` depends on, cheaply: a tuple's class and its
    members', an array's dtype, dimensions, layout and flags, else the Python type."""
    if isinstance(a, np.ndarray):
        f = a.flags
        return (np.ndarray, a.dtype.str, a.ndim, f.c_contiguous, f.f_contiguous, f.writeable, f.aligned)
    if isinstance(a, tuple):
        return (type(a), *(type_fingerprint(v) for v in a))
    return type(a)


#: (dispatcher id, argument fingerprints) already found compiled in this process.
_KNOWN_COMPILED: set[tuple] = set()


def is_compiled(dispatcher, args: tuple) -> bool:
    """Whether numba holds `dispatcher` compiled for these arguments' types, in memory or
    in its on-disk cache (an entry for this source and signature in the cache's index);
    True when numba's cache cannot be asked (then nothing is said about compiling). An
    answer True is kept for the arguments' fingerprint (typing them costs milliseconds)."""
    known = (id(dispatcher), tuple(type_fingerprint(a) for a in args))
    if known in _KNOWN_COMPILED:
        return True
    try:
        sig = tuple(dispatcher.typeof_pyval(a) for a in args)
        if sig in dispatcher.overloads:
            _KNOWN_COMPILED.add(known)
            return True
        cache = dispatcher._cache
        found = cache._index_key(sig, dispatcher.targetctx.codegen()) in cache._cache_file._load_index()
    except Exception:  # noqa: BLE001 - numba's cache internals: an unknown layout says nothing
        return True
    if found:
        _KNOWN_COMPILED.add(known)
    return found


def note_compile(model: Model, calls: list[tuple]) -> bool:
    """Log (INFO) that the time loop is about to be compiled, with the measured estimate,
    when any of `calls` ((dispatcher, args)) is not compiled yet; True when it is not."""
    if all(is_compiled(f, args) for f, args in calls):
        return False
    name, dim = model.scenario.solver.scheme, model.config.dimension
    where = "in space" if dim == 3 else "in the plane"
    seconds, slow = compile_seconds(name, dim), machine_slowdown()
    busy = f"; this machine is busy, {slow:.1f}x" if slow > 1.2 else ""
    log.info(
        f"compiling the time loop of the {name} scheme {where} (about {describe_seconds(slow * seconds)}: "
        f"{describe_seconds(seconds)} of CPU measured on a cold cache{busy}; cached afterwards) ..."
    )
    return True


def progress_bar(total: int, desc: str, file=None):
    """The run's progress bar over its output times, started once the loop is compiled:
    until the first output it shows no rate and no time left ("?"), never an estimate
    made from the compile time."""
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="out", leave=False, file=file)


def run(
    model: Model,
    *,
    progress: bool = False,
    should_stop: Callable[[], bool] | None = None,
    interruptible: bool = True,
    start: dict | None = None,
) -> RunRecord:
    """Run the time loop of `model` to its t_end.

    progress: a bar on stderr; should_stop: polled between chunks (a stop request);
    interruptible: SIGINT/SIGTERM stop the run between chunks (main thread only);
    start: a restart (solver.snapshot.capture of a run of the same model ended at one of
    this run's output times t1): the loop goes on from there, its outputs from t1 on.
    """
    if start is not None:
        return _run_from(model, start, progress, should_stop, interruptible)
    g, cfg = model.granular, model.config
    times = output_times(cfg.t_end, cfg.out_dt)
    arr = LoopArrays(model, times, len(model.plate_contacts))
    st, w = arr.st, arr.w
    st.y[:] = model.initial_state
    if model.plate_q0 is not None:  # a precompressed plate starts deflected, at rest
        st.q[:] = model.plate_q0
        st.u[:] = model.plate_u0
    set_reference(w, st, cfg.dimension)
    w.plate_free[:] = 1
    w.plate_free[model.plate_contacts] = 0
    lists = ContactLists(model)
    if cfg.face_skin > 0.0:  # this run's own (patch contacts move their face)
        lists.g = lists.g._replace(pc_x=g.pc_x.copy())
        attach_patches(model, lists, arr, model.initial_patches)  # touching between nodes at t = 0
        st, w = arr.st, arr.w  # grown
    st.count[S.C_LEVEL] = level_for(model.scenario.time.dt_initial, cfg)
    calls = [
        (loop.initialise, (st, lists.g, arr.p, cfg, w)),
        (loop.start_scheme, (arr.sw, st, lists.g, cfg)),
        (loop.record, (0, st, lists.g, arr.p, w, arr.out)),
        *sensor_calls(arr.sw, st, lists.g, cfg, arr.out),
        (loop.advance, (float(times[-1]), FIRST_BUDGET, lists.g, arr.p, cfg, st, arr.w, arr.sw, arr.out)),
    ]
    t1 = time.perf_counter()
    note_compile(model, calls)
    compile_calls(calls)  # before the bar and the loop's clock: neither counts the compile
    loop.initialise(st, lists.g, arr.p, cfg, w)
    loop.start_scheme(arr.sw, st, lists.g, cfg)
    loop.record(0, st, lists.g, arr.p, w, arr.out)
    first_sensor_sample(model, arr.sw, st, lists.g, arr.out)
    st.count[S.C_OUT] = 1
    return _finish(model, times, arr, lists, t1, progress, should_stop, interruptible)


def sensor_calls(sw, st: S.State, g, cfg, out: S.Output) -> list[tuple]:
    """The compiled call a run with sensors makes from Python (its first sample), to
    compile before the loop's clock starts; none without sensors."""
    return [(loop.record_sensors, (sw, st, g, cfg, out))] if len(out.sensor_granule) else []


def first_sensor_sample(model: Model, sw, st: S.State, g, out: S.Output) -> None:
    """The sensors' sample at the run's first output time, when it is a sample time (to
    SNAP_RTOL intervals: a restart's clock is the first run's end, to its rounding)."""
    if not len(out.sensor_target):
        return
    if out.sensor_target[0] <= st.clock[S.T_NOW] + SNAP_RTOL * sensor_interval(model.scenario):
        loop.record_sensors(sw, st, g, model.config, out)


def _run_from(model: Model, start: dict, progress: bool, should_stop, interruptible: bool) -> RunRecord:
    """`run` from a captured state at an output time t1 (its clock): the outputs are the
    output times from t1 on, the first one the captured state itself."""
    cfg = model.config
    all_times = output_times(cfg.t_end, cfg.out_dt)
    t1 = float(start["st.clock"][S.T_NOW])
    o1 = int(np.argmin(np.abs(all_times - t1)))
    times = all_times[o1:]
    arr = LoopArrays(model, times, len(start["st.normal"]))
    lists = ContactLists(model)
    snapshot.restore(start, arr, lists)
    st = arr.st
    calls = [
        (loop.record, (0, st, lists.g, arr.p, arr.w, arr.out)),
        *sensor_calls(arr.sw, st, lists.g, cfg, arr.out),
        (loop.advance, (float(times[-1]), FIRST_BUDGET, lists.g, arr.p, cfg, st, arr.w, arr.sw, arr.out)),
    ]
    c1 = time.perf_counter()
    note_compile(model, calls)
    compile_calls(calls)
    loop.record(0, st, lists.g, arr.p, arr.w, arr.out)
    first_sensor_sample(model, arr.sw, st, lists.g, arr.out)
    st.count[S.C_OUT] = 1
    return _finish(model, times, arr, lists, c1, progress, should_stop, interruptible, first=o1)


def _finish(
    model: Model, times, arr: LoopArrays, lists: ContactLists, t1: float, progress, should_stop, interruptible, first=0
):
    """The loop from the first output on (its first call timed from t1 [perf_counter s];
    times[0] is the run's output time number `first`), and the run's record."""
    t_first = time.perf_counter() - t1  # includes compiling / loading the loop
    bar = None
    if progress:
        bar = progress_bar(len(times) - 1, model.scenario.name)
    polls = [should_stop] if should_stop is not None else []
    earlier: list[dict] = []
    t2 = time.perf_counter()
    c2, c3 = time.process_time(), time.thread_time()
    try:
        with stop_on_signals() if interruptible else _never() as signalled, numba_threads(model.config.threads):
            status = _loop_chunks(
                times,
                model,
                arr,
                lambda: signalled() or any(f() for f in polls),
                bar.update if bar is not None else (lambda n: None),
                lists,
                earlier,
                first,
            )
    finally:
        if bar is not None:
            bar.close()
    st, w = arr.st, arr.w
    info = {
        "first_call_time_s": t_first,
        "loop_time_s": time.perf_counter() - t2,
        "loop_cpu_s": time.process_time() - c2,
        "loop_thread_cpu_s": time.thread_time() - c3,
        "n_steps": int(st.count[S.C_STEPS]),
        "threads": int(model.config.threads),
        "n_iterations": int(st.count[S.C_ITERS]),
        "n_retries": int(st.count[S.C_RETRIES]),
        "n_friction_bound": int(st.count[S.C_FRICTION_BOUND]),
        "overlap_warnings": overlap_warnings(model, w),
    }
    message = "ok" if status == S.OK else status_message(status, model, st)
    body = getattr(arr.sw, "body", None) if model.body is not None else None
    for line in info["overlap_warnings"]:
        warnings.warn(
            f"{model.scenario.name}: {line}: Hertz's law assumes overlaps small against the radii.",
            RuntimeWarning,
            stacklevel=2,
        )
    return RunRecord(
        out=arr.out,
        n_valid=int(st.count[S.C_OUT]),
        status=status,
        message=message,
        info=info,
        contacts=lists.changes(body),
        body=body,
        snapshot=snapshot.capture(arr, lists) if status == S.OK else None,
        earlier=tuple(earlier),
    )


@contextmanager
def numba_threads(n: int):
    """Numba's parallel loops on n threads inside the block (solver.blocks), the count
    before restored after it; 1: nothing changes (the serial loop starts no thread)."""
    if n <= 1:
        yield
        return
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(n)
    try:
        yield
    finally:
        numba.set_num_threads(before)


@contextmanager
def _never():
    yield lambda: False
