"""VTK time series of a run for ParaView, through meshio.

    >>> from granplate.results.export import export_vtk
    >>> export_vtk(gp.read("steel-r1.nc"), "vtk/")      # -> vtk/steel-r1.pvd

One file per plate-field snapshot (`field_time`) and per part:

- ``plate_NNNN.vtu``: the plate as VTK quadratic quads ("quad8"), undeformed node
  coordinates [m] with point data ``displacement`` (3 components, z = 0) [m] and cell
  data ``von_mises`` (largest in each element) [Pa]. Use ParaView's "Warp By Vector"
  to show the deformed plate.
- ``granules_NNNN.vtu``: one vertex per granule at its current centre [m] with point
  data ``radius`` [m], ``velocity`` (3 components) [m/s], ``speed`` [m/s],
  ``angular_velocity`` [rad/s], ``rotation`` [rad] and ``granule_index`` (position in
  the result's granule list). Show them with the "Point Gaussian" representation,
  scaled by ``radius``, or a Glyph filter (sphere, scale by radius, factor 2).

and ``NAME.pvd`` (both parts, part 0 = plate, part 1 = granules), ``NAME-plate.pvd`` and
``NAME-granules.pvd`` collection files holding the times [s].

A run in space (dimension = 3, no plate) is written per output time (`time`) as
``spheres_NNNN.vtu``: one vertex per sphere at its centre [m] with point data
``radius`` [m], ``velocity`` [m/s] and ``angular_velocity`` [rad/s] (3 components
each), ``speed`` [m/s], ``material_id`` (position of the sphere's material in the
result's sorted material names, listed in the .pvd's comment) and ``granule_index``; and
``NAME.pvd`` holding the times [s]. In ParaView: open NAME.pvd, Apply, then Filters >
Glyph with Glyph Type "Sphere", Scale Array "radius", Scale Factor 2 (the sphere glyph's
radius is 0.5) and Glyph Mode "All Points"; colour by speed or material_id.

A run in space with an elastic body (the result holds `body_ux`, results.body) is written
per body field snapshot (`field_time`) as ``body_NNNN.vtu``: the body's quadratic cells
(VTK_QUADRATIC_HEXAHEDRON, VTK_TRIQUADRATIC_HEXAHEDRON or VTK_QUADRATIC_TETRA: meshio's
"hexahedron20", "hexahedron27", "tetra10", by the nodes per cell) at the undeformed node
coordinates [m], with point data ``displacement`` (3 components) [m] and cell data
``von_mises`` (largest in each element) [Pa] ("Warp By Vector" shows it deformed); and
``spheres_NNNN.vtu`` at the output nearest each snapshot; ``NAME.pvd`` holds both per
time (part 0 = body, part 1 = spheres), ``NAME-body.pvd`` and ``NAME-spheres.pvd`` each.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, NamedTuple
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np
import xarray as xr

from granplate.results import analysis as an
from granplate.model.dimension import SPACE
from granplate.results.dataset import dimension_spec, has_solid


def _points3(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(n, 3) points from x, y [m] (z = 0)."""
    return np.column_stack([x, y, np.zeros_like(x)]).astype(float)


def plate_mesh(ds: xr.Dataset, k: int) -> meshio.Mesh:
    """The plate at field snapshot k as a meshio Mesh (quad8 cells, displacement, von Mises)."""
    pts = _points3(ds["node_x"].values, ds["node_y"].values)
    u = _points3(ds["plate_ux"].values[k], ds["plate_uy"].values[k])
    cells = [("quad8", np.asarray(ds["element_nodes"].values, dtype=np.int64))]
    return meshio.Mesh(
        pts,
        cells,
        point_data={"displacement": u},
        cell_data={"von_mises": [np.asarray(ds["plate_von_mises"].values[k], dtype=float)]},
    )


def granule_cloud(ds: xr.Dataset, i: int) -> meshio.Mesh:
    """The granules at output index i of ds.time as a meshio Mesh (one vertex each)."""
    n = ds.sizes["granule"]
    vx, vy = ds["vx"].values[i], ds["vy"].values[i]
    return meshio.Mesh(
        _points3(ds["x"].values[i], ds["y"].values[i]),
        [("vertex", np.arange(n, dtype=np.int64)[:, None])],
        point_data={
            "radius": np.asarray(ds["radius"].values, dtype=float),
            "velocity": _points3(vx, vy),
            "speed": np.hypot(vx, vy),
            "angular_velocity": np.asarray(ds["omega"].values[i], dtype=float),
            "rotation": np.asarray(ds["theta"].values[i], dtype=float),
            "granule_index": np.arange(n, dtype=np.int64),
        },
    )


