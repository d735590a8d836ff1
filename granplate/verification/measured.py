"""Yielding spheres against measurement: Burgoyne & Daraio's 15 compressions of two equal
metal spheres (Phys. Rev. E 89, 032203, 2014; data CC BY 4.0, granplate/verification/data/
burgoyne2014/README.md), their measures, and the normal laws replayed along them.

The measures are those of the data's summary.csv, written again here from the curves (so
that the same code measures a measured and a computed curve): the loading slope
dF/d(delta) (least squares between 30% and 90% of the peak force on the loading branch),
the approach speed over that band (least squares of displacement on time), and the
residual displacement of a Hertzian unloading fit F = K (delta - delta_r)^(3/2) from the
peak down to the first sample below 30% of it (a straight line through F^(2/3)), over the
displacement at the peak force.

A law is replayed directly along the measured overlap: each curve's displacement history
drives the law's compiled kernel from a virgin contact (the law "johnson" with its yield
strength fixed by the measured approach speed, `cavity.johnson_replay`; Thornton's with
its rate-free Y, `plastic.plastic_force`), the force is computed, and the same measures are
taken from it. Functions, no plotting (tests/test_measured_contacts.py).
"""

from __future__ import annotations

import csv
import math
from importlib import resources
from typing import NamedTuple

import numpy as np

#: the spheres' radius [m] and the materials' names (granplate's built-in library) by the
#: summary's material column
SPHERE_RADIUS = 3.175e-3
MATERIALS = {"steel_440C": "steel_440c", "steel_302": "steel_302", "aluminium_2017": "aluminium_2017"}
#: the force band of the loading slope, fractions of the peak force; the end of the
#: unloading fit, a fraction of the peak force
SLOPE_BAND = (0.3, 0.9)
UNLOAD_END = 0.3
#: the law "johnson"'s unloading factor was fitted on this curve (docs/model.md section 3.10)
FITTED_ON = "force12_5"
#: the targets: the loading slope within 20% of the measured one, residual / peak within 0.06
SLOPE_RTOL = 0.2
RATIO_ATOL = 0.06

CITATION = (
    'H. A. Burgoyne and C. Daraio, "Strain-rate-dependent model for the dynamic compression of '
    "elastoplastic spheres\", Phys. Rev. E 89, 032203 (2014); data from the authors' repository "
    "Daraio-lab/Burgoyne_PRE_2014 (GitHub), licence CC BY 4.0 "
    "(https://creativecommons.org/licenses/by/4.0/)."
)


class Curve(NamedTuple):
    """One measured record: name, material (granplate's name), time [s], displacement [m],
    force [N], and its summary.csv row (dict of strings)."""

    name: str
    material: str
    t: np.ndarray
    delta: np.ndarray
    force: np.ndarray
    summary: dict


def data_dir():
    """The data's folder inside the package (a Traversable)."""
    return resources.files("granplate.verification") / "data" / "burgoyne2014"


def load_curves() -> list[Curve]:
    """The 15 curves in summary.csv's order."""
    root = data_dir()
    with (root / "summary.csv").open() as f:
        rows = list(csv.DictReader(f))
    out = []
    for row in rows:
        with (root / row["csv"]).open() as f:
            a = np.loadtxt(f, delimiter=",", skiprows=1)
        name = row["csv"].rsplit("/", 1)[-1][:-4]
        out.append(Curve(name, MATERIALS[row["material"]], a[:, 0], a[:, 1], a[:, 2], row))
    return out


def slope_band(force: np.ndarray) -> np.ndarray:
    """Mask of the loading branch's samples (up to the peak force) between 30% and 90% of
    the peak force."""
    k = int(np.argmax(force))
    lo, hi = SLOPE_BAND
    m = np.zeros(len(force), bool)
    m[: k + 1] = True
    return m & (force >= lo * force[k]) & (force <= hi * force[k])


def loading_slope(delta: np.ndarray, force: np.ndarray) -> float:
    """dF/d(delta) [N/m]: least squares over `slope_band`."""
    m = slope_band(force)
    return float(np.polyfit(delta[m], force[m], 1)[0])


def approach_speed(t: np.ndarray, delta: np.ndarray, force: np.ndarray) -> float:
    """The mean approach speed [m/s] over `slope_band`: least squares of delta on t."""
    m = slope_band(force)
    return float(np.polyfit(t[m], delta[m], 1)[0])


