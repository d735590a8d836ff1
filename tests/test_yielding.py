"""The run's largest Hertz peak pressure per material pair (results.yielding): the numpy
pass over the granule pairs picks the same contact and numbers as taking every contact's
row in turn."""

from __future__ import annotations

import dataclasses

import numpy as np

from granplate.bench.scaling_space import launched_fcc
from granplate.model.arrays import build_model
from granplate.results.yielding import contact_yield, pair_yield
from granplate.solver.driver import ContactPeaks


def every_row_maximum(model, peaks) -> dict:
    """The reference: every contact's row, the first of the largest p0 per pair label."""
    best: dict = {}
    for row in contact_yield(model, peaks):
        if row[0] not in best or row[1] > best[row[0]][1]:
            best[row[0]] = row
    return best


def test_pair_maxima_equal_every_contacts_rows():
    """Three materials, granule pairs with ties (the first kept: its time tells): the same
    pair labels, contact, pressure, ratio, time and law as the contact-by-contact maximum."""
    s = launched_fcc((2, 2, 2))
    names = ("steel", "ptfe", "bearing_steel")
    granules = tuple(dataclasses.replace(g, material=names[k % 3]) for k, g in enumerate(s.granules))
    model = build_model(dataclasses.replace(s, granules=granules))
    rng = np.random.default_rng(3)
    n = 400
    i = rng.integers(0, len(granules), n)
    j = (i + rng.integers(1, len(granules), n)) % len(granules)
    delta = rng.uniform(1e-8, 1e-5, n)
    delta[50:60] = delta[40]  # equal overlaps: the first in order is kept
    i[50:60], j[50:60] = i[40], j[40]
    peaks = ContactPeaks(
        granule=i.astype(np.int64),
        partner=j.astype(np.int64),
        delta_max=delta,
        time=rng.uniform(0.0, 1e-3, n),
    )
    want = every_row_maximum(model, peaks)
    got = pair_yield(model, peaks)
    assert list(got.pair) == sorted(want)
    assert len(got.pair) >= 6
    for k, label in enumerate(got.pair):
        row = want[label]
        assert (got.pressure[k], got.time[k], got.contact[k], got.law[k]) == (row[1], row[4], row[5], row[6])
        assert got.ratio[k] == row[2] or (np.isnan(got.ratio[k]) and np.isnan(row[2]))
