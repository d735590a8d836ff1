"""The contact watch after every accepted step (docs/model.md section 1.3): how far each
granule has moved since the contact list was built (past cfg.rebuild_move the chunk ends
and the driver rebuilds the list), the largest overlap of every contact against the
smaller radius (the step's largest one, found by granular_rhs; past cfg.overlap_stop
the run stops), and granules without a plate contact near the plate's face: within
cfg.face_skin R of it the chunk ends and the driver gives them a patch contact
(docs/model.md section 3.5); one that reaches the face without a contact stops the run.
"""

from __future__ import annotations

from numba import prange

from granplate.jit import njit

from granplate.physics.contact import plate_overlap
from granplate.solver.blocks import block_range
from granplate.solver.state import (
    ERR_CONTACT,
    ERR_ITER,
    ERR_JUMP,
    ERR_N,
    ERR_OVERLAP,
    ERR_PLATE_REACH,
    ERR_RESID,
    ERR_T,
    ERR_VT,
    NEW_PLATE,
    OK,
    PARTNER_PLATE,
    REBUILD,
)


@njit(cache=True)
def note_overlap(i, partner, rel, ovl, ovl_with):
    """Keep the largest relative overlap `rel` of granule i and its partner."""
    if rel > ovl[i]:
        ovl[i] = rel
        ovl_with[i] = partner


@njit(cache=True)
def stop(status, t, err, i, partner, value, rel):
    """Fill the failure record: granule i, its partner, the overlap or distance [m] and
    its ratio to the smaller radius; return `status`."""
    err[ERR_T] = t
    err[ERR_CONTACT] = i
    err[ERR_ITER] = partner
    err[ERR_N] = value
    err[ERR_RESID] = rel
    err[ERR_VT] = 0.0
    return status


