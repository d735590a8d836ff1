"""The O(N log N) neighbour search against the O(N^2) double loop (same pairs, same order)."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.model.arrays import build_model, find_pairs
from granplate.model.neighbours import brute_force_pairs, candidate_pairs, contact_pairs
from granplate.setup.scenario import LatticeLayout, Scenario


def _random_packing(seed: int, n: int, spread: float):
    """n polydisperse discs (radii 1 mm x U[1 - spread, 1 + spread]) dropped at random in a
    box sized for a dense-ish packing; overlaps allowed (the search is pure geometry)."""
    rng = np.random.default_rng(seed)
    r = 1e-3 * rng.uniform(1.0 - spread, 1.0 + spread, n)
    side = 2e-3 * np.sqrt(n)
    return rng.uniform(0.0, side, n), rng.uniform(0.0, side, n), r


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("gap_ratio", [0.0, 0.05, 0.5])
def test_same_pairs_as_double_loop_on_random_polydisperse_packings(seed, gap_ratio):
    """contact_pairs equals brute_force_pairs exactly (pairs and order) on seeded random packings."""
    x, y, r = _random_packing(seed, 400, spread=0.6)
    fast, slow = contact_pairs(x, y, r, gap_ratio), brute_force_pairs(x, y, r, gap_ratio)
    assert len(slow) > 50
    assert fast.dtype == slow.dtype == np.int64
    np.testing.assert_array_equal(fast, slow)


def test_same_pairs_on_a_touching_lattice_with_boundary_gaps():
    """On a touching hexagonal lattice (gaps 0 up to rounding) both searches keep exactly the touching pairs."""
    m = build_model(Scenario(layout=LatticeLayout(columns=9, rows=8, radius=1e-3)))
    x, y, r = m.initial_state[:, 0], m.initial_state[:, 1], m.granular.radius
    np.testing.assert_array_equal(contact_pairs(x, y, r, 0.0), brute_force_pairs(x, y, r, 0.0))
    np.testing.assert_array_equal(m.pairs, brute_force_pairs(x, y, r, 0.05))


def test_find_pairs_is_the_neighbour_search():
    """model.arrays.find_pairs returns the neighbour search's pairs."""
    x, y, r = _random_packing(3, 200, spread=0.3)
    np.testing.assert_array_equal(find_pairs(x, y, r, 0.05), brute_force_pairs(x, y, r, 0.05))


def test_pairs_sorted_and_degenerate_sizes():
    """Pairs come sorted (i < j, lexicographic); zero and one granule give an empty (0, 2) array."""
    x, y, r = _random_packing(4, 300, spread=0.5)
    p = contact_pairs(x, y, r, 0.1)
    assert np.all(p[:, 0] < p[:, 1])
    assert [tuple(q) for q in p] == sorted(tuple(q) for q in p)
    for n in (0, 1):
        assert contact_pairs(x[:n], y[:n], r[:n], 0.05).shape == (0, 2)
    assert candidate_pairs(x[:1], y[:1], 1.0).shape == (0, 2)


def test_ten_thousand_granules_pair_count():
    """A 100 x 100 hexagonal layout (9950 granules) gives exactly its touching pairs: 99 x 198
    between neighbouring columns plus 50 x 99 + 50 x 98 within the columns."""
    m = build_model(Scenario(layout=LatticeLayout(columns=100, rows=100, radius=1e-3)))
    across = 99 * (2 * 100 - 2)
    vertical = 50 * 99 + 50 * 98
    assert m.n_granules == 9950
    assert len(m.pairs) == across + vertical


@pytest.mark.parametrize("n", [2, 14, 64, 65, 300])
@pytest.mark.parametrize("dim", [2, 3])
def test_close_pairs_equal_the_k_d_trees(n, dim):
    """setup.pairs: the all-pairs search of a few points and the k-d tree return the same
    pairs in the same order (sorted i < j) on seeded random points, in the plane and in space."""
    from granplate.setup.pairs import all_pairs, close_pairs, tree_pairs

    rng = np.random.default_rng(100 * n + dim)
    points = rng.uniform(0.0, 1.0, size=(n, dim))
    distance = 0.5 if n < 20 else 2.0 / n ** (1.0 / dim)
    want = tree_pairs(points, distance)
    assert n < 20 or len(want) > n // 4
    np.testing.assert_array_equal(all_pairs(points, distance), want)
    np.testing.assert_array_equal(close_pairs(points, distance), want)
    assert close_pairs(points, distance).dtype == np.int64


@pytest.mark.parametrize("dim", [2, 3])
def test_python_hypot_is_math_hypot_bit_for_bit(dim):
    """python_hypot, which decides a touching lattice's pairs in contact_pairs, equals
    math.hypot on every element: spread magnitudes, zeros, lattice steps off by round-off,
    and a subnormal largest component."""
    import math

    from granplate.model.neighbours import python_hypot

    rng = np.random.default_rng(dim)
    n = 20_000
    spread = rng.normal(size=(dim, n)) * 10.0 ** rng.integers(-300, 300, size=(1, n))
    lattice = rng.integers(-3, 4, size=(dim, n)) * np.sqrt(2.0) * 1e-3 + rng.normal(size=(dim, n)) * 1e-19
    c = np.concatenate([spread, lattice, rng.normal(size=(dim, 4))], axis=1)
    c[0, -4:] = 0.0
    c[:, -1] = 0.0
    c[:, -2] = 3e-310
    got = python_hypot(*c)
    want = np.array([math.hypot(*c[:, k]) for k in range(c.shape[1])])
    np.testing.assert_array_equal(got, want)
