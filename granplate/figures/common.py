"""Shared pieces of every figure: the Figure factory, saving, time axes, colours."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # matplotlib and xarray load when a figure is drawn, not when the CLI starts
    import xarray as xr
    from matplotlib.figure import Figure

#: Resolution of the PNG files [dots per inch].
PNG_DPI = 150

#: Colours of the library's materials; other materials take the next of OTHER_COLOURS.
MATERIAL_COLOURS = {"steel": "#8fa3b8", "ptfe": "#f2c14e"}
OTHER_COLOURS = ("#7fc97f", "#beaed4", "#fdc086", "#f0027f", "#bf5b17", "#66a61e")


#: (unit, seconds) from the largest: a duration is written in the largest unit it reaches.
DURATION_UNITS = (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6), ("ns", 1e-9))


def readable_duration(seconds: float) -> str:
    """A duration [s] in the largest unit it reaches, 4 significant digits at most: 0.1 ->
    "100 ms", 2e-5 -> "20 µs", 1.5 -> "1.5 s", 3e-10 -> "0.3 ns"."""
    for unit, size in DURATION_UNITS:
        if abs(seconds) >= size:
            return f"{seconds / size:.4g} {unit}"
    return f"{seconds / DURATION_UNITS[-1][1]:.4g} ns"


def new_figure(width: float, height: float) -> Figure:
    """A Figure [inches] on the Agg canvas with constrained layout."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig: Figure, out_dir: str | Path, stem: str, dpi: int = PNG_DPI) -> list[Path]:
    """Write fig as STEM.png and STEM.pdf in out_dir (created); returns the two paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"{stem}.png", out / f"{stem}.pdf"]
    fig.savefig(paths[0], dpi=dpi)
    fig.savefig(paths[1])
    return paths


def material_colours(names) -> dict[str, str]:
    """A fixed colour per material name (library materials always the same colour)."""
    out, k = {}, 0
    for name in names:
        if name in out:
            continue
        if name in MATERIAL_COLOURS:
            out[name] = MATERIAL_COLOURS[name]
        else:
            out[name] = OTHER_COLOURS[k % len(OTHER_COLOURS)]
            k += 1
    return out


def scenario_name(ds: xr.Dataset) -> str:
    """The result's scenario name ("result" when it carries none)."""
    return str(ds.attrs.get("scenario_name", "result"))


def time_axis(ax, t_end_ms: float) -> None:
    """A time axis in milliseconds from 0 to t_end_ms, with a light grid."""
    ax.set_xlabel("time [ms]")
    ax.set_xlim(0.0, t_end_ms)
    ax.grid(True, lw=0.3, alpha=0.5)


#: Two curves of a panel coincide when they differ by less than this fraction of the
#: panel's largest value (e.g. granules placed symmetrically about the load's centre).
COINCIDE = 1e-6
#: Markers of a curve drawn over an identical one, so that both stay visible.
MARKERS = ("o", "s", "^", "v", "D", "P", "X")


def plot_curves(ax, t, curves: list[tuple[str, object, str]], rtol: float = COINCIDE, **style) -> list:
    """Plot (label, values, gid) curves over t; a curve equal to an earlier one (within
    rtol of the panel's largest |value|; default COINCIDE, round-off) is drawn dashed with
    sparse markers, its label saying which it equals ("= A" within COINCIDE, "~ A" with
    the tolerance otherwise), so that no curve hides under another. Returns the lines."""
    import numpy as np

    arrays = [np.asarray(v, float) for _, v, _ in curves]
    top = max((float(np.max(np.abs(a))) for a in arrays if a.size), default=0.0)
    lines, drawn, k_marker = [], [], 0
    for (label, _, gid), y in zip(curves, arrays):
        gaps = [(lab, float(np.max(np.abs(y - yy)))) for lab, yy in drawn if top > 0 and y.size]
        twin = next(((lab, gap) for lab, gap in gaps if gap <= rtol * top), None)
        if twin is None:
            lines += ax.plot(t, y, label=label, gid=gid, **style)
        else:
            marker = MARKERS[k_marker % len(MARKERS)]
            k_marker += 1
            same = f"= {twin[0]}" if twin[1] <= COINCIDE * top else f"~ {twin[0]} within {rtol:.0%} of the peak"
            lines += ax.plot(
                t,
                y,
                label=f"{label} ({same})",
                gid=gid,
                ls="--",
                marker=marker,
                markevery=max(len(y) // 12, 1),
                markersize=4,
                **style,
            )
        drawn.append((label, y))
    return lines
