"""The residual compliance in series at an elastic body's contacts (docs/model.md section
3.9): the dropped modes respond statically, u_s = R_S N over the residual dofs S
(solid/residual.py), so the contacts' static forces solve delta_k = delta0_k - sum_j R_kj
N_j, N_k = F(delta_k), by Gauss-Seidel over the contacts in touch, each by Newton on its own
overlap; each contact's rows on S, the matrix R_kj between the contacts, the load R_S sum
r_k N_k and the residual's pull along the surface as the patch weights move.
"""

from __future__ import annotations

from granplate.jit import njit

from granplate.model.inputs import GEO_DELTA, GEO_NSTAT, GEO_NX, HIST_MAX, HIST_RATE
from granplate.physics.laws import normal_law_force, normal_law_slopes

#: Gauss-Seidel sweeps of the residual solve at most, and its tolerance on the forces
#: (relative to the largest); Newton steps per contact and their overlap tolerance.
RESID_SWEEPS = 200
RESID_RTOL = 1e-13
NEWTON_STEPS = 60
NEWTON_RTOL = 1e-14


@njit(cache=True)
def residual_tilt(b, buf, k, counts, upos, z, out) -> None:
    """The residual's pull along the surface on contact k (its static force in geo's
    GEO_NSTAT; z = R_S sum_j r_j N_j on the touched dofs, `residual_load`): out (3,) =
    N_k grad(r_k)^T z [N], the force -dPi/dx of the residual energy Pi = 1/2 N^T R N as
    r_k's weights move with the granule (docs/model.md section 3.9)."""
    i = b.active[k]
    g = b.geo[buf]
    d0 = 0.0
    d1 = 0.0
    d2 = 0.0
    for e in range(counts[k]):
        ze = z[upos[b.rcol[k, e]]]
        d0 += ze * b.rgrad[k, e, 0]
        d1 += ze * b.rgrad[k, e, 1]
        d2 += ze * b.rgrad[k, e, 2]
    nk = g[i, GEO_NSTAT]
    out[0] = nk * d0
    out[1] = nk * d1
    out[2] = nk * d2


@njit(cache=True)
def static_overlap(target, r, c, delta_max, speed, clip) -> float:
    """The overlap delta [m] with delta + r F(delta) = target (F the law's static force,
    r the contact's own residual compliance [m/N]): Newton from delta = target, which
    converges from above for a convex increasing F; 0 when target <= 0."""
    if target <= 0.0:
        return 0.0
    if r == 0.0:
        return target
    x = target
    for _ in range(NEWTON_STEPS):
        phi = x + r * normal_law_force(x, 0.0, c, delta_max, speed, clip) - target
        slope = 1.0 + r * normal_law_slopes(x, c, delta_max, speed)[0]
        dx = phi / slope
        x_new = x - dx
        if x_new <= 0.0:
            x_new = 0.5 * x
        if abs(x_new - x) <= NEWTON_RTOL * target:
            return x_new
        x = x_new
    return x


@njit(entry=True, cache=True)
def residual_rows(b, buf, i, k) -> int:
    """Contact k (granule i) as a combination of the residual dofs: its normal n times its
    patch's weights on the dofs of S (rcol, rcoef row k), and each term's gradient in the
    granule's position (rgrad). Returns how many terms."""
    g = b.geo[buf, i]
    nt = 0
    for e in range(b.count[buf, i]):
        w = b.weights[buf, i, e]
        node = b.entry[buf, i, e]
        for c in range(3):
            s = b.node_resid[node, c]
            nc = g[GEO_NX + c]
            if s < 0 or nc == 0.0:
                continue
            b.rcol[k, nt] = s
            b.rcoef[k, nt] = w * nc
            for d in range(3):
                b.rgrad[k, nt, d] = b.grad[i, e, d] * nc
            nt += 1
    return nt


@njit(entry=True, cache=True)
def touched_dofs(b, n_act, counts, upos, ulist) -> int:
    """The residual dofs U the contacts in touch load: ulist[:n] (n returned), upos[s] their
    position in it (upos all -1 on entry)."""
    n = 0
    for k in range(n_act):
        for e in range(counts[k]):
            s = b.rcol[k, e]
            if upos[s] < 0:
                upos[s] = n
                ulist[n] = s
                n += 1
    return n


@njit(entry=True, cache=True)
def residual_matrix(b, n_act, counts, upos, ulist, n_u, rows, rmat) -> None:
    """rmat[k, j] = r_k^T R_S r_j [m/N] between the contacts in touch: for each k its row
    r_k^T R_S over the touched dofs U (kept in rows[k], for `residual_load`), then its
    products with every r_j (j >= k)."""
    for k in range(n_act):
        row = rows[k]
        for a in range(n_u):
            row[a] = 0.0
        for e in range(counts[k]):
            ce = b.rcoef[k, e]
            r = b.resid[b.rcol[k, e]]
            for a in range(n_u):
                row[a] += ce * r[ulist[a]]
        for j in range(k, n_act):
            s = 0.0
            for e2 in range(counts[j]):
                s += row[upos[b.rcol[j, e2]]] * b.rcoef[j, e2]
            rmat[k, j] = s
            rmat[j, k] = s


@njit(cache=True)
def residual_load(b, buf, n_act, rows, n_u, z) -> None:
    """z = R_S sum_k r_k N_k on the touched dofs U [m] (N_k the static forces), from the
    contacts' rows r_k^T R_S (R_S symmetric)."""
    g = b.geo[buf]
    for a in range(n_u):
        z[a] = 0.0
    for k in range(n_act):
        nk = g[b.active[k], GEO_NSTAT]
        if nk == 0.0:
            continue
        row = rows[k]
        for a in range(n_u):
            z[a] += nk * row[a]


@njit(cache=True)
def solve_static(b, buf, n_act, delta0, rmat, clip) -> float:
    """The static normal forces N_k = F(delta0_k - sum_j R_kj N_j) of the n_act contacts in
    touch (b.active[:n_act], overlaps delta0 [m] without the residual), by Gauss-Seidel
    over them, each by `static_overlap`: into geo's GEO_NSTAT and GEO_DELTA. Returns the
    residual compliance's energy 1/2 N^T R N [J]."""
    g = b.geo[buf]
    for k in range(n_act):
        g[b.active[k], GEO_NSTAT] = 0.0
    for _ in range(RESID_SWEEPS):
        change = 0.0
        largest = 0.0
        for k in range(n_act):
            i = b.active[k]
            target = delta0[k]
            for j in range(n_act):
                if j != k:
                    target -= rmat[k, j] * g[b.active[j], GEO_NSTAT]
            x = static_overlap(target, rmat[k, k], b.coef[i], b.hist[i, HIST_MAX], b.hist[i, HIST_RATE], clip)
            n = normal_law_force(x, 0.0, b.coef[i], b.hist[i, HIST_MAX], b.hist[i, HIST_RATE], clip) if x > 0.0 else 0.0
            change = max(change, abs(n - g[i, GEO_NSTAT]))
            largest = max(largest, n)
            g[i, GEO_NSTAT] = n
            g[i, GEO_DELTA] = x
        if change <= RESID_RTOL * largest or n_act == 1:
            break
    e = 0.0
    for k in range(n_act):
        nk = g[b.active[k], GEO_NSTAT]
        for j in range(n_act):
            e += 0.5 * nk * rmat[k, j] * g[b.active[j], GEO_NSTAT]
    return e
