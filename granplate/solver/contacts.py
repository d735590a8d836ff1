"""The contact watch after every accepted step (docs/model.md section 1.3): how far each
granule has moved since the contact list was built (past cfg.rebuild_move the chunk ends
and the driver rebuilds the list), the largest overlap of every contact against the
smaller radius (past cfg.overlap_stop the run stops), and granules without a plate
contact reaching the plate's face (the run stops).
"""
from __future__ import annotations

from numba import njit

from granplate.physics.contact import pair_overlap, plate_overlap, wall_overlap
from granplate.solver.state import (
    ERR_CONTACT, ERR_ITER, ERR_JUMP, ERR_N, ERR_OVERLAP, ERR_PLATE_REACH, ERR_RESID, ERR_T, ERR_VT,
    OK, PARTNER_PLATE, REBUILD,
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


@njit(cache=True)
def watch_contacts(t, y, u, g, cfg, w, err):
    """Check the state after an accepted step; returns OK, REBUILD (the list must be
    rebuilt: a granule moved cfg.rebuild_move since it was built), ERR_OVERLAP,
    ERR_PLATE_REACH or ERR_JUMP with err filled."""
    for p in range(g.pair_ij.shape[0]):
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        ri = g.radius[i]
        rj = g.radius[j]
        delta, _, _ = pair_overlap(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj)
        if delta > 0.0:
            rel = delta / min(ri, rj)
            note_overlap(i, j, rel, w.ovl, w.ovl_with)
            note_overlap(j, i, rel, w.ovl, w.ovl_with)
            if rel > cfg.overlap_stop:
                return stop(ERR_OVERLAP, t, err, i, j, delta, rel)
    for k in range(g.wall_i.shape[0]):
        i = g.wall_i[k]
        delta = wall_overlap(y[i, 0], y[i, 1], g.radius[i], g.wall_geo[k, 0], g.wall_geo[k, 1], g.wall_geo[k, 2])
        if delta > 0.0:
            rel = delta / g.radius[i]
            note_overlap(i, -1 - g.wall_w[k], rel, w.ovl, w.ovl_with)
            if rel > cfg.overlap_stop:
                return stop(ERR_OVERLAP, t, err, i, -1 - g.wall_w[k], delta, rel)
    for k in range(g.pc_i.shape[0]):
        i = g.pc_i[k]
        delta = plate_overlap(y[i, 0], g.radius[i], g.pc_x[k] + u[2 * k])
        if delta > 0.0:
            rel = delta / g.radius[i]
            note_overlap(i, PARTNER_PLATE, rel, w.ovl, w.ovl_with)
            if rel > cfg.overlap_stop:
                return stop(ERR_OVERLAP, t, err, i, PARTNER_PLATE, delta, rel)
    face = cfg.plate_x0 + plate_face(u)
    status = OK
    move2 = cfg.rebuild_move * cfg.rebuild_move
    for i in range(y.shape[0]):
        if w.plate_free[i] != 0 and cfg.plate_ylo < y[i, 1] < cfg.plate_yhi:
            reach = plate_overlap(y[i, 0], g.radius[i], face)
            if reach > 0.0:
                return stop(ERR_PLATE_REACH, t, err, i, PARTNER_PLATE, reach, reach / g.radius[i])
        if cfg.rebuild_move > 0.0:
            dx = y[i, 0] - w.yref[i, 0]
            dy = y[i, 1] - w.yref[i, 1]
            d2 = dx * dx + dy * dy
            if d2 > move2:
                status = REBUILD
                jump = cfg.rebuild_move + g.radius[i]
                if d2 > jump * jump:
                    return stop(ERR_JUMP, t, err, i, -1, d2 ** 0.5, d2 ** 0.5 / g.radius[i])
    return status
