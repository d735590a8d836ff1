"""Linear modes of an assembly about its static state (docs/model.md section 3.13).

Small motions u of the granules' centres about the static state (the scenario's
[precompression] equilibrium, `model.static`, or the positions given) obey M u'' + K u = 0,
with M the granules' masses (translations; without friction a contact exerts no torque, so
spins decouple with zero stiffness) and K the contacts' normal stiffness

    K = sum over contacts k_c (e_i - e_j)(e_i - e_j)^T (x) n n^T,   k_c = dN/d delta = (3/2) A delta^(1/2)   (M1)

(a wall contact: e_i alone; the granule-granule and granule-wall contacts in touch at the
static state). The transverse stiffness of the contact forces (-N/|d| (I - n n^T), which
makes a compressed straight chain neutral or unstable sideways) is left out, as the linear
theory of granular crystals does. The frequencies are f = sqrt(lambda) / (2 pi) of the
generalised eigenproblem K v = lambda M v (scipy: dense `eigh` up to DENSE_MAX unknowns,
else `eigsh` in shift-invert about 0 with a fixed start vector for the lowest `count`).
Directions without stiffness (a granule free to slide sideways, rattlers) give lambda = 0:
`zero_modes` counts them. Contacts with no overlap carry no stiffness: an assembly that is
not precompressed (and not under gravity) has only zero modes.

For a monatomic chain of masses m and contact stiffness k the modes fill the acoustic band
up to the cut-off f_c = (1/pi) sqrt(k/m); a diatomic chain (masses m1 > m2) has an acoustic
band up to sqrt(2k/m1)/(2 pi), a gap, and an optical band from sqrt(2k/m2)/(2 pi) to
sqrt(2k (1/m1 + 1/m2))/(2 pi) (`chain_band_edges`).

With the plane's plate (a 2D [plate]) the plate's mass-normalised modal coordinates q join the
unknowns (its block of M the identity, of K diag(omega^2)), and each plate contact (a rigid
layer, n = (1, 0)) couples the granule's x-displacement s to the plate's normal displacement
there, Phi_n q + R_n F (the kept modes' shapes at the contact's driving dof and a truncated
basis' residual compliance, massless): its spring k_c in series with R_n, condensed statically,

    K += B^T K_e B,   K_e = (I + K_s R_n)^-1 K_s,   B (s, q) = s - Phi_n q                    (M2)

(K_s = diag(k_c) at the static overlaps, the plate deflected at rest; with every mode kept
R_n = 0 and the plate is its finite-element model exactly). Solved densely (`eigh`; beyond
DENSE_MAX unknowns the lowest `count`, 50 by default, by `subset_by_index`).

An elastic solid in space (the [plate] of a 3D scenario, `model.body`) joins the same way
(`body_contacts`, `body_coupled_stiffness`): its kept M-orthonormal modes q (M the identity,
K diag(omega^2); a free body's rigid modes at 0), and each granule-solid contact, found by the
loop's own contact pass (solver.body: the closest point of the surface, its outward normal n,
its patch's weights w_a over the surface nodes, the overlap with the residual in series),
couples the granule's displacement along n to the surface's normal displacement there:

    K += B^T K_e B,   K_e = (I + K_s R_n)^-1 K_s,   B (u, q) = n . u_i - phi_n q,
    phi_n = n . sum_a w_a Phi_a,   (R_n)_kj = r_k^T R_S r_j                               (M4)

(K_s = diag((3/2) A delta^(1/2)) at the overlaps at t = 0, the body at its modal state then: a
scenario with a solid has no [precompression]; R_S the residual compliance over the face's
normal dofs, r_k contact k's normal times its weights there; the tangential stiffness of the
deformed surface's tilt left out, as the transverse terms are).

A piston (a force-driven wall, or the held precompression wall; `pistons_of`) is one more
unknown, its displacement s along its drive's direction e, of mass M: a contact of granule i on
its wall (normal n, stiffness k_c) changes its overlap by n . u_i + c s, c = -n . e,

    K[i, i] += k_c n n^T,   K[i, s] = K[s, i]^T += k_c c n,   K[s, s] += k_c c^2          (M3)

(`with_pistons`); its share of a mode is `Modes.pistons`. Walls under displacement or velocity
drives, and frozen ones, are fixed; a granule under a displacement or velocity drive moves
only across the drive's direction (`held_directions`, the static state's basis).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np


#: the most unknowns solved densely (all modes); beyond, the lowest `count` by eigsh
DENSE_MAX = 3000
#: lambda below this fraction of the largest is a zero mode
ZERO_RTOL = 1e-10


class Modes(NamedTuple):
    """frequencies: (n,) [Hz], ascending, zero modes included (as 0); shapes: (n, ng, d) the
    M-orthonormal mode shapes [kg^-1/2]; zero_modes: how many have no stiffness;
    contacts: the contacts in touch that give K (the plate's included); plate: (n, nm) the
    plate's modal coordinates q of each M-orthonormal mode [-] (in space the elastic solid's,
    the [plate] of a 3D scenario; (0, 0) without a plate);
    pistons: (n, np) each piston's displacement along its drive's direction in each
    M-orthonormal mode [kg^-1/2] ((0, 0) without one); piston_walls: (np,) their walls'
    indices in the scenario; piston_mass: (np,) their masses [kg]."""

    frequencies: np.ndarray
    shapes: np.ndarray
    zero_modes: int
    contacts: int
    plate: np.ndarray = np.zeros((0, 0))
    pistons: np.ndarray = np.zeros((0, 0))
    piston_walls: np.ndarray = np.zeros(0, np.int64)
    piston_mass: np.ndarray = np.zeros(0)


class Pistons(NamedTuple):
    """The pistons of the granular arrays (force-driven walls, the held precompression wall's
    included, model.drives `with_piston`): walls (np,) their indices in the scenario; mass (np,)
    [kg]; direction (np, d) the unit direction e their drive pushes along."""

    walls: np.ndarray
    mass: np.ndarray
    direction: np.ndarray


def pistons_of(g) -> Pistons:
    """The pistons of the granular arrays g: every force drive on a wall (its mass PAR_MASS)."""
    from granplate.physics.drives import KIND_FORCE, PAR_MASS

    k = np.flatnonzero((g.drive_target < 0) & (g.drive_kind == KIND_FORCE))
    d = g.wall_geo.shape[1] - 1
    return Pistons(
        (-1 - g.drive_target[k]).astype(np.int64),
        np.asarray(g.drive_par[k, PAR_MASS], float),
        np.asarray(g.drive_dir, float).reshape(-1, d)[k],
    )


def with_pistons(g, x: np.ndarray, k_granules, pistons: Pistons):
    """K of (M1) over the granules' centres x (ng, d) [m] with each piston's displacement s
    along its direction e as one more unknown (M3): a contact of granule i on the piston's
    wall, of normal n and stiffness k_c, has the overlap's change n . u_i + c s, c = -n . e, and
    adds k_c c n to the (i, s) block and k_c c^2 to (s, s). A sparse (ng d + np, ng d + np)
    matrix [N/m]."""
    from scipy.sparse import bmat, coo_matrix

    from granplate.model.static import contact_terms

    d = x.shape[1]
    size, npist = len(g.mass) * d, len(pistons.walls)
    _, (wi, _, _, wk, wn, _, _) = contact_terms(x, 0.0, g, -1)
    rows, cols, vals = [], [], []
    diag = np.zeros(npist)
    for p, (w, e) in enumerate(zip(pistons.walls, pistons.direction)):
        on = g.wall_w == w
        c = -wn[on] @ e
        for q in range(d):
            rows.append(wi[on] * d + q)
            cols.append(np.full(int(on.sum()), p))
            vals.append(wk[on] * c * wn[on, q])
        diag[p] = float(np.sum(wk[on] * c * c))
    coupling = coo_matrix(
        (
            np.concatenate(vals or [np.zeros(0)]),
            (np.concatenate(rows or [np.zeros(0, int)]), np.concatenate(cols or [np.zeros(0, int)])),
        ),
        shape=(size, npist),
    )
    return bmat([[k_granules, coupling], [coupling.T, coo_matrix(np.diag(diag))]]).tocsr()


def stiffness_matrix(g, x: np.ndarray):
    """K of (M1) over the granules' centres x (ng, d) [m] of the granular arrays g, as a sparse
    (ng d, ng d) matrix [N/m], and the number of contacts in touch."""
    from scipy.sparse import coo_matrix

    from granplate.model.static import contact_terms

    d = x.shape[1]
    # every wall at its own offset (no wall is the servo's: index -1)
    (i, j, delta, _, k, n, _), (wi, wdelta, _, wk, wn, _, _) = contact_terms(x, 0.0, g, -1)
    rows, cols, vals = [], [], []
    for p in range(d):
        for q in range(d):
            kp = k * n[:, p] * n[:, q]
            for a, b, sign in ((i, i, 1.0), (j, j, 1.0), (i, j, -1.0), (j, i, -1.0)):
                rows.append(a * d + p)
                cols.append(b * d + q)
                vals.append(sign * kp)
            rows.append(wi * d + p)
            cols.append(wi * d + q)
            vals.append(wk * wn[:, p] * wn[:, q])
    size = len(g.mass) * d
    K = coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(size, size)).tocsr()
    return K, int(np.count_nonzero(delta > 0.0) + np.count_nonzero(wdelta > 0.0))


def linear_modes(model, count: int | None = None) -> Modes:
    """The modes (M1) of a built model (`model.arrays.build_model`: precompressed when its
    scenario says so) about its initial positions; `count`: the lowest count (None: all, up to
    DENSE_MAX unknowns)."""
    from scipy.linalg import eigh

    g = model.granular
    d = g.wall_geo.shape[1] - 1
    x = np.ascontiguousarray(model.initial_state[:, :d])
    K, touching = stiffness_matrix(g, x)
    pistons = pistons_of(g)
    K = with_pistons(g, x, K, pistons)
    body = getattr(model, "body", None)
    if (getattr(model, "plate", None) is not None and len(model.plate_arrays.omega2)) or body is not None:
        m = np.concatenate([np.repeat(g.mass, d), pistons.mass])
        return coupled_modes(model, K, m, touching, count, pistons)
    free, m = held_directions(g, d, pistons.mass)
    K = (free.T @ K @ free).tocsr()  # a driven granule's prescribed direction is no unknown
    size = len(m)
    w = 1.0 / np.sqrt(m)
    if size <= DENSE_MAX:
        lam, v = eigh((K.toarray() * w[:, None]) * w[None, :])
    else:
        from scipy.sparse import diags
        from scipy.sparse.linalg import eigsh

        want = min(count or 50, size - 2)
        sym = diags(w) @ K @ diags(w)
        v0 = np.ones(size) / math.sqrt(size)  # a fixed start vector: the same modes on every run
        lam, v = eigsh(sym.tocsc(), k=want, sigma=-1e-9 * float(abs(sym).max()), which="LM", v0=v0)
        order = np.argsort(lam)
        lam, v = lam[order], v[:, order]
    top = float(np.max(np.abs(lam))) if len(lam) else 0.0
    zero = np.abs(lam) <= ZERO_RTOL * max(top, 1e-300)
    lam = np.where(zero, 0.0, lam)
    freq = np.sqrt(np.maximum(lam, 0.0)) / (2.0 * math.pi)
    z = (free @ (v * w[:, None])).T
    ng = len(g.mass) * d
    shapes, on_pistons = z[:, :ng].reshape(len(lam), len(g.mass), d), np.ascontiguousarray(z[:, ng:])
    if count is not None:
        freq, shapes, on_pistons = freq[:count], shapes[:count], on_pistons[:count]
    return Modes(
        freq, shapes, int(np.count_nonzero(zero)), touching, np.zeros((0, 0)), *_piston_fields(on_pistons, pistons)
    )


def held_directions(g, d: int, extra_mass: np.ndarray):
    """(P, m): the unknowns' basis P, a sparse (ng d + ne, nf + ne) matrix with orthonormal
    columns (`model.static.granule_freedom`: a granule under a displacement or velocity drive
    moves only across its drive's direction, its motion along it being prescribed; the ne
    unknowns after the granules', the pistons', as they are), and each column's mass m
    (nf + ne,) [kg]: its granule's, then extra_mass (ne,)."""
    from scipy.sparse import block_diag, identity

    from granplate.model.static import granule_freedom

    t = granule_freedom(g, d)
    mass = np.asarray(t.multiply(t).T @ np.repeat(np.asarray(g.mass, float), d)).ravel()
    ne = len(extra_mass)
    basis = block_diag([t, identity(ne)], format="csr") if ne else t.tocsr()
    return basis, np.append(mass, np.asarray(extra_mass, float))


