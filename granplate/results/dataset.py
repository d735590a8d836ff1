"""Output buffers -> an xarray Dataset with units and descriptions; netCDF I/O.

Every name is documented in docs/output.md. The scenario (as TOML), the package version
and the solver's figures travel in the attributes, so any figure can be traced back.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from dataclasses import replace
from typing import Any, Callable, NamedTuple

import numpy as np
import xarray as xr

from granplate.version import __version__
from granplate.model.dimension import DIMENSIONS, Dimension, of_number, of_state
from granplate.plate.peaks import BLOCK, block_starts, peak_maxima, split_coordinates, time_maxima
from granplate.solver import state as K
from granplate.results.contact_table import LINK_VARIABLES
from granplate.results.yielding import largest, pair_yield
from granplate.solver.driver import INTERRUPTED_STATUS

#: name -> (units, description) of every data variable
VARIABLES: dict[str, tuple[str, str]] = {
    "x": ("m", "granule centre, horizontal"),
    "y": ("m", "granule centre, vertical"),
    "theta": ("rad", "granule rotation (anticlockwise)"),
    "vx": ("m/s", "granule velocity, horizontal"),
    "vy": ("m/s", "granule velocity, vertical"),
    "omega": ("rad/s", "granule angular velocity (anticlockwise)"),
    "z": ("m", "granule centre, depth (dimension = 3)"),
    "vz": ("m/s", "granule velocity, depth (dimension = 3)"),
    "omega_x": ("rad/s", "granule spin vector, x component (dimension = 3)"),
    "omega_y": ("rad/s", "granule spin vector, y component (dimension = 3)"),
    "omega_z": ("rad/s", "granule spin vector, z component (dimension = 3)"),
    "E_shock": ("J", "work of the applied shock, int sum(F_i vx_i + tau_i omega_i) dt or int F.dx/dt (bare plate)"),
    "E_granular": (
        "J",
        "granular energy E_g: kinetic (translation, rotation) + 2/5 A delta^5/2 of every granule, wall and plate contact (eq. 9)",
    ),
    "E_plate": ("J", "plate energy E_p = 1/2 v^T M v + 1/2 x^T K x (eq. 9)"),
    "E_plate_dynamic": (
        "J",
        "plate energy about its static state at t = 0: E_p - E_p(0) - F_s . (u - u_s) (a precompressed plate)",
    ),
    "D_viscous": ("J", "energy dissipated by the damping part of the normal forces (eq. 10)"),
    "D_friction": ("J", "energy dissipated by friction (eq. 10)"),
    "D_plastic": ("J", "plastic work of the contacts that yield (docs/model.md eq. P10; 0 under Hertz's law)"),
    "pair_max_contact_pressure": (
        "Pa",
        "largest Hertz peak pressure p0 = (2/pi) E* sqrt(delta/R*) over the pair's contacts and the run (docs/model.md eq. P2)",
    ),
    "pair_yield_onset_ratio": (
        "1",
        "that p0 over the yield onset 1.6 Y of the softer body (eq. P1); NaN where Y is unknown",
    ),
    "pair_yield_strength": (
        "Pa",
        "Y of the softer body of the pair (a wall or the plate's face: the granule's); NaN where unknown",
    ),
    "pair_max_pressure_time": ("s", "when the contact of that largest p0 reached its largest overlap"),
    "pair_max_pressure_contact": ("1", "that contact: granule labels, or a granule and 'wall w' / 'plate'"),
    "pair_normal_law": ("1", "the pair's normal law (contact.normal_law: hertz, thornton or johnson)"),
    "E_contact": ("J", "elastic energy stored in all contacts (part of E_granular)"),
    "KE_horizontal": ("J", "granular kinetic energy, horizontal translation"),
    "KE_vertical": ("J", "granular kinetic energy, vertical translation"),
    "KE_rotational": ("J", "granular kinetic energy, rotation"),
    "KE_depth": ("J", "granular kinetic energy, translation along z (dimension = 3)"),
    "energy_residual": (
        "1",
        "(E_p + E_g + D - E_shock - E_initial) / max over past times of (E_shock + E_initial), eq. 11",
    ),
    "energy_residual_max": ("1", "largest |energy_residual| over the steps since the previous output"),
    "max_von_mises": ("Pa", "maximum over the plate's quadrature points of the plane-stress von Mises stress (eq. 12)"),
    "max_von_mises_disc": (
        "Pa",
        "largest von Mises stress averaged over a disc of radius plate.stress_radius (eq. 12, docs/model.md section 4.4)",
    ),
    "max_eps_yy": ("1", "maximum over the plate's quadrature points of |eps_yy|"),
    "plate_vx_symmetry": ("m/s", "plate horizontal velocity along the symmetry line y = y0 + height/2"),
    "body_q": ("kg^1/2 m", "the elastic body's modal coordinates (M-orthonormal modes; dimension = 3)"),
    "body_qd": ("kg^1/2 m/s", "the elastic body's modal velocities (dimension = 3)"),
    "plate_ux": ("m", "plate nodal displacement, horizontal (at field_time)"),
    "plate_uy": ("m", "plate nodal displacement, vertical (at field_time)"),
    "plate_von_mises": ("Pa", "largest von Mises stress in each element (at field_time)"),
    "contact_normal_force": ("N", "normal force on the plate at each plate contact (+x)"),
    "contact_tangential_force": ("N", "friction force on the plate at each contact (+y)"),
    "contact_slip_rate": ("m/s", "tangential slip rate v_t at each plate contact (eq. 6)"),
    "local_map_modulus": ("1", "largest |lambda| of the frictional local map (eq. 8) since the previous output"),
    "iterations": ("1", "largest number of interface iterations a contact's force needed since the previous output"),
    "dt_min": ("s", "smallest time step since the previous output"),
    "dt_max": ("s", "largest time step since the previous output"),
    "n_steps": ("1", "time steps taken so far"),
    "n_iterations": ("1", "interface iterations taken so far"),
    "E_gravity": ("J", "work of gravity on the granules, sum of m g . (x - x(0)) (docs/model.md section 3.11)"),
    "E_drive": ("J", "work of the drives on the granules (docs/model.md section 3.11)"),
    "wall_force": ("N", "normal force each wall receives from the granules (positive in compression)"),
    "drive_force": ("N", "force each drive applies on its wall or granule along its direction"),
    "drive_displacement": ("m", "displacement of each drive's wall or granule along its direction since t = 0"),
    "sensor_force": (
        "N",
        "each sensor's reading: half the sum of the normal contact forces on its granule (compression positive; docs/model.md section 3.15)",
    ),
    "contact_time_formed": (
        "s",
        "time each plate contact formed: 0 for those at t = 0, a patch contact's when its granule came within contact.skin R of the face",
    ),
}


VARIABLES.update(LINK_VARIABLES)  # the contact table's (results.contact_table)


#: the Dataset's names of the granules' state columns, by the number of columns (the
#: plane's 6, space's 9; model.dimension)
STATE_VARIABLES: dict[int, tuple[str, ...]] = {d.state_columns: d.state_variables for d in DIMENSIONS.values()}


def _var(name: str, dims, data) -> xr.DataArray:
    units, desc = VARIABLES[name]
    return xr.DataArray(data, dims=dims, attrs={"units": units, "long_name": desc})


def plate_maxima(plate, qf: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Largest von Mises stress [Pa] (eq. 12), largest disc-averaged von Mises stress [Pa]
    (docs/model.md section 4.4) and largest |eps_yy| [-] over the plate's Gauss points at
    each output time, from qf (time, n_modes [+ 2 n_contacts forces of a truncated
    basis]); the strains are computed once for all three (granplate.plate.peaks)."""
    every = time_maxima(plate, qf)
    return every[:, 0].copy(), every[:, 1].copy(), every[:, 2].copy()


