"""Scenario -> model arrays in space (`dimension = 3`, docs/model.md section 3.7): the
granules' centres, velocities and spin vectors, their pair and wall contact lists and
coefficients (the same laws and coefficients as the plane, `model.arrays`), the shock's
shares (model.loads: "force", a half-sine total force shared by the loaded granules along
a direction, docs/model.md section 5.4; "line", the plane's line load on a planar
packing, section 5.1), the elastic body of its [plate] (model.body) and
the loop's settings. `model.arrays.build_model` calls `build_space_model` for a scenario
of dimension 3: the one place the model's dimension is decided.
"""

from __future__ import annotations

import math
import operator

import numpy as np

from granplate.model import loads
from granplate.model.contacts import contact_lists
from granplate.model.coefficients import scenario_history_columns
from granplate.model.inputs import STATE_COLUMNS, Granular3, PlateArrays, no_history
from granplate.model.relists import with_pair_kinds
from granplate.setup.pairs import contact_search_distance, superset_pairs
from granplate.physics.contact import N_COEF
from granplate.setup.scenario import Scenario


def centres(s: Scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """x, y, z [m] and radii [m] of the granules."""
    g = s.granules
    return (
        np.array([q.x for q in g], float),
        np.array([q.y for q in g], float),
        np.array([q.z for q in g], float),
        np.array([q.radius for q in g], float),
    )


def spin_vector(omega) -> tuple[float, float, float]:
    """A granule's spin (wx, wy, wz) [rad/s] from its `omega` field (a 3-vector in space)."""
    w = tuple(float(v) for v in omega)
    return (w[0], w[1], w[2])


def initial_state_3d(s: Scenario) -> np.ndarray:
    """(ng, 9) x, y, z, vx, vy, vz, wx, wy, wz of every granule at t = 0."""
    g = s.granules
    y0 = np.zeros((len(g), STATE_COLUMNS[3]))
    if len(g):
        y0[:, :6] = np.array(list(map(operator.attrgetter("x", "y", "z", "vx", "vy", "vz"), g)), float)
        y0[:, 6:] = np.array(list(map(operator.attrgetter("omega"), g)), float)  # three numbers each (validated)
    return y0


def granule_momentum(m: float, r: float, g) -> float:
    """m (|v| + R |omega|) [kg m/s] of granule g of mass m [kg] and radius r [m]."""
    return m * (math.sqrt(g.vx**2 + g.vy**2 + g.vz**2) + r * math.sqrt(sum(w * w for w in spin_vector(g.omega))))


def force_floor_3d(
    s: Scenario, mass: np.ndarray, r: np.ndarray, shares: np.ndarray, out_dt: float, state: np.ndarray | None = None
) -> float:
    """The implicit scheme's smallest force scale [N] (as model.arrays.force_floor): a
    fraction of the shock's peak force plus the initial momentum per output interval
    (the sum over the granules in their order; those at rest add nothing, so only the
    moving ones, by `state`'s velocities and spins when given, are summed)."""
    from granplate.model.arrays import FORCE_FLOOR_FRACTION

    if len(r) == 0:
        return 0.0
    shock = abs(loads.amplitude(s)) * float(np.abs(shares).sum())
    moving = range(len(r)) if state is None else np.flatnonzero((state[:, 3:] != 0.0).any(axis=1)).tolist()
    momentum = sum(granule_momentum(mass[i], r[i], s.granules[i]) for i in moving)
    return FORCE_FLOOR_FRACTION * (shock + float(momentum) / out_dt)


def frictionless(s: Scenario) -> bool:
    """Whether no granule-granule or granule-wall contact of the scenario can have friction
    (contact.mu and every [[contact.pairs]] override between its materials zero): its
    friction need not be split off the RK4 step (solver.rk4: the step then reuses the
    derivative at t_n as its first stage, one force evaluation fewer)."""
    names = {g.material for g in s.granules}
    partners = names | {w.material for w in s.walls}
    return all(s.contact.for_pair(a, b)[1] == 0.0 for a in names for b in partners)


def shared_candidates(s: Scenario, x, y, z, r) -> np.ndarray | None:
    """One k-d tree search for both the pairs touching at t = 0 and the loop's Verlet list
    (each keeps its own pairs of these by its exact test): sorted pairs holding every pair
    within the larger of their search distances (the one validation kept, when it searched
    the same centres that far: setup.pairs.superset_pairs), or None for fewer than two."""
    if len(r) < 2:
        return None
    c = s.contact
    distance = contact_search_distance(float(r.max()), c.neighbour_gap, c.skin, c.detection == "dynamic")
    return superset_pairs(np.column_stack([x, y, z]), distance)  # validation's search, when it kept it


def build_space_model(s: Scenario):
    """The Model of a validated, resolved scenario of dimension 3, with its elastic body
    (model.body) when it has a [plate]."""
    from granplate.model.drives import drive_fields, driven_initial_state
    from granplate.model.arrays import (
        Model,
        find_pairs_and_walls,
        loop_config,
        masses_and_inertias,
        pair_coefficients,
        wall_arrays,
    )

    x, y, z, r = centres(s)
    mats = [s.material(g.material) for g in s.granules]
    rho = np.array([m.rho for m in mats], float)
    mass, inertia = masses_and_inertias(r, rho)
    cand = shared_candidates(s, x, y, z, r)
    pairs, wc = find_pairs_and_walls(s, x, y, r, z, cand)
    loop_pairs, loop_wc = contact_lists(s.contact, s.walls, x, y, r, z, cand)
    state = initial_state_3d(s)
    wall_geo, wall_coef = wall_arrays(s, mats, r, mass, loop_wc)
    shares, torques = loads.resultants(s, np.column_stack([x, y, z]), r)
    columns = scenario_history_columns(s)  # history rows: 4 numbers; 18 under a history law (11 under verlet)
    granular = Granular3(
        mass=mass,
        inertia=inertia,
        radius=r,
        pair_ij=loop_pairs,
        pair_coef=pair_coefficients(s, mats, r, mass, loop_pairs),
        wall_i=np.ascontiguousarray(loop_wc[:, 0]),
        wall_geo=wall_geo,
        wall_coef=wall_coef,
        wall_w=np.ascontiguousarray(loop_wc[:, 1]),
        pc_i=np.zeros(0, np.int64),
        pc_x=np.zeros(0),
        pc_coef=np.zeros((0, N_COEF)),
        shock_force=shares,
        shock_torque=torques,
        pair_hist=no_history(len(loop_pairs), columns),
        wall_hist=no_history(len(loop_wc), columns),
        pc_hist=no_history(0, columns),
    )
    drives = drive_fields(s, np.column_stack([x, y, z]))
    granular = with_pair_kinds(granular._replace(**drives))
    cfg = loop_config(
        s,
        np.zeros(len(r)),
        np.zeros(len(r)),
        r,
        mass,
        floor=force_floor_3d(s, mass, r, shares, s.time.output_interval, state),
    )._replace(
        q0=loads.amplitude(s), dimension=3, split_friction=s.solver.granular_friction == "split" and not frictionless(s)
    )
    solid, body, rigid = None, None, np.zeros(len(r), bool)
    if s.plate is not None:
        from granplate.model.body import build_body

        solid, body, rigid = build_body(s, mats, r, mass)
    nm = 0 if solid is None else solid.n_modes
    omega2 = np.zeros(0) if solid is None else solid.omega**2
    plate_arrays = PlateArrays(omega2=omega2, phi_d=np.zeros((0, nm)), load_modal=np.zeros(nm))
    return Model(
        scenario=s,
        labels=tuple(g.label or str(i + 1) for i, g in enumerate(s.granules)),
        granular=granular,
        plate_arrays=plate_arrays,
        config=cfg,
        plate=None,
        initial_state=driven_initial_state(state, drives),
        pairs=pairs,
        wall_contacts=wc,
        plate_contacts=np.zeros(0, np.int64),
        materials=tuple(mats),
        solid=solid,
        body=body,
        body_rigid=rigid,
    )
