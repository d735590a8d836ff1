"""The velocity-Verlet loop on several threads (solver.blocks, solver.threads): the same
physics as the serial loop to round-off, bitwise repeatable, the energy balance held."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from granplate.bench.scaling_space import launched_fcc
from granplate.errors import ScenarioError, YieldWarning
from granplate.model.arrays import build_model
from granplate.results.run import simulate
from granplate.setup.scenario import Drive, Wall
from granplate.setup.threads import PARALLEL_MIN_GRANULES, available_threads, check_threads, loop_threads
from granplate.setup.validate import validate
from granplate.solver import granular3d
from granplate.solver.blocks import N_FPAR, N_SPAR, normal_forces_blocks
from granplate.solver.driver import ContactLists
from granplate.model.inputs import HIST_END, HIST_MAX, HIST_TIME, HIST_XI, N_HIST_STEP

THREADS = min(2, available_threads())


def packing(threads: int | None, mu: float = 0.3):
    """A struck FCC packing (48 spheres) against a wall, damped, with friction, verlet, `threads`."""
    s = launched_fcc((3, 2, 2), mu=mu, t_end=12e-6, scheme="verlet")
    floor = Wall(normal=(1.0, 0.0, 0.0), offset=float(max(g.x + g.radius for g in s.granules)), label="floor")
    contact = dataclasses.replace(s.contact, alpha_n=0.3)  # damped: D_viscous is booked too
    return dataclasses.replace(
        s, walls=(floor,), contact=contact, solver=dataclasses.replace(s.solver, threads=threads)
    )


def run(s):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", YieldWarning)
        return simulate(s, progress=False)


@pytest.fixture(scope="module")
def runs():
    return {n: run(packing(n)) for n in (1, THREADS)} | {"again": run(packing(THREADS))}


def test_threads_equal_the_serial_loop_to_round_off(runs):
    """Positions, velocities and energies on THREADS threads are the serial run's within
    1e-12 of their scale (only the order of the force sums differs)."""
    one, many = runs[1], runs[THREADS]
    assert many.attrs["threads"] == THREADS and one.attrs["threads"] == 1
    for name in ("x", "y", "z", "vx", "vy", "vz", "omega_x", "E_granular", "D_viscous", "D_friction"):
        a, b = one[name].values, many[name].values
        assert np.abs(a - b).max() <= 1e-12 * max(np.abs(a).max(), 1e-30), name
    assert one.wall_force.values.max() > 1.0 and one.D_friction.values[-1] > 0.0 and one.D_viscous.values[-1] > 0.0
    np.testing.assert_allclose(many.wall_force.values, one.wall_force.values, rtol=1e-10, atol=1e-9)


def test_threaded_run_is_bitwise_repeatable(runs):
    """Two runs on the same number of threads give the same bits (fixed blocks, whatever
    the scheduling)."""
    for name in ("x", "vx", "vz", "E_granular", "wall_force"):
        assert np.array_equal(runs[THREADS][name].values, runs["again"][name].values), name


def test_threaded_run_keeps_the_energy_balance(runs):
    """Eq. (11) holds on several threads as on one: the residual within solver.energy_tol
    and within 1e-9 of the serial run's."""
    a, b = runs[1].energy_residual.values, runs[THREADS].energy_residual.values
    assert np.abs(b).max() < 1e-4
    assert np.abs(a - b).max() < 1e-9


@pytest.mark.parametrize("nb", [1, 3, 7])
def test_block_force_pass_equals_the_serial_pass(nb):
    """normal_forces_blocks with nb blocks (any count, whatever the threads) gives the
    serial pass's accelerations to round-off and its overlaps and largest overlap exactly."""
    s = packing(1, mu=0.0)
    m = build_model(s)
    lists = ContactLists(m)
    lists.refresh(m.initial_state)
    g, cfg = lists.g, m.config
    rng = np.random.default_rng(7)
    y = m.initial_state.copy()
    y[:, :3] += rng.normal(0.0, 2e-6, (len(y), 3))  # overlaps of a few um, some pairs apart
    y[:, 3:6] += rng.normal(0.0, 0.1, (len(y), 3))
    ng = len(y)
    acc0, fd0, fl0 = (np.zeros((ng, 9)) for _ in range(3))
    serial = granular3d.normal_forces(0.0, y, g, cfg, acc0, fd0, fl0, -1.0)
    end0 = g.pair_hist[:, HIST_END].copy()
    acc1, fd1, fl1 = (np.zeros((ng, 9)) for _ in range(3))
    blocks = normal_forces_blocks(
        0.0, y, g, cfg, acc1, fd1, fl1, np.zeros((nb, ng, N_FPAR)), np.zeros((nb, N_SPAR)), -1.0
    )
    assert np.array_equal(g.pair_hist[:, HIST_END], end0)
    assert (blocks.ovl, blocks.ovl_i, blocks.ovl_j) == (serial.ovl, serial.ovl_i, serial.ovl_j)
    assert serial.ovl > 0.0
    scale = np.abs(acc0).max()
    assert np.abs(acc1 - acc0).max() <= 1e-13 * scale
    assert blocks.e_pot == pytest.approx(serial.e_pot, rel=1e-13)


