"""Range checks of a 3D scenario's solid ([plate] when dimension = 3), each naming the
field and its allowed range: the box or the mesh file, the material, the element, the
faces held (names that exist, no face both clamped and on rollers), the cut-off. The
mesh itself (cells, Jacobians, face groups) is checked when it is read (solid.mesh).

The granules against the solid at t = 0 (`check_solid_clearance`, the one owner of the
rule and its message): a granule may touch the solid but not cross its surface, and its
centre never lies inside it. For a box the signed distance of a centre to the surface is
in closed form (`box_signed_distance`); for a mesh file it is the surface's
(solid.surface.closest_point), computed where the file is read."""

from __future__ import annotations

import math
import numbers
from typing import Any, Sequence

from granplate.errors import ScenarioError
from granplate.setup.fields import finite, material_exists, positive, string_in
from granplate.setup.granules_file import granule_path
from granplate.setup.scenario import SOLID_ELEMENTS, Scenario, Solid

#: Box faces (solid.mesh.BOX_FACES, repeated here: setup sits below the solid layer).
BOX_FACES: tuple[str, ...] = ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")
#: Elements per side of a box.
ELEMENTS_RANGE = (1, 1000)
#: The cut-off's range [Hz].
MAX_FREQUENCY_RANGE = (1.0, 1.0e9)


def _triple(path: str, v: Any) -> tuple:
    if not isinstance(v, tuple) or len(v) != 3:
        raise ScenarioError(path, v, "must be three numbers [x, y, z]")
    return v


def check_box(sd: Solid) -> None:
    """size, elements and origin of a box."""
    if sd.size is None or sd.elements is None:
        missing = "plate.size" if sd.size is None else "plate.elements"
        raise ScenarioError(
            missing,
            None,
            "a 3D [plate] needs size [Lx, Ly, Lz] (m) and elements [nx, ny, nz], or a mesh file (plate.mesh)",
        )
    for i, v in enumerate(_triple("plate.size", sd.size)):
        positive(f"plate.size[{i}]", v)
    lo, hi = ELEMENTS_RANGE
    for i, v in enumerate(_triple("plate.elements", sd.elements)):
        if not isinstance(v, numbers.Integral) or isinstance(v, bool) or not lo <= v <= hi:
            raise ScenarioError(f"plate.elements[{i}]", v, f"must be an integer in [{lo}, {hi}]")
    if sd.origin is not None:
        for i, v in enumerate(_triple("plate.origin", sd.origin)):
            finite(f"plate.origin[{i}]", v)


def check_faces(sd: Solid, names: tuple[str, ...] | None) -> None:
    """clamped and rollers name faces that exist (names None: not known before the mesh
    file is read) and none twice."""
    for field in ("clamped", "rollers"):
        for name in getattr(sd, field):
            if names is not None and name not in names:
                string_in(f"plate.{field}", name, names)
    both = set(sd.clamped) & set(sd.rollers)
    if both:
        raise ScenarioError("plate.rollers", sorted(both), "a face cannot be both clamped and on rollers")


def check_solid_fields(sd: Solid) -> None:
    """Every field of a solid but its material (which needs the scenario)."""
    if sd.mesh is not None:
        if sd.size is not None or sd.elements is not None:
            raise ScenarioError(
                "plate.mesh", sd.mesh, "a mesh file excludes plate.size and plate.elements: give one or the other"
            )
        if not isinstance(sd.mesh, str) or not sd.mesh:
            raise ScenarioError("plate.mesh", sd.mesh, "must be a file name (Gmsh .msh)")
        names = None
    else:
        check_box(sd)
        names = BOX_FACES
    string_in("plate.element", sd.element, SOLID_ELEMENTS)
    check_faces(sd, names)
    lo, hi = MAX_FREQUENCY_RANGE
    f = finite("plate.max_frequency", sd.max_frequency)
    if not lo <= f <= hi:
        raise ScenarioError("plate.max_frequency", sd.max_frequency, f"must be in [{lo:g}, {hi:g}] Hz")
    if sd.patch_radius is not None:
        pr = finite("plate.patch_radius", sd.patch_radius, "must be >= 0 [m] (0: a point patch)")
        if not pr >= 0.0:
            raise ScenarioError("plate.patch_radius", sd.patch_radius, "must be >= 0 [m] (0: a point patch)")
    for k, rp in enumerate(sd.rigid_patches):
        path = f"plate.rigid_patches[{k}]"
        if len(rp.centre) != 3 or not all(math.isfinite(float(c)) for c in rp.centre):
            raise ScenarioError(f"{path}.centre", list(rp.centre), "must be three finite numbers [m]")
        r = finite(f"{path}.radius", rp.radius, "must be > 0 [m]")
        if not r > 0.0:
            raise ScenarioError(f"{path}.radius", rp.radius, "must be > 0 [m]")
        if rp.axis is not None:
            ax = rp.axis
            if (
                not isinstance(ax, tuple)
                or len(ax) != 3
                or not all(isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c) for c in ax)
                or not any(c != 0.0 for c in ax)
            ):
                raise ScenarioError(
                    f"{path}.axis",
                    list(ax) if isinstance(ax, tuple) else ax,
                    "must be three finite numbers, not all zero (the strip's direction), or absent (a disc)",
                )
        if not isinstance(rp.rotates, bool):
            raise ScenarioError(
                f"{path}.rotates", rp.rotates, "must be true (six rigid motions) or false (translation only)"
            )
    if not isinstance(sd.rigid_layers, bool):
        raise ScenarioError("plate.rigid_layers", sd.rigid_layers, "must be true or false")
    if sd.rigid_layers and sd.mesh is not None:
        raise ScenarioError(
            "plate.rigid_layers",
            True,
            "the paper's rigid layers are placed on a box's face "
            "(plate.size); on a mesh file's solid give plate.rigid_patches",
        )
    if sd.rigid_layer_width is not None:
        w = finite(
            "plate.rigid_layer_width", sd.rigid_layer_width, "must be > 0 [m] (or absent: one element edge along y)"
        )
        if not w > 0.0:
            raise ScenarioError(
                "plate.rigid_layer_width", sd.rigid_layer_width, "must be > 0 [m] (or absent: one element edge along y)"
            )
    if not isinstance(sd.residual, bool):
        raise ScenarioError("plate.residual", sd.residual, "must be true or false")
    if sd.stress_radius is not None:
        r = finite(
            "plate.stress_radius",
            sd.stress_radius,
            "must be > 0 [m] (or absent: a quarter of the body's smallest extent)",
        )
        if not r > 0.0:
            raise ScenarioError(
                "plate.stress_radius",
                sd.stress_radius,
                "must be > 0 [m] (or absent: a quarter of the body's smallest extent)",
            )


