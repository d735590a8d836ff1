"""Sensitivity checks behind the report's discussion of where we differ from the paper.

Each `SensitivityRun` is a preset with a few changed fields (finer mesh, another rigid-layer
width, a smaller time step, plate fields at every output, a contact-law variant) run
for a possibly shorter time; `granplate reproduce` runs them beside the presets (reusing
unchanged results like the presets) and `granplate.report` compares each with its
baseline over the same time window.

Also here: von Mises stress evaluated at the Q8 element nodes (rather than at the Gauss
points the simulator uses), from the nodal displacements a result stores, by the plate's
own strain operator and plane-stress law (`granplate.plate`), to show how much the
"maximum stress in the plate" depends on where it is sampled.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import xarray as xr


@dataclass(frozen=True)
class SensitivityRun:
    """One sensitivity run: `preset` with `changes` (dotted paths), up to t_end [s].

    baseline: the result it is compared with (a preset name, or another check's name);
    t_end None keeps the preset's 2 ms; slow: left out unless all checks are asked for;
    role: what it varies, one of ROLES (the report's discussion groups runs by it).
    """

    name: str
    preset: str
    changes: dict = field(default_factory=dict)
    t_end: float | None = None
    purpose: str = ""
    baseline: str = ""
    slow: bool = False
    role: str = "numerics"

    def __post_init__(self) -> None:
        if self.role not in ROLES:
            raise ValueError(f"role = {self.role!r}: allowed {ROLES}")


#: What a sensitivity run varies: where the stress is sampled (plate fields kept at every
#: output), the mesh (same rigid layer), the rigid-layer width, a numerical setting (time
#: step), a modelling choice (contact law).
ROLES = ("sampling", "mesh", "layer", "numerics", "model")


#: The time window of the stress checks [s]: the steel cases' stress peak (~0.3 ms) is in it.
STRESS_WINDOW = 5e-4

#: Every check the report knows how to discuss.
CHECKS: tuple[SensitivityRun, ...] = (
    SensitivityRun(
        "steel-r1-fields",
        "steel-r1",
        {"time.field_interval": 1e-6},
        STRESS_WINDOW,
        "plate displacements at every output, to evaluate von Mises at the element nodes",
        baseline="steel-r1",
        role="sampling",
    ),
    SensitivityRun(
        "bare-plate-fields",
        "bare-plate",
        {"time.field_interval": 1e-6},
        STRESS_WINDOW,
        "plate displacements at every output, to evaluate von Mises at the element nodes",
        baseline="bare-plate",
        role="sampling",
    ),
    SensitivityRun(
        "steel-r1-ny80",
        "steel-r1",
        {"plate.ny": 80, "plate.rigid_layer_width": 0.0025, "time.field_interval": 1e-6},
        STRESS_WINDOW,
        "mesh 2x finer along y (1.25 mm elements), same 2.5 mm rigid layer",
        baseline="steel-r1",
        role="mesh",
    ),
    SensitivityRun(
        "steel-r1-ny80-w1.25",
        "steel-r1",
        {"plate.ny": 80},
        STRESS_WINDOW,
        "mesh 2x finer along y, rigid layer one (fine) element edge = 1.25 mm",
        baseline="steel-r1",
        role="layer",
    ),
    SensitivityRun(
        "steel-r1-w5",
        "steel-r1",
        {"plate.rigid_layer_width": 0.005},
        STRESS_WINDOW,
        "rigid layer 5 mm wide (two element edges) on the default mesh",
        baseline="steel-r1",
        role="layer",
    ),
    SensitivityRun(
        "steel-r1-dt2",
        "steel-r1",
        {"time.dt_max": 2e-8, "time.dt_initial": 2e-8},
        STRESS_WINDOW,
        "time step halved (dt_max = 2e-8 s)",
        baseline="steel-r1",
        role="numerics",
    ),
    SensitivityRun(
        "bare-plate-ny80",
        "bare-plate",
        {"plate.ny": 80},
        None,
        "bare plate, mesh 2x finer along y",
        baseline="bare-plate",
        role="mesh",
    ),
    SensitivityRun(
        "ptfe-r05-dt2",
        "ptfe-r05",
        {"time.dt_max": 2e-8, "time.dt_initial": 2e-8},
        None,
        "time step halved (dt_max = 2e-8 s)",
        baseline="ptfe-r05",
        role="numerics",
    ),
    SensitivityRun(
        "ptfe-r05-raw-eq2",
        "ptfe-r05",
        {"contact.clip_tensile": False},
        None,
        "the paper's raw eq. (2): the damped normal force may pull",
        baseline="ptfe-r05",
        role="model",
    ),
    SensitivityRun(
        "ptfe-r05-alpha-steel",
        "ptfe-r05",
        {"contact.pairs[0].alpha_n": 6.313e-3},
        None,
        "steel-PTFE damping alpha_n = 6.313e-3 (the steel value) instead of 6.313e-2",
        baseline="ptfe-r05",
        role="model",
    ),
    SensitivityRun(
        "ptfe-r05-ny80",
        "ptfe-r05",
        {"plate.ny": 80, "plate.rigid_layer_width": 0.0025},
        None,
        "mesh 2x finer along y, same 2.5 mm rigid layer",
        baseline="ptfe-r05",
        role="mesh",
    ),
    SensitivityRun(
        "steel-r1-ny160",
        "steel-r1",
        {"plate.ny": 160, "plate.rigid_layer_width": 0.0025, "time.field_interval": 1e-6},
        STRESS_WINDOW,
        "mesh 4x finer along y (0.625 mm elements), same 2.5 mm rigid layer",
        baseline="steel-r1",
        role="mesh",
        slow=True,
    ),
    SensitivityRun(
        "ptfe-r05-ny80-w1.25",
        "ptfe-r05",
        {"plate.ny": 80},
        None,
        "mesh 2x finer along y, rigid layer one (fine) element edge = 1.25 mm",
        baseline="ptfe-r05",
        role="layer",
        slow=True,
    ),
)


def runs_of(baseline: str, *roles: str) -> list[str]:
    """Names of the checks compared with `baseline` that vary one of `roles`, in CHECKS order."""
    return [c.name for c in CHECKS if c.baseline == baseline and c.role in roles]


def get_check(name: str) -> SensitivityRun:
    """The check called `name` (KeyError listing the names if there is none)."""
    for c in CHECKS:
        if c.name == name:
            return c
    raise KeyError(f"no check {name!r}; checks are {[c.name for c in CHECKS]}")


def check_scenario(check: SensitivityRun, t_end: float | None = None):
    """The Scenario a check runs: its preset with its changes, ending at the earlier of
    the check's t_end and `t_end` [s] (None: no cap)."""
    from granplate.setup.presets import preset
    from granplate.setup.io import with_changes

    ends = [v for v in (check.t_end, t_end) if v is not None]
    changes = dict(check.changes)
    if ends:
        changes["time.t_end"] = min(ends)
    return with_changes(preset(check.preset), changes)


# --------------------------------------------------------------------------------------
# Stresses at the element nodes, by the plate's own recovery
# --------------------------------------------------------------------------------------
#: Where stress_series samples the stress: the 8 Q8 nodes of each element (corners and
#: midsides of skfem's reference square [0, 1]^2) or the simulator's 3 x 3 Gauss points.
SAMPLING = ("nodes", "gauss")

#: The Q8 nodes on skfem's reference square [0, 1]^2: (2, 8).
_Q8_REFERENCE_NODES = np.array([[0, 1, 1, 0, 0.5, 1, 0.5, 0], [0, 0, 1, 1, 0, 0.5, 1, 0.5]], dtype=float)


def stress_operator(ds: xr.Dataset, where: str = "nodes"):
    """(strain operator, plane-stress D [Pa]) of the result's plate, sampled `where`.

    The strain operator (granplate.plate.strain_operator) maps the full nodal displacement
    vector [m] to (eps_xx, eps_yy, gamma_xy) at the sampling points of every element; the
    mesh is rebuilt from the result's scenario and checked against its node coordinates.
    """
    from skfem import Basis

    from granplate.plate import node_coordinates, plane_stress_matrix, plate_mesh, q8_basis, strain_operator
    from granplate.results.dataset import scenario_of

    if where not in SAMPLING:
        raise ValueError(f"where = {where!r}: allowed {SAMPLING}")
    s = scenario_of(ds)
    p = s.plate
    mesh = plate_mesh(p.x0, p.y0, p.width, p.height, p.nx, p.ny)
    basis = q8_basis(mesh)
    if where == "nodes":
        weights = np.full(_Q8_REFERENCE_NODES.shape[1], 1.0 / _Q8_REFERENCE_NODES.shape[1])
        basis = Basis(mesh, basis.elem, quadrature=(_Q8_REFERENCE_NODES, weights))
    xy = node_coordinates(basis)
    if not (np.allclose(xy[:, 0], ds["node_x"].values) and np.allclose(xy[:, 1], ds["node_y"].values)):
        raise ValueError("the result's plate nodes do not match the mesh of its scenario")
    m = s.material(p.material)
    return strain_operator(basis), plane_stress_matrix(float(m.E), float(m.nu))


def stress_series(ds: xr.Dataset, where: str = "nodes", chunk: int = 200) -> np.ndarray:
    """Max von Mises stress over the plate at each field_time [Pa], sampled at the element
    nodes (where="nodes", not averaged between elements) or the 3 x 3 Gauss points
    (where="gauss", the simulator's own points), from the stored nodal displacements."""
    from granplate.plate import von_mises_plane_stress

    op, D = stress_operator(ds, where)
    ux, uy = np.asarray(ds["plate_ux"].values), np.asarray(ds["plate_uy"].values)
    out = []
    for i in range(0, len(ux), chunk):
        x_full = np.stack([ux[i : i + chunk], uy[i : i + chunk]], axis=-1).reshape(len(ux[i : i + chunk]), -1)
        exx, eyy, gxy = (op @ x_full.T).reshape(3, -1, x_full.shape[0])
        sxx, syy, sxy = (D[a, 0] * exx + D[a, 1] * eyy + D[a, 2] * gxy for a in range(3))
        out.append(von_mises_plane_stress(sxx, syy, sxy).max(axis=0))
    return np.concatenate(out) if out else np.zeros(0)


def max_in_window(ds: xr.Dataset, var: str, t_end: float) -> float:
    """Largest value of a (time,) variable over time <= t_end [s] (within 1e-12 s)."""
    t = ds["time"].values
    v = np.asarray(ds[var].values)[t <= t_end + 1e-12]
    return float(v.max()) if v.size else float("nan")
