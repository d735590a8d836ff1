"""An elastic body in space in the time loop (docs/model.md section 3.9): the granules'
contacts on its surface, their forces with the residual compliance in series, the
friction there, and the body's modes kicked by the contact forces and turned exactly
between kicks. The velocity-Verlet scheme (solver/schemes/verlet.py) calls these; the
arrays are model.inputs.BodyArrays (`b`), whose per-granule state lives in two buffers
(`buf`: t_n's and the trial step's end).

A granule touches the body at the closest point of the undeformed surface to its centre
(`follow_closest`, seeded with the last face), with the outward normal n there, its
patch's weights w_a over surface nodes (a disc about the point, `disc_patch`, or the
face's shape functions there) and the overlap

    delta0 = R - d + n . u_c,   u_c = sum_a w_a u_a = sum_a w_a Phi_a q,

(physics.space.surface_overlap). The dropped modes respond statically, u_s = R_S N over
the residual dofs S (solid/residual.py), in series with the contact law's static force:
delta = delta0 - sum_j R_kj N_j, N_k = F(delta_k), solved by Gauss-Seidel over the
contacts in touch (each contact by Newton on its own overlap). The force on the granule
is N n with N the law's whole force at (delta, its rate) (damping included), plus the
static force's pull along the deformed surface's tilt and the residual's moving weights
(the exact gradient of the contact's potential); the body gets -N n over the patch, on the
modes Phi^T (w (x) -N n). Friction is split off as for
granule pairs (solver.granular3d.friction_flow): an exact impulse along the slip, against
the granule's and the body's mobility along it, booked as the kinetic energy it removes.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from granplate.model.inputs import (
    GEO_DAMP,
    GEO_DELTA,
    GEO_DIST,
    GEO_ETA,
    GEO_GX,
    GEO_GY,
    GEO_GZ,
    GEO_N,
    GEO_NSTAT,
    GEO_NX,
    GEO_NY,
    GEO_NZ,
    GEO_TOUCH,
    GEO_XI,
    HIST_END,
    HIST_MAX,
    HIST_RATE,
)
from granplate.physics.contact import COEF_KS, COEF_MU, contact_arm
from granplate.physics.laws import normal_law_force, normal_law_response, normal_law_slopes
from granplate.physics.space import friction_along_slip, normal_rate_3d, slip_velocity_3d, surface_overlap
from granplate.solid.surface import face_shape_functions, follow_closest
from granplate.solver.granular import friction_impulse
from granplate.solver.granular3d import VX, WX, X, apply_friction_impulse

#: Gauss-Seidel sweeps of the residual solve at most, and its tolerance on the forces
#: (relative to the largest); Newton steps per contact and their overlap tolerance.
RESID_SWEEPS = 200
RESID_RTOL = 1e-13
NEWTON_STEPS = 60
NEWTON_RTOL = 1e-14
#: A granule is located on the surface when its centre lies within REACH radii of the
#: body's bounding box (a surface that moves out of the box by more than REACH - 1 radii
#: towards a granule would be missed).
REACH = 2.0


@njit(cache=True)
def has_body(b) -> bool:
    """Whether the run has an elastic body (faces to touch)."""
    return b.face_nodes.shape[0] > 0


@njit(cache=True)
def sensor_loads(b, buf, load):
    """Add half the normal force [N] of each granule's contact with the body, as the force
    pass into buffer buf left it, to its sensor reading load[i] (docs/model.md section
    3.15); nothing without a body."""
    if not has_body(b):
        return
    for i in range(load.shape[0]):
        if b.geo[buf, i, GEO_TOUCH] != 0.0:
            load[i] += 0.5 * b.geo[buf, i, GEO_N]


@njit(cache=True)
def near_box(b, x, y, z, reach) -> bool:
    """Whether a centre lies within `reach` [m] of the body's bounding box."""
    d2 = 0.0
    for c, v in ((0, x), (1, y), (2, z)):
        lo = b.box[0, c] - v
        hi = v - b.box[1, c]
        e = max(lo, hi, 0.0)
        d2 += e * e
    return d2 <= reach * reach


