"""The plate maxima over output times (granplate.plate.peaks): the bound that lets a
summary skip output times, and the skipping itself."""

from __future__ import annotations

import numpy as np
import pytest

import granplate as gp
from granplate.plate import peaks as P


@pytest.fixture(scope="module")
def plate():
    return gp.build_model(gp.with_changes(gp.preset("steel-r1"), {"time.t_end": 1e-5})).plate


def test_unit_peaks_bound_every_combination_of_modes(plate):
    """Triangle inequality of a norm: the three maxima at random coordinates never exceed
    sum_i |c_i| m_i, and a single mode's maxima scale with |c_i| (positive homogeneity)."""
    m = P.unit_peaks(plate, plate.n_modes)
    rng = np.random.default_rng(7)
    c = rng.normal(size=(40, plate.n_modes)) * rng.uniform(0, 1e-6, size=(40, 1)) / (1 + np.arange(plate.n_modes))
    exact = P.block_maxima(plate, c)
    assert np.all(exact <= np.abs(c) @ m * (1 + 1e-12))
    i = 5
    single = np.zeros((2, plate.n_modes))
    single[:, i] = (-3e-7, 2e-7)
    np.testing.assert_allclose(P.block_maxima(plate, single), np.abs(single[:, [i]]) * m[i], rtol=1e-12)


def synthetic_run(plate, n: int, spike: int | None) -> np.ndarray:
    """Coordinates of a plate ringing in its first modes with a slow envelope (a broad
    maximum), plus, at one output time, a spike in a high mode."""
    rng = np.random.default_rng(11)
    t = np.arange(n)[:, None]
    k = np.arange(plate.n_modes)[None, :]
    amp = 1e-6 * np.exp(-k / 4.0) * rng.uniform(0.5, 1.0, size=(1, plate.n_modes))
    c = (
        amp
        * np.sin(0.05 * t * (1 + k) + rng.uniform(0, 6, size=(1, plate.n_modes)))
        * np.exp(-(((t - n / 2) / (n / 4)) ** 2))
    )
    if spike is not None:
        c[spike, plate.n_modes // 2] += 50 * float(np.abs(c).max())
    return np.ascontiguousarray(c)


@pytest.mark.parametrize("spike", [None, 137])
def test_skipping_times_keeps_the_maxima_bit_for_bit(plate, spike):
    """peak_maxima's largest values equal those of every output time (time_maxima) bit for
    bit, while fewer times are evaluated; a spike between the reference times is found."""
    c = synthetic_run(plate, 400, spike)
    every = P.time_maxima(plate, c)
    some = P.peak_maxima(plate, c)
    assert np.array_equal(np.nanmax(some, axis=0), every.max(axis=0))
    assert np.isfinite(some[:, 0]).sum() < len(c)
    if spike is not None:
        assert every[:, 0].argmax() == spike and np.isfinite(some[spike, 0])


def test_time_maxima_stop_after_a_block(plate):
    """A stop request after the first block leaves exactly that block's rows, equal to
    those of the whole computation."""
    c = synthetic_run(plate, 100, None)
    part = P.time_maxima(plate, c, should_stop=lambda: True)
    assert len(part) == P.BLOCK
    assert np.array_equal(part, P.time_maxima(plate, c)[: P.BLOCK])


def test_distance_peaks_is_the_weighted_distance(plate):
    """The compiled bound term equals its definition, |c[a] - c[b]| m (and |c[a]| m from
    rest), to round-off."""
    m = P.unit_peaks(plate, plate.n_modes)
    c = synthetic_run(plate, 50, None)
    rows, refs = np.array([3, 10, 49, 0]), np.array([0, 12, -1, 7])
    want = np.stack([np.abs(c[a] - (c[b] if b >= 0 else 0.0)) @ m for a, b in zip(rows, refs)])
    np.testing.assert_allclose(P.distance_peaks(c, m, rows, refs), want, rtol=1e-12)


@pytest.mark.parametrize("strides", [(32,), (32, 8), (64, 16, 4), (8, 2)])
def test_any_reference_refinement_keeps_the_maxima_bit_for_bit(plate, strides):
    """Whatever the references' spacing, the largest values equal those of every output
    time bit for bit (the bounds are rigorous at every level)."""
    c = synthetic_run(plate, 400, 137)
    every = P.time_maxima(plate, c)
    some = P.peak_maxima(plate, c, strides=strides)
    assert np.array_equal(np.nanmax(some, axis=0), every.max(axis=0))


@pytest.mark.parametrize("n", [1, 5, 64, 300])
def test_a_plate_at_rest_and_short_runs(plate, n):
    """A plate at rest (every bound zero: no block stays open after the first references)
    and runs shorter than a block give the maxima of every output time bit for bit."""
    for c in (np.zeros((n, plate.n_modes)), synthetic_run(plate, n, None)):
        some = P.peak_maxima(plate, c)
        assert np.array_equal(np.nanmax(some, axis=0), P.time_maxima(plate, c).max(axis=0))
