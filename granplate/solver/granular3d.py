"""The granular medium in space (docs/model.md section 3.7): the time derivative of every
granule's state (x, y, z, vx, vy, vz, wx, wy, wz) with the contact forces of eqs. (2)-(5)
on the 3D kinematics of physics.space, the friction split off exactly per contact, and the
kinetic energies. The same signatures as solver.granular (the plane), so that the RK4
step and the time loop are the same code (solver.dimension picks the module from the
granular arrays' type). No plate contacts in space yet: the plate arguments are unused.
"""

from __future__ import annotations

from granplate.jit import njit


from granplate.model.inputs import HIST_END, HIST_MAX, HIST_RATE
from granplate.physics.contact import COEF_MU, contact_arm
from granplate.physics.laws import (
    keeps_history,
    normal_law_force,
    normal_law_response,
    normal_law_response_inline,
    tangential_friction,
    tangential_scale,
)
from granplate.physics.shock import shock_amplitude
from granplate.physics.space import (
    arm_torque_3d,
    friction_along_slip,
    normal_rate_3d,
    pair_contact_3d,
    slip_velocity_3d,
    wall_overlap_3d,
)
from granplate.solver.drives import begin_pass, book_wall, finish_pass, wall_motion
from granplate.solver.clearing import clear_overlap, clear_rows
from granplate.solver.granular import ForceSums, commit_overlap, slip_relaxation_rate
from granplate.solver.mindlin_history import mindlin_contact, mindlin_old_force, mindlin_parted, mindlin_touched
from granplate.solver.mindlin_rk4 import space_stages
from granplate.solver.prefetch import PAIRS_AHEAD, prefetch_row

#: state columns of a granule in space
X, Y, Z, VX, VY, VZ, WX, WY, WZ = range(9)
N_STATE = 9


@njit(cache=True)
def _speed(vx, vy, vz):
    return (vx * vx + vy * vy + vz * vz) ** 0.5


@njit(cache=True)
def pair_slip(y, i, j, nx, ny, nz, ai, aj):
    """Overlap rate and slip velocity vector of the pair i, j (n from i to j) [m/s]."""
    rvx = y[i, VX] - y[j, VX]
    rvy = y[i, VY] - y[j, VY]
    rvz = y[i, VZ] - y[j, VZ]
    ddot = normal_rate_3d(rvx, rvy, rvz, nx, ny, nz)
    vs = slip_velocity_3d(
        rvx,
        rvy,
        rvz,
        ai * y[i, WX] + aj * y[j, WX],
        ai * y[i, WY] + aj * y[j, WY],
        ai * y[i, WZ] + aj * y[j, WZ],
        nx,
        ny,
        nz,
    )
    return ddot, vs[0], vs[1], vs[2]


@njit(cache=True)
def wall_slip(y, i, nx, ny, nz, a):
    """Overlap rate and slip velocity vector of granule i on a wall at rest [m/s]."""
    ddot = normal_rate_3d(y[i, VX], y[i, VY], y[i, VZ], nx, ny, nz)
    vs = slip_velocity_3d(y[i, VX], y[i, VY], y[i, VZ], a * y[i, WX], a * y[i, WY], a * y[i, WZ], nx, ny, nz)
    return ddot, vs[0], vs[1], vs[2]


@njit(cache=True)
def add_friction(dy, i, a, nx, ny, nz, fx, fy, fz, sign):
    """Add sign * f and the torque a n x f (sign 1: on i, the first body; -1 keeps the
    torque's sign, the force's reversed: on j, whose torque is a_j n x f_i)."""
    dy[i, VX] += sign * fx
    dy[i, VY] += sign * fy
    dy[i, VZ] += sign * fz
    tx, ty, tz = arm_torque_3d(a, nx, ny, nz, fx, fy, fz)
    dy[i, WX] += tx
    dy[i, WY] += ty
    dy[i, WZ] += tz


