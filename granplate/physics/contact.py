"""Contact laws of the paper, eqs. (2)-(10), one small pure function each.

Every function is compiled by numba and used as-is by the time loop (granplate.solver);
tests call the very same functions. Units: metres, newtons, seconds, pascals.

Kinematics: the overlap delta and its rate, and the slip rate v_t of eq. (6), for the
three contact kinds (granule-granule, granule-wall, granule-plate through a rigid layer).

Normal force (eq. 2): |N| = A delta^(3/2) + gamma d(delta)/dt with A = 4/3 E* sqrt(R*)
(eq. 3) and gamma = alpha_n sqrt(m* A) delta^(1/4). A contact never pulls: when the
damping term would make the force tensile (a fast separation), the magnitude is clipped
at zero (docs/model.md section 3.2); `clip=False` gives the paper's raw eq. (2) instead.

Friction (eq. 5): |f| = mu |N| tanh(k_s v_t), opposed to the slip rate v_t (eq. 6); on a
sphere it also gives a torque -|f| R (both spheres spin against the slip).
"""

from __future__ import annotations

import math

from granplate.jit import njit


@njit(entry=True, cache=True)
def hertz_coefficient(e_star: float, r_star: float) -> float:
    """A = 4/3 E* sqrt(R*) [N/m^(3/2)], paper eq. (3)."""
    return 4.0 / 3.0 * e_star * math.sqrt(r_star)


@njit(entry=True, cache=True)
def damping_coefficient(alpha_n: float, m_star: float, a: float) -> float:
    """c such that gamma = c delta^(1/4): c = alpha_n sqrt(m* A), paper eq. (3).

    m* = 0 (rigid layer, docs/model.md section 3.4) gives c = 0: no viscous damping.
    """
    return alpha_n * math.sqrt(m_star * a)


#: columns of the coefficient arrays pair_coef, wall_coef, pc_coef (model arrays):
#: Hertz coefficient A [N/m^1.5] (eq. 3), damping coefficient c with gamma = c delta^(1/4)
#: (eq. 3), the contact's law ids (below), friction coefficient mu [-], regularisation k_s
#: [s/m] (eq. 5), and the yield
#: overlap delta_y [m] of the yielding laws (docs/model.md section 3.6, eq. P3; inf under
#: Hertz's law, eq. 2); then the law "johnson"'s (docs/model.md section 3.10; 0 under the
#: other laws): R* Y [N/m], the rate
#: coefficient C [-], 1 / (L rate_ref) [s/m] with L the length that makes the approach speed a
#: strain rate, the hardness ratio h [-], the unloading factor kappa [-] and x_h, the
#: overlap over delta_y where the pressure reaches h Y (eqs. J1-J8); then Mindlin's
#: tangential law (docs/model.md section 3.16, physics.mindlin): 8 G* [Pa], the tangential
#: stiffness per unit contact radius (0 under eq. 5's tanh law, which reads COEF_MU), and
#: its Coulomb coefficient mu [-] (a Mindlin contact's COEF_MU is 0, so that the tanh law's
#: passes skip it) and its tangential damping factor x_t [-] (eta_t = x_t c delta^(1/4)).
#: The law ids (setup.law_registry) are integer values on which the laws dispatch: the
#: normal law (COEF_NLAW: NORMAL_LAW_IDS, physics.laws) and the tangential law (COEF_TLAW:
#: TANGENTIAL_LAW_IDS). No other column selects a law: a Hertz row's COEF_DY is inf (a
#: yield overlap never reached), a tanh row's COEF_KT 0. The columns every force pass reads
#: of every listed contact (A, c, the ids, mu) are the row's first eight numbers, one
#: cache line of 64 bytes: a contact out of touch or under Hertz's law costs the pass one
#: line of its row, not both (docs/benchmarks.md, "Every core in one run").
COEF_A, COEF_C, COEF_NLAW, COEF_TLAW, COEF_MU, COEF_KS, COEF_DY = 0, 1, 2, 3, 4, 5, 6
COEF_SY, COEF_RC, COEF_RL, COEF_H, COEF_KAPPA, COEF_XH = 7, 8, 9, 10, 11, 12
COEF_KT, COEF_MUT, COEF_XT = 13, 14, 15
N_COEF = 16
#: the normal law's own columns, COEF_DY..COEF_XH: the yield overlap (inf for a law that
#: never yields) and six parameters a law reads as it defines them (its `law_columns`)
N_LAW_COLUMNS = COEF_XH - COEF_DY + 1


@njit(cache=True)
def contact_arm(radius: float, delta: float, shrink: float) -> float:
    """Lever arm of the friction force on a sphere [m]: R - shrink delta (shrink = 0: the
    radius, docs/model.md section 3.2; 1/2 between spheres or 1 against a rigid body: the contact point)."""
    return radius - shrink * delta


