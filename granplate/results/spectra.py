"""Spectra of recorded signals and the transmission between two of them.

A signal is one column of a time-indexed Dataset variable: `wall_force` (time, wall),
`drive_force` or `drive_displacement` (time, drive), `sensor_force` (sensor_time, sensor:
on the sensors' own time axis), named "VARIABLE:LABEL" (e.g. "wall_force:bottom",
"drive_displacement:piston", "sensor_force:b10"). The signals of one table share their
sample times. The spectrum is the one-sided
amplitude spectrum of the (periodic) Hann-windowed signal, scaled so that a sine of amplitude a at
a bin frequency reads a (docs/output.md, "Spectra"):

    X(f_k) = (2 / sum_n w_n) |sum_n w_n x_n exp(-2 pi i k n / N)|,  w_n = Hann window,

with its mean removed first (a static preload would otherwise leak into the low bins).
The transmission between an output and a reference signal is abs(X_out(f) / X_in(f)) with
the same window; bins where the reference is below `floor` times its peak are NaN.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from granplate.errors import ScenarioError

SIGNAL_VARIABLES = ("wall_force", "drive_force", "drive_displacement", "sensor_force")
WINDOW = "hann"


def signal_names(ds: xr.Dataset) -> list[str]:
    """Every recorded signal of the result as "VARIABLE:LABEL", in Dataset order."""
    names = []
    for var in SIGNAL_VARIABLES:
        if var in ds:
            dim = ds[var].dims[1]
            names += [f"{var}:{lab}" for lab in ds[dim].values]
    return names


def signal(ds: xr.Dataset, name: str) -> tuple[np.ndarray, np.ndarray, str]:
    """The times [s], values and unit of the signal "VARIABLE:LABEL" (a bare VARIABLE
    with one column is accepted); a ScenarioError names the allowed signals otherwise."""
    allowed = signal_names(ds)
    var, _, label = name.partition(":")
    if var not in SIGNAL_VARIABLES or var not in ds:
        raise ScenarioError("--signal", name, "allowed: " + (", ".join(allowed) or "none (the run records none)"))
    da = ds[var]
    dim = da.dims[1]
    labels = [str(v) for v in ds[dim].values]
    if label == "" and len(labels) == 1:
        label = labels[0]
    if label not in labels:
        raise ScenarioError("--signal", name, "allowed: " + ", ".join(allowed))
    values = np.asarray(da.values[:, labels.index(label)], dtype=float)
    t = np.asarray(ds[da.dims[0]].values, dtype=float)
    return t, values, str(da.attrs.get("units", ""))


def sample_interval(t: np.ndarray) -> float:
    """The uniform sample interval [s] of times t; ScenarioError if fewer than 4 samples or
    the spacing varies by more than 1e-6 of the interval."""
    if t.size < 4:
        raise ScenarioError("signal", f"{t.size} samples", "a spectrum needs at least 4 output times")
    dt = np.diff(t)
    h = float(np.mean(dt))
    if h <= 0 or np.max(np.abs(dt - h)) > 1e-6 * h:
        raise ScenarioError("signal", "output times", "a spectrum needs uniformly spaced output times")
    return h


def amplitude_spectrum(x: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies [Hz] and the one-sided Hann-windowed amplitude spectrum (the signal's
    units) of samples x at interval dt [s]; a sine of amplitude a at a bin frequency
    reads a there (coherent gain sum(w)/2 divided out)."""
    x = np.asarray(x, dtype=float)
    w = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(x.size) / x.size)  # periodic Hann
    spec = np.fft.rfft(w * (x - x.mean()))
    f = np.fft.rfftfreq(x.size, dt)
    amp = 2.0 * np.abs(spec) / w.sum()
    amp[0] /= 2.0
    return f, amp


