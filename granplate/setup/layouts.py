"""Packings generated from a layout: hexagonal and square lattices, space lattices (sc, bcc,
fcc, hcp), chains, imperfections.

Each kind is built in small steps, one concept each: the column radii and materials, the
column x positions (offsets that make neighbours touch), the sites, the intruders, the
walls and the plate position; `imperfect` then applies seeded imperfections to any
packing. `geometry.layout_packing` chooses the kind (the paper's packing lives there).

Lattice geometry (origin at the bottom-left corner of the granular domain, x to the right):

    a    = max_c R_c                         half the vertical pitch
    hexagonal: d_c = sqrt((R_c + R_c+1)^2 - a^2),   square: d_c = R_c + R_c+1
    x_1  = R_1,  x_c+1 = R_1 + (d_1 + ... + d_c)
    row k = 1..rows (from the top) of an odd column (every column of a square packing):
        y = (2 (rows - k) + 1) a;  of an even hexagonal column (rows - 1 granules):
        y = 2 (rows - k) a
    then shifted so that min(x - R) = min(y - R) = 0 (no shift when column 1 holds the
    largest radius); walls x = 0 (left), y = 0 (bottom), y = max(y + R) (top); plate left
    edge x = max(x + R).

Space lattices (`SpaceLattice`, 3D): lattice planes normal to x (the load direction), each
a net in (y, z) of the rectangular in-plane cell (Ly, Lz) = PLANE_CELL[kind] x R (R the
largest radius) with the sites PLANE_SITES[kind][t] (fractions of the cell) on planes of
type t = p mod (planes per cell):

    sc:  Ly = Lz = 2R,             one plane per cell, sites (0, 0)
    bcc: Ly = Lz = 4R / sqrt(3),   planes (0, 0) | (1/2, 1/2)
    fcc: Ly = Lz = 2 sqrt(2) R,    planes (0, 0), (1/2, 1/2) | (1/2, 0), (0, 1/2)
    hcp: Ly = 2R, Lz = 2 sqrt(3) R, planes (0, 0), (1/2, 1/2) | (1/2, 1/6), (0, 2/3)

Planes p and p+1 of radii R_p, R_p+1 are d_p = sqrt((R_p + R_p+1)^2 - rho^2) apart in x,
rho the in-plane distance from a site to the nearest sites of the next plane (0, sqrt(8/3) R,
sqrt(2) R, 2R / sqrt(3)), so that they touch: with one radius, d = 2R (sc), 2R / sqrt(3)
(bcc: half the cube edge), sqrt(2) R (fcc: half the cube edge), 2 sqrt(2/3) R (hcp: c / 2).
x_1 = R_1; the packing is then shifted so that its lowest surfaces are at x = y = z = 0,
and the walls touch its outermost surfaces.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np

from granplate.setup.scenario import (
    BOX_WALLS,
    ChainLayout,
    Granule,
    Imperfections,
    LatticeLayout,
    Layer,
    SpaceLattice,
    Wall,
)


class Packing(NamedTuple):
    """A generated packing: granules, walls, the plate's left edge x [m] (touching the
    rightmost granule surface) and the labels of column 1 (the loaded side)."""

    granules: tuple[Granule, ...]
    walls: tuple[Wall, ...]
    plate_x: float
    column1: tuple[str, ...]


def site_label(column: int, row: int) -> str:
    """Label of the lattice site in column `column`, row `row` (both 1-based)."""
    return f"c{column}r{row}"


# --------------------------------------------------------------------------- lattices

#: intruder_columns given by a rule: the first intruder column and the step between them.
INTRUDER_COLUMN_RULES: dict[str, int] = {"odd": 1, "even": 2}


def intruder_column_numbers(lay: LatticeLayout) -> tuple[int, ...]:
    """The intruder columns (1-based): intruder_columns as given, or every even / odd one."""
    if isinstance(lay.intruder_columns, str):
        return tuple(range(INTRUDER_COLUMN_RULES[lay.intruder_columns], lay.columns + 1, 2))
    return lay.intruder_columns


def column_radii(lay: LatticeLayout) -> list[float]:
    """R_c [m] of each column: column_radii (or radius), times intruder_ratio in the
    intruder columns."""
    radii = list(lay.column_radii) if lay.column_radii else [lay.radius] * lay.columns
    intruders = intruder_column_numbers(lay)
    return [r * lay.intruder_ratio if c + 1 in intruders else r for c, r in enumerate(radii)]


def column_materials(lay: LatticeLayout) -> list[str]:
    """Material of each column: column_materials (or material); intruder columns take the
    intruder material."""
    mats = list(lay.column_materials) if lay.column_materials else [lay.material] * lay.columns
    intruders = intruder_column_numbers(lay)
    return [intruder_material(lay) if c + 1 in intruders else m for c, m in enumerate(mats)]


def intruder_material(lay: LatticeLayout) -> str:
    """The intruders' material (intruder_material, or material when None)."""
    return lay.material if lay.intruder_material is None else lay.intruder_material


