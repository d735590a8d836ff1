"""Scenario input: TOML/dict reading, validation messages, round trips (docs/scenario.md)."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import pytest

from granplate.setup import io as scenario_io
from granplate.errors import ScenarioError
from granplate.setup.materials import LIBRARY, Material
from granplate.setup.presets import preset
from granplate.setup.scenario import Granule, Load, PairCoefficients, Plate, Scenario, Solver, TimeSettings, Wall
from granplate.setup.validate import SCHEMES, validate

DOC = Path(__file__).resolve().parents[1] / "docs" / "scenario.md"


def _two_spheres(**changes) -> Scenario:
    """Two steel spheres flying at each other, no plate, no load."""
    s = Scenario(
        name="two-spheres",
        granules=(Granule(0.0, 0.0, 0.01, "steel", "a", vx=1.0), Granule(0.03, 0.0, 0.01, "steel", "b", vx=-1.0)),
        load=Load(kind="none"),
    )
    return dataclasses.replace(s, **changes)


def _with(changes):
    return lambda: validate(scenario_io.with_changes(preset("steel-r1"), changes))


def _granules(*gs, walls=()):
    return lambda: validate(_two_spheres(granules=gs, walls=walls))


def _toml(text, validated=False):
    if validated:
        return lambda: validate(scenario_io.loads(text))
    return lambda: scenario_io.loads(text)


STEEL = "steel"
BAD = [
    # (id, action, field path in the message, allowed range in the message)
    (
        "zero radius",
        _granules(Granule(0, 0, 0.0, STEEL, "a"), Granule(1, 0, 0.01, STEEL, "b")),
        "granules[0].radius",
        "must be > 0",
    ),
    ("negative modulus", _with({"materials.ptfe.E": -5e9}), "materials.ptfe.E", "must be > 0"),
    ("nu = 0.5", _with({"materials.steel.nu": 0.5}), "materials.steel.nu", "must be in (-1, 0.5)"),
    ("nu = -1", _with({"materials.ptfe.nu": -1.0}), "materials.ptfe.nu", "must be in (-1, 0.5)"),
    (
        "R2_ratio 0.3",
        _with({"layout.R2_ratio": 0.3}),
        "layout.R2_ratio",
        "must be in [0.41421356, 1] (sqrt(2)-1 <= R2/R1 <= 1)",
    ),
    (
        "R2_ratio 1.2",
        _with({"layout.R2_ratio": 1.2}),
        "layout.R2_ratio",
        "must be in [0.41421356, 1] (sqrt(2)-1 <= R2/R1 <= 1)",
    ),
    (
        "overlapping granules",
        _granules(Granule(0, 0, 0.01, STEEL, "a"), Granule(0.015, 0, 0.01, STEEL, "b")),
        "granules[0]",
        "overlaps granule 'b'",
    ),
    (
        "granule through a wall",
        _granules(Granule(0.005, 0.05, 0.01, STEEL, "a"), walls=(Wall((-1.0, 0.0), 0.0, "left"),)),
        "granules[0]",
        "penetrates wall 'left'",
    ),
    ("granule through the plate", _with({"plate.x0": 0.05}), "granules[9]", "penetrates the plate"),
    (
        "unknown field",
        _toml("[plate]\nnxx = 4\n"),
        "plate.nxx",
        "unknown field 'plate.nxx'; did you mean 'plate.nx'? allowed: width, height",
    ),
    (
        "missing field",
        _toml(
            '[[granules]]\nx = 0\ny = 0\nradius = 0.01\nmaterial = "steel"\n'
            '[[granules]]\nx = 0\ny = 0.1\nmaterial = "steel"\n'
        ),
        "granules[1].radius",
        "missing required field 'granules[1].radius'",
    ),
    ("zero yield strength", _with({"materials.ptfe.Y": 0.0}), "materials.ptfe.Y", "must be > 0"),
    ("negative yield strength", _with({"materials.steel.Y": -355e6}), "materials.steel.Y", "must be > 0"),
    (
        "NaN yield strength",
        _toml(
            "[materials.wood]\nE = 1e10\nnu = 0.3\nrho = 600\nY = nan\n"
            '[[granules]]\nx = 0\ny = 0\nradius = 0.01\nmaterial = "wood"\n'
            '[load]\nkind = "none"\n',
            validated=True,
        ),
        "materials.wood.Y",
        "must be > 0 (a finite number)",
    ),
    (
        "infinite yield strength",
        _with({"materials.steel.Y": math.inf}),
        "materials.steel.Y",
        "must be > 0 (a finite number)",
    ),
    (
        "text yield strength",
        _toml('[materials.steel]\nE = 2e11\nnu = 0.3\nrho = 7850\nY = "hard"\n'),
        "materials.steel.Y",
        "wrong type: expected a number",
    ),
    (
        "missing material key",
        _toml("[materials.wood]\nE = 1e10\nnu = 0.3\n"),
        "materials.wood.rho",
        "missing required field",
    ),
    ("wrong type string", _toml('[load]\nq0 = "strong"\n'), "load.q0", "wrong type: expected a number"),
    ("wrong type bool", _toml("[time]\nt_end = true\n"), "time.t_end", "wrong type: expected a number"),
    ("float for an integer", _toml("[plate]\nny = 40.5\n"), "plate.ny", "expected an integer"),
    ("negative t_end", _with({"time.t_end": -1e-3}), "time.t_end", "must be > 0"),
    ("infinite t_end", _with({"time.t_end": math.inf}), "time.t_end", "must be > 0"),
    (
        "unknown material",
        _with({"layout.intruder_material": "wood"}),
        "layout.intruder_material",
        "unknown material; defined materials are: aluminium_2017, bearing_steel, ptfe, steel, steel_302, steel_440c",
    ),
    (
        "unknown granule material",
        _granules(Granule(0, 0, 0.01, "wood", "a"), Granule(1, 0, 0.01, STEEL, "b")),
        "granules[0].material",
        "unknown material",
    ),
    (
        "unknown pair material",
        _with({"contact.pairs": [{"materials": ["steel", "oak"]}]}),
        "contact.pairs[0].materials[1]",
        "unknown material",
    ),
    (
        "unknown preset or file",
        lambda: scenario_io.load_scenario("steel-r3"),
        "file",
        "no such file or preset; presets are: bare-plate, steel-r1",
    ),
    (
        "duplicate labels",
        _granules(Granule(0, 0, 0.01, STEEL, "a"), Granule(1, 0, 0.01, STEEL, "a")),
        "granules[1].label",
        "unique",
    ),
    ("q0 negative", _with({"load.q0": -1.0}), "load.q0", "must be >= 0"),
    ("load kind", _with({"load.kind": "point"}), "load.kind", "'line', 'none'"),
    ("load target", _with({"load.target": "wall"}), "load.target", "'granules', 'plate'"),
    (
        "load on a missing plate",
        lambda: validate(_two_spheres(load=Load(target="plate"))),
        "load.target",
        "needs a [plate]",
    ),
    (
        "load on missing granules",
        lambda: validate(Scenario(plate=Plate(x0=0.0), load=Load(target="granules"))),
        "load.target",
        "needs granules",
    ),
    ("loaded label unknown", _with({"load.granules": ["2", "Z"]}), "load.granules[1]", "no granule has this label"),
    ("load duration", _with({"load.duration": 0.0}), "load.duration", "must be > 0"),
    ("load length", _with({"load.length": -0.05}), "load.length", "must be > 0"),
    (
        "non-unit wall normal",
        _granules(
            Granule(0.02, 0, 0.01, STEEL, "a"),
            Granule(0.05, 0, 0.01, STEEL, "b"),
            walls=(Wall((-1.0, 0.1), 0.0, "left"),),
        ),
        "walls[0].normal",
        "must be a unit vector",
    ),
    ("plate thickness", _with({"plate.thickness": 0.0}), "plate.thickness", "must be > 0"),
    ("plate width", _with({"plate.width": -0.01}), "plate.width", "must be > 0"),
    ("plate nx", _with({"plate.nx": 0}), "plate.nx", "must be an integer >= 1"),
    (
        "clamped edge",
        _with({"plate.clamped_edges": ["top", "front"]}),
        "plate.clamped_edges",
        "must be a subset of 'top', 'bottom', 'left', 'right'",
    ),
    ("n_modes", _with({"plate.n_modes": -1}), "plate.n_modes", "must be an integer >= 0"),
    ("rigid layer", _with({"plate.rigid_layer_width": 0.0}), "plate.rigid_layer_width", "must be > 0"),
    (
        "plate without position",
        lambda: validate(Scenario(plate=Plate(), load=Load("none"))),
        "plate.x0",
        "must be given",
    ),
    ("dt order", _with({"time.dt_initial": 1e-7}), "time.dt_initial", "must be <= time.dt_max"),
    ("dt_min", _with({"time.dt_min": 1e-7, "time.dt_max": 1e-6}), "time.dt_min", "must be <= time.dt_initial"),
    ("output interval", _with({"time.t_end": 1e-7}), "time.output_interval", "must be <= time.t_end"),
    ("field interval", _with({"time.field_interval": 2.5e-6}), "time.field_interval", "whole multiple"),
    ("scheme", _with({"solver.scheme": "monolithic"}), "solver.scheme", "'paper'"),
    (
        "granular friction",
        _with({"solver.granular_friction": "explicit"}),
        "solver.granular_friction",
        "'split', 'rk4'",
    ),
    ("lambda_target", _with({"solver.lambda_target": 1.0}), "solver.lambda_target", "must be in (0, 1)"),
    ("iteration tolerance", _with({"solver.iteration_rtol": 0.0}), "solver.iteration_rtol", "must be > 0"),
    ("max iterations", _with({"solver.max_iterations": 0}), "solver.max_iterations", "must be an integer >= 1"),
    ("energy tol", _with({"solver.energy_tol": -1e-4}), "solver.energy_tol", "must be > 0"),
    ("mu", _with({"contact.mu": -0.1}), "contact.mu", "must be >= 0"),
    ("k_s", _with({"contact.k_s": 0.0}), "contact.k_s", "must be > 0"),
    ("alpha_n", _with({"contact.alpha_n": -1.0}), "contact.alpha_n", "must be >= 0"),
    ("neighbour gap", _with({"contact.neighbour_gap": -0.1}), "contact.neighbour_gap", "must be >= 0"),
    ("layout R1", _with({"layout.R1": 0.0}), "layout.R1", "must be > 0"),
    (
        "nothing to simulate",
        lambda: validate(Scenario(load=Load(kind="none"))),
        "granules",
        "needs granules (or a [layout]) or a [plate]",
    ),
    (
        "layout and granules",
        lambda: validate(dataclasses.replace(preset("steel-r1"), granules=(Granule(0.5, 0.5, 0.01, STEEL),))),
        "granules",
        "either [layout] or [[granules]]",
    ),
    ("toml syntax", _toml("[plate\nnx = 4\n"), "toml", "TOML syntax error"),
]


@pytest.mark.parametrize("action, field, allowed", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_input_is_refused_with_field_and_allowed_range(action, field, allowed):
    """Each bad input raises a ScenarioError whose message names the field path and what is allowed."""
    with pytest.raises(ScenarioError) as info:
        action()
    msg = str(info.value)
    assert f"'{field}'" in msg, msg
    assert allowed in msg, msg
    assert info.value.field == field


def test_valid_scenarios_pass():
    """The two-sphere impact, a layout at sqrt(2)-1 and at the 1e-12 tolerance, and exact touches all validate."""
    validate(_two_spheres())
    validate(scenario_io.with_changes(preset("steel-r1"), {"layout.R2_ratio": math.sqrt(2.0) - 1.0}))
    validate(scenario_io.with_changes(preset("steel-r1"), {"layout.R2_ratio": 1.0 + 5e-13}))
    validate(scenario_io.with_changes(preset("ptfe-r05"), {"plate.ny": 80, "plate.nx": 8}))
    touching = _two_spheres(
        granules=(Granule(0.0, 0.0, 0.01, STEEL, "a"), Granule(0.02 - 5e-12, 0.0, 0.01, STEEL, "b"))
    )
    validate(touching)


def test_toml_syntax_error_names_the_line(tmp_path):
    """A TOML syntax error in a file becomes a ScenarioError carrying tomllib's line number."""
    p = tmp_path / "bad.toml"
    p.write_text('name = "x"\n[plate\n')
    with pytest.raises(ScenarioError, match=r"line 2"):
        scenario_io.load(p)
    with pytest.raises(ScenarioError, match=r"line 2"):
        scenario_io.load_scenario(str(p))


