"""Conservation cases: the energy balance of every preset, the momenta of a free
assembly, and forces equal to minus the gradient of the contact energies.

The energy residual (E_p + E_g + D - E_shock - E_0) / max(E_in) is an output of every run
(docs/model.md section 7). It is a discretisation error, so besides its size we check that it
shrinks when the step is halved: a term missing from the bookkeeping would leave a
residual that does not.
"""

from __future__ import annotations

import math

import numpy as np

from granplate.solver.schemes.implicit import ENERGY_STEP_FRACTION
from granplate.setup.scenario import Solver
from .base import EPS, Case, CaseResult, Check, Context, load_case_scenario, new_figure, observed_order, simulate

#: Shortened run of the fast suite [s]: the 10 µs shock and the first arrivals at the plate.
SHORT_T_END = 5e-5
#: Largest energy residual accepted at the default step.
RESIDUAL_TOL = 1e-6
RESIDUAL_WHY = (
    "one part per million, a hundred times below the simulator's own abort "
    "threshold (solver.energy_tol = 1e-4) and far above the values seen (1e-10 ... "
    "1e-8); the order row below shows that what remains is discretisation error."
)


#: The implicit scheme's step control lets the residual grow by solver.energy_tol times
#: schemes.implicit.ENERGY_STEP_FRACTION over a run.
IMPLICIT_RESIDUAL_TOL = Solver().energy_tol * ENERGY_STEP_FRACTION
IMPLICIT_RESIDUAL_WHY = (
    "the implicit scheme picks its step so that the residual grows by at most "
    f"solver.energy_tol x ENERGY_STEP_FRACTION = {Solver().energy_tol:g} x "
    f"{ENERGY_STEP_FRACTION:g} over a run (its "
    "accuracy, not a stability limit, sets the step, so the residual is larger "
    "than the paper scheme's at its tiny steps, and its order is not a step "
    "property)."
)


def _halved(s):
    """The scenario with every step halved: dt_max, dt_initial and the eq. (8) target."""
    from granplate.setup.io import with_changes

    return with_changes(
        s,
        {
            "time.dt_max": s.time.dt_max / 2,
            "time.dt_initial": s.time.dt_initial / 2,
            "solver.lambda_target": s.solver.lambda_target / 2,
        },
    )


def _residual(ds) -> float:
    return float(np.max(np.abs(ds.energy_residual_max.values)))


def short_run_checks(series, checks):
    """Each preset's 50 us runs, appended to `checks` (and the paper scheme's run to `series`): the largest
    residual under the implicit scheme and under the paper scheme, and the paper scheme's observed order
    under step halving (the bare plate: Newmark's exact balance to round-off)."""
    from granplate.setup.io import with_changes
    from granplate.setup.presets import preset, preset_names

    for name in preset_names():
        # the default (implicit) scheme: its step control holds the residual's growth
        r_imp = _residual(simulate_short(preset(name)))
        checks.append(
            Check(
                f"max |energy residual|, {name}, 50 µs, implicit scheme",
                "-",
                0.0,
                "exact balance E_p + E_g + D = E_shock (docs/model.md section 7)",
                r_imp,
                IMPLICIT_RESIDUAL_TOL,
                IMPLICIT_RESIDUAL_WHY,
                kind="max",
            )
        )
        # the paper scheme: size and order under step halving
        s = with_changes(preset(name), {"solver.scheme": "paper"})
        ds = simulate_short(s)
        ds2 = simulate_short(_halved(s))
        r1, r2 = _residual(ds), _residual(ds2)
        series[name] = ds
        n_steps = int(ds.n_steps.values[-1]) if "n_steps" in ds else 0
        if s.layout is None and not s.granules:  # bare plate: Newmark's exact energy identity
            checks.append(
                Check(
                    f"max |energy residual|, {name}, 50 µs",
                    "-",
                    0.0,
                    "Newmark average acceleration + trapezoidal load work: exact balance",
                    r1,
                    max(n_steps, 1) * EPS * 10,
                    "for a linear undamped system the average-acceleration rule with "
                    "the trapezoidal work of the load conserves energy exactly; only "
                    "round-off accumulates (10 eps per step).",
                    kind="max",
                )
            )
            continue
        checks.append(
            Check(
                f"max |energy residual|, {name}, 50 µs",
                "-",
                0.0,
                "exact balance E_p + E_g + D = E_shock (docs/model.md section 7)",
                r1,
                RESIDUAL_TOL,
                RESIDUAL_WHY,
                kind="max",
            )
        )
        checks.append(
            Check(
                f"observed order of the residual, {name}, h -> h/2",
                "-",
                1.0,
                "consistency: the residual vanishes as h -> 0",
                observed_order(r1, r2),
                1.0,
                "any consistent bookkeeping gives order >= 1; expected between 5/4 "
                "(t^(1/4) onset of the damping force, see Chung & Ooi test 3) and 2 "
                "(trapezoidal interface work on the plate side).",
                kind="min",
            )
        )


