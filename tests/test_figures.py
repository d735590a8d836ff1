"""The generic figures and `granplate show` draw the run's own numbers and the model's own
contact network: every figure builds for a paper preset and for a two-sphere run without
a plate, the network has exactly the model's contacts, the drawn forces are Hertz's, and
the commands write their files or exit 2 with one clear line."""

from __future__ import annotations

import math

import numpy as np
import pytest

import granplate as gp
from granplate.cli import main
from granplate.figures import assembly, run, show
from granplate.figures.common import plot_curves, new_figure
from granplate.results.dataset import write
from granplate.setup.materials import LIBRARY, effective_modulus, sphere_mass

from conftest import two_spheres
from short_results import short_results

#: The generic figures of a 2D run with granules and a plate, in order.
PLATE_FIGURES = ["energies", "contact-forces", "stress-strain", "granule-speeds"]

#: Two steel spheres approaching at 0.1 m/s each (no damping): their collision lasts
#: about 84 us, so the run covers the largest overlap (~42 us) with outputs every 0.2 us.
SPHERE_SPEED = 0.1


@pytest.fixture(scope="module")
def steel():
    return short_results()["steel-r1"]


@pytest.fixture(scope="module")
def spheres():
    return gp.simulate(two_spheres(SPHERE_SPEED, t_end=6e-5, out=2e-7), progress=False)


@pytest.fixture(scope="module")
def files(tmp_path_factory, steel, spheres):
    d = tmp_path_factory.mktemp("results")
    return {"steel": write(steel, d / "steel-r1.nc"), "spheres": write(spheres, d / "two.nc")}


def _lines(fig, gid):
    found = [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_gid() == gid]
    assert found, f"no line with gid {gid!r}"
    return found


def _contacts(fig):
    (coll,) = [c for ax in fig.axes for c in ax.collections if c.get_gid() == "contacts"]
    return coll


def _model_contacts(scenario) -> int:
    m = gp.build_model(scenario)
    return len(m.pairs) + len(m.wall_contacts) + len(m.plate_contacts)


def _units_everywhere(fig):
    """Every axis with data states its unit in brackets (a shared time axis on its lowest panel)."""
    for ax in fig.axes:
        if ax.get_lines() or ax.collections:
            xlabels = [a.get_xlabel() for a in ax.get_shared_x_axes().get_siblings(ax)]
            assert any("[" in x for x in xlabels) and "[" in ax.get_ylabel(), (xlabels, ax.get_ylabel())


# --------------------------------------------------------------------------------------
# Generic figures of a run
# --------------------------------------------------------------------------------------
def test_every_figure_of_a_paper_preset_draws_its_numbers(steel):
    """steel-r1 has every quantity of a 2D run: its four figures, each curve the dataset's
    own values; the 3D body's figures are skipped with their reason."""
    figs = run.figures(steel)
    assert list(figs) == PLATE_FIGURES
    assert [n for n in run.FIGURES if n not in figs] == [
        "body-stress",
        "body-contact-forces",
        "wall-forces",
        "sensor-forces",
    ]
    assert run.missing("sensor-forces", steel) == "the run has no [[sensors]]"
    assert run.missing("wall-forces", steel).startswith("the run has no drives or gravity")
    for name in ("body-stress", "body-contact-forces"):
        assert run.missing(name, steel) == "the run has no 3D elastic body"
    for fig in figs.values():
        _units_everywhere(fig)
    e = figs["energies"]
    np.testing.assert_array_equal(_lines(e, "energy:plate")[0].get_ydata(), steel.E_plate.values)
    d = steel.D_viscous.values + steel.D_friction.values
    np.testing.assert_array_equal(_lines(e, "energy:dissipated")[0].get_ydata(), d)
    ref = float(steel.E_shock.values[-1])
    np.testing.assert_allclose(_lines(e, "fraction:shock")[0].get_ydata()[-1], 1.0, rtol=1e-12)
    np.testing.assert_allclose(_lines(e, "fraction:granular")[0].get_ydata(), steel.E_granular.values / ref)
    np.testing.assert_array_equal(_lines(e, "energy:residual")[0].get_ydata(), steel.energy_residual.values)
    np.testing.assert_allclose(_lines(e, "energy:plate")[0].get_xdata()[-1], 1e3 * float(steel.time[-1]))
    c = figs["contact-forces"]
    for k, lab in enumerate(steel.contact.values):
        np.testing.assert_array_equal(
            _lines(c, f"normal:{lab}")[0].get_ydata(), steel.contact_normal_force.values[:, k]
        )
        np.testing.assert_array_equal(
            _lines(c, f"tangential:{lab}")[0].get_ydata(), steel.contact_tangential_force.values[:, k]
        )
    s = figs["stress-strain"]
    np.testing.assert_allclose(_lines(s, "max_von_mises")[0].get_ydata(), steel.max_von_mises.values / 1e6)
    assert "MPa" in _lines(s, "max_von_mises")[0].axes.get_ylabel()
    v = figs["granule-speeds"]
    speeds = np.hypot(steel.vx.values, steel.vy.values)
    np.testing.assert_allclose(v.axes[0].collections[0].get_paths()[0].vertices[:, 1].max(), speeds.max())


