"""The scenario side of three-dimensional assemblies (`dimension = 3`): fields, reading and
writing, the box, the force load, the checks before a run, and 2D left exactly as it was."""

from __future__ import annotations

import copy
import hashlib
import json
import dataclasses
import itertools
import math
import re
from pathlib import Path

import numpy as np
import pytest

from granplate.errors import ScenarioError
from granplate.setup import io as scenario_io
from granplate.model.loads import loaded_labels
from granplate.setup.geometry import box_walls, resolve
from granplate.setup.presets import preset, preset_names
from granplate.setup.scenario import BOX_WALLS, Box, Granule, Load, Scenario, Wall
from granplate.setup.validate import validate
from field_paths import mutated, numeric_fields

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "scenario.md"

#: Two steel spheres in a box, a force on the one furthest against +x.
BASE: dict = {
    "name": "box-3d",
    "description": "two spheres in a box",
    "dimension": 3,
    "materials": {"soft": {"E": 1e9, "nu": 0.3, "rho": 1200.0}},
    "granules": [
        {
            "label": "a",
            "x": 0.02,
            "y": 0.02,
            "z": 0.02,
            "radius": 0.01,
            "material": "steel",
            "vx": 0.1,
            "vz": -0.1,
            "omega": [1.0, -2.0, 3.0],
        },
        {"label": "b", "x": 0.045, "y": 0.02, "z": 0.025, "radius": 0.01, "material": "soft"},
    ],
    "walls": [{"label": "tilted", "normal": [1.0, 1.0, 0.0], "point": [0.06, 0.03, 0.0]}],
    "box": {"lower": [0.0, 0.0, 0.0], "upper": [0.08, 0.04, 0.04], "material": "soft"},
    "load": {"kind": "force", "force": 5.0, "duration": 1e-5, "direction": [2.0, 0.0, 0.0]},
    "time": {"t_end": 2e-6, "output_interval": 1e-6, "field_interval": 2e-6},
}


def base(**changes) -> dict:
    """BASE with top-level entries replaced."""
    d = copy.deepcopy(BASE)
    d.update(changes)
    return d


def refused(d: dict | Scenario) -> ScenarioError:
    """The ScenarioError that reading (a dict) and validating raise."""
    with pytest.raises(ScenarioError) as info:
        validate(scenario_io.from_dict(d) if isinstance(d, dict) else d)
    return info.value


def test_base_scenario_reads_validates_and_resolves():
    """BASE is valid; its resolved form holds vectors, the walls of the plane and the box."""
    s = scenario_io.from_dict(BASE)
    validate(s)
    r = resolve(s)
    assert s.dimension == 3 and r.box is None
    assert r.granules[0].omega == (1.0, -2.0, 3.0) and r.granules[1].omega == (0.0, 0.0, 0.0)
    assert [w.label for w in r.walls] == ["tilted", *BOX_WALLS]
    # the plane through (0.06, 0.03, 0) with normal (1, 1, 0)/sqrt 2: offset 0.09 / sqrt 2
    assert r.walls[0].offset == pytest.approx(0.09 / math.sqrt(2.0), rel=1e-15)
    validate(r)
    assert resolve(r) == r


def test_defaults_of_the_new_fields():
    """Defaults: dimension 2, z = vz = 0, omega 0, no point, no box, force 0 along +x."""
    s = Scenario()
    g = Granule(0.0, 0.0, 0.01, "steel")
    assert s.dimension == 2 and s.box is None
    assert (g.z, g.vz, g.omega) == (0.0, 0.0, 0.0) and g.spin() == (0.0, 0.0, 0.0)
    assert Wall((1.0, 0.0), 0.0).point is None
    assert Load().force == 0.0 and Load().direction == (1.0, 0.0, 0.0)
    assert Granule(0.0, 0.0, 0.01, "steel", omega=2.5).spin() == (0.0, 0.0, 2.5)
    assert Granule(0.0, 0.0, 0.01, "steel", omega=(1.0, 2.0, 3.0)).spin() == (1.0, 2.0, 3.0)


