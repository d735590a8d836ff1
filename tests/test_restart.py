"""Restart from a result: a run restarted at t1 from a result's stored state and continued
to t2 equals the run straight to t2 bitwise (granules, energies, the plate's modal state,
the contacts' histories), with yielding (Thornton) contacts and friction, for the implicit
scheme with a 2D plate and velocity Verlet in 3D; mismatched restarts are refused by field."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import granplate as gp
from granplate.errors import ScenarioError
from granplate.model.inputs import HIST_XI, HIST_XI_END, N_HIST, N_HIST_NORMAL, N_HIST_STEP, N_MINDLIN
from granplate.results.dataset import read, write
from granplate.results.restart import restart_state
from granplate.results.run import simulate
from granplate.setup.geometry import resolve

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"
T1, T2 = 5e-5, 1e-4


def yielding(example: str, scheme: str) -> gp.Scenario:
    """The example with Thornton's yielding law, friction mu = 0.3, outputs every 10 us."""
    text = (EXAMPLES / example).read_text()
    extra = f'output_interval = 1e-5\n\n[contact]\nnormal_law = "thornton"\nmu = 0.3\n\n[solver]\nscheme = "{scheme}"\n'
    return gp.loads(text.replace("[time]\nt_end = 1e-4\n", "[time]\nt_end = 1e-4\n" + extra))


def same_end(straight, restarted) -> None:
    """Every output variable at t2 and every stored loop array (State, plate modes,
    contact histories) equal bitwise."""
    assert float(restarted.time[0]) == T1 and float(restarted.time[-1]) == T2
    assert restarted.attrs["E_initial"] == straight.attrs["E_initial"]  # the balance's E_0: the first run's
    for name, v in straight.data_vars.items():
        if "time" in v.dims and v.dims[0] == "time" and name in restarted:
            a, b = v.isel(time=-1).values, restarted[name].isel(time=-1).values
            np.testing.assert_array_equal(a, b, err_msg=str(name))
    s0, s1 = restart_state(straight), restart_state(restarted)
    for key in ("st.y", "st.q", "st.qd", "st.acc", "g.pair_hist", "g.wall_hist", "g.pc_hist"):
        np.testing.assert_array_equal(s0[key], s1[key], err_msg=key)


@pytest.fixture(scope="module")
def plate_runs(tmp_path_factory):
    s = yielding("chain.toml", "implicit")
    first = simulate(s, t_end=T1)
    path = write(first, tmp_path_factory.mktemp("restart") / "first.nc")
    return s, simulate(s), first, read(path)


def test_implicit_2d_plate_restart_equals_straight_run(plate_runs):
    s, straight, first, from_file = plate_runs
    assert float(straight.D_plastic[-1]) > 0.0 and float(straight.D_friction[-1]) > 0.0  # yield, friction
    assert not any(k.startswith("b.") for k in restart_state(first))  # no body in space: nothing of it kept
    same_end(straight, simulate(s, start_from=from_file))


def widened(ds):
    """ds with its restart state's history rows of four columns widened to N_HIST (as a result
    written when every run kept 18), the new columns zero."""
    for name in [str(v) for v in ds.data_vars if str(v).startswith(("restart_g__", "restart_stores__"))]:
        v = ds[name].values
        if name.endswith("_hist") and v.ndim == 2 and v.shape[1] == N_HIST_NORMAL:
            w = np.zeros((v.shape[0], N_HIST))
            w[:, :N_HIST_NORMAL] = v
            ds = ds.drop_vars(name).assign({name: ((f"{name}_rows", f"{name}_columns"), w)})
    return ds


def test_history_rows_of_a_run_without_a_history_law_are_the_normal_laws(plate_runs):
    """Friction without history (tanh): each contact's history is the normal law's four
    numbers; a result written when the rows were 18 numbers restarts to the same end, bitwise."""
    s, straight, first, _ = plate_runs
    state = restart_state(first)
    assert state["g.pair_hist"].shape[1] == state["g.pc_hist"].shape[1] == N_HIST_NORMAL
    old = widened(first)
    assert restart_state(old)["g.pair_hist"].shape[1] == N_HIST
    same_end(straight, simulate(s, start_from=old))


def with_trial_columns(ds):
    """ds with its restart state's Mindlin rows of N_HIST_STEP columns widened to N_HIST as a
    result written when every run kept the trial apart: the trial columns a copy of the
    committed ones (what the commit leaves)."""
    for name in [str(v) for v in ds.data_vars if str(v).startswith(("restart_g__", "restart_stores__"))]:
        v = ds[name].values
        if name.endswith("_hist") and v.ndim == 2 and v.shape[1] == N_HIST_STEP:
            w = np.zeros((v.shape[0], N_HIST))
            w[:, :N_HIST_STEP] = v
            w[:, HIST_XI_END : HIST_XI_END + N_MINDLIN] = v[:, HIST_XI : HIST_XI + N_MINDLIN]
            ds = ds.drop_vars(name).assign({name: ((f"{name}_rows", f"{name}_columns"), w)})
    return ds