def test_two_spheres_without_plate_skip_plate_figures(spheres):
    """No plate: energies (no E_plate curve) and speeds only; the others say why not."""
    figs = run.figures(spheres)
    assert list(figs) == ["energies", "granule-speeds"]
    assert run.missing("contact-forces", spheres) == "the run has no plate contacts"
    assert run.missing("stress-strain", spheres) == "the run has no plate"
    assert run.missing("body-stress", spheres) == "the run has no 3D elastic body"
    assert not [ln for ax in figs["energies"].axes for ln in ax.get_lines() if ln.get_gid() == "energy:plate"]
    assert "E_initial" in figs["energies"].axes[1].get_ylabel()  # no load: fractions of the initial energy
    for lab in ("a", "b"):
        k = list(spheres.granule.values).index(lab)
        np.testing.assert_allclose(
            _lines(figs["granule-speeds"], f"speed:{lab}")[0].get_ydata(),
            np.hypot(spheres.vx.values[:, k], spheres.vy.values[:, k]),
        )
    for fig in figs.values():
        _units_everywhere(fig)


def test_bare_plate_has_no_granule_figures():
    """The bare plate: energies (E_plate, no E_granular curve) and stress-strain only."""
    bare = short_results()["bare-plate"]
    figs = run.figures(bare)
    assert list(figs) == ["energies", "stress-strain"]
    gids = {ln.get_gid() for ax in figs["energies"].axes for ln in ax.get_lines()}
    assert "energy:plate" in gids and "energy:granular" not in gids
    assert run.missing("granule-speeds", bare) == "the run has no granules"


def test_coinciding_curves_stay_visible():
    """A curve equal to an earlier one is drawn dashed with markers and says which it equals."""
    fig = new_figure(3, 2)
    ax = fig.add_subplot()
    t = np.linspace(0, 1, 50)
    a, b, c = plot_curves(ax, t, [("A", np.sin(t), "a"), ("B", np.cos(t), "b"), ("E", np.sin(t), "e")])
    assert a.get_linestyle() == "-" and b.get_linestyle() == "-"
    assert c.get_linestyle() == "--" and c.get_marker() not in ("", "None", None) and c.get_label() == "E (= A)"


def test_curves_within_a_tolerance_coincide():
    """A curve 0.06% of the peak off an earlier one is drawn as coinciding under rtol = 1%
    (and says so), not under the default round-off tolerance; 2% off stays its own."""
    fig = new_figure(3, 2)
    ax = fig.add_subplot()
    t = np.linspace(0, 1, 50)
    y = np.sin(3 * t)
    curves = [("A", y, "a"), ("B", y + 6e-4 * y.max(), "b"), ("C", y + 2e-2 * y.max(), "c")]
    a, b, c = plot_curves(ax, t, curves, rtol=0.01)
    assert b.get_linestyle() == "--" and b.get_label() == "B (~ A within 1% of the peak)"
    assert c.get_linestyle() == "-" and c.get_label() == "C"
    assert all(ln.get_linestyle() == "-" for ln in plot_curves(fig.add_subplot(), t, curves))


