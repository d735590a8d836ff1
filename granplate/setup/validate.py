"""Refuse a bad scenario before anything runs.

`validate(scenario)` raises `ScenarioError(field, value, allowed)` for the first problem
found. `field` is the dotted path as written in TOML (`granules[3].radius`,
`materials.ptfe.nu`, `layout.R2_ratio`, `time.t_end`...; indices are 0-based, in file
order), `allowed` says in words what would be accepted. The layout is checked as
`layout.*` before it is expanded; everything else is checked on the resolved scenario
(`geometry.resolve`), so generated granules are named `granules[i]` with their label.

The plate's fields and mesh are checked too, before anything is built (setup.plate_checks,
the one owner of those rules: the plate layer runs the same checks on a direct caller's
inputs); single fields are checked by setup.fields.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import operator
import threading
import weakref
from collections import Counter
from typing import Any

import numpy as np

from granplate.errors import ScenarioError
from granplate.setup.geometry import granule_named, layout_packing, plane_offset, resolve, unit
from granplate.setup.layouts import (
    INTRUDER_COLUMN_RULES,
    column_radii,
    layer_planes,
    half_pitch,
    hexagonal_offsets,
    lattice_sites,
    plane_clash,
    plane_gap_distance,
    plane_layers,
    plane_type,
    planes_along_x,
    planes_per_cell,
    sites_per_cell,
    space_sites,
)
from granplate.setup.drive_checks import check_drives, check_gravity
from granplate.setup.fields import (
    check_dimension,
    finite,
    int_at_least,
    is_number,
    material_exists,
    nonneg,
    positive,
    string_in,
)
from granplate.setup.granules_file import granule_path
from granplate.setup.pouring import check_poured
from granplate.setup.pairs import close_pairs, contact_search_distance, superset_pairs
from granplate.setup.plate_checks import check_plate_fields, check_plate_mesh
from granplate.setup.solid_checks import (
    box_corners,
    box_distances,
    check_solid,
    check_solid_clearance,
    is_box,
    solid_named,
    wall_contact_on_box,
    wall_cuts_box,
)
from granplate.setup.plate_cost import MEMORY_SHARE, physical_memory
from granplate.setup.materials import Material
from granplate.setup.scenario import (
    Solid,
    BOX_WALLS,
    LAYOUT_KINDS,
    LAYOUT_KINDS_BY_DIMENSION,
    NORMAL_LAWS,
    SPACE_LATTICE_KINDS,
    SQRT2_MINUS_1,
    ChainLayout,
    Granule,
    Imperfections,
    LatticeLayout,
    Layer,
    Layout,
    Plate,
    PouredLayout,
    Scenario,
    SpaceLattice,
)

#: Lever arms of the friction torque (Contact.torque_arm).
TORQUE_ARMS: tuple[str, ...] = ("radius", "contact_point")
DETECTIONS: tuple[str, ...] = ("dynamic", "fixed")
#: Normal laws (of NORMAL_LAWS) that need the yield strength Y of every body that can
#: yield at a contact (both granules; the granule alone against a wall or the plate).
YIELDING_LAWS: tuple[str, ...] = ("thornton", "johnson")
#: Coupling schemes the solver knows (Solver.scheme).
SCHEMES: tuple[str, ...] = ("paper", "implicit", "verlet")
#: Schemes of the granules alone: a scenario with a [plate] is refused with them.
GRANULAR_SCHEMES: tuple[str, ...] = ("verlet",)
#: Treatments of the granule-granule and granule-wall friction (Solver.granular_friction).
GRANULAR_FRICTIONS: tuple[str, ...] = ("split", "rk4")
#: Load kinds (Load.kind: "line" is 2D, "force" 3D) and targets (Load.target).
LOAD_KINDS: tuple[str, ...] = ("line", "force", "none")
LOAD_KINDS_BY_DIMENSION: dict[int, tuple[str, ...]] = {2: ("line", "none"), 3: ("force", "line", "none")}
LOAD_TARGETS: tuple[str, ...] = ("granules", "plate")
#: Plate edges that may be clamped (Plate.clamped_edges).

#: Relative tolerance on overlaps/penetrations at t = 0 (times the smaller radius).
OVERLAP_RTOL = 1e-9
#: Largest Young's modulus [Pa] and density [kg/m^3] of a material: about ten times and
#: four times those of the stiffest and the densest solids (diamond, osmium).
E_MAX = 1e13
RHO_MAX = 1e5
#: Tolerance on |normal| - 1 for walls (2D; a 3D wall's normal may have any length > 0).
NORMAL_TOL = 1e-9
#: Relative tolerance of a 3D wall's offset against point . n when both are given.
PLANE_RTOL = 1e-12
#: Tolerance on the R2/R1 bounds.
RATIO_TOL = 1e-12
#: Relative tolerance for field_interval being a multiple of output_interval.
INTERVAL_RTOL = 1e-9
#: Every coordinate and size lies within LENGTH_RANGE x the scenario's smallest length h
#: (`length_scale`): there the spacing of doubles, 2.2e-16 |x|, stays below 2.2e-10 h,
#: under the OVERLAP_RTOL x h tolerance at t = 0, so overlaps and gaps are resolved (and
#: the k-d tree's squared distances cannot overflow).
LENGTH_RANGE = 1e6
#: A layout's radii [m]: from a nanometre (below it a continuum contact law means nothing) to
#: a kilometre; its size ratios (taper, dimer, decorated, intruder) within 1 / LENGTH_RANGE
#: .. LENGTH_RANGE of the radius they scale, so that the granules it makes stay in the range
#: every coordinate is checked against (LENGTH_RANGE).
LAYOUT_RADIUS_RANGE: tuple[float, float] = (1e-9, 1e3)
#: The most sites a space lattice may have: `resolve` builds each sphere in Python (about a
#: second per 10^5), and the solver's scaling is measured up to 10^4 granules.
MAX_LAYOUT_SITES = 1_000_000


# --------------------------------------------------------------------------- sections


def _check_dimension(s: Scenario) -> None:
    check_dimension(s.dimension)


#: The end of every message refusing a 3D field in a 2D scenario.
SET_3D = "or set dimension = 3 (spheres in space)"


def _check_planar(s: Scenario) -> None:
    """A 2D scenario (as written) uses none of the 3D fields."""
    if s.box is not None:
        raise ScenarioError("box", "[box]", f"a box of six walls is 3D: give [[walls]] in 2D, {SET_3D}")
    for i, g in enumerate(() if _planar_granules(s.granules) else s.granules):
        for f in ("z", "vz"):
            v = getattr(g, f)
            if not (is_number(v) and v == 0.0):
                raise ScenarioError(_granule(s, i, f), v, f"must be 0 in 2D (discs in the plane), {SET_3D}")
        if isinstance(g.omega, tuple):
            raise ScenarioError(
                _granule(s, i, "omega"),
                list(g.omega),
                f"must be a number in 2D (the spin about z [rad/s]); a vector [wx, wy, wz] is 3D: {SET_3D}",
            )
    for k, w in enumerate(s.walls):
        p = f"walls[{k}]"
        if isinstance(w.normal, tuple) and len(w.normal) == 3:
            raise ScenarioError(
                f"{p}.normal", list(w.normal), f"has 3 components, a plane of 3D: give [nx, ny] in 2D, {SET_3D}"
            )
        if w.point is not None:
            raise ScenarioError(f"{p}.point", w.point, f"a point on a plane is 3D: give offset in 2D, {SET_3D}")
    if s.load.kind == "force":
        raise ScenarioError(
            "load.kind",
            s.load.kind,
            f'a total force [N] along a direction is 3D; in 2D use kind = "line" (q0 [N/m]) or "none", {SET_3D}',
        )
    lay = s.layout
    if lay is not None and isinstance(lay.kind, str) and lay.kind in SPACE_LATTICE_KINDS:
        raise ScenarioError(
            "layout.kind",
            lay.kind,
            "a lattice of spheres in space is 3D: in 2D use "
            "one of " + ", ".join(repr(k) for k in LAYOUT_KINDS_BY_DIMENSION[2]) + f", {SET_3D}",
        )
    if isinstance(lay, ChainLayout) and lay.z is not None:
        raise ScenarioError("layout.z", lay.z, f"a chain's depth z is 3D: leave it out in 2D, {SET_3D}")
    if isinstance(s.plate, Solid):
        raise ScenarioError(
            "plate",
            "[plate]",
            "an elastic solid (size, elements or mesh) is 3D: "
            f"in 2D the [plate] is a plane-stress plate (width, height, thickness), {SET_3D}",
        )


def _check_spatial(s: Scenario) -> None:
    """A 3D scenario (as written): granules, walls and a box, or a 3D layout; its [plate]
    an elastic solid (setup.solid_checks); vector spins; walls as planes."""
    if s.plate is not None:
        if not isinstance(s.plate, Solid):
            raise ScenarioError(
                "plate",
                "[plate]",
                "in 3D the [plate] is an elastic solid (setup.scenario."
                "Solid: size, elements, origin or mesh, material, element, clamped, rollers, "
                "max_frequency), not a plane-stress plate: set dimension = 2 for a plate",
            )
        check_solid(s)
    lay = s.layout
    if (
        lay is not None
        and isinstance(lay.kind, str)
        and lay.kind in LAYOUT_KINDS
        and lay.kind not in LAYOUT_KINDS_BY_DIMENSION[3]
    ):
        raise ScenarioError(
            "layout.kind",
            lay.kind,
            "a packing of discs in the plane is 2D: in 3D use "
            "one of " + ", ".join(repr(k) for k in LAYOUT_KINDS_BY_DIMENSION[3]) + " (or list [[granules]])",
        )
    if s.load.kind == "line" and s.load.target == "plate" and isinstance(s.plate, Solid) and not is_box(s.plate):
        raise ScenarioError(
            "load.target",
            s.load.target,
            "a line load on a 3D solid acts on a box's face "
            "xmin (plate.size); a mesh file's solid takes loads through granules",
        )
    spins = [g.omega for g in s.granules]
    vectors = set(map(type, spins)) <= {tuple} and set(map(len, spins)) <= {3}
    for i, g in enumerate(() if vectors else s.granules):
        om = g.omega
        if not isinstance(om, tuple):
            if is_number(om) and om == 0.0:
                continue  # the default: resolve makes it (0, 0, 0)
            raise ScenarioError(_granule(s, i, "omega"), om, "omega is a vector [wx, wy, wz] in 3D (rad/s)")
        if len(om) != 3:
            raise ScenarioError(
                _granule(s, i, "omega"), list(om), "omega is a vector [wx, wy, wz] in 3D (rad/s): three numbers"
            )
    for k, w in enumerate(s.walls):
        _check_plane(f"walls[{k}]", w)
    if s.box is not None:
        _check_box(s)


def _vector3(path: str, v: Any, what: str) -> tuple[float, float, float]:
    """Three finite numbers, or a ScenarioError naming `path` (`what`: the vector, in words)."""
    if not isinstance(v, tuple) or len(v) != 3 or not all(is_number(c) and math.isfinite(c) for c in v):
        raise ScenarioError(path, list(v) if isinstance(v, tuple) else v, f"must be three finite numbers {what}")
    return v


def _direction(path: str, v: Any, what: str) -> tuple[float, float, float]:
    """A 3D direction: three finite numbers, not all zero (any length: normalised)."""
    _vector3(path, v, what)
    if not math.hypot(*v) > 0.0:
        raise ScenarioError(path, list(v), f"must be nonzero {what} (any length > 0: normalised)")
    return v


def _check_plane(p: str, w: Any) -> None:
    """A 3D wall: a nonzero normal [nx, ny, nz] and offset, or point, or both agreeing."""
    n = w.normal
    if isinstance(n, tuple) and len(n) == 2:
        raise ScenarioError(
            f"{p}.normal", list(n), "has 2 components, a line of 2D: in 3D give [nx, ny, nz] (a plane's normal)"
        )
    _direction(f"{p}.normal", n, "[nx, ny, nz]")
    if w.offset is None and w.point is None:
        raise ScenarioError(
            f"{p}.offset", None, f"give the plane's offset [m] or a point on it, {p}.point = [x, y, z] [m]"
        )
    if w.offset is not None:
        finite(f"{p}.offset", w.offset)
    if w.point is None:
        return
    _vector3(f"{p}.point", w.point, "[x, y, z] [m] (a point on the plane)")
    if w.offset is not None:
        through = plane_offset(n, w.point)
        scale = max(abs(w.offset), math.hypot(*w.point))
        if not abs(w.offset - through) <= PLANE_RTOL * scale:
            raise ScenarioError(
                f"{p}.point",
                list(w.point),
                f"lies on the plane of offset {through:.15g} m (point . n, n the unit "
                f"normal), not {p}.offset = {w.offset!r} m; give one of the two, or "
                f"both agreeing within {PLANE_RTOL:g} relative",
            )


def _check_box(s: Scenario) -> None:
    b = s.box
    lo = _vector3("box.lower", b.lower, "[x0, y0, z0] [m]")
    hi = _vector3("box.upper", b.upper, "[x1, y1, z1] [m]")
    for k, axis in enumerate("xyz"):
        if not lo[k] < hi[k]:
            raise ScenarioError(
                "box.upper",
                list(hi),
                f"must exceed box.lower = {list(lo)} along "
                f"every axis ({axis}: {hi[k]!r} <= {lo[k]!r}); allowed: lower < upper",
            )
    material_exists("box.material", b.material, s)


def _check_materials(s: Scenario) -> None:
    if not isinstance(s.materials, dict) or not s.materials:
        raise ScenarioError("materials", s.materials, "must be a non-empty table of materials")
    for name, m in s.materials.items():
        p = f"materials.{name}"
        positive(f"{p}.E", m.E)
        if m.E > E_MAX:
            raise ScenarioError(
                f"{p}.E", m.E, f"must be in (0, {E_MAX:g}] Pa (diamond, the stiffest solid, has 1.2e12)"
            )
        finite(f"{p}.nu", m.nu, "must be in (-1, 0.5) (a finite number)")
        if not -1.0 < m.nu < 0.5:
            raise ScenarioError(f"{p}.nu", m.nu, "must be in (-1, 0.5)")
        positive(f"{p}.rho", m.rho)
        if m.Y is not None:  # the yield strength is optional (None: unknown)
            positive(f"{p}.Y", m.Y)
        _check_johnson_fields(p, m)
        if m.rho > RHO_MAX:
            raise ScenarioError(
                f"{p}.rho", m.rho, f"must be in (0, {RHO_MAX:g}] kg/m^3 (osmium, the densest solid, has 22,590)"
            )


#: Allowed ranges of the law "johnson"'s material fields (docs/model.md section 3.10):
#: C in [0, 1]; hardness_ratio in [1.5, 4] (above the cavity pressure where the law's bridge
#: ends, 1.24; measured metals 2.6-3); unloading_factor in (0, 0.5] (beyond, the residual overlap of a contact just past yield
#: would fall below zero).
RATE_COEFFICIENT_MAX = 1.0
HARDNESS_RATIO_RANGE = (1.5, 4.0)
UNLOADING_FACTOR_MAX = 0.5


def _check_johnson_fields(p: str, m: Material) -> None:
    """A material's optional fields of the law "johnson": C and rate_ref both or neither."""
    if m.C is not None:
        finite(f"{p}.C", m.C)
        if not 0.0 <= m.C <= RATE_COEFFICIENT_MAX:
            raise ScenarioError(
                f"{p}.C",
                m.C,
                f"must be in [0, {RATE_COEFFICIENT_MAX:g}] (the yield "
                "strength's rate coefficient, Y(rate) = Y [1 + C ln(rate / rate_ref)])",
            )
        if m.rate_ref is None:
            raise ScenarioError(
                f"{p}.rate_ref",
                None,
                f"missing: {p}.C = {m.C!r} needs the reference strain rate rate_ref [1/s] (give both or neither)",
            )
    if m.rate_ref is not None:
        positive(f"{p}.rate_ref", m.rate_ref)
        if m.C is None:
            raise ScenarioError(
                f"{p}.C",
                None,
                f"missing: {p}.rate_ref = {m.rate_ref!r} needs the rate coefficient C (give both or neither)",
            )
    if m.hardness_ratio is not None:
        lo, hi = HARDNESS_RATIO_RANGE
        finite(f"{p}.hardness_ratio", m.hardness_ratio)
        if not lo <= m.hardness_ratio <= hi:
            raise ScenarioError(
                f"{p}.hardness_ratio",
                m.hardness_ratio,
                f"must be in [{lo:g}, {hi:g}] (the fully plastic mean pressure over Y; Tabor's metals: 2.8)",
            )
    if m.unloading_factor is not None:
        finite(f"{p}.unloading_factor", m.unloading_factor)
        if not 0.0 < m.unloading_factor <= UNLOADING_FACTOR_MAX:
            raise ScenarioError(
                f"{p}.unloading_factor",
                m.unloading_factor,
                f"must be in (0, {UNLOADING_FACTOR_MAX:g}] (the elastic unloading span's factor; Hertz's 3/4 "
                "would leave a negative residual overlap just past yield)",
            )


