"""Layouts in space (sc, bcc, fcc, hcp lattices, chains, intruders, imperfections): geometry
against the textbook lattices and closed forms, validation messages, reproducible seeds, the
resolve round trip, the examples and a short run."""

from __future__ import annotations

import dataclasses
import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from granplate.cli import main
from granplate.errors import ScenarioError
from granplate.setup import io as scenario_io
from granplate.setup.geometry import layout_packing, resolve
from granplate.setup.scenario import BOX_WALLS, Box, ChainLayout, Imperfections, Layer, Load, Scenario, SpaceLattice
from granplate.setup.validate import OVERLAP_RTOL, validate

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "docs" / "examples").glob("3d-*.toml"))
R = 0.01
REL = 1e-12
#: Touching neighbours in the bulk and sites per conventional cell (textbook values).
BULK_NEIGHBOURS = {"sc": 6, "bcc": 8, "fcc": 12, "hcp": 12}
SITES_PER_CELL = {"sc": 1, "bcc": 2, "fcc": 4, "hcp": 4}
KINDS = tuple(BULK_NEIGHBOURS)


def _centres(granules) -> np.ndarray:
    return np.array([(g.x, g.y, g.z) for g in granules], float)


def _force_scenario(lay, **kw) -> Scenario:
    return Scenario(dimension=3, layout=lay, load=Load(kind="force", force=10.0), **kw)


def _textbook_lattice(kind: str, r: float, n: int) -> np.ndarray:
    """Points of the infinite lattice of spheres of radius r (n cells each way from the origin),
    written from the textbook bases (x the stacking axis), independently of the package."""
    if kind in ("sc", "bcc", "fcc"):
        a = {"sc": 2.0 * r, "bcc": 4.0 * r / math.sqrt(3.0), "fcc": 2.0 * math.sqrt(2.0) * r}[kind]
        basis = {
            "sc": [(0, 0, 0)],
            "bcc": [(0, 0, 0), (0.5, 0.5, 0.5)],
            "fcc": [(0, 0, 0), (0, 0.5, 0.5), (0.5, 0, 0.5), (0.5, 0.5, 0)],
        }[kind]
        cells = np.array(list(itertools.product(range(-n, n + 1), repeat=3)), float)
        return np.concatenate([(cells + np.array(b)) * a for b in basis])
    a, c = 2.0 * r, 4.0 * math.sqrt(2.0 / 3.0) * r  # hcp: triangular nets in (y, z), ABAB along x
    a1, a2 = np.array([a, 0.0]), np.array([a / 2.0, math.sqrt(3.0) * a / 2.0])
    ij = np.array(list(itertools.product(range(-4 * n, 4 * n + 1), repeat=2)), float)
    net = ij[:, :1] * a1 + ij[:, 1:] * a2
    points = []
    for layer in range(-n, 2 * n + 1):
        shift = (a1 + a2) / 3.0 if layer % 2 else np.zeros(2)
        yz = net + shift
        points.append(np.column_stack([np.full(len(yz), layer * c / 2.0), yz]))
    return np.concatenate(points)


@pytest.mark.parametrize("kind", KINDS)
def test_lattice_sites_are_the_textbook_lattice(kind):
    """Every site of a 4 x 3 x 3 packing lies on the textbook lattice (to 1e-12 R), one sphere per
    site, sites per cell x cells of them."""
    lay = SpaceLattice(kind=kind, cells=(4, 3, 3), radius=R)
    gs = layout_packing(lay).granules
    assert len(gs) == SITES_PER_CELL[kind] * 4 * 3 * 3
    x = _centres(gs)
    x -= x[0]  # site x1y1z1 at the origin of the textbook lattice
    dist, _ = cKDTree(_textbook_lattice(kind, R, 6)).query(x)
    assert dist.max() < 1e-12 * R
    assert cKDTree(x).query(x, k=2)[0][:, 1].min() > R  # no two spheres on one site


