"""Scenario -> an elastic body's arrays in the loop (docs/model.md section 3.9): the solid
built (solid.build_solid, cached in the run store) with its residual compliance over the
normal dofs of the face the granules rest on, its boundary's quadratic faces with their
rows of the modes, each granule's closest face at t = 0 (the seed of its search) and its
contact coefficients with the body (the 2D plate contact's laws with the body's
material: E* of both, the granule's mass as m*, the pair's friction), and the modal
forces of a line load on the body (the bare plate's shock, solid.traction).
"""

from __future__ import annotations

import hashlib
from collections import Counter
from pathlib import Path
from typing import NamedTuple

import numpy as np

from granplate.model import loads
from granplate.model.inputs import N_GEO, BodyArrays, no_history
from granplate.physics.contact import N_COEF, damping_coefficient, hertz_coefficient
from granplate.setup.materials import effective_modulus
from granplate.setup.scenario import Scenario


def residual_face(s: Scenario, surface, mesh) -> tuple[str | None, str]:
    """(the named face most granules are closest to, its dofs' components): a box face's
    normal axis ("x", "y" or "z"), a mesh group's "xyz"; (None, "") without granules or
    named faces."""
    from granplate.solid.surface import closest_point

    groups = {int(f): name for name, facets in (mesh.boundaries or {}).items() for f in np.asarray(facets)}
    votes = Counter()
    for g in s.granules:
        face = closest_point(surface, (g.x, g.y, g.z)).face
        name = groups.get(int(surface.facets[face]))
        if name is not None:
            votes[name] += 1
    if not votes:
        return None, ""
    name = votes.most_common(1)[0][0]
    if s.plate.mesh is None and name in ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax"):
        return name, name[0]
    return name, "xyz"


def body_coefficients(
    s: Scenario, mats, r: np.ndarray, mass: np.ndarray, body_material, on_rigid: np.ndarray | None = None
) -> np.ndarray:
    """(ng, N_COEF) each granule's contact coefficients with the body: Hertz A with E* of
    both materials and the granule's radius (the body flat there), damping with m* = m_i
    (the body's mass much larger), the pair's friction, yield overlap and law ids; a granule on a
    rigid patch (on_rigid) meets a rigid body, the 2D rigid layer's law (E* of the granule
    alone, m* = 0: no damping, docs/model.md section 3.4). The tangential law's columns
    (Mindlin's, docs/model.md section 3.16) from 1/G* of both, or of the granule alone on a
    rigid patch."""
    from granplate.model.arrays import coefficient_row, law_coefficients
    from granplate.model.coefficients import normal_law_id, tangential_law_columns
    from granplate.physics.mindlin import tangential_compliance

    coef = np.zeros((len(r), N_COEF))
    compliance = np.zeros(len(r))
    for i, m in enumerate(mats):
        alpha, mu, ks = s.contact.for_pair(m.name, body_material.name)
        rigid = on_rigid is not None and bool(on_rigid[i])
        other = None if rigid else body_material
        e_star = effective_modulus(m, other)
        a = hertz_coefficient(e_star, float(r[i]))
        coef[i] = coefficient_row(
            a,
            damping_coefficient(alpha, 0.0 if rigid else float(mass[i]), a),
            mu,
            ks,
            law_coefficients(s, m, other, body_material.name, e_star, float(r[i]), 2.0 * float(r[i])),
            normal_law_id(s, m.name, body_material.name),
        )
        compliance[i] = tangential_compliance(m.E, m.nu)
        if not rigid:
            compliance[i] += tangential_compliance(body_material.E, body_material.nu)
    tangential_law_columns(s, coef, compliance)
    return coef


def on_rigid_patches(s: Scenario, points: np.ndarray) -> np.ndarray:
    """(ng,) bool: whether each granule's closest surface point at t = 0 (points (ng, 3) [m])
    lies on one of the solid's rigid patches."""
    from granplate.solid.tie import in_patch

    on = np.zeros(len(points), bool)
    for rp in s.plate.rigid_patches:
        on |= in_patch(points, rp)
    return on


