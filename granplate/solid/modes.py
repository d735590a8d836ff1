"""The solid's modes below a cut-off: K phi = omega^2 M phi, mass-normalised
(Phi^T M Phi = I), from scipy's eigsh in shift-invert mode over windows of the spectrum.

Windows: each eigsh call asks for the `window` eigenvalues nearest a shift sigma (one
sparse LU of K - sigma M); all eigenvalues within the farthest one's distance are then
found. A window's values are kept up to a cut placed in the widest gap of its upper half
(below its top, whose cluster may be incomplete); the next shift is placed a quarter of a window's width above
the cut, so that its window reaches below it (checked, and moved down when it does not). The windows
stop once one reaches past max_omega^2.

Windows side by side: a `plan` names the first windows (shift, values) and a pool of
threads solves them at once (SuperLU and ARPACK release the GIL, and scipy's ARPACK keeps
its state per call); they are then taken in order as if solved one by one: a planned
window that does not reach down to the last cut is dropped with those after it, and the
windows go on one by one from there. `split_plan` cuts a large window in two (the second
shifted by a mode-count estimate): on the 40 x 40 x 2 hex20 plate (215 modes below
150 kHz) two windows of 120 and 130 values took 40 s side by side on 2 cores against
69 s for one of 250. The plan depends on the problem only, never on the cores: the
same windows, the same modes on any machine.

A body held nowhere (no clamp, no roller) keeps its six rigid-body modes (three
translations, three rotations) with frequency exactly 0: they are built analytically from
the node coordinates and M-orthonormalised, the eigensolver's six near-zero modes are
dropped (their count is checked) and its elastic modes M-orthogonalised against them.

Deterministic: every window starts from the same seeded start vector v0, and each mode's
sign is the plate's rule (`plate.modes.fix_mode_signs`: a positive projection on a fixed
reference vector, which holds for the symmetric and antisymmetric modes of a square plate,
whose largest entries come in pairs of opposite sign).
"""

from __future__ import annotations

from collections import deque
from concurrent.futures import Executor
from typing import Any, Callable, Sequence

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from granplate.plate.modes import fix_mode_signs
from granplate.solid.factor import factorised, one_blas_thread

#: Eigenvalues asked for per shift-invert window.
WINDOW_MODES = 60
#: Seed of the start vector v0 of every window.
V0_SEED = 20260
#: The first shift is -FIRST_SHIFT_SHARE mean(diag K / diag M), far below the first
#: elastic eigenvalue and negative: K - sigma M is positive definite even for a free body.
FIRST_SHIFT_SHARE = 1e-8
#: A free body's rigid-body eigenvalues must lie below this share of the first elastic one.
RIGID_RTOL = 1e-6
#: A window of at least this many values is solved as two side by side (split_plan).
SPLIT_VALUES = 160
#: The first window of a split asks this share of the values: the smaller one, as it
#: shares its core with the residual's factorisation (solid.build.modes_and_residual).
SPLIT_LOW_SHARE = 0.4
#: The second window asks the rest and this share more (the overlap that lets it reach
#: below the first window's cut).
SPLIT_OVERLAP = 0.1
#: Windows before giving up (a guard against a cut-off far above the mesh's spectrum).
MAX_WINDOWS = 200


def rigid_body_modes(xyz: np.ndarray) -> np.ndarray:
    """(3 n_nodes, 6) rigid-body displacements [m per unit]: translations along x, y, z,
    then rotations about the centroid's x, y, z axes (u = e_k x (x - c))."""
    n = xyz.shape[0]
    r = xyz - xyz.mean(axis=0)
    R = np.zeros((n, 3, 6))
    for k in range(3):
        R[:, k, k] = 1.0
    R[:, 1, 3], R[:, 2, 3] = -r[:, 2], r[:, 1]  # about x: (0, -z, y)
    R[:, 0, 4], R[:, 2, 4] = r[:, 2], -r[:, 0]  # about y: (z, 0, -x)
    R[:, 0, 5], R[:, 1, 5] = -r[:, 1], r[:, 0]  # about z: (-y, x, 0)
    return R.reshape(3 * n, 6)


def m_orthonormal(V: np.ndarray, M: sp.spmatrix) -> np.ndarray:
    """V's columns M-orthonormalised (Cholesky of V^T M V): V L^-T."""
    L = np.linalg.cholesky(V.T @ (M @ V))
    return la.solve_triangular(L, V.T, lower=True).T


def rigid_modes(nodes: np.ndarray, M: sp.spmatrix) -> np.ndarray:
    """A free body's rigid-body modes as modes_below gives them (n, 6): M-orthonormal,
    signs fixed; nodes (n_nodes, 3) [m]. Known before the eigensolver runs."""
    return fix_mode_signs(m_orthonormal(rigid_body_modes(nodes), M))


