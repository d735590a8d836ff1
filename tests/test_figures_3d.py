"""Seeing runs in space (dimension = 3): `granplate show` draws three projections of the
spheres at their true positions and radii, depth-sorted and depth-shaded, the box's
walls at its faces, the model's contact network, and forces that are Hertz's closed form;
`plot` draws the run's own energies and 3D speeds and skips the plate figures; `export`
writes every output time as spheres that meshio reads back; `animate` and `run` work."""

from __future__ import annotations

import copy
import json
import math
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest
from matplotlib.colors import to_rgb

import granplate as gp
from granplate.cli import main
from granplate.errors import YieldWarning
from granplate.figures import run, space
from granplate.figures.common import material_colours
from granplate.results.dataset import write
from granplate.results.export import export_vtk
from granplate.setup import io as scenario_io
from granplate.setup.materials import LIBRARY, effective_modulus, sphere_mass

#: Four spheres in a box (two touching the floor and the back wall), one pushed along +x.
BOX: dict = {
    "name": "box-3d",
    "description": "four spheres in a box, one pushed",
    "dimension": 3,
    "granules": [
        {
            "label": "a",
            "x": 0.012,
            "y": 0.01,
            "z": 0.01,
            "radius": 0.01,
            "material": "steel",
            "vx": 1.0,
            "vz": -0.3,
            "omega": [1.0, -2.0, 3.0],
        },
        {"label": "b", "x": 0.032, "y": 0.01, "z": 0.01, "radius": 0.01, "material": "steel"},
        {"label": "c", "x": 0.022, "y": 0.0274, "z": 0.01, "radius": 0.01, "material": "ptfe"},
        {"label": "d", "x": 0.022, "y": 0.016, "z": 0.027, "radius": 0.009, "material": "ptfe"},
    ],
    "box": {"lower": [0.0, 0.0, 0.0], "upper": [0.06, 0.045, 0.045], "material": "steel"},
    "load": {"kind": "force", "force": 50.0, "duration": 2e-5, "direction": [1.0, 0.0, 0.0]},
    "time": {"t_end": 4e-5, "output_interval": 2e-6, "field_interval": 1e-5},
}

#: Two steel spheres meeting head-on along DIRECTION, each at HEAD_ON_SPEED, undamped.
DIRECTION = np.array([1.0, 2.0, 2.0]) / 3.0
HEAD_ON_SPEED = 0.5
RADIUS = 0.01

#: Steel spheres at these speeds pass Hertz's onset of yield (the run says so once).
pytestmark = pytest.mark.filterwarnings("ignore", category=YieldWarning)


def head_on_scenario():
    c = np.array([0.05, 0.05, 0.05])
    a, b = c - RADIUS * DIRECTION, c + RADIUS * DIRECTION
    va, vb = HEAD_ON_SPEED * DIRECTION, -HEAD_ON_SPEED * DIRECTION
    granule = lambda lab, p, v: {
        "label": lab,
        "x": p[0],
        "y": p[1],
        "z": p[2],
        "vx": v[0],
        "vy": v[1],  # noqa: E731
        "vz": v[2],
        "radius": RADIUS,
        "material": "steel",
    }
    return scenario_io.from_dict(
        {
            "name": "head-on-3d",
            "dimension": 3,
            "granules": [granule("a", a, va), granule("b", b, vb)],
            "load": {"kind": "none"},
            "contact": {"alpha_n": 0.0, "mu": 0.0},
            "time": {"t_end": 5e-5, "output_interval": 2e-7, "field_interval": 1e-5, "contact_interval": 2e-7},
        }
    )


@pytest.fixture(scope="module")
def box_scenario():
    return scenario_io.from_dict(copy.deepcopy(BOX))


@pytest.fixture(scope="module")
def box(box_scenario):
    return gp.simulate(box_scenario, progress=False)


@pytest.fixture(scope="module")
def head_on():
    return gp.simulate(head_on_scenario(), progress=False)


@pytest.fixture(scope="module")
def box_file(tmp_path_factory, box):
    return write(box, tmp_path_factory.mktemp("r3") / "box-3d.nc")


def _circles(fig, view: str):
    return {
        p.get_gid().split(":")[1]: p
        for ax in fig.axes
        for p in ax.patches
        if str(p.get_gid()).startswith("granule:") and p.get_gid().endswith(f":{view}")
    }


