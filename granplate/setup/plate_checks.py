"""The plate's fields and mesh checked before anything is built: each field in its range,
an even `plate.ny` (a row of nodes on the symmetry line), the plate contacts at t = 0 (on
a left-edge node: a rigid layer; between nodes: a patch contact, where patch contacts are
possible), rigid layers that neither overlap nor reach a clamped node,
`plate.n_modes` at most the number of reduced dofs, and a basis that fits the machine
(setup.plate_cost). Counts come from the mesh's structure alone (docs/model.md section 4),
so no matrix is assembled.

These checks are the only ones: the plate layer (`plate.constraints`, `plate.build`) calls
them on its own inputs and reports their ScenarioError as a PlateError.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from granplate.errors import ScenarioError
from granplate.setup.fields import finite, int_at_least, positive, string_in
from granplate.setup.plate_cost import MODE_CHOICES, basis_kind, check_fits, truncation_supported
from granplate.setup.scenario import Plate, Scenario

#: Relative tolerance (times the plate height / width) for "a point lies on a mesh node".
NODE_RTOL = 1e-9

#: The plate's edges, any subset of which `plate.clamped_edges` may clamp.
PLATE_EDGES: tuple[str, ...] = ("top", "bottom", "left", "right")


def check_plate_fields(p: Plate, x0: float) -> None:
    """Each of the plate's own fields in its range; x0 [m] is the resolved left edge."""
    for f in ("width", "height", "thickness"):
        positive(f"plate.{f}", getattr(p, f))
    finite("plate.x0", x0)
    finite("plate.y0", p.y0)
    int_at_least("plate.nx", p.nx, 1)
    int_at_least("plate.ny", p.ny, 1)
    if p.rigid_layer_width is not None:
        positive("plate.rigid_layer_width", p.rigid_layer_width)
    check_clamped_edges(p)
    int_at_least("plate.n_modes", p.n_modes, 0)
    string_in("plate.modes", p.modes, MODE_CHOICES)
    if p.max_frequency is not None:
        positive("plate.max_frequency", p.max_frequency)
    if p.stress_radius is not None:
        positive("plate.stress_radius", p.stress_radius)
        if p.stress_radius > max(p.width, p.height):
            raise ScenarioError(
                "plate.stress_radius",
                p.stress_radius,
                f"allowed: 0 < r <= max(plate.width, plate.height) = "
                f"{max(p.width, p.height):g} m (a disc larger than the plate "
                "averages over all of it)",
            )


def check_clamped_edges(p: Plate) -> None:
    """`plate.clamped_edges` is a tuple of names from PLATE_EDGES."""
    edges = p.clamped_edges
    if not isinstance(edges, tuple) or not all(isinstance(e, str) and e in PLATE_EDGES for e in edges):
        raise ScenarioError(
            "plate.clamped_edges", edges, "must be a subset of " + ", ".join(repr(e) for e in PLATE_EDGES)
        )


def check_mode_count(p: Plate, n_red: int) -> None:
    """`plate.n_modes` is 0 (all) or at most the n_red reduced dofs."""
    if p.n_modes > n_red:
        raise ScenarioError("plate.n_modes", p.n_modes, f"allowed: 0 (all) or 1..{n_red}")


def faces_plate(p: Plate, gap_ratio: float, x: float, y: float, radius: float) -> bool:
    """A granule at (x, y) [m] faces the plate's left edge, so that it has a plate contact:
    its gap x0 - (x + R) is at most gap_ratio * R and y0 < y < y0 + height."""
    return p.x0 - (x + radius) <= gap_ratio * radius and p.y0 < y < p.y0 + p.height


def plate_contact_heights(s: Scenario) -> list[float]:
    """y [m] of the granules facing the plate's left edge (`faces_plate`), in granule
    order (s resolved, with a plate)."""
    return [float(s.granules[i].y) for i in facing_granules(s)]


