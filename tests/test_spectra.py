"""Spectra of recorded signals: a pure sine's spectrum peaks at its frequency with its
amplitude, and the transmission of a scaled copy is the scale factor (closed forms)."""

import numpy as np
import pytest
import xarray as xr

from granplate.errors import ScenarioError
from granplate.results import spectra


def _result(n: int = 1000, dt: float = 1e-6) -> xr.Dataset:
    t = np.arange(n) * dt
    f0 = 50 * 1.0 / (n * dt)  # a bin frequency: 50 kHz
    wall = np.column_stack([3.0 + 2.0 * np.sin(2 * np.pi * f0 * t), 0.5 * np.sin(2 * np.pi * f0 * t)])
    ds = xr.Dataset(coords={"time": t, "wall": ["bottom", "top"], "drive": ["piston"]})
    ds["wall_force"] = (("time", "wall"), wall, {"units": "N"})
    ds["drive_displacement"] = (("time", "drive"), 1e-6 * np.sin(2 * np.pi * f0 * t)[:, None], {"units": "m"})
    ds.attrs["f0"] = f0
    return ds


def test_sine_peaks_at_its_frequency_with_its_amplitude():
    """A sine of amplitude 2 N at 50 kHz (a bin) on a 3 N mean: peak at 50 kHz reading 2 N."""
    ds = _result()
    t, x, unit = spectra.signal(ds, "wall_force:bottom")
    f, a = spectra.amplitude_spectrum(x, spectra.sample_interval(t))
    k = int(np.argmax(a))
    assert unit == "N"
    assert f[k] == pytest.approx(ds.attrs["f0"])
    assert a[k] == pytest.approx(2.0, rel=1e-9)
    assert a[0] < 1e-9  # the mean is removed


def test_transmission_of_a_scaled_copy_is_its_scale():
    """top = 0.25 bottom's oscillation: |X_top / X_bottom| = 0.25 wherever the reference is above its floor."""
    table = spectra.spectrum_table(_result(), ["wall_force:top"], reference="wall_force:bottom")
    tr = table["transmission"].values[0]
    ok = np.isfinite(tr)
    assert ok.sum() >= 3
    assert np.allclose(tr[ok], 0.25, rtol=1e-6)
    assert table["amplitude"].attrs["window"] == "hann"


def test_transmission_carries_the_ratio_of_the_units(tmp_path):
    """A wall force over a drive's displacement: 2 N per 1e-6 m at the drive's frequency = 2e6 N/m, so labelled."""
    table = spectra.spectrum_table(
        _result(), ["wall_force:bottom", "wall_force:top"], reference="drive_displacement:piston"
    )
    assert list(table["transmission_units"].values) == ["N/m", "N/m"]
    k = int(np.argmax(table["amplitude"].values[0]))
    assert table["transmission"].values[0, k] == pytest.approx(2e6, rel=1e-6)
    path = tmp_path / "t.csv"
    spectra.write_csv(table, str(path))
    assert "transmission wall_force:bottom [N/m]" in path.read_text().splitlines()[0]
    same = spectra.spectrum_table(_result(), ["wall_force:top"], reference="wall_force:bottom")
    assert list(same["transmission_units"].values) == ["1"]


def test_table_lists_every_signal_and_writes_csv(tmp_path):
    """Without names, every recorded signal is in the table; the CSV has one column per signal plus frequency."""
    table = spectra.spectrum_table(_result(), [])
    assert list(table["signal"].values) == ["wall_force:bottom", "wall_force:top", "drive_displacement:piston"]
    path = tmp_path / "s.csv"
    spectra.write_csv(table, str(path))
    head = path.read_text().splitlines()[0]
    assert head.startswith("frequency [Hz],amplitude wall_force:bottom [N]")
    assert np.loadtxt(path, delimiter=",", skiprows=1).shape == (table.sizes["frequency"], 4)


def test_unknown_signal_is_refused_naming_the_allowed_ones():
    """An unknown signal name is a ScenarioError listing what the result records."""
    with pytest.raises(ScenarioError, match="wall_force:bottom"):
        spectra.signal(_result(), "wall_force:side")
    with pytest.raises(ScenarioError, match="4 output times"):
        spectra.sample_interval(np.arange(3.0))


def test_plot_figure_spectrum_writes_figure_and_csv(tmp_path):
    """`granplate plot RESULT --figure spectrum --signal --reference` writes PNG, PDF and a CSV whose peak is the sine's."""
    from granplate.cli import main

    ds = _result()
    ds.attrs["scenario_name"] = "sine"
    path = tmp_path / "sine.nc"
    ds.to_netcdf(path)
    args = ["plot", str(path), "--figure", "spectrum", "--signal", "wall_force:top", "--reference", "wall_force:bottom"]
    assert main([*args, "--out", str(tmp_path)]) == 0
    assert (tmp_path / "sine-spectrum.png").is_file() and (tmp_path / "sine-spectrum.pdf").is_file()
    data = np.loadtxt(tmp_path / "sine-spectrum.csv", delimiter=",", skiprows=1)
    k = int(np.argmax(data[:, 1]))
    assert (
        data[k, 0] == pytest.approx(ds.attrs["f0"])
        and data[k, 1] == pytest.approx(0.5)
        and data[k, 2] == pytest.approx(0.25)
    )