def half_pitch(radii: list[float]) -> float:
    """a = max R_c [m]: half the vertical distance between granules of one column."""
    return max(radii)


def hexagonal_offsets(radii: list[float], a: float) -> list[float]:
    """d_c = sqrt((R_c + R_c+1)^2 - a^2) [m]: neighbours of columns c and c+1, a apart in y,
    touch (the paper's column_offset with a = R1). NaN when R_c + R_c+1 < a."""
    return [math.sqrt((ri + rj) ** 2 - a**2) if ri + rj >= a else math.nan for ri, rj in zip(radii[:-1], radii[1:])]


def square_offsets(radii: list[float]) -> list[float]:
    """d_c = R_c + R_c+1 [m]: neighbours of columns c and c+1 in the same row touch."""
    return [ri + rj for ri, rj in zip(radii[:-1], radii[1:])]


def column_offsets(lay: LatticeLayout) -> list[float]:
    """The x distances d_c [m] between columns c and c+1 of the layout's kind."""
    radii = column_radii(lay)
    if lay.kind == "square":
        return square_offsets(radii)
    return hexagonal_offsets(radii, half_pitch(radii))


def column_x(first_radius: float, offsets: list[float]) -> list[float]:
    """x_c [m]: x_1 = R_1 and x_c+1 = R_1 + (d_1 + ... + d_c)."""
    xs, acc = [first_radius], 0.0
    for d in offsets:
        acc += d
        xs.append(first_radius + acc)
    return xs


def rows_in_column(lay: LatticeLayout, column: int) -> int:
    """rows, or rows - 1 in an even column of a hexagonal packing."""
    return lay.rows - 1 if lay.kind == "hexagonal" and column % 2 == 0 else lay.rows


def row_y(lay: LatticeLayout, column: int, row: int, a: float) -> float:
    """y [m] of row `row` (1 = top) of column `column`, before the shift to the origin."""
    if lay.kind == "hexagonal" and column % 2 == 0:
        return float(2 * (lay.rows - row)) * a
    return float(2 * (lay.rows - row) + 1) * a


def lattice_sites(lay: LatticeLayout) -> list[Granule]:
    """The perfect sites, column by column (1..columns), each from the top row down."""
    radii, mats = column_radii(lay), column_materials(lay)
    a = half_pitch(radii)
    xs = column_x(radii[0], column_offsets(lay))
    return [
        Granule(xs[c - 1], row_y(lay, c, k, a), radii[c - 1], mats[c - 1], label=site_label(c, k))
        for c in range(1, lay.columns + 1)
        for k in range(1, rows_in_column(lay, c) + 1)
    ]


def intruder_sites(lay: LatticeLayout, labels: list[str]) -> set[str]:
    """Labels of the single-site intruders: intruder_sites, and every intruder_every-th
    site (1-based, in granule order)."""
    chosen = set(lay.intruder_sites)
    n = lay.intruder_every
    if n > 0:
        chosen |= {lab for k, lab in enumerate(labels, start=1) if k % n == 0}
    return chosen


def place_intruders(lay: LatticeLayout, sites: list[Granule]) -> list[Granule]:
    """Sites chosen as intruders take radius intruder_ratio x R and the intruder material."""
    chosen = intruder_sites(lay, [g.label for g in sites])
    mat = intruder_material(lay)
    return [
        dataclasses.replace(g, radius=g.radius * lay.intruder_ratio, material=mat) if g.label in chosen else g
        for g in sites
    ]


