"""Plate contacts that form during a run on the plate's face (docs/model.md section 3.5):
a granule thrown at the plate from a gap, at a node and between nodes, against Hertz's
rigid-wall impact on a stiff plate and against itself under mesh refinement; and a
granule sliding along the face under friction, with every joule accounted.

In the drop and slide cases no granule touches the plate at t = 0, so every plate contact
is a patch contact that the run creates when the granule comes within contact.skin R of
the face. The touch case starts a granule against the face between nodes, so that its
patch contact exists from t = 0, and holds it against the same granule reaching the face
during the run, at that height and on a node.
"""

from __future__ import annotations

import math

import numpy as np

from .base import Case, CaseResult, Check, Context, new_figure, simulate
from .granular import hertz_reference

#: the granule: steel, radius R [m]; the plate's face at x = X0 [m], 0.1 m tall.
R = 0.01
X0 = 0.03
PLATE_HEIGHT = 0.1
#: the patch width [m], fixed so that it does not shrink when the mesh is refined.
PATCH_WIDTH = 0.0025
#: stiff-plate limit: a plate this thick [m] is 1e4 times stiffer (and heavier) than the
#: paper's 1 mm one; the contact law is Hertz's against a rigid flat (E_k -> infinity).
STIFF_THICKNESS = 10.0
#: tolerated relative difference of the restitution between nodes and at a node, by
#: plate.ny (measured: 3.4%, 1.05%, 0.23%).
RESTITUTION_GAP = {20: 0.05, 40: 0.015, 80: 0.005}


def drop_scenario(
    y: float,
    *,
    vx: float = 1.0,
    vy: float = 0.0,
    ny: int = 40,
    mu: float = 0.0,
    gap: float = 5.5e-4,
    t_end: float = 1e-3,
    thickness: float = 0.001,
    dt_max: float = 1e-7,
    out: float = 1e-6,
    scheme: str = "implicit",
):
    """One steel granule of radius R at height y [m], `gap` [m] from the plate's face,
    thrown at it with (vx, vy) [m/s] (no load, no damping at the plate: m* = 0); the
    paper's plate with ny elements along y, a patch of PATCH_WIDTH, friction mu."""
    from granplate.setup.scenario import Contact, Granule, Load, Plate, Scenario, Solver, TimeSettings

    plate = Plate(x0=X0, y0=0.0, height=PLATE_HEIGHT, ny=ny, thickness=thickness, rigid_layer_width=PATCH_WIDTH)
    return Scenario(
        name="face-drop",
        granules=(Granule(x=X0 - R - gap, y=y, radius=R, material="steel", label="g", vx=vx, vy=vy),),
        walls=(),
        plate=plate,
        load=Load(kind="none"),
        contact=Contact(pairs=(), mu=mu),
        time=TimeSettings(t_end=t_end, dt_initial=dt_max, dt_max=dt_max, output_interval=out, field_interval=out),
        solver=Solver(scheme=scheme),
    )


def bounce(ds) -> dict:
    """The impact's measures: restitution -vx_end/vx_0, contact time [s] (first to last
    output with a normal force), peak normal force [N], largest |energy residual|,
    the contact's normal and tangential impulses [N s] and the patch's travel [m]."""
    t = ds.time.values
    fn = ds.contact_normal_force.values[:, 0]
    ft = ds.contact_tangential_force.values[:, 0]
    on = np.flatnonzero(fn > 0.0)
    dt = np.diff(t)
    return {
        "e": float(-ds.vx.values[-1, 0] / ds.vx.values[0, 0]),
        "t_c": float(t[on[-1]] - t[on[0]] + dt[0]) if on.size else math.nan,
        "f_max": float(fn.max()),
        "residual": float(np.abs(ds.energy_residual.values).max()),
        "j_n": float(np.sum(0.5 * (fn[1:] + fn[:-1]) * dt)),
        "j_t": float(np.sum(0.5 * (ft[1:] + ft[:-1]) * dt)),
        "travel": float(ds.y.values[on[-1], 0] - ds.y.values[on[0], 0]) if on.size else 0.0,
        "contacts": int(ds.sizes.get("contact", 0)),
    }


