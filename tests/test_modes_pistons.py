"""Pistons and driven granules in the linear modes (docs/model.md section 3.13, (M3)): a held
precompression wall or a force-driven wall is one degree of freedom along its normal with its
mass, a granule under a velocity drive none along the drive's direction. Truths: the
closed-form frequencies and shapes of a sphere between a fixed wall and a piston (two
masses, two springs k = (3/2) F / delta at the static overlap; the held top wall, or a
force-driven side wall), the limit of an infinitely heavy piston (the fixed wall's modes
plus the piston's slow ring on the chain's springs in series), and a sphere between a wall
and a held one, sqrt((k_w + k_p) / m) / (2 pi)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import granplate as gp
from granplate.commands.modes import granule_fraction, modes_record, piston_fraction
from granplate.model.arrays import build_model
from granplate.results.modes import linear_modes
from tests.test_precompression_drives import SIDE  # a bead between a fixed side wall and a piston

F0 = 10.0
R = 0.005

TEXT = """
name = "piston-modes"
dimension = 3
[[walls]]
label = "floor"
normal = [-1.0, 0.0, 0.0]
offset = 0.0
[[walls]]
label = "top"
normal = [1.0, 0.0, 0.0]
offset = {top!r}
{beads}
[precompression]
target = "wall top"
force = {force!r}
{mode}
{drives}
[contact]
mu = 0.0
alpha_n = 0.0
[time]
t_end = 2e-6
dt_initial = 2e-8
dt_max = 2e-8
output_interval = 2e-7
field_interval = 2e-7
[solver]
scheme = "verlet"
"""


def chain(count: int, mode: str = 'mode = "frozen"', drives: str = "") -> gp.Scenario:
    """`count` steel beads along x between the floor and the top wall, pressed by F0."""
    beads = "".join(
        f'[[granules]]\nx = {R + 2 * R * k!r}\ny = 0.0\nz = 0.0\nradius = {R}\nmaterial = "steel"\n'
        for k in range(count)
    )
    return gp.loads(TEXT.format(top=2 * R * count, beads=beads, force=F0, mode=mode, drives=drives))


def held(count: int, mass: float) -> gp.Scenario:
    return chain(count, f'mode = "held"\nmass = {mass!r}')


def two_mass_modes(k: float, m: float, M: float) -> tuple[np.ndarray, np.ndarray]:
    """The sphere (m) on a fixed spring k and a piston (M) on it by another spring k:
    det([[2k, -k], [-k, k]] - w^2 diag(m, M)) = 0, so m M w^4 - k (2 M + m) w^2 + k^2 = 0;
    the frequencies [Hz] ascending and each mode's piston-to-sphere amplitude ratio
    s / u = (2k - w^2 m) / k."""
    root = math.sqrt((2 * M + m) ** 2 - 4 * m * M)
    w2 = k * np.array([(2 * M + m) - root, (2 * M + m) + root]) / (2 * m * M)
    return np.sqrt(w2) / (2 * math.pi), (2 * k - w2 * m) / k


def test_a_sphere_under_a_held_wall_rings_as_two_masses_on_two_springs():
    """One sphere between the fixed floor and the held top wall of mass M = 3 m: the two
    modes along the column and their shapes (the wall's displacement over the sphere's,
    sign-invariant) as the closed form to 1e-9; nothing else has stiffness (2 zero modes)."""
    m = float(build_model(chain(1)).granular.mass[0])
    M = 3.0 * m
    model = build_model(held(1, M))
    delta = R - float(model.initial_state[0, 0])  # the floor's overlap (the floor at x = 0)
    k = 1.5 * F0 / delta  # the Hertz tangent stiffness at the static overlap, both contacts carrying F0
    modes = linear_modes(model)
    assert modes.pistons.shape == (4, 1) and modes.piston_mass[0] == pytest.approx(M)
    assert modes.zero_modes == 2
    live = np.flatnonzero(modes.frequencies > 0.0)
    want, ratio = two_mass_modes(k, m, M)
    np.testing.assert_allclose(modes.frequencies[live], want, rtol=1e-9)
    u, s_ = modes.shapes[live, 0, 0], modes.pistons[live, 0]
    np.testing.assert_allclose(-s_ / u, ratio, rtol=1e-9)  # the wall's x (s is along e = -x) over the sphere's
    np.testing.assert_allclose(m * u**2 + M * s_**2, 1.0, rtol=1e-12)  # M-orthonormal
    np.testing.assert_allclose(granule_fraction(modes)[live] + piston_fraction(modes)[live], 1.0, rtol=1e-12)
    record = modes_record(modes, ["floor", "top"])
    assert record["pistons"] == [{"wall": "top", "mass": pytest.approx(M)}]
    assert len(record["piston_fraction"]) == len(record["frequencies"]) == 4


def test_a_sphere_against_a_force_driven_wall_rings_as_two_masses_on_two_springs():
    """The sphere between the floor and the frozen top wall (F0 along x) and, across, between a
    fixed wall and a piston of mass M = 3 m pushing with P = 4 N (a force-driven wall): along
    y the closed form of the two masses on springs k_y = (3/2) P / delta_y, along x the sphere
    between fixed walls, sqrt(2 k_x / m) / (2 pi), k_x = (3/2) F0 / delta_x, to 1e-9; the
    piston's amplitude over the sphere's as the closed form."""
    m = float(build_model(chain(1)).granular.mass[0])
    M, push = 3.0 * m, 4.0
    model = build_model(chain(1, drives=SIDE.format(r=R, push=push, mass=M)))
    x = model.initial_state[0, :3]
    k_x, k_y = 1.5 * F0 / (R - x[0]), 1.5 * push / x[1]  # the overlaps on the floor and on the fixed side wall
    modes = linear_modes(model)
    assert list(modes.piston_walls) == [2] and modes.zero_modes == 1
    live = np.flatnonzero(modes.frequencies > 0.0)
    want, ratio = two_mass_modes(k_y, m, M)
    along_x = math.sqrt(2.0 * k_x / m) / (2.0 * math.pi)
    np.testing.assert_allclose(modes.frequencies[live], np.sort(np.append(want, along_x)), rtol=1e-9)
    sideways = live[np.abs(modes.shapes[live, 0, 1]) > 1e-3 * np.abs(modes.shapes[live, 0]).max()]
    u, s_ = modes.shapes[sideways, 0, 1], modes.pistons[sideways, 0]
    np.testing.assert_allclose(s_ / u, ratio, rtol=1e-9)  # s along e = +y
    assert modes_record(modes, ["floor", "top", "left", "right"])["pistons"][0]["wall"] == "left"


def test_a_heavy_held_wall_gives_the_fixed_walls_modes_and_its_own_slow_ring():
    """A chain of 5 under a held wall: as its mass grows from 1 kg to 1e6 kg the chain's modes
    tend to those under the frozen (fixed) wall, their gap falling as 1 / M; the extra,
    lowest mode is the wall on the chain's springs in series, sqrt(k_s / M) / (2 pi),
    1 / k_s = 2 / k_w + 4 / k_p (the two wall contacts and four pairs, each (3/2) F0 / delta)."""
    fixed_model = build_model(chain(5))
    fixed = linear_modes(fixed_model).frequencies
    fixed = fixed[fixed > 0.0]
    gaps = []
    for mass in (1.0, 1e3, 1e6):
        model = build_model(held(5, mass))
        f = linear_modes(model).frequencies
        f = f[f > 0.0]
        assert len(f) == len(fixed) + 1
        gaps.append(float(np.max(np.abs(f[1:] / fixed - 1.0))))
    assert gaps[0] > 1e-3 and gaps[2] < 1e-8
    assert gaps[1] / gaps[2] == pytest.approx(1e3, rel=1e-2)  # first order in 1 / M
    x = model.initial_state[:, 0]
    delta_w = R - x[0]
    delta_p = 2 * R - np.diff(x)
    k_s = 1.0 / (2.0 * delta_w / (1.5 * F0) + float(np.sum(delta_p)) / (1.5 * F0))
    assert f[0] == pytest.approx(math.sqrt(k_s / 1e6) / (2 * math.pi), rel=1e-6)


def held_bead(direction) -> str:
    """A velocity drive holding the first bead (on the floor) still along `direction`."""
    return (
        f'[[drives]]\ntarget = "granule g0"\nkind = "velocity"\ndirection = {list(map(float, direction))!r}\n'
        'profile = "constant"\nvalue = 0.0\n'
    )


def test_a_bead_held_by_a_drive_moves_only_across_its_direction():
    """Two beads between the floor and the frozen top wall, the lower one held along the column
    by a velocity drive: it is no unknown along x, and the upper one rings between it and the
    top wall, sqrt((k_w + k_p) / m) / (2 pi) (k = (3/2) F0 / delta at each static overlap), to
    1e-9; held across the column instead, the modes along it are the undriven chain's."""
    model = build_model(chain(2, drives=held_bead((1, 0, 0))))
    g = model.granular
    x = model.initial_state[:, 0]
    m = float(g.mass[1])
    top = float(g.wall_geo[g.wall_w == 1, 3][0])
    k_w, k_p = 1.5 * F0 / (x[1] + R - top), 1.5 * F0 / (2 * R - (x[1] - x[0]))
    modes = linear_modes(model)
    assert len(modes.frequencies) == 5 and modes.zero_modes == 4
    assert modes.frequencies[-1] == pytest.approx(math.sqrt((k_w + k_p) / m) / (2 * math.pi), rel=1e-9)
    assert np.all(modes.shapes[:, 0, 0] == 0.0)
    free = linear_modes(build_model(chain(2))).frequencies
    across = linear_modes(build_model(chain(2, drives=held_bead((0, 1, 0))))).frequencies
    assert len(across) == 5
    np.testing.assert_allclose(across[across > 0.0], free[free > 0.0], rtol=1e-12)
