"""The velocity-Verlet passes on every core (`solver.threads`, docs/model.md section 6.6):
the contacts and the granules cut into `nb` fixed blocks, each block's sums kept apart
and then added in block order.

Each block k takes the contiguous range `block_range(k, nb, n)` of the pair list (or of
the granules), whatever thread runs it. A block of pairs owns a range of granules
(`owned_rows`): it writes their forces straight into the pass's arrays, and the forces on
the few granules past its own (its pairs' partners) into the buffer of the thread that
runs it, `fpar[t]` (thread t of T runs blocks t, t + T, ...: `thread_pairs`); each
granule then takes the buffers' rows in a fixed order (`gather_forces`). No two blocks
write the same number, so a run is bitwise the same for a given thread count however the
threads are scheduled, and it differs from the serial loop (`solver.threads = 1`,
solver.granular3d.normal_forces) only by the order in which each granule's contact forces
and the energy sums are added: round-off. The contact laws, the overlaps and the largest
overlap (its first occurrence in pair order, as the serial pass finds it) are the same
numbers. The wall contacts, few beside the pairs, run serially after the blocks, in the
serial order, because a wall's load and a driven wall's force are shared sums.

Numba's parallel loops (`prange`) run the blocks; numba's thread count is set by the driver
(`numba.set_num_threads`) for the run. The parallel functions are not cached on their own:
numba's cache of a parallel function, written by two processes compiling it at once (a
test suite's workers, a study's), can pair pieces of the two compilations and crash the
next process that loads it. Their code is compiled into the cached loop that calls them.
"""

from __future__ import annotations

import os

# OpenMP's idle threads spin about 30,000 turns (tens of microseconds: the gap between two
# passes of a step) before they sleep, not GNU OpenMP's default 300,000: a thread spinning
# on holds a core that the step's serial part, or another process on a shared machine,
# needs. Read once, when the threading layer loads with these kernels; a user's own
# GOMP_SPINCOUNT or OMP_WAIT_POLICY is kept. Measured in docs/benchmarks.md.
os.environ.setdefault("GOMP_SPINCOUNT", "30000")

from numba import prange  # noqa: E402
from granplate.jit import njit  # noqa: E402

from granplate.solver.drives import begin_pass
from granplate.solver.clearing import clear_rows
from granplate.solver.granular import ForceSums, commit_history, commit_rows
from granplate.solver.granular3d import BUF_DAMP, N_BUF, VX, WX, pair_forces, shock_loads, wall_forces
from granplate.solver.mindlin_space import wall_mindlin

#: columns of a thread's buffer row fpar[t, i], for a granule i outside the own rows
#: (`owned_rows`) of the block that wrote it: the damping part of the forces on it
#: (x, y, z) [N], the normal forces (x, y, z) [N] and, under Mindlin's law, the tangential
#: forces' torques (x, y, z) [N m] (their forces are in F_X's columns): solver.granular3d's
#: buffer columns.
F_DX, F_X, F_T = BUF_DAMP, VX, WX
N_FPAR = N_BUF
#: columns of a block's sums spar[k]: viscous power [W], stored energy [J], plastic work
#: [J], the largest overlap / smaller radius [-], its granule and its partner (as floats),
#: the kicks' load and damping work [J], Mindlin's springs' energy and losses [J], (row
#: 0: in all) how many granules the last force pass gave a damping force (`gather_forces`),
#: (row k: block k's) the range [S_TLO, S_THI) of the buffer rows it wrote (as floats), and
#: (row 0, set by the scheme before a pass) 1 where the pass's load rows (S_ZERO_LOADS), its
#: damping rows (S_ZERO_DAMP) are all zero already, so the blocks leave them uncleared; a
#: block of granules' kinetic energies KE_x, KE_y, KE_z, KE_rot [J] (S_KX to S_KR); (row 0,
#: set by the scheme) 1 where the passes over granules deal their blocks out to the threads
#: in turn as the pairs' are (S_DEALT: `granule_block`).
S_VISC, S_EPOT, S_PLASTIC, S_OVL, S_OVL_I, S_OVL_J, S_WLOAD, S_WDAMP, S_ET, S_LOST, S_DAMPED = range(11)
S_TLO, S_THI, S_ZERO_LOADS, S_ZERO_DAMP = range(11, 15)
S_KX, S_KY, S_KZ, S_KR = range(15, 19)
S_DEALT = 19
#: (row k) the pairs [S_PLO, S_PHI) of block k of the last pass (as floats: `pair_blocks`),
#: how many of them touched (S_TOUCH), and the end of its next range (S_EDGE, worked out
#: before the old ranges are let go)
S_PLO, S_PHI, S_TOUCH, S_EDGE = 20, 21, 22, 23
#: (row 0, set by the scheme) 1 where the accelerations' rows are zero from the velocity
#: columns on already (the step's first kick cleared them as it read them:
#: solver.kicks.kick_drift's `clear`), so the pair blocks leave them uncleared (S_ZERO_ACC);
#: 1 where the blocks' kinetic energies S_KX..S_KR are those of the state the loop checks
#: next (the closing kick computed them: S_KE_READY)
S_ZERO_ACC, S_KE_READY = 24, 25
#: (row k, the first kick) the largest squared move of block k's granules since the contact
#: list's reference [m^2] (S_MOVED); (row 0) 1 where those are the state's the loop watches
#: next (S_MOVES_READY)
S_MOVED, S_MOVES_READY = 26, 27
#: (row 0, set by the scheme) 1 where the pass leaves acc's forces and torques [N, N m]
#: undivided: the closing kick makes them accelerations (solver.kicks.divide_kick); (row k)
#: how many of block k's pairs gave their granules a damping force (S_PUSHED)
S_UNDIVIDED, S_PUSHED = 28, 29
N_SPAR = 30

