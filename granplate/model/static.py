"""Static precompression (docs/model.md section 3.12): the assembly at rest under a wall's
force, the state a precompressed run starts from.

The granules' centres X and the target wall's offset o minimise the potential energy

    Pi(X, o, u) = sum over contacts (2/5) A delta^(5/2) - sum_i m_i g . x_i + F o + 1/2 u^T K_c u   (S1)

(Hertz's energy of eq. 9 at every granule-granule, granule-wall and granule-plate contact in
the model's lists, gravity's potential, the servo's: the wall, whose unit normal n points out
of the assembly, is pushed inwards with the force F, so its offset o along n falls while the
contacts on it carry less than F; and the plate's strain energy, the plate condensed to the
normal displacements u of its contacts, K_c the inverse of its static compliance there, the
modes' and the residual's, `plate_compliance`). At the minimum every granule's net force
vanishes, the wall's contacts carry F and the plate's contacts carry K_c u:

    sum_j A delta_ij^(3/2) n_ij + sum_walls A delta^(3/2) (-n) + m_i g = 0,
    sum over the wall's contacts A delta^(3/2) = F,  A delta_k^(3/2) = (K_c u)_k        (S2)

Its gradient is the residual of (S2). It is minimised by L-BFGS (scipy) from the given
positions, then polished by Newton steps on the contacts' normal stiffness 3/2 A
delta^(1/2) n n^T (a positive semi-definite matrix, the transverse geometric terms left
out, so that every step descends) until the largest residual force is below tolerance x F.
A granule under a displacement or velocity drive is held along the drive's direction only
(its prescribed motion starts there) and free across it; a granule under a force drive is
free, the drive's value at t = 0, P(0) e, a load in (S1) (-P(0) e . x_i: the rest state the
run starts from, nothing when the profile starts at 0). A force-driven wall (a piston) is a
servo as the target is, pushing with its drive's value at t = 0 (`static_pistons`); the
other walls stay at their offsets (a displacement- or velocity-driven wall starts where the
scenario puts it) and are supports, as are the held granules and the plate. The laws of
friction do not enter: the static state is frictionless (friction needs a history that
precompression does not have).

Pure functions of the model's arrays (no I/O): `static_state` returns the equilibrium and
`precompressed` the model that starts from it.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from granplate.errors import ScenarioError, SimulationError
from granplate.physics.contact import COEF_A


class StaticState(NamedTuple):
    """The static equilibrium of `static_state`.

    positions: (ng, d) the granules' centres [m]; offset: the target wall's offset along its
    unit normal [m] (shifted from `offset0` by the precompression); residual: the largest
    net force on a granule, the wall or the plate over F [-]; iterations: the minimiser's and
    Newton's steps; wall_force: the force the wall's contacts carry [N] (F to the residual);
    plate_u: (nk,) the plate's normal displacement at each plate contact [m] and plate_force:
    (nk,) the normal force each contact puts on the plate [N] (empty without a plate);
    pistons: the force-driven walls held as servos (`static_pistons`) and piston_offsets (np,)
    their offsets at rest [m]."""

    positions: np.ndarray
    offset: float
    offset0: float
    residual: float
    iterations: int
    wall_force: float
    plate_u: np.ndarray = np.zeros(0)
    plate_force: np.ndarray = np.zeros(0)
    pistons: Pistons | None = None
    piston_offsets: np.ndarray = np.zeros(0)


class PlateStatics(NamedTuple):
    """The plate condensed to the normal dofs of its nk contacts (docs/model.md section 3.12).

    compliance: (2 nk, 2 nk) the static compliance at the contacts' driving dofs [m/N] (x, y
    of each), Phi_d diag(1/omega^2) Phi_d^T + R: the loop's own modal model at rest;
    stiffness: (nk, nk) the inverse of its normal block [N/m], K_c of (S1); direction: (nk, d)
    each contact's unit normal into the plate (None: the plane's plate, e_x; an elastic solid
    in space, model.body_static: minus the surface's outward normal)."""

    compliance: np.ndarray
    stiffness: np.ndarray
    direction: np.ndarray | None = None


