"""The contacts' coefficient rows (docs/model.md eqs. 3-5 and the normal laws' columns,
sections 3.6 and 3.10): Hertz's A, the damping c, friction mu and k_s, the yield
overlap and the law "johnson"'s constants, Mindlin's columns and the contact's normal and
tangential law ids (setup.law_registry), for granule pairs (E*, R*, m* of the two),
granules against rigid walls and against the plate's rigid layers (R* = R, m* = m or 0),
with the walls' planes. The columns are physics.contact's COEF_*.
"""

from __future__ import annotations

import math

import numpy as np

from granplate.physics.contact import (
    COEF_A,
    COEF_C,
    COEF_DY,
    COEF_KS,
    COEF_MU,
    COEF_NLAW,
    COEF_TLAW,
    COEF_XH,
    N_COEF,
    damping_coefficient,
    hertz_coefficient,
)
from granplate.physics.laws import tangential_columns
from granplate.physics.mindlin import tangential_compliance
from granplate.physics.laws import law_columns
from granplate.setup.materials import (
    effective_modulus,
    softer_material,
)
from granplate.model.inputs import history_columns
from granplate.setup.law_registry import HERTZ, NORMAL_LAW_IDS, TANGENTIAL_LAW_REGISTRY, TANH
from granplate.setup.scenario import Scenario


def scenario_history_columns(s: Scenario) -> int:
    """The columns of the contacts' history rows of a run of s (model.inputs.history_columns):
    Mindlin's need them all (under velocity Verlet, which moves them on in place, all but the
    trial's), the other tangential laws the normal law's four."""
    return history_columns(TANGENTIAL_LAW_REGISTRY[s.contact.tangential_law].history, s.solver.scheme == "verlet")


def coefficient_row(a: float, c: float, mu: float, k_s: float, law=math.inf, normal_law: int = HERTZ) -> np.ndarray:
    """One row of pair_coef / wall_coef / pc_coef in the columns of physics.contact:
    Hertz A [N/m^1.5], damping c, mu [-], k_s [s/m] (eqs. 3, 5), the normal law's
    columns from COEF_DY on (`law_coefficients`; inf alone: a yield overlap never
    reached), the normal law's id `normal_law`
    (setup.law_registry's NORMAL_LAW_IDS, `normal_law_id`) and the tanh law's tangential id
    (`tangential_columns` makes a row another tangential law's)."""
    row = np.zeros(N_COEF)
    row[COEF_A], row[COEF_C], row[COEF_MU], row[COEF_KS] = a, c, mu, k_s
    law = np.atleast_1d(np.asarray(law, float))
    row[COEF_DY : COEF_DY + len(law)] = law
    row[COEF_NLAW], row[COEF_TLAW] = normal_law, TANH
    return row


def normal_law_of(s: Scenario, a: str, b: str) -> str:
    """The normal law (contact.normal_law, or its [[contact.pairs]] override) between
    materials a and b."""
    return s.contact.law_for_pair(a, b)


def normal_law_id(s: Scenario, a: str, b: str) -> int:
    """The id (COEF_NLAW, setup.law_registry) of the normal law between materials a and b
    (`normal_law_of`)."""
    return NORMAL_LAW_IDS[normal_law_of(s, a, b)]


def law_coefficients(s: Scenario, a, b, b_name: str, e_star: float, r_star: float, length: float) -> np.ndarray:
    """The normal law's columns COEF_DY..COEF_XH (physics.laws' `law_columns`: its module's)
    of a contact of material a (a granule's Material) with b (a granule's Material, or None
    for a rigid wall or the plate's face, whose material is b_name), E* [Pa], R* [m],
    `length` [m] the length that makes the approach speed a strain rate (the sum of the
    radii; a diameter against a rigid body). Hertz's: [inf, 0...]; a yielding law's yield
    overlap is its softer body's (validation refuses a yielding law where the Y it needs is
    unknown)."""
    return law_columns(normal_law_of(s, a.name, b_name), softer_material(a, b), e_star, r_star, length)


