"""The plane's plate under its own weight (docs/model.md section 3.11, "The plate's weight").

Gravity g [m/s^2] acts on the plate's mass as the body force rho t g, whose consistent
nodal forces are f_g = M (g at every node) (M the consistent mass: the shape functions sum
to one). The plate starts at rest in its static sag x_s = K_r^-1 T^T f_g, the full
finite-element static solution whatever modal basis the run keeps. The loop integrates the
plate's motion about that sag: with x = x_s + x', the weight and the sag's elastic force
cancel in every mode and in the residual compliance, so x' obeys the equations of motion
without the weight, and the plate stays at rest until a contact or the shock moves it. The
sag enters the contacts through the face they measure from: a rigid-layer contact k's
overlap is x_i + R_i - (x0 + x_s,k + u_k), x_s,k the sag of its driving node along x.

Energy: with E_p' = 1/2 v^T M v + 1/2 x'^T K x' (what the loop books as E_p) and W_gp =
f_g . (x - x_s) gravity's work on the plate since t = 0, the plate's true energy is
E_p = E_p' + W_gp + E_sag (E_sag = 1/2 f_g . x_s, the sag's strain energy, constant):
E_p - W_gp = E_p' + E_sag, so eq. (11) holds with E_p' and the granules' W_g alone.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from granplate.plate.constraints import reduce_matrix


def weight_forces(plate_model, g: np.ndarray) -> np.ndarray:
    """(n_red,) consistent nodal forces of the plate's own weight on its reduced dofs [N]:
    T^T M (g at every node), g (2,) [m/s^2] (plane stress: rho t g per unit area)."""
    n_nodes = plate_model.n_full // 2
    accel = np.tile(np.asarray(g, float), n_nodes)
    return np.asarray(plate_model.T.T @ (plate_model.mass_matrix() @ accel)).ravel()


def weight_sag(plate_model, g: np.ndarray) -> np.ndarray:
    """(n_red,) the plate's static sag under its own weight, K_r x_s = T^T M g [m] (one sparse
    factorisation of the full reduced stiffness, independent of the modal basis)."""
    K_r = sp.csc_matrix(reduce_matrix(plate_model.stiffness_matrix(), plate_model.T))
    return np.asarray(spla.splu(K_r).solve(weight_forces(plate_model, g)))


def sag_energy(plate_model, g: np.ndarray) -> float:
    """E_sag = 1/2 f_g . x_s [J]: the strain energy the plate holds at rest in its sag."""
    return 0.5 * float(weight_forces(plate_model, g) @ weight_sag(plate_model, g))


def sag_at_contacts(plate_model, g: np.ndarray) -> np.ndarray:
    """(nk,) the sag along x of each rigid-layer contact's driving node [m]."""
    x_s = weight_sag(plate_model, g)
    return np.ascontiguousarray(x_s[np.asarray(plate_model.drive_dofs)[:, 0]])


def has_plate_weight(model) -> bool:
    """Whether the model's plate (the plane's) carries gravity: a plate and a nonzero g."""
    g = model.granular.gravity
    return model.plate is not None and len(g) == 2 and bool(np.any(np.asarray(g) != 0.0))


def weighed(model):
    """The model with its plate resting in its sag under its own weight: each rigid-layer
    contact's face (`pc_x`) moved by its driving node's sag along x; the model itself without
    gravity or a plate. The loop's plate state (q, u) is the motion about the sag."""
    if not has_plate_weight(model):
        return model
    g = model.granular
    sag = sag_at_contacts(model.plate, g.gravity)
    return dataclasses.replace(model, granular=g._replace(pc_x=np.ascontiguousarray(g.pc_x + sag)))
