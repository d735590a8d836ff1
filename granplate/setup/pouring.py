"""A poured packing, `[layout] kind = "poured"` (docs/scenario.md, "Poured packings";
docs/model.md section 3.14): its fields' checks, the seeded radii, the container's walls,
the loose column the granules are dropped from, and the settled packing read from the
run store.

The settling itself needs the time loop, a layer above this one: `results.pouring`
registers it here (`register_settler`) when it is imported, which `import granplate`
(the package's root, and so any import of granplate) does. `poured_packing` asks the run store first and settles only what it
does not hold.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any, Callable

import numpy as np

from granplate import store
from granplate.errors import ScenarioError
from granplate.setup.fields import is_number, positive, string_in
from granplate.setup import deposition
from granplate.setup.scenario import BOX_WALLS, POURED_DISTRIBUTIONS, POURED_DROPS, PouredLayout, Scenario, Wall

#: The run store's kind and format of a settled packing.
STORE_KIND = "poured"
STORE_FORMAT = 1
#: The loose column's cell: (1 + CELL_GAP) x the largest diameter a side; each granule is
#: moved at random within the room its cell leaves it.
CELL_GAP = 0.2
#: The fractions of a discrete distribution sum to 1 within this.
FRACTION_TOL = 1e-9
#: A poured layout's radii [m] (as every layout's: setup.validate.LAYOUT_RADIUS_RANGE).
RADIUS_RANGE = (1e-9, 1e3)
#: The container's sides at most this many largest radii (the loose column's cells are counted).
CONTAINER_MAX = 1e4
#: The most granules a poured packing may hold.
COUNT_MAX = 1_000_000
#: The largest settling friction coefficient (Mindlin's mu, layout.settle_friction).
SETTLE_FRICTION_MAX = 2.0
#: The largest softening of a ramped settling (layout.settle_softening: the first phase's
#: stiffness is the real law's over it).
SETTLE_SOFTENING_MAX = 1e6
#: A truncated normal or lognormal draw gives up after this many rounds of redraws.
REDRAW_ROUNDS = 1000

#: The settler `results.pouring` registers: (scenario, layout) -> settled arrays.
_SETTLER: list[Callable[[Scenario, PouredLayout], dict[str, np.ndarray]]] = []


def register_settler(settle: Callable[[Scenario, PouredLayout], dict[str, np.ndarray]]) -> None:
    """Make `settle` the function that settles a packing the store does not hold."""
    _SETTLER[:] = [settle]


def check_poured(s: Scenario, lay: PouredLayout) -> None:
    """The poured layout's fields, each refused by name (ScenarioError) before anything runs."""
    c = lay.count
    if not (isinstance(c, int) and not isinstance(c, bool) and 1 <= c <= COUNT_MAX):
        raise ScenarioError("layout.count", c, f"must be an integer in [1, {COUNT_MAX}]")
    rr = lay.radius_range
    if not (isinstance(rr, tuple) and len(rr) == 2 and all(is_number(v) for v in rr)):
        raise ScenarioError("layout.radius_range", rr, "must be two numbers [min, max] [m]")
    for k in (0, 1):
        positive(f"layout.radius_range[{k}]", rr[k])
        if not RADIUS_RANGE[0] <= rr[k] <= RADIUS_RANGE[1]:
            raise ScenarioError(
                f"layout.radius_range[{k}]", rr[k], f"allowed: {RADIUS_RANGE[0]:g} m <= radius <= {RADIUS_RANGE[1]:g} m"
            )
    if not rr[0] <= rr[1]:
        raise ScenarioError("layout.radius_range", list(rr), "must be [min, max] with min <= max")
    string_in("layout.distribution", lay.distribution, POURED_DISTRIBUTIONS)
    string_in("layout.drop", lay.drop, POURED_DROPS)
    _check_distribution(lay)
    if not (isinstance(lay.seed, int) and not isinstance(lay.seed, bool) and lay.seed >= 0):
        raise ScenarioError("layout.seed", lay.seed, "must be an integer >= 0")
    for f in ("material", "wall_material"):
        if getattr(lay, f) not in s.materials:
            raise ScenarioError(f"layout.{f}", getattr(lay, f), "must name a material of the library or [materials]")
    if lay.container:
        if not (isinstance(lay.container, tuple) and len(lay.container) == s.dimension):
            raise ScenarioError("layout.container", lay.container, f"must be {s.dimension} lengths [m] (or left out)")
        for k, v in enumerate(lay.container):
            positive(f"layout.container[{k}]", v)
            if not v <= CONTAINER_MAX * rr[1]:
                raise ScenarioError(f"layout.container[{k}]", v, f"allowed: <= {CONTAINER_MAX:g} x radius_range[1]")
            if not v >= 2.0 * rr[1]:
                raise ScenarioError(f"layout.container[{k}]", v, "must hold the largest granule: >= 2 radius_range[1]")
    pour_gravity(s, lay)
    positive("layout.settle_tolerance", lay.settle_tolerance)
    if not lay.settle_tolerance < 1.0:
        raise ScenarioError("layout.settle_tolerance", lay.settle_tolerance, "must be in (0, 1)")
    positive("layout.settle_damping", lay.settle_damping)
    if not lay.settle_damping <= 2.0:
        raise ScenarioError("layout.settle_damping", lay.settle_damping, "must be in (0, 2] (alpha_n of eq. 3)")
    positive("layout.settle_time", lay.settle_time)
    f = lay.settle_friction
    if not (is_number(f) and 0.0 <= f <= SETTLE_FRICTION_MAX):
        raise ScenarioError(
            "layout.settle_friction", f, f"must be in [0, {SETTLE_FRICTION_MAX:g}] (Mindlin's mu; 0: off)"
        )
    if f > 0.0 and s.dimension != 3:
        raise ScenarioError(
            "layout.settle_friction", f, "Mindlin's friction runs in space: dimension = 3 (0 in the plane)"
        )
    _check_ramp(s, lay)