def facing_granules(s: Scenario) -> list[int]:
    """Indices of the granules facing the plate's left edge at t = 0 (`faces_plate`), in
    granule order (s resolved, with a plate): its plate contacts at t = 0."""
    return [i for i, g in enumerate(s.granules) if faces_plate(s.plate, s.contact.neighbour_gap, g.x, g.y, g.radius)]


def on_face_node(p: Plate, y: float) -> bool:
    """Whether height y [m] is that of a left-edge node (within NODE_RTOL x height)."""
    return bool(np.any(np.abs(left_edge_node_heights(p) - y) <= NODE_RTOL * p.height))


def split_initial_contacts(s: Scenario) -> tuple[list[int], list[int]]:
    """The plate contacts at t = 0 as (on a node, between nodes): granule indices, in
    granule order (s resolved, with a plate). A contact on a face node gets a rigid layer
    (docs/model.md section 3.4: the paper's model), one between nodes a patch contact
    (section 3.5), the same as a contact that forms during the run."""
    facing = facing_granules(s)
    on = [i for i in facing if on_face_node(s.plate, s.granules[i].y)]
    return on, [i for i in facing if i not in set(on)]


def left_edge_node_heights(p: Plate) -> np.ndarray:
    """y [m] of the 2 ny + 1 Q8 nodes on the plate's left edge, bottom to top."""
    corners = np.linspace(p.y0, p.y0 + p.height, p.ny + 1)
    y = np.empty(2 * p.ny + 1)
    y[0::2] = corners
    y[1::2] = 0.5 * (corners[:-1] + corners[1:])
    return y


def clamped_left_nodes(p: Plate) -> set[int]:
    """Indices (into left_edge_node_heights) of the left-edge nodes on a clamped edge."""
    n = 2 * p.ny + 1
    if "left" in p.clamped_edges:
        return set(range(n))
    return ({0} if "bottom" in p.clamped_edges else set()) | ({n - 1} if "top" in p.clamped_edges else set())


def clamped_node_count(p: Plate) -> int:
    """Number of Q8 nodes on the clamped edges (corners shared by two edges counted once)."""
    ni, nj = 2 * p.nx, 2 * p.ny  # node lattice (i, j), 0 <= i <= ni, 0 <= j <= nj
    lines = {
        "left": {(0, j) for j in range(nj + 1)},
        "right": {(ni, j) for j in range(nj + 1)},
        "bottom": {(i, 0) for i in range(ni + 1)},
        "top": {(i, nj) for i in range(ni + 1)},
    }
    return len(set().union(*(lines[e] for e in p.clamped_edges)))


def reduced_dof_count(p: Plate, n_slaved: int) -> int:
    """Dofs left after clamping and slaving n_slaved rigid-layer nodes: 2 per free node."""
    n_nodes = (p.nx + 1) * (p.ny + 1) + p.nx * (p.ny + 1) + p.ny * (p.nx + 1)
    return 2 * (n_nodes - clamped_node_count(p) - n_slaved)


def check_symmetry_row(p: Plate) -> None:
    """An even `plate.ny`, so that the symmetry line is a row of element edges."""
    if p.ny % 2:
        raise ScenarioError(
            "plate.ny",
            p.ny,
            f"must be even so that the symmetry line y = y0 + height/2 = {p.y0 + p.height / 2:g} m "
            "is a row of element edges (with Q8 nodes along it)",
        )


def _contact_node(p: Plate, name: str, yk: float, left_y: np.ndarray) -> int:
    """Index of the left-edge node at the height yk [m] of the contact of `name` (a
    granule, for the message); ScenarioError when none."""
    at = np.flatnonzero(np.abs(left_y - yk) <= NODE_RTOL * p.height)
    if at.size != 1:
        raise ScenarioError(
            "plate.ny",
            p.ny,
            f"the rigid layer of {name} at y={yk:g} m is not on a mesh node; the left-edge node "
            f"spacing is height/(2 ny) = {p.height / (2 * p.ny):g} m; allowed: a layer at a multiple "
            "of height/(2 ny) above plate.y0",
        )
    return int(at[0])


