"""The paper's three-column packing and scenario resolution (docs/model.md section 1).

`paper_layout` turns a `Layout` into the 14 granules (1..5, intruders 6..9, A..E), the
left, bottom and top walls and the x position of the plate's left edge; the other layout
kinds are built in `layouts` and `layout_packing` picks the kind. `resolve` turns
any scenario into an explicit one: the layout expanded, the plate placed, every granule
and wall labelled.

Geometry (origin at the bottom-left corner of the granular domain, x to the right):

    d  = sqrt((R1 + R2)^2 - R1^2)       horizontal offset between neighbouring columns
    column 1 (1..5):   x = R1,          y = 9R1, 7R1, 5R1, 3R1, R1
    column 2 (6..9):   x = R1 + d,      y = 8R1, 6R1, 4R1, 2R1       (radius R2)
    column 3 (A..E):   x = R1 + 2d,     y = 9R1, 7R1, 5R1, 3R1, R1
    plate left edge:   xp = R1 + 2d + R1
    walls:             x = 0 (left), y = 0 (bottom), y = 10 R1 (top)
"""

from __future__ import annotations

import dataclasses
import math
import threading
import weakref

from granplate.errors import ScenarioError
from granplate.setup import layouts, pouring
from granplate.setup.granules_file import granule_path
from granplate.setup.scenario import (
    BOX_WALLS,
    Box,
    ChainLayout,
    Contact,
    Granule,
    LatticeLayout,
    Layout,
    Plate,
    PouredLayout,
    RigidPatch,
    Scenario,
    Solid,
    SpaceLattice,
    Wall,
)

#: Labels of the paper's granules, in the order `paper_layout` returns them.
PAPER_LABELS: tuple[str, ...] = ("1", "2", "3", "4", "5", "6", "7", "8", "9", "A", "B", "C", "D", "E")
#: Labels of the three walls `paper_layout` returns, in order.
PAPER_WALLS: tuple[str, ...] = ("left", "bottom", "top")


def column_offset(R1: float, R2: float) -> float:
    """d = sqrt((R1 + R2)^2 - R1^2) [m]: the x distance between neighbouring columns.

    With it, an intruder at (R1 + d, 2k R1) touches the heavy granules at (R1, (2k +- 1) R1)
    and at (R1 + 2d, (2k +- 1) R1) exactly. R2 = R1 gives sqrt(3) R1 (hexagonal packing),
    R2 = 0.5 R1 gives 1.1180 R1.
    """
    return math.sqrt((R1 + R2) ** 2 - R1**2)


def paper_layout(layout: Layout) -> tuple[tuple[Granule, ...], tuple[Wall, ...], float]:
    """The paper's packing: (granules 1..9, A..E), (left, bottom, top walls), plate x0.

    Heavy granules (1..5, A..E) take `layout.heavy_material` and radius R1, intruders
    (6..9) `layout.intruder_material` and radius R2 = R2_ratio R1; the walls take
    `layout.wall_material`. No range checks here: `validate` refuses a bad layout first.
    """
    R1 = layout.R1
    R2 = layout.R2_ratio * R1
    d = column_offset(R1, R2)
    heavy_y = (9.0 * R1, 7.0 * R1, 5.0 * R1, 3.0 * R1, R1)
    intruder_y = (8.0 * R1, 6.0 * R1, 4.0 * R1, 2.0 * R1)
    x1, x2, x3 = R1, R1 + d, R1 + 2.0 * d
    hm, im = layout.heavy_material, layout.intruder_material

    granules: list[Granule] = []
    granules += [Granule(x1, y, R1, hm, label=lab) for lab, y in zip("12345", heavy_y)]
    granules += [Granule(x2, y, R2, im, label=lab) for lab, y in zip("6789", intruder_y)]
    granules += [Granule(x3, y, R1, hm, label=lab) for lab, y in zip("ABCDE", heavy_y)]

    wm = layout.wall_material
    walls = (
        Wall((-1.0, 0.0), 0.0, label="left", material=wm),
        Wall((0.0, -1.0), 0.0, label="bottom", material=wm),
        Wall((0.0, 1.0), 10.0 * R1, label="top", material=wm),
    )
    xp = x3 + R1
    return tuple(granules), walls, xp


