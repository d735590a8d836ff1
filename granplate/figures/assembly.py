"""What `granplate show` draws, as plain arrays [m, N]: an `Assembly`.

`of_scenario(scenario)` is the assembly before the run (the contact network at t = 0, no
forces); `of_result(ds, time)` is the assembly of a result at one output time: the
granules where they are, the plate deformed (displacements magnified) when a plate-field
snapshot exists at that time, and the normal force of every contact.

Contact forces at a time of a result are read, never recomputed:

- granule-granule and granule-wall: the result's contact table (`link_*`, docs/output.md:
  the normal force of each contact's own law, with its history and damping, at the
  output times every time.contact_interval); a time without a table is drawn at the
  nearest time with one (a result without any table: no such contacts drawn);
- granule-plate: the stored `contact_normal_force` (docs/output.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

from granplate.errors import ScenarioError
from granplate.model.arrays import find_pairs_and_walls, find_plate_contacts
from granplate.model.loads import loaded_granules
from granplate.results import analysis as an
from granplate.results.contact_table import links_of
from granplate.results.dataset import scenario_of
from granplate.setup.geometry import resolve
from granplate.setup.scenario import Load, Scenario, Wall

#: Contact kinds, in the order of `Assembly.segments`.
CONTACT_KINDS = ("granule", "wall", "plate")

#: The drawn plate displacement is about this fraction of the plate's width.
DRAWN_DISPLACEMENT = 0.15

#: The largest magnification of plate displacements (a plate the wave has not reached
#: yet is drawn at most this much magnified, i.e. visibly undeformed).
MAX_MAGNIFY = 1e4

#: Q8 element outline in VTK order: corner, mid-side, corner, ... (docs/output.md).
Q8_OUTLINE = (0, 4, 1, 5, 2, 6, 3, 7)


@dataclass(frozen=True)
class PlateDrawing:
    """The plate as drawn [m]: its undeformed rectangle (x0, y0, width, height), the
    element outlines (n_elem, k, 2), each rigid layer as a polyline (n_pts, 2); deformed:
    whether a displacement snapshot was drawn, magnified `magnify` times, and its largest
    nodal displacement [m]; clamped_edges: plate.clamped_edges ("top", "bottom", ...)."""

    rectangle: tuple[float, float, float, float]
    elements: np.ndarray
    rigid_layers: tuple[np.ndarray, ...]
    magnify: float = 1.0
    deformed: bool = False
    largest_displacement: float = 0.0
    clamped_edges: tuple[str, ...] = ()


@dataclass(frozen=True)
class Assembly:
    """An assembly as drawn [m, N].

    x, y, radius: granule centres and radii; labels, materials: per granule; walls: the
    resolved scenario's walls; plate: a PlateDrawing or None; load: the scenario's load
    and loaded: mask of the granules it pushes (all False for a plate load);
    segments: (nc, 2, 2) contact lines (centre to centre, centre to wall, centre to the
    plate), kinds: CONTACT_KINDS entry per segment; forces: normal force per segment
    [N] or None (a scenario); time [s] and time_note: the result time shown (None for a
    scenario).
    """

    name: str
    x: np.ndarray
    y: np.ndarray
    radius: np.ndarray
    labels: tuple[str, ...]
    materials: tuple[str, ...]
    walls: tuple[Wall, ...]
    plate: PlateDrawing | None
    load: Load
    loaded: np.ndarray
    segments: np.ndarray
    kinds: tuple[str, ...]
    forces: np.ndarray | None = None
    time: float | None = None
    time_note: str = ""


# --------------------------------------------------------------------------------------
# Contacts
# --------------------------------------------------------------------------------------
def contact_lists(scenario: Scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The contact network at t = 0 of a scenario (validated): (pairs (np, 2), wall
    contacts (nw, 2) [granule, wall], plate contacts (nk,) granule indices), the model's
    rules (model.arrays: gaps at most contact.neighbour_gap R; the plate's rigid layers,
    then the patch contacts of granules between its face nodes)."""
    from granplate.setup.validate import validate

    validate(scenario)
    s = resolve(scenario)
    x, y, r = (np.array([getattr(g, k) for g in s.granules], float) for k in ("x", "y", "radius"))
    pairs, walls = find_pairs_and_walls(s, x, y, r)
    on, between = find_plate_contacts(s)
    plate = np.concatenate([np.asarray(on, int).reshape(-1), np.asarray(between, int).reshape(-1)])
    return np.asarray(pairs, int).reshape(-1, 2), np.asarray(walls, int).reshape(-1, 2), plate


