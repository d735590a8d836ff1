"""Scenario -> model arrays: contact topology, coefficients (eqs. 3-4), load resultants
and the plate's modal model, built once per run (the plate part is cached on disk).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from granplate.model.contacts import contact_lists, fixed_wall_contacts
from granplate.model.drives import drive_fields, driven_initial_state
from granplate.model.inputs import HIST_MAX, HIST_XI, Config, Granular, PlateArrays, no_history, scheme_number
from granplate.physics.contact import (
    COEF_A,
    COEF_C,
    COEF_DY,
    COEF_H,
    COEF_KAPPA,
    COEF_KS,
    COEF_KT,
    COEF_MU,
    COEF_MUT,
    COEF_RC,
    COEF_RL,
    COEF_SY,
    COEF_XH,
    COEF_XT,
    N_COEF,
    damping_coefficient,
    hertz_coefficient,
)
from granplate.physics.cavity import hardness_overlap
from granplate.physics.mindlin import mindlin_coefficient, tangential_compliance
from granplate.physics.plastic import contact_yield_overlap
from granplate.errors import ScenarioError
from granplate.setup.geometry import resolve
from granplate.physics.shock import shock_resultants
from granplate.setup.materials import (
    DEFAULT_HARDNESS_RATIO,
    DEFAULT_UNLOADING_FACTOR,
    effective_modulus,
    softer_material,
    softer_yield_strength,
    sphere_inertia,
    sphere_mass,
)
from granplate.setup.scenario import Plate, Scenario
from granplate.setup.threads import loop_threads
from granplate.setup.plate_checks import split_initial_contacts
from granplate.setup.validate import validate

#: implicit scheme: the error estimate's smallest force scale, as a fraction of the
#: shock's peak resultant force on the granules (q0 times the load resultants).
FORCE_FLOOR_FRACTION = 1e-2


def force_floor(
    q0: float, fres: np.ndarray, tres: np.ndarray, r: np.ndarray, mass: np.ndarray, s: Scenario, out_dt: float
) -> float:
    """The implicit scheme's smallest force scale [N]: FORCE_FLOOR_FRACTION of the shock's
    peak resultant (q0 times the load resultants, torques over radii) plus the granules'
    initial momentum per output interval (for runs driven by initial velocities)."""
    if len(r) == 0:
        return 0.0
    shock = abs(q0) * float(np.abs(fres).sum() + np.abs(tres / r).sum())
    momentum = sum(m * (math.hypot(gr.vx, gr.vy) + rr * abs(gr.omega)) for m, rr, gr in zip(mass, r, s.granules))
    return FORCE_FLOOR_FRACTION * (shock + float(momentum) / out_dt)


def implicit_step_max(dt_max: float, out_dt: float) -> float:
    """The implicit scheme's largest step: out_dt / 2^k, the largest not above dt_max [s]
    (its steps are dyadic fractions of the output interval, which they tile exactly)."""
    k = max(0, math.ceil(math.log2(out_dt / dt_max) - 1e-12))
    return out_dt / 2.0**k


@dataclass(frozen=True)
class Model:
    """Everything the time loop needs, plus the names that label its arrays.

    scenario: the resolved scenario (layout expanded); labels: granule labels;
    pairs: (np, 2) granule pairs in contact at t = 0 (gap within contact.neighbour_gap);
    wall_contacts: (nw, 2) [granule, wall] likewise; plate_contacts: (nk,) granule index
    per rigid-layer contact (those on a face node at t = 0); initial_patches: the granules
    touching the face between nodes at t = 0, which the driver gives patch contacts before
    the first step (docs/model.md section 3.5); plate: the PlateModel or None; solid, body: an
    elastic body in space (dimension 3) and its loop arrays, or None. The loop's lists are in `granular`
    (pair_ij, wall_i: with contact.detection = "dynamic" the Verlet lists at t = 0,
    rebuilt during the run by `granular_with_contacts`). materials: each granule's Material.
    """

    scenario: Scenario
    labels: tuple[str, ...]
    granular: Granular
    plate_arrays: PlateArrays
    config: Config
    plate: object | None
    initial_state: np.ndarray
    pairs: np.ndarray
    wall_contacts: np.ndarray
    plate_contacts: np.ndarray
    materials: tuple = ()
    initial_patches: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    solid: object | None = None  # an elastic body in space: the built solid (solid.build.SolidModel)
    body: object | None = None  # and its arrays in the loop (model.inputs.BodyArrays)
    body_rigid: np.ndarray | None = None  # (ng,) bool: the granules on one of the body's rigid patches at t = 0
    run_walls: tuple = ()  # the walls where the run starts, when not the scenario's (a precompressed wall's static offset)

    @property
    def walls(self) -> tuple:
        """The walls where the run starts: `run_walls`, or the scenario's (the contact lists
        are rebuilt against them, a driven wall moved from there)."""
        return self.run_walls or self.scenario.walls

    # a precompressed plate at t = 0 (docs/model.md section 3.12): its modal displacements (nm,) and its
    # driving dofs' displacements (2 nk,) [m]; None: the plate starts undeformed
    plate_q0: np.ndarray | None = None
    plate_u0: np.ndarray | None = None

    @property
    def n_granules(self) -> int:
        return len(self.labels)

    @property
    def contact_labels(self) -> tuple[str, ...]:
        """Labels of the plate contacts (the granule touching the plate)."""
        return tuple(self.labels[i] for i in self.plate_contacts)


def coefficient_row(a: float, c: float, mu: float, k_s: float, law=math.inf) -> np.ndarray:
    """One row of pair_coef / wall_coef / pc_coef in the columns of physics.contact:
    Hertz A [N/m^1.5], damping c, mu [-], k_s [s/m] (eqs. 3, 5) and the normal law's
    columns from COEF_DY on (`law_coefficients`), or the yield overlap delta_y [m] alone
    (docs/model.md eq. P3; inf: Hertz's law)."""
    row = np.zeros(N_COEF)
    row[COEF_A], row[COEF_C], row[COEF_MU], row[COEF_KS] = a, c, mu, k_s
    law = np.atleast_1d(np.asarray(law, float))
    row[COEF_DY : COEF_DY + len(law)] = law
    return row


def normal_law_of(s: Scenario, a: str, b: str) -> str:
    """The normal law (contact.normal_law, or its [[contact.pairs]] override) between
    materials a and b."""
    return s.contact.law_for_pair(a, b)


def law_yield_overlap(s: Scenario, a, b, b_name: str, e_star: float, r_star: float) -> float:
    """COEF_DY of a contact of material a (a granule's Material) with b (a granule's
    Material, or None for a rigid wall or the plate's face, whose material is b_name):
    the yield overlap delta_y [m] (docs/model.md eqs. P1, P3) of the softer body under the
    elastic-plastic law "thornton", inf under Hertz's law. (Validation refuses "thornton"
    where the Y it needs is unknown.)"""
    if normal_law_of(s, a.name, b_name) not in ("thornton", "johnson"):
        return math.inf
    return contact_yield_overlap(e_star, r_star, softer_yield_strength(a, b))


def law_coefficients(s: Scenario, a, b, b_name: str, e_star: float, r_star: float, length: float) -> np.ndarray:
    """The normal law's columns COEF_DY..COEF_XH of a contact of material a with b (as
    `law_yield_overlap`), `length` [m] the length that makes the approach speed a strain
    rate (the sum of the radii; a diameter against a rigid body). Hertz: [inf, 0...];
    "thornton": [delta_y, 0...]; "johnson": delta_y, R* Y, C, 1 / (length rate_ref), h,
    kappa and x_h of the softer body (docs/model.md section 3.10; absent rate fields: rate-free)."""
    if normal_law_of(s, a.name, b_name) == "johnson":
        return johnson_columns(softer_material(a, b), e_star, r_star, length)
    out = np.zeros(COEF_XH - COEF_DY + 1)
    out[0] = law_yield_overlap(s, a, b, b_name, e_star, r_star)
    return out


def johnson_columns(m, e_star: float, r_star: float, length: float) -> np.ndarray:
    """The law "johnson"'s columns COEF_DY..COEF_XH of a contact whose softer body is
    of Material m (its Y known), E* [Pa], R* [m], `length` [m] (`law_coefficients`)."""
    out = np.zeros(COEF_XH - COEF_DY + 1)
    out[0] = contact_yield_overlap(e_star, r_star, m.Y)
    out[COEF_SY - COEF_DY] = r_star * m.Y
    if m.C is not None and m.rate_ref is not None:
        out[COEF_RC - COEF_DY] = m.C
        out[COEF_RL - COEF_DY] = 1.0 / (length * m.rate_ref)
    out[COEF_H - COEF_DY] = DEFAULT_HARDNESS_RATIO if m.hardness_ratio is None else m.hardness_ratio
    out[COEF_KAPPA - COEF_DY] = DEFAULT_UNLOADING_FACTOR if m.unloading_factor is None else m.unloading_factor
    out[COEF_XH - COEF_DY] = hardness_overlap(out[COEF_H - COEF_DY])
    return out


def _granule_arrays(s: Scenario):
    x = np.array([g.x for g in s.granules], float)
    y = np.array([g.y for g in s.granules], float)
    r = np.array([g.radius for g in s.granules], float)
    rho = np.array([s.material(g.material).rho for g in s.granules], float)
    return x, y, r, rho


def masses_and_inertias(r: np.ndarray, rho: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ng,) masses [kg] and moments of inertia [kg m^2] of spheres of radii r [m] and
    densities rho [kg/m^3]: `sphere_mass` and `sphere_inertia` once per distinct (r, rho)."""
    r, rho = np.asarray(r, float), np.asarray(rho, float)
    if not len(r):
        return np.zeros(0), np.zeros(0)
    if (rho == rho[0]).all():  # one density: the distinct radii (a sort of numbers, not of rows)
        radii, which = np.unique(r, return_inverse=True)
        kinds = np.column_stack([radii, np.full(len(radii), rho[0])])
    else:
        kinds, which = np.unique(np.column_stack([r, rho]), axis=0, return_inverse=True)
    mass = np.array([sphere_mass(k[0], k[1]) for k in kinds], float)  # numpy scalars, as granule by granule
    inertia = np.array([sphere_inertia(k[0], k[1]) for k in kinds], float)
    which = which.reshape(-1)
    return mass[which], inertia[which]


def find_pairs(x: np.ndarray, y: np.ndarray, r: np.ndarray, gap_ratio: float) -> np.ndarray:
    """Potential granule-granule contacts: pairs whose initial surface gap is at most
    gap_ratio * min(R_i, R_j) (the topology is fixed, docs/model.md section 1)."""
    from granplate.model.neighbours import contact_pairs

    return contact_pairs(x, y, r, gap_ratio)


def find_wall_contacts(s: Scenario, x, y, r, z=None) -> np.ndarray:
    """(granule, wall) pairs whose initial gap is at most neighbour_gap * R."""
    return fixed_wall_contacts(s.walls, x, y, r, s.contact.neighbour_gap, z)


def find_pairs_and_walls(s: Scenario, x, y, r, z=None, candidates=None) -> tuple[np.ndarray, np.ndarray]:
    """The pairs and (granule, wall) contacts touching at t = 0 (within contact.neighbour_gap;
    z: the centres' third coordinate in space, None in the plane; candidates: sorted pairs
    holding every pair within the search distance, `model.neighbours.contact_pairs`)."""
    from granplate.model.neighbours import contact_pairs

    return contact_pairs(x, y, r, s.contact.neighbour_gap, z, candidates), find_wall_contacts(s, x, y, r, z)


def find_plate_contacts(s: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """Granules facing the plate's left edge at t = 0 (setup.plate_checks.faces_plate), as
    (on a face node: rigid layers, between nodes: patch contacts from the start; docs/model.md
    section 1.3)."""
    if s.plate is None or not s.granules:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    on, between = split_initial_contacts(s)
    return np.array(on, np.int64), np.array(between, np.int64)


def loaded_granules(s: Scenario, x, r) -> np.ndarray:
    """Mask of the granules the line load pushes: load.granules, or column 1 (the
    granules whose left surface is leftmost)."""
    n = len(x)
    if s.load.kind == "none" or s.load.target != "granules" or n == 0:
        return np.zeros(n, bool)
    if s.load.granules:
        labels = [g.label for g in s.granules]
        return np.array([lab in s.load.granules for lab in labels])
    left = x - r
    return np.abs(left - left.min()) <= 1e-9 * r.max()


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
    # per pair of materials: E*, alpha_n, mu, k_s, whether the law is elastic-plastic (one value each when one pair)
    e_star, alpha, mu, ks = (np.empty(len(pairs)) if combo is not None else 0.0 for _ in range(4))
    plastic = np.zeros(len(pairs), bool)
    for c, ka, kb in combos:
        values = (effective_modulus(ka, kb), *s.contact.for_pair(ka.name, kb.name))
        if combo is None:
            e_star, alpha, mu, ks = values
            plastic[:] = normal_law_of(s, ka.name, kb.name) != "hertz"
            continue
        on = combo == c
        for column, v in zip((e_star, alpha, mu, ks), values):
            column[on] = v
        plastic |= on & (normal_law_of(s, ka.name, kb.name) != "hertz")
    coef_a = 4.0 / 3.0 * e_star * np.sqrt(r_star)  # hertz_coefficient
    pair_coef = np.zeros((len(pairs), N_COEF))
    pair_coef[:, COEF_A] = coef_a
    pair_coef[:, COEF_C] = alpha * np.sqrt(m_star * coef_a)  # damping_coefficient
    pair_coef[:, COEF_MU], pair_coef[:, COEF_KS], pair_coef[:, COEF_DY] = mu, ks, math.inf
    for p in np.flatnonzero(plastic).tolist():
        a, b = mats[i[p]], mats[j[p]]
        e_p = e_star if combo is None else float(e_star[p])
        pair_coef[p, COEF_DY : COEF_XH + 1] = law_coefficients(
            s, a, b, b.name, e_p, float(r_star[p]), float(r[i[p]] + r[j[p]])
        )
    if s.contact.tangential_law == "mindlin":
        compliance = np.array([tangential_compliance(m.E, m.nu) for m in kinds])
        mindlin_columns(pair_coef, compliance[kind[i]] + compliance[kind[j]], s.contact.tangential_damping)
    return pair_coef


def mindlin_columns(coef: np.ndarray, compliance: np.ndarray, damping: float) -> None:
    """Rows of `coef` made Mindlin's (docs/model.md section 3.16) in place: 8 G* from
    1 / G* = `compliance` [1/Pa] (per row, eq. M1) into COEF_KT, the Coulomb coefficient moved
    from COEF_MU (which the tanh law reads) to COEF_MUT, the tangential damping factor x_t
    (contact.tangential_damping) into COEF_XT."""
    coef[:, COEF_KT] = mindlin_coefficient(1.0) / compliance
    coef[:, COEF_MUT] = coef[:, COEF_MU]
    coef[:, COEF_MU] = 0.0
    coef[:, COEF_XT] = damping


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
    )
    if s.contact.tangential_law == "mindlin":
        rows = row.reshape(1, -1)
        mindlin_columns(rows, np.array([tangential_compliance(a.E, a.nu)]), s.contact.tangential_damping)
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
    plastic = np.zeros(len(wc), bool)
    for k in np.unique(w).tolist():
        wall = walls[k]
        nrm = np.asarray(wall.normal, float)
        at = w == k
        wall_geo[at] = (*(nrm / np.linalg.norm(nrm)), wall.offset)
        for c in np.unique(kind[i[at]]).tolist():
            on = at & (kind[i] == c)
            e_star[on] = effective_modulus(kinds[c], None)
            alpha[on], wall_coef[on, COEF_MU], wall_coef[on, COEF_KS] = s.contact.for_pair(kinds[c].name, wall.material)
            plastic |= on & (normal_law_of(s, kinds[c].name, wall.material) != "hertz")
    ri = r[i]
    coef_a = 4.0 / 3.0 * e_star * np.sqrt(ri)  # hertz_coefficient with R* = R
    wall_coef[:, COEF_A] = coef_a
    wall_coef[:, COEF_C] = alpha * np.sqrt(mass[i] * coef_a)  # damping_coefficient with m* = m
    wall_coef[:, COEF_DY] = math.inf
    for p in np.flatnonzero(plastic).tolist():
        wall_coef[p, COEF_DY : COEF_XH + 1] = law_coefficients(
            s, mats[i[p]], None, s.walls[w[p]].material, float(e_star[p]), float(ri[p]), 2.0 * float(ri[p])
        )
    if s.contact.tangential_law == "mindlin":  # a rigid wall: the granule's compliance alone
        compliance = np.array([tangential_compliance(kinds[c].E, kinds[c].nu) for c in kind[i]])
        mindlin_columns(wall_coef, compliance, s.contact.tangential_damping)
    return wall_geo, wall_coef


def plate_contact_coefficients(s: Scenario, mats, r: np.ndarray, pc: np.ndarray) -> np.ndarray:
    """(nk, N_COEF) coefficients against the plate's rigid layers: E_k, R_k -> infinity
    and m_k -> 0, so m* = 0 (no viscous damping)."""
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
        )
    return pc_coef


def face_contacts_possible(s: Scenario, plate_model) -> bool:
    """Whether granules may get patch contacts during the run (docs/model.md section 3.5):
    dynamic detection, granules, and a plate integrated in all its modes or in the
    truncated basis, whose static correction covers every face dof (section 4.5; a dense
    basis cut to plate.n_modes has none)."""
    return (
        s.contact.detection == "dynamic"
        and plate_model is not None
        and len(s.granules) > 0
        and (plate_model.n_modes == plate_model.n_red or plate_model.truncated)
    )


def plate_modal_arrays(s: Scenario, y: np.ndarray, pc: np.ndarray):
    """The plate's model (or None) and its PlateArrays (modes, shapes at the driving
    DOFs of the contacts pc, modal edge load, and the face's shapes when patch contacts
    may form)."""
    plate_model = None
    nk = len(pc)
    face_y, phi_face, resid_face = np.zeros(0), np.zeros((0, 0)), np.zeros((0, 0))
    if s.plate is not None:
        from granplate.plate import build_plate

        edge = None
        if s.load.kind == "line" and s.load.target == "plate":
            edge = (s.load.y0, s.load.length)
        plate_model = build_plate(
            s.plate,
            s.plate.x0,
            [float(y[i]) for i in pc],
            edge_load=edge,
            material=s.material(s.plate.material),
        )
        omega2 = np.asarray(plate_model.omega, float) ** 2
        # copies: the loop writes into its arrays, the plate model is shared (build_plate keeps it)
        phi_d = np.array(plate_model.phi_drive, float, order="C")
        load_modal = np.array(plate_model.edge_load_modal, float, order="C")
        resid = np.array(plate_model.resid, float, order="C")
        if face_contacts_possible(s, plate_model):
            face_y = np.array(plate_model.face_y, float, order="C")
            phi_face = np.array(plate_model.phi_face, float, order="C")
            resid_face = np.array(plate_model.resid_face, float, order="C")
    else:
        omega2 = np.zeros(0)
        phi_d = np.zeros((0, 0))
        load_modal = np.zeros(0)
        resid = np.zeros((0, 0))
    if phi_d.shape != (2 * nk, len(omega2)):
        phi_d = phi_d.reshape(2 * nk, len(omega2))
    return plate_model, PlateArrays(
        omega2=omega2,
        phi_d=phi_d,
        load_modal=load_modal,
        resid=resid,
        face_y=face_y,
        phi_face=phi_face,
        resid_face=resid_face,
    )


def loop_config(
    s: Scenario,
    fres: np.ndarray,
    tres: np.ndarray,
    r: np.ndarray,
    mass: np.ndarray,
    face: bool = False,
    floor: float | None = None,
) -> Config:
    """The loop's scalar settings from the scenario's load, contact, time and solver;
    face: whether granules may get patch contacts during the run; floor: the implicit
    scheme's force floor [N] when given (else `force_floor` of the plane's load)."""
    t = s.time
    sol = s.solver
    q0 = s.load.q0 if s.load.kind == "line" else 0.0
    plate = s.plate if isinstance(s.plate, Plate) else None  # the plane's plate (an elastic solid: model.body)
    return Config(
        q0=float(q0),
        duration=float(s.load.duration),
        clip=bool(s.contact.clip_tensile),
        lambda_target=float(sol.lambda_target),
        rtol=float(sol.iteration_rtol),
        atol=float(sol.iteration_atol),
        max_iter=int(sol.max_iterations),
        energy_tol=float(sol.energy_tol),
        dt_max=float(
            implicit_step_max(sol.implicit_dt_max, t.output_interval) if sol.scheme == "implicit" else t.dt_max
        ),
        dt_min=float(t.dt_min),
        out_dt=float(t.output_interval),
        t_end=float(t.t_end),
        load_on_plate=bool(s.load.kind == "line" and s.load.target == "plate"),
        arm_shrink=1.0 if s.contact.torque_arm == "contact_point" else 0.0,
        lammps_arms=s.contact.torque_arm == "lammps",
        scheme=scheme_number(sol.scheme),
        error_tol=float(sol.error_tol),
        force_floor=force_floor(q0, fres, tres, r, mass, s, t.output_interval) if floor is None else float(floor),
        rebuild_move=rebuild_move(s.contact.skin, r),
        overlap_stop=float(s.contact.overlap_stop),
        plate_x0=float(plate.x0) if plate is not None else math.inf,
        plate_ylo=float(plate.y0) if plate is not None else 0.0,
        plate_yhi=float(plate.y0 + plate.height) if plate is not None else 0.0,
        split_friction=sol.granular_friction == "split",
        face_skin=float(s.contact.skin) if face else 0.0,
        patch_width=float(plate.layer_width) if plate is not None else 0.0,
        threads=loop_threads(sol.threads, len(r), sol.scheme),
    )


def rebuild_move(skin: float, r: np.ndarray) -> float:
    """How far a granule may move [m] before the contact list is rebuilt (dynamic) or
    searched for unlisted overlaps (fixed): skin * R_min / 2 (docs/model.md section 1.3)."""
    return 0.5 * skin * float(r.min()) if len(r) else 0.0


def initial_state(s: Scenario, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(ng, 6) x, y, theta = 0, vx, vy, omega of every granule at t = 0."""
    y0 = np.zeros((len(x), 6))
    y0[:, 0] = x
    y0[:, 1] = y
    y0[:, 3] = [g.vx for g in s.granules]
    y0[:, 4] = [g.vy for g in s.granules]
    y0[:, 5] = [g.omega for g in s.granules]
    return y0


