"""Layout kinds (hexagonal, square, chain, intruders, imperfections): geometry against truth,
validation messages, reproducible seeds, the resolve command, the examples and a short run."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from granplate.cli import main
from granplate.errors import ScenarioError
from granplate.model.arrays import build_model
from granplate.setup import io as scenario_io
from granplate.setup.geometry import layout_packing, paper_layout, resolve
from granplate.setup.presets import preset
from granplate.setup.scenario import ChainLayout, Imperfections, LatticeLayout, Layout, Load, Plate, Scenario
from granplate.setup.validate import validate

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"
REL = 1e-12


def _dist(a, b):
    return math.hypot(a.x - b.x, a.y - b.y)


def _by_label(granules):
    return {g.label: g for g in granules}


def _touch(a, b):
    """a and b touch: centre distance = R_a + R_b to 1e-12 relative."""
    return _dist(a, b) == pytest.approx(a.radius + b.radius, rel=REL, abs=0.0)


def _no_overlaps(granules):
    for i, a in enumerate(granules):
        for b in granules[i + 1 :]:
            assert _dist(a, b) >= (a.radius + b.radius) * (1.0 - REL), (a.label, b.label)


def _expected_lattice_pairs(lay: LatticeLayout) -> set[tuple[str, str]]:
    """The touching pairs a perfect lattice must have, from its topology alone."""
    radii = (
        [lay.radius * (lay.intruder_ratio if c + 1 in lay.intruder_columns else 1.0) for c in range(lay.columns)]
        if not lay.column_radii
        else list(lay.column_radii)
    )
    a = max(radii)
    hexagonal = lay.kind == "hexagonal"
    n_rows = [lay.rows - 1 if hexagonal and c % 2 == 0 else lay.rows for c in range(1, lay.columns + 1)]
    pairs = set()
    for c in range(1, lay.columns + 1):
        if radii[c - 1] == a:  # vertical neighbours touch in the columns of the largest radius
            pairs |= {(f"c{c}r{k}", f"c{c}r{k + 1}") for k in range(1, n_rows[c - 1])}
        if c == lay.columns:
            continue
        if not hexagonal:
            pairs |= {(f"c{c}r{k}", f"c{c + 1}r{k}") for k in range(1, lay.rows + 1)}
        elif c % 2:  # odd c (rows), even c + 1 (rows - 1): even row k between odd rows k, k+1
            pairs |= {(f"c{c}r{k + d}", f"c{c + 1}r{k}") for k in range(1, lay.rows) for d in (0, 1)}
        else:
            pairs |= {(f"c{c}r{k}", f"c{c + 1}r{k + d}") for k in range(1, lay.rows) for d in (0, 1)}
    return pairs


def _touching_pairs(granules) -> set[tuple[str, str]]:
    out = set()
    for i, a in enumerate(granules):
        for b in granules[i + 1 :]:
            if _dist(a, b) <= (a.radius + b.radius) * (1.0 + 1e-9):
                out.add((a.label, b.label))
    return out


LATTICES = [
    LatticeLayout(kind="hexagonal", columns=3, rows=5),
    LatticeLayout(kind="hexagonal", columns=6, rows=4, radius=0.002),
    LatticeLayout(
        kind="hexagonal",
        columns=5,
        rows=5,
        column_radii=(0.01, 0.008, 0.01, 0.006, 0.009),
        column_materials=("steel", "ptfe", "steel", "ptfe", "steel"),
    ),
    LatticeLayout(
        kind="hexagonal", columns=5, rows=6, intruder_columns=(2, 4), intruder_ratio=0.5, intruder_material="ptfe"
    ),
    LatticeLayout(kind="square", columns=4, rows=3),
    LatticeLayout(kind="square", columns=4, rows=5, column_radii=(0.01, 0.007, 0.012, 0.005)),
]


@pytest.mark.parametrize("lay", LATTICES, ids=lambda l: f"{l.kind}-{l.columns}x{l.rows}")
def test_lattice_neighbours_touch_exactly_and_nothing_else(lay):
    """Every expected neighbour pair is at distance R_i + R_j (1e-12 relative), no pair overlaps,
    and the touching pairs are exactly the expected ones."""
    gs = layout_packing(lay).granules
    g = _by_label(gs)
    expected = _expected_lattice_pairs(lay)
    for a, b in expected:
        assert _touch(g[a], g[b]), (a, b)
    _no_overlaps(gs)
    assert _touching_pairs(gs) == expected


@pytest.mark.parametrize("lay", LATTICES, ids=lambda l: f"{l.kind}-{l.columns}x{l.rows}")
def test_lattice_counts_walls_and_plate(lay):
    """Granule count per kind; the left, bottom and top walls and the plate touch the outermost
    granules and no granule crosses them; the plate touches the last column."""
    p = layout_packing(lay)
    gs = p.granules
    odd, even = (lay.columns + 1) // 2, lay.columns // 2
    n = lay.columns * lay.rows if lay.kind == "square" else odd * lay.rows + even * (lay.rows - 1)
    assert len(gs) == n
    assert [w.label for w in p.walls] == ["left", "bottom", "top"]
    r_max = max(g.radius for g in gs)
    for w in p.walls:
        gaps = [w.offset - (g.x * w.normal[0] + g.y * w.normal[1]) - g.radius for g in gs]
        assert min(gaps) == pytest.approx(0.0, abs=REL * r_max), w.label
    plate_gaps = {g.label: p.plate_x - g.x - g.radius for g in gs}
    assert min(plate_gaps.values()) >= -REL * r_max
    last = [lab for lab in plate_gaps if lab.startswith(f"c{lay.columns}r")]
    widest = max(_by_label(gs)[lab].radius for lab in last)
    for lab in last:
        if _by_label(gs)[lab].radius == widest:
            assert plate_gaps[lab] == pytest.approx(0.0, abs=REL * r_max), lab
    assert p.column1 == tuple(g.label for g in gs if g.label.startswith("c1r"))


@pytest.mark.parametrize("ratio", [math.sqrt(2.0) - 1.0, 0.5, 0.75, 1.0])
def test_paper_packing_is_an_intruder_lattice(ratio):
    """A 3 x 5 hexagonal lattice with intruder column 2 gives exactly paper_layout's granules
    (positions, radii, materials bitwise; labels c1r1.. for 1..9, A..E) and plate x."""
    paper, walls, xp = paper_layout(Layout(R2_ratio=ratio, heavy_material="steel", intruder_material="ptfe"))
    lattice = layout_packing(
        LatticeLayout(
            columns=3, rows=5, radius=0.01, intruder_columns=(2,), intruder_ratio=ratio, intruder_material="ptfe"
        )
    )
    assert [(g.x, g.y, g.radius, g.material) for g in lattice.granules] == [
        (g.x, g.y, g.radius, g.material) for g in paper
    ]
    assert lattice.plate_x == xp
    assert [w.normal for w in lattice.walls] == [w.normal for w in walls]
    assert [w.offset for w in lattice.walls] == pytest.approx([w.offset for w in walls], rel=REL)


def test_hexagonal_column_offsets_follow_the_radii():
    """With column radii R_c, the x distance of columns c, c+1 is sqrt((R_c + R_c+1)^2 - a^2), a = max R."""
    radii = (0.01, 0.008, 0.01, 0.006, 0.009)
    gs = _by_label(layout_packing(LatticeLayout(columns=5, rows=5, column_radii=radii)).granules)
    for c in range(1, 5):
        dx = gs[f"c{c + 1}r1"].x - gs[f"c{c}r1"].x
        assert dx == pytest.approx(math.sqrt((radii[c - 1] + radii[c]) ** 2 - 0.01**2), rel=REL)


def test_single_site_intruders():
    """intruder_sites and intruder_every shrink exactly the chosen sites (radius x ratio, material),
    at their centres."""
    base = LatticeLayout(columns=3, rows=4)
    perfect = _by_label(layout_packing(base).granules)
    lay = dataclasses.replace(
        base, intruder_sites=("c1r2",), intruder_every=4, intruder_ratio=0.5, intruder_material="ptfe"
    )
    gs = layout_packing(lay).granules
    order = [g.label for g in gs]
    chosen = {"c1r2"} | {order[k - 1] for k in range(4, len(order) + 1, 4)}
    for g in gs:
        p = perfect[g.label]
        assert (g.x, g.y) == (p.x, p.y)
        assert (g.radius, g.material) == ((0.005, "ptfe") if g.label in chosen else (0.01, "steel"))


def _chain(**kw):
    return layout_packing(ChainLayout(**kw))


def test_chain_touches_tapers_and_alternates():
    """A chain's consecutive spheres touch on y = R_max; radii follow taper^(k-1) x dimer_ratio
    for even k, materials alternate; the wall and the plate touch the ends."""
    p = _chain(count=7, radius=0.01, taper=0.9, dimer_ratio=0.6, dimer_material="ptfe")
    gs = p.granules
    assert [g.label for g in gs] == [f"c{k}" for k in range(1, 8)]
    for k, g in enumerate(gs):
        assert g.radius == pytest.approx(0.01 * 0.9**k * (0.6 if k % 2 else 1.0), rel=REL)
        assert g.material == ("ptfe" if k % 2 else "steel")
        assert g.y == 0.01
    for a, b in zip(gs[:-1], gs[1:]):
        assert _touch(a, b)
    _no_overlaps(gs)
    assert [w.label for w in p.walls] == ["left"] and gs[0].x - gs[0].radius == 0.0
    assert p.plate_x == pytest.approx(gs[-1].x + gs[-1].radius, rel=REL)
    assert p.column1 == ("c1",)


def test_decorated_chain():
    """A decorated chain puts a sphere of decorated_ratio x R_k between k and k+1, all touching."""
    gs = _chain(count=4, radius=0.01, decorated_ratio=0.25, decorated_material="ptfe", y=0.05).granules
    assert [g.label for g in gs] == ["c1", "d1", "c2", "d2", "c3", "d3", "c4"]
    assert [g.radius for g in gs] == [0.01, 0.0025] * 3 + [0.01]
    assert {g.material for g in gs if g.label.startswith("d")} == {"ptfe"}
    assert all(g.y == 0.05 for g in gs)
    for a, b in zip(gs[:-1], gs[1:]):
        assert _touch(a, b)
    _no_overlaps(gs)


IMPERFECT = LatticeLayout(
    columns=6,
    rows=6,
    radius=0.01,
    imperfections=Imperfections(seed=11, radius_spread=0.05, jitter=0.03, vacancy_fraction=0.1),
)


def test_imperfections_reproducible_and_seed_dependent():
    """The same seed gives the same granules; a different seed different ones."""
    a = layout_packing(IMPERFECT).granules
    assert layout_packing(IMPERFECT).granules == a
    other = dataclasses.replace(IMPERFECT, imperfections=dataclasses.replace(IMPERFECT.imperfections, seed=12))
    assert layout_packing(other).granules != a


def test_imperfections_stay_in_their_sites():
    """Each imperfect granule lies inside its perfect site's disc, with radius in
    [R (1 - jitter - spread), R (1 - jitter)]; round(fraction x n) sites are removed; no overlaps."""
    perfect = _by_label(layout_packing(dataclasses.replace(IMPERFECT, imperfections=None)).granules)
    gs = layout_packing(IMPERFECT).granules
    assert len(gs) == len(perfect) - round(0.1 * len(perfect))
    for g in gs:
        p = perfect[g.label]
        assert p.radius * (1 - 0.08) <= g.radius <= p.radius * (1 - 0.03)
        assert _dist(g, p) <= 0.03 * p.radius * (1 + REL)
        assert _dist(g, p) + g.radius <= p.radius * (1 + REL)
    _no_overlaps(gs)
    validate(Scenario(layout=IMPERFECT))


def test_zero_imperfections_and_explicit_vacancies():
    """Zero amplitudes give back the perfect packing; listed vacancies are removed, also from the
    loaded column, which resolve hands to the load."""
    zero = dataclasses.replace(IMPERFECT, imperfections=Imperfections(seed=5))
    assert layout_packing(zero).granules == layout_packing(dataclasses.replace(IMPERFECT, imperfections=None)).granules
    holes = dataclasses.replace(IMPERFECT, imperfections=Imperfections(seed=5, vacancies=("c1r2", "c3r3")))
    labels = {g.label for g in layout_packing(holes).granules}
    assert "c1r2" not in labels and "c3r3" not in labels and len(labels) == 6 * 6 - 3 - 2
    r = resolve(Scenario(layout=holes))
    assert r.load.granules == ("c1r1", "c1r3", "c1r4", "c1r5", "c1r6")


def test_paper_layout_with_imperfections():
    """Imperfections apply to the paper's kind too (labels 1..9, A..E), and keep its walls and plate x."""
    lay = Layout(R2_ratio=0.5, imperfections=Imperfections(seed=1, radius_spread=0.02, vacancies=("7",)))
    p = layout_packing(lay)
    _, walls, xp = paper_layout(Layout(R2_ratio=0.5))
    assert [g.label for g in p.granules] == list("12345689ABCDE")
    assert p.walls == walls and p.plate_x == xp
    validate(Scenario(layout=lay, plate=Plate()))


