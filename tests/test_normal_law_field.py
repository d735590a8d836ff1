"""The scenario's choice of normal law (`contact.normal_law`, a pair's `normal_law`): its
default, the pair rule, TOML round trips and the refusals before anything runs
(docs/scenario.md, `[contact]`)."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest

from granplate.commands.resolve import resolved_toml
from granplate.errors import ScenarioError
from granplate.setup.geometry import resolve
from granplate.setup import io as scenario_io
from granplate.setup.materials import LIBRARY, Material
from granplate.setup.presets import PRESETS, preset
from granplate.setup.scenario import NORMAL_LAWS, Contact, Granule, Load, PairCoefficients, Plate, Scenario, Wall
from granplate.setup.validate import possible_contacts, validate

DOC = Path(__file__).resolve().parents[1] / "docs" / "scenario.md"
#: A material without a yield strength (Y unknown).
GLASS = Material("glass", E=6.3e10, nu=0.23, rho=2500.0)
#: The same glass with a yield strength [Pa].
HARD_GLASS = dataclasses.replace(GLASS, Y=1e9)
LEFT = Wall((-1.0, 0.0), 0.0, "left")


def _scene(
    materials: tuple[str, ...],
    walls: tuple[Wall, ...] = (),
    plate: Plate | None = None,
    glass: Material = GLASS,
    **contact,
) -> Scenario:
    """Granules of the given materials in a row along y = 0.05 (radius 5 mm, 1 mm gaps,
    the first one 1 mm right of x = 0), unloaded, with the contact fields given."""
    granules = tuple(Granule(0.006 + 0.011 * i, 0.05, 0.005, m, f"g{i}") for i, m in enumerate(materials))
    return Scenario(
        name="law",
        materials={**LIBRARY, "glass": glass},
        granules=granules,
        walls=walls,
        plate=plate,
        load=Load(kind="none"),
        contact=Contact(**contact),
    )


def _refused(s: Scenario) -> ScenarioError:
    with pytest.raises(ScenarioError) as info:
        validate(s)
    assert "\n" not in str(info.value)
    return info.value


def test_default_law_is_hertz_everywhere():
    """The default contact and every preset select "hertz" for every pair of their materials."""
    assert NORMAL_LAWS == ("hertz", "thornton", "johnson")
    assert Contact().normal_law == "hertz"
    for name in PRESETS:
        c = preset(name).contact
        for a in LIBRARY:
            for b in LIBRARY:
                assert c.law_for_pair(a, b) == "hertz", (name, a, b)


def test_pair_override_wins_with_the_rule_of_for_pair():
    """A pair's normal_law overrides the contact's for that pair only, in either order; an
    entry naming a material twice is the only one for that material with itself; a later
    entry with a law wins, one without a law leaves it; the default applies elsewhere."""
    c = Contact(
        normal_law="hertz",
        pairs=(
            PairCoefficients(("steel", "ptfe"), normal_law="thornton"),
            PairCoefficients(("ptfe", "ptfe"), normal_law="thornton"),
            PairCoefficients(("ptfe", "ptfe"), normal_law="hertz"),
            PairCoefficients(("steel", "ptfe"), alpha_n=0.1),
        ),
    )
    assert c.law_for_pair("steel", "ptfe") == c.law_for_pair("ptfe", "steel") == "thornton"
    assert c.law_index("ptfe", "steel") == 0
    assert c.law_for_pair("ptfe", "ptfe") == "hertz" and c.law_index("ptfe", "ptfe") == 2
    assert c.law_for_pair("steel", "steel") == "hertz" and c.law_index("steel", "steel") is None
    flipped = dataclasses.replace(c, normal_law="thornton")
    assert flipped.law_for_pair("steel", "steel") == "thornton"
    assert flipped.law_for_pair("ptfe", "ptfe") == "hertz"
    assert c.for_pair("steel", "ptfe") == (0.1, c.mu, c.k_s)  # the other coefficients as before


def test_toml_round_trip_keeps_both_fields():
    """normal_law at both levels is read from TOML, written back and read again equal; the
    default "hertz" is not written, so a preset's text is what it was."""
    text = (
        '[[granules]]\nx = 0.0\ny = 0.0\nradius = 0.01\nmaterial = "steel"\n'
        '[contact]\nnormal_law = "thornton"\n'
        '[[contact.pairs]]\nmaterials = ["steel", "ptfe"]\nnormal_law = "hertz"\n'
    )
    s = scenario_io.loads(text)
    assert s.contact.normal_law == "thornton"
    assert s.contact.pairs == (PairCoefficients(("steel", "ptfe"), normal_law="hertz"),)
    assert scenario_io.loads(scenario_io.dumps(s)) == s
    assert scenario_io.from_dict(scenario_io.to_dict(s)) == s
    assert 'normal_law = "thornton"' in scenario_io.dumps(s)
    steel = preset("steel-r1")
    assert "normal_law" not in scenario_io.dumps(steel)
    changed = scenario_io.with_changes(
        steel, {"contact.normal_law": "thornton", "contact.pairs[0].normal_law": "thornton"}
    )
    assert changed.contact.law_for_pair("ptfe", "steel") == "thornton"
    assert scenario_io.with_changes(changed, {"contact.normal_law": None}).contact.normal_law == "hertz"


