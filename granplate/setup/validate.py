"""Refuse a bad scenario before anything runs.

`validate(scenario)` raises `ScenarioError(field, value, allowed)` for the first problem
found. `field` is the dotted path as written in TOML (`granules[3].radius`,
`materials.ptfe.nu`, `layout.R2_ratio`, `time.t_end`...; indices are 0-based, in file
order), `allowed` says in words what would be accepted. The layout is checked as
`layout.*` before it is expanded; everything else is checked on the resolved scenario
(`geometry.resolve`), so generated granules are named `granules[i]` with their label.

The plate's mesh is checked too, before anything is built (setup.plate_checks); single
fields are checked by setup.fields. The plate layer itself only checks the internal
consistency of its inputs.
"""
from __future__ import annotations

import dataclasses
import math
import numbers
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from granplate.errors import ScenarioError
from granplate.setup.geometry import granule_named, layout_packing, resolve
from granplate.setup.layouts import column_radii, half_pitch, hexagonal_offsets, lattice_sites
from granplate.setup.fields import finite, int_at_least, is_number, material_exists, nonneg, positive, string_in
from granplate.setup.plate_checks import check_plate_mesh
from granplate.setup.plate_cost import MODE_CHOICES
from granplate.setup.scenario import (LAYOUT_KINDS, SQRT2_MINUS_1, ChainLayout, Granule,
                                      Imperfections, LatticeLayout, Layout, Scenario)

#: Lever arms of the friction torque (Contact.torque_arm).
TORQUE_ARMS: tuple[str, ...] = ("radius", "contact_point")
DETECTIONS: tuple[str, ...] = ("dynamic", "fixed")
#: Coupling schemes the solver knows (Solver.scheme).
SCHEMES: tuple[str, ...] = ("paper", "implicit")
#: Treatments of the granule-granule and granule-wall friction (Solver.granular_friction).
GRANULAR_FRICTIONS: tuple[str, ...] = ("split", "rk4")
#: Load kinds (Load.kind) and targets (Load.target).
LOAD_KINDS: tuple[str, ...] = ("line", "none")
LOAD_TARGETS: tuple[str, ...] = ("granules", "plate")
#: Plate edges that may be clamped (Plate.clamped_edges).
PLATE_EDGES: tuple[str, ...] = ("top", "bottom", "left", "right")

#: Relative tolerance on overlaps/penetrations at t = 0 (times the smaller radius).
OVERLAP_RTOL = 1e-9
#: Tolerance on |normal| - 1 for walls.
NORMAL_TOL = 1e-9
#: Tolerance on the R2/R1 bounds.
RATIO_TOL = 1e-12
#: Relative tolerance for field_interval being a multiple of output_interval.
INTERVAL_RTOL = 1e-9


# --------------------------------------------------------------------------- sections

def _check_materials(s: Scenario) -> None:
    if not isinstance(s.materials, dict) or not s.materials:
        raise ScenarioError("materials", s.materials, "must be a non-empty table of materials")
    for name, m in s.materials.items():
        p = f"materials.{name}"
        positive(f"{p}.E", m.E)
        finite(f"{p}.nu", m.nu, "must be in (-1, 0.5) (a finite number)")
        if not -1.0 < m.nu < 0.5:
            raise ScenarioError(f"{p}.nu", m.nu, "must be in (-1, 0.5)")
        positive(f"{p}.rho", m.rho)


def _check_layout(s: Scenario) -> None:
    lay = s.layout
    if lay is None:
        return
    string_in("layout.kind", lay.kind, tuple(LAYOUT_KINDS))
    if not isinstance(lay, LAYOUT_KINDS[lay.kind]):
        raise ScenarioError("layout.kind", lay.kind,
                            f"a {type(lay).__name__} must have kind one of " + ", ".join(
                                repr(k) for k, c in LAYOUT_KINDS.items() if isinstance(lay, c)))
    if lay.kind == "paper":
        _check_paper_layout(s, lay)
    elif lay.kind == "chain":
        _check_chain_layout(s, lay)
    else:
        _check_lattice_layout(s, lay)
    if lay.imperfections is not None:
        _check_imperfections(lay.imperfections, layout_packing(
            dataclasses.replace(lay, imperfections=None)).granules)


