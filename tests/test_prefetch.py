"""solver.prefetch: the cache hint changes no number, and only a 2D array's row is asked for."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit
from numba.core.errors import TypingError

from granplate.solver.prefetch import prefetch_row


@njit(cache=False)
def _touch_rows(a, rows):
    s = 0.0
    for k in range(rows.shape[0]):
        prefetch_row(a, rows[k])
        s += a[rows[k], 0]
    return s


@pytest.mark.parametrize("dtype", [np.int32, np.int64])
def test_prefetch_changes_no_number(dtype):
    """Asking for rows ahead (any integer index type) leaves the array and what the loop
    reads from it as they are, bit for bit."""
    rng = np.random.default_rng(5)
    a = rng.normal(size=(1000, 9))
    before = a.copy()
    rows = rng.integers(0, 1000, 300).astype(dtype)
    assert _touch_rows(a, rows) == sum(before[r, 0] for r in rows)
    assert np.array_equal(a, before)


def test_prefetch_takes_only_a_row_of_a_2d_array():
    """A 1D array or a float index is refused when the kernel compiles (no silent wrong
    address)."""

    @njit(cache=False)
    def one_d(a):
        prefetch_row(a, 0)

    @njit(cache=False)
    def float_row(a):
        prefetch_row(a, 0.5)

    with pytest.raises(TypingError):
        one_d(np.zeros(4))
    with pytest.raises(TypingError):
        float_row(np.zeros((4, 3)))
