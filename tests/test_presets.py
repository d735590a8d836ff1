"""The paper's six cases as presets (docs/model.md section 8)."""

from __future__ import annotations

import pytest

from granplate.setup import io as scenario_io
from granplate.errors import ScenarioError
from granplate.setup.geometry import resolve
from granplate.setup.presets import DESCRIPTIONS, preset, preset_names
from granplate.setup.scenario import Contact, Plate, Solver, TimeSettings
from granplate.setup.validate import validate

NAMES = ["bare-plate", "steel-r1", "steel-r05", "ptfe-r05", "ptfe-r05-moderate", "ptfe-r05-weak"]


def test_exactly_the_six_paper_cases():
    """preset_names() lists exactly the six cases of docs/model.md section 8, each described with a paper figure."""
    assert preset_names() == NAMES
    for n in NAMES:
        s = preset(n)
        assert s.name == n
        assert "Fig." in s.description and s.description == DESCRIPTIONS[n]


@pytest.mark.parametrize("name", NAMES)
def test_toml_round_trip(name, tmp_path):
    """dumps then loads (and dump then load) of every preset gives an equal Scenario."""
    s = preset(name)
    assert scenario_io.loads(scenario_io.dumps(s)) == s
    path = tmp_path / f"{name}.toml"
    scenario_io.dump(s, path)
    assert scenario_io.load(path) == s
    assert scenario_io.load_scenario(str(path)) == s


@pytest.mark.parametrize("name", NAMES)
def test_presets_are_valid_with_paper_defaults(name):
    """Every preset validates and uses the default contact, time and solver settings (the
    granules' friction inside RK4, as its golden results were computed)."""
    s = preset(name)
    validate(s)
    assert s.contact == Contact() and s.contact.for_pair("steel", "ptfe")[0] == 6.313e-2
    assert s.time == TimeSettings() and s.time.t_end == 2e-3
    assert s.solver == Solver(granular_friction="rk4")


@pytest.mark.parametrize(
    "name, q0",
    [
        ("bare-plate", 50_000.0),
        ("steel-r1", 50_000.0),
        ("steel-r05", 50_000.0),
        ("ptfe-r05", 50_000.0),
        ("ptfe-r05-moderate", 10_000.0),
        ("ptfe-r05-weak", 2_000.0),
    ],
)
def test_shock_intensities(name, q0):
    """q0 is 50 kN/m for the main cases, 10 kN/m and 2 kN/m for the moderate and weak ones."""
    assert preset(name).load.q0 == q0


def test_setups():
    """bare-plate loads a plate at x0 = 0 with no granules; the others load the granules of their layout."""
    b = preset("bare-plate")
    assert b.granules == () and b.walls == () and b.layout is None
    assert b.plate == Plate(x0=0.0) and b.load.target == "plate"
    expected = {
        "steel-r1": (1.0, "steel"),
        "steel-r05": (0.5, "steel"),
        "ptfe-r05": (0.5, "ptfe"),
        "ptfe-r05-moderate": (0.5, "ptfe"),
        "ptfe-r05-weak": (0.5, "ptfe"),
    }
    for n, (ratio, mat) in expected.items():
        s = preset(n)
        assert (s.layout.R2_ratio, s.layout.intruder_material) == (ratio, mat)
        assert s.plate == Plate() and s.load.target == "granules"
        assert len(resolve(s).granules) == 14


def test_preset_by_name_and_unknown_name():
    """load_scenario accepts a preset name; an unknown name lists the presets."""
    assert scenario_io.load_scenario("ptfe-r05") == preset("ptfe-r05")
    with pytest.raises(ScenarioError, match="presets are: bare-plate"):
        preset("steel-r2")


def test_with_changes_tweaks_a_preset():
    """with_changes sets dotted paths on a preset and leaves the rest equal."""
    s = preset("steel-r1")
    t = scenario_io.with_changes(s, {"load.q0": 1e4, "time.t_end": 1e-4, "layout.R2_ratio": 0.5, "plate.ny": 80})
    assert (t.load.q0, t.time.t_end, t.layout.R2_ratio, t.plate.ny) == (1e4, 1e-4, 0.5, 80)
    assert t.contact == s.contact and t.materials == s.materials
    assert scenario_io.with_changes(s, {}) == s
    assert scenario_io.with_changes(s, {"plate": None}).plate is None
    m = scenario_io.with_changes(s, {"materials.ptfe.E": 1e9})
    assert m.material("ptfe").E == 1e9 and m.material("steel") == s.material("steel")
