"""The rules of [layout]: each layout kind's fields (paper, hexagonal, square, chain; the
space lattices and their layers, planes and intruders; imperfections), checked before the
layout is expanded, named `layout.*`.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from typing import Any


from granplate.errors import ScenarioError
from granplate.setup.geometry import layout_packing
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
from granplate.setup.fields import finite, int_at_least, material_exists, nonneg, positive, string_in
from granplate.setup.pouring import check_poured
from granplate.setup.scenario import (
    BOX_WALLS,
    LAYOUT_KINDS,
    SQRT2_MINUS_1,
    ChainLayout,
    Granule,
    Imperfections,
    LatticeLayout,
    Layer,
    Layout,
    PouredLayout,
    Scenario,
    SpaceLattice,
)
from granplate.setup.check_base import LENGTH_RANGE, OVERLAP_RTOL


#: Tolerance on the R2/R1 bounds.
RATIO_TOL = 1e-12
#: A layout's radii [m]: from a nanometre (below it a continuum contact law means nothing) to
#: a kilometre; its size ratios (taper, dimer, decorated, intruder) within 1 / LENGTH_RANGE
#: .. LENGTH_RANGE of the radius they scale, so that the granules it makes stay in the range
#: every coordinate is checked against (LENGTH_RANGE).
LAYOUT_RADIUS_RANGE: tuple[float, float] = (1e-9, 1e3)
#: The most sites a space lattice may have: `resolve` builds each sphere in Python (about a
#: second per 10^5), and the solver's scaling is measured up to 10^4 granules.
MAX_LAYOUT_SITES = 1_000_000


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
