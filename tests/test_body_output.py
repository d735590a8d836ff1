"""A 3D result with an elastic body's fields, written out and drawn: `export --vtk` writes
the body's quadratic cells and the spheres per snapshot into one .pvd that meshio reads back
with the Dataset's numbers; `show` draws the body deformed (magnification in the title),
coloured by von Mises [MPa] at the snapshot of the largest stress, with a colour bar."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest
import xarray as xr

from granplate.cli import main
from granplate.results.body import body_data, body_operators
from granplate.results.dataset import write
from granplate.results.export import export_vtk
from granplate.setup import io as scenario_io
from granplate.solid.build import build_solid
from granplate.solid.surface import closest_point

SOLID = {"size": [0.04, 0.04, 0.01], "elements": [4, 4, 2], "clamped": ["xmin"], "max_frequency": 8e4}
R = 0.004
N_T = 21


@pytest.fixture(scope="module")
def result():
    """A synthetic 3D result: one sphere resting on the top face, pressing on it with a
    force that grows and falls, the modes at rest, snapshots every 5th output."""
    s = scenario_io.from_dict(
        {
            "name": "body-out",
            "dimension": 3,
            "plate": SOLID,
            "granules": [{"label": "a", "x": 0.03, "y": 0.02, "z": 0.01 + R + 1e-5, "radius": R, "material": "steel"}],
            "time": {"t_end": 2e-4, "output_interval": 1e-5, "field_interval": 5e-5},
        }
    )
    solid = build_solid(s.plate, surface=None, cache=False)
    ops = body_operators(solid, 0.005)
    t = np.linspace(0.0, 2e-4, N_T)
    cp = closest_point(ops.surface, (0.03, 0.02, 0.0101))
    face = np.full((N_T, 1), cp.face)
    xi = np.broadcast_to(cp.xi, (N_T, 1, 2)).copy()
    force = np.zeros((N_T, 1, 3))
    force[:, 0, 2] = -100.0 * np.sin(np.pi * t / 2e-4)
    q = np.zeros((N_T, solid.n_modes))
    data, coords = body_data(solid, q, q, t, face, xi, force, 5, 0.005, operators=ops)
    g = {
        "x": 0.03,
        "y": 0.02,
        "z": 0.01 + R,
        "vx": 0.0,
        "vy": 0.0,
        "vz": 0.0,
        "omega_x": 0.0,
        "omega_y": 0.0,
        "omega_z": 0.0,
    }
    spheres = {
        k: xr.DataArray(np.full((N_T, 1), v), dims=("time", "granule"), attrs={"units": "m"}) for k, v in g.items()
    }
    ds = xr.Dataset(
        {**spheres, **data},
        coords={
            "time": ("time", t, {"units": "s"}),
            "granule": ("granule", np.array(["a"])),
            "radius": ("granule", np.array([R])),
            "material": ("granule", np.array(["steel"])),
            **coords,
        },
    )
    ds.attrs.update({"scenario_name": "body-out", "scenario_toml": scenario_io.dumps(s)})
    return ds


def test_vtk_series_holds_the_datasets_numbers(result, tmp_path):
    """Each snapshot's .vtu: the body's hexahedron20 cells, displacement and von Mises equal
    the Dataset's; the .pvd lists the body (part 0) and the spheres (part 1) at each time."""
    pvd = export_vtk(result, tmp_path)
    entries = [e.attrib for e in ET.parse(pvd).getroot().iter("DataSet")]
    ft = result["field_time"].values
    assert len(ft) == 5 and len(entries) == 2 * len(ft)
    for k, t in enumerate(ft):
        at = [e for e in entries if float(e["timestep"]) == t]
        assert sorted(e["part"] for e in at) == ["0", "1"]
        body = meshio.read(tmp_path / f"body_{k:04d}.vtu")
        cells = body.cells_dict["hexahedron20"]
        assert np.array_equal(cells, result["body_element_nodes"].values)
        assert np.allclose(body.points, np.column_stack([result[f"body_node_{c}"].values for c in "xyz"]))
        u = np.column_stack([result[f"body_u{c}"].values[k] for c in "xyz"])
        assert np.array_equal(body.point_data["displacement"], u)
        assert np.array_equal(body.cell_data["von_mises"][0], result["body_von_mises"].values[k])
        spheres = meshio.read(tmp_path / f"spheres_{k:04d}.vtu")
        assert np.allclose(spheres.points[0], [0.03, 0.02, 0.01 + R])
    assert np.abs(u).max() > 0.0


def test_netcdf_round_trip_and_export_command(result, tmp_path, capsys):
    """The result written to netCDF and read by `granplate export --vtk` gives the same files."""
    path = tmp_path / "body-out.nc"
    write(result, path)
    assert main(["export", str(path), "--vtk", str(tmp_path / "vtk")]) == 0
    assert "snapshots of the body" in capsys.readouterr().out
    body = meshio.read(tmp_path / "vtk" / "body_0002.vtu")
    assert np.array_equal(body.cell_data["von_mises"][0], result["body_von_mises"].values[2])
    assert main(["show", str(path), "-o", str(tmp_path / "show.png")]) == 0
    assert (tmp_path / "show.png").stat().st_size > 0


def test_show_draws_the_deformed_body_coloured_by_von_mises(result):
    """The body's faces in each view coloured 0 .. the largest von Mises [MPa] of the
    snapshot of the largest stress (the middle one: the force's peak), the magnification
    in the title, a colour bar in MPa."""
    from granplate.figures import space

    a = space.of_result(result)
    vm = result["body_von_mises"].values
    k = int(np.argmax(vm.max(axis=1)))
    assert k == 2 and a.time == pytest.approx(result["field_time"].values[2])
    assert a.body_stress.max() == pytest.approx(vm[k].max())
    fig = space.draw(a)
    assert f"x{a.body_scale:g}" in fig._suptitle.get_text() and a.body_scale > 1
    bodies = [c for ax in fig.axes for c in ax.collections if str(c.get_gid()).startswith("body:")]
    assert len(bodies) == 3
    labels = [ax.get_xlabel() for ax in fig.axes]
    assert any("von Mises stress [MPa]" in lab for lab in labels)
    later = space.of_result(result, time=2e-4)
    assert later.time == pytest.approx(2e-4) and later.body_largest < a.body_largest
