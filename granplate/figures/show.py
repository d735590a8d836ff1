"""Draw an `Assembly` (`granplate show`): granules to scale, coloured by material and
labelled where the label fits, walls hatched on their solid side, the plate with its
mesh and rigid layers, the load, and the contact network (line width proportional to
the normal force for a result). Axes in mm, equal aspect.

    >>> from granplate.figures import assembly, show
    >>> fig = show.draw(assembly.of_scenario(gp.preset("steel-r1")))
    >>> fig.savefig("steel-r1.png", dpi=150, bbox_inches="tight")   # the legend is beside the axes
"""

from __future__ import annotations

import numpy as np
from matplotlib.cm import ScalarMappable
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib import colormaps
from matplotlib.colors import ListedColormap, Normalize
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch, Polygon

from granplate.figures.assembly import Assembly, load_profile
from granplate.figures.common import material_colours, new_figure, readable_duration

MM = 1e3  # m -> mm

#: Contact line colours by kind (a scenario: no forces).
KIND_COLOURS = {"granule": "0.1", "wall": "tab:purple", "plate": "tab:red"}
KIND_NAMES = {"granule": "granule-granule", "wall": "granule-wall", "plate": "granule-plate"}
#: The widest contact line [points] (the largest force of a result).
MAX_LINE_WIDTH = 6.0
#: Contacts below this fraction of the largest force are drawn thin and dotted.
OPEN_FRACTION = 0.01
#: Labels are drawn only at this font size [points] or above.
MIN_FONT = 5.0
MAX_FONT = 14.0
#: Force colours: the upper part of YlOrRd (orange to dark red), readable on any granule.
FORCE_CMAP = ListedColormap(colormaps["YlOrRd"](np.linspace(0.35, 1.0, 256)), name="force")
LOAD_COLOUR = "crimson"


def clip_line(point: np.ndarray, direction: np.ndarray, box: tuple[float, float, float, float]):
    """The part of the line point + s direction inside box (x0, x1, y0, y1): its two end
    points, or None when the line misses the box (Liang-Barsky)."""
    lo, hi = -np.inf, np.inf
    for p, d, a, b in ((point[0], direction[0], box[0], box[1]), (point[1], direction[1], box[2], box[3])):
        if abs(d) < 1e-15:
            if not a <= p <= b:
                return None
            continue
        s1, s2 = sorted(((a - p) / d, (b - p) / d))
        lo, hi = max(lo, s1), min(hi, s2)
    if lo >= hi:
        return None
    return point + lo * direction, point + hi * direction


def label_font_size(radius_pt: float, label: str) -> float:
    """Font size [points] of a label inside a circle of radius_pt points: the text's
    height within 1.1 r and its width (about 0.65 of the size per character) within 1.2 r;
    0 when below MIN_FONT (too small to read: not drawn)."""
    size = min(1.1 * radius_pt, 1.2 * radius_pt / (0.65 * max(len(label), 1)), MAX_FONT)
    return size if size >= MIN_FONT else 0.0


def _box(a: Assembly, arrow_room: float) -> tuple[float, float, float, float]:
    """The drawn region [mm]: granules, plate (deformed too), room for the load arrows."""
    xs, ys = [], []
    if len(a.x):
        xs += [(a.x - a.radius).min(), (a.x + a.radius).max()]
        ys += [(a.y - a.radius).min(), (a.y + a.radius).max()]
    if a.plate is not None:
        x0, y0, w, h = a.plate.rectangle
        e = a.plate.elements
        xs += [x0, x0 + w, e[..., 0].min(), e[..., 0].max()]
        ys += [y0, y0 + h, e[..., 1].min(), e[..., 1].max()]
    x_lo, x_hi, y_lo, y_hi = min(xs) * MM, max(xs) * MM, min(ys) * MM, max(ys) * MM
    m = 0.06 * max(x_hi - x_lo, y_hi - y_lo)
    return x_lo - m - arrow_room, x_hi + m, y_lo - m, y_hi + m


