"""Space lattices sized in lattice planes (`layout.planes`, `layout.layers[k].planes`):
truth is the lattice sized in cells, whose first planes an odd count of planes reproduces
site for site (fcc: two planes a cell, stacked ABAB), and the rule that a size is given
one way only."""

from __future__ import annotations

import dataclasses

import pytest

from granplate.errors import ScenarioError
from granplate.setup.geometry import layout_packing
from granplate.setup.scenario import Layer, Load, Scenario, SpaceLattice
from granplate.setup.validate import validate

R = 0.005


def _sites(lay) -> list[tuple]:
    return sorted(
        (round(g.x, 12), round(g.y, 12), round(g.z, 12), g.radius, g.material) for g in layout_packing(lay).granules
    )


def _scenario(lay) -> Scenario:
    return Scenario(dimension=3, layout=lay, load=Load(kind="force", force=10.0))


@pytest.mark.parametrize("kind", ["fcc", "bcc", "hcp", "sc"])
def test_an_odd_number_of_planes_is_the_first_planes_of_the_cells(kind):
    """planes = 3 gives the first three lattice planes of cells[0] = 3 (ABA for fcc), and
    planes = 2 x cells (1 x for sc) gives the cells' packing exactly."""
    cells = SpaceLattice(kind=kind, cells=(3, 2, 2), radius=R, walls=())
    three = dataclasses.replace(cells, cells=(0, 2, 2), planes=3)
    xs = sorted({x for x, *_ in _sites(cells)})[:3]
    assert _sites(three) == [s for s in _sites(cells) if s[0] in xs]
    per_cell = 1 if kind == "sc" else 2
    assert _sites(dataclasses.replace(three, planes=3 * per_cell)) == _sites(cells)
    validate(_scenario(three))


def test_layers_in_planes_mix_with_layers_in_cells():
    """A layer of 3 planes then one cell of smaller PTFE spheres: 5 planes, the radii and
    materials plane by plane."""
    lay = SpaceLattice(
        kind="fcc",
        cells=(0, 2, 2),
        radius=R,
        walls=(),
        layers=(Layer(planes=3), Layer(count=1, radius=0.8 * R, material="ptfe")),
    )
    by_x: dict[float, set] = {}
    for x, _, _, r, m in _sites(lay):
        by_x.setdefault(x, set()).add((r, m))
    assert [by_x[x] for x in sorted(by_x)] == [{(R, "steel")}] * 3 + [{(0.8 * R, "ptfe")}] * 2
    validate(_scenario(lay))


@pytest.mark.parametrize(
    "lay, field, names",
    [
        (SpaceLattice(kind="fcc", cells=(2, 2, 2), planes=3), "layout.planes", "layout.cells[0]"),
        (
            SpaceLattice(kind="fcc", cells=(0, 2, 2), planes=3, layers=(Layer(count=1),)),
            "layout.planes",
            "layout.layers",
        ),
        (
            SpaceLattice(kind="fcc", cells=(0, 2, 2), layers=(Layer(count=1, planes=3),)),
            "layout.layers[0].planes",
            "layout.layers[0].count",
        ),
        (SpaceLattice(kind="fcc", cells=(0, 2, 2), planes=0), "layout.planes", "integer >= 1"),
    ],
)
def test_a_size_given_two_ways_is_refused_naming_both(lay, field, names):
    """Refused before anything runs, the message naming both fields."""
    with pytest.raises(ScenarioError) as err:
        validate(_scenario(lay))
    assert err.value.field == field and names in str(err.value)