def test_load_scenario_validates_files(tmp_path):
    """load_scenario refuses a file that parses but is physically invalid."""
    p = tmp_path / "s.toml"
    scenario_io.dump(scenario_io.with_changes(preset("steel-r1"), {"plate.thickness": -1.0}), p)
    scenario_io.load(p)  # shape is fine
    with pytest.raises(ScenarioError, match="plate.thickness"):
        scenario_io.load_scenario(str(p))


def test_dict_round_trip_of_a_custom_scenario():
    """from_dict(to_dict(s)) == s for a scenario using every table, optional values and a user material."""
    mats = dict(LIBRARY)
    mats["rubber"] = Material("rubber", E=1e7, nu=0.49, rho=1100.0)
    s = Scenario(
        name="everything",
        description="all tables",
        materials=mats,
        granules=(
            Granule(0.01, 0.01, 0.01, "rubber", "a", vx=2.0, vy=-1.0, omega=3.0),
            Granule(0.03, 0.01, 0.01, "steel", "b"),
        ),
        walls=(Wall((-1.0, 0.0), 0.0, "left"), Wall((0.0, -1.0), 0.0, "floor", "rubber")),
        plate=Plate(
            x0=0.04, nx=2, ny=20, rigid_layer_width=0.004, clamped_edges=("top", "bottom", "right"), n_modes=30
        ),
        load=Load(target="granules", q0=1234.5, granules=("a",)),
        contact=dataclasses.replace(
            preset("steel-r1").contact,
            pairs=(
                PairCoefficients(("steel", "rubber"), alpha_n=0.1, mu=0.3, k_s=50.0),
                PairCoefficients(("steel", "steel"), mu=0.2),
            ),
            clip_tensile=False,
        ),
        time=TimeSettings(t_end=1e-4, output_interval=1e-6, field_interval=1e-5),
        solver=Solver(lambda_target=0.3, max_iterations=10),
    )
    validate(s)
    d = scenario_io.to_dict(s)
    assert scenario_io.from_dict(d) == s
    assert scenario_io.loads(scenario_io.dumps(s)) == s
    assert "x0" not in scenario_io.to_dict(preset("steel-r1"))["plate"]  # None omitted
    assert d["walls"][0]["normal"] == [-1.0, 0.0]  # tuples as arrays


