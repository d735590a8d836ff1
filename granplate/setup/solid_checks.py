"""Range checks of a 3D scenario's solid ([plate] when dimension = 3), each naming the
field and its allowed range: the box or the mesh file, the material, the element, the
faces held (names that exist, no face both clamped and on rollers), the cut-off. The
mesh itself (cells, Jacobians, face groups) is checked when it is read (solid.mesh)."""
from __future__ import annotations

import numbers
from typing import Any

from granplate.errors import ScenarioError
from granplate.setup.fields import finite, material_exists, positive, string_in
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
        raise ScenarioError(missing, None, "a 3D [plate] needs size [Lx, Ly, Lz] (m) and elements "
                            "[nx, ny, nz], or a mesh file (plate.mesh)")
    for i, v in enumerate(_triple("plate.size", sd.size)):
        positive(f"plate.size[{i}]", v)
    lo, hi = ELEMENTS_RANGE
    for i, v in enumerate(_triple("plate.elements", sd.elements)):
        if not isinstance(v, numbers.Integral) or isinstance(v, bool) or not lo <= v <= hi:
            raise ScenarioError(f"plate.elements[{i}]", v, f"must be an integer in [{lo}, {hi}]")
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
            raise ScenarioError("plate.mesh", sd.mesh, "a mesh file excludes plate.size and plate.elements: "
                                "give one or the other")
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


def check_solid(s: Scenario) -> None:
    """A scenario's solid: its fields and its material."""
    check_solid_fields(s.plate)
    material_exists("plate.material", s.plate.material, s)