def _wall_lines(fig, view: str):
    return {
        ln.get_gid().split(":")[1]: ln
        for ax in fig.axes
        for ln in ax.get_lines()
        if str(ln.get_gid()).startswith("wall:") and ln.get_gid().endswith(f":{view}")
    }


# --------------------------------------------------------------------------------------
# show
# --------------------------------------------------------------------------------------
def test_show_scenario_projections_radii_depth_and_walls(box_scenario):
    """Each view holds every sphere at its projected centre with its radius, stacked far
    to near and darkened in proportion to its distance; the box's faces are its edge-on
    walls; the network has the model's contacts at t = 0; axes in mm."""
    a = space.of_scenario(box_scenario)
    model = gp.build_model(box_scenario)
    assert len(a.segments) == len(model.pairs) + len(model.wall_contacts) > 0
    fig = space.draw(a)
    colours = material_colours(a.materials)
    g = {d["label"]: d for d in BOX["granules"]}
    lo, hi = BOX["box"]["lower"], BOX["box"]["upper"]
    for (u, v, d, sign), view, seen in (
        (space.PROJECTIONS[0], "xy", ("xmin", "xmax", "ymin", "ymax")),
        (space.PROJECTIONS[1], "xz", ("xmin", "xmax", "zmin", "zmax")),
        (space.PROJECTIONS[2], "yz", ("ymin", "ymax", "zmin", "zmax")),
    ):
        circles = _circles(fig, view)
        assert set(circles) == set(g)
        axis = "xyz"
        for lab, c in circles.items():
            assert c.center == pytest.approx((g[lab][axis[u]] * 1e3, g[lab][axis[v]] * 1e3))
            assert c.radius == pytest.approx(g[lab]["radius"] * 1e3)
        depth = {lab: sign * g[lab][axis[d]] for lab in g}
        by_depth = sorted(g, key=lambda lab: depth[lab])
        z = [circles[lab].zorder for lab in by_depth]
        assert z == sorted(z) and len(set(z)) == len(z)  # the nearest drawn last
        near, far = by_depth[-1], by_depth[0]
        assert circles[near].get_facecolor()[:3] == pytest.approx(to_rgb(colours[g[near]["material"]]))
        assert circles[far].get_facecolor()[:3] == pytest.approx(
            [c * (1 - space.DEPTH_DARKEN) for c in to_rgb(colours[g[far]["material"]])]
        )
        walls = _wall_lines(fig, view)
        assert set(walls) == set(seen)
        for lab, ln in walls.items():  # each face of the box, corner to corner
            k = "xyz".index(lab[0])
            along = u if k == v else v
            fixed = (lo if lab.endswith("min") else hi)[k] * 1e3
            xs, ys = ln.get_xdata(), ln.get_ydata()
            coord, other = (ys, xs) if k == v else (xs, ys)
            assert coord == pytest.approx([fixed, fixed])
            assert sorted(other) == pytest.approx([lo[along] * 1e3, hi[along] * 1e3])
    for ax in fig.axes[:3]:
        assert "[mm]" in ax.get_xlabel() and "[mm]" in ax.get_ylabel()


def test_show_result_force_is_hertz_peak_in_space(head_on):
    """Head-on along (1, 2, 2)/3 without damping: at the largest overlap the drawn force is
    Hertz's peak A delta_max^(3/2), delta_max = (5 m* v^2 / (4 A))^(2/5) (energy
    conservation), on the line between the centres; the widest line."""
    pos = space.positions(head_on)
    gap = np.linalg.norm(pos[:, 1] - pos[:, 0], axis=1)
    t_peak = float(head_on.time.values[np.argmin(gap)])
    a = space.of_result(head_on, t_peak)
    steel = LIBRARY["steel"]
    a_hertz = 4.0 / 3.0 * effective_modulus(steel, steel) * math.sqrt(RADIUS / 2)
    m_star = sphere_mass(RADIUS, steel.rho) / 2
    delta = (5 * m_star * (2 * HEAD_ON_SPEED) ** 2 / (4 * a_hertz)) ** 0.4
    np.testing.assert_allclose(a.forces, [a_hertz * delta**1.5], rtol=2e-3)
    seg = a.segments[0]
    np.testing.assert_allclose((seg[1] - seg[0]) / np.linalg.norm(seg[1] - seg[0]), DIRECTION, atol=1e-9)
    fig = space.draw(a)
    for view in ("xy", "xz", "yz"):
        (coll,) = [c for ax in fig.axes for c in ax.collections if c.get_gid() == f"contacts:{view}"]
        assert coll.get_linewidths()[0] == space.MAX_LINE_WIDTH
    assert any("contact normal force [N]" in ax.get_xlabel() for ax in fig.axes)
    assert space.of_result(head_on).time == float(head_on.time[-1])