def test_resolve_output_keeps_the_laws(tmp_path):
    """`granplate resolve` of a layout scenario with both fields set writes them, and its
    output reads back to the same laws."""
    s = scenario_io.with_changes(
        preset("ptfe-r05"), {"contact.normal_law": "thornton", "contact.pairs[0].normal_law": "hertz"}
    )
    f = tmp_path / "s.toml"
    scenario_io.dump(s, f)
    back = scenario_io.loads(resolved_toml(str(f)))
    assert back.layout is None and back.granules
    assert back.contact == s.contact


@pytest.mark.parametrize(
    "text, field",
    [
        ('[contact]\nnormal_law = "thorton"\n', "contact.normal_law"),
        ('[[contact.pairs]]\nmaterials = ["steel", "ptfe"]\nnormal_law = "Thornton"\n', "contact.pairs[0].normal_law"),
    ],
)
def test_misspelled_law_is_refused_on_reading_with_a_suggestion(text, field):
    """A misspelled law in a file is refused on reading, naming the field, the allowed
    values and the closest one."""
    with pytest.raises(ScenarioError) as info:
        scenario_io.loads(text)
    assert info.value.field == field
    assert "must be one of 'hertz', 'thornton', 'johnson' (did you mean 'thornton'?)" in str(info.value)


@pytest.mark.parametrize(
    "contact, field, value",
    [
        ({"normal_law": "plastic"}, "contact.normal_law", "plastic"),
        ({"normal_law": 1}, "contact.normal_law", 1),
        (
            {"pairs": (PairCoefficients(("steel", "steel"), normal_law="mindlin"),)},
            "contact.pairs[0].normal_law",
            "mindlin",
        ),
    ],
)
def test_unknown_law_in_python_is_refused_by_validate(contact, field, value):
    """A scenario built in Python with a law outside NORMAL_LAWS (or not a string) is
    refused by validate, naming the field and the allowed values."""
    err = _refused(_scene(("steel", "steel"), **contact))
    assert err.field == field and err.value == value
    assert "must be one of 'hertz', 'thornton', 'johnson'" in str(err)
    assert "did you mean" not in str(err)  # nothing close to suggest


@pytest.mark.parametrize(
    "s, field, material, kind",
    [
        (
            _scene(("glass", "glass"), normal_law="thornton"),
            "contact.normal_law",
            "glass",
            "granule-granule contacts glass-glass",
        ),
        (
            _scene(("steel", "glass"), normal_law="thornton"),
            "contact.normal_law",
            "glass",
            "granule-granule contacts steel-glass",
        ),
        (
            _scene(("glass",), walls=(LEFT,), normal_law="thornton"),
            "contact.normal_law",
            "glass",
            "granule-wall contacts glass-steel",
        ),
        (
            _scene(("glass",), plate=Plate(x0=0.02), normal_law="thornton"),
            "contact.normal_law",
            "glass",
            "granule-plate contacts glass-steel",
        ),
        (
            _scene(
                ("steel", "steel", "glass"),
                pairs=(
                    PairCoefficients(("steel", "steel"), normal_law="thornton"),
                    PairCoefficients(("glass", "steel"), alpha_n=0.1),
                    PairCoefficients(("glass", "steel"), normal_law="thornton"),
                ),
            ),
            "contact.pairs[2].normal_law",
            "glass",
            "granule-granule contacts steel-glass",
        ),
    ],
    ids=["glass-glass", "steel-glass", "glass-wall", "glass-plate", "pair override"],
)
def test_thornton_without_yield_strength_is_refused(s, field, material, kind):
    """ "thornton" at a pair that can occur, with a yielding body whose material has no Y,
    is refused naming the field that set the law, the material, the contact and the fix."""
    err = _refused(s)
    assert err.field == field and err.value == "thornton"
    assert (f"needs the yield strength of material '{material}' ({kind}): set materials.{material}.Y [Pa]") in str(err)