def table_time(ds: xr.Dataset, ti: int, note: str) -> tuple[int, str]:
    """(output index, note) of the time drawn for output ti: ti itself when the result's
    contact table covers it (or the result has none), else the nearest time it covers."""
    if "link_table_time" not in ds.coords or not ds.sizes.get("link_table_time", 0):
        return ti, note
    t = ds["time"].values
    tt = np.asarray(ds["link_table_time"].values, float)
    k = int(np.argmin(np.abs(tt - t[ti])))
    if tt[k] == t[ti]:
        return ti, note
    return int(np.argmin(np.abs(t - tt[k]))), f"{note}; drawn at the nearest time of the contact table"


def result_links(ds: xr.Dataset, ti: int, labels) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(pairs (np, 2), wall contacts (nw, 2) [granule, wall], plate contacts (nk,) granule
    indices, their normal forces [N] in that order) of a result at output ti: the contact
    table's rows at that time (none without a table there) and the plate contacts with
    their stored `contact_normal_force`."""
    links = links_of(ds, float(ds["time"].values[ti]))
    pairs, walls, forces = np.zeros((0, 2), int), np.zeros((0, 2), int), []
    if links is not None:
        to_pair = links.partner >= 0
        pairs = np.column_stack([links.granule[to_pair], links.partner[to_pair]]).astype(int)
        walls = np.column_stack([links.granule[~to_pair], -1 - links.partner[~to_pair]]).astype(int)
        forces = [links.values[to_pair, 1], links.values[~to_pair, 1]]
    plate = np.zeros(0, int)
    if "contact" in ds.coords and "contact_normal_force" in ds:
        index = {str(v): k for k, v in enumerate(labels)}
        plate = np.array([index[str(c)] for c in ds["contact"].values], int)
        forces.append(np.maximum(np.asarray(ds["contact_normal_force"].values[ti], float), 0.0))
    return pairs, walls, plate, np.concatenate(forces) if forces else np.zeros(0)


def wall_foot(x: float, y: float, wall: Wall) -> tuple[float, float]:
    """The point of the wall's line nearest to (x, y) [m]."""
    n = np.asarray(wall.normal, float)
    n = n / np.linalg.norm(n)
    gap = wall.offset - (x * n[0] + y * n[1])
    return x + gap * n[0], y + gap * n[1]


def contact_segments(x, y, r, walls, pairs, wall_contacts, plate_contacts) -> tuple[np.ndarray, tuple[str, ...]]:
    """Contact lines [m] (nc, 2, 2) and their kinds: granule centre to centre, centre to
    the wall's nearest point, centre to the granule's contact point on the plate (+x)."""
    segs, kinds = [], []
    for i, j in pairs:
        segs.append(((x[i], y[i]), (x[j], y[j])))
        kinds.append("granule")
    for i, w in wall_contacts:
        segs.append(((x[i], y[i]), wall_foot(x[i], y[i], walls[w])))
        kinds.append("wall")
    for i in plate_contacts:
        segs.append(((x[i], y[i]), (x[i] + r[i], y[i])))
        kinds.append("plate")
    return np.asarray(segs, float).reshape(-1, 2, 2), tuple(kinds)


# --------------------------------------------------------------------------------------
# Load
# --------------------------------------------------------------------------------------
def load_profile(load: Load, y: np.ndarray) -> np.ndarray:
    """sin(pi (y - y0) / L) on the load's y-range, 0 outside: the shape of q(y) [-]."""
    u = (np.asarray(y, float) - load.y0) / load.length
    return np.where((u >= 0) & (u <= 1), np.sin(np.pi * np.clip(u, 0, 1)), 0.0)


