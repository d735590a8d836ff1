"""Every paper figure draws its datasets' own numbers (no copies, no typed-in values),
with units on its axes and a caption, and is written as PNG and PDF."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.paper import plots

from short_results import short_results


@pytest.fixture(scope="module")
def runs():
    return short_results()


def _all_axes(fig):
    """The figure's axes and their insets."""
    return [a for ax in fig.axes for a in [ax, *ax.child_axes]]


def _lines(fig, gid):
    found = [ln for ax in _all_axes(fig) for ln in ax.get_lines() if ln.get_gid() == gid]
    assert found, f"no line with gid {gid!r}"
    return found


def _meshes(fig, gid):
    found = [c for ax in fig.axes for c in ax.collections if c.get_gid() == gid]
    assert found, f"no image with gid {gid!r}"
    return found


def _normalised(ds, var):
    """var / (E_shock at the end + E_initial), computed here from the raw variables."""
    ref = float(ds.E_shock.values[-1]) + float(ds.attrs.get("E_initial", 0.0))
    return ds[var].values / ref


def _check_axes_and_caption(fig):
    assert plots.caption_of(fig).startswith("Fig.")
    for ax in _all_axes(fig):
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            if label:
                assert "[" in label and "]" in label, f"label without units: {label!r}"
        if getattr(ax, "_colorbar", None) is not None:  # a colour bar: its one label has units
            assert ax.get_xlabel() or ax.get_ylabel()
            continue
        if ax.get_lines() or ax.collections:
            has_x = ax.get_xlabel() or any(o.get_xlabel() for o in ax.get_shared_x_axes().get_siblings(ax))
            assert has_x, "an axis with data but no x label"


def test_fig3_draws_stress_and_energies(runs):
    """Fig. 3: (a, b) max von Mises [MPa] of each run; (c) E_g, E_p, sums over E_shock."""
    bare, steel = runs["bare-plate"], runs["steel-r1"]
    fig = plots.fig_3(bare, steel)
    vm = _lines(fig, "max_von_mises")
    assert len(vm) == 2
    np.testing.assert_array_equal(vm[0].get_ydata(), bare.max_von_mises.values / 1e6)
    np.testing.assert_array_equal(vm[1].get_ydata(), steel.max_von_mises.values / 1e6)
    np.testing.assert_array_equal(vm[1].get_xdata(), steel.time.values * 1e3)
    np.testing.assert_allclose(_lines(fig, "energy:plate")[0].get_ydata(), _normalised(steel, "E_plate"), rtol=1e-12)
    np.testing.assert_allclose(
        _lines(fig, "energy:granular")[0].get_ydata(), _normalised(steel, "E_granular"), rtol=1e-12
    )
    total = (
        _normalised(steel, "E_plate")
        + _normalised(steel, "E_granular")
        + _normalised(steel, "D_viscous")
        + _normalised(steel, "D_friction")
    )
    np.testing.assert_allclose(_lines(fig, "energy:total")[0].get_ydata(), total, rtol=1e-12)
    _check_axes_and_caption(fig)
    assert "bare-plate" in plots.caption_of(fig) and "steel-r1" in plots.caption_of(fig)


def test_fig3_follows_a_changed_dataset(runs):
    """Changing the dataset changes the figure: it plots the data, not a stored copy."""
    steel = runs["steel-r1"].copy(deep=True)
    steel["E_plate"] = steel["E_plate"] * 0.5
    fig = plots.fig_3(runs["bare-plate"], steel)
    np.testing.assert_allclose(
        _lines(fig, "energy:plate")[0].get_ydata(), 0.5 * _normalised(runs["steel-r1"], "E_plate"), rtol=1e-12
    )