def to_origin(granules: list[Granule]) -> list[Granule]:
    """The granules shifted so that min(x - R) = min(y - R) = 0 (left and bottom walls)."""
    dx = min(g.x - g.radius for g in granules)
    dy = min(g.y - g.radius for g in granules)
    if dx == 0.0 and dy == 0.0:
        return granules
    return [dataclasses.replace(g, x=g.x - dx, y=g.y - dy) for g in granules]


def enclosing_walls(granules: list[Granule], material: str) -> tuple[Wall, ...]:
    """Walls `left` (x = 0), `bottom` (y = 0) and `top` (y = max(y + R)), granules at the origin."""
    top = max(g.y + g.radius for g in granules)
    return (
        Wall((-1.0, 0.0), 0.0, label="left", material=material),
        Wall((0.0, -1.0), 0.0, label="bottom", material=material),
        Wall((0.0, 1.0), top, label="top", material=material),
    )


def plate_x(granules: list[Granule] | tuple[Granule, ...]) -> float:
    """The plate's left edge [m]: max(x + R), touching the rightmost granule."""
    return max(g.x + g.radius for g in granules)


def lattice_packing(lay: LatticeLayout) -> Packing:
    """A hexagonal or square packing (see the module docstring)."""
    granules = to_origin(place_intruders(lay, lattice_sites(lay)))
    column1 = tuple(site_label(1, k) for k in range(1, rows_in_column(lay, 1) + 1))
    return Packing(tuple(granules), enclosing_walls(granules, lay.wall_material), plate_x(granules), column1)


def planar_in_space(packing: Packing) -> Packing:
    """A planar packing (paper, hexagonal, square) lifted into space: its granules in the
    plane z = 0 with spin vectors (0, 0, 0), its walls the planes through its lines
    (normal (nx, ny, 0), the same offset [m])."""
    granules = tuple(dataclasses.replace(g, z=0.0, omega=(0.0, 0.0, 0.0)) for g in packing.granules)
    walls = tuple(dataclasses.replace(w, normal=(float(w.normal[0]), float(w.normal[1]), 0.0)) for w in packing.walls)
    return packing._replace(granules=granules, walls=walls)


# --------------------------------------------------------------------------- chains


def chain_radii(lay: ChainLayout) -> list[float]:
    """R_k [m] = radius taper^(k-1), times dimer_ratio for even k (k = 1..count)."""
    return [lay.radius * lay.taper**k * (lay.dimer_ratio if k % 2 else 1.0) for k in range(lay.count)]


def chain_materials(lay: ChainLayout) -> list[str]:
    """Material of granule k: dimer_material (or material) for even k, material otherwise."""
    dimer = lay.material if lay.dimer_material is None else lay.dimer_material
    return [dimer if k % 2 else lay.material for k in range(lay.count)]


def chain_beads(lay: ChainLayout) -> list[tuple[str, float, str]]:
    """(label, radius, material) along the chain: c1, [d1,] c2, [d2,] ... c{count}."""
    small_mat = lay.material if lay.decorated_material is None else lay.decorated_material
    beads = []
    for k, (r, m) in enumerate(zip(chain_radii(lay), chain_materials(lay)), start=1):
        beads.append((f"c{k}", r, m))
        if lay.decorated_ratio > 0.0 and k < lay.count:
            beads.append((f"d{k}", lay.decorated_ratio * r, small_mat))
    return beads


def touching_x(radii: list[float]) -> list[float]:
    """Centres [m] of spheres in a row that touch: x_1 = R_1, x_k+1 = x_k + R_k + R_k+1."""
    xs = [radii[0]]
    for ra, rb in zip(radii[:-1], radii[1:]):
        xs.append(xs[-1] + ra + rb)
    return xs


def chain_packing(lay: ChainLayout, dimension: int = 2) -> Packing:
    """A chain along y = lay.y (default: the largest radius), wall `left` at x = 0; in 3D
    along y = lay.y, z = lay.z (defaults: the largest radius) between the walls "xmin"
    (x = 0) and "xmax" (x = the last granule's surface)."""
    beads = chain_beads(lay)
    radii = [r for _, r, _ in beads]
    y = max(radii) if lay.y is None else lay.y
    if dimension == 3:
        z = max(radii) if lay.z is None else lay.z
        granules = tuple(
            Granule(x, y, r, m, label=lab, z=z, omega=(0.0, 0.0, 0.0))
            for (lab, r, m), x in zip(beads, touching_x(radii))
        )
        end = plate_x(granules)
        walls = (
            Wall((-1.0, 0.0, 0.0), 0.0, label="xmin", material=lay.wall_material),
            Wall((1.0, 0.0, 0.0), end, label="xmax", material=lay.wall_material),
        )
        return Packing(granules, walls, end, ("c1",))
    granules = tuple(Granule(x, y, r, m, label=lab) for (lab, r, m), x in zip(beads, touching_x(radii)))
    walls = (Wall((-1.0, 0.0), 0.0, label="left", material=lay.wall_material),)
    return Packing(granules, walls, plate_x(granules), ("c1",))