def plate_statics(p) -> PlateStatics:
    """The static compliance and condensed stiffness of the plate arrays p (model.inputs.
    PlateArrays): the modes' share Phi_d diag(1/omega^2) Phi_d^T plus a truncated basis'
    residual compliance R (docs/model.md section 4.5). ScenarioError naming plate.n_modes
    when the kept modes leave a contact without stiffness (a dense basis cut too short)."""
    phi = np.asarray(p.phi_d, float)
    c = (phi / np.asarray(p.omega2, float)[None, :]) @ phi.T
    if p.resid.shape[0]:
        c = c + np.asarray(p.resid, float)
    cn = c[0::2, 0::2]
    if cn.shape[0] and np.linalg.cond(cn) > 1e12:
        raise ScenarioError(
            "plate.n_modes",
            cn.shape[0],
            "the kept modes give the plate's contacts no independent static stiffness, which "
            "[precompression] needs: keep every mode (plate.n_modes = 0) or the truncated basis",
        )
    return PlateStatics(compliance=c, stiffness=np.linalg.inv(cn) if cn.shape[0] else np.zeros((0, 0)))


def contact_terms(x: np.ndarray, o, g, wall):
    """Overlaps, forces, slopes and normals of every listed pair and wall contact at centres x
    and the servo walls' offsets o (a wall index `wall` and its offset, or arrays of them, the
    target's first; -1: none): (pairs: i, j, delta, f, k, n) and (walls: i, delta, f, k, n,
    on_target)."""
    r = g.radius
    i, j = g.pair_ij[:, 0], g.pair_ij[:, 1]
    d = x[i] - x[j]
    dist = np.linalg.norm(d, axis=1)
    n = d / np.where(dist > 0.0, dist, 1.0)[:, None]
    delta = np.maximum(r[i] + r[j] - dist, 0.0)
    a = g.pair_coef[:, COEF_A]
    f, k = a * delta**1.5, 1.5 * a * np.sqrt(delta)
    d_ = x.shape[1]
    wi = g.wall_i
    wn = g.wall_geo[:, :d_]
    walls = np.atleast_1d(np.asarray(wall, np.int64))
    off = g.wall_geo[:, d_].copy()
    for w, v in zip(walls, np.broadcast_to(np.asarray(o, float), walls.shape)):
        off[g.wall_w == w] = v
    wdelta = np.maximum(r[wi] + np.einsum("kd,kd->k", x[wi], wn) - off, 0.0)
    wa = g.wall_coef[:, COEF_A]
    wf, wk = wa * wdelta**1.5, 1.5 * wa * np.sqrt(wdelta)
    return (i, j, delta, f, k, n, a), (wi, wdelta, wf, wk, wn, g.wall_w == walls[0], wa)


def plate_terms(x: np.ndarray, u: np.ndarray, g, direction=None):
    """Overlaps, forces and slopes of the plate contacts (rigid layers, n = (1, 0); docs/model.md
    section 3.4; or along `direction` (nk, d), each contact's unit normal into the plate) at
    centres x and the plate's normal displacements u at them: (i, delta, f, k, a)."""
    pi = np.asarray(getattr(g, "pc_i", np.zeros(0, np.int64)), np.int64)
    if not len(pi):
        z = np.zeros(0)
        return pi, z, z, z, z
    pa = g.pc_coef[:, COEF_A]
    along = x[pi, 0] if direction is None else np.einsum("kd,kd->k", x[pi], direction)
    pdelta = np.maximum(along + g.radius[pi] - (g.pc_x + u), 0.0)
    return pi, pdelta, pa * pdelta**1.5, 1.5 * pa * np.sqrt(pdelta), pa


