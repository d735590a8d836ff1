"""The VTK export reads back with meshio: quadratic quads carrying the plate's
displacement and von Mises stress, granules as points with radius and velocity, and a
.pvd collection listing every snapshot time."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

from granplate.results.export import export_vtk

from short_results import short_results


@pytest.fixture(scope="module")
def steel(tmp_path_factory):
    ds = short_results()["steel-r1"]
    out = tmp_path_factory.mktemp("vtk")
    return ds, out, export_vtk(ds, out)


def test_plate_files_read_back(steel):
    """Each plate file: quad8 cells = element_nodes, displacement = plate_ux/uy, von Mises."""
    ds, out, _ = steel
    for k in (0, ds.sizes["field_time"] - 1):
        m = meshio.read(out / f"plate_{k:04d}.vtu")
        assert [c.type for c in m.cells] == ["quad8"]
        np.testing.assert_array_equal(m.cells[0].data, ds.element_nodes.values)
        np.testing.assert_allclose(m.points[:, 0], ds.node_x.values)
        np.testing.assert_allclose(m.point_data["displacement"][:, 0], ds.plate_ux.values[k])
        np.testing.assert_allclose(m.point_data["displacement"][:, 1], ds.plate_uy.values[k])
        np.testing.assert_allclose(m.cell_data["von_mises"][0], ds.plate_von_mises.values[k])


def test_granule_files_read_back(steel):
    """Each granule file: one vertex per granule at its centre, radius and velocity."""
    ds, out, _ = steel
    k = ds.sizes["field_time"] - 1
    i = int(np.argmin(np.abs(ds.time.values - ds.field_time.values[k])))
    m = meshio.read(out / f"granules_{k:04d}.vtu")
    assert m.points.shape == (ds.sizes["granule"], 3)
    np.testing.assert_allclose(m.points[:, 0], ds.x.values[i])
    np.testing.assert_allclose(m.point_data["radius"], ds.radius.values)
    np.testing.assert_allclose(m.point_data["velocity"][:, 0], ds.vx.values[i])
    np.testing.assert_allclose(m.point_data["velocity"][:, 1], ds.vy.values[i])


def test_pvd_lists_every_snapshot(steel):
    """The .pvd collection names existing files at the field times, plate part 0, granules 1."""
    ds, out, pvd = steel
    sets = ET.parse(pvd).getroot().find("Collection").findall("DataSet")
    assert len(sets) == 2 * ds.sizes["field_time"]
    plate_times = [float(s.get("timestep")) for s in sets if s.get("part") == "0"]
    np.testing.assert_allclose(plate_times, ds.field_time.values)
    assert all((out / s.get("file")).is_file() for s in sets)
    assert (out / "steel-r1-plate.pvd").is_file() and (out / "steel-r1-granules.pvd").is_file()


def test_bare_plate_has_no_granule_files(tmp_path):
    ds = short_results()["bare-plate"]
    pvd = export_vtk(ds, tmp_path)
    assert not list(tmp_path.glob("granules_*.vtu"))
    assert len(ET.parse(pvd).getroot().find("Collection").findall("DataSet")) == ds.sizes["field_time"]
