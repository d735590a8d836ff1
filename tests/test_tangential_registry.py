"""The tangential laws' registry (setup.law_registry.TANGENTIAL_LAW_REGISTRY) and dispatch
(physics.laws). Truth: closed forms of two toy laws a user adds as one module and one
registry line each (a dashpot rate law and a linear spring with a Coulomb cap, Cundall and
Strack's), the registered laws' own functions, and the source: no pass outside the
dispatch names a tangential law's function or compares a law id."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from granplate.physics import laws
from granplate.physics.contact import COEF_KS, COEF_KT, COEF_MU, COEF_MUT, COEF_TLAW, N_COEF, friction_magnitude
from granplate.setup import law_registry
from granplate.setup.law_registry import MINDLIN, TANGENTIAL_LAW_IDS, TANH, TangentialLaw

PACKAGE = Path(laws.__file__).resolve().parents[1]

DASHPOT = """
import math
from granplate.jit import njit
from granplate.physics.contact import COEF_KS


@njit(cache=True, inline="always")
def law_friction(n_abs, v_t, coef):
    return coef[COEF_KS] * v_t


@njit(cache=True, inline="always")
def law_slopes(n_abs, v_t, coef):
    return 0.0, coef[COEF_KS]


@njit(cache=True, inline="always")
def law_relaxed_slip(v_t, n_abs, coef, inv_mass_t, dt):
    return v_t * math.exp(-coef[COEF_KS] * inv_mass_t * dt)


def law_columns(coef, compliance, contact):
    coef[:, COEF_KS] = 2.0
"""

SPRING = """
import math
from granplate.jit import njit
from granplate.physics.contact import COEF_KT, COEF_MU, COEF_MUT


@njit(cache=True, inline="always")
def law_scale(coef, r_star, delta):
    return 1.0


@njit(cache=True, inline="always")
def law_stiffness(coef, a):
    return coef[COEF_KT]


@njit(cache=True, inline="always")
def law_energy(coef, a, xx, xy, xz):
    return 0.5 * coef[COEF_KT] * (xx * xx + xy * xy + xz * xz)


@njit(cache=True, inline="always")
def _capped(xx, xy, xz, k, f_crit):
    mag = k * math.sqrt(xx * xx + xy * xy + xz * xz)
    s = f_crit / mag if mag > f_crit else 1.0
    return -k * xx * s, -k * xy * s, -k * xz * s, xx * s, xy * s, xz * s


@njit(cache=True, inline="always")
def law_step(xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, vx, vy, vz, dt, n_abs, f0x, f0y, f0z):
    k = coef[COEF_KT]
    fx, fy, fz, xx, xy, xz = _capped(xx + vx * dt, xy + vy * dt, xz + vz * dt, k, coef[COEF_MUT] * n_abs)
    return fx, fy, fz, xx, xy, xz, 0.5 * k * (xx * xx + xy * xy + xz * xz), 0.0


@njit(cache=True, inline="always")
def law_stage(xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, ix, iy, iz, vx, vy, vz, n_abs):
    k = coef[COEF_KT]
    fx, fy, fz, xx, xy, xz = _capped(xx + ix, xy + iy, xz + iz, k, coef[COEF_MUT] * n_abs)
    return fx, fy, fz, xx, xy, xz, 0.5 * k * (xx * xx + xy * xy + xz * xz)


def law_columns(coef, compliance, contact):
    coef[:, COEF_KT] = 1e6
    coef[:, COEF_MUT] = coef[:, COEF_MU]
    coef[:, COEF_MU] = 0.0
"""


@pytest.fixture
def toy_laws(tmp_path, monkeypatch):
    """The registry with the two toy laws added as a user adds them (one module and one line
    each); returns the dispatch built from it and the laws' ids."""
    (tmp_path / "granplate_toy_dashpot.py").write_text(DASHPOT)
    (tmp_path / "granplate_toy_spring.py").write_text(SPRING)
    monkeypatch.syspath_prepend(str(tmp_path))
    registry = dict(law_registry.TANGENTIAL_LAW_REGISTRY)
    registry["dashpot"] = TangentialLaw("granplate_toy_dashpot")
    registry["spring"] = TangentialLaw("granplate_toy_spring", history=True)
    monkeypatch.setattr(law_registry, "TANGENTIAL_LAW_REGISTRY", registry)
    return laws.tangential_dispatch(registry), list(registry).index("dashpot"), list(registry).index("spring")


