"""The compiled time loop: choose the step, let the scheme try it, commit or retry,
check the energy balance (eq. 11) and record the output. Scheme-independent; the
scheme's hooks are picked at compile time from its scratch type (solver/schemes).

Everything here is numba-compiled (cached on disk), takes only arrays and named tuples
of arrays, allocates nothing per step and runs no Python per step.
"""

from __future__ import annotations

import math

from granplate.jit import NO_REFCOUNT, njit

from granplate.physics.energy import energy_residual, energy_total
from granplate.solver import schemes as S
from granplate.solver.blocks import accept_rows
from granplate.solver.contacts import watch_contacts
from granplate.solver.dimension import granular_rhs, kinetic_energies, sensor_loads
from granplate.solver.granular import commit_histories
from granplate.solver.rk4 import RK4_FRICTION_LIMIT
from granplate.solver.interface import accept_contacts, contact_modulus, first_guess, move_patches, place_patch
from granplate.solver.ladder import level_step
from granplate.solver.plate_modal import driving_dofs, modal_acceleration, plate_energy, step_matrices
from granplate.model.inputs import DR_F
from granplate.solver.drives import accept_pistons, drive_displacement, piston_energy, restore_pistons, walls_moved
from granplate.solver.state import (
    A_DRIVE,
    A_GRAVITY,
    E_DRIVE,
    E_GRAVITY,
    REBUILD,
    A_FRIC,
    A_PLASTIC,
    A_SHOCK_G,
    A_SHOCK_P,
    A_VISC,
    C_FRICTION_BOUND,
    C_ITERS,
    C_LEVEL,
    C_OUT,
    C_RETRIES,
    C_STEPS,
    CUSTOM_H,
    D_FRIC,
    D_PLASTIC,
    D_VISC,
    E_GRAN,
    KE_Z,
    E_IN_MAX,
    E_PLATE,
    E_POT,
    E_POTG,
    E_SHOCK,
    E_STATIC,
    E_ZERO,
    ERR_BUFFER,
    ERR_CONTACT,
    ERR_ENERGY,
    ERR_H,
    ERR_ITER,
    ERR_LAM,
    ERR_N,
    ERR_NAN,
    ERR_NOCONV,
    ERR_RESID,
    ERR_T,
    ERR_VT,
    H_LAST,
    KE_ROT,
    KE_X,
    KE_Y,
    N_LEVELS,
    OK,
    PAUSED,
    RES_LAST,
    RESID,
    RESID_MAX,
    S_DT_MAX,
    S_DT_MIN,
    S_ITERS,
    S_LAM_MAX,
    S_RETRIES,
    S_STEPS,
    T_NOW,
    T_TRIAL,
)


@njit(entry=True, cache=True)
def initialise(st, g, p, cfg, w):
    """Forces, accelerations and energies at t = 0 (state y, q, qd already set); the
    granules' derivative as every step's end one (without the split-off friction); the
    contacts' histories start at their overlaps at t = 0 (a contact that starts beyond
    its yield overlap starts loaded there: no plastic work is booked for it)."""
    pr = granular_rhs(
        st.clock[T_NOW],
        st.y,
        st.u,
        st.v,
        g,
        cfg,
        st.k1,
        st.force,
        st.normal,
        st.slip,
        False,
        w.fbar,
        cfg.split_friction,
        True,
    )
    commit_histories(st.clock[T_NOW], g)
    accept_pistons(g)
    st.p1[0] = pr.p_shock
    st.p1[1] = pr.p_visc
    st.p1[2] = pr.p_fric
    st.p1[3] = pr.p_drive
    st.p1[4] = pr.p_grav
    st.clock[E_POT] = pr.e_pot
    modal_acceleration(st.clock[T_NOW], st, p, cfg, st.force)
    driving_dofs(st, p)
    for d in range(st.force.shape[0]):
        st.force_prev[d] = st.force[d]
        st.pforce[d] = st.force[d]
    kx, ky, kz, kr = kinetic_energies(st.y, g)
    e0 = kx + ky + kz + kr + pr.e_pot + piston_energy(g) + plate_energy(st.q, st.qd, st.force, p.omega2, p.resid)
    st.clock[E_ZERO] = e0
    st.clock[E_IN_MAX] = e0
    reset_interval(w)


