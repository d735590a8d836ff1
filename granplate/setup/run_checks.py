"""The rules of [time] and [solver]: steps and intervals, the size of the output a run
would write against the machine's memory, the scheme and its granular friction.
"""

from __future__ import annotations

import math

from granplate.errors import ScenarioError
from granplate.setup.threads import check_threads
from granplate.setup.fields import finite, int_at_least, nonneg, positive, string_in
from granplate.setup.plate_cost import MEMORY_SHARE, physical_memory
from granplate.setup.scenario import Solid, Plate, Scenario


#: Coupling schemes the solver knows (Solver.scheme).
SCHEMES: tuple[str, ...] = ("paper", "implicit", "verlet")
#: Schemes of the granules alone: a scenario with a [plate] is refused with them.
GRANULAR_SCHEMES: tuple[str, ...] = ("verlet",)
#: Treatments of the granule-granule and granule-wall friction (Solver.granular_friction).
GRANULAR_FRICTIONS: tuple[str, ...] = ("split", "rk4")
#: The velocities velocity Verlet's force pass reads at t + h (Solver.verlet_damping).
VERLET_DAMPINGS: tuple[str, ...] = ("predicted", "half_step")
#: Relative tolerance for field_interval being a multiple of output_interval.
INTERVAL_RTOL = 1e-9


def _check_time(s: Scenario) -> None:
    t = s.time
    for f in ("t_end", "dt_initial", "dt_max", "dt_min", "output_interval", "field_interval"):
        positive(f"time.{f}", getattr(t, f))
    if t.dt_min > t.dt_initial:
        raise ScenarioError(
            "time.dt_min", t.dt_min, f"must be <= time.dt_initial = {t.dt_initial!r} (dt_min <= dt_initial <= dt_max)"
        )
    if t.dt_initial > t.dt_max:
        raise ScenarioError(
            "time.dt_initial", t.dt_initial, f"must be <= time.dt_max = {t.dt_max!r} (dt_min <= dt_initial <= dt_max)"
        )
    if t.output_interval > t.t_end:
        raise ScenarioError("time.output_interval", t.output_interval, f"must be <= time.t_end = {t.t_end!r}")
    r = t.field_interval / t.output_interval
    n = round(r)
    if n < 1 or abs(r - n) > INTERVAL_RTOL * r or n > 2**53:
        raise ScenarioError(
            "time.field_interval",
            t.field_interval,
            f"must be a whole multiple n of time.output_interval = "
            f"{t.output_interval!r}, 1 <= n <= 2^53 (beyond, every double is whole)",
        )
    _check_restart_interval(t)
    _check_contact_interval(t)
    _check_restart_table(s)


def contact_steps(t) -> int:
    """The contact table's interval in output intervals (TimeSettings t): time.contact_interval,
    or time.field_interval when absent; 0: no table."""
    dt = t.field_interval if t.contact_interval is None else t.contact_interval
    return round(dt / t.output_interval)


def _check_contact_interval(t) -> None:
    """time.contact_interval: 0 (no contact table) or a whole multiple of output_interval."""
    if t.contact_interval is None:
        return
    nonneg("time.contact_interval", t.contact_interval)
    dt = float(t.contact_interval)
    if dt == 0.0:
        return
    r = dt / t.output_interval
    n = round(r)
    if n < 1 or abs(r - n) > INTERVAL_RTOL * r or n > 2**53:
        raise ScenarioError(
            "time.contact_interval",
            dt,
            f"must be 0 (no contact table) or a whole multiple n of time.output_interval = "
            f"{t.output_interval!r} s, 1 <= n <= 2^53 (absent: time.field_interval)",
        )


def _check_restart_table(s: Scenario) -> None:
    """[restart]: result a non-empty file name, time (when given) >= 0 [s]; whether the
    file holds a state at that time is checked when the run starts (results.restart)."""
    r = s.restart
    if r is None:
        return
    if not isinstance(r.result, str) or not r.result.strip():
        raise ScenarioError(
            "restart.result", r.result, "must name a result netCDF file (relative to the scenario file)"
        )
    if r.time is not None:
        nonneg("restart.time", r.time)


#: The most loop states a result stores before its end time (time.restart_interval).
MAX_RESTART_STATES = 20


def restart_steps(t) -> int:
    """time.restart_interval in output intervals (TimeSettings t; 0: none)."""
    return 0 if t.restart_interval is None else round(t.restart_interval / t.output_interval)


