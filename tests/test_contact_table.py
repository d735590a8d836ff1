"""The result's contact table (link_*, results.contact_table) against truths it did not
compute: statics (a precompressed chain carries its force F0 at every contact, and each
wall's contacts add up to the force the loop booked on that wall, wall_force), Thornton's
law replayed along the recorded overlaps from a virgin contact (physics.plastic, P8) with
the loop's wall_force beside it, the size rule of time.contact_interval, and the figures
reading it (no module of granplate.figures builds a model or calls a contact law)."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

import granplate as gp
from granplate.errors import ScenarioError, YieldWarning
from granplate.physics.plastic import contact_yield_overlap, plastic_force
from granplate.setup.materials import LIBRARY, effective_modulus
from granplate.setup.validate import validate

PRESSED = """
name = "pressed-chain"
dimension = {dimension}
{granules}
[precompression]
target = "{wall}"
force = 10.0
[time]
t_end = 1e-5
dt_initial = 1e-8
dt_max = 1e-8
output_interval = 1e-6
field_interval = 5e-6
[solver]
scheme = "verlet"
"""

DISCS = "".join(
    f'[[granules]]\nx = {0.005 + 0.01 * k!r}\ny = 0.005\nradius = 0.005\nmaterial = "steel"\n' for k in range(6)
) + (
    '[[walls]]\nlabel = "left"\nnormal = [-1.0, 0.0]\noffset = 0.0\n'
    '[[walls]]\nlabel = "right"\nnormal = [1.0, 0.0]\noffset = 0.06\n[load]\nkind = "none"\n'
)
#: A chain pressed by 10 N passes Hertz's onset of yield (the run says so once).
pytestmark = pytest.mark.filterwarnings("ignore", category=YieldWarning)

SPHERES = '[layout]\nkind = "chain"\ncount = 6\nradius = 0.005\nmaterial = "steel"\n'


@pytest.mark.parametrize("dimension", [2, 3])
def test_a_pressed_chain_table_carries_the_force_and_the_walls_receive_it(dimension):
    """Every pair and wall contact carries F0 = 10 N (to the static solve's 1e-8), at every
    time of the table (every field_interval: 3 of the 11 outputs, the last included), and
    the table's contacts on each wall add up to the run's wall_force to round-off."""
    granules, wall = (DISCS, "wall right") if dimension == 2 else (SPHERES, "wall xmax")
    ds = gp.simulate(gp.loads(PRESSED.format(dimension=dimension, granules=granules, wall=wall)), progress=False)
    np.testing.assert_allclose(ds.link_table_time.values, [0.0, 5e-6, 1e-5], rtol=1e-12, atol=1e-18)
    partner = ds.link_partner.values
    assert len(partner) == 3 * 7 and ds.link_overlap.values.min() > 0.0
    np.testing.assert_allclose(ds.link_normal_force.values, 10.0, rtol=1e-7)
    np.testing.assert_array_equal(ds.link_tangential_force.values, 0.0)  # at rest: no slip
    for t in ds.link_table_time.values:
        on = ds.link_time.values == t
        for w in range(ds.sizes["wall"]):
            mine = on & (partner == -1 - w)
            assert mine.sum() == 1
            booked = float(ds.wall_force.sel(time=t).values[w])
            assert float(ds.link_normal_force.values[mine].sum()) == pytest.approx(booked, rel=1e-12)


RADIUS = 0.01
THORNTON = f"""
name = "thornton-impacts"
dimension = 3
[[granules]]
label = "a"
x = {RADIUS + 1e-6!r}
y = 0.0
z = 0.0
vx = -1.0
radius = {RADIUS!r}
material = "steel"
[[granules]]
label = "b"
x = 0.1
y = 0.0
z = 0.0
vx = 1.0
radius = {RADIUS!r}
material = "steel"
[[granules]]
label = "c"
x = {0.1 + 2 * RADIUS + 2e-6!r}
y = 0.0
z = 0.0
vx = -1.0
radius = {RADIUS!r}
material = "steel"
[[walls]]
label = "floor"
normal = [-1.0, 0.0, 0.0]
offset = 0.0
material = "steel"
[load]
kind = "none"
[contact]
alpha_n = 0.0
mu = 0.0
normal_law = "thornton"
[time]
t_end = 8e-5
dt_initial = 2e-7
dt_max = 2e-7
output_interval = 2e-7
field_interval = 8e-5
contact_interval = 2e-7
[solver]
scheme = "verlet"
"""


@pytest.fixture(scope="module")
def impacts():
    return gp.simulate(gp.loads(THORNTON), progress=False)


def replay(delta: np.ndarray, a: float, dy: float) -> np.ndarray:
    """Thornton's force (P8) along the overlaps delta from a virgin contact."""
    out, dmax = np.zeros(len(delta)), 0.0
    for k, d in enumerate(delta):
        out[k] = plastic_force(a, dy, float(d), dmax) if d > 0.0 else 0.0
        dmax = max(dmax, float(d))
    return out


@pytest.mark.parametrize("partner, r_star, e_star", [(-1, RADIUS, "wall"), (2, RADIUS / 2, "pair")])
def test_thornton_table_is_the_laws_replay_not_hertz(impacts, partner, r_star, e_star):
    """A sphere on a wall and a head-on pair, both steel under Thornton's law, undamped: at
    every output the table's normal force is the law replayed along the table's own overlaps
    (its largest overlap the loop's, output = step), unloading far below Hertz's A delta^(3/2);
    the wall's contact is the force the loop booked on the wall."""
    steel = LIBRARY["steel"]
    es = effective_modulus(steel, None) if e_star == "wall" else effective_modulus(steel, steel)
    a, dy = 4.0 / 3.0 * es * math.sqrt(r_star), contact_yield_overlap(es, r_star, steel.Y)
    mine = impacts.link_partner.values == partner
    t, delta, force = (impacts[k].values[mine] for k in ("link_time", "link_overlap", "link_normal_force"))
    assert len(t) > 50 and delta.max() > 5 * dy
    assert np.all(np.diff(t) > 0)  # one row per output while in touch, one contact
    np.testing.assert_allclose(force, replay(delta, a, dy), rtol=1e-9)
    hertz = a * delta**1.5
    assert np.max(np.abs(force - hertz)) > 0.3 * force.max()
    if partner < 0:
        booked = impacts.wall_force.sel(time=t).values[:, 0]
        np.testing.assert_allclose(force, booked, rtol=1e-9)


def test_contact_interval_is_checked_and_zero_writes_no_table():
    """time.contact_interval: a whole multiple of output_interval or 0 (no table), the field
    named; 0 writes no link_* variables."""
    s = gp.loads(THORNTON.replace("contact_interval = 2e-7", "contact_interval = 3e-7"))
    with pytest.raises(ScenarioError, match="time.contact_interval"):
        validate(s)
    with pytest.raises(ScenarioError, match="time.contact_interval"):
        validate(gp.loads(THORNTON.replace("contact_interval = 2e-7", "contact_interval = -1.0")))
    text = PRESSED.format(dimension=3, granules=SPHERES, wall="wall xmax").replace(
        "field_interval = 5e-6", "field_interval = 5e-6\ncontact_interval = 0.0"
    )
    ds = gp.simulate(gp.loads(text), progress=False)
    assert not [k for k in ds.variables if str(k).startswith("link")]


#: What a figure may not import: the model's builder and coefficients, and any contact law.
FORBIDDEN_NAMES = {"build_model", "pair_coefficients", "wall_arrays", "normal_law_force", "hertz_coefficient"}


def test_no_figure_builds_a_model_or_calls_a_contact_law():
    """No module under granplate/figures imports granplate.physics, build_model or the
    coefficient builders (they read the result, never recompute it)."""
    root = Path(gp.__file__).parent / "figures"
    bad = []
    for path in sorted(root.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                names = {a.name for a in node.names}
                if node.module.startswith("granplate.physics") or names & FORBIDDEN_NAMES:
                    bad.append(f"{path.name}:{node.lineno} from {node.module} import {', '.join(sorted(names))}")
            elif isinstance(node, ast.Import):
                bad += [f"{path.name}:{node.lineno} import {a.name}" for a in node.names if "physics" in a.name]
    assert not bad, bad
    assert len(list(root.glob("*.py"))) > 5


def test_table_rows_follow_the_whole_runs_times():
    """Every 5th output time of the whole run and t_end: from t = 0, and in a run restarted
    at the 3rd output time (its rows 2 and 7 are the run's 5th and 10th, its last t_end)."""
    from granplate.results.contact_table import table_rows

    dt = 1e-6
    np.testing.assert_array_equal(table_rows(11, 5, dt * np.arange(11), 10 * dt, dt), [0, 5, 10])
    np.testing.assert_array_equal(table_rows(10, 5, dt * np.arange(3, 13), 12 * dt, dt), [2, 7, 9])
    np.testing.assert_array_equal(table_rows(10, 0, dt * np.arange(10), 9 * dt, dt), [])


def test_johnson_wall_contact_is_the_force_the_loop_booked():
    """Under the law "johnson" on a rate-dependent steel (its yield strength fixed by the
    approach speed when the contact first yields: the history's rate factor) the table's force on the wall is, at every output
    in touch, the force the loop booked on the wall (wall_force), and the contact yielded."""
    text = THORNTON.replace('normal_law = "thornton"', 'normal_law = "johnson"').replace('"steel"', '"steel_302"')
    text = text.replace("dt_initial = 2e-7\ndt_max = 2e-7", "dt_initial = 5e-8\ndt_max = 5e-8")  # 4 steps an output
    ds = gp.simulate(gp.loads(text), progress=False)
    mine = ds.link_partner.values == -1
    t, force = ds.link_time.values[mine], ds.link_normal_force.values[mine]
    assert len(t) > 50 and float(ds.D_plastic[-1]) > 0.0
    np.testing.assert_allclose(force, ds.wall_force.sel(time=t).values[:, 0], rtol=1e-9)


def _gas(dimension: int) -> str:
    """Eight steel granules (R = 4 mm, gaps 0.3 mm) flying at 4 m/s between four walls (six in
    space): pairs and walls come into touch and part again over the run's 301 output times."""
    rng = np.random.default_rng(7)
    d = dimension
    text = f'name = "gas"\ndimension = {d}\n[load]\nkind = "none"\n'
    for k in range(8):
        x, y = 0.0045 + 0.0083 * (k % 4), 0.0045 + 0.0083 * (k // 4)
        v = rng.normal(size=d)
        v = [float(c) for c in 4.0 * v / np.linalg.norm(v)]
        pos = f"x = {x!r}\ny = {y!r}\n" + (f"z = {0.0045!r}\n" if d == 3 else "")
        vel = f"vx = {v[0]!r}\nvy = {v[1]!r}\n" + (f"vz = {v[2]!r}\n" if d == 3 else "")
        text += f'[[granules]]\n{pos}{vel}radius = 0.004\nmaterial = "steel"\n'
    for axis, (lo, hi) in enumerate([(0.0, 0.0335), (0.0, 0.0174), (0.0, 0.009)][:d]):
        for sign, off in ((-1.0, lo), (1.0, hi)):
            n = [0.0] * d
            n[axis] = sign
            text += f"[[walls]]\nnormal = {n}\noffset = {sign * off!r}\n"
    return text + (
        "[time]\nt_end = 3e-4\ndt_initial = 1e-8\ndt_max = 5e-8\noutput_interval = 1e-6\n"
        'field_interval = 1e-6\n[solver]\nscheme = "verlet"\n[contact]\ndetection = "dynamic"\n'
    )


@pytest.mark.parametrize("dimension", [2, 3])
@pytest.mark.parametrize("law", ["hertz", "thornton"])
def test_blocks_of_output_times_give_the_table_of_one_time_at_a_time(dimension, law, monkeypatch):
    """A gas of granules between walls, every output time tabled (elastic, and yielding so
    that every output time's overlaps enter the histories): the table built in blocks of
    output times (small blocks forced, several taken and some halved as the granules move)
    holds the same rows and numbers, bit for bit, as the one built one output time at a time
    with the candidate pairs searched at that time."""
    import dataclasses

    from granplate.model.arrays import build_model
    from granplate.results import contact_table as ct
    from granplate.setup.run_checks import contact_steps
    from granplate.solver.driver import run

    s = gp.loads(_gas(dimension))
    if law == "thornton":
        steel = dataclasses.replace(LIBRARY["steel"], Y=3e8)
        s = dataclasses.replace(
            s, materials={**s.materials, "steel": steel}, contact=dataclasses.replace(s.contact, normal_law=law)
        )
    model = build_model(s)
    rec = run(model)
    args = (model, rec.out, rec.n_valid, rec.contacts.peaks, contact_steps(s.time))
    monkeypatch.setattr(ct, "BLOCK_ROWS", 200)
    blocks, _ = ct.contact_table(*args)
    monkeypatch.setattr(ct, "block_candidates", lambda ys, r: None)
    one_at_a_time, _ = ct.contact_table(*args)
    times = blocks["link_time"].values
    assert len(np.unique(times)) > 20 and (blocks["link_partner"].values < 0).any()
    assert (blocks["link_partner"].values >= 0).any() and (np.diff(times) >= 0).all()
    if law == "thornton":  # contacts that yielded, their history read
        assert (
            blocks["link_overlap"].values > contact_yield_overlap(effective_modulus(steel, steel), 0.002, 3e8)
        ).any()
    for name in blocks:
        np.testing.assert_array_equal(blocks[name].values, one_at_a_time[name].values, err_msg=name)