def test_show_result_pair_forces_are_hertz_of_the_stored_centres(box):
    """Every contact of the box in touch at 0.03 ms, and only those: eq. (2)'s A delta^(3/2)
    + c delta^(1/4) d(delta)/dt with A = 4/3 E* sqrt(R*), c = alpha_n sqrt(m* A) of the two
    materials (R* = R, m* = m, E* = E/(1 - nu^2) at a wall), delta and its rate from the
    stored centres and velocities (the result's contact table, drawn as read)."""
    a = space.of_result(box, 3e-5)
    ti = int(np.argmin(np.abs(box.time.values - 3e-5)))
    pos = space.positions(box)[ti]
    vel = np.stack([box[k].values[ti] for k in ("vx", "vy", "vz")], axis=-1)
    r = box.radius.values
    names = [str(m) for m in box.material.values]
    mats = [LIBRARY[m] for m in names]
    mass = [sphere_mass(r[i], mats[i].rho) for i in range(len(r))]
    contact = gp.loads(box.attrs["scenario_toml"]).contact
    touching = 0
    for i in range(len(r)):
        for j in range(i + 1, len(r)):
            touching += r[i] + r[j] > np.linalg.norm(pos[j] - pos[i])
    touching += sum(int(np.sum((pos[:, k] - r < 0.0) | (pos[:, k] + r > [0.06, 0.045, 0.045][k]))) for k in range(3))
    assert len(a.segments) == touching > 0
    for k, ((p, q), kind) in enumerate(zip(a.segments, a.kinds)):
        i = int(np.argmin(np.linalg.norm(pos - p, axis=1)))
        if kind == "granule":
            j = int(np.argmin(np.linalg.norm(pos - q, axis=1)))
            n = (pos[j] - pos[i]) / np.linalg.norm(pos[j] - pos[i])
            d, rate = r[i] + r[j] - np.linalg.norm(pos[j] - pos[i]), float((vel[i] - vel[j]) @ n)
            e_star, r_star = effective_modulus(mats[i], mats[j]), r[i] * r[j] / (r[i] + r[j])
            m_star, alpha = mass[i] * mass[j] / (mass[i] + mass[j]), contact.for_pair(names[i], names[j])[0]
        else:
            n = (q - p) / np.linalg.norm(q - p)  # the segment runs from the centre to the plane
            d, rate = r[i] - np.linalg.norm(q - p), float(vel[i] @ n)
            e_star, r_star, m_star, alpha = (
                effective_modulus(mats[i], None),
                r[i],
                mass[i],
                contact.for_pair(names[i], "steel")[0],
            )
        big_a = 4 / 3 * e_star * math.sqrt(r_star)
        f = big_a * d**1.5 + alpha * math.sqrt(m_star * big_a) * d**0.25 * rate
        assert a.forces[k] == pytest.approx(f, rel=1e-9)
    assert a.forces.max() > 100.0  # a and b are pressed together at 0.03 ms


def test_time_outside_a_3d_run_is_refused(box):
    with pytest.raises(gp.ScenarioError, match="--time"):
        space.of_result(box, 1.0)


# --------------------------------------------------------------------------------------
# plot
# --------------------------------------------------------------------------------------
def test_plot_draws_the_runs_energies_and_3d_speeds(box):
    """No plate: energies (KE_depth, the sum with the dissipation) and speeds from all
    three components; the plate figures say why they are skipped."""
    figs = run.figures(box)
    assert list(figs) == ["energies", "granule-speeds"]
    assert run.missing("contact-forces", box) == "the run has no plate contacts"
    assert run.missing("stress-strain", box) == "the run has no plate"
    lines = {ln.get_gid(): ln for ax in figs["energies"].axes for ln in ax.get_lines()}
    np.testing.assert_array_equal(lines["energy:depth"].get_ydata(), box.KE_depth.values)
    np.testing.assert_allclose(
        lines["energy:total"].get_ydata(),
        box.E_granular.values + box.D_viscous.values + box.D_friction.values + box.D_plastic.values,
    )
    assert "energy:plate" not in lines and "energy:plastic" not in lines  # Hertz: no plastic work
    speeds = {ln.get_gid(): ln for ax in figs["granule-speeds"].axes for ln in ax.get_lines()}
    for k, lab in enumerate(box.granule.values):
        v = np.sqrt(box.vx.values[:, k] ** 2 + box.vy.values[:, k] ** 2 + box.vz.values[:, k] ** 2)
        np.testing.assert_allclose(speeds[f"speed:{lab}"].get_ydata(), v)
    assert float(box.vz.values[0, 0]) != 0.0  # the z component counts