#: The default patch radius as a share of the body's smallest extent.
PATCH_SHARE = 0.25


def patch_radius(s: Scenario, extent: np.ndarray, reach: float) -> float:
    """The contact patch's radius [m]: plate.patch_radius (0: a point), else PATCH_SHARE of
    the body's smallest extent (extent (3,) [m]), and at least the smallest the mesh
    resolves (solid.patch.MIN_PATCH_RATIO x reach, the farthest a surface point lies from a
    node)."""
    from granplate.solid.patch import MIN_PATCH_RATIO

    if s.plate.patch_radius is not None:
        return float(s.plate.patch_radius)
    return max(PATCH_SHARE * float(np.min(extent)), MIN_PATCH_RATIO * reach)


def modal_line_load(s: Scenario, surface, solid) -> np.ndarray:
    """(nm,) Phi^T f: the modal forces per unit q0 of a line load on the body (load.kind
    "line", target "plate" (model.loads.plate_edge): the bare plate's shock on the box's face xmin,
    solid.traction); zeros for any other load."""
    edge = loads.plate_edge(s)
    if edge is None:
        return np.zeros(solid.n_modes)
    from granplate.solid.traction import face_xmin_line_load

    sd = s.plate
    f = face_xmin_line_load(
        surface,
        3 * len(solid.nodes),
        float(sd.origin[0]),
        float(sd.size[2]),
        edge[0],
        edge[1],
        1e-9 * max(sd.size),
    )
    return np.ascontiguousarray(solid.Phi.T @ f[solid.dofs])


class SurfaceGeometry(NamedTuple):
    """A solid's mesh and what the loop needs of its boundary, which depend on its geometry
    alone: the quadratic faces, their neighbours, the surface nodes (solid.patch) and the
    farthest a point of the surface lies from a node [m]."""

    mesh: object
    surface: object
    neighbours: np.ndarray
    nodes: object
    reach: float


#: Surface geometries built in this process, most recent last (the designs of a study that
#: vary anything but the body's geometry, a benchmark's repeats, share one).
_GEOMETRIES: dict[tuple, SurfaceGeometry] = {}
#: How many a process keeps.
GEOMETRIES_KEPT = 2


def geometry_key(sd) -> tuple:
    """What identifies a solid's geometry: a box's size, elements and (resolved) origin, or
    a mesh file's content (SHA-256), and the element."""
    if sd.mesh is not None:
        return ("mesh", hashlib.sha256(Path(sd.mesh).read_bytes()).hexdigest(), sd.element)
    return ("box", tuple(map(float, sd.size)), tuple(map(int, sd.elements)), tuple(map(float, sd.origin)), sd.element)


def surface_geometry(sd) -> SurfaceGeometry:
    """The solid's SurfaceGeometry, kept in this process by `geometry_key`."""
    from granplate.solid.build import solid_mesh
    from granplate.solid.fe import vector_basis
    from granplate.solid.patch import farthest_from_nodes, surface_nodes
    from granplate.solid.surface import boundary_surface, face_neighbours

    key = geometry_key(sd)
    if key in _GEOMETRIES:
        _GEOMETRIES[key] = _GEOMETRIES.pop(key)  # most recent last
        return _GEOMETRIES[key]
    mesh = solid_mesh(sd)
    surface = boundary_surface(vector_basis(mesh, sd.element))
    sn = surface_nodes(surface)
    geo = SurfaceGeometry(
        mesh=mesh,
        surface=surface,
        neighbours=face_neighbours(surface),
        nodes=sn,
        reach=farthest_from_nodes(surface, sn.xyz),
    )
    _GEOMETRIES[key] = geo
    while len(_GEOMETRIES) > GEOMETRIES_KEPT:
        _GEOMETRIES.pop(next(iter(_GEOMETRIES)))
    return geo


