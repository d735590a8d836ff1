"""Neighbour search: the potential granule-granule contacts in O(N log N), at t = 0 by
the initial gap (contact.detection = "fixed") or as a Verlet list (`verlet_pairs`,
`verlet_walls`; docs/model.md section 1.3).

A pair (i, j) is a potential contact when its initial surface gap is at most
gap_ratio * min(R_i, R_j) (docs/model.md section 1, the topology is fixed):

    |c_j - c_i| - R_i - R_j <= gap_ratio * min(R_i, R_j)

`contact_pairs` finds them with `setup.pairs.close_pairs` (a k-d tree, or all pairs for a
few granules): every
such pair has centres at most 2 R_max + gap_ratio R_max apart, so the tree returns a
superset of candidates in O(N log N) for packings of bounded size ratio, and the exact
test above (the same floating-point expression as the O(N^2) double loop,
`brute_force_pairs`) picks the pairs. The result is sorted (i, j), i < j: identical to
the double loop's. Every function takes the centres as x, y and, in space, z (None in the
plane: the plane's expressions are kept as they are).
"""

from __future__ import annotations

import math

import numpy as np
from granplate.jit import njit

from granplate.setup.pairs import close_pairs

#: Relative margin on the k-d tree's search distance, so that rounding never drops a pair
#: that the exact test would keep.
SEARCH_MARGIN = 1e-9


def is_contact(dx: float, dy: float, ri: float, rj: float, gap_ratio: float, dz: float | None = None) -> bool:
    """True when the surface gap |(dx, dy[, dz])| - R_i - R_j [m] is at most gap_ratio min(R_i, R_j)."""
    dist = math.hypot(dx, dy) if dz is None else math.hypot(dx, dy, dz)
    return dist - ri - rj <= gap_ratio * min(ri, rj)


