"""The implicit scheme's dyadic steps (solver/ladder.py): they tile the output interval,
never go below dt_min, and a position that the rounding of t has pushed off the grid is
brought back on it by one odd step, so the clock always moves on."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.results.run import build_model
from granplate.solver.ladder import dyadic_level, fits, level_step, position_tolerance, realign_step
from granplate.solver.schemes import implicit
from granplate.solver.state import C_LEVEL, N_COUNT, N_LEVELS
from granplate.verification.face_contacts import drop_scenario


@pytest.fixture(scope="module")
def cfg():
    """The config of a granule thrown at the rigid layer (dt_max = 1 us, dt_min = 1e-13 s, t_end = 1 ms)."""
    return build_model(drop_scenario(0.05, vx=1.0, vy=4.0, mu=0.3, t_end=1e-3, out=1e-6, gap=2e-4)).config


def deepest(cfg) -> int:
    """The deepest dyadic level whose step is not below dt_min."""
    return max(lv for lv in range(0, N_LEVELS, 4) if level_step(lv, cfg) >= cfg.dt_min)


def test_exact_dyadic_positions_keep_the_coarsest_tiling_level(cfg):
    """At 5 steps of level 8 (an odd multiple) the level is 8 from any coarser one; at
    4 steps of level 8 (one of level 4) it is 4; at the output time itself, any level."""
    h8 = level_step(8, cfg)
    assert dyadic_level(0, 5 * h8, cfg) == 8
    assert dyadic_level(1, 4 * h8, cfg) == 4
    assert dyadic_level(0, 0.0, cfg) == 0


def test_position_rounded_after_small_steps_never_goes_below_dt_min(cfg):
    """The collapse seen at t = 3.53e-4 s: 3 steps of 2^-24 us past an output, off by one
    rounding unit of t, fitted no level down to the ladder's end (1.8e-21 s, below the
    rounding of t, so t + h == t and the run spun). Now the level stays at or above
    dt_min and the odd step onto its grid moves the clock and lands on the grid."""
    target = (np.arange(1001) * cfg.out_dt)[353]
    t = target + 3 * level_step(96, cfg) * (1 + 1e-6 * 1.0156)  # t as the stalled run had it
    pos = t - target
    lv = dyadic_level(93, pos, cfg)
    assert level_step(lv, cfg) >= cfg.dt_min
    h = realign_step(lv, pos, cfg)
    assert 0.0 < h < level_step(lv, cfg) and t + h > t
    assert fits((t + h) - target, level_step(lv, cfg), position_tolerance(cfg))


def test_plan_always_moves_the_clock_and_lands_on_the_grid(cfg):
    """From 2000 seeded random positions in an interval late in the run (and every
    starting level), the implicit plan takes a step that moves t; its ladder steps are
    never below dt_min; after an odd step that does not land, the next one lands or
    is a ladder step of the same level (the position is back on its grid)."""
    rng = np.random.default_rng(7)
    t_out = 0.000353
    count = np.zeros(N_COUNT, np.int64)
    realigned = 0
    for _ in range(2000):
        pos = rng.uniform(0.0, cfg.out_dt) * rng.choice([1.0, 1e-3, 1e-6])
        count[C_LEVEL] = rng.integers(0, N_LEVELS)
        t = t_out + pos
        level, h, slot, land = implicit.plan(None, count, cfg, t - t_out, t_out + cfg.out_dt - t)
        assert level <= deepest(cfg) and (land or t + h > t)
        if slot == N_LEVELS and not land:
            t2 = t + h
            assert t2 < t_out + cfg.out_dt
            lv2, h2, slot2, land2 = implicit.plan(None, count, cfg, t2 - t_out, t_out + cfg.out_dt - t2)
            assert land2 or (slot2 < N_LEVELS and lv2 == level)
            realigned += 1
    assert realigned > 100
