"""The contact laws' registry (setup.law_registry) and the dispatch on law ids agree: setup
allows exactly the registered names, the coefficient rows carry each law's id, each
registered normal law's id gives that law's closed-form force and slope at one overlap
(Hertz A delta^(3/2); Thornton's loading line, docs/model.md eq. P5; the fully plastic line
2 pi R* h Y delta of "johnson", section 3.10), each tangential id its law, and an unknown
name is refused at setup by field."""

from __future__ import annotations

import math

import numpy as np
import pytest

from granplate.errors import ScenarioError
from granplate.model.coefficients import pair_coefficient_row, pair_coefficients, wall_coefficient_row
from granplate.physics.contact import (
    COEF_A,
    COEF_DY,
    COEF_KS,
    COEF_MU,
    COEF_NLAW,
    COEF_TLAW,
    COEF_XH,
    friction_magnitude,
)
from granplate.physics.laws import normal_law_force, normal_law_response, normal_law_slopes
from granplate.results.contact_table import tangential_magnitude
from granplate.setup.law_registry import (
    HERTZ,
    MINDLIN,
    NORMAL_LAW_IDS,
    TANGENTIAL_LAW_IDS,
    TANH,
    YIELDING_LAWS,
)
from granplate.setup.materials import DEFAULT_HARDNESS_RATIO, LIBRARY
from granplate.setup.scenario import NORMAL_LAWS, TANGENTIAL_LAWS, Contact, Granule, Load, PairCoefficients, Scenario
from granplate.setup.validate import validate

R = 0.005  # [m] both spheres' radius
STEEL = LIBRARY["steel"]  # E = 200 GPa, nu = 0.3, Y = 355 MPa
E_STAR = STEEL.E / (2.0 * (1.0 - STEEL.nu**2))
R_STAR = R / 2.0
P_Y = 1.6 * STEEL.Y  # Thornton's limiting pressure (P1)
A = 4.0 / 3.0 * E_STAR * math.sqrt(R_STAR)  # eq. (3)


def scene(**contact) -> Scenario:
    """Two steel spheres 1 mm apart, unloaded, with the contact fields given."""
    granules = (Granule(0.006, 0.05, R, "steel", "a"), Granule(0.017, 0.05, R, "steel", "b"))
    return Scenario(name="laws", granules=granules, load=Load(kind="none"), contact=Contact(**contact))


def row(normal_law: str, tangential_law: str = "tanh") -> np.ndarray:
    """The steel pair's coefficient row as the loop builds it (no damping)."""
    s = scene(normal_law=normal_law, tangential_law=tangential_law, alpha_n=0.0)
    return pair_coefficients(s, [STEEL, STEEL], np.full(2, R), np.ones(2), np.array([[0, 1]]))[0]


def hertz(c: np.ndarray):
    """A delta^(3/2) at twice the steel pair's Thornton yield overlap, its slope 3/2 A delta^(1/2)."""
    d = 2.0 * row("thornton")[COEF_DY]
    return d, A * d**1.5, 1.5 * A * math.sqrt(d)


def thornton(c: np.ndarray):
    """Loading at 3 delta_y (P5): F_y + pi p_y R* (delta - delta_y), F_y = A delta_y^(3/2),
    delta_y = (pi p_y / (2 E*))^2 R* (P3); slope pi p_y R*."""
    d_y = (math.pi * P_Y / (2.0 * E_STAR)) ** 2 * R_STAR
    d = 3.0 * d_y
    return d, A * d_y**1.5 + math.pi * P_Y * R_STAR * (d - d_y), math.pi * P_Y * R_STAR


def johnson(c: np.ndarray):
    """Past the hardness (twice its overlap x_h delta_y), at the reference rate: the mean
    pressure h Y over the disc pi a^2 = 2 pi R* delta, F = 2 pi R* h Y delta; slope 2 pi R* h Y."""
    d = 2.0 * c[COEF_XH] * c[COEF_DY]
    k = 2.0 * math.pi * R_STAR * DEFAULT_HARDNESS_RATIO * STEEL.Y
    return d, k * d, k


#: each registered normal law's closed form: a law added to the registry needs its line here.
CLOSED_FORMS = {"hertz": hertz, "thornton": thornton, "johnson": johnson}


