"""Restart from an earlier output time (time.restart_interval): a run restarted at a stored
time t1 before its end and continued to t2 equals the straight run to t2 bitwise at every
output time from t1 on (implicit scheme, plate in the plane, Thornton's yielding contacts and
friction; velocity Verlet of a chain in space struck obliquely; the first row's statistics
over the interval before t1 excepted: they cover no step of the restarted run); the
scenario's [restart] gives what --from/--from-time give; a time at which no state is
stored and other bad input are refused, naming the field."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from granplate.errors import ScenarioError
from granplate.results.dataset import read, write
from granplate.results.restart import restart_state, restart_times
from granplate.results.run import simulate
from tests.test_restart import T2, yielding

T1 = 3e-5  # the first of the stored times 30, 60, 90 us (restart_interval 30 us) and the end, 100 us


def with_interval(s, interval: float):
    return dataclasses.replace(s, time=dataclasses.replace(s.time, restart_interval=interval))


@pytest.fixture(scope="module")
def straight(tmp_path_factory):
    """The straight run to t2 with a state stored every 30 us, written and read back."""
    s = with_interval(yielding("chain.toml", "implicit"), 3e-5)
    path = write(simulate(s), tmp_path_factory.mktemp("earlier") / "straight.nc")
    return s, read(path)


def test_restart_at_an_earlier_time_equals_the_straight_run(straight):
    s, ds = straight
    assert restart_times(ds) == pytest.approx([3e-5, 6e-5, 9e-5, 1e-4], rel=1e-12)
    assert float(ds.D_plastic[-1]) > 0.0 and float(ds.D_friction[-1]) > 0.0  # yield, friction
    rest = simulate(s, start_from=ds, start_time=T1)
    assert rest.attrs["restarted_at"] == pytest.approx(T1, rel=1e-12) and float(rest.time[-1]) == T2
    on = ds.time.values >= rest.time.values[0]
    assert np.array_equal(ds.time.values[on], rest.time.values)
    first_row_differs = []
    for name, v in ds.data_vars.items():
        if v.dims and v.dims[0] == "time" and name in rest:
            np.testing.assert_array_equal(rest[name].values[1:], v.values[on][1:], err_msg=str(name))
            if not np.array_equal(rest[name].values[0], v.values[on][0]):
                first_row_differs.append(name)
    # the state at t1 is the same; the first row's statistics over the interval before it
    # cover no step of the restarted run
    assert first_row_differs == ["energy_residual_max", "iterations", "dt_min", "dt_max"]
    s0, s1 = restart_state(ds), restart_state(rest)
    for key in ("st.y", "st.q", "st.qd", "st.acc", "g.pair_hist", "g.wall_hist", "g.pc_hist"):
        np.testing.assert_array_equal(s0[key], s1[key], err_msg=key)
    # the restarted run stores its own states at the same times of the whole run
    assert restart_times(rest) == pytest.approx([6e-5, 9e-5, 1e-4], rel=1e-12)
    np.testing.assert_array_equal(restart_state(rest, 6e-5)["st.y"], restart_state(ds, 6e-5)["st.y"])


@pytest.mark.filterwarnings("ignore:.*overlap_warn")
def test_verlet_3d_oblique_restart_at_an_earlier_time_equals_the_straight_run():
    """Velocity Verlet of a chain in space struck obliquely: yielding and sliding contacts
    (D_plastic, D_friction each a share of E_shock); every output row from t1 on bitwise."""
    s = yielding("3d-chain.toml", "verlet")
    s = dataclasses.replace(s, load=dataclasses.replace(s.load, force=2000.0, direction=(1.0, 0.6, 0.3)))
    s = with_interval(s, 3e-5)
    ds = simulate(s)
    e_shock = float(ds.E_shock[-1])
    assert float(ds.D_plastic[-1]) > 1e-2 * e_shock and float(ds.D_friction[-1]) > 1e-3 * e_shock
    rest = simulate(s, start_from=ds, start_time=6e-5)
    n = rest.sizes["time"]
    for name in ("x", "y", "z", "vx", "vy", "vz", "E_granular", "D_plastic", "D_friction", "energy_residual"):
        np.testing.assert_array_equal(rest[name].values[1:], ds[name].values[-n + 1 :], err_msg=name)
    for key in ("st.y", "st.acc", "g.pair_hist", "g.wall_hist"):
        np.testing.assert_array_equal(restart_state(rest)[key], restart_state(ds)[key], err_msg=key)


def test_a_time_not_stored_is_refused_listing_the_stored_ones(straight):
    s, ds = straight
    with pytest.raises(
        ScenarioError, match=r"'from_time' = 5e-05.*available: t = 3\.0+\d*e-05, 6\.0+\d*e-05, 9e-05, 0\.0001"
    ):
        simulate(s, start_from=ds, start_time=5e-5)


@pytest.mark.parametrize(
    "interval, why",
    [(2.5e-5, "whole multiple of time.output_interval"), (1e-5 / 2, "whole multiple"), (-1.0, "must be > 0")],
)
def test_bad_restart_interval_refused(interval, why):
    from granplate.setup.validate import validate

    with pytest.raises(ScenarioError, match=rf"time\.restart_interval.*{why}"):
        validate(with_interval(yielding("chain.toml", "implicit"), interval))


def test_restart_states_are_bounded():
    """At most MAX_RESTART_STATES states before t_end (the Dataset's size stays bounded)."""
    from granplate.setup.run_checks import MAX_RESTART_STATES
    from granplate.setup.validate import validate

    s = yielding("chain.toml", "implicit")
    validate(with_interval(s, 1e-5))  # 9 states before the end
    s = dataclasses.replace(s, time=dataclasses.replace(s.time, output_interval=1e-6, field_interval=1e-6))
    with pytest.raises(
        ScenarioError, match=rf"time\.restart_interval.*would store 99 loop states.*at most {MAX_RESTART_STATES}"
    ):
        validate(with_interval(s, 1e-6))


def test_scenario_restart_key_equals_the_option(straight, tmp_path):
    """[restart] result (relative to the scenario file) and time give the run the option
    gives; the command line's options override them; bad input is refused naming the field."""
    import granplate as gp
    from granplate.setup.io import dumps
    from granplate.setup.validate import validate

    s, ds = straight
    write(ds, tmp_path / "straight.nc")
    text = dumps(s) + '\n[restart]\nresult = "straight.nc"\ntime = 3e-5\n'
    (tmp_path / "go-on.toml").write_text(text)
    keyed = gp.load_scenario(tmp_path / "go-on.toml")
    assert keyed.restart.result == str(tmp_path / "straight.nc")
    by_key = simulate(keyed)
    by_option = simulate(s, start_from=ds, start_time=T1)
    for name in ("x", "y", "vx", "E_granular", "E_plate", "D_plastic", "D_friction", "energy_residual"):
        np.testing.assert_array_equal(by_key[name].values, by_option[name].values, err_msg=name)
    assert by_key.attrs["restarted_at"] == by_option.attrs["restarted_at"]
    from granplate.cli import main

    out = tmp_path / "late.nc"  # the command line: its --from-time overrides restart.time
    assert main(["run", str(tmp_path / "go-on.toml"), "--from-time", "9e-5", "-o", str(out), "-q"]) == 0
    late = read(out)
    assert float(late.time[0]) == pytest.approx(9e-5, rel=1e-12)
    np.testing.assert_array_equal(late.x.values, ds.x.values[-2:])
    assert main(["run", str(tmp_path / "go-on.toml"), "--from", str(tmp_path / "none.nc"), "-q"]) == 2
    with pytest.raises(ScenarioError, match=r"'restart\.time' = 4e-05.*available: t = 3"):
        simulate(gp.with_changes(keyed, {"restart.time": 4e-5}))
    with pytest.raises(ScenarioError, match=r"'restart\.result' = .*missing\.nc.*no such file"):
        simulate(gp.with_changes(keyed, {"restart.result": str(tmp_path / "missing.nc")}))
    (tmp_path / "not-a-result.nc").write_text("text")
    with pytest.raises(ScenarioError, match=r"'restart\.result' = .*not-a-result\.nc.*cannot be read"):
        simulate(gp.with_changes(keyed, {"restart.result": str(tmp_path / "not-a-result.nc")}))
    with pytest.raises(ScenarioError, match=r"'restart\.time' = -1\.0: must be >= 0"):
        validate(gp.with_changes(keyed, {"restart.time": -1.0}))
    with pytest.raises(ScenarioError, match=r"'restart\.result' = '': must name a result"):
        validate(gp.with_changes(keyed, {"restart.result": ""}))
    with pytest.raises(ScenarioError, match=r"'granules' = \d+: granules; the result has \d+"):
        simulate(gp.with_changes(keyed, {"layout.count": 7}))
    with pytest.raises(ScenarioError, match=r"'from_time' = 3e-05.*needs a result"):
        simulate(s, start_time=3e-5)


def test_a_run_that_stopped_keeps_its_earlier_states(straight):
    """A result without its end state (a run stopped before its end) holds the states stored
    before; a restart goes on from the last of them and ends where the straight run does."""
    from granplate.results.restart import with_restart

    s, ds = straight
    states = [restart_state(ds, t) for t in (3e-5, 6e-5)]
    bare = ds.drop_vars([k for k in ds.data_vars if str(k).startswith("restart_")])
    bare.attrs = {k: v for k, v in ds.attrs.items() if not k.startswith("restart_")}
    stopped = with_restart(bare, None, states)
    assert "restart_time" not in stopped.attrs and restart_times(stopped) == pytest.approx([3e-5, 6e-5], rel=1e-12)
    rest = simulate(s, start_from=stopped)
    assert float(rest.time[0]) == pytest.approx(6e-5, rel=1e-12)
    np.testing.assert_array_equal(restart_state(rest)["st.y"], restart_state(ds)["st.y"])
    with pytest.raises(ScenarioError, match=r"the run stopped before its end"):
        simulate(s, start_from=stopped, start_time=1e-4)
