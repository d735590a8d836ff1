"""An elastic body in space under the implicit scheme (docs/model.md sections 3.9 and
6.7): its modes advanced exactly for contact forces linear over the step, the granules'
RK4 stages reading the body's motion at t + h/2 and t + h, and the end force found by a
partitioned (staggered) fixed point iterated to convergence within each step.

One step t -> t + h (solver/schemes/implicit.py, `attempt`):
1. the granules' split-off friction's opening half step, then the body's (the same
   exact impulse as velocity Verlet's, solver.body_friction), on the modes' velocities too;
2. the modal contact force F0 = Phi^T F at (y_n, q_n, qd_n) (the force pass of t_n's
   buffer; recomputed after the friction half step, whose velocities its damping reads);
3. the modes over h with f(s) = F0 + (F1 - F0) s/h + L(s) exactly (Newmark above omega h
   = 1, solver.plate_modal's coefficients, as the plane's plate): q, q' at t + h/2 and
   t + h, affine in the guessed end force F1;
4. RK4 of the granules with the body's contact forces (solver.body.contact_forces, the
   residual compliance in series) at each stage's granule state against the surface's
   motion there; the end pass gives F1' = Phi^T F(y_n+1, q_n+1, qd_n+1);
5. F1 <- F1 + omega (F1' - F1), omega by Aitken's delta-squared rule, until
   |F1' - F1| <= iteration_rtol |F| (the max over modes); the closing friction half steps.

Converged, the step is the monolithic one: the body's work is the exact integral of the
linear force against its velocity, the granules' the RK4 quadrature of the same forces,
and eq. (11)'s residual the scheme's own error, which the step control holds.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from granplate.jit import njit

from granplate.model.inputs import GEO_DAMP, GEO_DELTA, GEO_NX, GEO_NY, GEO_NZ, GEO_TOUCH, BodyArrays
from granplate.physics.shock import shock_amplitude
from granplate.solver import body as B
from granplate.solver import body_mindlin as BM
from granplate.solver.body_surface import surface_velocity
from granplate.solver.granular import commit_history
from granplate.solver import mindlin_rk4 as MR
from granplate.solver.granular3d import VX
from granplate.solver.state import PARTNER_BODY
from granplate.solver.plate_modal import (
    MC_IF0,
    MC_IF1,
    MC_IQ,
    MC_IV,
    MC_QF0,
    MC_QF1,
    MC_QQ,
    MC_QV,
    MC_STRIDE,
    MC_VF0,
    MC_VF1,
    MC_VQ,
    MC_VV,
    N_MCOEF,
)

#: columns of BodyStep.flags: the buffer holding t_n's contact state (0 or 1), the
#: last Aitken relaxation factor.
CUR, RELAX = range(2)
#: the first relaxation factor of a step's fixed point (Aitken's rule sets the later ones)
RELAX_FIRST = 1.0
#: bounds of |omega| (Aitken's factor), so that one noisy difference cannot stall or blow it up
RELAX_MIN, RELAX_MAX = 0.02, 2.0
#: columns of BodyStep.sums: the end pass's stored energy [J], viscous power [W], plastic
#: work [J], largest overlap / radius, its granule, Mindlin's power -F_t . v_s [W] and
#: largest sticking rate [1/s]; the springs' committed energy at the step's start [J]
S_EPOT, S_PVISC, S_PLASTIC, S_OVL, S_OVL_I, S_PFRIC, S_RATE, S_SPRING0 = range(8)


class BodyStep(NamedTuple):
    """The implicit scheme's scratch for an elastic body: its modes at the step's start,
    middle and end (rows 0, 1, 2), the fixed point's iterate and last residual, the
    extrapolation's start force, the end pass's accelerations and sums, and the step's
    modal coefficients."""

    qs: np.ndarray  # (3, nm) modal displacement at t, t + h/2, t + h [m kg^1/2]
    qds: np.ndarray  # (3, nm) modal velocity there [m kg^1/2 / s]
    f1: np.ndarray  # (nm,) the end force the modes move with (the iterate) [N kg^-1/2]
    fres: np.ndarray  # (nm,) the last iteration's residual F1' - F1 [N kg^-1/2]
    fprev: np.ndarray  # (nm,) the last accepted step's start force [N kg^-1/2]
    acc: np.ndarray  # (ng, nc) the end pass's accelerations [m/s^2]
    fdamp: np.ndarray  # (ng, nc) the passes' damping forces (not used by this scheme) [N]
    pv: np.ndarray  # (4,) the body contacts' viscous power at the RK4 stages [W]
    pf: np.ndarray  # (4,) their Mindlin springs' power -F_t . v_s at the RK4 stages [W]
    sums: np.ndarray  # (8,) the end pass's S_* values, the springs' start energy
    flags: np.ndarray  # (2,) CUR, RELAX
    mc: np.ndarray  # (nm, N_MCOEF) the step's modal coefficients (solver.plate_modal)


def new_body_step(ng: int, nm: int, nc: int) -> BodyStep:
    """A BodyStep for ng granules of nc state columns and nm modes."""
    z = np.zeros
    flags = z(2)
    flags[RELAX] = RELAX_FIRST
    return BodyStep(
        qs=z((3, nm)),
        qds=z((3, nm)),
        f1=z(nm),
        fres=z(nm),
        fprev=z(nm),
        acc=z((ng, nc)),
        fdamp=z((ng, nc)),
        pv=z(4),
        pf=z(4),
        sums=z(8),
        flags=flags,
        mc=z((nm, N_MCOEF)),
    )


@njit(cache=True)
def load_amplitudes(t, h, cfg):
    """The body's line load amplitude q0 f(t) at the step's start and end [N/m] (0, 0
    when the shock acts on the granules)."""
    if not cfg.load_on_plate:
        return 0.0, 0.0
    return shock_amplitude(t, cfg), shock_amplitude(t + h, cfg)


@njit(cache=True)
def modal_stages(t, h, b, bs, cfg):
    """The modes at t + h/2 and t + h (rows 1, 2 of bs.qs, bs.qds) from row 0 under the
    force F0 + (F1 - F0) s/h + L(s): F0 = b.fmodal[CUR], F1 = bs.f1, L the line load's
    projection linear between its amplitudes, plus the body's own weight, constant
    (b.weight: zeros without gravity; docs/model.md sections 3.11 and 6.7)."""
    cur = int(bs.flags[CUR])
    amp0, amp1 = load_amplitudes(t, h, cfg)
    for m in range(bs.qs.shape[1]):
        f0 = b.fmodal[cur, m] + amp0 * b.load[m] + b.weight[m]
        f1 = bs.f1[m] + amp1 * b.load[m] + b.weight[m]
        q0 = bs.qs[0, m]
        v0 = bs.qds[0, m]
        c = bs.mc[m]
        for j in range(2):
            base = j * MC_STRIDE
            bs.qs[j + 1, m] = (
                c[base + MC_QQ] * q0 + c[base + MC_QV] * v0 + c[base + MC_QF0] * f0 + c[base + MC_QF1] * f1
            )
            bs.qds[j + 1, m] = (
                c[base + MC_VQ] * q0 + c[base + MC_VV] * v0 + c[base + MC_VF0] * f0 + c[base + MC_VF1] * f1
            )


@njit(cache=True)
def pass_at(y, row, buf, b, bs, g, cfg, acc, record):
    """The body's contact forces at granule state y and the modes of row `row` of bs.qs,
    bs.qds into buffer buf (solver.body.contact_forces), their accelerations added to acc;
    with cfg.history_stages Mindlin's law there too, in the RK4 stage the contacts'
    histories stand at (solver.body_mindlin.stage_forces; record: the step's end, its
    trial histories written). Returns (stored energy, the springs' included [J], viscous
    power [W], plastic work [J], largest overlap / radius, its granule, the springs' power
    -F_t . v_s [W], their largest sticking rate [1/s])."""
    ep, _, wp, _, ovl, ovl_i = B.contact_forces(
        y, bs.qs[row], bs.qds[row], b, buf, g.radius, g.mass, cfg.clip, acc, bs.fdamp, True
    )
    e_t = 0.0
    pf = 0.0
    rate = 0.0
    if cfg.history_stages:
        e_t, pf, rate = BM.stage_forces(
            y, bs.qds[row], b, buf, g.radius, g.mass, g.inertia, cfg.arm_shrink, acc, record
        )
    return ep + e_t, damping_power(y, bs.qds[row], b, buf), wp, ovl, ovl_i, pf, rate


@njit(cache=True)
def damping_power(y, qd, b, buf) -> float:
    """The power the contacts' damping forces D dissipate [W]: D times the rate at which
    the granule approaches the modes' surface, (v - v_s) . (-n), the whole of it (the
    residual compliance's share included: its energy is the static force's alone, so the
    damping force's work on the granule and on the modes is all dissipated; velocity
    Verlet books the same as its kicks' work)."""
    g = b.geo[buf]
    power = 0.0
    for i in range(y.shape[0]):
        if g[i, GEO_TOUCH] == 0.0 or g[i, GEO_DELTA] <= 0.0 or g[i, GEO_DAMP] == 0.0:
            continue
        v0, v1, v2 = surface_velocity(b, buf, i, qd)
        rate = -(
            (y[i, VX] - v0) * g[i, GEO_NX] + (y[i, VX + 1] - v1) * g[i, GEO_NY] + (y[i, VX + 2] - v2) * g[i, GEO_NZ]
        )
        power += g[i, GEO_DAMP] * rate
    return power


