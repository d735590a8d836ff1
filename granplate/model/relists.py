"""The loop's contact lists replaced during a run (docs/model.md section 1.3): a rebuilt
list's coefficients (each pair's row computed once per run) and histories (each contact's
row carried over, or kept aside while it is off the list, so that its largest overlap holds
for the whole run), and patch contacts appended on the plate's face (section 3.5).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from granplate.model.coefficients import coefficient_kinds, pair_coefficients, plate_contact_coefficients, wall_arrays
from granplate.model.inputs import HIST_MAX, HIST_XI, Granular, no_history
from granplate.physics.contact import N_COEF
from granplate.setup.scenario import Scenario

if TYPE_CHECKING:  # pragma: no cover
    from granplate.model.arrays import Model


def carried_history(old_keys: np.ndarray, old_hist: np.ndarray, new_keys: np.ndarray, store: dict) -> np.ndarray:
    """The histories (columns HIST_*) of the contacts new_keys (n, 2) of a rebuilt list:
    each one's row from the old list (old_keys, old_hist) or from `store`, which holds the
    contacts that left the list with a history, keyed (i, j), and takes those leaving now.
    A contact keeps its largest overlap (and so its plastic flattening, docs/model.md
    section 3.6) for the whole run, whether or not the list holds it. Keys are matched by
    sorting (no per-contact Python): a rebuild of 10^6 contacts takes a fraction of a second."""
    new_keys = np.asarray(new_keys, np.int64).reshape(-1, 2)
    has = (old_hist[:, HIST_MAX] > 0.0) | np.any(old_hist[:, HIST_XI : HIST_XI + 3] != 0.0, axis=1)
    keys = np.asarray(old_keys, np.int64).reshape(-1, 2)[has]
    rows = old_hist[has]
    if store:
        keys = np.vstack([np.array(list(store), np.int64).reshape(-1, 2), keys])
        rows = np.vstack([np.array(list(store.values()), float).reshape(-1, old_hist.shape[1]), rows])
    out = no_history(len(new_keys), old_hist.shape[1])
    store.clear()
    if not len(keys):
        return out
    span = int(max(keys[:, 1].max(), new_keys[:, 1].max() if len(new_keys) else 0)) + 1
    code = keys[:, 0] * span + keys[:, 1]
    new_code = new_keys[:, 0] * span + new_keys[:, 1]
    order = np.argsort(new_code, kind="stable")
    pos = np.minimum(np.searchsorted(new_code[order], code), max(len(order) - 1, 0))
    found = (new_code[order[pos]] == code) if len(order) else np.zeros(len(code), bool)
    out[order[pos[found]]] = rows[found]  # the old list's row after the store's (it is the newer)
    store.update(zip(map(tuple, keys[~found].tolist()), rows[~found]))
    return out


def cached_pair_coefficients(s: Scenario, mats, g: Granular, pairs: np.ndarray, known: dict) -> np.ndarray:
    """`pair_coefficients` of the pairs (n, 2), each pair's row computed once per run:
    known["codes"] (sorted i * ng + j) and known["rows"] hold those met so far and take the
    new ones (the same numbers, bit for bit, as computing them again)."""
    ng = len(g.radius)
    code = pairs[:, 0] * ng + pairs[:, 1]
    kc = known.get("codes", np.zeros(0, np.int64))
    kr = known.get("rows", np.zeros((0, N_COEF)))
    pos = np.minimum(np.searchsorted(kc, code), max(len(kc) - 1, 0))
    hit = (kc[pos] == code) if len(kc) else np.zeros(len(code), bool)
    if hit.all():
        return np.take(kr, pos, axis=0)
    new = np.flatnonzero(~hit)
    rows = pair_coefficients(s, mats, g.radius, g.mass, pairs[new])
    if hit.any():
        out = np.empty((len(pairs), N_COEF))
        out[new] = rows
        out[hit] = np.take(kr, pos[hit], axis=0)
    else:
        out = rows
    new_code = code[new]
    if len(new_code) > 1 and not np.all(new_code[1:] >= new_code[:-1]):
        order = np.argsort(new_code, kind="stable")
        new_code, rows = new_code[order], rows[order]
    at = np.searchsorted(kc, new_code, side="right")  # (the rows merged in code order: copies of both)
    known["codes"], known["rows"] = np.insert(kc, at, new_code), np.insert(kr, at, rows, axis=0)
    return out


def with_pair_kinds(g: Granular) -> Granular:
    """`g` with its pairs' coefficient kinds (pair_kind, kind_coef: model.inputs.Granular)
    made from pair_coef (`coefficient_kinds`)."""
    kind, table = coefficient_kinds(g.pair_coef)
    return g._replace(pair_kind=kind, kind_coef=table)


def pair_kinds_stale(g: Granular) -> bool:
    """Whether g's pair kinds are not its pairs' (another count: a Granular made without
    them, or from a stored run's arrays)."""
    return g.pair_kind.shape[0] != g.pair_ij.shape[0] or (len(g.pair_ij) > 0 and not len(g.kind_coef))


def granular_with_contacts(
    model: Model,
    g: Granular,
    pairs: np.ndarray,
    wc: np.ndarray,
    known: dict | None = None,
    stores: tuple[dict, dict] | None = None,
) -> Granular:
    """`g` with the contact lists pairs (np, 2) and wc (nw, 2) [granule, wall], their
    coefficients and their histories carried over (`carried_history`; stores: the pairs'
    and the walls' histories off the list, keyed (i, j) and (i, wall), updated); known:
    the pairs' coefficient rows met so far (`cached_pair_coefficients`), reused and extended;
    their kinds made anew (`with_pair_kinds`)."""
    s, mats = model.scenario, list(model.materials)
    known = {} if known is None else known
    stores = ({}, {}) if stores is None else stores
    pairs = np.ascontiguousarray(pairs, np.int64).reshape(-1, 2)
    pair_coef = cached_pair_coefficients(s, mats, g, pairs, known)
    wall_geo, wall_coef = wall_arrays(s, mats, g.radius, g.mass, wc, model.walls)
    wc = np.asarray(wc, np.int64).reshape(-1, 2)
    return with_pair_kinds(
        g._replace(
            pair_ij=pairs,
            pair_coef=pair_coef,
            wall_i=np.ascontiguousarray(wc[:, 0]),
            wall_geo=wall_geo,
            wall_coef=wall_coef,
            wall_w=np.ascontiguousarray(wc[:, 1]),
            pair_hist=carried_history(g.pair_ij, g.pair_hist, pairs, stores[0]),
            wall_hist=carried_history(np.column_stack([g.wall_i, g.wall_w]), g.wall_hist, wc, stores[1]),
        )
    )


def granular_with_patch_contacts(model: Model, g: Granular, new: np.ndarray) -> Granular:
    """`g` with a patch contact appended for each granule of `new` (docs/model.md section
    3.5): the coefficients of a rigid layer (m* = 0), the overlap measured from the
    undeformed face, pc_patch = 1, and a fresh history."""
    new = np.asarray(new, np.int64).ravel()
    s, mats = model.scenario, list(model.materials)
    patch = g.pc_patch if len(g.pc_patch) == len(g.pc_i) else np.zeros(len(g.pc_i), np.int64)
    return g._replace(
        pc_i=np.concatenate([g.pc_i, new]).astype(np.int64),
        pc_x=np.concatenate([g.pc_x, np.full(len(new), float(s.plate.x0))]),
        pc_coef=np.ascontiguousarray(
            np.vstack([g.pc_coef.reshape(-1, N_COEF), plate_contact_coefficients(s, mats, g.radius, new)])
        ),
        pc_patch=np.concatenate([patch, np.ones(len(new), np.int64)]),
        pc_hist=np.vstack([g.pc_hist.reshape(-1, g.pc_hist.shape[1]), no_history(len(new), g.pc_hist.shape[1])]),
    )