def _check_layout(s: Scenario) -> None:
    lay = s.layout
    if lay is None:
        return
    string_in("layout.kind", lay.kind, tuple(LAYOUT_KINDS))
    if not isinstance(lay, LAYOUT_KINDS[lay.kind]):
        raise ScenarioError(
            "layout.kind",
            lay.kind,
            f"a {type(lay).__name__} must have kind one of "
            + ", ".join(repr(k) for k, c in LAYOUT_KINDS.items() if isinstance(lay, c)),
        )
    if isinstance(lay, PouredLayout):
        check_poured(s, lay)
        return
    if lay.kind == "paper":
        _check_paper_layout(s, lay)
    elif lay.kind == "chain":
        _check_chain_layout(s, lay)
    elif isinstance(lay, SpaceLattice):
        _check_space_lattice(s, lay)
    else:
        _check_lattice_layout(s, lay)
    if lay.imperfections is not None:
        _check_imperfections(
            lay.imperfections, layout_packing(dataclasses.replace(lay, imperfections=None), s.dimension).granules
        )


def layout_radius(path: str, value: Any) -> None:
    """A layout's radius [m], within LAYOUT_RADIUS_RANGE."""
    lo, hi = LAYOUT_RADIUS_RANGE
    positive(path, value)
    if not lo <= float(value) <= hi:
        raise ScenarioError(path, value, f"allowed: {lo:g} m <= radius <= {hi:g} m")