def layout_packing(layout: Layout | LatticeLayout | ChainLayout | SpaceLattice, dimension: int = 2) -> layouts.Packing:
    """The packing of any layout kind (paper, hexagonal, square, chain; sc, bcc, fcc, hcp in
    space), imperfections applied. `dimension`: the scenario's, which places a chain in the
    plane or in space (a space lattice is always 3D); in space a planar packing lies in
    the plane z = 0 (`layouts.planar_in_space`)."""
    if isinstance(layout, SpaceLattice):
        dimension = 3
        packing = layouts.space_packing(layout)
    elif layout.kind == "paper":
        granules, walls, xp = paper_layout(layout)
        packing = layouts.Packing(granules, walls, xp, PAPER_LABELS[:5])
    elif layout.kind == "chain":
        packing = layouts.chain_packing(layout, dimension)
    else:
        packing = layouts.lattice_packing(layout)
    planar = dimension == 3 and not isinstance(layout, SpaceLattice) and layout.kind != "chain"
    if layout.imperfections is not None:
        packing = layouts.imperfect(packing, layout.imperfections, 2 if planar else dimension)
    return layouts.planar_in_space(packing) if planar else packing


def default_granule_label(index: int) -> str:
    """The label `resolve` gives an unlabelled granule at 0-based position `index`."""
    return f"g{index}"


def default_wall_label(index: int) -> str:
    """The label `resolve` gives an unlabelled wall at 0-based position `index`."""
    return f"w{index}"


def unit(v: tuple[float, ...]) -> tuple[float, ...]:
    """v / |v| [-] (v nonzero and finite: `validate` refuses the others first)."""
    norm = math.hypot(*v)
    return tuple(c / norm for c in v)


def along_plus_x(direction: object) -> bool:
    """Whether a load direction is +x (the layers' stacking direction): (d, 0, 0), d > 0."""
    return (
        isinstance(direction, tuple)
        and len(direction) == 3
        and direction[1:] == (0.0, 0.0)
        and isinstance(direction[0], (int, float))
        and not isinstance(direction[0], bool)
        and direction[0] > 0.0
    )


def plane_offset(normal: tuple[float, ...], point: tuple[float, ...]) -> float:
    """offset = point . n [m], n = normal / |normal|: the plane through `point` [m]."""
    return math.fsum(p * n for p, n in zip(point, unit(normal)))


def box_walls(box: Box) -> tuple[Wall, ...]:
    """The six walls of a box, labelled BOX_WALLS: "xmin" is normal -e_x, offset -x0,
    "xmax" +e_x, offset x1, and so on along y and z (unit normals, offsets [m])."""
    walls = []
    for axis in range(3):
        e = tuple(1.0 if k == axis else 0.0 for k in range(3))
        walls.append(
            Wall(
                tuple(-1.0 if k == axis else 0.0 for k in range(3)),
                0.0 - float(box.lower[axis]),
                label=BOX_WALLS[2 * axis],
                material=box.material,
            )
        )
        walls.append(Wall(e, float(box.upper[axis]), label=BOX_WALLS[2 * axis + 1], material=box.material))
    return tuple(walls)


def solid_against(sd: Solid, granules: tuple[Granule, ...], xp: float) -> tuple[float, float, float]:
    """The origin [m] of a box solid placed against a packing: its face xmin at the
    packing's far side xp [m], centred on the packing's extent in y and z."""
    ys = [v for g in granules for v in (g.y - g.radius, g.y + g.radius)]
    zs = [v for g in granules for v in (g.z - g.radius, g.z + g.radius)]
    cy = 0.5 * (min(ys) + max(ys)) if ys else 0.0
    cz = 0.5 * (min(zs) + max(zs)) if zs else 0.0
    return (float(xp), cy - 0.5 * float(sd.size[1]), cz - 0.5 * float(sd.size[2]))


#: A granule touches the solid at t = 0 when its centre lies within (1 + TOUCH_RTOL) R of the box.
TOUCH_RTOL = 1e-6


def rigid_layers(sd: Solid, granules: tuple[Granule, ...]) -> tuple[RigidPatch, ...]:
    """The paper's rigid layers on a placed box solid (docs/model.md section 4.2): at each
    granule touching it at t = 0, a translation-only rigid patch across the box's z extent
    (a strip along z through the contact point), sd.rigid_layer_width [m] wide along the
    face (None: one element edge along the face's in-plane axis other than z). A granule
    touching a face normal to z is a ScenarioError (a strip along z would cross it)."""
    lo = [float(o) for o in sd.origin]
    hi = [o + float(L) for o, L in zip(lo, sd.size)]
    patches = []
    for g in granules:
        c = (g.x, g.y, g.z)
        p = [min(max(v, a), b) for v, a, b in zip(c, lo, hi)]
        d = math.dist(c, p)
        if d > (1.0 + TOUCH_RTOL) * g.radius or d == 0.0:
            continue
        axis = max(range(3), key=lambda k: abs(c[k] - p[k]))
        if axis == 2:
            raise ScenarioError(
                "plate.rigid_layers",
                True,
                f"granule {g.label or '?'} touches a face normal to z: "
                "the rigid layers lie across the solid's z extent, on its faces normal to x or y",
            )
        along = 1 - axis
        w = sd.rigid_layer_width if sd.rigid_layer_width is not None else sd.size[along] / sd.elements[along]
        patches.append(
            RigidPatch(
                centre=(p[0], p[1], p[2]),
                radius=0.5 * float(w) * (1.0 + TOUCH_RTOL),
                axis=(0.0, 0.0, 1.0),
                rotates=False,
            )
        )
    return tuple(patches)


