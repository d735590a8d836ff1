"""Verification of the 3D elastic solid (`granplate.solid`) against plate theory.

- `solid-plate-frequencies`: the lowest frequencies of a clamped square plate (its four
  side faces clamped) built by `build_solid`, a thin one (a/h = 50) against Leissa's
  Kirchhoff table and an independent Ritz solution of Mindlin's equations, and a
  moderately thick one (a/h = 10) against Mindlin (Ritz), under in-plane refinement with
  the observed order of convergence;
- `solid-static-plate`: the centre deflection of the thin clamped plate under a uniform
  pressure on its top face, from the simulator's own modal basis plus its residual
  compliance (what a coupled run uses), against the Kirchhoff plate (Ritz; Timoshenko's
  coefficient), under refinement; and that modes plus residual compliance equal the
  direct static solve (the truncation is exact in statics).

The references are `verification.plate_theory` and `verification.plate_ritz` (their
tests check them against the published values).
"""
from __future__ import annotations

import math

import numpy as np

from .base import Case, CaseResult, Check, Context, new_figure

#: The plate: a square of side SIDE [m], steel, clamped on its four side faces.
SIDE = 0.1
THIN = 0.002  # a/h = 50
THICK = 0.01  # a/h = 10
CLAMPED = ("xmin", "xmax", "ymin", "ymax")
#: In-plane elements per side of the meshes (hex20); elements through the thickness.
THIN_MESHES = (6, 12, 24)
THICK_MESHES = (4, 8, 16)
THIN_LAYERS, THICK_LAYERS = 1, 2
#: Modes kept: every mode below this frequency parameter lambda^2 = omega a^2 sqrt(rho h / D).
PARAMETER_CUT = 140.0
#: The uniform pressure of the static case [Pa] (linear: any value).
PRESSURE = 1e4

MODEL_WHY = ("3D elasticity against Mindlin's plate: the clamped side faces hold every point "
             "of the thickness (Mindlin's clamp holds the mid-plane's deflection and rotation "
             "only), and the hex20 plate has one or two elements through the thickness; both "
             "stiffen by ~(h/a)^2 x O(10): measured +0.6% at a/h = 50, +1.1% at a/h = 10 in the "
             "mesh limit.")


def _steel():
    from granplate.setup.materials import LIBRARY

    return LIBRARY["steel"]


def rigidity(h: float) -> float:
    """D = E h^3 / (12 (1 - nu^2)) of the steel plate [N m]."""
    from .plate_theory import flexural_rigidity

    st = _steel()
    return flexural_rigidity(st.E, h, st.nu)


def clamped_plate(n: int, layers: int, h: float, cache: bool = False):
    """The clamped square plate of n x n x layers hex20 elements, modes below
    PARAMETER_CUT and the residual compliance over its top face's z dofs."""
    from granplate.setup.scenario import Solid
    from granplate.solid.build import build_solid

    st = _steel()
    f_cut = PARAMETER_CUT / SIDE**2 * math.sqrt(rigidity(h) / (st.rho * h)) / (2 * math.pi)
    sd = Solid(size=(SIDE, SIDE, h), elements=(n, n, layers), clamped=CLAMPED, max_frequency=f_cut)
    return build_solid(sd, st, surface="zmax", components="z", cache=cache)


def frequency_parameters(model, h: float, count: int = 3) -> np.ndarray:
    """lambda^2 = omega a^2 sqrt(rho h / D) of the lowest `count` modes."""
    st = _steel()
    return model.omega[:count] * SIDE**2 * math.sqrt(st.rho * h / rigidity(h))


def richardson(values: np.ndarray) -> tuple[float, float]:
    """(limit, observed order) from three values on meshes halved in turn
    (`plate_mesh.observed_orders` and `plate_mesh.richardson`)."""
    from .plate_mesh import observed_orders
    from .plate_mesh import richardson as limit_at

    order = observed_orders(list(values))[-1]
    return limit_at(list(values), order), order


def top_pressure_loads(model, pressure: float) -> np.ndarray:
    """The consistent nodal forces [N] of a uniform pressure (downwards, -z) on the top
    face, on the reduced dofs of the residual compliance (model.surface_dofs)."""
    from skfem import FacetBasis, LinearForm, asm

    from granplate.solid.boundary import reduced_index
    from granplate.solid.fe import ELEMENTS, INTORDER

    fb = FacetBasis(model.mesh, ELEMENTS[model.element](), facets=model.mesh.boundaries["zmax"], intorder=INTORDER)
    nodal = asm(LinearForm(lambda v, w: -pressure * v), fb)
    where = reduced_index(model.dofs, 3 * np.arange(len(nodal)) + 2)
    held = where >= 0  # the clamped edges' share goes to the supports
    forces = np.zeros(len(model.dofs))
    forces[where[held]] = nodal[held]
    return forces[model.surface_dofs]