def layout_ratio(path: str, value: Any, power: int = 1) -> None:
    """A layout's size ratio whose power-th power scales a radius (a chain's taper: count - 1)
    within 1 / LENGTH_RANGE .. LENGTH_RANGE, so that the radii it makes stay within the length
    range every coordinate is checked against."""
    positive(path, value)
    if not power * abs(math.log(float(value))) <= math.log(LENGTH_RANGE):
        what = "value" if power == 1 else f"value^{power} (the last radius over the first)"
        raise ScenarioError(
            path, value, f"allowed: {what} within {1.0 / LENGTH_RANGE:g} .. {LENGTH_RANGE:g} (a ratio of radii)"
        )


def _check_paper_layout(s: Scenario, lay: Layout) -> None:
    layout_radius("layout.R1", lay.R1)
    r = finite("layout.R2_ratio", lay.R2_ratio, f"must be in [{SQRT2_MINUS_1:.8f}, 1] (sqrt(2)-1 <= R2/R1 <= 1)")
    if not (SQRT2_MINUS_1 - RATIO_TOL <= r <= 1.0 + RATIO_TOL):
        raise ScenarioError(
            "layout.R2_ratio", lay.R2_ratio, f"must be in [{SQRT2_MINUS_1:.8f}, 1] (sqrt(2)-1 <= R2/R1 <= 1)"
        )
    for f in ("heavy_material", "intruder_material", "wall_material"):
        material_exists(f"layout.{f}", getattr(lay, f), s)


def _list_of_columns(path: str, values: Any, columns: int) -> None:
    if not isinstance(values, tuple) or (values and len(values) != columns):
        raise ScenarioError(
            path, values, f"must be empty or a list of {columns} values (one per column, layout.columns)"
        )


def _check_lattice_layout(s: Scenario, lay: LatticeLayout) -> None:
    int_at_least("layout.columns", lay.columns, 1)
    int_at_least("layout.rows", lay.rows, 2 if lay.kind == "hexagonal" and lay.columns > 1 else 1)
    layout_radius("layout.radius", lay.radius)
    for f in ("material", "wall_material"):
        material_exists(f"layout.{f}", getattr(lay, f), s)
    if lay.intruder_material is not None:
        material_exists("layout.intruder_material", lay.intruder_material, s)
    _list_of_columns("layout.column_radii", lay.column_radii, lay.columns)
    for c, r in enumerate(lay.column_radii):
        layout_radius(f"layout.column_radii[{c}]", r)
    _list_of_columns("layout.column_materials", lay.column_materials, lay.columns)
    for c, m in enumerate(lay.column_materials):
        material_exists(f"layout.column_materials[{c}]", m, s)
    layout_ratio("layout.intruder_ratio", lay.intruder_ratio)
    if isinstance(lay.intruder_columns, str):
        string_in("layout.intruder_columns", lay.intruder_columns, tuple(INTRUDER_COLUMN_RULES))
    for k, c in enumerate(() if isinstance(lay.intruder_columns, str) else lay.intruder_columns):
        if not isinstance(c, numbers.Integral) or isinstance(c, bool) or not 1 <= c <= lay.columns:
            raise ScenarioError(
                f"layout.intruder_columns[{k}]", c, f"must be a column number in 1..{lay.columns} (layout.columns)"
            )
    int_at_least("layout.intruder_every", lay.intruder_every, 0)
    sites = [g.label for g in lattice_sites(dataclasses.replace(lay, intruder_columns=()))]
    check_intruder_sites(
        lay, sites, f"c1r1..c{lay.columns}r{lay.rows} (column, row from the top; even hexagonal columns have rows - 1)"
    )
    _check_column_offsets(lay)