def test_plot_shows_the_plastic_work_of_yielding_contacts(box_scenario):
    """Under Thornton's law the dissipation drawn includes D_plastic, drawn alone too, and
    the sum of the stored and dissipated energies is E_granular + D (the run's own)."""
    import dataclasses

    s = dataclasses.replace(
        box_scenario,
        contact=dataclasses.replace(box_scenario.contact, normal_law="thornton"),
        time=dataclasses.replace(box_scenario.time, t_end=3.2e-5),
    )
    ds = gp.simulate(s, progress=False)
    assert float(ds.D_plastic.values[-1]) > 0.0
    lines = {ln.get_gid(): ln for ax in run.fig_energies(ds).axes for ln in ax.get_lines()}
    np.testing.assert_array_equal(lines["energy:plastic"].get_ydata(), ds.D_plastic.values)
    np.testing.assert_allclose(
        lines["energy:dissipated"].get_ydata(), ds.D_viscous.values + ds.D_friction.values + ds.D_plastic.values
    )
    residual = (lines["energy:total"].get_ydata() - ds.E_shock.values - ds.attrs["E_initial"]) / (
        float(ds.E_shock.values[-1]) + ds.attrs["E_initial"]
    )
    assert np.abs(residual).max() < 1e-6  # the drawn sum balances what was put in (eq. 11)