@njit(cache=True)
def open_step(t, h, y0, split, st, b, bs, g, cfg, k1, p1, fresh) -> float:
    """The step's start: the modes from the state (st.q, st.qd), the body's friction half
    step on y0 and on them (split: the opening half of the split-off friction), the force
    pass at t_n again where the velocities moved (fresh: k1, p1 are the granules' own,
    just recomputed, and gain the body's share; else they are t_n's, the body's in them),
    then the modes' motion over the step (`modal_stages`); Mindlin's springs' stage sums
    begun around that pass (`begin_stages`, `next_stage`). Returns the friction's
    dissipation [J]."""
    cur = int(bs.flags[CUR])
    bs.sums[S_SPRING0] = begin_stages(b, cfg)
    for m in range(bs.qs.shape[1]):
        bs.qs[0, m] = st.q[m]
        bs.qds[0, m] = st.qd[m]
    fric = 0.0
    if split:
        fric = B.friction_flow(y0, bs.qds[0], 0.5 * h, b, cur, g.radius, g.mass, g.inertia, cfg.arm_shrink, True)
    if fresh:
        _, pv, _, _, _, pf, _ = pass_at(y0, 0, cur, b, bs, g, cfg, k1, False)
        p1[1] += pv
        p1[2] += pf
    modal_stages(t, h, b, bs, cfg)
    next_stage(b, cfg, 1.0, 0.5 * h, False)
    return fric


