"""The one sparse factorisation the solid needs: SuperLU (scipy) of a symmetric matrix
under a geometric nested-dissection ordering of its dofs (split at the median of the
longest extent, the nodes of one side touching the other side as the separator, the
smaller side's, ordered last), with the diagonal pivots kept (SymmetricMode). On a thin
40 x 40 x 2 hex20 plate (50,895 dofs) it cut the LU's fill from 77 M (SuperLU's
MMD_AT_PLUS_A) to 43 M entries (58 M with the left side's separator always).

SuperLU's supernodes and ARPACK's Lanczos steps call BLAS on small blocks and single
vectors, which a threaded OpenBLAS slows on a shared machine (threads waiting for a busy
core): `one_blas_thread` runs them on one thread (measured on that plate, 2 cores under
load: a solve 0.055 s against 0.060 s, the Schur-complement factorisation 15.8 s against
18.2 s, the eigensolver's work between solves several times faster). The dense
triangular solves of the residual compliance keep every thread.
"""

from __future__ import annotations

import contextlib
from typing import Callable, Iterator

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

#: Dof sets at most this large are not dissected further.
LEAF_DOFS = 64


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """BLAS on one thread inside the block (threadpoolctl; unchanged where it is missing)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - threadpoolctl is a dependency
        yield
        return
    with threadpool_limits(limits=1, user_api="blas"):
        yield


def nested_dissection(pattern: sp.spmatrix, xyz: np.ndarray, leaf: int = LEAF_DOFS) -> np.ndarray:
    """A fill-reducing order of the dofs (a permutation) from the matrix pattern and each
    dof's position xyz (n, 3) [m]: split at the median of the longest extent, the
    separator the smaller of the two sides' dofs that touch the other side (where the
    median falls on a plane of element faces, the plane's nodes rather than the elements
    beside it: on the 40 x 40 x 2 hex20 plate 42.9 M factor entries against 57.9 M with
    the left side's, a solve 41 ms against 54 ms)."""
    adj = sp.csr_matrix(pattern, dtype=np.float64, copy=True)
    adj.data[:] = 1.0
    parts: list[np.ndarray] = []
    stack: list[tuple[np.ndarray, bool]] = [(np.arange(adj.shape[0]), False)]
    while stack:  # post-order: both halves, then their separator
        nodes, is_separator = stack.pop()
        if is_separator or len(nodes) <= leaf:
            parts.append(nodes)
            continue
        p = xyz[nodes]
        axis = int(np.argmax(p.max(axis=0) - p.min(axis=0)))
        left = p[:, axis] < np.median(p[:, axis])
        if left.all() or not left.any():
            parts.append(nodes)
            continue
        lhs, rhs = nodes[left], nodes[~left]
        sep_l, sep_r = touching(adj, lhs, rhs), touching(adj, rhs, lhs)
        if sep_r.sum() < sep_l.sum():  # the smaller one-sided separator
            lhs, rhs, sep_l = rhs, lhs, sep_r
        stack += [(lhs[sep_l], True), (rhs, False), (lhs[~sep_l], False)]
    return np.concatenate(parts)


def touching(adj: sp.csr_matrix, these: np.ndarray, others: np.ndarray) -> np.ndarray:
    """Which of the dofs `these` share a matrix entry with any of `others` (bool)."""
    mark = np.zeros(adj.shape[0])
    mark[others] = 1.0
    return (adj[these] @ mark) > 0


def factorised(A: sp.spmatrix, xyz: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """x = A^-1 b for b (n,) or (n, m), from one SuperLU factorisation of the symmetric A
    under nested_dissection(A, xyz)."""
    order = nested_dissection(A, xyz)
    lu = spla.splu(
        sp.csc_matrix(sp.csr_matrix(A)[order][:, order]),
        permc_spec="NATURAL",
        diag_pivot_thresh=0.0,
        options={"SymmetricMode": True},
    )

    def solve(b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        x = np.empty_like(b)
        x[order] = lu.solve(np.ascontiguousarray(b[order]))
        return x

    solve.fill = lu.L.nnz + lu.U.nnz  # type: ignore[attr-defined]
    return solve