def build_model(scenario: Scenario) -> Model:
    """Validate, resolve and turn a scenario into the loop's arrays (in space, dimension =
    3: `model.space.build_space_model`)."""
    from granplate.model.static import precompressed

    validate(scenario)
    s = resolve(scenario)
    if s.dimension == 3:
        from granplate.model.space import build_space_model

        return precompressed(build_space_model(s))
    x, y, r, rho = _granule_arrays(s)
    mats = [s.material(g.material) for g in s.granules]
    mass, inertia = masses_and_inertias(r, rho)
    pairs = find_pairs(x, y, r, s.contact.neighbour_gap)
    wc = find_wall_contacts(s, x, y, r)
    loop_pairs, loop_wc = contact_lists(s.contact, s.walls, x, y, r)
    wall_geo, wall_coef = wall_arrays(s, mats, r, mass, loop_wc)
    pc, patches = find_plate_contacts(s)
    fres, tres = shock_resultants(y, r, loaded_granules(s, x, r), s.load.y0, s.load.length)
    plate_model, plate_arrays = plate_modal_arrays(s, y, pc)
    if len(patches) and len(plate_arrays.face_y) == 0:  # pragma: no cover - guarded by validation
        raise ScenarioError(
            "contact.detection",
            s.contact.detection,
            "granules touching the face between nodes at t = 0 need patch contacts",
        )
    granular = Granular(
        mass=mass,
        inertia=inertia,
        radius=r,
        pair_ij=loop_pairs,
        pair_coef=pair_coefficients(s, mats, r, mass, loop_pairs),
        wall_i=np.ascontiguousarray(loop_wc[:, 0]),
        wall_geo=wall_geo,
        wall_coef=wall_coef,
        wall_w=np.ascontiguousarray(loop_wc[:, 1]),
        pc_i=pc,
        pc_x=np.full(len(pc), float(s.plate.x0) if s.plate is not None else 0.0),
        pc_coef=plate_contact_coefficients(s, mats, r, pc),
        shock_force=fres,
        shock_torque=tres,
        pair_hist=no_history(len(loop_pairs)),
        wall_hist=no_history(len(loop_wc)),
        pc_hist=no_history(len(pc)),
    )
    drives = drive_fields(s, np.column_stack([x, y]))
    granular = granular._replace(**drives)
    model = Model(
        scenario=s,
        labels=tuple(g.label or str(i + 1) for i, g in enumerate(s.granules)),
        granular=granular,
        plate_arrays=plate_arrays,
        config=loop_config(s, fres, tres, r, mass, face=len(plate_arrays.face_y) > 0),
        plate=plate_model,
        initial_state=driven_initial_state(initial_state(s, x, y), drives),
        pairs=pairs,
        wall_contacts=wc,
        plate_contacts=pc,
        materials=tuple(mats),
        initial_patches=patches,
    )
    return precompressed(model)