# --------------------------------------------------------------------------- space lattices

#: The in-plane cell (Ly, Lz) of each space lattice, in units of the largest radius.
PLANE_CELL: dict[str, tuple[float, float]] = {
    "sc": (2.0, 2.0),
    "bcc": (4.0 / math.sqrt(3.0), 4.0 / math.sqrt(3.0)),
    "fcc": (2.0 * math.sqrt(2.0), 2.0 * math.sqrt(2.0)),
    "hcp": (2.0, 2.0 * math.sqrt(3.0)),
}
#: The sites (fy, fz) of each plane type in the in-plane cell (fractions of Ly, Lz), one
#: list per plane of a conventional cell along x.
PLANE_SITES: dict[str, tuple[tuple[tuple[float, float], ...], ...]] = {
    "sc": (((0.0, 0.0),),),
    "bcc": (((0.0, 0.0),), ((0.5, 0.5),)),
    "fcc": (((0.0, 0.0), (0.5, 0.5)), ((0.5, 0.0), (0.0, 0.5))),
    "hcp": (((0.0, 0.0), (0.5, 0.5)), ((0.5, 1.0 / 6.0), (0.0, 2.0 / 3.0))),
}


def space_site_label(plane: int, row: int, site: int) -> str:
    """Label of a space lattice's site: plane along x, row along y, site along z (1-based)."""
    return f"x{plane}y{row}z{site}"


def planes_per_cell(kind: str) -> int:
    """Lattice planes normal to x in one conventional cell: 1 (sc) or 2 (bcc, fcc, hcp)."""
    return len(PLANE_SITES[kind])


def sites_per_cell(kind: str) -> int:
    """Sites in one conventional cell: 1 (sc), 2 (bcc), 4 (fcc), 4 (hcp, orthohexagonal)."""
    return sum(len(s) for s in PLANE_SITES[kind])


def layer_planes(kind: str, layer: Layer) -> int:
    """The lattice planes of a layer: its `planes`, else `count` cells (1 when neither) of
    planes_per_cell(kind) planes each."""
    if layer.planes is not None:
        return layer.planes
    return planes_per_cell(kind) * (1 if layer.count is None else layer.count)


def planes_along_x(lay: SpaceLattice) -> int:
    """The lattice planes along x: the layers' planes added up, else `planes`, else
    cells[0] cells of planes_per_cell(kind) planes each."""
    if lay.layers:
        return sum(layer_planes(lay.kind, ly) for ly in lay.layers)
    if lay.planes is not None:
        return lay.planes
    return planes_per_cell(lay.kind) * lay.cells[0]


def plane_layers(lay: SpaceLattice) -> list[tuple[float, str]]:
    """(R_p [m], material) of each lattice plane p = 1.. along x."""
    if not lay.layers:
        return [(lay.radius, lay.material)] * planes_along_x(lay)
    return [
        (lay.radius if ly.radius is None else ly.radius, lay.material if ly.material is None else ly.material)
        for ly in lay.layers
        for _ in range(layer_planes(lay.kind, ly))
    ]


def plane_gap_distance(kind: str, t: int, u: int, r_max: float) -> float:
    """rho [m]: the in-plane distance from a site of plane type t to the nearest site of
    plane type u (0 when they are the same type), on the net of the largest radius r_max."""
    ly, lz = (c * r_max for c in PLANE_CELL[kind])
    return min(
        math.hypot((fu[0] - ft[0] + iy) * ly, (fu[1] - ft[1] + iz) * lz)
        for ft in PLANE_SITES[kind][t]
        for fu in PLANE_SITES[kind][u]
        for iy in (-1, 0, 1)
        for iz in (-1, 0, 1)
    )


