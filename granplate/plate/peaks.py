"""The plate's largest stresses over the output times, exactly, at a fraction of the cost.

At each output time the plate outputs three maxima over its Gauss points: the von Mises
stress (eq. 12), the disc-averaged von Mises stress (docs/model.md section 4.4) and
|eps_yy|. `block_maxima` computes them exactly for a block of times (one modal-to-nodal
matrix product, the sparse strain operator, then the stresses); every route computes
them in the same aligned blocks of BLOCK times (`block_starts`), so that a value is the
same bits whichever route computed it.

A run's largest value over all times (what `summary` reports) needs only the blocks
that can hold it. With c(t) the plate's coordinates at time t (the modal coordinates,
and the contact forces of a truncated basis), each Gauss point's von Mises stress is a
norm of a linear map of c (the stresses are linear in c, and sqrt(s^T P s) with P
positive definite is a norm of them), so the triangle inequality bounds it:

    vm_max(t) <= vm_max(r) + sum_i |c_i(t) - c_i(r)| m_i,   m_i = max_g vm_g(e_i),

for any time r (with vm_max(r) = 0, r "at rest", this is sum_i |c_i(t)| m_i); likewise
the disc averages (non-negative weights) and |eps_yy| (linear), each with its own unit
peaks m (`unit_peaks`: one pass over the unit coordinates, kept per plate). `peak_maxima`
evaluates the maxima at every 64th time (REFERENCE_STRIDES), bounds every other time from
its two nearest references, evaluates every 16th, then every 4th time inside the blocks
whose bound still exceeds the largest reference value (tighter bounds, a higher floor;
the sums of the bounds are compiled, `distance_peaks`), and evaluates
exactly only the blocks whose bound exceeds the largest value found so far (largest bound
first). The bounds carry a relative
margin (BOUND_MARGIN, far above the round-off of the products) so that a skipped block
provably holds no computed value above the maximum.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from granplate.jit import njit

from granplate.plate.stress import plane_stresses, von_mises_plane_stress

#: Output times per exact block (the same blocks on every route).
BLOCK = 32
#: The references' spacing [output times], coarse to fine: every 64th output time is
#: evaluated to bound the times between, then every 16th and 4th inside the blocks still open.
REFERENCE_STRIDES = (64, 16, 4)
#: Relative margin of the bounds [-]: covers the round-off of the products (about
#: n_modes x 1e-16 of the sum of absolute terms) many times over.
BOUND_MARGIN = 1e-9
#: Names of the three maxima, in the columns' order.
MAXIMA = ("max_von_mises", "max_von_mises_disc", "max_eps_yy")


def split_coordinates(plate, c: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(modal coordinates, contact forces or None) of the coordinates c (time, n_modes [+ 2
    n_contacts forces of a truncated basis])."""
    return c[:, : plate.n_modes], (c[:, plate.n_modes :] if c.shape[1] > plate.n_modes else None)


def block_maxima(plate, c: np.ndarray) -> np.ndarray:
    """(len(c), 3): the largest von Mises stress [Pa], disc-averaged von Mises stress [Pa]
    and |eps_yy| [-] over the plate's Gauss points at each row of c (see split_coordinates);
    the strains are computed once for all three."""
    if len(c) == 0:
        return np.zeros((0, 3))
    exx, eyy, gxy = plate.strains(*split_coordinates(plate, c))
    vm = von_mises_plane_stress(*plane_stresses(plate.D, exx, eyy, gxy))
    return np.stack(
        [vm.reshape(len(c), -1).max(axis=1), plate.max_disc_von_mises(vm), np.abs(eyy).reshape(len(c), -1).max(axis=1)],
        axis=1,
    )


def block_starts(n: int, block: int = BLOCK) -> np.ndarray:
    """First output index of each block of `block` times among n."""
    return np.arange(0, n, block)


def time_maxima(
    plate, c: np.ndarray, should_stop: Callable[[], bool] | None = None, on_block: Callable[[int], None] | None = None
) -> np.ndarray:
    """The three maxima (time, 3) at every output time (block by block). should_stop:
    polled after each block; when it says yes, the rows computed so far are returned
    (at least one block). on_block(n_rows): called after each block."""
    n = len(c)
    out = np.zeros((n, 3))
    for i in block_starts(n):
        rows = slice(i, min(i + BLOCK, n))
        out[rows] = block_maxima(plate, c[rows])
        if on_block is not None:
            on_block(rows.stop - rows.start)
        if should_stop is not None and rows.stop < n and should_stop():
            return out[: rows.stop]
    return out


#: The unit peaks last computed: (plate key, peaks) (a study's designs share one plate:
#: computed once per process).
_LAST_UNIT_PEAKS: list = []


