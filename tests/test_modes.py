"""Linear modes about the static state (`granplate modes`, results.modes): the truth is the
closed-form spectra of precompressed chains: two spheres between walls, a monatomic chain
(its staggered mode exactly at the cut-off f_c = (1/pi) sqrt(k/m), since a wall's contact is
twice as stiff as a pair's: k = (3/2) A^(2/3) F0^(1/3)), the tridiagonal matrix of a chain
solved independently, and a diatomic chain's band gap."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import granplate as gp
from granplate.cli import main
from granplate.model.arrays import build_model
from granplate.physics.contact import COEF_A
from granplate.results.modes import chain_band_edges, linear_modes

F0 = 10.0


def chain_text(n: int, ratio: float = 1.0) -> str:
    return f"""
name = "modes-chain"
dimension = 3
[layout]
kind = "chain"
count = {n}
radius = 0.005
material = "steel"
dimer_ratio = {ratio}
[precompression]
target = "wall xmax"
force = {F0}
"""


def chain(n: int, ratio: float = 1.0):
    return build_model(gp.loads(chain_text(n, ratio)))


def stiffness(a: float) -> float:
    """dN/d delta at the force F0: (3/2) A^(2/3) F0^(1/3) [N/m]."""
    return 1.5 * a ** (2.0 / 3.0) * F0 ** (1.0 / 3.0)


def test_two_spheres_between_walls():
    """Two equal spheres pressed between walls: along the axis omega^2 = k_w / m (in phase) and
    (k_w + 2 k) / m (out of phase); the four transverse directions have no stiffness. Shapes
    compared sign-invariantly."""
    m = chain(2)
    g = m.granular
    k, kw, mass = stiffness(g.pair_coef[0, COEF_A]), stiffness(g.wall_coef[0, COEF_A]), g.mass[0]
    md = linear_modes(m)
    assert md.zero_modes == 4
    live = md.frequencies[md.frequencies > 0]
    expected = np.sqrt([kw / mass, (kw + 2 * k) / mass]) / (2 * math.pi)
    np.testing.assert_allclose(live, expected, rtol=1e-9)
    shapes = md.shapes[md.frequencies > 0][:, :, 0]
    for s, ref in zip(shapes, ([1.0, 1.0], [1.0, -1.0])):
        cos = abs(np.dot(s, ref)) / (np.linalg.norm(s) * np.linalg.norm(ref))
        assert cos == pytest.approx(1.0, abs=1e-9)


def test_a_monatomic_chain_reaches_its_cut_off_and_is_its_tridiagonal_matrix():
    """A chain of 30: the axial spectrum is the eigenvalues of the tridiagonal matrix with k
    between spheres and k_w = 2 k at the walls (solved here by numpy), and its top is the
    cut-off f_c = (1/pi) sqrt(k/m) exactly (the staggered mode satisfies the walls' condition
    when k_w = 2 k)."""
    m = chain(30)
    g = m.granular
    k, kw, mass = stiffness(g.pair_coef[0, COEF_A]), stiffness(g.wall_coef[0, COEF_A]), g.mass[0]
    assert kw == pytest.approx(2 * k, rel=1e-12)
    t = np.diag(np.full(30, 2 * k)) - np.diag(np.full(29, k), 1) - np.diag(np.full(29, k), -1)
    t[0, 0] = t[-1, -1] = k + kw
    expected = np.sqrt(np.linalg.eigvalsh(t) / mass) / (2 * math.pi)
    md = linear_modes(m)
    live = md.frequencies[md.frequencies > 0]
    np.testing.assert_allclose(live, expected, rtol=1e-9)
    assert live.max() == pytest.approx(chain_band_edges(k, mass)["cutoff"], rel=1e-9)


def test_a_diatomic_chain_has_its_gap():
    """A dimer chain (radii 1 : 0.7, one pair stiffness): no bulk mode inside the gap between
    the acoustic band's top sqrt(2k/m1)/(2 pi) and the optical band's bottom sqrt(2k/m2)/(2 pi);
    at most one surface mode per end falls in it or beyond the optical top."""
    m = chain(40, 0.7)
    g = m.granular
    k = stiffness(g.pair_coef[0, COEF_A])
    e = chain_band_edges(k, g.mass[0], g.mass[1])
    f = linear_modes(m).frequencies
    f = f[f > 0]
    inside = (f > e["acoustic_top"] * (1 + 1e-9)) & (f < e["optical_bottom"] * (1 - 1e-9))
    above = f > e["optical_top"] * (1 + 1e-9)
    assert len(f) == 40 and inside.sum() + above.sum() <= 2
    assert e["acoustic_top"] < e["optical_bottom"] < e["optical_top"]


def test_modes_command_prints_and_writes_json(tmp_path, capsys):
    """`granplate modes FILE --json J`: the frequencies [Hz] printed and written as
    {"frequencies": [...]}, the same as `linear_modes`."""
    path = tmp_path / "chain.toml"
    path.write_text(chain_text(5))
    out = tmp_path / "modes.json"
    assert main(["modes", str(path), "--json", str(out), "--figure", str(tmp_path / "m.png")]) == 0
    printed = capsys.readouterr().out
    got = json.loads(out.read_text())
    expected = linear_modes(build_model(gp.loads(chain_text(5)))).frequencies
    np.testing.assert_allclose(got["frequencies"], expected, rtol=1e-12)
    assert "Hz" in printed and (tmp_path / "m.png").stat().st_size > 0