def carried_history(old_keys: np.ndarray, old_hist: np.ndarray, new_keys: np.ndarray, store: dict) -> np.ndarray:
    """The histories (columns HIST_*) of the contacts new_keys (n, 2) of a rebuilt list:
    each one's row from the old list (old_keys, old_hist) or from `store`, which holds the
    contacts that left the list with a history, keyed (i, j), and takes those leaving now.
    A contact keeps its largest overlap (and so its plastic flattening, docs/model.md
    section 3.6) for the whole run, whether or not the list holds it. Keys are matched by
    sorting (no per-contact Python): a rebuild of 10^6 contacts takes a fraction of a second."""
    new_keys = np.asarray(new_keys, np.int64).reshape(-1, 2)
    has = (old_hist[:, HIST_MAX] > 0.0) | np.any(old_hist[:, HIST_XI : HIST_XI + 3] != 0.0, axis=1)
    keys = np.asarray(old_keys, np.int64).reshape(-1, 2)[has]
    rows = old_hist[has]
    if store:
        keys = np.vstack([np.array(list(store), np.int64).reshape(-1, 2), keys])
        rows = np.vstack([np.array(list(store.values()), float).reshape(-1, old_hist.shape[1]), rows])
    out = no_history(len(new_keys))
    store.clear()
    if not len(keys):
        return out
    span = int(max(keys[:, 1].max(), new_keys[:, 1].max() if len(new_keys) else 0)) + 1
    code = keys[:, 0] * span + keys[:, 1]
    new_code = new_keys[:, 0] * span + new_keys[:, 1]
    order = np.argsort(new_code, kind="stable")
    pos = np.minimum(np.searchsorted(new_code[order], code), max(len(order) - 1, 0))
    found = (new_code[order[pos]] == code) if len(order) else np.zeros(len(code), bool)
    out[order[pos[found]]] = rows[found]  # the old list's row after the store's (it is the newer)
    store.update(zip(map(tuple, keys[~found].tolist()), rows[~found]))
    return out


