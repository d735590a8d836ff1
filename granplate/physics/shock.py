"""The half-sine shock of docs/model.md section 5 (paper Fig. 2c, d).

q(y, t) = q0 sin(pi t / T) sin(pi (y - y0) / L) on 0 <= t <= T and y0 <= y <= y0 + L.
On granules the line load pushes +x on the left surface of each loaded granule over
[y_i - R_i, y_i + R_i]: F_i = int q dy and tau_i = -int (y - y_i) q dy (closed forms
below). On the bare plate the same q acts on the left edge as consistent nodal forces
(plate.py).
"""

from __future__ import annotations

import math

import numpy as np
from granplate.jit import njit


@njit(cache=True)
def time_profile(t: float, duration: float) -> float:
    """sin(pi t / T) for 0 <= t <= T, else 0 [-]."""
    if t < 0.0 or t > duration:
        return 0.0
    return math.sin(math.pi * t / duration)


@njit(cache=True)
def shock_amplitude(t: float, cfg) -> float:
    """The shock's amplitude at t [s]: cfg.q0 (its peak, [N/m] on a line, [N] as a total
    force) times the half-sine `time_profile` of cfg.duration; the one call every kernel
    makes for it."""
    return cfg.q0 * time_profile(t, cfg.duration)


def _primitives(u: float, y0: float, yc: float, length: float) -> tuple[float, float]:
    """Antiderivatives in u = pi (y - y0) / L of sin(u) dy and (y - yc) sin(u) dy."""
    s = length / math.pi
    f = -s * math.cos(u)
    m = s * ((y0 - yc) * (-math.cos(u)) + s * (math.sin(u) - u * math.cos(u)))
    return f, m


def granule_resultants(yc: float, radius: float, y0: float, length: float) -> tuple[float, float]:
    """Force and torque per unit q0 on a granule of centre yc and radius R [m, m^2].

    F/q0 = int sin(pi (y - y0)/L) dy and tau/q0 = -int (y - yc) sin(...) dy over
    [yc - R, yc + R] intersected with [y0, y0 + L]. Zero when they do not intersect.
    """
    a = max(yc - radius, y0)
    b = min(yc + radius, y0 + length)
    if b <= a:
        return 0.0, 0.0
    ua = math.pi * (a - y0) / length
    ub = math.pi * (b - y0) / length
    fa, ma = _primitives(ua, y0, yc, length)
    fb, mb = _primitives(ub, y0, yc, length)
    return fb - fa, -(mb - ma)


def shock_resultants(
    y: np.ndarray, radius: np.ndarray, loaded: np.ndarray, y0: float, length: float
) -> tuple[np.ndarray, np.ndarray]:
    """Per-granule force and torque per unit q0 (arrays of shape (n_granules,)).

    `loaded` is a boolean mask of the granules that take the load (column 1).
    """
    force = np.zeros(len(y))
    torque = np.zeros(len(y))
    for i in np.flatnonzero(loaded):
        force[i], torque[i] = granule_resultants(float(y[i]), float(radius[i]), y0, length)
    return force, torque


def total_impulse(q0: float, duration: float, length: float) -> float:
    """Impulse of the whole shock, q0 (2L/pi)(2T/pi) [N s]."""
    return q0 * (2.0 * length / math.pi) * (2.0 * duration / math.pi)
