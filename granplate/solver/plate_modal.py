"""The plate in the loop: mass-normalised modes q'' + omega^2 q = Phi_d^T F + L(t),
stepped by Newmark's average acceleration (beta = 1/4, gamma = 1/2) or exactly for
forces linear over the step, and the driving-DOF compliance G(h) of criterion (8).

A truncated basis (p.resid not empty, docs/model.md section 4.5) adds the static
response of the modes it drops at the driving DOFs: u_d = Phi_d q + R F, with energy
1/2 F^T R F; G(h) gains 4 R / h^2. The functions marked "static part" add it; with every
mode kept p.resid is (0, 0) and they add nothing.
"""

from __future__ import annotations

import math

from granplate.jit import njit

from granplate.physics.shock import shock_amplitude


@njit(cache=True)
def edge_load_amplitudes(t, h, cfg):
    """The edge load's amplitude q0 f(t) at the start and end of a step [N/m] (0, 0 when
    the shock acts on the granules)."""
    if not cfg.load_on_plate:
        return 0.0, 0.0
    return shock_amplitude(t, cfg), shock_amplitude(t + h, cfg)


@njit(cache=True)
def step_matrices(h, p, dmode, gmat):
    """For step h: dmode[m] = 1/(1 + h^2 omega_m^2/4) and G(h) = Phi_d diag(dmode) Phi_d^T."""
    nm = p.omega2.shape[0]
    nd = p.phi_d.shape[0]
    for m in range(nm):
        dmode[m] = 1.0 / (1.0 + 0.25 * h * h * p.omega2[m])
    for a in range(nd):
        for b in range(a, nd):
            s = 0.0
            for m in range(nm):
                s += p.phi_d[a, m] * dmode[m] * p.phi_d[b, m]
            gmat[a, b] = s
            gmat[b, a] = s
    # static part: the dropped modes respond quasi-statically, h^2/4 G = R
    for a in range(p.resid.shape[0]):
        for b in range(nd):
            gmat[a, b] += 4.0 * p.resid[a, b] / (h * h)


@njit(cache=True)
def newmark_predict(t, h, st, p, cfg, dmode, qdd_star, astar):
    """Plate predictor: q''* = (f_ext(t+h) - omega^2 (q + h q' + h^2/4 q'')) dmode and
    a* = Phi_d q''*, so that a_n+1 = a* + G(h) F_n+1 at the driving DOFs."""
    nm = p.omega2.shape[0]
    nd = p.phi_d.shape[0]
    amp = 0.0
    if cfg.load_on_plate:
        amp = shock_amplitude(t + h, cfg)
    for m in range(nm):
        qt = st.q[m] + h * st.qd[m] + 0.25 * h * h * st.qdd[m]
        qdd_star[m] = (amp * p.load_modal[m] - p.omega2[m] * qt) * dmode[m]
    for d in range(nd):
        s = 0.0
        for m in range(nm):
            s += p.phi_d[d, m] * qdd_star[m]
        astar[d] = s


@njit(cache=True)
def newmark_correct(t, h, st, p, cfg, dmode, qdd_star, force):
    """Advance every mode with the converged interface forces (Newmark average
    acceleration); returns the work of the edge load over the step (trapezoidal, which
    is exact for this scheme's energy balance) [J]."""
    nm = p.omega2.shape[0]
    nd = p.phi_d.shape[0]
    amp0, amp1 = edge_load_amplitudes(t, h, cfg)
    loaded = amp0 != 0.0 or amp1 != 0.0  # unloaded, every term of the work is 0: skip the sum
    work = 0.0
    for m in range(nm):
        proj = 0.0
        for d in range(nd):
            proj += p.phi_d[d, m] * force[d]
        qdd1 = qdd_star[m] + dmode[m] * proj
        qt = st.q[m] + h * st.qd[m] + 0.25 * h * h * st.qdd[m]
        q1 = qt + 0.25 * h * h * qdd1
        if loaded:
            work += 0.5 * (amp0 + amp1) * p.load_modal[m] * (q1 - st.q[m])
        st.qd[m] += 0.5 * h * (st.qdd[m] + qdd1)
        st.q[m] = q1
        st.qdd[m] = qdd1
    return work