#: what a pair in touch costs a pass beside one apart, less one (the weight the blocks are
#: balanced by: `pair_blocks`; measured on the 10,192-sphere packing: under Mindlin's law a
#: block's time grows by about four pairs apart per pair in touch; the normal pass gave
#: the same times with 1, 2, 4 or 8, all about 7% faster than blocks of equal pair counts)
TOUCH_WEIGHT = 4.0


#: blocks of pairs per thread under a law whose contacts in touch cost much more than those
#: apart (Mindlin's), dealt out in turn (thread t of T runs blocks t, t + T, ...): the
#: contacts in touch gather where a wave has reached, and granules are often numbered along
#: the direction it travels, so each thread then takes slabs across the packing rather than
#: one half of it (docs/benchmarks.md). The normal pass runs one block per thread (balanced
#: too: `pair_forces_blocks`).
BLOCKS_PER_THREAD = 4


def block_count(threads: int) -> int:
    """The blocks (rows of the sums spar) of a run on `threads` threads: none for one thread
    (the serial passes), else BLOCKS_PER_THREAD per thread; the buffers fpar are one per
    thread."""
    return BLOCKS_PER_THREAD * threads if threads > 1 else 0


@njit(cache=True)
def block_range(k, nb, n):
    """The items [lo, hi) of block k of nb over n items (contiguous, sizes within one)."""
    return (k * n) // nb, ((k + 1) * n) // nb