def test_threads_field_is_checked_and_resolved(monkeypatch):
    """solver.threads: an integer from 1 to the machine's threads, named when refused;
    absent means every core (or GRANPLATE_THREADS) from PARALLEL_MIN_GRANULES granules on,
    for verlet only."""
    n = available_threads()
    for bad in (0, -1, n + 1, 1.5, True, "2"):
        with pytest.raises(ScenarioError, match="solver.threads"):
            check_threads(bad)
    with pytest.raises(ScenarioError, match="solver.threads"):
        validate(packing(n + 1))
    monkeypatch.delenv("GRANPLATE_THREADS", raising=False)
    assert loop_threads(None, PARALLEL_MIN_GRANULES, "verlet") == n
    monkeypatch.setenv("GRANPLATE_THREADS", "1")
    assert loop_threads(None, PARALLEL_MIN_GRANULES, "verlet") == 1
    monkeypatch.setenv("GRANPLATE_THREADS", "zero")
    with pytest.raises(ScenarioError, match="GRANPLATE_THREADS"):
        loop_threads(None, PARALLEL_MIN_GRANULES, "verlet")
    monkeypatch.delenv("GRANPLATE_THREADS")
    assert loop_threads(None, PARALLEL_MIN_GRANULES - 1, "verlet") == 1
    assert loop_threads(2, 10, "implicit") == 1
    assert build_model(packing(None)).config.threads == 1  # 48 spheres: serial


def _numba_threads() -> int:
    import numba

    return int(numba.config.NUMBA_NUM_THREADS)


def test_study_workers_run_one_thread_each():
    """A local Dask cluster's workers run numba on one thread, so designs that leave
    solver.threads out do not oversubscribe the cores the workers share."""
    from granplate.results.engine import dask_client

    with dask_client(workers=1) as client:
        assert client.submit(_numba_threads, pure=False).result() == 1


@pytest.mark.parametrize("nt, nb", [(1, 1), (3, 3), (2, 8)])
def test_block_mindlin_pass_equals_the_serial_pass(nt, nb):
    """Mindlin's force pass in nb blocks dealt out to nt buffers (solver.blocks.
    mindlin_forces_blocks: a thread's blocks in turn, into its buffer) gives the serial
    pass's accelerations and spins to round-off, each contact's history bit for bit
    (its own step alone), and the springs' energy and losses to round-off."""
    from granplate.solver.blocks import mindlin_forces_blocks
    from granplate.solver.mindlin_space import normal_mindlin_forces

    s = packing(1, mu=0.3)
    s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, tangential_law="mindlin"))
    m = build_model(s)
    lists = ContactLists(m)
    lists.refresh(m.initial_state)
    g, cfg = lists.g, m.config
    rng = np.random.default_rng(11)
    y = m.initial_state.copy()
    y[:, :3] += rng.normal(0.0, 2e-6, (len(y), 3))
    y[:, 3:9] += rng.normal(0.0, 0.1, (len(y), 6))
    ng = len(y)
    start = g.pair_hist.copy(), g.wall_hist.copy()
    out = []
    for blocks in (False, True):
        hist, wall = (h.copy() for h in start)  # both from the same committed histories
        acc, fd, fl = (np.zeros((ng, 9)) for _ in range(3))
        for _ in range(3):  # three steps, the histories moving on between them
            g.pair_hist[:] = hist
            g.wall_hist[:] = wall
            if blocks:
                sums, e_t, lost = mindlin_forces_blocks(
                    0.0, y, y, 1e-8, g, cfg, acc, fd, fl, np.zeros((nt, ng, N_FPAR)), np.zeros((nb, N_SPAR)), 1e-8
                )
            else:
                sums, e_t, lost = normal_mindlin_forces(0.0, y, y, 1e-8, g, cfg, acc, fd, fl, 1e-8)
            hist, wall = g.pair_hist.copy(), g.wall_hist.copy()  # (velocity Verlet's rows: moved on in place)
        out.append((acc.copy(), g.pair_hist.copy(), e_t, lost))
    (a0, h0, e0, l0), (a1, h1, e1, l1) = out
    assert g.pair_hist.shape[1] == N_HIST_STEP
    assert np.array_equal(h0, h1)
    assert e0 > 0.0 and np.abs(h0[:, HIST_XI : HIST_XI + 3]).max() > 0.0
    assert np.abs(a1 - a0).max() <= 1e-13 * np.abs(a0).max()
    assert np.abs(a0[:, 6:9]).max() > 0.0  # the tangential forces' torques
    assert e1 == pytest.approx(e0, rel=1e-13) and l1 == pytest.approx(l0, rel=1e-12, abs=1e-25)


