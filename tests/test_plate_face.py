"""The plate's face and its patch weights (granplate/plate/face.py, docs/model.md section
3.5): consistent nodal weights of a uniform traction against exact integrals, and the
face's mode shapes against the full modes."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.plate.face import patch_weight_vector
from granplate.setup.plate_checks import left_edge_node_heights
from granplate.setup.scenario import Plate

PLATE = Plate(x0=0.03, y0=0.0, height=0.1, ny=40)
FACE_Y = left_edge_node_heights(PLATE)


def edge_interpolant(face_y: np.ndarray, values: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The face's quadratic interpolant of nodal values at heights y (Lagrange on each
    3-node edge element, written here from its definition)."""
    out = np.empty_like(y)
    for j, yy in enumerate(y):
        e = min(int(np.searchsorted(face_y, yy, side="right") - 1) // 2, (len(face_y) - 1) // 2 - 1)
        ys, vs = face_y[2 * e : 2 * e + 3], values[2 * e : 2 * e + 3]
        out[j] = sum(vs[a] * np.prod([(yy - ys[b]) / (ys[a] - ys[b]) for b in range(3) if b != a]) for a in range(3))
    return out


@pytest.mark.parametrize("y_c", [0.05, 0.0504375, 0.05123, 0.0011, 0.0995])
def test_weights_are_the_patch_average_of_the_face_interpolant(y_c):
    """sum w_n f_n equals the mean over the patch (cut to the face) of the face's quadratic
    interpolant of f, by fine quadrature, for random nodal values; sum w_n = 1."""
    width = 0.0025
    w = patch_weight_vector(FACE_Y, y_c, width)
    assert w.sum() == pytest.approx(1.0, abs=1e-14)
    rng = np.random.default_rng(7)
    f = rng.normal(size=len(FACE_Y))
    lo, hi = max(y_c - width / 2, 0.0), min(y_c + width / 2, 0.1)
    ys = np.linspace(lo, hi, 20001)
    mean = np.trapezoid(edge_interpolant(FACE_Y, f, ys), ys) / (hi - lo)
    assert w @ f == pytest.approx(mean, abs=1e-7)
    assert np.count_nonzero(w) <= 7  # local: only the nodes under the patch


def test_centred_patch_is_symmetric_and_linear_fields_give_the_centre():
    """A patch centred on a node weighs its neighbours symmetrically; a linear field
    averages to its value at the patch centre (uniform traction: the centroid)."""
    w = patch_weight_vector(FACE_Y, 0.05, 0.0025)
    k = int(np.argmin(abs(FACE_Y - 0.05)))
    np.testing.assert_allclose(w[k - 3 : k + 4], w[k - 3 : k + 4][::-1], atol=1e-15)
    for y_c in (0.05, 0.0504375, 0.0731):
        assert patch_weight_vector(FACE_Y, y_c, 0.0025) @ FACE_Y == pytest.approx(y_c, rel=1e-14)


def test_zero_width_patch_is_a_point_load():
    """w = 0: the weights are the shape functions at y_c (1 at a node, nodal values
    interpolated quadratically between)."""
    w = patch_weight_vector(FACE_Y, 0.05, 0.0)
    assert w[np.argmin(abs(FACE_Y - 0.05))] == pytest.approx(1.0) and w.sum() == pytest.approx(1.0)
    y_c = 0.0504375
    w = patch_weight_vector(FACE_Y, y_c, 0.0)
    assert w @ FACE_Y**2 == pytest.approx(y_c**2, rel=1e-13)


def test_face_modes_are_the_modes_at_the_face_nodes():
    """phi_face rows are T Phi at the left-edge nodes, bottom to top; clamped ends are zero."""
    from granplate.plate import build_plate

    p = Plate(x0=0.03, y0=0.0, height=0.1, ny=8, nx=2)
    pm = build_plate(p, p.x0, [0.05], cache=False)
    np.testing.assert_allclose(pm.face_y, left_edge_node_heights(p), atol=1e-15)
    full = pm.T @ pm.Phi
    for j, n in enumerate(pm.face_nodes):
        np.testing.assert_array_equal(pm.phi_face[2 * j], full[2 * n])
        np.testing.assert_array_equal(pm.phi_face[2 * j + 1], full[2 * n + 1])
    assert not pm.phi_face[[0, 1, -2, -1]].any()  # the clamped corners
