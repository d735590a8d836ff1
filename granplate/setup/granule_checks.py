"""The rules of the granules: their fields and speeds, the range of their lengths, overlaps
between them at t = 0 beyond what a contact accounts for, and their penetration of walls and
the plate.
"""

from __future__ import annotations

import math
import operator

import numpy as np

from granplate.errors import ScenarioError
from granplate.setup.geometry import unit
from granplate.setup.fields import finite, is_number, material_exists, nonneg, positive
from granplate.setup.pairs import close_pairs, contact_search_distance, superset_pairs
from granplate.setup.solid_checks import is_box
from granplate.setup.materials import Material
from granplate.setup.scenario import Solid, BOX_WALLS, Granule, Plate, Scenario
from granplate.setup.check_base import (
    LENGTH_RANGE,
    OVERLAP_RTOL,
    _column,
    _floats,
    _granule,
    bar_wave_speed,
    length_scale,
)


def _planar_granules(gs: tuple[Granule, ...]) -> bool:
    """Whether every granule has z = vz = 0.0 and a number omega (`_check_planar` passes)."""
    cols = [_column(gs, f) for f in ("z", "vz", "omega")]
    return all(c is not None for c in cols) and not cols[0].any() and not cols[1].any()


def _granule_columns(s: Scenario) -> dict[str, np.ndarray] | None:
    """The granules' numbers by field (3D: omega as (n, 3)), or None when one is not a
    Python float (or, in 3D, an omega not three of them)."""
    gs = s.granules
    names = (
        ("x", "y", "z", "radius", "vx", "vy", "vz") if s.dimension == 3 else ("x", "y", "radius", "vx", "vy", "omega")
    )
    cols = {f: _column(gs, f) for f in names}
    if s.dimension == 3:
        spins = list(map(operator.attrgetter("omega"), gs))
        if set(map(type, spins)) != {tuple} or set(map(len, spins)) != {3}:
            return None
        flat = _floats([w for om in spins for w in om])
        cols["omega"] = None if flat is None else flat.reshape(-1, 3)
    else:
        cols["omega"] = None if cols["omega"] is None else cols["omega"][:, None]
    return None if any(c is None for c in cols.values()) else cols


def _granules_pass(s: Scenario) -> bool:
    """Whether every granule passes `_check_granules` (numpy over the columns: the same
    comparisons on the same doubles); False when one may not."""
    gs = s.granules
    cols = _granule_columns(s)
    mats = list(map(operator.attrgetter("material"), gs))
    labels = list(map(operator.attrgetter("label"), gs))
    if cols is None or set(map(type, mats)) != {str} or set(map(type, labels)) != {str}:
        return False
    if len(set(labels)) != len(labels) or not set(mats) <= set(s.materials):
        return False
    with np.errstate(all="ignore"):
        if not all(np.isfinite(c).all() for c in cols.values()) or not (cols["radius"] > 0.0).all():
            return False
        speed = {m: bar_wave_speed(s.material(m)) for m in set(mats)}
        c = np.array([speed[m] for m in mats], float)
        speeds = [np.abs(cols[f]) for f in (("vx", "vy", "vz") if s.dimension == 3 else ("vx", "vy"))]
        speeds += [np.abs(w) * cols["radius"] for w in cols["omega"].T]
        return all((v < c).all() for v in speeds)