# --- modal integration of the "implicit" scheme ---------------------------------------------
# Each mode is a harmonic oscillator q'' + omega^2 q = f(s) whose force is linear over the
# step, f(s) = f0 + (f1 - f0) s / h (a held friction force has f0 = f1). Every mode's
# state at s = h/2 and s = h is linear in (q0, qd0, f0, f1); mcoef holds, per ladder level
# and mode, the coefficients, for s = h/2 (base 0) and s = h (base MC_STRIDE):
#   q(s) = QQ q0 + QV qd0 + QF0 f0 + QF1 f1,   qd(s) = VQ q0 + VV qd0 + VF0 f0 + VF1 f1,
# and of the integral of q over the step (for the work of the plate's edge load):
#   int q = IQ q0 + IV qd0 + IF0 f0 + IF1 f1.
# Modes with omega h <= EXACT_OMEGA_H are integrated exactly (no period error however
# large the step); the stiffer ones by Newmark's average acceleration, which keeps them
# quasi-static and bounded (their exact response, sampled once per step, would alias).
MC_QQ, MC_QV, MC_QF0, MC_QF1, MC_VQ, MC_VV, MC_VF0, MC_VF1 = range(8)
MC_STRIDE = 8
MC_IQ, MC_IV, MC_IF0, MC_IF1 = 16, 17, 18, 19
N_MCOEF = 20
#: modes with omega h up to this are integrated exactly, stiffer ones by Newmark.
EXACT_OMEGA_H = 1.0


@njit(cache=True)
def sinc(x):
    """sin(x)/x."""
    if abs(x) < 1e-4:
        return 1.0 - x * x / 6.0
    return math.sin(x) / x


@njit(cache=True)
def one_minus_cos_over_x2(x):
    """(1 - cos x)/x^2, without cancellation."""
    sh = sinc(0.5 * x)
    return 0.5 * sh * sh


@njit(cache=True)
def x_minus_sin_over_x3(x):
    """(x - sin x)/x^3, by its series for small x."""
    if abs(x) < 0.1:
        x2 = x * x
        return 1.0 / 6.0 - x2 * (1.0 / 120.0 - x2 * (1.0 / 5040.0 - x2 / 362880.0))
    return (x - math.sin(x)) / (x * x * x)


@njit(cache=True)
def cos_remainder_over_x4(x):
    """(x^2/2 - 1 + cos x)/x^4, by its series for small x."""
    if abs(x) < 0.2:
        x2 = x * x
        return 1.0 / 24.0 - x2 * (1.0 / 720.0 - x2 * (1.0 / 40320.0 - x2 / 3628800.0))
    return (0.5 * x * x - 1.0 + math.cos(x)) / (x * x * x * x)


@njit(cache=True)
def exact_mode_coefficients(h, w2, row):
    """Exact response of q'' + w2 q = f0 + (f1 - f0) s/h (layout: MC_*)."""
    om = math.sqrt(max(w2, 0.0))
    for j in range(2):
        s = 0.5 * h if j == 0 else h
        x = om * s
        sw = s * sinc(x)  # sin(omega s)/omega
        a = s * s * one_minus_cos_over_x2(x)  # (1 - cos)/omega^2
        b = s * s * s * x_minus_sin_over_x3(x) / h  # (s - sw)/(omega^2 h)
        c = math.cos(x)
        base = j * MC_STRIDE
        row[base + MC_QQ] = c
        row[base + MC_QV] = sw
        row[base + MC_QF0] = a - b
        row[base + MC_QF1] = b
        row[base + MC_VQ] = -w2 * sw
        row[base + MC_VV] = c
        row[base + MC_VF0] = sw - a / h
        row[base + MC_VF1] = a / h
    x = om * h
    qa = h * h * h * x_minus_sin_over_x3(x)
    qb = h * h * h * cos_remainder_over_x4(x)
    row[MC_IQ] = row[MC_STRIDE + MC_QV]
    row[MC_IV] = row[MC_STRIDE + MC_QF0] + row[MC_STRIDE + MC_QF1]
    row[MC_IF0] = qa - qb
    row[MC_IF1] = qb


