"""Modes of the plate: the generalized eigenproblem K_r phi = omega^2 M_r phi and its sign rule."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg
import scipy.sparse as sp

if TYPE_CHECKING:  # pragma: no cover
    from granplate.plate.build import PlateModel


def modal_basis(K_r: sp.spmatrix, M_r: sp.spmatrix, n_modes: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Lowest n_modes (0 = all) of K_r phi = omega^2 M_r phi, dense scipy.linalg.eigh.

    Returns (Phi, omega): Phi (n_red, n_modes) mass-normalised (Phi^T M_r Phi = I),
    each column signed by `fix_mode_signs`; omega [rad/s] ascending (tiny negative
    eigenvalues of rigid motions are clipped to 0).
    """
    n = K_r.shape[0]
    Kd = K_r.toarray() if sp.issparse(K_r) else np.asarray(K_r)
    Md = M_r.toarray() if sp.issparse(M_r) else np.asarray(M_r)
    subset = None if n_modes in (0, n) else [0, n_modes - 1]
    lam, Phi = scipy.linalg.eigh(Kd, Md, subset_by_index=subset)
    return np.ascontiguousarray(fix_mode_signs(Phi)), np.sqrt(np.maximum(lam, 0.0))


def sign_reference(n: int) -> np.ndarray:
    """A fixed, generic weight vector of length n (no symmetry of the mesh maps it to +-itself).

    w_i = 1 + frac(i * golden ratio): positive, aperiodic, the same on every machine.
    """
    return 1.0 + np.modf(np.arange(n) * 0.6180339887498949)[0]


def fix_mode_signs(Phi: np.ndarray) -> np.ndarray:
    """Sign each column of Phi so that sign_reference . phi > 0.

    A deterministic rule that also holds for symmetric and antisymmetric modes, whose
    largest entries come in pairs of opposite sign (a rule based on the largest entry then
    depends on round-off, and two eigensolvers can disagree).
    """
    s = sign_reference(Phi.shape[0]) @ Phi
    return Phi * np.where(s < 0.0, -1.0, 1.0)


def transverse_mode_frequencies(model: PlateModel, n: int = 3) -> np.ndarray:
    """Frequencies [Hz] of the n lowest modes whose kinetic energy is mostly along x.

    For a strip clamped at its ends along y these are its in-plane bending modes; the
    others are extensional (along y). Phi is mass-normalised, so v^T M v = 1 per mode.
    """
    M = model.mass_matrix()
    out: list[float] = []
    for j in range(model.n_modes):
        vx = model.T @ model.Phi[:, j]
        vx[1::2] = 0.0
        if vx @ (M @ vx) > 0.5:
            out.append(float(model.omega[j]) / (2.0 * np.pi))
            if len(out) == n:
                break
    return np.array(out)