def test_setup_allows_exactly_the_registered_names():
    """Setup's allowed names are the registry's, in its order; the ids are distinct integers."""
    assert NORMAL_LAWS == tuple(NORMAL_LAW_IDS) and TANGENTIAL_LAWS == tuple(TANGENTIAL_LAW_IDS)
    assert set(YIELDING_LAWS) <= set(NORMAL_LAW_IDS) and "hertz" not in YIELDING_LAWS
    for ids in (NORMAL_LAW_IDS, TANGENTIAL_LAW_IDS):
        assert len(set(ids.values())) == len(ids) and all(isinstance(v, int) for v in ids.values())
    assert set(CLOSED_FORMS) == set(NORMAL_LAW_IDS)


@pytest.mark.parametrize("law", list(NORMAL_LAW_IDS))
def test_each_normal_law_id_gives_its_closed_form(law):
    """The row holds the law's id; at one overlap (loading, rate factor 1) the dispatch gives
    the law's closed-form force and slope to 1e-12, its response the same force."""
    c = row(law)
    assert c[COEF_NLAW] == NORMAL_LAW_IDS[law] and c[COEF_TLAW] == TANH
    assert c[COEF_A] == pytest.approx(A, rel=1e-14)
    d, force, slope = CLOSED_FORMS[law](c)
    assert normal_law_force(d, 0.0, c, 0.0, 1.0, True) == pytest.approx(force, rel=1e-12)
    assert normal_law_response(d, 0.0, c, 0.0, 1.0, True)[0] == normal_law_force(d, 0.0, c, 0.0, 1.0, True)
    assert normal_law_slopes(d, c, d, 1.0)[0] == pytest.approx(slope, rel=1e-12)


def test_law_id_alone_selects_the_law():
    """A Thornton row given Hertz's id is Hertz's law at any overlap: the id, not the yield
    overlap, chooses; a yielding law within its yield overlap takes Hertz's code, bitwise."""
    c = row("thornton")
    d = 3.0 * c[COEF_DY]
    h = c.copy()
    h[COEF_NLAW] = HERTZ
    assert normal_law_force(d, 0.0, h, 0.0, 1.0, True) == pytest.approx(A * d**1.5, rel=1e-12)
    below = 0.5 * c[COEF_DY]
    assert normal_law_response(below, 0.3, c, below, 1.0, True) == normal_law_response(below, 0.3, h, 0.0, 1.0, True)


def test_every_contact_kind_carries_both_ids():
    """Pair rows (many at once, and one at a time: its normal law) and wall rows carry the normal law's id of
    the pair's materials (a [[contact.pairs]] override included) and the tangential law's id."""
    pair = PairCoefficients(("steel", "steel"), normal_law="johnson")
    s = scene(normal_law="thornton", tangential_law="mindlin", pairs=(pair,))
    rows = pair_coefficients(s, [STEEL, STEEL], np.full(2, R), np.ones(2), np.array([[0, 1]]))
    assert rows[0, COEF_NLAW] == NORMAL_LAW_IDS["johnson"] and rows[0, COEF_TLAW] == MINDLIN
    one = pair_coefficient_row(s, STEEL, STEEL, R, R, 1.0, 1.0)
    assert one[COEF_NLAW] == NORMAL_LAW_IDS["johnson"]
    wall = wall_coefficient_row(s, STEEL, "steel", R, 1.0)
    assert wall[COEF_NLAW] == NORMAL_LAW_IDS["johnson"] and wall[COEF_TLAW] == MINDLIN
    assert row("hertz")[COEF_NLAW] == HERTZ and row("hertz", "mindlin")[COEF_TLAW] == MINDLIN


def test_each_tangential_law_id_selects_its_law():
    """A tanh row's friction is mu |N| tanh(k_s v_t) (eq. 5); a Mindlin row's depends on its
    history (the contact table says NaN)."""
    c = row("hertz")
    assert tangential_magnitude(2.0, 1e-3, c) == abs(friction_magnitude(2.0, 1e-3, c[COEF_MU], c[COEF_KS]))
    assert tangential_magnitude(2.0, 1e-3, c) == pytest.approx(
        2.0 * c[COEF_MU] * math.tanh(c[COEF_KS] * 1e-3), rel=1e-14
    )
    assert math.isnan(tangential_magnitude(2.0, 1e-3, row("hertz", "mindlin")))