def node_spacing(ny: int) -> float:
    """Distance between neighbouring face nodes [m] (corner and mid-side)."""
    return PLATE_HEIGHT / (2 * ny)


def face_drop(ctx: Context) -> CaseResult:
    """Stiff plate: Hertz's rigid-wall impact; paper's plate: node vs between nodes."""
    from granplate.setup.materials import LIBRARY, effective_modulus, sphere_mass

    steel = LIBRARY["steel"]
    v = 1.0
    ref = hertz_reference(sphere_mass(R, steel.rho), effective_modulus(steel, None), R, v)
    spots = (("node", 0.05), ("between", 0.05 + 0.37 * node_spacing(40)))
    stiff = {
        where: bounce(simulate(drop_scenario(y, thickness=STIFF_THICKNESS, t_end=6.4e-4, out=2.5e-7)))
        for where, y in (spots if ctx.full else spots[1:])
    }
    meshes = (20, 40, 80) if ctx.full else (20, 40)
    soft = {
        ny: {
            where: bounce(simulate(drop_scenario(y, ny=ny, t_end=1e-3)))
            for where, y in (("node", 0.05), ("between", 0.05 + 0.37 * node_spacing(ny)))
        }
        for ny in meshes
    }
    checks = []
    for where, b in stiff.items():
        checks.append(
            Check(
                f"contact time, stiff plate, {where}",
                "s",
                ref["t_c"],
                "Hertz, sphere on a rigid flat: t_c = 2.9433 delta_max / v",
                b["t_c"],
                0.02,
                "the plate 1e4 times stiffer than the paper's leaves ~1e-3 of the contact's "
                "compliance to it; the output every 0.25 us samples t_c to 0.2%.",
            )
        )
        checks.append(
            Check(
                f"restitution, stiff plate, {where}",
                "-",
                1.0,
                "elastic impact on a rigid wall (no damping at the plate: m* = 0)",
                b["e"],
                0.01,
                "the energy left in the plate's vibrations of a stiff, heavy plate is below 1%.",
            )
        )
    for ny in meshes:
        s = soft[ny]
        checks.append(
            Check(
                f"restitution between nodes vs at a node, ny = {ny}",
                "-",
                s["node"]["e"],
                "the same impact centred on a face node",
                s["between"]["e"],
                RESTITUTION_GAP[ny],
                "the patch spreads the force over 2.5 mm whatever the nodes: the two "
                "differ by the mesh's resolution of the patch (two, four and eight "
                "node spacings wide), shrinking with refinement at about second order.",
            )
        )
    diffs = [abs(soft[ny]["between"]["e"] - soft[ny]["node"]["e"]) for ny in meshes]
    checks.append(
        Check(
            f"node/between-node restitution gap, ny = {meshes[-1]} over ny = {meshes[0]}",
            "-",
            0.0,
            "convergence under refinement: the gap must shrink",
            diffs[-1] / max(diffs[0], 1e-300),
            1.0,
            "the finer mesh resolves the patch better, so the position of the nodes matters less.",
            kind="max",
        )
    )
    worst = max(b["residual"] for d in (stiff, *soft.values()) for b in d.values())
    checks.append(
        Check(
            "largest |energy residual| of eq. (11), every run",
            "-",
            0.0,
            "E_p + E_g + D = E_shock + E_initial at every output",
            worst,
            1e-5,
            "the implicit scheme's own residual with a rigid-layer contact is 2e-6 on this "
            "impact; the patch contact (weights frozen over a step, overlap continuous when "
            "it moves) adds no term.",
            kind="max",
        )
    )
    desc = (
        "A steel sphere (R = 1 cm) 0.55 mm from the plate's face flies at it at 1 m/s, centred "
        "on a face node or 0.37 node spacings above one; it has no plate contact at t = 0 and "
        "gets a patch contact (2.5 mm wide) when it comes within contact.skin R of the face. "
        f"On a plate {STIFF_THICKNESS:g} m thick (1e4 times stiffer and heavier) the impact is "
        "Hertz's on a rigid wall; on the paper's plate the restitution (the energy left in the "
        "plate) must not depend on where the nodes are, more so as the mesh is refined "
        f"(ny = {', '.join(map(str, meshes))})."
    )
    return CaseResult.of(
        desc, checks, plot={"stiff": stiff, "ref": ref, "meshes": meshes, "soft": soft}, tables=[_table(soft, meshes)]
    )