@njit(cache=True)
def granular_rhs(t, y, up, vp, g, cfg, dy, fplate, normal, slip, hold, fbar, split=False, record=False):
    """Time derivative dy of the state y (ng, 9) in space: shock, normal forces of every
    listed pair and wall contact (physics.laws, with each contact's history) and, unless
    split, their friction on the slip vector (physics.space). As solver.granular.granular_rhs
    (record: the contacts' end overlaps into HIST_END); returns its ForceSums."""
    begin_derivative(y, dy)
    begin_pass(t, g)
    p_shock = 0.0 if cfg.load_on_plate else shock_derivative(t, y, g, cfg, dy)
    p_visc = 0.0
    p_fric = 0.0
    e_pot = 0.0
    rate = 0.0
    ovl = 0.0
    ovl_i = -1
    ovl_j = -1
    w_plastic = 0.0
    half_shrink = 0.5 * cfg.arm_shrink
    for p in range(g.pair_ij.shape[0]):
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        ri = g.radius[i]
        rj = g.radius[j]
        delta, nx, ny, nz = pair_contact_3d(y[i, X], y[i, Y], y[i, Z], ri, y[j, X], y[j, Y], y[j, Z], rj)
        if record:
            g.pair_hist[p, HIST_END] = max(delta, 0.0)
        if delta <= 0.0:
            continue
        r_min = min(ri, rj)
        if delta > ovl * r_min:
            ovl = delta / r_min
            ovl_i = i
            ovl_j = j
        c = g.pair_coef[p]
        rvx = y[i, VX] - y[j, VX]
        rvy = y[i, VY] - y[j, VY]
        rvz = y[i, VZ] - y[j, VZ]
        n, pv, ep, wp = normal_law_response(
            delta,
            normal_rate_3d(rvx, rvy, rvz, nx, ny, nz),
            c,
            g.pair_hist[p, HIST_MAX],
            g.pair_hist[p, HIST_RATE],
            cfg.clip,
        )
        fnx = n * nx
        fny = n * ny
        fnz = n * nz
        dy[i, VX] -= fnx
        dy[i, VY] -= fny
        dy[i, VZ] -= fnz
        dy[j, VX] += fnx
        dy[j, VY] += fny
        dy[j, VZ] += fnz
        p_visc += pv
        e_pot += ep
        w_plastic += wp
        if split or c[COEF_MU] == 0.0:
            continue
        ai = contact_arm(ri, delta, half_shrink)
        aj = contact_arm(rj, delta, half_shrink)
        vsx, vsy, vsz = slip_velocity_3d(
            rvx,
            rvy,
            rvz,
            ai * y[i, WX] + aj * y[j, WX],
            ai * y[i, WY] + aj * y[j, WY],
            ai * y[i, WZ] + aj * y[j, WZ],
            nx,
            ny,
            nz,
        )
        speed = _speed(vsx, vsy, vsz)
        f_mag = tangential_friction(n, speed, c)
        fx, fy, fz = friction_along_slip(f_mag, speed, vsx, vsy, vsz)
        add_friction(dy, i, ai, nx, ny, nz, fx, fy, fz, 1.0)
        add_friction(dy, j, aj, nx, ny, nz, fx, fy, fz, -1.0)
        p_fric += f_mag * speed
        rate = max(
            rate,
            slip_relaxation_rate(
                n,
                speed,
                c,
                1.0 / g.mass[i] + 1.0 / g.mass[j] + ai * ai / g.inertia[i] + aj * aj / g.inertia[j],
            ),
        )
    p_visc, e_pot, w_plastic, p_fric, rate, ovl, ovl_i, ovl_j = wall_derivative(
        y, g, cfg, dy, split, record, p_visc, e_pot, w_plastic, p_fric, rate, ovl, ovl_i, ovl_j
    )
    if cfg.history_stages:  # Mindlin's law in RK4's stages (solver.mindlin_rk4)
        p_fric, e_pot, rate = space_stages(y, dy, g, cfg, record, p_fric, e_pot, rate)
    accelerations(dy, g)
    p_drive, p_grav = finish_pass(y, dy, g)
    return ForceSums(p_shock, p_visc, p_fric, e_pot, rate, ovl, ovl_i, ovl_j, 0.0, w_plastic, p_drive, p_grav)


