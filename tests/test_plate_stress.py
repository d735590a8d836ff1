"""The disc-averaged von Mises stress (granplate.plate.stress, docs/model.md section 4.4)
against closed-form means over discs, half discs and quarter discs, and against a field
with the rigid-punch singularity r^(-1/2), whose point peak has no mesh limit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from granplate import plate as gp
from granplate.plate.stress import (
    DISC_CENTRE_SPACING,
    disc_average_operator,
    disc_centres,
    max_disc_average,
    quadrature_points,
)

WIDTH, HEIGHT, RADIUS = 0.01, 0.1, 0.0025
MESHES = ((4, 40), (8, 80), (16, 160))


def _points(nx: int, ny: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss points [m] and weights [m^2] of the nx x ny Q8 plate [0, WIDTH] x [0, HEIGHT]."""
    basis = gp.q8_basis(gp.plate_mesh(0.0, 0.0, WIDTH, HEIGHT, nx, ny))
    return quadrature_points(basis).reshape(-1, 2), np.asarray(basis.dx).ravel()


def _row(centres: np.ndarray, point: tuple[float, float]) -> int:
    return int(np.argmin(np.linalg.norm(centres - np.asarray(point), axis=1)))


def test_disc_centres_are_a_mesh_free_lattice_over_the_plate():
    """Corners and edges included, spacing at most the one asked, whatever the mesh."""
    c = disc_centres(0.05, 0.0, WIDTH, HEIGHT, DISC_CENTRE_SPACING * RADIUS)
    assert c.shape == (17 * 161, 2)
    for corner in ((0.05, 0.0), (0.06, 0.1)):
        assert np.min(np.linalg.norm(c - corner, axis=1)) < 1e-15
    assert np.diff(np.unique(c[:, 1])).max() <= DISC_CENTRE_SPACING * RADIUS * (1 + 1e-12)


@pytest.mark.parametrize("centre, share", [((0.005, 0.05), 1.0), ((0.0, 0.05), 0.5), ((0.0, 0.0), 0.25)])
def test_mean_of_squared_distance_converges_to_r2_over_2(centre, share):
    """Mean of rho^2 over a disc, a half disc (edge) or a quarter disc (corner) of radius r is
    r^2 / 2; the rows are weights summing to 1 (a constant is averaged exactly); the error
    falls with the mesh (the quadrature of the disc's indicator: about first order)."""
    errors = []
    for nx, ny in MESHES:
        pts, w = _points(nx, ny)
        centres = np.array([centre])
        op = disc_average_operator(pts, w, centres, RADIUS)
        np.testing.assert_allclose(np.asarray(op.sum(axis=1)).ravel(), 1.0, rtol=1e-14)
        rho2 = np.sum((pts - centre) ** 2, axis=1)
        errors.append(abs(float((op @ rho2)[0]) / (0.5 * RADIUS**2) - 1))
        area = float(w[np.sum((pts - centre) ** 2, axis=1) <= RADIUS**2].sum())
        assert area == pytest.approx(share * math.pi * RADIUS**2, rel=0.25)
    assert errors[-1] < 0.03 and errors[2] < errors[0] / 2


def test_punch_singularity_point_peak_grows_but_disc_mean_converges():
    """f = rho^(-1/2) about a point of the left edge (a rigid flat punch's end): the largest
    Gauss-point value grows as h^(-1/2) under refinement, while its mean over the half disc
    of radius r converges to the closed form (4/3) r^(-1/2)."""
    tip = (0.0, 0.05)
    exact = 4.0 / 3.0 / math.sqrt(RADIUS)
    peaks, means = [], []
    for nx, ny in MESHES:
        pts, w = _points(nx, ny)
        f = np.sum((pts - tip) ** 2, axis=1) ** -0.25
        centres = disc_centres(0.0, 0.0, WIDTH, HEIGHT, DISC_CENTRE_SPACING * RADIUS)
        op = disc_average_operator(pts, w, centres, RADIUS)
        peaks.append(f.max())
        means.append(float((op @ f)[_row(centres, tip)]))
    assert all(b > 1.3 * a for a, b in zip(peaks, peaks[1:]))  # 2^(1/2) per halving
    errors = [abs(m / exact - 1) for m in means]
    assert errors[-1] < 0.05 and errors[-1] < errors[0]


def test_max_disc_average_is_the_largest_row_and_bounded_by_the_peak():
    """The largest disc mean over the discs, for a batch of fields; a mean never exceeds
    the field's largest value (positive weights summing to 1)."""
    pts, w = _points(4, 40)
    centres = disc_centres(0.0, 0.0, WIDTH, HEIGHT, DISC_CENTRE_SPACING * RADIUS)
    op = disc_average_operator(pts, w, centres, RADIUS)
    rng = np.random.default_rng(7)
    fields = rng.random((3, len(pts)))
    got = max_disc_average(op, fields)
    np.testing.assert_allclose(got, [(op @ f).max() for f in fields], rtol=1e-15)
    assert np.all(got <= fields.max(axis=1)) and np.all(got > 0)


def test_plate_model_disc_radius_follows_the_scenario():
    """build_plate takes Plate.stress_radius (default a quarter of the width) and refuses a
    radius that is not a positive length within the plate's size, naming the field."""
    from granplate.setup.scenario import Plate

    x0 = 0.0
    default = gp.build_plate(Plate(), x0, [0.05], cache=False)
    assert default.disc_radius == pytest.approx(0.25 * WIDTH)
    assert default.disc_op.shape == (len(default.disc_centres), default.qp_xy.shape[0] * default.n_qp)
    with pytest.raises(gp.PlateError, match="plate.stress_radius"):
        gp.build_plate(Plate(stress_radius=-1.0), x0, [0.05], cache=False)


def test_scenario_refuses_a_bad_stress_radius():
    """plate.stress_radius must be a positive length at most the plate's larger side."""
    import dataclasses

    from granplate.errors import ScenarioError
    from granplate.setup.presets import preset
    from granplate.setup.validate import validate

    s = preset("steel-r1")
    for bad in (0.0, -1e-3, 1.0, float("nan")):
        with pytest.raises(ScenarioError, match="plate.stress_radius"):
            validate(dataclasses.replace(s, plate=dataclasses.replace(s.plate, stress_radius=bad)))
    validate(dataclasses.replace(s, plate=dataclasses.replace(s.plate, stress_radius=1e-3)))


def test_run_records_the_disc_average_below_the_peak():
    """A run's max_von_mises_disc is a mean of its Gauss-point stresses: positive once the
    wave has reached the plate, never above max_von_mises at the same output, and the
    summary's value is its largest."""
    from granplate.results.dataset import summary

    from short_results import short_results

    ds = short_results()["steel-r1"]
    disc, peak = ds["max_von_mises_disc"].values, ds["max_von_mises"].values
    assert ds["max_von_mises_disc"].attrs["units"] == "Pa"
    assert np.all(disc <= peak * (1 + 1e-12)) and disc.max() > 0.1 * peak.max()
    assert summary(ds)["max_von_mises_disc"] == float(disc.max())
