"""The set-up's numpy passes against the equations granule by granule and pair by pair: the
contact coefficients of eqs. (3)-(4) (`pair_coefficient_row`, `wall_coefficient_row`),
the masses, the touching pairs (`is_contact`), bit for bit, on a polydisperse packing of
three materials with pair overrides and an elastic-plastic pair; and validation's
vectorised checks raise the message of the granule-by-granule check."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from granplate.errors import ScenarioError
from granplate.model.arrays import (
    masses_and_inertias,
    pair_coefficient_row,
    pair_coefficients,
    wall_arrays,
    wall_coefficient_row,
)
from granplate.model.neighbours import candidate_pairs, contact_pairs, is_contact
from granplate.physics.contact import COEF_DY
from granplate.setup.materials import LIBRARY, sphere_inertia, sphere_mass
from granplate.setup.scenario import Contact, Granule, PairCoefficients, Scenario, Wall
from granplate.setup.validate import validate


def _scenario(n: int = 300, seed: int = 3) -> Scenario:
    rng = np.random.default_rng(seed)
    names = ["steel", "ptfe", "glass"] if "glass" in LIBRARY else ["steel", "ptfe", "aluminium"]
    names = [m for m in names if m in LIBRARY][:3]
    side = round(n ** (1 / 3)) + 1
    granules = []
    for k in range(n):
        c = np.array([k % side, (k // side) % side, k // side**2], float) * 2.0e-3 + 1.5e-3
        r = float(rng.uniform(0.6e-3, 0.85e-3))
        granules.append(
            Granule(
                *(c + rng.uniform(-1e-4, 1e-4, 3))[:2].tolist(),
                radius=r,
                material=names[k % len(names)],
                label=f"g{k}",
                vx=float(rng.normal()),
                omega=tuple(rng.normal(size=3).tolist()),
                z=float(c[2]),
            )
        )
    pairs = (
        PairCoefficients((names[0], names[1]), alpha_n=0.05, mu=0.3),
        PairCoefficients((names[1], names[1]), normal_law="thornton"),
    )
    walls = (Wall((-1.0, 0.0, 0.0), 0.0, "xmin"), Wall((0.0, 0.0, 2.0), 0.02 + 1e-3, "top", material=names[1]))
    return Scenario(
        dimension=3, granules=tuple(granules), walls=walls, contact=Contact(pairs=pairs, skin=0.5, neighbour_gap=0.4)
    )


def test_contact_coefficients_equal_the_pair_by_pair_equations_bit_for_bit():
    s = _scenario()
    mats = [s.material(g.material) for g in s.granules]
    r = np.array([g.radius for g in s.granules])
    rho = np.array([m.rho for m in mats])
    mass, inertia = masses_and_inertias(r, rho)
    assert mass.tolist() == [sphere_mass(a, b) for a, b in zip(r, rho)]
    assert inertia.tolist() == [sphere_inertia(a, b) for a, b in zip(r, rho)]
    x, y, z = (np.array([getattr(g, f) for g in s.granules]) for f in "xyz")
    pairs = candidate_pairs(x, y, 2.5 * r.max(), z)
    assert len(pairs) > 500
    got = pair_coefficients(s, mats, r, mass, pairs)
    want = np.array([pair_coefficient_row(s, mats[i], mats[j], r[i], r[j], mass[i], mass[j]) for i, j in pairs])
    assert np.isfinite(want[:, COEF_DY]).any() and np.isinf(want[:, COEF_DY]).any()  # both laws present
    np.testing.assert_array_equal(got, want)
    wc = np.array([(i, w) for w in range(2) for i in range(0, len(r), 7)])
    geo, coef = wall_arrays(s, mats, r, mass, wc)
    np.testing.assert_array_equal(
        coef, [wall_coefficient_row(s, mats[i], s.walls[w].material, r[i], mass[i]) for i, w in wc]
    )
    np.testing.assert_array_equal(geo[:, 3], [s.walls[w].offset for _, w in wc])


def test_touching_pairs_equal_the_exact_test_pair_by_pair():
    s = _scenario(200, seed=5)
    x, y, z, r = (np.array([getattr(g, f) for g in s.granules]) for f in ("x", "y", "z", "radius"))
    cand = candidate_pairs(x, y, 3.0 * r.max(), z)
    want = [(i, j) for i, j in cand.tolist() if is_contact(x[j] - x[i], y[j] - y[i], r[i], r[j], 0.4, z[j] - z[i])]
    assert 0 < len(want) < len(cand)
    assert contact_pairs(x, y, r, 0.4, z).tolist() == [list(p) for p in want]
    # a pair exactly at the limit, decided by is_contact itself
    edge = 2.0 + 0.4 * 1.0
    xs, ys, zs, rs = np.array([0.0, edge]), np.zeros(2), np.zeros(2), np.ones(2)
    assert contact_pairs(xs, ys, rs, 0.4, zs).tolist() == (
        [[0, 1]] if is_contact(edge, 0.0, 1.0, 1.0, 0.4, 0.0) else []
    )


@pytest.mark.parametrize(
    "change,field,allowed",
    [
        ({"radius": -1.0}, "granules[57].radius", "must be > 0"),
        ({"vx": math.inf}, "granules[57].vx", "must be a finite number"),
        ({"x": 1e300}, "granules[57].x", "allowed: |value| <= "),
        ({"label": "g3"}, "granules[57].label", "labels must be unique; granules[3] has it too"),
        ({"material": "unobtainium"}, "granules[57].material", "unknown material"),
        ({"omega": (0.0, 1e9, 0.0)}, "granules[57].omega[1]", "allowed: |omega[1]| x radius < sqrt(E / rho)"),
    ],
)
def test_vectorised_checks_raise_the_granule_by_granule_message(change, field, allowed):
    s = _scenario(120, seed=7)
    s = dataclasses.replace(
        s, walls=(), granules=tuple(dataclasses.replace(g, vx=0.0, omega=(0.0, 0.0, 0.0)) for g in s.granules)
    )
    validate(s)
    gs = list(s.granules)
    gs[57] = dataclasses.replace(gs[57], **change)
    with pytest.raises(ScenarioError) as e:
        validate(dataclasses.replace(s, granules=tuple(gs)))
    assert e.value.field == field and e.value.allowed.startswith(allowed)