def full_run_checks(ctx, full_rows, checks):
    """With ctx.full, the full 2 ms runs' largest residual appended to `checks`, each run's summary to
    `full_rows`."""
    if ctx.full:
        from .coupled import study_run

        for name, s_full in full_runs():
            summ = study_run(ctx, s_full)
            full_rows.append((name, summ))
            checks.append(
                Check(
                    f"max |energy residual|, {name}, full 2 ms run",
                    "-",
                    0.0,
                    "exact balance E_p + E_g + D = E_shock (docs/model.md section 7)",
                    summ["energy_residual_max"],
                    RESIDUAL_TOL,
                    RESIDUAL_WHY,
                    kind="max",
                )
            )


def energy_residual(ctx: Context) -> CaseResult:
    """Energy residual of every preset: its size with both schemes, and its decrease under
    step halving with the paper scheme."""
    checks = []
    series = {}
    full_rows = []

    short_run_checks(series, checks)
    full_run_checks(ctx, full_rows, checks)
    desc = (
        "Every preset (`granplate presets`) is run for 50 µs (the shock and the first "
        "arrivals at the plate) with the default (implicit) scheme, and with the paper "
        "scheme at its default settings and again with every step halved "
        "(time.dt_max, time.dt_initial and solver.lambda_target halved); the largest "
        "per-step residual |E_p + E_g + D - E_shock - E_0| / max(E_in) is reported. "
        + (
            "With --full the full 2 ms runs are checked too."
            if ctx.full
            else "The full 2 ms runs are checked by `granplate verify --full`."
        )
    )
    res = CaseResult.of(desc, checks, plot={"series": series})
    if full_rows:
        lines = ["| preset | E_shock [J] | max abs residual, 2 ms | steps |", "|---|---|---|---|"]
        for name, summ in full_rows:
            lines.append(f"| {name} | {summ['e_shock']:.4e} | {summ['energy_residual_max']:.2e} | {summ['n_steps']} |")
        res.tables.append("\n".join(lines))
    return res


def draw_energy_residual(p: dict):
    """The figure of energy_residual, from its numbers."""
    series = p["series"]
    fig, axes = new_figure()
    ax = axes[0, 0]
    for name, ds in series.items():
        r = np.abs(ds.energy_residual_max.values)
        ax.semilogy(ds.time.values * 1e6, np.where(r > 0, r, np.nan), lw=1, label=name)
    ax.set_xlabel("time [µs]")
    ax.set_ylabel("|energy residual| per output interval [-]")
    ax.set_title("paper scheme, default step (40 ns), first 50 µs")
    ax.legend(fontsize=7)
    return fig


def full_runs() -> list:
    """(preset, scenario) of the full-length runs checked with --full: every preset with
    the paper scheme."""
    from granplate.setup.io import with_changes
    from granplate.setup.presets import preset, preset_names

    return [(name, with_changes(preset(name), {"solver.scheme": "paper"})) for name in preset_names()]


def simulate_short(s):
    """The scenario run for SHORT_T_END seconds."""
    from granplate.results.run import simulate as run

    return run(s, t_end=SHORT_T_END, progress=False)


