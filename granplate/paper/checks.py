"""Sensitivity checks behind the report's discussion of where we differ from the paper.

Each `Check` is a preset with a few changed fields (finer mesh, another rigid-layer
width, a smaller time step, plate fields at every output, a contact-law variant) run
for a possibly shorter time; `granplate reproduce` runs them beside the presets (reusing
unchanged results like the presets) and `granplate.report` compares each with its
baseline over the same time window.

Also here: von Mises stress evaluated at the Q8 element nodes (rather than at the Gauss
points the simulator uses), from the nodal displacements a result stores, to show how
much the "maximum stress in the plate" depends on where it is sampled.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import xarray as xr

#: Reference coordinates of the Q8 nodes in VTK_QUADRATIC_QUAD order on [-1, 1]^2:
#: 4 corners anticlockwise, then the midsides of edges 0-1, 1-2, 2-3, 3-0.
Q8_NODES = np.array(
    [[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0]], dtype=float
)

#: 3 x 3 Gauss-Legendre points on [-1, 1]^2 (the simulator's stress points).
GAUSS_3X3 = np.array([[a, b] for a in (-np.sqrt(0.6), 0.0, np.sqrt(0.6)) for b in (-np.sqrt(0.6), 0.0, np.sqrt(0.6))])


@dataclass(frozen=True)
class Check:
    """One sensitivity run: `preset` with `changes` (dotted paths), up to t_end [s].

    baseline: the result it is compared with (a preset name, or another check's name);
    t_end None keeps the preset's 2 ms; slow: left out unless all checks are asked for.
    """

    name: str
    preset: str
    changes: dict = field(default_factory=dict)
    t_end: float | None = None
    purpose: str = ""
    baseline: str = ""
    slow: bool = False


#: The time window of the stress checks [s]: the steel cases' stress peak (~0.3 ms) is in it.
STRESS_WINDOW = 5e-4

#: Every check the report knows how to discuss.
CHECKS: tuple[Check, ...] = (
    Check("steel-r1-fields", "steel-r1", {"time.field_interval": 1e-6}, STRESS_WINDOW,
          "plate displacements at every output, to evaluate von Mises at the element nodes",
          baseline="steel-r1"),
    Check("bare-plate-fields", "bare-plate", {"time.field_interval": 1e-6}, STRESS_WINDOW,
          "plate displacements at every output, to evaluate von Mises at the element nodes",
          baseline="bare-plate"),
    Check("steel-r1-ny80", "steel-r1",
          {"plate.ny": 80, "plate.rigid_layer_width": 0.0025, "time.field_interval": 1e-6},
          STRESS_WINDOW, "mesh 2x finer along y (1.25 mm elements), same 2.5 mm rigid layer",
          baseline="steel-r1"),
    Check("steel-r1-ny80-w1.25", "steel-r1", {"plate.ny": 80}, STRESS_WINDOW,
          "mesh 2x finer along y, rigid layer one (fine) element edge = 1.25 mm",
          baseline="steel-r1"),
    Check("steel-r1-w5", "steel-r1", {"plate.rigid_layer_width": 0.005}, STRESS_WINDOW,
          "rigid layer 5 mm wide (two element edges) on the default mesh",
          baseline="steel-r1"),
    Check("steel-r1-dt2", "steel-r1", {"time.dt_max": 2e-8, "time.dt_initial": 2e-8},
          STRESS_WINDOW, "time step halved (dt_max = 2e-8 s)", baseline="steel-r1"),
    Check("bare-plate-ny80", "bare-plate", {"plate.ny": 80}, None,
          "bare plate, mesh 2x finer along y", baseline="bare-plate"),
    Check("ptfe-r05-dt2", "ptfe-r05", {"time.dt_max": 2e-8, "time.dt_initial": 2e-8}, None,
          "time step halved (dt_max = 2e-8 s)", baseline="ptfe-r05"),
    Check("ptfe-r05-raw-eq2", "ptfe-r05", {"contact.clip_tensile": False}, None,
          "the paper's raw eq. (2): the damped normal force may pull", baseline="ptfe-r05"),
    Check("ptfe-r05-alpha-steel", "ptfe-r05", {"contact.pairs[0].alpha_n": 6.313e-3}, None,
          "steel-PTFE damping alpha_n = 6.313e-3 (the steel value) instead of 6.313e-2",
          baseline="ptfe-r05"),
    Check("ptfe-r05-ny80", "ptfe-r05", {"plate.ny": 80, "plate.rigid_layer_width": 0.0025}, None,
          "mesh 2x finer along y, same 2.5 mm rigid layer", baseline="ptfe-r05"),
    Check("steel-r1-ny160", "steel-r1",
          {"plate.ny": 160, "plate.rigid_layer_width": 0.0025, "time.field_interval": 1e-6},
          STRESS_WINDOW, "mesh 4x finer along y (0.625 mm elements), same 2.5 mm rigid layer",
          baseline="steel-r1", slow=True),
    Check("ptfe-r05-ny80-w1.25", "ptfe-r05", {"plate.ny": 80}, None,
          "mesh 2x finer along y, rigid layer one (fine) element edge = 1.25 mm",
          baseline="ptfe-r05", slow=True),
)


def check_names(include_slow: bool = False) -> list[str]:
    """Names of the checks to run (the slow ones only when asked)."""
    return [c.name for c in CHECKS if include_slow or not c.slow]


def get_check(name: str) -> Check:
    """The check called `name` (KeyError listing the names if there is none)."""
    for c in CHECKS:
        if c.name == name:
            return c
    raise KeyError(f"no check {name!r}; checks are {[c.name for c in CHECKS]}")


def check_scenario(check: Check, t_end: float | None = None):
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
# Q8 stresses at arbitrary reference points
# --------------------------------------------------------------------------------------
def q8_shape_derivatives(points: np.ndarray) -> np.ndarray:
    """dN_a/d(xi, eta) of the 8 serendipity shape functions at reference points.

    points: (n_p, 2) in [-1, 1]^2; returns (n_p, 8, 2), node order as Q8_NODES.
    """
    xi, eta = points[:, 0:1], points[:, 1:2]
    a, b = Q8_NODES[:, 0][None, :], Q8_NODES[:, 1][None, :]
    corner = (np.abs(a) == 1) & (np.abs(b) == 1)
    mid_x = a == 0  # midside on an edge eta = +-1
    d_xi = np.where(
        corner, 0.25 * a * (1 + eta * b) * (2 * xi * a + eta * b),
        np.where(mid_x, -xi * (1 + eta * b), 0.5 * a * (1 - eta**2)),
    )
    d_eta = np.where(
        corner, 0.25 * b * (1 + xi * a) * (xi * a + 2 * eta * b),
        np.where(mid_x, 0.5 * b * (1 - xi**2), -eta * (1 + xi * a)),
    )
    return np.stack([d_xi, d_eta], axis=-1)


def q8_gradients(element_xy: np.ndarray, points: np.ndarray) -> np.ndarray:
    """dN_a/d(x, y) [1/m] at reference points of each element.

    element_xy: (n_el, 8, 2) node coordinates [m]; points (n_p, 2); returns (n_el, n_p, 8, 2).
    """
    dref = q8_shape_derivatives(points)  # (p, a, r)
    jac = np.einsum("eai,par->epir", element_xy, dref)  # J[i, r] = dx_i / dxi_r
    inv = np.linalg.inv(jac)  # dxi_r/dx_i: inv[r, i]
    return np.einsum("par,epri->epai", dref, inv)


def von_mises_at(
    ux: np.ndarray, uy: np.ndarray, node_xy: np.ndarray, elements: np.ndarray,
    points: np.ndarray, E: float, nu: float,
) -> np.ndarray:
    """Plane-stress von Mises stress [Pa] at reference points of every element.

    ux, uy: (n_t, n_nodes) nodal displacements [m]; node_xy (n_nodes, 2) [m]; elements
    (n_el, 8) VTK-ordered node indices; points (n_p, 2) reference coordinates; E [Pa], nu.
    Returns (n_t, n_el, n_p). Stresses are not averaged between elements.
    """
    grad = q8_gradients(node_xy[elements], points)  # (e, p, a, j)
    uxe, uye = ux[:, elements], uy[:, elements]  # (t, e, a)
    exx = np.einsum("tea,epa->tep", uxe, grad[..., 0])
    eyy = np.einsum("tea,epa->tep", uye, grad[..., 1])
    gxy = np.einsum("tea,epa->tep", uxe, grad[..., 1]) + np.einsum("tea,epa->tep", uye, grad[..., 0])
    c = E / (1 - nu**2)
    sxx = c * (exx + nu * eyy)
    syy = c * (nu * exx + eyy)
    sxy = c * 0.5 * (1 - nu) * gxy
    return np.sqrt(np.maximum(sxx**2 - sxx * syy + syy**2 + 3 * sxy**2, 0.0))


def plate_material(ds: xr.Dataset) -> tuple[float, float]:
    """(E [Pa], nu) of the plate, read from the result's scenario."""
    from granplate.setup.io import loads

    s = loads(ds.attrs["scenario_toml"])
    m = s.material(s.plate.material)
    return float(m.E), float(m.nu)


def stress_series(ds: xr.Dataset, where: str = "nodes", chunk: int = 200) -> np.ndarray:
    """Max von Mises stress over the plate at each field_time [Pa], sampled at the element
    nodes (where="nodes") or the 3 x 3 Gauss points (where="gauss")."""
    points = Q8_NODES if where == "nodes" else GAUSS_3X3
    E, nu = plate_material(ds)
    xy = np.stack([ds["node_x"].values, ds["node_y"].values], axis=1)
    elements = np.asarray(ds["element_nodes"].values, dtype=np.int64)
    ux, uy = np.asarray(ds["plate_ux"].values), np.asarray(ds["plate_uy"].values)
    out = []
    for i in range(0, len(ux), chunk):
        vm = von_mises_at(ux[i:i + chunk], uy[i:i + chunk], xy, elements, points, E, nu)
        out.append(vm.reshape(len(vm), -1).max(axis=1))
    return np.concatenate(out) if out else np.zeros(0)


def max_in_window(ds: xr.Dataset, var: str, t_end: float) -> float:
    """Largest value of a (time,) variable over time <= t_end [s] (within 1e-12 s)."""
    t = ds["time"].values
    v = np.asarray(ds[var].values)[t <= t_end + 1e-12]
    return float(v.max()) if v.size else float("nan")