def _unit_key(plate) -> tuple | None:
    """What identifies a plate's unit peaks: its stored arrays and the averaging discs
    (None for a plate built without the store: not kept)."""
    if not plate.arrays_key:
        return None
    return (plate.arrays_key, plate.disc_radius, plate.disc_op.shape, plate.disc_op.nnz)


def unit_peaks(plate, n_cols: int) -> np.ndarray:
    """(n_cols, 3): block_maxima of each unit coordinate e_i (i < n_cols): m_i of the
    bounds above [Pa per unit, Pa per unit, 1 per unit]. The columns of the modes and the
    rigid layers' forces are kept for the plate (the last one asked); a truncated basis'
    patch-contact columns (which depend on the run) are computed each time."""
    n_base = min(n_cols, plate.n_modes + plate.psi.shape[1])
    key = _unit_key(plate)
    if key is not None and _LAST_UNIT_PEAKS and _LAST_UNIT_PEAKS[0][0] == key:
        base = _LAST_UNIT_PEAKS[0][1][:n_base]
    else:
        n_all = plate.n_modes + plate.psi.shape[1]
        base = _unit_rows(plate, 0, n_all, n_cols=max(n_cols, n_all))
        if key is not None:
            _LAST_UNIT_PEAKS[:] = [(key, base)]
        base = base[:n_base]
    if n_cols == n_base:
        return base
    return np.concatenate([base, _unit_rows(plate, n_base, n_cols, n_cols)])


def _unit_rows(plate, first: int, stop: int, n_cols: int) -> np.ndarray:
    """block_maxima of the unit coordinates e_first .. e_(stop-1) in n_cols coordinates."""
    out = np.zeros((stop - first, 3))
    for i in range(first, stop, 4 * BLOCK):
        j = min(i + 4 * BLOCK, stop)
        e = np.zeros((j - i, n_cols))
        e[np.arange(j - i), np.arange(i, j)] = 1.0
        out[i - first : j - first] = block_maxima(plate, e)
    return out


@njit(entry=True, cache=True)
def distance_peaks(c: np.ndarray, m: np.ndarray, rows: np.ndarray, refs: np.ndarray) -> np.ndarray:
    """(len(rows), 3): sum_i |c[rows[k], i] - c[refs[k], i]| m[i] (m: (n, 3)) for each k (refs[k] < 0:
    from rest, sum_i |c[rows[k], i]| m[i]): how far each maximum can move between the two
    output times, the triangle inequality's term [Pa, Pa, -]."""
    out = np.zeros((len(rows), 3))
    for k in range(len(rows)):
        a = rows[k]
        b = refs[k]
        s0 = s1 = s2 = 0.0
        for i in range(c.shape[1]):
            d = abs(c[a, i] - c[b, i]) if b >= 0 else abs(c[a, i])
            s0 += d * m[i, 0]
            s1 += d * m[i, 1]
            s2 += d * m[i, 2]
        out[k, 0] = s0
        out[k, 1] = s1
        out[k, 2] = s2
    return out


def rest_bounds(c: np.ndarray, m: np.ndarray) -> np.ndarray:
    """(time, 3): the bounds from rest, |c| m, at every output time."""
    c = np.ascontiguousarray(c, dtype=float)
    rows = np.arange(len(c))
    return distance_peaks(c, np.ascontiguousarray(m, dtype=float), rows, np.full(len(c), -1))


def reference_bounds(
    c: np.ndarray, m: np.ndarray, rows: np.ndarray, ref: np.ndarray, ref_values: np.ndarray, rest: np.ndarray
) -> np.ndarray:
    """(len(rows), 3) upper bounds of the three maxima at the output indices rows, from the
    values ref_values (n_ref, 3) at the sorted output indices ref: the smaller of the
    bounds from the nearest reference before and after and of rest (the bound from rest,
    |c| m, at every output time), with the margin (which also covers the sums' round-off)."""
    best = rest[rows]
    pos = np.searchsorted(ref, rows)
    c = np.ascontiguousarray(c, dtype=float)
    m = np.ascontiguousarray(m, dtype=float)
    rows = np.asarray(rows, dtype=np.int64)
    for side in (np.clip(pos - 1, 0, len(ref) - 1), np.clip(pos, 0, len(ref) - 1)):
        r = ref[side]
        bound = ref_values[side] + distance_peaks(c, m, rows, np.asarray(r, dtype=np.int64)) + BOUND_MARGIN * rest[r]
        best = np.minimum(best, bound)
    return best * (1.0 + BOUND_MARGIN) + BOUND_MARGIN * rest[rows]