def _check_granules(s: Scenario) -> None:
    if _granules_pass(s):
        return
    seen: dict[str, int] = {}
    for i, g in enumerate(s.granules):
        finite(_granule(s, i, "x"), g.x)
        finite(_granule(s, i, "y"), g.y)
        if s.dimension == 3:
            finite(_granule(s, i, "z"), g.z)
        positive(_granule(s, i, "radius"), g.radius)
        for f in ("vx", "vy") + (("vz",) if s.dimension == 3 else ("omega",)):
            finite(_granule(s, i, f), getattr(g, f))
        if s.dimension == 3:
            for k, w in enumerate(g.omega):
                finite(_granule(s, i, f"omega[{k}]"), w)
        material_exists(_granule(s, i, "material"), g.material, s)
        _check_speeds(s, i, g, s.material(g.material))
        if not isinstance(g.label, str):
            raise ScenarioError(_granule(s, i, "label"), g.label, "must be a string")
        if g.label in seen:
            raise ScenarioError(
                _granule(s, i, "label"), g.label, f"labels must be unique; {_granule(s, seen[g.label])} has it too"
            )
        seen[g.label] = i


def _check_speeds(s: Scenario, i: int, g: Granule, m: Material) -> None:
    """|vx|, |vy| (|vz|) and the surface speed |omega| R (each component in 3D) below the
    wave speed of the granule's material: Hertz's law is quasi-static and holds for impact
    speeds far below it."""
    c = bar_wave_speed(m)
    if isinstance(g.omega, tuple):
        spins = [(f"omega[{k}]", w) for k, w in enumerate(g.omega)]
        speeds = [("vx", g.vx), ("vy", g.vy), ("vz", g.vz)]
    else:
        spins, speeds = [("omega", g.omega)], [("vx", g.vx), ("vy", g.vy)]
    checks = [(f, abs(v), v) for f, v in speeds] + [(f, abs(w) * g.radius, w) for f, w in spins]
    for f, speed, value in checks:
        if not speed < c:
            unit = f"|{f}| x radius" if f.startswith("omega") else f"|{f}|"
            raise ScenarioError(
                _granule(s, i, f),
                value,
                f"allowed: {unit} < sqrt(E / rho) = {c:.6g} m/s, the elastic "
                f"wave speed of material '{m.name}' (Hertz's contact law is "
                "quasi-static: it holds for speeds far below it)",
            )


def _wall_paths(s: Scenario, boxed: bool) -> list[str]:
    """The field that places each wall of the resolved `s`: walls[k].offset, or, for the six
    walls a box expanded into (the last six when `boxed`), box.lower[axis] / box.upper[axis]."""
    n = len(s.walls) - (len(BOX_WALLS) if boxed else 0)
    paths = [f"walls[{k}].offset" for k in range(n)]
    if boxed:
        paths += [f"box.{'upper' if j % 2 else 'lower'}[{j // 2}]" for j in range(len(BOX_WALLS))]
    return paths


def _check_lengths(s: Scenario, boxed: bool = False) -> None:
    """Coordinates and sizes within LENGTH_RANGE x the smallest length (see LENGTH_RANGE);
    boxed: the last six walls are the expanded box (named as its corners' fields)."""
    h, what = length_scale(s)
    limit = LENGTH_RANGE * h
    why = (
        f"{LENGTH_RANGE:g} x the smallest length of the scenario, h = {h:.6g} m ({what}): "
        f"farther out, round-off of a coordinate (2.2e-16 |x|) exceeds the {OVERLAP_RTOL:g} h "
        "overlap tolerance at t = 0"
    )
    coords = ("x", "y", "z", "radius") if s.dimension == 3 else ("x", "y", "radius")
    cols = [_column(s.granules, f) for f in coords] if s.granules else []
    inside = all(c is not None and (np.abs(c) <= limit).all() for c in cols)
    values = [] if inside else [(_granule(s, i, f), getattr(g, f)) for i, g in enumerate(s.granules) for f in coords]
    values += [
        (path, -w.offset if ".lower[" in path else w.offset)  # box.lower: offset -x0
        for path, w in zip(_wall_paths(s, boxed), s.walls)
    ]
    values += [
        (f"walls[{k}].point[{c}]", x)
        for k, w in enumerate(s.walls)
        if w.point is not None
        for c, x in enumerate(w.point)
    ]
    if isinstance(s.plate, Solid) and is_box(s.plate):
        values += [(f"plate.{f}[{k}]", getattr(s.plate, f)[k]) for f in ("size", "origin") for k in range(3)]
    elif isinstance(s.plate, Plate):
        pl = s.plate
        values += [
            (f"plate.{f}", getattr(pl, f))
            for f in ("x0", "y0", "width", "height", "thickness", "rigid_layer_width")
            if getattr(pl, f) is not None
        ]
    for path, v in values:
        if not abs(v) <= limit:
            raise ScenarioError(path, v, f"allowed: |value| <= {limit:.6g} m, {why}")