def _draw_walls(ax, a: Assembly, box) -> list:
    """Each wall as a line across the box, hatched on its solid side (+normal)."""
    width = 0.03 * max(box[1] - box[0], box[3] - box[2])
    drawn = []
    for wall in a.walls:
        n = np.asarray(wall.normal, float)
        n = n / np.linalg.norm(n)
        ends = clip_line(n * wall.offset * MM, np.array([-n[1], n[0]]), box)
        if ends is None:
            continue
        p, q = ends
        ax.add_patch(
            Polygon(
                [p, q, q + width * n, p + width * n],
                closed=True,
                fill=False,
                hatch="///",
                ec="0.4",
                lw=0,
                zorder=1,
                gid=f"wall-hatch:{wall.label}",
            )
        )
        drawn += ax.plot([p[0], q[0]], [p[1], q[1]], color="0.2", lw=2.0, zorder=2, gid=f"wall:{wall.label}")
    return drawn


def _draw_plate(ax, a: Assembly) -> None:
    p = a.plate
    if p is None:
        return
    mesh = PolyCollection(
        p.elements * MM, facecolors="#e3e9f0", edgecolors="0.45", linewidths=0.3, zorder=1, gid="plate:mesh"
    )
    ax.add_collection(mesh)
    if p.deformed:
        x0, y0, w, h = (v * MM for v in p.rectangle)
        ax.add_patch(
            Polygon(
                [(x0, y0), (x0 + w, y0), (x0 + w, y0 + h), (x0, y0 + h)],
                closed=True,
                fill=False,
                ls="--",
                lw=0.7,
                ec="0.3",
                zorder=2,
                gid="plate:undeformed",
            )
        )
    x0, y0, w, h = (v * MM for v in p.rectangle)
    t = 0.08 * w  # the clamp's drawn thickness [mm]
    strips = {
        "top": [(x0, y0 + h), (x0 + w, y0 + h), (x0 + w, y0 + h + t), (x0, y0 + h + t)],
        "bottom": [(x0, y0), (x0 + w, y0), (x0 + w, y0 - t), (x0, y0 - t)],
        "left": [(x0, y0), (x0, y0 + h), (x0 - t, y0 + h), (x0 - t, y0)],
        "right": [(x0 + w, y0), (x0 + w, y0 + h), (x0 + w + t, y0 + h), (x0 + w + t, y0)],
    }
    for edge in p.clamped_edges:
        ax.add_patch(
            Polygon(
                strips[edge],
                closed=True,
                fc="0.35",
                ec="0.35",
                hatch="xxxx",
                lw=0.5,
                zorder=2,
                gid=f"plate:clamped:{edge}",
            )
        )
    for k, layer in enumerate(p.rigid_layers):
        ax.plot(
            layer[:, 0] * MM,
            layer[:, 1] * MM,
            color="darkred",
            lw=4,
            solid_capstyle="butt",
            zorder=3,
            gid=f"plate:rigid-layer:{k}",
        )


def _draw_granules(ax, a: Assembly, colours: dict[str, str]) -> None:
    for x, y, r, lab, mat in zip(a.x, a.y, a.radius, a.labels, a.materials):
        ax.add_patch(
            Circle(
                (x * MM, y * MM), r * MM, fc=colours[mat], ec="0.15", lw=0.6, alpha=0.9, zorder=4, gid=f"granule:{lab}"
            )
        )