@njit(entry=True, cache=True)
def start_scheme(sw, st, g, b, cfg):
    """What the scheme adds at t = 0 after `initialise` (its hook `start`): the contact
    energies of the elastic body in space b (solver.body) join E_pot, E_p and E_0."""
    e_pot, e_static = S.start(sw, st.clock[T_NOW], st, g, b, cfg)
    if e_pot != 0.0 or e_static != 0.0:
        st.clock[E_POT] += e_pot
        st.clock[E_STATIC] = e_static
        st.clock[E_ZERO] += e_pot + e_static
        st.clock[E_IN_MAX] = st.clock[E_ZERO]


@njit(cache=True)
def reset_interval(w):
    """Restart the per-output-interval maxima."""
    for k in range(w.lam_int.shape[0]):
        w.lam_int[k] = 0.0
        w.it_int[k] = 0
    w.dt_int[0] = 1e300
    w.dt_int[1] = 0.0
    w.res_int[0] = 0.0


@njit(cache=True)
def energy_terms(y, q, qd, force, clock, acc, g, omega2, resid):
    """The terms of eq. (11) at t_n: (E_shock, E_g (with the pistons' kinetic energy,
    solver.drives), E_p, KE_x, KE_y, KE_z, KE_rot) [J]
    (E_in: `energy_in`)
    (KE_z = 0 in the plane). (Arrays, not the state tuples, but for the granular arrays g
    that tell the dimension: this runs every step.)"""
    kx, ky, kz, kr = kinetic_energies(y, g)
    return energy_terms_of(kx, ky, kz, kr, q, qd, force, clock, acc, g, omega2, resid)


@njit(cache=True)
def energy_terms_of(kx, ky, kz, kr, q, qd, force, clock, acc, g, omega2, resid):
    """`energy_terms` from the granules' kinetic energies KE_x, KE_y, KE_z, KE_rot [J]."""
    eg = kx + ky + kz + kr + clock[E_POT] + piston_energy(g)
    ep = plate_energy(q, qd, force, omega2, resid) + clock[E_STATIC]
    eshock = acc[A_SHOCK_G] + acc[A_SHOCK_P]
    return eshock, eg, ep, kx, ky, kz, kr


@njit(cache=True)
def energy_in(clock, eshock, acc):
    """E_in of eq. (11) [J]: the energy at t = 0, the shock's work, and gravity's and the
    drives' work (docs/model.md section 3.11)."""
    return clock[E_ZERO] + eshock + (acc[A_GRAVITY] + acc[A_DRIVE])


@njit(entry=True, cache=True)
def record(o, st, g, p, w, out):
    """Write the state at t_n into output row o and restart the interval maxima."""
    eshock, eg, ep, kx, ky, kz, kr = energy_terms(st.y, st.q, st.qd, st.force, st.clock, st.acc, g, p.omega2, p.resid)
    e_in = energy_in(st.clock, eshock, st.acc)
    denom = max(st.clock[E_IN_MAX], 1e-300)
    out.t[o] = st.clock[T_NOW]
    for i in range(st.y.shape[0]):
        for c in range(st.y.shape[1]):
            out.y[o, i, c] = st.y[i, c]
    e = out.energy[o]
    e[E_SHOCK] = eshock
    e[E_GRAN] = eg
    e[E_PLATE] = ep
    e[D_VISC] = st.acc[A_VISC]
    e[D_FRIC] = st.acc[A_FRIC]
    e[D_PLASTIC] = st.acc[A_PLASTIC]
    e[KE_X] = kx
    e[KE_Y] = ky
    e[KE_ROT] = kr
    e[KE_Z] = kz
    e[RESID] = energy_residual(energy_total(eg, ep, st.acc[A_VISC], st.acc[A_FRIC], st.acc[A_PLASTIC]), e_in, denom)
    e[RESID_MAX] = w.res_int[0]
    e[E_POTG] = st.clock[E_POT]
    e[E_GRAVITY] = st.acc[A_GRAVITY]
    e[E_DRIVE] = st.acc[A_DRIVE]
    for w_ in range(g.wall_load.shape[0]):
        out.wall_force[o, w_] = g.wall_load[w_]
    for k in range(g.drive_target.shape[0]):
        out.drive[o, k, 0] = g.drive_now[k, DR_F]
        out.drive[o, k, 1] = drive_displacement(st.y, g, k)
    for m in range(st.q.shape[0]):
        out.q[o, m] = st.q[m]
        out.qd[o, m] = st.qd[m]
    lam_max = 0.0
    for k in range(st.normal.shape[0]):
        out.force[o, k, 0] = st.force[2 * k]
        out.force[o, k, 1] = st.force[2 * k + 1]
        out.slip[o, k] = st.slip[k]
        out.lam[o, k] = w.lam_int[k]
        out.iters[o, k] = w.it_int[k]
        lam_max = max(lam_max, w.lam_int[k])
    s = out.stats[o]
    s[S_STEPS] = st.count[C_STEPS]
    s[S_DT_MIN] = w.dt_int[0] if w.dt_int[1] > 0.0 else 0.0
    s[S_DT_MAX] = w.dt_int[1]
    s[S_ITERS] = st.count[C_ITERS]
    s[S_RETRIES] = st.count[C_RETRIES]
    s[S_LAM_MAX] = lam_max
    reset_interval(w)