# --------------------------------------------------------------------------- momenta


def _momenta(ds) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """(p_x, p_y, L_z about the origin) over time, and their scales sum m|v|, sum |m r x v| + |I w|."""
    m = ds.mass.values
    r = ds.radius.values
    inertia = 0.4 * m * r**2
    x, y, vx, vy, w = (ds[k].values for k in ("x", "y", "vx", "vy", "omega"))
    px = (m * vx).sum(axis=1)
    py = (m * vy).sum(axis=1)
    L = (m * (x * vy - y * vx)).sum(axis=1) + (inertia * w).sum(axis=1)
    p_scale = float(np.max(np.sum(m * np.hypot(vx, vy), axis=1)))
    L_scale = float(np.max(np.sum(np.abs(m * (x * vy - y * vx)) + np.abs(inertia * w), axis=1)))
    return px, py, L, p_scale, L_scale


def friction_couple(model, y: np.ndarray) -> tuple[float, float, float]:
    """At state y: (dL/dt from granular_rhs, -sum f delta over the pairs, torque scale).

    dL/dt = sum m (x a_y - y a_x) + I alpha about the origin (velocity terms cancel). With the
    default torques of docs/model.md section 3.2 (arm R on each granule) a frictional pair leaves the couple
    f (d - R_i - R_j) = -f delta, so dL/dt = -sum_pairs f delta.
    """
    from granplate.physics.contact import normal_force, pair_overlap, pair_rates
    from granplate.physics.laws import tangential_friction
    from granplate.solver import granular as K

    g, cfg = model.granular, model.config
    ng = y.shape[0]
    dy = np.zeros((ng, 6))
    z = np.zeros(0)
    K.granular_rhs(0.0, y, z, z, g, cfg, dy, z, z, z, False, z)
    m, inertia = g.mass, g.inertia
    terms = np.concatenate([m * y[:, 0] * dy[:, 4], -m * y[:, 1] * dy[:, 3], inertia * dy[:, 5]])
    dL = float(terms.sum())
    couple = 0.0
    for p, (i, j) in enumerate(g.pair_ij):
        delta, nx, nz = pair_overlap(y[i, 0], y[i, 1], g.radius[i], y[j, 0], y[j, 1], g.radius[j])
        if delta <= 0.0:
            continue
        ddot, vt = pair_rates(y[i, 3], y[i, 4], y[i, 5], y[j, 3], y[j, 4], y[j, 5], nx, nz, g.radius[i], g.radius[j])
        n, _ = normal_force(delta, ddot, g.pair_coef[p, 0], g.pair_coef[p, 1], cfg.clip)
        couple -= tangential_friction(n, vt, g.pair_coef[p]) * delta
    return dL, couple, float(np.abs(terms).sum())


def momentum_checks(mom, checks, tol, roundoff_why):
    """Linear momentum conserved to round-off in each run (with friction, frictionless, with the
    contact-point arm); angular momentum too without friction and with the contact-point arm, appended
    to `checks`."""
    for k in ("friction", "frictionless", "friction, contact-point arm"):
        px, py, L, ps, Ls = mom[k]
        drift = float(max(np.abs(px - px[0]).max(), np.abs(py - py[0]).max()) / ps)
        checks.append(
            Check(
                f"linear momentum drift / sum m|v|, {k}",
                "-",
                0.0,
                "Newton's third law: conserved",
                drift,
                tol,
                roundoff_why,
                kind="max",
            )
        )
    px, py, L, ps, Ls = mom["frictionless"]
    checks.append(
        Check(
            "angular momentum drift / scale, frictionless (mu = 0)",
            "-",
            0.0,
            "central forces: conserved",
            float(np.abs(L - L[0]).max() / Ls),
            tol,
            roundoff_why,
            kind="max",
        )
    )
    px, py, L, ps, Ls = mom["friction, contact-point arm"]
    L_drift = float(np.abs(L - L[0]).max() / Ls)
    checks.append(
        Check(
            "angular momentum drift / scale, with friction (mu = 0.3), contact.torque_arm = contact_point",
            "-",
            0.0,
            "conserved to round-off",
            L_drift,
            tol,
            roundoff_why,
            kind="max",
        )
    )