@njit(entry=True, cache=True)
def pair_overlap(xi: float, yi: float, ri: float, xj: float, yj: float, rj: float):
    """Overlap of spheres i, j, delta = R_i + R_j - |s_j - s_i| [m] (negative: a gap),
    and the unit normal (nx, nz) from i to j. Returns (delta, nx, nz)."""
    dx = xj - xi
    dz = yj - yi
    dist = math.sqrt(dx * dx + dz * dz)
    return ri + rj - dist, dx / dist, dz / dist


#: a squared centre distance beyond (R_i + R_j)^2 (1 + APART_MARGIN) is a gap whatever the
#: rounding of its square root (`pair_apart`).
APART_MARGIN = 1e-9


@njit(cache=True)
def pair_apart(xi: float, yi: float, ri: float, xj: float, yj: float, rj: float) -> bool:
    """Whether spheres i, j are certainly apart (delta < 0 in `pair_overlap`), told from the
    squared distance without its square root: the cheap test that skips the listed pairs
    out of touch. Near touch (within round-off) it says False and pair_overlap decides."""
    dx = xj - xi
    dz = yj - yi
    reach = ri + rj
    return dx * dx + dz * dz > reach * reach * (1.0 + APART_MARGIN)


@njit(cache=True)
def pair_normal_rate(vxi: float, vyi: float, vxj: float, vyj: float, nx: float, nz: float) -> float:
    """Overlap rate d(delta)/dt of spheres i, j [m/s] (the normal part of `pair_rates`)."""
    return -((vxj - vxi) * nx + (vyj - vyi) * nz)


@njit(entry=True, cache=True)
def pair_rates(
    vxi: float, vyi: float, wi: float, vxj: float, vyj: float, wj: float, nx: float, nz: float, ai: float, aj: float
):
    """Overlap rate d(delta)/dt and slip rate v_t (eq. 6) of spheres i, j [m/s].

    t = (-nz, nx); v_t = (v_i - v_j).t + a_i omega_i + a_j omega_j with the arms a_i, a_j.
    """
    ddot = pair_normal_rate(vxi, vyi, vxj, vyj, nx, nz)
    vt = -(vxi - vxj) * nz + (vyi - vyj) * nx + ai * wi + aj * wj
    return ddot, vt


@njit(cache=True)
def wall_overlap(x: float, y: float, r: float, nx: float, nz: float, offset: float) -> float:
    """Overlap of a sphere with the rigid wall {s.n = offset} (n: its outward normal) [m]."""
    return x * nx + y * nz + r - offset


@njit(cache=True)
def wall_rates(vx: float, vy: float, w: float, nx: float, nz: float, a: float):
    """Overlap rate and slip rate v_t (eq. 6) of a sphere on a fixed wall [m/s]."""
    return vx * nx + vy * nz, -vx * nz + vy * nx + a * w


@njit(entry=True, cache=True)
def plate_overlap(x: float, r: float, edge_x: float) -> float:
    """Overlap of a sphere with the plate's rigid layer at x = edge_x (n = (1, 0)) [m]."""
    return x + r - edge_x


@njit(cache=True)
def plate_rates(vx: float, vy: float, w: float, a: float, edge_vx: float, edge_vy: float):
    """Overlap rate and slip rate v_t (eq. 6) against the moving plate edge [m/s]
    (t = (0, 1): v_t = v_y - v_edge,y + a omega)."""
    return vx - edge_vx, vy - edge_vy + a * w


@njit(cache=True)
def hertz_elastic(delta: float, a: float) -> float:
    """Elastic part of the normal force A delta^(3/2) [N]; zero when not in contact."""
    if delta <= 0.0:
        return 0.0
    return a * delta * math.sqrt(delta)


@njit(entry=True, cache=True)
def normal_force(delta: float, delta_dot: float, a: float, c: float, clip: bool):
    """Magnitude of the normal force |N| of eq. (2) and its elastic part [N].

    |N| = A delta^(3/2) + c delta^(1/4) d(delta)/dt for delta > 0, else 0. With clip,
    |N| >= 0 (no tensile force). Returns (N, elastic).
    """
    if delta <= 0.0:
        return 0.0, 0.0
    sq = math.sqrt(delta)
    elastic = a * delta * sq
    n = elastic + c * math.sqrt(sq) * delta_dot
    if clip and n < 0.0:
        n = 0.0
    return n, elastic


@njit(entry=True, cache=True)
def friction_magnitude(n_abs: float, v_t: float, mu: float, k_s: float) -> float:
    """Signed friction mu |N| tanh(k_s v_t) [N], eq. (5); the force on i is minus this along t."""
    return mu * n_abs * math.tanh(k_s * v_t)


@njit(cache=True)
def contact_energy(delta: float, a: float) -> float:
    """Elastic energy stored in a Hertz contact, 2/5 A delta^(5/2) [J] (eq. 9)."""
    if delta <= 0.0:
        return 0.0
    return 0.4 * a * delta * delta * math.sqrt(delta)