def test_fig4_two_sizes_energies_kinetic_velocities(runs):
    """Fig. 4: per size, energies, KE split [mJ] and vx, vy of granules 3, 8, C."""
    r1, r05 = runs["steel-r1"], runs["steel-r05"]
    fig = plots.fig_4(r1, r05)
    for k, ds in enumerate((r1, r05)):
        np.testing.assert_allclose(_lines(fig, "energy:plate")[k].get_ydata(), _normalised(ds, "E_plate"), rtol=1e-12)
        for part, var in (
            ("horizontal", "KE_horizontal"),
            ("vertical", "KE_vertical"),
            ("rotational", "KE_rotational"),
        ):
            np.testing.assert_allclose(_lines(fig, f"kinetic:{part}")[k].get_ydata(), ds[var].values * 1e3, rtol=1e-12)
        for lab in ("3", "8", "C"):
            np.testing.assert_array_equal(_lines(fig, f"vx:{lab}")[k].get_ydata(), ds.vx.sel(granule=lab).values)
            np.testing.assert_array_equal(_lines(fig, f"vy:{lab}")[k].get_ydata(), ds.vy.sel(granule=lab).values)
    _check_axes_and_caption(fig)


def test_fig5_ptfe(runs):
    """Fig. 5: PTFE energies, kinetic split and velocities of granules 3, 8, C."""
    ds = runs["ptfe-r05"]
    fig = plots.fig_5(ds)
    np.testing.assert_allclose(_lines(fig, "energy:granular")[0].get_ydata(), _normalised(ds, "E_granular"), rtol=1e-12)
    np.testing.assert_allclose(_lines(fig, "kinetic:vertical")[0].get_ydata(), ds.KE_vertical.values * 1e3, rtol=1e-12)
    np.testing.assert_array_equal(_lines(fig, "vx:8")[0].get_ydata(), ds.vx.sel(granule="8").values)
    _check_axes_and_caption(fig)


def test_fig6_space_time_maps(runs):
    """Fig. 6: the colour maps hold vx of columns 1..3 (top to bottom) and the plate's line."""
    steel, ptfe = runs["steel-r05"], runs["ptfe-r05"]
    fig = plots.fig_6(steel, ptfe)
    for k, ds in enumerate((steel, ptfe)):
        for c, labels in enumerate((list("12345"), list("6789"), list("ABCDE")), start=1):
            mesh = _meshes(fig, f"vx:column{c}")[k]
            np.testing.assert_array_equal(
                np.asarray(mesh.get_array()).reshape(len(ds.time), -1), ds.vx.sel(granule=labels).values
            )
        plate = _meshes(fig, "vx:plate")[k]
        np.testing.assert_array_equal(
            np.asarray(plate.get_array()).reshape(len(ds.time), -1), ds.plate_vx_symmetry.values
        )
    _check_axes_and_caption(fig)


def test_fig7_strain(runs):
    """Fig. 7: max |eps_yy| in microstrain, steel then PTFE."""
    steel, ptfe = runs["steel-r05"], runs["ptfe-r05"]
    fig = plots.fig_7(steel, ptfe)
    lines = _lines(fig, "max_eps_yy")
    np.testing.assert_allclose(lines[0].get_ydata(), steel.max_eps_yy.values * 1e6, rtol=1e-12)
    np.testing.assert_allclose(lines[1].get_ydata(), ptfe.max_eps_yy.values * 1e6, rtol=1e-12)
    _check_axes_and_caption(fig)


def test_fig8_three_intensities(runs):
    """Fig. 8: each panel (and its zoom) shows its own run's plate share."""
    cases = [runs[n] for n in ("ptfe-r05-weak", "ptfe-r05-moderate", "ptfe-r05")]
    fig = plots.fig_8(*cases)
    for k, ds in enumerate(cases):
        np.testing.assert_allclose(_lines(fig, "energy:plate")[k].get_ydata(), _normalised(ds, "E_plate"), rtol=1e-12)
        np.testing.assert_allclose(
            _lines(fig, "energy-zoom:plate")[k].get_ydata(), _normalised(ds, "E_plate"), rtol=1e-12
        )
    assert "q0 = 2 kN/m" in fig.axes[0].get_title(loc="left")
    _check_axes_and_caption(fig)