def resolve(scenario: Scenario) -> Scenario:
    """An equivalent, explicit scenario: layout expanded, plate placed, labels filled.

    - With a `layout`: granules and walls come from `layout_packing` (any kind),
      `layout` becomes None, and a plate with `x0 = None` is placed at the layout's xp.
      With imperfections and an empty `load.granules`, the load is given column 1's labels
      (the leftmost-surface rule would pick one granule of a polydisperse column; in 3D
      plane 1's, when the load's direction is +x). A 3D layout with a `box` is a
      ScenarioError (the layout makes its walls). A layout together with
      explicit granules or walls is a ScenarioError (give one or the other).
    - Without a layout, a plate needs an explicit `x0` (ScenarioError otherwise). A 3D
      box solid (`Solid`) without an `origin` is placed against the layout's packing
      (`solid_against`), or at [0, 0, 0] without a layout; its `rigid_layers` become
      explicit rigid patches (`rigid_layers`).
    - Unlabelled granules get the label "g<i>", unlabelled walls "w<i>" (i: 0-based index).
    - In 3D (`dimension = 3`): a `box` becomes its six walls (`box_walls`), after the
      explicit walls, and `box` None; a wall given by a `point` gets offset = point . n
      (`plane_offset`); a granule's default scalar omega 0 becomes (0, 0, 0).

    Idempotent: resolving a resolved scenario returns an equal scenario. Range checks are
    `validate`'s job; this function only builds. The last scenario resolved is remembered
    (by identity: it is frozen), so that validating and building a run resolve it once.
    """
    if _LAST.pair and _LAST.pair[0]() is scenario:
        return _LAST.pair[1]
    resolved = _expanded(scenario)
    _LAST.pair[:] = [weakref.ref(scenario), resolved]
    return resolved


class _LastResolved(threading.local):
    """The scenario this thread resolved last (a weak reference) and its resolved form."""

    def __init__(self):
        self.pair: list = []


_LAST = _LastResolved()


def _expanded(scenario: Scenario) -> Scenario:
    """`resolve`'s work, on every call."""
    granules, walls, plate, load = scenario.granules, scenario.walls, scenario.plate, scenario.load
    xp = 0.0
    contact = scenario.contact
    if scenario.layout is not None:
        if granules and not isinstance(scenario.layout, PouredLayout):
            raise ScenarioError(
                "granules", f"{len(granules)} granules", "give either [layout] or [[granules]], not both"
            )
        if walls:
            raise ScenarioError(
                "walls",
                f"{len(walls)} walls",
                "give either [layout] or [[walls]], not both (the layout generates the left, bottom and top walls)",
            )
        if scenario.box is not None:
            raise ScenarioError(
                "box",
                "[box]",
                "give either [layout] or [box], not both (a 3D layout generates the walls around it: layout.walls)",
            )
        if isinstance(scenario.layout, PouredLayout):
            granules, walls, xp, contact = _poured(scenario, scenario.layout)
        else:
            granules, walls, xp, column1 = layout_packing(scenario.layout, scenario.dimension)
        if isinstance(plate, Plate) and plate.x0 is None:
            plate = dataclasses.replace(plate, x0=xp)
        along_x = scenario.dimension == 2 or along_plus_x(load.direction)
        if getattr(scenario.layout, "imperfections", None) is not None and not load.granules and along_x:
            load = dataclasses.replace(load, granules=column1)
    if isinstance(plate, Solid) and plate.origin is None and plate.mesh is None:
        plate = dataclasses.replace(
            plate, origin=solid_against(plate, granules, xp) if scenario.layout is not None else (0.0, 0.0, 0.0)
        )
    if isinstance(plate, Solid) and plate.rigid_layers:
        plate = dataclasses.replace(
            plate,
            rigid_layers=False,
            rigid_layer_width=None,
            rigid_patches=plate.rigid_patches + rigid_layers(plate, granules),
        )
    if isinstance(plate, Plate) and plate.x0 is None:
        raise ScenarioError(
            "plate.x0", None, "must be given when the scenario has no [layout] (the plate's lower-left corner x [m])"
        )
    box = scenario.box
    if scenario.dimension == 3:
        granules = tuple(
            dataclasses.replace(g, omega=(0.0, 0.0, 0.0)) if not isinstance(g.omega, tuple) and g.omega == 0.0 else g
            for g in granules
        )
        walls = tuple(
            dataclasses.replace(w, offset=plane_offset(w.normal, w.point))
            if w.offset is None and w.point is not None
            else w
            for w in walls
        )
        if box is not None:
            walls, box = walls + box_walls(box), None
    granules = tuple(g if g.label else _relabelled(g, default_granule_label(i)) for i, g in enumerate(granules))
    walls = tuple(w if w.label else dataclasses.replace(w, label=default_wall_label(i)) for i, w in enumerate(walls))
    return dataclasses.replace(
        scenario, layout=None, granules=granules, walls=walls, plate=plate, load=load, box=box, contact=contact
    )


