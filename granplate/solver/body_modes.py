"""An elastic body's modes in the velocity-Verlet step (docs/model.md section 3.9): the half
kicks by the contact forces and by a load on the body (its own weight too), each with its work, the exact free
vibration of every mode between kicks, and the modal velocity the force pass reads.
"""

from __future__ import annotations

import math

from numba import njit


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
    the step's end as the granules' is predicted, v + h/2 a_n; the body's weight b.weight
    with the contact forces)."""
    for m in range(b.qd.shape[0]):
        b.qdp[m] = b.qd[m] + hk * (b.fmodal[buf, m] + b.weight[m])
