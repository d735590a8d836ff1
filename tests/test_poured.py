"""Poured packings (`[layout] kind = "poured"`): the settled packing carries its weight on
the floor (statics: the floor's Hertz forces sum to the total weight), rests, is the same
for the same seed, is kept in the run store; the radii follow the requested distribution;
bad fields are refused by name."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import granplate.results.pouring  # noqa: F401  (registers the settling)
from granplate.errors import ScenarioError
from granplate.physics.contact import COEF_A
from granplate.setup import pouring
from granplate.setup.geometry import resolve
from granplate.setup.scenario import Contact, Gravity, PouredLayout, Scenario
from granplate.setup.validate import validate

G = 9.81


@pytest.fixture
def store_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path))
    return tmp_path


def poured(dimension: int, count: int = 24, **kw) -> Scenario:
    g = (0.0, -G) if dimension == 2 else (0.0, 0.0, -G)
    lay = PouredLayout(count=count, radius_range=(0.001, 0.0013), seed=3, **kw)
    return Scenario(dimension=dimension, layout=lay, gravity=Gravity(g), contact=Contact(pairs=()))


def floor_force_and_weight(s: Scenario) -> tuple[float, float]:
    """(the Hertz forces A delta^(3/2) of the granules on the floor (y = 0 in 2D, z = 0 in
    3D, against gravity), their total weight) [N]."""
    from granplate.model.arrays import build_model

    m = build_model(s)
    r = m.scenario
    label, axis = ("ymin", "y") if s.dimension == 2 else ("zmin", "z")
    floor = [k for k, w in enumerate(r.walls) if w.label == label][0]
    g = m.granular
    f = 0.0
    for c, (i, w) in enumerate(zip(g.wall_i, g.wall_w)):
        if w == floor:
            delta = g.radius[i] - getattr(r.granules[i], axis)
            f += g.wall_coef[c, COEF_A] * max(delta, 0.0) ** 1.5
    return f, float(g.mass.sum()) * G


@pytest.mark.parametrize(("dimension", "count"), [(2, 24), (3, 8)])
def test_settled_packing_carries_its_weight_on_the_floor(store_dir, dimension, count):
    """Statics: granules at rest in a box press on the floor with their whole weight (the
    side walls push sideways; their friction, held by nothing once at rest, carries none
    beyond the tolerance)."""
    s = poured(dimension, count)
    validate(s)
    r = resolve(s)
    assert len(r.granules) == count and r.contact.overlap_start > 0.0
    f, weight = floor_force_and_weight(s)
    assert f == pytest.approx(weight, rel=0.01)


def test_same_seed_same_packing_and_the_store_is_reused(store_dir, monkeypatch, tmp_path_factory):
    """The same seed settles to the same packing (in a fresh store); a second resolve reads
    the store and does not settle again."""
    s = poured(2, count=10)
    first = resolve(s).granules
    monkeypatch.setattr(pouring, "_SETTLER", [lambda *a: pytest.fail("settled again")])
    again = resolve(dataclasses.replace(s, name="again")).granules
    assert again == first
    monkeypatch.setattr(pouring, "_SETTLER", [granplate.results.pouring.settle])
    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path_factory.mktemp("fresh")))
    fresh = resolve(dataclasses.replace(s, name="fresh")).granules
    assert [(g.x, g.y) for g in fresh] == [(g.x, g.y) for g in first]


@pytest.mark.parametrize(
    ("changes", "mean", "std"),
    [
        ({"distribution": "uniform", "radius_range": (1e-3, 2e-3)}, 1.5e-3, 1e-3 / math.sqrt(12)),
        ({"distribution": "normal", "radius_range": (0.5e-3, 2.5e-3), "mean": 1.5e-3, "std": 0.2e-3}, 1.5e-3, 0.2e-3),
        ({"distribution": "lognormal", "radius_range": (0.1e-3, 10e-3), "mean": 1.5e-3, "std": 0.3e-3}, 1.5e-3, 0.3e-3),
    ],
)
def test_radii_follow_the_distribution(changes, mean, std):
    """Seeded samples of 20,000 radii: mean and std within 2% of the requested ones (the
    standard error of the mean is std / 141, under 0.2%)."""
    r = pouring.poured_radii(PouredLayout(count=20000, seed=7, **changes))
    assert r.mean() == pytest.approx(mean, rel=0.02)
    assert r.std() == pytest.approx(std, rel=0.02)
    assert r.min() >= changes["radius_range"][0] and r.max() <= changes["radius_range"][1]


def test_discrete_sizes_take_their_fractions():
    """Number fractions: the counts are the fractions x count, rounded."""
    r = pouring.poured_radii(
        PouredLayout(
            count=100, distribution="discrete", radius_range=(1e-3, 2e-3), sizes=(1e-3, 2e-3), fractions=(0.3, 0.7)
        )
    )
    assert np.count_nonzero(r == 1e-3) == 30 and np.count_nonzero(r == 2e-3) == 70


def test_loose_column_is_apart_and_inside():
    """The loose column: no two granules touch, none crosses a wall."""
    lay = PouredLayout(count=200, radius_range=(1e-3, 2e-3), seed=2)
    g = (0.0, 0.0, -G)
    r = pouring.poured_radii(lay)
    c = pouring.loose_column(lay, 3, g, r)
    d = np.linalg.norm(c[:, None] - c[None], axis=2) - r[:, None] - r[None]
    np.fill_diagonal(d, 1.0)
    assert d.min() > 0.0
    for w in pouring.container_walls(lay, 3, g):
        assert (c @ np.asarray(w.normal) + r < w.offset).all()


@pytest.mark.parametrize(
    ("changes", "field"),
    [
        ({"count": 0}, "layout.count"),
        ({"radius_range": (2e-3, 1e-3)}, "layout.radius_range"),
        ({"distribution": "discrete", "sizes": (1e-3,), "fractions": (0.5,)}, "layout.fractions"),
        ({"distribution": "normal", "mean": 1e-3}, "layout.std"),
        ({"distribution": "weibull"}, "layout.distribution"),
        ({"settle_tolerance": 2.0}, "layout.settle_tolerance"),
    ],
)
def test_bad_fields_are_refused_by_name(changes, field):
    """Each bad field is named before anything runs."""
    s = poured(2)
    with pytest.raises(ScenarioError) as err:
        validate(dataclasses.replace(s, layout=dataclasses.replace(s.layout, **changes)))
    assert err.value.field == field


def test_no_gravity_is_refused():
    """A poured packing needs layout.g or [gravity]."""
    s = dataclasses.replace(poured(2), gravity=None)
    with pytest.raises(ScenarioError) as err:
        validate(s)
    assert err.value.field == "layout.g"


def test_a_settling_that_does_not_converge_says_so_and_keeps_its_state(store_dir):
    """Too short a settle_time: refused naming it, with the residual, the state kept."""
    s = poured(2, count=8)
    s = dataclasses.replace(s, layout=dataclasses.replace(s.layout, settle_time=1e-4))
    with pytest.raises(ScenarioError) as err:
        resolve(s)
    assert err.value.field == "layout.settle_time" and "kinetic energy / gravity's work" in str(err.value)
    assert list((store_dir / "poured-partial").glob("*.npz"))


@pytest.mark.slow
def test_poured_protector_example_runs(store_dir):
    """docs/examples/poured-protector.toml settles, then its striker hits the packing and the
    plate takes energy while the balance (eq. 11) holds; the settled overlaps' stored energy
    is part of E_initial, so the granules' energy never exceeds what was put in."""
    from pathlib import Path

    from granplate.results.run import simulate
    from granplate.setup.io import load_scenario

    s = load_scenario(str(Path(__file__).resolve().parents[1] / "docs" / "examples" / "poured-protector.toml"))
    with pytest.warns(Warning):  # an 8 m/s steel striker passes the onset of yield, as it says
        ds = simulate(s, t_end=1.5e-4)
    striker = list(ds.granule.values).index("striker")
    assert ds.vx.values[-1, striker] < 0.9 * 8.0
    assert float(ds.E_plate.max()) > 0.0
    e0 = float(ds.E_granular.values[0] + ds.E_plate.values[0])
    assert ds.attrs["E_initial"] == pytest.approx(e0, rel=1e-12)
    assert float(ds.E_granular.max()) <= ds.attrs["E_initial"] * (1.0 + 1e-9)


def test_poured_protector_in_space_runs(store_dir):
    """docs/examples/3d-poured-protector.toml settles against the solid's face (its settled
    overlaps allowed by contact.overlap_start), its striker hits the packing, the solid takes
    energy, the contacts yield, and the balance (eq. 11) holds from E_initial."""
    from pathlib import Path

    from granplate.results.run import simulate
    from granplate.setup.geometry import resolve
    from granplate.setup.io import load_scenario

    s = load_scenario(str(Path(__file__).resolve().parents[1] / "docs" / "examples" / "3d-poured-protector.toml"))
    assert resolve(s).contact.overlap_start is not None
    with pytest.warns(Warning):  # a 2 m/s steel striker passes the onset of yield, as it says
        ds = simulate(s, t_end=1e-4)
    striker = list(ds.granule.values).index("striker")
    assert ds.vx.values[-1, striker] < 0.5 * 2.0
    assert float(ds.E_plate.max()) > 0.0
    assert float(ds.D_plastic.values[-1]) > 0.1 * ds.attrs["E_initial"]
    assert float(np.max(np.abs(ds.energy_residual.values))) < s.solver.energy_tol
