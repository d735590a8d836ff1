"""The rules of [load]: the fields every kind has, then each kind's own (`LOAD_RULES`:
its dimensions and checks; model.loads holds its arrays)."""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

from granplate.errors import ScenarioError
from granplate.setup.fields import finite, positive, string_in
from granplate.setup.scenario import Scenario
from granplate.setup.check_base import _direction, length_scale


#: Load targets (Load.target).
LOAD_TARGETS: tuple[str, ...] = ("granules", "plate")


def _check_load(s: Scenario) -> None:
    """The fields every load kind has, then its kind's own rules (`LOAD_RULES`)."""
    ld = s.load
    string_in("load.kind", ld.kind, LOAD_KINDS_BY_DIMENSION[s.dimension])
    string_in("load.target", ld.target, LOAD_TARGETS)
    q0 = finite("load.q0", ld.q0, "must be >= 0 (a finite number) [N/m]")
    if not q0 >= 0.0:
        raise ScenarioError("load.q0", ld.q0, "must be >= 0 [N/m]")
    positive("load.duration", ld.duration)
    positive("load.length", ld.length)
    finite("load.y0", ld.y0)
    force = finite("load.force", ld.force, "must be >= 0 (a finite number) [N]")
    if not force >= 0.0:
        raise ScenarioError("load.force", ld.force, "must be >= 0 [N]")
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
    LOAD_RULES[ld.kind].rules(s)


def _line_rules(s: Scenario) -> None:
    """A line load (model.loads.line): q0 within E h, and the bodies its target needs."""
    ld = s.load
    e_max, h = _stiffest_modulus(s), length_scale(s)[0]
    if not ld.q0 <= e_max * h:
        raise ScenarioError(
            "load.q0",
            ld.q0,
            f"allowed: 0 <= q0 <= E h = {e_max * h:.6g} N/m, E = {e_max:.6g} Pa the "
            f"largest Young's modulus of the granules and plate, h = {h:.6g} m the "
            "smallest length (a granule radius or plate element edge): a larger "
            "line load presses on h harder than E, far beyond Hertz's small "
            "overlaps and linear elasticity",
        )
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


def _force_rules(s: Scenario) -> None:
    """A total force on granules (model.loads.force): within E h^2, along a direction."""
    ld = s.load
    if not s.granules:
        raise ScenarioError("load.kind", ld.kind, 'a force load needs [[granules]]; use kind = "none"')
    e_max, h = _stiffest_modulus(s), length_scale(s)[0]
    if not ld.force <= e_max * h * h:
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


def _no_rules(s: Scenario) -> None:
    """No shock: nothing more to check."""


class LoadRules(NamedTuple):
    """A load kind's dimensions and its own field rules (model.loads holds its arrays)."""

    dimensions: tuple[int, ...]
    rules: Callable[[Scenario], None]


#: Each load kind (Load.kind) by name, in the order error messages list them.
LOAD_RULES: dict[str, LoadRules] = {
    "line": LoadRules((2, 3), _line_rules),
    "force": LoadRules((3,), _force_rules),
    "none": LoadRules((2, 3), _no_rules),
}
LOAD_KINDS: tuple[str, ...] = tuple(LOAD_RULES)
LOAD_KINDS_BY_DIMENSION: dict[int, tuple[str, ...]] = {
    d: tuple(
        sorted((k for k, r in LOAD_RULES.items() if d in r.dimensions), key=lambda k: len(LOAD_RULES[k].dimensions))
    )
    for d in (2, 3)
}


def _stiffest_modulus(s: Scenario) -> float:
    """The largest Young's modulus [Pa] of the granules' and the plate's materials."""
    names = {g.material for g in s.granules} | ({s.plate.material} if s.plate is not None else set())
    return max(s.material(n).E for n in names)