def _draw_labels(fig: Figure, ax, a: Assembly) -> int:
    """Labels sized from the radius as drawn; returns how many were too small to draw."""
    fig.draw_without_rendering()
    scale = ax.transData.transform((1.0, 0.0))[0] - ax.transData.transform((0.0, 0.0))[0]  # px per mm
    skipped = 0
    for x, y, r, lab in zip(a.x, a.y, a.radius, a.labels):
        size = label_font_size(r * MM * scale * 72.0 / fig.dpi, lab)
        if size == 0.0:
            skipped += 1
            continue
        ax.text(
            x * MM,
            y * MM,
            lab,
            ha="center",
            va="center",
            fontsize=size,
            zorder=6,
            gid=f"label:{lab}",
            color="black",
            bbox={"boxstyle": "round,pad=0.05", "fc": "white", "ec": "none", "alpha": 0.6},
        )
    return skipped


def _draw_contacts(fig: Figure, ax, a: Assembly) -> list:
    """One LineCollection (gid "contacts") with a segment per contact; legend handles."""
    segs = a.segments * MM
    if len(segs) == 0:
        return []
    if a.forces is None:
        colours = [KIND_COLOURS[k] for k in a.kinds]
        lines = LineCollection(segs, colors=colours, linewidths=1.2, zorder=5, gid="contacts")
        ax.add_collection(lines)
        return [
            Line2D([], [], color=KIND_COLOURS[k], lw=1.2, label=f"contact {KIND_NAMES[k]} ({a.kinds.count(k)})")
            for k in KIND_COLOURS
            if k in a.kinds
        ]
    f = np.asarray(a.forces, float)
    f_max = float(f.max()) if len(f) else 0.0
    norm = Normalize(0.0, f_max if f_max > 0 else 1.0)
    cmap = ScalarMappable(norm, FORCE_CMAP)
    open_ = f <= OPEN_FRACTION * f_max
    widths = np.where(open_, 0.6, MAX_LINE_WIDTH * f / (f_max if f_max > 0 else 1.0))
    colours = [(0.45, 0.45, 0.45, 1.0) if o else cmap.to_rgba(v) for o, v in zip(open_, f)]
    styles = [":" if o else "-" for o in open_]
    lines = LineCollection(
        segs, colors=colours, linewidths=widths, linestyles=styles, zorder=5, gid="contacts", capstyle="round"
    )
    ax.add_collection(lines)
    fig.colorbar(
        cmap,
        ax=ax,
        label="contact normal force [N]",
        orientation="horizontal",
        shrink=0.6,
        pad=0.02,
        aspect=40,
        location="bottom",
    )
    return [
        Line2D(
            [],
            [],
            color=cmap.to_rgba(f_max),
            lw=MAX_LINE_WIDTH,
            label=f"contact force, width ∝ force\n(widest: {f_max:.3g} N)",
        ),
        Line2D(
            [],
            [],
            color="0.45",
            lw=0.6,
            ls=":",
            label=f"contact below {OPEN_FRACTION:.0%} of the largest ({int(open_.sum())})",
        ),
    ]


def _load_text(a: Assembly) -> str:
    ld = a.load
    text = (
        f"load: q0 = {ld.q0 / 1e3:.4g} kN/m half-sine, T = {readable_duration(ld.duration)},\n"
        f"y = {ld.y0 * MM:.4g}-{(ld.y0 + ld.length) * MM:.4g} mm"
    )
    if a.time is not None and a.time > ld.duration:
        text += " (over at this time)"
    return text