def _check_ramp(s: Scenario, lay: PouredLayout) -> None:
    """settle_softening in [1, SETTLE_SOFTENING_MAX] (above 1: the ramped settling, in
    space) and settle_residual in (0, 1]."""
    k = lay.settle_softening
    if not (is_number(k) and 1.0 <= k <= SETTLE_SOFTENING_MAX):
        raise ScenarioError(
            "layout.settle_softening", k, f"must be in [1, {SETTLE_SOFTENING_MAX:g}] (1: the time loop's settling)"
        )
    if k > 1.0 and s.dimension != 3:
        raise ScenarioError(
            "layout.settle_softening", k, "the ramped settling runs in space: dimension = 3 (1 in the plane)"
        )
    r = lay.settle_residual
    if not (is_number(r) and 0.0 < r <= 1.0):
        raise ScenarioError(
            "layout.settle_residual", r, "must be in (0, 1] (a granule's residual force over its weight)"
        )


def _check_distribution(lay: PouredLayout) -> None:
    """The fields the distribution reads: sizes and fractions (discrete), mean and std."""
    lo, hi = lay.radius_range
    if lay.distribution == "discrete":
        sz, fr = lay.sizes, lay.fractions
        if not (isinstance(sz, tuple) and sz and all(is_number(v) and v > 0 for v in sz)):
            raise ScenarioError("layout.sizes", sz, "must be one or more radii > 0 [m] (distribution = 'discrete')")
        if not (isinstance(fr, tuple) and len(fr) == len(sz) and all(is_number(v) and v >= 0 for v in fr)):
            raise ScenarioError("layout.fractions", fr, f"must be {len(sz)} number fractions >= 0, one per size")
        if not abs(math.fsum(fr) - 1.0) <= FRACTION_TOL:
            raise ScenarioError("layout.fractions", list(fr), f"must sum to 1 (they sum to {math.fsum(fr):.12g})")
        if not all(lo <= v <= hi for v in sz):
            raise ScenarioError("layout.sizes", list(sz), f"must lie in radius_range [{lo:g}, {hi:g}] m")
    elif lay.distribution in ("normal", "lognormal"):
        positive("layout.mean", lay.mean)
        positive("layout.std", lay.std)
        if not lo <= lay.mean <= hi:
            raise ScenarioError("layout.mean", lay.mean, f"must lie in radius_range [{lo:g}, {hi:g}] m (the cut)")


def pour_gravity(s: Scenario, lay: PouredLayout) -> tuple[float, ...]:
    """The gravity g [m/s^2] the packing settles under: layout.g, else [gravity] g; one
    nonzero component (along an axis: that axis' wall is the floor)."""
    g = lay.g if lay.g else (s.gravity.g if s.gravity is not None else ())
    path = "layout.g" if lay.g else "gravity.g"
    if not g:
        raise ScenarioError(
            "layout.g", [], "a poured packing settles under gravity: give layout.g or [gravity] g [m/s^2]"
        )
    if not (isinstance(g, tuple) and len(g) == s.dimension and all(is_number(v) and math.isfinite(v) for v in g)):
        raise ScenarioError(path, g, f"must be {s.dimension} finite numbers [m/s^2]")
    if sum(1 for v in g if v != 0.0) != 1:
        raise ScenarioError(path, list(g), "a poured packing needs gravity along one axis (one nonzero component)")
    return tuple(float(v) for v in g)


