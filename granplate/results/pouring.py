"""Settling a poured packing with the project's own time loop (docs/model.md section 3.14).

`settle(scenario, layout)`: the layout's granules in their loose column
(`setup.pouring.loose_column`), the container's walls and the pouring gravity make a
generated scenario of the velocity-Verlet scheme; `simulate` runs it in chunks of
`chunk_steps` steps, each chunk starting from the last one's end state, until the
kinetic energy is at most settle_tolerance x the work gravity has done: first with the
contact damping alpha_n = settle_damping, then with the scenario's own contact
coefficients (so that the packing rests with the real material). The settled centres and
radii go to the run store (`setup.pouring.STORE_KIND`); a settling that does not converge
within settle_time keeps what it reached in the store under the kind "poured-partial"
and stops with the residual kinetic energy and what to change. Importing this module
registers `settle` with `setup.pouring` (`granplate/__init__.py` does, so every import of
granplate has it). With layout.settle_softening > 1 (3D) the settling is `results.ramped`'s
instead, stored the same way.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import warnings

import numpy as np

from granplate import store
from granplate.errors import ScenarioError
from granplate.model.dimension import of_number
from granplate.setup import pouring
from granplate.setup.scenario import Granule, Gravity, Load, PouredLayout, Scenario, Solver, TimeSettings

log = logging.getLogger("granplate")

#: Steps per contact duration (Hertz's, at the speed of a fall through the column).
STEPS_PER_CONTACT = 30
#: Granule-steps of one chunk of the settling (one progress line each), and the bounds of
#: its steps.
CHUNK_GRANULE_STEPS = 20_000_000
CHUNK_STEPS = (2000, 40000)
#: The damped phase quenches the granules' motion after a chunk whose kinetic energy is
#: at most this fraction of gravity's work (the fall is over).
QUENCH_BELOW = 1e-4
#: Output rows per chunk (the end state is the last).
CHUNK_OUTPUTS = 4
#: Mindlin's tangential damping x_t of a settling with layout.settle_friction (docs/model.md
#: section 3.16: eta_t = x_t c delta^(1/4), the normal damping's coefficient at x_t = 1).
SETTLE_TANGENTIAL_DAMPING = 1.0


def hertz_contact_time(r: float, rho: float, E: float, nu: float, v: float) -> float:
    """The duration [s] of a Hertz impact of two equal spheres of radius r [m] at the
    relative speed v [m/s]: 2.87 (m*^2 / (R* E*^2 v))^(1/5) (Johnson, Contact Mechanics, eq. 11.24),
    m* = m/2, R* = r/2, E* = E / (2 (1 - nu^2))."""
    m = rho * 4.0 / 3.0 * math.pi * r**3
    e_star = E / (2.0 * (1.0 - nu**2))
    return 2.87 * ((0.5 * m) ** 2 / (0.5 * r * e_star**2 * v)) ** 0.2


def settling_step(s: Scenario, lay: PouredLayout, g: tuple[float, ...]) -> float:
    """The Verlet step [s]: the contact time of the smallest granules at the speed of a fall
    through the loose column's height (at least one cell), over STEPS_PER_CONTACT."""
    m = s.material(lay.material)
    h = pouring.cell_size(lay) * (math.ceil(lay.count / _per_layer(lay, s.dimension, g)) + 1)
    v = math.sqrt(2.0 * math.hypot(*g) * h)
    return hertz_contact_time(float(lay.radius_range[0]), m.rho, m.E, m.nu, v) / STEPS_PER_CONTACT


