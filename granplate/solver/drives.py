"""Gravity and drives in the time loop (docs/model.md section 3.11), in either dimension
(the translational velocity columns start at 3 in both; d = the directions' length).

Every force pass (the RK4 derivative, the Verlet force pass) starts with `begin_pass`
(the drives' motion at its time, the walls' loads zeroed), lets the wall contacts use
their wall's motion (`wall_motion`) and book their forces (`book_wall`), and ends with
`finish_pass`: gravity on every granule, and on each driven granule the force that gives
it its prescribed acceleration along the direction (or the prescribed force), which is
the force the drive applies, recorded with its power. After a step, `hold_drives` sets a
driven granule's velocity along its direction to the prescribed one (the drive's
impulse, its work booked); the schemes book the drives' work and gravity's (RK4's
quadrature of their powers; Verlet's kicks, `drive_kick_work`, `gravity_kick_work`).

A force drive on a wall makes it a piston of mass M (`is_piston`): its displacement s and
velocity v along the drive's direction e are state (drive_now DR_S, DR_V), which
`begin_pass` leaves as they are; the contacts on it push back with R (their normal forces
against e, summed by `book_wall`), and `finish_pass` gives it M s'' = P(t) - R. The
velocity-Verlet scheme kicks and drifts it like a granule's one degree of freedom
(`piston_kick_drift`, `piston_kick`), booking P's share of each kick as the drive's work
and the damping's as dissipation; its kinetic energy 1/2 M v^2 (`piston_energy`) is part
of E_g.

Under the RK4 schemes (paper, implicit) a piston is one more degree of freedom of the
granular RK4 step (solver.rk4): `pistons_at_start` puts it at its state at the last
accepted step (DR_SC, DR_VC, DR_AC), `piston_stage` books a stage's (v, a) into the RK4
sums and moves it to the next stage, `piston_rk4_end` to the step's end, and
`accept_pistons` takes the trial step's state once the step is accepted (`restore_pistons`
puts a rejected one back). Its contacts' work on the granules is internal to E_g, P's work
is RK4's quadrature of P v (its share of the drives' power), the damping's is in the
contacts' viscous power at their relative rate.
"""

from __future__ import annotations

from granplate.jit import njit

from granplate.model.inputs import (
    DR_A,
    DR_AC,
    DR_F,
    DR_FD,
    DR_KS,
    DR_KV,
    DR_P,
    DR_PD,
    DR_R,
    DR_REF,
    DR_S,
    DR_SC,
    DR_V,
    DR_VC,
    DR_VH,
    HIST_MAX,
    HIST_RATE,
)
from granplate.physics.drives import KIND_FORCE, PAR_MASS, drive_motion
from granplate.physics.laws import normal_law_response
from granplate.solver.kicks import half_kick

#: the first velocity column of a granule's state (both dimensions)
V0 = 3


@njit(entry=True, cache=True)
def is_piston(g, k):
    """Whether drive k pushes a wall with a force (the wall a piston)."""
    return g.drive_target[k] < 0 and g.drive_kind[k] == KIND_FORCE


@njit(cache=True)
def begin_pass(t, g):
    """The drives' motion at t [s] into drive_now (DR_S, DR_V, DR_A; a force drive's
    force in DR_A; a piston's s and v, its state, kept), their forces and powers zeroed,
    and the walls' loads zeroed."""
    for w in range(g.wall_load.shape[0]):
        g.wall_load[w] = 0.0
    for k in range(g.drive_target.shape[0]):
        s, v, a = drive_motion(t, g.drive_kind[k], g.drive_prof[k], g.drive_par[k], g.drive_tab[k], g.drive_tlen[k])
        now = g.drive_now[k]
        if not is_piston(g, k):
            now[DR_S] = s
            now[DR_V] = v
        now[DR_A] = a
        now[DR_F] = 0.0
        now[DR_P] = 0.0
        now[DR_PD] = 0.0
        now[DR_FD] = 0.0


@njit(cache=True)
def wall_normal_dot(g, w, k):
    """n . e of wall contact w's outward normal n and drive k's direction e (+-1)."""
    ne = 0.0
    for c in range(g.drive_dir.shape[1]):
        ne += g.wall_geo[w, c] * g.drive_dir[k, c]
    return ne


@njit(cache=True)
def wall_motion(g, w):
    """(the shift of wall contact w's offset [m], its wall's velocity along the outward
    normal [m/s], its drive or -1) at the last `begin_pass`."""
    if g.wall_drive.shape[0] == 0:
        return 0.0, 0.0, -1
    k = g.wall_drive[g.wall_w[w]]
    if k < 0:
        return 0.0, 0.0, -1
    ne = wall_normal_dot(g, w, k)
    return g.drive_now[k, DR_S] * ne, g.drive_now[k, DR_V] * ne, k


