"""What a solid costs before it is built: its dofs, the fill of its factorisation, its
mode count below the cut-off, and from them the peak memory and the set-up time, so that
a body too large for the machine is refused with the numbers and what to change.

Model (constants calibrated on the hex20 plates of `granplate bench --solid`, 2 cores):
- fill of one LU (solid.factor): FILL_PER_DOF_SEP n s entries, s the dofs of the largest
  nested-dissection separator (a cross-section normal to the longest side);
- memory: LU_COPIES factorisations of BYTES_PER_ENTRY each, the Krylov and mode vectors
  (3 WINDOW n + n_modes n floats);
- time: per window one factorisation (FACTOR_SECONDS n s^2) and SOLVES_PER_VALUE solves per
  eigenvalue asked (SOLVE_SECONDS per LU entry each); the residual compliance over n_s
  dofs: one more factorisation with those dofs last, whose dense trailing block and its
  inverse cost DENSE_SECONDS n_s^3 and DENSE_BYTES n_s^2.
The mode count is a Weyl estimate: a plate's flexural and in-plane modes over the two
larger sides and the body's volume modes, an upper bound of what was measured (130
against 107 on the 100 x 100 x 5 mm plate below 100 kHz).

Against `granplate bench --solid` (docs/benchmarks.md, "3D solids"): on the 50,895-dof
plate the estimate is an upper bound (time 138 s and 175 s against 78 s and 111 s
measured, memory 2.5 GB and 3.7 GB against 1.8 GB and 3.2 GB, without and with the
residual compliance); on meshes of about 10,000 dofs it is about half the measured time
(fixed costs dominate there), which no refusal depends on.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from granplate.errors import ScenarioError

FILL_PER_DOF_SEP = 1.6
BYTES_PER_ENTRY = 12.0
LU_COPIES = 2.5
FACTOR_SECONDS = 2.5e-10
SOLVE_SECONDS = 4.0e-9
DENSE_SECONDS = 2.5e-10
DENSE_BYTES = 60.0
SOLVES_PER_VALUE = 2.5
#: Share of the machine's physical memory a solid may take.
MEMORY_SHARE = 0.7


class SolidCost(NamedTuple):
    """The estimate: dofs, separator dofs, LU entries, modes, windows, bytes, seconds."""

    n_dofs: int
    separator: int
    fill: float
    n_modes: int
    windows: int
    memory: float
    seconds: float


def box_dofs(elements: tuple[int, int, int], element: str) -> tuple[int, int]:
    """(dofs, separator dofs) of a box of nx x ny x nz elements (before supports)."""
    nx, ny, nz = (int(n) for n in elements)
    if element == "hex20":
        nodes = lambda a, b, c: (
            (a + 1) * (b + 1) * (c + 1) + a * (b + 1) * (c + 1) + (a + 1) * b * (c + 1) + (a + 1) * (b + 1) * c
        )
        plane = lambda b, c: (b + 1) * (c + 1) + b * (c + 1) + (b + 1) * c
    else:  # hex27 and tet10: the triquadratic node lattice
        nodes = lambda a, b, c: (2 * a + 1) * (2 * b + 1) * (2 * c + 1)
        plane = lambda b, c: (2 * b + 1) * (2 * c + 1)
    dims = sorted((nx, ny, nz), reverse=True)
    return 3 * nodes(nx, ny, nz), 3 * plane(dims[1], dims[2])


def mode_count(size: tuple[float, float, float], E: float, nu: float, rho: float, max_omega: float) -> int:
    """Weyl estimate of the modes below max_omega [rad/s] of a body of these sides [m]."""
    h, b, a = sorted(float(s) for s in size)
    area, volume = a * b, a * b * h
    D = E * h**3 / (12.0 * (1.0 - nu**2))
    flexural = area * max_omega / (4.0 * math.pi) * math.sqrt(rho * h / D)
    c_plate = math.sqrt(E / (rho * (1.0 - nu**2)))
    c_shear = math.sqrt(E / (2.0 * rho * (1.0 + nu)))
    c_long = math.sqrt(E * (1.0 - nu) / (rho * (1.0 + nu) * (1.0 - 2.0 * nu)))
    in_plane = area * max_omega**2 / (4.0 * math.pi) * (1.0 / c_plate**2 + 1.0 / c_shear**2)
    volume_modes = volume * max_omega**3 / (6.0 * math.pi**2) * (1.0 / c_long**3 + 2.0 / c_shear**3)
    return int(math.ceil(flexural + in_plane + volume_modes)) + 6


def omega_below(count: float, size: tuple[float, float, float], E: float, nu: float, rho: float) -> float:
    """The angular frequency [rad/s] below which mode_count puts `count` modes (bisection)."""
    lo, hi = 0.0, 1.0
    while mode_count(size, E, nu, rho, hi) < count and hi < 1e15:
        hi *= 2.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if mode_count(size, E, nu, rho, mid) < count else (lo, mid)
    return hi


def estimate(n_dofs: int, separator: int, n_modes: int, n_surface: int, window: int) -> SolidCost:
    """The cost of modes (windows of `window` values) and a residual compliance over
    n_surface dofs of a body of n_dofs dofs (module docstring)."""
    n_modes = min(n_modes, n_dofs)
    fill = FILL_PER_DOF_SEP * n_dofs * separator
    windows = 1 if window >= n_modes else max(1, math.ceil(n_modes / max(1, window // 2)))
    memory = LU_COPIES * BYTES_PER_ENTRY * fill + 8.0 * n_dofs * (3 * window + n_modes) + DENSE_BYTES * n_surface**2
    seconds = windows * (FACTOR_SECONDS * n_dofs * separator**2 + SOLVES_PER_VALUE * window * SOLVE_SECONDS * fill) + (
        n_surface > 0
    ) * (FACTOR_SECONDS * n_dofs * separator**2 + DENSE_SECONDS * float(n_surface) ** 3)
    return SolidCost(n_dofs, separator, fill, n_modes, windows, memory, seconds)


def check_fits(cost: SolidCost, memory: float, seconds: float | None = None, elements: object = "") -> None:
    """ScenarioError (field plate.elements, its value `elements`: the box's, or the mesh
    file's) when the solid would need more than `memory` bytes (or, given, `seconds`), with
    the numbers and what to change."""
    over_memory = memory > 0 and cost.memory > memory
    over_time = seconds is not None and cost.seconds > seconds
    if not (over_memory or over_time):
        return
    raise ScenarioError(
        "plate.elements",
        elements,
        f"this solid ({cost.n_dofs} dofs, about {cost.n_modes} modes in {cost.windows} eigensolver windows, "
        f"{cost.fill / 1e6:.3g} M factor entries) needs about {cost.memory / 1e9:.3g} GB and {cost.seconds:.3g} s "
        f"to build; this machine allows {memory / 1e9:.3g} GB"
        + (f" and {seconds:.3g} s" if seconds is not None else "")
        + "; use fewer elements (plate.elements) or a lower plate.max_frequency",
    )
