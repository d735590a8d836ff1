"""Contact kinematics in space (docs/model.md section 3.7): the overlap, its rate and the
slip velocity vector of granule-granule and granule-wall contacts in three dimensions,
and the friction force and torques on that slip vector. One small pure function each,
compiled by numba; the normal laws (eqs. 2-4, the plastic law) and the friction
magnitude (eq. 5) are the dimension-free functions of physics.contact, physics.plastic
and physics.laws.

Notation: n is the unit normal from granule i to its partner (granule j, or into the
wall); the slip velocity at the contact point is

    v_s = (v_i - v_j)_t + (a_i w_i + a_j w_j) x n,      (x)_t = x - (x . n) n,

with the arms a_i, a_j (`contact.contact_arm`); friction on i is
f_i = -mu |N| tanh(k_s |v_s|) v_s / |v_s| and -f_i on j, with torques a_i n x f_i on i and
a_j n x f_i on j. In the plane z = 0 with spins along z this is eq. (6) of the plane:
v_s = v_t t with t = (-n_y, n_x, 0), and the torques are -f a along z.
"""

from __future__ import annotations

import math

from granplate.jit import njit

from granplate.physics.contact import APART_MARGIN


@njit(cache=True)
def pair_overlap_3d(xi, yi, zi, ri, xj, yj, zj, rj):
    """Overlap delta = R_i + R_j - |s_j - s_i| [m] and the unit normal from i to j:
    (delta, nx, ny, nz)."""
    dx = xj - xi
    dy = yj - yi
    dz = zj - zi
    dist = math.sqrt(dx * dx + dy * dy + dz * dz)
    return ri + rj - dist, dx / dist, dy / dist, dz / dist


@njit(cache=True)
def pair_apart_3d(xi, yi, zi, ri, xj, yj, zj, rj) -> bool:
    """Whether spheres i, j are certainly apart (as `contact.pair_apart`, in space)."""
    dx = xj - xi
    dy = yj - yi
    dz = zj - zi
    reach = ri + rj
    return dx * dx + dy * dy + dz * dz > reach * reach * (1.0 + APART_MARGIN)


@njit(cache=True)
def pair_contact_3d(xi, yi, zi, ri, xj, yj, zj, rj):
    """(delta, nx, ny, nz): `pair_overlap_3d` of spheres i, j where they touch (delta > 0),
    the normal scaled by one reciprocal of the distance; where they do not, delta <= 0 and
    a zero normal, without the square root where the squared distance says they are
    certainly apart (`pair_apart_3d`: delta = -inf). The pair loops' one test per listed pair."""
    dx = xj - xi
    dy = yj - yi
    dz = zj - zi
    d2 = dx * dx + dy * dy + dz * dz
    reach = ri + rj
    if d2 > reach * reach * (1.0 + APART_MARGIN):
        return -math.inf, 0.0, 0.0, 0.0
    dist = math.sqrt(d2)
    delta = reach - dist
    if delta <= 0.0:
        return delta, 0.0, 0.0, 0.0
    inv = 1.0 / dist
    return delta, dx * inv, dy * inv, dz * inv


@njit(cache=True)
def wall_overlap_3d(x, y, z, r, nx, ny, nz, offset) -> float:
    """Overlap of a sphere with the plane wall {s.n = offset} (n: its outward unit normal) [m]."""
    return x * nx + y * ny + z * nz + r - offset


@njit(cache=True)
def normal_rate_3d(vx, vy, vz, nx, ny, nz) -> float:
    """Overlap rate d(delta)/dt [m/s] from the relative velocity v_i - v_j (or v against a
    wall at rest) and the normal n from i to its partner."""
    return vx * nx + vy * ny + vz * nz


@njit(cache=True)
def slip_velocity_3d(vx, vy, vz, sx, sy, sz, nx, ny, nz):
    """The slip velocity vector v_s [m/s] at the contact point: the tangential part of the
    relative velocity (vx, vy, vz) = v_i - v_j plus (sx, sy, sz) x n, where s = a_i w_i +
    a_j w_j [m/s] (a_i w_i against a wall). Returns (v_sx, v_sy, v_sz)."""
    vn = vx * nx + vy * ny + vz * nz
    return (vx - vn * nx + sy * nz - sz * ny, vy - vn * ny + sz * nx - sx * nz, vz - vn * nz + sx * ny - sy * nx)


@njit(cache=True)
def friction_vector_3d(f_mag, vsx, vsy, vsz):
    """The friction force on granule i [N]: magnitude f_mag = mu |N| tanh(k_s |v_s|)
    (contact.friction_magnitude with |v_s|) along -v_s / |v_s|; zero without slip."""
    return friction_along_slip(f_mag, math.sqrt(vsx * vsx + vsy * vsy + vsz * vsz), vsx, vsy, vsz)


@njit(cache=True)
def friction_along_slip(f_mag, speed, vsx, vsy, vsz):
    """`friction_vector_3d` with the slip speed |v_s| [m/s] already known (no second square
    root): f_mag along -v_s / speed [N]; zero without slip."""
    if speed == 0.0:
        return 0.0, 0.0, 0.0
    k = -f_mag / speed
    return k * vsx, k * vsy, k * vsz


@njit(cache=True)
def arm_torque_3d(a, nx, ny, nz, fx, fy, fz):
    """The torque a n x f [N m] of the friction force f at arm a along the normal n."""
    return a * (ny * fz - nz * fy), a * (nz * fx - nx * fz), a * (nx * fy - ny * fx)


@njit(cache=True)
def surface_overlap(r, distance, u_n) -> float:
    """Overlap [m] of a sphere of radius r whose centre lies `distance` [m] outside the
    undeformed surface of an elastic body (signed: negative inside) whose surface moved
    u_n [m] along its outward normal at the closest point: r - distance + u_n
    (docs/model.md section 3.8)."""
    return r - distance + u_n
