"""The paper's packing (docs/model.md section 1) and scenario resolution."""

from __future__ import annotations

import dataclasses
import math

import pytest

from granplate.errors import ScenarioError
from granplate.setup.geometry import column_offset, paper_layout, resolve
from granplate.setup.scenario import Granule, Layout, Plate, Scenario, Wall

RATIOS = [math.sqrt(2.0) - 1.0, 0.5, 0.75, 1.0]
R1 = 0.01


def _by_label(granules):
    return {g.label: g for g in granules}


def _dist(a, b):
    return math.hypot(a.x - b.x, a.y - b.y)


@pytest.mark.parametrize("ratio", RATIOS)
def test_intruders_touch_their_four_heavy_neighbours(ratio):
    """Each intruder 6..9 is at distance exactly R1 + R2 from its two column-1 and two column-3 neighbours."""
    gs, _, _ = paper_layout(Layout(R1=R1, R2_ratio=ratio))
    g = _by_label(gs)
    neighbours = {"6": "12AB", "7": "23BC", "8": "34CD", "9": "45DE"}
    for intr, heavy in neighbours.items():
        assert g[intr].radius == pytest.approx(ratio * R1, abs=1e-15)
        for h in heavy:
            assert abs(_dist(g[intr], g[h]) - (R1 + ratio * R1)) < 1e-12, (intr, h)


@pytest.mark.parametrize("ratio", RATIOS)
def test_boundaries_touch_the_right_granules(ratio):
    """A..E touch the plate edge, 1..5 the left wall, 1 and A the top wall, 5 and E the bottom wall."""
    gs, walls, xp = paper_layout(Layout(R1=R1, R2_ratio=ratio))
    g = _by_label(gs)
    w = {wall.label: wall for wall in walls}

    def gap(gr: Granule, wall: Wall) -> float:
        return wall.offset - (gr.x * wall.normal[0] + gr.y * wall.normal[1]) - gr.radius

    for lab in "ABCDE":
        assert abs(xp - (g[lab].x + g[lab].radius)) < 1e-12
    for lab in "12345":
        assert abs(gap(g[lab], w["left"])) < 1e-12
    for lab in "1A":
        assert abs(gap(g[lab], w["top"])) < 1e-12
    for lab in "5E":
        assert abs(gap(g[lab], w["bottom"])) < 1e-12
    # and nothing crosses any wall or the plate
    for gr in gs:
        assert all(gap(gr, wall) > -1e-12 for wall in walls)
        assert gr.x + gr.radius <= xp + 1e-12


def test_layout_order_labels_materials_and_walls():
    """Granules come as 1..9, A..E with heavy/intruder materials; walls left, bottom, top as specified."""
    gs, walls, xp = paper_layout(Layout(R2_ratio=0.5, intruder_material="ptfe"))
    assert [g.label for g in gs] == list("123456789ABCDE")
    assert [g.material for g in gs] == ["steel"] * 5 + ["ptfe"] * 4 + ["steel"] * 5
    assert [g.y for g in gs[:5]] == pytest.approx([0.09, 0.07, 0.05, 0.03, 0.01])
    assert [g.y for g in gs[5:9]] == pytest.approx([0.08, 0.06, 0.04, 0.02])
    assert [(w.label, w.normal, w.offset) for w in walls] == [
        ("left", (-1.0, 0.0), 0.0),
        ("bottom", (0.0, -1.0), 0.0),
        ("top", (0.0, 1.0), 0.1),
    ]
    d = column_offset(0.01, 0.005)
    assert xp == pytest.approx(0.01 + 2 * d + 0.01, abs=1e-15)


def test_half_radius_intruders_give_d_1_1180_R1():
    """R2 = 0.5 R1 gives d = sqrt(1.25) R1 = 1.1180 R1; R2 = R1 gives sqrt(3) R1 (hexagonal)."""
    assert column_offset(R1, 0.5 * R1) / R1 == pytest.approx(1.1180, abs=5e-5)
    assert column_offset(R1, R1) / R1 == pytest.approx(math.sqrt(3.0), rel=1e-14)
    gs, _, _ = paper_layout(Layout(R1=R1, R2_ratio=0.5))
    g = _by_label(gs)
    assert (g["8"].x - g["3"].x) / R1 == pytest.approx(1.1180, abs=5e-5)


def test_resolve_expands_layout_and_places_plate():
    """resolve fills granules, walls and plate.x0 from the layout, drops the layout, and is idempotent."""
    s = Scenario(layout=Layout(R2_ratio=0.5), plate=Plate())
    r = resolve(s)
    gs, walls, xp = paper_layout(s.layout)
    assert r.layout is None and r.granules == gs and r.walls == walls
    assert r.plate.x0 == xp
    assert resolve(r) == r
    # an explicit plate.x0 is kept
    s2 = dataclasses.replace(s, plate=Plate(x0=0.2))
    assert resolve(s2).plate.x0 == 0.2


def test_resolve_labels_unlabelled_granules_and_walls():
    """Unlabelled granules/walls get 'g<i>'/'w<i>' labels; labelled ones keep theirs."""
    s = Scenario(
        granules=(Granule(0.0, 0.0, 0.01, "steel"), Granule(0.03, 0.0, 0.01, "steel", label="b")),
        walls=(Wall((-1.0, 0.0), 0.01),),
    )
    r = resolve(s)
    assert [g.label for g in r.granules] == ["g0", "b"]
    assert [w.label for w in r.walls] == ["w0"]


def test_resolve_refuses_plate_without_position_or_layout_with_granules():
    """A plate with x0 = None and no layout, or a layout plus explicit granules, is a ScenarioError."""
    with pytest.raises(ScenarioError, match="plate.x0"):
        resolve(Scenario(plate=Plate()))
    with pytest.raises(ScenarioError, match="granules"):
        resolve(Scenario(layout=Layout(), granules=(Granule(0.0, 0.0, 0.01, "steel"),)))
