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

from granplate.model.neighbours import contact_pairs, verlet_pairs, verlet_walls


class Missed(NamedTuple):
    """An overlap no contact of the list accounts for: granule i, its partner (a granule
    j >= 0 or the wall -1 - w) and the overlap [m]."""

    i: int
    partner: int
    overlap: float


def wall_planes(walls) -> tuple[np.ndarray, np.ndarray]:
    """(nw, 2) unit outward normals and (nw,) offsets [m] of the scenario's walls."""
    normals = np.array([w.normal for w in walls], float).reshape(-1, 2)
    if len(normals):
        normals = normals / np.linalg.norm(normals, axis=1)[:, None]
    offsets = np.array([w.offset for w in walls], float)
    return normals, offsets


def fixed_wall_contacts(walls, x, y, r, gap_ratio: float) -> np.ndarray:
    """(granule, wall) pairs whose initial gap is at most gap_ratio * R, sorted (wall, granule)."""
    out = []
    for w, wall in enumerate(walls):
        nx, ny = wall.normal
        for i in range(len(x)):
            gap = wall.offset - (x[i] * nx + y[i] * ny) - r[i]
            if gap <= gap_ratio * r[i]:
                out.append((i, w))
    return np.array(out, np.int64).reshape(-1, 2)


def contact_lists(contact, walls, x, y, r) -> tuple[np.ndarray, np.ndarray]:
    """The loop's (np, 2) granule pairs and (nw, 2) [granule, wall] contacts for the
    positions x, y [m] under the scenario's `contact` settings: the Verlet lists
    (detection = "dynamic") or the pairs within neighbour_gap (detection = "fixed")."""
    if contact.detection == "fixed":
        return (contact_pairs(x, y, r, contact.neighbour_gap),
                fixed_wall_contacts(walls, x, y, r, contact.neighbour_gap))
    normals, offsets = wall_planes(walls)
    return verlet_pairs(x, y, r, contact.skin), verlet_walls(x, y, r, normals, offsets, contact.skin)


def pair_keys(pairs: np.ndarray, n: int) -> np.ndarray:
    """One integer per pair (i n + j)."""
    return pairs[:, 0] * n + pairs[:, 1]


def missed_contacts(pairs, wall_contacts, cand_pairs, cand_walls, normals, offsets,
                    x, y, r) -> list[Missed]:
    """Overlapping pairs of the candidate lists that are not in the loop's lists, largest
    overlap first."""
    n = len(x)
    out = []
    if len(cand_pairs):
        i, j = cand_pairs[:, 0], cand_pairs[:, 1]
        delta = r[i] + r[j] - np.hypot(x[j] - x[i], y[j] - y[i])
        new = ~np.isin(pair_keys(cand_pairs, n), pair_keys(pairs, n))
        out += [Missed(int(a), int(b), float(d)) for a, b, d in zip(i[new & (delta > 0)], j[new & (delta > 0)],
                                                                     delta[new & (delta > 0)])]
    if len(cand_walls):
        i, w = cand_walls[:, 0], cand_walls[:, 1]
        delta = x[i] * normals[w, 0] + y[i] * normals[w, 1] + r[i] - offsets[w]
        new = ~np.isin(i * len(offsets) + w, wall_contacts[:, 0] * len(offsets) + wall_contacts[:, 1])
        out += [Missed(int(a), -1 - int(b), float(d)) for a, b, d in zip(i[new & (delta > 0)], w[new & (delta > 0)],
                                                                          delta[new & (delta > 0)])]
    return sorted(out, key=lambda m: -m.overlap)