def check_intruder_sites(lay, sites: list[str], names: str) -> None:
    """A lattice's intruder_sites are among its `sites` (labels; `names` describes them),
    and a single-site intruder is no larger than its site."""
    known = set(sites)
    for k, lab in enumerate(lay.intruder_sites):
        if lab not in known:
            raise ScenarioError(f"layout.intruder_sites[{k}]", lab, f"no such site; sites are {names}")
    if (lay.intruder_sites or lay.intruder_every) and lay.intruder_ratio > 1.0:
        raise ScenarioError(
            "layout.intruder_ratio",
            lay.intruder_ratio,
            "must be in (0, 1] with intruder_sites or intruder_every "
            "(a single-site intruder larger than its site overlaps its neighbours)",
        )


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
            raise ScenarioError(
                what,
                value,
                f"columns {c + 1} and {c + 2} cannot touch: R_{c + 1} + R_{c + 2} = "
                f"{radii[c] + radii[c + 1]:.6g} m < the largest radius {a:.6g} m; "
                "allowed: R_c + R_c+1 >= max R (hexagonal packing)",
            )
    for c in range(len(radii) - 2):
        gap = d[c] + d[c + 1] - radii[c] - radii[c + 2]
        if gap < -OVERLAP_RTOL * min(radii[c], radii[c + 2]):
            raise ScenarioError(
                what,
                value,
                f"columns {c + 1} and {c + 3} overlap by {-gap:.6g} m (column "
                f"{c + 2} too small to hold them apart); allowed: "
                "d_c + d_c+1 >= R_c + R_c+2 with d_c = sqrt((R_c + R_c+1)^2 - a^2), "
                "e.g. R_c+1 >= (sqrt(2) - 1) R_c for equal outer columns",
            )


def _check_space_lattice(s: Scenario, lay: SpaceLattice) -> None:
    """A space lattice's fields, then its planes: neighbours reach each other, nothing else overlaps."""
    cells = lay.cells
    if not isinstance(cells, tuple) or len(cells) != 3:
        raise ScenarioError(
            "layout.cells",
            cells,
            "must be three integers [nx, ny, nz] >= 1 (cells along x, the load direction, y and z)",
        )
    _check_planes(lay)
    for k, n in enumerate(cells):
        if k == 0 and n == 0 and (lay.layers or lay.planes is not None):
            continue  # the layers' counts or layout.planes give the planes along x
        int_at_least(f"layout.cells[{k}]", n, 1)
    layers_ok = isinstance(lay.layers, tuple) and all(isinstance(ly, Layer) for ly in lay.layers)
    if layers_ok:
        _check_layer_sizes(lay)
    n_planes = planes_along_x(lay) if layers_ok else planes_per_cell(lay.kind) * cells[0]
    n_sites = sites_per_cell(lay.kind) * n_planes * cells[1] * cells[2] // planes_per_cell(lay.kind)
    if n_sites > MAX_LAYOUT_SITES:
        raise ScenarioError(
            "layout.cells",
            list(cells),
            f"makes {n_sites} sites ({sites_per_cell(lay.kind)} "
            f"per {lay.kind} cell); allowed: at most {MAX_LAYOUT_SITES} sites",
        )
    layout_radius("layout.radius", lay.radius)
    for f in ("material", "wall_material"):
        material_exists(f"layout.{f}", getattr(lay, f), s)
    if lay.intruder_material is not None:
        material_exists("layout.intruder_material", lay.intruder_material, s)
    _check_layers(s, lay)
    if not isinstance(lay.walls, tuple):
        raise ScenarioError(
            "layout.walls",
            lay.walls,
            "must be a list of wall names, a subset of " + ", ".join(repr(w) for w in BOX_WALLS),
        )
    for k, w in enumerate(lay.walls):
        string_in(f"layout.walls[{k}]", w, BOX_WALLS)
        if w in lay.walls[:k]:
            raise ScenarioError(f"layout.walls[{k}]", w, "each wall at most once")
    layout_ratio("layout.intruder_ratio", lay.intruder_ratio)
    int_at_least("layout.intruder_every", lay.intruder_every, 0)
    _check_space_planes(lay)
    sites = [g.label for g in space_sites(lay)]
    check_intruder_sites(
        lay,
        sites,
        f"{sites[0]}..{sites[-1]} (x{{plane}}y{{row}}z{{site}}: plane along x, row along y, site along z, from 1)",
    )


def _check_planes(lay: SpaceLattice) -> None:
    """layout.planes: an integer >= 1, instead of cells[0] and of the layers' sizes."""
    if lay.planes is None:
        return
    int_at_least("layout.planes", lay.planes, 1)
    if lay.layers:
        raise ScenarioError(
            "layout.planes",
            lay.planes,
            "give layout.planes or layout.layers, not both (with layers, each layer's count or planes sizes it)",
        )
    if isinstance(lay.cells, tuple) and lay.cells and lay.cells[0] != 0:
        raise ScenarioError(
            "layout.planes",
            lay.planes,
            f"give layout.planes (lattice planes along x) or "
            f"layout.cells[0] = {lay.cells[0]} (cells along x), not both: with planes write "
            f"cells = [0, ny, nz]",
        )


def _check_layer_sizes(lay: SpaceLattice) -> None:
    """Each layer's size: count (cells) >= 1 or planes >= 1, not both."""
    if not isinstance(lay.layers, tuple):
        return
    for k, ly in enumerate(lay.layers):
        p = f"layout.layers[{k}]"
        if ly.count is not None and ly.planes is not None:
            raise ScenarioError(
                f"{p}.planes",
                ly.planes,
                f"give {p}.count (cells along x, "
                f"{planes_per_cell(lay.kind)} lattice planes each for {lay.kind}) or {p}.planes "
                "(lattice planes), not both",
            )
        if ly.planes is not None:
            int_at_least(f"{p}.planes", ly.planes, 1)
        elif ly.count is not None:
            int_at_least(f"{p}.count", ly.count, 1)


def _check_layers(s: Scenario, lay: SpaceLattice) -> None:
    """Each layer: its size (`_check_layer_sizes`), radius (or None), material (or None);
    the planes add up to those of cells[0] (unless cells[0] is 0: then they give it)."""
    if not isinstance(lay.layers, tuple):
        raise ScenarioError("layout.layers", lay.layers, "must be a list of tables {count or planes, radius, material}")
    for k, ly in enumerate(lay.layers):
        p = f"layout.layers[{k}]"
        if ly.radius is not None:
            layout_radius(f"{p}.radius", ly.radius)
        if ly.material is not None:
            material_exists(f"{p}.material", ly.material, s)
    radii = [lay.radius if ly.radius is None else ly.radius for ly in lay.layers]
    for k, r in enumerate(radii):
        if not max(radii) <= LENGTH_RANGE * r:
            raise ScenarioError(
                f"layout.layers[{k}].radius",
                r,
                f"allowed: at least 1 / {LENGTH_RANGE:g} "
                f"of the largest layer radius {max(radii):.6g} m (a ratio of radii)",
            )
    n = planes_per_cell(lay.kind)
    total = planes_along_x(lay)
    if lay.layers and lay.cells[0] != 0 and total != n * lay.cells[0]:
        raise ScenarioError(
            "layout.layers",
            [ly.count if ly.planes is None else f"{ly.planes} planes" for ly in lay.layers],
            f"the layers add up to {total} lattice planes ({total / n:g} cells); allowed: they "
            f"add up to layout.cells[0] = {lay.cells[0]} (the cells along x; 0: as many as "
            f"the layers' counts add up to)",
        )


def _layer_of_plane(lay: SpaceLattice, plane: int) -> int:
    """The index in layout.layers of the layer holding plane `plane` (0-based)."""
    acc = 0
    for k, ly in enumerate(lay.layers):
        acc += layer_planes(lay.kind, ly)
        if plane < acc:
            return k
    return len(lay.layers) - 1  # pragma: no cover (the counts add up to cells[0])


