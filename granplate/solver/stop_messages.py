"""Why a run stopped, in words: the status codes of the loop (solver/state.py) and of the
contact watch (solver/contacts.py, model/contacts.py) as messages naming the quantities,
the limits and what to change, and the overlap warnings after a run."""

from __future__ import annotations

import numpy as np

from granplate.model.arrays import Model
from granplate.solver import state as S

#: status of a run stopped by a signal (SIGINT, SIGTERM) or a stop request.
INTERRUPTED = -1
INTERRUPTED_STATUS = "interrupted by the user"


def status_message(status: int, model: Model, st: S.State) -> str:
    """Why the run stopped, naming the quantities, the limits and what to change."""
    e = st.err
    cfg = model.config
    t = e[S.ERR_T]
    if status == INTERRUPTED:
        return f"{INTERRUPTED_STATUS} at t = {st.clock[S.T_NOW]:.6e} s."
    if status == S.ERR_NOCONV and int(e[S.ERR_ITER]) == 0:
        return (
            f"the time step cannot move the clock on at t = {t:.6e} s (step {e[S.ERR_H]:.3e} s, "
            f"time.dt_min = {cfg.dt_min:.3e} s): the step control has collapsed. Raise time.dt_min "
            f"or solver.error_tol."
        )
    if status == S.ERR_NOCONV:
        k = int(e[S.ERR_CONTACT])
        where = f"plate contact '{model.contact_labels[k]}'" if 0 <= k < len(model.contact_labels) else "the interface"
        return (
            f"the interface-force iteration cannot go on at t = {t:.6e} s: {where} has "
            f"|N| = {e[S.ERR_N]:.4g} N, slip rate {e[S.ERR_VT]:.4g} m/s, local-map modulus "
            f"|lambda| = {e[S.ERR_LAM]:.3g} (eq. 8) with step {e[S.ERR_H]:.3e} s after "
            f"{int(e[S.ERR_ITER])} iterations, and the step may not go below time.dt_min = "
            f"{cfg.dt_min:.3e} s. Lower solver.lambda_target, raise solver.max_iterations or "
            f"lower time.dt_min."
        )
    if status == S.ERR_ENERGY:
        return (
            f"energy balance broken at t = {t:.6e} s: residual (E_p + E_g + D - E_in)/E_in = "
            f"{e[S.ERR_RESID]:.3e} exceeds solver.energy_tol = {cfg.energy_tol:.1e} "
            f"(step {e[S.ERR_H]:.3e} s). Lower {step_ceiling(model)} or solver.lambda_target."
        )
    if status in (S.ERR_OVERLAP, S.ERR_MISSED, S.ERR_PLATE_REACH, S.ERR_JUMP):
        return contact_message(status, model, st)
    if status == S.ERR_NAN:
        return f"the state became non-finite (NaN/inf) at t = {t:.6e} s (step {e[S.ERR_H]:.3e} s)."
    return f"output buffer exhausted at t = {t:.6e} s (internal error, status {status})."


def step_ceiling(model: Model) -> str:
    """The field that caps the run's step: solver.implicit_dt_max under the implicit
    scheme (model.arrays caps its steps by it, not by time.dt_max), else time.dt_max."""
    return "solver.implicit_dt_max" if model.scenario.solver.scheme == "implicit" else "time.dt_max"


def partner_name(model: Model, partner: int) -> str:
    """'granule X', 'wall w (x, y)' or 'the plate' from a partner code (state.PARTNER_PLATE)."""
    if partner == S.PARTNER_PLATE:
        return "the plate"
    if partner < 0:
        w = -1 - partner
        return f"wall {w} (normal {tuple(model.scenario.walls[w].normal)}, offset {model.scenario.walls[w].offset:g} m)"
    return f"granule '{model.labels[partner]}'"


def contact_message(status: int, model: Model, st: S.State) -> str:
    """Why the contact watch stopped the run (solver/contacts.py, model/contacts.py)."""
    e = st.err
    c = model.scenario.contact
    cfg = model.config
    t = e[S.ERR_T]
    i = int(e[S.ERR_CONTACT])
    who = f"granule '{model.labels[i]}'"
    other = partner_name(model, int(e[S.ERR_ITER]))
    where = "(at " + ", ".join(f"{name} = {v:.6g} m" for name, v in zip("xyz", st.y[i, : cfg.dimension])) + ")"
    if status == S.ERR_OVERLAP:
        return (
            f"{who} {where} and {other} overlap by {e[S.ERR_N]:.4g} m at t = {t:.6e} s, "
            f"{e[S.ERR_RESID]:.3g} of the smaller radius, beyond contact.overlap_stop = "
            f"{c.overlap_stop:g}: Hertz's law assumes small overlaps. Lower the load or "
            f"time.dt_max, or stiffen the contact."
        )
    if status == S.ERR_MISSED:
        how = (
            'it is not one of the fixed contacts (contact.detection = "fixed"); use detection = "dynamic"'
            if c.detection == "fixed"
            else "the contact formed unseen within one step: lower time.dt_max or raise contact.skin"
        )
        return (
            f"{who} {where} and {other} interpenetrate by {e[S.ERR_N]:.4g} m at t = {t:.6e} s "
            f"and no contact accounts for it: {how}."
        )
    if status == S.ERR_PLATE_REACH:
        if cfg.face_skin > 0.0:
            why = (
                "it came from farther than contact.skin R within one step, so its patch contact "
                "formed unseen: lower time.dt_max or raise contact.skin"
            )
        elif c.detection == "fixed":
            why = (
                f'with contact.detection = "fixed" plate contacts are those at t = 0 (within '
                f'contact.neighbour_gap = {c.neighbour_gap:g} R of the plate); use detection = "dynamic"'
            )
        else:
            why = (
                "contacts forming on the plate's face need every mode or the truncated basis' "
                'static correction; use plate.n_modes = 0 (with plate.modes = "all"), or '
                'plate.modes = "truncated" (a dense basis cut to plate.n_modes keeps plate '
                "contacts to those at t = 0)"
            )
        return (
            f"{who} {where} reached the plate's face at t = {t:.6e} s (overlap "
            f"{e[S.ERR_N]:.4g} m) but has no plate contact: {why}."
        )
    return (
        f"{who} {where} moved {e[S.ERR_N]:.4g} m ({e[S.ERR_RESID]:.3g} radii) in one step at "
        f"t = {t:.6e} s: contacts may have been passed through. Lower time.dt_max."
    )


def overlap_warnings(model: Model, w: S.Work) -> list[str]:
    """One line per granule whose largest contact overlap exceeded contact.overlap_warn
    (of the smaller radius), with that contact's partner: Hertz's law assumes small overlaps."""
    lim = model.scenario.contact.overlap_warn
    out = []
    seen = set()
    for i in np.flatnonzero(w.ovl > lim):
        j = int(w.ovl_with[i])
        key = (min(i, j), max(i, j)) if j >= 0 else (int(i), j)
        if key in seen:
            continue
        seen.add(key)
        out.append(
            f"granule '{model.labels[i]}' and {partner_name(model, j)}: overlap "
            f"{w.ovl[i]:.3g} of the smaller radius (contact.overlap_warn = {lim:g})"
        )
    return out