def test_ints_accepted_for_floats_and_defaults_filled():
    """Integers are accepted where floats go, and absent fields take the dataclass defaults."""
    s = scenario_io.loads('[[granules]]\nx = 0\ny = 1\nradius = 1\nmaterial = "steel"\n[load]\nq0 = 50000\n')
    g = s.granules[0]
    assert (g.x, g.y, g.radius) == (0.0, 1.0, 1.0) and isinstance(g.x, float)
    assert s.load == Load(q0=50_000.0) and isinstance(s.load.q0, float)
    assert s.plate is None and s.layout is None and s.time == TimeSettings()
    assert s.materials == LIBRARY


def test_user_material_overrides_library():
    """A [materials.steel] table overrides the library's steel; new names are added."""
    s = scenario_io.loads(
        "[materials.steel]\nE = 2.1e11\nnu = 0.29\nrho = 7800\n[materials.glass]\nE = 6.3e10\nnu = 0.23\nrho = 2500\n"
    )
    assert s.material("steel") == Material("steel", 2.1e11, 0.29, 7800.0)
    assert s.material("glass").rho == 2500.0 and s.material("ptfe") == LIBRARY["ptfe"]


def test_yield_strength_is_optional_and_round_trips():
    """Y is read, written back by dumps (a preset's TOML round-trips it), absent means
    unknown (None), and the library's materials carry their documented Y."""
    s = scenario_io.loads(
        "[materials.glass]\nE = 6.3e10\nnu = 0.23\nrho = 2500\n"
        "[materials.wood]\nE = 1e10\nnu = 0.3\nrho = 600\nY = 4e7\n"
    )
    assert s.material("glass").Y is None and s.material("wood").Y == 4e7
    assert scenario_io.loads(scenario_io.dumps(s, all_materials=True)) == s
    text = scenario_io.dumps(preset("ptfe-r05"))
    assert "Y = 11000000.0" in text and "Y = 355000000.0" in text
    assert scenario_io.loads(text) == preset("ptfe-r05")
    assert (LIBRARY["steel"].Y, LIBRARY["bearing_steel"].Y, LIBRARY["ptfe"].Y) == (355e6, 2.0e9, 11e6)
    assert dataclasses.replace(LIBRARY["bearing_steel"], name="steel", Y=355e6) == LIBRARY["steel"]


