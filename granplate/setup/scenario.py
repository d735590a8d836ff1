"""Scenario: everything that defines a run, as frozen dataclasses (SI units throughout).

A scenario is written as a TOML file (see docs/scenario.md) or built in Python. The
paper's three-column packing is generated from a `Layout`, hexagonal and square packings
from a `LatticeLayout`, chains from a `ChainLayout`, sc, bcc, fcc and hcp lattices of
spheres in space from a `SpaceLattice`; any other assembly is given granule by granule. Validation (`validate`) refuses bad input before anything runs,
with a `ScenarioError` naming the field, the value and what is allowed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from granplate.setup.law_registry import NORMAL_LAW_IDS, TANGENTIAL_LAW_IDS
from granplate.setup.materials import LIBRARY, Material


@dataclass(frozen=True)
class Granule:
    """One sphere: centre (x, y, z) [m], radius [m], material name, initial velocities.

    vx, vy, vz [m/s]; omega [rad/s]: in 2D (`Scenario.dimension = 2`) a float, the spin
    about z (positive anticlockwise), and z = vz = 0; in 3D the vector (wx, wy, wz).
    label is the paper's name ("1".."9", "A".."E") or any unique string.
    """

    x: float
    y: float
    radius: float
    material: str
    label: str = ""
    vx: float = 0.0
    vy: float = 0.0
    omega: float | tuple[float, float, float] = 0.0
    z: float = 0.0
    vz: float = 0.0

    def spin(self) -> tuple[float, float, float]:
        """The angular velocity vector (wx, wy, wz) [rad/s]: (0, 0, omega) in 2D."""
        if isinstance(self.omega, tuple):
            return self.omega
        return (0.0, 0.0, self.omega)


@dataclass(frozen=True)
class Wall:
    """A rigid, clamped wall: the line (2D) or plane (3D) {p : p . n = offset}, n the unit normal.

    normal: from the granules into the wall (outward for the granular domain), [nx, ny]
    of unit length in 2D, [nx, ny, nz] of any length > 0 in 3D (n = normal / |normal|);
    offset [m]. The left wall x = 0 is normal (-1, 0), offset 0; the top wall y = 0.1 is
    normal (0, 1), offset 0.1. point [m]: 3D only, a point on the plane instead of (or
    agreeing with) offset: `geometry.resolve` sets offset = point . n.
    """

    normal: tuple[float, ...]
    offset: float | None = None
    label: str = ""
    material: str = "steel"
    point: tuple[float, float, float] | None = None


#: Labels of the six walls a `Box` expands into, in order (`geometry.box_walls`).
BOX_WALLS: tuple[str, ...] = ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")


@dataclass(frozen=True)
class Box:
    """A 3D box of six walls, `[box]`: lower = (x0, y0, z0), upper = (x1, y1, z1) [m].

    Expanded by `geometry.resolve` into the walls "xmin" (normal -e_x, offset -x0),
    "xmax" (+e_x, x1), "ymin", "ymax", "zmin", "zmax", of `material`, after the explicit
    walls; the granules live inside, lower < s < upper.
    """

    lower: tuple[float, float, float]
    upper: tuple[float, float, float]
    material: str = "steel"


@dataclass(frozen=True)
class Imperfections:
    """Seeded imperfections of a generated packing (any layout kind), `[layout.imperfections]`.

    Every granule stays inside the disc of its perfect site (radius R at the perfect centre),
    so nothing overlaps and nothing crosses a wall or the plate; the packing becomes loose.
    seed: numpy.random.default_rng(seed), integer >= 0; radius_spread [-]: radii uniform in
    [R (1 - jitter - radius_spread), R (1 - jitter)]; jitter [-]: each granule shrunk by
    jitter R and its centre moved uniformly within a disc of radius jitter R;
    radius_spread + jitter < 1. vacancy_fraction [-]: round(fraction x sites) sites
    removed at random, in [0, 1); vacancies: labels of sites removed as well.
    Gaps close during a run (contact.detection = "dynamic"); with detection = "fixed" only
    the pairs whose gap at t = 0 is within contact.neighbour_gap x the smaller radius interact.
    """

    seed: int = 0
    radius_spread: float = 0.0
    jitter: float = 0.0
    vacancy_fraction: float = 0.0
    vacancies: tuple[str, ...] = ()


@dataclass(frozen=True)
class Layout:
    """The paper's packing (docs/model.md section 1): columns 1..5, intruders 6..9, A..E.

    R1: heavy-granule radius [m]; R2_ratio = R2 / R1 in [sqrt(2) - 1, 1].
    Generates the 14 granules, the left, bottom and top walls and the plate's x position.
    kind: "paper" (the default, not written to TOML); imperfections: None (perfect) or
    seeded imperfections.
    """

    R1: float = 0.01
    R2_ratio: float = 1.0
    heavy_material: str = "steel"
    intruder_material: str = "steel"
    wall_material: str = "steel"
    kind: str = "paper"
    imperfections: Imperfections | None = None


@dataclass(frozen=True)
class LatticeLayout:
    """A hexagonal or square packing of vertical columns, `kind = "hexagonal"` or `"square"`.

    Columns are numbered 1..columns from the loaded side (x increasing), rows 1..rows from
    the top; odd columns of a hexagonal packing hold `rows` granules, even ones rows - 1
    (shifted by half a pitch), a square packing `rows` in every column. Neighbours touch:
    the vertical pitch is 2 a with a = the largest column radius, and the column offsets
    are sqrt((R_c + R_c+1)^2 - a^2) (hexagonal) or R_c + R_c+1 (square). Walls left,
    bottom, top enclose the packing; the plate is placed against the rightmost surface.

    radius [m], material: every column's, unless column_radii / column_materials (one per
    column) are given. intruder_columns: whole columns whose radius is intruder_ratio x the
    column's radius (the offsets follow, as the paper's column 2), or "even" / "odd": every
    even (odd) column, the heavy / light alternation whatever `columns`; intruder_sites (labels
    "c{column}r{row}") and intruder_every = n (every n-th site in granule order, 0 = none):
    single sites whose granule is intruder_ratio (<= 1) x the site's radius, at its centre
    (loose when < 1). Intruders take intruder_material (None = material).
    """

    kind: str = "hexagonal"
    columns: int = 3
    rows: int = 5
    radius: float = 0.01
    material: str = "steel"
    column_radii: tuple[float, ...] = ()
    column_materials: tuple[str, ...] = ()
    intruder_ratio: float = 1.0
    intruder_material: str | None = None
    intruder_columns: tuple[int, ...] | str = ()
    intruder_sites: tuple[str, ...] = ()
    intruder_every: int = 0
    wall_material: str = "steel"
    imperfections: Imperfections | None = None


@dataclass(frozen=True)
class ChainLayout:
    """A horizontal chain of touching spheres along y = y (default: the largest radius).

    Granule k = 1..count ("c{k}", from the loaded side) has radius radius x taper^(k-1),
    times dimer_ratio and with dimer_material (None = material) when k is even (a dimer
    chain); decorated_ratio > 0 puts a small granule "d{k}" of radius decorated_ratio x
    R_k (decorated_material, None = material) between granules k and k + 1.
    One wall, `left`, touches granule 1; the plate is placed against the last granule.
    In 3D (`dimension = 3`) the chain runs along x at height y and depth z [m] (default:
    the largest radius) between the walls "xmin" (x = 0) and "xmax" (the last surface);
    z is 3D only (None in 2D).
    """

    kind: str = "chain"
    count: int = 10
    radius: float = 0.01
    material: str = "steel"
    taper: float = 1.0
    dimer_ratio: float = 1.0
    dimer_material: str | None = None
    decorated_ratio: float = 0.0
    decorated_material: str | None = None
    y: float | None = None
    z: float | None = None
    wall_material: str = "steel"
    imperfections: Imperfections | None = None


#: Kinds of `SpaceLattice` (3D lattices): simple cubic, body-centred cubic, face-centred
#: cubic, hexagonal close-packed.
SPACE_LATTICE_KINDS: tuple[str, ...] = ("sc", "bcc", "fcc", "hcp")


@dataclass(frozen=True)
class Layer:
    """One layer of a `SpaceLattice`, `layout.layers[k]`: `count` conventional cells along x
    (the load direction; 2 lattice planes each for bcc, fcc and hcp, 1 for sc) or `planes`
    lattice planes (any number, odd too; not both; neither: one cell) whose spheres have
    `radius` [m] (None = the layout's radius) and `material` (None = the layout's material)."""

    count: int | None = None
    radius: float | None = None
    material: str | None = None
    planes: int | None = None


@dataclass(frozen=True)
class SpaceLattice:
    """A lattice of spheres in space (`dimension = 3`), `kind` one of SPACE_LATTICE_KINDS.

    cells = (nx, ny, nz): conventional cells along x (the load direction), y, z. A cell holds
    1 (sc), 2 (bcc), 4 (fcc) or 4 (hcp, the orthohexagonal cell) sites; each cell along x is
    1 (sc) or 2 lattice planes normal to x, numbered 1.. from the loaded side (x smallest).
    Spheres of the largest radius R touch as the lattice says: sc along the axes (edge 2R),
    bcc along the body diagonals (edge 4R / sqrt(3)), fcc (edge 2 sqrt(2) R) and hcp (a = 2R,
    c = 4 sqrt(2/3) R) at 2R, 12 neighbours. layers: cells along x of their own radius and
    material (the counts add up to nx; empty = one layer of radius, material); the planes'
    spacing follows their radii so that neighbours in adjacent planes touch. Site labels
    "x{plane}y{row}z{site}" (1-based: plane along x, row along y in the plane, site along z
    in the row). planes: the lattice planes along x instead of cells[0] (which is then 0; any
    number, odd too: the stacking goes on plane by plane, ABA... for fcc's two plane types).
    intruder_sites, intruder_every, intruder_ratio (<= 1), intruder_material: single
    sites shrunk at their centres, as in `LatticeLayout`. walls: which of the six walls
    (BOX_WALLS) enclose the packing, each touching its outermost surfaces, of wall_material.
    """

    kind: str = "fcc"
    cells: tuple[int, int, int] = (2, 2, 2)
    radius: float = 0.01
    material: str = "steel"
    layers: tuple[Layer, ...] = ()
    planes: int | None = None
    intruder_ratio: float = 1.0
    intruder_material: str | None = None
    intruder_sites: tuple[str, ...] = ()
    intruder_every: int = 0
    walls: tuple[str, ...] = BOX_WALLS
    wall_material: str = "steel"
    imperfections: Imperfections | None = None


#: Size distributions of a poured packing (`PouredLayout.distribution`).
POURED_DISTRIBUTIONS: tuple[str, ...] = ("uniform", "discrete", "normal", "lognormal")
#: How a poured packing's granules are dropped (`PouredLayout.drop`).
POURED_DROPS: tuple[str, ...] = ("column", "sequential")


@dataclass(frozen=True)
class PouredLayout:
    """A poured packing, `kind = "poured"` (2D and 3D; docs/scenario.md, "Poured packings";
    the settling: docs/model.md section 3.14).

    count granules of `material`, radii drawn with numpy.random.default_rng(seed) from
    `distribution`: "uniform" in radius_range = [min, max] [m]; "discrete": the radii
    `sizes` [m] with the number fractions `fractions` (summing to 1); "normal" or
    "lognormal": the radius' mean and std [m], cut to radius_range (draws outside it are
    drawn again). They are placed at random (seeded, apart) in a loose column above the
    floor of a container, the box [0, container] [m] open on the side gravity comes from
    (empty container: a footprint of ceil(count^(1/d)) largest diameters a side), walls of
    wall_material labelled as a [box]'s, and settled under gravity g [m/s^2] (empty: the
    scenario's [gravity]; one of them is needed, along a coordinate axis) until the
    kinetic energy is at most settle_tolerance x the work gravity did, first with the
    contact damping settle_damping and no friction, then with the scenario's own. settle_time [s]: the
    longest settling simulated. settle_friction [-] (3D; 0: off): the packing settles instead in one
    phase of Mindlin's friction of that coefficient (docs/model.md sections 3.14 and 3.16) with the
    damping settle_damping, and rests as a frictional packing. settle_softening [-] (3D; 1: off):
    above 1, the ramped settling (docs/model.md section 3.14): the fall at every contact's stiffness
    over settle_softening, the stiffness ramped to the real law's, settled when also every granule's
    residual force is at most settle_residual [-] of its weight. drop: "column" (the loose column
    above, all granules falling at once) or "sequential": one at a time, each rolled to rest on
    the pile before the next (`setup.deposition`), then settled at the real stiffness (in space by
    the ramped settling's kernel, its fall skipped). The settled packing is kept in the run store.
    """

    kind: str = "poured"
    count: int = 100
    radius_range: tuple[float, float] = (0.001, 0.001)
    distribution: str = "uniform"
    sizes: tuple[float, ...] = ()
    fractions: tuple[float, ...] = ()
    mean: float | None = None
    std: float | None = None
    seed: int = 0
    material: str = "steel"
    container: tuple[float, ...] = ()
    wall_material: str = "steel"
    g: tuple[float, ...] = ()
    settle_tolerance: float = 1e-9
    settle_damping: float = 1.0
    settle_time: float = 2.0
    settle_friction: float = 0.0
    settle_softening: float = 1.0
    settle_residual: float = 1e-2
    drop: str = "column"


#: `[layout] kind` -> the dataclass that holds that kind's fields.
LAYOUT_KINDS: dict[str, type] = {
    "paper": Layout,
    "hexagonal": LatticeLayout,
    "square": LatticeLayout,
    "chain": ChainLayout,
    **{k: SpaceLattice for k in SPACE_LATTICE_KINDS},
    "poured": PouredLayout,
}
#: The layout kinds of each dimension (`Scenario.dimension`); a chain is either, and the
#: planar packings (paper, hexagonal, square) lie in the plane z = 0 in space.
LAYOUT_KINDS_BY_DIMENSION: dict[int, tuple[str, ...]] = {
    2: ("paper", "hexagonal", "square", "chain", "poured"),
    3: SPACE_LATTICE_KINDS + ("chain", "paper", "hexagonal", "square", "poured"),
}


#: Default radius of the stress-averaging discs, as a fraction of the plate's width along
#: x (its thickness across which the shock travels) [-]: 2.5 mm on the paper's plate.
STRESS_RADIUS_FRACTION = 0.25


@dataclass(frozen=True)
class Plate:
    """The elastic plate (plane stress, Q8 elements), docs/model.md section 4.

    x0, y0: lower-left corner [m] (x0 = None: placed against the layout's last column);
    width (along x) and height (along y) [m]; thickness [m]; nx, ny: elements along x, y;
    rigid_layer_width: w [m] (None = one element edge along y); clamped_edges: subset of
    {"top", "bottom", "left", "right"}; n_modes: number of modes kept (0 = all, which is
    exactly Newmark on the full system); modes: the modal basis, "all" (dense
    eigendecomposition of the whole model), "truncated" (the modes up to max_frequency
    from a sparse eigensolver plus the static residual compliance at the contacts,
    docs/model.md section 4.5) or "auto" ("all" up to DENSE_DOF_LIMIT reduced dofs,
    "truncated" above); max_frequency: the truncated basis' cut-off [Hz] (None:
    DEFAULT_MAX_FREQUENCY); stress_radius: radius [m] of the discs over which the von
    Mises stress is averaged (docs/model.md section 4.4; None: STRESS_RADIUS_FRACTION
    x width, the plate's thickness across which the shock travels).
    """

    width: float = 0.01
    height: float = 0.1
    thickness: float = 0.001
    material: str = "steel"
    x0: float | None = None
    y0: float = 0.0
    nx: int = 4
    ny: int = 40
    rigid_layer_width: float | None = None
    clamped_edges: tuple[str, ...] = ("top", "bottom")
    n_modes: int = 0
    modes: str = "auto"
    max_frequency: float | None = None
    stress_radius: float | None = None

    @property
    def disc_radius(self) -> float:
        """The stress-averaging disc radius actually used [m]."""
        return STRESS_RADIUS_FRACTION * self.width if self.stress_radius is None else self.stress_radius

    @property
    def element_height(self) -> float:
        """Element edge along y [m]."""
        return self.height / self.ny

    @property
    def layer_width(self) -> float:
        """The rigid-layer width actually used [m]."""
        return self.element_height if self.rigid_layer_width is None else self.rigid_layer_width


#: The solid's elements (Solid.element): 20-node serendipity and 27-node triquadratic
#: hexahedra, 10-node tetrahedra.
SOLID_ELEMENTS: tuple[str, ...] = ("hex20", "hex27", "tet10")
#: The solid's default cut-off [Hz] (Solid.max_frequency): the lowest that kept the plate's
#: peak energy share and the peak contact force within 1% of a 300 kHz basis in each coupled
#: case measured (a 300-sphere protector pressed on a 5 mm steel plate, 5 mm and 2 mm steel
#: spheres dropped on it at 1 m/s; docs/benchmarks.md, "Coupled 3D solid").
SOLID_MAX_FREQUENCY = 1.5e5


@dataclass(frozen=True)
class RigidPatch:
    """A rigid patch tied to a solid's surface (docs/model.md section 3.9): the surface nodes
    within `radius` [m] of `centre` [m] move as one rigid body; a granule touching it meets
    a rigid body (E* of the granule alone, no damping: the 2D rigid layer's law).

    axis: None (a disc: distance to the centre) or a direction [ax, ay, az] (a strip: the
    nodes within `radius` of the line through `centre` along it, e.g. [0, 0, 1] across a
    slab's thickness); rotates: whether the patch moves as a rigid body in all six motions
    (true) or in translation only (false: the paper's rigid layer, whose rotation is
    neglected)."""

    centre: tuple[float, float, float]
    radius: float
    axis: tuple[float, float, float] | None = None
    rotates: bool = True


@dataclass(frozen=True)
class Solid:
    """The elastic solid of a `dimension = 3` scenario (its [plate] table), docs/model.md
    section "The 3D solid".

    A box: size [Lx, Ly, Lz] [m], elements [nx, ny, nz], origin [x, y, z] of its lowest
    corner [m]; its faces are named xmin, xmax, ymin, ymax, zmin, zmax. Or mesh: a Gmsh
    file of hexahedra or tetrahedra whose physical surface groups name the faces
    (exclusive with size and elements). material: a material's name; element: "hex20",
    "hex27" or "tet10"; clamped: faces with every dof fixed; rollers: faces whose normal
    dof is fixed (flat, normal to an axis); free elsewhere (a body held nowhere keeps its
    six rigid-body modes). max_frequency: the modes kept [Hz] (default
    SOLID_MAX_FREQUENCY). stress_radius: the radius [m] of the balls the body's stress is
    averaged over (None: a quarter of the body's smallest extent; docs/model.md section 3.8).
    residual: whether the contacts feel the static residual compliance of the modes above
    max_frequency (docs/model.md section 3.9: in series with Hertz's law, it adds the mesh's
    own compliance under a point load, which grows as the mesh is refined). patch_radius:
    the radius [m] of the disc of surface a contact's force is spread over (0: a point;
    None: a quarter of the body's smallest extent, at least what the mesh resolves).
    rigid_patches: patches of the surface tied rigid (RigidPatch), the paper's rigid layers in 3D.
    rigid_layers: the paper's rigid layers (docs/model.md section 4.2) for a planar packing
    (granules in one plane z = const): `resolve` adds a translation-only rigid patch across
    the solid's z extent at each granule touching it at t = 0, rigid_layer_width [m] wide
    along the face (None: one element edge along y, as in 2D). origin None: placed against
    a [layout]'s packing (its face xmin touching the packing's far side, centred on the
    packing in y and z), else at [0, 0, 0].
    """

    size: tuple[float, float, float] | None = None
    elements: tuple[int, int, int] | None = None
    origin: tuple[float, float, float] | None = None
    mesh: str | None = None
    material: str = "steel"
    element: str = "hex20"
    clamped: tuple[str, ...] = ()
    rollers: tuple[str, ...] = ()
    max_frequency: float = SOLID_MAX_FREQUENCY
    stress_radius: float | None = None
    residual: bool = True
    patch_radius: float | None = None
    rigid_patches: tuple[RigidPatch, ...] = ()
    rigid_layers: bool = False
    rigid_layer_width: float | None = None


@dataclass(frozen=True)
class Load:
    """The half-sine shock of docs/model.md section 5.

    q(y, t) = q0 sin(pi t / T) sin(pi (y - y0) / L) on 0 <= t <= T, y0 <= y <= y0 + L.
    kind: "line" (2D), "force" (3D) or "none"; target: "granules" (push +x on the left
    surface of the loaded granules) or "plate" (consistent nodal forces on the plate's
    left edge); q0 [N/m], duration T [s], length L [m], y0 [m]; granules: labels of the
    loaded granules (empty = every granule touching the leftmost wall, i.e. column 1).
    kind = "force" (3D): a total force F(t) = force sin(pi t / T) [N] along direction
    (any length > 0, normalised by the solver), shared equally by the loaded granules
    (empty `granules`: those whose surface is furthest against the direction,
    `model.loads.force`).
    """

    kind: str = "line"
    target: str = "granules"
    q0: float = 50_000.0
    duration: float = 1e-5
    length: float = 0.05
    y0: float = 0.025
    granules: tuple[str, ...] = ()
    force: float = 0.0
    direction: tuple[float, float, float] = (1.0, 0.0, 0.0)


#: Normal contact laws (`Contact.normal_law`, `PairCoefficients.normal_law`): "hertz",
#: eq. (2)'s elastic law with eq. (3)'s damping; "thornton", Thornton's (1997)
#: elastic-perfectly plastic law (docs/model.md section 3.6), which needs the yield
#: strength Y of every body that can yield at the contact; "johnson", Hertz to yield,
#: then Johnson's expanding-cavity mean pressure over the plastic contact disc up to the
#: hardness, with a rate-dependent yield strength (docs/model.md section 3.10), which needs
#: Y likewise. The names of the laws' registry (setup.law_registry), in its order.
NORMAL_LAWS: tuple[str, ...] = tuple(NORMAL_LAW_IDS)
#: Tangential laws (Contact.tangential_law): "tanh", eq. (5)'s regularised Coulomb law
#: without history (the paper's), and "mindlin", Mindlin's tangential spring 8 G* a with a
#: Coulomb limit mu |N| and each contact's elastic tangential displacement as history
#: (docs/model.md section 3.16; under the scheme "verlet", in the plane and in space, and
#: on the elastic solid in space), and "mindlin_force", the same law in its incremental
#: form with the elastic tangential force as history (LAMMPS's `mindlin_rescale/force`).
#: The names of the laws' registry (setup.law_registry).
TANGENTIAL_LAWS: tuple[str, ...] = tuple(TANGENTIAL_LAW_IDS)


@dataclass(frozen=True)
class PairCoefficients:
    """Contact coefficients for one material pair (order-free), overriding the defaults.

    alpha_n [-], mu [-], k_s [s/m], normal_law (one of NORMAL_LAWS): None keeps the
    `Contact` value.
    """

    materials: tuple[str, str]
    alpha_n: float | None = None
    mu: float | None = None
    k_s: float | None = None
    normal_law: str | None = None

    def matches(self, a: str, b: str) -> bool:
        """Whether this entry is the pair of materials a and b (in either order); a pair
        of one material matches only an entry that names it twice."""
        return {a, b} == set(self.materials) and (a != b or self.materials[0] == self.materials[1])


@dataclass(frozen=True)
class Contact:
    """Contact-law coefficients (docs/model.md sections 2-3).

    mu: Coulomb coefficient [-]; k_s: tanh smoothing [s/m]; alpha_n: damping coefficient
    [-] of eq. (3) for pairs not listed in `pairs`; clip_tensile: the normal force never
    pulls (True, docs/model.md section 3.2) or the paper's raw eq. (2) (False); detection:
    which pairs can touch (docs/model.md section 1.3): "dynamic" finds granule-granule and
    granule-wall contacts as they form and drops them as they open (a Verlet list of pairs
    within (R_i + R_j)(1 + skin), rebuilt when a granule has moved skin * R_min / 2),
    "fixed" keeps the pairs whose initial surface gap is at most neighbour_gap x the
    smaller radius (the paper's fixed topology; an overlap of any other pair stops the
    run); skin [-]: the Verlet list's margin, a fraction of R_i + R_j; neighbour_gap [-]:
    the initial gap, as a fraction of the smaller radius, of the fixed pairs and of the
    plate contacts (fixed in both modes); overlap_warn, overlap_stop [-]: an overlap beyond
    this fraction of the smaller radius warns (Hertz assumes small overlaps) or stops the
    run; overlap_start [-]: the largest overlap of two granules, or of a granule and a
    wall, allowed at t = 0, a fraction of the smaller radius (None: touching, within
    round-off; a poured packing's resolved form sets it to hold its settled contacts,
    at most overlap_warn); normal_law: the normal force law of pairs not listed in `pairs` (one of
    NORMAL_LAWS: "hertz", eq. 2, "thornton", elastic-perfectly plastic, docs/model.md
    section 3.6, or "johnson", elastic-plastic up to the hardness, section 3.10; walls and
    the plate are rigid bodies to it, so a granule-wall or granule-plate contact takes the
    law of the granule's material with the wall's or the plate's, `law_for_pair`); torque_arm: lever arm of the friction torque,
    "radius" (R_i, paper eq. 1, docs/model.md section 3.2) or "contact_point" (R_i - delta/2 for a
    pair, R_i - delta at a wall or plate: the true contact point, which conserves the
    angular momentum of a free assembly; with "radius" each sliding pair adds a couple
    -f delta). The slip rate uses the same arms, so the friction power stays f v_t. "lammps"
    (contact.tangential_law = "mindlin" only): LAMMPS's pair granular, the slip rate at the
    arm R_i and the torque at R_i - delta/2 between spheres (R_i at a wall), for a side by
    side run with LAMMPS; the arms differ, so the couples' extra work is booked in
    D_friction (docs/model.md section 3.16).
    tangential_law: the friction law of every granule-granule, granule-wall and
    granule-plate contact and of the granules' contacts on the elastic solid in space (one
    of TANGENTIAL_LAWS): "tanh", eq. (5), or "mindlin", Mindlin's tangential spring with a
    Coulomb limit mu |N| and history (docs/model.md section 3.16; its mu is `mu` and the
    pairs' mu, k_s unused; in the plane and in space, every scheme), or "mindlin_force", the same
    law in its incremental form (the elastic force as history; where "mindlin" runs);
    tangential_damping: Mindlin's tangential damping x_t [-] (LAMMPS's `mindlin NULL x_t mu`):
    eta_t = x_t c delta^(1/4), x_t times eq. (3)'s normal damping coefficient (0: none).
    """

    mu: float = 0.099
    k_s: float = 1000.0
    alpha_n: float = 6.313e-3
    pairs: tuple[PairCoefficients, ...] = (PairCoefficients(("steel", "ptfe"), alpha_n=6.313e-2),)
    clip_tensile: bool = True
    neighbour_gap: float = 0.05
    torque_arm: str = "radius"
    detection: str = "dynamic"
    skin: float = 0.1
    overlap_warn: float = 0.05
    overlap_stop: float = 0.2
    overlap_start: float | None = None
    normal_law: str = "hertz"
    tangential_law: str = "tanh"
    tangential_damping: float = 0.0

    def for_pair(self, a: str, b: str) -> tuple[float, float, float]:
        """(alpha_n, mu, k_s) for materials a and b."""
        alpha, mu, ks = self.alpha_n, self.mu, self.k_s
        for p in self.pairs:
            if p.matches(a, b):
                alpha = alpha if p.alpha_n is None else p.alpha_n
                mu = mu if p.mu is None else p.mu
                ks = ks if p.k_s is None else p.k_s
        return alpha, mu, ks

    def law_index(self, a: str, b: str) -> int | None:
        """Index in `pairs` of the entry that sets the normal law of materials a and b (the
        last matching one with a normal_law, as `for_pair` lets later entries win), or
        None when the contact default `normal_law` applies."""
        found = None
        for k, p in enumerate(self.pairs):
            if p.normal_law is not None and p.matches(a, b):
                found = k
        return found

    def law_for_pair(self, a: str, b: str) -> str:
        """The normal law (one of NORMAL_LAWS) for materials a and b: the pair's override,
        else `normal_law`. At a granule-wall or granule-plate contact, b is the wall's or
        the plate's material (a rigid body to the law: only the granule's Y matters)."""
        k = self.law_index(a, b)
        law = None if k is None else self.pairs[k].normal_law
        return self.normal_law if law is None else law


@dataclass(frozen=True)
class TimeSettings:
    """Time settings [s]: end time, initial/max/min step, output intervals.

    output_interval: scalar outputs and granule states; field_interval: plate
    displacement snapshots (a multiple of output_interval); sensor_interval: the
    [[sensors]]' samples (None: output_interval), landed on by the steps like the
    output times; restart_interval: the loop's whole state is also stored at the output
    times k restart_interval before t_end (a multiple of output_interval; None: at t_end
    only; docs/how-to/restart.md); contact_interval: the contact table's times, the forces
    of every granule-granule and granule-wall contact in touch (a multiple of
    output_interval; None: every field_interval; 0: no table; docs/output.md).
    """

    t_end: float = 2e-3
    dt_initial: float = 4e-8
    dt_max: float = 4e-8
    dt_min: float = 1e-13
    output_interval: float = 1e-6
    field_interval: float = 2e-5
    sensor_interval: float | None = None
    restart_interval: float | None = None
    contact_interval: float | None = None


@dataclass(frozen=True)
class Solver:
    """Coupling solver settings (docs/model.md section 6).

    scheme: "implicit" (default: Newton on the interface forces with the plate-contact
    friction held over the step, plate modes integrated exactly, step from an error
    estimate; an elastic solid in 3D by a fixed point within each step, section 6.7),
    "paper" (the paper's fixed-point interpolation-iteration with the criterion (8) step
    control; the plane's plate only) or "verlet" (velocity Verlet of the granules and of
    an elastic solid in 3D, not of the plane's plate: one normal-force pass per fixed
    step time.dt_max, friction split off exactly; docs/model.md section 6.5);
    lambda_target: the local-map modulus the step control aims for (< 1);
    iteration_rtol, iteration_atol [N]: convergence of the interface forces;
    max_iterations: per step before the step is retried at half size;
    energy_tol: the largest relative energy residual a run accepts;
    error_tol: "implicit" scheme, the local error (relative distance of the interface
    forces and the granules' net forces from their extrapolation) the step control aims
    at; the step is also held to an energy-residual growth of energy_tol / 2 over the run;
    energy_span: "implicit" scheme, the simulated time [s] over which that growth is spread
    (None: time.t_end); a run continued from a result (--from) takes the straight run's
    steps when both legs give it the straight run's t_end;
    implicit_dt_max: "implicit" scheme, the largest step [s] (rounded down to
    time.output_interval / 2^k; time.dt_max bounds the "paper" scheme);
    granular_friction: friction at granule-granule and granule-wall contacts, "split"
    (a step too large for RK4 on it takes it apart: exact friction half steps around RK4
    of the other forces) or "rk4" (always in RK4, the step cut to keep RK4 stable on it);
    threads: how many cores the "verlet" scheme's loop uses (an integer from 1 to the
    machine's cores; absent: every core for an assembly of at least PARALLEL_MIN_GRANULES
    granules, else 1; 1: the serial loop; docs/model.md section 6.6);
    verlet_damping: the velocities the "verlet" scheme's force pass reads at t + h, so its
    contact damping: "predicted" (absent: the default; v + h/2 a_n, second order) or "half_step"
    (v at t + h/2, LAMMPS's `fix nve/sphere`: the same algorithm as LAMMPS's, step for
    step; docs/model.md section 6.5).
    """

    scheme: str = "implicit"
    lambda_target: float = 0.5
    iteration_rtol: float = 1e-9
    iteration_atol: float = 1e-10
    max_iterations: int = 60
    energy_tol: float = 1e-4
    error_tol: float = 1e-3
    implicit_dt_max: float = 1e-6
    granular_friction: str = "split"
    threads: int | None = None
    energy_span: float | None = None
    verlet_damping: str | None = None


#: What a drive prescribes along its direction (`Drive.kind`).
DRIVE_KINDS: tuple[str, ...] = ("displacement", "velocity", "force")
#: How a precompressing wall behaves during the run (Precompression.mode).
PRECOMPRESSION_MODES: tuple[str, ...] = ("frozen", "held")
#: The two kinds of body a drive moves (`Drive.target` = "wall LABEL" or "granule LABEL").
DRIVE_TARGETS: tuple[str, ...] = ("wall", "granule")


@dataclass(frozen=True)
class Gravity:
    """A uniform body force on every granule: the acceleration g [m/s^2], [gx, gy] in the
    plane, [gx, gy, gz] in space (docs/model.md section 3.11)."""

    g: tuple[float, ...] = ()


@dataclass(frozen=True)
class Precompression:
    """Static precompression before t = 0 (docs/model.md section 3.12): the wall `target`
    ("wall LABEL") is pushed into the assembly with the force `force` [N] along its inward
    normal and the granules (with gravity, if given, and the other walls fixed) are brought
    to static equilibrium, to a residual force of `tolerance` x force on every granule and
    on the wall, in at most `max_iterations` steps of the minimiser. mode: "frozen" (the wall
    then stays where equilibrium left it: displacement-controlled during the run) or "held"
    (the wall becomes a piston of mass `mass` [kg] pushed by the constant force `force`: a
    servo that keeps holding it, force-controlled; solver.scheme = "verlet"). mass: the held
    wall's mass [kg], read with mode = "held" only; 0 (the default): the granules' total
    mass."""

    target: str = ""
    force: float = 0.0
    mode: str = "frozen"
    tolerance: float = 1e-8
    max_iterations: int = 20000
    mass: float = 0.0


@dataclass(frozen=True)
class Drive:
    """Prescribed motion of a wall or a granule, or a prescribed force on either, along
    a unit `direction` (docs/model.md section 3.11).

    target: "wall LABEL" or "granule LABEL" (the `label` of a [[walls]] or [[granules]]
    entry, or of a wall or granule a layout made); kind: "displacement" [m], "velocity"
    [m/s] or "force" [N] along the direction; profile: the time profile P(t) of that
    quantity, with its fields: "constant" (value), "ramp" (value reached at duration,
    held after), "half-sine" (amplitude sin(pi t / duration) over the duration, 0 after),
    "harmonic" (value + amplitude sin(2 pi frequency t)), "table" (linear between the
    points times [s], values; the first value before them, the last after; or read from
    the CSV `file` of two columns, time and value, which the reader turns into times and
    values), "chirp" (amplitude sin(phi(t)) over the duration, its frequency swept linearly
    from `frequency` to `frequency_end` [Hz], held at its last value after; a displacement or
    a force). A displacement drive moves its body by P(t) - P(0) from where the scenario
    puts it; a velocity drive sets the body's velocity along the direction to P(t) from
    t = 0 on. A force drive on a wall makes it a rigid piston of mass `mass` [kg] (required
    there, read nowhere else) moving along its normal, pushed by P(t) and by its contacts
    (solver.scheme = "verlet"). label: the drive's name in the Dataset (default: the target).
    """

    target: str
    kind: str = "velocity"
    direction: tuple[float, ...] = ()
    profile: str = "constant"
    value: float = 0.0
    amplitude: float = 0.0
    frequency: float = 0.0
    duration: float = 0.0
    frequency_end: float = 0.0
    times: tuple[float, ...] = ()
    values: tuple[float, ...] = ()
    file: str | None = None
    label: str = ""
    mass: float = 0.0

    @property
    def name(self) -> str:
        """The drive's name in the Dataset: its label, or its target."""
        return self.label or self.target


@dataclass(frozen=True)
class Sensor:
    """A force sensor embedded in a granule (docs/model.md section 3.15): it reads half
    the sum of the normal contact forces on that granule [N], every time.sensor_interval.

    granule: the `label` of a [[granules]] entry (or of a granule a layout made; an
    unlabelled granule's label is its 1-based index, "3"); name: the sensor's name in the
    Dataset (default: the granule's label).
    """

    granule: str
    name: str = ""

    @property
    def label(self) -> str:
        """The sensor's name in the Dataset: its name, or its granule's label."""
        return self.name or self.granule


@dataclass(frozen=True)
class Restart:
    """A run that goes on from a result's stored state (docs/how-to/restart.md): `result`,
    the result netCDF file (a path relative to the scenario file's folder; the scenario as
    read holds it joined to that folder), and `time` [s], one of its stored restart times
    (absent: the last). The command line's `--from` and `--from-time` override them."""

    result: str = ""
    time: float | None = None


@dataclass(frozen=True)
class Scenario:
    """A complete run definition. Either `layout` or explicit `granules`/`walls`.

    dimension: 2 (discs in the plane, the paper's model; the default) or 3 (spheres in
    space: granules, walls and an optional `box`, or a 3D `layout`; no plate yet).
    granules_file: the file the granules were read from (`granules_file = "PATH"`, as the
    scenario gives it; setup.granules_file), so that messages name its rows and columns;
    None for [[granules]] tables. Not part of the scenario's value: a scenario read from a
    file equals the same one given as tables, and is written as tables (`io.to_dict`).
    gravity: a body force on every granule (None: none); drives: prescribed motions of
    walls and granules and prescribed forces on granules (docs/model.md section 3.11);
    precompression: the static state the run starts from (None: as given; section 3.12);
    sensors: force sensors in granules, sampled every time.sensor_interval (section 3.15);
    restart: the result the run goes on from (None: a run from t = 0; docs/how-to/restart.md).
    """

    name: str = "custom"
    description: str = ""
    materials: dict[str, Material] = field(default_factory=lambda: dict(LIBRARY))
    layout: Layout | LatticeLayout | ChainLayout | SpaceLattice | PouredLayout | None = None
    granules: tuple[Granule, ...] = ()
    walls: tuple[Wall, ...] = ()
    plate: Plate | Solid | None = None
    load: Load = Load()
    contact: Contact = Contact()
    time: TimeSettings = TimeSettings()
    solver: Solver = Solver()
    dimension: int = 2
    box: Box | None = None
    granules_file: str | None = field(default=None, compare=False)
    gravity: Gravity | None = None
    drives: tuple[Drive, ...] = ()
    precompression: Precompression | None = None
    sensors: tuple[Sensor, ...] = ()
    restart: Restart | None = None

    def material(self, name: str) -> Material:
        """The material called `name` (file-defined ones override the library)."""
        return self.materials[name]


SQRT2_MINUS_1 = math.sqrt(2.0) - 1.0
