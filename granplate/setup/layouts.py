"""Packings generated from a layout: hexagonal and square lattices, chains, imperfections.

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
"""
from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np

from granplate.setup.scenario import ChainLayout, Granule, Imperfections, LatticeLayout, Wall


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

def column_radii(lay: LatticeLayout) -> list[float]:
    """R_c [m] of each column: column_radii (or radius), times intruder_ratio in the
    intruder columns."""
    radii = list(lay.column_radii) if lay.column_radii else [lay.radius] * lay.columns
    return [r * lay.intruder_ratio if c + 1 in lay.intruder_columns else r
            for c, r in enumerate(radii)]


def column_materials(lay: LatticeLayout) -> list[str]:
    """Material of each column: column_materials (or material); intruder columns take the
    intruder material."""
    mats = list(lay.column_materials) if lay.column_materials else [lay.material] * lay.columns
    return [intruder_material(lay) if c + 1 in lay.intruder_columns else m
            for c, m in enumerate(mats)]


def intruder_material(lay: LatticeLayout) -> str:
    """The intruders' material (intruder_material, or material when None)."""
    return lay.material if lay.intruder_material is None else lay.intruder_material


def half_pitch(radii: list[float]) -> float:
    """a = max R_c [m]: half the vertical distance between granules of one column."""
    return max(radii)


def hexagonal_offsets(radii: list[float], a: float) -> list[float]:
    """d_c = sqrt((R_c + R_c+1)^2 - a^2) [m]: neighbours of columns c and c+1, a apart in y,
    touch (the paper's column_offset with a = R1). NaN when R_c + R_c+1 < a."""
    return [math.sqrt((ri + rj) ** 2 - a**2) if ri + rj >= a else math.nan
            for ri, rj in zip(radii[:-1], radii[1:])]


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
    return [Granule(xs[c - 1], row_y(lay, c, k, a), radii[c - 1], mats[c - 1],
                    label=site_label(c, k))
            for c in range(1, lay.columns + 1) for k in range(1, rows_in_column(lay, c) + 1)]


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
    return [dataclasses.replace(g, radius=g.radius * lay.intruder_ratio, material=mat)
            if g.label in chosen else g for g in sites]


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
    return (Wall((-1.0, 0.0), 0.0, label="left", material=material),
            Wall((0.0, -1.0), 0.0, label="bottom", material=material),
            Wall((0.0, 1.0), top, label="top", material=material))


def plate_x(granules: list[Granule] | tuple[Granule, ...]) -> float:
    """The plate's left edge [m]: max(x + R), touching the rightmost granule."""
    return max(g.x + g.radius for g in granules)


def lattice_packing(lay: LatticeLayout) -> Packing:
    """A hexagonal or square packing (see the module docstring)."""
    granules = to_origin(place_intruders(lay, lattice_sites(lay)))
    column1 = tuple(site_label(1, k) for k in range(1, rows_in_column(lay, 1) + 1))
    return Packing(tuple(granules), enclosing_walls(granules, lay.wall_material),
                   plate_x(granules), column1)


# --------------------------------------------------------------------------- chains

def chain_radii(lay: ChainLayout) -> list[float]:
    """R_k [m] = radius taper^(k-1), times dimer_ratio for even k (k = 1..count)."""
    return [lay.radius * lay.taper**k * (lay.dimer_ratio if k % 2 else 1.0)
            for k in range(lay.count)]


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


def chain_packing(lay: ChainLayout) -> Packing:
    """A chain along y = lay.y (default: the largest radius), wall `left` at x = 0."""
    beads = chain_beads(lay)
    radii = [r for _, r, _ in beads]
    y = max(radii) if lay.y is None else lay.y
    granules = tuple(Granule(x, y, r, m, label=lab)
                     for (lab, r, m), x in zip(beads, touching_x(radii)))
    walls = (Wall((-1.0, 0.0), 0.0, label="left", material=lay.wall_material),)
    return Packing(granules, walls, plate_x(granules), ("c1",))


# --------------------------------------------------------------------------- imperfections

def imperfect_radii(radii: np.ndarray, imp: Imperfections, u: np.ndarray) -> np.ndarray:
    """R (1 - jitter - radius_spread u) [m], u uniform in [0, 1)."""
    return radii * (1.0 - imp.jitter - imp.radius_spread * u)


def jitter_offsets(radii: np.ndarray, imp: Imperfections, u_angle: np.ndarray,
                   u_radius: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(dx, dy) [m] uniform within the disc of radius jitter R (polar draw)."""
    rho = imp.jitter * radii * np.sqrt(u_radius)
    theta = 2.0 * math.pi * u_angle
    return rho * np.cos(theta), rho * np.sin(theta)


def vacant(labels: list[str], imp: Imperfections, rng: np.random.Generator) -> set[str]:
    """Labels removed: round(vacancy_fraction x sites) drawn at random, plus `vacancies`."""
    n_drop = round(imp.vacancy_fraction * len(labels))
    drawn = rng.choice(len(labels), size=n_drop, replace=False) if n_drop else []
    return {labels[int(k)] for k in drawn} | set(imp.vacancies)


def imperfect(packing: Packing, imp: Imperfections) -> Packing:
    """The packing with seeded imperfections; walls and plate stay where they were.

    Draws, in this order, from numpy.random.default_rng(seed), one number per site each:
    the radius factor, the jitter angle, the jitter distance; then the vacancies. So a
    change of one amplitude leaves the other draws alone, and zero amplitudes give back the
    perfect packing.
    """
    rng = np.random.default_rng(imp.seed)
    gs = packing.granules
    n = len(gs)
    r0 = np.array([g.radius for g in gs], float)
    u_r, u_a, u_d = rng.random(n), rng.random(n), rng.random(n)
    radii = imperfect_radii(r0, imp, u_r)
    dx, dy = jitter_offsets(r0, imp, u_a, u_d)
    labels = [g.label for g in gs]
    gone = vacant(labels, imp, rng)
    granules = tuple(dataclasses.replace(g, x=g.x + float(dx[k]), y=g.y + float(dy[k]),
                                         radius=float(radii[k]))
                     for k, g in enumerate(gs) if g.label not in gone)
    column1 = tuple(lab for lab in packing.column1 if lab not in gone)
    return packing._replace(granules=granules, column1=column1)