def test_symmetric_plate_contacts_are_drawn_as_coinciding(steel):
    """steel-r1's plate contacts symmetric about the load's centre (A and E, B and D) carry
    equal forces; with D's made 0.06% larger (as a longer run leaves them), D is still
    drawn dashed with markers over B and its legend says "within 1% of the peak", E's
    says "= contact A"; the antisymmetric friction forces stay separate curves."""
    ds = steel.copy(deep=True)
    labels = [str(c) for c in ds.contact.values]
    assert labels == list("ABCDE")
    ds["contact_normal_force"].values[:, 3] *= 1.0006
    fig = run.fig_contact_forces(ds)
    (d,), (e,) = _lines(fig, "normal:D"), _lines(fig, "normal:E")
    for line in (d, e):
        assert line.get_linestyle() == "--" and line.get_marker() not in ("", "None", None)
    assert d.get_label() == "contact D (~ contact B within 1% of the peak)"
    assert e.get_label() == "contact E (= contact A)"
    assert all(_lines(fig, f"normal:{lab}")[0].get_linestyle() == "-" for lab in "ABC")
    assert _lines(fig, "tangential:D")[0].get_linestyle() == "-"  # -B's, not B's
    legend = [txt.get_text() for txt in fig.axes[0].get_legend().get_texts()]
    assert "contact D (~ contact B within 1% of the peak)" in legend


# --------------------------------------------------------------------------------------
# show: the assembly
# --------------------------------------------------------------------------------------
def test_show_scenario_draws_the_models_contact_network():
    """Before the run: one segment per model contact (27 pairs, 9 wall, 5 plate contacts for
    steel-r1), every granule, the 5 rigid layers, and load arrows on the 3 column-1
    granules that meet the load's y-range 25-75 mm (granules 2, 3, 4)."""
    s = gp.preset("steel-r1")
    fig = show.draw(assembly.of_scenario(s))
    assert len(_contacts(fig).get_segments()) == _model_contacts(s) == 27 + 9 + 5
    ax = fig.axes[0]
    assert sum(str(p.get_gid()).startswith("granule:") for p in ax.patches) == 14
    assert sum(str(ln.get_gid()).startswith("plate:rigid-layer:") for ln in ax.get_lines()) == 5
    arrows = [t for t in ax.texts if str(t.get_gid()).startswith("load:arrow:")]
    assert len(arrows) == 3
    assert sorted(round(a.xy[1]) for a in arrows) == [30, 50, 70]  # mm: the centres of 4, 3, 2
    assert ax.get_xlabel() == "x [mm]" and ax.get_ylabel() == "y [mm]"
    assert "steel-r1" in ax.get_title(loc="left")
    labels = {t.get_text() for t in ax.texts if str(t.get_gid()).startswith("label:")}
    assert labels == {str(g) for g in "123456789ABCDE"}


def test_show_result_forces_are_hertz_at_the_largest_overlap(spheres):
    """At the largest overlap of a head-on collision the drawn force is Hertz's peak,
    A delta_max^(3/2) with delta_max = (5 m* v^2 / (4 A))^(2/5) (energy conservation), and
    the line is the widest."""
    gap = spheres.x.values[:, 1] - spheres.x.values[:, 0]
    t_peak = float(spheres.time.values[np.argmin(gap)])
    a = assembly.of_result(spheres, t_peak)
    steel = LIBRARY["steel"]
    r = 0.01
    a_hertz = 4.0 / 3.0 * effective_modulus(steel, steel) * math.sqrt(r / 2)
    m_star = sphere_mass(r, steel.rho) / 2
    delta = (5 * m_star * (2 * SPHERE_SPEED) ** 2 / (4 * a_hertz)) ** 0.4
    np.testing.assert_allclose(a.forces, [a_hertz * delta**1.5], rtol=2e-3)
    fig = show.draw(a)
    coll = _contacts(fig)
    assert len(coll.get_segments()) == 1 and coll.get_linewidths()[0] == show.MAX_LINE_WIDTH
    assert "requested" in fig.axes[0].get_title(loc="left")
    default = assembly.of_result(spheres)
    assert default.time == float(spheres.time[-1]) and default.time_note == "last output time (no plate)"