@njit(cache=True, inline="always")
def granule_block(spar, nt, t, s, n):
    """Block number s (of nb / nt) of thread t's share of spar's nb blocks of n granules
    over nt threads (nt dividing nb): (k, lo, hi), block k and its granules [lo, hi)
    (`block_range`), the blocks dealt out in turn (k = t + s nt) where spar[0, S_DEALT]
    says the pairs' are (Mindlin's law: `thread_pairs`), else in one run (k = t nb / nt +
    s, as the pairs' one block per thread). A pass over the granules that takes its blocks
    so finds each granule's rows where the pair pass that wrote them ran: in the same
    core's cache."""
    nb = spar.shape[0]
    k = t + s * nt if spar[0, S_DEALT] != 0.0 else t * (nb // nt) + s
    lo, hi = block_range(k, nb, n)
    return k, lo, hi


@njit(cache=True)
def pair_blocks(spar, nb, n_p, balanced):
    """The pairs [spar[k, S_PLO], spar[k, S_PHI]) of each block k of nb over the n_p listed
    pairs, before a pass: `block_range`'s equal shares, or (`balanced`, and the last pass
    ran over as many pairs) shares of equal cost by the last pass's counts of pairs in
    touch (S_TOUCH), each block's pairs taken as evenly spread over it: a pair apart counts
    one, a pair in touch 1 + TOUCH_WEIGHT. The counts are the same numbers in every run of a
    given thread count, so the blocks are too."""
    same = balanced and nb > 0 and int(spar[nb - 1, S_PHI]) == n_p and int(spar[0, S_PLO]) == 0
    if not same:
        for k in range(nb):
            lo, hi = block_range(k, nb, n_p)
            spar[k, S_PLO] = lo
            spar[k, S_PHI] = hi
        return
    total = 0.0
    for k in range(nb):
        total += (spar[k, S_PHI] - spar[k, S_PLO]) + TOUCH_WEIGHT * spar[k, S_TOUCH]
    k = 0
    below = 0.0  # the cost of the old blocks before block k
    start = 0
    for j in range(1, nb):
        target = total * j / nb
        while k < nb - 1 and below + (spar[k, S_PHI] - spar[k, S_PLO]) + TOUCH_WEIGHT * spar[k, S_TOUCH] <= target:
            below += (spar[k, S_PHI] - spar[k, S_PLO]) + TOUCH_WEIGHT * spar[k, S_TOUCH]
            k += 1
        lo, hi = spar[k, S_PLO], spar[k, S_PHI]
        cost = (hi - lo) + TOUCH_WEIGHT * spar[k, S_TOUCH]
        cut = lo + (hi - lo) * min(max((target - below) / cost, 0.0), 1.0) if cost > 0.0 else lo
        edge = min(max(int(cut), start), n_p)
        spar[j - 1, S_EDGE] = edge
        start = edge
    prev = 0
    for j in range(nb):
        edge = int(spar[j, S_EDGE]) if j < nb - 1 else n_p
        spar[j, S_PLO] = prev
        spar[j, S_PHI] = edge
        prev = edge


@njit(cache=True)
def owner_start(k, nb, pair_ij, ng, spar):
    """The first granule block k of nb owns (`owned_rows`): 0 for the first block, ng past
    the last; else the first granule of its pairs (from spar[k, S_PLO]: `pair_blocks`), at
    least any earlier block's (so the blocks' rows follow one another whatever the pair
    order; sorted pairs make them the granules each block's pairs start from)."""
    if k <= 0:
        return 0
    if k >= nb:
        return ng
    n_p = pair_ij.shape[0]
    a = 0
    for q in range(1, k + 1):
        lo = int(spar[q, S_PLO])
        a = max(a, pair_ij[lo, 0] if lo < n_p else ng)
    return min(a, ng)


@njit(cache=True)
def owned_rows(k, nb, pair_ij, ng, spar):
    """The granules [lo, hi) whose rows block k of nb writes straight into the
    accelerations: no other block writes them there (their forces from other blocks' pairs
    wait in the buffers of the threads that run those blocks, `gather_forces`)."""
    return owner_start(k, nb, pair_ij, ng, spar), owner_start(k + 1, nb, pair_ij, ng, spar)


@njit(cache=True, inline="always")
def block_pairs(yv, yn, h, g, cfg, k, nb, buf, spar, acc, fdamp, fload, tangential, commit_t):
    """Block k of nb's pairs (`block_range` of the pair list; solver.granular3d.pair_forces):
    its own granules' rows cleared and their forces put straight into acc and fdamp, the
    other granules' into the buffer buf; its sums into spar[k]. Returns (the springs' energy
    [J], their losses [J], and the buffer rows [lo, hi) it wrote)."""
    ng = acc.shape[0]
    own_lo, own_hi = owned_rows(k, nb, g.pair_ij, ng, spar)
    clear_rows(  # (its buffer is zero already: `gather_rows` zeroes what it reads)
        acc,
        fdamp,
        fload,
        own_lo,
        own_hi,
        spar[0, S_ZERO_ACC] == 0.0,
        spar[0, S_ZERO_DAMP] == 0.0,
        spar[0, S_ZERO_LOADS] == 0.0,
    )
    lo, hi = int(spar[k, S_PLO]), int(spar[k, S_PHI])
    pv, ep, wp, ovl, ovl_i, ovl_j, e_t, lost, t_lo, t_hi, n_touch, n_damp = pair_forces(
        yv, yn, h, g, cfg, lo, hi, acc, fdamp, buf, own_lo, own_hi, tangential, commit_t
    )
    spar[k, S_TOUCH] = n_touch
    spar[k, S_PUSHED] = n_damp
    spar[k, S_VISC] = pv
    spar[k, S_EPOT] = ep
    spar[k, S_PLASTIC] = wp
    spar[k, S_OVL] = ovl
    spar[k, S_OVL_I] = ovl_i
    spar[k, S_OVL_J] = ovl_j
    return e_t, lost, t_lo, t_hi


@njit(cache=True, inline="always")
def thread_pairs(yv, yn, h, g, cfg, t, nb, fpar, spar, acc, fdamp, fload, tangential, commit_t):
    """The share of thread t of T (T = the buffers fpar): blocks t, t + T, ... of nb in
    turn (`block_pairs`), their buffered forces in fpar[t] and each block k's rows' range
    in spar[k, S_TLO:S_THI + 1] (a thread's blocks lie apart: the rows between them are
    not its to gather); under Mindlin's law (`tangential`) each block's springs' energy and
    losses into spar[k, S_ET], spar[k, S_LOST]."""
    for k in range(t, nb, fpar.shape[0]):
        e_t, lost, b_lo, b_hi = block_pairs(
            yv, yn, h, g, cfg, k, nb, fpar[t], spar, acc, fdamp, fload, tangential, commit_t
        )
        if tangential:
            spar[k, S_ET] = e_t
            spar[k, S_LOST] = lost
        spar[k, S_TLO] = b_lo
        spar[k, S_THI] = b_hi


@njit(parallel=True)
def pair_forces_blocks(y, g, cfg, fpar, spar, acc, fdamp, fload, commit_t):
    """The normal forces of every listed granule pair at state y (space), one block per
    thread (`thread_pairs`), the blocks of equal cost by the last pass's counts of pairs in
    touch (`pair_blocks`: a wave puts them in one part of the packing): block k clears its own granules' rows of acc, fdamp and fload
    and puts its pairs' forces on them there, on other granules into its thread's buffer
    fpar[k] (one block per thread: k = t); its viscous power, stored energy, plastic work
    and largest overlap into spar[k]; each pair's overlap into HIST_END, committed at
    commit_t [s] (as solver.granular3d.normal_forces)."""
    nt = fpar.shape[0]
    pair_blocks(spar, nt, g.pair_ij.shape[0], True)
    for t in prange(nt):
        thread_pairs(y, y, 0.0, g, cfg, t, nt, fpar, spar, acc, fdamp, fload, False, commit_t)


@njit(cache=True)
def gather_rows(fpar, spar, n_pair_blocks, acc, fdamp, mass, inertia, lo, hi, count=True):
    """`gather_forces` for granules lo..hi-1: the buffered forces of each thread's buffer
    fpar[t], in the rows [spar[k, S_TLO], spar[k, S_THI]) its blocks k (of n_pair_blocks,
    dealt out as `thread_pairs` does) wrote that meet them, added in buffer order (and
    zeroed, ready for the next pass: a row two of its blocks wrote is added once), then the
    division (none where spar[0, S_UNDIVIDED]: the closing kick divides); returns how many
    have a damping force (0 without `count`: the pass gave none, `may_have_damped`)."""
    nt = fpar.shape[0]
    for t in range(nt):
        for k in range(t, n_pair_blocks, nt):
            for i in range(max(lo, int(spar[k, S_TLO])), min(hi, int(spar[k, S_THI]))):
                for c in range(3):
                    acc[i, VX + c] += fpar[t, i, F_X + c]
                    fdamp[i, VX + c] += fpar[t, i, F_DX + c]
                    acc[i, WX + c] += fpar[t, i, F_T + c]
                    fpar[t, i, F_X + c] = 0.0
                    fpar[t, i, F_DX + c] = 0.0
                    fpar[t, i, F_T + c] = 0.0
    if spar[0, S_UNDIVIDED] == 0.0:
        for i in range(lo, hi):
            for c in range(3):
                acc[i, VX + c] /= mass[i]
                acc[i, WX + c] /= inertia[i]
    n_damped = 0
    if count:
        for i in range(lo, hi):
            for c in range(3):
                if fdamp[i, VX + c] != 0.0 or fdamp[i, WX + c] != 0.0:
                    n_damped += 1
                    break
    return n_damped


@njit(cache=True)
def may_have_damped(g, fdamp, spar, n_pair_blocks) -> bool:
    """Whether the pass may have given a granule a damping force: one of its pair blocks
    did (spar[k, S_PUSHED]), or a wall contact's granule has one (the walls add theirs
    serially); else every row of fdamp is zero (cleared, or known zero: S_ZERO_DAMP) and
    the gather need not read them."""
    for k in range(n_pair_blocks):
        if spar[k, S_PUSHED] != 0.0:
            return True
    for w in range(g.wall_i.shape[0]):
        i = g.wall_i[w]
        for c in range(3, fdamp.shape[1]):
            if fdamp[i, c] != 0.0:
                return True
    return False


@njit(parallel=True)
def gather_forces(fpar, acc, fdamp, mass, inertia, spar, n_pair_blocks, count=True):
    """Each granule's forces from the threads' buffers (the pass's n_pair_blocks blocks of
    pairs wrote them: `gather_rows`), added in buffer order to what acc
    and fdamp hold (its own block's pairs', the shock's and the walls'), then acc's forces and
    torques made accelerations: acc[:, 3:6] /= mass, acc[:, 6:9] /= inertia (space's
    velocity and spin columns; left to the closing kick where spar[0, S_UNDIVIDED]). The granules in blocks, each thread's those of its pair
    blocks (`granule_block`); how many of them have a damping force (fdamp
    not zero; where `count`, else none) into spar[0, S_DAMPED]."""
    nb = spar.shape[0]
    nt = fpar.shape[0]
    for t in prange(nt):
        for s in range(nb // nt):
            k, lo, hi = granule_block(spar, nt, t, s, acc.shape[0])
            spar[k, S_DAMPED] = gather_rows(fpar, spar, n_pair_blocks, acc, fdamp, mass, inertia, lo, hi, count)
    n = 0.0
    for k in range(nb):
        n += spar[k, S_DAMPED]
    spar[0, S_DAMPED] = n


@njit(cache=True)
def normal_forces_blocks(t, y, g, cfg, acc, fdamp, fload, fpar, spar, commit_t):
    """solver.granular3d.normal_forces on every core: the pairs in blocks
    (`pair_forces_blocks`, which clear the rows too), the shock (serial), the walls in the
    serial order, then the blocks' forces gathered in block order with the division by the
    inertias (`gather_forces`). Returns the ForceSums (sums over the blocks in block order;
    the largest overlap's first occurrence in the serial order)."""
    begin_pass(t, g)
    pair_forces_blocks(y, g, cfg, fpar, spar, acc, fdamp, fload, commit_t)
    p_shock = 0.0
    if not cfg.load_on_plate:
        p_shock = shock_loads(t, y, g, cfg, acc, fload)
    p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j = block_sums(spar, fpar.shape[0])
    p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j = wall_forces(
        y, g, cfg, acc, fdamp, p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j
    )
    n_pb = fpar.shape[0]
    gather_forces(fpar, acc, fdamp, g.mass, g.inertia, spar, n_pb, may_have_damped(g, fdamp, spar, n_pb))
    return ForceSums(p_shock, p_visc, 0.0, e_pot, 0.0, ovl, ovl_i, ovl_j, 0.0, w_plastic, 0.0, 0.0)


@njit(parallel=True)
def pair_mindlin_blocks(yv, yn, h, g, cfg, fpar, spar, acc, fdamp, fload, commit_t):
    """`pair_forces_blocks` with Mindlin's law in it (solver.granular3d.pair_forces with its
    tangential step: forces, damping parts and torques), in BLOCKS_PER_THREAD blocks per
    thread dealt out in turn (every row of spar a block: `thread_pairs`); the springs'
    energy and losses into S_ET, S_LOST. Each contact's tangential step reads and writes its
    own history row alone."""
    pair_blocks(spar, spar.shape[0], g.pair_ij.shape[0], True)
    for t in prange(fpar.shape[0]):
        thread_pairs(yv, yn, h, g, cfg, t, spar.shape[0], fpar, spar, acc, fdamp, fload, True, commit_t)


@njit(cache=True)
def block_sums(spar, nb):
    """The sums of the pass's nb blocks (spar's first rows) in block order: (viscous power
    [W], stored energy [J], plastic work [J], the largest overlap and its pair (its first
    occurrence in block order))."""
    p_visc = 0.0
    e_pot = 0.0
    w_plastic = 0.0
    ovl = 0.0
    ovl_i = -1
    ovl_j = -1
    for k in range(nb):
        p_visc += spar[k, S_VISC]
        e_pot += spar[k, S_EPOT]
        w_plastic += spar[k, S_PLASTIC]
        if spar[k, S_OVL] > ovl:
            ovl = spar[k, S_OVL]
            ovl_i = int(spar[k, S_OVL_I])
            ovl_j = int(spar[k, S_OVL_J])
    return p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j


@njit(cache=True)
def mindlin_forces_blocks(t, yv, yn, h, g, cfg, acc, fdamp, fload, fpar, spar, commit_t):
    """solver.mindlin_space.normal_mindlin_forces on every core: the pairs with their
    Mindlin forces in blocks (`pair_mindlin_blocks`, which clear the rows too), the shock
    (serial), the walls' normal forces in the serial order, the blocks' forces and torques
    gathered in block order with the division by the inertias (`gather_forces`), then the
    walls' Mindlin forces. Returns (the ForceSums, the springs' energy [J], their losses [J]), each
    sum over the blocks in block order."""
    begin_pass(t, g)
    pair_mindlin_blocks(yv, yn, h, g, cfg, fpar, spar, acc, fdamp, fload, commit_t)
    p_shock = 0.0
    if not cfg.load_on_plate:
        p_shock = shock_loads(t, yn, g, cfg, acc, fload)
    p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j = block_sums(spar, spar.shape[0])
    e_t = 0.0
    lost = 0.0
    for k in range(spar.shape[0]):
        e_t += spar[k, S_ET]
        lost += spar[k, S_LOST]
    p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j = wall_forces(
        yn, g, cfg, acc, fdamp, p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j
    )
    n_pb = spar.shape[0]
    gather_forces(fpar, acc, fdamp, g.mass, g.inertia, spar, n_pb, may_have_damped(g, fdamp, spar, n_pb))
    e_w, lost_w = wall_mindlin(yv, yn, h, g, cfg, acc)
    sums = ForceSums(p_shock, p_visc, 0.0, e_pot, 0.0, ovl, ovl_i, ovl_j, 0.0, w_plastic, 0.0, 0.0)
    return sums, e_t + e_w, lost + lost_w


@njit(cache=True)
def work_sums(spar):
    """(the load's work, the damping force's work) [J] of the blocks, in block order."""
    w_load = 0.0
    w_damp = 0.0
    for k in range(spar.shape[0]):
        w_load += spar[k, S_WLOAD]
        w_damp += spar[k, S_WDAMP]
    return w_load, w_damp


@njit(parallel=True)
def copy_rows(dst, src):
    """dst[:] = src, granule by granule on every core."""
    for i in prange(src.shape[0]):
        for c in range(src.shape[1]):
            dst[i, c] = src[i, c]


@njit(parallel=True)
def accept_rows(y, k1, ynew, kend):
    """The accepted step's state and derivatives (solver.loop.accept_granular's copies:
    y = ynew, k1 = kend), granule by granule on every core. (The derivatives of the step
    before, k0, serve the implicit scheme's error alone, which runs on one thread.)"""
    for i in prange(y.shape[0]):
        for c in range(y.shape[1]):
            y[i, c] = ynew[i, c]
            k1[i, c] = kend[i, c]


@njit(parallel=True)
def commit_pair_histories(t, hist, coef, nb):
    """solver.granular.commit_history of the pairs on every core, in nb blocks of rows (one
    per thread, Config.threads: numba's get_num_threads here would keep the loop from its
    disk cache; each row on its own: the same numbers)."""
    for k in prange(nb):
        lo, hi = block_range(k, nb, hist.shape[0])
        commit_rows(t, hist, coef, lo, hi)


@njit(cache=True)
def commit_histories_blocks(t, g, nb):
    """solver.granular.commit_histories with the pairs on every core, in nb blocks."""
    commit_pair_histories(t, g.pair_hist, g.pair_coef, nb)
    commit_history(t, g.wall_hist, g.wall_coef)
    commit_history(t, g.pc_hist, g.pc_coef)