@pytest.mark.parametrize(
    "contact, field",
    [
        ({"normal_law": "plastic"}, "contact.normal_law"),
        ({"pairs": (PairCoefficients(("steel", "steel"), normal_law="plastic"),)}, "contact.pairs[0].normal_law"),
        ({"tangential_law": "coulomb"}, "contact.tangential_law"),
    ],
)
def test_unknown_law_is_refused_at_setup(contact, field):
    """A law name outside the registry is refused by validate, naming the field and every registered name."""
    with pytest.raises(ScenarioError) as info:
        validate(scene(**contact))
    assert info.value.field == field
    names = TANGENTIAL_LAW_IDS if "tangential" in field else NORMAL_LAW_IDS
    assert all(f"'{name}'" in str(info.value) for name in names)


#: a normal law written as a user would add one (docs/architecture.md, "Adding a normal law"):
#: a linear spring k delta, k = R* Y / delta_y of the row (any constant of the row would do)
LINEAR_LAW = """
import numpy as np
from granplate.jit import njit
from granplate.physics.contact import COEF_DY, COEF_SY, N_LAW_COLUMNS


@njit(cache=True, inline="always")
def law_response(delta, delta_dot, coef, delta_max, rate, clip):
    k = coef[COEF_SY] / coef[COEF_DY]
    return k * delta, 0.0, 0.5 * k * delta * delta, 0.0


@njit(cache=True, inline="always")
def law_force(delta, delta_dot, coef, delta_max, rate, clip):
    return coef[COEF_SY] / coef[COEF_DY] * delta


@njit(cache=True, inline="always")
def law_slopes(delta, coef, delta_max, rate):
    return coef[COEF_SY] / coef[COEF_DY], 0.0


@njit(cache=True, inline="always")
def law_rate(d, d_old, t, t_old, rate, coef):
    return rate + 1.0


def law_columns(softer, e_star, r_star, length):
    out = np.zeros(N_LAW_COLUMNS)
    out[0], out[1] = 1e-6, 2.0 * r_star * e_star * 1e-6
    return out
"""


def test_a_new_normal_law_is_one_module_and_one_registry_entry(tmp_path, monkeypatch):
    """A law given as one module and one registry line is found by name (its columns) and
    dispatched by its id, the next after the registered ones: its closed form k delta, slope
    k, energy k delta^2 / 2, its own history update; the registered laws keep their ids."""
    from numba import njit

    from granplate.physics import laws
    from granplate.setup import law_registry

    (tmp_path / "granplate_linear_law.py").write_text(LINEAR_LAW)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(law_registry.NORMAL_LAW_REGISTRY, "linear", law_registry.NormalLaw("granplate_linear_law"))
    names = list(law_registry.NORMAL_LAW_REGISTRY)
    modules = [laws.law_module(n) for n in names]
    response = laws.pick_of(tuple(m.law_response for m in modules), 6)
    slopes = laws.pick_of(tuple(m.law_slopes for m in modules), 4)
    rate = laws.pick_of(tuple(m.law_rate for m in modules), 6)

    @njit
    def call(law, d, c):
        return (
            response(law, d, 0.0, c, 0.0, 1.0, True),
            slopes(law, d, c, 0.0, 1.0),
            rate(law, d, 0.0, 1.0, 0.0, 5.0, c),
        )

    c = row("hertz")
    c[COEF_DY : COEF_XH + 1] = laws.law_columns("linear", STEEL, E_STAR, R_STAR, 2 * R)
    k = 2.0 * R_STAR * E_STAR
    (n, pv, ep, wp), (kd, kv), r = call(names.index("linear"), 2e-6, c)
    assert (n, ep, kd, r) == pytest.approx((k * 2e-6, 0.5 * k * 4e-12, k, 6.0), rel=1e-14)
    (n, pv, ep, wp), (kd, kv), r = call(HERTZ, 2e-6, c)
    assert n == pytest.approx(A * 2e-6**1.5, rel=1e-12) and r == 5.0


def test_every_registered_law_module_gives_the_interface():
    """Each registry entry's module gives every function the dispatch builds on (law_module's check), and a
    module lacking one is refused naming it."""
    from granplate.physics import laws
    from granplate.setup import law_registry

    for name in NORMAL_LAW_IDS:
        module = laws.law_module(name)
        assert all(callable(getattr(module, f)) for f in laws.LAW_FUNCTIONS)
    bad = law_registry.NormalLaw("granplate.physics.mindlin")
    with pytest.MonkeyPatch.context() as mp:
        mp.setitem(law_registry.NORMAL_LAW_REGISTRY, "broken", bad)
        with pytest.raises(ImportError, match="lacks law_response"):
            laws.law_module("broken")
