"""The velocity-Verlet step's passes over the granules (docs/model.md sections 6.5, 6.6):
the first kick with the drift and the closing kick (solver.kicks), serially in chunks of
CHUNK granules or on every core in blocks (solver.blocks), each measuring what the checks
after the step need while its rows are in the core's caches: the largest move since the
contact list was made (the contact watch's screen) and the kinetic energies (the energy
check). The serial passes carry their sums from chunk to chunk in granule order, so they
give the bits of one pass over every granule; the blocks' sums are added in block order.
"""

from __future__ import annotations

from numba import prange

from granplate.jit import njit
from granplate.solver.blocks import (
    BLOCKS_PER_THREAD,
    S_KR,
    S_KX,
    S_MOVED,
    S_WDAMP,
    S_WLOAD,
    granule_block,
    work_sums,
)
from granplate.solver.contacts import largest_move as block_largest_move
from granplate.solver.dimension import kinetic_energies_part
from granplate.solver.kicks import divide_kick, kick, kick_drift

#: the state's leading columns that drift (x, y, theta in the plane; x, y, z in space),
#: each at the rate held N_DRIFT columns to its right; the columns from N_DRIFT on are
#: velocities and spins, which the kicks change.
N_DRIFT = 3
#: entries of Scratch.notes, what the serial step's kicks measured while each chunk of rows
#: was in the cache, for the loop's checks after the step: the largest squared move of a
#: granule since the contact list's reference [m^2] (NOTE_MOVED) and 1 where it is the
#: state's the loop watches next (NOTE_MOVES_READY); the kinetic energies KE_x, KE_y,
#: KE_z, KE_rot [J] (NOTE_KX to NOTE_KR) and 1 where they are the state's the loop checks
#: next (NOTE_KE_READY). The threaded step keeps these in its blocks' sums (solver.blocks).
NOTE_MOVED, NOTE_MOVES_READY, NOTE_KX, NOTE_KY, NOTE_KZ, NOTE_KR, NOTE_KE_READY = range(7)
N_NOTES = 7
#: granules per chunk of the serial kicks: a chunk's rows (72 bytes each in space) are
#: still in the core's caches when the measure after its kick reads them
CHUNK = 1024


@njit(parallel=True)
def kinetic_energy_blocks(y, g, spar):
    """The kinetic energies of the granules in the blocks of spar's rows
    (solver.blocks.granule_block: each thread's blocks dealt as its pair blocks), each block's into spar[k, S_KX:S_KR + 1], summed in block order: deterministic
    for a given thread count, the serial sums' to round-off."""
    nt = spar.shape[0] // BLOCKS_PER_THREAD
    for t in prange(nt):
        for s in range(BLOCKS_PER_THREAD):
            k, lo, hi = granule_block(spar, nt, t, s, y.shape[0])
            block_kinetic_energies(y, g, spar, k, lo, hi)
    return kinetic_sums(spar)


@njit(cache=True, inline="always")
def block_kinetic_energies(y, g, spar, k, lo, hi):
    """The kinetic energies of granules lo..hi-1 (block k) into spar[k, S_KX:S_KR + 1]."""
    kx, ky, kz, kr = kinetic_energies_part(y, g, lo, hi, (0.0, 0.0, 0.0, 0.0))
    spar[k, S_KX] = kx
    spar[k, S_KX + 1] = ky
    spar[k, S_KX + 2] = kz
    spar[k, S_KR] = kr


@njit(cache=True)
def kinetic_sums(spar):
    """(KE_x, KE_y, KE_z, KE_rot) [J]: the blocks' (spar[k, S_KX:S_KR + 1]) in block order."""
    nb = spar.shape[0]
    kx = 0.0
    ky = 0.0
    kz = 0.0
    kr = 0.0
    for k in range(nb):
        kx += spar[k, S_KX]
        ky += spar[k, S_KX + 1]
        kz += spar[k, S_KX + 2]
        kr += spar[k, S_KR]
    return kx, ky, kz, kr


@njit(parallel=True)
def first_kick_blocks(y0, y, acc, fdamp, fload, h, ypred, spar, predict, loads, damped, clear, yref, ndim):
    """solver.kicks.kick_drift from y0 into y over blocks of granules (each granule's update
    is the serial one's, bit for bit; the work sums per block into spar[k], S_WLOAD and
    S_WDAMP; fload and fdamp read only where `loads` and `damped`; acc's kicked columns
    zeroed as they are read where `clear`), each thread's blocks those of the pair pass's
    blocks (solver.blocks.granule_block); each block's largest squared move since the
    contact list's reference yref (its first ndim columns) [m^2] into spar[k, S_MOVED] while
    its rows are at hand (`largest_move`: the contact watch's screen). Returns (the load's work, the damping
    force's work) [J], summed in block order."""
    nt = spar.shape[0] // BLOCKS_PER_THREAD
    for t in prange(nt):
        for s in range(BLOCKS_PER_THREAD):
            k, lo, hi = granule_block(spar, nt, t, s, y.shape[0])
            spar[k, S_WLOAD], spar[k, S_WDAMP] = kick_drift(
                y0, y, acc, fdamp, fload, h, ypred, N_DRIFT, lo, hi, predict, loads, damped, clear
            )
            spar[k, S_MOVED] = block_largest_move(y, yref, lo, hi, ndim)
    return work_sums(spar)


