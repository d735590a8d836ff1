"""The static residual compliance of a truncated modal basis over a set of dofs S
(surface dofs where contact forces act):

    R = G[S, S] - Phi_S diag(1/omega^2) Phi_S^T   [m/N]   (kept elastic modes only)

G is the static flexibility: K^-1 for a held body. A free body has no K^-1; G is then the
inertia-relief flexibility, the projected pseudo-inverse G = P^T K^+ P with
P = I - M Phi_r Phi_r^T (Phi_r its M-orthonormal rigid-body modes): a load f is balanced
by the rigid-body inertia forces M Phi_r Phi_r^T f, the body is supported at six dofs
that stop its rigid motion without reacting (the balanced load has no reaction), and the
rigid part is projected out of the displacement, x = (I - Phi_r Phi_r^T M) K_s^-1 P f.
Then G = sum over every elastic mode of phi phi^T / omega^2, the kept modes' share is
subtracted, and R holds what the truncation misses.

One sparse LU of K (or of the supported K; solid.factor); G's columns over S come from block solves of
CHUNK unit loads at a time (only the rows S kept), so memory stays at n CHUNK + |S|^2.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from granplate.solid.factor import factorised

#: Unit loads solved per block.
CHUNK = 512


def support_dofs(rigid: np.ndarray) -> np.ndarray:
    """Six dofs that together stop every rigid-body motion (QR with column pivoting of
    the rigid modes' rows)."""
    _, _, piv = la.qr(rigid.T, pivoting=True, mode="economic")
    return np.sort(piv[: rigid.shape[1]])


def flexibility(K: sp.spmatrix, xyz: np.ndarray, M: sp.spmatrix | None = None,
                rigid: np.ndarray | None = None) -> Callable[[np.ndarray], np.ndarray]:
    """x = G f for loads f (n, m) [N] -> (n, m) [m]: K^-1 f (held body, rigid None), or the
    inertia-relief flexibility of a free body with M-orthonormal rigid modes rigid (n, 6);
    xyz (n, 3): each dof's position [m] (the factorisation's ordering)."""
    if rigid is None:
        return factorised(K, xyz)
    n = K.shape[0]
    keep = np.setdiff1d(np.arange(n), support_dofs(rigid))
    lu_solve = factorised(sp.csr_matrix(K)[keep][:, keep], xyz[keep])
    MR = M @ rigid

    def solve(f: np.ndarray) -> np.ndarray:
        f = np.asarray(f, dtype=float)
        balanced = f - MR @ (rigid.T @ f)
        x = np.zeros_like(balanced)
        x[keep] = lu_solve(balanced[keep])
        return x - rigid @ (MR.T @ x)

    return solve


def flexibility_block(solve: Callable[[np.ndarray], np.ndarray], n: int, dofs: np.ndarray,
                      columns: np.ndarray | None = None, chunk: int = CHUNK) -> np.ndarray:
    """G[dofs, columns] [m/N] (columns: a subset of dofs, default all), from unit loads
    solved chunk at a time."""
    columns = dofs if columns is None else columns
    out = np.empty((len(dofs), len(columns)))
    for start in range(0, len(columns), chunk):
        cols = columns[start:start + chunk]
        f = np.zeros((n, len(cols)))
        f[cols, np.arange(len(cols))] = 1.0
        out[:, start:start + len(cols)] = solve(f)[dofs]
    return out


def residual_compliance(K: sp.spmatrix, dofs: np.ndarray, Phi: np.ndarray, omega: np.ndarray,
                        xyz: np.ndarray, M: sp.spmatrix | None = None, rigid: np.ndarray | None = None,
                        chunk: int = CHUNK) -> np.ndarray:
    """R (|S|, |S|) [m/N] over the dofs S of the (reduced) system (module docstring);
    xyz (n, 3): each dof's position [m].

    Phi, omega: the kept modes (a free body's zero modes are left out of the sum);
    M, rigid: a free body's mass and M-orthonormal rigid modes (None: a held body)."""
    dofs = np.asarray(dofs, dtype=np.int64)
    G = flexibility_block(flexibility(K, xyz, M, rigid), K.shape[0], dofs, chunk=chunk)
    elastic = omega > 0.0
    phi_s = Phi[dofs][:, elastic]
    R = G - (phi_s / omega[elastic] ** 2) @ phi_s.T
    return 0.5 * (R + R.T)