def mass_operator(M: sp.spmatrix) -> spla.LinearOperator:
    """x -> M x, as the scalar mass matrix on each node's three dofs when M = M_s (x) I_3
    (every node's x, y, z dofs kept and consecutive, as an isotropic solid's consistent
    mass with whole nodes clamped): a ninth of the entries, half the time of M's own
    product on the 50,895-dof plate (2.1 ms against 4.1 ms); else M's own product."""
    n = M.shape[0]
    if n % 3 == 0 and n:
        Ms = sp.csr_matrix(M)[0::3][:, 0::3]
        if 3 * Ms.nnz == M.nnz:
            probe = np.random.default_rng(V0_SEED).standard_normal(n)
            if np.allclose((Ms @ probe.reshape(-1, 3)).ravel(), M @ probe, rtol=1e-12, atol=0.0):
                return spla.LinearOperator(M.shape, matvec=lambda x: (Ms @ x.reshape(-1, 3)).ravel(), dtype=float)
    return spla.aslinearoperator(M)


def split_plan(
    k: int, max_lambda: float, lambda_below: Callable[[float], float]
) -> tuple[tuple[float | None, int], ...]:
    """The first windows (shift [rad^2/s^2], None for the first shift; values): one of k
    values below SPLIT_VALUES, else two: SPLIT_LOW_SHARE of them from the first shift, and
    one shifted halfway (in lambda) between the estimated top of the first and max_lambda,
    asking the rest and an overlap. lambda_below(c): the omega^2 below which a mode-count
    estimate puts c modes."""
    if k < SPLIT_VALUES:
        return ((None, k),)
    low = int(SPLIT_LOW_SHARE * k)
    sigma = 0.5 * (lambda_below(low) + max_lambda)
    return ((None, low), (sigma, k - low + int(SPLIT_OVERLAP * k)))


class _Later:
    """A window solved when its result is first asked for (no pool: one by one)."""

    def __init__(self, fn: Callable[..., Any], *args: Any) -> None:
        self._call, self._value = (fn, args), None

    def result(self) -> Any:
        if self._call is not None:
            fn, args = self._call
            self._value, self._call = fn(*args), None
        return self._value

    def cancel(self) -> bool:
        self._call = None
        return True


def shift_inverse(K: sp.spmatrix, M: sp.spmatrix, sigma: float, xyz: np.ndarray) -> spla.LinearOperator:
    """(K - sigma M)^-1 as a LinearOperator (one sparse LU, solid.factor)."""
    return spla.LinearOperator(K.shape, matvec=factorised(K - sigma * M, xyz), dtype=float)