def friction_couple_check(s_fric, runs, checks):
    """The angular momentum's balance with friction under the centre arm (eq. 1, docs/model.md section
    3.1): dL/dt against the couple -f delta the pairs leave, at every output time, appended to `checks`.
    Returns (the run, the couple at each output time)."""
    from granplate.model.arrays import build_model

    model = build_model(s_fric)
    ds = runs["friction"]
    state = np.stack([ds[k].values for k in ("x", "y", "theta", "vx", "vy", "omega")], axis=-1)
    worst = 0.0
    defect = np.zeros(len(ds.time))
    for n in range(len(ds.time)):
        dL, couple, scale = friction_couple(model, np.ascontiguousarray(state[n]))
        defect[n] = couple
        if scale > 0:
            worst = max(worst, abs(dL - couple) / scale)
    checks.append(
        Check(
            "dL/dt + sum f delta, every output, / sum of torque terms",
            "-",
            0.0,
            "eq. (1), docs/model.md section 3.1: torque arm R leaves the couple -f delta per pair",
            worst,
            100 * EPS,
            "both sides evaluated at the same state: round-off of a sum of ~20 terms (100 eps).",
            kind="max",
        )
    )
    return ds, defect


def free_assembly(ctx: Context) -> CaseResult:
    """Linear and angular momentum of a free assembly (no walls, no plate, no load)."""

    s_fric = load_case_scenario("free-assembly")
    s_free = load_case_scenario("free-assembly", {"contact.mu": 0.0})
    s_arm = load_case_scenario("free-assembly", {"contact.torque_arm": "contact_point"})
    runs = {
        "friction": simulate(s_fric),
        "frictionless": simulate(s_free),
        "friction, contact-point arm": simulate(s_arm),
    }
    n_steps = int(runs["friction"].n_steps.values[-1])
    tol = n_steps * EPS
    roundoff_why = (
        f"pairwise forces cancel exactly, so only round-off accumulates: {n_steps} "
        f"steps x eps = {tol:.1e} (worst case, linear growth)."
    )
    checks = []
    mom = {k: _momenta(ds) for k, ds in runs.items()}
    momentum_checks(mom, checks, tol, roundoff_why)
    ds, defect = friction_couple_check(s_fric, runs, checks)
    L_fric = mom["friction"][2]
    L_change = float(L_fric[-1] - L_fric[0])
    impulse = (
        float(np.trapezoid(defect, ds.time.values))
        if hasattr(np, "trapezoid")
        else float(np.trapz(defect, ds.time.values))
    )
    desc = (
        "Four steel spheres (R = 8-10 mm) with spins collide obliquely in free space, no "
        "walls, plate or load (`free-assembly.toml`: mu = 0.3, alpha_n = 0.05, h = 10 ns, 1 ms, "
        "several collisions with sliding and damping), and the same with mu = 0. Linear "
        "momentum sum m v and angular momentum about the origin sum m (x v_y - y v_x) + I "
        "omega are evaluated at every output (1 µs)."
    )
    notes = [
        "With the torques of the paper's eq. (1) (docs/model.md section 3, the default "
        "contact.torque_arm = radius) angular momentum is not conserved when friction acts: "
        "friction acts on each sphere with arm R_i, "
        "but the two arms add up to R_i + R_j = d + delta, not to the centre distance d, so every "
        f"sliding pair applies a net couple -f delta. Integrated here: {impulse:.3e} N m s, the "
        f"observed change of L ({L_change:.3e} N m s). The row 'dL/dt + sum f delta' shows "
        "that this couple is the whole story. A torque arm R_i - delta/2 (the distance to the "
        "contact point; slip rate with the same arms, so that the friction power stays f v_t), "
        "the option contact.torque_arm = contact_point, conserves L to round-off, as the "
        "conservation row shows.",
        "The free assembly needs h = 10 ns: while a frictional contact sticks, the tanh law "
        "relaxes the slip at rate mu k_s |N| (1/m_i + 1/m_j + R_i^2/I_i + R_j^2/I_j), about 2e8 "
        "1/s at the peak force here, and RK4 is stable only below h times that rate = 2.8. With "
        "solver.granular_friction = rk4 the step control bounds h times that rate by 1 at every "
        "granule contact; the default (split) solves that friction exactly per contact at any "
        "step; the scenario fixes dt_max = 10 ns anyway.",
    ]
    return CaseResult.of(desc, checks, plot={"ds": ds, "mom": mom}, notes=notes)