@njit(cache=True)
def first_kick_serial(y0, y, acc, fdamp, fload, h, ypred, predict, loads, damped, clear, yref, ndim, notes):
    """solver.kicks.kick_drift of every granule, in chunks of CHUNK granules, each chunk's
    largest squared move since the contact list's reference yref (its first ndim columns)
    [m^2] measured while its rows are in the cache, the largest into notes[NOTE_MOVED] (the
    contact watch's screen, as `first_kick_blocks` measures it per block). The works are
    carried from chunk to chunk: bit for bit one call of kick_drift over every granule.
    Returns (the load's work, the damping force's work) [J]."""
    wl = 0.0
    wd = 0.0
    d2 = 0.0
    n = y.shape[0]
    for lo in range(0, n, CHUNK):
        hi = min(lo + CHUNK, n)
        wl, wd = kick_drift(y0, y, acc, fdamp, fload, h, ypred, N_DRIFT, lo, hi, predict, loads, damped, clear, wl, wd)
        d2 = max(d2, block_largest_move(y, yref, lo, hi, ndim))
    notes[NOTE_MOVED] = d2
    notes[NOTE_MOVES_READY] = 1.0  # (the positions move in this kick alone)
    return wl, wd


@njit(cache=True)
def closing_kick_serial(y, acc, fdamp, fload, hk, dy, loads, damped, g, energies, divide, n_move, notes):
    """solver.kicks.kick of every granule (where `divide`, solver.kicks.divide_kick), in
    chunks of CHUNK granules, and where `energies` the kinetic energies at the kicked state
    while each chunk's rows are in the cache, into notes[NOTE_KX:NOTE_KR + 1] (as
    `closing_kick_blocks` takes them per block; the step's check then reads them:
    `step_kinetic_energies`). The works and energies are carried from chunk to chunk: bit
    for bit the kick's and the energies' passes over every granule. Returns (the load's
    work, the damping force's work) [J]."""
    wl = 0.0
    wd = 0.0
    ke = (0.0, 0.0, 0.0, 0.0)
    n = y.shape[0]
    for lo in range(0, n, CHUNK):
        hi = min(lo + CHUNK, n)
        if divide:
            wl, wd = divide_kick(
                y, acc, fdamp, fload, hk, dy, N_DRIFT, n_move, g.mass, g.inertia, lo, hi, loads, damped, wl, wd
            )
        else:
            wl, wd = kick(y, acc, fdamp, fload, hk, dy, N_DRIFT, lo, hi, loads, damped, wl, wd)
        if energies:
            ke = kinetic_energies_part(y, g, lo, hi, ke)
    if energies:
        notes[NOTE_KX], notes[NOTE_KY], notes[NOTE_KZ], notes[NOTE_KR] = ke
        notes[NOTE_KE_READY] = 1.0
    return wl, wd


@njit(parallel=True)
def closing_kick_blocks(y, acc, fdamp, fload, hk, dy, n_drift, spar, loads, damped, g, energies, divide, n_move):
    """solver.kicks.kick over blocks of granules (as `first_kick_blocks`; where `divide`,
    solver.kicks.divide_kick from the pass's forces, n_move velocity columns by the mass),
    and where `energies` each block's kinetic energies at the kicked state while its rows
    are at hand (`block_kinetic_energies`: a pass over the granules fewer). Returns (the
    load's work, the damping force's work) [J], summed in block order."""
    nt = spar.shape[0] // BLOCKS_PER_THREAD
    for t in prange(nt):
        for s in range(BLOCKS_PER_THREAD):
            k, lo, hi = granule_block(spar, nt, t, s, y.shape[0])
            if divide:
                spar[k, S_WLOAD], spar[k, S_WDAMP] = divide_kick(
                    y, acc, fdamp, fload, hk, dy, n_drift, n_move, g.mass, g.inertia, lo, hi, loads, damped
                )
            else:
                spar[k, S_WLOAD], spar[k, S_WDAMP] = kick(y, acc, fdamp, fload, hk, dy, n_drift, lo, hi, loads, damped)
            if energies:
                block_kinetic_energies(y, g, spar, k, lo, hi)
    return work_sums(spar)