def peak_maxima(plate, c: np.ndarray, block: int = BLOCK, strides: tuple[int, ...] = REFERENCE_STRIDES) -> np.ndarray:
    """(time, 3): block_maxima at the blocks that can hold a maximum over the run, NaN
    at the others (their values provably do not exceed the maximum). The maxima over
    time (nanmax) equal those of time_maxima bit for bit.

    strides: the references' spacing in output times, coarse to fine: every strides[0]-th
    time first, then every finer stride inside the blocks still open (whose bound exceeds
    the largest reference value), each level tightening the bounds and raising the floor."""
    n = len(c)
    out = np.full((n, 3), np.nan)
    if n == 0:
        return out
    m = unit_peaks(plate, c.shape[1])
    rest = rest_bounds(c, m)  # bounds from rest, every output time
    starts = block_starts(n, block)
    stops = np.minimum(starts + block, n)
    known = np.zeros(n, dtype=bool)
    values = np.zeros((n, 3))
    upper = np.maximum.reduceat(rest * (1.0 + BOUND_MARGIN), starts, axis=0)  # (n_blocks, 3)
    open_blocks = np.arange(len(starts))
    floor = np.full(3, -np.inf)  # below the exact maximum: the largest reference value, less the margin
    for level, stride in enumerate(strides):
        if level == 0:
            new = np.arange(0, n, stride)
            if new[-1] != n - 1:
                new = np.append(new, n - 1)
        elif not len(open_blocks):
            break
        else:
            new = np.concatenate([np.arange(starts[k], stops[k], stride) for k in open_blocks])
            new = new[~known[new]]
        if len(new):
            values[new] = block_maxima(plate, np.ascontiguousarray(c[new]))
            known[new] = True
            floor = np.maximum(floor, values[new].max(axis=0) * (1.0 - BOUND_MARGIN))
        open_blocks = open_blocks[np.any(upper[open_blocks] > floor, axis=1)]
        if len(open_blocks):  # the bounds from the references, in the blocks still open
            rows = np.concatenate([np.arange(starts[k], stops[k]) for k in open_blocks])
            anchors = np.flatnonzero(known)
            bounds = reference_bounds(c, m, rows, anchors, values[anchors], rest)
            upper[open_blocks] = np.minimum(
                upper[open_blocks], np.maximum.reduceat(bounds, np.searchsorted(rows, starts[open_blocks]), axis=0)
            )
            open_blocks = open_blocks[np.any(upper[open_blocks] > floor, axis=1)]
    scale = np.maximum(upper.max(axis=0), np.finfo(float).tiny)
    best = floor.copy()  # a block bounded by the floor holds no value up to the maximum
    done = np.ones(len(starts), dtype=bool)
    done[open_blocks] = False
    if not len(open_blocks):  # every bound at the floor (a plate at rest): one block still gives the maxima
        done[int(np.argmax((upper / scale).max(axis=1)))] = False
        best = np.full(3, -np.inf)

    def evaluate(k: int) -> np.ndarray:
        rows = slice(starts[k], stops[k])
        out[rows] = values[rows] = block_maxima(plate, c[rows])
        known[rows] = True
        return out[rows].max(axis=0)

    def tighten(k: int, best: np.ndarray) -> None:  # the evaluated rows bound their neighbours more tightly
        anchors = np.flatnonzero(known)
        for j in (k - 1, k + 1):
            if 0 <= j < len(starts) and not done[j] and np.any(upper[j] > best):
                nb = np.arange(starts[j], stops[j])
                upper[j] = np.minimum(upper[j], reference_bounds(c, m, nb, anchors, values[anchors], rest).max(axis=0))

    largest_bound_first(upper, best, done, scale, evaluate, tighten)
    return out


def largest_bound_first(
    upper: np.ndarray,
    best: np.ndarray,
    done: np.ndarray,
    scale: np.ndarray,
    evaluate: Callable[[int], np.ndarray],
    tighten: Callable[[int, np.ndarray], None] | None = None,
) -> None:
    """Evaluate the blocks still open, the largest bound first (upper (n_blocks, 3) over
    scale), while a block's bound exceeds the largest value found so far (best (3,)):
    evaluate(k) -> block k's maxima (3,); tighten(k, best) may lower the others' bounds
    after block k. done (n_blocks,) marks the blocks evaluated (or closed), in place."""
    while True:
        open_ = ~done & np.any(upper > best, axis=1)
        if not open_.any():
            return
        k = int(np.argmax(np.where(open_, (upper / scale).max(axis=1), -np.inf)))
        best = np.maximum(best, evaluate(k))
        done[k] = True
        if tighten is not None:
            tighten(k, best)