def test_schemes_constant():
    """The solver schemes accepted are listed in SCHEMES: the paper's one, the implicit one
    (the default) and velocity Verlet of the granules alone; anything else is refused
    naming solver.scheme."""
    assert SCHEMES == ("paper", "implicit", "verlet")
    assert Solver().scheme == "implicit"


def _doc_block(title: str) -> str:
    text = DOC.read_text()
    m = re.search(re.escape(title) + r".*?```toml\n(.*?)```", text, re.S)
    assert m, title
    return m.group(1)


def test_docs_examples_load_and_validate():
    """docs/scenario.md's steel-r1 example is dumps(preset) verbatim, and its custom example validates."""
    assert _doc_block("<!-- example: steel-r1 -->") == scenario_io.dumps(preset("steel-r1"))
    s = scenario_io.loads(_doc_block("<!-- example: two-spheres -->"))
    validate(s)
    assert s.plate is None and s.load.kind == "none" and len(s.granules) == 2
    assert s.granules[0].vx > 0 > s.granules[1].vx


def test_docs_two_sphere_example_bounces_as_stated():
    """docs/scenario.md's two-sphere example, 1 mm apart at t = 0, does collide: momentum
    stays zero (equal masses,
    opposite velocities), the spheres come apart at the speed the page states (0.991 m/s),
    and the energy kept is that speed squared (98.2%)."""
    import granplate as gp

    s = scenario_io.loads(_doc_block("<!-- example: two-spheres -->"))
    ds = gp.simulate(s, progress=False)
    vx = ds.vx.values
    gap = ds.x.values[:, 1] - ds.x.values[:, 0] - 0.02
    assert gap[0] == pytest.approx(1e-3) and gap.min() < 0 < gap[-1]
    assert abs(vx[-1].sum()) < 1e-12
    assert vx[-1, 0] == pytest.approx(-0.991, abs=5e-4) and vx[-1, 1] == pytest.approx(0.991, abs=5e-4)
    kept = float(ds.E_granular[-1] / ds.E_granular[0])
    assert kept == pytest.approx(vx[-1, 1] ** 2, rel=1e-6) and kept == pytest.approx(0.982, abs=5e-4)


