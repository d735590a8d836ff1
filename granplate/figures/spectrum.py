"""The spectrum figure of a result (`granplate plot RESULT --figure spectrum`): the
amplitude spectrum of each chosen signal (a) in its units against frequency [kHz], and
with a reference signal the transmission abs(X_out / X_ref) (b) on a log scale, in the
signal's unit over the reference's ([1] where they agree); the
numbers are written beside it as CSV (`granplate.results.spectra`, docs/output.md)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from granplate.figures.common import new_figure, save_figure, scenario_name
from granplate.results import spectra


def fig_spectrum(table: xr.Dataset, title: str = "") -> Figure:
    """Amplitude spectra (a) and, where the table has one, transmission (b)."""
    has_tr = "transmission" in table
    fig = new_figure(9.0, 3.0 * (1 + int(has_tr)) + 0.6)
    axes = list(np.atleast_1d(fig.subplots(1 + int(has_tr), 1, sharex=True)))
    f_khz = 1e-3 * table["frequency"].values
    for i, name in enumerate(table["signal"].values):
        unit = table["signal_units"].values[i]
        axes[0].semilogy(f_khz[1:], table["amplitude"].values[i, 1:], lw=1.0, label=f"{name} [{unit}]")
        if has_tr:
            t_unit = table["transmission_units"].values[i]
            axes[1].semilogy(f_khz[1:], table["transmission"].values[i, 1:], lw=1.0, label=f"{name} [{t_unit}]")
    axes[0].set_ylabel("amplitude [signal's unit]")
    axes[0].set_title("(a) one-sided amplitude spectrum, Hann window", loc="left", fontsize=10)
    axes[0].legend(fontsize=8, frameon=False)
    if has_tr:
        ref = table["transmission"].attrs["reference"]
        t_units = sorted(set(table["transmission_units"].values.tolist()))
        axes[1].set_ylabel(
            f"transmission [{t_units[0]}]" if len(t_units) == 1 else "transmission [signal's unit / reference's]"
        )
        axes[1].legend(fontsize=8, frameon=False)
        axes[1].set_title(f"(b) |X / X_ref|, reference {ref}", loc="left", fontsize=10)
    axes[-1].set_xlabel("frequency [kHz]")
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def plot_spectra(paths: list[Path], names: list[str], reference: str | None, out_dir: str) -> int:
    """Draw NAME-spectrum.png/.pdf and write NAME-spectrum.csv for each result; exit status 0."""
    from granplate.results.dataset import read

    for path in paths:
        ds = read(str(path))
        stem = ds.attrs.get("scenario_name") or path.stem
        table = spectra.spectrum_table(ds, names, reference)
        for written in save_figure(fig_spectrum(table, scenario_name(ds)), out_dir, f"{stem}-spectrum"):
            print(f"written {written}")
        csv = Path(out_dir) / f"{stem}-spectrum.csv"
        spectra.write_csv(table, str(csv))
        print(f"written {csv}")
    return 0