@njit(cache=True)
def stage_pass(y, row, b, bs, g, cfg, acc, stage, weight, tau, final) -> None:
    """An inner RK4 stage's body forces (granule state y, the modes of row `row`) into the
    trial step's buffer, added to the stage's derivative acc; its viscous power into
    bs.pv[stage], its Mindlin springs' into bs.pf[stage], their stage sums moved on
    (`next_stage` with weight, tau, final)."""
    _, pv, _, _, _, pf, _ = pass_at(y, row, 1 - int(bs.flags[CUR]), b, bs, g, cfg, acc, False)
    bs.pv[stage] = pv
    bs.pf[stage] = pf
    next_stage(b, cfg, weight, tau, final)


@njit(cache=True)
def end_pass(y, b, bs, g, cfg) -> None:
    """The end pass at (y_n+1, the modes at t + h) into the trial step's buffer (its
    modal force the fixed point's F1'), the accelerations into bs.acc, the sums into
    bs.sums."""
    for i in range(bs.acc.shape[0]):
        for c in range(bs.acc.shape[1]):
            bs.acc[i, c] = 0.0
    ep, pv, wp, ovl, ovl_i, pf, rate = pass_at(y, 2, 1 - int(bs.flags[CUR]), b, bs, g, cfg, bs.acc, True)
    bs.sums[S_EPOT] = ep
    bs.sums[S_PFRIC] = pf
    bs.sums[S_RATE] = rate
    bs.sums[S_PVISC] = pv
    bs.sums[S_PLASTIC] = wp
    bs.sums[S_OVL] = ovl
    bs.sums[S_OVL_I] = ovl_i