# --------------------------------------------------------------------------------------
# Plate
# --------------------------------------------------------------------------------------
def grid_elements(x0: float, y0: float, width: float, height: float, nx: int, ny: int) -> np.ndarray:
    """Element outlines (nx ny, 4, 2) [m] of the structured nx x ny plate mesh."""
    xs, ys = np.linspace(x0, x0 + width, nx + 1), np.linspace(y0, y0 + height, ny + 1)
    out = [
        ((xs[i], ys[j]), (xs[i + 1], ys[j]), (xs[i + 1], ys[j + 1]), (xs[i], ys[j + 1]))
        for i in range(nx)
        for j in range(ny)
    ]
    return np.asarray(out, float)


def layer_spans(contact_y, width: float) -> list[tuple[float, float]]:
    """(y_lo, y_hi) [m] of the rigid layer of each plate contact (docs/model.md 4.2)."""
    return [(float(yk) - width / 2, float(yk) + width / 2) for yk in contact_y]


def nice_factor(value: float) -> float:
    """The largest of 1, 2, 5 x 10^k not above value (at least 1)."""
    if not value > 1:
        return 1.0
    k = math.floor(math.log10(value))
    for m in (5, 2, 1):
        if m * 10**k <= value:
            return float(m * 10**k)
    return float(10**k)  # pragma: no cover


def scenario_plate(s: Scenario, plate_contacts, y) -> PlateDrawing | None:
    """The undeformed plate of a resolved scenario: its mesh and rigid layers."""
    p = s.plate
    if p is None:
        return None
    elements = grid_elements(p.x0, p.y0, p.width, p.height, p.nx, p.ny)
    layers = tuple(
        np.array([[p.x0, lo], [p.x0, hi]]) for lo, hi in layer_spans([y[i] for i in plate_contacts], p.layer_width)
    )
    return PlateDrawing((p.x0, p.y0, p.width, p.height), elements, layers, clamped_edges=tuple(p.clamped_edges))


def result_plate(s: Scenario, ds: xr.Dataset, t: float) -> PlateDrawing | None:
    """The plate of a result at time t [s]: deformed (magnified) when a field snapshot
    exists at t, else undeformed."""
    if not an.has_plate(ds) or s.plate is None:
        return None
    p = s.plate
    xy = np.stack([ds["node_x"].values, ds["node_y"].values], axis=1)
    k = snapshot_at(ds, t)
    magnify, deformed, umax = 1.0, False, 0.0
    if k is not None:
        u = np.stack([ds["plate_ux"].values[k], ds["plate_uy"].values[k]], axis=1)
        umax = float(np.hypot(u[:, 0], u[:, 1]).max())
        magnify = nice_factor(min(DRAWN_DISPLACEMENT * p.width / umax, MAX_MAGNIFY)) if umax > 0 else 1.0
        deformed = True
        xy = xy + magnify * u
    elements = xy[np.asarray(ds["element_nodes"].values)[:, Q8_OUTLINE]]
    x_nodes, y_nodes = ds["node_x"].values, ds["node_y"].values
    left = np.abs(x_nodes - p.x0) <= 1e-9 * p.width
    ys = ds["contact_y"].values if "contact_y" in ds else []
    layers = []
    for lo, hi in layer_spans(ys, p.layer_width):
        band = np.flatnonzero(left & (y_nodes >= lo - 1e-9 * p.height) & (y_nodes <= hi + 1e-9 * p.height))
        layers.append(xy[band[np.argsort(y_nodes[band])]])
    return PlateDrawing(
        (p.x0, p.y0, p.width, p.height), elements, tuple(layers), magnify, deformed, umax, tuple(p.clamped_edges)
    )


# --------------------------------------------------------------------------------------
# Times of a result
# --------------------------------------------------------------------------------------
def snapshot_at(ds: xr.Dataset, t: float) -> int | None:
    """Index of the plate-field snapshot at time t [s] (None when there is none)."""
    if ds.sizes.get("field_time", 0) == 0 or "plate_ux" not in ds:
        return None
    ft = ds["field_time"].values
    k = int(np.argmin(np.abs(ft - t)))
    tol = 1e-6 * max(float(ds["time"].values[-1]), 1e-300)
    return k if abs(ft[k] - t) <= tol else None


