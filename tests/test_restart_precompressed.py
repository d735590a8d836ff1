"""Restart of a precompressed run: a 3D diatomic chain pressed by 10 N ([precompression])
and shaken by a driven wall, run to t1, restarted and continued to t2, equals the run straight
to t2 bitwise, and its energy balance (eq. 11, the static state's stored energy in E_initial)
holds at every step of the restarted run to round-off; every contact-list rebuild keeps the
target wall at its static offset (the truth: the static state's wall offset)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import granplate as gp
from granplate.model.arrays import build_model
from granplate.results.restart import restart_state
from granplate.results.run import simulate
from granplate.solver.driver import ContactLists

EXAMPLE = Path(__file__).resolve().parents[1] / "docs" / "examples" / "diatomic-chain.toml"
T1, T2 = 1e-4, 2e-4


def test_rebuilt_lists_keep_the_precompressed_wall_where_the_static_state_left_it():
    model = build_model(gp.load_scenario(EXAMPLE))
    lists = ContactLists(model)
    before = lists.g.wall_geo.copy()
    assert lists.refresh(model.initial_state) is None
    np.testing.assert_array_equal(lists.g.wall_geo, before)  # the wall "xmax" 27 um inside its given offset
    assert before[-1, -1] < model.scenario.walls[1].offset - 1e-5


def test_precompressed_chain_restart_equals_straight_run_and_keeps_the_balance():
    s = gp.with_changes(gp.load_scenario(EXAMPLE), {"time.t_end": T2, "time.field_interval": T2})
    straight = simulate(s)
    rest = simulate(s, start_from=simulate(s, t_end=T1))
    assert rest.attrs["E_initial"] == straight.attrs["E_initial"] > 0.0  # the stored energy of the static state
    assert float(rest.time[0]) == T1 and float(rest.time[-1]) == T2
    on = straight.time.values >= T1
    for name in ("x", "vx", "E_granular", "E_drive", "D_viscous", "wall_force", "energy_residual"):
        np.testing.assert_array_equal(rest[name].values[1:], straight[name].values[on][1:], err_msg=name)
    np.testing.assert_array_equal(restart_state(rest)["st.y"], restart_state(straight)["st.y"])
    assert float(np.max(np.abs(rest.energy_residual_max.values))) < 1e-10
    assert float(np.max(np.abs(straight.x.values[-1] - straight.x.values[0]))) > 0.0  # the chain moved