@njit(entry=True, cache=True)
def record_sensors(sw, st, g, b, cfg, out):
    """Write every sensor's reading at t_n into the next sensor row (docs/model.md section
    3.15): half the sum of the normal forces on its granule, of its pair and wall contacts
    (`sensor_loads`), of its plate contacts (their |N| at t_n) and of its contact with the
    elastic body in space b (the hook body_sensor_loads of the scheme whose scratch is sw)."""
    s = out.sensor_n[0]
    sensor_loads(st.y, g, cfg, out.sensor_load)
    S.body_sensor_loads(sw, b, out.sensor_load)
    for k in range(g.pc_i.shape[0]):
        out.sensor_load[g.pc_i[k]] += 0.5 * st.normal[k]
    out.sensor_t[s] = st.clock[T_NOW]
    for j in range(out.sensor_granule.shape[0]):
        out.sensor_force[s, j] = out.sensor_load[out.sensor_granule[j]]
    out.sensor_n[0] = s + 1


@njit(cache=True)
def next_landing(t_out, out):
    """The next time a step must land on [s]: the next output time t_out, or the next
    sensor sample time when it comes first; and whether it is t_out."""
    s = out.sensor_n[0]
    if s < out.sensor_target.shape[0] and out.sensor_target[s] < t_out:
        return out.sensor_target[s], False
    return t_out, True


@njit(cache=True)
def fail(status, err, t, h, contact, n, vt, lam, resid, it):
    """Fill the failure record err (st.err: time, contact, |N|, slip, |lambda|, step,
    residual, iterations) and return `status`."""
    err[ERR_T] = t
    err[ERR_CONTACT] = contact
    err[ERR_N] = n
    err[ERR_VT] = vt
    err[ERR_LAM] = lam
    err[ERR_H] = h
    err[ERR_RESID] = resid
    err[ERR_ITER] = it
    return status


@njit(cache=True)
def step_too_small(t, h, it, worst, lam, normal, slip, st):
    """ERR_NOCONV: the step would go below dt_min, at `worst` (or -1)."""
    if worst < 0:
        return fail(ERR_NOCONV, st.err, t, h, -1.0, 0.0, 0.0, lam, 0.0, it)
    return fail(ERR_NOCONV, st.err, t, h, worst, normal[worst], slip[worst], lam, 0.0, it)


@njit(cache=True)
def check_energy(h, ke, q, qd, force, clock, acc, g, omega2, resid, energy_tol, res_int, err):
    """Eq. (11) after an accepted step, the granules' kinetic energies ke = (KE_x, KE_y,
    KE_z, KE_rot) [J] given (the scheme's hook step_kinetic_energies): keep the residual's
    running values (clock, res_int); returns OK, ERR_NAN or ERR_ENERGY (above energy_tol)
    with err filled. (Arrays, not the state tuples: this runs every step.)"""
    eshock, eg, ep, kx, ky, kz, kr = energy_terms_of(
        ke[0], ke[1], ke[2], ke[3], q, qd, force, clock, acc, g, omega2, resid
    )
    e_in = energy_in(clock, eshock, acc)
    if e_in > clock[E_IN_MAX]:
        clock[E_IN_MAX] = e_in
    total = energy_total(eg, ep, acc[A_VISC], acc[A_FRIC], acc[A_PLASTIC])
    if not (math.isfinite(total) and math.isfinite(e_in)):
        return fail(ERR_NAN, err, clock[T_NOW], h, -1.0, 0.0, 0.0, 0.0, 0.0, 0)
    denom = clock[E_IN_MAX]
    if denom > 0.0:
        res = energy_residual(total, e_in, denom)
        clock[RES_LAST] = res
        res_int[0] = max(res_int[0], abs(res))
        if abs(res) > energy_tol:
            return fail(ERR_ENERGY, err, clock[T_NOW], h, -1.0, 0.0, 0.0, 0.0, res, 0)
    return OK