def material_names(ds: xr.Dataset) -> list[str]:
    """The result's material names, sorted: material_id i is the i-th."""
    return sorted({str(m) for m in ds["material"].values})


def sphere_cloud(ds: xr.Dataset, i: int) -> meshio.Mesh:
    """The spheres of a 3D result at output index i as a meshio Mesh (one vertex each)."""
    n = ds.sizes["granule"]
    pos = np.column_stack([ds[k].values[i] for k in SPACE.positions]).astype(float)
    vel = np.column_stack([ds[k].values[i] for k in SPACE.velocities]).astype(float)
    spin = np.column_stack([ds[k].values[i] for k in SPACE.spins]).astype(float)
    names = material_names(ds)
    return meshio.Mesh(
        pos,
        [("vertex", np.arange(n, dtype=np.int64)[:, None])],
        point_data={
            "radius": np.asarray(ds["radius"].values, dtype=float),
            "velocity": vel,
            "speed": np.linalg.norm(vel, axis=1),
            "angular_velocity": spin,
            "material_id": np.array([names.index(str(m)) for m in ds["material"].values], dtype=np.int64),
            "granule_index": np.arange(n, dtype=np.int64),
        },
    )


#: The meshio cell type of a body's cells by their nodes.
BODY_CELLS = {20: "hexahedron20", 27: "hexahedron27", 10: "tetra10"}


def body_mesh(ds: xr.Dataset, k: int) -> meshio.Mesh:
    """The body at field snapshot k as a meshio Mesh (quadratic cells, displacement, von Mises)."""
    pts = np.column_stack([ds[f"body_node_{c}"].values for c in "xyz"]).astype(float)
    u = np.column_stack([ds[f"body_u{c}"].values[k] for c in "xyz"]).astype(float)
    cells = np.asarray(ds["body_element_nodes"].values, dtype=np.int64)
    return meshio.Mesh(
        pts,
        [(BODY_CELLS[cells.shape[1]], cells)],
        point_data={"displacement": u},
        cell_data={"von_mises": [np.asarray(ds["body_von_mises"].values[k], dtype=float)]},
    )


def export_body(ds: xr.Dataset, out_dir: str | Path, name: str | None = None) -> Path:
    """Write the body and the spheres of 3D run `ds` at each body snapshot (field_time) into
    out_dir (module docstring); returns the combined .pvd path."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    name = name or str(ds.attrs.get("scenario_name", "result"))
    ft = np.asarray(ds["field_time"].values, dtype=float)
    ti = an.time_indices(ds, ft) if ds.sizes.get("time", 0) else np.zeros(0, np.int64)
    spheres = ds.sizes.get("granule", 0) > 0 and len(ti) == len(ft)
    body_entries, sphere_entries = [], []
    for k, t in enumerate(ft):
        meshio.write(out / f"body_{k:04d}.vtu", body_mesh(ds, k))
        body_entries.append((float(t), 0, f"body_{k:04d}.vtu"))
        if spheres:
            meshio.write(out / f"spheres_{k:04d}.vtu", sphere_cloud(ds, int(ti[k])))
            sphere_entries.append((float(t), 1, f"spheres_{k:04d}.vtu"))
    (out / f"{name}-body.pvd").write_text(pvd_text(body_entries))
    if spheres:
        (out / f"{name}-spheres.pvd").write_text(pvd_text([(t, 0, f) for t, _, f in sphere_entries]))
    combined = out / f"{name}.pvd"
    combined.write_text(pvd_text(sorted(body_entries + sphere_entries)))
    return combined


def export_spheres(ds: xr.Dataset, out_dir: str | Path, name: str | None = None) -> Path:
    """Write the spheres of 3D run `ds` into out_dir, one .vtu per output time, and the
    collection NAME.pvd (default: the scenario name); returns the .pvd path."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    name = name or str(ds.attrs.get("scenario_name", "result"))
    entries = []
    for i, t in enumerate(np.asarray(ds["time"].values, dtype=float)):
        f = f"spheres_{i:04d}.vtu"
        meshio.write(out / f, sphere_cloud(ds, i))
        entries.append((float(t), 0, f))
    ids = ", ".join(f"{k} = {m}" for k, m in enumerate(material_names(ds))).replace("--", "- -")
    pvd = out / f"{name}.pvd"
    pvd.write_text(pvd_text(entries).replace("<Collection>", f"<!-- material_id: {ids} -->\n  <Collection>", 1))
    return pvd


