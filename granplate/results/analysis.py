"""Observables derived from a result Dataset: normalised energies, kinetic-energy split,
per-column shares, arrival times (paper section 3).

Pure functions of an xarray Dataset written by `granplate.simulate`; no plotting, no IO.
The figures (`granplate.plots`) and the report (`granplate.report`) both draw their
numbers from here, so a figure and the table that quotes it can never disagree.

    >>> from granplate.results import analysis
    >>> e = analysis.normalised_energies(ds)   # dict of arrays, fractions of E_shock
    >>> analysis.plate_share(ds)["peak"]       # the plate's peak share of E_shock
"""

from __future__ import annotations

import numpy as np
import xarray as xr

#: Keys of `normalised_energies`, in plotting order, with a readable label.
ENERGY_CURVES: dict[str, str] = {
    "granular": "granular medium $E_g$",
    "plate": "plate $E_p$",
    "sum": "$E_g + E_p$",
    "total": "$E_g + E_p + D$",
}

#: Keys of `kinetic_split`, with a readable label.
KINETIC_PARTS: dict[str, str] = {
    "horizontal": "horizontal",
    "vertical": "vertical",
    "rotational": "rotational",
}


def load_work(e_shock: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The load's work E_shock(t) [J] split into what it put in and what it took back,
    both non-decreasing and non-negative, E_shock = put_in - taken: the sums of E_shock's
    rises and of its falls between output times. A load takes energy back when its force
    opposes the velocity of the granules it pushes (granules moving toward it, as with
    initial velocities against the load): its power F . v is then negative."""
    e = np.asarray(e_shock, dtype=float)
    step = np.diff(e, prepend=0.0)
    return np.cumsum(np.maximum(step, 0.0)), np.cumsum(np.maximum(-step, 0.0))


def energy_put_in(ds: xr.Dataset) -> np.ndarray:
    """E_initial + the load's work put in so far + the work of gravity and the drives [J] over
    time (`load_work`, `body_force_work`): the energy put into the run; E_p + E_g + D never exceeds it (eq. 11: they sum to E_initial +
    E_shock, which the load's work taken back lowers)."""
    e0 = float(ds.attrs.get("E_initial", 0.0))
    if not ds.sizes.get("time", 0):
        return np.zeros(0)
    return e0 + load_work(ds["E_shock"].values)[0] + body_force_work(ds)


def body_force_work(ds: xr.Dataset) -> np.ndarray | float:
    """The work of gravity and the drives so far [J] over time (E_gravity + E_drive, eq. 11;
    0.0 for a run without them)."""
    return sum((ds[name].values for name in ("E_gravity", "E_drive") if name in ds), 0.0)


def reference_energy(ds: xr.Dataset) -> float:
    """The energy put in [J]: E_initial plus the work the load put in (E_shock at the last
    output for a load that never takes energy back, `load_work`).

    Every normalised quantity here divides by this number (the paper's "applied shock
    energy"), so no share of it exceeds 1 beyond the energy residual; 1.0 when the run put
    no energy in (avoids dividing by zero).
    """
    e = energy_put_in(ds)
    ref = float(e[-1]) if len(e) else 0.0
    return ref if ref > 0 else 1.0


def times_ms(ds: xr.Dataset, coord: str = "time") -> np.ndarray:
    """The dataset's times in milliseconds."""
    return np.asarray(ds[coord].values, dtype=float) * 1e3


def time_indices(ds: xr.Dataset, times: np.ndarray) -> np.ndarray:
    """Index into ds.time of the output nearest to each of `times` [s]."""
    t = ds["time"].values
    idx = np.searchsorted(t, times).clip(0, len(t) - 1)
    prev = (idx - 1).clip(0)
    return np.where(np.abs(t[prev] - times) < np.abs(t[idx] - times), prev, idx)


def has_granules(ds: xr.Dataset) -> bool:
    """Whether the run has granules (the bare plate has none)."""
    return ds.sizes.get("granule", 0) > 0


def has_plate(ds: xr.Dataset) -> bool:
    """Whether the run has a plate."""
    return "E_plate" in ds and "node" in ds.dims


def has_elastic_energy(ds: xr.Dataset) -> bool:
    """Whether the run has an elastic plate or a 3D elastic body, whose energy is E_plate."""
    return "E_plate" in ds and ("node" in ds.dims or "body_q" in ds)


def normalised_energies(ds: xr.Dataset) -> dict[str, np.ndarray]:
    """E_g, E_p, E_g + E_p and E_g + E_p + D over time, each / reference_energy [-].

    D = D_viscous + D_friction (paper eqs. 9-11), + D_plastic where contacts yielded
    (docs/model.md section 3.6); "total" is 1 once the shock is over when the energy
    balance holds.
    """
    ref = reference_energy(ds)
    eg = np.asarray(ds["E_granular"].values, float)
    ep = np.asarray(ds["E_plate"].values, float)
    d = np.asarray(ds["D_viscous"].values, float) + np.asarray(ds["D_friction"].values, float)
    if "D_plastic" in ds:
        d = d + np.asarray(ds["D_plastic"].values, float)
    return {"granular": eg / ref, "plate": ep / ref, "sum": (eg + ep) / ref, "total": (eg + ep + d) / ref}


def kinetic_split(ds: xr.Dataset) -> dict[str, np.ndarray]:
    """Granular kinetic energy [J] split into horizontal, vertical and rotational parts."""
    return {
        "horizontal": np.asarray(ds["KE_horizontal"].values, float),
        "vertical": np.asarray(ds["KE_vertical"].values, float),
        "rotational": np.asarray(ds["KE_rotational"].values, float),
    }


def plate_share(ds: xr.Dataset) -> dict[str, float]:
    """The plate's share of the energy put in [-]: peak, final (last output) and time mean."""
    ep = normalised_energies(ds)["plate"]
    return {"peak": float(ep.max()), "final": float(ep[-1]), "mean": float(ep.mean())}


def granule_index(ds: xr.Dataset, label: str) -> int:
    """Position of the granule called `label` (KeyError naming the labels if absent)."""
    labels = [str(v) for v in ds["granule"].values]
    if label not in labels:
        raise KeyError(f"no granule {label!r}; granules are {labels}")
    return labels.index(label)


def columns(ds: xr.Dataset, rtol: float = 1e-6) -> list[list[str]]:
    """Granule labels grouped by initial x (the packing's columns), left to right.

    Within a column, top to bottom (the paper's numbering: 1..5, 6..9, A..E).
    """
    if not has_granules(ds):
        return []
    x0 = np.asarray(ds["x"].values[0], float)
    y0 = np.asarray(ds["y"].values[0], float)
    labels = [str(v) for v in ds["granule"].values]
    scale = float(np.max(ds["radius"].values))
    order = np.argsort(x0, kind="stable")
    groups: list[list[int]] = []
    for i in order:
        if groups and abs(x0[i] - x0[groups[-1][0]]) <= rtol * scale:
            groups[-1].append(int(i))
        else:
            groups.append([int(i)])
    return [[labels[i] for i in sorted(g, key=lambda i: -y0[i])] for g in groups]


def granule_kinetic_energy(ds: xr.Dataset) -> np.ndarray:
    """Kinetic energy of each granule [J], (time, granule): 1/2 m v^2 + 1/2 (2/5 m R^2) w^2."""
    m = np.asarray(ds["mass"].values, float)
    inertia = 0.4 * m * np.asarray(ds["radius"].values, float) ** 2
    vx, vy, w = (np.asarray(ds[k].values, float) for k in ("vx", "vy", "omega"))
    return 0.5 * m * (vx**2 + vy**2) + 0.5 * inertia * w**2


def column_kinetic_share(ds: xr.Dataset) -> list[float]:
    """Share of the granular kinetic energy carried by each column, over the whole run [-].

    sum over time of a column's kinetic energy / sum over time of all granules' (the
    paper's "energy stays in column 1" for PTFE intruders, Figs. 5-6).
    """
    ke = granule_kinetic_energy(ds)
    total = ke.sum()
    labels = [str(v) for v in ds["granule"].values]
    out = []
    for col in columns(ds):
        idx = [labels.index(lab) for lab in col]
        out.append(float(ke[:, idx].sum() / total) if total > 0 else 0.0)
    return out


def arrival_time(ds: xr.Dataset, fraction: float = 0.01) -> float:
    """First time [s] the plate holds `fraction` of the energy put in (nan if never)."""
    ep = normalised_energies(ds)["plate"]
    hit = np.flatnonzero(ep >= fraction)
    return float(ds["time"].values[hit[0]]) if hit.size else float("nan")


def vertical_kinetic_share(ds: xr.Dataset) -> float:
    """Vertical part of the granular kinetic energy, summed over the run / all of it [-]."""
    k = kinetic_split(ds)
    total = (k["horizontal"] + k["vertical"] + k["rotational"]).sum()
    return float(k["vertical"].sum() / total) if total > 0 else 0.0


def peak_stress_location(ds: xr.Dataset) -> tuple[float, float, float]:
    """(time [s], x from the plate's left edge [m], y [m]) of the element with the largest
    von Mises stress among the field snapshots (x, y: the mean of its 4 corner nodes)."""
    vm = ds["plate_von_mises"].values
    k, e = np.unravel_index(int(np.argmax(vm)), vm.shape)
    nodes = ds["element_nodes"].values[e, :4]
    x = float(ds["node_x"].values[nodes].mean() - ds["node_x"].values.min())
    y = float(ds["node_y"].values[nodes].mean())
    return float(ds["field_time"].values[k]), x, y


def run_info(ds: xr.Dataset) -> dict:
    """The solver's run record (wall time, steps, status) stored in the attributes."""
    import json

    try:
        return json.loads(ds.attrs.get("run_info", "{}"))
    except (TypeError, ValueError):
        return {}


def max_energy_residual(ds: xr.Dataset) -> float:
    """Largest |energy residual| of eq. (11) over the run [-]."""
    return float(np.max(np.abs(ds["energy_residual_max"].values))) if ds.sizes.get("time", 0) else 0.0