def plane_type(kind: str, plane: int) -> int:
    """The type t of plane `plane` (0-based): plane mod planes_per_cell(kind)."""
    return plane % planes_per_cell(kind)


def plane_spacings(kind: str, radii: list[float]) -> list[float]:
    """d_p = sqrt((R_p + R_p+1)^2 - rho^2) [m]: the x distance at which planes p and p+1
    touch. NaN when R_p + R_p+1 < rho (they cannot reach each other)."""
    r_max = max(radii)
    out = []
    for p, (ra, rb) in enumerate(zip(radii[:-1], radii[1:])):
        rho = plane_gap_distance(kind, plane_type(kind, p), plane_type(kind, p + 1), r_max)
        out.append(math.sqrt((ra + rb) ** 2 - rho**2) if ra + rb >= rho else math.nan)
    return out


def plane_clash(kind: str, radii: list[float]) -> tuple[int, int, float] | None:
    """(p, q, overlap [m]) of the first pair of planes q >= p + 2 (0-based) whose spheres
    overlap (nearest sites sqrt((x_q - x_p)^2 + rho^2) apart < R_p + R_q), or None."""
    xs = column_x(radii[0], plane_spacings(kind, radii))
    r_max = max(radii)
    n = planes_per_cell(kind)
    rho = {(t, u): plane_gap_distance(kind, t, u, r_max) for t in range(n) for u in range(n)}
    for p in range(len(radii)):
        for q in range(p + 2, len(radii)):
            if not xs[q] - xs[p] < 2.0 * r_max:
                break  # farther planes are farther apart still
            gap = math.hypot(xs[q] - xs[p], rho[plane_type(kind, p), plane_type(kind, q)]) - radii[p] - radii[q]
            if gap < -1e-9 * min(radii[p], radii[q]):
                return p, q, -gap
    return None


def plane_sites(lay: SpaceLattice, plane: int, x: float, radius: float, material: str, r_max: float) -> list[Granule]:
    """The sites of plane `plane` (0-based) at x [m], row by row (y increasing), each row
    along z: ny x nz in-plane cells of the net of r_max."""
    ly, lz = (c * r_max for c in PLANE_CELL[lay.kind])
    sites = PLANE_SITES[lay.kind][plane_type(lay.kind, plane)]
    ranks = {fy: k for k, fy in enumerate(sorted({fy for fy, _ in sites}))}
    per_row = len(ranks)
    _, ny, nz = lay.cells
    found = []
    for j in range(ny):
        for fy, fz in sorted(sites):
            row = j * per_row + ranks[fy] + 1
            for k in range(nz):
                found.append(
                    (
                        row,
                        k + 1,
                        Granule(
                            x,
                            (j + fy) * ly,
                            radius,
                            material,
                            label=space_site_label(plane + 1, row, k + 1),
                            z=(k + fz) * lz,
                            omega=(0.0, 0.0, 0.0),
                        ),
                    )
                )
    return [g for _, _, g in sorted(found, key=lambda e: (e[0], e[1]))]


def space_sites(lay: SpaceLattice) -> list[Granule]:
    """The perfect sites, plane by plane (x increasing), each row by row."""
    layers = plane_layers(lay)
    radii = [r for r, _ in layers]
    r_max = max(radii)
    xs = column_x(radii[0], plane_spacings(lay.kind, radii))
    return [g for p, ((r, m), x) in enumerate(zip(layers, xs)) for g in plane_sites(lay, p, x, r, m, r_max)]


def to_corner(granules: list[Granule]) -> list[Granule]:
    """The spheres shifted so that min(x - R) = min(y - R) = min(z - R) = 0."""
    dx = min(g.x - g.radius for g in granules)
    dy = min(g.y - g.radius for g in granules)
    dz = min(g.z - g.radius for g in granules)
    return [dataclasses.replace(g, x=g.x - dx, y=g.y - dy, z=g.z - dz) for g in granules]


def enclosing_box(
    granules: list[Granule] | tuple[Granule, ...], labels: tuple[str, ...], material: str
) -> tuple[Wall, ...]:
    """The walls `labels` (of BOX_WALLS, in that order) touching the spheres' outermost
    surfaces: "xmin" normal -e_x, offset -min(x - R); "xmax" +e_x, max(x + R); and so on."""
    walls = []
    for k, name in enumerate(BOX_WALLS):
        if name not in labels:
            continue
        axis, upper = divmod(k, 2)
        coord = [[g.x, g.y, g.z][axis] for g in granules]
        sign = 1.0 if upper else -1.0
        offset = max(sign * c + g.radius for c, g in zip(coord, granules))
        normal = tuple(sign if a == axis else 0.0 for a in range(3))
        walls.append(Wall(normal, offset, label=name, material=material))
    return tuple(walls)


