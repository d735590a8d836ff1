"""What a plate model costs before it is built: which modal basis a mesh gets, and the
memory and time of building it, so that a plate too large for the machine is refused
with a message instead of crashing (docs/model.md section 4.5).

Two bases (Plate.modes):
- "all": every mode, from a dense generalized eigendecomposition (scipy.linalg.eigh):
  memory ~ DENSE_BYTES_PER_DOF2 n^2, time ~ DENSE_SECONDS_PER_DOF3 n^3 (n reduced dofs);
- "truncated": the modes up to Plate.max_frequency from a sparse shift-invert
  eigensolver plus the static residual compliance at the contacts and over the face's
  dofs (for patch contacts): memory and time about linear in n (one sparse
  factorisation of K_r, a few hundred vectors), plus the dense face compliance,
  FACE_BYTES_PER_DOF2 (2 n_face)^2 (32 x 320: 321 face nodes, 3.3 MB).
"auto" is "all" up to DENSE_DOF_LIMIT reduced dofs (the paper's 4 x 40 mesh has 1,082,
4 x 80 has about 2,200), "truncated" above where the plate supports it (at least one
clamped edge, no load on its edge), else "all".
"""

from __future__ import annotations

import os

from granplate.errors import ScenarioError

#: Plate.modes values.
MODE_CHOICES: tuple[str, ...] = ("auto", "all", "truncated")
#: "auto" uses the dense basis up to this many reduced dofs.
DENSE_DOF_LIMIT = 3000
#: The truncated basis' default cut-off [Hz] (Plate.max_frequency = None).
DEFAULT_MAX_FREQUENCY = 1.0e6
#: Peak memory of the dense eigendecomposition per n^2 [bytes] (dense K, M, the
#: eigenvectors and LAPACK's work space; measured 1.0 GB at n = 4,194).
DENSE_BYTES_PER_DOF2 = 60.0
#: Time of the dense eigendecomposition per n^3 [s] (measured 59 s at n = 4,194 on 2 cores).
DENSE_SECONDS_PER_DOF3 = 8.0e-10
#: Peak memory of the truncated basis per reduced dof [bytes] (sparse K_r, M_r, their
#: factorisation, the Lanczos vectors; an upper bound of the measured values).
TRUNCATED_BYTES_PER_DOF = 40_000.0
#: Time of the truncated basis per reduced dof [s] (an upper bound of the measured values).
TRUNCATED_SECONDS_PER_DOF = 3.0e-3
#: Memory of the truncated basis' face residual compliance per (face dof)^2 [bytes]
#: (one float64 matrix over the 2 n_face face dofs).
FACE_BYTES_PER_DOF2 = 8.0
#: Share of the machine's physical memory a plate may take.
MEMORY_SHARE = 0.7


def physical_memory() -> float:
    """The machine's physical memory [bytes] (0 when the system does not say)."""
    try:
        return float(os.sysconf("SC_PHYS_PAGES")) * float(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-POSIX
        return 0.0


def basis_kind(modes: str, n_red: int, supported: bool = True) -> str:
    """The basis a plate of n_red reduced dofs gets: "all" or "truncated" (supported:
    whether the plate allows the truncated one, see the module docstring)."""
    if modes == "auto":
        return "truncated" if n_red > DENSE_DOF_LIMIT and supported else "all"
    return modes


def truncation_supported(clamped_edges, edge_load: bool) -> bool:
    """Whether a plate with these clamped edges and (edge_load) a load on its edge can
    take the truncated basis: its static correction needs a clamped plate and covers the
    contact forces only."""
    return bool(clamped_edges) and not edge_load


def build_estimate(kind: str, n_red: int, n_face: int = 0) -> tuple[float, float]:
    """(peak memory [bytes], time [s]) of building a basis of `kind` for n_red dofs
    (n_face: the face's nodes, whose residual compliance the truncated basis keeps)."""
    if kind == "all":
        return DENSE_BYTES_PER_DOF2 * n_red**2, DENSE_SECONDS_PER_DOF3 * n_red**3
    return (
        TRUNCATED_BYTES_PER_DOF * n_red + FACE_BYTES_PER_DOF2 * (2 * n_face) ** 2,
        TRUNCATED_SECONDS_PER_DOF * n_red,
    )


def check_fits(kind: str, n_red: int, modes: str, memory: float | None = None, n_face: int = 0) -> None:
    """ScenarioError (field plate.modes) when building the basis would not fit in memory
    (memory [bytes], None: MEMORY_SHARE of the machine's physical memory; n_face: see
    build_estimate)."""
    if memory is None:
        memory = MEMORY_SHARE * physical_memory()
    need, seconds = build_estimate(kind, n_red, n_face)
    if memory <= 0.0 or need <= memory:
        return
    hint = (
        'use plate.modes = "truncated" (or "auto"), or fewer elements (plate.nx, plate.ny)'
        if kind == "all"
        else "use fewer elements (plate.nx, plate.ny)"
    )
    raise ScenarioError(
        "plate.modes",
        modes,
        f"the {kind!r} modal basis of this plate ({n_red} reduced dofs) needs about "
        f"{need / 1e9:.3g} GB and {seconds:.3g} s to build; this machine allows "
        f"{memory / 1e9:.3g} GB; {hint}",
    )
