"""Sequential deposition of a poured packing, `[layout] drop = "sequential"` (docs/model.md
section 3.14, "Sequential deposition").

The granules are dropped one at a time, each from just above the pile at a random (seeded)
place of the container's footprint, and each rolls without friction on the granules
already at rest and on the container's walls until it rests (Visscher & Bolsterli,
Nature 239, 504, 1972; Jullien & Meakin, Europhys. Lett. 4, 1385, 1987): the quasi-static
limit of a pour, in which every granule comes to rest before the next arrives. A granule's
path is a steepest descent of its height under its contacts: its motion is gravity's
direction projected on the cone its contacts allow (the directions that open no contact:
`cone_projection`), a straight fall where it touches nothing, and it stops where that
projection vanishes (a pocket of supports that carries its weight, or the floor). The
contacts are exact touches (no overlap): the elastic settling under the real stiffness
(`results.ramped`) starts from this packing.

Every function works in the container's frame of the fall: coordinate `axis` is the height
above the floor; `deposit` maps it back.
"""

from __future__ import annotations

import math

import numpy as np

from granplate.dense import solve_dense
from granplate.jit import njit

#: A contact is active (it constrains the motion) when its surface gap is at most this
#: fraction of the falling granule's radius.
TOUCH = 1e-9
#: A rolling step is at most this fraction of the granule's radius times the size of the
#: projected gravity (so that the steps shrink where the path levels out).
ROLL_STEP = 0.2
#: A granule rests where its projected gravity is at most this fraction of g.
REST = 1e-6
#: The most descent steps of one granule (it stops where it is, without overlap, beyond).
MAX_STEPS = 20_000
#: The release height above the pile's top, a fraction of the granule's radius.
RELEASE_GAP = 0.01
#: A rest is a perch where its weakest support carries less than MARGIN of the weight:
#: the granule is lifted by LIFT and moved across by at most NUDGE radii, at most TRIES
#: times, to find a firmer rest.
MARGIN = 0.05
LIFT = 0.05
NUDGE = 0.2
TRIES = 8
#: The kinds of touch that are no granule.
FLOOR = -1
SIDE = -2
#: `cone_projection`: a direction opens no contact where it enters none by more than
#: CONE_TOL; a set of normals whose Gram matrix has a pivot at most SINGULAR is skipped.
CONE_TOL = 1e-12
SINGULAR = 1e-12
#: A touched granule stays in touch through a rolling step where the step's direction
#: along its normal is at most this (the cone's faces are met to round-off).
KEEP = 1e-9
#: The alternating projections after a rolling step: at most this many sweeps, until every
#: kept contact is met and every overlap undone to this fraction of the radius.
PROJECTION_SWEEPS = 100
PROJECTION_TOL = 1e-13