def test_figA1_local_map_modulus(runs):
    """Fig. A.1: |lambda| of contacts A, B, C from the dataset."""
    ds = runs["steel-r1"]
    fig = plots.fig_A1(ds)
    for lab in ("A", "B", "C"):
        np.testing.assert_array_equal(
            _lines(fig, f"lambda:{lab}")[0].get_ydata(), ds.local_map_modulus.sel(contact=lab).values
        )
    _check_axes_and_caption(fig)


def test_save_writes_png_and_pdf(runs, tmp_path):
    """save_figure writes STEM.png and STEM.pdf, both non-empty."""
    paths = plots.save_figure(plots.fig_7(runs["steel-r05"], runs["ptfe-r05"]), tmp_path, "fig7")
    assert [p.name for p in paths] == ["fig7.png", "fig7.pdf"]
    assert paths[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert paths[1].read_bytes()[:4] == b"%PDF"


@pytest.mark.parametrize(
    "name, key", [("3", "3"), ("fig4", "4"), ("Fig. 5", "5"), ("A.1", "A1"), ("a1", "A1"), ("figA1", "A1")]
)
def test_figure_names(name, key):
    """Figure names are read loosely; every figure names the presets it needs."""
    assert plots.figure_key(name) == key


def test_unknown_figure_name():
    with pytest.raises(KeyError):
        plots.figure_key("9")


def test_paper_figure_of_a_custom_scenario_is_a_clean_error(tmp_path, capsys):
    """`granplate plot FILE --figure 5` on a two-sphere result: exit 2, one line naming the
    figure and what it needs (granules 3, 8, C and a plate), no traceback."""
    import granplate as gp
    from granplate.cli import main
    from granplate.results.dataset import write

    from conftest import two_spheres

    path = write(gp.simulate(two_spheres(0.1, t_end=2e-6, out=1e-6), progress=False), tmp_path / "two.nc")
    for figure, needs, n in (("5", "granules 3, 8 and C", 1), ("A1", "contacts A, B and C", 1), ("7", "a plate", 2)):
        assert main(["plot", *[str(path)] * n, "--figure", figure, "--out", str(tmp_path)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("granplate: error:") and "Traceback" not in err and err.count("\n") == 1
        assert f"figure {figure}" in err and needs in err and "two-spheres" in err


def test_coinciding_vertical_velocities_stay_visible(runs):
    """Granules 3 and C have vy = 0 (symmetry; round-off apart): C is drawn dashed with
    markers over 3 and its legend says so; the panel letters are distinct; units stay."""
    fig = plots.fig_5(runs["ptfe-r05"])
    (line3,), (lineC,) = _lines(fig, "vy:3"), _lines(fig, "vy:C")
    ax = lineC.axes
    top = max(float(np.max(np.abs(ln.get_ydata()))) for ln in lineC.axes.get_lines())
    assert np.max(np.abs(line3.get_ydata() - lineC.get_ydata())) <= plots.COINCIDE * top
    assert lineC.get_linestyle() != line3.get_linestyle() and lineC.get_marker() not in ("", "None", None)
    assert "= granule 3" in lineC.get_label()
    assert "[m/s]" in ax.get_ylabel() and "[ms]" in ax.get_xlabel()
    titles = [a.get_title(loc="left")[:3] for a in fig.axes if a.get_title(loc="left")]
    assert len(titles) == len(set(titles)) == 4
    fig4 = plots.fig_4(runs["steel-r1"], runs["steel-r05"])
    letters = [a.get_title(loc="left")[:3] for a in fig4.axes if a.get_title(loc="left")]
    assert sorted(letters) == [f"({c})" for c in "abcdefgh"]
    _check_axes_and_caption(fig)
    _check_axes_and_caption(fig4)
