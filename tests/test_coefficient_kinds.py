"""The pairs' coefficient kinds (model.coefficients.coefficient_kinds, model.relists): each
pair's row of the kinds' table is its own coefficient row bit for bit, wherever the pairs
are made (the model, a rebuilt list, a run's lists), and a packing of several sizes runs
to the same bits on one thread and to round-off on several as its rows say."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from granplate.bench.scaling_space import launched_fcc
from granplate.errors import YieldWarning
from granplate.model import coefficients
from granplate.model.arrays import build_model, granular_with_contacts
from granplate.model.coefficients import coefficient_kinds
from granplate.model.relists import cached_pair_coefficients, pair_kinds_stale, with_pair_kinds
from granplate.physics.contact import N_COEF
from granplate.results.run import simulate
from granplate.setup.threads import available_threads
from granplate.solver.run_contacts import ContactLists


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def rows_of_kinds() -> np.ndarray:
    """Rows of three kinds, two of them apart only by the sign of a zero, one with a NaN."""
    rng = np.random.default_rng(5)
    base = rng.random((3, N_COEF))
    base[1, 6], base[2, 6] = 0.0, -0.0
    base[0, 7] = np.nan
    return base[rng.integers(0, 3, 500)]


def test_kinds_give_every_row_bit_for_bit():
    """table[kind] is rows to the bit (signed zeros and NaNs kept), one row per kind."""
    rows = rows_of_kinds()
    kind, table = coefficient_kinds(rows)
    assert kind.dtype == np.int32 and len(table) == 3
    assert same_bits(table[kind], rows)


def test_one_kind_and_none():
    """A packing of one size and material: one row; no pairs: an empty table."""
    rows = np.repeat(rows_of_kinds()[:1], 40, axis=0)
    kind, table = coefficient_kinds(rows)
    assert len(table) == 1 and not kind.any() and same_bits(table[kind], rows)
    kind, table = coefficient_kinds(np.zeros((0, N_COEF)))
    assert kind.shape == (0,) and table.shape == (0, N_COEF)


def test_rows_of_one_key_are_told_apart(monkeypatch):
    """Every row mixed into the same key (a multiplier of 0): the rows are sorted by their
    bits instead, and each still finds its own."""
    monkeypatch.setattr(coefficients, "_KEY_PRIME", np.uint64(0))
    rows = rows_of_kinds()
    kind, table = coefficient_kinds(rows)
    assert len(table) == 3 and same_bits(table[kind], rows)


def polydisperse(threads: int | None = 1):
    """The struck FCC packing of 48 spheres with every third sphere 2% smaller: pairs of
    four kinds (the sizes in either order), Mindlin's law."""
    s = launched_fcc((3, 2, 2), mu=0.3, law="mindlin", t_end=8e-6, scheme="verlet")
    granules = tuple(
        dataclasses.replace(g, radius=0.98 * g.radius) if i % 3 == 0 else g for i, g in enumerate(s.granules)
    )
    return dataclasses.replace(s, granules=granules, solver=dataclasses.replace(s.solver, threads=threads))


def test_model_and_rebuilt_lists_carry_their_pairs_kinds():
    """build_model, a rebuilt list and a run's lists of a Granular made without kinds: each
    pair's kind row is its coefficient row, to the bit."""
    m = build_model(polydisperse())
    g = m.granular
    assert 1 < len(g.kind_coef) < len(g.pair_ij)
    assert same_bits(g.kind_coef[g.pair_kind], g.pair_coef)
    fewer = g.pair_ij[::2]
    g2 = granular_with_contacts(m, g, fewer, np.column_stack([g.wall_i, g.wall_w]))
    assert len(g2.pair_kind) == len(fewer) and same_bits(g2.kind_coef[g2.pair_kind], g2.pair_coef)
    bare = g._replace(pair_kind=np.zeros(0, np.int32), kind_coef=np.zeros((0, N_COEF)))
    assert pair_kinds_stale(bare) and not pair_kinds_stale(with_pair_kinds(bare))
    lists = ContactLists(dataclasses.replace(m, granular=bare))
    assert same_bits(lists.g.kind_coef[lists.g.pair_kind], lists.g.pair_coef)


def test_cached_rows_are_the_rows_computed_again():
    """model.relists.cached_pair_coefficients over calls whose pairs overlap, come in any
    order, all met or none: each row is pair_coefficients' own to the bit, and the cache
    stays sorted by code with each pair once."""
    m = build_model(polydisperse())
    s, mats, g = m.scenario, list(m.materials), m.granular
    rng = np.random.default_rng(11)
    pairs = g.pair_ij
    known: dict = {}
    for take in (pairs[::3], pairs[rng.permutation(len(pairs))[: len(pairs) // 2]], pairs, pairs[::-5], pairs[:0]):
        got = cached_pair_coefficients(s, mats, g, np.ascontiguousarray(take), known)
        assert same_bits(got, coefficients.pair_coefficients(s, mats, g.radius, g.mass, take))
        codes = known["codes"]
        assert np.all(codes[1:] > codes[:-1]) and len(codes) == len(known["rows"])
    assert len(known["codes"]) == len(pairs)


@pytest.mark.parametrize("threads", sorted({1, min(2, available_threads())}))
def test_polydisperse_packing_runs_as_its_rows_say(threads):
    """The run whose pair loop reads the kinds' table gives the bits of the same run whose
    table holds one row per pair (pair_kind = 0, 1, ...: each pair its own row), on one
    thread and on several."""
    s = polydisperse(threads)
    m = build_model(s)
    g = m.granular
    own = g._replace(pair_kind=np.arange(len(g.pair_ij), dtype=np.int32), kind_coef=g.pair_coef.copy())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", YieldWarning)
        a = simulate(s, model=m, progress=False)
        b = simulate(s, model=dataclasses.replace(m, granular=own), progress=False)
    for name in ("x", "vx", "omega_y", "E_granular", "energy_residual"):
        assert np.array_equal(a[name].values, b[name].values), name
    assert float(np.abs(a["vx"].values).max()) > 0.0