@njit(cache=True)
def book_wall(g, w, k, n, damp):
    """Wall contact w's normal force n [N] (its damping part damp [N]) on its wall's load
    and, for a driven wall (drive k >= 0), on the force the drive applies along its
    direction (the contact forces on the granules, -n n . e; a piston's R), its damping
    part, and the damping forces' power at the wall's velocity [W]."""
    if g.wall_load.shape[0] > 0:
        g.wall_load[g.wall_w[w]] += n
    if k >= 0:
        ne = wall_normal_dot(g, w, k)
        g.drive_now[k, DR_F] -= n * ne
        g.drive_now[k, DR_FD] -= damp * ne
        g.drive_now[k, DR_PD] -= damp * g.drive_now[k, DR_V] * ne


@njit(cache=True)
def along(a, i, g, k):
    """The component of row i of the state (or derivative) a's velocity columns along
    drive k's direction."""
    x = 0.0
    for c in range(g.drive_dir.shape[1]):
        x += a[i, V0 + c] * g.drive_dir[k, c]
    return x


@njit(cache=True)
def finish_pass(y, acc, g):
    """End a force pass at state y with the accelerations acc (every other force in):
    gravity on every granule; each driven granule's acceleration along its direction
    made the prescribed one (or the prescribed force added), the force that takes
    (mass x the acceleration it changes) and its power recorded; a driven wall's power; a
    piston's acceleration (P - R) / M, its force P recorded. Returns (the power of the
    granules' drives, of the pistons' forces and of the contact damping forces at the
    driven walls' velocities, gravity's power) [W]."""
    ng = y.shape[0]
    p_grav = 0.0
    for c in range(g.gravity.shape[0]):
        gc = g.gravity[c]
        for i in range(ng):
            acc[i, V0 + c] += gc
            p_grav += g.mass[i] * gc * y[i, V0 + c]
    power = 0.0
    for k in range(g.drive_target.shape[0]):
        now = g.drive_now[k]
        i = g.drive_target[k]
        if i >= 0:
            m = g.mass[i]
            if g.drive_kind[k] == KIND_FORCE:
                da = now[DR_A] / m
            else:
                da = now[DR_A] - along(acc, i, g, k)
            for c in range(g.drive_dir.shape[1]):
                acc[i, V0 + c] += da * g.drive_dir[k, c]
            now[DR_F] = m * da
            now[DR_P] = now[DR_F] * along(y, i, g, k)
            power += now[DR_P]
        elif g.drive_kind[k] == KIND_FORCE:  # a piston: pushed by P (in DR_A) and by its contacts (R)
            now[DR_R] = now[DR_F]
            now[DR_F] = now[DR_A]
            now[DR_A] = (now[DR_F] - now[DR_R]) / g.drive_par[k, PAR_MASS]
            now[DR_P] = now[DR_F] * now[DR_V]
            power += now[DR_P]
        else:  # a wall: its elastic work is booked exactly (`wall_shift_energy`), its damping's here
            now[DR_P] = now[DR_F] * now[DR_V]
            power += now[DR_PD]
    return power, p_grav


@njit(cache=True)
def hold_drives(t, y, g):
    """Each granule under a displacement or velocity drive: its velocity along the
    direction set to the prescribed one at t [s] (the drive's impulse). Returns its work,
    the kinetic energy it adds [J]."""
    work = 0.0
    for k in range(g.drive_target.shape[0]):
        i = g.drive_target[k]
        if i < 0 or g.drive_kind[k] == KIND_FORCE:
            continue
        _, v, _ = drive_motion(t, g.drive_kind[k], g.drive_prof[k], g.drive_par[k], g.drive_tab[k], g.drive_tlen[k])
        dv = v - along(y, i, g, k)
        if dv == 0.0:
            continue
        v_old = along(y, i, g, k)
        for c in range(g.drive_dir.shape[1]):
            y[i, V0 + c] += dv * g.drive_dir[k, c]
        work += 0.5 * g.mass[i] * (v * v - v_old * v_old)
    return work


@njit(cache=True)
def gravity_kick_work(y, acc, g, hk):
    """The work of gravity over a Verlet half kick of hk [s] from velocities y with
    accelerations acc: hk m g . (v + hk a / 2) [J], the kinetic energy its share of the
    kick adds."""
    work = 0.0
    for c in range(g.gravity.shape[0]):
        gc = g.gravity[c]
        for i in range(y.shape[0]):
            work += hk * g.mass[i] * gc * (y[i, V0 + c] + 0.5 * hk * acc[i, V0 + c])
    return work