def _check_space_planes(lay: SpaceLattice) -> None:
    """Neighbouring planes reach each other (R_p + R_p+1 >= rho) and planes two or more apart
    do not overlap (the layers' radii; one radius always passes)."""
    radii = [r for r, _ in plane_layers(lay)]
    if not lay.layers or len(radii) < 2:
        return
    r_max = max(radii)
    for p in range(len(radii) - 1):
        rho = plane_gap_distance(lay.kind, plane_type(lay.kind, p), plane_type(lay.kind, p + 1), r_max)
        if not radii[p] + radii[p + 1] >= rho:
            k = _layer_of_plane(lay, p if radii[p] < radii[p + 1] else p + 1)
            raise ScenarioError(
                f"layout.layers[{k}].radius",
                min(radii[p], radii[p + 1]),
                f"planes {p + 1} and {p + 2} cannot touch: R_p + R_p+1 = "
                f"{radii[p] + radii[p + 1]:.6g} m < {rho:.6g} m, the in-plane distance to "
                f"the next plane's sites on the {lay.kind} net of the largest radius "
                f"{r_max:.6g} m; allowed: R_p + R_p+1 >= that distance",
            )
    clash = plane_clash(lay.kind, radii)
    if clash is not None:
        p, q, overlap = clash
        thin = min(range(p + 1, q), key=lambda m: radii[m])
        k = _layer_of_plane(lay, thin)
        raise ScenarioError(
            f"layout.layers[{k}].radius",
            radii[thin],
            f"planes {p + 1} and {q + 1} overlap by {overlap:.6g} m: plane {thin + 1} "
            f"between them (radius {radii[thin]:.6g} m) is too small to hold them apart; "
            "allowed: a radius that keeps every pair of planes apart",
        )


def _check_chain_layout(s: Scenario, lay: ChainLayout) -> None:
    int_at_least("layout.count", lay.count, 1)
    layout_radius("layout.radius", lay.radius)
    layout_ratio("layout.taper", lay.taper, power=max(int(lay.count) - 1, 1))
    layout_ratio("layout.dimer_ratio", lay.dimer_ratio)
    nonneg("layout.decorated_ratio", lay.decorated_ratio)
    if lay.decorated_ratio > 0.0:
        layout_ratio("layout.decorated_ratio", lay.decorated_ratio)
    for f in ("material", "wall_material", "dimer_material", "decorated_material"):
        if getattr(lay, f) is not None:
            material_exists(f"layout.{f}", getattr(lay, f), s)
    for f in ("y", "z"):
        v = getattr(lay, f)
        if v is not None:
            finite(f"layout.{f}", v)
            if not abs(float(v)) <= LENGTH_RANGE * lay.radius:
                raise ScenarioError(
                    f"layout.{f}",
                    v,
                    f"allowed: |{f}| <= {LENGTH_RANGE:g} x layout.radius = {LENGTH_RANGE * lay.radius:.6g} m",
                )


def _check_imperfections(imp: Imperfections, sites: tuple[Granule, ...]) -> None:
    p = "layout.imperfections"
    int_at_least(f"{p}.seed", imp.seed, 0)
    for f in ("radius_spread", "jitter", "vacancy_fraction"):
        v = finite(f"{p}.{f}", getattr(imp, f), "must be in [0, 1) (a finite number)")
        if not 0.0 <= v < 1.0:
            raise ScenarioError(f"{p}.{f}", v, "must be in [0, 1)")
    if not imp.radius_spread + imp.jitter < 1.0:
        raise ScenarioError(
            f"{p}.jitter",
            imp.jitter,
            f"radius_spread + jitter must be < 1 (radius_spread = "
            f"{imp.radius_spread!r}: the smallest radius R (1 - jitter - "
            "radius_spread) must stay > 0)",
        )
    labels = {g.label for g in sites}
    for k, lab in enumerate(imp.vacancies):
        if lab not in labels:
            raise ScenarioError(
                f"{p}.vacancies[{k}]",
                lab,
                "no such site in the perfect packing (labels such as "
                + ", ".join(list(g.label for g in sites)[:3])
                + ", ...)",
            )


def _granule(s: Scenario, i: int, field: str | None = None) -> str:
    """How messages name granule i of `s` (or its field): `granules[i].field`, or the row
    and column of its granules_file (setup.granules_file.granule_path)."""
    return granule_path(s.granules_file, i, field, s.dimension)


def _floats(values: list) -> np.ndarray | None:
    """`values` as an array when every one is a Python float (else None: the checks then go
    granule by granule, as their messages need)."""
    if set(map(type, values)) != {float}:
        return None
    return np.array(values, float)


class _PerThread(threading.local):
    """What one thread's validation keeps (threads validate scenarios side by side):
    `columns`, the granules whose columns `_column` holds (a strong reference: identity
    is the key) and the columns by field, emptied when `validate` returns; `passed`, the
    scenario that passed last (a weak reference) and its materials then."""

    def __init__(self):
        self.columns: list = [None, {}]
        self.passed: list = []


_THREAD = _PerThread()


def _column(gs: tuple[Granule, ...], field: str) -> np.ndarray | None:
    """The granules' `field` as `_floats` gives it, extracted once per validation."""
    if _THREAD.columns[0] is not gs:
        _THREAD.columns[:] = [gs, {}]
    cols = _THREAD.columns[1]
    if field not in cols:
        cols[field] = _floats(list(map(operator.attrgetter(field), gs)))
    return cols[field]


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


def bar_wave_speed(m: Material) -> float:
    """c = sqrt(E / rho) [m/s]: the speed of elastic waves along a bar of material m."""
    return math.sqrt(m.E / m.rho)


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


def length_scale(s: Scenario) -> tuple[float, str]:
    """(h [m], the field it comes from): the smallest length of a resolved scenario, a
    granule radius or a plate element edge (width / nx, height / ny; a box solid's
    size / elements along each axis); its radii and plate sizes already checked to be
    positive numbers."""
    key = ("length_scale", id(s))  # once per validation of the resolved scenario
    if _THREAD.columns[0] is s.granules and key in _THREAD.columns[1]:
        return _THREAD.columns[1][key]
    found = _smallest_radius(s)
    if isinstance(s.plate, Solid) and is_box(s.plate):
        found += [(s.plate.size[k] / s.plate.elements[k], f"plate.size[{k}] / plate.elements[{k}]") for k in range(3)]
    elif isinstance(s.plate, Plate):
        found += [
            (s.plate.width / s.plate.nx, "plate.width / plate.nx"),
            (s.plate.height / s.plate.ny, "plate.height / plate.ny"),
        ]
    if not found:  # a solid of a mesh file alone: no length known before the file is read
        return math.inf, "no granule"
    if _THREAD.columns[0] is s.granules:
        _THREAD.columns[1][key] = min(found)
    return min(found)


def _smallest_radius(s: Scenario) -> list[tuple[float, str]]:
    """[(R, path)]: the granule radius that `length_scale`'s min picks, with the path
    that breaks its ties (the smallest string), or every (radius, path) pair when one is
    not a Python float."""
    r = _column(s.granules, "radius") if s.granules else None
    if r is None or not np.isfinite(r).all():
        return [(g.radius, _granule(s, i, "radius")) for i, g in enumerate(s.granules)]
    r_min = float(r.min())
    ties = np.flatnonzero(r == r_min).tolist()
    if len(ties) > 1:  # the path that sorts first: its number is all that differs (and what follows it)
        # (granule_path: `granules[i].radius`, or `FILE, row i+1, column radius`)
        after, shift = ("]", 0) if s.granules_file is None else (",", 1)
        ties = [int(min([f"{i + shift}{after}" for i in ties])[:-1]) - shift]
    return [(r_min, _granule(s, ties[0], "radius"))]


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