def check_solid(s: Scenario) -> None:
    """A scenario's solid: its fields and its material."""
    check_solid_fields(s.plate)
    material_exists("plate.material", s.plate.material, s)


def is_box(sd: Solid) -> bool:
    """Whether the solid is a box (size and elements), not a mesh file."""
    return sd.mesh is None


def box_signed_distance(lower: Sequence[float], upper: Sequence[float], p: Sequence[float]) -> float:
    """The signed distance [m] of point p [m] to the surface of the box lower..upper [m]:
    outside, the Euclidean distance to the box (positive); inside, minus the distance to
    the nearest face (negative); zero on the surface."""
    gaps = [max(lo - x, 0.0, x - hi) for lo, hi, x in zip(lower, upper, p)]
    outside = math.hypot(*gaps)
    if outside > 0.0:
        return outside
    return -min(min(x - lo, hi - x) for lo, hi, x in zip(lower, upper, p))


def box_corners(sd: Solid) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(lower, upper) corners [m] of a box solid."""
    lo = tuple(float(o) for o in (sd.origin or (0.0, 0.0, 0.0)))
    return lo, tuple(o + float(s) for o, s in zip(lo, sd.size))


def solid_named(sd: Solid) -> str:
    """The solid as a message names it: its box corners, or its mesh file."""
    if is_box(sd):
        lo, hi = box_corners(sd)
        return (
            f"the elastic solid (the box [{', '.join(f'{v:.6g}' for v in lo)}] .. "
            f"[{', '.join(f'{v:.6g}' for v in hi)}] m of plate.origin and plate.size)"
        )
    return f"the elastic solid (the surface of plate.mesh = {sd.mesh!r})"


def check_solid_clearance(s: Scenario, distances: Sequence[float], named: dict[int, str], rtol: float) -> None:
    """No granule of the resolved `s` crosses the solid's surface at t = 0.

    distances: the signed distance [m] of each granule's centre to the surface (positive
    outside); named: how messages name granule i; rtol: the tolerance on a penetration,
    times the granule's radius. A centre inside the solid is always refused."""
    what = solid_named(s.plate)
    move = "plate.origin" if is_box(s.plate) else "the mesh"
    for i, (g, d) in enumerate(zip(s.granules, distances)):
        if d < 0.0:
            raise ScenarioError(
                granule_path(s.granules_file, i, None, s.dimension),
                g.label,
                f"{named[i]} has its centre inside {what}, {-d:.6g} m below its surface, at t = 0; "
                f"move the granule or the solid ({move}) so that the granule lies outside it "
                f"(distance from its centre to the surface >= its radius {g.radius:.6g} m)",
            )
        pen = g.radius - d
        if pen > rtol * g.radius:
            raise ScenarioError(
                granule_path(s.granules_file, i, None, s.dimension),
                g.label,
                f"{named[i]} penetrates {what} by {pen:.6g} m at t = 0; a granule may touch the "
                f"solid but not cross it: move the granule or the solid ({move}) so that the "
                f"distance from its centre to the surface ({d:.6g} m) is at least its radius "
                f"{g.radius:.6g} m",
            )


def wall_cuts_box(
    normal: Sequence[float], offset: float, lower: Sequence[float], upper: Sequence[float], tol: float
) -> bool:
    """Whether the wall plane n.x = offset [m] (n a unit normal) passes through the inside of
    the box lower..upper [m], deeper than tol [m] (a plane along a face does not)."""
    lo = sum(min(n * a, n * b) for n, a, b in zip(normal, lower, upper))
    hi = sum(max(n * a, n * b) for n, a, b in zip(normal, lower, upper))
    return lo + tol < offset < hi - tol


def wall_contact_on_box(
    normal: Sequence[float],
    offset: float,
    centre: Sequence[float],
    radius: float,
    lower: Sequence[float],
    upper: Sequence[float],
    tol: float,
) -> bool:
    """Whether a sphere (centre, radius [m]) within tol [m] of touching the wall n.x = offset
    (n a unit normal, the sphere on the side n.x < offset) touches it at a point of the box
    lower..upper's surface, within tol: the wall then lies on the face the sphere meets."""
    gap = offset - sum(n * c for n, c in zip(normal, centre))
    if abs(gap - radius) > tol:
        return False
    point = [c + gap * n for n, c in zip(normal, centre)]
    return abs(box_signed_distance(lower, upper, point)) <= tol


def box_distances(s: Scenario) -> list[float]:
    """The signed distance [m] of each granule's centre to the surface of the box solid
    of the resolved `s` (`box_signed_distance`)."""
    lo, hi = box_corners(s.plate)
    return [box_signed_distance(lo, hi, (g.x, g.y, g.z)) for g in s.granules]