# --------------------------------------------------------------------------- validation


def _lat(**kw):
    return lambda: validate(Scenario(layout=LatticeLayout(**kw)))


def _chn(**kw):
    return lambda: validate(Scenario(layout=ChainLayout(**kw)))


def _imp(**kw):
    return lambda: validate(Scenario(layout=LatticeLayout(imperfections=Imperfections(**kw))))


BAD = [
    (
        "unknown kind",
        lambda: scenario_io.loads('[layout]\nkind = "cubic"\n'),
        "layout.kind",
        "must be one of 'paper', 'hexagonal', 'square', 'chain'",
    ),
    ("kind of the wrong class", _lat(kind="chain"), "layout.kind", "must have kind one of"),
    (
        "chain field on a lattice",
        lambda: scenario_io.loads('[layout]\nkind = "square"\ncount = 3\n'),
        "layout.count",
        "unknown field 'layout.count'",
    ),
    ("zero columns", _lat(columns=0), "layout.columns", "must be an integer >= 1"),
    ("one hexagonal row", _lat(rows=1), "layout.rows", "must be an integer >= 2"),
    ("negative radius", _lat(radius=-0.01), "layout.radius", "must be > 0"),
    ("unknown material", _lat(material="wood"), "layout.material", "unknown material"),
    ("unknown wall material", _lat(wall_material="wood"), "layout.wall_material", "unknown material"),
    (
        "column_radii length",
        _lat(columns=3, column_radii=(0.01, 0.01)),
        "layout.column_radii",
        "must be empty or a list of 3 values",
    ),
    ("column radius zero", _lat(columns=2, column_radii=(0.01, 0.0)), "layout.column_radii[1]", "must be > 0"),
    (
        "column_materials length",
        _lat(columns=2, column_materials=("steel",)),
        "layout.column_materials",
        "must be empty or a list of 2 values",
    ),
    (
        "column material unknown",
        _lat(columns=2, column_materials=("steel", "wood")),
        "layout.column_materials[1]",
        "unknown material",
    ),
    ("intruder ratio zero", _lat(intruder_ratio=0.0), "layout.intruder_ratio", "must be > 0"),
    ("intruder material", _lat(intruder_material="wood"), "layout.intruder_material", "unknown material"),
    (
        "intruder column out of range",
        _lat(columns=3, intruder_columns=(4,)),
        "layout.intruder_columns[0]",
        "must be a column number in 1..3",
    ),
    (
        "intruder column rule",
        _lat(columns=3, intruder_columns="evn"),
        "layout.intruder_columns",
        "must be one of 'odd', 'even' (did you mean 'even'?)",
    ),
    ("intruder every negative", _lat(intruder_every=-1), "layout.intruder_every", "must be an integer >= 0"),
    ("intruder site unknown", _lat(intruder_sites=("c2r5",)), "layout.intruder_sites[0]", "no such site"),
    (
        "site intruder larger than its site",
        _lat(intruder_sites=("c1r1",), intruder_ratio=1.5),
        "layout.intruder_ratio",
        "must be in (0, 1] with intruder_sites or intruder_every",
    ),
    (
        "columns cannot touch",
        _lat(columns=3, column_radii=(0.002, 0.002, 0.01)),
        "layout.column_radii",
        "columns 1 and 2 cannot touch",
    ),
    (
        "intruder column too small",
        _lat(columns=3, intruder_columns=(2,), intruder_ratio=0.3),
        "layout.intruder_ratio",
        "columns 1 and 3 overlap",
    ),
    ("chain count", _chn(count=0), "layout.count", "must be an integer >= 1"),
    ("chain radius", _chn(radius=0.0), "layout.radius", "must be > 0"),
    ("chain taper", _chn(taper=0.0), "layout.taper", "must be > 0"),
    ("chain dimer ratio", _chn(dimer_ratio=-1.0), "layout.dimer_ratio", "must be > 0"),
    ("chain decoration", _chn(decorated_ratio=-0.1), "layout.decorated_ratio", "must be >= 0"),
    ("chain dimer material", _chn(dimer_material="wood"), "layout.dimer_material", "unknown material"),
    ("chain decoration material", _chn(decorated_material="wood"), "layout.decorated_material", "unknown material"),
    ("chain y", _chn(y=math.inf), "layout.y", "must be a finite number"),
    ("seed negative", _imp(seed=-1), "layout.imperfections.seed", "must be an integer >= 0"),
    ("spread 1", _imp(radius_spread=1.0), "layout.imperfections.radius_spread", "must be in [0, 1)"),
    ("jitter negative", _imp(jitter=-0.1), "layout.imperfections.jitter", "must be in [0, 1)"),
    ("vacancy fraction", _imp(vacancy_fraction=1.0), "layout.imperfections.vacancy_fraction", "must be in [0, 1)"),
    (
        "spread + jitter",
        _imp(radius_spread=0.6, jitter=0.5),
        "layout.imperfections.jitter",
        "radius_spread + jitter must be < 1",
    ),
    ("unknown vacancy", _imp(vacancies=("c9r9",)), "layout.imperfections.vacancies[0]", "no such site"),
    (
        "layout and granules",
        lambda: validate(dataclasses.replace(resolve(Scenario(layout=LatticeLayout())), layout=LatticeLayout())),
        "granules",
        "either [layout] or [[granules]]",
    ),
]