def cached_pair_coefficients(s: Scenario, mats, g: Granular, pairs: np.ndarray, known: dict) -> np.ndarray:
    """`pair_coefficients` of the pairs (n, 2), each pair's row computed once per run:
    known["codes"] (sorted i * ng + j) and known["rows"] hold those met so far and take the
    new ones (the same numbers, bit for bit, as computing them again)."""
    ng = len(g.radius)
    code = pairs[:, 0] * ng + pairs[:, 1]
    kc = known.get("codes", np.zeros(0, np.int64))
    kr = known.get("rows", np.zeros((0, N_COEF)))
    pos = np.minimum(np.searchsorted(kc, code), max(len(kc) - 1, 0))
    hit = (kc[pos] == code) if len(kc) else np.zeros(len(code), bool)
    out = np.empty((len(pairs), N_COEF))
    out[hit] = kr[pos[hit]]
    if not hit.all():
        rows = pair_coefficients(s, mats, g.radius, g.mass, pairs[~hit])
        out[~hit] = rows
        codes = np.concatenate([kc, code[~hit]])
        order = np.argsort(codes, kind="stable")
        known["codes"], known["rows"] = codes[order], np.vstack([kr, rows])[order]
    return out


def granular_with_contacts(
    model: Model,
    g: Granular,
    pairs: np.ndarray,
    wc: np.ndarray,
    known: dict | None = None,
    stores: tuple[dict, dict] | None = None,
) -> Granular:
    """`g` with the contact lists pairs (np, 2) and wc (nw, 2) [granule, wall], their
    coefficients and their histories carried over (`carried_history`; stores: the pairs'
    and the walls' histories off the list, keyed (i, j) and (i, wall), updated); known:
    the pairs' coefficient rows met so far (`cached_pair_coefficients`), reused and extended."""
    s, mats = model.scenario, list(model.materials)
    known = {} if known is None else known
    stores = ({}, {}) if stores is None else stores
    pairs = np.ascontiguousarray(pairs, np.int64).reshape(-1, 2)
    pair_coef = cached_pair_coefficients(s, mats, g, pairs, known)
    wall_geo, wall_coef = wall_arrays(s, mats, g.radius, g.mass, wc, model.walls)
    wc = np.asarray(wc, np.int64).reshape(-1, 2)
    return g._replace(
        pair_ij=pairs,
        pair_coef=pair_coef,
        wall_i=np.ascontiguousarray(wc[:, 0]),
        wall_geo=wall_geo,
        wall_coef=wall_coef,
        wall_w=np.ascontiguousarray(wc[:, 1]),
        pair_hist=carried_history(g.pair_ij, g.pair_hist, pairs, stores[0]),
        wall_hist=carried_history(np.column_stack([g.wall_i, g.wall_w]), g.wall_hist, wc, stores[1]),
    )


def granular_with_patch_contacts(model: Model, g: Granular, new: np.ndarray) -> Granular:
    """`g` with a patch contact appended for each granule of `new` (docs/model.md section
    3.5): the coefficients of a rigid layer (m* = 0), the overlap measured from the
    undeformed face, pc_patch = 1, and a fresh history."""
    new = np.asarray(new, np.int64).ravel()
    s, mats = model.scenario, list(model.materials)
    patch = g.pc_patch if len(g.pc_patch) == len(g.pc_i) else np.zeros(len(g.pc_i), np.int64)
    return g._replace(
        pc_i=np.concatenate([g.pc_i, new]).astype(np.int64),
        pc_x=np.concatenate([g.pc_x, np.full(len(new), float(s.plate.x0))]),
        pc_coef=np.ascontiguousarray(
            np.vstack([g.pc_coef.reshape(-1, N_COEF), plate_contact_coefficients(s, mats, g.radius, new)])
        ),
        pc_patch=np.concatenate([patch, np.ones(len(new), np.int64)]),
        pc_hist=np.vstack([g.pc_hist.reshape(-1, g.pc_hist.shape[1]), no_history(len(new))]),
    )