def transmission(x_out: np.ndarray, x_in: np.ndarray, dt: float, floor: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies [Hz] and abs(X_out / X_in) of two equally sampled signals (same Hann
    window); NaN where the reference's amplitude is below floor times its peak."""
    f, a_out = amplitude_spectrum(x_out, dt)
    _, a_in = amplitude_spectrum(x_in, dt)
    ratio = np.full_like(a_out, np.nan)
    ok = a_in > floor * a_in.max() if a_in.max() > 0 else np.zeros(a_in.shape, bool)
    ratio[ok] = a_out[ok] / a_in[ok]
    return f, ratio


def ratio_unit(unit: str, ref_unit: str) -> str:
    """The unit of a signal in `unit` over a reference in `ref_unit`: "1" where they agree."""
    return "1" if unit == ref_unit else f"{unit}/{ref_unit}"


def spectrum_table(ds: xr.Dataset, names: list[str], reference: str | None = None) -> xr.Dataset:
    """The spectra of the named signals (none: every signal on the first one's time axis;
    all on the same sample times) (and, with a reference, each one's transmission
    relative to it) as a Dataset on a `frequency` [Hz] coordinate: `amplitude` (signal,
    frequency) in each signal's units and `transmission` (signal, frequency) in the signal's
    unit over the reference's (`transmission_units`: "1" where they agree, "N/m" for a
    force over a displacement)."""
    if not names:  # every signal on the first one's time axis
        names = signal_names(ds)
        axis = ds[names[0].partition(":")[0]].dims[0] if names else None
        names = [n for n in names if ds[n.partition(":")[0]].dims[0] == axis]
    if not names:
        raise ScenarioError("--signal", "none", "the run records no wall, drive or sensor signal")
    rows, units, trans = [], [], []
    f = np.zeros(0)
    t0 = None
    ref_unit = ""
    if reference:
        t0, ref, ref_unit = signal(ds, reference)
    else:
        ref = None
    for name in names:
        t, x, unit = signal(ds, name)
        if t0 is None:
            t0 = t
        elif t.shape != t0.shape or not np.allclose(t, t0, rtol=0.0, atol=1e-9 * float(np.ptp(t0) or 1.0)):
            first = reference if reference else names[0]
            raise ScenarioError(
                "--signal",
                name,
                f"its samples are not those of {first} ({t.size} against {t0.size} times): signals on "
                "different time axes (the output's `time`, the sensors' `sensor_time`) go in separate spectra",
            )
        dt = sample_interval(t)
        f, amp = amplitude_spectrum(x, dt)
        rows.append(amp)
        units.append(unit)
        if ref is not None:
            trans.append(transmission(x, ref, dt)[1])
    out = xr.Dataset(coords={"frequency": ("frequency", f, {"units": "Hz"}), "signal": ("signal", names)})
    out["amplitude"] = (("signal", "frequency"), np.array(rows))
    out["amplitude"].attrs = {"units": ",".join(units), "window": WINDOW, "long_name": "one-sided amplitude spectrum"}
    out["signal_units"] = ("signal", units)
    if ref is not None:
        t_units = [ratio_unit(u, ref_unit) for u in units]
        out["transmission"] = (("signal", "frequency"), np.array(trans))
        out["transmission"].attrs = {"units": ",".join(t_units), "window": WINDOW, "reference": str(reference)}
        out["transmission_units"] = ("signal", t_units)
    return out


def write_csv(table: xr.Dataset, path: str) -> None:
    """The spectra as CSV: a frequency column [Hz], then each signal's amplitude (and
    transmission) column, headed "amplitude NAME [UNIT]" / "transmission NAME [UNIT/REF]"
    ("1" where the two units agree)."""
    cols = [table["frequency"].values]
    head = ["frequency [Hz]"]
    for i, name in enumerate(table["signal"].values):
        cols.append(table["amplitude"].values[i])
        head.append(f"amplitude {name} [{table['signal_units'].values[i]}]")
        if "transmission" in table:
            cols.append(table["transmission"].values[i])
            head.append(f"transmission {name} [{table['transmission_units'].values[i]}]")
    np.savetxt(path, np.column_stack(cols), delimiter=",", header=",".join(head), comments="")