def draw_face_drop(p: dict):
    """The figure of face_drop, from its numbers."""
    stiff, ref, meshes, soft = p["stiff"], p["ref"], p["meshes"], p["soft"]
    fig, axes = new_figure(ncols=2, width=4.6)
    ax = axes[0, 0]
    for where, b in stiff.items():
        ax.bar(where, b["t_c"] / ref["t_c"])
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_ylabel("contact time / Hertz t_c [-]")
    ax.set_title("stiff plate", fontsize=9)
    ax = axes[0, 1]
    ax.plot([node_spacing(n) * 1e3 for n in meshes], [soft[n]["node"]["e"] for n in meshes], "o-", label="at a node")
    ax.plot(
        [node_spacing(n) * 1e3 for n in meshes], [soft[n]["between"]["e"] for n in meshes], "s--", label="between nodes"
    )
    ax.set_xlabel("face node spacing [mm]")
    ax.set_ylabel("restitution [-]")
    ax.set_title("paper's plate, patch 2.5 mm", fontsize=9)
    ax.legend(fontsize=8)
    return fig


def _table(soft: dict, meshes) -> str:
    rows = [
        "| ny | node spacing [mm] | e at a node | e between nodes | contact time at a node [us] | between [us] |",
        "|---|---|---|---|---|---|",
    ]
    for ny in meshes:
        a, b = soft[ny]["node"], soft[ny]["between"]
        rows.append(
            f"| {ny} | {node_spacing(ny) * 1e3:.3g} | {a['e']:.5f} | {b['e']:.5f} | "
            f"{a['t_c'] * 1e6:.1f} | {b['t_c'] * 1e6:.1f} |"
        )
    return "\n".join(rows)


def face_slide(ctx: Context) -> CaseResult:
    """An oblique impact with friction: the granule slides along the face, its patch follows."""
    mu = 0.3
    ds = simulate(drop_scenario(0.05, vx=1.0, vy=4.0, mu=mu, t_end=1e-3, out=5e-7))
    b = bounce(ds)
    d_fric = float(ds.D_friction.values[-1])
    e0 = float(ds.E_granular.values[0])
    checks = [
        Check(
            "patch travel along the face during the contact",
            "m",
            node_spacing(40),
            "one face-node spacing",
            b["travel"],
            node_spacing(40),
            "the granule slides past a face node or more while in touch: the patch and its weights move with it.",
            kind="min",
        ),
        Check(
            "tangential over normal impulse on the plate",
            "-",
            mu,
            "Coulomb's bound mu (eq. 5)",
            abs(b["j_t"]) / b["j_n"],
            mu * 1.001,
            "the smooth tanh law never exceeds mu |N| (0.1% for the trapezoidal impulses).",
            kind="max",
        ),
        Check(
            "friction dissipation / initial energy",
            "-",
            0.0,
            "sliding dissipates (eq. 10)",
            d_fric / e0,
            1e-3,
            "a slip of ~4 m/s under mu = 0.3 dissipates a fair share of the impact energy.",
            kind="min",
        ),
        Check(
            "largest |energy residual| of eq. (11)",
            "-",
            0.0,
            "every joule accounted: E_p + E_g + D = E_initial",
            b["residual"],
            1e-5,
            "as the normal impact: the moving patch adds no term.",
            kind="max",
        ),
    ]
    desc = (
        "The sphere of the drop case hits the face at 1 m/s while moving up at 4 m/s, with "
        f"mu = {mu}: it slides along the face while in touch, so its patch contact moves (new "
        "weights between steps, the overlap kept continuous). Checks: the patch moved, "
        "Coulomb's bound, the friction dissipated, and the energy balance of eq. (11)."
    )
    return CaseResult.of(desc, checks, plot={"ds": ds, "e0": e0})