def test_show_result_network_widths_and_plate(steel):
    """A result: the contacts of its contact table at that time and its plate contacts,
    their forces as stored, line widths proportional to the force, the default time a plate
    snapshot of largest E_plate with the plate deformed and the magnification in the title."""
    a = assembly.of_result(steel)
    on = steel.link_time.values == a.time
    assert on.sum() > 0 and len(a.segments) == on.sum() + steel.sizes["contact"]
    ti = int(np.argmin(np.abs(steel.time.values - a.time)))
    plate = [k for k, kind in enumerate(a.kinds) if kind == "plate"]
    np.testing.assert_allclose(a.forces[plate], np.maximum(steel.contact_normal_force.values[ti], 0.0))
    table = [k for k, kind in enumerate(a.kinds) if kind != "plate"]
    np.testing.assert_array_equal(np.sort(a.forces[table]), np.sort(steel.link_normal_force.values[on]))
    snaps = steel.field_time.values
    assert np.min(np.abs(snaps - a.time)) < 1e-12
    ep_snap = [float(steel.E_plate.sel(time=t, method="nearest")) for t in snaps]
    assert float(steel.E_plate.values[ti]) == max(ep_snap)
    assert a.plate.deformed and a.plate.magnify >= 1
    fig = show.draw(a)
    coll = _contacts(fig)
    assert len(coll.get_segments()) == len(a.segments)
    w, f = coll.get_linewidths(), a.forces
    loaded = f > show.OPEN_FRACTION * f.max()
    np.testing.assert_allclose(w[loaded] / show.MAX_LINE_WIDTH, f[loaded] / f.max())
    assert f"x{a.plate.magnify:g}" in fig.axes[0].get_title(loc="left")
    assert any("contact normal force [N]" in ax.get_xlabel() for ax in fig.axes)


def test_default_time_when_the_plate_never_moved(steel):
    """A plate that never moved (E_plate 0 throughout) gives no plate peak to show: the
    default time is the output of largest granular energy, named so in the title."""
    still = steel.copy()
    still["E_plate"] = still["E_plate"] * 0.0
    i, note = assembly.choose_time(still, None)
    assert i == int(np.argmax(steel["E_granular"].values)) and i > 0
    assert note == "time of the largest granular energy (the plate never moved)"


def test_time_outside_the_run_is_refused(steel):
    with pytest.raises(gp.ScenarioError, match="--time"):
        assembly.of_result(steel, 1.0)
    with pytest.raises(gp.ScenarioError, match="--time"):
        assembly.of_result(steel, -1e-5)


def test_label_size_follows_the_radius():
    """Labels scale with the drawn radius and are skipped when too small to read."""
    assert show.label_font_size(10.0, "3") > show.label_font_size(6.0, "3") > 0
    assert show.label_font_size(1.0, "3") == 0.0
    assert show.label_font_size(100.0, "A") == show.MAX_FONT


# --------------------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------------------
def test_cli_show_scenario_preset_and_result(tmp_path, files, capsys):
    toml = tmp_path / "two.toml"
    gp.dump(two_spheres(SPHERE_SPEED), toml)
    for target, out in (
        (str(toml), "a.png"),
        ("steel-r1", "b.png"),
        (str(files["steel"]), "c.png"),
        (str(files["spheres"]), "d.pdf"),
    ):
        assert main(["show", target, "-o", str(tmp_path / out)]) == 0
        assert (tmp_path / out).stat().st_size > 1000
    assert main(["show", str(files["steel"]), "--time", "4e-5", "-o", str(tmp_path / "e.png")]) == 0
    assert "written" in capsys.readouterr().out