@pytest.mark.parametrize(
    "s",
    [
        _scene(("glass",), normal_law="thornton"),
        _scene(("steel", "glass"), walls=(LEFT,), plate=Plate(x0=0.03), glass=HARD_GLASS, normal_law="thornton"),
        _scene(
            ("steel", "steel"),
            walls=(dataclasses.replace(LEFT, material="glass"),),
            plate=Plate(x0=0.03, material="glass"),
            normal_law="thornton",
        ),
        _scene(("steel", "glass"), pairs=(PairCoefficients(("glass", "glass"), normal_law="thornton"),)),
        _scene(
            ("glass", "glass"), normal_law="thornton", pairs=(PairCoefficients(("glass", "glass"), normal_law="hertz"),)
        ),
    ],
    ids=["one granule alone", "every Y given", "rigid bodies of glass", "pair that cannot occur", "hertz override"],
)
def test_thornton_where_no_yielding_body_lacks_y_is_accepted(s):
    """ "thornton" is accepted where every body that can yield has a Y: a lone granule
    touches nothing, walls and the plate never yield, a pair override on materials that
    never meet needs nothing, and a "hertz" override takes the pair out."""
    validate(s)


def test_possible_contacts_are_the_pairs_the_scenario_can_hold():
    """The material pairs that can touch: each pair of granule materials once (a material
    with itself only when two granules share it), each granule material with each wall
    material and with the plate's."""
    bottom = Wall((0.0, -1.0), 0.0, "bottom", "ptfe")
    s = _scene(("steel", "glass", "steel"), walls=(LEFT, bottom), plate=Plate(x0=0.04, material="ptfe"))
    assert possible_contacts(s) == [
        ("granule-granule", "steel", "steel"),
        ("granule-granule", "steel", "glass"),
        ("granule-wall", "steel", "steel"),
        ("granule-wall", "steel", "ptfe"),
        ("granule-wall", "glass", "steel"),
        ("granule-wall", "glass", "ptfe"),
        ("granule-plate", "steel", "ptfe"),
        ("granule-plate", "glass", "ptfe"),
    ]


def test_layout_scenario_is_refused_the_same_way():
    """A [layout] whose intruders are of a material without Y is refused under "thornton"
    as the same granules written out (`geometry.resolve`) are, and accepted once the
    material has a Y."""
    glass = {"materials.glass": {"E": GLASS.E, "nu": GLASS.nu, "rho": GLASS.rho}}
    s = scenario_io.with_changes(
        preset("steel-r1"), {**glass, "layout.intruder_material": "glass", "contact.normal_law": "thornton"}
    )
    validate(scenario_io.with_changes(s, {"contact.normal_law": "hertz"}))
    err = _refused(s)
    assert err.field == "contact.normal_law"
    assert "material 'glass' (granule-granule contacts steel-glass)" in str(err)
    written_out = resolve(s)
    assert written_out.layout is None and len(written_out.granules) == 14
    assert str(_refused(written_out)) == str(err)
    validate(scenario_io.with_changes(s, {"materials.glass.Y": 1e9}))


def test_every_contact_field_is_documented():
    """docs/scenario.md has a row for every [contact] field and names every pair field."""
    doc = DOC.read_text()
    for f in dataclasses.fields(Contact):
        assert f"| `{f.name}` |" in doc, f.name
    start = doc.index("Each `[[contact.pairs]]` table")
    pairs = doc[start : doc.index("\n\n", start)]
    for f in dataclasses.fields(PairCoefficients):
        assert re.search(rf"`{f.name}[` ]", pairs), f.name