@njit(cache=True)
def tangent_map(X, dN, t) -> None:
    """t (3, 2) = J (J^T J)^-1, J = sum_a X_a grad_xi(N_a)^T the face's Jacobian at the
    point of the shape functions' derivatives dN: a face gradient to the surface gradient
    in space."""
    j00 = j01 = j10 = j11 = j20 = j21 = 0.0
    for a in range(dN.shape[0]):
        j00 += X[a, 0] * dN[a, 0]
        j01 += X[a, 0] * dN[a, 1]
        j10 += X[a, 1] * dN[a, 0]
        j11 += X[a, 1] * dN[a, 1]
        j20 += X[a, 2] * dN[a, 0]
        j21 += X[a, 2] * dN[a, 1]
    a00 = j00 * j00 + j10 * j10 + j20 * j20
    a01 = j00 * j01 + j10 * j11 + j20 * j21
    a11 = j01 * j01 + j11 * j11 + j21 * j21
    det = a00 * a11 - a01 * a01
    i00 = a11 / det
    i01 = -a01 / det
    i11 = a00 / det
    t[0, 0] = j00 * i00 + j01 * i01
    t[0, 1] = j00 * i01 + j01 * i11
    t[1, 0] = j10 * i00 + j11 * i01
    t[1, 1] = j10 * i01 + j11 * i11
    t[2, 0] = j20 * i00 + j21 * i01
    t[2, 1] = j20 * i01 + j21 * i11


@njit(cache=True)
def patch_frame(nx, ny, nz):
    """Two unit tangents (t1, t2) of the plane normal to n: t1 along e x n for the axis e
    least aligned with n (constant over a flat face), t2 = n x t1."""
    ax, ay, az = abs(nx), abs(ny), abs(nz)
    if ax <= ay and ax <= az:  # e = x: e x n = (0, -nz, ny)
        t1x, t1y, t1z = 0.0, -nz, ny
    elif ay <= az:  # e = y: (nz, 0, -nx)
        t1x, t1y, t1z = nz, 0.0, -nx
    else:  # e = z: (-ny, nx, 0)
        t1x, t1y, t1z = -ny, nx, 0.0
    inv = 1.0 / math.sqrt(t1x * t1x + t1y * t1y + t1z * t1z)
    t1x *= inv
    t1y *= inv
    t1z *= inv
    return t1x, t1y, t1z, ny * t1z - nz * t1y, nz * t1x - nx * t1z, nx * t1y - ny * t1x


@njit(cache=True)
def locate(b, buf, i, p, out, N, dN) -> None:
    """Granule i's contact on the undeformed surface (docs/model.md section 3.9), centre p
    (3,) [m], into buffer buf: the closest point (face, face coordinates, signed distance,
    outward normal: geo), searched from the face it last touched; and its patch as entries
    (surface node, weight, the weight's gradient in the granule's position [1/m]): the
    face's shape functions at the point (radius b.patch[0] = 0), or the disc of that
    radius about the point (`disc_patch`)."""
    seed = b.face[buf, i] if b.face[buf, i] >= 0 else b.face[1 - buf, i]
    f = follow_closest(b.face_nodes, b.kind[0], b.neighbours, seed, p, out)
    b.face[buf, i] = f
    g = b.geo[buf, i]
    g[GEO_XI] = out[0]
    g[GEO_ETA] = out[1]
    g[GEO_NX] = out[5]
    g[GEO_NY] = out[6]
    g[GEO_NZ] = out[7]
    g[GEO_DIST] = out[8]
    if b.patch[0] > 0.0:
        disc_patch(b, buf, i, out[2], out[3], out[4], out[5], out[6], out[7])
        return
    face_shape_functions(b.kind[0], out[0], out[1], N, dN)
    t = np.empty((3, 2))
    tangent_map(b.face_nodes[f], dN, t)
    for a in range(N.shape[0]):
        b.entry[buf, i, a] = b.face_snode[f, a]
        b.weights[buf, i, a] = N[a]
        for c in range(3):
            b.grad[i, a, c] = t[c, 0] * dN[a, 0] + t[c, 1] * dN[a, 1]
    b.count[buf, i] = N.shape[0]