def pair_coefficient_row(s: Scenario, a, b, ri: float, rj: float, mi: float, mj: float) -> np.ndarray:
    """The coefficient row of one pair of granules of Materials a and b, radii ri, rj [m] and
    masses mi, mj [kg]: E*, R*, m* of the two (eqs. 3-4), the pair's alpha_n, mu, k_s and
    normal law (`pair_coefficients` gives the same numbers for many pairs at once)."""
    e_star = effective_modulus(a, b)
    r_star = ri * rj / (ri + rj)
    m_star = mi * mj / (mi + mj)
    alpha, mu, ks = s.contact.for_pair(a.name, b.name)
    coef_a = hertz_coefficient(e_star, r_star)
    return coefficient_row(
        coef_a,
        damping_coefficient(alpha, m_star, coef_a),
        mu,
        ks,
        law_coefficients(s, a, b, b.name, e_star, r_star, ri + rj),
        normal_law_id(s, a.name, b.name),
    )


def material_indices(mats) -> tuple[list, np.ndarray]:
    """The distinct Materials of `mats` (one per granule, by name) and each granule's index
    among them."""
    index: dict[str, int] = {}
    kinds = []
    for m in mats:
        if m.name not in index:
            index[m.name] = len(kinds)
            kinds.append(m)
    return kinds, np.array([index[m.name] for m in mats], np.int64).reshape(-1)