@pytest.mark.parametrize("kind", KINDS)
def test_bulk_neighbours_touch_at_2r(kind):
    """In a 5 x 5 x 5 packing the nearest neighbours are 2R apart (1e-12 relative, well within
    validation's 1e-9 R), each bulk sphere has 6 (sc), 8 (bcc), 12 (fcc, hcp) of them, and no
    other sphere comes within 1.1 x 2R."""
    gs = layout_packing(SpaceLattice(kind=kind, cells=(5, 5, 5), radius=R)).granules
    x = _centres(gs)
    tree = cKDTree(x)
    d, _ = tree.query(x, k=2)
    assert np.abs(d[:, 1] - 2.0 * R).max() <= REL * 2.0 * R
    touching = np.array([len(n) - 1 for n in tree.query_ball_point(x, 2.0 * R * (1.0 + 1e-9))])
    near = np.array([len(n) - 1 for n in tree.query_ball_point(x, 2.2 * R)])
    np.testing.assert_array_equal(touching, near)
    lo, hi = x.min(axis=0) + 2.0 * R * (1 - 1e-9), x.max(axis=0) - 2.0 * R * (1 - 1e-9)
    bulk = np.all((x >= lo) & (x <= hi), axis=1)
    assert bulk.sum() >= 8
    assert set(touching[bulk]) == {BULK_NEIGHBOURS[kind]}
    assert touching.max() == BULK_NEIGHBOURS[kind]


@pytest.mark.parametrize(
    "kind,edge",
    [("sc", 2.0), ("bcc", 4.0 / math.sqrt(3.0)), ("fcc", 2.0 * math.sqrt(2.0)), ("hcp", 4.0 * math.sqrt(2.0 / 3.0))],
)
def test_cell_edge_along_x(kind, edge):
    """The conventional cell's edge along x: 2R (sc), 4R / sqrt(3) (bcc), 2 sqrt(2) R (fcc),
    c = 4 sqrt(2/3) R (hcp), between a site and the same site one cell further."""
    g = {g.label: g for g in layout_packing(SpaceLattice(kind=kind, cells=(3, 1, 1), radius=R)).granules}
    step = 1 if kind == "sc" else 2
    assert g[f"x{1 + step}y1z1"].x - g["x1y1z1"].x == pytest.approx(edge * R, rel=REL)
    assert (g[f"x{1 + step}y1z1"].y, g[f"x{1 + step}y1z1"].z) == (g["x1y1z1"].y, g["x1y1z1"].z)


@pytest.mark.parametrize("kind", KINDS)
def test_box_walls_touch_the_outermost_spheres(kind):
    """The six walls (BOX_WALLS, in order) touch the outermost surfaces, no sphere crosses one,
    the lowest surfaces are at x = y = z = 0, and the packing validates."""
    lay = SpaceLattice(kind=kind, cells=(3, 2, 2), radius=R)
    p = layout_packing(lay)
    assert [w.label for w in p.walls] == list(BOX_WALLS)
    x = _centres(p.granules)
    radii = np.array([g.radius for g in p.granules])
    for w in p.walls:
        gaps = w.offset - x @ np.array(w.normal) - radii
        assert gaps.min() == pytest.approx(0.0, abs=REL * R), w.label
    np.testing.assert_allclose((x - radii[:, None]).min(axis=0), 0.0, atol=REL * R)
    validate(_force_scenario(lay))


def test_walls_subset_opens_the_other_sides():
    """layout.walls keeps only the walls named, in the box's order."""
    p = layout_packing(SpaceLattice(kind="sc", cells=(2, 2, 2), walls=("zmax", "xmin")))
    assert [w.label for w in p.walls] == ["xmin", "zmax"]


def _plane_of(label: str) -> int:
    return int(label[1 : label.index("y")])


#: The paper's stack in space: heavy / light-intruder / heavy, one cell each.
STACK = SpaceLattice(
    kind="fcc",
    cells=(3, 3, 3),
    radius=R,
    layers=(Layer(1), Layer(1, radius=0.8 * R, material="ptfe"), Layer(1, material="steel")),
)


