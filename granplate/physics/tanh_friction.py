"""The paper's friction law, eq. (5)'s regularised Coulomb law f = mu |N| tanh(k_s v_t), as a
registered tangential law: the interface every rate law (a tangential law without history,
whose force follows from |N| and the slip rate) gives physics.laws (docs/architecture.md,
"Adding a tangential law"). The law itself is physics.contact's (`friction_magnitude`,
`slip_after_friction`); here it takes the common arguments: |N| [N], the slip rate v_t
[m/s] and the contact's coefficient row `coef` (physics.contact's columns: mu in COEF_MU,
k_s in COEF_KS).
"""

from __future__ import annotations

import numpy as np

from granplate.jit import njit
from granplate.physics.contact import COEF_KS, COEF_MU, friction_magnitude, friction_slope, slip_after_friction


@njit(cache=True, inline="always")
def law_friction(n_abs: float, v_t: float, coef) -> float:
    """Signed friction mu |N| tanh(k_s v_t) [N], eq. (5); on the first body it acts along -t."""
    return friction_magnitude(n_abs, v_t, coef[COEF_MU], coef[COEF_KS])


@njit(cache=True, inline="always")
def law_slopes(n_abs: float, v_t: float, coef):
    """(d f / d|N| [-], d f / d v_t [N s/m]) of eq. (5): mu tanh(k_s v_t) and
    mu |N| k_s / cosh^2(k_s v_t), the slope that criterion (8) and Newton's Jacobian use."""
    mu = coef[COEF_MU]
    k_s = coef[COEF_KS]
    return friction_magnitude(1.0, v_t, mu, k_s), friction_slope(n_abs, v_t, mu, k_s)


@njit(cache=True, inline="always")
def law_relaxed_slip(v_t: float, n_abs: float, coef, inv_mass_t: float, dt: float) -> float:
    """The slip rate [m/s] after the law alone has acted for dt [s] at a contact of
    tangential inverse mass inv_mass_t [1/kg] with |N| held: eq. (5)'s exact flow
    (`slip_after_friction`), what the split friction ("split") applies."""
    return slip_after_friction(v_t, n_abs, coef[COEF_MU], coef[COEF_KS], inv_mass_t, dt)


def law_columns(coef: np.ndarray, compliance: np.ndarray, contact) -> None:
    """The law's columns of the rows `coef`, in place (compliance: each row's 1/G* [1/Pa],
    unused; contact: the scenario's Contact): none beyond mu and k_s (COEF_MU, COEF_KS),
    which every row holds from the contact's settings."""