@njit(cache=True)
def close_friction(y, h, b, bs, g, cfg) -> float:
    """The body's closing friction half step at the step's end (the end pass's normal
    forces, on y and the modes' end velocities). Returns its dissipation [J]."""
    buf = 1 - int(bs.flags[CUR])
    return B.friction_flow(y, bs.qds[2], 0.5 * h, b, buf, g.radius, g.mass, g.inertia, cfg.arm_shrink, False)


@njit(cache=True)
def end_sums(b, bs, cfg, w) -> tuple:
    """The end pass's share of the trial step's end values (solver.rk4): its accelerations
    added to w.kend, its viscous power to w.pend[1], its Mindlin springs' to w.pend[2], its
    plastic work to w.dacc[3], its overlap to the largest (w.ovl_new, w.ovl_who) where
    larger. Returns (its stored energy [J], the springs' largest sticking rate [1/s], the
    rise of their energy over the step [J])."""
    for i in range(w.kend.shape[0]):
        for c in range(w.kend.shape[1]):
            w.kend[i, c] += bs.acc[i, c]
    w.pend[1] += bs.sums[S_PVISC]
    w.pend[2] += bs.sums[S_PFRIC]
    w.dacc[3] += bs.sums[S_PLASTIC]
    if bs.sums[S_OVL] > w.ovl_new[0]:
        w.ovl_new[0] = bs.sums[S_OVL]
        w.ovl_who[0] = int(bs.sums[S_OVL_I])
        w.ovl_who[1] = PARTNER_BODY
    return bs.sums[S_EPOT], bs.sums[S_RATE], spring_rise(b, cfg, bs.sums[S_SPRING0])


@njit(cache=True)
def first_guess(h, h_last, b, bs) -> None:
    """The fixed point's first iterate: the start force extrapolated linearly over the
    last two steps (h_last [s]: the last step, 0 before the first)."""
    cur = int(bs.flags[CUR])
    ratio = h / h_last if h_last > 0.0 else 0.0
    for m in range(bs.f1.shape[0]):
        f0 = b.fmodal[cur, m]
        bs.f1[m] = f0 + ratio * (f0 - bs.fprev[m])


@njit(cache=True)
def relax(it, rtol, b, bs) -> bool:
    """One update of the fixed point F1 <- F1 + omega (F1' - F1) after iteration `it`
    (F1' the end pass's modal force), omega by Aitken's rule from the last two
    residuals. Returns whether |F1' - F1| <= rtol max(|F0|, |F1'|) (the max over the
    modes) already held (then F1 is left as the modes moved with)."""
    cur = int(bs.flags[CUR])
    nxt = 1 - cur
    r_max = 0.0
    f_max = 0.0
    num = 0.0
    den = 0.0
    for m in range(bs.f1.shape[0]):
        r = b.fmodal[nxt, m] - bs.f1[m]
        r_max = max(r_max, abs(r))
        f_max = max(f_max, abs(b.fmodal[nxt, m]), abs(b.fmodal[cur, m]))
        dr = r - bs.fres[m]
        num += bs.fres[m] * dr
        den += dr * dr
    if r_max <= rtol * f_max:
        return True
    omega = RELAX_FIRST
    if it > 1 and den > 0.0:
        omega = -bs.flags[RELAX] * num / den
        mag = min(max(abs(omega), RELAX_MIN), RELAX_MAX)
        omega = mag if omega >= 0.0 else -mag
    bs.flags[RELAX] = omega
    for m in range(bs.f1.shape[0]):
        r = b.fmodal[nxt, m] - bs.f1[m]
        bs.fres[m] = r
        bs.f1[m] += omega * r
    return False