def test_layers_set_radii_and_materials_plane_by_plane():
    """Planes 1-2 and 5-6 are steel of R, planes 3-4 PTFE of 0.8 R; the x spacing of planes of
    radii R_p, R_q is sqrt((R_p + R_q)^2 - 2 R^2) (fcc: rho = sqrt(2) R), so each sphere touches
    4 spheres in each neighbouring plane (a heavy one 4 in its own plane too), and nothing overlaps."""
    gs = layout_packing(STACK).granules
    for g in gs:
        light = _plane_of(g.label) in (3, 4)
        assert (g.radius, g.material) == ((0.8 * R, "ptfe") if light else (R, "steel")), g.label
    xs = {}
    for g in gs:
        xs.setdefault(_plane_of(g.label), set()).add(g.x)
    assert all(len(v) == 1 for v in xs.values())
    xs = [xs[p].pop() for p in range(1, 7)]
    radii = [R, R, 0.8 * R, 0.8 * R, R, R]
    for p in range(5):
        d = math.sqrt((radii[p] + radii[p + 1]) ** 2 - 2.0 * R**2)
        assert xs[p + 1] - xs[p] == pytest.approx(d, rel=REL)
    x = _centres(gs)
    r = np.array([g.radius for g in gs])
    tree = cKDTree(x)
    for i, j in tree.query_pairs(2.0 * R * (1 + 1e-9)):
        assert np.linalg.norm(x[i] - x[j]) >= (r[i] + r[j]) * (1 - OVERLAP_RTOL)
    by_label = {g.label: k for k, g in enumerate(gs)}

    def touching_planes(label):
        c = by_label[label]
        return sorted(
            _plane_of(gs[j].label)
            for j in tree.query_ball_point(x[c], 2.0 * R * (1 + 1e-9))
            if j != c and abs(np.linalg.norm(x[j] - x[c]) - r[j] - r[c]) < REL * R
        )

    assert touching_planes("x3y3z2") == [2] * 4 + [4] * 4  # light: loose in its own plane
    assert touching_planes("x2y3z2") == [1] * 4 + [2] * 4 + [3] * 4  # heavy: 12 neighbours
    validate(_force_scenario(STACK))


def test_layers_counts_give_the_cells_along_x_when_cells0_is_zero():
    """cells[0] = 0 with layers builds exactly the packing of cells[0] = the counts' sum, so a
    study can vary one layer's count alone."""
    import dataclasses

    two = SpaceLattice(
        kind="fcc", cells=(0, 2, 2), radius=R, layers=(Layer(2), Layer(1, radius=0.8 * R, material="ptfe"), Layer(1))
    )
    assert layout_packing(two) == layout_packing(dataclasses.replace(two, cells=(4, 2, 2)))
    assert len(layout_packing(two).granules) == 4 * 4 * 2 * 2
    validate(_force_scenario(two))


def test_single_site_intruders_shrink_at_their_centres():
    """intruder_sites and intruder_every shrink exactly the chosen sites (radius x ratio, material),
    at their centres."""
    base = SpaceLattice(kind="bcc", cells=(2, 2, 2), radius=R)
    perfect = {g.label: g for g in layout_packing(base).granules}
    lay = dataclasses.replace(
        base, intruder_sites=("x2y1z1",), intruder_every=5, intruder_ratio=0.5, intruder_material="ptfe"
    )
    gs = layout_packing(lay).granules
    order = [g.label for g in gs]
    chosen = {"x2y1z1"} | {order[k - 1] for k in range(5, len(order) + 1, 5)}
    for g in gs:
        p = perfect[g.label]
        assert (g.x, g.y, g.z) == (p.x, p.y, p.z)
        assert (g.radius, g.material) == ((0.5 * R, "ptfe") if g.label in chosen else (R, "steel"))
    validate(_force_scenario(lay))


def test_chain_in_space_touches_between_two_walls():
    """A tapered, decorated dimer chain in 3D: consecutive spheres touch along x at y = z = R_max
    (or the given y, z), radii as in 2D, walls xmin and xmax touch the ends."""
    lay = ChainLayout(count=5, radius=R, taper=0.9, dimer_ratio=0.6, dimer_material="ptfe", decorated_ratio=0.3)
    p = layout_packing(lay, dimension=3)
    flat = layout_packing(lay)
    gs = p.granules
    assert [(g.label, g.x, g.radius, g.material) for g in gs] == [
        (g.label, g.x, g.radius, g.material) for g in flat.granules
    ]
    assert all(g.y == g.z == R for g in gs)
    for a, b in zip(gs[:-1], gs[1:]):
        assert b.x - a.x == pytest.approx(a.radius + b.radius, rel=REL)
    assert [(w.label, w.normal) for w in p.walls] == [("xmin", (-1.0, 0.0, 0.0)), ("xmax", (1.0, 0.0, 0.0))]
    assert gs[0].x - gs[0].radius == 0.0 and p.walls[1].offset == gs[-1].x + gs[-1].radius
    placed = layout_packing(dataclasses.replace(lay, y=0.03, z=-0.02), dimension=3).granules
    assert all((g.y, g.z) == (0.03, -0.02) for g in placed)
    validate(_force_scenario(lay))


