"""The elastic solid in space under its own weight (docs/model.md section 3.11, "The solid's
weight").

Gravity g [m/s^2] acts on the solid's mass as the body force rho g, whose consistent nodal
forces on the free dofs are f_g = (M (g at every node))_free (M the full consistent mass:
the shape functions sum to one, so M times a rigid translation is the weight's load; the
clamped dofs' rows dropped). On the modes it is the constant modal force

    f_k = phi_k^T f_g   [N kg^-1/2],                                               (G1)

which the velocity-Verlet scheme integrates exactly: each mode turns about its static
deflection (solver.body_modes.turn_weighed), the weight's work f . (q(t + h) - q(t)) booked as
gravity's in eq. (11) (as the granules' weight is). The solid starts at rest in
its static sag under its weight (as the plane's plate does), the modal static deflection

    q_k = f_k / omega_k^2,                                                          (G2)

and, where the body has a residual compliance (plate.residual), the dropped modes' static
share u_r = K^-1 f_g - Phi diag(1/omega^2) Phi^T f_g, constant in time: the surface is moved
by it (the contacts measure from the sagged surface, the 2D plate's `pc_x` shift), so that
the surface at rest is the finite-element static solution K u = f_g, whatever the modes
kept. Eq. (11) with the residual's constant share: its strain energy and gravity's work on
it change together by the contacts' coupling only (1/2 (F + f)^T R (F + f) - f^T R (F - F0)
= 1/2 F^T R F + const), so the loop books the contacts' residual energy alone.

A body with a rigid-body mode the weight loads (no clamped face or rollers that hold it)
has no static sag: refused, naming gravity.g.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from granplate.errors import ScenarioError


def weight_load(solid, g) -> np.ndarray:
    """(n_red,) f_g: the consistent nodal forces [N] of the solid's own weight on its free
    dofs, (M a)[dofs] with a = g at every node (g (3,) [m/s^2])."""
    from granplate.solid.fe import mass_matrix

    accel = np.tile(np.asarray(g, float), len(solid.nodes))
    return np.asarray(mass_matrix(solid.basis, solid.material.rho) @ accel)[solid.dofs]


def modal_weight(solid, g) -> np.ndarray:
    """(nm,) f_k = Phi^T f_g [N kg^-1/2] of (G1). ScenarioError naming gravity.g when a
    rigid-body mode (omega = 0) carries weight: the body is not held against gravity."""
    f = np.ascontiguousarray(solid.Phi.T @ weight_load(solid, g))
    free = solid.omega <= 0.0
    scale = float(np.max(np.abs(f), initial=0.0))
    if np.any(np.abs(f[free]) > 1e-9 * max(scale, 1e-300)):
        raise ScenarioError(
            "gravity.g",
            list(map(float, g)),
            "the elastic solid is not held against its weight (a rigid-body mode carries it): clamp a face or "
            "give rollers across gravity (plate.clamped, plate.rollers), or leave out [gravity]",
        )
    return f


def modal_sag(solid, g) -> np.ndarray:
    """(nm,) the modes' static deflection q_k = f_k / omega_k^2 of (G2) [m kg^1/2]."""
    f = modal_weight(solid, g)
    om2 = solid.omega**2
    return np.ascontiguousarray(np.where(om2 > 0.0, f / np.where(om2 > 0.0, om2, 1.0), 0.0))


def static_sag(solid, g) -> np.ndarray:
    """(n_red,) the finite-element static solution K u = f_g [m] on the free dofs (one
    sparse factorisation of the reduced stiffness)."""
    from granplate.solid.boundary import reduced
    from granplate.solid.build import solid_stiffness
    from granplate.solid.factor import factorised

    K = reduced(
        solid_stiffness(solid.basis, solid.mesh, solid.element, solid.material, solid.rigid_patches), solid.dofs
    )
    return np.asarray(factorised(K, solid.nodes[solid.dofs // 3])(weight_load(solid, g)))


def residual_sag(solid, g) -> np.ndarray:
    """(n_red,) the dropped modes' static share of the sag [m]: K^-1 f_g - Phi q (q of G2)."""
    return static_sag(solid, g) - solid.Phi @ modal_sag(solid, g)


def has_body_weight(model) -> bool:
    """Whether the model's elastic solid carries gravity: a body and a nonzero g."""
    g = model.granular.gravity
    return model.body is not None and len(g) == 3 and bool(np.any(np.asarray(g) != 0.0))


def shifted_surface(body, shift: np.ndarray):
    """The BodyArrays `body` with its surface nodes moved by `shift` (n_red,) [m] (a reduced
    displacement; fixed dofs stay): the faces' nodes, the surface nodes, their grid and the
    bounding box."""
    from granplate.solid.patch import node_grid

    rows = body.node_rows
    move = np.where(rows >= 0, shift[np.maximum(rows, 0)], 0.0)  # (n_sn, 3)
    xyz = np.ascontiguousarray(body.node_xyz + move)
    faces = np.ascontiguousarray(body.face_nodes + move[body.face_snode])
    grid = node_grid(xyz, float(body.grid[0]))
    reach = float(np.max(np.abs(move), initial=0.0))
    return body._replace(
        face_nodes=faces,
        node_xyz=xyz,
        grid=np.array([grid.cell]),
        grid_origin=grid.origin,
        grid_shape=grid.shape,
        cell_start=grid.start,
        cell_nodes=grid.nodes,
        box=np.ascontiguousarray(body.box + np.array([[-reach], [reach]])),
    )


def weighed_body(model):
    """The model with its elastic solid under its own weight: the modal force of (G1) in the
    body's arrays (`weight`), the run starting in the sag of (G2) (`plate_q0`, at rest), the
    surface moved by the residual share where the body has a residual compliance; the model
    itself without gravity or a body."""
    if not has_body_weight(model):
        return model
    g = np.asarray(model.granular.gravity, float)
    solid = model.solid
    body = model.body._replace(weight=modal_weight(solid, g))
    if body.resid.shape[0]:
        body = shifted_surface(body, residual_sag(solid, g))
    return dataclasses.replace(model, body=body, plate_q0=modal_sag(solid, g), plate_u0=np.zeros(0))