@njit(cache=True)
def prepare_slot(sw, h, slot, st, p, w):
    """G(h) and the scheme's matrices for `slot`: once per ladder level, and for an
    odd step (slot N_LEVELS) whenever it changes (see `needs_matrices`)."""
    if slot == N_LEVELS:
        st.clock[CUSTOM_H] = h
    else:
        w.g_ok[slot] = 1
    step_matrices(h, p, w.dmode[slot], w.gmat[slot])
    S.prepare_level(sw, h, p, slot)


@njit(cache=True)
def needs_matrices(h, slot, clock, g_ok):
    """Whether `slot` lacks its matrices for step h (checked every step, so it takes
    arrays, not the state tuples)."""
    if slot == N_LEVELS:
        return clock[CUSTOM_H] != h
    return g_ok[slot] == 0


@njit(cache=True)
def accept_granular(t, h, land, t_out, plate_work, e_pot, st, w, rows):
    """Take the trial step's granule state, derivatives (unless `rows` is False: taken
    already) and work (with the plastic work of the contacts loaded past their largest
    overlaps) into the state and move the clock (onto t_out, the output or sensor sample time,
    when the step lands on it)."""
    if rows:
        for i in range(st.y.shape[0]):
            for c in range(st.y.shape[1]):
                st.y[i, c] = w.ynew[i, c]
                st.k0[i, c] = st.k1[i, c]
                st.k1[i, c] = w.kend[i, c]
    for c in range(5):
        st.p1[c] = w.pend[c]
    st.acc[A_SHOCK_G] += w.dacc[0]
    st.acc[A_VISC] += w.dacc[1]
    st.acc[A_FRIC] += w.dacc[2]
    st.acc[A_PLASTIC] += w.dacc[3]
    st.acc[A_GRAVITY] += w.dacc[4]
    st.acc[A_DRIVE] += w.dacc[5]
    st.acc[A_SHOCK_P] += plate_work
    st.clock[E_POT] = e_pot
    st.clock[T_NOW] = t_out if land else t + h
    st.clock[H_LAST] = h
    st.count[C_STEPS] += 1
    w.dt_int[0] = min(w.dt_int[0], h)
    w.dt_int[1] = max(w.dt_int[1], h)