@njit(refcount=True, cache=True)
def cone_projection(normals: np.ndarray, m: int, g: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The projection of the direction g on the cone {u : n_k . u >= 0, k < m} of the
    first m unit normals: g + sum_k lambda_k n_k with lambda >= 0 (the least squares'),
    found exactly among the sets of at most d normals (Caratheodory) whose multipliers
    are >= 0 and whose direction opens no contact; the shortest such direction. weights[:m]:
    the multipliers lambda_k (where the projection vanishes, the share of g each normal carries)."""
    d = len(g)
    weights[:m] = 0.0
    best = g.copy()
    best_size = math.inf
    a = np.zeros((d, d))
    b = np.zeros(d)
    lam = np.zeros(d)
    pick = np.zeros(d, np.int64)
    trial = np.zeros(d)
    for k in range(d + 1):
        if k > m:
            break
        for a_ in range(k):
            pick[a_] = a_
        while True:
            ok = True
            if k > 0:  # the multipliers: (N N^T) lambda = -N g
                for i in range(k):
                    b[i] = 0.0
                    for c in range(d):
                        b[i] -= normals[pick[i], c] * g[c]
                    for j in range(k):
                        s = 0.0
                        for c in range(d):
                            s += normals[pick[i], c] * normals[pick[j], c]
                        a[i, j] = s
                ok = solve_dense(a[:k, :k], b[:k]) > SINGULAR
                for i in range(k):
                    lam[i] = b[i]
                    ok = ok and lam[i] >= 0.0
            if ok:
                for c in range(d):
                    trial[c] = g[c]
                    for i in range(k):
                        trial[c] += lam[i] * normals[pick[i], c]
                for q in range(m):
                    s = 0.0
                    for c in range(d):
                        s += normals[q, c] * trial[c]
                    ok = ok and s >= -CONE_TOL
                size = 0.0
                for c in range(d):
                    size += trial[c] * trial[c]
                if ok and size < best_size:
                    best_size = size
                    best[:] = trial
                    weights[:m] = 0.0
                    for i in range(k):
                        weights[pick[i]] = lam[i]
            # the next set of k normals out of m (lexicographic)
            i = k - 1
            while i >= 0 and pick[i] == m - k + i:
                i -= 1
            if i < 0:
                break
            pick[i] += 1
            for j in range(i + 1, k):
                pick[j] = pick[j - 1] + 1
    return best


@njit(cache=True)
def _column(p: np.ndarray, hax: np.ndarray, cell: float, ncell: np.ndarray) -> int:
    """The flat index of the column (cells across the footprint) that holds the point p."""
    col = 0
    for k in range(len(hax)):
        c = min(max(int(p[hax[k]] / cell), 0), ncell[k] - 1)
        col = col * ncell[k] + c
    return col


@njit(cache=True)
def _neighbours(p, hax, cell, ncell, head, nxt, out) -> int:
    """The granules at rest in the 3^(d-1) columns around p's: their indices in out, their count."""
    nh = len(hax)
    total = 1
    for _ in range(nh):
        total *= 3
    count = 0
    for combo in range(total):
        col, rest, ok = 0, combo, True
        for k in range(nh):
            off = rest % 3 - 1
            rest //= 3
            c = min(max(int(p[hax[k]] / cell), 0), ncell[k] - 1) + off
            if c < 0 or c >= ncell[k]:
                ok = False
                break
            col = col * ncell[k] + c
        if not ok:
            continue
        j = head[col]
        while j >= 0:
            out[count] = j
            count += 1
            j = nxt[j]
    return count


@njit(cache=True)
def _ray_to_sphere(p, u, c, reach: float) -> float:
    """The distance along the unit direction u from p to where |p + t u - c| = reach (inf:
    never, or moving away)."""
    wu, ww = 0.0, 0.0
    for a in range(len(p)):
        w = p[a] - c[a]
        wu += w * u[a]
        ww += w * w
    if wu >= 0.0:
        return math.inf
    disc = wu * wu - (ww - reach * reach)
    if disc < 0.0:
        return math.inf
    return max(0.0, -wu - math.sqrt(disc))


@njit(cache=True)
def _gap(p, c, reach: float, n) -> float:
    """|p - c| - reach [m]; n: the unit normal from c to p."""
    dist = 0.0
    for a in range(len(p)):
        n[a] = p[a] - c[a]
        dist += n[a] * n[a]
    dist = math.sqrt(dist)
    for a in range(len(p)):
        n[a] /= dist
    return dist - reach


@njit(cache=True)
def _touch_again(p, r, centres, radii, kept, nk, cand, nc, hax, axis, size, n):
    """After a rolling step: p moved back onto the kept contacts (granules it rolls on) and
    out of any granule, side wall or the floor it entered, by alternating projections."""
    for _ in range(PROJECTION_SWEEPS):
        worst = 0.0
        for q in range(nk):
            j = kept[q]
            e = _gap(p, centres[j], r + radii[j], n)
            for a in range(len(p)):
                p[a] -= e * n[a]
            worst = max(worst, abs(e))
        for q in range(nc):
            j = cand[q]
            e = _gap(p, centres[j], r + radii[j], n)
            if e < 0.0:
                for a in range(len(p)):
                    p[a] -= e * n[a]
                worst = max(worst, -e)
        for k in hax:
            lo, hi = r, size[k] - r
            worst = max(worst, lo - p[k], p[k] - hi)
            p[k] = min(max(p[k], lo), hi)
        worst = max(worst, r - p[axis])
        p[axis] = max(p[axis], r)
        if worst <= PROJECTION_TOL * r:
            return


@njit(cache=True)
def _margin(weights, touching, m: int) -> float:
    """The weakest support's share of the weight [-] (1 on the floor)."""
    total, low = 0.0, math.inf
    for k in range(m):
        if weights[k] > 0.0:
            if touching[k] == FLOOR:
                return 1.0
            total += weights[k]
            low = min(low, weights[k])
    return low / total if total > 0.0 else 1.0


@njit(refcount=True, cache=True)
def _settle_one(p, r, centres, radii, hax, axis, size, cell, ncell, head, nxt, cand, normals, kept, nudges) -> int:
    """Move the granule of radius r from p down its path of steepest descent until it
    rests (module docstring); p is updated in place. A rest whose weakest support carries
    less than MARGIN of the weight (a perch the packing's elastic sag would tip) is left
    again, at most len(nudges) times: the granule lifted by LIFT r and moved across by
    NUDGE r times the next row of nudges (each in [-1, 1]). Returns the steps taken."""
    d = len(p)
    g = np.zeros(d)
    g[axis] = -1.0
    u = np.zeros(d)
    n = np.zeros(d)
    touching = np.zeros(normals.shape[0], np.int64)
    weights = np.zeros(normals.shape[0])
    tries = 0
    for step in range(MAX_STEPS):
        nc = _neighbours(p, hax, cell, ncell, head, nxt, cand)
        m = 0
        # the floor and the side walls: the planes p[k] >= r and p[k] <= size[k] - r
        if p[axis] - r <= TOUCH * r:
            normals[m, :] = 0.0
            normals[m, axis] = 1.0
            touching[m] = FLOOR
            m += 1
        for k in hax:
            for side in (-1.0, 1.0):
                gap = p[k] - r if side < 0 else size[k] - r - p[k]
                if gap <= TOUCH * r:
                    normals[m, :] = 0.0
                    normals[m, k] = -side
                    touching[m] = SIDE
                    m += 1
        for q in range(nc):
            j = cand[q]
            if _gap(p, centres[j], r + radii[j], n) <= TOUCH * r and m < normals.shape[0]:
                normals[m, :] = n
                touching[m] = j
                m += 1
        dirn = cone_projection(normals, m, g, weights)
        size_d = math.sqrt(np.sum(dirn * dirn))
        if size_d <= REST:
            if tries == len(nudges) or _margin(weights, touching, m) >= MARGIN:
                return step
            p[axis] += LIFT * r
            for q in range(len(hax)):
                p[hax[q]] += NUDGE * r * nudges[tries, q]
            tries += 1
            _touch_again(p, r, centres, radii, kept, 0, cand, nc, hax, axis, size, n)
            continue
        for a in range(d):
            u[a] = dirn[a] / size_d
        s = math.inf if m == 0 else ROLL_STEP * r * size_d
        # the first new touch along u: the floor, the side walls, the granules at rest
        # (a plane touched already is one of the cone's faces: u does not enter it)
        if u[axis] < 0.0 and p[axis] - r > TOUCH * r:
            s = min(s, (p[axis] - r) / -u[axis])
        for k in hax:
            if u[k] < 0.0 and p[k] - r > TOUCH * r:
                s = min(s, (p[k] - r) / -u[k])
            elif u[k] > 0.0 and size[k] - r - p[k] > TOUCH * r:
                s = min(s, (size[k] - r - p[k]) / u[k])
        nk = 0
        for q in range(m):
            if touching[q] >= 0:
                un = 0.0
                for a in range(d):
                    un += u[a] * normals[q, a]
                if un <= KEEP:  # rolls on it (does not lift off): stays in touch
                    kept[nk] = touching[q]
                    nk += 1
        for q in range(nc):
            j = cand[q]
            hit = _ray_to_sphere(p, u, centres[j], r + radii[j])
            if hit > 0.0:
                s = min(s, hit)
        if not math.isfinite(s):
            return step
        for a in range(d):
            p[a] += s * u[a]
        if m > 0:
            _touch_again(p, r, centres, radii, kept, nk, cand, nc, hax, axis, size, n)
    return MAX_STEPS


@njit(refcount=True, cache=True)
def deposit_frame(radii: np.ndarray, start: np.ndarray, size: np.ndarray, axis: int, cell: float, nudges: np.ndarray):
    """The granules of `radii` dropped in turn from `start` (n, d): its footprint coordinates
    (the height is set at release) in the box [0, size] whose floor is height 0 along `axis`;
    nudges (n, TRIES, d - 1): each granule's moves off a perch (`_settle_one`).
    Returns (centres (n, d) [m] at rest, release heights (n,) [m], steps (n,))."""
    n, d = start.shape
    hax = np.array([k for k in range(d) if k != axis], np.int64)
    ncell = np.array([max(1, int(size[k] / cell)) for k in hax], np.int64)
    total = 1
    for k in range(len(hax)):
        total *= ncell[k]
    head = np.full(total, -1, np.int64)
    nxt = np.full(n, -1, np.int64)
    cand = np.empty(n, np.int64)
    normals = np.zeros((64, d))
    kept = np.zeros(64, np.int64)
    centres = np.zeros((n, d))
    release = np.zeros(n)
    steps = np.zeros(n, np.int64)
    top = 0.0
    for i in range(n):
        p = start[i].copy()
        p[axis] = top + radii[i] * (1.0 + RELEASE_GAP)
        release[i] = p[axis]
        steps[i] = _settle_one(
            p, radii[i], centres, radii, hax, axis, size, cell, ncell, head, nxt, cand, normals, kept, nudges[i]
        )
        centres[i] = p
        col = _column(p, hax, cell, ncell)
        nxt[i] = head[col]
        head[col] = i
        top = max(top, p[axis] + radii[i])
    return centres, release, steps


def deposit(
    radii: np.ndarray, size: tuple[float, ...], axis: int, sign: float, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sequential deposition of `radii` [m] (in their order) into the box [0, size] [m]
    whose floor faces gravity along +-e_axis (sign +1: gravity points to +e_axis, the floor
    at size[axis]); each granule's place across the footprint drawn with
    numpy.random.default_rng([seed, 2]). Returns (centres at rest (n, d) [m], centres at
    release (n, d) [m], descent steps (n,))."""
    radii = np.asarray(radii, float)
    n, d = len(radii), len(size)
    box = np.asarray(size, float)
    rng = np.random.default_rng([seed, 2])
    start = np.zeros((n, d))
    for k in range(d):
        if k != axis:
            start[:, k] = radii + rng.uniform(0.0, 1.0, n) * (box[k] - 2.0 * radii)
    nudges = rng.uniform(-1.0, 1.0, (n, TRIES, d - 1))
    cell = 2.0 * float(radii.max()) * (1.0 + ROLL_STEP + NUDGE)
    centres, release, steps = deposit_frame(radii, start, box, axis, cell, nudges)
    dropped = centres.copy()
    dropped[:, axis] = release
    if sign > 0:
        centres[:, axis] = box[axis] - centres[:, axis]
        dropped[:, axis] = box[axis] - dropped[:, axis]
    return centres, dropped, steps