def _check_paper_layout(s: Scenario, lay: Layout) -> None:
    positive("layout.R1", lay.R1)
    r = finite("layout.R2_ratio", lay.R2_ratio,
                f"must be in [{SQRT2_MINUS_1:.8f}, 1] (sqrt(2)-1 <= R2/R1 <= 1)")
    if not (SQRT2_MINUS_1 - RATIO_TOL <= r <= 1.0 + RATIO_TOL):
        raise ScenarioError("layout.R2_ratio", lay.R2_ratio,
                            f"must be in [{SQRT2_MINUS_1:.8f}, 1] (sqrt(2)-1 <= R2/R1 <= 1)")
    for f in ("heavy_material", "intruder_material", "wall_material"):
        material_exists(f"layout.{f}", getattr(lay, f), s)


def _list_of_columns(path: str, values: Any, columns: int) -> None:
    if not isinstance(values, tuple) or (values and len(values) != columns):
        raise ScenarioError(path, values, f"must be empty or a list of {columns} values "
                            "(one per column, layout.columns)")


def _check_lattice_layout(s: Scenario, lay: LatticeLayout) -> None:
    int_at_least("layout.columns", lay.columns, 1)
    int_at_least("layout.rows", lay.rows, 2 if lay.kind == "hexagonal" and lay.columns > 1 else 1)
    positive("layout.radius", lay.radius)
    for f in ("material", "wall_material"):
        material_exists(f"layout.{f}", getattr(lay, f), s)
    if lay.intruder_material is not None:
        material_exists("layout.intruder_material", lay.intruder_material, s)
    _list_of_columns("layout.column_radii", lay.column_radii, lay.columns)
    for c, r in enumerate(lay.column_radii):
        positive(f"layout.column_radii[{c}]", r)
    _list_of_columns("layout.column_materials", lay.column_materials, lay.columns)
    for c, m in enumerate(lay.column_materials):
        material_exists(f"layout.column_materials[{c}]", m, s)
    positive("layout.intruder_ratio", lay.intruder_ratio)
    for k, c in enumerate(lay.intruder_columns):
        if not isinstance(c, numbers.Integral) or isinstance(c, bool) or not 1 <= c <= lay.columns:
            raise ScenarioError(f"layout.intruder_columns[{k}]", c,
                                f"must be a column number in 1..{lay.columns} (layout.columns)")
    int_at_least("layout.intruder_every", lay.intruder_every, 0)
    sites = [g.label for g in lattice_sites(dataclasses.replace(lay, intruder_columns=()))]
    known = set(sites)
    for k, lab in enumerate(lay.intruder_sites):
        if lab not in known:
            raise ScenarioError(f"layout.intruder_sites[{k}]", lab,
                                f"no such site; sites are c1r1..c{lay.columns}r{lay.rows} "
                                "(column, row from the top; even hexagonal columns have rows - 1)")
    if (lay.intruder_sites or lay.intruder_every) and lay.intruder_ratio > 1.0:
        raise ScenarioError("layout.intruder_ratio", lay.intruder_ratio,
                            "must be in (0, 1] with intruder_sites or intruder_every "
                            "(a single-site intruder larger than its site overlaps its neighbours)")
    _check_column_offsets(lay)