@njit(cache=True, inline="always")  # granular_rhs in steps, inlined: no call, no compile of its own
def begin_derivative(y, dy):
    """dy's position columns the velocities of y (ng, 9), its force and torque columns zero."""
    for i in range(y.shape[0]):
        for c in range(3):
            dy[i, c] = y[i, 3 + c]
        for c in range(3, 9):
            dy[i, c] = 0.0


@njit(cache=True, inline="always")  # granular_rhs in steps, inlined: no call, no compile of its own
def shock_derivative(t, y, g, cfg, dy) -> float:
    """The shock's forces and torques on the loaded granules at t [s] added to dy's force
    and torque columns; returns its power [W]."""
    p_shock = 0.0
    amp = shock_amplitude(t, cfg)
    if amp != 0.0:
        for i in range(y.shape[0]):
            for c in range(3):
                f = amp * g.shock_force[i, c]
                tq = amp * g.shock_torque[i, c]
                dy[i, VX + c] += f
                dy[i, WX + c] += tq
                p_shock += f * y[i, VX + c] + tq * y[i, WX + c]
    return p_shock


@njit(cache=True, inline="always")  # granular_rhs in steps, inlined: no call, no compile of its own
def accelerations(dy, g):
    """dy's force and torque columns [N, N m] divided by the masses and inertias."""
    for i in range(dy.shape[0]):
        inv_m = 1.0 / g.mass[i]
        inv_i = 1.0 / g.inertia[i]
        for c in range(3):
            dy[i, VX + c] *= inv_m
            dy[i, WX + c] *= inv_i


@njit(cache=True, inline="always")  # granular_rhs in steps, inlined: no call, no compile of its own
def wall_derivative(y, g, cfg, dy, split, record, p_visc, e_pot, w_plastic, p_fric, rate, ovl, ovl_i, ovl_j):
    """`granular_rhs`'s wall contacts: their normal forces and, unless split, their
    friction into dy, their sums added to those given and the largest overlap kept;
    returns (p_visc, e_pot, w_plastic, p_fric, rate, ovl, ovl_i, ovl_j)."""
    for w in range(g.wall_i.shape[0]):
        i = g.wall_i[w]
        ri = g.radius[i]
        nx = g.wall_geo[w, 0]
        ny = g.wall_geo[w, 1]
        nz = g.wall_geo[w, 2]
        shift, vn, kd = wall_motion(g, w)
        delta = wall_overlap_3d(y[i, X], y[i, Y], y[i, Z], ri, nx, ny, nz, g.wall_geo[w, 3] + shift)
        if record:
            g.wall_hist[w, HIST_END] = max(delta, 0.0)
        if delta <= 0.0:
            continue
        if delta > ovl * ri:
            ovl = delta / ri
            ovl_i = i
            ovl_j = -1 - g.wall_w[w]
        c = g.wall_coef[w]
        ddot = normal_rate_3d(y[i, VX], y[i, VY], y[i, VZ], nx, ny, nz) - vn
        n, pv, ep, wp = normal_law_response(
            delta, ddot, c, g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip
        )
        book_wall(g, w, kd, n, pv / ddot if pv != 0.0 else 0.0)
        dy[i, VX] -= n * nx
        dy[i, VY] -= n * ny
        dy[i, VZ] -= n * nz
        p_visc += pv
        e_pot += ep
        w_plastic += wp
        if split or c[COEF_MU] == 0.0:
            continue
        a = contact_arm(ri, delta, cfg.arm_shrink)
        _, vsx, vsy, vsz = wall_slip(y, i, nx, ny, nz, a)
        speed = _speed(vsx, vsy, vsz)
        f_mag = tangential_friction(n, speed, c)
        fx, fy, fz = friction_along_slip(f_mag, speed, vsx, vsy, vsz)
        add_friction(dy, i, a, nx, ny, nz, fx, fy, fz, 1.0)
        p_fric += f_mag * speed
        rate = max(rate, slip_relaxation_rate(n, speed, c, 1.0 / g.mass[i] + a * a / g.inertia[i]))
    return p_visc, e_pot, w_plastic, p_fric, rate, ovl, ovl_i, ovl_j