def test_with_changes_states_the_changes_in_the_description():
    """A changed scenario never keeps a description that contradicts it: the preset's line
    is followed by every changed field with its value; the name stays."""
    s = preset("steel-r1")
    t = scenario_io.with_changes(s, {"load.q0": 1e12, "layout.intruder_material": "ptfe"})
    assert t.name == s.name
    assert t.description == s.description + ('; changed: load.q0 = 1e+12, layout.intruder_material = "ptfe"')
    # a second round merges: a field changed again shows its latest value, in its first place
    u = scenario_io.with_changes(t, {"load.q0": 2e4, "plate": None, "plate.clamped_edges": None, "name": "mine"})
    assert u.name == "mine"
    assert u.description == (
        s.description + "; changed: load.q0 = 20000, layout.intruder_material = "
        '"ptfe", plate = removed, plate.clamped_edges = removed'
    )
    # the TOML text carries it, and reading it back changes nothing
    assert scenario_io.loads(scenario_io.dumps(u)) == u


def test_with_changes_description_edge_cases():
    """No change keeps the description; an explicit description wins; an empty one gets the list alone."""
    s = preset("ptfe-r05")
    assert scenario_io.with_changes(s, {}).description == s.description
    assert scenario_io.with_changes(s, {"name": "x"}).description == s.description
    # numerical settings are not part of a description: a shortened run keeps the preset's
    numerical = scenario_io.with_changes(s, {"time.t_end": 1e-4, "solver.scheme": "paper"})
    assert numerical.description == s.description and numerical.time.t_end == 1e-4
    assert scenario_io.with_changes(s, {"load.q0": 1.0, "description": "mine"}).description == "mine"
    e = _two_spheres(description="")
    once = scenario_io.with_changes(e, {"granules[0].vx": 2.5, "contact.clip_tensile": False})
    assert once.description == "changed: granules[0].vx = 2.5, contact.clip_tensile = false"
    twice = scenario_io.with_changes(once, {"granules[0].vx": 3.0})
    assert twice.description == "changed: granules[0].vx = 3, contact.clip_tensile = false"
    lists = scenario_io.with_changes(preset("steel-r1"), {"plate.clamped_edges": ["top", "right"], "plate.ny": 80})
    assert lists.description.endswith('changed: plate.clamped_edges = ["top", "right"], plate.ny = 80')
    again = scenario_io.with_changes(lists, {"plate.ny": 40})
    assert again.description.endswith('changed: plate.clamped_edges = ["top", "right"], plate.ny = 40')