def draw_face_slide(p: dict):
    """The figure of face_slide, from its numbers."""
    ds, e0 = p["ds"], p["e0"]
    fig, axes = new_figure()
    ax = axes[0, 0]
    t = ds.time.values * 1e3
    for name, lab in (("E_granular", "E_g"), ("E_plate", "E_p"), ("D_friction", "D_friction")):
        ax.plot(t, ds[name].values / e0, label=lab)
    ax.plot(t, ds.energy_residual.values * 1e3, label="residual x 1e3")
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("energy / initial energy [-]")
    ax.legend(fontsize=8)
    return fig


def touch_heights(ny: int) -> tuple[float, float]:
    """(on a node, between nodes) heights [m] of the touch case on the plate with ny elements."""
    return 0.05, 0.05 + 0.37 * node_spacing(ny)


def face_touch(ctx: Context) -> CaseResult:
    """A granule touching the face between nodes at t = 0 against one reaching a node."""
    meshes = (20, 40, 80) if ctx.full else (20, 40)
    runs = {}
    for ny in meshes:
        on, between = touch_heights(ny)
        runs[ny] = {
            "touch": _measures(simulate(drop_scenario(between, gap=0.0, ny=ny, t_end=5e-4))),
            "node": _measures(simulate(drop_scenario(on, ny=ny, t_end=1e-3))),
        }
    same = _measures(simulate(drop_scenario(touch_heights(40)[1], ny=40, t_end=1e-3)))
    checks = []
    for ny in meshes:
        r = runs[ny]
        checks.append(
            Check(
                f"restitution, touching between nodes at t = 0 vs reaching a node, ny = {ny}",
                "-",
                r["node"]["e"],
                "the same impact on a patch formed during the run at a face node",
                r["touch"]["e"],
                RESTITUTION_GAP[ny],
                "the patch (2.5 mm) is resolved by two, four and eight node spacings: the "
                "node's position matters less as the mesh is refined, as for the drop case.",
            )
        )
    diffs = {ny: abs(runs[ny]["touch"]["e"] - runs[ny]["node"]["e"]) for ny in meshes}
    order = (
        float(np.polyfit(np.log([node_spacing(n) for n in meshes]), np.log([diffs[n] for n in meshes]), 1)[0])
        if min(diffs.values()) > 0
        else math.inf
    )
    checks.append(
        Check(
            "order of convergence of the restitution gap (log-log fit over ny)",
            "-",
            2.0,
            "second order in the node spacing",
            order,
            1.5,
            "the consistent weights integrate the patch exactly; what is left is the "
            "quadratic interpolation of the face's motion across the patch.",
            kind="min",
        )
    )
    checks.append(
        Check(
            "restitution, touching at t = 0 vs reaching the same height from a gap, ny = 40",
            "-",
            same["e"],
            "the patch contact the run forms at that height (case plate-face-drop)",
            runs[40]["touch"]["e"],
            1e-4,
            "the same contact law, weights and plate; only the step pattern differs "
            "(the contact opens at t = 0 rather than 0.55 ms later).",
        )
    )
    checks.append(
        Check(
            "plate energy after the bounce, touching at t = 0 vs from a gap, ny = 40",
            "J",
            same["E_p"],
            "as above",
            runs[40]["touch"]["E_p"],
            1e-3,
            "the plate keeps ~12% of 1/2 m v^2; its share follows the contact history to the step.",
        )
    )
    worst = max(b["residual"] for r in runs.values() for b in r.values())
    checks.append(
        Check(
            "largest |energy residual| of eq. (11), every run",
            "-",
            0.0,
            "E_p + E_g + D = E_initial at every output (solver.energy_tol = 1e-4 at every step)",
            max(worst, same["residual"]),
            1e-5,
            "the patch contact placed before the first step adds no term: its overlap and force are zero at t = 0.",
            kind="max",
        )
    )
    desc = (
        "The steel sphere of the drop case (R = 1 cm, 1 m/s) starts against the paper's plate "
        "(zero gap), 0.37 node spacings above a face node: it has a patch contact (2.5 mm wide) "
        "from t = 0, placed by the driver before the first step with the same machinery as a "
        "patch that forms during the run. The truth is that patch: formed at a face node "
        "(the sphere thrown from 0.55 mm), the gap between the two must shrink at about second "
        f"order under refinement (ny = {', '.join(map(str, meshes))}); formed at the same height, the "
        "two must agree to the time step."
    )
    return CaseResult.of(
        desc, checks, tables=[_touch_table(runs, meshes)], plot={"runs": runs, "meshes": meshes, "diffs": diffs}
    )