def _names(n: int, names: Sequence[str] | None) -> list[str]:
    return list(names) if names is not None else [f"contact {k}" for k in range(n)]


def rigid_layers(
    p: Plate, contact_y: Sequence[float], left_y: np.ndarray | None = None, names: Sequence[str] | None = None
) -> list[tuple[int, list[int]]]:
    """(driving node, other layer nodes) of each rigid-layer contact at the heights
    contact_y [m], as indices into left_y [m] (the heights of the left-edge nodes, in any
    order; None: `left_edge_node_heights`); refuses a contact off the left edge or between
    nodes, and overlapping layers. names: the granule of each contact, as the messages
    name it (default: "contact k")."""
    names = _names(len(contact_y), names)
    left_y = left_edge_node_heights(p) if left_y is None else np.asarray(left_y)
    half, tol = 0.5 * p.layer_width, NODE_RTOL * p.height
    owner: dict[int, int] = {}
    layers = []
    for k, yk in enumerate(contact_y):
        if not (p.y0 - tol <= yk <= p.y0 + p.height + tol):
            raise ScenarioError(
                "plate.y0",
                p.y0,
                f"{names[k]} at y={yk:g} m lies outside the plate's left edge [{p.y0:g}, {p.y0 + p.height:g}] m",
            )
        at = _contact_node(p, names[k], yk, left_y)
        members = [int(n) for n in np.flatnonzero(np.abs(left_y - yk) <= half + tol)]
        for n in members:
            if n in owner:
                j = owner[n]
                raise ScenarioError(
                    "plate.rigid_layer_width",
                    p.rigid_layer_width,
                    f"the rigid layers of {names[j]} at y={contact_y[j]:g} m and {names[k]} at y={yk:g} m "
                    f"share the node at y={left_y[n]:g} m with w = {p.layer_width:g} m; "
                    "allowed: w smaller than the distance between neighbouring contacts",
                )
            owner[n] = k
        layers.append((at, [n for n in members if n != at]))
    return layers


def check_layers_off_clamps(
    p: Plate,
    contact_y: Sequence[float],
    layers: Sequence[tuple[int, Sequence[int]]],
    clamped: set[int],
    names: Sequence[str] | None = None,
) -> None:
    """Refuse a contact on a clamped node, or a rigid layer that reaches one: layers as
    `rigid_layers` gives them and clamped, in the same node numbering (the plate layer's
    mesh nodes, or the indices of `clamped_left_nodes`); names as in `rigid_layers`."""
    names = _names(len(contact_y), names)
    for k, (at, members) in enumerate(layers):
        at = int(at)
        if at in clamped:
            raise ScenarioError(
                "plate.clamped_edges",
                p.clamped_edges,
                f"{names[k]} touches the plate at y={contact_y[k]:g} m, on a clamped node; allowed: "
                "contacts on free parts of the left edge only",
            )
        if any(int(n) in clamped for n in members):
            raise ScenarioError(
                "plate.rigid_layer_width",
                p.rigid_layer_width,
                f"the rigid layer of {names[k]} at y={contact_y[k]:g} m (w = {p.layer_width:g} m) "
                "reaches a clamped node; allowed: a width that keeps every layer off the clamped edges",
            )


def patches_possible(s: Scenario, n_red: int, kind: str) -> bool:
    """Whether plate contacts may be patch contacts (docs/model.md section 3.5): dynamic
    detection and a plate in all its modes or in the truncated basis (a dense basis cut
    to plate.n_modes has no static correction over the face); `kind` as `basis_kind`."""
    return s.contact.detection == "dynamic" and (kind == "truncated" or s.plate.n_modes in (0, n_red))