def energy_and_forces(x: np.ndarray, o, g, wall, force, u=None, kc=None, load=None, direction=None):
    """(Pi [J] of (S1), the net force on every granule (ng, d) [N], the net force on each servo
    wall along its inward normal (nw,) [N], the net force on each plate contact's normal dof
    (nk,) [N]) at centres x, the servo walls' (`wall`, an index or (nw,) indices, the target's
    first) offsets o pushed in by `force` (scalars or (nw,) [m], [N]), plate displacements u
    (kc: the plate's condensed stiffness K_c) and load: (ng, d) constant forces on the granules
    [N] (the force drives' `drive_loads`), direction: the plate contacts' (`plate_terms`): minus
    the gradient of Pi."""
    (i, j, delta, f, _, n, a), (wi, wdelta, wf, _, wn, on, wa) = contact_terms(x, o, g, wall)
    pi, pdelta, pf, _, pa = plate_terms(x, np.zeros(0) if u is None else u, g, direction)
    mass = g.mass
    grav = np.asarray(g.gravity, float) if len(g.gravity) else np.zeros(x.shape[1])
    walls = np.atleast_1d(np.asarray(wall, np.int64))
    push = np.broadcast_to(np.asarray(force, float), walls.shape)
    e = 0.4 * (np.sum(a * delta**2.5) + np.sum(wa * wdelta**2.5)) - float(np.sum(mass[:, None] * x * grav))
    e += float(np.sum(push * np.broadcast_to(np.asarray(o, float), walls.shape)))  # the servos' work
    on_plate = np.zeros(0)
    if len(pi):
        ku = kc @ u
        e += 0.4 * float(np.sum(pa * pdelta**2.5)) + 0.5 * float(u @ ku)
        on_plate = pf - ku  # the contacts push the plate in, its stiffness back
    net = np.zeros_like(x)
    np.add.at(net, i, f[:, None] * n)
    np.add.at(net, j, -f[:, None] * n)
    np.add.at(net, wi, -wf[:, None] * wn)
    if direction is None:
        np.add.at(net[:, 0], pi, -pf)
    else:
        np.add.at(net, pi, -pf[:, None] * direction)
    net += mass[:, None] * grav
    if load is not None:
        e -= float(np.sum(load * x))
        net += load
    on_wall = np.array([np.sum(wf[g.wall_w == w]) for w in walls]) - push  # the contacts push out, the servo in
    return e, net, on_wall, on_plate


def _normal_stiffness(x: np.ndarray, o, g, wall, u=None, kc=None, direction=None):
    """The contacts' normal stiffness over every granule's coordinates, the plate contacts'
    normal displacements and the servo walls' offsets (the last unknowns, in `wall`'s order),
    as a sparse matrix: 3/2 A delta^(1/2) n n^T blocks and the plate's K_c (S1's Hessian
    without the transverse geometric terms)."""
    from scipy.sparse import coo_matrix

    (i, j, _, _, k, n, _), (wi, _, _, wk, wn, _, _) = contact_terms(x, o, g, wall)
    pi, _, _, pk, _ = plate_terms(x, np.zeros(0) if u is None else u, g, direction)
    walls = np.atleast_1d(np.asarray(wall, np.int64))
    d = x.shape[1]
    nk = len(pi)
    index = np.arange(len(g.mass))
    first_u = len(g.mass) * d  # the plate's unknowns follow the granules', the walls' theirs
    size = first_u + nk + len(walls)
    rows, cols, vals = [], [], []

    def block(a, b, kk, nn, sign):
        ok = (a >= 0) & (b >= 0) & (kk > 0.0)
        for p in range(d):
            for q in range(d):
                rows.append(a[ok] * d + p)
                cols.append(b[ok] * d + q)
                vals.append(sign * kk[ok] * nn[ok, p] * nn[ok, q])

    ii, jj = index[i], index[j]
    block(ii, ii, k, n, 1.0)
    block(jj, jj, k, n, 1.0)
    block(ii, jj, k, n, -1.0)
    block(jj, ii, k, n, -1.0)
    wii = index[wi]
    block(wii, wii, wk, wn, 1.0)
    for c, w in enumerate(walls):
        last = first_u + nk + c
        on = g.wall_w == w
        sel = on & (wii >= 0) & (wk > 0.0)
        for p in range(d):  # d delta / d x = n, d delta / d o = -1
            rows += [wii[sel] * d + p, np.full(sel.sum(), last)]
            cols += [np.full(sel.sum(), last), wii[sel] * d + p]
            vals += [-wk[sel] * wn[sel, p], -wk[sel] * wn[sel, p]]
        rows.append(np.array([last]))
        cols.append(np.array([last]))
        vals.append(np.array([float(np.sum(wk[on]))]))
    if nk:  # d delta / d x_i = e (e_x: the plane's plate), d delta / d u_k = -1; the plate's K_c
        ku = first_u + np.arange(nk)
        pii = index[pi]
        sel = pii >= 0
        if direction is None:  # the plane's plate: along x alone
            rows += [pii[sel] * d, pii[sel] * d, ku[sel]]
            cols += [pii[sel] * d, ku[sel], pii[sel] * d]
            vals += [pk[sel], -pk[sel], -pk[sel]]
        else:
            e = np.asarray(direction, float)
            block(pii, pii, pk, e, 1.0)
            for p in range(d):
                rows += [pii[sel] * d + p, ku[sel]]
                cols += [ku[sel], pii[sel] * d + p]
                vals += [-pk[sel] * e[sel, p], -pk[sel] * e[sel, p]]
        rows += [ku, np.repeat(ku, nk)]
        cols += [ku, np.tile(ku, nk)]
        vals += [pk, np.asarray(kc, float).ravel()]
    return coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(size, size)).tocsc()