@njit(cache=True)
def disc_patch(b, buf, i, x0, x1, x2, nx, ny, nz) -> None:
    """Granule i's patch of radius a = b.patch[0] about the surface point x [m] (normal n):
    every surface node within a of x, weighted by its share of the surface times the kernel
    (1 - r^2/a^2)^2 and normalised, so that the weights are smooth in x and, as the mesh is
    refined, average the surface over the disc; their gradients in the granule's position
    are the kernel's along the surface (I - n n^T). Nodes by the grid of cells of b.grid."""
    a = b.patch[0]
    cell = b.grid[0]
    o0, o1, o2 = b.grid_origin[0], b.grid_origin[1], b.grid_origin[2]
    s0, s1, s2 = b.grid_shape[0], b.grid_shape[1], b.grid_shape[2]
    c0 = int((x0 - o0) / cell)
    c1 = int((x1 - o1) / cell)
    c2 = int((x2 - o2) / cell)
    n = 0
    total = 0.0
    dt0 = dt1 = dt2 = 0.0
    inv_a2 = 1.0 / (a * a)
    for k0 in range(max(c0 - 1, 0), min(c0 + 2, s0)):
        for k1 in range(max(c1 - 1, 0), min(c1 + 2, s1)):
            for k2 in range(max(c2 - 1, 0), min(c2 + 2, s2)):
                cid = (k0 * s1 + k1) * s2 + k2
                for q in range(b.cell_start[cid], b.cell_start[cid + 1]):
                    node = b.cell_nodes[q]
                    d0 = b.node_xyz[node, 0] - x0
                    d1 = b.node_xyz[node, 1] - x1
                    d2 = b.node_xyz[node, 2] - x2
                    rho2 = (d0 * d0 + d1 * d1 + d2 * d2) * inv_a2
                    if rho2 >= 1.0 or n >= b.entry.shape[2]:
                        continue
                    one = 1.0 - rho2
                    k = b.node_area[node] * one * one
                    dk = b.node_area[node] * 4.0 * one * inv_a2  # dk/dx = dk * (X_node - x)
                    b.entry[buf, i, n] = node
                    b.weights[buf, i, n] = k
                    b.grad[i, n, 0] = dk * d0
                    b.grad[i, n, 1] = dk * d1
                    b.grad[i, n, 2] = dk * d2
                    total += k
                    dt0 += dk * d0
                    dt1 += dk * d1
                    dt2 += dk * d2
                    n += 1
    b.count[buf, i] = n
    inv = 1.0 / total
    for e in range(n):
        w = b.weights[buf, i, e] * inv
        b.weights[buf, i, e] = w
        g0 = (b.grad[i, e, 0] - w * dt0) * inv
        g1 = (b.grad[i, e, 1] - w * dt1) * inv
        g2 = (b.grad[i, e, 2] - w * dt2) * inv
        gn = g0 * nx + g1 * ny + g2 * nz  # along the surface only: the foot moves tangentially
        b.grad[i, e, 0] = g0 - gn * nx
        b.grad[i, e, 1] = g1 - gn * ny
        b.grad[i, e, 2] = g2 - gn * nz


@njit(cache=True)
def surface_velocity(b, buf, i, qd):
    """The surface's velocity at granule i's contact (buffer buf), its patch's weighted mean
    sum_e w_e Phi_e qd [m/s] (x, y, z)."""
    nm = qd.shape[0]
    v = np.zeros(3)
    for e in range(b.count[buf, i]):
        w = b.weights[buf, i, e]
        if w == 0.0:
            continue
        node = b.entry[buf, i, e]
        for c in range(3):
            row = b.node_rows[node, c]
            if row < 0:
                continue
            sv = 0.0
            for m in range(nm):
                sv += b.phi[row, m] * qd[m]
            v[c] += w * sv
    return v[0], v[1], v[2]