def tangential_row(name: str, mu: float = 0.3, k_s: float = 1e3) -> np.ndarray:
    """A coefficient row with mu, k_s and the tangential law `name`'s columns and id."""
    c = np.zeros((1, N_COEF))
    c[0, COEF_MU], c[0, COEF_KS] = mu, k_s
    contact = type("Contact", (), {"tangential_damping": 0.0})()
    laws.tangential_columns(name, c, np.array([1e-11]), contact)
    return c[0]


def rate_values(d):
    """A compiled caller of the rate dispatch `d` (what a pass calls)."""
    friction, slopes, relaxed = d.friction, d.slopes, d.relaxed_slip

    @njit
    def call(law, n, v, c, inv_m, dt):
        return friction(law, n, v, c), slopes(law, n, v, c), relaxed(law, v, n, c, inv_m, dt)

    return call


def history_values(d):
    """A compiled caller of the history dispatch `d`."""
    keeps, step, stage, energy, stiffness = d.keeps_history, d.step, d.stage, d.energy, d.stiffness

    @njit
    def call(law, c, v, dt, n):
        s = step(law, 0.0, 0.0, 0.0, 1.0, 1.0, c, 1e-6, 1.0, 0.0, 0.0, 0.0, v, 0.0, dt, n, 0.0, 0.0, 0.0)
        g = stage(law, 0.0, 0.0, 0.0, 1.0, 1.0, c, 1e-6, 1.0, 0.0, 0.0, 0.0, v * dt, 0.0, 0.0, v, 0.0, n)
        return keeps(law), s, g, energy(law, c, 1.0, 0.0, 1e-6, 0.0), stiffness(law, c, 1.0)

    return call


def test_a_new_rate_law_is_one_module_and_one_registry_entry(toy_laws):
    """A dashpot f = eta v_t given as one module and one registry line is dispatched by its
    id: its force eta v_t, its slopes (0, eta) and the split's exact flow v e^(-eta dt / m_t);
    the tanh law keeps eq. (5) and a history law's id gives no rate friction."""
    d, dashpot, _ = toy_laws
    call = rate_values(d)
    c = np.zeros(N_COEF)
    c[COEF_MU], c[COEF_KS] = 0.3, 2.0
    f, (f_n, f_v), v1 = call(dashpot, 10.0, 0.5, c, 4.0, 0.1)
    assert (f, f_n, f_v) == (1.0, 0.0, 2.0)
    assert v1 == pytest.approx(0.5 * math.exp(-0.8), rel=1e-15)
    f, (f_n, f_v), v1 = call(TANH, 10.0, 0.5, c, 4.0, 0.1)
    assert f == friction_magnitude(10.0, 0.5, 0.3, 2.0) and f_n == pytest.approx(0.3 * math.tanh(1.0), rel=1e-15)
    assert f_v == pytest.approx(0.3 * 10.0 * 2.0 / math.cosh(1.0) ** 2, rel=1e-14) and 0.0 < v1 < 0.5
    assert call(MINDLIN, 10.0, 0.5, c, 4.0, 0.1) == (0.0, (0.0, 0.0), 0.5)