def prescribed_granules(g) -> np.ndarray:
    """(ng,) bool: the granules a displacement or velocity drive moves (held along its
    direction in the static state)."""
    from granplate.physics.drives import KIND_FORCE

    out = np.zeros(len(g.mass), bool)
    on = (g.drive_target >= 0) & (g.drive_kind != KIND_FORCE)
    out[g.drive_target[on]] = True
    return out


def granule_freedom(g, d: int):
    """The static state's free coordinates: a sparse (ng d, nf) matrix T with orthonormal
    columns, the granules' displacements T z. A granule under a displacement or velocity
    drive along e spans the plane (the line in 2D) across e; every other granule, a
    force-driven one included, all d directions."""
    from scipy.linalg import null_space
    from scipy.sparse import coo_matrix

    from granplate.physics.drives import KIND_FORCE

    across = {}
    for k, i in enumerate(g.drive_target):
        if i >= 0 and g.drive_kind[k] != KIND_FORCE:
            e = np.asarray(g.drive_dir[k], float)
            across[int(i)] = null_space(e[None, :] / np.linalg.norm(e))  # (d, d - 1), orthonormal
    rows, cols, vals, col = [], [], [], 0
    for i in range(len(g.mass)):
        basis = across.get(i, np.eye(d))
        for c in range(basis.shape[1]):
            rows += [i * d + p for p in range(d)]
            cols += [col] * d
            vals += list(basis[:, c])
            col += 1
    return coo_matrix((vals, (rows, cols)), shape=(len(g.mass) * d, col)).tocsr()


def drive_loads(g, d: int) -> np.ndarray:
    """(ng, d) the force drives' pushes on their granules at t = 0 [N], P(0) e: the static
    state's loads (zero where a profile starts at 0: a half-sine, a chirp, a harmonic without
    a mean)."""
    from granplate.physics.drives import KIND_FORCE, profile_terms

    load = np.zeros((len(g.mass), d))
    for k, i in enumerate(g.drive_target):
        if i >= 0 and g.drive_kind[k] == KIND_FORCE:
            p0 = profile_terms(0.0, g.drive_prof[k], g.drive_par[k], g.drive_tab[k], g.drive_tlen[k])[1]
            load[i] += float(p0) * np.asarray(g.drive_dir[k], float)
    return load


class Pistons(NamedTuple):
    """The force-driven walls in the static state (docs/model.md section 3.12): walls (np,)
    their indices in the scenario; force (np,) their drives' push into the assembly at t = 0,
    -P(0) e . n [N]; offset0 (np,) their offsets along their unit normals n [m]."""

    walls: np.ndarray
    force: np.ndarray
    offset0: np.ndarray