@njit(cache=True)
def newmark_mode_coefficients(h, w2, row):
    """Newmark (beta 1/4, gamma 1/2) for the same oscillator, with the acceleration at
    the start consistent with f0 and the motion inside the step at the constant average
    acceleration (the interpolation of the paper's scheme); the integral of q is the
    trapezoid h (q0 + q1)/2, which makes the edge-load work (L0 + L1)/2 (q1 - q0), the
    work Newmark's energy identity balances (layout: MC_*)."""
    dd = 1.0 / (1.0 + 0.25 * h * h * w2)
    # a1 = qdd at the end; aavg = (qdd0 + qdd1)/2, qdd0 = f0 - w2 q0
    a1_q = -w2 * dd * (1.0 - 0.25 * h * h * w2)
    a1_v = -w2 * dd * h
    a1_f0 = -0.25 * w2 * dd * h * h
    a1_f1 = dd
    m_q = 0.5 * (-w2 + a1_q)
    m_v = 0.5 * a1_v
    m_f0 = 0.5 * (1.0 + a1_f0)
    m_f1 = 0.5 * a1_f1
    for j in range(2):
        s = 0.5 * h if j == 0 else h
        base = j * MC_STRIDE
        hs = 0.5 * s * s
        row[base + MC_QQ] = 1.0 + hs * m_q
        row[base + MC_QV] = s + hs * m_v
        row[base + MC_QF0] = hs * m_f0
        row[base + MC_QF1] = hs * m_f1
        row[base + MC_VQ] = s * m_q
        row[base + MC_VV] = 1.0 + s * m_v
        row[base + MC_VF0] = s * m_f0
        row[base + MC_VF1] = s * m_f1
    hb = 0.5 * h
    row[MC_IQ] = hb * (1.0 + row[MC_STRIDE + MC_QQ])
    row[MC_IV] = hb * row[MC_STRIDE + MC_QV]
    row[MC_IF0] = hb * row[MC_STRIDE + MC_QF0]
    row[MC_IF1] = hb * row[MC_STRIDE + MC_QF1]


@njit(cache=True)
def modal_coefficients(h, omega2, coef):
    """Fill coef (nm, N_MCOEF) for a step h: exact for omega h <= EXACT_OMEGA_H, else
    Newmark."""
    for m in range(omega2.shape[0]):
        if omega2[m] * h * h <= EXACT_OMEGA_H * EXACT_OMEGA_H:
            exact_mode_coefficients(h, omega2[m], coef[m])
        else:
            newmark_mode_coefficients(h, omega2[m], coef[m])


