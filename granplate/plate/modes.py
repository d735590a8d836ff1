"""Modes of the plate: the generalized eigenproblem K_r phi = omega^2 M_r phi and its sign rule."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

if TYPE_CHECKING:  # pragma: no cover
    from granplate.plate.plate_model import PlateModel


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


#: Fewest modes the sparse eigensolver asks for.
FIRST_MODE_COUNT = 32
#: Modes asked for per mode Weyl's law predicts below the cut-off (a margin: the
#: finite-element spectrum lies above the continuum's).
WEYL_MARGIN = 1.15
#: Growth of the number of modes asked when the cut-off was not reached.
MODE_COUNT_GROWTH = 1.5
#: Relative tolerance of the sparse eigensolver (ARPACK's tol).
EIGSH_TOL = 1e-12


def weyl_mode_count(area: float, E: float, nu: float, rho: float, omega: float) -> float:
    """Number of in-plane modes of a plane-stress plate of `area` [m^2] below omega
    [rad/s] by Weyl's law: N ~ area omega^2 / (4 pi) (1/c_L^2 + 1/c_T^2), with
    c_L^2 = E / (rho (1 - nu^2)) and c_T^2 = E / (2 rho (1 + nu)) [m^2/s^2]."""
    c_l2 = E / (rho * (1.0 - nu * nu))
    c_t2 = E / (2.0 * rho * (1.0 + nu))
    return area * omega * omega / (4.0 * np.pi) * (1.0 / c_l2 + 1.0 / c_t2)


def truncated_modal_basis(
    K_r: sp.spmatrix,
    M_r: sp.spmatrix,
    drive: np.ndarray,
    max_omega: float,
    n_modes: int = 0,
    expected: float = 0.0,
    face: sp.spmatrix | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The modes up to max_omega [rad/s] (or the n_modes lowest when n_modes > 0) and the
    static residual shapes at the driving dofs (docs/model.md section 4.5).

    One sparse LU factorisation of K_r (positive definite: the plate is clamped) serves
    scipy.sparse.linalg.eigsh in shift-invert mode about sigma = 0 (its start vector fixed,
    so the basis is the same on every run) and the static solves. The number of modes
    asked starts at WEYL_MARGIN times `expected` (weyl_mode_count), at least
    FIRST_MODE_COUNT, and grows by MODE_COUNT_GROWTH until the largest found exceeds
    max_omega.

    Returns (Phi, omega, Psi, R_face): Phi (n_red, nm) mass-normalised and signed by
    `fix_mode_signs`, omega (nm,) ascending, and Psi (n_red, nd) = K_r^-1 E_d -
    Phi diag(1/omega^2) Phi_d^T, the displacement per unit force at each driving dof
    that the kept modes miss (E_d: the unit vectors of the dofs `drive`), so that the
    static response at the driving dofs, Phi_d diag(1/omega^2) Phi_d^T + Psi[drive], is
    exactly K_r^-1 restricted to them; R_face = `face_residual_compliance` of the face
    map `face` ((0, 0) when face is None).
    """
    n = K_r.shape[0]
    K = sp.csc_matrix(K_r)
    M = sp.csc_matrix(M_r)
    lu = spla.splu(K)
    opinv = spla.LinearOperator((n, n), matvec=lu.solve, dtype=float)
    v0 = sign_reference(n)
    k = n_modes if n_modes > 0 else max(FIRST_MODE_COUNT, int(WEYL_MARGIN * expected))
    k = min(k, n - 1)
    while True:
        ncv = min(n, k + max(k // 2, 20))
        lam, Phi = spla.eigsh(K, k=k, M=M, sigma=0.0, which="LM", OPinv=opinv, v0=v0, tol=EIGSH_TOL, ncv=ncv)
        order = np.argsort(lam)
        lam, Phi = lam[order], Phi[:, order]
        omega = np.sqrt(np.maximum(lam, 0.0))
        if n_modes > 0 or omega[-1] > max_omega or k == n - 1:
            break
        k = min(int(MODE_COUNT_GROWTH * k), n - 1)
    if n_modes == 0:
        keep = omega <= max_omega
        lam, Phi, omega = lam[keep], Phi[:, keep], omega[keep]
    # M-orthonormalise once more (ARPACK's vectors are orthonormal to its tolerance)
    Phi = Phi / np.sqrt(np.einsum("ij,ij->j", Phi, M @ Phi))
    Phi = np.ascontiguousarray(fix_mode_signs(Phi))
    drive = np.asarray(drive, dtype=np.int64).ravel()
    unit = np.zeros((n, drive.size))
    unit[drive, np.arange(drive.size)] = 1.0
    Psi = lu.solve(unit) - Phi @ (Phi[drive].T / lam[:, None])
    R_face = np.zeros((0, 0)) if face is None else face_residual_compliance(lu.solve, Phi, lam, face)
    return Phi, omega, Psi, R_face


#: Static solves per block when computing the face's residual compliance (bounded memory).
FACE_SOLVE_BLOCK = 64


def face_residual_compliance(solve, Phi: np.ndarray, lam: np.ndarray, face: sp.spmatrix) -> np.ndarray:
    """R_face = E (K_r^-1 - Phi diag(1/lam) Phi^T) E^T [m/N], (nf, nf), symmetrised: the
    static compliance the kept modes miss between every pair of face dofs (docs/model.md
    section 4.5), which patch contacts average as w^T R_face w.

    solve: x -> K_r^-1 x (the factorisation the eigensolver used); Phi (n_red, nm), lam
    (nm,) = omega^2 [rad^2/s^2]; face: (nf, n_red) sparse 0/1 map from the reduced dofs
    to the face's full dofs (T's face rows: a clamped dof's row is empty, the nodes of a
    rigid layer share their driving dof's column). Solved FACE_SOLVE_BLOCK columns at a
    time, only the face rows kept.
    """
    E = sp.csr_matrix(face)
    nf = E.shape[0]
    Et = sp.csc_matrix(E.T)
    R = np.empty((nf, nf))
    for j0 in range(0, nf, FACE_SOLVE_BLOCK):
        j1 = min(nf, j0 + FACE_SOLVE_BLOCK)
        R[:, j0:j1] = E @ solve(Et[:, j0:j1].toarray())
    phi_face = E @ Phi
    R -= (phi_face / lam) @ phi_face.T
    return np.ascontiguousarray(0.5 * (R + R.T))


def residual_compliance(Psi: np.ndarray, drive: np.ndarray) -> np.ndarray:
    """R = Psi[drive], symmetrised [m/N] (nd, nd): the static compliance of the driving
    dofs that the kept modes miss (docs/model.md section 4.5)."""
    R = Psi[np.asarray(drive, dtype=np.int64).ravel()]
    return np.ascontiguousarray(0.5 * (R + R.T))


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