def draw_free_assembly(p: dict):
    """The figure of free_assembly, from its numbers."""
    ds, mom = p["ds"], p["mom"]
    fig, axes = new_figure()
    ax = axes[0, 0]
    t = ds.time.values * 1e3
    for k, style in (("friction", "-"), ("frictionless", "--"), ("friction, contact-point arm", ":")):
        px, py, L, ps, Ls = mom[k]
        ax.semilogy(t, np.abs(px - px[0]) / ps + 1e-18, style, lw=1, label=f"|d p_x| / scale, {k}")
        ax.semilogy(t, np.abs(L - L[0]) / Ls + 1e-18, style, lw=1.5, label=f"|d L| / scale, {k}")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("relative drift [-]")
    ax.set_ylim(1e-18, 1e-2)
    ax.legend(fontsize=7)
    return fig


# --------------------------------------------------------------------------- force gradient

#: Displacements [m] that press the force-gradient assembly into overlap (g0, g1, g2) and
#: the plate contact's driving-dof displacement (x, y).
PRESS = np.array([[-3e-6, -2e-6], [-6e-6, 1.5e-6], [-1.2e-5, -4e-6]])
PLATE_U = np.array([-2e-5, 1e-6])


def _energy_and_forces(model, y: np.ndarray, up: np.ndarray):
    """(contact energy, forces on the granules (ng, 2), torques (ng,), force on the plate)."""
    from granplate.solver import granular as K

    g, cfg = model.granular, model.config
    ng = y.shape[0]
    nd = up.shape[0]
    dy = np.zeros((ng, 6))
    fplate = np.zeros(nd)
    nk = nd // 2
    out = K.granular_rhs(0.0, y, up, np.zeros(nd), g, cfg, dy, fplate, np.zeros(nk), np.zeros(nk), False, np.zeros(nk))
    forces = dy[:, 3:5] * g.mass[:, None]
    return float(out.e_pot), forces, dy[:, 5] * g.inertia, fplate


def _gradient(fun, x0: np.ndarray, eta: float) -> np.ndarray:
    """4th-order central differences of a scalar function."""
    grad = np.zeros_like(x0)
    for k in range(x0.size):

        def at(s):
            x = x0.copy()
            x.flat[k] += s
            return fun(x)

        grad.flat[k] = (8 * (at(eta) - at(-eta)) - (at(2 * eta) - at(-2 * eta))) / (12 * eta)
    return grad