def static_top(model, f_s: np.ndarray) -> np.ndarray:
    """u_S = Phi_S Omega^-2 Phi_S^T f_S + R f_S [m]: the top face's z displacement under
    loads f_S there, from the kept modes and the residual compliance (docs/model.md 4.7)."""
    elastic = model.omega > 0.0
    phi = model.Phi[model.surface_dofs][:, elastic]
    return phi @ ((phi.T @ f_s) / model.omega[elastic] ** 2) + model.resid @ f_s


def direct_static_top(model, f_s: np.ndarray) -> np.ndarray:
    """The same displacement from one sparse solve K u = f (no modes)."""
    import scipy.sparse.linalg as spla

    from granplate.solid.boundary import reduced
    from granplate.solid.fe import stiffness_matrix

    st = model.material
    K = reduced(stiffness_matrix(model.basis, st.E, st.nu), model.dofs)
    f = np.zeros(len(model.dofs))
    f[model.surface_dofs] = f_s
    return spla.spsolve(K.tocsc(), f)[model.surface_dofs]


def centre_index(model) -> int:
    """The top face's dof nearest the centre of the plate."""
    xyz = model.nodes[model.dofs[model.surface_dofs] // 3]
    return int(np.argmin(np.hypot(xyz[:, 0] - SIDE / 2, xyz[:, 1] - SIDE / 2)))


# --------------------------------------------------------------------------- frequencies

def plate_frequencies(ctx: Context) -> CaseResult:
    """Clamped square plates, thin and moderately thick, against Kirchhoff and Mindlin."""
    from .plate_ritz import mindlin_frequency_parameters
    from .plate_theory import LEISSA_CCCC_SQUARE

    thin = np.array([frequency_parameters(clamped_plate(n, THIN_LAYERS, THIN), THIN) for n in THIN_MESHES])
    thick = np.array([frequency_parameters(clamped_plate(n, THICK_LAYERS, THICK), THICK) for n in THICK_MESHES])
    mind_thin = mindlin_frequency_parameters("C", THIN / SIDE, count=3)
    mind_thick = mindlin_frequency_parameters("C", THICK / SIDE, count=3)
    lim_thin, p_thin = richardson(thin[:, 0])
    lim_thick, p_thick = richardson(thick[:, 0])
    nf = THIN_MESHES[-1]
    mesh_why = ("the finest mesh's discretisation error (about a quarter of the 12 x 12 mesh's, "
                "order ~2) plus the model-form difference: " + MODEL_WHY)
    checks = [
        *[Check(f"lambda^2 of mode {i + 1}, a/h = 50, {nf} x {nf} x 1", "-", float(mind_thin[i]),
                "Mindlin plate, Ritz (plate_ritz, 10 x 10 terms)", float(thin[-1, i]), 0.015, mesh_why)
          for i in range(3)],
        Check("lambda^2 of mode 1, a/h = 50, mesh limit (Richardson)", "-", float(mind_thin[0]),
              "Mindlin plate, Ritz", lim_thin, 0.01, MODEL_WHY),
        Check("lambda^2 of mode 1, a/h = 50, mesh limit (Richardson)", "-", LEISSA_CCCC_SQUARE[0],
              "Kirchhoff plate, Leissa (1969), clamped square", lim_thin, 0.01,
              "Kirchhoff neglects shear and rotary inertia, -(h/a)^2 x O(10) = -0.5% at a/h = 50, "
              "of the opposite sign to the 3D clamp's stiffening."),
        Check("observed order of lambda^2_1 under in-plane refinement, a/h = 50", "-", 2.0,
              "quadratic elements; the bending error falls at least as h^2", p_thin, 1.5,
              "a quadratic element's eigenvalue error falls as h^2 or faster (h^4 for smooth modes); "
              "1.5 allows for the pre-asymptotic coarse mesh.", kind="min"),
        Check(f"lambda^2 of mode 1, a/h = 10, mesh limit (Richardson)", "-", float(mind_thick[0]),
              "Mindlin plate, Ritz, kappa = 5/6", lim_thick, 0.02, MODEL_WHY),
        Check("observed order of lambda^2_1 under in-plane refinement, a/h = 10", "-", 2.0,
              "quadratic elements", p_thick, 1.5, "as for the thin plate.", kind="min"),
    ]
    desc = ("A steel square plate of side 100 mm, its four side faces clamped, built by the "
            "simulator's `build_solid` (hex20 elements, modes below lambda^2 = 140 from "
            "the shift-invert eigensolver): thin (h = 2 mm, meshes 6 x 6 x 1, 12 x 12 x 1, "
            "24 x 24 x 1) and moderately thick (h = 10 mm, 4 x 4 x 2, 8 x 8 x 2, 16 x 16 x 2). "
            "References: Leissa's table of the clamped Kirchhoff square, and an independent "
            "Ritz solution of Mindlin's plate equations (polynomial basis, kappa = 5/6).")
    rows = ["| mesh | h [mm] | lambda^2_1 | lambda^2_2 | lambda^2_3 |", "| --- | ---: | ---: | ---: | ---: |"]
    for n, lam in zip(THIN_MESHES, thin):
        rows.append(f"| {n} x {n} x {THIN_LAYERS} | {THIN * 1e3:g} | " + " | ".join(f"{v:.3f}" for v in lam) + " |")
    rows.append(f"| Mindlin (Ritz) | {THIN * 1e3:g} | " + " | ".join(f"{v:.3f}" for v in mind_thin) + " |")
    rows.append(f"| Kirchhoff (Leissa) | - | " + " | ".join(f"{v:.2f}" for v in LEISSA_CCCC_SQUARE[:3]) + " |")
    for n, lam in zip(THICK_MESHES, thick):
        rows.append(f"| {n} x {n} x {THICK_LAYERS} | {THICK * 1e3:g} | " + " | ".join(f"{v:.3f}" for v in lam) + " |")
    rows.append(f"| Mindlin (Ritz) | {THICK * 1e3:g} | " + " | ".join(f"{v:.3f}" for v in mind_thick) + " |")
    notes = [f"Mesh limits (Richardson, lambda^2_1): a/h = 50: {lim_thin:.3f} (order {p_thin:.2f}), "
             f"{lim_thin / mind_thin[0] - 1:+.2%} from Mindlin, {lim_thin / LEISSA_CCCC_SQUARE[0] - 1:+.2%} "
             f"from Kirchhoff; a/h = 10: {lim_thick:.3f} (order {p_thick:.2f}), "
             f"{lim_thick / mind_thick[0] - 1:+.2%} from Mindlin."]
    return CaseResult.of(desc, checks, notes=notes, tables=["\n".join(rows)],
                         plot={"thin": thin[:, 0].tolist(), "thick": thick[:, 0].tolist(),
                               "mind_thin": float(mind_thin[0]), "mind_thick": float(mind_thick[0]),
                               "leissa": LEISSA_CCCC_SQUARE[0]})


def draw_plate_frequencies(p: dict):
    """lambda^2_1 against the element size, thin and thick, with the references."""
    fig, axes = new_figure(ncols=2, width=5.0)
    for ax, key, meshes, ref, label in ((axes[0, 0], "thin", THIN_MESHES, p["mind_thin"], "a/h = 50"),
                                        (axes[0, 1], "thick", THICK_MESHES, p["mind_thick"], "a/h = 10")):
        size = [SIDE / n * 1e3 for n in meshes]
        ax.plot(size, p[key], "o-", label="granplate hex20")
        ax.axhline(ref, color="k", ls="--", label="Mindlin (Ritz)")
        if key == "thin":
            ax.axhline(p["leissa"], color="g", ls=":", label="Kirchhoff (Leissa)")
        ax.set_xscale("log")
        ax.set_xlabel("in-plane element size [mm]")
        ax.set_ylabel("frequency parameter lambda^2_1 [-]")
        ax.set_title(f"clamped square, {label}")
        ax.legend(fontsize=8)
    return fig


# --------------------------------------------------------------------------- statics

def static_plate(ctx: Context) -> CaseResult:
    """Centre deflection of the clamped thin plate under a uniform pressure."""
    from .plate_ritz import kirchhoff_centre_deflection
    from .plate_theory import TIMOSHENKO_CENTRE_DEFLECTION

    D = rigidity(THIN)
    coeff, modal_share, truncation = [], [], math.nan
    for n in THIN_MESHES:
        model = clamped_plate(n, THIN_LAYERS, THIN)
        f_s = top_pressure_loads(model, PRESSURE)
        u = static_top(model, f_s)
        c = centre_index(model)
        coeff.append(-u[c] * D / (PRESSURE * SIDE**4))
        elastic = model.omega > 0.0
        phi = model.Phi[model.surface_dofs][:, elastic]
        modal_share.append(float((phi @ ((phi.T @ f_s) / model.omega[elastic] ** 2))[c] / u[c]))
        if n == THIN_MESHES[1]:
            direct = direct_static_top(model, f_s)
            truncation = float(np.max(np.abs(u - direct)) / np.max(np.abs(direct)))
    coeff = np.array(coeff)
    limit, order = richardson(coeff)
    ritz = kirchhoff_centre_deflection("C", "uniform")
    nf = THIN_MESHES[-1]
    checks = [
        Check(f"w D / (q a^4) at the centre, {nf} x {nf} x 1", "-", ritz,
              "Kirchhoff plate, Ritz (plate_ritz); Timoshenko: 0.00126", float(coeff[-1]), 0.02,
              "the finest mesh is ~1% short of its limit (order ~2 from 6 x 6 to 24 x 24), and 3D "
              "elasticity differs from Kirchhoff by ~(h/a)^2 x O(10) at a/h = 50."),
        Check("w D / (q a^4) at the centre, mesh limit (Richardson)", "-", ritz,
              "Kirchhoff plate, Ritz", limit, 0.01,
              "3D elasticity against Kirchhoff's plate at a/h = 50: shear deflection adds and the "
              "clamped side faces (every point of the thickness held) take away, each ~(h/a)^2 x "
              "O(10); measured -0.4% in the mesh limit."),
        Check("w D / (q a^4), mesh limit, against Timoshenko's coefficient", "-",
              TIMOSHENKO_CENTRE_DEFLECTION[("C", "uniform")], "Timoshenko & Woinowsky-Krieger (1959), ch. 6",
              limit, 0.01, "Timoshenko's 0.00126 is rounded to three digits (the Ritz value is 0.0012653)."),
        Check("observed order of the centre deflection under refinement", "-", 2.0,
              "quadratic elements", order, 1.5, "at least h^2 for quadratic elements; 1.5 allows for "
              "the coarse 6 x 6 mesh.", kind="min"),
        Check(f"max |u_modes+R - u_direct| / max |u| over the top face, {THIN_MESHES[1]} x {THIN_MESHES[1]} x 1",
              "-", 0.0, "one sparse solve K u = f", truncation, 1e-8,
              "the residual compliance is G - Phi Omega^-2 Phi^T over the loaded dofs: modes plus it "
              "are the static solution exactly, up to the factorisations' round-off.", kind="max"),
    ]
    desc = ("The thin clamped plate of `solid-plate-frequencies` (a/h = 50) under a uniform "
            "pressure q on its top face (consistent nodal forces from the face's shape "
            "functions), its top-face deflection computed as a coupled run sees it: the kept "
            "modes' static response plus the residual compliance over the top face's z dofs "
            "(`build_solid`, docs/model.md section 4.7). Reference: the clamped Kirchhoff "
            "square (Ritz; Timoshenko's tabulated 0.00126 q a^4 / D).")
    notes = [f"w D / (q a^4) on {', '.join(f'{n} x {n}' for n in THIN_MESHES)}: "
             f"{', '.join(f'{v:.6f}' for v in coeff)}; limit {limit:.6f} (order {order:.2f}), "
             f"{limit / ritz - 1:+.2%} from Kirchhoff (Ritz {ritz:.7f}). The kept modes carry "
             f"{', '.join(f'{s:.1%}' for s in modal_share)} of the centre deflection, the residual "
             "compliance the rest."]
    return CaseResult.of(desc, checks, notes=notes,
                         plot={"coeff": coeff.tolist(), "ritz": ritz, "limit": limit})


def draw_static_plate(p: dict):
    """The centre deflection coefficient against the element size."""
    fig, axes = new_figure()
    ax = axes[0, 0]
    size = [SIDE / n * 1e3 for n in THIN_MESHES]
    ax.plot(size, np.array(p["coeff"]) * 1e3, "o-", label="granplate hex20 (modes + residual compliance)")
    ax.axhline(p["ritz"] * 1e3, color="k", ls="--", label="Kirchhoff (Ritz)")
    ax.axhline(p["limit"] * 1e3, color="C1", ls=":", label="mesh limit (Richardson)")
    ax.set_xscale("log")
    ax.set_xlabel("in-plane element size [mm]")
    ax.set_ylabel("centre deflection w D / (q a^4) [1e-3]")
    ax.legend(fontsize=8)
    return fig


CASES: tuple[Case, ...] = (
    Case("solid-plate-frequencies", "solid", "3D solid: clamped square plates, thin and thick, vs Kirchhoff and Mindlin",
         plate_frequencies, draw=draw_plate_frequencies),
    Case("solid-static-plate", "solid", "3D solid: clamped plate under a uniform pressure vs Kirchhoff",
         static_plate, draw=draw_static_plate),
)