def static_pistons(g, wall: int) -> Pistons:
    """The force-driven walls of the granular arrays g other than the target `wall`, with
    contact rows (a piston out of the lists' reach touches nothing at rest): each a servo in the
    static state pushing with its drive's value at t = 0."""
    from granplate.physics.drives import KIND_FORCE, profile_terms

    d = g.wall_geo.shape[1] - 1
    walls, force, offset0 = [], [], []
    for k, t in enumerate(g.drive_target):
        w = -1 - int(t)
        rows = np.flatnonzero(g.wall_w == w)
        if t >= 0 or g.drive_kind[k] != KIND_FORCE or w == wall or not len(rows):
            continue
        p0 = float(profile_terms(0.0, g.drive_prof[k], g.drive_par[k], g.drive_tab[k], g.drive_tlen[k])[1])
        n = g.wall_geo[rows[0], :d]
        walls.append(w)
        force.append(-p0 * float(np.asarray(g.drive_dir[k], float) @ n))
        offset0.append(float(g.wall_geo[rows[0], d]))
    return Pistons(np.array(walls, np.int64), np.array(force, float), np.array(offset0, float))


def unsupported_granules(g, wall: int, gravity: bool, pistons: Pistons | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The granules the static state cannot hold, by the contact lists' graph (pairs, wall and
    plate contacts within the lists' reach): (those in a group of granules touching the target
    wall or a piston pushing at t = 0 but no support (another wall, the plate or a held
    granule, a displacement or velocity drive's): the force has no path to a support; under
    gravity, those in a group touching no support or pushing wall: they would fall). Pistons
    (`static_pistons`) are no supports. A granule held along one direction counts as a support
    (the graph does not see directions: a load it cannot carry stops the minimiser)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = len(g.mass)
    i, j = g.pair_ij[:, 0], g.pair_ij[:, 1]
    adj = coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n))
    _, label = connected_components(adj, directed=False)
    servo = np.append(np.asarray([] if pistons is None else pistons.walls, np.int64), wall)
    pushing = np.append(np.asarray([] if pistons is None else pistons.walls[pistons.force != 0.0], np.int64), wall)
    support = np.zeros(n, bool)
    support[g.wall_i[~np.isin(g.wall_w, servo)]] = True
    support[prescribed_granules(g)] = True
    support[np.asarray(getattr(g, "pc_i", np.zeros(0, np.int64)), np.int64)] = True  # the plate is clamped
    pushed = np.zeros(n, bool)
    pushed[g.wall_i[np.isin(g.wall_w, pushing)]] = True
    held_groups = np.unique(label[support])
    free_group = ~np.isin(label, held_groups)
    no_path = free_group & np.isin(label, np.unique(label[pushed]))
    falling = free_group & ~pushed if gravity else np.zeros(n, bool)
    return np.flatnonzero(no_path), np.flatnonzero(falling)


def _refuse_unsupported(g, wall: int, target: str, pistons: Pistons) -> None:
    """ScenarioError naming precompression.target or gravity.g for the granules
    `unsupported_granules` finds."""
    heavy = bool(len(g.gravity)) and bool(np.any(g.gravity != 0.0))
    no_path, falling = unsupported_granules(g, wall, heavy, pistons)
    if len(no_path):
        also = " (or a force-driven wall's, pushing at t = 0)" if len(pistons.walls) else ""
        raise ScenarioError(
            "precompression.target",
            target or f"wall {wall}",
            f"its force{also} has no path to a support: granules {', '.join(str(k + 1) for k in no_path[:5])} "
            "touch it but, through their contacts, no fixed or displacement-driven wall, the plate or a held "
            "granule (close the packing against a wall opposite it)",
        )
    if len(falling):
        raise ScenarioError(
            "gravity.g",
            list(g.gravity),
            f"granules {', '.join(str(k + 1) for k in falling[:5])} rest on no wall, directly or through "
            "their contacts: under gravity they would fall through (give them a floor)",
        )