def test_docs_python_example_runs(tmp_path, monkeypatch, capsys):
    """docs/scenario.md's Python block runs as written (in an empty directory)."""
    m = re.search(r"```python\n(.*?)```", DOC.read_text(), re.S)
    assert m
    monkeypatch.chdir(tmp_path)
    exec(compile(m.group(1), "docs/scenario.md", "exec"), {"__name__": "docs_example"})
    out = capsys.readouterr().out
    assert "changed: load.q0 = 10000, layout.R2_ratio = 0.5, plate.ny = 80" in out
    assert (tmp_path / "my_case.toml").exists()


@pytest.mark.parametrize(
    "text, field, near",
    [
        ('nmae = "x"', "nmae", "name"),
        ("[layout]\nR2_ratoi = 0.5", "layout.R2_ratoi", "layout.R2_ratio"),
        ('[layout]\nkind = "chain"\ncuont = 3', "layout.cuont", "layout.count"),
        ("[layout.imperfections]\njiter = 0.1", "layout.imperfections.jiter", "layout.imperfections.jitter"),
        ("[plate]\nnxx = 4", "plate.nxx", "plate.nx"),
        ("[contact]\nskn = 0.1", "contact.skn", "contact.skin"),
        ('[[contact.pairs]]\nmaterials = ["steel", "ptfe"]\nmuu = 0.2', "contact.pairs[0].muu", "contact.pairs[0].mu"),
        ("[materials.foam]\nE = 1e6\nnu = 0.2\nrh = 30.0", "materials.foam.rh", "materials.foam.rho"),
        (
            '[[granules]]\nx = 0\ny = 0\nmaterial = "steel"\nradius = 0.01\nraduis = 0.01',
            "granules[0].raduis",
            "granules[0].radius",
        ),
        ("[[walls]]\nnormal = [1.0, 0.0]\noffset = 0.0\nofset = 1.0", "walls[0].ofset", "walls[0].offset"),
        ("[load]\nduraton = 1e-5", "load.duraton", "load.duration"),
        ("[time]\nt_edn = 1e-4", "time.t_edn", "time.t_end"),
        ('[solver]\nshceme = "paper"', "solver.shceme", "solver.scheme"),
    ],
)
def test_unknown_field_suggests_the_closest_name(text, field, near):
    """A misspelled key in any table: the error names it, suggests the closest allowed
    name (difflib) with its dotted path, and still lists the allowed ones."""
    with pytest.raises(ScenarioError) as err:
        scenario_io.loads(text)
    msg = str(err.value)
    assert err.value.field == field
    assert f"did you mean '{near}'? allowed: " in msg


