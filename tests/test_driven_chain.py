"""A harmonically driven precompressed chain (verification case `driven-chain`) and its linear
reference (granplate.verification.chain_response). Truth: the linear response against closed
forms (one bead between two springs, the monatomic dispersion relation, the dimer's band
edges) and an independent ODE integration; the simulated chain, driven at 1e-4 of its static
overlap, against that linear response below and above its band edges."""

from __future__ import annotations

import math

import numpy as np
import pytest

from granplate.verification import all_cases
from granplate.verification.chain_response import (
    LinearChain,
    bloch_ratio,
    contact_dashpot,
    contact_stiffness,
    linear_history,
    lock_in,
    steady_displacements,
    transmission,
)
from granplate.verification.driven_chain_cases import F0, chain_model, driven_checks, driven_scenario


def test_contact_stiffness_and_dashpot_are_eq3_at_the_static_overlap():
    """k = dN/d delta of N = A delta^(3/2) at delta0 = (F0/A)^(2/3) (a centred difference);
    c = alpha_n sqrt(m* A) delta0^(1/4)."""
    a, f0 = 7.1e9, 10.0
    d0 = (f0 / a) ** (2.0 / 3.0)
    h = 1e-6 * d0
    slope = (a * (d0 + h) ** 1.5 - a * (d0 - h) ** 1.5) / (2.0 * h)
    assert contact_stiffness(a, f0) == pytest.approx(slope, rel=1e-9)
    assert contact_dashpot(0.3, 2e-3, a, f0) == pytest.approx(0.3 * math.sqrt(2e-3 * a) * d0**0.25, rel=1e-12)


def test_one_bead_between_two_springs():
    """N = 1, undamped: U = k0 / (k0 + k1 - m w^2), T = k1 U, the closed form of one mass."""
    ch = LinearChain(np.array([2.0]), np.array([3.0, 5.0]), np.zeros(2))
    w = 1.1
    assert steady_displacements(ch, w)[0] == pytest.approx(3.0 / (8.0 - 2.0 * w * w), rel=1e-12)
    assert transmission(ch, w) == pytest.approx(15.0 / (8.0 - 2.0 * w * w), rel=1e-12)


def test_bloch_ratio_is_the_monatomic_dispersion_relation():
    """Monatomic, undamped: in the pass band |lambda| = 1 with cos q = 1 - m w^2 / (2k); above
    the cut-off 2 sqrt(k/m) lambda is real, negative, below 1 in size, lambda + 1/lambda =
    2 - m w^2 / k."""
    k, m = 1.2e7, 3.5e-3
    wc = 2.0 * math.sqrt(k / m)
    lam = bloch_ratio([m], k, 0.6 * wc)
    assert abs(lam) == pytest.approx(1.0, abs=1e-12)
    assert lam.real == pytest.approx(1.0 - m * (0.6 * wc) ** 2 / (2.0 * k), rel=1e-12)
    lam = bloch_ratio([m], k, 1.3 * wc)
    assert lam.real < 0.0 and abs(lam.imag) < 1e-12 and abs(lam) < 1.0
    assert lam.real + 1.0 / lam.real == pytest.approx(2.0 - m * (1.3 * wc) ** 2 / k, rel=1e-12)


def test_bloch_ratio_of_a_dimer_opens_its_gap_at_the_closed_form_edges():
    """Dimer (m1 > m2), undamped: the cell's |lambda| = 1 just below sqrt(2k/m1) and just above
    sqrt(2k/m2), below 1 between (the gap)."""
    k, m1, m2 = 1e7, 4e-3, 1.5e-3
    top, bottom = math.sqrt(2.0 * k / m1), math.sqrt(2.0 * k / m2)
    assert abs(bloch_ratio([m1, m2], k, 0.999 * top)) == pytest.approx(1.0, abs=1e-9)
    assert abs(bloch_ratio([m1, m2], k, 1.001 * bottom)) == pytest.approx(1.0, abs=1e-9)
    for w in (1.001 * top, 0.5 * (top + bottom), 0.999 * bottom):
        assert abs(bloch_ratio([m1, m2], k, w)) < 0.99


def test_linear_history_against_an_ode_integration():
    """Three damped beads driven from rest: linear_history's far-wall force and displacements
    equal scipy's DOP853 integration of M u'' + C u' + K u = e_1 (k_0 s + c_0 s') (rtol 1e-10)."""
    from scipy.integrate import solve_ivp

    from granplate.verification.chain_response import tridiagonal

    ch = LinearChain(np.array([1.0, 0.5, 2.0]), np.array([4.0, 3.0, 2.0, 5.0]), np.array([0.1, 0.05, 0.02, 0.2]))
    w, a = 1.7, 0.3
    kk, cc = tridiagonal(ch.stiffness), tridiagonal(ch.dashpot)

    def rhs(t, y):
        u, v = y[:3], y[3:]
        f = -kk @ u - cc @ v
        f[0] += ch.stiffness[0] * a * math.sin(w * t) + ch.dashpot[0] * a * w * math.cos(w * t)
        return np.concatenate([v, f / ch.masses])

    t = np.linspace(0.0, 30.0, 301)
    sol = solve_ivp(rhs, (0.0, 30.0), np.zeros(6), t_eval=t, method="DOP853", rtol=1e-12, atol=1e-14)
    force, u = linear_history(ch, w, a, t)
    np.testing.assert_allclose(u, sol.y[:3].T, atol=1e-10)
    np.testing.assert_allclose(force, ch.stiffness[-1] * sol.y[2] + ch.dashpot[-1] * sol.y[5], atol=1e-9)