def _check_restart_interval(t) -> None:
    """time.restart_interval: a whole multiple of output_interval, at most MAX_RESTART_STATES
    states before t_end."""
    if t.restart_interval is None:
        return
    positive("time.restart_interval", t.restart_interval)
    dt = float(t.restart_interval)
    r = dt / t.output_interval
    n = round(r)
    if n < 1 or abs(r - n) > INTERVAL_RTOL * r:
        raise ScenarioError(
            "time.restart_interval",
            dt,
            f"must be a whole multiple of time.output_interval = {t.output_interval!r} s (absent: the end only)",
        )
    count = (math.ceil(t.t_end / t.output_interval - 1e-9) - 1) // n  # output times k n before the last
    if count > MAX_RESTART_STATES:
        raise ScenarioError(
            "time.restart_interval",
            dt,
            f"would store {count} loop states before time.t_end = {t.t_end!r} s, allowed at most "
            f"{MAX_RESTART_STATES}: raise it to at least {t.t_end / (MAX_RESTART_STATES + 1)!r} s",
        )


#: Bytes kept per output time, per granule (its state in the buffers, the Dataset and
#: the file written: 3 copies of 6 numbers and a few per contact) and per plate dof (the
#: modal coordinates and their rates, 3 copies), and per plate snapshot and plate dof
#: (displacements, strains and stresses at the nodes, 3 copies).
OUTPUT_BYTES_PER_GRANULE = 3 * 8 * 12
OUTPUT_BYTES_PER_DOF = 3 * 8 * 2
FIELD_BYTES_PER_DOF = 3 * 8 * 4
#: Bytes of a contact table's row (time.contact_interval): 40 bytes, 2 copies (the rows
#: built, the Dataset); about 3 rows per granule and table time in the plane, 6 in space
#: (a close packing's 12 neighbours).
LINK_BYTES_PER_ROW = 2 * 40
LINK_ROWS_PER_GRANULE = {2: 3, 3: 6}
#: Bytes the model and the loop hold per granule beside the outputs: its contact list and
#: coefficients, histories, state and scratch (8,300 measured at a million spheres in
#: space, docs/benchmarks.md).
MODEL_BYTES_PER_GRANULE = 8_500


def output_bytes_per_second(s: Scenario) -> float:
    """About the memory [bytes] a run's outputs take per second of simulated time: a row
    of the granules' states and the plate's modal coordinates per output_interval, a plate
    snapshot per field_interval, the contact table per contact_interval (s resolved)."""
    t = s.time
    n_dof = 0  # a 3D solid writes no fields yet (its coupling comes with its outputs)
    if isinstance(s.plate, Plate):
        p = s.plate
        n_dof = 2 * ((p.nx + 1) * (p.ny + 1) + p.nx * (p.ny + 1) + p.ny * (p.nx + 1))
    row = OUTPUT_BYTES_PER_GRANULE * len(s.granules) + OUTPUT_BYTES_PER_DOF * n_dof + 400.0
    steps = contact_steps(t)
    link = LINK_BYTES_PER_ROW * LINK_ROWS_PER_GRANULE[s.dimension]
    table = link * len(s.granules) / (steps * t.output_interval) if steps > 0 else 0.0
    return row / t.output_interval + FIELD_BYTES_PER_DOF * n_dof / t.field_interval + table


def _check_output_size(s: Scenario) -> None:
    """The outputs of t_end fit in MEMORY_SHARE of the machine's memory beside the model and
    the loop (MODEL_BYTES_PER_GRANULE a granule), at the output stride of a run of many
    granules (setup.output_stride)."""
    from granplate.setup.output_stride import with_output_stride

    s = with_output_stride(s)
    total = MEMORY_SHARE * physical_memory()
    model = MODEL_BYTES_PER_GRANULE * len(s.granules)
    memory = total - model
    t_max = max(memory, 0.0) / output_bytes_per_second(s)
    t = s.time
    if total > 0.0 and not t.t_end <= t_max:
        need = t.t_end * output_bytes_per_second(s)
        raise ScenarioError(
            "time.t_end",
            t.t_end,
            f"allowed: t_end <= {t_max:.3g} s with these output intervals: the outputs would need "
            f"about {need / 1e9:.3g} GB ({t.t_end / t.output_interval:.3g} "
            f"output times, time.output_interval = {t.output_interval!r} s; "
            f"{t.t_end / t.field_interval:.3g} plate snapshots, time.field_interval = "
            f"{t.field_interval!r} s) beside about {model / 1e9:.3g} GB for the model of "
            f"{len(s.granules)} granules, this machine allows {total / 1e9:.3g} GB in all: raise "
            "the intervals or shorten t_end",
        )