def space_packing(lay: SpaceLattice) -> Packing:
    """An sc, bcc, fcc or hcp packing (see the module docstring); column1: plane 1's labels."""
    granules = to_corner(place_intruders(lay, space_sites(lay)))
    first = tuple(g.label for g in granules if g.label.startswith("x1y"))
    return Packing(tuple(granules), enclosing_box(granules, lay.walls, lay.wall_material), plate_x(granules), first)


# --------------------------------------------------------------------------- imperfections


def imperfect_radii(radii: np.ndarray, imp: Imperfections, u: np.ndarray) -> np.ndarray:
    """R (1 - jitter - radius_spread u) [m], u uniform in [0, 1)."""
    return radii * (1.0 - imp.jitter - imp.radius_spread * u)


def jitter_offsets(
    radii: np.ndarray, imp: Imperfections, u_angle: np.ndarray, u_radius: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(dx, dy) [m] uniform within the disc of radius jitter R (polar draw)."""
    rho = imp.jitter * radii * np.sqrt(u_radius)
    theta = 2.0 * math.pi * u_angle
    return rho * np.cos(theta), rho * np.sin(theta)


def vacant(labels: list[str], imp: Imperfections, rng: np.random.Generator) -> set[str]:
    """Labels removed: round(vacancy_fraction x sites) drawn at random, plus `vacancies`."""
    n_drop = round(imp.vacancy_fraction * len(labels))
    drawn = rng.choice(len(labels), size=n_drop, replace=False) if n_drop else []
    return {labels[int(k)] for k in drawn} | set(imp.vacancies)


def jitter_offsets_3d(
    radii: np.ndarray, imp: Imperfections, u_azimuth: np.ndarray, u_radius: np.ndarray, u_polar: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(dx, dy, dz) [m] uniform within the ball of radius jitter R: distance jitter R u^(1/3),
    direction uniform on the sphere (azimuth 2 pi u, cos(polar) = 2 u - 1)."""
    rho = imp.jitter * radii * np.cbrt(u_radius)
    phi = 2.0 * math.pi * u_azimuth
    cos_t = 2.0 * u_polar - 1.0
    sin_t = np.sqrt(1.0 - cos_t**2)
    return rho * sin_t * np.cos(phi), rho * sin_t * np.sin(phi), rho * cos_t


def imperfect(packing: Packing, imp: Imperfections, dimension: int = 2) -> Packing:
    """The packing with seeded imperfections; walls and plate stay where they were.

    Draws, in this order, from numpy.random.default_rng(seed), one number per site each:
    the radius factor, the jitter angle, the jitter distance (in 3D then the polar angle's
    cosine: the jitter is uniform in the ball of radius jitter R); then the vacancies. So a
    change of one amplitude leaves the other draws alone, and zero amplitudes give back the
    perfect packing.
    """
    rng = np.random.default_rng(imp.seed)
    gs = packing.granules
    n = len(gs)
    r0 = np.array([g.radius for g in gs], float)
    u_r, u_a, u_d = rng.random(n), rng.random(n), rng.random(n)
    radii = imperfect_radii(r0, imp, u_r)
    if dimension == 3:
        dx, dy, dz = jitter_offsets_3d(r0, imp, u_a, u_d, rng.random(n))
    else:
        dx, dy = jitter_offsets(r0, imp, u_a, u_d)
    labels = [g.label for g in gs]
    gone = vacant(labels, imp, rng)
    moved = (lambda g, k: {"z": g.z + float(dz[k])}) if dimension == 3 else (lambda g, k: {})
    granules = tuple(
        dataclasses.replace(g, x=g.x + float(dx[k]), y=g.y + float(dy[k]), radius=float(radii[k]), **moved(g, k))
        for k, g in enumerate(gs)
        if g.label not in gone
    )
    column1 = tuple(lab for lab in packing.column1 if lab not in gone)
    return packing._replace(granules=granules, column1=column1)