def test_kicks_that_skip_zero_rows_change_no_bit():
    """solver.kicks with `loads` / `damped` False (the rows known all zero) give the bits of
    the kicks that read those rows: the same state, prediction and works."""
    from granplate.solver.kicks import kick, kick_drift

    rng = np.random.default_rng(3)
    y0, acc = rng.normal(size=(50, 9)), rng.normal(size=(50, 9))
    zeros = np.zeros((50, 9))
    out = []
    for flag in (True, False):
        y, ypred = y0.copy(), np.zeros((50, 9))
        w1 = kick_drift(y, y, acc, zeros, zeros, 1e-3, ypred, 3, 0, 50, True, flag, flag)
        dy = np.zeros((50, 9))
        w2 = kick(y, acc, zeros, zeros, 5e-4, dy, 3, 0, 50, flag, flag)
        out.append((y, ypred, dy, w1, w2))
    (a, b) = out
    for u, v in zip(a[:3], b[:3]):
        assert np.array_equal(u, v)
    assert a[3] == b[3] == (0.0, 0.0) and a[4] == b[4] == (0.0, 0.0)


@pytest.mark.parametrize("alpha_n", [0.0, 0.3])
def test_block_pass_counts_the_granules_it_damps(alpha_n):
    """The threaded pass in space counts the granules given a damping force (solver.blocks
    S_DAMPED): none without damping (so the kicks may skip fdamp), some with it, and fdamp
    is then the serial pass's to round-off."""
    from granplate.solver.blocks import S_DAMPED

    s = packing(1, mu=0.0)
    s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, alpha_n=alpha_n))
    m = build_model(s)
    lists = ContactLists(m)
    lists.refresh(m.initial_state)
    g, cfg = lists.g, m.config
    y = m.initial_state.copy()
    y[:, :3] += np.random.default_rng(5).normal(0.0, 2e-6, (len(y), 3))
    y[:, 3:6] += 0.1
    ng = len(y)
    acc0, fd0, fl0 = (np.zeros((ng, 9)) for _ in range(3))
    granular3d.normal_forces(0.0, y, g, cfg, acc0, fd0, fl0, -1.0)
    acc1, fd1, fl1 = (np.full((ng, 9), 7.0) for _ in range(3))  # the pass clears what it writes
    spar = np.zeros((2, N_SPAR))
    normal_forces_blocks(0.0, y, g, cfg, acc1, fd1, fl1, np.zeros((2, ng, N_FPAR)), spar, -1.0)
    assert spar[0, S_DAMPED] == np.count_nonzero(np.abs(fd0).sum(axis=1))
    assert (spar[0, S_DAMPED] > 0) == (alpha_n > 0.0)
    assert np.abs(fd1[:, 3:] - fd0[:, 3:]).max() <= 1e-13 * max(np.abs(fd0).max(), 1e-30)
    assert np.abs(acc1[:, 3:] - acc0[:, 3:]).max() <= 1e-13 * np.abs(acc0).max()
    assert not fl1[:, 3:].any()


