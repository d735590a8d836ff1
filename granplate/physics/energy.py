"""The energy balance of the coupled system, paper eq. (11):

    E_p + E_g + D_visc + D_fric + D_plastic = E_in,   E_in = E(0) + E_shock,

judged relative to a scale (the largest E_in met so far). The stored energies are eqs.
(9)-(10) (contact.contact_energy, the granules' and the plate's kinetic energies); D_plastic is
the plastic work of yielding contacts (docs/model.md section 3.6, eq. P10), zero under Hertz's law.
"""

from __future__ import annotations

from granplate.jit import njit


@njit(cache=True)
def energy_total(e_granular: float, e_plate: float, d_visc: float, d_fric: float, d_plastic: float) -> float:
    """Left side of eq. (11): E_g + E_p + D_visc + D_fric + D_plastic [J]."""
    return e_granular + e_plate + d_visc + d_fric + d_plastic


@njit(cache=True)
def energy_residual(total: float, e_in: float, scale: float) -> float:
    """Relative residual of eq. (11), (E_g + E_p + D - E_in) / scale [-]."""
    return (total - e_in) / scale