def residual_ratio(delta: np.ndarray, force: np.ndarray) -> float:
    """delta_r / delta at the peak force [-], delta_r of the Hertzian unloading fit
    F = K (delta - delta_r)^(3/2) from the peak down to the first sample below 30% of it
    (a line through F^(2/3)); nan where the fit finds no unloading (a force falling while the
    displacement grows: a residual beyond the peak's displacement)."""
    k = int(np.argmax(force))
    below = np.flatnonzero(force[k:] < UNLOAD_END * force[k])
    end = k + int(below[0]) if len(below) else len(force)
    d, f = delta[k:end], force[k:end]
    if len(d) < 3:
        return math.nan
    slope, intercept = np.polyfit(d, np.maximum(f, 0.0) ** (2.0 / 3.0), 1)
    ratio = -intercept / slope / delta[k]
    return float(ratio) if slope > 0.0 and ratio < 1.0 else math.nan


def measures(t: np.ndarray, delta: np.ndarray, force: np.ndarray) -> dict:
    """{"slope" [N/m], "ratio" [-], "speed" [m/s], "peak" [N]} of one curve."""
    return {
        "slope": loading_slope(delta, force),
        "ratio": residual_ratio(delta, force),
        "speed": approach_speed(t, delta, force),
        "peak": float(np.max(force)),
    }


def contact_of(material: str):
    """(E* [Pa], R* [m], A [N/m^1.5], Material) of two equal spheres of `material`."""
    from granplate.physics.contact import hertz_coefficient
    from granplate.setup.materials import LIBRARY, effective_modulus

    m = LIBRARY[material]
    e_star = effective_modulus(m, m)
    r_star = 0.5 * SPHERE_RADIUS
    return e_star, r_star, hertz_coefficient(e_star, r_star), m


def johnson_row(material: str, **changes) -> np.ndarray:
    """The coefficient row of the law "johnson" between two equal spheres of `material`
    (its fields changed by `changes`, e.g. unloading_factor), as the loop builds it."""
    import dataclasses

    from granplate.model.arrays import coefficient_row
    from granplate.physics.laws import law_columns
    from granplate.setup.law_registry import JOHNSON

    e_star, r_star, a, m = contact_of(material)
    m = dataclasses.replace(m, **changes)
    return coefficient_row(a, 0.0, 0.0, 0.0, law_columns("johnson", m, e_star, r_star, 2.0 * SPHERE_RADIUS), JOHNSON)


def replay_johnson(c: Curve, speed: float | None = None, **changes) -> np.ndarray:
    """The law "johnson"'s force [N] along c's displacement, its yield strength fixed by
    the curve's measured approach speed (or `speed` [m/s]; -1: rate-free)."""
    from granplate.physics.cavity import johnson_replay

    v = approach_speed(c.t, c.delta, c.force) if speed is None else speed
    return johnson_replay(np.ascontiguousarray(c.delta), johnson_row(c.material, **changes), v)


def replay_thornton(c: Curve) -> np.ndarray:
    """Thornton's law's force [N] (docs/model.md section 3.6, rate-free Y) along c's
    displacement from a virgin contact."""
    from granplate.physics.plastic import contact_yield_overlap, plastic_force

    e_star, r_star, a, m = contact_of(c.material)
    dy = contact_yield_overlap(e_star, r_star, m.Y)
    out = np.zeros(len(c.delta))
    dmax = 0.0
    for i, d in enumerate(c.delta):
        if d > 0.0:
            out[i] = plastic_force(a, dy, float(d), dmax)
        dmax = max(dmax, float(d))
    return out


def comparison(curves: list[Curve] | None = None, loop: bool = True, drives: bool = False) -> list[dict]:
    """Per curve: the measured measures and those of the replays ("johnson" and "thornton"
    directly from the laws; "loop": "johnson" through the loop's contact pass and history
    commit, `replay_contact_pass`, unless loop=False; "drives": the whole time loop with the
    test's motion prescribed by drives, `replay_drives`, if drives=True), with the ratios the
    targets judge (slope / measured, residual ratio - measured)."""
    rows = []
    for c in curves or load_curves():
        meas = measures(c.t, c.delta, c.force)
        row = {"name": c.name, "material": c.material, "measured": meas}
        replays = [("johnson", c.delta, replay_johnson(c, meas["speed"])), ("thornton", c.delta, replay_thornton(c))]
        if loop:
            replays.append(("loop", c.delta, replay_contact_pass(c)))
        if drives:
            replays.append(("drives", *replay_drives(c)))
        for law, d, f in replays:
            got = measures(c.t, d, f)
            got["slope_ratio"] = got["slope"] / meas["slope"]
            got["ratio_error"] = got["ratio"] - meas["ratio"]
            got["force"] = f
            row[law] = got
        rows.append(row)
    return rows