@njit(cache=True)
def normal_motion(b, buf, i, q) -> float:
    """The surface's normal displacement u_n = n . u_c [m] at granule i's contact (buffer
    buf; u_c its patch's weighted mean), and its gradient in the granule's position (the
    deformed surface's tilt, [-]) into geo's GEO_GX..GEO_GZ: sum_e grad(w_e) n . u_e."""
    g = b.geo[buf, i]
    nm = q.shape[0]
    un = 0.0
    gx = 0.0
    gy = 0.0
    gz = 0.0
    for e in range(b.count[buf, i]):
        node = b.entry[buf, i, e]
        ua = 0.0
        for c in range(3):
            row = b.node_rows[node, c]
            nc = g[GEO_NX + c]
            if row < 0 or nc == 0.0:
                continue
            sq = 0.0
            for m in range(nm):
                sq += b.phi[row, m] * q[m]
            ua += nc * sq
        un += b.weights[buf, i, e] * ua
        gx += b.grad[i, e, 0] * ua
        gy += b.grad[i, e, 1] * ua
        gz += b.grad[i, e, 2] * ua
    g[GEO_GX] = gx
    g[GEO_GY] = gy
    g[GEO_GZ] = gz
    return un


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
def spread(b, buf, i, fx, fy, fz, out, scale) -> None:
    """out[m] += scale * (Phi^T f)_m for the force f [N] at granule i's contact (buffer
    buf), spread over its patch's nodes by the weights."""
    for e in range(b.count[buf, i]):
        w = b.weights[buf, i, e] * scale
        if w == 0.0:
            continue
        node = b.entry[buf, i, e]
        for c in range(3):
            row = b.node_rows[node, c]
            if row < 0:
                continue
            fc = w * (fx if c == 0 else (fy if c == 1 else fz))
            for m in range(out.shape[0]):
                out[m] += b.phi[row, m] * fc


