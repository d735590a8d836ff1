"""The run's arrays (solver.loop_arrays): their pages mapped at set-up leave every number
as it was, nested named tuples included, and arrays that cannot be written alone."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pytest

from granplate.solver.loop_arrays import MAP_BYTES, map_pages


class Inner(NamedTuple):
    big: np.ndarray
    small: np.ndarray


class Outer(NamedTuple):
    inner: Inner
    data: np.ndarray
    frozen: np.ndarray
    strided: np.ndarray
    count: int


def test_mapping_pages_changes_no_number():
    """Arrays over MAP_BYTES (C-contiguous, writeable), in nested tuples too, keep every
    bit; a read-only array and a strided view are passed by; small arrays are untouched."""
    rng = np.random.default_rng(2)
    data = rng.normal(size=(3 * MAP_BYTES // 8 + 17,))
    data[5] = -0.0
    frozen = rng.normal(size=(MAP_BYTES // 8 + 1,))
    frozen.flags.writeable = False
    base = rng.normal(size=(2 * MAP_BYTES // 8, 2))
    inner = Inner(big=np.zeros((MAP_BYTES // 8, 3)), small=np.arange(5.0))
    tup = Outer(inner=inner, data=data, frozen=frozen, strided=base[:, 0], count=3)
    before = [a.copy() for a in (inner.big, inner.small, data, frozen, base)]
    map_pages(tup)
    for a, b in zip((inner.big, inner.small, data, frozen, base), before):
        assert np.array_equal(a.view(np.uint8), b.view(np.uint8))


def _fresh_pages(nbytes: int):
    """`nbytes` of an anonymous private mapping of their own (as numpy's large zeros are),
    none of its pages written yet: no allocator can hand out pages an earlier test mapped."""
    mmap = pytest.importorskip("mmap")
    region = mmap.mmap(-1, nbytes, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
    return region, np.frombuffer(region, dtype=np.float64)


def test_mapping_pages_maps_them_now():
    """The kernel maps a fresh array's pages when map_pages writes them, not when the loop
    first does: writing the whole array afterwards takes (almost) no page fault."""
    resource = pytest.importorskip("resource")

    def faults() -> int:
        return resource.getrusage(resource.RUSAGE_SELF).ru_minflt

    nbytes = 64 * MAP_BYTES
    least = nbytes // (4 << 20)  # (at least one fault per 2 MiB huge page, half of them)
    control, plain = _fresh_pages(nbytes)
    before = faults()
    plain[:] = 1.0
    if faults() - before < least:
        del plain
        control.close()
        pytest.skip("this kernel does not count page faults in getrusage's ru_minflt")
    del plain
    control.close()

    region, fresh = _fresh_pages(nbytes)
    before = faults()
    map_pages(Inner(big=fresh, small=np.zeros(1)))
    mapped = faults() - before
    before = faults()
    fresh[:] = 1.0
    later = faults() - before
    assert mapped >= least
    assert later <= 4
    del fresh
    region.close()
