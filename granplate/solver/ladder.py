"""The ladder of time steps h_l = dt_max 2^(-l/4): G(h) and a scheme's per-step matrices
are computed once per level and kept, so changing the step never refactors the plate.
"""
from __future__ import annotations

import math

from numba import njit

from granplate.solver.state import LEVEL_RATIO, N_LEVELS


@njit(cache=True)
def level_step(level, cfg):
    """Step of ladder level l: dt_max 2^(-l/4) [s]."""
    return cfg.dt_max * LEVEL_RATIO**level


@njit(cache=True)
def level_for(h, cfg):
    """Smallest ladder level whose step does not exceed h."""
    if h >= cfg.dt_max:
        return 0
    lv = int(math.ceil(math.log(h / cfg.dt_max) / math.log(LEVEL_RATIO) - 1e-9))
    return min(max(lv, 0), N_LEVELS - 1)


@njit(cache=True)
def dyadic_level(level, pos, cfg):
    """The level to use at `pos` [s] into the output interval when the steps must tile
    it: only every fourth level, h = dt_max / 2^k (dt_max = out_dt / 2^j, see
    model.arrays.implicit_step_max), and a step starts only where it fits a whole
    number of times since the last output, so the steps land on it without a step of
    odd size (whose matrices would have to be recomputed)."""
    lv = level + (-level) % 4
    while lv + 4 < N_LEVELS:
        r = pos / level_step(lv, cfg)
        if abs(r - round(r)) <= 1e-6:
            break
        lv += 4
    return lv


@njit(cache=True)
def step_to_output(level, rem, on_ladder_landing, cfg):
    """The step from level `level` when `rem` [s] is left to the next output time.

    Returns (h, slot, land): the ladder step (slot = level), or, near the output, the
    remainder (land) or half of it (slot N_LEVELS: an odd step). With
    on_ladder_landing, a remainder equal to the ladder step is taken on the ladder.
    """
    h_lvl = level_step(level, cfg)
    if on_ladder_landing and abs(rem - h_lvl) <= 1e-9 * h_lvl:
        return h_lvl, level, True
    if rem <= h_lvl * (1.0 + 1e-9):
        return rem, N_LEVELS, True
    if rem < 2.0 * h_lvl:
        return 0.5 * rem, N_LEVELS, False
    return h_lvl, level, False
