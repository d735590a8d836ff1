"""The rules of [materials.NAME]: elastic constants, density, the yield strength and the
optional fields of the law "johnson" (rate coefficient and reference rate, hardness ratio,
unloading factor).
"""

from __future__ import annotations

from granplate.errors import ScenarioError
from granplate.setup.fields import finite, positive
from granplate.setup.materials import Material
from granplate.setup.scenario import Scenario


#: Largest Young's modulus [Pa] and density [kg/m^3] of a material: about ten times and
#: four times those of the stiffest and the densest solids (diamond, osmium).
E_MAX = 1e13
RHO_MAX = 1e5


def _check_materials(s: Scenario) -> None:
    if not isinstance(s.materials, dict) or not s.materials:
        raise ScenarioError("materials", s.materials, "must be a non-empty table of materials")
    for name, m in s.materials.items():
        p = f"materials.{name}"
        positive(f"{p}.E", m.E)
        if m.E > E_MAX:
            raise ScenarioError(
                f"{p}.E", m.E, f"must be in (0, {E_MAX:g}] Pa (diamond, the stiffest solid, has 1.2e12)"
            )
        finite(f"{p}.nu", m.nu, "must be in (-1, 0.5) (a finite number)")
        if not -1.0 < m.nu < 0.5:
            raise ScenarioError(f"{p}.nu", m.nu, "must be in (-1, 0.5)")
        positive(f"{p}.rho", m.rho)
        if m.Y is not None:  # the yield strength is optional (None: unknown)
            positive(f"{p}.Y", m.Y)
        _check_johnson_fields(p, m)
        if m.rho > RHO_MAX:
            raise ScenarioError(
                f"{p}.rho", m.rho, f"must be in (0, {RHO_MAX:g}] kg/m^3 (osmium, the densest solid, has 22,590)"
            )


#: Allowed ranges of the law "johnson"'s material fields (docs/model.md section 3.10):
#: C in [0, 1]; hardness_ratio in [1.5, 4] (above the cavity pressure where the law's bridge
#: ends, 1.24; measured metals 2.6-3); unloading_factor in (0, 0.5] (beyond, the residual overlap of a contact just past yield
#: would fall below zero).
RATE_COEFFICIENT_MAX = 1.0
HARDNESS_RATIO_RANGE = (1.5, 4.0)
UNLOADING_FACTOR_MAX = 0.5


def _check_johnson_fields(p: str, m: Material) -> None:
    """A material's optional fields of the law "johnson": C and rate_ref both or neither."""
    if m.C is not None:
        finite(f"{p}.C", m.C)
        if not 0.0 <= m.C <= RATE_COEFFICIENT_MAX:
            raise ScenarioError(
                f"{p}.C",
                m.C,
                f"must be in [0, {RATE_COEFFICIENT_MAX:g}] (the yield "
                "strength's rate coefficient, Y(rate) = Y [1 + C ln(rate / rate_ref)])",
            )
        if m.rate_ref is None:
            raise ScenarioError(
                f"{p}.rate_ref",
                None,
                f"missing: {p}.C = {m.C!r} needs the reference strain rate rate_ref [1/s] (give both or neither)",
            )
    if m.rate_ref is not None:
        positive(f"{p}.rate_ref", m.rate_ref)
        if m.C is None:
            raise ScenarioError(
                f"{p}.C",
                None,
                f"missing: {p}.rate_ref = {m.rate_ref!r} needs the rate coefficient C (give both or neither)",
            )
    if m.hardness_ratio is not None:
        lo, hi = HARDNESS_RATIO_RANGE
        finite(f"{p}.hardness_ratio", m.hardness_ratio)
        if not lo <= m.hardness_ratio <= hi:
            raise ScenarioError(
                f"{p}.hardness_ratio",
                m.hardness_ratio,
                f"must be in [{lo:g}, {hi:g}] (the fully plastic mean pressure over Y; Tabor's metals: 2.8)",
            )
    if m.unloading_factor is not None:
        finite(f"{p}.unloading_factor", m.unloading_factor)
        if not 0.0 < m.unloading_factor <= UNLOADING_FACTOR_MAX:
            raise ScenarioError(
                f"{p}.unloading_factor",
                m.unloading_factor,
                f"must be in (0, {UNLOADING_FACTOR_MAX:g}] (the elastic unloading span's factor; Hertz's 3/4 "
                "would leave a negative residual overlap just past yield)",
            )