def plate_coordinates(plate, q: np.ndarray, force: np.ndarray | None) -> np.ndarray:
    """(time, n_modes [+ 2 n_contacts]): the modal coordinates, and beside them the contact
    forces [N] that a truncated basis' static part needs (docs/model.md section 4.5)."""
    if force is None or not plate.truncated:
        return q
    return np.concatenate([q, np.asarray(force, dtype=float).reshape(len(q), -1)], axis=1)


def symmetry_velocity(plate, qd: np.ndarray) -> np.ndarray:
    """(time, n_symmetry) horizontal velocity [m/s] of the symmetry line's nodes from the
    modal velocities qd (time, n_modes): only their rows of T Phi are formed."""
    rows = 2 * np.asarray(plate.symmetry_nodes, dtype=np.int64)
    if len(rows) == 0:
        return np.zeros((len(qd), 0))
    shapes = np.asarray(plate.T[rows] @ plate.Phi)  # (n_symmetry, n_modes) [kg^-1/2]
    return qd @ shapes.T


#: Output times per block of the fields (the symmetry line's velocity and the snapshots
#: in those times): larger than the stresses' blocks, the products being cheaper per time.
FIELD_BLOCK = 8 * BLOCK


class _Bar:
    """A progress bar of one phase of building the result (tqdm on stderr), or nothing."""

    def __init__(self, enabled: bool, total: int, what: str):
        self.bar = None
        if enabled and total:
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc=f"result: {what}", unit="out", leave=False)

    def update(self, n: int) -> None:
        if self.bar is not None:
            self.bar.update(n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def plate_fields(
    model,
    q: np.ndarray,
    qd: np.ndarray,
    times: np.ndarray,
    force: np.ndarray | None = None,
    should_stop: Callable[[], bool] | None = None,
    progress: bool = False,
    plate=None,
) -> tuple[dict[str, Any], int]:
    """Plate outputs computed from the modal coordinates after the run, and the number of
    output times they cover; force (time, 2 n_contacts) [N]: the contact forces on the
    plate, whose static part a truncated basis adds to the displacements and stresses
    (docs/model.md section 4.5).

    Computed block by block, first the stresses (the three maxima at every output time),
    then the fields (the symmetry line's velocity, the snapshots); progress: a bar per
    phase; should_stop: polled after each block: when it says yes, the outputs cover the
    output times computed so far (fewer than len(times)); plate: the plate with the run's
    contacts (`run_contacts`; default model.plate)."""
    plate = model.plate if plate is None else plate
    s = model.scenario
    out: dict[str, Any] = {}  # the variables, and "_field_time" (an array of times [s])
    qf = plate_coordinates(plate, q, force)
    n = len(times)
    bar = _Bar(progress, n, "stresses")
    try:
        every = time_maxima(plate, qf, should_stop, bar.update)
    finally:
        bar.close()
    n = len(every)
    stride = max(1, int(round(s.time.field_interval / s.time.output_interval)))
    idx = np.arange(0, n, stride)
    if n == len(times) and n and idx[-1] != n - 1 and np.isclose(times[-1], s.time.t_end):
        idx = np.append(idx, n - 1)
    sym = np.asarray(plate.symmetry_nodes)
    vx = np.zeros((n, len(sym)))
    u = np.zeros((len(idx), plate.node_xy.shape[0], 2))
    vm = np.zeros((len(idx), plate.elements.shape[0]))
    bar = _Bar(progress, n, "fields")
    try:
        done, kept = 0, 0
        for i in block_starts(n, FIELD_BLOCK):
            rows = slice(i, min(i + FIELD_BLOCK, n))
            vx[rows] = symmetry_velocity(plate, qd[rows])
            snaps = np.flatnonzero((idx >= rows.start) & (idx < rows.stop))
            if len(snaps):
                c = split_coordinates(plate, qf[idx[snaps]])
                u[snaps] = plate.full_displacement(*c)
                vm[snaps] = plate.von_mises(*c).max(axis=-1)
            done, kept = rows.stop, (int(snaps[-1]) + 1 if len(snaps) else kept)
            bar.update(rows.stop - rows.start)
            if should_stop is not None and done < n and should_stop():
                break
    finally:
        bar.close()
    if done < n:
        n, every, vx, idx, u, vm = done, every[:done], vx[:done], idx[:kept], u[:kept], vm[:kept]
    out["max_von_mises"] = _var("max_von_mises", ("time",), every[:, 0].copy())
    out["max_von_mises_disc"] = _var("max_von_mises_disc", ("time",), every[:, 1].copy())
    out["max_eps_yy"] = _var("max_eps_yy", ("time",), every[:, 2].copy())
    out["plate_vx_symmetry"] = _var("plate_vx_symmetry", ("time", "x_symmetry"), vx)
    out["plate_ux"] = _var("plate_ux", ("field_time", "node"), u[..., 0].copy())
    out["plate_uy"] = _var("plate_uy", ("field_time", "node"), u[..., 1].copy())
    out["plate_von_mises"] = _var("plate_von_mises", ("field_time", "element"), vm)
    out["_field_time"] = times[idx]
    return out, n


#: What a summary-only Dataset holds (`to_dataset(..., summary_only=True)`): what
#: `summary` and the studies' metrics read.
SUMMARY_VARIABLES = (
    "E_shock",
    "E_granular",
    "E_plate",
    "E_plate_dynamic",
    "D_viscous",
    "D_friction",
    "D_plastic",
    "energy_residual_max",
    "max_von_mises",
    "max_von_mises_disc",
    "max_eps_yy",
    "max_von_mises_ball",
    "max_displacement",
)


class RunContacts(NamedTuple):
    """The output's contact axis: the model's plate contacts (at t = 0), then the patch
    contacts the run formed."""

    granule: np.ndarray  # (nk,) int64: the granule of each plate contact
    y: np.ndarray  # (nk,) [m]: its height on the face (a patch contact's where it formed)
    time_formed: np.ndarray  # (nk,) [s]: when it formed (0 for the model's)
    plate: Any  # the plate with every contact's height (its truncated basis' static part reads them), or None


def run_contacts(model, contacts=None) -> RunContacts:
    """The contact axis of a run of `model` whose contacts changed as `contacts` says
    (solver.driver.ContactChanges; None: as the model's)."""
    plate = model.plate
    granule = np.asarray(model.plate_contacts, np.int64)
    y = np.asarray(plate.contact_y, float) if plate is not None else np.zeros(len(granule))
    t = np.zeros(len(granule))
    if contacts is not None and len(contacts.granule):
        granule = np.concatenate([granule, contacts.granule])
        y = np.concatenate([y, contacts.y])
        t = np.concatenate([t, contacts.time])
        plate = replace(plate, contact_y=y)
    return RunContacts(granule=granule, y=y, time_formed=t, plate=plate)


def to_dataset(
    model,
    out: K.Output,
    n: int,
    info: dict,
    summary_only: bool = False,
    contacts=None,
    should_stop: Callable[[], bool] | None = None,
    progress: bool = False,
) -> xr.Dataset:
    """Build the result Dataset from the first n output rows.

    summary_only: only the variables `summary` reads (SUMMARY_VARIABLES, the time and
    granule coordinates and the attributes), the same numbers at a fraction of the cost
    (no plate fields, snapshots or per-contact records; the plate maxima only at the
    output times that can hold the run's largest value, NaN at the others:
    granplate.plate.peaks); contacts: how the run's contacts changed
    (solver.driver.ContactChanges: the patch contacts extend the contact axis; None: none
    formed). progress: a bar per phase of the plate outputs; should_stop: polled while
    they are computed: when it says yes, the Dataset holds the output times computed so
    far and its status says "interrupted by the user at t = ..."."""
    s = model.scenario
    axis = run_contacts(model, contacts)
    plate_data: dict[str, xr.DataArray] = {}
    if model.plate is not None:
        plate_data, n_done = _plate_outputs(model, out, n, axis, summary_only, should_stop, progress)
        n, info = _interrupted_at(out, n, n_done, info)
    body_data: dict[str, xr.DataArray] = {}
    body_coords: dict = {}
    if model.solid is not None:
        body_data, body_coords, n_done = body_outputs(model, out, n, summary_only, should_stop)
        n, info = _interrupted_at(out, n, n_done, info)
    t = out.t[:n].copy()
    data: dict[str, xr.DataArray] = dict(body_data)
    data.update(_state_and_energies(model, out, n, summary_only))
    coords = _coordinates(model, t, axis, summary_only)
    info = _yield_outputs(model, contacts, data, coords, info)
    coords.update(body_coords)
    if summary_only:
        data.update(plate_data)
        ds = xr.Dataset(data, coords=coords)
        return _with_scenario(ds, _attrs(model, out, n, info), s)
    data.update(_step_outputs(out, n, axis))
    data.update(wall_and_drive_outputs(model, out, n, coords))
    data.update(sensor_outputs(model, out, float(t[-1]) if n else -math.inf, coords))
    data.update(link_outputs(model, out, n, contacts, coords))
    if model.plate is not None:
        _add_plate_mesh(data, coords, plate_data, axis.plate)
    ds = xr.Dataset(data, coords=coords)
    if len(axis.granule) == 0:
        ds = ds.drop_dims("contact", errors="ignore")
    return _with_scenario(ds, _attrs(model, out, n, info), s)


def _interrupted_at(out: K.Output, n: int, n_done: int, info: dict) -> tuple[int, dict]:
    """(the output rows kept, the run's info): n and info as they are when every row was
    built (n_done == n); else the n_done rows built and the status of a run interrupted
    while its result was built."""
    if n_done >= n:
        return n, info
    status = f"{INTERRUPTED_STATUS} at t = {out.t[n_done - 1]:.6e} s, while building the result."
    return n_done, {**info, "status": status}


def _plate_outputs(model, out: K.Output, n: int, axis, summary_only: bool, should_stop, progress: bool):
    """(the plate's variables, the output rows built): its maxima alone over the output
    times that can hold the run's largest value (summary_only, granplate.plate.peaks), or
    its fields (`plate_fields`, polling should_stop), from the modal coordinates and the
    contact forces of the first n rows."""
    force = out.force[:n].reshape(n, out.force.shape[1] * out.force.shape[2])
    if not summary_only:
        return plate_fields(
            model,
            out.q[:n],
            out.qd[:n],
            out.t[:n],
            force,
            should_stop=should_stop,
            progress=progress,
            plate=axis.plate,
        )
    plate_data: dict[str, xr.DataArray] = {}
    every = peak_maxima(axis.plate, plate_coordinates(axis.plate, out.q[:n], force))
    for col, name in enumerate(("max_von_mises", "max_von_mises_disc", "max_eps_yy")):
        plate_data[name] = _var(name, ("time",), every[:, col].copy())
    return plate_data, n


#: the energy columns of the output (solver.state) and their variables' names
ENERGY_VARIABLES = (
    (K.E_SHOCK, "E_shock"),
    (K.E_GRAN, "E_granular"),
    (K.E_PLATE, "E_plate"),
    (K.D_VISC, "D_viscous"),
    (K.D_FRIC, "D_friction"),
    (K.D_PLASTIC, "D_plastic"),
    (K.E_POTG, "E_contact"),
    (K.KE_X, "KE_horizontal"),
    (K.KE_Y, "KE_vertical"),
    (K.KE_ROT, "KE_rotational"),
    (K.RESID, "energy_residual"),
    (K.RESID_MAX, "energy_residual_max"),
    (K.KE_Z, "KE_depth"),
)


def _state_and_energies(model, out: K.Output, n: int, summary_only: bool) -> dict[str, xr.DataArray]:
    """The granules' states (not with summary_only) and the energies of the first n output
    rows, as the Dataset's variables: the state variables of the state's dimension, the
    energy balance's terms (those `summary` reads with summary_only), the plate's energy
    about its static state, gravity's and the drives' work where the run has them."""
    s = model.scenario
    y = out.y[:n]
    e = out.energy[:n]
    data: dict[str, xr.DataArray] = {}
    dim = of_state(y.shape[2])
    if not summary_only:
        for c, name in enumerate(dim.state_variables):
            data[name] = _var(name, ("time", "granule"), y[:, :, c].copy())
    for col, name in ENERGY_VARIABLES:
        if dim.foreign(name):  # (KE_depth: in space only)
            continue
        if not summary_only or name in SUMMARY_VARIABLES:
            data[name] = _var(name, ("time",), e[:, col].copy())
    if model.plate_q0 is not None:
        data["E_plate_dynamic"] = _var(
            "E_plate_dynamic", ("time",), plate_energy_about_static(model, out.q[:n], e[:, K.E_PLATE], out.force[:n])
        )
    if s.gravity is not None:
        data["E_gravity"] = _var("E_gravity", ("time",), e[:, K.E_GRAVITY].copy())
    if s.drives:
        data["E_drive"] = _var("E_drive", ("time",), e[:, K.E_DRIVE].copy())
    return data


def _coordinates(model, t: np.ndarray, axis, summary_only: bool) -> dict:
    """The Dataset's coordinates: time [s], the granules (label, radius, mass, material)
    and, but with summary_only, the plate contacts' granules."""
    s = model.scenario
    coords = {
        "time": ("time", t, {"units": "s", "long_name": "time"}),
        "granule": ("granule", np.array(model.labels, dtype=str), {"long_name": "granule label (paper numbering)"}),
        **(
            {}
            if summary_only
            else {
                "contact": (
                    "contact",
                    np.array([model.labels[i] for i in axis.granule], dtype=str),
                    {"long_name": "granule at each plate contact"},
                )
            }
        ),
        "radius": ("granule", model.granular.radius.copy(), {"units": "m", "long_name": "granule radius"}),
        "mass": ("granule", model.granular.mass.copy(), {"units": "kg", "long_name": "granule mass"}),
        "material": (
            "granule",
            np.array([g.material for g in s.granules], dtype=str),
            {"long_name": "granule material"},
        ),
    }
    return coords


def _yield_outputs(model, contacts, data: dict, coords: dict, info: dict) -> dict:
    """The contacts' largest pressures by material pair (results.yielding, where the run
    recorded its contacts' peaks) into data and coords (material_pair); returns the run's
    info with the largest contact pressure and its yield-onset ratio added."""
    py = pair_yield(model, contacts.peaks) if contacts is not None and contacts.peaks is not None else None
    if py is None:
        return info
    coords["material_pair"] = (
        "material_pair",
        np.array(py.pair, dtype=str),
        {"long_name": "material pair of contacts (docs/model.md section 3.6)"},
    )
    for name, values in (
        ("pair_max_contact_pressure", py.pressure),
        ("pair_yield_onset_ratio", py.ratio),
        ("pair_yield_strength", py.yield_strength),
        ("pair_max_pressure_time", py.time),
        ("pair_max_pressure_contact", np.array(py.contact, dtype=str)),
        ("pair_normal_law", np.array(py.law, dtype=str)),
    ):
        data[name] = _var(name, ("material_pair",), values)
    p_max, ratio = largest(py)
    return {**info, "max_contact_pressure": p_max, "yield_onset_ratio": ratio}


def _step_outputs(out: K.Output, n: int, axis) -> dict[str, xr.DataArray]:
    """The plate contacts' forces, slip rates, local map moduli and iterations, and the
    steps' statistics (smallest and largest step, steps and iterations per output
    interval) of the first n output rows; each plate contact's time of forming."""
    return {
        "contact_normal_force": _var("contact_normal_force", ("time", "contact"), out.force[:n, :, 0].copy()),
        "contact_tangential_force": _var("contact_tangential_force", ("time", "contact"), out.force[:n, :, 1].copy()),
        "contact_slip_rate": _var("contact_slip_rate", ("time", "contact"), out.slip[:n].copy()),
        "local_map_modulus": _var("local_map_modulus", ("time", "contact"), out.lam[:n].copy()),
        "iterations": _var("iterations", ("time", "contact"), out.iters[:n].copy()),
        "dt_min": _var("dt_min", ("time",), out.stats[:n, K.S_DT_MIN].copy()),
        "dt_max": _var("dt_max", ("time",), out.stats[:n, K.S_DT_MAX].copy()),
        "n_steps": _var("n_steps", ("time",), out.stats[:n, K.S_STEPS].astype(np.int64)),
        "n_iterations": _var("n_iterations", ("time",), out.stats[:n, K.S_ITERS].astype(np.int64)),
        "contact_time_formed": _var("contact_time_formed", ("contact",), axis.time_formed),
    }


def _add_plate_mesh(data: dict, coords: dict, plate_data: dict, plate) -> None:
    """The plate's fields (plate_data, its snapshot times as the coordinate field_time),
    its nodes [m], the x of its symmetry line [m], its elements and its contacts' y [m]
    into data and coords."""
    ft = plate_data.pop("_field_time")
    data.update(plate_data)
    coords["field_time"] = ("field_time", ft, {"units": "s", "long_name": "time of the plate field snapshots"})
    coords["node_x"] = ("node", plate.node_xy[:, 0].copy(), {"units": "m", "long_name": "plate node x"})
    coords["node_y"] = ("node", plate.node_xy[:, 1].copy(), {"units": "m", "long_name": "plate node y"})
    coords["x_symmetry"] = (
        "x_symmetry",
        plate.node_xy[np.asarray(plate.symmetry_nodes), 0].copy(),
        {"units": "m", "long_name": "x along the plate's symmetry line"},
    )
    data["element_nodes"] = xr.DataArray(
        np.asarray(plate.elements, np.int64),
        dims=("element", "element_node"),
        attrs={"long_name": "plate element connectivity (VTK quadratic quad order)"},
    )
    data["contact_y"] = xr.DataArray(
        np.asarray(plate.contact_y, float),
        dims=("contact",),
        attrs={"units": "m", "long_name": "y of each plate contact"},
    )


#: Scenarios with more granules than this keep them out of the result's scenario_toml, as the
#: variables `scenario_granule_COLUMN` (dimension scenario_granule, the columns of a
#: granules file): a million [[granules]] tables would take a minute to write and read back.
GRANULES_IN_TOML_MAX = 10_000
GRANULE_VARIABLE = "scenario_granule_"


def _with_scenario(ds: xr.Dataset, attrs: dict, s) -> xr.Dataset:
    """ds with its attributes and the scenario it was made from: `scenario_toml`, its
    granules inside (up to GRANULES_IN_TOML_MAX) or beside it as variables, the TOML then
    ending in a comment with their count and digest (so that two scenarios' texts differ
    when their granules do: reproduce and the studies compare them)."""
    import hashlib

    from granplate.setup.granules_file import granule_columns
    from granplate.setup.io import dumps

    if len(s.granules) <= GRANULES_IN_TOML_MAX:
        ds.attrs.update({**attrs, "scenario_toml": dumps(s)})
        return ds
    cols = granule_columns(s.granules, s.dimension)
    digest = hashlib.sha256()
    for k, v in cols.items():
        arr = np.asarray(v, dtype=str if k in ("material", "label") else float)
        digest.update(k.encode() + arr.tobytes())
        ds[GRANULE_VARIABLE + k] = xr.DataArray(
            arr, dims=("scenario_granule",), attrs={"long_name": f"the scenario's granules: column {k}"}
        )
    text = dumps(replace(s, granules=()))
    note = f"# granules: {len(s.granules)} in the variables {GRANULE_VARIABLE}*, sha256 {digest.hexdigest()}\n"
    ds.attrs.update({**attrs, "scenario_toml": text + note, "scenario_granules": "variables"})
    return ds


def stress_ball_radius(model) -> float:
    """The radius [m] of the body's stress balls: plate.stress_radius, else a quarter of the
    body's smallest extent."""
    sd = model.scenario.plate
    if sd.stress_radius is not None:
        return float(sd.stress_radius)
    nodes = model.solid.nodes
    return 0.25 * float((nodes.max(axis=0) - nodes.min(axis=0)).min())


def body_outputs(
    model, out: K.Output, n: int, summary_only: bool, should_stop: Callable[[], bool] | None = None
) -> tuple[dict[str, xr.DataArray], dict, int]:
    """An elastic body's outputs in space (docs/output.md): its contacts at the output
    times (results.body_contacts), its modal coordinates and, from them and the contacts'
    static loads, its fields (results.body.body_data); and the output times they cover
    (fewer than n when should_stop said yes)."""
    from granplate.results.body import body_data
    from granplate.results.body_contacts import body_contacts, contact_variables, patch_forces

    contacts = body_contacts(model, out.y[:n], out.q[:n], out.qd[:n])
    s = model.scenario
    stride = max(1, int(round(s.time.field_interval / s.time.output_interval)))
    data, coords = body_data(
        model.solid,
        out.q[:n],
        out.qd[:n],
        out.t[:n],
        contacts.face,
        contacts.xi,
        contacts.force,
        stride,
        stress_ball_radius(model),
        summary_only=summary_only,
        should_stop=should_stop,
        nodal_forces=patch_forces(model, contacts),
    )
    n_done = data["max_von_mises"].shape[0] if "max_von_mises" in data else n
    if not summary_only:
        data.update({k: v[:n_done] for k, v in contact_variables(contacts).items()})
        data["body_q"] = _var("body_q", ("time", "mode"), out.q[:n_done].copy())
        data["body_qd"] = _var("body_qd", ("time", "mode"), out.qd[:n_done].copy())
        coords["mode_frequency"] = (
            "mode",
            model.solid.frequencies.copy(),
            {"units": "Hz", "long_name": "the elastic body's natural frequencies"},
        )
    return data, coords, n_done


def starts_loaded(s) -> bool:
    """Whether scenario s (resolved) starts with stored elastic energy that is energy put in:
    a precompressed run, or one whose contacts may start overlapped (`contact.overlap_start`,
    a poured packing's settled overlaps)."""
    return s.precompression is not None or s.contact.overlap_start is not None


def initial_energy(energy0: np.ndarray, stored: bool = False) -> float:
    """E_initial [J]: the kinetic energy of the initial velocities, 1/2 m v^2 + 1/2 I omega^2
    summed over the granules (the first output row's KE_x + KE_y + KE_rot, + KE_z in space), exactly 0 for a
    run from rest. The plate starts undeformed and at rest; contacts that touch at t = 0
    (overlaps within validation's 1e-9 R) hold only the round-off energy of their overlaps
    (~1e-33 J), which is not energy put in (it stays in the loop's eq. (11) reference).
    stored: a run whose contacts start with elastic energy (`starts_loaded`: a precompressed
    run, docs/model.md section 3.12, or overlaps allowed by contact.overlap_start): E_initial
    is then the whole E_g + E_p at t = 0."""
    if stored:
        return float(energy0[K.E_GRAN] + energy0[K.E_PLATE])
    return float(energy0[K.KE_X] + energy0[K.KE_Y] + energy0[K.KE_ROT] + energy0[K.KE_Z])


def _attrs(model, out: K.Output, n: int, info: dict) -> dict:
    """The result's attributes: version, scheme, E_initial and the run's figures (the
    scenario: `_with_scenario`)."""
    s = model.scenario
    attrs = {
        "title": f"granplate result: {s.name}",
        "scenario_name": s.name,
        "granplate_version": __version__,
        "dimension": int(s.dimension),
        "elastic_body": "solid" if model.solid is not None else "plate" if model.plate is not None else "none",
        "scheme": s.solver.scheme,
        "conventions": "SI units; see docs/output.md",
        "run_info": json.dumps(info),
        "E_initial": initial_energy(out.energy[0], starts_loaded(s)) if n else 0.0,
    }
    attrs.update(info)
    return attrs


def write(ds: xr.Dataset, path: str | Path) -> Path:
    """Write a result to netCDF (its floats and the contact table compressed) and return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    enc = {
        v: {"zlib": True, "complevel": 4}
        for v in ds.data_vars
        if ds[v].dtype.kind == "f" or (ds[v].dtype.kind == "i" and ds[v].dims == ("link",))
    }
    ds.to_netcdf(path, encoding=enc)
    return path


def read(path: str | Path) -> xr.Dataset:
    """Open a result written by `write` (loaded into memory)."""
    with xr.open_dataset(path) as ds:
        return ds.load()


#: Unit of every number in `summary` ("1": a pure number; the *_fraction values are
#: fractions of e_in = e_shock + e_initial).
SUMMARY_UNITS: dict[str, object] = {
    "t_end": "s",
    "e_shock": "J",
    "e_load_taken": "J",
    "e_initial": "J",
    "e_gravity": "J",
    "e_drive": "J",
    "e_in": "J",
    "e_in_max": "J",
    "ep_max_fraction": "1",
    "ep_final_fraction": "1",
    "ep_dynamic_max_fraction": "1",
    "eg_max_fraction": "1",
    "eg_final_fraction": "1",
    "dissipated_fraction": "1",
    "plastic_fraction": "1",
    "max_contact_pressure": "Pa",
    "yield_onset_ratio": "1",
    "contact_pairs": {"max_contact_pressure": "Pa", "yield_onset_ratio": "1", "yield_strength": "Pa", "time": "s"},
    "max_von_mises": "Pa",
    "max_von_mises_disc": "Pa",
    "max_eps_yy": "1",
    "energy_residual_max": "1",
    "n_steps": "1",
    "threads": "1",
    "wall_time_s": "s",
    "loop_time_s": "s",
    "compile_time_s": "s",
    "output_stride": "1",
    "output_interval_given": "s",
    "n_granules": "1",
    "max_von_mises_ball": "Pa",
    "max_displacement": "m",
}


def wall_and_drive_outputs(model, out: K.Output, n: int, coords: dict) -> dict[str, xr.DataArray]:
    """wall_force (time, wall) and drive_force, drive_displacement (time, drive), with the
    coordinates `wall` (the walls' labels, or "wall K") and `drive` (the drives' names,
    model.drives.drive_names) added to coords; none for a run without walls or drives."""
    from granplate.model.drives import drive_names

    s = model.scenario
    data: dict[str, xr.DataArray] = {}
    if s.walls:
        coords["wall"] = (
            "wall",
            np.array([w.label or f"wall {k + 1}" for k, w in enumerate(s.walls)], dtype=str),
            {"long_name": "wall label"},
        )
        data["wall_force"] = _var("wall_force", ("time", "wall"), out.wall_force[:n].copy())
    names = drive_names(s)
    if names:
        coords["drive"] = (
            "drive",
            np.array(names, dtype=str),
            {"long_name": "drive (its label, or its target; a held precompression's wall by its target)"},
        )
        data["drive_force"] = _var("drive_force", ("time", "drive"), out.drive[:n, :, 0].copy())
        data["drive_displacement"] = _var("drive_displacement", ("time", "drive"), out.drive[:n, :, 1].copy())
    return data


def link_outputs(model, out: K.Output, n: int, contacts, coords: dict) -> dict[str, xr.DataArray]:
    """The contact table (results.contact_table: every granule-granule and granule-wall
    contact in touch every time.contact_interval), with its coordinate `link_table_time`
    added to coords; none for time.contact_interval = 0."""
    from granplate.results.contact_table import contact_table
    from granplate.setup.run_checks import contact_steps

    peaks = contacts.peaks if contacts is not None else None
    data, more = contact_table(model, out, n, peaks, contact_steps(model.scenario.time))
    coords.update(more)
    return data


def sensor_outputs(model, out: K.Output, t_last: float, coords: dict) -> dict[str, xr.DataArray]:
    """sensor_force (sensor_time, sensor) of the samples recorded up to t_last [s] (the
    Dataset's last output time), with the coordinates `sensor_time` (its own time axis)
    and `sensor` (the sensors' names) added to coords; none for a run without sensors."""
    s = model.scenario
    if not s.sensors:
        return {}
    n = int(out.sensor_n[0])
    n = int(np.searchsorted(out.sensor_t[:n], t_last, side="right"))
    coords["sensor_time"] = (
        "sensor_time",
        out.sensor_t[:n].copy(),
        {"units": "s", "long_name": "the sensors' sample times (time.sensor_interval)"},
    )
    coords["sensor"] = (
        "sensor",
        np.array([x.label for x in s.sensors], dtype=str),
        {"long_name": "sensor (its name, or its granule's label)"},
    )
    return {"sensor_force": _var("sensor_force", ("sensor_time", "sensor"), out.sensor_force[:n].copy())}


def summary(ds: xr.Dataset) -> dict:
    """The headline figures of a run (the CLI's table and --summary JSON), units in "units".

    Energies are fractions of e_in = e_shock + e_initial + e_gravity + e_drive [J], the
    energy put in: the work the load put in, the energy present at t = 0 and the work of
    gravity and the drives at t_end (0 for a run without them; docs/output.md); they are None when
    e_in = 0. e_shock is E_shock at t_end unless the load also took energy back
    (e_load_taken: its force against granules moving toward it, `analysis.load_work`),
    so that neither is negative and no share exceeds 1 beyond the energy residual; the
    energies at t_end add up to e_in - e_load_taken. Plate metrics are None for a run
    without a plate (not applicable, not zero).
    """
    from granplate.results.analysis import energy_put_in, load_work

    e0 = float(ds.attrs.get("E_initial", 0.0))
    put_in, taken = load_work(ds.E_shock.values) if ds.sizes["time"] else (np.zeros(1), np.zeros(1))
    e_shock, e_taken = float(put_in[-1]), float(taken[-1])
    # the work of gravity and the drives at t_end (0 for a run without them)
    e_gravity, e_drive = (
        float(ds[name][-1]) if name in ds and ds.sizes["time"] else 0.0 for name in ("E_gravity", "E_drive")
    )
    e_in = e_shock + e0 + e_gravity + e_drive
    ref = e_in if e_in > 0 else None
    has_plate = "max_von_mises" in ds
    info = json.loads(ds.attrs.get("run_info", "{}"))
    plastic = float(ds.D_plastic[-1]) if "D_plastic" in ds and ds.sizes["time"] else 0.0

    def fraction(energy, plate: bool = False) -> float | None:
        if ref is None or (plate and not has_plate):
            return None
        return float(energy) / ref

    out = {
        "scenario": ds.attrs.get("scenario_name", ""),
        "units": {},
        "t_end": float(ds.time[-1]),
        "e_shock": e_shock,
        "e_load_taken": e_taken,
        "e_initial": e0,
        "e_gravity": e_gravity,
        "e_drive": e_drive,
        "e_in": e_in,
        "e_in_max": float(np.max(energy_put_in(ds))) if ds.sizes["time"] else e_in,
        "ep_max_fraction": fraction(ds.E_plate.max(), plate=True),
        "ep_final_fraction": fraction(ds.E_plate[-1], plate=True),
        "ep_dynamic_max_fraction": _dynamic_fraction(ds, e_in - e0) if has_plate else None,
        "eg_max_fraction": fraction(ds.E_granular.max()),
        "eg_final_fraction": fraction(ds.E_granular[-1]),
        "dissipated_fraction": fraction(ds.D_viscous[-1] + ds.D_friction[-1] + plastic),
        "plastic_fraction": fraction(plastic),
        "max_contact_pressure": _finite(ds.attrs.get("max_contact_pressure")),
        "yield_onset_ratio": _finite(ds.attrs.get("yield_onset_ratio")),
        "contact_pairs": pair_table(ds),
        "max_von_mises": float(ds.max_von_mises.max()) if has_plate else None,
        "max_von_mises_disc": (
            float(ds.max_von_mises_disc.max()) if has_plate and "max_von_mises_disc" in ds else None
        ),
        "max_eps_yy": float(ds.max_eps_yy.max()) if has_plate and "max_eps_yy" in ds else None,
        "energy_residual_max": float(np.max(np.abs(ds.energy_residual_max))),
        "n_steps": int(info.get("n_steps", 0)),
        "threads": int(info.get("threads", 1)),  # the loop's threads (solver.threads)
        "wall_time_s": float(info.get("wall_time_s", 0.0)),  # without compile_time_s
        "loop_time_s": float(info.get("loop_time_s", 0.0)),  # the time loop alone (wall)
        "compile_time_s": float(info.get("compile_time_s", 0.0)),  # numba compiling the kernels first
        # an elastic solid in space: its largest ball-averaged stress and displacement
        **{name: float(ds[name].max()) for name in ("max_von_mises_ball", "max_displacement") if name in ds},
    }
    if "output_stride" in ds.attrs:  # a run of many granules output at a stride (setup.output_stride)
        out["output_stride"] = int(ds.attrs["output_stride"])
        out["output_interval_given"] = float(ds.attrs["output_interval_given"])
        out["n_granules"] = int(ds.sizes.get("granule", 0))
    out["units"] = {k: u for k, u in SUMMARY_UNITS.items() if k in out}  # every number's unit
    return out


def _dynamic_fraction(ds: xr.Dataset, work: float) -> float | None:
    """The plate's peak energy about its static state at t = 0 (E_plate_dynamic; E_plate for a
    run whose plate starts unloaded) over the work put in after t = 0 (e_in - e_initial) [-]:
    the plate's peak share of the shock, a precompressed plate's static energy left out.
    None when nothing was put in after t = 0."""
    if work <= 0.0 or not ds.sizes["time"]:
        return None
    ep = ds["E_plate_dynamic"] if "E_plate_dynamic" in ds else ds["E_plate"]
    return float(np.max(np.asarray(ep.values, float))) / work


def plate_energy_about_static(model, q: np.ndarray, e_plate: np.ndarray, force: np.ndarray) -> np.ndarray:
    """(n,) the plate's energy about its precompressed state at t = 0 [J] (docs/model.md
    section 3.12): E_p - E_p(0) - F_s . (u - u_s), the static contact forces' work through the
    driving dofs' displacement since t = 0 taken off, F_s . (u - u_s) = (omega^2 q_s) . (q - q_s)
    + F_s^T R (F - F_s) (omega^2 q_s = Phi_d^T F_s). With every mode it is exactly 1/2 q'^2 +
    1/2 omega^2 (q - q_s)^2, the energy of the plate's motion about its static state; on a
    truncated basis, the residual compliance's coupling of the initial contacts with patch
    contacts formed during the run is left out. q: (n, nm) modal displacements; e_plate: (n,)
    E_p [J]; force: (n, nk, 2) the contacts' forces on the plate [N], the first rows the
    model's contacts at t = 0."""
    p = model.plate_arrays
    qs = np.asarray(model.plate_q0, float)
    lin = (q - qs[None, :]) @ (np.asarray(p.omega2, float) * qs)
    nd0 = p.resid.shape[0]
    if nd0:
        f0 = force[:, : nd0 // 2, :].reshape(len(force), nd0)
        fs = f0[0]
        lin = lin + (f0 - fs[None, :]) @ (np.asarray(p.resid, float) @ fs)
    return np.asarray(e_plate - e_plate[0] - lin, float)


def _finite(value) -> float | None:
    """A float, or None for a value that is absent or NaN (unknown)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def pair_table(ds: xr.Dataset) -> list[dict]:
    """The per-material-pair contact pressures of a result (one dict per pair: pair,
    max_contact_pressure [Pa], yield_onset_ratio [-] or None, yield_strength [Pa] or None,
    time [s], contact, normal_law); empty for a result without them."""
    if "material_pair" not in ds.coords:
        return []
    return [
        {
            "pair": str(ds.material_pair.values[k]),
            "max_contact_pressure": float(ds.pair_max_contact_pressure.values[k]),
            "yield_onset_ratio": _finite(ds.pair_yield_onset_ratio.values[k]),
            "yield_strength": _finite(ds.pair_yield_strength.values[k]),
            "time": float(ds.pair_max_pressure_time.values[k]),
            "contact": str(ds.pair_max_pressure_contact.values[k]),
            "normal_law": str(ds.pair_normal_law.values[k]),
        }
        for k in range(ds.sizes["material_pair"])
    ]


def dimension_of(ds: xr.Dataset) -> int:
    """A result's dimension, 2 or 3: its attribute `dimension` (results of granplate before
    0.2.1, without it: 3 where it has the depth z)."""
    d = ds.attrs.get("dimension")
    return int(d) if d is not None else 3 if "z" in ds.variables else 2


def dimension_spec(ds: xr.Dataset) -> Dimension:
    """A result's dimension as `model.dimension.Dimension` (its names; `dimension_of`)."""
    return of_number(dimension_of(ds))


def elastic_body_of(ds: xr.Dataset) -> str:
    """A result's elastic body: "plate" (the plane's modal plate), "solid" (a 3D elastic body)
    or "none", from its attribute `elastic_body` (older results: from its variables)."""
    b = ds.attrs.get("elastic_body")
    if b is not None:
        return str(b)
    if "body_ux" in ds.variables or "body_q" in ds.variables:
        return "solid"
    return "plate" if "node" in ds.dims else "none"


def has_solid(ds: xr.Dataset) -> bool:
    """Whether a result holds a 3D elastic body's fields: its body is a solid
    (`elastic_body_of`) and its displacement snapshots are stored (a summary-only result
    keeps the maxima alone)."""
    return elastic_body_of(ds) == "solid" and "body_ux" in ds.variables


def scenario_of(ds: xr.Dataset):
    """The Scenario a result was made from, read back from its `scenario_toml` attribute.

    Raises ScenarioError naming the attribute when the result carries none.
    """
    from granplate.errors import ScenarioError
    from granplate.setup.io import loads

    text = ds.attrs.get("scenario_toml")
    if not text:
        raise ScenarioError(
            "result attribute scenario_toml", None, "missing: not a result written by granplate.simulate"
        )
    s = loads(str(text))
    if ds.attrs.get("scenario_granules") != "variables":
        return s
    from granplate.setup.granules_file import granules_of_columns

    cols = {k[len(GRANULE_VARIABLE) :]: ds[k].values for k in ds.data_vars if str(k).startswith(GRANULE_VARIABLE)}
    return replace(s, granules=granules_of_columns(cols, s.dimension, "the result's scenario_granule_*"))