def _check_overlaps(s: Scenario, named: dict[int, str]) -> None:
    """Granules may touch but not overlap at t = 0 (k-d tree over the centres; the
    coordinates are within LENGTH_RANGE x h, so its squared distances cannot overflow)."""
    gs = s.granules
    tol = start_overlap(s)
    for i, j in _overlapping_pairs(gs, s.dimension, s.contact, tol):
        gi, gj = gs[i], gs[j]
        dist = math.dist(_centre(gi, s.dimension), _centre(gj, s.dimension))
        overlap = gi.radius + gj.radius - dist
        if overlap > tol * min(gi.radius, gj.radius):
            raise ScenarioError(
                _granule(s, i),
                gi.label,
                f"{named[i]} overlaps {named[j]} ({_granule(s, j)}) by {overlap:.6g} m at t = 0; "
                f"granules may touch but not overlap (tolerance "
                f"{tol:g} x the smaller radius, contact.overlap_start)",
            )


def start_overlap(s: Scenario) -> float:
    """The overlap allowed at t = 0, a fraction of the smaller radius [-]: contact.overlap_start
    (checked here: in [0, contact.overlap_warn]) or OVERLAP_RTOL when it is None."""
    v = s.contact.overlap_start
    if v is None:
        return OVERLAP_RTOL
    nonneg("contact.overlap_start", v)
    warn = s.contact.overlap_warn
    if is_number(warn) and not float(v) <= warn:
        raise ScenarioError(
            "contact.overlap_start",
            v,
            f"must lie in [0, contact.overlap_warn = {warn:g}] (a fraction of the smaller radius)",
        )
    return max(OVERLAP_RTOL, float(v))


def _centre(g: Granule, dimension: int) -> tuple[float, ...]:
    """The centre [m]: (x, y) in 2D, (x, y, z) in 3D."""
    return (g.x, g.y, g.z) if dimension == 3 else (g.x, g.y)


def _close_pairs(gs: tuple[Granule, ...], dimension: int = 2) -> list[tuple[int, int]]:
    """Sorted pairs (i < j) of granules whose centres are at most 2 R_max apart
    (setup.pairs.close_pairs, in the plane or in space): every pair that can overlap."""
    if len(gs) < 2:
        return []
    xy = np.array([_centre(g, dimension) for g in gs], float)
    r_max = max(g.radius for g in gs)
    return [tuple(p) for p in close_pairs(xy, 2.0 * r_max * (1.0 + 1e-9)).tolist()]


#: Relative margin on the numpy distances of `_overlapping_pairs` (their rounding against
#: math.dist's is a few units of 1e-16): a pair within it is checked by math.dist.
DISTANCE_MARGIN = 1e-12
#: The largest contact.neighbour_gap and contact.skin for which the overlap check searches as
#: far as the model's lists and keeps its search for them (`_overlapping_pairs`).
SHARED_SEARCH_MAX = 1.0