def _draw_load(ax, a: Assembly, arrow_len: float) -> list:
    """Arrows (+x) on the loaded granules' left surfaces or on the plate's left edge,
    length following the half-sine profile in y, and the load's y-range as a bar."""
    ld = a.load
    if ld.kind == "none":
        return []
    if ld.target == "granules":
        idx = [
            i
            for i in np.flatnonzero(a.loaded)
            if a.y[i] + a.radius[i] > ld.y0 and a.y[i] - a.radius[i] < ld.y0 + ld.length
        ]
        if not idx:
            return []
        tips = [((a.x[i] - a.radius[i]) * MM, a.y[i] * MM) for i in idx]
        shape = load_profile(ld, np.array([a.y[i] for i in idx]))
    elif a.plate is not None:
        x0, y0, _, h = a.plate.rectangle
        ys = np.linspace(ld.y0, ld.y0 + ld.length, 7)[1:-1]
        tips = [(x0 * MM, yy * MM) for yy in ys]
        shape = load_profile(ld, ys)
    else:
        return []
    for k, ((tx, ty), sh) in enumerate(zip(tips, shape)):
        length = arrow_len * max(float(sh), 0.25)
        ax.annotate(
            "",
            xy=(tx, ty),
            xytext=(tx - length, ty),
            zorder=7,
            gid=f"load:arrow:{k}",
            arrowprops={"arrowstyle": "-|>", "color": LOAD_COLOUR, "lw": 1.8, "mutation_scale": 12},
        )
    bar_x = min(t[0] for t in tips) - arrow_len * 1.15
    ax.plot(
        [bar_x, bar_x],
        [ld.y0 * MM, (ld.y0 + ld.length) * MM],
        color=LOAD_COLOUR,
        lw=3,
        solid_capstyle="butt",
        zorder=7,
        gid="load:range",
    )
    return [Line2D([], [], color=LOAD_COLOUR, lw=1.8, marker=">", label=_load_text(a))]


def _title(a: Assembly) -> str:
    head = f"{a.name}"
    if a.time is None:
        return f"{head}: assembly before the run"
    lines = [f"{head} at t = {a.time * 1e3:.4g} ms", a.time_note]
    if a.plate is not None:
        if a.plate.deformed:
            lines.append(
                f"plate displacements magnified x{a.plate.magnify:g} (largest "
                f"{a.plate.largest_displacement:.3g} m)" + ("; granules at true positions" if len(a.x) else "")
            )
        else:
            lines.append("plate undeformed: no plate-field snapshot at this time")
    return "\n".join(lines)


def draw(a: Assembly, width: float = 8.0) -> Figure:
    """The figure of an assembly (see the module docstring)."""
    r_ref = float(a.radius.max()) if len(a.radius) else (a.plate.rectangle[2] if a.plate else 0.01)
    arrow_len = 1.2 * r_ref * MM if a.load.kind != "none" else 0.0
    box = _box(a, arrow_room=1.3 * arrow_len)
    aspect = (box[3] - box[2]) / (box[1] - box[0])
    fig = new_figure(width, min(max(0.62 * width * aspect + 1.2, 3.5), 11.0))
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    ax.set_xlim(box[0], box[1])
    ax.set_ylim(box[2], box[3])
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    colours = material_colours(a.materials)
    walls = _draw_walls(ax, a, box)
    _draw_plate(ax, a)
    _draw_granules(ax, a, colours)
    handles = [Patch(fc=c, ec="0.15", label=f"{m} ({a.materials.count(m)} granules)") for m, c in colours.items()]
    if walls:
        handles.append(Patch(fc="white", ec="0.3", hatch="///", label="rigid wall (hatched: solid side)"))
    if a.plate is not None:
        handles.append(Patch(fc="#e3e9f0", ec="0.45", label="plate, element edges"))
        if a.plate.clamped_edges:
            handles.append(
                Patch(fc="0.35", ec="0.35", hatch="xxxx", label="plate clamped: " + ", ".join(a.plate.clamped_edges))
            )
        if a.plate.rigid_layers:
            handles.append(Line2D([], [], color="darkred", lw=4, label=f"rigid layers ({len(a.plate.rigid_layers)})"))
    handles += _draw_contacts(fig, ax, a)
    handles += _draw_load(ax, a, arrow_len)
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)
    ax.set_title(_title(a), fontsize=10, loc="left")
    skipped = _draw_labels(fig, ax, a)
    if skipped:
        ax.text(
            1.0,
            -0.08,
            f"{skipped} labels too small to draw",
            transform=ax.transAxes,
            ha="right",
            fontsize=7,
            color="0.4",
        )
    return fig