@njit(cache=True)
def end_energy(t, h, b, bs, cfg, qn, qdn):
    """The modes at the step's end into qn, qdn; returns (the line load's work over the
    step, exact for its linear interpolation [J], the body's energy at the end: the modes'
    and the residual compliance's [J])."""
    cur = int(bs.flags[CUR])
    amp0, amp1 = load_amplitudes(t, h, cfg)
    work = 0.0
    energy = 0.0
    for m in range(bs.qs.shape[1]):
        q1 = bs.qs[2, m]
        v1 = bs.qds[2, m]
        if cfg.load_on_plate:
            f0 = b.fmodal[cur, m] + amp0 * b.load[m] + b.weight[m]
            f1 = bs.f1[m] + amp1 * b.load[m] + b.weight[m]
            c = bs.mc[m]
            qint = c[MC_IQ] * bs.qs[0, m] + c[MC_IV] * bs.qds[0, m] + c[MC_IF0] * f0 + c[MC_IF1] * f1
            work += b.load[m] * (amp1 * q1 - amp0 * bs.qs[0, m] - (amp1 - amp0) * qint / h)
        qn[m] = q1
        qdn[m] = v1
        energy += 0.5 * (v1 * v1 + b.omega[m] * b.omega[m] * q1 * q1)
    return work, energy + b.static[1 - cur]


@njit(cache=True)
def weight_work(b, bs) -> float:
    """The work of the body's own weight over the step [J]: the constant modal force
    b.weight times the modes' displacement, exactly (0 without gravity)."""
    work = 0.0
    for m in range(bs.qs.shape[1]):
        work += b.weight[m] * (bs.qs[2, m] - bs.qs[0, m])
    return work


@njit(cache=True)
def accept(t, h, b, bs) -> float:
    """The accepted step: its start force kept for the next guess, the contacts'
    histories committed at t + h, the buffers swapped. Returns the residual compliance's
    energy at t + h [J]."""
    cur = int(bs.flags[CUR])
    for m in range(bs.fprev.shape[0]):
        bs.fprev[m] = b.fmodal[cur, m]
    from_buf = 1 - cur
    commit_history(t + h, b.hist, b.coef)
    bs.flags[CUR] = from_buf
    return b.static[from_buf]


def body_step_for(body: BodyArrays, ng: int, nc: int) -> BodyStep:
    """The BodyStep of a run with this body (nm its modes; none: an empty one)."""
    return new_body_step(ng if body.face_nodes.shape[0] > 0 else 0, body.omega.shape[0], nc)


@njit(cache=True)
def stage_work(h6, bs) -> tuple:
    """The body contacts' viscous and Mindlin work at the RK4 step's inner stages 2-4
    (Simpson's weights 2, 2, 1 times h6 = h / 6 [s]; stage 1's powers are in the step's
    first stage sums) [J]."""
    visc = h6 * (2.0 * bs.pv[1] + 2.0 * bs.pv[2] + bs.pv[3])
    fric = h6 * (2.0 * bs.pf[1] + 2.0 * bs.pf[2] + bs.pf[3])
    return visc, fric


@njit(cache=True)
def begin_stages(b, cfg) -> float:
    """`solver.mindlin_rk4.begin_stages` for the body's contacts (with cfg.history_stages):
    their stage sums zero, inside a step. Returns their springs' committed energy [J]."""
    if not cfg.history_stages:
        return 0.0
    return MR.begin_rows(b.hist, b.coef)


@njit(cache=True)
def next_stage(b, cfg, weight, tau, final) -> None:
    """`solver.mindlin_rk4.next_stage` for the body's contacts (with cfg.history_stages)."""
    if cfg.history_stages:
        MR.next_rows(b.hist, b.coef, weight, tau, final)


@njit(cache=True)
def spring_rise(b, cfg, e_start) -> float:
    """The rise of the body contacts' springs' energy over the step [J] (e_start what
    `begin_stages` returned; 0 without Mindlin's law)."""
    if not cfg.history_stages:
        return 0.0
    return MR.energy_rows(b.hist, b.coef) - e_start
