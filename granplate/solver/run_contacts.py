"""The loop's contact lists during a run, between compiled chunks: rebuilt (contact.detection
= "dynamic") or checked (fixed) from the granules' positions (model/contacts.py), the
histories of the contacts that left them, and how they changed (the patch contacts formed,
the rebuilds, every contact's largest overlap)."""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from granplate.model.arrays import Model, granular_with_contacts
from granplate.model.contacts import Missed, centre_coordinates, contact_lists, missed_contacts, wall_planes
from granplate.model.inputs import DR_REF, DR_S, HIST_MAX, HIST_RATE, HIST_TIME, no_history
from granplate.model.neighbours import verlet_pairs, verlet_walls
from granplate.model.relists import pair_kinds_stale, with_pair_kinds
from granplate.solver import state as S


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
        if pair_kinds_stale(g):  # (a Granular made without its pairs' kinds)
            g = with_pair_kinds(g)
        # this run's own histories (the loop updates them in place)
        self.g = g._replace(
            pair_hist=no_history(len(g.pair_ij), g.pair_hist.shape[1]),
            wall_hist=no_history(len(g.wall_i), g.wall_hist.shape[1]),
            pc_hist=no_history(len(g.pc_i), g.pc_hist.shape[1]),
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