def _overlapping_pairs(
    gs: tuple[Granule, ...], dimension: int = 2, contact=None, tol: float = OVERLAP_RTOL
) -> list[tuple[int, int]]:
    """The pairs of `_close_pairs` (sorted) that may overlap beyond the tolerance: those
    whose overlap from numpy's distance comes within DISTANCE_MARGIN of it (the check then
    measures each with math.dist, as for every pair). contact: the scenario's [contact],
    whose searches at t = 0 the model makes next (its search is kept for them when its
    gap and skin are numbers up to SHARED_SEARCH_MAX, so that it stays a search of
    neighbours; else None)."""
    if contact is not None and not all(
        is_number(v) and 0.0 <= v <= SHARED_SEARCH_MAX for v in (contact.neighbour_gap, contact.skin)
    ):
        contact = None
    centres = [_column(gs, f) for f in ("x", "y", "z")[:dimension]] if len(gs) > 1 else []
    r = _column(gs, "radius") if len(gs) > 1 else None
    if r is None or any(c is None for c in centres):
        return _close_pairs(gs, dimension)
    points = np.column_stack(centres)
    c = contact
    # one search for this check and the model's lists (setup.pairs.superset_pairs): every
    # pair within 2 R_max, and within what the lists need, which keep it for themselves
    share = (
        contact_search_distance(float(r.max()), c.neighbour_gap, c.skin, c.detection == "dynamic")
        if contact is not None
        else 0.0
    )
    pairs = superset_pairs(points, max(2.0 * float(r.max()) * (1.0 + 1e-9), share), keep=contact is not None)
    i, j = pairs[:, 0], pairs[:, 1]
    dist = np.sqrt(((points[j] - points[i]) ** 2).sum(axis=1))
    overlap = r[i] + r[j] - dist
    may = overlap > tol * np.minimum(r[i], r[j]) - DISTANCE_MARGIN * (r[i] + r[j] + dist)
    return [tuple(p) for p in pairs[may].tolist()]


def _check_wall_penetration(s: Scenario, named: dict[int, str]) -> None:
    """No granule crosses a wall at t = 0 (3D: the plane of unit normal n = normal / |normal|)."""
    for k, w in enumerate(s.walls):
        n = w.normal
        if s.dimension == 3:
            n = unit(n)
        for i, g in enumerate(s.granules if _may_cross_wall(s, n, w.offset) else ()):
            depth = g.x * n[0] + g.y * n[1] + (g.z * n[2] if s.dimension == 3 else 0.0)
            pen = depth + g.radius - w.offset
            if pen > start_overlap(s) * g.radius:
                raise ScenarioError(
                    _granule(s, i),
                    g.label,
                    f"{named[i]} penetrates wall '{w.label}' (walls[{k}]) by {pen:.6g} m at t = 0; "
                    f"a granule may touch a wall but not cross it",
                )


def _may_cross_wall(s: Scenario, n: tuple[float, ...], offset: float) -> bool:
    """Whether a granule may cross the wall {p . n = offset} (numpy: the same operations on
    the same doubles as `_check_wall_penetration`; True when a value is not a Python float)."""
    cols = [_column(s.granules, f) for f in ("x", "y", "z", "radius")]
    if not s.granules or any(c is None for c in cols) or not all(is_number(c) for c in (*n, offset)):
        return bool(s.granules)
    x, y, z, r = cols
    depth = x * n[0] + y * n[1] + (z * n[2] if s.dimension == 3 else 0.0)
    with np.errstate(all="ignore"):
        return not (depth + r - offset <= start_overlap(s) * r).all()


def _check_plate_penetration(s: Scenario, named: dict[int, str]) -> None:
    """No granule crosses the plate's left edge at t = 0."""
    pl = s.plate
    if not isinstance(pl, Plate):
        return
    x0 = pl.x0
    for i, g in enumerate(s.granules):
        if pl.y0 <= g.y <= pl.y0 + pl.height:
            pen = g.x + g.radius - x0
            if pen > start_overlap(s) * g.radius:
                raise ScenarioError(
                    _granule(s, i),
                    g.label,
                    f"{named[i]} penetrates the plate (left edge plate.x0 = {x0:.6g} m) by {pen:.6g} m at "
                    f"t = 0; granules must lie left of the plate (x + radius <= plate.x0)",
                )