def test_cli_plot_generic_figures(tmp_path, files, capsys):
    """Without --figure: PNG + PDF per figure; the figures a run lacks are a printed note,
    one line per reason."""
    assert main(["plot", str(files["steel"]), str(files["spheres"]), "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    written = sorted(p.name for p in tmp_path.iterdir())
    expected = [f"steel-r1-{n}.{e}" for n in PLATE_FIGURES for e in ("png", "pdf")]
    expected += [f"two-spheres-{n}.{e}" for n in ("energies", "granule-speeds") for e in ("png", "pdf")]
    assert written == sorted(expected)
    assert "no stress-strain figure: the run has no plate" in out
    assert out.count("no body-stress, body-contact-forces figures: the run has no 3D elastic body") == 2


@pytest.mark.parametrize(
    "argv, words",
    [
        (["show", "no-such.nc"], ("no-such.nc", "no such file")),
        (["show", "no-such-preset"], ("no-such-preset", "no such file or preset")),
        (["plot", "no-such.nc"], ("no-such.nc", "no such file")),
    ],
)
def test_cli_bad_input_exits_2(argv, words, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("granplate: error:") and err.count("\n") == 1 and "Traceback" not in err
    assert all(w in err for w in words)


def test_cli_time_outside_or_on_a_scenario_exits_2(files, capsys):
    assert main(["show", str(files["steel"]), "--time", "1"]) == 2
    err = capsys.readouterr().err
    assert "--time" in err and "0.0001 s" in err and err.count("\n") == 1
    assert main(["show", "steel-r1", "--time", "1e-5"]) == 2
    assert "only with a result" in capsys.readouterr().err


def test_show_result_draws_contacts_formed_during_the_run():
    """Two spheres 1 mm apart: no contact line at t = 0, one at the time of closest approach."""
    from granplate.setup.scenario import Granule, Load, Scenario, TimeSettings

    s = Scenario(
        name="head-on",
        granules=(
            Granule(x=0.01, y=0.05, radius=0.01, material="steel", label="a", vx=1.0),
            Granule(x=0.031, y=0.05, radius=0.01, material="steel", label="b", vx=-1.0),
        ),
        load=Load(kind="none"),
        time=TimeSettings(t_end=6e-4, output_interval=2e-6, field_interval=2e-6),
    )
    ds = gp.simulate(s, progress=False)
    gap = (ds.x.values[:, 1] - ds.x.values[:, 0]) - 0.02
    start = assembly.of_result(ds, float(ds.time[0]))
    closest = assembly.of_result(ds, float(ds.time[int(np.argmin(gap))]))
    assert gap.min() < 0 < gap[0]
    assert list(start.kinds).count("granule") == 0
    assert list(closest.kinds).count("granule") == 1


def test_energies_of_a_yielding_impact_count_the_plastic_work():
    """Two steel spheres meeting at 1 m/s under Thornton's law (well past their yield
    velocity): the drawn dissipation is D_viscous + D_friction + D_plastic and the drawn
    sum E_granular + D keeps the energy put in (eq. 11), to the run's residual."""
    ds = gp.simulate(two_spheres(1.0, t_end=6e-5, out=2e-7, normal_law="thornton"), progress=False)
    plastic = ds.D_plastic.values
    assert run.has_plastic_work(ds) and plastic[-1] > 0.1 * float(ds.attrs["E_initial"])
    e = run.fig_energies(ds)
    np.testing.assert_array_equal(
        _lines(e, "energy:dissipated")[0].get_ydata(), ds.D_viscous.values + ds.D_friction.values + plastic
    )
    total = _lines(e, "energy:total")[0].get_ydata()
    e_in = float(ds.attrs["E_initial"])
    assert np.max(np.abs(total - e_in)) / e_in <= np.max(np.abs(ds.energy_residual.values)) + 1e-12
    assert "D_{plastic}" in _lines(e, "energy:dissipated")[0].get_label()
    # an elastic run keeps the label and curve without the plastic term
    assert not run.has_plastic_work(gp.simulate(two_spheres(0.01, t_end=2e-6, out=2e-7), progress=False))