def test_round_trip_of_every_new_field():
    """dumps/loads and to_dict/from_dict give back the same 3D scenario, as written and resolved."""
    s = scenario_io.from_dict(BASE)
    r = resolve(s)
    for x in (s, r):
        assert scenario_io.loads(scenario_io.dumps(x)) == x
        assert scenario_io.from_dict(scenario_io.to_dict(x)) == x
    text = scenario_io.dumps(r)
    assert "dimension = 3" in text and "[box]" not in text and text.count("[[walls]]") == 7
    for key in ("z = ", "vz = ", "omega = [", "force = 5.0", "direction = ["):
        assert key in text, key
    assert "[box]" in scenario_io.dumps(s) and "point = [" in scenario_io.dumps(s)


def test_resolve_cli_writes_the_3d_scenario(tmp_path, capsys):
    """`granplate resolve` of a 3D file prints z, vz, omega vectors and the box as six walls."""
    from granplate.cli import main

    f = tmp_path / "box.toml"
    f.write_text(scenario_io.dumps(scenario_io.from_dict(BASE)))
    assert main(["resolve", str(f)]) == 0
    r = scenario_io.loads(capsys.readouterr().out)
    assert r == resolve(scenario_io.from_dict(BASE))
    assert r.box is None and [w.label for w in r.walls][1:] == list(BOX_WALLS)


def test_box_expands_into_six_walls():
    """[box] lower = (x0, y0, z0), upper = (x1, y1, z1): xmin is -e_x at offset -x0, xmax +e_x at x1, ..."""
    lo, hi = (-0.01, 0.02, -0.03), (0.04, 0.05, 0.06)
    walls = box_walls(Box(lo, hi, material="ptfe"))
    assert [w.label for w in walls] == ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"]
    for axis in range(3):
        e = np.eye(3)[axis]
        wmin, wmax = walls[2 * axis], walls[2 * axis + 1]
        assert np.array_equal(wmin.normal, -e) and wmin.offset == -lo[axis]
        assert np.array_equal(wmax.normal, e) and wmax.offset == hi[axis]
    assert {w.material for w in walls} == {"ptfe"}
    # the box's inside is exactly where s . n < offset for all six
    rng = np.random.default_rng(7)
    pts = rng.uniform(-0.1, 0.1, size=(200, 3))
    inside = np.all((pts > lo) & (pts < hi), axis=1)
    by_walls = np.all([pts @ np.array(w.normal) < w.offset for w in walls], axis=0)
    assert np.array_equal(inside, by_walls) and inside.any()


def test_box_walls_come_after_the_explicit_walls():
    """resolve appends the box's walls after the explicit ones, with their labels."""
    r = resolve(scenario_io.from_dict(BASE))
    assert r.walls[0].label == "tilted" and r.walls[1:] == box_walls(scenario_io.from_dict(BASE).box)


def test_wall_point_and_offset():
    """A 3D wall by a point gets offset = point . n/|n|; both given must agree to 1e-12."""
    n, p = (0.0, 3.0, 4.0), (0.5, 0.03, 0.04)
    off = (3.0 * 0.03 + 4.0 * 0.04) / 5.0
    r = resolve(scenario_io.from_dict(base(walls=[{"normal": list(n), "point": list(p)}])))
    assert r.walls[0].offset == pytest.approx(off, rel=1e-15)
    validate(scenario_io.from_dict(base(walls=[{"normal": list(n), "point": list(p), "offset": off * (1 + 1e-13)}])))
    err = refused(base(walls=[{"normal": list(n), "point": list(p), "offset": off * (1 + 1e-9)}]))
    assert "walls[0].point" in str(err) and "1e-12" in str(err)
    err = refused(base(walls=[{"normal": list(n)}]))
    assert "walls[0].offset" in str(err) and "walls[0].point" in str(err)


def test_force_loaded_granules_are_those_furthest_against_the_direction():
    """Default force-loaded granules: the smallest s . d - R (ties within 1e-9 R_max), or load.granules."""
    gs = (
        Granule(x=0.02, y=0.0, z=0.0, radius=0.01, material="steel", label="p"),
        Granule(x=0.015, y=0.1, z=0.0, radius=0.005, material="steel", label="q"),
        Granule(x=0.05, y=0.0, z=0.2, radius=0.01, material="steel", label="r"),
    )
    s = Scenario(dimension=3, granules=gs, load=Load(kind="force", force=1.0))
    assert loaded_labels(s) == ("p", "q")  # both reach x = 0.01
    up = dataclasses.replace(s, load=Load(kind="force", force=1.0, direction=(0.0, 0.0, -3.0)))
    assert loaded_labels(up) == ("r",)  # furthest against -z: largest z + R
    given = dataclasses.replace(s, load=Load(kind="force", force=1.0, granules=("r",)))
    assert loaded_labels(given) == ("r",)