def _check_solver(s: Scenario) -> None:
    sv = s.solver
    string_in("solver.scheme", sv.scheme, SCHEMES)
    string_in("solver.granular_friction", sv.granular_friction, GRANULAR_FRICTIONS)
    if sv.verlet_damping is not None:
        string_in("solver.verlet_damping", sv.verlet_damping, VERLET_DAMPINGS)
    if sv.verlet_damping == "half_step" and sv.scheme != "verlet":
        raise ScenarioError(
            "solver.verlet_damping",
            sv.verlet_damping,
            f'sets the velocities velocity Verlet\'s force pass reads: solver.scheme = "verlet" only, not {sv.scheme!r}',
        )
    if sv.verlet_damping == "half_step" and isinstance(s.plate, Solid):
        raise ScenarioError(
            "solver.verlet_damping",
            sv.verlet_damping,
            "an elastic solid's contacts read its modes' predicted velocities (docs/model.md section 3.9): "
            "\"predicted\" only with a [plate] in space (the half step's is LAMMPS's convention for granules alone)",
        )
    if sv.scheme in GRANULAR_SCHEMES:
        _check_granular_scheme(s)
    elif isinstance(s.plate, Solid):
        _check_solid_scheme(s)
    lam = finite("solver.lambda_target", sv.lambda_target, "must be in (0, 1)")
    if not 0.0 < lam < 1.0:
        raise ScenarioError("solver.lambda_target", sv.lambda_target, "must be in (0, 1)")
    positive("solver.iteration_rtol", sv.iteration_rtol)
    positive("solver.iteration_atol", sv.iteration_atol)
    int_at_least("solver.max_iterations", sv.max_iterations, 1)
    positive("solver.energy_tol", sv.energy_tol)
    positive("solver.error_tol", sv.error_tol)
    positive("solver.implicit_dt_max", sv.implicit_dt_max)
    if sv.energy_span is not None:
        positive("solver.energy_span", sv.energy_span)
    check_threads(sv.threads)


#: Schemes that drive an elastic solid in 3D besides the granular ones (docs/model.md
#: section 6.7): its modes advanced exactly for contact forces linear over the step.
SOLID_SCHEMES: tuple[str, ...] = ("implicit",)


def _check_solid_scheme(s: Scenario) -> None:
    """An elastic solid in 3D under a plate scheme: "implicit" (not "paper", whose
    predictor-corrector is written for the plane's plate contacts), friction split off."""
    sv = s.solver
    if sv.scheme not in SOLID_SCHEMES:
        raise ScenarioError(
            "solver.scheme",
            sv.scheme,
            "an elastic solid in 3D is coupled to the granules by velocity Verlet (docs/model.md section 3.9) "
            "or by the implicit scheme (section 6.7), not by the paper's scheme (written for the plane's plate "
            'contacts): set solver.scheme = "implicit" or "verlet"',
        )
    if sv.granular_friction != "split":
        raise ScenarioError(
            "solver.granular_friction",
            sv.granular_friction,
            f'must be "split" with an elastic solid in 3D and solver.scheme = {sv.scheme!r} (the friction at '
            "the solid's contacts is split off exactly, as velocity Verlet's, docs/model.md section 6.7)",
        )


def _check_granular_scheme(s: Scenario) -> None:
    """A scheme of the granules alone (GRANULAR_SCHEMES): no plate (an elastic solid in
    space is its own: docs/model.md section 3.9), friction split off."""
    sv = s.solver
    if s.plate is not None and not isinstance(s.plate, Solid):
        raise ScenarioError(
            "solver.scheme",
            sv.scheme,
            "velocity Verlet does not drive the plane's plate: the plate's contacts (rigid layers and face "
            "patches, docs/model.md sections 3.4-3.5) move its modes inside the paper's and the implicit "
            "scheme's steps only (sections 6.1-6.2), while velocity Verlet's kicks take the granules alone "
            "(section 6.5; in space it drives the elastic solid, section 3.9): "
            'set solver.scheme = "implicit" or "paper"',
        )
    if sv.granular_friction != "split":
        raise ScenarioError(
            "solver.granular_friction",
            sv.granular_friction,
            'must be "split" with solver.scheme '
            f"= {sv.scheme!r} (its friction is split off exactly, never inside the step)",
        )
