"""The generic figures of a run on a 3D elastic body (`granplate plot RESULT`): the
body-stress figure draws the run's own largest von Mises stress, ball average and largest
displacement, body-contact-forces the normal force of exactly the granules that touched
the body, every axis with its unit; a 2D run skips the body figures and a 3D body run the
plate's figures, each with a one-line reason."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import granplate as gp
from granplate.cli import main
from granplate.errors import YieldWarning
from granplate.figures import run
from granplate.figures.cli import skipped_notes
from granplate.results.dataset import has_solid, write
from granplate.setup import io as scenario_io

from conftest import two_spheres

#: A steel sphere (R = 2.5 mm) dropped at 1 m/s on the top face of a 20 x 20 x 4 mm steel
#: box (4 x 4 x 1 hex20 elements) clamped on its face xmin, its contact lasting about
#: 18 us; a second sphere hangs above the box and never touches it.
DROP: dict = {
    "name": "drop-on-box",
    "dimension": 3,
    "granules": [
        {"label": "ball", "x": 0.01, "y": 0.01, "z": 0.0065, "radius": 0.0025, "material": "steel", "vz": -1.0},
        {"label": "aloft", "x": 0.004, "y": 0.004, "z": 0.012, "radius": 0.002, "material": "steel"},
    ],
    "plate": {
        "size": [0.02, 0.02, 0.004],
        "elements": [4, 4, 1],
        "origin": [0.0, 0.0, 0.0],
        "material": "steel",
        "clamped": ["xmin"],
    },
    "load": {"kind": "none"},
    "time": {"t_end": 4e-5, "output_interval": 1e-6, "field_interval": 1e-5},
}

#: The generic figures a 3D run on an elastic body has, in order.
BODY_FIGURES = ["energies", "body-stress", "body-contact-forces", "granule-speeds"]

#: A 1 m/s steel-on-steel impact passes Hertz's onset of yield (the run says so once).
pytestmark = pytest.mark.filterwarnings("ignore", category=YieldWarning)


@pytest.fixture(scope="module")
def drop():
    return gp.simulate(scenario_io.from_dict(copy.deepcopy(DROP)), progress=False)


def _lines(fig, gid):
    found = [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_gid() == gid]
    assert len(found) == 1, f"{len(found)} lines with gid {gid!r}"
    return found[0]


def _units_everywhere(fig):
    """Every axis with data states its unit in brackets (a shared time axis on its lowest panel)."""
    for ax in fig.axes:
        if ax.get_lines() or ax.collections:
            xlabels = [a.get_xlabel() for a in ax.get_shared_x_axes().get_siblings(ax)]
            assert any("[" in x for x in xlabels) and "[" in ax.get_ylabel(), (xlabels, ax.get_ylabel())


def test_the_drop_is_a_body_run(drop):
    """The run touched the body (a peak normal force of the order of 100 N), stressed and
    moved it, and kept its modes: what the figures below draw is not zero."""
    assert has_solid(drop) and drop.sizes["mode"] > 0
    force = drop.body_contact_normal_force.values
    assert 50.0 < force[:, 0].max() < 200.0 and np.all(force[:, 1] == 0.0)
    assert drop.max_von_mises.values.max() > 1e6 and drop.max_displacement.values.max() > 1e-7


def test_a_body_run_has_the_body_figures_and_not_the_plates(drop):
    """A 3D body run: energies, body-stress, body-contact-forces and speeds; the plate's
    contact-forces and stress-strain are refused, each with a one-line reason naming the
    body figure to read instead."""
    assert list(run.figures(drop)) == BODY_FIGURES
    assert run.missing("contact-forces", drop) == "the run's elastic body is a 3D solid: see body-contact-forces"
    assert run.missing("stress-strain", drop) == "eps_yy is a 2D plate strain; a 3D body has body-stress"


def test_a_body_run_without_touching_granules_says_so(drop):
    """No granule touched the body: body-contact-forces says so, contact-forces points to
    no figure; without granules at all, both say the run has none."""
    untouched = drop.assign(body_contact_normal_force=drop.body_contact_normal_force * 0.0)
    assert run.missing("body-contact-forces", untouched) == "no granule touched the body"
    assert run.missing("contact-forces", untouched) == "the run's elastic body is a 3D solid"
    bare = drop.isel(granule=slice(0, 0))
    assert run.missing("body-contact-forces", bare) == "the run has no granules"
    assert run.missing("granule-speeds", bare) == "the run has no granules"
    assert list(run.figures(bare)) == ["energies", "body-stress"]


def test_body_stress_draws_the_runs_maxima_in_mpa_and_um(drop):
    """The body-stress curves are the Dataset's max_von_mises and max_von_mises_ball / 1e6
    [MPa] and max_displacement * 1e6 [um] against time * 1e3 [ms], on axes with units."""
    fig = run.fig_body_stress(drop)
    t_ms = drop.time.values * 1e3
    for gid, values in (
        ("max_von_mises", drop.max_von_mises.values / 1e6),
        ("max_von_mises_ball", drop.max_von_mises_ball.values / 1e6),
        ("max_displacement", drop.max_displacement.values * 1e6),
    ):
        line = _lines(fig, gid)
        np.testing.assert_array_equal(line.get_ydata(), values)
        np.testing.assert_array_equal(line.get_xdata(), t_ms)
    assert "[MPa]" in _lines(fig, "max_von_mises").axes.get_ylabel()
    assert "[um]" in _lines(fig, "max_displacement").axes.get_ylabel()
    _units_everywhere(fig)


def test_body_contact_forces_draw_the_touching_granules(drop):
    """One curve per granule that touched the body, its normal force [N] over time [ms];
    the granule that never touched is not drawn."""
    fig = run.fig_body_contact_forces(drop)
    gids = {ln.get_gid() for ax in fig.axes for ln in ax.get_lines()}
    assert gids == {"body-normal:ball"}
    np.testing.assert_array_equal(
        _lines(fig, "body-normal:ball").get_ydata(), drop.body_contact_normal_force.values[:, 0]
    )
    assert "[N]" in fig.axes[0].get_ylabel()
    _units_everywhere(fig)


def test_many_touching_granules_draw_an_envelope_and_the_largest(drop):
    """Beyond MAX_LABELLED touching granules: their min-max envelope and the FASTEST
    largest by peak force, largest first."""
    n = run.MAX_LABELLED + 2
    scale = np.arange(1, n + 1, dtype=float)
    f = drop.body_contact_normal_force.values[:, :1] * scale[None, :]
    many = drop.isel(granule=[0] * n).assign_coords(granule=[f"g{k}" for k in range(n)])
    many["body_contact_normal_force"] = (("time", "granule"), f)
    fig = run.fig_body_contact_forces(many)
    (envelope,) = [c for c in fig.axes[0].collections if c.get_gid() == "body-normal:envelope"]
    assert envelope.get_paths()[0].vertices[:, 1].max() == pytest.approx(f.max())
    drawn = [ln.get_gid() for ln in fig.axes[0].get_lines()]
    assert drawn == [f"body-normal:g{k}" for k in range(n - 1, n - 1 - run.FASTEST, -1)]


def test_a_2d_run_refuses_the_body_figures():
    """Two spheres in the plane: no body-stress or body-contact-forces figure, the reason
    given; the 2D figures it can have are drawn."""
    ds = gp.simulate(two_spheres(0.01, t_end=2e-6, out=2e-7), progress=False)
    for name in ("body-stress", "body-contact-forces"):
        assert run.missing(name, ds) == "the run has no 3D elastic body"
    assert list(run.figures(ds)) == ["energies", "granule-speeds"]


def test_skipped_figures_are_one_note_per_reason():
    """Figures skipped for the same reason share one line, in figure order."""
    notes = skipped_notes(
        {
            "contact-forces": "no plate contacts",
            "stress-strain": "no plate",
            "body-stress": "no body",
            "body-contact-forces": "no body",
        }
    )
    assert notes == [
        "no contact-forces figure: no plate contacts",
        "no stress-strain figure: no plate",
        "no body-stress, body-contact-forces figures: no body",
    ]


def test_cli_plot_of_a_body_run(tmp_path, drop, capsys):
    """`granplate plot` of a 3D body result writes the body figures (PNG and PDF), status 0,
    and names the plate figures it skips with their reasons."""
    path = write(drop, tmp_path / "drop.nc")
    assert main(["plot", str(path), "--out", str(tmp_path / "figs")]) == 0
    out = capsys.readouterr().out
    written = sorted(p.name for p in (tmp_path / "figs").iterdir())
    assert written == sorted(f"drop-on-box-{n}.{e}" for n in BODY_FIGURES for e in ("png", "pdf"))
    assert "no contact-forces figure: the run's elastic body is a 3D solid: see body-contact-forces" in out
    assert "no stress-strain figure: eps_yy is a 2D plate strain; a 3D body has body-stress" in out


# --------------------------------------------------------------------------------------
# animate
# --------------------------------------------------------------------------------------
def _gif_frames(path) -> int:
    from PIL import Image

    with Image.open(path) as im:
        return im.n_frames


def test_frames_of_a_body_run_are_its_field_snapshots_on_one_scale(drop):
    """The frames of a body run are its field snapshots: each at the nearest output, its
    body the snapshot's displacement (one magnification for all, from the largest over the
    frames) and element stresses (one colour scale, the largest over the frames), its
    spheres where the run put them."""
    from granplate.figures import space

    times = space.frame_times(drop)
    np.testing.assert_array_equal(times, drop.field_time.values)
    idx = [0, 2, len(times) - 1]
    frames = space.frames_of_result(drop, idx)
    assert [a.time for a in frames] == pytest.approx(times[idx], abs=1e-15)
    assert len({a.body_scale for a in frames}) == 1
    stress = drop.body_von_mises.values[idx]
    assert all(a.stress_top == stress.max() for a in frames)
    for j, (a, k) in enumerate(zip(frames, idx)):
        ti = int(np.argmin(np.abs(drop.time.values - times[k])))
        np.testing.assert_array_equal(a.pos, space.positions(drop)[ti])
        assert np.isin(a.body_stress, stress[j]).all() and a.body_stress.max() == stress[j].max()
    largest = [
        float(np.linalg.norm(np.column_stack([drop[f"body_u{c}"].values[k] for c in "xyz"]), axis=1).max()) for k in idx
    ]
    assert [a.body_largest for a in frames] == pytest.approx(largest)
    assert frames[0].body_scale == space.magnification(max(largest), 0.02)  # the box's largest side


def test_the_animation_redraws_each_frame_where_the_run_was(drop):
    """draw(f) puts every sphere of each view at frame f's projected centre [mm] and draws
    the body's faces as frame f's; the title names the frame's time."""
    from granplate.figures import space

    frames = space.frames_of_result(drop, [0, 2, 4])
    fig, draw = space.animation(frames)
    for f, a in enumerate(frames):
        draw(f)
        for (u, v, _, _), view in zip(space.PROJECTIONS, ("xy", "xz", "yz")):
            circles = {
                p.get_gid().split(":")[1]: p
                for ax in fig.axes
                for p in ax.patches
                if str(p.get_gid()).startswith("granule:") and p.get_gid().endswith(f":{view}")
            }
            for i, lab in enumerate(a.labels):
                assert circles[lab].center == pytest.approx((a.pos[i, u] * 1e3, a.pos[i, v] * 1e3))
            (body,) = [c for ax in fig.axes for c in ax.collections if c.get_gid() == f"body:{view}"]
            drawn = np.sort(np.concatenate([p.vertices[:-1].ravel() for p in body.get_paths()]))
            faces = a.body_faces[:, :, [u, v]] * 1e3
            np.testing.assert_allclose(drawn, np.sort(faces.ravel()), atol=1e-9)
        assert f"t = {a.time * 1e3:.4g} ms" in fig._suptitle.get_text()