def build_body(s: Scenario, mats, r: np.ndarray, mass: np.ndarray):
    """(the SolidModel, its BodyArrays, (ng,) bool: each granule on a rigid patch at t = 0)
    of the scenario's elastic solid."""
    from granplate.solid.boundary import reduced_index
    from granplate.solid.build import build_solid
    from granplate.solid.patch import check_patch_radius, node_grid, patch_capacity
    from granplate.solid.surface import closest_point

    sd = s.plate
    material = s.material(sd.material)
    geo = surface_geometry(sd)
    mesh, surface, sn = geo.mesh, geo.surface, geo.nodes
    if sd.mesh is not None:  # a mesh file's surface against the granules (a box's: setup.validate)
        from granplate.setup.geometry import granule_named
        from granplate.setup.granule_checks import start_overlap
        from granplate.solid.clearance import check_clearance

        check_clearance(s, mesh, {i: granule_named(s, s, i) for i in range(len(s.granules))}, start_overlap(s))
    face, components = residual_face(s, surface, mesh) if sd.residual else (None, "")
    solid = build_solid(sd, material, surface=face, components=components or "z")
    rows = reduced_index(solid.dofs, (3 * sn.full[:, None] + np.arange(3)).ravel()).reshape(-1, 3)
    where = np.full(len(solid.dofs), -1, np.int64)
    where[solid.surface_dofs] = np.arange(len(solid.surface_dofs))
    resid_index = np.where(rows >= 0, where[np.maximum(rows, 0)], -1)
    ng, nm = len(r), solid.n_modes
    reach = geo.reach
    radius = patch_radius(s, sn.xyz.max(axis=0) - sn.xyz.min(axis=0), reach)
    n_p = surface.dofs.shape[1]
    grid = node_grid(sn.xyz, max(radius, 1e-12))
    if radius > 0.0:
        check_patch_radius(radius, reach)
        n_p = max(n_p, patch_capacity(sn.xyz, radius, reach))
    closest = [closest_point(surface, (g.x, g.y, g.z)) for g in s.granules]
    seeds = np.array([c.face for c in closest], np.int64)
    points = np.array([c.point for c in closest], float).reshape(-1, 3)
    box = np.array([solid.nodes.min(axis=0), solid.nodes.max(axis=0)])
    rigid = on_rigid_patches(s, points)
    z = np.zeros
    arrays = BodyArrays(
        face_nodes=np.ascontiguousarray(surface.nodes),
        face_snode=sn.face_snode,
        node_xyz=sn.xyz,
        node_area=sn.area,
        node_rows=np.ascontiguousarray(rows, np.int64),
        node_resid=np.ascontiguousarray(resid_index, np.int64),
        grid=np.array([grid.cell]),
        grid_origin=grid.origin,
        grid_shape=grid.shape,
        cell_start=grid.start,
        cell_nodes=grid.nodes,
        neighbours=geo.neighbours,
        kind=np.array([surface.kind], np.int64),
        phi=np.ascontiguousarray(solid.Phi),
        omega=solid.omega.copy(),
        resid=np.ascontiguousarray(solid.resid),
        box=box,
        coef=body_coefficients(s, mats, r, mass, material, rigid),
        load=modal_line_load(s, surface, solid),
        weight=z(nm),
        patch=np.array([radius]),
        face=np.vstack([seeds, seeds]),
        geo=z((2, ng, N_GEO)),
        entry=np.zeros((2, ng, n_p), np.int64),
        weights=z((2, ng, n_p)),
        count=np.zeros((2, ng), np.int64),
        grad=z((ng, n_p, 3)),
        fmodal=z((2, nm)),
        fdamp=z((2, nm)),
        hist=no_history(ng),
        q=z(nm),
        qd=z(nm),
        qdp=z(nm),
        static=z(2),
        active=np.zeros(ng, np.int64),
        rcol=np.zeros((ng, 3 * n_p), np.int64),
        rcoef=z((ng, 3 * n_p)),
        rgrad=z((ng, 3 * n_p, 3)),
        mrow=z(nm),
    )
    return solid, arrays, rigid