def floor_axis(g: tuple[float, ...]) -> tuple[int, float]:
    """(axis, sign): gravity points along +-e_axis; sign +1 when it points to +e_axis."""
    axis = next(k for k, v in enumerate(g) if v != 0.0)
    return axis, math.copysign(1.0, g[axis])


def _truncated(rng: np.random.Generator, draw: Callable[[int], np.ndarray], n: int, lo: float, hi: float) -> np.ndarray:
    """n draws of `draw` inside [lo, hi] (those outside drawn again)."""
    out = np.empty(0)
    for _ in range(REDRAW_ROUNDS):
        x = draw(n - len(out))
        out = np.concatenate([out, x[(x >= lo) & (x <= hi)]])
        if len(out) == n:
            return out
    raise ScenarioError("layout.radius_range", [lo, hi], "holds too little of the distribution: widen the cut")


def poured_radii(lay: PouredLayout) -> np.ndarray:
    """The count radii [m], numpy.random.default_rng(seed): uniform in radius_range, the
    discrete sizes with their number fractions (rounded counts, largest remainders first,
    shuffled), or a normal / lognormal of the radius' mean and std cut to radius_range."""
    rng = np.random.default_rng(lay.seed)
    lo, hi, n = float(lay.radius_range[0]), float(lay.radius_range[1]), lay.count
    if lay.distribution == "uniform":
        return rng.uniform(lo, hi, n) if hi > lo else np.full(n, lo)
    if lay.distribution == "discrete":
        want = np.asarray(lay.fractions, float) * n
        counts = np.floor(want).astype(int)
        for k in np.argsort(-(want - counts), kind="stable")[: n - counts.sum()]:
            counts[k] += 1
        return rng.permutation(np.repeat(np.asarray(lay.sizes, float), counts))
    m, sd = float(lay.mean), float(lay.std)
    if lay.distribution == "normal":
        return _truncated(rng, lambda k: rng.normal(m, sd, k), n, lo, hi)
    s2 = math.log1p((sd / m) ** 2)  # lognormal of mean m and std sd: sigma^2, mu below
    return _truncated(rng, lambda k: rng.lognormal(math.log(m) - 0.5 * s2, math.sqrt(s2), k), n, lo, hi)


def container_size(lay: PouredLayout, dimension: int) -> tuple[float, ...]:
    """The container's sides [m]: layout.container, else ceil(count^(1/d)) cells of the
    loose column a side."""
    if lay.container:
        return tuple(float(v) for v in lay.container)
    side = math.ceil(lay.count ** (1.0 / dimension)) * cell_size(lay)
    return (side,) * dimension


def cell_size(lay: PouredLayout) -> float:
    """The loose column's cell [m]: (1 + CELL_GAP) x the largest diameter."""
    return 2.0 * float(lay.radius_range[1]) * (1.0 + CELL_GAP)


def container_walls(lay: PouredLayout, dimension: int, g: tuple[float, ...]) -> tuple[Wall, ...]:
    """The box [0, container] without its side facing up (against g), labelled as a
    [box]'s walls ("xmin", "xmax", ...), of wall_material."""
    size = container_size(lay, dimension)
    axis, sign = floor_axis(g)
    walls = []
    for k in range(dimension):
        e = tuple(1.0 if j == k else 0.0 for j in range(dimension))
        for side, label in ((-1.0, BOX_WALLS[2 * k]), (1.0, BOX_WALLS[2 * k + 1])):
            if k == axis and side == -sign:
                continue  # open to gravity's source
            walls.append(
                Wall(tuple(side * v for v in e), 0.0 if side < 0 else size[k], label=label, material=lay.wall_material)
            )
    return tuple(walls)