@njit(cache=True)
def kinetic_energies(y, mass, inertia, kx=0.0, ky=0.0, kz=0.0, kr=0.0):
    """Kinetic energy of the granules along x, y, z and of their spins [J]: (KE_x, KE_y,
    KE_z, KE_rot), added in granule order to kx, ky, kz, kr (those of granules before these:
    a range's sums carried on)."""
    for i in range(y.shape[0]):
        kx += 0.5 * mass[i] * y[i, VX] * y[i, VX]
        ky += 0.5 * mass[i] * y[i, VY] * y[i, VY]
        kz += 0.5 * mass[i] * y[i, VZ] * y[i, VZ]
        kr += 0.5 * inertia[i] * (y[i, WX] * y[i, WX] + y[i, WY] * y[i, WY] + y[i, WZ] * y[i, WZ])
    return kx, ky, kz, kr


@njit(cache=True)
def force_error(k1, k0, kend, ratio, mass, inertia, radius, sc, err):
    """The implicit scheme's error terms of the granules (as solver.granular.force_error):
    m a and I alpha / R against their linear extrapolation; returns (scale, error) [N]."""
    for i in range(kend.shape[0]):
        for c in range(6):
            m = mass[i] if c < 3 else inertia[i] / radius[i]
            sc = max(sc, m * abs(kend[i, 3 + c]))
            pred = k1[i, 3 + c] + ratio * (k1[i, 3 + c] - k0[i, 3 + c])
            err = max(err, m * abs(kend[i, 3 + c] - pred))
    return sc, err


@njit(cache=True, inline="always")  # per contact: arrays and scalars only
def push_pair(out_i, out_j, i, j, col_i, col_j, s, nx, ny, nz):
    """A pair's force s n [N] (n from i to j) on its granules: minus on i into
    out_i[i, col_i:col_i + 3], plus on j into out_j[j, col_j:col_j + 3]."""
    out_i[i, col_i] -= s * nx
    out_i[i, col_i + 1] -= s * ny
    out_i[i, col_i + 2] -= s * nz
    out_j[j, col_j] += s * nx
    out_j[j, col_j + 1] += s * ny
    out_j[j, col_j + 2] += s * nz


#: columns of a thread's buffer row (solver.blocks' fpar[t, i]) of a granule outside the
#: own rows of the block that wrote it: the damping part of its forces (x, y, z) [N] in BUF_DAMP's; its forces
#: [N] and torques [N m] in the columns they have in the accelerations (VX, WX).
BUF_DAMP = 0
N_BUF = 9


@njit(cache=True, inline="always")
def row_target(acc, fdamp, buf, i, own_lo, own_hi, t_lo, t_hi):
    """Where a pass puts granule i's forces: its own rows [own_lo, own_hi) straight into
    acc and fdamp (damping in column VX), any other into the buffer buf (damping in
    BUF_DAMP), the buffered rows' range [t_lo, t_hi) widened. Returns (the forces' array, the
    damping's, the damping's column, t_lo, t_hi)."""
    if own_lo <= i < own_hi:
        return acc, fdamp, VX, t_lo, t_hi
    return buf, buf, BUF_DAMP, min(t_lo, i), max(t_hi, i + 1)


@njit(cache=True)
def normal_forces(t, y, g, cfg, acc, fdamp, fload, commit_t, forces=True, damp=True, loads=True, divide=True):
    """The velocity-Verlet force pass in space (as solver.granular.normal_forces): shock
    and normal forces of every listed pair and wall contact at state y (no friction), the
    accelerations into acc[:, 3:9], each granule's damping force and shock load apart
    (fdamp, fload [:, 3:9] [N, N m]; the normal forces act through the centres, a line
    load's torques on the spins), the contacts' overlaps into HIST_END (the pairs'
    committed at commit_t [s]; < 0: not). Their rows are cleared first where `forces`,
    `damp`, `loads` (solver.clearing.clear_rows); without `divide`, acc keeps the forces
    and torques [N, N m] (the closing kick divides them: solver.kicks.divide_kick). Returns
    the ForceSums."""
    ng = y.shape[0]
    clear_rows(acc, fdamp, fload, 0, ng, forces, damp, loads)
    begin_pass(t, g)
    p_shock = 0.0
    if not cfg.load_on_plate:
        p_shock = shock_loads(t, y, g, cfg, acc, fload)
    p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j, _, _, _, _, _, _ = pair_forces(
        y, y, 0.0, g, cfg, 0, g.pair_ij.shape[0], acc, fdamp, acc, 0, ng, False, commit_t
    )  # (every granule its own: no buffer)
    p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j = wall_forces(
        y, g, cfg, acc, fdamp, p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j
    )
    if divide:
        for i in range(ng):
            for c in range(3):
                acc[i, VX + c] /= g.mass[i]
                acc[i, WX + c] /= g.inertia[i]
    return ForceSums(p_shock, p_visc, 0.0, e_pot, 0.0, ovl, ovl_i, ovl_j, 0.0, w_plastic, 0.0, 0.0)