def two_spheres(material: str):
    """A 3D scenario of two touching spheres (R = SPHERE_RADIUS, `material`) under the law
    "johnson", undamped and frictionless: the measured test's contact, for the loop's own
    contact pass (`replay_contact_pass`)."""
    import granplate as gp

    r = SPHERE_RADIUS
    return gp.loads(f"""name = "two-spheres-{material}"
dimension = 3
[[granules]]
label = "rear"
x = 0.0
y = 0.0
z = 0.0
radius = {r!r}
material = "{material}"
[[granules]]
label = "front"
x = {2 * r!r}
y = 0.0
z = 0.0
radius = {r!r}
material = "{material}"
[load]
kind = "none"
[contact]
alpha_n = 0.0
mu = 0.0
normal_law = "johnson"
[solver]
scheme = "verlet"
""")


def lead_in(c: Curve) -> tuple[np.ndarray, np.ndarray]:
    """(t [s], delta [m]) of c with the approach before the record started: a straight line
    from zero overlap at the record's first approach speed (over its first microsecond),
    sampled as the record is. The record starts past the yield overlap; the loop fixes a
    contact's yield strength from the overlap's growth in the step that first passes yield."""
    dt = float(c.t[1] - c.t[0])
    k = max(int(round(1e-6 / dt)), 1)
    v = float((c.delta[k] - c.delta[0]) / (c.t[k] - c.t[0]))
    n = int(math.ceil(c.delta[0] / (v * dt)))
    t0 = c.t[0] - dt * np.arange(n, 0, -1)
    return np.concatenate([t0, c.t]), np.concatenate([np.maximum(c.delta[0] - v * (c.t[0] - t0), 0.0), c.delta])


def replay_contact_pass(c: Curve) -> np.ndarray:
    """The force [N] of the time loop's own contact pass in space (`solver.granular3d.
    normal_forces`, the velocity-Verlet force pass) and its history commit (`solver.granular.
    commit_histories`: delta_max and the speed fixing the yield strength) on two spheres
    whose overlap follows c's displacement after `lead_in`, sample by sample; at c's samples."""
    from granplate.model.arrays import build_model
    from granplate.solver.granular import commit_histories
    from granplate.solver.granular3d import normal_forces

    model = build_model(two_spheres(c.material))
    g, cfg = model.granular, model.config
    t, delta = lead_in(c)
    rate = np.gradient(delta, t)
    y = np.array(model.initial_state, float).copy()
    acc, fdamp, fload = np.zeros_like(y), np.zeros_like(y), np.zeros_like(y)
    out = np.zeros(len(t))
    for k in range(len(t)):
        y[0, 3] = rate[k]
        y[1, 0] = 2.0 * SPHERE_RADIUS - delta[k]
        normal_forces(float(t[k]), y, g, cfg, acc, fdamp, fload, -1.0)  # (committed below)
        out[k] = abs(acc[1, 3]) * g.mass[1]
        commit_histories(float(t[k]), g)
    return out[len(t) - len(c.t) :]


def driven_test(c: Curve):
    """The measured test as a scenario: `two_spheres` of c's material, the rear sphere held by
    a velocity drive of value 0, the front one pushed toward it along the line of centres by a
    velocity table, the rate of c's displacement after `lead_in` (the spheres touch at t = 0);
    the velocity-Verlet step a tenth of the record's sampling, an output per sample."""
    import dataclasses

    from granplate.setup.scenario import Drive

    t, d = lead_in(c)
    t = t - t[0]
    dt = float(np.mean(np.diff(t)))
    n = len(t) - 1
    drives = (
        Drive(target="granule rear", kind="velocity", direction=(1.0, 0.0, 0.0), value=0.0),
        Drive(
            target="granule front",
            kind="velocity",
            direction=(-1.0, 0.0, 0.0),
            profile="table",
            times=tuple(float(x) for x in t),
            values=tuple(float(x) for x in np.gradient(d, t)),
        ),
    )
    s = two_spheres(c.material)
    step = dataclasses.replace(
        s.time, t_end=n * dt, dt_initial=dt / 10, dt_max=dt / 10, output_interval=dt, field_interval=n * dt
    )
    return dataclasses.replace(s, name=f"driven-{c.name}", drives=drives, time=step)


def replay_drives(c: Curve) -> tuple[np.ndarray, np.ndarray]:
    """(displacement [m], force [N]) over c's samples, read from the whole time loop's Dataset:
    the front sphere's drive_displacement and the held rear sphere's drive_force (the contact
    force, as a load cell on the fixed side reads it; the pushing drive's force adds the front
    sphere's inertia) of `driven_test`: the measured test replayed as it was done."""
    import warnings

    from granplate.results.run import simulate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # overlaps past overlap_warn: the test's own
        ds = simulate(driven_test(c))
    n = len(c.t)
    x = ds["drive_displacement"].sel(drive="granule front").values[-n:]
    f = ds["drive_force"].sel(drive="granule rear").values[-n:]
    return np.ascontiguousarray(x), np.ascontiguousarray(f)