def centre_distances(x, y, z, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """|s_j - s_i| [m] of the pairs (i, j) (z None: in the plane)."""
    d = np.hypot(x[j] - x[i], y[j] - y[i])
    return d if z is None else np.hypot(d, z[j] - z[i])


def normal_coordinates(x, y, z, normal) -> np.ndarray:
    """s . n [m] of every centre along a unit normal n (2 or 3 components)."""
    s = x * normal[0] + y * normal[1]
    return s if z is None else s + z * normal[2]


def _centres(x, y, z) -> np.ndarray:
    return np.column_stack([x, y] if z is None else [x, y, z])


def brute_force_pairs(x: np.ndarray, y: np.ndarray, r: np.ndarray, gap_ratio: float) -> np.ndarray:
    """(n_pairs, 2) potential contacts by the O(N^2) double loop (the reference)."""
    n = len(x)
    out = [
        (i, j) for i in range(n) for j in range(i + 1, n) if is_contact(x[j] - x[i], y[j] - y[i], r[i], r[j], gap_ratio)
    ]
    return np.array(out, np.int64).reshape(-1, 2)


def search_distance(r: np.ndarray, gap_ratio: float) -> float:
    """Largest centre distance [m] of a potential contact: (2 + gap_ratio) R_max, plus margin
    (as setup.pairs.contact_search_distance)."""
    return (2.0 + gap_ratio) * float(r.max()) * (1.0 + SEARCH_MARGIN)


def candidate_pairs(x: np.ndarray, y: np.ndarray, distance: float, z: np.ndarray | None = None) -> np.ndarray:
    """(n, 2) sorted pairs (i < j) of centres at most `distance` [m] apart
    (setup.pairs.close_pairs: all pairs for a few centres, else a k-d tree)."""
    if len(x) < 2:
        return np.zeros((0, 2), np.int64)
    return close_pairs(_centres(x, y, z), distance)


#: Relative margin within which numpy's distance of a pair cannot decide `is_contact` the
#: way math.hypot does (their roundings differ by a few units of 1e-16): such a pair is
#: decided by `is_contact` itself.
DECIDE_MARGIN = 1e-12


@njit(cache=True, inline="always")
def _exact_product(a: float, b: float) -> tuple[float, float]:
    """(p, e) with p = fl(a b) and p + e = a b exactly (Dekker's product by Veltkamp's split)."""
    ta, tb = a * 134217729.0, b * 134217729.0
    ah, bh = ta - (ta - a), tb - (tb - b)
    al, bl = a - ah, b - bh
    p = ah * bh
    q = ah * bl + al * bh
    s = p + q
    return s, p - s + q + al * bl


@njit(cache=True, inline="always")
def _fast_sum(a: float, b: float) -> tuple[float, float]:
    """(s, e) with s = fl(a + b), s + e = a + b exactly for |a| >= |b| (Dekker's fast two-sum)."""
    s = a + b
    return s, b - (s - a)


@njit(entry=True, cache=True)
def _hypot_columns(c: np.ndarray) -> np.ndarray:
    """CPython's vector_norm of each column of c (k, n) (`python_hypot`), for finite
    components whose largest magnitude is 0 or normal."""
    k, n = c.shape
    out = np.zeros(n)
    for e in range(n):
        top = 0.0
        for d in range(k):
            top = max(top, abs(c[d, e]))
        if top == 0.0:
            continue
        scale = math.ldexp(1.0, -math.frexp(top)[1])
        csum, frac1, frac2 = 1.0, 0.0, 0.0
        for d in range(k):
            v = abs(c[d, e]) * scale
            hi, lo = _exact_product(v, v)
            csum, carry = _fast_sum(csum, hi)
            frac1, frac2 = frac1 + lo, frac2 + carry
        h = math.sqrt(csum - 1.0 + (frac1 + frac2))
        hi, lo = _exact_product(-h, h)
        csum, carry = _fast_sum(csum, hi)
        frac1, frac2 = frac1 + lo, frac2 + carry
        h = h + (csum - 1.0 + (frac1 + frac2)) / (2.0 * h)
        out[e] = h / scale
    return out


def python_hypot(*components: np.ndarray) -> np.ndarray:
    """math.hypot(*components) of every element, bit for bit, compiled: CPython's
    vector_norm (its lossless scaling by a power of two, the squares' exact products summed
    beside their round-off, the square root and its one differential correction), for
    finite components (a subnormal largest magnitude: math.hypot itself)."""
    c = np.ascontiguousarray(np.vstack([np.ravel(np.asarray(x, float)) for x in components]))
    out = _hypot_columns(c)
    top = np.max(np.abs(c), axis=0) if c.shape[1] else np.zeros(0)
    for k in np.flatnonzero((top > 0.0) & (top < np.finfo(float).tiny)).tolist():  # subnormal: CPython's own
        out[k] = math.hypot(*(float(x) for x in c[:, k]))
    return out


def contacts_among(cand: np.ndarray, x, y, r, gap_ratio: float, z=None) -> np.ndarray:
    """The mask of the candidate pairs (n, 2) that `is_contact` keeps, decided by numpy
    for every pair but those within DECIDE_MARGIN of the limit (those by `is_contact`'s
    own expression with math.hypot's distance, `python_hypot`: a touching lattice puts
    every pair there)."""
    i, j = cand[:, 0], cand[:, 1]
    dist = centre_distances(x, y, z, i, j)
    ri, rj = r[i], r[j]
    gap, limit = dist - ri - rj, gap_ratio * np.minimum(ri, rj)
    band = DECIDE_MARGIN * (dist + ri + rj)
    keep = gap <= limit - band
    near = np.flatnonzero(~keep & ~(gap > limit + band))
    if len(near):
        a, b = i[near], j[near]
        d = (x[b] - x[a], y[b] - y[a]) + (() if z is None else (z[b] - z[a],))
        keep[near] = python_hypot(*d) - r[a] - r[b] <= gap_ratio * np.minimum(r[a], r[b])
    return keep


def contact_pairs(
    x: np.ndarray,
    y: np.ndarray,
    r: np.ndarray,
    gap_ratio: float,
    z: np.ndarray | None = None,
    candidates: np.ndarray | None = None,
) -> np.ndarray:
    """(n_pairs, 2) potential contacts, sorted (i, j) with i < j, in O(N log N).

    Same pairs in the same order as `brute_force_pairs`: the k-d tree gives candidates and
    `is_contact` decides each one as the double loop does (`contacts_among`). candidates:
    sorted pairs that hold every pair within `search_distance` (from a search at a larger
    distance, shared with `verlet_pairs`), else searched here.
    """
    x, y, r = (np.asarray(a, float) for a in (x, y, r))
    if len(x) < 2:
        return np.zeros((0, 2), np.int64)
    cand = candidate_pairs(x, y, search_distance(r, gap_ratio), z) if candidates is None else candidates
    return cand[contacts_among(cand, x, y, r, gap_ratio, z)].reshape(-1, 2)


def verlet_distance(r: np.ndarray, skin: float) -> float:
    """The search distance of `verlet_pairs`: 2 R_max (1 + skin), plus margin [m]."""
    return 2.0 * float(r.max()) * (1.0 + skin) * (1.0 + SEARCH_MARGIN)


def verlet_pairs(
    x: np.ndarray,
    y: np.ndarray,
    r: np.ndarray,
    skin: float,
    z: np.ndarray | None = None,
    candidates: np.ndarray | None = None,
) -> np.ndarray:
    """(n_pairs, 2) pairs whose centres are at most (R_i + R_j)(1 + skin) apart, sorted
    (i, j) with i < j, in O(N log N) (the Verlet list of docs/model.md section 1.3);
    candidates: as `contact_pairs`', holding every pair within `verlet_distance`."""
    x, y, r = (np.asarray(a, float) for a in (x, y, r))
    if len(x) < 2:
        return np.zeros((0, 2), np.int64)
    cand = candidate_pairs(x, y, verlet_distance(r, skin), z) if candidates is None else candidates
    i, j = cand[:, 0], cand[:, 1]
    keep = centre_distances(x, y, z, i, j) <= (r[i] + r[j]) * (1.0 + skin)
    return np.ascontiguousarray(cand[keep]).reshape(-1, 2)


def verlet_walls(
    x: np.ndarray,
    y: np.ndarray,
    r: np.ndarray,
    normals: np.ndarray,
    offsets: np.ndarray,
    skin: float,
    z: np.ndarray | None = None,
) -> np.ndarray:
    """(n, 2) [granule, wall] whose gap offset - s.n - R is at most skin R (granules
    beyond the wall included), sorted (wall, granule); normals: (nw, 2 or 3) unit outward."""
    x, y, r = (np.asarray(a, float) for a in (x, y, r))
    out = [np.zeros((0, 2), np.int64)]
    for w in range(len(offsets)):
        gap = offsets[w] - normal_coordinates(x, y, z, normals[w]) - r
        i = np.flatnonzero(gap <= skin * r)
        out.append(np.column_stack([i, np.full(len(i), w)]).astype(np.int64))
    return np.concatenate(out).reshape(-1, 2)


#: Most cells per centre of `reaching_pairs`' dense cell grid (a sparser assembly, its
#: bounding box mostly empty, is searched by the k-d tree instead).
CELLS_PER_CENTRE = 8


@njit(entry=True, cache=True)
def _grid_pairs(p, r, reach, lo, h, nc):  # pragma: no cover - compiled
    """Sorted pairs (i < j) of the centres p (n, d <= 3) [m] with |p_j - p_i|^2 <= ((R_i +
    R_j) reach)^2, from a cell grid of side h >= 2 R_max reach [m] from corner lo with
    nc (3,) cells per axis: each centre against the centres of its cell and the 26 (8 in
    the plane) around it, its partners sorted by insertion."""
    n, d = p.shape
    key = np.empty(n, np.int64)
    cell = np.zeros((n, 3), np.int64)
    for i in range(n):
        for k in range(d):
            cell[i, k] = min(int((p[i, k] - lo[k]) / h), nc[k] - 1)
        key[i] = (cell[i, 0] * nc[1] + cell[i, 1]) * nc[2] + cell[i, 2]
    start = np.zeros(nc[0] * nc[1] * nc[2] + 1, np.int64)
    for i in range(n):
        start[key[i] + 1] += 1
    for c in range(1, len(start)):
        start[c] += start[c - 1]
    member = np.empty(n, np.int64)
    fill = start[:-1].copy()
    for i in range(n):
        member[fill[key[i]]] = i
        fill[key[i]] += 1
    out = np.empty((max(16, 8 * n), 2), np.int64)
    m = 0
    buf = np.empty(64, np.int64)
    span = np.ones(3, np.int64)
    for k in range(d, 3):
        span[k] = 0
    for i in range(n):
        nb = 0
        for a in range(max(cell[i, 0] - span[0], 0), min(cell[i, 0] + span[0], nc[0] - 1) + 1):
            for b in range(max(cell[i, 1] - span[1], 0), min(cell[i, 1] + span[1], nc[1] - 1) + 1):
                for c in range(max(cell[i, 2] - span[2], 0), min(cell[i, 2] + span[2], nc[2] - 1) + 1):
                    q = (a * nc[1] + b) * nc[2] + c
                    for s in range(start[q], start[q + 1]):
                        j = member[s]
                        if j <= i:
                            continue
                        d2 = 0.0
                        for k in range(d):
                            e = p[j, k] - p[i, k]
                            d2 += e * e
                        lim = (r[i] + r[j]) * reach
                        if d2 <= lim * lim:
                            if nb == len(buf):
                                buf = np.concatenate((buf, np.empty(nb, np.int64)))
                            buf[nb] = j
                            nb += 1
        for u in range(1, nb):  # insertion sort: a few partners each
            v = buf[u]
            w = u - 1
            while w >= 0 and buf[w] > v:
                buf[w + 1] = buf[w]
                w -= 1
            buf[w + 1] = v
        if m + nb > out.shape[0]:
            grown = np.empty((2 * out.shape[0] + nb, 2), np.int64)
            grown[:m] = out[:m]
            out = grown
        for u in range(nb):
            out[m, 0] = i
            out[m, 1] = buf[u]
            m += 1
    return out[:m].copy()


def reaching_pairs(points: np.ndarray, r: np.ndarray, reach: float = 1.0 + SEARCH_MARGIN) -> np.ndarray:
    """(n, 2) sorted pairs (i < j) of the centres points (n, 2 or 3) [m] whose squared
    distance is at most ((R_i + R_j) reach)^2: with the default reach, a superset of the
    pairs that touch or overlap by any rounding of their distance (`is_contact` with no
    gap, the loop's overlap). A compiled cell grid of side 2 R_max reach, one pass, no sort
    beyond each centre's few partners; a sparse assembly (more than CELLS_PER_CENTRE cells
    per centre) or non-finite centres: the k-d tree (`candidate_pairs`), the same test after it."""
    p = np.ascontiguousarray(points, dtype=float)
    r = np.ascontiguousarray(r, dtype=float)
    n = len(p)
    if n < 2:
        return np.zeros((0, 2), np.int64)
    h = 2.0 * float(r.max()) * reach * (1.0 + SEARCH_MARGIN)
    lo, hi = p.min(axis=0), p.max(axis=0)
    nc = np.ones(3, np.int64)
    if np.isfinite(p).all() and h > 0.0:
        span = np.floor((hi - lo) / h) + 1.0
        if float(np.prod(span)) <= CELLS_PER_CENTRE * n + 64:
            nc[: p.shape[1]] = span.astype(np.int64)
            return _grid_pairs(p, r, float(reach), lo, h, nc)
    cand = close_pairs(p, h)
    i, j = cand[:, 0], cand[:, 1]
    d2 = np.sum((p[j] - p[i]) ** 2, axis=1)
    return np.ascontiguousarray(cand[d2 <= ((r[i] + r[j]) * reach) ** 2]).reshape(-1, 2)
