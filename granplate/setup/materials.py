"""Materials and the effective contact properties of paper eq. (4)."""
from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Material:
    """An isotropic linear-elastic material.

    E: Young's modulus [Pa]; nu: Poisson ratio [-]; rho: density [kg/m^3].
    """

    name: str
    E: float
    nu: float
    rho: float

    @property
    def plane_modulus(self) -> float:
        """E / (1 - nu^2) [Pa]: the effective modulus against a rigid body (eq. 4)."""
        return self.E / (1.0 - self.nu**2)


#: Built-in material library (docs/model.md section 2).
LIBRARY: dict[str, Material] = {
    "steel": Material("steel", E=200e9, nu=0.30, rho=7850.0),
    "ptfe": Material("ptfe", E=0.54e9, nu=0.42, rho=2150.0),
}


def effective_modulus(a: Material, b: Material | None) -> float:
    """E* of eq. (4) [Pa]; b = None is a rigid body (wall, rigid layer)."""
    inv = (1.0 - a.nu**2) / a.E
    if b is not None:
        inv += (1.0 - b.nu**2) / b.E
    return 1.0 / inv


def sphere_mass(radius: float, rho: float) -> float:
    """m = 4/3 pi R^3 rho [kg]."""
    return 4.0 / 3.0 * math.pi * radius**3 * rho


def sphere_inertia(radius: float, rho: float) -> float:
    """I = 2/5 m R^2 [kg m^2] of a solid sphere."""
    return 0.4 * sphere_mass(radius, rho) * radius**2