@njit(cache=True)
def sensor_loads(y, g, cfg, load):
    """Every granule's sensor reading at state y [N] into load (ng,), as
    solver.granular.sensor_loads in space: half the sum of the normal forces of its
    listed pair and wall contacts (docs/model.md section 3.15)."""
    for i in range(load.shape[0]):
        load[i] = 0.0
    for p in range(g.pair_ij.shape[0]):
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        delta, nx, ny, nz = pair_contact_3d(
            y[i, X], y[i, Y], y[i, Z], g.radius[i], y[j, X], y[j, Y], y[j, Z], g.radius[j]
        )
        if delta <= 0.0:
            continue
        ddot = normal_rate_3d(y[i, VX] - y[j, VX], y[i, VY] - y[j, VY], y[i, VZ] - y[j, VZ], nx, ny, nz)
        n = normal_law_force(delta, ddot, g.pair_coef[p], g.pair_hist[p, HIST_MAX], g.pair_hist[p, HIST_RATE], cfg.clip)
        load[i] += 0.5 * n
        load[j] += 0.5 * n
    for w in range(g.wall_i.shape[0]):
        i = g.wall_i[w]
        nx = g.wall_geo[w, 0]
        ny = g.wall_geo[w, 1]
        nz = g.wall_geo[w, 2]
        shift, vn, _ = wall_motion(g, w)
        delta = wall_overlap_3d(y[i, X], y[i, Y], y[i, Z], g.radius[i], nx, ny, nz, g.wall_geo[w, 3] + shift)
        if delta <= 0.0:
            continue
        ddot = normal_rate_3d(y[i, VX], y[i, VY], y[i, VZ], nx, ny, nz) - vn
        n = normal_law_force(delta, ddot, g.wall_coef[w], g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip)
        load[i] += 0.5 * n


@njit(cache=True)
def shock_loads(t, y, g, cfg, acc, fload):
    """The shock's force and torque on every loaded granule at t (eq. 12 resultants times
    `shock_amplitude`) into fload and added to acc (velocity and spin columns); returns its
    power [W] (0 when the amplitude is 0)."""
    p_shock = 0.0
    amp = shock_amplitude(t, cfg)
    if amp != 0.0:
        for i in range(y.shape[0]):
            for c in range(3):
                f = amp * g.shock_force[i, c]
                tq = amp * g.shock_torque[i, c]
                fload[i, VX + c] = f
                fload[i, WX + c] = tq
                acc[i, VX + c] += f
                acc[i, WX + c] += tq
                p_shock += f * y[i, VX + c] + tq * y[i, WX + c]
    return p_shock