def draw_face_touch(p: dict):
    """The figure of face_touch, from its numbers."""
    runs, meshes, diffs = p["runs"], p["meshes"], p["diffs"]
    fig, axes = new_figure(ncols=2, width=4.6)
    h = [node_spacing(n) * 1e3 for n in meshes]
    ax = axes[0, 0]
    for key, lab in (("e", "restitution"), ("E_p", "plate energy"), ("f_max", "force peak")):
        ax.loglog(h, [abs(runs[n]["touch"][key] / runs[n]["node"][key] - 1.0) for n in meshes], "o-", label=lab)
    ax.loglog(h, [diffs[meshes[0]] / runs[meshes[0]]["node"]["e"] * (x / h[0]) ** 2 for x in h], "k:", label="slope 2")
    ax.set_xlabel("face node spacing [mm]")
    ax.set_ylabel("|between at t = 0 / at a node - 1| [-]")
    ax.legend(fontsize=7)
    ax = axes[0, 1]
    for n in meshes:
        ax.plot(np.asarray(runs[n]["touch"]["t"]) * 1e3, runs[n]["touch"]["fn"], label=f"ny = {n}, at t = 0")
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("normal force [N]")
    ax.legend(fontsize=7)
    return fig


def _measures(ds) -> dict:
    """bounce(ds) and the plate's energy at the end [J], with the normal force's history."""
    b = bounce(ds)
    b["E_p"] = float(ds.E_plate.values[-1])
    on = np.flatnonzero(ds.contact_normal_force.values[:, 0] > 0.0)
    t0 = ds.time.values[max(on[0] - 1, 0)] if on.size else 0.0
    b["t"] = ds.time.values - t0
    b["fn"] = ds.contact_normal_force.values[:, 0]
    return b


def _touch_table(runs: dict, meshes) -> str:
    rows = [
        "| ny | node spacing [mm] | e at a node | e between, at t = 0 | plate energy: between / node - 1 "
        "| force peak: between / node - 1 |",
        "|---|---|---|---|---|---|",
    ]
    for ny in meshes:
        a, b = runs[ny]["node"], runs[ny]["touch"]
        rows.append(
            f"| {ny} | {node_spacing(ny) * 1e3:.3g} | {a['e']:.5f} | {b['e']:.5f} | "
            f"{b['E_p'] / a['E_p'] - 1:+.2%} | {b['f_max'] / a['f_max'] - 1:+.2%} |"
        )
    return "\n".join(rows)


CASES: tuple[Case, ...] = (
    Case(
        "plate-face-drop",
        "coupled",
        "Patch contact: impact at a node and between nodes, stiff-plate Hertz limit",
        face_drop,
        draw=draw_face_drop,
    ),
    Case(
        "plate-face-slide",
        "coupled",
        "Patch contact: a granule sliding along the face under friction",
        face_slide,
        draw=draw_face_slide,
    ),
    Case(
        "plate-face-touch",
        "coupled",
        "Patch contact from t = 0: a granule touching the face between nodes against one reaching a node",
        face_touch,
        draw=draw_face_touch,
    ),
)