# --------------------------------------------------------------------------------------
# export
# --------------------------------------------------------------------------------------
def test_export_spheres_read_back(tmp_path, box):
    """One .vtu per output time: a vertex per sphere at its centre, radius, velocity and
    spin vectors, material ids; the .pvd lists every time in order."""
    pvd = export_vtk(box, tmp_path)
    assert pvd == tmp_path / "box-3d.pvd"
    times = box.time.values
    rows = ET.parse(pvd).getroot().find("Collection").findall("DataSet")
    assert [float(r.get("timestep")) for r in rows] == pytest.approx(list(times))
    names = sorted(set(str(m) for m in box.material.values))
    for i in (0, len(times) // 2, len(times) - 1):
        m = meshio.read(tmp_path / rows[i].get("file"))
        n = box.sizes["granule"]
        assert len(m.points) == n and [c.type for c in m.cells] == ["vertex"]
        np.testing.assert_allclose(m.points, np.stack([box.x[i], box.y[i], box.z[i]], axis=1))
        np.testing.assert_allclose(m.point_data["radius"], box.radius.values)
        np.testing.assert_allclose(m.point_data["velocity"], np.stack([box.vx[i], box.vy[i], box.vz[i]], axis=1))
        np.testing.assert_allclose(
            m.point_data["angular_velocity"], np.stack([box.omega_x[i], box.omega_y[i], box.omega_z[i]], axis=1)
        )
        assert [names[k] for k in m.point_data["material_id"]] == [str(v) for v in box.material.values]
    assert "0 = ptfe, 1 = steel" in pvd.read_text()


# --------------------------------------------------------------------------------------
# animate
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("frames", [4, None])
def test_animate_draws_the_output_times_of_a_run_without_a_body(tmp_path, box, frames):
    """Without an elastic body the frames are the output times (all 21, or thinned to 4),
    one GIF frame each, the contact forces on the largest force over the frames."""
    from PIL import Image

    from granplate.paper.animate import animate

    np.testing.assert_array_equal(space.frame_times(box), box.time.values)
    written = animate(box, tmp_path / "box.gif", frames=frames)
    with Image.open(written) as im:
        assert im.n_frames == (frames or box.sizes["time"])
    drawn = space.frames_of_result(box, [0, 10, 15])
    assert {a.force_top for a in drawn} == {max(float(a.forces.max()) for a in drawn if len(a.forces))}


# --------------------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------------------
def test_cli_run_show_plot_export_animate_in_space(tmp_path, box_scenario, box_file, capsys):
    """run -o --summary, show (scenario, result, --time), plot, export and animate on a 3D
    scenario: status 0, their files written and non-empty, no traceback."""
    toml = tmp_path / "box.toml"
    gp.dump(box_scenario, toml)
    res, summ = tmp_path / "r.nc", tmp_path / "s.json"
    assert main(["run", str(toml), "-o", str(res), "--summary", str(summ), "-q"]) == 0
    out = capsys.readouterr().out
    assert "granular energy, peak / E_in" in out and res.stat().st_size > 0
    s = json.loads(summ.read_text())
    assert s["scenario"] == "box-3d" and s["ep_max_fraction"] is None and 0 < s["eg_max_fraction"] <= 1.0 + 1e-9
    for argv, made in (
        (["show", str(toml), "-o", str(tmp_path / "a.png")], "a.png"),
        (["show", str(res), "-o", str(tmp_path / "b.pdf")], "b.pdf"),
        (["show", str(box_file), "--time", "3e-5", "-o", str(tmp_path / "c.png")], "c.png"),
        (["plot", str(box_file), "--out", str(tmp_path / "figs")], "figs/box-3d-energies.png"),
        (["export", str(box_file), "--vtk", str(tmp_path / "vtk")], "vtk/box-3d.pvd"),
        (["animate", str(box_file), "-o", str(tmp_path / "m.gif"), "--frames", "3"], "m.gif"),
    ):
        assert main(argv) == 0, argv
        assert (tmp_path / made).stat().st_size > 500, made
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err + captured.out
    assert "no stress-strain figure: the run has no plate" in captured.out
    assert len(list((tmp_path / "vtk").glob("spheres_*.vtu"))) == gp.read(box_file).sizes["time"]


def test_cli_show_3d_time_outside_exits_2(box_file, capsys):
    assert main(["show", str(box_file), "--time", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("granplate: error:") and "--time" in err and err.count("\n") == 1


#: Two spheres resting on a clamped box solid (20 x 10 x 4 mm of 4 x 2 x 1 hex20 elements).
ON_SOLID: dict = {
    "name": "on-solid",
    "dimension": 3,
    "granules": [
        {"label": "a", "x": 0.006, "y": 0.005, "z": 0.007, "radius": 0.003, "material": "steel"},
        {"label": "b", "x": 0.012, "y": 0.005, "z": 0.007, "radius": 0.003, "material": "ptfe"},
    ],
    "plate": {
        "size": [0.02, 0.01, 0.004],
        "elements": [4, 2, 1],
        "origin": [0.0, 0.0, 0.0],
        "material": "bearing_steel",
        "clamped": ["xmin"],
    },
    "load": {"kind": "none"},
    "time": {"t_end": 1e-5, "output_interval": 1e-6, "field_interval": 1e-5},
}


def _collections(fig, prefix: str) -> dict:
    return {
        c.get_gid().split(":")[1]: c
        for ax in fig.axes
        for c in ax.collections
        if str(c.get_gid()).startswith(prefix + ":")
    }


def _length(segments) -> float:
    s = np.asarray(segments, float)
    return float(np.linalg.norm(s[:, 1] - s[:, 0], axis=-1).sum())


def test_show_draws_a_box_solid_its_edges_and_clamped_face():
    """A box solid: its outline lies on the box's 12 edges, of total length 4 (Lx + Ly + Lz);
    the clamped face xmin's outline is its perimeter 2 (Ly + Lz); each view draws their
    projections in mm over a light fill, and the legend names material and element count."""
    a = space.of_scenario(scenario_io.from_dict(copy.deepcopy(ON_SOLID)))
    L = np.array([0.02, 0.01, 0.004])
    assert _length(a.solid_edges) == pytest.approx(4.0 * L.sum(), rel=1e-12)
    ends = a.solid_edges.reshape(-1, 3)
    on_extremes = (np.isclose(ends, 0.0, atol=1e-15) | np.isclose(ends, L, atol=1e-15)).sum(axis=1)
    assert np.all(on_extremes >= 2)  # on an edge of the box: two coordinates at a face
    assert _length(a.clamped_edges) == pytest.approx(2.0 * (L[1] + L[2]), rel=1e-12)
    assert np.allclose(a.clamped_edges[:, :, 0], 0.0)
    fig = space.draw(a)
    edges, clamped, fills = (_collections(fig, k) for k in ("solid-edges", "solid-clamped", "solid"))
    assert set(edges) == set(clamped) == set(fills) == {"xy", "xz", "yz"}
    for (u, v, _, _), view in zip(space.PROJECTIONS, ("xy", "xz", "yz")):
        drawn = np.array(edges[view].get_segments())
        assert np.allclose(drawn, a.solid_edges[:, :, [u, v]] * 1e3)
        assert min(to_rgb(fills[view].get_facecolor()[0])) > 0.7  # filled lightly
    texts = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert "elastic solid: bearing_steel, 8 hex20 elements, clamped: xmin" in texts, texts
    assert "clamped faces" in texts


def _l_shaped_msh(path, size: float):
    """Three cubes of side `size` [m] in an L (x-y plane: cells at (0,0), (1,0), (0,1)), the
    face x = 0 as the group 'left'."""
    pts = np.array([[x, y, z] for z in (0, 1) for y in (0, 1, 2) for x in (0, 1, 2)], float)
    node = lambda x, y, z: int(np.flatnonzero((pts == [x, y, z]).all(axis=1))[0])  # noqa: E731
    cube = lambda x, y: [
        node(x + dx, y + dy, dz)
        for dx, dy, dz in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]  # noqa: E731
    ]
    quads = [[node(0, y, 0), node(0, y + 1, 0), node(0, y + 1, 1), node(0, y, 1)] for y in (0, 1)]
    hexes = [cube(0, 0), cube(1, 0), cube(0, 1)]
    m = meshio.Mesh(
        pts * size,
        [("hexahedron", np.array(hexes)), ("quad", np.array(quads))],
        cell_data={"gmsh:physical": [np.full(3, 2), np.full(2, 1)], "gmsh:geometrical": [np.full(3, 2), np.full(2, 1)]},
        field_data={"left": np.array([1, 2]), "body": np.array([2, 3])},
    )
    meshio.write(str(path), m, file_format="gmsh22", binary=False)
    return str(path)


@pytest.mark.parametrize("radius,ok", [(0.004, True), (0.006, False)])
def test_show_draws_a_gmsh_solid_and_checks_its_surface(tmp_path, radius, ok):
    """An L-shaped body of three 10 mm cubes: its outline is the L prism's 18 edges (22 cube
    sides, one segment each), its clamped group 'left' outlined by its perimeter (6 sides); a sphere in
    the notch, 5 mm from the body (inside its bounding box), is drawn with radius 4 mm and
    refused with radius 6 mm, 1 mm too deep (the surface's signed distance, not the box's)."""
    from granplate.errors import ScenarioError
    from granplate.setup.validate import validate

    d = copy.deepcopy(ON_SOLID)
    d["plate"] = {"mesh": _l_shaped_msh(tmp_path / "l.msh", 0.01), "clamped": ["left"]}
    d["granules"] = [{"label": "notch", "x": 0.015, "y": 0.015, "z": 0.005, "radius": radius, "material": "steel"}]
    s = scenario_io.from_dict(d)
    validate(s)  # a mesh file's surface is read where it is drawn (or built), not by validate
    if not ok:
        with pytest.raises(ScenarioError, match="'notch'.* penetrates the elastic solid .*by 0.001 m") as e:
            space.of_scenario(s)
        assert e.value.field == "granules[0]"
        return
    a = space.of_scenario(s)
    assert _length(a.solid_edges) == pytest.approx(22 * 0.01, rel=1e-12) and len(a.solid_edges) == 22
    assert _length(a.clamped_edges) == pytest.approx(6 * 0.01, rel=1e-12)
    assert "3 hex20 elements" in a.solid_label
    space.draw(a)


def test_cli_show_a_solid_run_it_and_show_its_result(tmp_path, capsys):
    """`granplate show` of a 3D scenario with a solid writes its figure (status 0); `granplate
    run` of it (the verlet scheme, its file naming none) writes a result with the body's
    fields, which `granplate show` draws (status 0)."""
    toml = tmp_path / "on-solid.toml"
    gp.dump(scenario_io.from_dict(copy.deepcopy(ON_SOLID)), toml)
    assert main(["show", str(toml), "-o", str(tmp_path / "s.png")]) == 0
    assert (tmp_path / "s.png").stat().st_size > 500
    assert main(["run", str(toml), "-o", str(tmp_path / "r.nc"), "-q"]) == 0
    ds = gp.read(tmp_path / "r.nc")
    assert "body_ux" in ds and "max_von_mises_ball" in ds and ds.attrs["status"] == "ok"
    assert main(["show", str(tmp_path / "r.nc"), "-o", str(tmp_path / "r.png")]) == 0
    assert (tmp_path / "r.png").stat().st_size > 500