def test_shocked_undamped_packing_on_threads_equals_the_serial_loop():
    """A packing shocked on its first plane (docs/examples/3d-fcc.toml, alpha_n = 0,
    verlet) on THREADS threads: the threaded kicks read the loads while the shock lasts and
    skip their zero rows after it, and the shock's work, the energies and the state are
    the serial run's to round-off."""
    from pathlib import Path

    from granplate.setup.io import load

    base = load(Path(__file__).resolve().parents[1] / "docs" / "examples" / "3d-fcc.toml")
    base = dataclasses.replace(
        base,
        contact=dataclasses.replace(base.contact, alpha_n=0.0),
        time=dataclasses.replace(base.time, t_end=2e-5, output_interval=1e-6, field_interval=1e-6),
    )
    ds = {}
    for n in (1, THREADS):
        ds[n] = run(dataclasses.replace(base, solver=dataclasses.replace(base.solver, scheme="verlet", threads=n)))
    one, many = ds[1], ds[THREADS]
    assert one.E_shock.values[-1] > 0.0 and one.E_shock.values[-1] == one.E_shock.values[len(one.E_shock) // 2]
    for name in ("x", "vx", "vy", "E_granular", "E_shock", "D_viscous"):
        a, b = one[name].values, many[name].values
        assert np.abs(a - b).max() <= 1e-12 * np.abs(a).max(), name  # (measured: at most 1e-14)
    assert np.abs(one.energy_residual.values - many.energy_residual.values).max() < 1e-12


def _pass_commits(s, force_pass, seed):
    """The pair histories after `force_pass(y, g, cfg, commit_t)` at a perturbed state of
    scenario s: committed by the pass at t (commit_t = t) and by the loop's commit after a
    pass that commits nothing (commit_t = -1, then solver.granular.commit_history), each
    from the same histories; returns both and the histories before."""
    from granplate.solver.granular import commit_history

    m = build_model(s)
    lists = ContactLists(m)
    lists.refresh(m.initial_state)
    g, cfg = lists.g, m.config
    rng = np.random.default_rng(seed)
    y = m.initial_state.copy()
    dim = 3 if y.shape[1] == 9 else 2
    y[:, :dim] += rng.normal(0.0, 2e-6, (len(y), dim))
    y[:, dim : 2 * dim] += rng.normal(0.0, 0.1, (len(y), dim))
    t = 3.7e-6
    before = g.pair_hist.copy()
    force_pass(y, g, cfg, -1.0)
    commit_history(t, g.pair_hist, g.pair_coef)
    after_step = g.pair_hist.copy()
    g.pair_hist[:] = before
    force_pass(y, g, cfg, t)
    return g.pair_hist.copy(), after_step, before, t


def _space_passes():
    from granplate.solver.blocks import mindlin_forces_blocks
    from granplate.solver.mindlin_space import normal_mindlin_forces

    def arrays(y):
        return (np.zeros((len(y), 9)) for _ in range(3))

    def serial(y, g, cfg, commit_t):
        granular3d.normal_forces(0.0, y, g, cfg, *arrays(y), commit_t)

    def blocks(y, g, cfg, commit_t):
        normal_forces_blocks(0.0, y, g, cfg, *arrays(y), np.zeros((3, len(y), N_FPAR)), np.zeros((3, N_SPAR)), commit_t)

    def mindlin(y, g, cfg, commit_t):
        normal_mindlin_forces(0.0, y, y, 1e-8, g, cfg, *arrays(y), commit_t)

    def mindlin_blocks(y, g, cfg, commit_t):
        acc, fd, fl = arrays(y)
        mindlin_forces_blocks(
            0.0, y, y, 1e-8, g, cfg, acc, fd, fl, np.zeros((2, len(y), N_FPAR)), np.zeros((8, N_SPAR)), commit_t
        )

    return {"serial": serial, "blocks": blocks, "mindlin": mindlin, "mindlin_blocks": mindlin_blocks}


@pytest.mark.parametrize("kind", ["serial", "blocks", "mindlin", "mindlin_blocks"])
def test_force_pass_commits_the_largest_overlaps_as_the_step_commit_does(kind):
    """Velocity Verlet's force pass in space, told the step's end time, commits each pair's
    largest overlap, its time and its yielding law's rate factor to the bits the commit
    after the step gives (every Verlet step is accepted, so the loop then skips it)."""
    law = "mindlin" if kind.startswith("mindlin") else "tanh"
    s = packing(1, mu=0.3 if law == "mindlin" else 0.0)
    s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, normal_law="johnson", tangential_law=law))
    in_pass, after_step, before, t = _pass_commits(s, _space_passes()[kind], 13)
    assert np.array_equal(in_pass, after_step)
    grew = after_step[:, HIST_MAX] > before[:, HIST_MAX]
    assert grew.any() and np.all(after_step[grew, HIST_TIME] == t)


def test_plane_force_passes_commit_the_largest_overlaps_as_the_step_commit_does():
    """The same in the plane: solver.granular.normal_forces and Mindlin's pass
    (solver.mindlin_plane) committing in the pass give the commit after the step's bits."""
    from pathlib import Path

    from granplate.setup.io import load
    from granplate.solver import granular
    from granplate.solver.mindlin_plane import normal_mindlin_forces

    base = load(Path(__file__).resolve().parents[1] / "docs" / "examples" / "square.toml")
    for law, mu in (("tanh", 0.0), ("mindlin", 0.3)):
        s = dataclasses.replace(
            base,
            plate=None,
            contact=dataclasses.replace(base.contact, normal_law="johnson", tangential_law=law, mu=mu),
            solver=dataclasses.replace(base.solver, scheme="verlet"),
        )

        def plane_pass(y, g, cfg, commit_t, law=law):
            acc, fd, fl = (np.zeros((len(y), 6)) for _ in range(3))
            if law == "mindlin":
                normal_mindlin_forces(0.0, y, y, 1e-8, g, cfg, acc, fd, fl, commit_t)
            else:
                granular.normal_forces(0.0, y, g, cfg, acc, fd, fl, commit_t)

        in_pass, after_step, before, t = _pass_commits(s, plane_pass, 17)
        assert np.array_equal(in_pass, after_step), law
        grew = after_step[:, HIST_MAX] > before[:, HIST_MAX]
        assert grew.any() and np.all(after_step[grew, HIST_TIME] == t), law


