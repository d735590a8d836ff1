"""`granplate show` in space (dimension = 3): an assembly of spheres drawn as three
orthogonal projections side by side (x-y seen from +z, x-z seen from -y, y-z seen from
+x), each sphere a circle of its true radius coloured by material, drawn far to near and
darkened with its distance from the viewer; the walls as their traces (a wall whose
plane contains the viewing direction is a line: the six walls of a box draw its
outline; an oblique plane is listed, not drawn); the contact network as lines between
touching centres (and from a centre to its wall), width and colour by the normal force
for a result. An elastic solid ([plate] of a 3D scenario) is drawn under the spheres in each
view: its boundary facets filled lightly, its outline (the edges where the surface creases:
a box's 12 edges) and its clamped faces' outlines as thick lines, labelled with its
material, element and element count; from its mesh alone (solid.mesh: the box, or the
file read and checked), no modes built. Axes in mm.

    >>> from granplate.figures import space
    >>> fig = space.draw(space.of_scenario(scenario))        # before the run
    >>> fig = space.draw(space.of_result(ds, time=2e-5))       # a result at t = 0.02 ms

A result with an elastic body's fields (results.body: `body_ux`, ...) draws the body
deformed at one of its field snapshots: its boundary faces (the faces of the stored VTK
cells that one cell has, `solid.vtk_cells.boundary_faces`) at the nodes displaced by
the displacement times a stated magnification, painted far to near, each coloured by its
element's von Mises stress [MPa] (a colour bar), over the undeformed outline; the
snapshot of the largest von Mises stress, or the one nearest `time`, with the spheres at
the output nearest it.

An animation (`granplate animate`) draws the same views frame by frame:
`frames_of_result(ds, indices)` the assemblies at `frame_times(ds)[indices]` (the body's
field snapshots for a result with a body, else the output times), on one magnification
of the body and one colour scale each for its stress and the contact forces;
`animation(frames)` the figure laid out once over the region holding every frame, and
the function that redraws it with frame f.

Contact forces of a result at one output time are read from the result: the granule-
granule and granule-wall contacts from its contact table (`link_*`, docs/output.md: the
normal force of each contact's own law with its history and damping, every
time.contact_interval; a time without a table is drawn at the nearest time with one, an
animation's frame without one draws no such contacts), the contacts on an elastic body
from its `body_contact_*`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import xarray as xr
from matplotlib.cm import ScalarMappable
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.colors import Normalize, to_rgb
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch

from granplate.figures.common import material_colours, new_figure, readable_duration
from granplate.setup.scenario import Load, Scenario, Wall
from granplate.model.dimension import SPACE

MM = 1e3  # m -> mm

#: The three views: (horizontal axis, vertical axis, depth axis, sign): depth * sign grows
#: towards the viewer (x-y seen from +z, x-z from -y, y-z from +x: right-handed views).
PROJECTIONS = ((0, 1, 2, 1.0), (0, 2, 1, -1.0), (1, 2, 0, 1.0))
AXIS_NAMES = ("x", "y", "z")
#: The farthest sphere of a view is darkened by this fraction (the nearest not at all).
DEPTH_DARKEN = 0.4
#: A wall is drawn in a view when its normal is within this of perpendicular to the view.
EDGE_ON = 1e-9
#: The widest contact line [points] (the largest force of a result).
MAX_LINE_WIDTH = 5.0
#: Contacts below this fraction of the largest force are drawn thin and dotted.
OPEN_FRACTION = 0.01
#: Contact line colours by kind (a scenario: no forces).
KIND_COLOURS = {"granule": "0.1", "wall": "tab:purple", "body": "tab:blue"}
KIND_NAMES = {"granule": "granule-granule", "wall": "granule-wall", "body": "granule-body"}
LOAD_COLOUR = "crimson"
#: The solid: the fill's share of its material colour (the rest white), its outline and
#: its clamped faces' outlines (colour, width [points]).
SOLID_TINT = 0.25
SOLID_EDGE = ("0.25", 1.0)
CLAMPED_EDGE = ("tab:blue", 3.5)
#: The deformed body: its colour map, and the largest displacement drawn as this share of
#: the body's largest side (the magnification rounded down to 1, 2 or 5 times a power of 10).
BODY_CMAP = "viridis"
BODY_DEFORMATION = 0.08
MPA = 1e-6  # Pa -> MPa


def _no_segments() -> np.ndarray:
    return np.zeros((0, 2, 3))


@dataclass(frozen=True)
class Assembly3D:
    """An assembly in space as drawn [m, N].

    pos (n, 3) centres and radius (n,); labels, materials per granule; walls: the
    resolved planes (box walls included); load and loaded: the scenario's load and the
    mask of the granules it pushes; segments (nc, 2, 3) contact lines (centre to centre,
    centre to the wall's nearest point, centre to its contact on an elastic body), kinds
    per segment ("granule", "wall", "body"); forces:
    normal force per segment [N] or None (a scenario); time [s] and time_note: the
    result time shown (None for a scenario). The elastic solid of a scenario (empty
    without one): solid_faces (nf, k, 3) its boundary facets' corners [m], solid_edges
    (ne, 2, 3) its outline, clamped_edges (nc, 2, 3) the outlines of its clamped faces,
    solid_label its material, element and element count, solid_material its material.
    A result's deformed body (empty without one): body_faces (nf, k, 3) its boundary
    faces' corners displaced body_scale times [m], body_stress (nf,) the von Mises stress
    of each face's element [Pa], body_largest the largest displacement [m], body_note
    which snapshot. stress_top [Pa] and force_top [N]: the tops of the colour scales of
    the body's stress and of the contact forces, shared by the frames of an animation
    (None: this assembly's own largest).
    """

    name: str
    pos: np.ndarray
    radius: np.ndarray
    labels: tuple[str, ...]
    materials: tuple[str, ...]
    walls: tuple[Wall, ...]
    load: Load
    loaded: np.ndarray
    segments: np.ndarray
    kinds: tuple[str, ...]
    forces: np.ndarray | None = None
    time: float | None = None
    time_note: str = ""
    solid_faces: np.ndarray = field(default_factory=lambda: np.zeros((0, 4, 3)))
    solid_edges: np.ndarray = field(default_factory=_no_segments)
    clamped_edges: np.ndarray = field(default_factory=_no_segments)
    solid_label: str = ""
    solid_material: str = ""
    body_faces: np.ndarray = field(default_factory=lambda: np.zeros((0, 4, 3)))
    body_stress: np.ndarray = field(default_factory=lambda: np.zeros(0))
    body_scale: float = 1.0
    body_largest: float = 0.0
    body_note: str = ""
    stress_top: float | None = None
    force_top: float | None = None


# --------------------------------------------------------------------------------------
# Contacts
# --------------------------------------------------------------------------------------
def unit_normal(wall: Wall) -> np.ndarray:
    """The wall's unit normal (n, 3) [-]."""
    n = np.asarray(wall.normal, float)
    return n / np.linalg.norm(n)


def touching(s: Scenario, pos: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(pairs (np, 2), wall contacts (nw, 2) [granule, wall]) of the spheres at pos [m]
    within contact.neighbour_gap R (the model's rule for contacts at t = 0)."""
    from granplate.model.arrays import find_pairs_and_walls

    pairs, wc = find_pairs_and_walls(s, pos[:, 0], pos[:, 1], r, pos[:, 2])
    return np.asarray(pairs, int).reshape(-1, 2), np.asarray(wc, int).reshape(-1, 2)


def wall_foot(p: np.ndarray, wall: Wall) -> np.ndarray:
    """The point of the wall's plane nearest to p [m]."""
    n = unit_normal(wall)
    return p + (float(wall.offset) - float(p @ n)) * n


def contact_segments(pos, walls, pairs, wall_contacts) -> tuple[np.ndarray, tuple[str, ...]]:
    """Contact lines [m] (nc, 2, 3): centre to centre, centre to the wall's nearest point."""
    segs = [(pos[i], pos[j]) for i, j in pairs]
    segs += [(pos[i], wall_foot(pos[i], walls[w])) for i, w in wall_contacts]
    kinds = ("granule",) * len(pairs) + ("wall",) * len(wall_contacts)
    return np.asarray(segs, float).reshape(-1, 2, 3), kinds


def body_contacts_at(ds: xr.Dataset, ti: int, pos: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(contact lines (nb, 2, 3) [m] from each granule touching the elastic body at output
    ti to its contact, R along the force on the body; their normal forces (nb,) [N]), from
    the result's body_contact_* (none without them)."""
    if "body_contact_normal_force" not in ds or "body_contact_force" not in ds:
        return _no_segments(), np.zeros(0)
    fn = np.nan_to_num(np.asarray(ds["body_contact_normal_force"].values[ti], float))
    f = np.nan_to_num(np.asarray(ds["body_contact_force"].values[ti], float))
    norm = np.linalg.norm(f, axis=-1)
    on = np.flatnonzero((fn > 0.0) & (norm > 0.0))
    ends = pos[on] + r[on, None] * f[on] / norm[on, None]
    return np.stack([pos[on], ends], axis=1).reshape(-1, 2, 3), fn[on]


def result_links(ds: xr.Dataset, ti: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(pairs (np, 2), wall contacts (nw, 2) [granule, wall], their normal forces [N] in that
    order) of a result at output ti: its contact table's rows at that time (none without)."""
    from granplate.results.contact_table import links_of

    links = links_of(ds, float(ds["time"].values[ti]))
    if links is None:
        return np.zeros((0, 2), int), np.zeros((0, 2), int), np.zeros(0)
    to_pair = links.partner >= 0
    pairs = np.column_stack([links.granule[to_pair], links.partner[to_pair]]).astype(int)
    walls = np.column_stack([links.granule[~to_pair], -1 - links.partner[~to_pair]]).astype(int)
    return pairs, walls, np.concatenate([links.values[to_pair, 1], links.values[~to_pair, 1]])


# --------------------------------------------------------------------------------------
# Builders
# --------------------------------------------------------------------------------------
def positions(ds: xr.Dataset, upto: int | None = None) -> np.ndarray:
    """Centres (time, granule, 3) [m] of a 3D result (up to output index `upto`, inclusive)."""
    sl = slice(None) if upto is None else slice(0, upto + 1)
    return np.stack([ds[k].values[sl] for k in SPACE.positions], axis=-1).astype(float)


def solid_drawing(s: Scenario, written: Scenario | None = None) -> dict:
    """The Assembly3D fields of the resolved scenario's elastic solid (none: {}; written:
    the scenario as written, which names its granules in a message), from its
    mesh alone (solid.build.solid_mesh: the box, or the file read and checked); a mesh
    file's surface is checked against the granules here (solid.clearance), a box's was by
    `validate`."""
    from granplate.setup.scenario import Solid

    sd = s.plate
    if not isinstance(sd, Solid):
        return {}
    from granplate.setup.geometry import granule_named
    from granplate.setup.granule_checks import start_overlap
    from granplate.solid.build import solid_mesh
    from granplate.solid.clearance import check_clearance
    from granplate.solid.mesh import boundary_polygons, outline_edges

    mesh = solid_mesh(sd)
    if sd.mesh is not None:
        check_clearance(
            s, mesh, {i: granule_named(written or s, s, i) for i in range(len(s.granules))}, start_overlap(s)
        )
    clamped = [outline_edges(mesh, mesh.boundaries[name]) for name in sd.clamped]
    held = f", clamped: {', '.join(sd.clamped)}" if sd.clamped else ", free"
    held += f", rollers: {', '.join(sd.rollers)}" if sd.rollers else ""
    return {
        "solid_faces": boundary_polygons(mesh),
        "solid_edges": outline_edges(mesh),
        "clamped_edges": np.concatenate(clamped) if clamped else _no_segments(),
        "solid_label": f"elastic solid: {sd.material}, {mesh.t.shape[1]} {sd.element} elements{held}",
        "solid_material": sd.material,
    }


def body_touching(s: Scenario, pos: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Contact lines (nb, 2, 3) [m] from each granule of the resolved `s` touching its elastic
    solid at t = 0 (the sphere's gap to the surface at most contact.neighbour_gap R, the
    rule of the pairs) to the nearest point of the surface: a box's in closed form, a mesh
    file's by `solid.surface.closest_point`. None without a solid."""
    from granplate.setup.scenario import Solid
    from granplate.setup.solid_checks import box_corners, box_signed_distance, is_box

    sd = s.plate
    if not isinstance(sd, Solid) or not len(pos):
        return _no_segments()
    if is_box(sd):
        lo, hi = box_corners(sd)
        near = np.clip(pos, lo, hi)
        dist = np.array([box_signed_distance(lo, hi, p) for p in pos])
    else:
        from granplate.solid.build import solid_mesh
        from granplate.solid.fe import vector_basis
        from granplate.solid.surface import boundary_surface, closest_point

        surface = boundary_surface(vector_basis(solid_mesh(sd), sd.element))
        found = [closest_point(surface, p) for p in pos]
        near = np.array([c.point for c in found], float)
        dist = np.array([c.distance for c in found], float)
    touch = dist - r <= s.contact.neighbour_gap * r
    return np.stack([pos[touch], near[touch]], axis=1).reshape(-1, 2, 3)


def of_scenario(scenario: Scenario) -> Assembly3D:
    """The 3D assembly of a scenario before its run: initial centres, the contacts
    touching at t = 0 (no forces: granule pairs, walls and the elastic solid,
    `body_touching`), its elastic solid (`solid_drawing`)."""
    from granplate.model.loads import loaded_granules
    from granplate.setup.geometry import resolve

    s = resolve(scenario)
    pos = np.array([(g.x, g.y, g.z) for g in s.granules], float).reshape(-1, 3)
    r = np.array([g.radius for g in s.granules], float)
    pairs, wc = touching(s, pos, r)
    segs, kinds = contact_segments(pos, s.walls, pairs, wc)
    body = body_touching(s, pos, r)
    return Assembly3D(
        name=s.name,
        pos=pos,
        radius=r,
        labels=tuple(g.label or str(i + 1) for i, g in enumerate(s.granules)),
        materials=tuple(g.material for g in s.granules),
        walls=s.walls,
        load=s.load,
        loaded=loaded_granules(s, pos, r),
        segments=np.concatenate([segs, body]),
        kinds=kinds + ("body",) * len(body),
        **solid_drawing(s, scenario),
    )


def of_result(ds: xr.Dataset, time: float | None = None) -> Assembly3D:
    """The 3D assembly of a result at `time` [s] (None: the last output): centres and
    contact forces at the nearest output (module docstring)."""
    from granplate.figures.assembly import choose_time, table_time
    from granplate.results.dataset import has_solid

    s, solid = _result_scenario(ds)
    if has_solid(ds):
        k, body_note = body_snapshot(ds, time)
        ti, _ = choose_time(ds, float(ds["field_time"].values[k]))
        return _assembly_at(ds, s, ti, "the output nearest the body's snapshot", solid, body_drawing(ds, k, body_note))
    ti, note = table_time(ds, *choose_time(ds, time))
    return _assembly_at(ds, s, ti, note)


def _result_scenario(ds: xr.Dataset) -> tuple[Scenario, dict]:
    """(the result's resolved scenario, its solid's drawing without the undeformed facets,
    {} without a body's fields)."""
    from granplate.results.dataset import scenario_of
    from granplate.results.dataset import has_solid
    from granplate.setup.geometry import resolve

    s = resolve(scenario_of(ds))
    solid = {k: v for k, v in solid_drawing(s).items() if k != "solid_faces"} if has_solid(ds) else {}
    return s, solid


def _assembly_at(
    ds: xr.Dataset, s: Scenario, ti: int, note: str, solid: dict | None = None, body: dict | None = None, **scales
) -> Assembly3D:
    """The result's assembly at output index ti: centres, the contacts of its contact table
    there with their forces (`result_links`); solid and body: the fields of `solid_drawing`
    and `body_drawing`; scales: stress_top, force_top."""
    from granplate.model.loads import loaded_granules

    pos, p0 = (np.stack([ds[k].values[o] for k in SPACE.positions], axis=-1).astype(float) for o in (ti, 0))
    r = np.asarray(ds["radius"].values, float)
    pairs, wc, forces = result_links(ds, ti)
    segs, kinds = contact_segments(pos, s.walls, pairs, wc)
    body_segs, body_forces = body_contacts_at(ds, ti, pos, r)
    return Assembly3D(
        name=s.name,
        pos=pos,
        radius=r,
        labels=tuple(str(v) for v in ds["granule"].values),
        materials=tuple(str(v) for v in ds["material"].values),
        walls=s.walls,
        load=s.load,
        loaded=loaded_granules(s, p0, r),
        segments=np.concatenate([segs, body_segs]),
        kinds=kinds + ("body",) * len(body_segs),
        forces=np.concatenate([forces, body_forces]),
        time=float(ds["time"].values[ti]),
        time_note=note,
        **(solid or {}),
        **(body or {}),
        **scales,
    )


def frame_times(ds: xr.Dataset) -> np.ndarray:
    """The times [s] an animation of a 3D result can draw: the body's field snapshots
    (`field_time`) for a result with an elastic body's fields, else every output time."""
    from granplate.results.dataset import has_solid

    return np.asarray(ds["field_time" if has_solid(ds) else "time"].values, float)


def frames_of_result(ds: xr.Dataset, indices) -> list[Assembly3D]:
    """The assemblies of a 3D result at frame_times(ds)[indices], drawn with one region's
    colour scales: with a body, its snapshots at those field times under one
    magnification (the largest displacement over them drawn as BODY_DEFORMATION of the
    body's largest side) and one stress scale, the spheres at the nearest outputs; the
    contact forces on one scale (the largest over the frames)."""
    from granplate.figures.assembly import choose_time

    s, solid = _result_scenario(ds)
    times = frame_times(ds)
    indices = [int(k) for k in indices]
    n = len(indices)
    bodies: list[dict] = [{} for _ in indices]
    scales: dict = {}
    if solid:
        nodes = np.column_stack([ds[f"body_node_{c}"].values for c in "xyz"]).astype(float)
        u = np.stack([ds[f"body_u{c}"].values[indices] for c in "xyz"], axis=-1).astype(float)
        largest = float(np.linalg.norm(u, axis=-1).max()) if u.size else 0.0
        scale = magnification(largest, float((nodes.max(axis=0) - nodes.min(axis=0)).max()))
        bodies = [body_drawing(ds, k, f"field snapshot {k + 1} of {len(times)}", scale) for k in indices]
        vm = np.asarray(ds["body_von_mises"].values, float)[indices]
        scales["stress_top"] = float(vm.max()) if vm.size else 0.0
    frames = []
    for f, (k, body) in enumerate(zip(indices, bodies)):
        ti, _ = choose_time(ds, float(times[k]))
        frames.append(_assembly_at(ds, s, ti, f"frame {f + 1} of {n}", solid, body))
    top = max((float(a.forces.max()) for a in frames if a.forces is not None and len(a.forces)), default=0.0)
    scales["force_top"] = top
    return [dataclasses.replace(a, **scales) for a in frames]


def body_snapshot(ds: xr.Dataset, time: float | None) -> tuple[int, str]:
    """(field snapshot index, note) of the body drawn: the largest von Mises stress, or the
    snapshot nearest `time` [s] (within the run's output times, else a ScenarioError)."""
    from granplate.figures.assembly import choose_time

    ft = np.asarray(ds["field_time"].values, float)
    if len(ft) == 0:
        from granplate.errors import ScenarioError

        raise ScenarioError("result", str(ds.attrs.get("scenario_name", "")), "has no body field snapshots")
    if time is None:
        k = int(np.argmax(np.asarray(ds["body_von_mises"].values).max(axis=1)))
        note = "the body's snapshot of the largest von Mises stress"
        if "max_von_mises" in ds and ds["max_von_mises"].dims == ("time",) and ds.sizes.get("time", 0):
            vm = np.asarray(ds["max_von_mises"].values, float)
            i = int(np.nanargmax(vm))
            if not np.isclose(float(ds["time"].values[i]), ft[k], rtol=0.0, atol=1e-15):
                note += (
                    f" (the peak, {vm[i] * MPA:.3g} MPa, between snapshots, at t = "
                    f"{float(ds['time'].values[i]) * 1e3:.4g} ms)"
                )
        return k, note
    choose_time(ds, time)  # within the run
    return int(np.argmin(np.abs(ft - time))), "the body's snapshot nearest the requested time"


def magnification(largest: float, extent: float) -> float:
    """The displacement magnification that draws `largest` [m] as about BODY_DEFORMATION of
    `extent` [m], rounded down to 1, 2 or 5 times a power of ten (1 when nothing moved)."""
    if not largest > 0.0:
        return 1.0
    raw = BODY_DEFORMATION * extent / largest
    power = 10.0 ** np.floor(np.log10(raw))
    return float(max(m for m in (1.0, 2.0, 5.0) if m * power <= raw * (1 + 1e-12)) * power)


def body_drawing(ds: xr.Dataset, k: int, note: str, scale: float | None = None) -> dict:
    """The Assembly3D fields of the body at field snapshot k (module docstring); scale:
    the displacements' magnification (None: `magnification` of this snapshot's largest)."""
    from granplate.solid.vtk_cells import boundary_faces

    cells = np.asarray(ds["body_element_nodes"].values, np.int64)
    element = {20: "hex20", 27: "hex27", 10: "tet10"}[cells.shape[1]]
    nodes = np.column_stack([ds[f"body_node_{c}"].values for c in "xyz"]).astype(float)
    u = np.column_stack([ds[f"body_u{c}"].values[k] for c in "xyz"]).astype(float)
    largest = float(np.linalg.norm(u, axis=1).max()) if len(u) else 0.0
    if scale is None:
        scale = magnification(largest, float((nodes.max(axis=0) - nodes.min(axis=0)).max()))
    faces, owner = boundary_faces(cells, element)
    t = float(ds["field_time"].values[k])
    return {
        "body_faces": nodes[faces] + scale * u[faces],
        "body_stress": np.asarray(ds["body_von_mises"].values[k], float)[owner],
        "body_scale": scale,
        "body_largest": largest,
        "body_note": f"t = {t * 1e3:.4g} ms, {note}",
    }


# --------------------------------------------------------------------------------------
# Drawing
# --------------------------------------------------------------------------------------
def depth_fraction(depth: np.ndarray) -> np.ndarray:
    """0 for the nearest sphere, 1 for the farthest (depth grows towards the viewer)."""
    d = np.asarray(depth, float)
    span = float(d.max() - d.min()) if d.size else 0.0
    return (d.max() - d) / span if span > 0 else np.zeros_like(d)


def shaded(colour: str, fraction: float) -> tuple[float, float, float]:
    """colour darkened by DEPTH_DARKEN * fraction (fraction 0: unchanged)."""
    return tuple(c * (1.0 - DEPTH_DARKEN * float(fraction)) for c in to_rgb(colour))


def bounds(a: Assembly3D, margin: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) corners [m] of the drawn region: the spheres and the axis-aligned
    walls (a box), widened by margin times the largest side."""
    lo = (a.pos - a.radius[:, None]).min(axis=0) if len(a.radius) else np.zeros(3)
    hi = (a.pos + a.radius[:, None]).max(axis=0) if len(a.radius) else np.zeros(3)
    if len(a.solid_edges) or len(a.body_faces):  # the solid bounds every axis
        ends = np.concatenate([a.solid_edges.reshape(-1, 3), a.body_faces.reshape(-1, 3)])
        lo, hi = (
            (np.minimum(lo, ends.min(axis=0)), np.maximum(hi, ends.max(axis=0)))
            if len(a.radius)
            else (ends.min(axis=0), ends.max(axis=0))
        )
    for w in a.walls:  # an axis-aligned wall bounds its axis
        n = unit_normal(w)
        k = int(np.argmax(np.abs(n)))
        if abs(abs(n[k]) - 1.0) < EDGE_ON:
            c = float(w.offset) * n[k]
            lo[k], hi[k] = min(lo[k], c), max(hi[k], c)
    m = margin * float((hi - lo).max()) if np.any(hi > lo) else 0.01
    return lo - m, hi + m


def wall_trace(wall: Wall, view: tuple, lo: np.ndarray, hi: np.ndarray):
    """The wall's line in a view (two end points [m], clipped to the drawn region), or
    None when its plane is not seen edge-on in that view."""
    from granplate.figures.show import clip_line

    u, v, d, _ = view
    n = unit_normal(wall)
    if abs(n[d]) > EDGE_ON:
        return None
    n2 = np.array([n[u], n[v]])
    n2 = n2 / np.linalg.norm(n2)
    return clip_line(n2 * float(wall.offset), np.array([-n2[1], n2[0]]), (lo[u], hi[u], lo[v], hi[v]))


def _force_style(forces: np.ndarray, top: float | None = None):
    """(widths, colours, styles, colour map, open, top) of the contact lines by normal
    force, on the scale 0..top [N] (None: the largest of forces)."""
    from granplate.figures.show import FORCE_CMAP

    f_max = top if top is not None else (float(forces.max()) if len(forces) else 0.0)
    cmap = ScalarMappable(Normalize(0.0, f_max if f_max > 0 else 1.0), FORCE_CMAP)
    open_ = forces <= OPEN_FRACTION * f_max
    widths = np.where(open_, 0.6, MAX_LINE_WIDTH * forces / (f_max if f_max > 0 else 1.0))
    colours = [(0.45, 0.45, 0.45, 1.0) if o else cmap.to_rgba(v) for o, v in zip(open_, forces)]
    return widths, colours, [":" if o else "-" for o in open_], cmap, open_, f_max


def _draw_view(ax, a: Assembly3D, view: tuple, colours: dict, lo, hi) -> int:
    """One projection of the region lo..hi [m]; returns the number of walls drawn as lines
    (each clipped to the region without its margin: a box's walls meet at its corners)."""
    _view_axes(ax, view, lo, hi)
    return _view_content(ax, a, view, colours)


def _view_axes(ax, view: tuple, lo, hi) -> None:
    """A projection's axes: the region lo..hi [m] at equal scales, labels [mm], title, grid."""
    u, v, d, sign = view
    ax.set_aspect("equal")
    ax.set_xlim(lo[u] * MM, hi[u] * MM)
    ax.set_ylim(lo[v] * MM, hi[v] * MM)
    ax.set_xlabel(f"{AXIS_NAMES[u]} [mm]")
    ax.set_ylabel(f"{AXIS_NAMES[v]} [mm]")
    toward = ("+" if sign > 0 else "-") + AXIS_NAMES[d]
    ax.set_title(f"{AXIS_NAMES[u]}-{AXIS_NAMES[v]}, seen from {toward}", fontsize=9, loc="left")
    ax.grid(True, lw=0.3, alpha=0.4)


def _view_content(ax, a: Assembly3D, view: tuple, colours: dict) -> int:
    """What one projection shows of assembly a: the solid, the walls, the spheres far to
    near, the contacts; returns the number of walls drawn as lines."""
    u, v, d, sign = view
    _draw_solid(ax, a, view, colours)
    drawn = 0
    inner = bounds(a, margin=0.0)
    for w in a.walls:
        ends = wall_trace(w, view, *inner)
        if ends is not None:
            p, q = ends
            ax.plot(
                [p[0] * MM, q[0] * MM],
                [p[1] * MM, q[1] * MM],
                color="0.2",
                lw=2.0,
                zorder=1,
                gid=f"wall:{w.label}:{AXIS_NAMES[u]}{AXIS_NAMES[v]}",
            )
            drawn += 1
    depth = sign * a.pos[:, d] if len(a.radius) else np.zeros(0)
    frac = depth_fraction(depth)
    order = np.argsort(depth, kind="stable")  # far first, near last (on top)
    for rank, i in enumerate(order):
        ax.add_patch(
            Circle(
                (a.pos[i, u] * MM, a.pos[i, v] * MM),
                a.radius[i] * MM,
                fc=shaded(colours[a.materials[i]], frac[i]),
                ec="0.1",
                lw=0.6,
                zorder=2 + rank,
                gid=f"granule:{a.labels[i]}:{AXIS_NAMES[u]}{AXIS_NAMES[v]}",
            )
        )
    if len(a.segments):
        segs = a.segments[:, :, [u, v]] * MM
        z_top = 3 + len(a.radius)
        if a.forces is None:
            lines = LineCollection(
                segs,
                colors=[KIND_COLOURS[k] for k in a.kinds],
                linewidths=1.2,
                zorder=z_top,
                gid=f"contacts:{AXIS_NAMES[u]}{AXIS_NAMES[v]}",
            )
        else:
            widths, cols, styles, *_ = _force_style(np.asarray(a.forces, float), a.force_top)
            lines = LineCollection(
                segs,
                colors=cols,
                linewidths=widths,
                linestyles=styles,
                zorder=z_top,
                capstyle="round",
                gid=f"contacts:{AXIS_NAMES[u]}{AXIS_NAMES[v]}",
            )
        ax.add_collection(lines)
    return drawn


def solid_fill(colour: str) -> tuple[float, float, float]:
    """The solid's light fill: SOLID_TINT of its material colour, the rest white."""
    return tuple(SOLID_TINT * c + (1.0 - SOLID_TINT) for c in to_rgb(colour))


def _draw_solid(ax, a: Assembly3D, view: tuple, colours: dict) -> None:
    """The solid in one view, under the spheres: its facets filled, its outline, its
    clamped faces' outlines thick (gids solid, solid-edges, solid-clamped: VIEW)."""
    u, v, d, sign = view
    uv = f"{AXIS_NAMES[u]}{AXIS_NAMES[v]}"
    if len(a.body_faces):  # the deformed body, far faces first
        order = np.argsort(sign * a.body_faces[:, :, d].mean(axis=1), kind="stable")
        cmap = body_colour_map(a)
        ax.add_collection(
            PolyCollection(
                a.body_faces[order][:, :, [u, v]] * MM,
                facecolors=cmap.to_rgba(a.body_stress[order] * MPA),
                edgecolors="0.35",
                linewidths=0.15,
                zorder=0.7,
                gid=f"body:{uv}",
            )
        )
    if not len(a.solid_edges):
        return
    if not len(a.body_faces):
        fill = solid_fill(colours.get(a.solid_material, "0.6"))
        ax.add_collection(
            PolyCollection(
                a.solid_faces[:, :, [u, v]] * MM, facecolors=[fill], edgecolors="none", zorder=0.5, gid=f"solid:{uv}"
            )
        )
    ax.add_collection(
        LineCollection(
            a.solid_edges[:, :, [u, v]] * MM,
            colors=SOLID_EDGE[0],
            linewidths=SOLID_EDGE[1],
            linestyles="--" if len(a.body_faces) else "-",
            zorder=0.8,
            gid=f"solid-edges:{uv}",
        )
    )
    if len(a.clamped_edges):
        ax.add_collection(
            LineCollection(
                a.clamped_edges[:, :, [u, v]] * MM,
                colors=CLAMPED_EDGE[0],
                linewidths=CLAMPED_EDGE[1],
                zorder=0.9,
                capstyle="butt",
                gid=f"solid-clamped:{uv}",
            )
        )


def body_colour_map(a: Assembly3D) -> ScalarMappable:
    """The von Mises stress [MPa] colours of the deformed body: 0 to its largest (to
    a.stress_top when set: an animation's scale)."""
    if a.stress_top is not None:
        top = a.stress_top * MPA
    else:
        top = float(a.body_stress.max()) * MPA if len(a.body_stress) else 0.0
    return ScalarMappable(Normalize(0.0, top if top > 0 else 1.0), BODY_CMAP)


def _title(a: Assembly3D) -> str:
    if len(a.body_faces):
        return (
            f"{a.name} at t = {a.time * 1e3:.4g} ms, {a.time_note} (in space)\n"
            f"elastic body: {a.body_note}; displacements magnified x{a.body_scale:g} (largest "
            f"{a.body_largest:.3g} m), coloured by von Mises stress [MPa]"
        )
    if a.time is None:
        return f"{a.name}: assembly before the run (in space; spheres darker with distance from the viewer)"
    return (
        f"{a.name} at t = {a.time * 1e3:.4g} ms, {a.time_note} (in space; spheres darker with distance from the viewer)"
    )


def _load_text(a: Assembly3D, series: bool = False) -> str | None:
    ld = a.load
    if ld.kind != "force" or not a.loaded.any():
        return None
    d = np.asarray(ld.direction, float)
    d = d / np.linalg.norm(d)
    text = (
        f"load: {ld.force:.4g} N half-sine, T = {readable_duration(ld.duration)}, along "
        f"({d[0]:.3g}, {d[1]:.3g}, {d[2]:.3g}), on {int(a.loaded.sum())} granule(s) (red outline)"
    )
    if a.time is not None and a.time > ld.duration and not series:
        text += ", over at this time"
    return text


def _mark_loaded(axes, a: Assembly3D) -> None:
    for ax, (u, v, _, _) in zip(axes, PROJECTIONS):
        for i in np.flatnonzero(a.loaded):
            ax.add_patch(
                Circle(
                    (a.pos[i, u] * MM, a.pos[i, v] * MM),
                    a.radius[i] * MM,
                    fill=False,
                    ec=LOAD_COLOUR,
                    lw=1.6,
                    zorder=4 + 2 * len(a.radius),
                    gid=f"load:{a.labels[i]}",
                )
            )


def legend_handles(a: Assembly3D, colours: dict, oblique: list[str], series: bool = False) -> list:
    """Legend entries: materials, walls, contacts, load; series: the legend of every frame
    of an animation (the contact forces on the scale a.force_top, no counts of the
    contacts or remarks that hold at one time only)."""
    handles = [
        Patch(fc=c, ec="0.1", label=f"{m} ({a.materials.count(m)} spheres)")
        for m, c in colours.items()
        if m in a.materials
    ]
    if len(a.body_faces):
        handles.append(
            Patch(
                fc=body_colour_map(a).to_rgba(0.5 * body_colour_map(a).norm.vmax),
                ec="0.35",
                label=f"elastic body deformed x{a.body_scale:g}, coloured by von Mises stress",
            )
        )
        if a.solid_label:
            handles.append(
                Line2D(
                    [], [], color=SOLID_EDGE[0], lw=SOLID_EDGE[1], ls="--", label=f"undeformed outline; {a.solid_label}"
                )
            )
    elif a.solid_label:
        handles.append(
            Patch(fc=solid_fill(colours.get(a.solid_material, "0.6")), ec=SOLID_EDGE[0], label=a.solid_label)
        )
        if len(a.clamped_edges):
            handles.append(Line2D([], [], color=CLAMPED_EDGE[0], lw=CLAMPED_EDGE[1], label="clamped faces"))
    if len(a.walls) > len(oblique):
        handles.append(Line2D([], [], color="0.2", lw=2.0, label="rigid walls seen edge-on"))
    if oblique:
        handles.append(Line2D([], [], color="none", label="oblique walls, not drawn: " + ", ".join(oblique)))
    if series:
        if a.force_top:
            _, _, _, cmap, _, f_max = _force_style(np.zeros(0), a.force_top)
            handles += [
                Line2D(
                    [],
                    [],
                    color=cmap.to_rgba(f_max),
                    lw=MAX_LINE_WIDTH,
                    label=f"contact force, width ∝ force (widest over the frames: {f_max:.3g} N)",
                ),
                Line2D([], [], color="0.45", lw=0.6, ls=":", label=f"contact below {OPEN_FRACTION:.0%} of the widest"),
            ]
    elif len(a.segments) and a.forces is None:
        handles += [
            Line2D([], [], color=KIND_COLOURS[k], lw=1.2, label=f"contact {KIND_NAMES[k]} ({a.kinds.count(k)})")
            for k in KIND_COLOURS
            if k in a.kinds
        ]
    elif len(a.segments):
        _, _, _, cmap, open_, f_max = _force_style(np.asarray(a.forces, float), a.force_top)
        handles += [
            Line2D(
                [],
                [],
                color=cmap.to_rgba(f_max),
                lw=MAX_LINE_WIDTH,
                label=f"contact force, width ∝ force (widest: {f_max:.3g} N)",
            ),
            Line2D(
                [],
                [],
                color="0.45",
                lw=0.6,
                ls=":",
                label=f"contact below {OPEN_FRACTION:.0%} of the largest ({int(open_.sum())})",
            ),
        ]
    text = _load_text(a, series)
    if text:
        handles.append(Patch(fc="none", ec=LOAD_COLOUR, lw=1.6, label=text))
    return handles


def draw(a: Assembly3D, width: float = 13.0) -> Figure:
    """The three orthogonal projections of a 3D assembly (module docstring)."""
    return _figure(a, width, bounds(a), series=False)[0]


def _figure(a: Assembly3D, width: float, region: tuple[np.ndarray, np.ndarray], series: bool):
    """(figure, its three views, the material colours) of assembly a drawn over region
    (lower, upper corners [m]); series: the legend of an animation's frames."""
    lo, hi = region
    span = (hi - lo) * MM
    fig = new_figure(width, min(max(width / 3.0 * span[1:].max() / max(span[:2].max(), 1e-12) + 2.2, 4.0), 9.0))
    axes = fig.subplots(1, 3, width_ratios=[span[0], span[0], span[1]])
    colours = material_colours(a.materials + ((a.solid_material,) if a.solid_material else ()))
    for ax, view in zip(axes, PROJECTIONS):
        _draw_view(ax, a, view, colours, lo, hi)
    _mark_loaded(axes, a)
    oblique = [
        w.label or f"wall {k}"
        for k, w in enumerate(a.walls)
        if all(wall_trace(w, view, lo, hi) is None for view in PROJECTIONS)
    ]
    if len(a.body_faces):
        fig.colorbar(
            body_colour_map(a),
            ax=list(axes),
            label="von Mises stress [MPa] (largest in each element)",
            orientation="horizontal",
            shrink=0.5,
            aspect=50,
            location="bottom",
        )
    if a.forces is not None and (len(a.segments) or (series and a.force_top)):
        cmap = _force_style(np.asarray(a.forces, float), a.force_top)[3]
        fig.colorbar(
            cmap,
            ax=list(axes),
            label="contact normal force [N]",
            orientation="horizontal",
            shrink=0.5,
            aspect=50,
            location="bottom",
        )
    fig.legend(
        handles=legend_handles(a, colours, oblique, series),
        loc="outside lower center",
        ncols=2,
        fontsize=8,
        frameon=False,
    )
    fig.suptitle(_title(a), fontsize=10, x=0.01, ha="left")
    return fig, axes, colours


def animation(frames: list[Assembly3D], width: float = 13.0):
    """(figure, draw) of an animation of the assemblies `frames` (`frames_of_result`):
    the figure `draw` makes, over the region that holds every frame, laid out once for
    the first frame; draw(f) redraws its three views and title with frame f."""
    lo = np.min([bounds(a)[0] for a in frames], axis=0)
    hi = np.max([bounds(a)[1] for a in frames], axis=0)
    fig, axes, colours = _figure(frames[0], width, (lo, hi), series=True)
    fig.canvas.draw()  # lay out once, then freeze the layout (re-solving it every frame is slow)
    fig.set_layout_engine("none")

    def draw_frame(f: int) -> None:
        a = frames[f]
        for ax, view in zip(axes, PROJECTIONS):  # the axes stay; what they show is replaced
            for artist in [*ax.patches, *ax.collections, *ax.lines, *ax.texts]:
                artist.remove()
            _view_content(ax, a, view, colours)
        _mark_loaded(axes, a)
        fig.suptitle(_title(a), fontsize=10, x=0.01, ha="left")  # the one title, its text replaced

    return fig, draw_frame