def _check_column_offsets(lay: LatticeLayout) -> None:
    """Neighbouring columns reach each other, and columns c and c+2 do not overlap."""
    radii = column_radii(lay)
    what = "layout.column_radii" if lay.column_radii else "layout.intruder_ratio"
    value = lay.column_radii if lay.column_radii else lay.intruder_ratio
    if lay.kind != "hexagonal" or len(radii) < 2:
        return
    a = half_pitch(radii)
    d = hexagonal_offsets(radii, a)
    for c in range(len(radii) - 1):
        if not radii[c] + radii[c + 1] >= a:
            raise ScenarioError(what, value,
                                f"columns {c + 1} and {c + 2} cannot touch: R_{c + 1} + R_{c + 2} = "
                                f"{radii[c] + radii[c + 1]:.6g} m < the largest radius {a:.6g} m; "
                                "allowed: R_c + R_c+1 >= max R (hexagonal packing)")
    for c in range(len(radii) - 2):
        gap = d[c] + d[c + 1] - radii[c] - radii[c + 2]
        if gap < -OVERLAP_RTOL * min(radii[c], radii[c + 2]):
            raise ScenarioError(what, value,
                                f"columns {c + 1} and {c + 3} overlap by {-gap:.6g} m (column "
                                f"{c + 2} too small to hold them apart); allowed: "
                                "d_c + d_c+1 >= R_c + R_c+2 with d_c = sqrt((R_c + R_c+1)^2 - a^2), "
                                "e.g. R_c+1 >= (sqrt(2) - 1) R_c for equal outer columns")


def _check_chain_layout(s: Scenario, lay: ChainLayout) -> None:
    int_at_least("layout.count", lay.count, 1)
    positive("layout.radius", lay.radius)
    positive("layout.taper", lay.taper)
    positive("layout.dimer_ratio", lay.dimer_ratio)
    nonneg("layout.decorated_ratio", lay.decorated_ratio)
    for f in ("material", "wall_material", "dimer_material", "decorated_material"):
        if getattr(lay, f) is not None:
            material_exists(f"layout.{f}", getattr(lay, f), s)
    if lay.y is not None:
        finite("layout.y", lay.y)


def _check_imperfections(imp: Imperfections, sites: tuple[Granule, ...]) -> None:
    p = "layout.imperfections"
    int_at_least(f"{p}.seed", imp.seed, 0)
    for f in ("radius_spread", "jitter", "vacancy_fraction"):
        v = finite(f"{p}.{f}", getattr(imp, f), "must be in [0, 1) (a finite number)")
        if not 0.0 <= v < 1.0:
            raise ScenarioError(f"{p}.{f}", v, "must be in [0, 1)")
    if not imp.radius_spread + imp.jitter < 1.0:
        raise ScenarioError(f"{p}.jitter", imp.jitter,
                            f"radius_spread + jitter must be < 1 (radius_spread = "
                            f"{imp.radius_spread!r}: the smallest radius R (1 - jitter - "
                            "radius_spread) must stay > 0)")
    labels = {g.label for g in sites}
    for k, lab in enumerate(imp.vacancies):
        if lab not in labels:
            raise ScenarioError(f"{p}.vacancies[{k}]", lab,
                                "no such site in the perfect packing (labels such as "
                                + ", ".join(list(g.label for g in sites)[:3]) + ", ...)")


def _check_granules(s: Scenario, named: dict[int, str]) -> None:
    seen: dict[str, int] = {}
    for i, g in enumerate(s.granules):
        p = f"granules[{i}]"
        finite(f"{p}.x", g.x)
        finite(f"{p}.y", g.y)
        positive(f"{p}.radius", g.radius)
        for f in ("vx", "vy", "omega"):
            finite(f"{p}.{f}", getattr(g, f))
        material_exists(f"{p}.material", g.material, s)
        if not isinstance(g.label, str):
            raise ScenarioError(f"{p}.label", g.label, "must be a string")
        if g.label in seen:
            raise ScenarioError(f"{p}.label", g.label,
                                f"labels must be unique; granules[{seen[g.label]}] has it too")
        seen[g.label] = i
    gs = s.granules
    for i, j in _close_pairs(gs):
        gi, gj = gs[i], gs[j]
        dist = math.hypot(gj.x - gi.x, gj.y - gi.y)
        overlap = gi.radius + gj.radius - dist
        if overlap > OVERLAP_RTOL * min(gi.radius, gj.radius):
            raise ScenarioError(
                f"granules[{i}]", gi.label,
                f"{named[i]} overlaps {named[j]} (granules[{j}]) by {overlap:.6g} m at t = 0; "
                f"granules may touch but not overlap (tolerance "
                f"{OVERLAP_RTOL:g} x the smaller radius)")