def choose_time(ds: xr.Dataset, time: float | None) -> tuple[int, str]:
    """(output index, note for the title) of the time to show.

    time None: with a plate, the plate-field snapshot of largest plate energy (so that
    the deformed plate can be drawn; the true peak time is named too); with a plate that
    never moved, the output of largest granular energy; else the last output. A given time [s] must lie within the run; the nearest output is shown.
    """
    t = ds["time"].values
    if len(t) == 0:
        raise ScenarioError("result", scenario_name_of(ds), "has no output times")
    if time is not None:
        half = 0.5 * (t[1] - t[0]) if len(t) > 1 else 0.0
        if not (t[0] - half <= time <= t[-1] + half):
            raise ScenarioError("--time", time, f"allowed: {t[0]:g} to {t[-1]:g} s (the run's output times)")
        i = int(np.argmin(np.abs(t - time)))
        return i, "the output nearest the requested time"
    if an.has_plate(ds) and float(np.max(ds["E_plate"].values)) > 0.0:
        ep = ds["E_plate"].values
        peak = int(np.argmax(ep))
        if ds.sizes.get("field_time", 0):
            snaps = an.time_indices(ds, ds["field_time"].values)
            best = int(snaps[np.argmax(ep[snaps])])
            if best == peak:
                return best, "time of the largest plate energy"
            return best, (
                f"the plate snapshot of largest plate energy; the peak, between snapshots, is at {t[peak] * 1e3:.4g} ms"
            )
        return peak, "time of the largest plate energy"
    if an.has_plate(ds):
        return int(np.argmax(ds["E_granular"].values)), "time of the largest granular energy (the plate never moved)"
    return len(t) - 1, "last output time (no plate)"


def scenario_name_of(ds: xr.Dataset) -> str:
    return str(ds.attrs.get("scenario_name", "result"))


# --------------------------------------------------------------------------------------
# Builders
# --------------------------------------------------------------------------------------
def of_scenario(scenario: Scenario) -> Assembly:
    """The assembly of a scenario before its run: initial positions, the model's contact
    network (no forces), the undeformed plate."""
    s = resolve(scenario)
    pairs, walls, plate = contact_lists(scenario)
    x = np.array([g.x for g in s.granules], float)
    y = np.array([g.y for g in s.granules], float)
    r = np.array([g.radius for g in s.granules], float)
    segs, kinds = contact_segments(x, y, r, s.walls, pairs, walls, plate)
    return Assembly(
        name=s.name,
        x=x,
        y=y,
        radius=r,
        labels=tuple(g.label for g in s.granules),
        materials=tuple(g.material for g in s.granules),
        walls=s.walls,
        plate=scenario_plate(s, plate, y),
        load=s.load,
        loaded=loaded_granules(s, np.column_stack([x, y]), r),
        segments=segs,
        kinds=kinds,
    )


def of_result(ds: xr.Dataset, time: float | None = None) -> Assembly:
    """The assembly of a result at `time` [s] (None: see `choose_time`): positions and
    contact forces at the nearest output (of the contact table's, `table_time`), the plate
    deformed when a snapshot exists."""
    scenario = scenario_of(ds)
    s = resolve(scenario)
    ti, note = table_time(ds, *choose_time(ds, time))
    t = float(ds["time"].values[ti])
    x, y = np.asarray(ds["x"].values[ti], float), np.asarray(ds["y"].values[ti], float)
    labels = tuple(str(v) for v in ds["granule"].values)
    pairs, walls, plate, forces = result_links(ds, ti, labels)
    r = np.asarray(ds["radius"].values, float)
    segs, kinds = contact_segments(x, y, r, s.walls, pairs, walls, plate)
    return Assembly(
        name=s.name,
        x=x,
        y=y,
        radius=r,
        labels=labels,
        materials=tuple(str(v) for v in ds["material"].values),
        walls=s.walls,
        plate=result_plate(s, ds, t),
        load=s.load,
        loaded=loaded_granules(s, np.column_stack([ds["x"].values[0], ds["y"].values[0]]), r),
        segments=segs,
        kinds=kinds,
        forces=forces,
        time=t,
        time_note=note,
    )