IMPERFECT = SpaceLattice(
    kind="fcc",
    cells=(4, 4, 4),
    radius=R,
    imperfections=Imperfections(seed=3, radius_spread=0.05, jitter=0.03, vacancy_fraction=0.1),
)


def test_imperfections_reproducible_and_seed_dependent():
    """The same seed gives the same spheres; another seed other spheres."""
    a = layout_packing(IMPERFECT).granules
    assert layout_packing(IMPERFECT).granules == a
    other = dataclasses.replace(IMPERFECT, imperfections=dataclasses.replace(IMPERFECT.imperfections, seed=4))
    assert layout_packing(other).granules != a


def test_imperfections_stay_in_their_balls():
    """Each imperfect sphere lies inside its perfect site's ball, radius in [R (1 - jitter - spread),
    R (1 - jitter)], its centre within jitter R; the jitter fills the ball uniformly (the mean of
    (|d| / (jitter R))^3 is 1/2 for a uniform ball, 1/3 ... per axis: all three axes move);
    round(fraction x n) sites are removed; nothing overlaps; it validates."""
    perfect = {g.label: g for g in layout_packing(dataclasses.replace(IMPERFECT, imperfections=None)).granules}
    gs = layout_packing(IMPERFECT).granules
    assert len(gs) == len(perfect) - round(0.1 * len(perfect))
    moves = []
    for g in gs:
        p = perfect[g.label]
        assert R * (1 - 0.08) <= g.radius <= R * (1 - 0.03)
        d = np.array([g.x - p.x, g.y - p.y, g.z - p.z])
        assert np.linalg.norm(d) + g.radius <= p.radius * (1 + REL)
        moves.append(d)
    moves = np.array(moves) / (0.03 * R)
    assert np.mean(np.linalg.norm(moves, axis=1) ** 3) == pytest.approx(0.5, abs=0.06)
    assert np.all(np.abs(moves).mean(axis=0) > 0.2)  # every axis jitters
    x = _centres(gs)
    r = np.array([g.radius for g in gs])
    for i, j in cKDTree(x).query_pairs(2.0 * R):
        assert np.linalg.norm(x[i] - x[j]) >= r[i] + r[j]
    validate(_force_scenario(IMPERFECT))


def test_zero_imperfections_and_vacancies_and_the_loaded_plane():
    """Zero amplitudes give the perfect packing back; listed vacancies are removed; resolve gives a
    force along +x plane 1's remaining labels (not along another direction)."""
    zero = dataclasses.replace(IMPERFECT, imperfections=Imperfections(seed=5))
    assert layout_packing(zero).granules == layout_packing(dataclasses.replace(IMPERFECT, imperfections=None)).granules
    holes = dataclasses.replace(
        IMPERFECT, cells=(2, 2, 2), imperfections=Imperfections(seed=5, jitter=0.01, vacancies=("x1y1z1", "x3y2z2"))
    )
    labels = [g.label for g in layout_packing(holes).granules]
    assert "x1y1z1" not in labels and "x3y2z2" not in labels and len(labels) == 32 - 2
    r = resolve(_force_scenario(holes))
    plane1 = tuple(lab for lab in labels if lab.startswith("x1y"))
    assert r.load.granules == plane1 and len(plane1) == 7
    sideways = resolve(
        Scenario(dimension=3, layout=holes, load=Load(kind="force", force=1.0, direction=(0.0, 0.0, 1.0)))
    )
    assert sideways.load.granules == ()