@njit(cache=True)
def wall_forces(y, g, cfg, acc, fdamp, p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j):
    """The velocity-Verlet pass's wall contacts at state y, one after another (a wall's
    load and a driven wall's force are shared sums): their normal forces added to acc and
    their damping parts to fdamp, each contact's overlap into HIST_END, booked on its wall
    and drive; the running sums (viscous power, stored energy, plastic work) and the
    largest overlap continued from the values given. Returns them."""
    for w in range(g.wall_i.shape[0]):
        i = g.wall_i[w]
        ri = g.radius[i]
        nx = g.wall_geo[w, 0]
        ny = g.wall_geo[w, 1]
        nz = g.wall_geo[w, 2]
        shift, vn, kd = wall_motion(g, w)
        delta = wall_overlap_3d(y[i, X], y[i, Y], y[i, Z], ri, nx, ny, nz, g.wall_geo[w, 3] + shift)
        g.wall_hist[w, HIST_END] = max(delta, 0.0)
        if delta <= 0.0:
            continue
        if delta > ovl * ri:
            ovl = delta / ri
            ovl_i = i
            ovl_j = -1 - g.wall_w[w]
        ddot = normal_rate_3d(y[i, VX], y[i, VY], y[i, VZ], nx, ny, nz) - vn
        n, pv, ep, wp = normal_law_response(
            delta, ddot, g.wall_coef[w], g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip
        )
        w_plastic += wp
        p_visc += pv
        e_pot += ep
        acc[i, VX] -= n * nx
        acc[i, VY] -= n * ny
        acc[i, VZ] -= n * nz
        d = 0.0
        if pv != 0.0:
            d = pv / ddot
            fdamp[i, VX] -= d * nx
            fdamp[i, VY] -= d * ny
            fdamp[i, VZ] -= d * nz
        book_wall(g, w, kd, n, d)
    return p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j


@njit(cache=True)
def couple_work(y, i, da, nx, ny, nz, fx, fy, fz, dt):
    """The work [J] over dt [s] of the couple da n x f (da [m], f [N]) on granule i's spin
    at state y."""
    tx, ty, tz = arm_torque_3d(da, nx, ny, nz, fx, fy, fz)
    return dt * (tx * y[i, WX] + ty * y[i, WY] + tz * y[i, WZ])


@njit(cache=True, inline="always")  # per contact: arrays and scalars only
def push_couple(out, i, col, arm, nx, ny, nz, fx, fy, fz):
    """The torque arm n x F [N m] (F on the first body [N]) into out[i, col:col + 3]."""
    tx, ty, tz = arm_torque_3d(arm, nx, ny, nz, fx, fy, fz)
    out[i, col] += tx
    out[i, col + 1] += ty
    out[i, col + 2] += tz