@njit(cache=True)
def exact_matrices(phi_d, coef, mmat):
    """Response of the driving DOFs to the unknown interface forces U over one step.

    mmat[r] (r = u(h/2), v(h/2), u(h), v(h)) = Phi_d diag(c_r) Phi_d^T column by column:
    a normal force (even DOF) is linear over the step and U is its end value (c_r = the
    f1 coefficient); a friction force (odd DOF) is held over the step at U (c_r = the f0
    plus the f1 coefficient).
    """
    nd = phi_d.shape[0]
    nm = phi_d.shape[1]
    for r in range(4):
        base = (r // 2) * MC_STRIDE
        c0 = base + (MC_QF0 if r % 2 == 0 else MC_VF0)
        c1 = base + (MC_QF1 if r % 2 == 0 else MC_VF1)
        for d in range(nd):
            for e in range(nd):
                held = e % 2 == 1
                acc = 0.0
                for m in range(nm):
                    c = coef[m, c1] + (coef[m, c0] if held else 0.0)
                    acc += phi_d[d, m] * c * phi_d[e, m]
                mmat[r, d, e] = acc


@njit(cache=True)
def exact_predict(t, h, st, p, cfg, coef, ustar):
    """Known part of the driving-DOF motion at t + h/2 and t + h: the free
    vibration, the edge load (linear over the step) and the normal forces' start values
    N_n (st.pforce, even DOFs) into ustar (4, nd); the unknowns' share is added by
    stage_motion_exact."""
    nm = p.omega2.shape[0]
    nd = p.phi_d.shape[0]
    amp0, amp1 = edge_load_amplitudes(t, h, cfg)
    for r in range(4):
        for d in range(nd):
            ustar[r, d] = 0.0
    for m in range(nm):
        f0 = amp0 * p.load_modal[m]
        for d in range(0, nd, 2):
            f0 += p.phi_d[d, m] * st.pforce[d]
        f1 = amp1 * p.load_modal[m]
        q0 = st.q[m]
        v0 = st.qd[m]
        for r in range(4):
            base = (r // 2) * MC_STRIDE + (0 if r % 2 == 0 else MC_VQ)
            val = coef[m, base] * q0 + coef[m, base + 1] * v0 + coef[m, base + 2] * f0 + coef[m, base + 3] * f1
            for d in range(nd):
                ustar[r, d] += p.phi_d[d, m] * val
    # static part R F(s) of the normal forces' start values: F(h/2) holds N_n / 2, F(h)
    # none, and dF/ds = (U - N_n)/h
    for d in range(p.resid.shape[0]):
        s0 = 0.0
        for e in range(0, nd, 2):
            s0 += p.resid[d, e] * st.pforce[e]
        ustar[0, d] += 0.5 * s0
        ustar[1, d] -= s0 / h
        ustar[3, d] -= s0 / h


@njit(cache=True)
def static_matrices(h, resid, mmat):
    """Static part of the driving-DOF response to the unknowns U (see exact_matrices),
    added to mmat: u(h/2) gains R U/2 (normal, linear from N_n) or R U (held friction),
    u(h) gains R U, v(h/2) and v(h) gain R U/h (normal) or nothing (held)."""
    nd = resid.shape[0]
    for d in range(nd):
        for e in range(nd):
            held = e % 2 == 1
            r = resid[d, e]
            mmat[0, d, e] += r if held else 0.5 * r
            mmat[2, d, e] += r
            if not held:
                mmat[1, d, e] += r / h
                mmat[3, d, e] += r / h


@njit(cache=True)
def static_energy(resid, force):
    """1/2 F^T R F [J]: the energy of the truncated basis' static part (0 with every mode)."""
    e = 0.0
    for a in range(resid.shape[0]):
        for b in range(resid.shape[0]):
            e += 0.5 * force[a] * resid[a, b] * force[b]
    return e


@njit(cache=True)
def exact_correct(t, h, st, p, cfg, coef, force, qn, qdn):
    """Every mode at the end of the step (into qn, qdn) with the interface forces `force`
    (normal: linear from st.pforce to force; friction: held at force). Returns the work
    of the edge load over the step (exact for its linear interpolation) [J] and the plate
    energy at the end [J]."""
    nm = p.omega2.shape[0]
    nd = p.phi_d.shape[0]
    amp0, amp1 = edge_load_amplitudes(t, h, cfg)
    work = 0.0
    energy = 0.0
    b = MC_STRIDE
    for m in range(nm):
        f0 = amp0 * p.load_modal[m]
        f1 = amp1 * p.load_modal[m]
        for d in range(nd):
            phi = p.phi_d[d, m]
            f1 += phi * force[d]
            f0 += phi * (force[d] if d % 2 == 1 else st.pforce[d])
        q0 = st.q[m]
        v0 = st.qd[m]
        q1 = coef[m, b + MC_QQ] * q0 + coef[m, b + MC_QV] * v0 + coef[m, b + MC_QF0] * f0 + coef[m, b + MC_QF1] * f1
        v1 = coef[m, b + MC_VQ] * q0 + coef[m, b + MC_VV] * v0 + coef[m, b + MC_VF0] * f0 + coef[m, b + MC_VF1] * f1
        if cfg.load_on_plate:
            qint = coef[m, MC_IQ] * q0 + coef[m, MC_IV] * v0 + coef[m, MC_IF0] * f0 + coef[m, MC_IF1] * f1
            work += p.load_modal[m] * (amp1 * q1 - amp0 * q0 - (amp1 - amp0) * qint / h)
        qn[m] = q1
        qdn[m] = v1
        energy += 0.5 * (v1 * v1 + p.omega2[m] * q1 * q1)
    if p.resid.shape[0] > 0:
        energy += static_energy(p.resid, force)
    return work, energy


@njit(cache=True)
def plate_energy(q, qd, force, omega2, resid):
    """E_p = 1/2 q'.q' + 1/2 sum omega^2 q^2 = 1/2 v^T M v + 1/2 x^T K x [J] (eq. 9),
    plus the static part 1/2 F^T R F of a truncated basis. (Arrays, not the state
    tuples: this runs every step.)"""
    e = 0.0
    for m in range(omega2.shape[0]):
        e += 0.5 * (qd[m] * qd[m] + omega2[m] * q[m] * q[m])
    if resid.shape[0] > 0:
        e += static_energy(resid, force)
    return e


@njit(cache=True)
def modal_acceleration(t, st, p, cfg, force):
    """q'' = L(t) + Phi_d^T F - omega^2 q for every mode, into st.qdd (at t = 0)."""
    amp = 0.0
    if cfg.load_on_plate:
        amp = shock_amplitude(t, cfg)
    for m in range(p.omega2.shape[0]):
        proj = 0.0
        for d in range(p.phi_d.shape[0]):
            proj += p.phi_d[d, m] * force[d]
        st.qdd[m] = amp * p.load_modal[m] + proj - p.omega2[m] * st.q[m]


@njit(cache=True)
def driving_dofs(st, p):
    """Displacement, velocity and acceleration of the driving DOFs from the modes
    (Phi_d q, Phi_d q', Phi_d q''), into st.u, st.v, st.a."""
    for d in range(p.phi_d.shape[0]):
        su = 0.0
        sv = 0.0
        sa = 0.0
        for m in range(p.omega2.shape[0]):
            su += p.phi_d[d, m] * st.q[m]
            sv += p.phi_d[d, m] * st.qd[m]
            sa += p.phi_d[d, m] * st.qdd[m]
        for e in range(p.resid.shape[0]):
            su += p.resid[d, e] * st.force[e]  # static part
        st.u[d] = su
        st.v[d] = sv
        st.a[d] = sa
