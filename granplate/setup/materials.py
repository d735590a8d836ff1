"""Materials and the effective contact properties of paper eq. (4)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Material:
    """An isotropic linear-elastic material.

    E: Young's modulus [Pa]; nu: Poisson ratio [-]; rho: density [kg/m^3];
    Y: yield strength [Pa] (None: unknown). Y enters no elastic law: it says where Hertz
    stops holding (the onset of yield, docs/model.md section 3.6).

    The law "johnson" (docs/model.md section 3.10) reads four more, all optional: C [-] and
    rate_ref [1/s], the yield strength's rate dependence Y(rate) = Y [1 + C ln(rate /
    rate_ref)] (both or neither; None: rate-free); hardness_ratio [-], the fully plastic
    mean pressure over Y (None: DEFAULT_HARDNESS_RATIO); unloading_factor [-], kappa of
    the elastic unloading span (None: DEFAULT_UNLOADING_FACTOR).
    """

    name: str
    E: float
    nu: float
    rho: float
    Y: float | None = None
    C: float | None = None
    rate_ref: float | None = None
    hardness_ratio: float | None = None
    unloading_factor: float | None = None

    @property
    def plane_modulus(self) -> float:
        """E / (1 - nu^2) [Pa]: the effective modulus against a rigid body (eq. 4)."""
        return self.E / (1.0 - self.nu**2)


#: Built-in material library (docs/model.md section 2). The paper gives E, nu and rho but
#: no grade; the yield strengths are those of the grades stated here:
#: - steel: a structural steel, EN 10025-2 S355 (minimum yield strength 355 MPa,
#:   thickness up to 16 mm);
#: - bearing_steel: a through-hardened bearing steel, AISI 52100 / 100Cr6 at about
#:   60 HRC (yield strength about 2.0 GPa, ASM Handbook vol. 1), with the elastic
#:   constants and density of `steel` (within the grade's handbook range) so that the
#:   two differ in Y alone;
#: - ptfe: unfilled PTFE, compressive yield stress at room temperature and quasi-static
#:   rate about 11 MPa (Rae & Dattelbaum 2004, Polymer 45, 7615).
#: - steel_440c, steel_302, aluminium_2017: the three metals of Burgoyne & Daraio's
#:   measured sphere compressions (Phys. Rev. E 89, 032203, 2014), E, nu, rho, Y and the
#:   rate coefficient C as the authors state them, rate_ref = 1e-3 per second (theirs);
#:   hardness_ratio and unloading_factor are the law "johnson"'s defaults (docs/model.md
#:   section 3.10 gives each value's source).
LIBRARY: dict[str, Material] = {
    "steel": Material("steel", E=200e9, nu=0.30, rho=7850.0, Y=355e6),
    "bearing_steel": Material("bearing_steel", E=200e9, nu=0.30, rho=7850.0, Y=2.0e9),
    "ptfe": Material("ptfe", E=0.54e9, nu=0.42, rho=2150.0, Y=11e6),
    "steel_440c": Material("steel_440c", E=200e9, nu=0.30, rho=7650.0, Y=1896e6, C=0.035, rate_ref=1e-3),
    "steel_302": Material("steel_302", E=200e9, nu=0.30, rho=7900.0, Y=600e6, C=0.025, rate_ref=1e-3),
    "aluminium_2017": Material("aluminium_2017", E=76e9, nu=0.30, rho=2700.0, Y=276e6, C=0.003, rate_ref=1e-3),
}

#: The law "johnson"'s fully plastic mean pressure over Y (docs/model.md eq. J4): Tabor's
#: hardness of a non-hardening metal, H = 2.8 Y (Tabor, The Hardness of Metals, 1951).
DEFAULT_HARDNESS_RATIO = 2.8
#: The law "johnson"'s unloading factor kappa (docs/model.md eq. J7; Hertz's value would
#: be 3/4), fitted on one measured curve, Burgoyne & Daraio's 440C record at 12.5 psi
#: (docs/validation.md, "Yielding spheres against measurement").
DEFAULT_UNLOADING_FACTOR = 0.40


def effective_modulus(a: Material, b: Material | None) -> float:
    """E* of eq. (4) [Pa]; b = None is a rigid body (wall, rigid layer)."""
    inv = (1.0 - a.nu**2) / a.E
    if b is not None:
        inv += (1.0 - b.nu**2) / b.E
    return 1.0 / inv


def softer_yield_strength(a: Material, b: Material | None) -> float | None:
    """Y of the body that yields first at a contact of a and b [Pa]: min(Y_a, Y_b);
    b = None is a rigid body (wall, rigid layer), which never yields: Y_a. None when a
    Y that matters is unknown."""
    if b is None:
        return a.Y
    if a.Y is None or b.Y is None:
        return None
    return min(a.Y, b.Y)


def softer_material(a: Material, b: Material | None) -> Material:
    """The body that yields first at a contact of a and b: the one with the smaller Y
    (a on a tie); b = None is a rigid body: a. Both Y known (validation's rule)."""
    if b is None or a.Y is None or b.Y is None or a.Y <= b.Y:
        return a
    return b


def sphere_mass(radius: float, rho: float) -> float:
    """m = 4/3 pi R^3 rho [kg]."""
    return 4.0 / 3.0 * math.pi * radius**3 * rho


def sphere_inertia(radius: float, rho: float) -> float:
    """I = 2/5 m R^2 [kg m^2] of a solid sphere."""
    return 0.4 * sphere_mass(radius, rho) * radius**2