def pair_coefficients(s: Scenario, mats, r: np.ndarray, mass: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """(np, N_COEF) coefficients of the granule pairs: E*, R*, m* of the two (eqs. 3-4).

    The rows of `pair_coefficient_row`, bit for bit: numpy does its operations on the same
    doubles in the same order (products, quotients, square roots, correctly rounded), E*
    and the pair's settings are computed once per pair of materials, and the yield overlap
    of an elastic-plastic pair pair by pair."""
    pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
    if not len(pairs):
        return np.zeros((0, N_COEF))
    r, mass = np.asarray(r, float), np.asarray(mass, float)
    kinds, kind = material_indices(mats)
    i, j = pairs[:, 0], pairs[:, 1]
    ri, rj, mi, mj = r[i], r[j], mass[i], mass[j]
    r_star = ri * rj / (ri + rj)
    m_star = mi * mj / (mi + mj)
    del ri, rj, mi, mj
    combos = (
        [(0, kinds[0], kinds[0])]
        if len(kinds) == 1
        else [
            (c, kinds[c // len(kinds)], kinds[c % len(kinds)])
            for c in np.unique(kind[i] * len(kinds) + kind[j]).tolist()
        ]
    )
    combo = None if len(combos) == 1 else kind[i] * len(kinds) + kind[j]
    # per pair of materials: E*, alpha_n, mu, k_s, the normal law's id (one value each when one pair)
    e_star, alpha, mu, ks = (np.empty(len(pairs)) if combo is not None else 0.0 for _ in range(4))
    nlaw = np.full(len(pairs), HERTZ, np.int64)
    for c, ka, kb in combos:
        values = (effective_modulus(ka, kb), *s.contact.for_pair(ka.name, kb.name))
        if combo is None:
            e_star, alpha, mu, ks = values
            nlaw[:] = normal_law_id(s, ka.name, kb.name)
            continue
        on = combo == c
        for column, v in zip((e_star, alpha, mu, ks), values):
            column[on] = v
        nlaw[on] = normal_law_id(s, ka.name, kb.name)
    plastic = nlaw != HERTZ
    coef_a = 4.0 / 3.0 * e_star * np.sqrt(r_star)  # hertz_coefficient
    pair_coef = np.zeros((len(pairs), N_COEF))
    pair_coef[:, COEF_A] = coef_a
    pair_coef[:, COEF_C] = alpha * np.sqrt(m_star * coef_a)  # damping_coefficient
    pair_coef[:, COEF_MU], pair_coef[:, COEF_KS], pair_coef[:, COEF_DY] = mu, ks, math.inf
    pair_coef[:, COEF_NLAW] = nlaw
    for p in np.flatnonzero(plastic).tolist():
        a, b = mats[i[p]], mats[j[p]]
        e_p = e_star if combo is None else float(e_star[p])
        pair_coef[p, COEF_DY : COEF_XH + 1] = law_coefficients(
            s, a, b, b.name, e_p, float(r_star[p]), float(r[i[p]] + r[j[p]])
        )
    compliance = kind_compliances(kinds)
    tangential_law_columns(s, pair_coef, compliance[kind[i]] + compliance[kind[j]])
    return pair_coef


#: An odd 64-bit multiplier (FNV-1a's prime) that mixes a row's bits into one key.
_KEY_PRIME = np.uint64(0x100000001B3)


def coefficient_kinds(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of the coefficient rows `rows` (n, N_COEF), by their bits: (kind
    (n,) int32, table (k, N_COEF)) with table[kind] equal to rows bit for bit, the kinds in
    the order of the rows' keys. A packing of one size and material has one kind, found by
    one comparison; else each row's bits are mixed into a key, the keys sorted, and the
    table checked against every row (rows of one key but other bits: sorted by their bits
    instead). For the 6 million pairs of a million spheres: 0.1 s for one kind, about 3 s
    for several (the sort)."""
    rows = np.ascontiguousarray(rows, float).reshape(-1, N_COEF)
    if not len(rows):
        return np.zeros(0, np.int32), np.zeros((0, N_COEF))
    bits = rows.view(np.uint64)
    if np.array_equal(bits, np.broadcast_to(bits[0], bits.shape)):
        return np.zeros(len(rows), np.int32), rows[:1].copy()
    key = np.zeros(len(rows), np.uint64)
    with np.errstate(over="ignore"):
        for c in range(N_COEF):
            key = (key ^ bits[:, c]) * _KEY_PRIME
    _, first, kind = np.unique(key, return_index=True, return_inverse=True)
    kind = kind.reshape(-1)
    if not all(np.array_equal(bits[first, c][kind], bits[:, c]) for c in range(N_COEF)):  # two rows of one key
        _, first, kind = np.unique(bits.view(np.dtype((np.void, 8 * N_COEF))).ravel(), True, True)
    return kind.reshape(-1).astype(np.int32), rows[first]


def kind_compliances(kinds) -> np.ndarray:
    """Each Material's share (2 - nu) / G [1/Pa] of a contact's tangential compliance 1/G*."""
    return np.array([tangential_compliance(m.E, m.nu) for m in kinds], float)


def tangential_law_columns(s: Scenario, coef: np.ndarray, compliance: np.ndarray) -> None:
    """The scenario's tangential law (contact.tangential_law) into the rows `coef` in place:
    its columns and id (physics.laws.tangential_columns), from each row's 1/G* = `compliance`
    [1/Pa] (the two bodies' shares summed, a rigid body's 0)."""
    if len(coef):
        tangential_columns(s.contact.tangential_law, coef, compliance, s.contact)


def wall_coefficient_row(s: Scenario, a, wall_material: str, ri: float, mi: float) -> np.ndarray:
    """The coefficient row of a granule of Material a, radius ri [m], mass mi [kg] against a
    rigid wall of `wall_material` (R* = R, m* = m)."""
    alpha, mu, ks = s.contact.for_pair(a.name, wall_material)
    e_star = effective_modulus(a, None)
    coef_a = hertz_coefficient(e_star, ri)
    row = coefficient_row(
        coef_a,
        damping_coefficient(alpha, mi, coef_a),
        mu,
        ks,
        law_coefficients(s, a, None, wall_material, e_star, ri, 2.0 * ri),
        normal_law_id(s, a.name, wall_material),
    )
    tangential_law_columns(s, row.reshape(1, -1), kind_compliances([a]))
    return row


def wall_arrays(s: Scenario, mats, r: np.ndarray, mass: np.ndarray, wc: np.ndarray, walls=None):
    """(nw, d + 1) [nx, ny, (nz,) offset] with the unit outward normal (d = the scenario's
    dimension), and (nw, N_COEF) coefficients against a rigid body (R* = R, m* = m): the
    rows of `wall_coefficient_row`, bit for bit (as `pair_coefficients`). walls: the
    Walls of the rows of wc (None: the scenario's; `Model.walls`)."""
    walls = s.walls if walls is None else walls
    wc = np.asarray(wc, np.int64).reshape(-1, 2)
    wall_geo = np.zeros((len(wc), s.dimension + 1))
    wall_coef = np.zeros((len(wc), N_COEF))
    if not len(wc):
        return wall_geo, wall_coef
    r, mass = np.asarray(r, float), np.asarray(mass, float)
    kinds, kind = material_indices(mats)
    i, w = wc[:, 0], wc[:, 1]
    e_star, alpha = np.empty(len(wc)), np.empty(len(wc))
    nlaw = np.full(len(wc), HERTZ, np.int64)
    for k in np.unique(w).tolist():
        wall = walls[k]
        nrm = np.asarray(wall.normal, float)
        at = w == k
        wall_geo[at] = (*(nrm / np.linalg.norm(nrm)), wall.offset)
        for c in np.unique(kind[i[at]]).tolist():
            on = at & (kind[i] == c)
            e_star[on] = effective_modulus(kinds[c], None)
            alpha[on], wall_coef[on, COEF_MU], wall_coef[on, COEF_KS] = s.contact.for_pair(kinds[c].name, wall.material)
            nlaw[on] = normal_law_id(s, kinds[c].name, wall.material)
    ri = r[i]
    coef_a = 4.0 / 3.0 * e_star * np.sqrt(ri)  # hertz_coefficient with R* = R
    wall_coef[:, COEF_A] = coef_a
    wall_coef[:, COEF_C] = alpha * np.sqrt(mass[i] * coef_a)  # damping_coefficient with m* = m
    wall_coef[:, COEF_DY] = math.inf
    wall_coef[:, COEF_NLAW] = nlaw
    for p in np.flatnonzero(nlaw != HERTZ).tolist():
        wall_coef[p, COEF_DY : COEF_XH + 1] = law_coefficients(
            s, mats[i[p]], None, s.walls[w[p]].material, float(e_star[p]), float(ri[p]), 2.0 * float(ri[p])
        )
    tangential_law_columns(s, wall_coef, kind_compliances(kinds)[kind[i]])  # a rigid wall: the granule's alone
    return wall_geo, wall_coef


def plate_contact_coefficients(s: Scenario, mats, r: np.ndarray, pc: np.ndarray) -> np.ndarray:
    """(nk, N_COEF) coefficients against the plate's rigid layers: E_k, R_k -> infinity
    and m_k -> 0, so m* = 0 (no viscous damping); the tangential law's columns with the
    granule's 1/G* alone (as E* is the granule's)."""
    pc_coef = np.zeros((len(pc), N_COEF))
    for k, i in enumerate(pc):
        alpha, mu, ks = s.contact.for_pair(mats[i].name, s.plate.material)
        e_star = effective_modulus(mats[i], None)
        a = hertz_coefficient(e_star, r[i])
        pc_coef[k] = coefficient_row(
            a,
            damping_coefficient(alpha, 0.0, a),
            mu,
            ks,
            law_coefficients(s, mats[i], None, s.plate.material, e_star, r[i], 2.0 * r[i]),
            normal_law_id(s, mats[i].name, s.plate.material),
        )
    tangential_law_columns(s, pc_coef, kind_compliances([mats[i] for i in pc]))  # a rigid layer: the granule's alone
    return pc_coef