@njit(entry=True, cache=True, **NO_REFCOUNT)
def advance(t_stop, max_attempts, g, p, b, cfg, st, w, sw, out):
    """Advance from st.clock[T_NOW] to t_stop (an output time) with the scheme whose
    scratch is sw, trying at most max_attempts steps; the elastic bodies are p (the modal
    plate) and b (the elastic body in space, or NoBodyArrays). Returns a status: OK, PAUSED
    (budget spent; call again) or an error, with st.err filled and the state the last
    accepted one. Steps land on the output times and on the sensors' sample times
    (out.sensor_target; `record_sensors` at each). After every accepted step the patch
    contacts follow their granules (interface.move_patches, then the scheme's hook
    contacts_moved) and the contact watch runs (solver/contacts.py): REBUILD asks the driver to rebuild the contact
    list, NEW_PLATE to add a patch contact, and to call again."""
    for _ in range(max_attempts):
        t = st.clock[T_NOW]
        if t >= t_stop - 1e-9 * cfg.dt_min:
            return OK
        o = st.count[C_OUT]
        if o >= out.t.shape[0]:
            return ERR_BUFFER
        t_land, on_output = next_landing(out.target[o], out)
        level, h, slot, land = S.plan(sw, st.count, cfg, t - out.target[o - 1], t_land - t)
        if not land and t + h <= t:  # a step too small to move the clock: it would spin
            return step_too_small(t, h, 0, -1, 0.0, st.normal, st.slip, st)
        if needs_matrices(h, slot, st.clock, w.g_ok):
            prepare_slot(sw, h, slot, st, p, w)
        ratio = h / st.clock[H_LAST] if st.clock[H_LAST] > 0.0 else 0.0
        first_guess(ratio, st, w)
        st.clock[T_TRIAL] = t_land if land else t + h  # (as accept_granular moves the clock)
        converged, it, worst, e_pot, rate = S.attempt(sw, t, h, slot, st, g, p, b, cfg, w)
        st.count[C_ITERS] += it
        if not converged:
            restore_pistons(g)
            st.count[C_RETRIES] += 1
            if level_step(level + 4, cfg) < cfg.dt_min or level + 4 >= N_LEVELS:
                lam = contact_modulus(worst, h, w.gmat[slot], g, w.normal_new, w.slip_new) if worst >= 0 else 0.0
                return step_too_small(t, h, it, worst, lam, w.normal_new, w.slip_new, st)
            st.count[C_LEVEL] = level + 4
            continue
        err, retry, plate_work, fric_work = S.judge(sw, t, h, slot, level, ratio, e_pot, st, g, p, b, cfg, w)
        if retry >= 0:
            restore_pistons(g)
            st.count[C_RETRIES] += 1
            st.count[C_LEVEL] = retry
            continue
        plate_work = S.commit(sw, t, h, slot, plate_work, fric_work, st, g, p, b, cfg, w)
        accept_pistons(g)
        apart = not S.steps_in_place(sw, g)  # (else the state holds the step's end already)
        if apart and cfg.threads > 1:  # the copies on every core (solver.blocks)
            accept_rows(st.y, st.k1, w.ynew, w.kend)
        accept_granular(t, h, land, t_land, plate_work, e_pot, st, w, apart and cfg.threads == 1)
        S.commit_histories(sw, st.clock[T_NOW], g, cfg)
        lam_max = accept_contacts(
            h, w.gmat[slot], g.pc_coef, w.normal_new, w.slip_new, w.conv_iter, st.normal, st.slip, w.lam_int, w.it_int
        )
        new_level, h_new = S.next_level(sw, h, slot, level, err, lam_max, rate, st.clock[T_NOW], cfg)
        if not cfg.split_friction and rate * h > 0.5 * RK4_FRICTION_LIMIT:  # the step was at RK4's friction bound
            st.count[C_FRICTION_BOUND] += 1
        if level_step(new_level, cfg) < cfg.dt_min:
            return step_too_small(st.clock[T_NOW], h_new, it, worst_contact(w), lam_max, st.normal, st.slip, st)
        st.count[C_LEVEL] = new_level
        ke = S.step_kinetic_energies(sw, st.y, g)
        status = check_energy(
            h, ke, st.q, st.qd, st.force, st.clock, st.acc, g, p.omega2, p.resid, cfg.energy_tol, w.res_int, st.err
        )
        if status != OK:
            return status
        if land:
            if out.sensor_n[0] < out.sensor_target.shape[0] and out.sensor_target[out.sensor_n[0]] <= t_land:
                record_sensors(sw, st, g, b, cfg, out)
            if on_output:
                record(o, st, g, p, w, out)
                st.count[C_OUT] = o + 1
        if g.pc_patch.shape[0] > 0 and move_patches(st, g, p, cfg, w):  # patch contacts follow their granules
            S.contacts_moved(sw, st.clock[T_NOW], st, p, cfg)
        status = watch_contacts(
            st.clock[T_NOW],
            st.y,
            st.u,
            g.radius,
            w.plate_free,
            w.yref,
            w.ovl,
            w.ovl_with,
            w.ovl_new,
            w.ovl_who,
            cfg.overlap_stop,
            cfg.plate_x0,
            cfg.plate_ylo,
            cfg.plate_yhi,
            cfg.rebuild_move,
            cfg.face_skin,
            cfg.dimension,
            S.largest_move(sw),
            w.wflag,
            st.err,
        )
        if status != OK:
            return status
        if g.wall_drive.shape[0] > 0 and cfg.rebuild_move > 0.0 and walls_moved(g, cfg.rebuild_move):
            return REBUILD  # a driven wall moved as far as a granule may before the list is rebuilt
    return OK if st.clock[T_NOW] >= t_stop - 1e-9 * cfg.dt_min else PAUSED


@njit(entry=True, cache=True)
def place_contact(sw, k, y_c, st, p, cfg, w):
    """Centre patch contact k at height y_c [m] on the face (interface.place_patch) and
    give the scheme whose scratch is sw its state at the contact's rows (its hook
    contact_placed); the driver calls this for every patch contact it adds."""
    place_patch(k, y_c, st, p, cfg, w)
    S.contact_placed(sw, k, st, p)


@njit(cache=True)
def worst_contact(w):
    """The plate contact with the largest |lambda| since the last output (-1: none)."""
    kw = -1
    for k in range(w.lam_int.shape[0]):
        if kw < 0 or w.lam_int[k] >= w.lam_int[kw]:
            kw = k
    return kw
