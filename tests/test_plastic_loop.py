"""The elastic-plastic law (docs/model.md section 3.6) in the time loop: impacts against
Thornton's closed forms, the contact history across list rebuilds, the plastic work in
eq. (11), Y -> infinity as Hertz bitwise, and how the runs report yield."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import granplate as gp
from granplate.errors import YieldWarning
from granplate.model.arrays import carried_history
from granplate.model.inputs import HIST_MAX, HIST_TIME, no_history
from granplate.physics.plastic import plastic_work, yield_overlap
from granplate.physics.contact import hertz_coefficient
from granplate.setup.materials import effective_modulus
from granplate.verification.plastic import thornton_restitution, thornton_yield_velocity

R = 0.01  # [m]
RHO = 7850.0
Y = 355e6  # [Pa] structural steel
MASS = 4.0 / 3.0 * math.pi * R**3 * RHO


def impact(
    kind: str,
    ratio: float,
    *,
    law: str = "thornton",
    scheme: str = "paper",
    skin: float = 0.1,
    y_strength: float = Y,
    alpha_n: float = 0.0,
    mu: float = 0.0,
    vy: float = 0.0,
    t_end: float = 2e-4,
    dt: float = 2e-8,
) -> tuple[gp.Scenario, float]:
    """A steel sphere (R = 1 cm) touching a rigid wall ("wall") or an equal sphere at rest
    ("pair") at t = 0 and moving into it at `ratio` times Thornton's yield velocity (P11)
    of a steel of Y = 355 MPa (its material's Y is y_strength);
    returns the scenario and that velocity [m/s]."""
    steel = gp.loads(f"[materials.steel]\nE = 2.0e11\nnu = 0.3\nrho = {RHO}\nY = {y_strength}\n").material("steel")
    if kind == "wall":
        e_star, r_star, m_star = effective_modulus(steel, None), R, MASS
    else:
        e_star, r_star, m_star = effective_modulus(steel, steel), R / 2, MASS / 2
    v_y = thornton_yield_velocity(e_star, r_star, m_star, 1.6 * Y)  # (of the structural steel, whatever y_strength)
    v = ratio * v_y
    other = (
        '[[walls]]\nlabel = "left"\nnormal = [-1.0, 0.0]\noffset = 0.0\nmaterial = "steel"\n'
        if kind == "wall"
        else f'[[granules]]\nlabel = "b"\nx = {-R}\ny = 0.0\nradius = {R}\nmaterial = "steel"\n'
    )
    text = f"""
name = "plastic-{kind}"
[materials.steel]
E = 2.0e11
nu = 0.30
rho = {RHO}
Y = {y_strength}
[[granules]]
label = "a"
x = {R}
y = 0.0
radius = {R}
material = "steel"
vx = {-v}
vy = {vy}
{other}
[load]
kind = "none"
[contact]
detection = "dynamic"
alpha_n = {alpha_n}
mu = {mu}
skin = {skin}
normal_law = "{law}"
pairs = []
[time]
t_end = {t_end}
dt_initial = {dt}
dt_max = {dt}
output_interval = 1e-6
field_interval = 1e-6
[solver]
scheme = "{scheme}"
"""
    return gp.loads(text), v


def rebound(ds, v: float, kind: str) -> float:
    """Coefficient of restitution: relative normal velocity after over before."""
    vx = ds.vx.values[-1]
    rel = vx[0] if kind == "wall" else vx[0] - vx[1]
    return rel / v


def quiet_simulate(s):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", YieldWarning)
        return gp.simulate(s, progress=False)


@pytest.mark.parametrize("kind", ["wall", "pair"])
@pytest.mark.parametrize("ratio", [2.0, 10.0, 100.0])
def test_impact_restitution_matches_thornton(kind, ratio):
    """Restitution of a head-on impact at 2-100 v_y equals Thornton's closed form (P12)
    within 0.1%, the plastic work D_plastic = 1/2 m* v^2 (1 - e^2), and eq. (11) holds."""
    s, v = impact(kind, ratio)
    ds = quiet_simulate(s)
    e = rebound(ds, v, kind)
    assert e == pytest.approx(thornton_restitution(ratio), rel=1e-3)
    m_star = MASS if kind == "wall" else MASS / 2
    assert float(ds.D_plastic[-1]) == pytest.approx(0.5 * m_star * v * v * (1 - e * e), rel=1e-6)
    assert float(np.max(np.abs(ds.energy_residual_max))) < 1e-6


def test_implicit_scheme_follows_the_plastic_law_too():
    """The implicit scheme (its Newton sees no granule-wall slope, but its error control
    sees the plastic work) gives Thornton's restitution (P12) within 0.1%."""
    s, v = impact("wall", 10.0, scheme="implicit")
    ds = quiet_simulate(s)
    assert rebound(ds, v, "wall") == pytest.approx(thornton_restitution(10.0), rel=1e-3)
    assert float(np.max(np.abs(ds.energy_residual_max))) < 1e-4


def test_history_survives_forced_list_rebuilds():
    """With a tiny Verlet skin the pair list is rebuilt many times during the contact; the
    contact's largest overlap is carried, so the rebound equals a run without rebuilds
    and Thornton's (P12). (A history dropped on a rebuild would unload along the loading
    line from a fresh delta_max and rebound at a different speed.)"""
    few, v = impact("pair", 10.0, skin=0.5)
    many, _ = impact("pair", 10.0, skin=2e-5)
    ds_few, ds_many = quiet_simulate(few), quiet_simulate(many)
    assert ds_many.attrs["n_rebuilds"] > 10 * max(ds_few.attrs["n_rebuilds"], 1)
    assert rebound(ds_many, v, "pair") == pytest.approx(rebound(ds_few, v, "pair"), rel=1e-9)
    assert rebound(ds_many, v, "pair") == pytest.approx(thornton_restitution(10.0), rel=1e-3)


def test_carried_history_keeps_contacts_that_leave_the_list():
    """carried_history: a contact's row follows its key into the new list; one that
    leaves is kept in the store and comes back with its row; untouched ones start at 0."""
    old = no_history(3)
    old[0, HIST_MAX], old[0, HIST_TIME] = 1e-6, 1e-5
    old[2, HIST_MAX] = 2e-6
    store: dict = {}
    new = carried_history([(0, 1), (1, 2), (2, 3)], old, [(2, 3), (5, 6)], store)
    assert new[0, HIST_MAX] == 2e-6 and new[1, HIST_MAX] == 0.0
    assert set(store) == {(0, 1)} and store[(0, 1)][HIST_TIME] == 1e-5
    back = carried_history([(2, 3), (5, 6)], new, [(0, 1), (2, 3)], store)
    assert back[0, HIST_MAX] == 1e-6 and back[1, HIST_MAX] == 2e-6 and store == {}


def test_infinite_yield_strength_is_hertz_bitwise():
    """With Y so large that delta_y exceeds any overlap the plastic law is Hertz's: the
    trajectory equals the elastic law's bit for bit, with no plastic work."""
    s_h, _ = impact("pair", 10.0, law="hertz", y_strength=1e13, alpha_n=0.05, mu=0.3, vy=0.01)
    s_t, _ = impact("pair", 10.0, law="thornton", y_strength=1e13, alpha_n=0.05, mu=0.3, vy=0.01)
    a, b = quiet_simulate(s_h), quiet_simulate(s_t)
    for name in ("x", "y", "vx", "vy", "omega", "E_granular", "D_viscous", "D_friction"):
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)
    assert float(b.D_plastic[-1]) == 0.0


