"""Small dense linear systems inside compiled kernels (a Newton step's Jacobian, a
granule's few contact normals): Gaussian elimination in place, no allocation, so that
the time loop's kernels may call it."""

from __future__ import annotations

import math

from granplate.jit import njit


@njit(cache=True)
def solve_dense(jac, rhs) -> float:
    """Solve jac x = rhs in place (x into rhs) by Gaussian elimination with partial
    pivoting; a zero pivot column gives x = 0 there. jac is overwritten. Returns the
    smallest pivot's size (0: singular; a caller that needs a well-posed system compares
    it with its own threshold)."""
    nd = rhs.shape[0]
    low = math.inf
    for col in range(nd):
        piv = col
        big = abs(jac[col, col])
        for r in range(col + 1, nd):
            if abs(jac[r, col]) > big:
                big = abs(jac[r, col])
                piv = r
        low = min(low, big)
        if big == 0.0:
            continue
        if piv != col:
            for b in range(nd):
                tmp = jac[col, b]
                jac[col, b] = jac[piv, b]
                jac[piv, b] = tmp
            tmp = rhs[col]
            rhs[col] = rhs[piv]
            rhs[piv] = tmp
        for r in range(col + 1, nd):
            fac = jac[r, col] / jac[col, col]
            if fac != 0.0:
                for b in range(col, nd):
                    jac[r, b] -= fac * jac[col, b]
                rhs[r] -= fac * rhs[col]
    for col in range(nd - 1, -1, -1):
        acc = rhs[col]
        for b in range(col + 1, nd):
            acc -= jac[col, b] * rhs[b]
        rhs[col] = acc / jac[col, col] if jac[col, col] != 0.0 else 0.0
    return low
