"""The elastic solid in space in the static state of [precompression] (docs/model.md section
3.12, "The elastic solid's static compliance").

The solid is condensed to the normal displacements u of the granules' contacts on it, as the
plane's plate is (model.static, eq. S1). Each granule within a radius of the surface at the
start of the static solve touches it where the loop's contact does (solver.body: the closest
point of the surface, its outward normal n, its patch's weights w_a over surface nodes);
there the surface's displacement into the body along e = -n is

    u_k = a_k . q + r_k^T R_S F_S,   a_k = Phi^T W_k^T e_k,                        (B1)

(W_k the patch's mean over the surface nodes' dofs, r_k its weights on the residual dofs S).
At rest the modes are static, q = q_w + diag(1/omega^2) sum_j a_j N_j (q_w the sag under
the body's own weight, model.body_weight), so the contacts' static compliance is

    C = A^T diag(1/omega^2) A + R_c,   R_c = r^T R_S r,                             (B2)

the modes' static stiffness omega^2 and the residual compliance in series, and K_c = C^-1
enters (S1) as the plate's does. A contact's overlap is delta_k = R_i + e_k . x_i -
(c_k + u_k), c_k = e_k . p_k + a_k . q_w the sagged surface along e_k. The contact's point,
normal and weights are those at the granules' positions when the solve starts (the static
displacements are small against the patch); the run then starts with the modes at
q = q_w + diag(1/omega^2) A N, and the residual's share from the loop's own static solve of
the same contacts.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class BodyContacts(NamedTuple):
    """The granules' contacts on the solid in the static state: granule (nk,) int, direction
    (nk, 3) each contact's unit normal into the body (-n), face (nk,) c_k [m], modal (nm, nk)
    the columns a_k of (B1) [kg^-1/2], compliance (nk, nk) C of (B2) [m/N]."""

    granule: np.ndarray
    direction: np.ndarray
    face: np.ndarray
    modal: np.ndarray
    compliance: np.ndarray


class Located(NamedTuple):
    """Where each granule touches the solid's surface (solver.body's `locate`, here from the
    solid layer's own kernels): near (ng,) bool, whether the granule is within a radius of
    the body's bounding box; distance (ng,) [m] from the surface to its centre; normal
    (ng, 3) the outward normal there; nodes, weights: per granule, its patch's surface nodes
    and their weights (summing to one)."""

    near: np.ndarray
    distance: np.ndarray
    normal: np.ndarray
    nodes: list
    weights: list


def located(body, x: np.ndarray, radius: np.ndarray) -> Located:
    """Each granule at centres x (ng, 3) [m] (radii (ng,) [m]) within a radius of the body's
    bounding box located on the surface of the BodyArrays `body` as the loop locates it
    (solver/body.py): the closest point by `follow_closest` from the granule's seed face,
    its patch the face's shape functions there (patch radius 0) or the disc of surface nodes
    within the patch radius a, weighted by their surface share times (1 - r^2/a^2)^2 and
    normalised."""
    from granplate.solid.closest import follow_closest
    from granplate.solid.surface import face_shape_functions

    ng = len(x)
    near = np.all((x >= body.box[0] - radius[:, None]) & (x <= body.box[1] + radius[:, None]), axis=1)
    distance, normal = np.full(ng, np.inf), np.zeros((ng, 3))
    nodes: list = [np.zeros(0, np.int64)] * ng
    weights: list = [np.zeros(0)] * ng
    kind, a = int(body.kind[0]), float(body.patch[0])
    out = np.empty(9)
    shape, d_shape = np.empty(body.face_nodes.shape[1]), np.empty((body.face_nodes.shape[1], 2))
    for i in np.flatnonzero(near):
        seed = int(body.face[0, i]) if body.face[0, i] >= 0 else 0
        f = follow_closest(body.face_nodes, kind, body.neighbours, seed, np.ascontiguousarray(x[i], float), out)
        distance[i], normal[i] = out[8], out[5:8]
        if a > 0.0:
            rho2 = np.sum((body.node_xyz - out[2:5]) ** 2, axis=1) / (a * a)
            inside = np.flatnonzero(rho2 < 1.0)
            k = body.node_area[inside] * (1.0 - rho2[inside]) ** 2
            nodes[i], weights[i] = inside, k / np.sum(k)
        else:
            face_shape_functions(kind, out[0], out[1], shape, d_shape)
            nodes[i], weights[i] = np.asarray(body.face_snode[f], np.int64), shape.copy()
    return Located(near, distance, normal, nodes, weights)


def body_contacts(model, x: np.ndarray, q_weight: np.ndarray) -> BodyContacts:
    """The contacts (B1)-(B2) of the granules within a radius of the solid's surface at
    centres x (ng, 3) [m], the modes sagged by q_weight (nm,) under the body's weight."""
    b = model.body
    r = model.granular.radius
    loc = located(b, x, r)
    dist = loc.distance
    who = np.flatnonzero(loc.near & (dist - r <= r))
    nm = len(b.omega)
    n_s = b.resid.shape[0]
    e = -loc.normal[who]
    a = np.zeros((nm, len(who)))
    rv = np.zeros((n_s, len(who)))
    for k, i in enumerate(who):
        for node, w in zip(loc.nodes[i], loc.weights[i]):
            for c in range(3):
                row = b.node_rows[node, c]
                if row >= 0:
                    a[:, k] += w * e[k, c] * b.phi[row]
                s = b.node_resid[node, c]
                if s >= 0:
                    rv[s, k] += w * e[k, c]
    om2 = b.omega**2
    inv = np.where(om2 > 0.0, 1.0 / np.where(om2 > 0.0, om2, 1.0), 0.0)
    c = (a * inv[:, None]).T @ a
    if n_s:
        c = c + rv.T @ b.resid @ rv
    face = np.einsum("kd,kd->k", e, x[who]) + dist[who] + a.T @ q_weight
    return BodyContacts(who.astype(np.int64), np.ascontiguousarray(e), face, a, c)