@pytest.mark.parametrize("scheme", ["paper", "implicit"])
def test_damped_oblique_impact_keeps_the_energy_balance(scheme):
    """An oblique, damped impact with friction on a wall: eq. (11) with D_plastic holds at
    every step within solver.energy_tol, every dissipation grows, and D_plastic equals
    Thornton's plastic work W_p (P10) at the contact's largest overlap, which the Dataset
    gives through its Hertz peak pressure (P2)."""
    s, v = impact("wall", 20.0, scheme=scheme, alpha_n=0.05, mu=0.3, vy=0.01)
    ds = quiet_simulate(s)
    assert float(np.max(np.abs(ds.energy_residual_max))) < s.solver.energy_tol
    for name in ("D_viscous", "D_friction", "D_plastic"):
        d = ds[name].values
        assert d[-1] > 0.0 and np.all(np.diff(d) >= -1e-18), name
    steel = s.material("steel")
    e_star = effective_modulus(steel, None)
    p0 = float(ds.pair_max_contact_pressure.sel(material_pair="steel-wall"))
    delta_max = (math.pi * p0 / (2 * e_star)) ** 2 * R
    a = hertz_coefficient(e_star, R)
    w_p = plastic_work(a, yield_overlap(e_star, R, 1.6 * Y), delta_max)
    assert float(ds.D_plastic[-1]) == pytest.approx(w_p, rel=1e-9)
    assert str(ds.pair_normal_law.sel(material_pair="steel-wall").values) == "thornton"