@pytest.mark.parametrize("action,field,allowed", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_layouts_are_refused_naming_field_and_range(action, field, allowed):
    """Each bad layout raises ScenarioError naming the field and the allowed range."""
    with pytest.raises(ScenarioError) as e:
        action()
    assert e.value.field == field
    assert allowed in str(e.value)


# --------------------------------------------------------------------------- TOML, resolve, examples

KINDS = [Layout(R2_ratio=0.5), *LATTICES, ChainLayout(count=5, taper=0.8, decorated_ratio=0.2), IMPERFECT]


@pytest.mark.parametrize("columns,numbers", [(3, (2,)), (5, (2, 4)), (6, (2, 4, 6))])
def test_even_intruder_columns_are_the_listed_even_columns(columns, numbers):
    """intruder_columns = "even" builds the packing of the even column numbers listed, and a
    scenario file carries the rule through a round trip (so a study varies columns alone)."""
    kw = dict(kind="hexagonal", columns=columns, rows=5, radius=0.01, intruder_ratio=0.5, intruder_material="ptfe")
    assert layout_packing(LatticeLayout(intruder_columns="even", **kw)) == layout_packing(
        LatticeLayout(intruder_columns=numbers, **kw)
    )
    s = Scenario(layout=LatticeLayout(intruder_columns="even", **kw))
    assert scenario_io.loads(scenario_io.dumps(s)) == s
    validate(s)


@pytest.mark.parametrize("lay", KINDS, ids=lambda l: l.kind)
def test_toml_round_trip_every_kind(lay):
    """dumps then loads gives the same scenario for every kind (kind written except for "paper")."""
    s = Scenario(layout=lay)
    text = scenario_io.dumps(s)
    assert scenario_io.loads(text) == s
    layout_text = text[text.index("[layout]") : text.index("[load]")]
    assert ("kind =" in layout_text) == (lay.kind != "paper")


def test_preset_output_has_no_kind_line():
    """`granplate preset` output is unchanged: the paper's layout writes no kind line."""
    assert 'kind = "paper"' not in scenario_io.dumps(preset("steel-r1"))


def _same_model(a, b):
    ma, mb = build_model(a), build_model(b)
    assert ma.labels == mb.labels
    np.testing.assert_array_equal(ma.initial_state, mb.initial_state)
    for f in (
        "mass",
        "inertia",
        "radius",
        "pair_ij",
        "pair_coef",
        "wall_i",
        "wall_geo",
        "wall_coef",
        "pc_i",
        "pc_x",
        "shock_force",
        "shock_torque",
    ):
        np.testing.assert_array_equal(getattr(ma.granular, f), getattr(mb.granular, f), err_msg=f)


@pytest.mark.parametrize("name", sorted(p.name for p in EXAMPLES.glob("*.toml") if "[layout]" in p.read_text()))
def test_examples_load_validate_and_resolve_to_the_same_model(name, tmp_path, capsys):
    """Every docs/examples file with a [layout] validates, and `granplate resolve` of it (printed
    TOML, and -o) builds the same granule arrays as the layout."""
    path = EXAMPLES / name
    s = scenario_io.load_scenario(str(path))
    assert s.layout is not None
    assert main(["resolve", str(path)]) == 0
    printed = capsys.readouterr().out
    explicit = scenario_io.loads(printed)
    assert explicit.layout is None and explicit.granules
    _same_model(s, explicit)
    out = tmp_path / "resolved.toml"
    assert main(["resolve", str(path), "-o", str(out)]) == 0
    assert out.read_text() == printed


def test_resolve_a_preset():
    """`granplate resolve steel-r05` prints the 14 granules and three walls of the preset."""
    from granplate.commands.resolve import resolved_toml

    s = scenario_io.loads(resolved_toml("steel-r05"))
    assert [g.label for g in s.granules] == list("123456789ABCDE")
    assert [w.label for w in s.walls] == ["left", "bottom", "top"]
    _same_model(preset("steel-r05"), s)


def test_short_run_of_a_small_hexagonal_protector_balances_energy():
    """A 4 x 3 hexagonal protector (steel and PTFE columns) against the plate, shocked for 2e-5 s:
    E_p + E_g + D = E_shock (energy residual below 1e-4)."""
    from granplate.results.run import simulate

    s = Scenario(
        layout=LatticeLayout(columns=4, rows=3, radius=0.01, column_materials=("steel", "ptfe", "steel", "ptfe")),
        plate=Plate(height=0.06, ny=24),
        load=Load(y0=0.01, length=0.04),
    )
    validate(s)
    ds = simulate(s, t_end=2e-5, progress=False)
    assert float(ds.E_shock[-1]) > 0
    assert float(np.abs(ds.energy_residual_max).max()) < 1e-4


def test_every_layout_field_is_documented():
    """docs/scenario.md has a table row for every field of every layout kind and of the imperfections."""
    from granplate.setup.scenario import LAYOUT_KINDS

    doc = (Path(__file__).resolve().parents[1] / "docs" / "scenario.md").read_text()
    for cls in {*LAYOUT_KINDS.values(), Imperfections}:
        for f in dataclasses.fields(cls):
            assert f"| `{f.name}` |" in doc, (cls.__name__, f.name)