@pytest.mark.parametrize(
    "lay",
    [STACK, IMPERFECT, SpaceLattice(kind="hcp", walls=("xmin",)), ChainLayout(count=3, z=0.05)],
    ids=["stack", "imperfect", "hcp", "chain"],
)
def test_toml_round_trip_and_resolve(lay):
    """dumps then loads gives the same scenario; the resolved scenario, written and read back,
    validates and holds the layout's spheres and walls."""
    s = _force_scenario(lay)
    assert scenario_io.loads(scenario_io.dumps(s)) == s
    r = resolve(s)
    back = scenario_io.loads(scenario_io.dumps(r))
    assert back == r and back.layout is None
    validate(back)
    p = layout_packing(lay, dimension=3)
    assert back.granules == p.granules and back.walls == p.walls


def test_resolve_command_writes_granules_and_walls(tmp_path, capsys):
    """`granplate resolve` of a 3D example prints [[granules]] with z and vector omega, and the
    walls as planes; -o writes the same text."""
    path = ROOT / "docs" / "examples" / "3d-fcc.toml"
    assert main(["resolve", str(path)]) == 0
    printed = capsys.readouterr().out
    s = scenario_io.loads(printed)
    assert s.dimension == 3 and s.layout is None and len(s.granules) == 4 * 27
    assert [w.label for w in s.walls] == list(BOX_WALLS) and len(s.walls[0].normal) == 3
    out = tmp_path / "r.toml"
    assert main(["resolve", str(path), "-o", str(out)]) == 0
    assert out.read_text() == printed


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_examples_validate_and_are_3d(path):
    """Every docs/examples/3d-*.toml validates as a 3D layout with a force load (a poured
    packing: struck by a granule with an initial velocity instead)."""
    s = scenario_io.load_scenario(str(path))
    assert s.dimension == 3 and s.layout is not None
    if s.layout.kind == "poured":
        assert s.load.kind == "none" and any(g.vx > 0.0 for g in s.granules)
    else:
        assert s.load.kind == "force"


def test_one_example_per_kind():
    """docs/examples has a 3D example of every space lattice kind, of the chain and of a
    poured packing."""
    kinds = {scenario_io.load(p).layout.kind for p in EXAMPLES}
    assert kinds == set(KINDS) | {"chain", "poured"}


def test_short_run_of_the_stack_balances_energy():
    """2 us of a force on plane 1 of a small sc stack (steel / PTFE / steel): energy residual below
    1e-6, the loaded plane moves along +x, the far plane has not moved yet at that time."""
    from granplate.results.run import simulate

    lay = SpaceLattice(kind="sc", cells=(3, 2, 2), radius=0.005, layers=(Layer(1), Layer(1, material="ptfe"), Layer(1)))
    s = _force_scenario(lay)
    validate(s)
    ds = simulate(s, t_end=2e-6, progress=False)
    assert float(np.abs(ds.energy_residual_max).max()) < 1e-6
    labels = [str(v) for v in ds.granule.values]
    first = [k for k, lab in enumerate(labels) if lab.startswith("x1y")]
    assert float(ds.vx[-1, first].min()) > 0.0


def _lay3(**kw):
    return lambda: validate(_force_scenario(SpaceLattice(**kw)))


