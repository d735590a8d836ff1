"""A poured packing settled with Mindlin's friction (layout.settle_friction): it reaches the
settling criterion, every granule is at rest, and it is in static equilibrium: the floor's
Hertz reaction differs from the total weight by no more than the side walls' friction can
carry (Coulomb: mu x their normal forces), the statics of a frictional packing in a box."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.errors import ScenarioError
from granplate.physics.contact import COEF_A
from granplate.results import pouring as rp
from granplate.setup import pouring
from granplate.setup.materials import LIBRARY, Material
from granplate.setup.scenario import Contact, Gravity, PouredLayout, Scenario

G = 9.81
MU = 0.5
#: A granule at rest: its speed [m/s] below this, a hundredth of a millimetre per second
#: (the fall ends at about 0.3 m/s).
REST_SPEED = 1e-5
#: Millimetre spheres of a steel a hundred times softer: the same statics (overlaps of tens
#: of nanometres, still far below the radius) at steps 100^(2/5) = 6.3 times longer, so the test is fast.
SOFT = Material(name="soft", E=2.0e9, nu=0.3, rho=7800.0)


def poured(count: int = 30, dimension: int = 3, **kw) -> Scenario:
    g = (0.0, -G) if dimension == 2 else (0.0, 0.0, -G)
    lay = PouredLayout(
        count=count,
        radius_range=(0.001, 0.0013),
        seed=3,
        settle_friction=MU,
        material="soft",
        wall_material="soft",
        **kw,
    )
    return Scenario(
        dimension=dimension,
        layout=lay,
        gravity=Gravity(g),
        contact=Contact(pairs=()),
        materials={**LIBRARY, "soft": SOFT},
    )


def wall_forces(s: Scenario, centres: np.ndarray) -> tuple[float, float, float]:
    """(the floor's Hertz force, the side walls' Hertz forces summed, the total weight) [N]
    of the granules at `centres`."""
    from granplate.model.arrays import build_model

    model = build_model(rp.loose_scenario(s, s.layout, s.layout.settle_damping, MU))
    gr, walls = model.granular, model.scenario.walls
    m = gr.mass
    floor, side = 0.0, 0.0
    for k, w in enumerate(walls):
        n = np.asarray(w.normal, float)
        delta = np.maximum(centres @ n + gr.radius - w.offset, 0.0)  # the wall's plane at n.x = offset
        rows = [c for c, (i, ww) in enumerate(zip(gr.wall_i, gr.wall_w)) if ww == k]
        a = gr.wall_coef[rows[0], COEF_A] if rows else 0.0
        f = float(np.sum(a * delta**1.5))
        floor, side = (floor + f, side) if w.label == "zmin" else (floor, side + f)
    return floor, side, float(m.sum()) * G


def test_settled_with_friction_rests_in_equilibrium(tmp_path, monkeypatch):
    """Criterion reached, every granule at rest, and |W - F_floor| <= mu sum N_side."""
    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path))
    s = poured()
    pouring.check_poured(s, s.layout)
    ends = []
    end_state = rp._end_state
    monkeypatch.setattr(rp, "_end_state", lambda ds: ends.append(end_state(ds)) or ends[-1])
    arrays = rp.settle(s, s.layout)
    last = ends[-1]
    assert np.abs(last[:, 3:6]).max() < REST_SPEED
    assert np.allclose(arrays["centres"], last[:, :3])
    floor, side, weight = wall_forces(s, arrays["centres"])
    assert abs(weight - floor) <= MU * side + 1e-3 * weight
    assert floor == pytest.approx(weight, rel=0.2)


@pytest.mark.parametrize(("value", "dimension"), [(-0.1, 3), (2.5, 3), (0.3, 2)])
def test_bad_settle_friction_is_refused_by_name(value, dimension):
    s = poured(dimension=dimension)
    s = Scenario(
        dimension=dimension,
        layout=PouredLayout(count=4, settle_friction=value),
        materials=s.materials,
        gravity=s.gravity,
        contact=Contact(pairs=()),
    )
    with pytest.raises(ScenarioError, match="layout.settle_friction"):
        pouring.check_poured(s, s.layout)


def test_without_settle_friction_the_store_key_is_unchanged():
    """A layout without settle_friction keys the run store as before the field existed."""
    s = poured(settle_time=2.0)
    plain = Scenario(
        dimension=3, layout=PouredLayout(count=30, radius_range=(0.001, 0.0013), seed=3), gravity=s.gravity
    )
    assert "settle_friction" not in pouring.store_payload(plain, plain.layout)["layout"]
    assert pouring.store_payload(s, s.layout)["layout"]["settle_friction"] == MU