def _close_pairs(gs: tuple[Granule, ...]) -> list[tuple[int, int]]:
    """Sorted pairs (i < j) of granules whose centres are at most 2 R_max apart (k-d tree):
    every pair that can overlap, found in O(N log N)."""
    if len(gs) < 2:
        return []
    xy = np.array([(g.x, g.y) for g in gs], float)
    r_max = max(g.radius for g in gs)
    pairs = cKDTree(xy).query_pairs(2.0 * r_max * (1.0 + 1e-9), output_type="ndarray")
    return sorted(map(tuple, pairs.tolist()))


def _check_walls(s: Scenario, named: dict[int, str]) -> None:
    seen: dict[str, int] = {}
    for k, w in enumerate(s.walls):
        p = f"walls[{k}]"
        n = w.normal
        if (not isinstance(n, tuple) or len(n) != 2
                or not all(is_number(c) and math.isfinite(c) for c in n)):
            raise ScenarioError(f"{p}.normal", n, "must be two finite numbers [nx, ny]")
        norm = math.hypot(n[0], n[1])
        if abs(norm - 1.0) > NORMAL_TOL:
            raise ScenarioError(f"{p}.normal", n,
                                f"must be a unit vector (|normal| = {norm:.12g}; "
                                f"allowed 1 within {NORMAL_TOL:g})")
        finite(f"{p}.offset", w.offset)
        material_exists(f"{p}.material", w.material, s)
        if not isinstance(w.label, str):
            raise ScenarioError(f"{p}.label", w.label, "must be a string")
        if w.label in seen:
            raise ScenarioError(f"{p}.label", w.label,
                                f"labels must be unique; walls[{seen[w.label]}] has it too")
        seen[w.label] = k
        for i, g in enumerate(s.granules):
            pen = g.x * n[0] + g.y * n[1] + g.radius - w.offset
            if pen > OVERLAP_RTOL * g.radius:
                raise ScenarioError(
                    f"granules[{i}]", g.label,
                    f"{named[i]} penetrates wall '{w.label}' (walls[{k}]) by {pen:.6g} m at t = 0; "
                    f"a granule may touch a wall but not cross it")


def _check_plate(s: Scenario, named: dict[int, str]) -> None:
    pl = s.plate
    if pl is None:
        return
    for f in ("width", "height", "thickness"):
        positive(f"plate.{f}", getattr(pl, f))
    material_exists("plate.material", pl.material, s)
    x0 = finite("plate.x0", pl.x0)
    finite("plate.y0", pl.y0)
    int_at_least("plate.nx", pl.nx, 1)
    int_at_least("plate.ny", pl.ny, 1)
    if pl.rigid_layer_width is not None:
        positive("plate.rigid_layer_width", pl.rigid_layer_width)
    edges = pl.clamped_edges
    if not isinstance(edges, tuple) or not all(isinstance(e, str) and e in PLATE_EDGES
                                               for e in edges):
        raise ScenarioError("plate.clamped_edges", edges,
                            "must be a subset of " + ", ".join(repr(e) for e in PLATE_EDGES))
    int_at_least("plate.n_modes", pl.n_modes, 0)
    string_in("plate.modes", pl.modes, MODE_CHOICES)
    if pl.max_frequency is not None:
        positive("plate.max_frequency", pl.max_frequency)
    if pl.stress_radius is not None:
        positive("plate.stress_radius", pl.stress_radius)
        if pl.stress_radius > max(pl.width, pl.height):
            raise ScenarioError("plate.stress_radius", pl.stress_radius,
                                f"allowed: 0 < r <= max(plate.width, plate.height) = "
                                f"{max(pl.width, pl.height):g} m (a disc larger than the plate "
                                "averages over all of it)")
    for i, g in enumerate(s.granules):
        if pl.y0 <= g.y <= pl.y0 + pl.height:
            pen = g.x + g.radius - x0
            if pen > OVERLAP_RTOL * g.radius:
                raise ScenarioError(
                    f"granules[{i}]", g.label,
                    f"{named[i]} penetrates the plate (left edge x0 = {x0:.6g} m) by {pen:.6g} m at "
                    f"t = 0; granules must lie left of the plate (x + radius <= plate.x0)")


