"""Pairs of points closer than a distance: the one search behind the neighbour lists and
the overlap check of a scenario.

`close_pairs` returns the sorted pairs (i, j), i < j, of points at most `distance` apart.
A few points are compared all against all (ALL_PAIRS_MAX or fewer: microseconds, and
scipy.spatial is not imported, which costs a fresh process about 0.15 s); more go through
a k-d tree (scipy.spatial.cKDTree.query_pairs, O(N log N)). Both compare the squared
distance with distance^2, so both return the same pairs in the same order.
"""

from __future__ import annotations

import threading

import numpy as np

#: Up to this many points, every pair is compared (above: a k-d tree).
ALL_PAIRS_MAX = 64


def all_pairs(points: np.ndarray, distance: float) -> np.ndarray:
    """(n_pairs, 2) sorted pairs (i < j) of the points (n, dim) [m] at most distance [m]
    apart, every pair compared: |p_j - p_i|^2 <= distance^2."""
    p = np.asarray(points, dtype=float)
    diff = p[None, :, :] - p[:, None, :]
    d2 = np.einsum("ijk,ijk->ij", diff, diff)
    i, j = np.nonzero(np.triu(d2 <= float(distance) ** 2, 1))  # row-major: sorted (i, j)
    return np.column_stack([i, j]).astype(np.int64).reshape(-1, 2)


def tree_pairs(points: np.ndarray, distance: float) -> np.ndarray:
    """The same pairs from a k-d tree (scipy.spatial.cKDTree.query_pairs), sorted (i, j).

    The tree is built by splitting at the middle of each node's extent, not its median,
    and without shrinking nodes to their points (`balanced_tree=False,
    compact_nodes=False`: the same pairs; for a million spheres of a packing, a third of
    the time); the pairs are sorted by the one key i n + j."""
    from scipy.spatial import cKDTree

    points = np.asarray(points, dtype=float)
    tree = cKDTree(points, balanced_tree=False, compact_nodes=False)
    pairs = tree.query_pairs(float(distance), output_type="ndarray").astype(np.int64).reshape(-1, 2)
    key = pairs[:, 0] * len(points) + pairs[:, 1]  # i < j < n: one integer per pair, in (i, j) order
    key.sort()
    out = np.empty((len(key), 2), np.int64)
    np.divmod(key, len(points), out=(out[:, 0], out[:, 1]))
    return out


def close_pairs(points: np.ndarray, distance: float) -> np.ndarray:
    """(n_pairs, 2) sorted pairs (i < j) of the points (n, dim) [m] at most distance [m]
    apart: all pairs compared for ALL_PAIRS_MAX points or fewer, else a k-d tree."""
    points = np.asarray(points, dtype=float)
    if len(points) < 2:
        return np.zeros((0, 2), np.int64)
    if len(points) <= ALL_PAIRS_MAX:
        return all_pairs(points, distance)
    return tree_pairs(points, distance)


#: Relative margin on a search distance, so that rounding never drops a pair an exact test
#: at the nominal distance would keep (model.neighbours.SEARCH_MARGIN).
SEARCH_MARGIN = 1e-9


def contact_search_distance(r_max: float, neighbour_gap: float, skin: float, dynamic: bool) -> float:
    """The distance [m] one search at t = 0 covers for both the pairs touching within
    neighbour_gap, (2 + gap) R_max, and (dynamic detection) the Verlet list's 2 R_max (1 +
    skin), with the search margin: model.neighbours' `search_distance` and
    `verlet_distance`, whichever is larger."""
    distance = (2.0 + neighbour_gap) * r_max * (1.0 + SEARCH_MARGIN)
    if dynamic:
        distance = max(distance, 2.0 * r_max * (1.0 + skin) * (1.0 + SEARCH_MARGIN))
    return distance


class _Kept(threading.local):
    """The search `superset_pairs` kept for this thread's next one: points, distance, pairs."""

    def __init__(self):
        self.search: list = []


_KEPT_BY_THREAD = _Kept()


def superset_pairs(points: np.ndarray, distance: float, keep: bool = False) -> np.ndarray:
    """(n_pairs, 2) sorted pairs (i < j) holding every pair of the points at most
    `distance` [m] apart, and perhaps more: the search kept from before when it was of the
    same points at a distance at least as large (then handed over and forgotten), else
    `close_pairs`. keep: remember this search for the next call (validation's overlap
    check keeps its search for the model's lists, which filter the pairs by their own
    exact tests: one k-d tree for a run's set-up)."""
    points = np.asarray(points, dtype=float)
    kept = _KEPT_BY_THREAD.search
    if kept:
        kept_points, kept_distance, kept_pairs = kept
        kept.clear()
        if kept_distance >= distance and kept_points.shape == points.shape and np.array_equal(kept_points, points):
            return kept_pairs
    pairs = close_pairs(points, distance)
    if keep:
        kept[:] = [points.copy(), float(distance), pairs]
    return pairs