def _check_walls(s: Scenario) -> None:
    seen: dict[str, int] = {}
    for k, w in enumerate(s.walls):
        p = f"walls[{k}]"
        n = w.normal
        if s.dimension == 3:
            _check_plane(p, w)
        elif not isinstance(n, tuple) or len(n) != 2 or not all(is_number(c) and math.isfinite(c) for c in n):
            raise ScenarioError(f"{p}.normal", n, "must be two finite numbers [nx, ny]")
        elif abs(math.hypot(n[0], n[1]) - 1.0) > NORMAL_TOL:
            norm = math.hypot(n[0], n[1])
            raise ScenarioError(
                f"{p}.normal", n, f"must be a unit vector (|normal| = {norm:.12g}; allowed 1 within {NORMAL_TOL:g})"
            )
        finite(f"{p}.offset", w.offset)
        material_exists(f"{p}.material", w.material, s)
        if not isinstance(w.label, str):
            raise ScenarioError(f"{p}.label", w.label, "must be a string")
        if w.label in seen:
            raise ScenarioError(f"{p}.label", w.label, f"labels must be unique; walls[{seen[w.label]}] has it too")
        seen[w.label] = k


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


def _check_plate(s: Scenario) -> None:
    pl = s.plate
    if not isinstance(pl, Plate):  # none, or a 3D solid (checked as written: _check_spatial)
        return
    check_plate_fields(pl, pl.x0)
    material_exists("plate.material", pl.material, s)


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


def _check_solid_penetration(s: Scenario, named: dict[int, str]) -> None:
    """No granule crosses the 3D solid's surface at t = 0, none has its centre inside it
    (setup.solid_checks.check_solid_clearance, tolerance OVERLAP_RTOL x the radius, as
    the plate's edge and the walls). A box in closed form; a mesh file's surface is
    checked where the file is read (solid.clearance), not here."""
    if isinstance(s.plate, Solid) and is_box(s.plate):
        check_solid_clearance(s, box_distances(s), named, OVERLAP_RTOL)


def _check_walls_off_solid(s: Scenario, r: Scenario) -> None:
    """No rigid wall of the resolved `r` passes through the 3D box solid, and none lies on the
    face a granule meets at t = 0 (it touches both at one point): the wall would take the
    load the solid should (the wall named as `s` places it: layout.walls, box or walls[k]).
    A wall along a face no granule meets (the paper's bottom wall along a clamped edge) is
    allowed."""
    if not (isinstance(r.plate, Solid) and is_box(r.plate)):
        return
    lo, hi = box_corners(r.plate)
    n_user = len(s.walls)
    for k, w in enumerate(r.walls):
        n = unit(w.normal)
        tol = OVERLAP_RTOL * min((g.radius for g in r.granules), default=min(r.plate.size))
        offset = w.offset  # along the unit normal, as _check_wall_penetration reads it
        if not (
            wall_cuts_box(n, offset, lo, hi, tol)
            or any(
                wall_contact_on_box(n, offset, (g.x, g.y, g.z), g.radius, lo, hi, r.contact.neighbour_gap * g.radius)
                for g in r.granules
            )
        ):
            continue
        if s.layout is not None:
            path, value, fix = (
                "layout.walls",
                w.label,
                (f"leave {w.label!r} out of layout.walls (e.g. walls = {[b for b in BOX_WALLS if b != w.label]})"),
            )
        elif k >= n_user:
            path, value, fix = "box", w.label, "move the box's face or the solid (plate.origin)"
        else:
            path, value, fix = f"walls[{k}]", w.label, "move or remove the wall, or move the solid (plate.origin)"
        raise ScenarioError(
            path,
            value,
            f"the rigid wall {w.label or k} (n = {list(w.normal)}, offset "
            f"{w.offset:.6g} m) passes through {solid_named(r.plate)} or lies on the face its "
            f"granules meet: a granule touching the solid there touches the wall too, which "
            f"would take the load the solid should; {fix}",
        )


def _check_load(s: Scenario) -> None:
    ld = s.load
    string_in("load.kind", ld.kind, LOAD_KINDS_BY_DIMENSION[s.dimension])
    string_in("load.target", ld.target, LOAD_TARGETS)
    q0 = finite("load.q0", ld.q0, "must be >= 0 (a finite number) [N/m]")
    if not q0 >= 0.0:
        raise ScenarioError("load.q0", ld.q0, "must be >= 0 [N/m]")
    e_max, h = _stiffest_modulus(s), length_scale(s)[0]
    if ld.kind == "line" and not q0 <= e_max * h:
        raise ScenarioError(
            "load.q0",
            ld.q0,
            f"allowed: 0 <= q0 <= E h = {e_max * h:.6g} N/m, E = {e_max:.6g} Pa the "
            f"largest Young's modulus of the granules and plate, h = {h:.6g} m the "
            "smallest length (a granule radius or plate element edge): a larger "
            "line load presses on h harder than E, far beyond Hertz's small "
            "overlaps and linear elasticity",
        )
    positive("load.duration", ld.duration)
    positive("load.length", ld.length)
    finite("load.y0", ld.y0)
    force = finite("load.force", ld.force, "must be >= 0 (a finite number) [N]")
    if not force >= 0.0:
        raise ScenarioError("load.force", ld.force, "must be >= 0 [N]")
    if ld.kind == "force":
        if not force <= e_max * h * h:
            raise ScenarioError(
                "load.force",
                ld.force,
                f"allowed: 0 <= force <= E h^2 = {e_max * h * h:.6g} N, E = {e_max:.6g} Pa "
                f"the largest Young's modulus of the granules, h = {h:.6g} m the "
                "smallest radius: a larger force presses on h^2 harder than E, far "
                "beyond Hertz's small overlaps",
            )
        _direction("load.direction", ld.direction, "[dx, dy, dz]")
        if ld.target != "granules":
            raise ScenarioError("load.target", ld.target, 'a force load acts on granules: use target = "granules"')
    if not isinstance(ld.granules, tuple) or not all(isinstance(x, str) for x in ld.granules):
        raise ScenarioError("load.granules", ld.granules, "must be a list of granule labels")
    labels = {g.label for g in s.granules}
    for i, lab in enumerate(ld.granules):
        if lab not in labels:
            raise ScenarioError(
                f"load.granules[{i}]",
                lab,
                "no granule has this label; labels are: " + ", ".join(g.label for g in s.granules),
            )
    if ld.kind == "force" and not s.granules:
        raise ScenarioError("load.kind", ld.kind, 'a force load needs [[granules]]; use kind = "none"')
    if ld.kind == "line":
        if ld.target == "plate" and s.plate is None:
            raise ScenarioError(
                "load.target",
                ld.target,
                'a load on the plate needs a [plate]; use target = "granules" or kind = "none"',
            )
        if ld.target == "granules" and not s.granules:
            raise ScenarioError(
                "load.target",
                ld.target,
                'a load on the granules needs granules (or a [layout]); use target = "plate" or kind = "none"',
            )


def _stiffest_modulus(s: Scenario) -> float:
    """The largest Young's modulus [Pa] of the granules' and the plate's materials."""
    names = {g.material for g in s.granules} | ({s.plate.material} if s.plate is not None else set())
    return max(s.material(n).E for n in names)


