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
granule pairs (solver.friction_space.friction_flow): an exact impulse along the slip, against
the granule's and the body's mobility along it, booked as the kinetic energy it removes.

The pieces have modules of their own, their names importable from here too: where a
granule touches the surface (`body_surface`), the residual compliance in series
(`body_residual`), the modes' kicks and turns (`body_modes`) and the friction
(`body_friction`).
"""

from __future__ import annotations

import math

import numpy as np
from granplate.jit import njit
from numba.extending import overload

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
    NoBodyArrays,
)
from granplate.physics.laws import normal_law_response, normal_law_slopes
from granplate.physics.space import normal_rate_3d, surface_overlap
from granplate.solid.surface import face_shape_functions
from granplate.solver.granular3d import VX, X

# the pieces, in modules of their own, importable from here as before
from granplate.solver.body_friction import friction_flow as friction_flow, slip_row as slip_row
from granplate.solver.body_modes import kick as kick, load_kick as load_kick
from granplate.solver.body_modes import predicted_velocity as predicted_velocity, turn as turn
from granplate.solver.body_modes import turn_weighed as turn_weighed
from granplate.solver.body_residual import NEWTON_RTOL as NEWTON_RTOL, NEWTON_STEPS as NEWTON_STEPS
from granplate.solver.body_residual import RESID_RTOL as RESID_RTOL, RESID_SWEEPS as RESID_SWEEPS
from granplate.solver.body_residual import residual_load, residual_matrix, residual_rows, residual_tilt
from granplate.solver.body_residual import solve_static, static_overlap as static_overlap, touched_dofs
from granplate.solver.body_surface import disc_patch, locate, near_box, normal_motion
from granplate.solver.body_surface import patch_frame as patch_frame, spread as spread, spread_both
from granplate.solver.body_surface import surface_velocity, tangent_map as tangent_map

#: A granule is located on the surface when its centre lies within REACH radii of the
#: body's bounding box (a surface that moves out of the box by more than REACH - 1 radii
#: towards a granule would be missed).
REACH = 2.0


def by_body(b, with_body, body_args, without, plain_args):
    """with_body(*body_args) in a run with an elastic body, without(*plain_args) in one
    without (b of type model.inputs.NoBodyArrays): chosen when the loop compiles, so that
    a run without a body never compiles the body's code (it doubled the loop's compile
    time)."""
    raise NotImplementedError("compiled use only")


@overload(by_body, inline="always")
def _by_body(b, with_body, body_args, without, plain_args):
    if getattr(b, "instance_class", None) is NoBodyArrays:
        return lambda b, with_body, body_args, without, plain_args: without(*plain_args)
    return lambda b, with_body, body_args, without, plain_args: with_body(*body_args)


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


@njit(refcount=True, cache=True, inline="always")
def touching_contacts(y, q, b, buf, radius, delta0) -> int:
    """Each granule of state y (ng, 9) within REACH R of the body's bounding box located on
    its surface (buffer buf; every granule's row of geo and its HIST_END cleared first), and
    those whose overlap without the residual, delta0 = R - d + n . u_c [m], is positive
    listed in b.active with it in delta0; returns how many."""
    n_fn = b.face_nodes.shape[1]
    out = np.empty(9)
    N = np.empty(n_fn)
    dN = np.empty((n_fn, 2))
    p = np.empty(3)
    n_act = 0
    g = b.geo[buf]
    for i in range(y.shape[0]):
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
    return n_act


@njit(refcount=True, cache=True, inline="always")
def static_in_series(b, buf, n_act, delta0, clip, counts, upos):
    """The static forces of the n_act contacts in touch with the residual compliance in
    series (`solve_static`; without a residual, N_k = F(delta0_k)): counts[k] the terms of
    contact k's row on the residual dofs, upos their positions among the touched dofs.
    Returns (the residual's energy [J], R_kj between the contacts [m/N], z = R_S sum_k r_k
    N_k on the touched dofs [m])."""
    e_static = 0.0
    resid = b.resid.shape[0] > 0
    n_s = b.resid.shape[0]
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
    return e_static, rmat, z


@njit(cache=True, inline="always")
def contact_response(k, y, qd, b, buf, mass, clip, acc, fdamp, scale_acc, rmat, counts, upos, z, tilt):
    """Contact k in touch (granule i = b.active[k], overlap delta > 0 in geo): the law's force
    N at (delta, its rate against the surface's velocity, the residual's share taken off),
    the force on the granule, N n plus the static force's pull along the deformed surface's
    tilt and the residual's weights (what makes the contact's work exact), into acc (/ m_i
    when scale_acc) and its damping part into fdamp; -N n and -D n spread on the modes.
    Returns (stored elastic energy [J], viscous power [W], plastic work [J])."""
    i = b.active[k]
    g = b.geo[buf]
    resid = b.resid.shape[0] > 0
    delta = g[i, GEO_DELTA]
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
    return ep, pv, wp


@njit(refcount=True, cache=True)
def contact_forces(y, q, qd, b, buf, radius, mass, clip, acc, fdamp, scale_acc):
    """The body's contact forces at granule state y (ng, 9), modal displacement q and
    velocity qd (nm,) into buffer buf: each granule within REACH R of the body's bounding
    box located on its surface (`touching_contacts`), the overlaps with the residual
    compliance in series (`static_in_series`), the law's forces (`contact_response`:
    damping at the overlap rate against the surface's velocity); acc[i, VX..VZ] gains
    N n / m_i (scale_acc True) or N n; fdamp[i, VX..VZ] the damping part [N];
    b.fmodal[buf], b.fdamp[buf] the modal projections of the forces on the body. The
    contacts' overlaps go to hist[:, HIST_END].

    Returns (stored elastic energy of the contacts [J], viscous power [W], plastic work past
    the largest overlaps [J], the residual's energy [J], the largest overlap / radius, its
    granule)."""
    for m in range(q.shape[0]):
        b.fmodal[buf, m] = 0.0
        b.fdamp[buf, m] = 0.0
    ng = y.shape[0]
    delta0 = np.empty(max(ng, 1))
    n_act = touching_contacts(y, q, b, buf, radius, delta0)
    counts = np.zeros(max(ng, 1), np.int64)
    upos = np.full(b.resid.shape[0], -1, np.int64)
    e_static, rmat, z = static_in_series(b, buf, n_act, delta0, clip, counts, upos)
    tilt = np.zeros(3)
    e_pot = 0.0
    p_visc = 0.0
    w_plastic = 0.0
    ovl = 0.0
    ovl_i = -1
    g = b.geo[buf]
    for k in range(n_act):
        i = b.active[k]
        delta = g[i, GEO_DELTA]
        b.hist[i, HIST_END] = delta
        if delta <= 0.0:
            continue
        ep, pv, wp = contact_response(k, y, qd, b, buf, mass, clip, acc, fdamp, scale_acc, rmat, counts, upos, z, tilt)
        e_pot += ep
        p_visc += pv
        w_plastic += wp
        if delta > ovl * radius[i]:
            ovl = delta / radius[i]
            ovl_i = i
    b.static[buf] = e_static
    return e_pot, p_visc, w_plastic, e_static, ovl, ovl_i


@njit(entry=True, cache=True)
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


@njit(entry=True, cache=True)
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