@pytest.mark.parametrize(
    "change,field,words",
    [
        ({"dimension": 4}, "dimension", "must be 2"),
        ({"dimension": 1}, "dimension", "or 3"),
        (
            {"plate": {"size": [0.1, 0.1, 0.005], "elements": [2, 2, 1], "origin": [0.0, 0.0, 0.008]}},
            "granules[0]",
            "granule 'a'",
        ),
        ({"plate": {"x0": 0.1}}, "plate.x0", "unknown"),
        ({"load": {"kind": "force", "direction": [0.0, 0.0, 0.0]}}, "load.direction", "nonzero"),
        ({"load": {"kind": "force", "direction": [1.0, math.nan, 0.0]}}, "load.direction", "finite"),
        ({"load": {"kind": "force", "force": -1.0}}, "load.force", ">= 0"),
        ({"load": {"kind": "force", "force": 1e300}}, "load.force", "E h^2"),
        ({"load": {"kind": "force", "granules": ["zz"]}}, "load.granules[0]", "no granule"),
        ({"walls": [{"normal": [1.0, 0.0], "offset": 0.1}]}, "walls[0].normal", "[nx, ny, nz]"),
        ({"walls": [{"normal": [0.0, 0.0, 0.0], "offset": 0.1}]}, "walls[0].normal", "nonzero"),
        ({"walls": [{"normal": [0.0, math.inf, 0.0], "offset": 0.1}]}, "walls[0].normal", "finite"),
        ({"walls": [{"normal": [0.0, 0.0, 1.0], "point": [0.0, math.nan, 0.0]}]}, "walls[0].point", "finite"),
        ({"box": {"lower": [0.0, 0.05, 0.0], "upper": [0.1, 0.04, 0.04]}}, "box.upper", "lower < upper"),
        (
            {"box": {"lower": [0.0, 0.0, 0.0], "upper": [0.1, 0.04, 0.04], "material": "stel"}},
            "box.material",
            "unknown material",
        ),
    ],
)
def test_3d_refusals_name_the_field(change, field, words):
    """Each bad 3D input is one ScenarioError naming the field and what is allowed."""
    d = base(**change)
    for k in [k for k, v in d.items() if v is None]:
        del d[k]
    msg = str(refused(d))
    assert f"'{field}'" in msg and words in msg, msg
    assert "\n" not in msg


def test_solid_needs_the_verlet_scheme_and_then_builds():
    """A box solid with the paper scheme is refused naming solver.scheme; with "verlet"
    (what a file that names no scheme gets) it validates and build_model gives the body's
    modes and contact arrays."""
    from granplate.model import build_model

    d = base(
        plate={
            "size": [0.1, 0.1, 0.005],
            "elements": [2, 2, 1],
            "max_frequency": 5e4,
            "origin": [0.2, 0.2, 0.2],
        },  # clear of the box's and the tilted wall's planes
        solver={"scheme": "paper"},
    )
    e = refused(d)
    assert e.field == "solver.scheme" and "verlet" in str(e) and "implicit" in str(e)
    d["solver"] = {"scheme": "verlet", "granular_friction": "split"}
    s = scenario_io.from_dict(d)
    validate(s)
    m = build_model(s)
    assert m.solid is not None and m.body.phi.shape[1] == m.solid.n_modes == len(m.plate_arrays.omega2)
    assert m.body.coef.shape[0] == len(m.labels)


def test_scalar_omega_in_3d_is_refused():
    """In 3D omega is a vector: a scalar in a file (even 0) or a nonzero scalar in Python is refused."""
    d = base()
    d["granules"][1]["omega"] = 0.0
    with pytest.raises(ScenarioError, match=r"'granules\[1\]\.omega'.*omega is a vector \[wx, wy, wz\] in 3D"):
        scenario_io.from_dict(d)
    s = scenario_io.from_dict(BASE)
    gs = (s.granules[0], dataclasses.replace(s.granules[1], omega=2.0))
    msg = str(refused(dataclasses.replace(s, granules=gs)))
    assert "'granules[1].omega'" in msg and "omega is a vector [wx, wy, wz] in 3D" in msg