BAD = [
    (
        "3D kind in 2D",
        lambda: validate(Scenario(layout=SpaceLattice(kind="hcp"))),
        "layout.kind",
        "a lattice of spheres in space is 3D",
    ),
    (
        "chain depth in 2D",
        lambda: validate(Scenario(layout=ChainLayout(z=0.01))),
        "layout.z",
        "a chain's depth z is 3D",
    ),
    (
        "unknown kind",
        lambda: scenario_io.loads('dimension = 3\n[layout]\nkind = "diamond"\n'),
        "layout.kind",
        "'sc', 'bcc', 'fcc', 'hcp'",
    ),
    (
        "2D field on a space lattice",
        lambda: scenario_io.loads('dimension = 3\n[layout]\nkind = "sc"\nrows = 3\n'),
        "layout.rows",
        "unknown field 'layout.rows'",
    ),
    (
        "cells length",
        lambda: scenario_io.loads('dimension = 3\n[layout]\nkind = "sc"\ncells = [2, 2]\n'),
        "layout.cells",
        "wrong length",
    ),
    ("zero cells", _lay3(cells=(2, 0, 2)), "layout.cells[1]", "must be an integer >= 1"),
    ("too many sites", _lay3(cells=(100, 100, 100)), "layout.cells", "at most 1000000 sites"),
    ("radius", _lay3(radius=-1.0), "layout.radius", "must be > 0"),
    ("material", _lay3(material="wood"), "layout.material", "unknown material"),
    ("wall material", _lay3(wall_material="wood"), "layout.wall_material", "unknown material"),
    (
        "layer count",
        _lay3(cells=(2, 2, 2), layers=(Layer(0), Layer(2))),
        "layout.layers[0].count",
        "must be an integer >= 1",
    ),
    (
        "layer radius",
        _lay3(cells=(2, 2, 2), layers=(Layer(1, radius=0.0), Layer(1))),
        "layout.layers[0].radius",
        "must be > 0",
    ),
    (
        "layer material",
        _lay3(cells=(2, 2, 2), layers=(Layer(1), Layer(1, material="wood"))),
        "layout.layers[1].material",
        "unknown material",
    ),
    (
        "layer radius ratio",
        _lay3(kind="sc", cells=(2, 2, 2), layers=(Layer(1, radius=1e-9), Layer(1, radius=1.0))),
        "layout.layers[0].radius",
        "of the largest layer radius",
    ),
    (
        "layer counts",
        _lay3(cells=(3, 2, 2), layers=(Layer(1), Layer(1))),
        "layout.layers",
        "add up to layout.cells[0] = 3",
    ),
    ("no cells along x without layers", _lay3(cells=(0, 2, 2)), "layout.cells[0]", "must be an integer >= 1"),
    (
        "planes cannot touch",
        _lay3(kind="fcc", cells=(3, 2, 2), layers=(Layer(1), Layer(1, radius=0.5 * R), Layer(1))),
        "layout.layers[1].radius",
        "planes 3 and 4 cannot touch",
    ),
    (
        "planes overlap",
        _lay3(kind="bcc", cells=(2, 2, 2), layers=(Layer(1, radius=1.1 * R), Layer(1))),
        "layout.layers[1].radius",
        "overlap by",
    ),
    ("wall name", _lay3(walls=("xmin", "top")), "layout.walls[1]", "must be one of 'xmin'"),
    ("wall twice", _lay3(walls=("xmin", "xmin")), "layout.walls[1]", "each wall at most once"),
    ("intruder ratio", _lay3(intruder_ratio=0.0), "layout.intruder_ratio", "must be > 0"),
    ("intruder material", _lay3(intruder_material="wood"), "layout.intruder_material", "unknown material"),
    ("intruder site", _lay3(intruder_sites=("c1r1",)), "layout.intruder_sites[0]", "no such site"),
    (
        "large site intruder",
        _lay3(intruder_every=2, intruder_ratio=1.5),
        "layout.intruder_ratio",
        "must be in (0, 1] with intruder_sites or intruder_every",
    ),
    ("intruder every", _lay3(intruder_every=-1), "layout.intruder_every", "must be an integer >= 0"),
    (
        "vacancy",
        _lay3(imperfections=Imperfections(vacancies=("x9y9z9",))),
        "layout.imperfections.vacancies[0]",
        "no such site",
    ),
    ("jitter", _lay3(imperfections=Imperfections(jitter=1.0)), "layout.imperfections.jitter", "must be in [0, 1)"),
    (
        "layout and box",
        lambda: validate(_force_scenario(SpaceLattice(), box=Box((0, 0, 0), (1, 1, 1)))),
        "box",
        "give either [layout] or [box]",
    ),
    ("chain z", lambda: validate(_force_scenario(ChainLayout(z=math.inf))), "layout.z", "must be a finite number"),
]


@pytest.mark.parametrize("action,field,allowed", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_3d_layouts_are_refused_naming_field_and_range(action, field, allowed):
    """Each bad 3D layout raises one ScenarioError naming the field and the allowed range."""
    with pytest.raises(ScenarioError) as e:
        action()
    assert e.value.field == field
    assert allowed in str(e.value) and "\n" not in str(e.value)


def test_every_3d_layout_field_is_documented():
    """docs/scenario.md has a table row for every field of the space lattice and of its layers."""
    doc = (ROOT / "docs" / "scenario.md").read_text()
    for cls in (SpaceLattice, Layer, ChainLayout):
        for f in dataclasses.fields(cls):
            assert f"| `{f.name}` |" in doc, (cls.__name__, f.name)
