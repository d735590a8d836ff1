"""Sequential deposition (setup/deposition.py) against geometry and statics: the cone
projection equals a non-negative least squares' (scipy); a granule comes to rest on the
floor, in the pocket of three touching spheres and between two touching discs at the
heights of the tetrahedron and the triangle; every deposited granule of a packing rests
(gravity projected on the cone of its contacts vanishes) without overlap; the same seed
gives the same packing; a poured layout with drop = "sequential" settles to a static
balance of the real Hertz law, in space and in the plane; a bad `drop` is refused by name."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import nnls

from granplate.errors import ScenarioError
from granplate.results import pouring as rp
from granplate.setup import deposition, io, pouring
from granplate.setup.pairs import close_pairs
from granplate.setup.scenario import Contact, Gravity, PouredLayout, Scenario

G = 9.81
R = 1e-3


def no_nudges(n: int, d: int) -> np.ndarray:
    return np.zeros((n, deposition.TRIES, d - 1))


@pytest.mark.parametrize("d", [2, 3])
def test_cone_projection_is_the_least_squares(d):
    """g + N^T lambda with lambda = argmin |g + N^T lambda|, lambda >= 0 (scipy.optimize.nnls)."""
    rng = np.random.default_rng(5)
    g = np.zeros(d)
    g[-1] = -1.0
    for _ in range(200):
        m = int(rng.integers(1, 5))
        normals = rng.normal(size=(m, d))
        normals[:, -1] = np.abs(normals[:, -1]) * rng.choice([-0.3, 1.0])
        normals /= np.linalg.norm(normals, axis=1)[:, None]
        lam, _ = nnls(normals.T, -g)
        want = g + normals.T @ lam
        got = deposition.cone_projection(np.ascontiguousarray(normals), m, g, np.zeros(m))
        assert np.allclose(got, want, atol=1e-9)


def test_a_granule_falls_to_the_floor():
    """Alone, it falls straight down: centre at height R, where it was dropped across."""
    c, rel, _ = deposition.deposit(np.array([R]), (0.01, 0.01, 0.01), 2, -1.0, 0)
    assert c[0, 2] == pytest.approx(R, abs=1e-15)
    assert np.array_equal(c[0, :2], rel[0, :2]) and rel[0, 2] > R


def test_tetrahedral_pocket():
    """A sphere on three touching spheres of the same radius R on the floor rests at the
    height R + 2 R sqrt(2/3) (a regular tetrahedron of edge 2 R), over their centroid."""
    box = np.full(3, 0.02)
    base = np.array([[0.008, 0.008], [0.010, 0.008], [0.009, 0.008 + math.sqrt(3) * 1e-3]])
    centroid = base.mean(axis=0)
    start = np.vstack([np.column_stack([base, np.zeros(3)]), [[centroid[0] + 2e-4, centroid[1] - 1e-4, 0.0]]])
    radii = np.full(4, R)
    cell = 2.0 * R * (1.0 + deposition.ROLL_STEP + deposition.NUDGE)
    c, _, _ = deposition.deposit_frame(radii, start, box, 2, cell, no_nudges(4, 3))
    assert np.allclose(c[:3, 2], R, atol=1e-15)
    assert c[3, 2] == pytest.approx(R + 2.0 * R * math.sqrt(2.0 / 3.0), rel=1e-9)
    assert np.allclose(c[3, :2], centroid, atol=1e-9)


def test_disc_between_two_discs():
    """In the plane, a disc on two touching discs of the same radius on the floor rests at
    R + sqrt(3) R, midway."""
    box = np.array([0.02, 0.02])
    start = np.array([[0.009, 0.0], [0.011, 0.0], [0.0101, 0.0]])
    cell = 2.0 * R * (1.0 + deposition.ROLL_STEP + deposition.NUDGE)
    c, _, _ = deposition.deposit_frame(np.full(3, R), start, box, 1, cell, no_nudges(3, 2))
    assert c[2, 1] == pytest.approx(R + math.sqrt(3.0) * R, rel=1e-9)
    assert c[2, 0] == pytest.approx(0.010, abs=1e-12)


@pytest.mark.parametrize(("d", "n"), [(2, 150), (3, 400)])
def test_every_granule_rests_without_overlap(d, n):
    """No overlap beyond 1e-9 of a radius; gravity projected on the cone of each granule's
    touches (granules, floor, side walls) vanishes: a frictionless rigid equilibrium."""
    radii = np.random.default_rng(3).uniform(1e-3, 1.3e-3, n)
    side = math.ceil(n ** (1.0 / d)) * 2.4 * 1.3e-3
    c, _, steps = deposition.deposit(radii, (side,) * d, d - 1, -1.0, 3)
    assert steps.max() < deposition.MAX_STEPS
    pairs = close_pairs(c, 2.6e-3)
    i, j = pairs[:, 0], pairs[:, 1]
    gap = np.linalg.norm(c[i] - c[j], axis=1) - radii[i] - radii[j]
    assert gap.min() >= -1e-9 * radii.min()
    assert np.all(c - radii[:, None] >= -1e-15)  # above the floor, inside the side walls
    assert np.all(c[:, :-1] + radii[:, None] <= side + 1e-15)
    g = np.zeros(d)
    g[-1] = -1.0
    for k in range(n):
        tol = deposition.TOUCH * radii[k]  # the deposition's own touch
        normals = [np.eye(d)[-1]] if c[k, -1] - radii[k] <= tol else []
        for a in range(d - 1):
            if c[k, a] - radii[k] <= tol:
                normals.append(np.eye(d)[a])
            if side - radii[k] - c[k, a] <= tol:
                normals.append(-np.eye(d)[a])
        for p, q in pairs[(gap <= tol) & ((i == k) | (j == k))]:
            other = q if p == k else p
            normals.append((c[k] - c[other]) / np.linalg.norm(c[k] - c[other]))
        nm = np.array(normals, float).reshape(-1, d)
        rest = deposition.cone_projection(nm, len(nm), g, np.zeros(len(nm)))
        assert np.linalg.norm(rest) <= deposition.REST, (k, nm)


def test_same_seed_same_packing_and_the_floor_follows_gravity():
    """Two depositions of one seed are equal bit for bit; gravity along +x puts the floor at x = size."""
    radii = np.random.default_rng(1).uniform(1e-3, 1.2e-3, 50)
    a = deposition.deposit(radii, (0.012, 0.012, 0.012), 2, -1.0, 4)
    b = deposition.deposit(radii, (0.012, 0.012, 0.012), 2, -1.0, 4)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    c, _, _ = deposition.deposit(radii, (0.012, 0.012, 0.012), 0, 1.0, 4)
    assert np.max(c[:, 0] + radii) == pytest.approx(0.012, abs=1e-15)


def sequential(count: int, dimension: int, **kw) -> Scenario:
    g = (0.0, -G) if dimension == 2 else (0.0, 0.0, -G)
    lay = PouredLayout(count=count, radius_range=(0.001, 0.0013), seed=3, drop="sequential", **kw)
    return Scenario(dimension=dimension, layout=lay, gravity=Gravity(g), contact=Contact(pairs=()))


def test_sequential_packing_settles_to_a_hertz_balance(tmp_path, monkeypatch):
    """In space (the ramped settling's kernel at the real stiffness, frictional): settled,
    every granule in balance to settle_residual, and the floor carrying the weight within
    Coulomb's bound at the side walls, Hertz's forces recomputed from the centres."""
    from tests.test_poured_ramped import hertz_residuals, side_wall_forces

    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path))
    s = sequential(40, 3, settle_friction=0.5)
    arrays = rp.settle(s, s.layout)
    assert float(arrays["residual"]) <= s.layout.settle_residual
    assert float(arrays["kinetic"]) <= s.layout.settle_tolerance
    _, floor, weight = hertz_residuals(s, arrays["centres"], arrays["radii"])
    side = side_wall_forces(s, arrays["centres"], arrays["radii"])
    assert abs(weight - floor) <= s.layout.settle_friction * side + s.layout.settle_residual * weight


def test_sequential_packing_in_the_plane(tmp_path, monkeypatch):
    """In the plane (the time loop's phases): settled, the floor carrying the discs' weight."""
    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path))
    s = sequential(12, 2)
    arrays = rp.settle(s, s.layout)
    c, r = arrays["centres"], arrays["radii"]
    assert c.shape == (12, 2) and float(arrays["overlap"]) < 1e-3
    assert np.all(c[:, 1] < 6 * r.max())  # piled on the floor, not left in the air


def test_drop_is_checked_and_keyed():
    """An unknown drop is refused by name; "column" keys the store as before the field existed."""
    s = sequential(4, 3)
    bad = Scenario(dimension=3, layout=PouredLayout(count=4, drop="pile"), gravity=s.gravity)
    with pytest.raises(ScenarioError, match="layout.drop"):
        pouring.check_poured(bad, bad.layout)
    plain = Scenario(dimension=3, layout=PouredLayout(count=4), gravity=s.gravity)
    assert "drop" not in pouring.store_payload(plain, plain.layout)["layout"]
    assert pouring.store_payload(s, s.layout)["layout"]["drop"] == "sequential"
    assert "drop" not in io.dumps(plain) and 'drop = "sequential"' in io.dumps(s)