def test_elastic_contacts_past_yield_warn_once_and_report_the_ratio():
    """A Hertz impact at 10 v_y passes the onset of yield: one YieldWarning naming the
    pair, the contact, the time, the ratio and the plastic law; the summary's
    yield_onset_ratio is p0 / (1.6 Y) with p0 = (2/pi) E* sqrt(delta_max / R*) (P2),
    above 1; under the plastic law no warning."""
    s, _ = impact("wall", 10.0, law="hertz")
    with pytest.warns(YieldWarning) as rec:
        ds = gp.simulate(s, progress=False)
    lines = [str(w.message) for w in rec if issubclass(w.category, YieldWarning)]
    assert len(lines) == 1
    assert "steel-wall" in lines[0] and "a-wall left" in lines[0] and "thornton" in lines[0] and "t = " in lines[0]
    summ = gp.summary(ds)
    steel = s.material("steel")
    e_star = effective_modulus(steel, None)
    # Hertz impact: delta_max from 1/2 m v^2 = 2/5 A delta^(5/2)
    v = float(-ds.vx.values[0, 0])
    delta_max = (1.25 * MASS * v * v / hertz_coefficient(e_star, R)) ** 0.4
    p0 = 2 / math.pi * e_star * math.sqrt(delta_max / R)
    assert summ["max_contact_pressure"] == pytest.approx(p0, rel=1e-4)
    assert summ["yield_onset_ratio"] == pytest.approx(p0 / (1.6 * Y), rel=1e-4)
    assert summ["yield_onset_ratio"] > 1.0
    assert f"{summ['yield_onset_ratio']:.3g}" in lines[0]
    plastic, _ = impact("wall", 10.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", YieldWarning)
        gp.simulate(plastic, progress=False)


def test_unknown_yield_strength_gives_no_ratio():
    """A material without Y: the pressure is reported, its ratio is null (unknown), no warning."""
    s, _ = impact("pair", 10.0, law="hertz")
    s = gp.loads(gp.dumps(s).replace(f"Y = {Y}", ""))
    with warnings.catch_warnings():
        warnings.simplefilter("error", YieldWarning)
        summ = gp.summary(gp.simulate(s, progress=False))
    assert summ["yield_onset_ratio"] is None and summ["max_contact_pressure"] > 0
    assert summ["contact_pairs"][0]["yield_onset_ratio"] is None


@pytest.mark.parametrize("scheme", ["paper", "implicit"])
def test_patch_contact_keeps_its_history_as_it_slides(scheme):
    """An oblique impact with friction on the paper's plate under the plastic law: the
    granule's patch contact slides past a face node while the contact yields; its history
    moves with it, so eq. (11) with D_plastic balances and D_plastic is Thornton's W_p (P10)
    at the contact's largest overlap (from the Dataset's Hertz peak pressure, P2)."""
    from granplate.verification.face_contacts import R as R_DROP, bounce, drop_scenario, node_spacing

    s = drop_scenario(0.05, vx=1.0, vy=4.0, mu=0.3, t_end=1e-3, out=5e-7)
    s = gp.with_changes(s, {"contact.normal_law": "thornton", "solver.scheme": scheme})
    ds = quiet_simulate(s)
    b = bounce(ds)
    assert b["travel"] > node_spacing(40)
    assert b["residual"] < 1e-5
    g = s.material(s.granules[0].material)
    e_star = effective_modulus(g, None)
    p0 = float(ds.pair_max_contact_pressure.sel(material_pair=f"{g.name}-plate"))
    delta_max = (math.pi * p0 / (2 * e_star)) ** 2 * R_DROP
    w_p = plastic_work(hertz_coefficient(e_star, R_DROP), yield_overlap(e_star, R_DROP, 1.6 * g.Y), delta_max)
    assert float(ds.D_plastic[-1]) == pytest.approx(w_p, rel=1e-9)
    assert float(ds.D_plastic[-1]) > 1e-3 * float(ds.E_granular[0])  # ~14% of the normal kinetic energy