@njit(cache=True)
def viscous_power(n: float, elastic: float, delta_dot: float) -> float:
    """Power dissipated by the damping part of the applied normal force [W].

    (|N| - A delta^(3/2)) d(delta)/dt: gamma (d delta/dt)^2 when not clipped, and exact
    (still >= 0) when the force is clipped at zero during a fast separation.
    """
    return (n - elastic) * delta_dot


@njit(cache=True)
def friction_power(f: float, v_t: float) -> float:
    """Power dissipated by friction, f v_t = mu |N| tanh(k_s v_t) v_t >= 0 [W]."""
    return f * v_t


@njit(cache=True)
def normal_force_slopes(delta: float, a: float, c: float):
    """dN/d(delta) = 3/2 A delta^(1/2) [N/m] and dN/d(delta rate) = c delta^(1/4) [N s/m]
    of eq. (2) in touch (delta > 0)."""
    sq = math.sqrt(delta)
    return 1.5 * a * sq, c * math.sqrt(sq)


@njit(cache=True)
def friction_slope(n_abs: float, v_t: float, mu: float, k_s: float) -> float:
    """d f / d v_t = mu k_s |N| / cosh^2(k_s v_t) [N s/m], the slope of eq. (5) that
    criterion (8) multiplies by the step and the compliance."""
    ch = math.cosh(k_s * v_t)
    return mu * n_abs * k_s / (ch * ch)


#: beyond this |k_s v_t| sinh(k_s v_t) is handled through its logarithm (no overflow).
_SINH_LOG = 20.0


@njit(cache=True)
def slip_after_friction(v_t: float, n_abs: float, mu: float, k_s: float, inv_mass_t: float, dt: float) -> float:
    """Slip rate [m/s] after friction alone has acted for dt [s] at one contact: the exact
    solution of d v_t/dt = -m_t^-1 mu |N| tanh(k_s v_t) (eq. 5 on the tangential inverse
    mass m_t^-1 [1/kg], |N| held), sinh(k_s v_t) = sinh(k_s v_t,0) exp(-mu k_s |N| m_t^-1 dt).

    Decays monotonically towards 0 without changing sign, for any dt (stable however stiff
    the friction is); in gross slip (|k_s v_t| >> 1) v_t falls by mu |N| m_t^-1 dt, in
    stick it relaxes exponentially at the rate of `friction_slope` times m_t^-1.
    """
    x = k_s * v_t
    decay = mu * k_s * n_abs * inv_mass_t * dt
    if x == 0.0 or decay <= 0.0:
        return v_t
    ax = abs(x)
    if ax < _SINH_LOG:
        return math.copysign(math.asinh(math.sinh(ax) * math.exp(-decay)), x) / k_s
    z = ax - decay  # log(2 sinh(ax) e^-decay) up to e^(-2 ax)
    if z > _SINH_LOG:
        return math.copysign(z, x) / k_s  # asinh(e^z / 2) = z up to e^(-2 z)
    return math.copysign(math.asinh(0.5 * math.exp(z)), x) / k_s


@njit(cache=True)
def local_map_modulus(slope: float, dt: float, c_t: float) -> float:
    """|lambda| of the frictional local map at a plate contact, paper eq. (8):
    1/2 (d f / d v_t) dt c_t, with the friction law's slope d f / d v_t [N s/m] (eq. 5's:
    `friction_slope`; physics.laws.tangential_slopes) and step dt [s].

    c_t: the tangential driving DOF's diagonal entry of (M + dt^2 K / 4)^-1 [1/kg].
    """
    return 0.5 * slope * dt * c_t


@njit(cache=True)
def normal_response(delta: float, delta_dot: float, a: float, c: float, clip: bool):
    """The normal law of one contact in touch (delta > 0), eqs. (2)-(3) and (9)-(10), without
    friction: (|N| [N], viscous power [W], stored energy [J]), as `contact_response` gives them."""
    n, el = normal_force(delta, delta_dot, a, c, clip)
    return n, viscous_power(n, el, delta_dot), contact_energy(delta, a)


@njit(cache=True)
def contact_response(delta: float, delta_dot: float, v_t: float, a: float, c: float, mu: float, k_s: float, clip: bool):
    """The whole law of one contact in touch (delta > 0), eqs. (2)-(5) and (9)-(10).

    Returns (|N|, signed friction f, viscous power, friction power, stored energy);
    the force on the first body is -|N| n - f t and its torque -f R.
    """
    n, el = normal_force(delta, delta_dot, a, c, clip)
    f = friction_magnitude(n, v_t, mu, k_s)
    return n, f, viscous_power(n, el, delta_dot), friction_power(f, v_t), contact_energy(delta, a)