def _refuse_unbalanced_loads(g, load: np.ndarray, d: int, direction=None) -> None:
    """ScenarioError naming the force drive (or gravity.g) whose push no support can react:
    the assembly's whole load, the drives' pushes at t = 0 `load` (ng, d) [N] and the weight,
    must lie in the span of the directions the supports push along (the walls' normals, the
    held granules' drive directions, the plate along x or its contacts' `direction`), or the frictionless static
    state has no equilibrium (a sideways push on a straight column between two walls)."""
    from scipy.linalg import orth

    from granplate.physics.drives import KIND_FORCE

    grav = np.asarray(g.gravity, float) if len(g.gravity) else np.zeros(d)
    total = load.sum(axis=0) + float(np.sum(g.mass)) * grav
    held = [g.drive_dir[k] for k, i in enumerate(g.drive_target) if i >= 0 and g.drive_kind[k] != KIND_FORCE]
    plate = [np.eye(d)[0]] if len(getattr(g, "pc_i", ())) else []
    if direction is not None:
        plate = list(np.asarray(direction, float))
    spans = np.array([*g.wall_geo[:, :d], *held, *plate], float).reshape(-1, d)
    q = orth(spans.T) if len(spans) else np.zeros((d, 0))
    free = total - q @ (q.T @ total)  # what no support can push back
    scale = float(np.sum(np.abs(load))) + float(np.sum(g.mass)) * float(np.linalg.norm(grav))
    if float(np.linalg.norm(free)) <= 1e-9 * max(scale, 1e-300):
        return
    for k, i in enumerate(g.drive_target):
        if i >= 0 and g.drive_kind[k] == KIND_FORCE and abs(float(np.dot(load[i], free))) > 0.0:
            raise ScenarioError(
                f"drives[{k}]",
                f"granule {i + 1}, {np.linalg.norm(load[i]):.4g} N at t = 0",
                f"its push at t = 0 has {np.linalg.norm(free):.4g} N no support can react: the static state "
                "is frictionless and its walls and held granules push along other directions (start its "
                "profile at 0, e.g. a half-sine or a harmonic without a mean, or push along a wall's normal)",
            )
    raise ScenarioError(
        "gravity.g",
        list(grav),
        f"the weight has {np.linalg.norm(free):.4g} N along no wall's normal: the frictionless static state "
        "has no equilibrium (give a wall across gravity)",
    )