def _piston_fields(on_pistons: np.ndarray, pistons: Pistons) -> tuple:
    """Modes' pistons, piston_walls and piston_mass ((0, 0) shapes without a piston)."""
    if not len(pistons.walls):
        return np.zeros((0, 0)), pistons.walls, pistons.mass
    return on_pistons, pistons.walls, pistons.mass


def plate_contact_stiffness(g, p, x: np.ndarray, u0: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """The plate contacts' granules (nk,) and their springs in series with the plate's residual
    compliance, K_e = (I + K_s R_n)^-1 K_s of (M2) (nk, nk) [N/m], K_s = diag((3/2) A
    delta^(1/2)) at the overlaps of centres x (ng, d) [m] against the plate displaced by u0
    (nk,) [m] at its contacts (p: model.inputs.PlateArrays); and how many are in touch."""
    from granplate.model.static import plate_terms

    pi, pdelta, _, pk, _ = plate_terms(x, u0, g)
    ks = np.diag(pk)
    if p.resid.shape[0] and len(pi):
        rn = np.asarray(p.resid, float)[0::2, 0::2]
        ke = np.linalg.solve(np.eye(len(pi)) + ks @ rn, ks)
        ks = 0.5 * (ke + ke.T)  # symmetric in exact arithmetic: (I + K R)^-1 K = K (I + R K)^-1
    return pi, ks, int(np.count_nonzero(pdelta > 0.0))


class BodyContacts(NamedTuple):
    """The granules' contacts in touch on an elastic body in space (docs/model.md section
    3.13, eq. M4): granule (nk,) their granules; normal (nk, 3) the body's outward normal at
    each contact point; phi_n (nk, nm) the kept modes' normal displacement there, n . sum_a w_a
    Phi_a [kg^-1/2]; overlap (nk,) [m] each one's overlap (the residual's share taken off,
    as the loop's contact pass finds it); k_s (nk,) the Hertz tangents (3/2) A delta^(1/2)
    [N/m]; r_n (nk, nk) the residual compliance between the contact points' normal
    displacements [m/N] ((0, 0) without one); k_e (nk, nk) the springs in series with it,
    (I + K_s R_n)^-1 K_s [N/m]."""

    granule: np.ndarray
    normal: np.ndarray
    phi_n: np.ndarray
    overlap: np.ndarray
    k_s: np.ndarray
    r_n: np.ndarray
    k_e: np.ndarray


def body_contacts(model, x: np.ndarray) -> BodyContacts:
    """The contacts of the granules at centres x (ng, 3) [m] on the model's elastic body at
    its modal state at t = 0 (solver.body's own contact pass: each granule's closest point,
    its patch's weights, the overlap with the residual compliance in series; the body's modes
    at their static state, `plate_q0`, under its weight and a [precompression]'s contact
    forces, model.body_static, else undeformed)."""
    from granplate.model.inputs import GEO_DELTA, GEO_NX, GEO_NZ, GEO_TOUCH, new_body_state
    from granplate.physics.contact import COEF_A
    from granplate.solver import body as sb

    g = model.granular
    b = new_body_state(model.body)
    y = np.zeros((len(g.mass), 9))
    y[:, :3] = x
    acc, fdamp = np.zeros_like(y), np.zeros_like(y)
    q0 = b.q.copy() if model.plate_q0 is None else np.ascontiguousarray(model.plate_q0, float)
    sb.contact_forces(y, q0, np.zeros_like(b.q), b, 0, g.radius, g.mass, False, acc, fdamp, False)
    geo = b.geo[0]
    granule = np.flatnonzero((geo[:, GEO_TOUCH] != 0.0) & (geo[:, GEO_DELTA] > 0.0))
    nk, nm = len(granule), len(b.omega)
    normal = np.ascontiguousarray(geo[granule, GEO_NX : GEO_NZ + 1])
    phi_n = np.zeros((nk, nm))
    for k, i in enumerate(granule):
        sb.spread(b, 0, i, normal[k, 0], normal[k, 1], normal[k, 2], phi_n[k], 1.0)
    overlap = geo[granule, GEO_DELTA].copy()
    k_s = 1.5 * b.coef[granule, COEF_A] * np.sqrt(overlap)
    r_n = body_residual(b, granule)
    k_e = np.diag(k_s)
    if r_n.shape[0]:
        ke = np.linalg.solve(np.eye(nk) + k_s[:, None] * r_n, k_e)
        k_e = 0.5 * (ke + ke.T)
    return BodyContacts(granule, normal, phi_n, overlap, k_s, r_n, k_e)


def body_residual(b, granule: np.ndarray) -> np.ndarray:
    """R_n (nk, nk) [m/N]: r_k^T R_S r_j between the contacts of `granule`, located in buffer
    0 of the body arrays b (solver.body's residual rows, each contact's normal times its
    weights on the residual dofs S); (0, 0) without a residual compliance."""
    from granplate.solver import body as sb

    nk, n_s = len(granule), b.resid.shape[0]
    if not n_s or not nk:
        return np.zeros((0, 0))
    counts = np.zeros(nk, np.int64)
    for k, i in enumerate(granule):
        b.active[k] = i
        counts[k] = sb.residual_rows(b, 0, i, k)
    upos, ulist = np.full(n_s, -1, np.int64), np.empty(n_s, np.int64)
    n_u = sb.touched_dofs(b, nk, counts, upos, ulist)
    rmat = np.zeros((nk, nk))
    sb.residual_matrix(b, nk, counts, upos, ulist, n_u, np.empty((nk, n_u)), rmat)
    return rmat


def coupled_stiffness(model, k_granules, x: np.ndarray) -> tuple[np.ndarray, int]:
    """The dense stiffness (nd + nm, nd + nm) [N/m, and 1/s^2 in the plate's block] of the
    granules (k_granules, (M1), nd unknowns: the granules' ng d, the pistons' after them, (M3))
    and the plate in modal coordinates (the plane's, or a 3D scenario's elastic body),
    coupled by its contacts (M2, M4); and the plate contacts in touch."""
    if getattr(model, "body", None) is not None:
        return body_coupled_stiffness(model, k_granules, x)
    g, p = model.granular, model.plate_arrays
    d = x.shape[1]
    nd, nm = k_granules.shape[0], len(p.omega2)
    u0 = np.zeros(len(g.pc_i)) if model.plate_u0 is None else np.asarray(model.plate_u0, float)[0::2]
    pi, ke, touching = plate_contact_stiffness(g, p, x, u0)
    k = np.zeros((nd + nm, nd + nm))
    k[:nd, :nd] = k_granules.toarray()
    k[nd:, nd:] = np.diag(np.asarray(p.omega2, float))
    b = np.zeros((len(pi), nd + nm))
    b[np.arange(len(pi)), pi * d] = 1.0  # the granule's x-displacement
    b[:, nd:] = -np.asarray(p.phi_d, float)[0::2]  # minus the plate's at the contact
    k += b.T @ ke @ b
    return k, touching


def body_coupled_stiffness(model, k_granules, x: np.ndarray) -> tuple[np.ndarray, int]:
    """`coupled_stiffness` with an elastic body in space (M4): its modal block diag(omega^2),
    and each contact's spring in series with the residual, B^T K_e B, B (u, q) = n . u_i -
    phi_n q; and the body's contacts in touch."""
    c = body_contacts(model, x)
    nd, nm = k_granules.shape[0], len(model.body.omega)
    k = np.zeros((nd + nm, nd + nm))
    k[:nd, :nd] = k_granules.toarray()
    k[nd:, nd:] = np.diag(np.asarray(model.body.omega, float) ** 2)
    b = np.zeros((len(c.granule), nd + nm))
    for q in range(3):
        b[np.arange(len(c.granule)), c.granule * 3 + q] = c.normal[:, q]  # the granule's normal displacement
    b[:, nd:] = -c.phi_n  # minus the surface's there
    k += b.T @ c.k_e @ b
    return k, len(c.granule)


def coupled_modes(model, k_granules, mass: np.ndarray, touching: int, count: int | None, pistons: Pistons) -> Modes:
    """The modes (M1)-(M3) of the granules (and pistons: k_granules and mass over both) and
    the plane's plate together (dense `eigh`; beyond DENSE_MAX unknowns the lowest `count`,
    50 by default)."""
    from scipy.linalg import eigh

    g = model.granular
    d = g.wall_geo.shape[1] - 1
    x = np.ascontiguousarray(model.initial_state[:, :d])
    k, on_plate = coupled_stiffness(model, k_granules, x)
    ng, nd = len(g.mass) * d, len(mass)
    free, m = held_directions(g, d, mass[ng:])  # a driven granule's prescribed direction is no unknown
    basis = np.zeros((k.shape[0], len(m) + k.shape[0] - nd))
    basis[:nd, : len(m)] = free.toarray()
    basis[nd:, len(m) :] = np.eye(k.shape[0] - nd)
    k = basis.T @ k @ basis
    w = np.concatenate([1.0 / np.sqrt(m), np.ones(k.shape[0] - len(m))])
    sym = (k * w[:, None]) * w[None, :]
    if len(w) <= DENSE_MAX:
        lam, v = eigh(sym)
    else:
        want = min(count or 50, len(w))
        lam, v = eigh(sym, subset_by_index=[0, want - 1])
    top = float(np.max(np.abs(lam))) if len(lam) else 0.0
    zero = np.abs(lam) <= ZERO_RTOL * max(top, 1e-300)
    lam = np.where(zero, 0.0, lam)
    freq = np.sqrt(np.maximum(lam, 0.0)) / (2.0 * math.pi)
    z = basis @ (v * w[:, None])
    shapes, plate = z[:ng].T.reshape(len(lam), len(g.mass), d), np.ascontiguousarray(z[nd:].T)
    on_pistons = np.ascontiguousarray(z[ng:nd].T)
    if count is not None:
        freq, shapes, plate, on_pistons = freq[:count], shapes[:count], plate[:count], on_pistons[:count]
    return Modes(
        freq, shapes, int(np.count_nonzero(zero)), touching + on_plate, plate, *_piston_fields(on_pistons, pistons)
    )


def chain_band_edges(k: float, m1: float, m2: float | None = None) -> dict[str, float]:
    """The band edges [Hz] of an infinite chain of contact stiffness k [N/m]: monatomic (m2
    None) its cut-off (1/pi) sqrt(k/m1); diatomic (masses m1, m2) the acoustic band's top, the
    optical band's bottom and top."""
    if m2 is None:
        return {"cutoff": math.sqrt(k / m1) / math.pi}
    heavy, light = max(m1, m2), min(m1, m2)
    return {
        "acoustic_top": math.sqrt(2.0 * k / heavy) / (2.0 * math.pi),
        "optical_bottom": math.sqrt(2.0 * k / light) / (2.0 * math.pi),
        "optical_top": math.sqrt(2.0 * k * (1.0 / m1 + 1.0 / m2)) / (2.0 * math.pi),
    }