@njit(cache=True)
def spread_both(b, buf, i, nx, ny, nz, n, d, out, out_d) -> None:
    """out += Phi^T (w (x) n N) and out_d += Phi^T (w (x) n D) in one pass over the rows:
    a normal force N n and its damping part D n [N] at granule i's contact."""
    for e in range(b.count[buf, i]):
        w = b.weights[buf, i, e]
        if w == 0.0:
            continue
        node = b.entry[buf, i, e]
        for c in range(3):
            row = b.node_rows[node, c]
            nc = nx if c == 0 else (ny if c == 1 else nz)
            if row < 0 or nc == 0.0:
                continue
            fc = w * nc * n
            fd = w * nc * d
            for m in range(out.shape[0]):
                phi = b.phi[row, m]
                out[m] += phi * fc
                out_d[m] += phi * fd


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


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
def contact_forces(y, q, qd, b, buf, radius, mass, clip, acc, fdamp, scale_acc):
    """The body's contact forces at granule state y (ng, 9), modal displacement q and
    velocity qd (nm,) into buffer buf: each granule within REACH R of the body's bounding
    box located on its surface, the overlaps with the residual compliance in series
    (`solve_static`), the law's forces (damping at the overlap rate against the surface's
    velocity); acc[i, VX..VZ] gains N n / m_i (scale_acc True) or N n; fdamp[i, VX..VZ]
    the damping part [N]; b.fmodal[buf], b.fdamp[buf] the modal projections of the forces
    on the body. The contacts' overlaps go to hist[:, HIST_END].

    Returns (stored elastic energy of the contacts [J], viscous power [W], plastic work past
    the largest overlaps [J], the residual's energy [J], the largest overlap / radius, its
    granule)."""
    nm = q.shape[0]
    for m in range(nm):
        b.fmodal[buf, m] = 0.0
        b.fdamp[buf, m] = 0.0
    n_fn = b.face_nodes.shape[1]
    out = np.empty(9)
    N = np.empty(n_fn)
    dN = np.empty((n_fn, 2))
    p = np.empty(3)
    ng = y.shape[0]
    delta0 = np.empty(max(ng, 1))
    counts = np.zeros(max(ng, 1), np.int64)
    n_act = 0
    g = b.geo[buf]
    for i in range(ng):
        g[i, GEO_TOUCH] = 0.0
        g[i, GEO_N] = 0.0
        g[i, GEO_NSTAT] = 0.0
        g[i, GEO_DAMP] = 0.0
        g[i, GEO_DELTA] = 0.0
        b.hist[i, HIST_END] = 0.0
        r = radius[i]
        if not near_box(b, y[i, X], y[i, X + 1], y[i, X + 2], REACH * r):
            continue
        p[0] = y[i, X]
        p[1] = y[i, X + 1]
        p[2] = y[i, X + 2]
        locate(b, buf, i, p, out, N, dN)
        d0 = surface_overlap(r, g[i, GEO_DIST], normal_motion(b, buf, i, q))
        if d0 <= 0.0:
            continue
        g[i, GEO_TOUCH] = 1.0
        b.active[n_act] = i
        delta0[n_act] = d0
        n_act += 1
    e_static = 0.0
    resid = b.resid.shape[0] > 0
    tilt = np.zeros(3)
    n_s = b.resid.shape[0]
    upos = np.full(n_s, -1, np.int64)
    ulist = np.empty(n_s, np.int64)
    n_u = 0
    rows = np.empty((0, 0))
    rmat = np.zeros((n_act, n_act))  # R_kj between the contacts in touch [m/N]
    if n_act > 0:
        if resid:
            for k in range(n_act):
                counts[k] = residual_rows(b, buf, b.active[k], k)
            n_u = touched_dofs(b, n_act, counts, upos, ulist)
            rows = np.empty((n_act, n_u))
            residual_matrix(b, n_act, counts, upos, ulist, n_u, rows, rmat)
        e_static = solve_static(b, buf, n_act, delta0, rmat, clip)
    z = np.empty(n_u)
    if resid and n_act > 0:
        residual_load(b, buf, n_act, rows, n_u, z)
    e_pot = 0.0
    p_visc = 0.0
    w_plastic = 0.0
    ovl = 0.0
    ovl_i = -1
    for k in range(n_act):
        i = b.active[k]
        r = radius[i]
        delta = g[i, GEO_DELTA]
        b.hist[i, HIST_END] = delta
        if delta <= 0.0:
            continue
        nx = g[i, GEO_NX]
        ny = g[i, GEO_NY]
        nz = g[i, GEO_NZ]
        v0, v1, v2 = surface_velocity(b, buf, i, qd)
        # the overlap's rate, with the normal from the granule into the body (-n); the
        # residual in series takes its share, d delta = d delta0 / (1 + R_kk F'(delta))
        ddot = normal_rate_3d(y[i, VX] - v0, y[i, VX + 1] - v1, y[i, VX + 2] - v2, -nx, -ny, -nz)
        if resid and rmat[k, k] > 0.0:
            ddot /= 1.0 + rmat[k, k] * normal_law_slopes(delta, b.coef[i], b.hist[i, HIST_MAX], b.hist[i, HIST_RATE])[0]
        n, pv, ep, wp = normal_law_response(delta, ddot, b.coef[i], b.hist[i, HIST_MAX], b.hist[i, HIST_RATE], clip)
        g[i, GEO_N] = n
        e_pot += ep
        p_visc += pv
        w_plastic += wp
        d = pv / ddot if pv != 0.0 else 0.0
        g[i, GEO_DAMP] = d
        inv = 1.0 / mass[i] if scale_acc else 1.0
        # the whole force along n, and the static force's pull along the deformed surface's
        # tilt and the residual's weights (what makes the contact's work exact)
        ns = g[i, GEO_NSTAT]
        tx = -ns * g[i, GEO_GX]
        ty = -ns * g[i, GEO_GY]
        tz = -ns * g[i, GEO_GZ]
        if resid:
            residual_tilt(b, buf, k, counts, upos, z, tilt)
            tx += tilt[0]
            ty += tilt[1]
            tz += tilt[2]
        acc[i, VX] += (n * nx + tx) * inv
        acc[i, VX + 1] += (n * ny + ty) * inv
        acc[i, VX + 2] += (n * nz + tz) * inv
        fdamp[i, VX] += d * nx
        fdamp[i, VX + 1] += d * ny
        fdamp[i, VX + 2] += d * nz
        spread_both(b, buf, i, nx, ny, nz, -n, -d, b.fmodal[buf], b.fdamp[buf])
        if delta > ovl * r:
            ovl = delta / r
            ovl_i = i
    b.static[buf] = e_static
    return e_pot, p_visc, w_plastic, e_static, ovl, ovl_i


@njit(cache=True)
def kick(qd, fmodal, fdamp, hk) -> float:
    """The modes' half kick qd += hk Phi^T F (hk = h/2 [s]); returns the damping part's
    work [J], hk F_d . (qd_before + qd_after)/2 (as the granules' kicks book theirs)."""
    w = 0.0
    for m in range(qd.shape[0]):
        dv = hk * fmodal[m]
        w += fdamp[m] * hk * (qd[m] + 0.5 * dv)
        qd[m] += dv
    return w