def _poured(scenario: Scenario, lay: PouredLayout) -> tuple[tuple[Granule, ...], tuple[Wall, ...], float, Contact]:
    """A poured layout's settled granules (then the scenario's own [[granules]]: a striker),
    its walls, the plate's x0 and the [contact] whose overlap_start holds the settled
    contacts (`pouring.poured_granules`; docs/scenario.md, "Poured packings")."""
    granules, walls, xp, overlap = pouring.poured_granules(scenario, lay)
    c = scenario.contact
    if overlap > 0.0 and c.overlap_start is None:
        c = dataclasses.replace(c, overlap_start=float(f"{overlap * (1.0 + POURED_OVERLAP_MARGIN):.3e}"))
    return granules + tuple(scenario.granules), walls, xp, c


#: The resolved form of a poured packing allows its settled overlaps plus this share.
POURED_OVERLAP_MARGIN = 0.01


def _relabelled(g: Granule, label: str) -> Granule:
    """`dataclasses.replace(g, label=label)`, a copy of its fields without a call of the
    frozen dataclass's `__init__` (a million granules in a fraction of a second)."""
    new = object.__new__(type(g))
    new.__dict__.update(g.__dict__, label=label)
    return new


#: The fields of each layout kind that place its granules (materials do not), in the
#: order a message lists them; the kind's radius is always listed.
PLACING_FIELDS: dict[type, tuple[str, ...]] = {
    Layout: ("R1", "R2_ratio", "imperfections"),
    LatticeLayout: (
        "kind",
        "columns",
        "rows",
        "radius",
        "column_radii",
        "intruder_ratio",
        "intruder_columns",
        "intruder_sites",
        "intruder_every",
        "imperfections",
    ),
    ChainLayout: ("count", "radius", "taper", "dimer_ratio", "decorated_ratio", "y", "z", "imperfections"),
    SpaceLattice: (
        "kind",
        "cells",
        "radius",
        "layers",
        "intruder_ratio",
        "intruder_sites",
        "intruder_every",
        "imperfections",
    ),
    PouredLayout: (
        "count",
        "radius_range",
        "distribution",
        "sizes",
        "fractions",
        "mean",
        "std",
        "seed",
        "container",
        "g",
    ),
}


def placing_fields(scenario: Scenario, index: int) -> tuple[str, ...]:
    """The scenario fields (dotted, as in TOML) that place granule `index` of the resolved
    scenario: its own x, y, radius in [[granules]], or the layout's fields that set the
    packing's geometry (those that differ from their defaults, and the kind's radius), so
    that a message about the granule names what to change. `scenario`: as written, before
    `resolve`."""
    lay = scenario.layout
    if lay is None:
        coords = ("x", "y", "z", "radius") if scenario.dimension == 3 else ("x", "y", "radius")
        return tuple(granule_path(scenario.granules_file, index, f, scenario.dimension) for f in coords)
    if isinstance(lay, PouredLayout) and isinstance(lay.count, int) and index >= lay.count:  # a striker
        coords = ("x", "y", "z", "radius") if scenario.dimension == 3 else ("x", "y", "radius")
        return tuple(f"granules[{index - lay.count}].{f}" for f in coords)
    primary = {Layout: "R1", PouredLayout: "radius_range"}.get(type(lay), "radius")
    default = type(lay)()
    return tuple(
        f"layout.{f}" for f in PLACING_FIELDS[type(lay)] if f == primary or getattr(lay, f) != getattr(default, f)
    )


def granule_named(scenario: Scenario, resolved: Scenario, index: int) -> str:
    """ "granule 'LABEL' (placed by FIELDS; centre (x, y), radius R [m])" for messages
    ((x, y, z) in 3D)."""
    g = resolved.granules[index]
    centre = f"{g.x:.6g}, {g.y:.6g}" + (f", {g.z:.6g}" if scenario.dimension == 3 else "")
    return (
        f"granule '{g.label}' (placed by {', '.join(placing_fields(scenario, index))}; centre "
        f"({centre}) m, radius {g.radius:.6g} m)"
    )
