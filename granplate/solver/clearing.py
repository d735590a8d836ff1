"""What a force pass clears before it writes: the granules' rows of its arrays, and each
contact's overlap of the pass (the velocity-Verlet passes of both dimensions, serial and in
blocks)."""

from __future__ import annotations

from granplate.jit import njit
from granplate.model.inputs import HIST_END


@njit(cache=True)
def clear_rows(acc, fdamp, fload, lo, hi, forces=True, damp=True, loads=True):
    """A force pass's clearing of granules lo..hi-1: their rows of acc, fdamp and fload from
    the velocity columns on (N_DRIFT, 3 in both dimensions) made zero where `forces`,
    `damp` and `loads` (else the caller knows them all zero already: the first kick
    cleared acc, solver.kicks.kick_drift; the last pass into fdamp or fload left it so,
    solver.schemes.verlet.note_quiet)."""
    if forces:
        for i in range(lo, hi):
            for c in range(3, acc.shape[1]):
                acc[i, c] = 0.0
    if damp:
        for i in range(lo, hi):
            for c in range(3, fdamp.shape[1]):
                fdamp[i, c] = 0.0
    if loads:
        for i in range(lo, hi):
            for c in range(3, fload.shape[1]):
                fload[i, c] = 0.0


@njit(cache=True, inline="always")
def clear_overlap(hist, k):
    """Contact k's overlap of this pass (HIST_END) made 0 before the pass finds it, written
    only where it is not 0 already: a contact out of touch leaves its history row unwritten,
    sparing its cache line the write back to memory (a million-granule packing's pairs are
    mostly out of touch)."""
    if hist[k, HIST_END] != 0.0:
        hist[k, HIST_END] = 0.0
