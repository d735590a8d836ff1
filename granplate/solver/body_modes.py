"""An elastic body's modes in the velocity-Verlet step (docs/model.md section 3.9): the half
kicks by the contact forces and by a load on the body, each with its work, the exact free
vibration of every mode between kicks, and the modal velocity the force pass reads; under the body's own weight (a constant modal
force, model.body_weight) the vibration about the static deflection, exactly, with the
weight's work.
"""

from __future__ import annotations

import math

from granplate.jit import njit


@njit(cache=True)
def kick(qd, fmodal, fdamp, hk) -> float:
    """The modes' half kick qd += hk Phi^T F (hk = h/2 [s]); returns the damping part's
    work [J], hk F_d . (qd_before + qd_after)/2 (as the granules' kicks book theirs)."""
    w = 0.0
    for m in range(qd.shape[0]):
        dv = hk * fmodal[m]
        w += fdamp[m] * hk * (qd[m] + 0.5 * dv)
        qd[m] += dv
    return w


@njit(cache=True)
def load_kick(qd, load, amp, hk) -> float:
    """The modes' half kick by a load on the body, qd += hk amp Phi^T f (load = Phi^T f per
    unit amplitude, amp the amplitude now); returns its work [J], the kinetic energy it
    adds, hk amp load . (qd_before + qd_after)/2 (docs/model.md section 5.3)."""
    w = 0.0
    if amp == 0.0:
        return w
    for m in range(qd.shape[0]):
        dv = hk * amp * load[m]
        w += dv * (qd[m] + 0.5 * dv)
        qd[m] += dv
    return w


@njit(cache=True)
def turn(q, qd, omega, h) -> None:
    """Each mode's free vibration over h [s], exactly: (q, qd) turned by omega h (a rigid-
    body mode, omega = 0, drifts: q += h qd)."""
    for m in range(q.shape[0]):
        om = omega[m]
        if om == 0.0:
            q[m] += h * qd[m]
            continue
        c = math.cos(om * h)
        s = math.sin(om * h)
        q0 = q[m]
        q[m] = c * q0 + s * qd[m] / om
        qd[m] = -om * s * q0 + c * qd[m]


@njit(cache=True)
def predicted_velocity(b, hk, buf) -> None:
    """The modal velocity the force pass reads, qdp = qd + hk Phi^T F_n (the velocity at
    the step's end as the granules' is predicted, v + h/2 a_n; the body's weight is in the
    turn, `turn_weighed`)."""
    for m in range(b.qd.shape[0]):
        b.qdp[m] = b.qd[m] + hk * b.fmodal[buf, m]


@njit(cache=True)
def turn_weighed(q, qd, omega, weight, h) -> float:
    """Each mode's exact motion over h [s] under the constant modal force `weight` (nm,)
    [N kg^-1/2] (the body's own weight, model.body_weight): the free vibration about the
    static deflection q_s = weight / omega^2, so that a mode at rest there stays there to
    round-off; returns the weight's work over h [J], sum weight . (q_after - q_before) (exact:
    the force is constant). A mode without weight turns as in `turn` (a rigid-body mode
    carries none: model.body_weight refuses it)."""
    w = 0.0
    for m in range(q.shape[0]):
        om = omega[m]
        f = weight[m]
        if om == 0.0:
            q[m] += h * qd[m]
            continue
        c = math.cos(om * h)
        s = math.sin(om * h)
        if f == 0.0:
            q0 = q[m]
            q[m] = c * q0 + s * qd[m] / om
            qd[m] = -om * s * q0 + c * qd[m]
            continue
        qs = f / (om * om)
        before = q[m]
        q0 = before - qs
        q[m] = qs + (c * q0 + s * qd[m] / om)
        qd[m] = -om * s * q0 + c * qd[m]
        w += f * (q[m] - before)
    return w