def window(
    K: sp.spmatrix,
    M: sp.spmatrix,
    sigma: float,
    k: int,
    v0: np.ndarray,
    xyz: np.ndarray,
    mass: spla.LinearOperator | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The k eigenpairs (lambda = omega^2 ascending, vectors) nearest sigma (xyz: each
    dof's position [m], for the factorisation's ordering; mass: M's product, default M's)."""
    mass = spla.aslinearoperator(M) if mass is None else mass
    with one_blas_thread():
        OPinv = shift_inverse(K, M, sigma, xyz)
        vals, vecs = spla.eigsh(K, k=k, M=mass, sigma=sigma, which="LM", v0=v0, OPinv=OPinv)
    order = np.argsort(vals)
    return vals[order], vecs[:, order]


def window_cut(vals: np.ndarray, below: float, floor: float = -np.inf) -> float:
    """A value inside the widest relative gap between a window's sorted eigenvalues above
    `below` in its upper half, below its top (`below` itself when fewer than two lie there).
    floor: the lowest value the next, planned window holds; the gap is then sought among
    the values above it, which both windows hold (the upper half where fewer than two)."""
    upper = vals[vals > max(below, floor)] if np.isfinite(floor) else vals[:0]
    if len(upper) < 2:
        upper = vals[len(vals) // 2 :]
        upper = upper[upper > below]
    if len(upper) < 2:
        return below
    gaps = np.diff(upper) / np.maximum(np.abs(upper[1:]), 1e-300)
    i = int(np.argmax(gaps))
    return 0.5 * float(upper[i] + upper[i + 1])


def eigenpairs_below(
    K: sp.spmatrix,
    M: sp.spmatrix,
    max_lambda: float,
    xyz: np.ndarray,
    k: int = WINDOW_MODES,
    seed: int = V0_SEED,
    plan: Sequence[tuple[float | None, int]] = (),
    pool: Executor | None = None,
    then: Callable[[], object] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Every eigenpair with lambda <= max_lambda [rad^2/s^2] (ascending), over
    shift-invert windows of k values (module docstring); xyz (n, 3): each dof's position [m].
    plan: the first windows (shift, None for the first shift; values), solved side by side
    on pool's threads (one by one without a pool; the same pairs either way); then: called
    once they are submitted (what else the pool should run after them)."""
    n = K.shape[0]
    k = max(1, min(k, n - 2))
    v0 = np.random.default_rng(seed).standard_normal(n)
    mass = mass_operator(M)
    sigma = -FIRST_SHIFT_SHARE * float(np.mean(K.diagonal() / M.diagonal()))
    start = pool.submit if pool is not None else _Later
    planned = [(sigma if s is None else float(s), max(1, min(int(v), n - 2))) for s, v in (plan or ((None, k),))]
    pending = deque((s, v, start(window, K, M, s, v, v0, xyz, mass)) for s, v in planned)
    if then is not None:
        then()
    below = -np.inf  # every eigenvalue <= below has been kept
    kept_vals, kept_vecs = [], []
    for _ in range(MAX_WINDOWS):
        if pending:
            sigma, size, job = pending.popleft()
            vals, vecs = job.result()
        else:
            size = k
            vals, vecs = window(K, M, sigma, k, v0, xyz, mass)
        radius = float(np.max(np.abs(vals - sigma)))
        if sigma - radius > below * (1 + 1e-12) and np.isfinite(below):  # a gap: shift down
            while pending:  # the plan's later windows start from a cut this one missed
                pending.popleft()[2].cancel()
            sigma = 0.5 * (sigma + below)
            continue
        done = vals[-1] > max_lambda or size >= n - 2
        floor = -np.inf
        if pending and not done:  # the next window is planned: cut where both hold the values
            upcoming, _, job = pending[0]
            floor = upcoming - float(np.max(np.abs(job.result()[0] - upcoming)))
        cut = max_lambda if done else window_cut(vals, below, floor)
        take = (vals > below) & (vals <= cut)
        kept_vals.append(vals[take])
        kept_vecs.append(vecs[:, take])
        if done:
            while pending:
                pending.popleft()[2].cancel()
            break
        width = float(vals[-1] - vals[0])
        below, sigma = cut, max(cut, float(vals[-1]) if cut == below else cut) + 0.25 * width
    else:  # pragma: no cover - guarded by the cost check's mode count
        raise RuntimeError(f"more than {MAX_WINDOWS} eigensolver windows below {max_lambda:.3g} rad^2/s^2")
    lam = np.concatenate(kept_vals)
    vec = np.concatenate(kept_vecs, axis=1)
    order = np.argsort(lam)
    return lam[order], vec[:, order]


def modes_below(
    K: sp.spmatrix,
    M: sp.spmatrix,
    max_omega: float,
    xyz: np.ndarray,
    rigid: np.ndarray | None = None,
    k: int = WINDOW_MODES,
    seed: int = V0_SEED,
    plan: Sequence[tuple[float | None, int]] = (),
    pool: Executor | None = None,
    then: Callable[[], object] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(omega (n_modes,) [rad/s] ascending, Phi (n, n_modes) [kg^-1/2]) of every mode up
    to max_omega [rad/s], M-orthonormal, signs fixed; xyz (n, 3): each dof's position [m].

    rigid: (n, 6) rigid-body displacements of a free body (rigid_body_modes), or None for a
    held one. A free body's first six modes are those, at omega = 0 exactly. plan, pool,
    then: the first windows, the threads that solve them side by side and what the pool
    runs after them (eigenpairs_below)."""
    lam, vec = eigenpairs_below(K, M, max_omega**2, xyz, k=k, seed=seed, plan=plan, pool=pool, then=then)
    if rigid is None:
        return np.sqrt(np.maximum(lam, 0.0)), fix_mode_signs(vec)
    R = m_orthonormal(rigid, M)
    n_rigid = R.shape[1]
    if len(lam) > n_rigid and not abs(lam[n_rigid - 1]) < RIGID_RTOL * lam[n_rigid]:
        raise RuntimeError(f"a free body should have {n_rigid} zero eigenvalues; found {lam[: n_rigid + 1]}")
    E = vec[:, n_rigid:]
    E = E - R @ (R.T @ (M @ E))
    E = E / np.sqrt(np.einsum("ij,ij->j", E, M @ E))
    omega = np.concatenate([np.zeros(n_rigid), np.sqrt(lam[n_rigid:])])
    return omega, np.hstack([fix_mode_signs(R), fix_mode_signs(E)])