@njit(cache=True)
def load_kick(qd, load, amp, hk) -> float:
    """The modes' half kick by a load on the body, qd += hk amp Phi^T f (load = Phi^T f per
    unit amplitude, amp the amplitude now); returns its work [J], the kinetic energy it
    adds, hk amp load . (qd_before + qd_after)/2 (docs/model.md section 5.3)."""
    w = 0.0
    if amp == 0.0:
        return w
    for m in range(qd.shape[0]):
        dv = hk * amp * load[m]
        w += dv * (qd[m] + 0.5 * dv)
        qd[m] += dv
    return w


@njit(cache=True)
def turn(q, qd, omega, h) -> None:
    """Each mode's free vibration over h [s], exactly: (q, qd) turned by omega h (a rigid-
    body mode, omega = 0, drifts: q += h qd)."""
    for m in range(q.shape[0]):
        om = omega[m]
        if om == 0.0:
            q[m] += h * qd[m]
            continue
        c = math.cos(om * h)
        s = math.sin(om * h)
        q0 = q[m]
        q[m] = c * q0 + s * qd[m] / om
        qd[m] = -om * s * q0 + c * qd[m]


@njit(cache=True)
def predicted_velocity(b, hk, buf) -> None:
    """The modal velocity the force pass reads, qdp = qd + hk Phi^T F_n (the velocity at
    the step's end as the granules' is predicted, v + h/2 a_n)."""
    for m in range(b.qd.shape[0]):
        b.qdp[m] = b.qd[m] + hk * b.fmodal[buf, m]


@njit(cache=True)
def slip_row(b, buf, i, sx, sy, sz, row) -> float:
    """row[m] = (Phi^T (w (x) s))_m, the modes' share of a unit impulse along s at granule
    i's contact point; returns row . row, the body's mobility along s [kg^-1]."""
    for m in range(row.shape[0]):
        row[m] = 0.0
    spread(b, buf, i, sx, sy, sz, row, 1.0)
    mob = 0.0
    for m in range(row.shape[0]):
        mob += row[m] * row[m]
    return mob


@njit(cache=True)
def friction_flow(y, qd, dt, b, buf, radius, mass, inertia, arm_shrink, forward) -> float:
    """Friction alone over dt [s] at every contact in touch on the body (buffer buf, |N|
    held), one after the other (forward or reversed): the exact impulse of
    solver.granular.friction_impulse along the slip s = v_s / |v_s| against the mobility
    1/m + a^2/I + |Phi^T (w (x) s)|^2, on the granule and, opposite, on the modes qd.
    Returns the energy dissipated [J]: the kinetic energy the impulses removed."""
    ng = y.shape[0]
    nm = qd.shape[0]
    row = np.empty(nm)
    work = 0.0
    g = b.geo[buf]
    for kk in range(ng):
        i = kk if forward else ng - 1 - kk
        if g[i, GEO_TOUCH] == 0.0:
            continue
        c = b.coef[i]
        if c[COEF_MU] == 0.0 or g[i, GEO_N] <= 0.0:
            continue
        nx = -g[i, GEO_NX]  # from the granule into the body
        ny = -g[i, GEO_NY]
        nz = -g[i, GEO_NZ]
        a = contact_arm(radius[i], g[i, GEO_DELTA], arm_shrink)
        v0, v1, v2 = surface_velocity(b, buf, i, qd)
        vsx, vsy, vsz = slip_velocity_3d(
            y[i, VX] - v0,
            y[i, VX + 1] - v1,
            y[i, VX + 2] - v2,
            a * y[i, WX],
            a * y[i, WX + 1],
            a * y[i, WX + 2],
            nx,
            ny,
            nz,
        )
        speed = math.sqrt(vsx * vsx + vsy * vsy + vsz * vsz)
        if speed == 0.0:
            continue
        sx = vsx / speed
        sy = vsy / speed
        sz = vsz / speed
        mob = slip_row(b, buf, i, sx, sy, sz, row)
        inv_m = 1.0 / mass[i]
        inv_i = 1.0 / inertia[i]
        imp, _ = friction_impulse(speed, g[i, GEO_N], c[COEF_MU], c[COEF_KS], inv_m + a * a * inv_i + mob, dt)
        if imp == 0.0:
            continue
        ke0 = 0.0
        for col in range(3):
            ke0 += 0.5 * mass[i] * y[i, VX + col] ** 2 + 0.5 * inertia[i] * y[i, WX + col] ** 2
        px, py, pz = friction_along_slip(imp, speed, vsx, vsy, vsz)
        apply_friction_impulse(y, i, a, inv_m, inv_i, nx, ny, nz, px, py, pz, 1.0)
        ke1 = 0.0
        for col in range(3):
            ke1 += 0.5 * mass[i] * y[i, VX + col] ** 2 + 0.5 * inertia[i] * y[i, WX + col] ** 2
        dke = ke1 - ke0
        for m in range(nm):  # the body gets -P = imp s
            dv = imp * row[m]
            dke += dv * (qd[m] + 0.5 * dv)
            qd[m] += dv
        work -= dke
    return work