@pytest.mark.parametrize(
    "make,field",
    [
        (lambda g, w: (dataclasses.replace(g, z=0.001), w), "granules[0].z"),
        (lambda g, w: (dataclasses.replace(g, vz=1.0), w), "granules[0].vz"),
        (lambda g, w: (dataclasses.replace(g, omega=(0.0, 0.0, 1.0)), w), "granules[0].omega"),
        (lambda g, w: (g, dataclasses.replace(w, normal=(-1.0, 0.0, 0.0))), "walls[0].normal"),
        (lambda g, w: (g, dataclasses.replace(w, point=(0.0, 0.0, 0.0))), "walls[0].point"),
    ],
)
def test_2d_refuses_the_3d_fields(make, field):
    """A 2D scenario with z, vz, a vector omega, a 3-component normal or a point: refused, naming
    the field and "set dimension = 3"."""
    g, w = Granule(0.01, 0.01, 0.01, "steel"), Wall((-1.0, 0.0), 0.0)
    g, w = make(g, w)
    msg = str(refused(Scenario(granules=(g,), walls=(w,), load=Load(kind="none"))))
    assert f"'{field}'" in msg and "set dimension = 3" in msg, msg


def test_2d_refuses_a_box_and_a_force_load():
    """[box] and load kind "force" in 2D: refused naming the field and "set dimension = 3"."""
    g = (Granule(0.01, 0.01, 0.01, "steel"),)
    msg = str(refused(Scenario(granules=g, box=Box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)))))
    assert "'box'" in msg and "set dimension = 3" in msg
    msg = str(refused(Scenario(granules=g, load=Load(kind="force", force=1.0))))
    assert "'load.kind'" in msg and "set dimension = 3" in msg


def test_spheres_apart_in_z_do_not_overlap():
    """Two spheres at the same (x, y) but 2.5 R apart in z are valid in 3D; closer in z, they overlap."""

    def two(dz):
        return Scenario(
            dimension=3,
            load=Load(kind="none"),
            granules=(
                Granule(0.0, 0.0, 0.01, "steel", label="a", z=0.0),
                Granule(0.0, 0.0, 0.01, "steel", label="b", z=dz),
            ),
        )

    validate(two(0.025))
    validate(two(0.02))  # touching
    msg = str(refused(two(0.015)))
    assert "overlaps" in msg and "0.005 m" in msg and "granules[0].z" in msg


def test_wall_contact_in_3d_uses_the_unit_normal():
    """A sphere touching a plane of non-unit normal is valid; past it by 1 mm it is refused with 1 mm."""

    def on(z):
        return Scenario(
            dimension=3,
            load=Load(kind="none"),
            walls=(Wall((0.0, 0.0, -7.0), 0.0),),
            granules=(Granule(0.3, -0.2, 0.01, "steel", z=z),),
        )

    validate(on(0.01))
    msg = str(refused(on(0.009)))
    assert "penetrates wall" in msg and "0.001 m" in msg


def test_lengths_range_applies_to_z():
    """The length range (1e6 h) holds for z and wall points as it does for x and y."""
    s = scenario_io.from_dict(BASE)
    gs = (dataclasses.replace(s.granules[0], z=1e300), s.granules[1])
    assert "'granules[0].z'" in str(refused(dataclasses.replace(s, granules=gs, box=None, walls=())))
    gs = (dataclasses.replace(s.granules[0], z=1e5), s.granules[1])
    msg = str(refused(dataclasses.replace(s, granules=gs, box=None, walls=())))
    assert "'granules[0].z'" in msg and "|value| <=" in msg