def static_state(
    g,
    x0: np.ndarray,
    wall: int,
    offset0: float,
    force: float,
    tolerance: float = 1e-8,
    max_iterations: int = 20000,
    target: str = "",
    plate: PlateStatics | None = None,
) -> StaticState:
    """The static equilibrium (S2) of the granular arrays g (model.inputs.Granular or
    Granular3) from centres x0 (ng, d) [m], the wall `wall` (index in the scenario's walls,
    offset0 [m] along its unit normal) pushed in with `force` [N], the plate (when g has plate
    contacts) condensed to its contacts by `plate` (`plate_statics`); converged when the
    largest net force on a granule, the wall or a plate contact is at most tolerance x force.
    The force-driven walls (`static_pistons`) are servos too, pushing with their drives' values
    at t = 0 (`StaticState.pistons`, `piston_offsets`). ScenarioError naming the field (`target`, the precompression's, or gravity.g) before
    minimising when the contacts give the force no path to a support or granules would fall
    (`unsupported_granules`); SimulationError with the residual reached (its `result` the
    StaticState) when it does not converge."""
    from scipy.optimize import minimize
    from scipy.sparse import block_diag, identity
    from scipy.sparse.linalg import spsolve

    d = x0.shape[1]
    pistons = static_pistons(g, wall)
    _refuse_unsupported(g, wall, target, pistons)
    walls = np.append(wall, pistons.walls)  # the servo walls, the target's first
    push = np.append(force, pistons.force)
    offsets0 = np.append(offset0, pistons.offset0)
    nw = len(walls)
    nk = len(getattr(g, "pc_i", ()))
    kc = plate.stiffness if plate is not None and nk else np.zeros((nk, nk))
    basis = granule_freedom(g, d)  # the granules' free coordinates
    nf = basis.shape[1]
    load = drive_loads(g, d)
    direction = plate.direction if plate is not None else None
    _refuse_unbalanced_loads(g, load, d, direction)
    a_min = float(np.min(g.wall_coef[g.wall_w == wall, COEF_A])) if np.any(g.wall_w == wall) else 1.0
    scale = (force / a_min) ** (2.0 / 3.0)  # the overlap F makes at the wall [m]: the unknowns' unit

    def unpack(z):
        x = x0 + (basis @ z[:nf]).reshape(-1, d) * scale
        return x, offsets0 + z[nf + nk :] * scale, z[nf : nf + nk] * scale

    def forces(z):
        x, o, u = unpack(z)
        e, net, on_wall, on_plate = energy_and_forces(x, o, g, walls, push, u, kc, load, direction)
        return e, basis.T @ net.ravel(), on_wall, on_plate  # the net force along the free coordinates

    def fun(z):
        e, net, on_wall, on_plate = forces(z)
        grad = np.concatenate([-net, -on_plate, -on_wall]) * scale
        return e / (force * scale), grad / (force * scale)

    def residual(z):
        _, net, on_wall, on_plate = forces(z)
        worst = max(float(np.max(np.abs(net), initial=0.0)), float(np.max(np.abs(on_plate), initial=0.0)))
        return max(worst, float(np.max(np.abs(on_wall)))) / force

    project = block_diag([basis.T, identity(nk + nw)], format="csr")  # onto the free unknowns
    z = np.zeros(nf + nk + nw)
    res = minimize(fun, z, jac=True, method="L-BFGS-B", options={"maxiter": max_iterations, "gtol": 1e-14, "ftol": 0.0})
    z, steps = res.x, int(res.nit)
    for _ in range(50):  # Newton on the normal stiffness, with a halving line search
        if residual(z) <= tolerance or steps >= max_iterations:
            break
        x, o, u = unpack(z)
        _, net, on_wall, on_plate = forces(z)
        h = project @ _normal_stiffness(x, o, g, walls, u, kc, direction) @ project.T * scale
        rhs = np.concatenate([net, on_plate, on_wall])
        dz = spsolve(h + identity(h.shape[0], format="csc") * (1e-12 * float(abs(h).max())), rhs)
        r0, t = residual(z), 1.0
        while t > 1e-6 and residual(z + t * dz) >= r0:
            t *= 0.5
        z = z + t * dz
        steps += 1
    x, o, u = unpack(z)
    _, net, on_wall, _ = forces(z)
    pf = plate_terms(x, u, g, direction)[2]
    state = StaticState(
        x, float(o[0]), float(offset0), residual(z), steps, float(on_wall[0] + force), u, pf, pistons, o[1:]
    )
    if not state.residual <= tolerance:  # NaN too
        raise SimulationError(
            f"precompression: no static equilibrium to a residual of {tolerance:g} x force after {steps} steps "
            f"(reached {state.residual:.3g}); give more precompression.max_iterations, a looser "
            "precompression.tolerance, or check that every granule rests on a path of contacts to a wall",
            state,
        )
    return state


