"""The ladder of time steps h_l = dt_max 2^(-l/4): G(h) and a scheme's per-step matrices
are computed once per level and kept, so changing the step never refactors the plate.
"""

from __future__ import annotations

import math

from granplate.jit import njit

from granplate.solver.state import LEVEL_RATIO, N_LEVELS


@njit(cache=True)
def level_step(level, cfg):
    """Step of ladder level l: dt_max 2^(-l/4) [s]."""
    return cfg.dt_max * LEVEL_RATIO**level


@njit(entry=True, cache=True)
def level_for(h, cfg):
    """Smallest ladder level whose step does not exceed h."""
    if h >= cfg.dt_max:
        return 0
    lv = int(math.ceil(math.log(h / cfg.dt_max) / math.log(LEVEL_RATIO) - 1e-9))
    return min(max(lv, 0), N_LEVELS - 1)


#: the time since the last output, t - t_out, is known to FIT_ULPS rounding units of the
#: run's end time (it is the difference of two times near t_end and the steps' sum):
#: a step "fits" it when it is a whole number of steps to within this or 1e-6 steps.
FIT_ULPS = 64.0
#: the rounding unit of float64 relative to 1 (machine epsilon).
EPS = 2.0**-52


@njit(cache=True)
def position_tolerance(cfg):
    """How well the time since the last output is known [s]: FIT_ULPS rounding units
    of the end time."""
    return FIT_ULPS * EPS * max(cfg.t_end, cfg.out_dt)


@njit(cache=True)
def fits(pos, h, tol):
    """Whether `pos` [s] is a whole number of steps h [s], to 1e-6 steps or tol [s]."""
    r = pos / h
    return abs(r - round(r)) <= max(1e-6, tol / h)


@njit(cache=True)
def dyadic_round(level, cfg):
    """The dyadic level (every fourth) whose step is the largest not above level
    `level`'s, or the deepest dyadic level whose step is not below dt_min when that
    one's is larger."""
    lv = level + (-level) % 4
    while lv >= 4 and level_step(lv, cfg) < cfg.dt_min:
        lv -= 4
    return lv


@njit(cache=True)
def dyadic_level(level, pos, cfg):
    """The level to use at `pos` [s] into the output interval when the steps must tile
    it: only every fourth level, h = dt_max / 2^k (dt_max = out_dt / 2^j, see
    model.arrays.implicit_step_max), and a step starts only where it fits a whole
    number of times since the last output, so the steps land on it without a step of
    odd size (whose matrices would have to be recomputed). Never a step below dt_min:
    where none down to it fits (pos off the dyadic grid), the level rounded up from
    `level`, and `realign_step` brings pos back onto its grid."""
    lv = dyadic_round(level, cfg)
    tol = position_tolerance(cfg)
    k = lv
    while k + 4 < N_LEVELS and level_step(k + 4, cfg) >= cfg.dt_min:
        if fits(pos, level_step(k, cfg), tol):
            return k
        k += 4
    if fits(pos, level_step(k, cfg), tol):
        return k
    return lv


@njit(cache=True)
def realign_step(level, pos, cfg):
    """The odd step [s] that brings `pos` [s] onto the next whole multiple of level
    `level`'s step, or 0 when pos is on it (see `dyadic_level`)."""
    h = level_step(level, cfg)
    if fits(pos, h, position_tolerance(cfg)):
        return 0.0
    return h * math.ceil(pos / h) - pos


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