def test_lock_in_reads_the_amplitude_at_its_frequency():
    """A sine of amplitude 0.7 on an offset, beside another of amplitude 2 at a frequency 30
    periods of the record away: the projection reads 0.7 (the other leaks below 1e-5)."""
    t = np.linspace(0.0, 0.01, 10001)
    w = 2.0 * math.pi * 5000.0
    y = 10.0 + 0.7 * np.sin(w * t + 0.3) + 2.0 * np.sin((w + 2.0 * math.pi * 3000.0) * t)
    assert lock_in(t, y, w) == pytest.approx(0.7, rel=1e-5)


def test_the_linear_model_reads_the_chain_as_the_model_does():
    """chain_model's closed forms (masses, A of eqs. 3-4, walls rigid) are the built dimer's:
    the pair and wall coefficients, and the damping c delta0^(1/4) of eq. (3)."""
    from granplate.model.arrays import build_model
    from granplate.physics.contact import COEF_A, COEF_C

    ch = chain_model(6, 0.7)
    g = build_model(driven_scenario(6, 5000.0, 1e-5, 0.7)).granular
    np.testing.assert_allclose(g.mass, ch.masses, rtol=1e-12)
    a_pair = float(g.pair_coef[0, COEF_A])
    assert contact_stiffness(a_pair, F0) == pytest.approx(ch.stiffness[1], rel=1e-12)
    assert float(g.pair_coef[0, COEF_C]) * (F0 / a_pair) ** (1.0 / 6.0) == pytest.approx(ch.dashpot[1], rel=1e-12)
    walls = sorted(
        (contact_stiffness(float(a), F0), float(c) * (F0 / float(a)) ** (1.0 / 6.0))
        for a, c in g.wall_coef[:, [COEF_A, COEF_C]]
    )
    ends = sorted([(ch.stiffness[0], ch.dashpot[0]), (ch.stiffness[-1], ch.dashpot[-1])])
    np.testing.assert_allclose(walls, ends, rtol=1e-12)


def test_driven_chains_follow_the_linear_solution():
    """The case's checks at a shorter size (a chain of 8 at 0.3, 0.7 and 1.3 f_c; a dimer of 18 in
    its acoustic band and its gap; 5 ms each, the last 2 ms measured): the transmitted amplitude
    within 1e-3 of the linear response, the decay per bead or cell within 2e-3 of the transfer
    matrix's, the far wall below 1e-3 of k_0 a beyond the band edges, the whole force history
    within 2e-3 of the linear response from rest."""
    checks, plot = driven_checks(8, (0.3, 0.7), (1.3,), 3e-3, 2e-3, dimer=(-0.5, 0.5), dimer_count=18)
    assert len(checks) == 8
    assert all(c.passed for c in checks), [(c.quantity, c.ours, c.reference) for c in checks if not c.passed]
    below, above = plot["rows"]["mono"][1], plot["rows"]["mono"][2]
    assert above["far"] < 1e-3 * below["far"]  # the cut-off stops what passes below it


def test_the_case_is_registered_and_slow():
    case = next(c for c in all_cases() if c.name == "driven-chain")
    assert case.slow and case.draw is not None


def test_the_diatomic_chain_example_stops_its_gap():
    """docs/examples/diatomic-chain.toml (20 beads, radii 1 : 0.7, 10 N, a chirp of 1-30 kHz
    over 10 ms): the far wall carries 10 N at t = 0 (the static state), eq. (11) holds to
    solver.energy_tol, and the transmission spectrum's medians over the acoustic band (2 kHz to
    0.9 of its top) and the gap's middle third are the linear steady state's within 25% (a sweep
    is not a steady state: it passes the resonances as they ring), their ratio about 1.4e-4."""
    from pathlib import Path

    import granplate as gp
    from granplate.results.spectra import spectrum_table
    from granplate.verification.driven_chain_cases import band_edges

    s = gp.load_scenario(str(Path(__file__).resolve().parents[1] / "docs" / "examples" / "diatomic-chain.toml"))
    ds = gp.simulate(s, progress=False)
    assert float(ds["wall_force"].sel(wall="xmax").values[0]) == pytest.approx(10.0, rel=1e-7)
    assert float(np.max(np.abs(ds["energy_residual"].values))) <= s.solver.energy_tol
    chain = chain_model(20, 0.7)
    top, bottom = band_edges(chain).values()
    table = spectrum_table(ds, ["wall_force:xmax"], "drive_displacement:shaker")
    f, measured = table["frequency"].values, table["transmission"].values[0]
    for lo, hi in ((2e3, 0.9 * top), (top + (bottom - top) / 3.0, bottom - (bottom - top) / 3.0)):
        band = (f > lo) & (f < hi)
        linear = np.median([abs(transmission(chain, 2.0 * math.pi * x)) for x in f[band]])
        assert float(np.nanmedian(measured[band])) == pytest.approx(linear, rel=0.25), (lo, hi)