def plate_at_rest(plate: PlateStatics, p, normal_force: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The plate at rest under the normal forces (nk,) [N] its contacts put on it: (q, u), the
    modal displacements q = diag(1/omega^2) Phi_d^T F (nm,) [m kg^(1/2)] and the driving dofs'
    displacements u = Phi_d q + R F (2 nk,) [m] (docs/model.md section 4.5), F the forces at
    the driving dofs (x: normal, y: none, the static state being frictionless)."""
    f = np.zeros(2 * len(normal_force))
    f[0::2] = normal_force
    q = (np.asarray(p.phi_d, float).T @ f) / np.asarray(p.omega2, float)
    u = np.asarray(p.phi_d, float) @ q
    if p.resid.shape[0]:
        u = u + np.asarray(p.resid, float) @ f
    return np.ascontiguousarray(q), np.ascontiguousarray(u)


def precompressed(model):
    """The model whose run starts from its scenario's [precompression] static state: the
    granules' centres moved to it, the target wall's offset with them (`run_walls`: where
    the walls are when the contact lists are rebuilt), the plate deflected under its contacts'
    static forces (`plate_q0`, `plate_u0`; space's elastic solid: its modes `plate_q0` under its
    weight and its contacts' forces, model.body_static), the driven granules' `drive_x0` (their drives'
    displacements count from there); the wall frozen there during the run, or, with
    mode = "held", a piston that keeps pushing with the force (`held_wall`); the model
    itself when the scenario has none."""
    from granplate.setup.precompression_checks import precompression_wall

    p = model.scenario.precompression
    if p is None:
        return model
    g = model.granular
    d = g.wall_geo.shape[1] - 1
    wall = precompression_wall(model.scenario)
    rows = g.wall_w == wall
    offset0 = float(g.wall_geo[rows, d][0]) if np.any(rows) else 0.0
    x0 = np.ascontiguousarray(model.initial_state[:, :d])
    plate = plate_statics(model.plate_arrays) if model.plate is not None else None
    g_static, body, q_weight = g, None, np.zeros(0)
    if model.body is not None:  # the elastic solid in space: its contacts' compliance (model.body_static)
        from granplate.model.body_static import body_statics

        q_weight = model.plate_q0 if model.plate_q0 is not None else np.zeros(len(model.body.omega))
        g_static, plate, body = body_statics(model, x0, q_weight)
    st = static_state(
        g_static, x0, wall, offset0, float(p.force), float(p.tolerance), int(p.max_iterations), str(p.target), plate
    )
    y0 = model.initial_state.copy()
    y0[:, :d] = st.positions
    geo = g.wall_geo.copy()
    geo[rows, d] = st.offset
    walls = list(model.scenario.walls)
    walls[wall] = dataclasses.replace(walls[wall], offset=st.offset)
    for w, o in zip(st.pistons.walls if st.pistons is not None else (), st.piston_offsets):
        geo[g.wall_w == w, d] = o  # a force-driven wall starts at rest where its drive's P(0) holds it
        walls[w] = dataclasses.replace(walls[w], offset=float(o))
    on_granule = g.drive_target >= 0
    x_drive = g.drive_x0.copy()
    x_drive[on_granule] = st.positions[
        g.drive_target[on_granule]
    ]  # a drive's displacement counts from the static state
    g = g._replace(wall_geo=geo, drive_x0=x_drive)
    if p.mode == "held":
        g = held_wall(g, model.scenario, wall, float(p.force), float(p.mass))
    out = dataclasses.replace(model, initial_state=y0, granular=g, run_walls=tuple(walls))
    if body is not None:  # the solid's modes at rest under its weight and the contacts' static forces
        from granplate.model.body_static import body_at_rest

        q0 = body_at_rest(body, model.body.omega, q_weight, st.plate_force)
        return dataclasses.replace(out, plate_q0=q0, plate_u0=np.zeros(0))
    if plate is None:
        return out
    q0, u0 = plate_at_rest(plate, model.plate_arrays, st.plate_force)
    return dataclasses.replace(out, plate_q0=q0, plate_u0=u0)


def held_wall(g, s, wall: int, force: float, mass: float):
    """The granular arrays g with the precompression's wall `wall` made a piston (model.drives
    `with_piston`) pushed into the assembly (along minus its unit outward normal) by `force`
    [N], of `mass` [kg] (0: the granules' total mass, docs/model.md section 3.12)."""
    from granplate.model.drives import with_piston

    n = np.asarray(s.walls[wall].normal, float)
    return with_piston(g, wall, -n / np.linalg.norm(n), force, mass if mass > 0.0 else float(np.sum(g.mass)))