def test_a_new_history_law_is_one_module_and_one_registry_entry(toy_laws):
    """A linear spring capped at mu |N| (Cundall-Strack) given as one module and one registry
    line keeps a history and is dispatched by its id: stuck, F = -k_t v dt and energy
    k_t (v dt)^2 / 2; sliding, |F| = mu |N| with the history cut back to mu |N| / k_t; a stage
    with the same increment gives the same force; Mindlin keeps its own id."""
    d, dashpot, spring = toy_laws
    call = history_values(d)
    c = np.zeros(N_COEF)
    c[COEF_KT], c[COEF_MUT] = 1e6, 0.3
    keeps, s, g, e, k = call(spring, c, 1e-3, 1e-3, 10.0)  # slip 1 um: 1 N < mu |N| = 3 N
    assert keeps and k == 1e6 and e == pytest.approx(0.5e-6, rel=1e-14)
    assert s[1] == pytest.approx(-1.0, rel=1e-12) and s[4] == pytest.approx(1e-6, rel=1e-12)
    assert s[6] == pytest.approx(0.5 * 1e6 * 1e-12, rel=1e-12) and g[:7] == pytest.approx(s[:7], rel=1e-14)
    _, s, _, _, _ = call(spring, c, 1e-2, 1e-3, 10.0)  # slip 10 um: capped at 3 N
    assert s[1] == pytest.approx(-3.0, rel=1e-12) and s[4] == pytest.approx(3e-6, rel=1e-12)
    assert not call(dashpot, c, 1e-3, 1e-3, 10.0)[0] and not call(TANH, c, 1e-3, 1e-3, 10.0)[0]
    keeps, _, _, e, k = call(MINDLIN, c, 1e-3, 1e-3, 10.0)
    assert keeps and k == 1e6 * 1.0 and e == pytest.approx(0.5e-6, rel=1e-14)  # 8 G* a with a = 1


def test_a_registered_law_writes_its_columns_and_id():
    """`tangential_columns` writes each registered law's id into COEF_TLAW and its columns:
    the tanh law keeps mu and k_s; Mindlin's moves mu to COEF_MUT and takes 8 G* = 8 / (1/G*)."""
    tanh = tangential_row("tanh")
    assert tanh[COEF_TLAW] == TANGENTIAL_LAW_IDS["tanh"] and (tanh[COEF_MU], tanh[COEF_KS]) == (0.3, 1e3)
    mindlin = tangential_row("mindlin")
    assert mindlin[COEF_TLAW] == MINDLIN and (mindlin[COEF_MU], mindlin[COEF_MUT]) == (0.0, 0.3)
    assert mindlin[COEF_KT] == pytest.approx(8e11, rel=1e-15)


def test_every_registered_tangential_module_gives_its_interface():
    """Each registry entry's module gives every function of its kind, and a module lacking one
    is refused naming it."""
    for name, law in law_registry.TANGENTIAL_LAW_REGISTRY.items():
        module = laws.tangential_module(name)
        wanted = laws.HISTORY_FUNCTIONS if law.history else laws.RATE_FUNCTIONS
        assert all(callable(getattr(module, f)) for f in wanted)
    with pytest.raises(ImportError, match="lacks law_friction"):
        laws.tangential_module("broken", TangentialLaw("granplate.physics.hertz"))
    with pytest.raises(ImportError, match="lacks law_scale"):
        laws.tangential_module("broken", TangentialLaw("granplate.physics.tanh_friction", history=True))


#: what only the laws' own modules and physics.laws may do: call a law's functions, compare
#: the id column (model.coefficients writes it); solver.settling, pouring's ramped
#: relaxation, runs Mindlin's law by design
LAW_NAMES = re.compile(
    r"\b(friction_magnitude|friction_slope|slip_after_friction|mindlin_step|stage_force|mindlin_force)\("
    r"|COEF_TLAW\]\s*[!=]=|\b(MINDLIN|TANH)\b\s*[!=]=|[!=]=\s*\b(MINDLIN|TANH)\b"
)
LAW_HOMES = {
    "physics/contact.py",
    "physics/tanh_friction.py",
    "physics/mindlin.py",
    "physics/mindlin_force.py",
    "physics/laws.py",
}


def test_every_pass_reaches_the_tangential_laws_through_the_dispatch():
    """No module outside the laws' own and physics.laws calls a tangential law's function or
    compares the law id column: each pass reaches the law of a contact by its id."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        if rel in LAW_HOMES or rel == "solver/settling.py":
            continue
        for k, line in enumerate(path.read_text().splitlines(), 1):
            if LAW_NAMES.search(line.split("#")[0]):
                found.append(f"{rel}:{k}: {line.strip()}")
    assert not found, "\n".join(found)