def loose_column(lay: PouredLayout, dimension: int, g: tuple[float, ...], radii: np.ndarray) -> np.ndarray:
    """(count, dimension) centres [m]: cells of `cell_size` filling the container's
    footprint layer by layer up from the floor (against g), each granule moved at random
    (seeded) within its cell's room, so that none touches another or a wall."""
    rng = np.random.default_rng([lay.seed, 1])
    size, h = container_size(lay, dimension), cell_size(lay)
    axis, sign = floor_axis(g)
    across = [k for k in range(dimension) if k != axis]
    per = [max(1, int(size[k] // h)) for k in across]
    n = len(radii)
    idx = np.arange(n)
    layer, rest = divmod(idx, int(np.prod(per)))
    centres = np.empty((n, dimension))
    room = h / 2.0 - radii  # how far a granule may move off its cell's centre
    for j, k in enumerate(across):
        cell = rest % per[j]
        rest = rest // per[j]
        offset = 0.5 * (size[k] - per[j] * h)
        centres[:, k] = offset + (cell + 0.5) * h + rng.uniform(-1.0, 1.0, n) * room
    height = (layer + 0.5) * h + rng.uniform(-1.0, 1.0, n) * room
    centres[:, axis] = height if sign < 0 else size[axis] - height
    return centres


def dropped(lay: PouredLayout, dimension: int, g: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    """(centres where the settling starts, centres the granules were released from) (count,
    dimension) [m] of `poured_radii(lay)`: the loose column (both the same), or for drop =
    "sequential" the granules deposited one by one (`setup.deposition.deposit`: at rest on
    the pile, each released just above it). Copies of the last few computed."""
    centres, release = _dropped(lay, dimension, tuple(g))
    return centres.copy(), release.copy()


def clear_dropped() -> None:
    """Forget the packings `dropped` keeps (a benchmark times them afresh)."""
    _dropped.cache_clear()


@functools.lru_cache(maxsize=4)
def _dropped(lay: PouredLayout, dimension: int, g: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    radii = poured_radii(lay)
    if lay.drop == "sequential":
        axis, sign = floor_axis(g)
        centres, release, _ = deposition.deposit(radii, container_size(lay, dimension), axis, sign, lay.seed)
        return centres, release
    c = loose_column(lay, dimension, g, radii)
    return c, c


def settles_ramped(s: Scenario, lay: PouredLayout) -> bool:
    """Whether the ramped settling's kernel settles `lay` (`results.ramped`, in space): with
    settle_softening > 1, or a sequential drop in space (its fall skipped)."""
    return lay.settle_softening > 1.0 or (lay.drop == "sequential" and s.dimension == 3)


def store_payload(s: Scenario, lay: PouredLayout) -> dict[str, Any]:
    """What a settled packing depends on: the layout, the dimension, gravity, the
    materials of granules and walls, and the scenario's contact coefficients (a layout
    without settle_friction, or without settle_softening, keys as before those fields existed)."""
    layout = dataclasses.asdict(lay)
    if not lay.settle_friction:
        del layout["settle_friction"]
    if lay.settle_softening == 1.0 and not settles_ramped(s, lay):  # keyed as before the ramped settling
        del layout["settle_softening"], layout["settle_residual"]
    if lay.drop == "column":  # keyed as before the sequential drop
        del layout["drop"]
    return {
        "layout": layout,
        "dimension": s.dimension,
        "g": list(pour_gravity(s, lay)),
        "materials": {m: dataclasses.asdict(s.material(m)) for m in {lay.material, lay.wall_material}},
        "contact": dataclasses.asdict(dataclasses.replace(s.contact, overlap_start=None)),
    }


def settled_arrays(s: Scenario, lay: PouredLayout) -> dict[str, np.ndarray]:
    """The settled packing's arrays ("centres" (count, d) [m], "radii" [m], "overlap" the
    largest overlap over the smaller radius [-]): from the run store, else settled by the
    registered settler (which stores them)."""
    found = store.load_arrays(STORE_KIND, store_payload(s, lay), STORE_FORMAT)
    if found is not None:
        return found
    if not _SETTLER:
        raise ScenarioError(
            "layout.kind",
            "poured",
            "the settled packing is not in the run store and no settler is loaded: "
            "register one (granplate.results.pouring does when imported, as `import granplate` does)",
        )
    return _SETTLER[0](s, lay)


def poured_granules(s: Scenario, lay: PouredLayout) -> tuple[tuple, tuple[Wall, ...], float, float]:
    """(granules "p1".."pN" at rest where they settled, the container's walls, the plate's
    x0 (the container's side along x: with a [plate], the wall "xmax" is left out and the
    plate takes its place), the largest overlap at rest over the smaller radius [-])."""
    from granplate.setup.scenario import Granule

    arrays = settled_arrays(s, lay)
    c, r = np.asarray(arrays["centres"], float), np.asarray(arrays["radii"], float)
    z = c[:, 2] if s.dimension == 3 else np.zeros(len(r))
    granules = tuple(
        Granule(float(c[i, 0]), float(c[i, 1]), float(r[i]), lay.material, label=f"p{i + 1}", z=float(z[i]))
        for i in range(len(r))
    )
    walls = container_walls(lay, s.dimension, pour_gravity(s, lay))
    if s.plate is not None:
        walls = tuple(w for w in walls if w.label != "xmax")
    return granules, walls, container_size(lay, s.dimension)[0], float(np.asarray(arrays["overlap"]).max(initial=0.0))