def test_unknown_field_far_from_every_name_suggests_nothing():
    """A key like no allowed one gets the list of allowed names without a guess."""
    with pytest.raises(ScenarioError, match="allowed: ") as err:
        scenario_io.loads("[plate]\nzzzzzz = 1")
    assert "did you mean" not in str(err.value)


def test_far_coordinates_and_fast_granules_are_refused_with_the_range():
    """A granule at x = 1e300 (which overflows the neighbour search's squared distances),
    a wall 1e7 radii out, a speed above sqrt(E/rho) and a shock pressing harder than E on
    the smallest length: each named, with the bound derived from the scenario."""
    g = (Granule(0.0, 0.0, 0.01, "steel", "a"), Granule(0.03, 0.0, 0.01, "steel", "b"))
    far = dataclasses.replace(g[1], x=1e300)
    with pytest.raises(
        ScenarioError,
        match=r"'granules\[1\]\.x'.*\|value\| <= 10000 m, 1e\+06 x the "
        r"smallest length of the scenario, h = 0\.01 m \(granules\[0\]\.radius\)",
    ):
        validate(_two_spheres(granules=(g[0], far)))
    wall = Wall((1.0, 0.0), 1.0e5, "far")
    with pytest.raises(ScenarioError, match=r"'walls\[0\]\.offset'"):
        validate(_two_spheres(walls=(wall,)))
    c = math.sqrt(LIBRARY["steel"].E / LIBRARY["steel"].rho)
    for f, v in (("vx", 1.01 * c), ("vy", -1.01 * c), ("omega", 1.01 * c / 0.01)):
        with pytest.raises(ScenarioError, match=rf"'granules\[0\]\.{f}'.*sqrt\(E / rho\) = {c:.6g} m/s"):
            validate(_two_spheres(granules=(dataclasses.replace(g[0], **{f: v}), g[1])))
    validate(_two_spheres(granules=(dataclasses.replace(g[0], vx=0.99 * c), g[1])))
    shock = Load(q0=2.01e9, length=0.05, y0=-0.025)  # E_steel x h = 2e11 x 0.01 = 2e9 N/m
    with pytest.raises(ScenarioError, match=r"'load\.q0'.*q0 <= E h = 2e\+09 N/m"):
        validate(_two_spheres(load=shock))
    validate(_two_spheres(load=dataclasses.replace(shock, q0=1.99e9)))
    validate(_two_spheres(load=dataclasses.replace(shock, kind="none")))  # no load: q0 unused


def test_smaller_dt_max_alone_sets_the_initial_step():
    """A [time] table that gives only dt_max below the default first step starts at dt_max
    (rather than being refused), and a given dt_initial is still checked against it."""
    import pytest

    from granplate.errors import ScenarioError
    from granplate.setup.io import loads
    from granplate.setup.validate import validate

    base = 'dimension = 3\n[[granules]]\nx = 0.0\ny = 0.0\nz = 0.0\nradius = 0.001\nmaterial = "steel"\n'
    s = loads(base + "[time]\nt_end = 1e-6\ndt_max = 1e-8\n")
    assert s.time.dt_initial == 1e-8
    validate(s)
    with pytest.raises(ScenarioError, match="dt_initial"):
        validate(loads(base + "[time]\nt_end = 1e-6\ndt_max = 1e-8\ndt_initial = 4e-8\n"))
    with pytest.raises(ScenarioError, match="dt_max"):
        validate(loads(base + "[time]\nt_end = 1e-6\ndt_max = -1e-8\n"))