def test_threaded_energy_check_sums_the_kinetic_energies_in_blocks():
    """The threaded Verlet step's kinetic energies (solver.schemes.verlet
    step_kinetic_energies: blocks on every core) are the serial sums to round-off, the
    same bits each call."""
    from granplate.solver.schemes.verlet_kicks import kinetic_energy_blocks

    m = build_model(packing(1, mu=0.0))
    g = m.granular
    y = m.initial_state.copy()
    y[:, 3:9] = np.random.default_rng(19).normal(0.0, 1.0, (len(y), 6))
    serial = np.array(granular3d.kinetic_energies(y, g.mass, g.inertia))
    spar = np.zeros((8, N_SPAR))
    blocks = np.array(kinetic_energy_blocks(y, g, spar))
    assert np.all(serial > 0.0)
    np.testing.assert_allclose(blocks, serial, rtol=1e-14)
    assert np.array_equal(blocks, np.array(kinetic_energy_blocks(y, g, spar)))


@pytest.mark.parametrize("case", ["quiet", "rebuild", "jump", "reach", "new_plate", "two"])
def test_screened_contact_watch_reports_what_the_serial_walk_does(case):
    """solver.contacts.watch_contacts screened in blocks on every core (Work.wflag longer
    than 1) returns the serial walk's status and failure record, wherever in the granule
    order the granule with something to report lies."""
    from granplate.solver.contacts import watch_contacts
    from granplate.solver.state import ERR_CONTACT, ERR_JUMP, ERR_PLATE_REACH, NEW_PLATE, OK, REBUILD

    rng = np.random.default_rng(11)
    ng, r, move = 203, 1e-3, 1e-3
    y = np.zeros((ng, 9))
    y[:, :3] = rng.uniform(0.0, 0.05, (ng, 3))
    yref = y[:, :3].copy()
    y[:, :3] += rng.uniform(-0.5, 0.5, (ng, 3)) * move / 2.0  # each moved less than `move`
    radius = np.full(ng, r)
    plate_free = np.zeros(ng, np.int64)
    x0 = 0.2  # the plate's face, beyond every granule
    k = 151
    if case == "rebuild":
        y[k, 1] = yref[k, 1] + 1.5 * move
    elif case == "jump":
        y[k, 2] = yref[k, 2] + 3.0 * move  # past rebuild_move + R
    elif case == "reach":
        plate_free[k], y[k, 0], yref[k, 0] = 1, x0, x0
    elif case == "new_plate":
        plate_free[k], y[k, 0], yref[k, 0] = 1, x0 - 1.2 * r, x0 - 1.2 * r
    elif case == "two":  # a rebuild early in the order, a patch contact later: the later status stands
        y[7, 0] = yref[7, 0] + 1.5 * move
        plate_free[k], y[k, 0], yref[k, 0] = 1, x0 - 1.2 * r, x0 - 1.2 * r
    want = {"quiet": OK, "rebuild": REBUILD, "jump": ERR_JUMP, "reach": ERR_PLATE_REACH}.get(case, NEW_PLATE)
    found = []
    for n_flags in (1, 2, 5):
        err = np.zeros(8)
        status = watch_contacts(
            0.0, y, np.zeros(0), radius, plate_free, yref, np.zeros(ng), np.zeros(ng, np.int64), np.zeros(1),
            np.full(2, -1, np.int64), 0.1, x0, -1.0, 1.0, move, 0.5, 3, -1.0, np.zeros(n_flags, np.int64), err,
        )  # fmt: skip
        found.append((status, err.tolist()))
    assert found[0][0] == want
    if want not in (OK, REBUILD):  # (a rebuild names no granule)
        assert found[0][1][ERR_CONTACT] == k
    assert found[1] == found[0] and found[2] == found[0]


