"""The rules of [precompression] (docs/model.md section 3.12): its target wall, force, mode
(a held wall's mass), tolerance and iterations, and what the static state can be
computed for (the plane's plate through rigid layers, space's elastic solid, the target wall
not driven, a granule near it)."""

from __future__ import annotations

import math

from granplate.errors import ScenarioError
from granplate.setup.drive_checks import piston_mass
from granplate.setup.fields import finite, int_at_least, is_number, positive, string_in
from granplate.setup.geometry import plane_offset, unit
from granplate.setup.scenario import PRECOMPRESSION_MODES, Plate, Scenario

#: The largest precompression force [N] (a kilo-tonne's weight: far past any granular crystal's).
FORCE_MAX = 1e7
#: The residual's relative tolerance: from round-off (1e-14) to a loose 1e-2.
TOLERANCE_RANGE = (1e-14, 1e-2)


def precompression_wall(s: Scenario) -> int:
    """The index of the precompression's target wall in s.walls (the scenario resolved);
    ScenarioError naming `precompression.target` when it is not "wall LABEL" of a wall."""
    p = s.precompression
    assert p is not None
    labels = [w.label for w in s.walls]
    kind, _, label = str(p.target).partition(" ")
    if kind != "wall" or label not in labels:
        named = ", ".join(f'"wall {x}"' for x in labels if x) or "none: give a [[walls]] entry a label"
        raise ScenarioError("precompression.target", p.target, f'must be "wall LABEL" of a labelled wall: {named}')
    return labels.index(label)


def check_precompression(s: Scenario) -> None:
    """[precompression] on the resolved scenario: its fields in range, its wall a labelled and
    undriven one, the plate (if any) the plane's and met through rigid layers (`_check_plate`),
    and some granule within reach of the wall (else the force has nowhere to go)."""
    p = s.precompression
    if p is None:
        return
    f = finite("precompression.force", p.force, f"must be > 0 and <= {FORCE_MAX:g} [N]")
    if not 0.0 < f <= FORCE_MAX:
        raise ScenarioError("precompression.force", p.force, f"must be > 0 and <= {FORCE_MAX:g} [N]")
    string_in("precompression.mode", p.mode, PRECOMPRESSION_MODES)
    positive("precompression.tolerance", p.tolerance)
    tol = float(p.tolerance)
    lo, hi = TOLERANCE_RANGE
    if not lo <= tol <= hi:
        raise ScenarioError(
            "precompression.tolerance", p.tolerance, f"allowed {lo:g} <= tolerance <= {hi:g} (relative)"
        )
    int_at_least("precompression.max_iterations", p.max_iterations, 1)
    _check_mode_mass(s)
    w = precompression_wall(s)
    laws = {s.contact.normal_law} | {pc.normal_law for pc in s.contact.pairs if getattr(pc, "normal_law", None)}
    if laws - {"hertz"}:
        raise ScenarioError(
            "precompression.target",
            p.target,
            "the static state is Hertz's (eq. 9's energy): a scenario with contact.normal_law = "
            f'{sorted(laws - {"hertz"})[0]!r} cannot be precompressed yet; leave out [precompression] or use "hertz"',
        )
    _check_plate(s)
    if any(d.target == p.target for d in s.drives):
        raise ScenarioError("precompression.target", p.target, "is driven by a [[drives]] entry: a wall is either")
    wall = s.walls[w]
    n = unit(tuple(float(c) for c in wall.normal))
    offset = wall.offset if wall.offset is not None else plane_offset(wall.normal, wall.point)
    gaps = [offset - math.fsum(a * b for a, b in zip(_centre(g, s.dimension), n)) - g.radius for g in s.granules]
    if not gaps or min(gaps) > max(g.radius for g in s.granules):
        raise ScenarioError(
            "precompression.target",
            p.target,
            "no granule within a radius of the wall: its force has nowhere to go (move the wall onto the packing)",
        )


def _check_mode_mass(s: Scenario) -> None:
    """mode = "held": its mass 0 (the granules' total) or in range (every scheme integrates
    the piston it makes); "frozen" reads no mass."""
    p = s.precompression
    assert p is not None
    if p.mode == "held":
        if not (is_number(p.mass) and p.mass == 0.0):
            piston_mass("precompression.mass", p.mass)
    elif not (is_number(p.mass) and p.mass == 0.0):
        raise ScenarioError(
            "precompression.mass",
            p.mass,
            'read with mode = "held" only (the held wall\'s mass [kg]); a frozen wall does not move: leave it out',
        )


def _check_plate(s: Scenario) -> None:
    """What the static state holds of a [plate]: the plane's plate, its compliance at the rigid
    layers of the granules on its face nodes at t = 0 (docs/model.md section 3.12); granules
    touching the face between nodes at t = 0 (patch contacts from the start) are refused,
    naming the field. Space's elastic solid holds its contacts wherever they are."""
    from granplate.setup.plate_checks import split_initial_contacts

    if s.plate is None:
        return
    if not isinstance(s.plate, Plate):
        return  # space's elastic solid: its contacts' static compliance (model.body_static)
    between = split_initial_contacts(s)[1]
    if between:
        name = s.granules[between[0]].label or str(between[0] + 1)
        raise ScenarioError(
            "precompression.target",
            s.precompression.target if s.precompression is not None else None,
            f"granule {name} touches the plate's face between nodes at t = 0 (a patch contact): a precompressed "
            "plate is met through rigid layers only, on the face's nodes (plate.ny sets them); move the "
            "granule onto a node or leave out [precompression]",
        )


def _centre(g, dimension: int) -> tuple[float, ...]:
    return (g.x, g.y) if dimension == 2 else (g.x, g.y, g.z)
