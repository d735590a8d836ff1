"""The rules of [load]: its kind by dimension, target, amplitude, duration and direction."""

from __future__ import annotations

from granplate.errors import ScenarioError
from granplate.setup.fields import finite, positive, string_in
from granplate.setup.scenario import Scenario
from granplate.setup.check_base import _direction, length_scale


#: Load kinds (Load.kind: "line" is 2D, "force" 3D) and targets (Load.target).
LOAD_KINDS: tuple[str, ...] = ("line", "force", "none")
LOAD_KINDS_BY_DIMENSION: dict[int, tuple[str, ...]] = {2: ("line", "none"), 3: ("force", "line", "none")}
LOAD_TARGETS: tuple[str, ...] = ("granules", "plate")


def _check_load(s: Scenario) -> None:
    ld = s.load
    string_in("load.kind", ld.kind, LOAD_KINDS_BY_DIMENSION[s.dimension])
    string_in("load.target", ld.target, LOAD_TARGETS)
    q0 = finite("load.q0", ld.q0, "must be >= 0 (a finite number) [N/m]")
    if not q0 >= 0.0:
        raise ScenarioError("load.q0", ld.q0, "must be >= 0 [N/m]")
    e_max, h = _stiffest_modulus(s), length_scale(s)[0]
    if ld.kind == "line" and not q0 <= e_max * h:
        raise ScenarioError(
            "load.q0",
            ld.q0,
            f"allowed: 0 <= q0 <= E h = {e_max * h:.6g} N/m, E = {e_max:.6g} Pa the "
            f"largest Young's modulus of the granules and plate, h = {h:.6g} m the "
            "smallest length (a granule radius or plate element edge): a larger "
            "line load presses on h harder than E, far beyond Hertz's small "
            "overlaps and linear elasticity",
        )
    positive("load.duration", ld.duration)
    positive("load.length", ld.length)
    finite("load.y0", ld.y0)
    force = finite("load.force", ld.force, "must be >= 0 (a finite number) [N]")
    if not force >= 0.0:
        raise ScenarioError("load.force", ld.force, "must be >= 0 [N]")
    if ld.kind == "force":
        if not force <= e_max * h * h:
            raise ScenarioError(
                "load.force",
                ld.force,
                f"allowed: 0 <= force <= E h^2 = {e_max * h * h:.6g} N, E = {e_max:.6g} Pa "
                f"the largest Young's modulus of the granules, h = {h:.6g} m the "
                "smallest radius: a larger force presses on h^2 harder than E, far "
                "beyond Hertz's small overlaps",
            )
        _direction("load.direction", ld.direction, "[dx, dy, dz]")
        if ld.target != "granules":
            raise ScenarioError("load.target", ld.target, 'a force load acts on granules: use target = "granules"')
    if not isinstance(ld.granules, tuple) or not all(isinstance(x, str) for x in ld.granules):
        raise ScenarioError("load.granules", ld.granules, "must be a list of granule labels")
    labels = {g.label for g in s.granules}
    for i, lab in enumerate(ld.granules):
        if lab not in labels:
            raise ScenarioError(
                f"load.granules[{i}]",
                lab,
                "no granule has this label; labels are: " + ", ".join(g.label for g in s.granules),
            )
    if ld.kind == "force" and not s.granules:
        raise ScenarioError("load.kind", ld.kind, 'a force load needs [[granules]]; use kind = "none"')
    if ld.kind == "line":
        if ld.target == "plate" and s.plate is None:
            raise ScenarioError(
                "load.target",
                ld.target,
                'a load on the plate needs a [plate]; use target = "granules" or kind = "none"',
            )
        if ld.target == "granules" and not s.granules:
            raise ScenarioError(
                "load.target",
                ld.target,
                'a load on the granules needs granules (or a [layout]); use target = "plate" or kind = "none"',
            )


def _stiffest_modulus(s: Scenario) -> float:
    """The largest Young's modulus [Pa] of the granules' and the plate's materials."""
    names = {g.material for g in s.granules} | ({s.plate.material} if s.plate is not None else set())
    return max(s.material(n).E for n in names)