@njit(cache=True)
def replay(ys, qs, qds, b, radius, mass, clip, face_out, xi_out, force_out, normal_out) -> None:
    """The body's contacts at recorded states (ys (nt, ng, 9), qs, qds (nt, nm)), one time
    after the other (each search seeded by the last): face_out (nt, ng) the face touched
    (-1: none), xi_out (nt, ng, 2) the point's face coordinates, force_out (nt, ng, 3) the
    force on the body [N], normal_out (nt, ng) |N| [N]. Uses buffer 0 of b (a copy); an
    elastic-plastic law's largest overlap is the largest at the recorded times so far."""
    ng = ys.shape[1]
    acc = np.zeros((ng, ys.shape[2]))
    fdamp = np.zeros((ng, ys.shape[2]))
    for i in range(ng):
        b.hist[i, HIST_MAX] = 0.0
    for o in range(ys.shape[0]):
        contact_forces(ys[o], qs[o], qds[o], b, 0, radius, mass, clip, acc, fdamp, True)
        for i in range(ng):
            b.hist[i, HIST_MAX] = max(b.hist[i, HIST_MAX], b.hist[i, HIST_END])
        for i in range(ng):
            g = b.geo[0, i]
            touching = g[GEO_TOUCH] != 0.0 and g[GEO_N] > 0.0
            face_out[o, i] = b.face[0, i] if touching else -1
            xi_out[o, i, 0] = g[GEO_XI]
            xi_out[o, i, 1] = g[GEO_ETA]
            n = g[GEO_N] if touching else 0.0
            normal_out[o, i] = n
            force_out[o, i, 0] = -n * g[GEO_NX]
            force_out[o, i, 1] = -n * g[GEO_NY]
            force_out[o, i, 2] = -n * g[GEO_NZ]


@njit(cache=True)
def patch_loads(b, face, xi, force, out_t, out_col, out_val) -> int:
    """The nodal forces of recorded contact forces spread over their disc patches (b.patch
    > 0): face (nt, ng) the face each granule touches (-1: none), xi (nt, ng, 2) its point
    there, force (nt, ng, 3) [N] the (normal) force on the body, whose direction gives the
    surface's normal. Writes (time row, reduced dof, force [N]) triples into out_* (room for
    every touching contact's b.entry.shape[2] x 3) and returns how many. Uses buffer 0 of b
    (a copy)."""
    n_fn = b.face_nodes.shape[1]
    N = np.empty(n_fn)
    dN = np.empty((n_fn, 2))
    k = 0
    for t in range(face.shape[0]):
        for i in range(face.shape[1]):
            f = face[t, i]
            if f < 0:
                continue
            fx = force[t, i, 0]
            fy = force[t, i, 1]
            fz = force[t, i, 2]
            mag = math.sqrt(fx * fx + fy * fy + fz * fz)
            if mag == 0.0:
                continue
            face_shape_functions(b.kind[0], xi[t, i, 0], xi[t, i, 1], N, dN)
            x0 = x1 = x2 = 0.0
            for a in range(n_fn):
                x0 += N[a] * b.face_nodes[f, a, 0]
                x1 += N[a] * b.face_nodes[f, a, 1]
                x2 += N[a] * b.face_nodes[f, a, 2]
            disc_patch(b, 0, i, x0, x1, x2, -fx / mag, -fy / mag, -fz / mag)
            for e in range(b.count[0, i]):
                node = b.entry[0, i, e]
                w = b.weights[0, i, e]
                for c in range(3):
                    row = b.node_rows[node, c]
                    if row < 0:
                        continue
                    out_t[k] = t
                    out_col[k] = row
                    out_val[k] = w * (fx if c == 0 else (fy if c == 1 else fz))
                    k += 1
    return k