def test_speeds_bound_vz_and_each_spin_component():
    """|vz| and |omega_k| R below sqrt(E / rho) of the granule's material (5,048 m/s for steel)."""
    s = scenario_io.from_dict(BASE)
    for change, field in (({"vz": 6000.0}, "granules[0].vz"), ({"omega": (0.0, 6e5, 0.0)}, "granules[0].omega[1]")):
        gs = (dataclasses.replace(s.granules[0], **change), s.granules[1])
        msg = str(refused(dataclasses.replace(s, granules=gs)))
        assert f"'{field}'" in msg and "sqrt(E / rho)" in msg, msg


def test_unknown_3d_fields_suggest_the_closest_name():
    """A misspelled box or granule field is refused with "did you mean"."""
    with pytest.raises(ScenarioError, match=r"did you mean 'box\.upper'"):
        scenario_io.from_dict(base(box={"lower": [0, 0, 0], "uper": [1, 1, 1]}))
    with pytest.raises(ScenarioError, match=r"did you mean 'dimension'"):
        scenario_io.from_dict(base(dimensions=3))
    d = base()
    d["granules"][0]["vzz"] = 1.0
    with pytest.raises(ScenarioError, match=r"did you mean 'granules\[0\]\.vz'"):
        scenario_io.from_dict(d)


#: sha256 of dumps(s) and dumps(resolve(s)) of every preset and 2D example file, as written
#: before the 3D fields existed: a change to how a 2D scenario is written changes the
#: stored results' keys of every scenario written before, and must show here.
DUMPS_DIGESTS = ROOT / "tests" / "golden" / "scenario_dumps.json"


def test_2d_files_are_written_as_before():
    """dumps of every preset and 2D example file, as written and resolved, is byte for byte
    what it was before the 3D fields (sha256 recorded then); no 3D key appears."""
    expected = json.loads(DUMPS_DIGESTS.read_text())
    assert set(preset_names()) <= set(expected)
    for name, digests in expected.items():
        s = preset(name) if name in preset_names() else scenario_io.load(ROOT / name)
        texts = {"written": scenario_io.dumps(s), "resolved": scenario_io.dumps(resolve(s))}
        for kind, text in texts.items():
            assert hashlib.sha256(text.encode()).hexdigest() == digests[kind], (name, kind)
            assert not re.search(r"^(dimension|z|vz|force|direction|point) = ", text, re.M), (name, kind)


def test_every_3d_field_is_documented():
    """docs/scenario.md has a table row for every field of Granule, Wall, Box, Load and the top level."""
    doc = DOC.read_text()
    for cls in (Granule, Wall, Box, Load):
        for f in dataclasses.fields(cls):
            assert re.search(rf"\| (`\w+`, )*`{f.name}`( ?, `\w+`)* \|", doc), (cls.__name__, f.name)
    for name in ("name", "description", "dimension"):
        assert f"| `{name}` |" in doc, name


def _doc_3d_example() -> str:
    m = re.search(r"<!-- example: box-3d -->\n```toml\n(.*?)```", DOC.read_text(), re.S)
    assert m
    return m.group(1)


def test_docs_3d_example_validates():
    """docs/scenario.md's 3D example (two spheres in a box) reads, validates and resolves to six walls."""
    s = scenario_io.loads(_doc_3d_example())
    validate(s)
    r = resolve(s)
    assert r.dimension == 3 and len(r.granules) == 2 and [w.label for w in r.walls] == list(BOX_WALLS)
    assert r.load.kind == "force" and loaded_labels(r) == (r.granules[0].label,)


# --------------------------------------------------------------------------- fuzz

BAD_VALUES: tuple = (-1, 0, math.nan, math.inf, 1e300, "x")


def names_field(message: str, path: str) -> bool:
    """The message names the field, its vector (walls[0].normal for walls[0].normal[1]), or,
    for a conflict between bodies, the body (granules[1] for granules[1].z)."""
    if re.search(re.escape(path) + r"(?![\w\[.])", message):
        return True
    vector = re.match(r"^(.*)\[\d\]$", path)
    if vector and re.search(re.escape(vector.group(1)) + r"(?![\w\[.])", message):
        return True
    body = re.match(r"^((?:granules|walls)\[\d+\])\.(?:x|y|z|radius|offset|point\[\d\]|normal\[\d\])$", path)
    if body and body.group(1) in message:
        return True
    # a box corner moved inside a granule: the granule crosses the box's wall
    return path.startswith("box.") and "penetrates wall" in message


