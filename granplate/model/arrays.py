"""Scenario -> model arrays: contact topology, coefficients (eqs. 3-4), load resultants
and the plate's modal model, built once per run (the plate part is cached on disk).
The coefficient rows are `model.coefficients`' and the lists replaced during a run
`model.relists`'; their names are importable from here too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from granplate.model.contacts import contact_lists, fixed_wall_contacts
from granplate.model.dimension import of_number
from granplate.model.drives import drive_fields, driven_initial_state
from granplate.model import loads
from granplate.model.inputs import Config, Granular, PlateArrays, no_history, scheme_number
from granplate.errors import ScenarioError
from granplate.model.coefficients import pair_coefficients, plate_contact_coefficients, scenario_history_columns
from granplate.model.coefficients import wall_arrays

# the coefficients and the lists replaced during a run have modules of their own; their
# names are importable from here as before
from granplate.model.coefficients import coefficient_row as coefficient_row
from granplate.model.coefficients import law_coefficients as law_coefficients
from granplate.model.coefficients import material_indices as material_indices, normal_law_of as normal_law_of
from granplate.model.coefficients import pair_coefficient_row as pair_coefficient_row
from granplate.model.coefficients import wall_coefficient_row as wall_coefficient_row
from granplate.model.relists import cached_pair_coefficients as cached_pair_coefficients
from granplate.model.relists import carried_history as carried_history
from granplate.model.relists import granular_with_contacts as granular_with_contacts
from granplate.model.relists import with_pair_kinds
from granplate.model.relists import granular_with_patch_contacts as granular_with_patch_contacts
from granplate.setup.geometry import resolve
from granplate.setup.law_registry import TANGENTIAL_LAW_REGISTRY
from granplate.setup.materials import sphere_inertia, sphere_mass
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

        edge = loads.plate_edge(s)
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


def rate_friction(c) -> bool:
    """Whether any pair or wall contact of the Contact settings `c` can carry a rate law's
    friction (the tangential law without history, mu > 0 by default or for some material
    pair): False lets velocity Verlet skip its per-step look for friction."""
    if TANGENTIAL_LAW_REGISTRY[c.tangential_law].history:
        return False
    return c.mu != 0.0 or any(p.mu is not None and p.mu != 0.0 for p in c.pairs)


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
    q0 = loads.amplitude(s)
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
        energy_span=float(t.t_end if sol.energy_span is None else sol.energy_span),
        load_on_plate=loads.plate_edge(s) is not None,
        arm_shrink=1.0 if s.contact.torque_arm == "contact_point" else 0.0,
        lammps_arms=s.contact.torque_arm == "lammps",
        history_friction=TANGENTIAL_LAW_REGISTRY[s.contact.tangential_law].history,
        history_stages=TANGENTIAL_LAW_REGISTRY[s.contact.tangential_law].history and sol.scheme != "verlet",
        rate_friction=rate_friction(s.contact),
        half_step_damping=sol.verlet_damping == "half_step",
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
    """Validate, resolve and turn a scenario into the loop's arrays, by its dimension's
    builder (`MODEL_BUILDERS`: `plane_model`, or in space `model.space.build_space_model`),
    from its static state where it has one (`model.static.precompressed`); the model's
    scenario has the output stride of a run of many granules (`setup.output_stride`)."""
    from granplate.model.static import precompressed
    from granplate.setup.output_stride import with_output_stride

    validate(scenario)
    s = with_output_stride(resolve(scenario))  # a run of many granules outputs at a stride
    return precompressed(MODEL_BUILDERS[of_number(s.dimension).name](s))


def space_model(s: Scenario) -> Model:
    """The loop's arrays of resolved scenario `s` in space (`model.space.build_space_model`),
    its elastic solid in its sag under its own weight (`model.body_weight.weighed_body`)."""
    from granplate.model.body_weight import weighed_body
    from granplate.model.space import build_space_model

    return weighed_body(build_space_model(s))


def plane_model(s: Scenario) -> Model:
    """The loop's arrays of resolved scenario `s` in the plane, its plate in its sag under
    its own weight (`model.plate_weight.weighed`)."""
    from granplate.model.plate_weight import weighed

    x, y, r, rho = _granule_arrays(s)
    mats = [s.material(g.material) for g in s.granules]
    mass, inertia = masses_and_inertias(r, rho)
    pairs = find_pairs(x, y, r, s.contact.neighbour_gap)
    wc = find_wall_contacts(s, x, y, r)
    loop_pairs, loop_wc = contact_lists(s.contact, s.walls, x, y, r)
    wall_geo, wall_coef = wall_arrays(s, mats, r, mass, loop_wc)
    pc, patches = find_plate_contacts(s)
    forces, torques = loads.resultants(s, np.column_stack([x, y]), r)
    fres, tres = np.ascontiguousarray(forces[:, 0]), np.ascontiguousarray(torques[:, 2])  # the plane's x and z
    plate_model, plate_arrays = plate_modal_arrays(s, y, pc)
    if len(patches) and len(plate_arrays.face_y) == 0:  # pragma: no cover - guarded by validation
        raise ScenarioError(
            "contact.detection",
            s.contact.detection,
            "granules touching the face between nodes at t = 0 need patch contacts",
        )
    columns = scenario_history_columns(s)  # history rows: 4 numbers; 18 under a history law (11 under verlet)
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
        pair_hist=no_history(len(loop_pairs), columns),
        wall_hist=no_history(len(loop_wc), columns),
        pc_hist=no_history(len(pc), columns),
    )
    drives = drive_fields(s, np.column_stack([x, y]))
    granular = with_pair_kinds(granular._replace(**drives))
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
    return weighed(model)


#: the model's builder of a resolved scenario by its dimension's name (model.dimension)
MODEL_BUILDERS = {"plane": plane_model, "space": space_model}