def pvd_text(entries: list[tuple[float, int, str]]) -> str:
    """A ParaView collection file listing (time [s], part, file name) entries."""
    rows = "\n".join(
        f'    <DataSet timestep="{t!r}" group="" part="{part}" file={quoteattr(name)}/>' for t, part, name in entries
    )
    return (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
        "  <Collection>\n"
        f"{rows}\n"
        "  </Collection>\n"
        "</VTKFile>\n"
    )


def export_vtk(ds: xr.Dataset, out_dir: str | Path, name: str | None = None) -> Path:
    """Write the VTK time series of run `ds` into out_dir; returns the combined .pvd path.

    name: stem of the .pvd files (default: the scenario name). The writer is the result's
    `vtk_kind`: a run in the plane is written by `export_plate` (its plate snapshots), a
    run in space by `export_spheres` (every output time), or with an elastic body by
    `export_body` (every body snapshot).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return vtk_kind(ds).write(ds, out, name)


def export_plate(ds: xr.Dataset, out_dir: str | Path, name: str | None = None) -> Path:
    """Write the plate and the granules of plane run `ds` at each plate snapshot
    (field_time, the granules at the output nearest to each) into out_dir (module
    docstring); returns the combined .pvd path."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    name = name or str(ds.attrs.get("scenario_name", "result"))
    if not an.has_plate(ds):
        raise ValueError("the result has no plate to export")
    ft = np.asarray(ds["field_time"].values, dtype=float)
    ti = an.time_indices(ds, ft)
    granules = an.has_granules(ds)
    plate_entries, granule_entries = [], []
    for k, t in enumerate(ft):
        plate_file = f"plate_{k:04d}.vtu"
        meshio.write(out / plate_file, plate_mesh(ds, k))
        plate_entries.append((float(t), 0, plate_file))
        if granules:
            gran_file = f"granules_{k:04d}.vtu"
            meshio.write(out / gran_file, granule_cloud(ds, int(ti[k])))
            granule_entries.append((float(t), 1, gran_file))
    (out / f"{name}-plate.pvd").write_text(pvd_text([(t, 0, f) for t, _, f in plate_entries]))
    if granules:
        (out / f"{name}-granules.pvd").write_text(pvd_text([(t, 0, f) for t, _, f in granule_entries]))
    combined = out / f"{name}.pvd"
    combined.write_text(pvd_text(sorted(plate_entries + granule_entries)))
    return combined


class VtkKind(NamedTuple):
    """How a kind of result is written to VTK: `write(ds, out_dir, name)` -> the .pvd path;
    `ready(ds)`: whether the result holds what it writes; `written(ds, pvd)`: what was
    written, in words, for the command line."""

    write: Callable[[xr.Dataset, Path, str | None], Path]
    ready: Callable[[xr.Dataset], bool]
    written: Callable[[xr.Dataset, Path], str]


def _sizes(ds: xr.Dataset, dim: str) -> int:
    return int(ds.sizes.get(dim, 0))


#: the VTK writers: a result with an elastic body's fields ("body"), else by its
#: dimension's name (model.dimension)
VTK_KINDS: dict[str, VtkKind] = {
    "body": VtkKind(
        export_body,
        lambda ds: True,
        lambda ds, pvd: (
            f"written {_sizes(ds, 'field_time')} snapshots of the body and {_sizes(ds, 'granule')} spheres; "
            f"open {pvd} in ParaView (Warp By Vector: displacement; Glyph: sphere, scale array radius, factor 2)"
        ),
    ),
    "space": VtkKind(
        export_spheres,
        lambda ds: True,
        lambda ds, pvd: (
            f"written {_sizes(ds, 'time')} output times of {_sizes(ds, 'granule')} spheres; open {pvd} "
            f"in ParaView (Glyph: sphere, scale array radius, factor 2)"
        ),
    ),
    "plane": VtkKind(
        export_plate,
        an.has_plate,
        lambda ds, pvd: f"written {_sizes(ds, 'field_time')} snapshots; open {pvd} in ParaView",
    ),
}


def vtk_kind(ds: xr.Dataset) -> VtkKind:
    """How result `ds` is written to VTK (`VTK_KINDS`)."""
    return VTK_KINDS["body" if has_solid(ds) else dimension_spec(ds).name]