@pytest.mark.parametrize("path,value", list(itertools.product(numeric_fields(BASE), BAD_VALUES)), ids=lambda v: repr(v))
def test_bad_number_in_3d_is_refused_by_name_or_valid(path, value):
    """Every numeric field of a 3D scenario (z, vz, omega components, normals, points, the box,
    the force) set to -1, 0, NaN, inf, 1e300 or a string: valid, or one line naming the field."""
    try:
        validate(scenario_io.from_dict(mutated(BASE, path, value)))
    except ScenarioError as err:
        msg = str(err)
        assert "\n" not in msg and names_field(msg, path), msg


#: A sphere and a pair (one of a user material with a yield stress, spinning) against the
#: face xmin of a small clamped solid plate, with friction and a pair override.
BASE_SOLID: dict = {
    "name": "fuzz-solid",
    "description": "two spheres against a small solid plate",
    "dimension": 3,
    "materials": {"soft": {"E": 1e9, "nu": 0.3, "rho": 1200.0, "Y": 2e7}},
    "granules": [
        {"label": "a", "x": 0.0, "y": 0.01, "z": 0.01, "radius": 0.0025, "material": "steel", "vx": 1.0},
        {
            "label": "b",
            "x": -0.006,
            "y": 0.01,
            "z": 0.01,
            "radius": 0.0025,
            "material": "soft",
            "vx": 1.0,
            "omega": [0.0, 1.0, 0.0],
        },
    ],
    "plate": {
        "size": [0.004, 0.02, 0.02],
        "elements": [1, 2, 2],
        "origin": [0.0026, 0.0, 0.0],
        "material": "steel",
        "clamped": ["ymin", "ymax"],
        "max_frequency": 1e5,
    },
    "contact": {
        "mu": 0.1,
        "k_s": 1000.0,
        "alpha_n": 6e-3,
        "pairs": [{"materials": ["steel", "soft"], "alpha_n": 0.01, "mu": 0.2, "k_s": 500.0}],
    },
    "time": {"t_end": 2e-7, "dt_max": 5e-8, "output_interval": 1e-7, "field_interval": 2e-7},
    "solver": {"scheme": "verlet", "granular_friction": "split"},
}


def _example(name: str) -> dict:
    import tomllib

    with open(ROOT / "docs" / "examples" / f"{name}.toml", "rb") as f:
        return tomllib.load(f)


@pytest.mark.parametrize(
    "path,value",
    [
        *((("solid", p), v) for p, v in itertools.product(numeric_fields(BASE_SOLID), BAD_VALUES)),
        *(
            (("3d-fcc-protector", p), v)
            for p, v in itertools.product(numeric_fields(_example("3d-fcc-protector")), BAD_VALUES)
        ),
    ],
    ids=lambda v: repr(v),
)
def test_bad_number_with_a_solid_is_refused_by_name_or_valid(path, value):
    """Every numeric field of a 3D scenario with an elastic solid (its size, elements, origin,
    cut-off; a layout placing the solid against it; a yield stress) set to -1, 0, NaN, inf,
    1e300 or a string: valid, or one line naming that field (not one derived from it)."""
    source, field = path
    base = BASE_SOLID if source == "solid" else _example(source)
    try:
        validate(scenario_io.from_dict(mutated(base, field, value)))
    except ScenarioError as err:
        msg = str(err)
        assert "\n" not in msg and names_field(msg, field), msg


def test_a_dimension_out_of_range_is_named_before_the_tables():
    """dimension = 5 with a 3D [plate]: the error is the dimension's, not the plate's fields."""
    d = mutated(BASE_SOLID, "dimension", 5)
    assert refused(d).field == "dimension"


def test_a_3d_file_without_a_load_table_has_no_load():
    """A 3D file without [load] reads as load.kind = "none" (the plane's line load has no
    meaning in space), validates, and writes back to the same scenario."""
    from granplate.setup.validate import validate

    s = scenario_io.loads(
        'dimension = 3\n[[granules]]\nx = 0.0\ny = 0.0\nz = 0.0\nradius = 0.01\nmaterial = "steel"\nvx = 1.0\n'
    )
    assert s.load.kind == "none"
    validate(s)
    assert scenario_io.loads(scenario_io.dumps(s)) == s