@njit(cache=True)
def plate_face(u):
    """The x of the plate's face for the reach test [m], relative to its undeformed x0:
    the largest displacement of a contact point, never below 0 (no false alarms when the
    plate moves away)."""
    dmax = 0.0
    for k in range(u.shape[0] // 2):
        dmax = max(dmax, u[2 * k])
    return dmax


@njit(cache=True, inline="always")
def near_plate(i, y, plate_free, plate_ylo, plate_yhi) -> bool:
    """Whether granule i, without a plate contact, lies within the plate's span
    plate_ylo < y < plate_yhi [m]."""
    return plate_free[i] != 0 and plate_ylo < y[i, 1] < plate_yhi


@njit(cache=True, inline="always")
def moved_squared(i, y, yref, ndim) -> float:
    """The square of how far granule i has moved since the contact list was built (its
    position in yref, the first ndim columns) [m^2]."""
    d2 = 0.0
    for c in range(ndim):
        dc = y[i, c] - yref[i, c]
        d2 += dc * dc
    return d2


@njit(cache=True, inline="always")
def largest_move(y, yref, lo, hi, ndim) -> float:
    """The largest `moved_squared` of granules lo..hi-1 [m^2] (0 for none)."""
    d2 = 0.0
    for i in range(lo, hi):
        d2 = max(d2, moved_squared(i, y, yref, ndim))
    return d2


@njit(cache=True)
def granules_quiet(
    lo, hi, y, radius, plate_free, yref, face, plate_x0, plate_ylo, plate_yhi, rebuild_move, face_skin, ndim
):
    """Whether granules lo..hi-1 give the watch's walk (`watch_contacts`) nothing to
    report: none without a plate contact reaches the face (at x = face [m]) or comes
    within face_skin R of the undeformed one, none has moved rebuild_move [m] or more."""
    move2 = rebuild_move * rebuild_move
    for i in range(lo, hi):
        if near_plate(i, y, plate_free, plate_ylo, plate_yhi):
            if plate_overlap(y[i, 0], radius[i], face) > 0.0:
                return False
            if face_skin > 0.0 and plate_overlap(y[i, 0], radius[i] * (1.0 + face_skin), plate_x0) > 0.0:
                return False
        if rebuild_move > 0.0 and moved_squared(i, y, yref, ndim) > move2:
            return False
    return True


@njit(parallel=True)
def quiet_blocks(
    flags, y, radius, plate_free, yref, face, plate_x0, plate_ylo, plate_yhi, rebuild_move, face_skin, ndim
):
    """`granules_quiet` over every granule in blocks on every core, one per entry of flags
    (solver.blocks's ranges; each block's answer into its flag): whether the serial walk
    would find nothing."""
    nb = flags.shape[0]
    for k in prange(nb):
        lo, hi = block_range(k, nb, y.shape[0])
        quiet = granules_quiet(
            lo, hi, y, radius, plate_free, yref, face, plate_x0, plate_ylo, plate_yhi, rebuild_move, face_skin, ndim
        )
        flags[k] = 1 if quiet else 0
    for k in range(nb):
        if flags[k] == 0:
            return False
    return True


@njit(cache=True)
def watch_contacts(
    t,
    y,
    u,
    radius,
    plate_free,
    yref,
    ovl,
    ovl_with,
    ovl_new,
    ovl_who,
    overlap_stop,
    plate_x0,
    plate_ylo,
    plate_yhi,
    rebuild_move,
    face_skin,
    ndim,
    moved2,
    flags,
    err,
):
    """Check the state after an accepted step; returns OK, REBUILD (the list must be
    rebuilt: a granule moved rebuild_move since it was built, at yref), NEW_PLATE (a
    granule without a plate contact is within face_skin R of the undeformed face: it needs
    a patch contact; err[ERR_CONTACT] names it), ERR_OVERLAP, ERR_PLATE_REACH or ERR_JUMP
    with err filled. The step's largest overlap comes from the last evaluation of the
    forces (ovl_new, ovl_who: granular.granular_rhs); ovl, ovl_with keep each granule's
    largest; ndim: the positions' dimension (2 or 3: the first ndim state columns). With
    more than one flag (a threaded run: Work.wflag) the granules are first screened in as
    many blocks on every core (`quiet_blocks`), and walked in order only when one has
    something to report: the same answer. moved2 >= 0: the largest squared move since yref
    of any granule [m^2], which the step measured as it moved them (the scheme's hook
    largest_move; -1: not measured); with no plate span to reach (plate_ylo >= plate_yhi,
    the granules in space) it is the screen, and the walk runs only when it finds a move
    of rebuild_move or more. (Arrays and the Config's scalars, not the tuples: this runs every step.)"""
    i = ovl_who[0]
    if i >= 0:
        partner = ovl_who[1]
        rel = ovl_new[0]
        note_overlap(i, partner, rel, ovl, ovl_with)
        if partner >= 0:
            note_overlap(partner, i, rel, ovl, ovl_with)
        if rel > overlap_stop:
            r = radius[i] if partner < 0 else min(radius[i], radius[partner])
            return stop(ERR_OVERLAP, t, err, i, partner, rel * r, rel)
    face = plate_x0 + plate_face(u)
    if moved2 >= 0.0 and plate_yhi <= plate_ylo:  # only the moves to screen, measured already
        if rebuild_move <= 0.0 or moved2 <= rebuild_move * rebuild_move:
            return OK
    elif flags.shape[0] > 1 and quiet_blocks(
        flags, y, radius, plate_free, yref, face, plate_x0, plate_ylo, plate_yhi, rebuild_move, face_skin, ndim
    ):
        return OK
    status = OK
    move2 = rebuild_move * rebuild_move
    for i in range(y.shape[0]):
        if near_plate(i, y, plate_free, plate_ylo, plate_yhi):
            reach = plate_overlap(y[i, 0], radius[i], face)
            if reach > 0.0:
                return stop(ERR_PLATE_REACH, t, err, i, PARTNER_PLATE, reach, reach / radius[i])
            if face_skin > 0.0 and plate_overlap(y[i, 0], radius[i] * (1.0 + face_skin), plate_x0) > 0.0:
                status = NEW_PLATE
                err[ERR_CONTACT] = i
        if rebuild_move > 0.0:
            d2 = moved_squared(i, y, yref, ndim)
            if d2 > move2:
                status = REBUILD
                jump = rebuild_move + radius[i]
                if d2 > jump * jump:
                    return stop(ERR_JUMP, t, err, i, -1, d2**0.5, d2**0.5 / radius[i])
    return status