def test_verlet_mindlin_histories_move_on_in_place_and_earlier_rows_restart_the_same():
    """Mindlin's law under velocity Verlet (an fcc stack in its box, so pairs and walls): each
    contact's history is N_HIST_STEP numbers moved on in place; the run restarts to the same
    end bitwise from its own result and from one whose rows keep the trial apart (N_HIST, as
    results were written before), which then runs the trial-and-commit path."""
    changes = {"contact.tangential_law": "mindlin", "contact.mu": 0.3, "solver.scheme": "verlet"}
    s = gp.load_scenario(EXAMPLES / "3d-fcc.toml", {**changes, "time.output_interval": 1e-5})
    straight = simulate(s)
    first = simulate(s, t_end=T1)
    state = restart_state(first)
    assert state["g.pair_hist"].shape[1] == state["g.wall_hist"].shape[1] == N_HIST_STEP
    assert np.count_nonzero(state["g.pair_hist"][:, HIST_XI : HIST_XI + 3]) > 0  # springs loaded
    assert np.count_nonzero(state["g.wall_hist"][:, HIST_XI : HIST_XI + 3]) > 0
    same_end(straight, simulate(s, start_from=first))
    old = with_trial_columns(first)
    assert restart_state(old)["g.pair_hist"].shape[1] == N_HIST
    rest = simulate(s, start_from=old)
    assert restart_state(rest)["g.pair_hist"].shape[1] == N_HIST  # the rows it read, kept
    for name, v in straight.data_vars.items():
        if "time" in v.dims and v.dims[0] == "time" and name in rest and not name.startswith("restart_"):
            np.testing.assert_array_equal(v.isel(time=-1).values, rest[name].isel(time=-1).values, err_msg=str(name))
    s0, s1 = restart_state(straight), restart_state(rest)
    for key in ("g.pair_hist", "g.wall_hist"):
        np.testing.assert_array_equal(s0[key], s1[key][:, :N_HIST_STEP], err_msg=key)


@pytest.mark.filterwarnings("ignore:.*overlap_warn")
def test_verlet_3d_restart_equals_straight_run():
    s = yielding("3d-chain.toml", "verlet")
    s = dataclasses.replace(s, load=dataclasses.replace(s.load, force=2000.0))
    straight = simulate(s)
    assert float(straight.D_plastic[-1]) > 0.0
    same_end(straight, simulate(s, start_from=simulate(s, t_end=T1)))


def test_mismatched_restart_refused_by_field(plate_runs):
    s, _, first, _ = plate_runs
    r = resolve(s)
    bigger = dataclasses.replace(r, granules=(dataclasses.replace(r.granules[0], radius=0.011), *r.granules[1:]))
    with pytest.raises(ScenarioError, match=r"granules\[0\]\.radius"):
        simulate(bigger, start_from=first)
    fewer = dataclasses.replace(r, granules=r.granules[:-1])
    with pytest.raises(ScenarioError, match=r"'granules' = 14: granules; the result has 15"):
        simulate(fewer, start_from=first)
    with pytest.raises(ScenarioError, match=r"'from_time' = 3e-05.*available: t = 5e-05"):
        simulate(s, start_from=first, start_time=3e-5)


def test_verlet_3d_elastic_body_restart_equals_straight_run_to_round_off():
    """An fcc packing on an elastic solid (modes and residual compliance), yielding
    contacts with friction: the restarted run ends where the straight one does to
    round-off (the body's contact search is re-seeded at the restart: not bitwise)."""
    text = (EXAMPLES / "3d-fcc-on-plate.toml").read_text()
    s = gp.loads(text.replace("[solver]\n", '[contact]\nnormal_law = "thornton"\nmu = 0.3\n\n[solver]\n'))
    straight = simulate(s, t_end=4e-5)
    first = simulate(s, t_end=2e-5)
    restarted = simulate(s, t_end=4e-5, start_from=first)
    assert float(straight.D_plastic[-1]) > 0.0 and float(straight.D_friction[-1]) > 0.0
    for name in ("x", "y", "z", "vx", "vy", "vz", "E_granular", "E_plate", "E_shock", "D_plastic", "D_friction"):
        a, b = straight[name].isel(time=-1).values, restarted[name].isel(time=-1).values
        np.testing.assert_allclose(b, a, rtol=0.0, atol=1e-9 * float(np.max(np.abs(a))), err_msg=name)
    s0, s1 = restart_state(straight), restart_state(restarted)
    for key in ("st.q", "st.qd", "b.hist"):
        np.testing.assert_allclose(s1[key], s0[key], rtol=0.0, atol=1e-9 * max(float(np.max(np.abs(s0[key]))), 1e-300))
    # a result written when the scheme's scratch held the body ("sw.body.x") restarts the same
    body = [str(v) for v in first.data_vars if str(v).startswith("restart_b__")]
    assert "restart_b__hist" in body
    former = first.rename({v: "restart_sw__body__" + v[len("restart_b__") :] for v in body})
    assert "b.hist" not in restart_state(former) and "sw.body.hist" in restart_state(former)
    again = simulate(s, t_end=4e-5, start_from=former)
    for name in ("x", "y", "z", "vx", "vy", "vz", "E_granular", "E_plate", "D_friction"):
        np.testing.assert_array_equal(again[name].values, restarted[name].values, err_msg=name)