#: Largest Coulomb coefficient (real dry pairs stay below about 2, rubber on glass).
MU_MAX = 10.0
#: Largest tanh smoothing k_s [s/m]: a smoothing slip rate 1/k_s of at least 1 um/s (the
#: paper's is 1 mm/s); a sharper law is a step in the slip rate that no time step resolves.
KS_MAX = 1e6


#: Largest damping coefficient alpha_n of eq. (3): near 2 a contact is already critically
#: damped (restitution about 0); more only stiffens the time integration.
ALPHA_N_MAX = 10.0


def _damping(path: str, alpha_n: Any) -> None:
    """alpha_n in [0, ALPHA_N_MAX] (None: not given)."""
    if alpha_n is None:
        return
    nonneg(path, alpha_n)
    if alpha_n > ALPHA_N_MAX:
        raise ScenarioError(
            path,
            alpha_n,
            f"must be in [0, {ALPHA_N_MAX:g}] (eq. 3's damping "
            "coefficient; near 2 a contact is already critically damped)",
        )


def _friction(path: str, mu: Any, k_s: Any) -> None:
    """mu in [0, MU_MAX] and k_s in (0, KS_MAX] (either None: not given)."""
    if mu is not None:
        nonneg(f"{path}.mu", mu)
        if mu > MU_MAX:
            raise ScenarioError(
                f"{path}.mu",
                mu,
                f"must be in [0, {MU_MAX:g}] (a Coulomb coefficient; real dry pairs stay below about 2)",
            )
    if k_s is not None:
        positive(f"{path}.k_s", k_s)
        if k_s > KS_MAX:
            raise ScenarioError(
                f"{path}.k_s",
                k_s,
                f"must be in (0, {KS_MAX:g}] s/m (a smoothing "
                "slip rate 1/k_s of at least 1 um/s; sharper, friction is a step no "
                "time step resolves)",
            )


def _check_contact(s: Scenario) -> None:
    c = s.contact
    _friction("contact", c.mu, c.k_s)
    _damping("contact.alpha_n", c.alpha_n)
    nonneg("contact.neighbour_gap", c.neighbour_gap)
    if c.neighbour_gap > 1.0:
        raise ScenarioError(
            "contact.neighbour_gap",
            c.neighbour_gap,
            "must be at most 1 (a gap of at most the smaller radius, as contact.skin)",
        )
    string_in("contact.torque_arm", c.torque_arm, TORQUE_ARMS)
    string_in("contact.detection", c.detection, DETECTIONS)
    string_in("contact.normal_law", c.normal_law, NORMAL_LAWS)
    positive("contact.skin", c.skin)
    if c.skin > 1.0:
        raise ScenarioError("contact.skin", c.skin, "must be at most 1 (a fraction of R_i + R_j)")
    positive("contact.overlap_warn", c.overlap_warn)
    if not c.overlap_warn < 1.0:
        raise ScenarioError(
            "contact.overlap_warn", c.overlap_warn, "must be in (0, 1) (a fraction of the smaller radius)"
        )
    positive("contact.overlap_stop", c.overlap_stop)
    if not c.overlap_warn <= c.overlap_stop < 1.0:
        raise ScenarioError(
            "contact.overlap_stop", c.overlap_stop, f"must lie in [contact.overlap_warn = {c.overlap_warn:g}, 1)"
        )
    if not isinstance(c.clip_tensile, bool):
        raise ScenarioError("contact.clip_tensile", c.clip_tensile, "must be true or false")
    for i, pc in enumerate(c.pairs):
        p = f"contact.pairs[{i}]"
        mats = pc.materials
        if not isinstance(mats, tuple) or len(mats) != 2:
            raise ScenarioError(f"{p}.materials", mats, "must be two material names")
        for k, m in enumerate(mats):
            material_exists(f"{p}.materials[{k}]", m, s)
        _damping(f"{p}.alpha_n", pc.alpha_n)
        _friction(p, pc.mu, pc.k_s)
        if pc.normal_law is not None:
            string_in(f"{p}.normal_law", pc.normal_law, NORMAL_LAWS)
    _check_yield_strengths(s)


def possible_contacts(s: Scenario) -> list[tuple[str, str, str]]:
    """(kind, a, b) for every pair of materials that can touch in the resolved scenario `s`:
    "granule-granule" for two materials of its granules (a with itself when two granules
    share it), "granule-wall" for a granule's material a and a wall's material b,
    "granule-plate" for a and the plate's material b; materials in the order the granules
    and walls first name them."""
    count = Counter(g.material for g in s.granules)
    mats = list(count)
    found = []
    for i, a in enumerate(mats):
        if count[a] > 1:
            found.append(("granule-granule", a, a))
        found += [("granule-granule", a, b) for b in mats[i + 1 :]]
    found += [("granule-wall", a, b) for a in mats for b in dict.fromkeys(w.material for w in s.walls)]
    if s.plate is not None:
        found += [("granule-plate", a, s.plate.material) for a in mats]
    return found


def _check_yield_strengths(s: Scenario) -> None:
    """A yielding normal law (YIELDING_LAWS) at a contact that can occur has the yield
    strength of each body there that can yield: both granules' materials, or the granule's
    alone against a wall or the plate (rigid bodies to the law, which never yield)."""
    c = s.contact
    for kind, a, b in possible_contacts(s):
        law = c.law_for_pair(a, b)
        if law not in YIELDING_LAWS:
            continue
        for m in dict.fromkeys((a, b) if kind == "granule-granule" else (a,)):
            if s.material(m).Y is None:
                k = c.law_index(a, b)
                path = "contact.normal_law" if k is None else f"contact.pairs[{k}].normal_law"
                raise ScenarioError(
                    path,
                    law,
                    f"needs the yield strength of material '{m}' ({kind} contacts {a}-{b}): set materials.{m}.Y [Pa]",
                )


def _check_time(s: Scenario) -> None:
    t = s.time
    for f in ("t_end", "dt_initial", "dt_max", "dt_min", "output_interval", "field_interval"):
        positive(f"time.{f}", getattr(t, f))
    if t.dt_min > t.dt_initial:
        raise ScenarioError(
            "time.dt_min", t.dt_min, f"must be <= time.dt_initial = {t.dt_initial!r} (dt_min <= dt_initial <= dt_max)"
        )
    if t.dt_initial > t.dt_max:
        raise ScenarioError(
            "time.dt_initial", t.dt_initial, f"must be <= time.dt_max = {t.dt_max!r} (dt_min <= dt_initial <= dt_max)"
        )
    if t.output_interval > t.t_end:
        raise ScenarioError("time.output_interval", t.output_interval, f"must be <= time.t_end = {t.t_end!r}")
    r = t.field_interval / t.output_interval
    n = round(r)
    if n < 1 or abs(r - n) > INTERVAL_RTOL * r or n > 2**53:
        raise ScenarioError(
            "time.field_interval",
            t.field_interval,
            f"must be a whole multiple n of time.output_interval = "
            f"{t.output_interval!r}, 1 <= n <= 2^53 (beyond, every double is whole)",
        )


#: Bytes kept per output time, per granule (its state in the buffers, the Dataset and
#: the file written: 3 copies of 6 numbers and a few per contact) and per plate dof (the
#: modal coordinates and their rates, 3 copies), and per plate snapshot and plate dof
#: (displacements, strains and stresses at the nodes, 3 copies).
OUTPUT_BYTES_PER_GRANULE = 3 * 8 * 12
OUTPUT_BYTES_PER_DOF = 3 * 8 * 2
FIELD_BYTES_PER_DOF = 3 * 8 * 4