@njit(cache=True)
def drive_kick_work(y, acc, g, hk):
    """The work of the driven granules' drive forces (drive_now DR_F) over a Verlet half
    kick of hk [s] from velocities y with accelerations acc: hk F (v + hk a / 2) along
    each direction [J], the kinetic energy the force's share of the kick adds."""
    work = 0.0
    for k in range(g.drive_target.shape[0]):
        i = g.drive_target[k]
        if i >= 0:
            work += hk * g.drive_now[k, DR_F] * (along(y, i, g, k) + 0.5 * hk * along(acc, i, g, k))
    return work


@njit(cache=True)
def wall_powers(g):
    """(the driven walls' power F v [W], the contact damping forces' power at their
    velocity [W]) at the last force pass; the pistons' are not counted (their kicks book
    them)."""
    p = 0.0
    pd = 0.0
    for k in range(g.drive_target.shape[0]):
        if g.drive_target[k] < 0 and not is_piston(g, k):
            p += g.drive_now[k, DR_P]
            pd += g.drive_now[k, DR_PD]
    return p, pd


@njit(cache=True)
def walls_moved(g, limit):
    """Whether a driven wall moved farther than limit [m] since the contact list was
    built (drive_now DR_REF, set by the driver)."""
    for k in range(g.drive_target.shape[0]):
        if g.drive_target[k] < 0 and abs(g.drive_now[k, DR_S] - g.drive_now[k, DR_REF]) > limit:
            return True
    return False


@njit(cache=True)
def drive_displacement(y, g, k):
    """Drive k's displacement along its direction [m]: its granule's centre from t = 0
    (the state y), or its wall's prescribed displacement."""
    i = g.drive_target[k]
    if i < 0:
        return g.drive_now[k, DR_S]
    x = 0.0
    for c in range(g.drive_dir.shape[1]):
        x += (y[i, c] - g.drive_x0[k, c]) * g.drive_dir[k, c]
    return x


@njit(cache=True)
def wall_contact_energy(y, g, w, k, clip, t):
    """The stored energy [J] of wall contact w (driven by drive k) with the granule at
    state y and the wall where it is at t [s] (the overlap as the force passes compute
    it, to the last bit: physics.contact.wall_overlap)."""
    d = g.drive_dir.shape[1]
    i = g.wall_i[w]
    xn = 0.0
    for c in range(d):
        xn += y[i, c] * g.wall_geo[w, c]
    s, _, _ = drive_motion(t, g.drive_kind[k], g.drive_prof[k], g.drive_par[k], g.drive_tab[k], g.drive_tlen[k])
    delta = xn + g.radius[i] - (g.wall_geo[w, d] + s * wall_normal_dot(g, w, k))
    if delta <= 0.0:
        return 0.0
    _, _, ep, _ = normal_law_response(
        delta, 0.0, g.wall_coef[w], g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], clip
    )
    return ep


@njit(cache=True)
def wall_shift_energy(y0, y1, g, clip, t0, t1):
    """The elastic work of the driven walls over a step from t0 to t1 [s], in which the
    granules move from state y0 to y1: the change of their contacts' stored energy as each
    wall moves from where it is at t0 to where it is at t1, the granules held at y0 and at
    y1 in turn, averaged (the symmetric split of the stored energy's change between the
    walls' moves and the granules', second order in the step). A piston's move is none of
    it: its contacts' energy is the assembly's own (E_g)."""
    if g.wall_drive.shape[0] == 0:
        return 0.0
    work = 0.0
    for w in range(g.wall_i.shape[0]):
        k = g.wall_drive[g.wall_w[w]]
        if k < 0 or is_piston(g, k):
            continue
        work += 0.5 * (
            wall_contact_energy(y1, g, w, k, clip, t1)
            - wall_contact_energy(y1, g, w, k, clip, t0)
            + wall_contact_energy(y0, g, w, k, clip, t1)
            - wall_contact_energy(y0, g, w, k, clip, t0)
        )
    return work


@njit(cache=True)
def piston_half_kick(now, v0: float, hk: float):
    """A piston's half kick from velocity v0 [m/s] over hk [s] with its row `now` of drive_now:
    (v0 + hk a, the work of P over it, the energy its damping force takes [J])."""
    v1, _, vm = half_kick(v0, now[DR_A], hk)
    return v1, now[DR_F] * vm, now[DR_FD] * vm