def _check_patches_at_start(s: Scenario, between: list[int], n_red: int, kind: str, names: dict[int, str]) -> None:
    """Granules touching the face between nodes at t = 0 need patch contacts."""
    if not between or patches_possible(s, n_red, kind):
        return
    p, i = s.plate, between[0]
    fixed = s.contact.detection == "fixed"
    field, value = ("contact.detection", "fixed") if fixed else ("plate.n_modes", p.n_modes)
    why = (
        "contacts with fixed detection are those of t = 0 on rigid layers, which sit on nodes"
        if fixed
        else "a dense basis cut to plate.n_modes has no static correction over the face"
    )
    raise ScenarioError(
        field,
        value,
        f"{names[i]} touches the plate's face at y={s.granules[i].y:g} m between face nodes (spacing "
        f"height/(2 ny) = {p.height / (2 * p.ny):g} m), which takes a patch contact (docs/model.md "
        f"section 3.5), and {why}; allowed: contact.detection = 'dynamic' with plate.n_modes = 0 "
        "(all modes, or plate.modes = 'truncated'), or the granule's contact on a node",
    )


def check_plate_mesh(s: Scenario, names: dict[int, str] | None = None) -> None:
    """The mesh the plate layer will build can hold the scenario (see the module docstring).
    names: how messages name granule i (default: "granule 'LABEL'")."""
    p = s.plate
    if p is None:
        return
    check_symmetry_row(p)
    on, between = split_initial_contacts(s)
    names = {i: names[i] if names is not None else f"granule '{s.granules[i].label}'" for i in on + between}
    contact_y = [float(s.granules[i].y) for i in on]
    on_names = [names[i] for i in on]
    layers = rigid_layers(p, contact_y, names=on_names)
    check_layers_off_clamps(p, contact_y, layers, clamped_left_nodes(p), on_names)
    n_red = reduced_dof_count(p, sum(len(m) for _, m in layers))
    check_mode_count(p, n_red)
    edge_load = s.load.kind == "line" and s.load.target == "plate"
    kind = basis_kind(p.modes, n_red, truncation_supported(p.clamped_edges, edge_load))
    if kind == "truncated":
        check_truncated_plate(s)
    _check_patches_at_start(s, between, n_red, kind, names)
    check_fits(kind, n_red, p.modes, n_face=2 * p.ny + 1)


def check_truncated_plate(s: Scenario) -> None:
    """What the truncated modal basis (docs/model.md section 4.5) supports."""
    p = s.plate
    if s.solver.scheme != "implicit":
        raise ScenarioError(
            "solver.scheme",
            s.solver.scheme,
            f"the truncated plate basis (plate.modes = {p.modes!r}, here with more than the "
            "dense limit of reduced dofs) is supported by the 'implicit' scheme only. Its static "
            "residual compliance R has no mass, so inside a step of the paper scheme the contact "
            "point's slip rate answers the friction force as R_tt / h, and the fixed-point "
            "iteration's modulus (eq. 8) grows like mu k_s |N| R_tt / h as the step shrinks: "
            "criterion (8)'s step control would make it worse, not better (steel-r1 on 8 x 80: "
            "R_tt = 1.4e-9 m/N and |N| up to 47 N give ~160 at the paper's 4e-8 s). Allowed: "
            "solver.scheme = 'implicit' (Newton on the interface forces, stable for any |lambda|), "
            "or plate.modes = 'all' where the dense basis fits (8 x 80: about 1 GB, 1 minute)",
        )
    if s.load.kind == "line" and s.load.target == "plate":
        raise ScenarioError(
            "load.target",
            s.load.target,
            "the truncated plate basis has a static correction at the contacts only, not for a "
            "load on the plate's edge; allowed: load.target = 'granules', or plate.modes = 'all'",
        )
    if not p.clamped_edges:
        raise ScenarioError(
            "plate.clamped_edges",
            p.clamped_edges,
            "the truncated plate basis needs a plate held by at least one clamped edge (its static "
            "compliance); allowed: a non-empty subset of top, bottom, left, right, or plate.modes = 'all'",
        )