def output_bytes_per_second(s: Scenario) -> float:
    """About the memory [bytes] a run's outputs take per second of simulated time: a row
    of the granules' states and the plate's modal coordinates per output_interval, a plate
    snapshot per field_interval (s resolved)."""
    t = s.time
    n_dof = 0  # a 3D solid writes no fields yet (its coupling comes with its outputs)
    if isinstance(s.plate, Plate):
        p = s.plate
        n_dof = 2 * ((p.nx + 1) * (p.ny + 1) + p.nx * (p.ny + 1) + p.ny * (p.nx + 1))
    row = OUTPUT_BYTES_PER_GRANULE * len(s.granules) + OUTPUT_BYTES_PER_DOF * n_dof + 400.0
    return row / t.output_interval + FIELD_BYTES_PER_DOF * n_dof / t.field_interval


def _check_output_size(s: Scenario) -> None:
    """The outputs of t_end fit in MEMORY_SHARE of the machine's memory."""
    memory = MEMORY_SHARE * physical_memory()
    t_max = memory / output_bytes_per_second(s)
    t = s.time
    if memory > 0.0 and not t.t_end <= t_max:
        raise ScenarioError(
            "time.t_end",
            t.t_end,
            f"allowed: t_end <= {t_max:.3g} s with these output intervals: the outputs would need "
            f"about {t.t_end / t_max * (memory / 1e9):.3g} GB ({t.t_end / t.output_interval:.3g} "
            f"output times, time.output_interval = {t.output_interval!r} s; "
            f"{t.t_end / t.field_interval:.3g} plate snapshots, time.field_interval = "
            f"{t.field_interval!r} s), this machine allows {memory / 1e9:.3g} GB",
        )


def _check_solver(s: Scenario) -> None:
    sv = s.solver
    string_in("solver.scheme", sv.scheme, SCHEMES)
    string_in("solver.granular_friction", sv.granular_friction, GRANULAR_FRICTIONS)
    if sv.scheme in GRANULAR_SCHEMES:
        _check_granular_scheme(s)
    elif isinstance(s.plate, Solid):
        raise ScenarioError(
            "solver.scheme",
            sv.scheme,
            "an elastic solid in 3D is coupled to the granules by "
            "velocity Verlet with its modes turned exactly (docs/model.md section 3.9): set "
            'solver.scheme = "verlet" and solver.granular_friction = "split"',
        )
    lam = finite("solver.lambda_target", sv.lambda_target, "must be in (0, 1)")
    if not 0.0 < lam < 1.0:
        raise ScenarioError("solver.lambda_target", sv.lambda_target, "must be in (0, 1)")
    positive("solver.iteration_rtol", sv.iteration_rtol)
    positive("solver.iteration_atol", sv.iteration_atol)
    int_at_least("solver.max_iterations", sv.max_iterations, 1)
    positive("solver.energy_tol", sv.energy_tol)
    positive("solver.error_tol", sv.error_tol)
    positive("solver.implicit_dt_max", sv.implicit_dt_max)


def _check_granular_scheme(s: Scenario) -> None:
    """A scheme of the granules alone (GRANULAR_SCHEMES): no plate (an elastic solid in
    space is its own: docs/model.md section 3.9), friction split off."""
    sv = s.solver
    if s.plate is not None and not isinstance(s.plate, Solid):
        raise ScenarioError(
            "solver.scheme",
            sv.scheme,
            'integrates the granules alone (velocity Verlet): a scenario with a [plate] needs "implicit" or "paper"',
        )
    if sv.granular_friction != "split":
        raise ScenarioError(
            "solver.granular_friction",
            sv.granular_friction,
            'must be "split" with solver.scheme '
            f"= {sv.scheme!r} (its friction is split off exactly, never inside the step)",
        )


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

    Order: dimension, materials, the fields of the other dimension (2D: no z, vz, vector
    omega, 3-component normal, point, box, solid or force load; 3D: no line load, the [plate] a
    solid and its fields, a 3D layout kind, vector omegas, walls as planes, the box), layout (as `layout.*`, before it is
    expanded), then on the resolved
    scenario: granules (values, speeds, unique labels), walls (unit normals), plate, the
    range of every coordinate and size (`LENGTH_RANGE`), overlaps and penetrations at
    t = 0 (walls, the plate's edge, a box solid's surface), load, contact (and the yield strengths its normal laws need), plate mesh (rigid
    layers of the contacts on nodes, patch contacts between nodes, n_modes), time, the
    outputs' memory, solver, gravity and drives. A scenario with neither granules (nor a layout) nor a plate
    is refused.
    """
    if _passed_before(scenario):
        return
    try:
        _validate(scenario)
    finally:
        _THREAD.columns[:] = [None, {}]
    _THREAD.passed[:] = [weakref.ref(scenario), dict(scenario.materials)]


def _validate(scenario: Scenario) -> None:
    """`validate`'s checks, in its order."""
    s = scenario
    if not isinstance(s.name, str):
        raise ScenarioError("name", s.name, "must be a string")
    if not isinstance(s.description, str):
        raise ScenarioError("description", s.description, "must be a string")
    _check_dimension(s)
    _check_materials(s)
    if s.dimension == 2:
        _check_planar(s)
    else:
        _check_spatial(s)
    _check_layout(s)
    if s.layout is None and not s.granules and s.plate is None:
        raise ScenarioError(
            "granules", (), "a scenario needs granules (or a [layout]) or a [plate], or both; it has neither"
        )
    if isinstance(s.plate, Plate) and s.plate.x0 is not None:
        finite("plate.x0", s.plate.x0)
    r = resolve(s)
    _check_granules(r)
    _check_walls(r)
    _check_plate(r)
    _check_lengths(r, boxed=s.dimension == 3 and s.box is not None)
    named = _GranuleNames(s, r)
    _check_overlaps(r, named)
    _check_wall_penetration(r, named)
    _check_plate_penetration(r, named)
    _check_solid_penetration(r, named)
    _check_walls_off_solid(s, r)
    _check_load(r)
    _check_contact(r)
    if isinstance(r.plate, Plate):
        check_plate_mesh(r, named)
    _check_time(r)
    _check_output_size(r)
    _check_solver(r)
    _check_drives(r)


def _check_drives(s: Scenario) -> None:
    """[gravity] and [[drives]] (setup.drive_checks): a harmonic drive's period held to
    the scheme's largest step, the speeds a drive asks for below the slowest wave speed."""
    check_gravity(s)
    if not s.drives:
        return
    if not isinstance(s.drives, tuple):
        raise ScenarioError("drives", s.drives, "must be a list of [[drives]] tables")
    step = s.solver.implicit_dt_max if s.solver.scheme == "implicit" else s.time.dt_max
    used = {g.material for g in s.granules} | {w.material for w in s.walls}
    speed = min((bar_wave_speed(s.material(m)) for m in used if m in s.materials), default=math.inf)
    check_drives(s, float(step), speed)


def _passed_before(scenario: Scenario) -> bool:
    """Whether `scenario` is the very object that passed last, with the same materials (a
    frozen scenario cannot change otherwise): a run validates it once, not on loading and
    again on building its model."""
    return (
        bool(_THREAD.passed)
        and _THREAD.passed[0]() is scenario
        and isinstance(scenario.materials, dict)
        and scenario.materials == _THREAD.passed[1]
    )


def validated(scenario: Scenario) -> Scenario:
    """`validate(scenario)`, then return `scenario` unchanged (for chaining)."""
    validate(scenario)
    return scenario