@njit(cache=True)
def pair_forces(yv, yn, h, g, cfg, lo, hi, acc, fdamp, buf, own_lo, own_hi, tangential, commit_t):
    """Listed pairs lo..hi-1 of the velocity-Verlet force pass in space: each pair's normal
    force at state yn (its overlap into HIST_END, committed at commit_t [s] as
    solver.granular.normal_forces says; < 0: not) on its granules (minus on i, plus on j)
    into acc[:, VX:VX + 3], its damping part into fdamp[:, VX:VX + 3]; with `tangential`,
    at the pairs whose tangential law keeps a history (Mindlin's: laws.keeps_history), its
    force from the same overlap and |N| (docs/model.md section 3.16; the slip from yv's
    velocities over h [s]) added to the forces and its torques into acc[:, WX:WX + 3], a
    parted pair's history ended (`mindlin_parted`). Granules outside [own_lo, own_hi) take
    theirs in the buffer buf instead (`row_target`; a block of the threaded passes,
    solver.blocks); the serial pass (`normal_forces`, solver.mindlin_space) owns every
    granule. Returns (viscous power [W], stored energy [J], plastic work [J], the largest
    overlap / smaller radius, its pair (i, j), the springs' energy [J], their losses [J],
    the range [t_lo, t_hi) of the buffer's rows written (empty: t_lo >= t_hi), how many
    of the pairs touch, and how many gave their granules a damping force). Each pair's coefficients are its kind's row (g.kind_coef[g.pair_kind[p]],
    pair_coef[p]'s bits: model.inputs.Granular), a few rows that stay in the cache.

    Written out per contact for speed: a compiled function called per contact with the
    granular arrays (or even a few of them) costs 3-30x this loop (measured on 56,754
    pairs: 0.74 ms per pass written out, 4.4 ms through an inlined per-contact function
    taking four arrays, 28 ms taking the arrays' named tuple). The rows of the second granule
    of the pair PAIRS_AHEAD places on are asked for ahead (solver.prefetch)."""
    p_visc = 0.0
    e_pot = 0.0
    w_plastic = 0.0
    e_t = 0.0
    lost = 0.0
    ovl = 0.0
    ovl_i = -1
    ovl_j = -1
    t_lo = acc.shape[0]
    t_hi = 0
    n_touch = 0
    n_damp = 0
    hist = g.pair_hist
    half_shrink = 0.5 * cfg.arm_shrink
    for p in range(lo, hi):
        if p + PAIRS_AHEAD < hi:  # (the second granule's rows of a pair ahead: solver.prefetch)
            ahead = g.pair_ij[p + PAIRS_AHEAD, 1]
            prefetch_row(yn, ahead)
            prefetch_row(acc, ahead)
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        ri = g.radius[i]
        rj = g.radius[j]
        clear_overlap(hist, p)
        c = g.kind_coef[g.pair_kind[p]]
        delta, nx, ny, nz = pair_contact_3d(yn[i, X], yn[i, Y], yn[i, Z], ri, yn[j, X], yn[j, Y], yn[j, Z], rj)
        kt = tangential and keeps_history(c)
        if delta <= 0.0:
            if kt and mindlin_touched(hist, p):
                lost += mindlin_parted(hist, p, c)
            continue
        hist[p, HIST_END] = delta
        n_touch += 1
        r_min = min(ri, rj)
        if delta > ovl * r_min:
            ovl = delta / r_min
            ovl_i = i
            ovl_j = j
        ddot = normal_rate_3d(yn[i, VX] - yn[j, VX], yn[i, VY] - yn[j, VY], yn[i, VZ] - yn[j, VZ], nx, ny, nz)
        n, pv, ep, wp = normal_law_response_inline(delta, ddot, c, hist[p, HIST_MAX], hist[p, HIST_RATE], cfg.clip)
        if commit_t >= 0.0:
            commit_overlap(commit_t, hist, p, delta, c)
        w_plastic += wp
        p_visc += pv
        e_pot += ep
        fi, di, ci, t_lo, t_hi = row_target(acc, fdamp, buf, i, own_lo, own_hi, t_lo, t_hi)
        fj, dj, cj, t_lo, t_hi = row_target(acc, fdamp, buf, j, own_lo, own_hi, t_lo, t_hi)
        push_pair(fi, fj, i, j, VX, VX, n, nx, ny, nz)
        if pv != 0.0:  # the damping part of |N|, pv / ddot
            push_pair(di, dj, i, j, ci, cj, pv / ddot, nx, ny, nz)
            n_damp += 1
        if kt:  # the history law's force (Mindlin's spring) from the same overlap and |N|
            ai = contact_arm(ri, delta, half_shrink)
            aj = contact_arm(rj, delta, half_shrink)
            _, vsx, vsy, vsz = pair_slip(yv, i, j, nx, ny, nz, ai, aj)
            a = tangential_scale(c, ri * rj / (ri + rj), delta)
            f0x, f0y, f0z = mindlin_old_force(hist, p, c)
            fx, fy, fz, e, dl = mindlin_contact(hist, p, c, a, delta, nx, ny, nz, vsx, vsy, vsz, h, n)
            ti = ai
            tj = aj
            if cfg.lammps_arms:  # LAMMPS's torque arms: their couples' extra work over h is lost from D
                ti = ri - 0.5 * delta
                tj = rj - 0.5 * delta
                dl -= couple_work(yv, i, ti - ai, nx, ny, nz, f0x + fx, f0y + fy, f0z + fz, 0.5 * h)
                dl -= couple_work(yv, j, tj - aj, nx, ny, nz, f0x + fx, f0y + fy, f0z + fz, 0.5 * h)
            e_t += e
            lost += dl
            fi[i, VX] += fx  # (F on i, -F on j)
            fi[i, VX + 1] += fy
            fi[i, VX + 2] += fz
            fj[j, VX] -= fx
            fj[j, VX + 1] -= fy
            fj[j, VX + 2] -= fz
            push_couple(fi, i, WX, ti, nx, ny, nz, fx, fy, fz)
            push_couple(fj, j, WX, tj, nx, ny, nz, fx, fy, fz)
    return p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j, e_t, lost, t_lo, t_hi, n_touch, n_damp