@njit(cache=True)
def piston_kick_drift(g, h):
    """Every piston (`is_piston`): the first half kick v += h/2 a, the drift s += h v, and
    the velocity the force pass at the step's end reads, v + h/2 a (as solver.kicks
    does a granule's). Returns (the work of P's share of the kick, the kinetic energy it adds
    [J]; the damping force's share, the energy it takes, dissipated [J])."""
    hk = 0.5 * h
    work = 0.0
    dissipated = 0.0
    for k in range(g.drive_target.shape[0]):
        if not is_piston(g, k):
            continue
        now = g.drive_now[k]
        now[DR_VH], w, d = piston_half_kick(now, now[DR_V], hk)
        work += w
        dissipated += d
        now[DR_S] += h * now[DR_VH]
        now[DR_V] = now[DR_VH] + hk * now[DR_A]
    return work, dissipated


@njit(cache=True)
def piston_kick(g, hk):
    """Every piston: the closing half kick v += hk a from its velocity after the first
    (hk = h/2 [s]). Returns (P's work, the damping's dissipation) [J] as `piston_kick_drift`."""
    work = 0.0
    dissipated = 0.0
    for k in range(g.drive_target.shape[0]):
        if not is_piston(g, k):
            continue
        now = g.drive_now[k]
        now[DR_V], w, d = piston_half_kick(now, now[DR_VH], hk)
        work += w
        dissipated += d
    return work, dissipated


@njit(cache=True)
def piston_energy(g):
    """The pistons' kinetic energy sum 1/2 M v^2 [J] (part of E_g; 0 without pistons)."""
    e = 0.0
    for k in range(g.drive_target.shape[0]):
        if is_piston(g, k):
            v = g.drive_now[k, DR_V]
            e += 0.5 * g.drive_par[k, PAR_MASS] * v * v
    return e


@njit(cache=True)
def pistons_at_start(g):
    """Every piston at its state at the last accepted step (DR_SC, DR_VC, DR_AC) with its
    RK4 sums zeroed: an RK4 step's first stage."""
    for k in range(g.drive_target.shape[0]):
        if is_piston(g, k):
            now = g.drive_now[k]
            now[DR_S] = now[DR_SC]
            now[DR_V] = now[DR_VC]
            now[DR_A] = now[DR_AC]
            now[DR_KS] = 0.0
            now[DR_KV] = 0.0


@njit(cache=True)
def piston_stage(g, weight, hs):
    """Every piston: the last stage's velocity and acceleration (DR_V, DR_A) added to the
    RK4 sums with `weight` (1, 2, 2, 1), then the piston moved to the next stage, its state
    at the step's start plus hs [s] times them (RK4's s + hs v_i, v + hs a_i)."""
    for k in range(g.drive_target.shape[0]):
        if is_piston(g, k):
            now = g.drive_now[k]
            v = now[DR_V]
            a = now[DR_A]
            now[DR_KS] += weight * v
            now[DR_KV] += weight * a
            now[DR_S] = now[DR_SC] + hs * v
            now[DR_V] = now[DR_VC] + hs * a


@njit(cache=True)
def piston_rk4_end(g, h):
    """Every piston at the RK4 step's end: the fourth stage's (v, a) added to the sums, then
    s = s_n + h/6 (v1 + 2 v2 + 2 v3 + v4), v = v_n + h/6 (a1 + 2 a2 + 2 a3 + a4)."""
    h6 = h / 6.0
    for k in range(g.drive_target.shape[0]):
        if is_piston(g, k):
            now = g.drive_now[k]
            now[DR_KS] += now[DR_V]
            now[DR_KV] += now[DR_A]
            now[DR_S] = now[DR_SC] + h6 * now[DR_KS]
            now[DR_V] = now[DR_VC] + h6 * now[DR_KV]


@njit(cache=True)
def accept_pistons(g):
    """Every piston's state at the last force pass (DR_S, DR_V, DR_A: the accepted trial
    step's end, or t = 0) taken as the state the next RK4 step starts from."""
    for k in range(g.drive_target.shape[0]):
        if is_piston(g, k):
            now = g.drive_now[k]
            now[DR_SC] = now[DR_S]
            now[DR_VC] = now[DR_V]
            now[DR_AC] = now[DR_A]


@njit(cache=True)
def restore_pistons(g):
    """Every piston back at its state at the last accepted step (after a rejected trial
    step, so that what reads DR_S and DR_V between steps sees the accepted state)."""
    for k in range(g.drive_target.shape[0]):
        if is_piston(g, k):
            now = g.drive_now[k]
            now[DR_S] = now[DR_SC]
            now[DR_V] = now[DR_VC]
            now[DR_A] = now[DR_AC]