def _per_layer(lay: PouredLayout, dimension: int, g: tuple[float, ...]) -> int:
    """Cells of the loose column per layer."""
    axis, _ = pouring.floor_axis(g)
    size, h = pouring.container_size(lay, dimension), pouring.cell_size(lay)
    return int(np.prod([max(1, int(size[k] // h)) for k in range(dimension) if k != axis]))


def chunk_steps(count: int) -> int:
    """Steps of one chunk: CHUNK_GRANULE_STEPS / count within CHUNK_STEPS."""
    return int(min(max(CHUNK_GRANULE_STEPS // max(count, 1), CHUNK_STEPS[0]), CHUNK_STEPS[1]))


def loose_scenario(s: Scenario, lay: PouredLayout, alpha_n: float | None, friction: float = 0.0) -> Scenario:
    """The generated scenario of the settling: the loose column, the container, the pouring
    gravity, the Verlet scheme at `settling_step`, no plate and no load; alpha_n: the
    contact damping of every pair, without friction (None: the scenario's own coefficients);
    friction > 0 (with alpha_n): Mindlin's friction of that coefficient instead, with the
    tangential damping SETTLE_TANGENTIAL_DAMPING.
    The regularised friction (mu tanh(k_s v), docs/model.md section 3.2) holds no static
    load without creeping, so the damped phase settles a frictionless packing, a true
    equilibrium, which friction at rest (v = 0) leaves one."""
    g = pouring.pour_gravity(s, lay)
    radii = pouring.poured_radii(lay)
    c, _ = pouring.dropped(lay, s.dimension, g)
    z = np.pad(c, ((0, 0), (0, 3 - c.shape[1])))[:, 2]  # 0 in the plane
    spin = of_number(s.dimension).spin((0.0, 0.0, 0.0))
    granules = tuple(
        Granule(
            float(c[i, 0]),
            float(c[i, 1]),
            float(radii[i]),
            lay.material,
            label=f"p{i + 1}",
            z=float(z[i]),
            omega=spin,
        )
        for i in range(len(radii))
    )
    contact = dataclasses.replace(s.contact, overlap_start=None, detection="dynamic")
    if alpha_n is not None:
        contact = dataclasses.replace(contact, alpha_n=alpha_n, mu=0.0, pairs=())
    if alpha_n is not None and friction > 0.0:
        contact = dataclasses.replace(
            contact, mu=friction, tangential_law="mindlin", tangential_damping=SETTLE_TANGENTIAL_DAMPING
        )
    dt = settling_step(s, lay, g)
    t = dt * chunk_steps(lay.count)
    return Scenario(
        name=f"{s.name}-pouring",
        dimension=s.dimension,
        materials=s.materials,
        granules=granules,
        walls=pouring.container_walls(lay, s.dimension, g),
        load=Load(kind="none"),
        contact=contact,
        gravity=Gravity(g),
        time=TimeSettings(
            t_end=t,
            dt_initial=dt,
            dt_max=dt,
            dt_min=dt,
            output_interval=t / CHUNK_OUTPUTS,
            field_interval=t / CHUNK_OUTPUTS,
        ),
        solver=dataclasses.replace(Solver(), scheme="verlet", energy_tol=1e-2),
    )


def release_centres(s: Scenario, lay: PouredLayout) -> np.ndarray:
    """(count, dimension) the centres [m] the granules were released from (gravity's work
    is counted from there): `setup.pouring.dropped`'s."""
    g = pouring.pour_gravity(s, lay)
    return pouring.dropped(lay, s.dimension, g)[1]


def _end_state(ds) -> np.ndarray:
    """The state (ng, columns) at the chunk's last output time."""
    from granplate.results.dataset import STATE_VARIABLES, dimension_of
    from granplate.solver.state import STATE_COLUMNS

    cols = STATE_COLUMNS[dimension_of(ds)]
    return np.column_stack([np.asarray(ds[name].values[-1], float) for name in STATE_VARIABLES[cols]])


def _restarted(model, state: np.ndarray):
    """`model` starting from `state`: its contact lists found at those positions."""
    from granplate.model.arrays import granular_with_contacts
    from granplate.model.contacts import contact_lists

    s, d = model.scenario, model.config.dimension
    z = state[:, 2] if d == 3 else None
    pairs, wc = contact_lists(s.contact, s.walls, state[:, 0], state[:, 1], model.granular.radius, z)
    g = granular_with_contacts(model, model.granular, pairs, wc)
    return dataclasses.replace(model, initial_state=np.ascontiguousarray(state), granular=g)


def energies(model, state: np.ndarray, start: np.ndarray, g: tuple[float, ...]) -> tuple[float, float]:
    """(kinetic energy, work gravity did since `start`) [J] at `state`."""
    d = model.config.dimension
    m, inertia = model.granular.mass, model.granular.inertia
    v = state[:, 3:6] if d == 3 else state[:, 3:5]
    w = state[:, 6:9] if d == 3 else state[:, 5:6]
    ke = 0.5 * float(np.sum(m * np.sum(v**2, axis=1)) + np.sum(inertia * np.sum(w**2, axis=1)))
    work = float(np.sum(m * ((state[:, :d] - start[:, :d]) @ np.asarray(g))))
    return ke, work


class _Chunks:
    """The settling's chunks of free motion. Without a tangential law with history (Mindlin's)
    each chunk starts afresh from the last one's end state (`_restarted`: its contact lists
    found anew); with one, each chunk is a restart of the last one's result (`simulate`'s start_from),
    so that every contact's tangential history goes on. `quench()`: the next chunk starts
    with the velocities and spins zero."""

    def __init__(self, model, state: np.ndarray):
        self.model, self.state, self.ds, self.t = model, state, None, 0.0
        self.chained = model.config.history_friction

    def run(self) -> np.ndarray:
        """One more chunk; its end state."""
        from granplate.results.run import simulate

        s, self.t = self.model.scenario, self.t + self.model.config.t_end
        with warnings.catch_warnings():  # the settling's impacts may pass yield: the packing is what counts
            warnings.simplefilter("ignore")
            if self.chained and self.ds is not None:
                s = dataclasses.replace(s, time=dataclasses.replace(s.time, t_end=self.t))
                self.ds = simulate(s, progress=False, start_from=self.ds)
            else:
                self.ds = simulate(s, model=_restarted(self.model, self.state), progress=False)
        self.state = _end_state(self.ds)
        return self.state.copy()

    def quench(self) -> None:
        self.state[:, 3:] = 0.0  # velocities and spins (the 2D rotation angle, column 2, stays)
        if self.chained and self.ds is not None:
            y = np.array(self.ds["restart_st__y"].values)
            y[:, 3:] = 0.0
            self.ds["restart_st__y"].values = y


def _phase(model, state, start, g, lay, t_done: float, phase: str, progress: bool, quench: bool = False):
    """Chunks of `model` from `state` until KE <= settle_tolerance x the work of gravity,
    or settle_time is spent: (state, t_done, KE / work, settled). quench: a chunk that ends
    with KE <= QUENCH_BELOW x the work but above the tolerance hands the next one its
    state at rest (velocities and spins zero: granules rolling on a flat floor, which
    nothing in the contact laws stops, stop)."""
    chunk = model.config.t_end
    chunks = _Chunks(model, state)
    ratio = math.inf
    while t_done < lay.settle_time:
        state, t_done = chunks.run(), t_done + chunk
        ke, work = energies(model, state, start, g)
        ratio = ke / work if work > 0.0 else math.inf
        line = f"pouring ({phase}): t = {t_done:.4g} s, kinetic / gravity's work = {ratio:.3g} (to {lay.settle_tolerance:g})"
        log.info(line)
        if progress:
            print("granplate: " + line, flush=True)
        if ratio <= lay.settle_tolerance:
            return state, t_done, ratio, True
        if quench and ratio <= QUENCH_BELOW:
            chunks.quench()
    return state, t_done, ratio, False


#: The settling's phases: (name, contact damping: "settle" (layout.settle_damping) or None
#: (the scenario's own)). A first phase of softer contacts (E / 1000, steps 16 times
#: longer) was tried: the switch to the real stiffness released its larger overlaps'
#: energy (kinetic / gravity's work 0.18) and the real phase took longer than it saved.
PHASES: tuple[tuple[str, str | None], ...] = (("damped", "settle"), ("real contacts", None))
#: The one phase of a settling with Mindlin's friction (layout.settle_friction > 0): the
#: packing rests held by its tangential springs, which a fresh phase would start without.
FRICTIONAL_PHASES: tuple[tuple[str, str | None], ...] = (("damped, Mindlin friction", "settle"),)


def phases(lay: PouredLayout) -> tuple[tuple[str, str | None], ...]:
    """The settling's phases of `lay`: PHASES, or FRICTIONAL_PHASES with settle_friction."""
    return FRICTIONAL_PHASES if lay.settle_friction > 0.0 else PHASES


def settle(s: Scenario, lay: PouredLayout, progress: bool = False) -> dict[str, np.ndarray]:
    """The settled packing of `lay` in scenario `s` (arrays "centres", "radii", "overlap":
    the largest overlap at rest over the smaller radius), stored in the run store."""
    from granplate.model.arrays import build_model

    g = pouring.pour_gravity(s, lay)
    payload = pouring.store_payload(s, lay)
    with store.exclusive(pouring.STORE_KIND, payload, pouring.STORE_FORMAT):
        found = store.load_arrays(pouring.STORE_KIND, payload, pouring.STORE_FORMAT)
        if found is not None:
            return found
        if pouring.settles_ramped(s, lay):
            return _settle_ramped(s, lay, payload, progress)
        state = start = None
        t, ratio, ok = 0.0, math.inf, True
        for phase, alpha_n in phases(lay):
            if not ok:
                break
            damping = lay.settle_damping if alpha_n == "settle" else None
            model = build_model(loose_scenario(s, lay, damping, lay.settle_friction))
            if state is None:
                state, start = model.initial_state.copy(), model.initial_state.copy()
                start[:, : s.dimension] = release_centres(s, lay)
            state, t, ratio, ok = _phase(model, state, start, g, lay, t, phase, progress, quench=damping is not None)
        arrays = settled_arrays(model, state)
        if not ok:
            path = store.save_arrays("poured-partial", payload, pouring.STORE_FORMAT, arrays)
            raise ScenarioError(
                "layout.settle_time",
                lay.settle_time,
                f"the packing has not settled: kinetic energy / gravity's work = {ratio:.3g} after {t:.4g} s, "
                f"above settle_tolerance = {lay.settle_tolerance:g}; raise layout.settle_time, "
                f"layout.settle_damping or layout.settle_tolerance (the state reached is kept: {path})",
            )
        store.save_arrays(pouring.STORE_KIND, payload, pouring.STORE_FORMAT, arrays)
        return arrays


def _settle_ramped(s: Scenario, lay: PouredLayout, payload: dict, progress: bool) -> dict[str, np.ndarray]:
    """`results.ramped`'s settling (layout.settle_softening > 1), stored as `settle`'s."""
    from granplate.results import ramped

    p, out = ramped.settle_ramped(s, lay, progress)
    arrays = ramped.stored_arrays(p, out)
    if not out.settled:
        path = store.save_arrays("poured-partial", payload, pouring.STORE_FORMAT, arrays)
        raise ScenarioError(
            "layout.settle_time",
            lay.settle_time,
            f"the packing has not settled: kinetic energy / gravity's work = {out.kinetic:.3g}, residual force / "
            f"weight = {out.residual:.3g} after {out.t:.4g} s (to {lay.settle_tolerance:g} and "
            f"{lay.settle_residual:g}); raise layout.settle_time, layout.settle_tolerance or layout.settle_residual "
            f"(the state reached is kept: {path})",
        )
    store.save_arrays(pouring.STORE_KIND, payload, pouring.STORE_FORMAT, arrays)
    return arrays


def settled_arrays(model, state: np.ndarray) -> dict[str, np.ndarray]:
    """The store's arrays of a state: `packing_arrays` of its centres."""
    d = model.config.dimension
    return packing_arrays(state[:, :d], np.asarray(model.granular.radius, float), model.scenario.walls)


def packing_arrays(centres: np.ndarray, radii: np.ndarray, walls) -> dict[str, np.ndarray]:
    """The store's arrays of a packing: centres (n, d) [m], radii [m] and the largest
    overlap at rest of a pair or a granule against one of the Walls, over the smaller radius [-]."""
    from granplate.setup.pairs import close_pairs

    c, r = np.array(centres, float), np.asarray(radii, float)
    worst = 0.0
    pairs = close_pairs(c, 2.0 * float(r.max())) if len(r) else np.zeros((0, 2), np.int64)
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        ov = (r[i] + r[j] - np.linalg.norm(c[i] - c[j], axis=1)) / np.minimum(r[i], r[j])
        worst = max(worst, float(ov.max()))
    for w in walls:
        n = np.asarray(w.normal, float) / np.linalg.norm(w.normal)
        worst = max(worst, float(((c @ n + r - w.offset) / r).max()))
    return {"centres": c, "radii": r, "overlap": np.array(max(worst, 0.0))}


pouring.register_settler(settle)