@pytest.mark.parametrize("case", ["quiet", "rebuild", "jump", "edge"])
def test_watch_screened_by_the_measured_moves_reports_what_the_walk_does(case):
    """solver.contacts.watch_contacts given the step's largest squared move (moved2, the
    threaded first kick's: solver.schemes.verlet.first_kick_blocks) with no plate span to
    reach returns the walk's status and failure record; the first kick's per-block moves
    are solver.contacts.largest_move's of its blocks, which cover every granule."""
    from granplate.solver.blocks import S_MOVED
    from granplate.solver.contacts import largest_move, watch_contacts
    from granplate.solver.schemes.verlet_kicks import first_kick_blocks
    from granplate.solver.state import ERR_CONTACT, ERR_JUMP, OK, REBUILD

    rng = np.random.default_rng(13)
    ng, r, move = 157, 1e-3, 1e-3
    y = np.zeros((ng, 9))
    y[:, :3] = rng.uniform(0.0, 0.05, (ng, 3))
    yref = y[:, :3].copy()
    y[:, :3] += rng.uniform(-0.5, 0.5, (ng, 3)) * move / 2.0
    k = 97
    if case == "rebuild":
        y[k, 1] = yref[k, 1] + 1.5 * move
    elif case == "jump":
        y[k, 2] = yref[k, 2] + 3.0 * move
    elif case == "edge":  # rebuild_move to round-off: the screen and the walk decide alike
        y[k, :3] = yref[k]
        y[k, 0] += move
    y[:, 3:] = rng.normal(0.0, 1.0, (ng, 6))
    acc, zeros = rng.normal(0.0, 1.0, (ng, 9)), np.zeros((ng, 9))
    if case == "edge":  # (held where it is)
        y[k, 3:], acc[k] = 0.0, 0.0
    spar = np.zeros((8, N_SPAR))  # (8 blocks: 2 threads' share, each thread's in one run)
    y1, ypred = y.copy(), np.zeros((ng, 9))
    first_kick_blocks(y, y1, acc, zeros, zeros, 1e-9, ypred, spar, True, False, False, False, yref, 3)
    y = y1
    bounds = [(i * ng) // 8 for i in range(9)]
    for b in range(8):
        assert spar[b, S_MOVED] == largest_move(y, yref, bounds[b], bounds[b + 1], 3)
    moved2 = max(spar[:, S_MOVED])
    found = []
    for m2 in (-1.0, moved2):
        err = np.zeros(8)
        status = watch_contacts(
            0.0, y, np.zeros(0), np.full(ng, r), np.ones(ng, np.int64), yref, np.zeros(ng), np.zeros(ng, np.int64),
            np.zeros(1), np.full(2, -1, np.int64), 0.1, 0.2, 0.0, 0.0, move, 0.5, 3, m2, np.zeros(1, np.int64), err,
        )  # fmt: skip
        found.append((status, err.tolist()))
    want = {"rebuild": REBUILD, "jump": ERR_JUMP, "quiet": OK}.get(case, found[0][0])
    assert found[0][0] == want and want in (OK, REBUILD, ERR_JUMP) and found[1] == found[0]
    if case == "jump":
        assert found[0][1][ERR_CONTACT] == k


def test_pair_blocks_balance_the_last_pass_cost_and_cover_the_list():
    """solver.blocks.pair_blocks: equal shares of the list without a last pass over as many
    pairs; after one, contiguous ranges covering every pair once whose cost (a pair apart
    1, in touch 1 + TOUCH_WEIGHT) is equal to within one block's spread-out estimate."""
    from granplate.solver.blocks import S_PHI, S_PLO, S_TOUCH, TOUCH_WEIGHT, pair_blocks

    nb, n_p = 8, 10_000
    spar = np.zeros((nb, N_SPAR))
    pair_blocks(spar, nb, n_p, True)  # no last pass: equal shares
    assert spar[:, S_PLO].tolist() == [k * n_p // nb for k in range(nb)]
    rng = np.random.default_rng(2)
    touching = rng.random(n_p) < np.linspace(0.9, 0.05, n_p)  # a wave's front: most contacts in touch early in the list
    cost = 1.0 + TOUCH_WEIGHT * touching
    for _ in range(4):  # each pass counts its blocks' contacts in touch, the next takes its ranges from them
        for k in range(nb):
            lo, hi = int(spar[k, S_PLO]), int(spar[k, S_PHI])
            spar[k, S_TOUCH] = touching[lo:hi].sum()
        pair_blocks(spar, nb, n_p, True)
    lo, hi = spar[:, S_PLO].astype(int), spar[:, S_PHI].astype(int)
    assert lo[0] == 0 and hi[-1] == n_p and np.array_equal(lo[1:], hi[:-1]) and np.all(hi >= lo)
    shares = np.array([cost[a:b].sum() for a, b in zip(lo, hi)])
    assert shares.max() / shares.mean() < 1.03
    static = np.array([cost[k * n_p // nb : (k + 1) * n_p // nb].sum() for k in range(nb)])
    assert static.max() / static.mean() > 1.3  # (the equal shares were far from it)
    pair_blocks(spar, nb, n_p + 1, True)  # another list: equal shares again
    assert spar[:, S_PLO].tolist() == [k * (n_p + 1) // nb for k in range(nb)]


def test_first_kick_that_clears_the_accelerations_changes_no_bit():
    """solver.kicks.kick_drift with `clear` (the threaded step in place: its force pass then
    writes over acc uncleared) gives the bits of the kick without it, and leaves zeros in
    exactly the columns it kicked."""
    from granplate.solver.kicks import kick_drift

    rng = np.random.default_rng(7)
    y0, acc0 = rng.normal(size=(40, 9)), rng.normal(size=(40, 9))
    fdamp, fload = rng.normal(size=(40, 9)), rng.normal(size=(40, 9))
    out = []
    for clear in (False, True):
        y, ypred, acc = y0.copy(), np.zeros((40, 9)), acc0.copy()
        works = kick_drift(y0, y, acc, fdamp, fload, 1e-3, ypred, 3, 5, 33, True, True, True, clear)
        out.append((y, ypred, works, acc))
    (y1, p1, w1, a1), (y2, p2, w2, a2) = out
    assert np.array_equal(y1, y2) and np.array_equal(p1, p2) and w1 == w2
    assert np.array_equal(a1, acc0)
    assert np.all(a2[5:33, 3:] == 0.0)
    assert np.array_equal(a2[5:33, :3], acc0[5:33, :3])
    assert np.array_equal(a2[:5], acc0[:5]) and np.array_equal(a2[33:], acc0[33:])


def test_closing_kick_gives_the_kinetic_energies_of_the_kicked_state():
    """solver.schemes.verlet.closing_kick_blocks: the serial kick's state and works to the
    bit (works to round-off: summed per block), and with `energies` the blocks' kinetic
    energies, summed in block order, those `kinetic_energy_blocks` finds at the kicked state,
    bit for bit; without, the energy columns are left as they were."""
    from granplate.solver.blocks import S_KR, S_KX
    from granplate.solver.kicks import kick
    from granplate.solver.schemes.verlet_kicks import closing_kick_blocks, kinetic_energy_blocks, kinetic_sums

    m = build_model(packing(1, mu=0.0))
    g = m.granular
    rng = np.random.default_rng(23)
    y0 = m.initial_state.copy()
    y0[:, 3:9] = rng.normal(0.0, 1.0, (len(y0), 6))
    acc, fdamp = rng.normal(size=y0.shape), rng.normal(size=y0.shape)
    fload = np.zeros_like(y0)
    y_serial, dy_serial = y0.copy(), np.zeros_like(y0)
    w_serial = kick(y_serial, acc, fdamp, fload, 5e-4, dy_serial, 3, 0, len(y0), False, True)
    for energies in (True, False):
        y, dy, spar = y0.copy(), np.zeros_like(y0), np.zeros((8, N_SPAR))
        spar[:, S_KX : S_KR + 1] = -1.0
        works = closing_kick_blocks(y, acc, fdamp, fload, 5e-4, dy, 3, spar, False, True, g, energies, False, 3)
        assert np.array_equal(y, y_serial) and np.array_equal(dy, dy_serial)
        np.testing.assert_allclose(works, w_serial, rtol=1e-12)
        if energies:
            sums = np.array(kinetic_sums(spar))
            assert np.all(sums > 0.0)
            assert np.array_equal(sums, np.array(kinetic_energy_blocks(y, g, np.zeros((8, N_SPAR)))))
        else:
            assert np.all(spar[:, S_KX : S_KR + 1] == -1.0)


@pytest.mark.parametrize("n_move, nc", [(3, 9), (2, 6)])
def test_dividing_kick_is_the_division_then_the_kick(n_move, nc):
    """solver.kicks.divide_kick from forces and torques: the accelerations the pass's
    division gives (the first n_move velocity columns by the mass, the rest by the inertia,
    as the plane's and space's passes divide) and the state, rates and works of `kick`
    after it, bit for bit; in space over blocks on threads too (closing_kick_blocks with
    `divide`)."""
    from granplate.solver.kicks import divide_kick, kick
    from granplate.solver.schemes.verlet_kicks import closing_kick_blocks

    rng = np.random.default_rng(31)
    n = 40
    y0, force = rng.normal(size=(n, nc)), rng.normal(size=(n, nc))
    fdamp, fload = rng.normal(size=(n, nc)), rng.normal(size=(n, nc))
    mass, inertia = rng.uniform(0.5, 2.0, n), rng.uniform(1e-3, 1e-2, n)
    acc = force.copy()
    acc[:, 3 : 3 + n_move] /= mass[:, None]
    acc[:, 3 + n_move :] /= inertia[:, None]
    y_ref, dy_ref = y0.copy(), np.zeros((n, nc))
    w_ref = kick(y_ref, acc, fdamp, fload, 5e-4, dy_ref, 3, 0, n, True, True)
    y, a, dy = y0.copy(), force.copy(), np.zeros((n, nc))
    w = divide_kick(y, a, fdamp, fload, 5e-4, dy, 3, n_move, mass, inertia, 0, n, True, True)
    assert np.array_equal(a[:, 3:], acc[:, 3:]) and np.array_equal(a[:, :3], force[:, :3])
    assert np.array_equal(y, y_ref) and np.array_equal(dy, dy_ref) and w == w_ref
    if nc == 6:
        return
    g = build_model(packing(1, mu=0.0)).granular._replace(mass=mass, inertia=inertia)
    y, a, dy = y0.copy(), force.copy(), np.zeros((n, nc))
    works = closing_kick_blocks(
        y, a, fdamp, fload, 5e-4, dy, 3, np.zeros((4, N_SPAR)), True, True, g, False, True, n_move
    )
    assert np.array_equal(a[:, 3:], acc[:, 3:]) and np.array_equal(y, y_ref) and np.array_equal(dy, dy_ref)
    np.testing.assert_allclose(works, w_ref, rtol=1e-12)


@pytest.mark.parametrize("target", ["granule", "wall"])
def test_driven_packing_on_threads_equals_the_serial_loop(target):
    """A driven granule (its velocity set after the closing kick: the kinetic energies are
    then summed apart) or a driven wall (the step kept apart from t_n's state: no clearing
    first kick) on THREADS threads: the serial loop's motion to round-off, the energy
    balance held."""
    s = packing(None)
    if target == "granule":
        first = dataclasses.replace(s.granules[0], label="pushed")
        s = dataclasses.replace(s, granules=(first, *s.granules[1:]))
        drive = Drive(target="granule pushed", kind="velocity", direction=(1.0, 0.0, 0.0), value=0.5)
    else:
        drive = Drive(
            target="wall floor",
            kind="displacement",
            direction=(-1.0, 0.0, 0.0),
            profile="ramp",
            value=2e-6,
            duration=1e-5,
        )
    s = dataclasses.replace(s, drives=(drive,))
    one = run(dataclasses.replace(s, solver=dataclasses.replace(s.solver, threads=1)))
    many = run(dataclasses.replace(s, solver=dataclasses.replace(s.solver, threads=THREADS)))
    np.testing.assert_allclose(many["x"].values, one["x"].values, rtol=0.0, atol=1e-12)
    v_scale = float(np.abs(one["vx"].values).max())
    np.testing.assert_allclose(many["vx"].values, one["vx"].values, rtol=0.0, atol=1e-9 * v_scale)
    a, b = one.energy_residual.values, many.energy_residual.values
    assert np.abs(b).max() < 1e-4
    assert np.abs(a - b).max() < 1e-9


def test_serial_pass_notes_its_zero_rows_for_the_kicks():
    """solver.schemes.verlet.note_quiet without blocks (one thread): after a pass without
    viscous power an all-zero damping buffer is noted quiet (the serial kicks then skip it
    and the loads' rows, to the same bits: test_kicks_that_skip_zero_rows_change_no_bit), one
    nonzero damping number anywhere in the velocity columns is not; a pass with viscous
    power damped a granule, so its buffer is not read; the loads are quiet once the shock
    is over."""
    from granplate.model.inputs import no_body
    from granplate.solver.schemes.verlet import new_scratch, note_quiet

    m = build_model(packing(1, mu=0.0))
    ng = m.n_granules
    sw = new_scratch(ng, 0, 0)
    b = no_body(ng, 0)
    late = 10.0 * m.config.duration
    note_quiet(sw, 1, late, b, m.config, 0.0)
    assert sw.quiet[1, 0] == 1.0 and sw.quiet[1, 1] == 1.0
    note_quiet(sw, 1, late, b, m.config, 1e-9)
    assert sw.quiet[1, 0] == 1.0 and sw.quiet[1, 1] == 0.0
    sw.fdamp[1, ng - 1, 8] = 1e-30
    note_quiet(sw, 1, late, b, m.config, 0.0)
    assert sw.quiet[1, 1] == 0.0
    sw.fdamp[1, ng - 1, 8] = 0.0
    sw.fdamp[1, 0, 2] = 1.0  # a position column: not a kick's
    note_quiet(sw, 1, late, b, m.config, 0.0)
    assert sw.quiet[1, 1] == 1.0