def force_gradient(ctx: Context) -> CaseResult:
    """Forces (granular_rhs) = minus the gradient of the contact energies (finite differences)."""
    from granplate.model.arrays import build_model

    model = build_model(load_case_scenario("force-gradient"))
    y = model.initial_state.copy()
    y[:, 0:2] += PRESS
    up = PLATE_U.copy()
    energy, forces, torques, fplate = _energy_and_forces(model, y, up)
    g = model.granular
    # every contact of the assembly is in overlap (so each force law is exercised)
    d_min = min(
        [g.radius[i] + g.radius[j] - math.hypot(*(y[j, :2] - y[i, :2])) for i, j in g.pair_ij]
        + [float(y[i, 0] * geo[0] + y[i, 1] * geo[1] + g.radius[i] - geo[2]) for i, geo in zip(g.wall_i, g.wall_geo)]
        + [float(y[i, 0] + g.radius[i] - (g.pc_x[k] + up[2 * k])) for k, i in enumerate(g.pc_i)]
    )
    if not d_min > 0:
        raise RuntimeError(f"force-gradient assembly not in overlap everywhere (min delta {d_min:g})")

    def e_pos(pos):
        yy = y.copy()
        yy[:, 0:2] = pos
        return _energy_and_forces(model, yy, up)[0]

    def e_plate(u):
        return _energy_and_forces(model, y, u)[0]

    eta = 2.0 ** round(math.log2(1e-3 * d_min))  # a power of two: x +- eta is exact
    grad_pos = _gradient(e_pos, y[:, 0:2].copy(), eta)
    grad_u = _gradient(e_plate, up.copy(), eta)
    scale = float(np.abs(forces).max())
    err_g = float(np.abs(forces + grad_pos).max() / scale)
    err_p = float(np.abs(fplate + grad_u).max() / scale)
    why = (
        "4th-order central differences with eta ~ 1e-3 delta_min, a power of two so that "
        "x +- eta is exact: truncation ~(eta/delta)^4 ~ 1e-12, round-off ~eps E/(eta F) ~ "
        "1e-12; tolerance 1e-10."
    )
    checks = [
        Check(
            "max |F + dE/dx| / max |F|, granules (2 pairs, 2 walls, 1 plate)",
            "-",
            0.0,
            "F = -grad E, E = sum 2/5 A delta^(5/2) (eq. 9)",
            err_g,
            1e-10,
            why,
            kind="max",
        ),
        Check(
            "max |F_plate + dE/du| / max |F|, plate contact",
            "-",
            0.0,
            "force on the plate = -dE/du at the driving dofs",
            err_p,
            1e-10,
            why,
            kind="max",
        ),
        Check(
            "max |torque| / (max |F| R), at rest",
            "-",
            0.0,
            "normal forces are central: no torque without slip",
            float(np.abs(torques).max() / (scale * g.radius.max())),
            EPS,
            "at zero velocity the friction is mu |N| tanh(0) = 0 exactly.",
            kind="max",
        ),
    ]
    etas = 2.0 ** np.round(np.log2(np.geomspace(1e-7, 0.3, 20) * d_min))
    errs = [float(np.abs(forces + _gradient(e_pos, y[:, 0:2].copy(), e)).max() / scale) for e in etas]
    desc = (
        "A static assembly (`force-gradient.toml`: three spheres, steel and PTFE, touching "
        "each other, a left and a bottom wall, and a 2 x 20 plate through a rigid layer) is "
        "pressed into overlap by displacing the granules and the plate contact by a few "
        f"µm (smallest overlap {d_min:.2e} m), at rest. The forces returned by the compiled "
        "`solver.granular.granular_rhs` are compared with minus the finite-difference gradient of "
        "the contact energy it returns (sum 2/5 A delta^(5/2) over every pair, wall and "
        "plate contact), with respect to every granule coordinate and the plate's "
        "driving displacement."
    )
    return CaseResult.of(desc, checks, plot={"etas": etas, "d_min": d_min, "errs": errs, "eta": eta})


def draw_force_gradient(p: dict):
    """The figure of force_gradient, from its numbers."""
    etas, d_min, errs, eta = p["etas"], p["d_min"], p["errs"], p["eta"]
    fig, axes = new_figure()
    ax = axes[0, 0]
    ax.loglog(etas / d_min, errs, "o-")
    ax.axvline(eta / d_min, color="k", ls=":", lw=0.8, label="step used")
    ax.set_xlabel("finite-difference step eta / delta_min [-]")
    ax.set_ylabel("max |F + dE/dx| / max |F| [-]")
    ax.set_title("truncation (eta^4) vs round-off (1/eta)")
    ax.legend(fontsize=8)
    return fig


CASES: tuple[Case, ...] = (
    Case(
        "energy-residual", "conservation", "Energy residual of every preset", energy_residual, draw=draw_energy_residual
    ),
    Case("free-assembly", "conservation", "Momenta of a free assembly", free_assembly, draw=draw_free_assembly),
    Case(
        "force-gradient",
        "conservation",
        "Forces = minus the gradient of the contact energies",
        force_gradient,
        draw=draw_force_gradient,
    ),
)