@pytest.mark.parametrize("frames, expected", [(3, 3), (None, 5)])
def test_animate_a_body_run_writes_its_frames(tmp_path, drop, frames, expected):
    """A GIF of the body run holds one frame per field snapshot (5), thinned to --frames."""
    from granplate.paper.animate import animate

    written = animate(drop, tmp_path / "drop.gif", frames=frames)
    assert written == tmp_path / "drop.gif" and _gif_frames(written) == expected


def test_cli_animate_show_export_of_a_body_run(tmp_path, drop, capsys):
    """`granplate animate` (a GIF of 3 frames), `show` and `export --vtk` of a 3D body
    result: status 0, their files written, no traceback."""
    path = write(drop, tmp_path / "drop.nc")
    assert main(["animate", str(path), "-o", str(tmp_path / "m.gif"), "--frames", "3"]) == 0
    assert _gif_frames(tmp_path / "m.gif") == 3
    assert main(["show", str(path), "-o", str(tmp_path / "s.png")]) == 0
    assert main(["export", str(path), "--vtk", str(tmp_path / "vtk")]) == 0
    assert (tmp_path / "s.png").stat().st_size > 1000 and (tmp_path / "vtk" / "drop-on-box.pvd").is_file()
    captured = capsys.readouterr()
    assert "Traceback" not in captured.out + captured.err


