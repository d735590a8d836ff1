"""The loop's whole state at the end of a run, as named arrays, and a run started from it
(a restart, docs/how-to/restart.md).

`capture(arr, lists)`: every array a continued run needs, keyed by a path such as
"st.y" (the State), "w.ovl" (the shared scratch), "sw.split" (the scheme's scratch), "b.x"
(the elastic body in space's contact state; nothing in a run without one), "p.phi_d" (the plate's contact rows of this run;
its other modal arrays are the model's), "g.pair_hist" (the contact lists and each contact's history: largest overlap, rate
factor, friction state), "stores.pair_key" / "stores.pair_hist" (the histories of the
contacts off the lists). The elastic body's model arrays (faces, modes, residual
compliance) are the model's and are not stored; its contact state is. The per-level caches (G(h) and the modal coefficients per step
level) are left out: they are recomputed, to the same numbers, when a level is first used.
`restore(snap, arr, lists)`: the same arrays put back in place of a fresh run's.
"""

from __future__ import annotations

import numpy as np

from granplate.model.inputs import NoBodyArrays
from granplate.model.relists import with_pair_kinds
from granplate.solver.state import CUSTOM_H

#: per-level caches, recomputed on first use (their `ok` flags are cleared on restore), and
#: the pairs' coefficient kinds, made again from the stored pair_coef on restore
CACHES = frozenset({"w.dmode", "w.gmat", "sw.mcoef", "sw.mmat", "g.pair_kind", "g.kind_coef"})
#: the elastic body's model arrays (the same in every run of the model: not stored)
BODY_MODEL = (
    "face_nodes face_snode node_xyz node_area node_rows node_resid grid grid_origin grid_shape "
    "cell_start cell_nodes neighbours kind phi omega resid box coef load"
).split()
#: the threaded passes' block buffers (solver.blocks: rewritten by every force pass, and
#: sized by the thread count, which a restart may change)
BLOCKS = frozenset({"sw.fpar", "sw.spar"})
#: scratch rewritten before every use (the threaded contact watch's flags, sized by the
#: thread count), and the Verlet kicks' hints which rows are zero and measures for the
#: checks after a step (a restart starts without them: its kicks read every row, to the
#: same sums, and the checks measure for themselves)
SCRATCH = frozenset({"b.mrow", "sw.quiet", "sw.notes", "w.wflag"})
LEFT_OUT = CACHES | BLOCKS | SCRATCH | {f"b.{name}" for name in BODY_MODEL}
#: the prefix the elastic body's state had in snapshots written when the scheme's scratch
#: held it (read as "b.")
FORMER_BODY = "sw.body."


def _flat(prefix: str, tup, out: dict[str, np.ndarray]) -> None:
    for name, value in zip(tup._fields, tup):
        key = f"{prefix}.{name}"
        if isinstance(value, np.ndarray):
            if key not in LEFT_OUT:
                out[key] = value.copy()
        elif isinstance(value, tuple) and hasattr(value, "_fields"):
            _flat(key, value, out)


def _store_arrays(store: dict, n_hist: int) -> tuple[np.ndarray, np.ndarray]:
    keys = sorted(store)
    k = np.array(keys, np.int64).reshape(-1, 2)
    h = np.array([store[key] for key in keys], float).reshape(-1, n_hist)
    return k, h


def capture(arr, lists) -> dict[str, np.ndarray]:
    """The run's state now (module docstring), as arrays keyed by path."""
    out: dict[str, np.ndarray] = {}
    body = () if isinstance(arr.b, NoBodyArrays) else (("b", arr.b),)  # none: nothing of it to keep
    for prefix, tup in (("st", arr.st), ("w", arr.w), ("sw", arr.sw), *body, ("g", lists.g)):
        _flat(prefix, tup, out)
    out["p.phi_d"], out["p.resid"] = arr.p.phi_d.copy(), arr.p.resid.copy()  # the rest of p: the model's
    n_hist = lists.g.pair_hist.shape[1]
    for name, store in zip(("pair", "wall"), lists.stores):
        out[f"stores.{name}_key"], out[f"stores.{name}_hist"] = _store_arrays(store, n_hist)
    return out


def _padded(stored: np.ndarray, fresh) -> np.ndarray:
    """A stored table with fewer columns than this run's (a result written before a column
    was added: the drives' state and parameters) completed by the fresh run's columns; one
    with more, the extra ones all zero (history rows written when every run kept Mindlin's
    columns, model.inputs.history_columns), cut to this run's."""
    if not (
        isinstance(fresh, np.ndarray) and stored.ndim == 2 and fresh.ndim == 2 and stored.shape[0] == fresh.shape[0]
    ):
        return stored
    if stored.shape[1] < fresh.shape[1]:
        out = fresh.copy()
        out[:, : stored.shape[1]] = stored
        return out
    if stored.shape[1] > fresh.shape[1] and not np.any(stored[:, fresh.shape[1] :]):
        return np.ascontiguousarray(stored[:, : fresh.shape[1]])
    return stored


def _history_row(h, n_hist: int) -> np.ndarray:
    """A stored contact's history row as this run's n_hist columns: completed with zeros (a
    result written before a column was added: Mindlin's tangential history), or cut where
    the extra columns are zero (written when every run kept Mindlin's columns)."""
    h = np.asarray(h, float)
    if len(h) > n_hist and not np.any(h[n_hist:]):
        return h[:n_hist].copy()
    out = np.zeros(max(n_hist, len(h)))
    out[: len(h)] = h
    return out


def _rebuilt(prefix: str, tup, snap: dict[str, np.ndarray]):
    values = {}
    for name, value in zip(tup._fields, tup):
        key = f"{prefix}.{name}"
        if key in snap:
            values[name] = _padded(
                np.array(snap[key], dtype=value.dtype if isinstance(value, np.ndarray) else None), value
            )
        elif isinstance(value, tuple) and hasattr(value, "_fields"):
            values[name] = _rebuilt(key, value, snap)
    return tup._replace(**values)


def restore(snap: dict[str, np.ndarray], arr, lists) -> None:
    """Put the captured arrays in place of `arr`'s (a loop_arrays.LoopArrays) and `lists`'s
    (a run_contacts.ContactLists); the per-level caches start empty. A snapshot written
    when the scheme's scratch held the elastic body ("sw.body.x") is read the same."""
    snap = {"b." + k[len(FORMER_BODY) :] if k.startswith(FORMER_BODY) else k: v for k, v in snap.items()}
    arr.st = _rebuilt("st", arr.st, snap)
    arr.w = _rebuilt("w", arr.w, snap)
    arr.sw = _rebuilt("sw", arr.sw, snap)
    arr.b = _rebuilt("b", arr.b, snap)
    arr.p = _rebuilt("p", arr.p, snap)
    arr.w.g_ok[:] = 0
    arr.st.clock[CUSTOM_H] = -1.0  # the odd step's matrices too
    lists.g = with_pair_kinds(_rebuilt("g", lists.g, snap))  # (the kinds of the stored pairs)
    lists.stores = tuple(
        {
            (int(i), int(j)): _history_row(h, lists.g.pair_hist.shape[1])
            for (i, j), h in zip(snap[f"stores.{n}_key"], snap[f"stores.{n}_hist"])
        }
        for n in ("pair", "wall")
    )