def _check_load(s: Scenario) -> None:
    ld = s.load
    string_in("load.kind", ld.kind, LOAD_KINDS)
    string_in("load.target", ld.target, LOAD_TARGETS)
    q0 = finite("load.q0", ld.q0, "must be >= 0 (a finite number) [N/m]")
    if not q0 >= 0.0:
        raise ScenarioError("load.q0", ld.q0, "must be >= 0 [N/m]")
    positive("load.duration", ld.duration)
    positive("load.length", ld.length)
    finite("load.y0", ld.y0)
    if not isinstance(ld.granules, tuple) or not all(isinstance(x, str) for x in ld.granules):
        raise ScenarioError("load.granules", ld.granules, "must be a list of granule labels")
    labels = {g.label for g in s.granules}
    for i, lab in enumerate(ld.granules):
        if lab not in labels:
            raise ScenarioError(f"load.granules[{i}]", lab,
                                "no granule has this label; labels are: "
                                + ", ".join(g.label for g in s.granules))
    if ld.kind == "line":
        if ld.target == "plate" and s.plate is None:
            raise ScenarioError("load.target", ld.target,
                                "a load on the plate needs a [plate]; use target = "
                                "\"granules\" or kind = \"none\"")
        if ld.target == "granules" and not s.granules:
            raise ScenarioError("load.target", ld.target,
                                "a load on the granules needs granules (or a [layout]); "
                                "use target = \"plate\" or kind = \"none\"")


def _check_contact(s: Scenario) -> None:
    c = s.contact
    nonneg("contact.mu", c.mu)
    positive("contact.k_s", c.k_s)
    nonneg("contact.alpha_n", c.alpha_n)
    nonneg("contact.neighbour_gap", c.neighbour_gap)
    string_in("contact.torque_arm", c.torque_arm, TORQUE_ARMS)
    string_in("contact.detection", c.detection, DETECTIONS)
    positive("contact.skin", c.skin)
    if c.skin > 1.0:
        raise ScenarioError("contact.skin", c.skin, "must be at most 1 (a fraction of R_i + R_j)")
    positive("contact.overlap_warn", c.overlap_warn)
    positive("contact.overlap_stop", c.overlap_stop)
    if not c.overlap_warn <= c.overlap_stop < 1.0:
        raise ScenarioError("contact.overlap_stop", c.overlap_stop,
                            f"must lie in [contact.overlap_warn = {c.overlap_warn:g}, 1)")
    if not isinstance(c.clip_tensile, bool):
        raise ScenarioError("contact.clip_tensile", c.clip_tensile, "must be true or false")
    for i, pc in enumerate(c.pairs):
        p = f"contact.pairs[{i}]"
        mats = pc.materials
        if not isinstance(mats, tuple) or len(mats) != 2:
            raise ScenarioError(f"{p}.materials", mats, "must be two material names")
        for k, m in enumerate(mats):
            material_exists(f"{p}.materials[{k}]", m, s)
        if pc.alpha_n is not None:
            nonneg(f"{p}.alpha_n", pc.alpha_n)
        if pc.mu is not None:
            nonneg(f"{p}.mu", pc.mu)
        if pc.k_s is not None:
            positive(f"{p}.k_s", pc.k_s)


