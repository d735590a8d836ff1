"""Which pairs can touch (docs/model.md section 1.3): the loop's granule-granule and
granule-wall contact lists, built at t = 0 and, with contact.detection = "dynamic",
rebuilt during the run (a Verlet list); and the search for overlaps that no contact of
the list accounts for.

dynamic: the list holds every pair whose centres are at most (R_i + R_j)(1 + skin) apart
and every (granule, wall) whose gap is at most skin R_i. The loop ends its chunk when a
granule has moved skin R_min / 2 since the list was built (solver/contacts.py), and the
list is rebuilt here: two granules that were farther apart than the list's margin cannot
have closed it, so no contact forms unseen. Pairs of the list that do not touch
contribute nothing (forces act only for positive overlap).

fixed: the paper's topology, the pairs whose gap at t = 0 is at most neighbour_gap times
the smaller radius; the list never changes and the search only checks that no other pair
overlaps.

Both lists are sorted, pairs by (i, j) and wall contacts by (wall, granule), so that the
touching pairs of a packing are summed in the same order whatever the mode.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from granplate.model.neighbours import centre_distances, contact_pairs, normal_coordinates, verlet_pairs, verlet_walls


class Missed(NamedTuple):
    """An overlap no contact of the list accounts for: granule i, its partner (a granule
    j >= 0 or the wall -1 - w) and the overlap [m]."""

    i: int
    partner: int
    overlap: float


def centre_coordinates(state: np.ndarray, dimension: int):
    """(x, y, z) columns of the granules' state [m] (its first `dimension` columns; z None
    in the plane), as the neighbour searches take them."""
    x, y, *z = (state[:, k] for k in range(dimension))
    return x, y, (z or [None])[0]


def wall_planes(walls, dimension: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """(nw, dimension) unit outward normals and (nw,) offsets [m] of the scenario's walls."""
    normals = np.array([w.normal for w in walls], float).reshape(-1, dimension)
    if len(normals):
        normals = normals / np.linalg.norm(normals, axis=1)[:, None]
    offsets = np.array([w.offset for w in walls], float)
    return normals, offsets


def fixed_wall_contacts(walls, x, y, r, gap_ratio: float, z=None) -> np.ndarray:
    """(granule, wall) pairs whose initial gap is at most gap_ratio * R, sorted (wall, granule)
    (each gap the same doubles in the same order as granule by granule: offset - s.n - R)."""
    x, y, r = (np.asarray(a, float) for a in (x, y, r))
    out = [np.zeros((0, 2), np.int64)]
    for w, wall in enumerate(walls):
        gap = wall.offset - normal_coordinates(x, y, None if z is None else np.asarray(z, float), wall.normal) - r
        i = np.flatnonzero(gap <= gap_ratio * r)
        out.append(np.column_stack([i, np.full(len(i), w)]).astype(np.int64))
    return np.concatenate(out).reshape(-1, 2)


def contact_lists(contact, walls, x, y, r, z=None, candidates=None) -> tuple[np.ndarray, np.ndarray]:
    """The loop's (np, 2) granule pairs and (nw, 2) [granule, wall] contacts for the
    positions x, y (and z in space) [m] under the scenario's `contact` settings: the
    Verlet lists (detection = "dynamic") or the pairs within neighbour_gap (detection = "fixed");
    candidates: sorted pairs holding every pair the list's search would find (shared
    with another search of the same positions), or None."""
    if contact.detection == "fixed":
        return (
            contact_pairs(x, y, r, contact.neighbour_gap, z, candidates),
            fixed_wall_contacts(walls, x, y, r, contact.neighbour_gap, z),
        )
    normals, offsets = wall_planes(walls, 2 if z is None else 3)
    return (
        verlet_pairs(x, y, r, contact.skin, z, candidates),
        verlet_walls(x, y, r, normals, offsets, contact.skin, z),
    )


def pair_keys(pairs: np.ndarray, n: int) -> np.ndarray:
    """One integer per pair (i n + j)."""
    return pairs[:, 0] * n + pairs[:, 1]


def missed_contacts(pairs, wall_contacts, cand_pairs, cand_walls, normals, offsets, x, y, r, z=None) -> list[Missed]:
    """Overlapping pairs of the candidate lists that are not in the loop's lists, largest
    overlap first."""
    n = len(x)
    out = []
    if len(cand_pairs):
        i, j = cand_pairs[:, 0], cand_pairs[:, 1]
        delta = r[i] + r[j] - centre_distances(x, y, z, i, j)
        new = ~np.isin(pair_keys(cand_pairs, n), pair_keys(pairs, n))
        out += [
            Missed(int(a), int(b), float(d))
            for a, b, d in zip(i[new & (delta > 0)], j[new & (delta > 0)], delta[new & (delta > 0)])
        ]
    if len(cand_walls):
        i, w = cand_walls[:, 0], cand_walls[:, 1]
        delta = normal_coordinates(x[i], y[i], None if z is None else z[i], normals[w].T) + r[i] - offsets[w]
        new = ~np.isin(i * len(offsets) + w, wall_contacts[:, 0] * len(offsets) + wall_contacts[:, 1])
        out += [
            Missed(int(a), -1 - int(b), float(d))
            for a, b, d in zip(i[new & (delta > 0)], w[new & (delta > 0)], delta[new & (delta > 0)])
        ]
    return sorted(out, key=lambda m: -m.overlap)