def test_show_draws_the_granules_contact_on_the_body(drop):
    """At an output where the ball presses the box, the drawing holds one granule-body
    contact line, from the ball's centre one radius along the force on the body (down,
    onto the top face), carrying that output's normal force; the sphere aloft has none."""
    from granplate.figures import space

    fn = np.nan_to_num(drop["body_contact_normal_force"].values)
    ti = int(np.argmax(fn[:, 0]))
    a = space._assembly_at(drop, space._result_scenario(drop)[0], ti, "test")
    body = [k for k, kind in enumerate(a.kinds) if kind == "body"]
    assert len(body) == 1
    (k,) = body
    assert a.forces[k] == pytest.approx(fn[ti, 0], rel=1e-12)
    start, end = a.segments[k]
    assert np.allclose(start, a.pos[0]) and end[2] == pytest.approx(a.pos[0, 2] - 0.0025, rel=1e-6)


def test_energies_draw_the_bodys_energy_and_the_whole_balance(drop):
    """The energy figure of a body run draws E_plate (the body's energy) and the sum
    E_granular + E_plate + D, which is E_shock + E_initial to the run's residual."""
    fig = run.fig_energies(drop)
    body = _lines(fig, "energy:plate")
    assert np.array_equal(body.get_ydata(), drop["E_plate"].values) and "elastic body" in body.get_label()
    total = _lines(fig, "energy:total")
    assert "E_{plate}" in total.get_label()
    e_in = float(drop["E_granular"].values[0])  # the ball's kinetic energy, no load
    assert np.allclose(total.get_ydata(), e_in, rtol=1e-4)