def body_statics(model, x: np.ndarray, q_weight: np.ndarray):
    """(the granular arrays with the solid's contacts as the static state's plate contacts
    (pc_i, pc_x = c_k, pc_coef), the PlateStatics of (B2) with their directions, the
    BodyContacts) at centres x (ng, 3) [m]. ScenarioError naming plate.max_frequency when the
    kept modes (and residual) leave a contact without static stiffness."""
    from granplate.errors import ScenarioError
    from granplate.model.static import PlateStatics

    bc = body_contacts(model, x, q_weight)
    g = model.granular
    g = g._replace(pc_i=bc.granule, pc_x=bc.face, pc_coef=np.ascontiguousarray(model.body.coef[bc.granule]))
    c = bc.compliance
    if len(c) and np.linalg.cond(c) > 1e12:
        raise ScenarioError(
            "plate.max_frequency",
            model.scenario.plate.max_frequency,
            "the kept modes give the solid's contacts no independent static stiffness, which [precompression] "
            "needs: keep more modes or the residual compliance (plate.residual = true)",
        )
    stiffness = np.linalg.inv(c) if len(c) else np.zeros((0, 0))
    return g, PlateStatics(compliance=c, stiffness=stiffness, direction=bc.direction), bc


def body_at_rest(bc: BodyContacts, omega: np.ndarray, q_weight: np.ndarray, normal_force: np.ndarray) -> np.ndarray:
    """(nm,) the modes at rest under the body's weight and the contacts' normal forces (nk,)
    [N] pushing it along their directions: q = q_weight + diag(1/omega^2) A N."""
    om2 = np.asarray(omega, float) ** 2
    inv = np.where(om2 > 0.0, 1.0 / np.where(om2 > 0.0, om2, 1.0), 0.0)
    return np.ascontiguousarray(q_weight + inv * (bc.modal @ normal_force))
