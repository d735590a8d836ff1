"""Animations of a run (paper Appendix B): granules as discs, the deformed plate mesh,
displacements magnified (125 times by default), granules coloured by speed and plate
elements by von Mises stress, with a time label.

    >>> from granplate.paper.animate import animate
    >>> animate(gp.read("ptfe-r05.nc"), "ptfe-r05.mp4")   # -> Path (.gif if no ffmpeg)

Frames are the result's plate-field snapshots (`field_time`, every 20 us by default),
thinned evenly to at most `frames`. MP4 goes through the ffmpeg binary of the pip
package imageio-ffmpeg; without it (or when ffmpeg fails) a GIF is written with Pillow.

A run in space (dimension = 3; `animate_space`, which `animate` calls for it) is drawn
per frame as `granplate show` draws it (`figures.space`): three orthogonal projections,
spheres at their true positions coloured by material, drawn far to near and shaded by
depth, walls as their traces, the contact network by force, an elastic body deformed and
coloured by von Mises stress; frames are the body's field snapshots (`field_time`) for a
run with an elastic body, else the output times, thinned the same way, on one region and
one set of scales (the body's magnification, its stress, the contact forces).
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, NamedTuple

import numpy as np
import xarray as xr
from matplotlib.animation import FFMpegWriter, PillowWriter
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.cm import ScalarMappable
from matplotlib.collections import PolyCollection
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.patches import Circle

from granplate.results import analysis as an
from granplate.results.dataset import dimension_spec

#: The paper's magnification of displacements in its animations.
MAGNIFY = 125.0

#: Corner/midside order that walks an element's boundary (VTK_QUADRATIC_QUAD indices).
BOUNDARY_ORDER = (0, 4, 1, 5, 2, 6, 3, 7)


def frame_indices(n_snapshots: int, frames: int | None) -> np.ndarray:
    """Evenly spread indices of at most `frames` snapshots (all when None), first and last kept."""
    if n_snapshots <= 0:
        return np.zeros(0, dtype=int)
    if frames is None or frames >= n_snapshots:
        return np.arange(n_snapshots)
    frames = max(int(frames), 2)
    return np.unique(np.linspace(0, n_snapshots - 1, frames).round().astype(int))


def magnified(reference: np.ndarray, current: np.ndarray, factor: float) -> np.ndarray:
    """reference + factor * (current - reference): displacements magnified."""
    return reference + factor * (current - reference)


def plate_polygons(ds: xr.Dataset, k: int, factor: float) -> np.ndarray:
    """Deformed element outlines [mm] at field snapshot k: (n_elem, 8, 2)."""
    xy = np.stack([ds["node_x"].values, ds["node_y"].values], axis=1)
    u = np.stack([ds["plate_ux"].values[k], ds["plate_uy"].values[k]], axis=1)
    nodes = (xy + factor * u) * 1e3
    elements = np.asarray(ds["element_nodes"].values)[:, BOUNDARY_ORDER]
    return nodes[elements]


def _walls(ds: xr.Dataset):
    from granplate.results.dataset import scenario_of

    return scenario_of(ds).walls


def _ffmpeg_path() -> str | None:
    try:
        import imageio_ffmpeg

        return imageio_ffmpeg.get_ffmpeg_exe()
    except Exception:  # noqa: BLE001 - any failure means "no ffmpeg": fall back to GIF
        return None


def _plate_artist(fig: Figure, ax, ds: xr.Dataset, snaps: np.ndarray, magnify: float):
    """The deformed plate mesh coloured by element von Mises stress [MPa]; (artist, stresses)."""
    vm = ds["plate_von_mises"].values[snaps] / 1e6
    norm = Normalize(0.0, max(float(vm.max()), 1e-9))
    plate = PolyCollection(
        plate_polygons(ds, int(snaps[0]), magnify), cmap="inferno_r", norm=norm, edgecolors="0.35", linewidths=0.3
    )
    plate.set_array(vm[0])
    ax.add_collection(plate)
    fig.colorbar(
        plate, ax=ax, label="plate von Mises stress [MPa]", orientation="horizontal", shrink=0.9, pad=0.01, aspect=35
    )
    return plate, vm


def _granule_artists(fig: Figure, ax, ds: xr.Dataset, ti: np.ndarray):
    """Discs (true radius) with labels; (circles, labels, speeds (frame, granule), colour map)."""
    x0, y0, r = ds["x"].values[0], ds["y"].values[0], ds["radius"].values
    speed = np.hypot(ds["vx"].values[ti], ds["vy"].values[ti])
    colours = ScalarMappable(Normalize(0.0, max(float(speed.max()), 1e-12)), "viridis")
    circles, texts = [], []
    for a, b, c, lab in zip(x0, y0, r, ds["granule"].values):
        circles.append(ax.add_patch(Circle((a * 1e3, b * 1e3), c * 1e3, ec="k", lw=0.5)))
        texts.append(
            ax.text(
                a * 1e3,
                b * 1e3,
                str(lab),
                ha="center",
                va="center",
                fontsize=7,
                color="w",
                bbox={"boxstyle": "circle,pad=0.1", "fc": "0.2", "ec": "none", "alpha": 0.6},
            )
        )
    fig.colorbar(colours, ax=ax, label="granule speed [m/s]", orientation="horizontal", shrink=0.9, pad=0.01, aspect=35)
    return circles, texts, speed, colours


def _draw_walls(ax, ds: xr.Dataset) -> None:
    """The rigid walls as thick grey lines."""
    for wall in _walls(ds):
        n, off = np.asarray(wall.normal, float), float(wall.offset) * 1e3
        if abs(n[0]) > 0.5:
            ax.axvline(off * np.sign(n[0]), color="0.3", lw=3)
        else:
            ax.axhline(off * np.sign(n[1]), color="0.3", lw=3)


def _limits(ds: xr.Dataset, snaps: np.ndarray, ti: np.ndarray, magnify: float) -> tuple[float, float, float, float]:
    """Axis limits [mm] holding the deformed plate, the moving granules and the walls."""
    ux, uy = ds["plate_ux"].values[snaps], ds["plate_uy"].values[snaps]
    xs = (ds["node_x"].values[None, :] + magnify * ux) * 1e3
    ys = (ds["node_y"].values[None, :] + magnify * uy) * 1e3
    x_lo, x_hi, y_lo, y_hi = xs.min(), xs.max(), ys.min(), ys.max()
    if an.has_granules(ds):
        r = ds["radius"].values * 1e3
        gx = magnified(ds["x"].values[0], ds["x"].values[ti], magnify) * 1e3
        gy = magnified(ds["y"].values[0], ds["y"].values[ti], magnify) * 1e3
        x_lo, x_hi = min(x_lo, 0.0, float((gx - r).min())), max(x_hi, float((gx + r).max()))
        y_lo, y_hi = min(y_lo, 0.0, float((gy - r).min())), max(y_hi, float((gy + r).max()))
    pad = 0.05 * (x_hi - x_lo)
    return x_lo - pad, x_hi + pad, y_lo - 2.0, y_hi + 2.0


def _save(fig: Figure, draw, n_frames: int, path: Path, fps: int, dpi: int, progress: bool = False) -> Path:
    """Render the frames into path (.mp4 through imageio-ffmpeg, else .gif); the path
    written. progress: a bar of the frames rendered on stderr."""
    import matplotlib
    from tqdm import tqdm

    def write(writer, target: Path) -> Path:
        with (
            writer.saving(fig, str(target), dpi),
            tqdm(total=n_frames, desc=target.name, unit="frame", leave=False, disable=not progress) as bar,
        ):
            for f in range(n_frames):
                draw(f)
                writer.grab_frame()  # one render per frame
                bar.update(1)
        return target

    ffmpeg = _ffmpeg_path() if path.suffix.lower() == ".mp4" else None
    if ffmpeg is not None:
        try:
            with matplotlib.rc_context({"animation.ffmpeg_path": ffmpeg}):
                even = ["-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p"]
                return write(FFMpegWriter(fps=fps, codec="libx264", extra_args=even), path)
        except Exception:  # noqa: BLE001 - ffmpeg present but failing: fall back to GIF
            path.unlink(missing_ok=True)
    return write(PillowWriter(fps=fps), path.with_suffix(".gif"))


def animate(
    ds: xr.Dataset,
    path: str | Path,
    *,
    frames: int | None = 120,
    fps: int = 15,
    magnify: float = MAGNIFY,
    dpi: int = 90,
    progress: bool = False,
) -> Path:
    """Write an animation of run `ds` to `path` (.mp4, or .gif) and return the path written.

    frames: at most this many frames (None: every field snapshot); fps: frames per
    second; magnify: displacement magnification [-] (unused in space); dpi: resolution;
    progress: a bar of the frames rendered on stderr.
    An .mp4 path falls back to .gif (Pillow) when ffmpeg is not available or fails.
    The animation is the result's dimension's (`ANIMATIONS`: `animate_plane`, `animate_space`).
    """
    return animation_of(ds).write(ds, path, frames=frames, fps=fps, magnify=magnify, dpi=dpi, progress=progress)


def animate_plane(
    ds: xr.Dataset,
    path: str | Path,
    *,
    frames: int | None = 120,
    fps: int = 15,
    magnify: float = MAGNIFY,
    dpi: int = 90,
    progress: bool = False,
) -> Path:
    """Write an animation of plane run `ds` to `path` (.mp4, or .gif) and return the path
    written: per frame the granules and the plate magnified by `magnify` at its field
    snapshots (`animate`)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    snaps = frame_indices(ds.sizes.get("field_time", 0), frames)
    if snaps.size == 0:
        raise ValueError("the result has no plate-field snapshots (field_time) to animate")
    ft = ds["field_time"].values[snaps]
    ti = an.time_indices(ds, ft)

    fig = Figure(figsize=(5.6, 8.0), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    plate, vm = _plate_artist(fig, ax, ds, snaps, magnify)
    circles: list[Circle] = []
    if an.has_granules(ds):
        circles, texts, speed, colours = _granule_artists(fig, ax, ds, ti)
        x0, y0 = ds["x"].values[0], ds["y"].values[0]
        _draw_walls(ax, ds)
    x_lo, x_hi, y_lo, y_hi = _limits(ds, snaps, ti, magnify)
    ax.set_xlim(x_lo, x_hi)
    ax.set_ylim(y_lo, y_hi)
    head = f"{ds.attrs.get('scenario_name', '')}: displacements x{magnify:g}"
    label = ax.set_title(f"{head},  t = {ft[0] * 1e3:.3f} ms", fontsize=10)

    def draw(f: int) -> None:
        plate.set_verts(plate_polygons(ds, int(snaps[f]), magnify))
        plate.set_array(vm[f])
        if circles:
            xi = magnified(x0, ds["x"].values[ti[f]], magnify) * 1e3
            yi = magnified(y0, ds["y"].values[ti[f]], magnify) * 1e3
            for circ, txt, a, b, col in zip(circles, texts, xi, yi, colours.to_rgba(speed[f])):
                circ.set_center((a, b))
                circ.set_facecolor(col)
                txt.set_position((a, b))
        label.set_text(f"{head},  t = {ft[f] * 1e3:.3f} ms")

    fig.canvas.draw()  # lay out once, then freeze the layout (re-solving it every frame is slow)
    fig.set_layout_engine("none")
    return _save(fig, draw, len(snaps), path, fps, dpi, progress)


def animate_space(
    ds: xr.Dataset, path: str | Path, *, frames: int | None = 120, fps: int = 15, dpi: int = 90, progress: bool = False
) -> Path:
    """Write an animation of 3D run `ds` to `path` (.mp4, or .gif) and return the path
    written: per frame the three projections `granplate show` draws (`figures.space`),
    at the body's field snapshots for a run with an elastic body, else at the output
    times, thinned evenly to at most `frames`; one region, one magnification of the body
    and one colour scale each for its stress and the contact forces over all frames."""
    from granplate.figures import space

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    indices = frame_indices(len(space.frame_times(ds)), frames)
    if indices.size == 0:
        raise ValueError("the result has no output times to animate")
    fig, draw = space.animation(space.frames_of_result(ds, indices))
    return _save(fig, draw, len(indices), path, fps, dpi, progress)


class Animation(NamedTuple):
    """One dimension's animation: `write(ds, path, frames=, fps=, magnify=, dpi=,
    progress=)` -> the path written; `ready(ds)`: whether the command line may start it (the
    plane needs plate-field snapshots; space checks its frames as it starts)."""

    write: Callable[..., Path]
    ready: Callable[[xr.Dataset], bool]


#: the animations by the dimension's name (model.dimension); space has no magnification
ANIMATIONS: dict[str, Animation] = {
    "plane": Animation(animate_plane, lambda ds: ds.sizes.get("field_time", 0) > 0),
    "space": Animation(lambda ds, path, magnify, **kw: animate_space(ds, path, **kw), lambda ds: True),
}


def animation_of(ds: xr.Dataset) -> Animation:
    """The animation of result `ds`'s dimension (`ANIMATIONS`)."""
    return ANIMATIONS[dimension_spec(ds).name]