def _check_time(s: Scenario) -> None:
    t = s.time
    for f in ("t_end", "dt_initial", "dt_max", "dt_min", "output_interval", "field_interval"):
        positive(f"time.{f}", getattr(t, f))
    if t.dt_min > t.dt_initial:
        raise ScenarioError("time.dt_min", t.dt_min,
                            f"must be <= time.dt_initial = {t.dt_initial!r} "
                            "(dt_min <= dt_initial <= dt_max)")
    if t.dt_initial > t.dt_max:
        raise ScenarioError("time.dt_initial", t.dt_initial,
                            f"must be <= time.dt_max = {t.dt_max!r} "
                            "(dt_min <= dt_initial <= dt_max)")
    if t.output_interval > t.t_end:
        raise ScenarioError("time.output_interval", t.output_interval,
                            f"must be <= time.t_end = {t.t_end!r}")
    r = t.field_interval / t.output_interval
    n = round(r)
    if n < 1 or abs(r - n) > INTERVAL_RTOL * r:
        raise ScenarioError("time.field_interval", t.field_interval,
                            f"must be a whole multiple (>= 1) of time.output_interval = "
                            f"{t.output_interval!r}")


def _check_solver(s: Scenario) -> None:
    sv = s.solver
    string_in("solver.scheme", sv.scheme, SCHEMES)
    string_in("solver.granular_friction", sv.granular_friction, GRANULAR_FRICTIONS)
    lam = finite("solver.lambda_target", sv.lambda_target, "must be in (0, 1)")
    if not 0.0 < lam < 1.0:
        raise ScenarioError("solver.lambda_target", sv.lambda_target, "must be in (0, 1)")
    positive("solver.iteration_rtol", sv.iteration_rtol)
    positive("solver.iteration_atol", sv.iteration_atol)
    int_at_least("solver.max_iterations", sv.max_iterations, 1)
    positive("solver.energy_tol", sv.energy_tol)
    positive("solver.error_tol", sv.error_tol)
    positive("solver.implicit_dt_max", sv.implicit_dt_max)


# --------------------------------------------------------------------------- entry point

class _GranuleNames(dict):
    """Granule i of the resolved scenario as messages name it (`geometry.granule_named`:
    its label and the fields that place it), made when a message asks."""

    def __init__(self, scenario: Scenario, resolved: Scenario):
        super().__init__()
        self.scenario, self.resolved = scenario, resolved

    def __missing__(self, i: int) -> str:
        return granule_named(self.scenario, self.resolved, i)


def validate(scenario: Scenario) -> None:
    """Raise ScenarioError(field, value, allowed) for the first problem in `scenario`.

    Order: materials, layout (as `layout.*`, before it is expanded), then on the resolved
    scenario: granules (values, unique labels, overlaps), walls (unit normals,
    penetration), plate, load, contact, plate mesh (rigid layers of the contacts on
    nodes, patch contacts between nodes, n_modes), time, solver. A scenario with neither granules
    (nor a layout) nor a plate is refused.
    """
    s = scenario
    if not isinstance(s.name, str):
        raise ScenarioError("name", s.name, "must be a string")
    if not isinstance(s.description, str):
        raise ScenarioError("description", s.description, "must be a string")
    _check_materials(s)
    _check_layout(s)
    if s.layout is None and not s.granules and s.plate is None:
        raise ScenarioError("granules", (), "a scenario needs granules (or a [layout]) "
                            "or a [plate], or both; it has neither")
    if s.plate is not None and s.plate.x0 is not None:
        finite("plate.x0", s.plate.x0)
    r = resolve(s)
    named = _GranuleNames(s, r)
    _check_granules(r, named)
    _check_walls(r, named)
    _check_plate(r, named)
    _check_load(r)
    _check_contact(r)
    check_plate_mesh(r, named)
    _check_time(r)
    _check_solver(r)


def validated(scenario: Scenario) -> Scenario:
    """`validate(scenario)`, then return `scenario` unchanged (for chaining)."""
    validate(scenario)
    return scenario
