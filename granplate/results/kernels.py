"""Compile every scheme's kernels once, in both dimensions (`granplate compile`, and the
first run that needs any).

numba compiles a time loop per coupling scheme and dimension (`loop.advance` specialised
on the scheme's scratch and the granules' arrays), plus what the model build and the
result need. Each `KernelSet` is one such pair with the short runs that compile it all;
`compile_kernels` runs those not yet in numba's on-disk cache (`missing`), one progress
line each with the measured estimate (solver/compile_seconds.json), corrected as it goes
by how this machine compares with the one measured. `measure` writes that file.
"""

from __future__ import annotations

import json
import logging
import os
import platform
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from granplate.setup.scenario import Scenario
from granplate.solver.compiling import (
    compile_clock,
    compile_seconds,
    compiled_loops,
    describe_seconds,
    machine_slowdown,
    set_name,
)

log = logging.getLogger(__name__)

#: Simulated time of a kernel set's short runs [s]: one step or a few compile everything.
SHORT_T_END = 1e-7
#: Environment variable: "all" (default), the command line's first run that needs a kernel
#: compiles every set; "own", a run compiles only its own kernels.
COMPILE_ENV = "GRANPLATE_COMPILE"


def compile_all_wanted() -> bool:
    """Whether the command line's first run compiles every kernel set ($GRANPLATE_COMPILE is
    not "own")."""
    return os.environ.get(COMPILE_ENV, "all").strip().lower() != "own"


def _with_sensor(s: Scenario) -> Scenario:
    """`s` with a force sensor in its first granule (docs/model.md section 3.15), so that
    its short run compiles the sensors' read too."""
    from dataclasses import replace

    from granplate.setup.drive_checks import granule_labels
    from granplate.setup.geometry import resolve
    from granplate.setup.scenario import Sensor

    return replace(s, sensors=(Sensor(granule=granule_labels(resolve(s))[0]),))


def _plane_granules(scheme: str) -> list[Scenario]:
    from granplate.setup.io import with_changes
    from granplate.setup.presets import preset

    if scheme == "verlet":  # the granules alone
        return [
            _with_sensor(
                with_changes(
                    preset("steel-r1"), {"plate": None, "solver.scheme": "verlet", "solver.granular_friction": "split"}
                )
            )
        ]
    return [_with_sensor(with_changes(preset("steel-r1"), {"solver.scheme": scheme}))]


#: A small fcc packing in space, the granules alone (a box of walls).
_FCC = """
name = "compile-fcc"
dimension = 3
[layout]
kind = "fcc"
cells = [1, 1, 1]
radius = 0.005
material = "steel"
[load]
kind = "force"
force = 50.0
duration = 1e-5
[solver]
scheme = "{scheme}"
granular_friction = "split"
"""


def _space_granules(scheme: str) -> list[Scenario]:
    from granplate.setup.io import loads, with_changes
    from granplate.setup.presets import preset

    alone = _with_sensor(loads(_FCC.format(scheme=scheme)))  # the granules alone, in a box, a sensor in one
    if scheme == "paper":  # (no elastic solid under the paper's scheme)
        return [alone]
    on_plate = with_changes(preset("3d-steel-r1"), {"plate.elements": [2, 8, 1]})
    if scheme == "implicit":  # an elastic solid makes the implicit scheme's loop one of its own
        return [alone, with_changes(on_plate, {"solver.scheme": "implicit"})]
    bare = with_changes(preset("3d-bare-plate"), {"plate.elements": [2, 8, 1]})
    return [on_plate, bare, alone]  # the granules alone in space run the same loop, its body empty


@dataclass(frozen=True)
class KernelSet:
    """The kernels of one coupling scheme in one dimension, and the short runs that
    compile them (scenarios: a function, so that nothing is built before it is needed)."""

    scheme: str
    dimension: int
    scenarios: Callable[[], list[Scenario]]
    solid: bool = False  # its runs compile the loop with an elastic solid too

    @property
    def loops(self) -> set[tuple[str, int, bool]]:
        """The (scheme, dimension, solid) keys of the loops its runs compile."""
        return {(self.scheme, self.dimension, False)} | ({(self.scheme, self.dimension, True)} if self.solid else set())

    @property
    def name(self) -> str:
        return set_name(self.scheme, self.dimension)

    @property
    def what(self) -> str:
        from granplate.model.dimension import of_number

        return f"the {self.scheme} scheme {of_number(self.dimension).where}"


#: Every kernel set, in the order measured (later sets reuse the callees of earlier ones).
KERNEL_SETS: tuple[KernelSet, ...] = (
    KernelSet("implicit", 2, lambda: _plane_granules("implicit")),
    KernelSet("paper", 2, lambda: _plane_granules("paper")),
    KernelSet("verlet", 2, lambda: _plane_granules("verlet")),
    KernelSet("implicit", 3, lambda: _space_granules("implicit"), solid=True),
    KernelSet("paper", 3, lambda: _space_granules("paper")),
    KernelSet("verlet", 3, lambda: _space_granules("verlet"), solid=True),
)


def missing(sets: tuple[KernelSet, ...] = KERNEL_SETS, compiled: set | None = None) -> list[KernelSet]:
    """The kernel sets some of whose time loops numba's cache does not hold (compiled: the
    (scheme, dimension, solid) keys it holds, default `compiled_loops()`): a cache that
    holds a scheme's loop for granules alone but not with a solid misses the set."""
    have = compiled_loops() if compiled is None else compiled
    return [k for k in sets if not k.loops <= set(have)]


def needs_compiling(scenario: Scenario, compiled: set | None = None) -> bool:
    """Whether a run of `scenario` would compile its time loop first."""
    from granplate.setup.scenario import Solid

    have = compiled_loops() if compiled is None else compiled
    key = (scenario.solver.scheme, getattr(scenario, "dimension", 2), isinstance(scenario.plate, Solid))
    return key not in have


def estimate(sets: list[KernelSet]) -> float:
    """Measured seconds to compile `sets` on a cold cache (solver/compile_seconds.json)."""
    return sum(compile_seconds(k.scheme, k.dimension) for k in sets)


def compile_set(kernels: KernelSet) -> tuple[float, float]:
    """Run the set's short runs (compiling what they need); the seconds numba compiled, and
    the process's CPU seconds meanwhile (compiling is single-threaded: on an idle machine
    the two agree, on a shared one the CPU seconds are what the compile itself costs)."""
    from granplate.results.run import simulate

    driver_log = logging.getLogger("granplate.solver.driver")
    level = driver_log.level
    driver_log.setLevel(logging.WARNING)  # this set's own line says what compiles
    cpu = time.process_time()
    try:
        with compile_clock() as clock:
            for s in kernels.scenarios():
                simulate(s, t_end=min(s.time.t_end, SHORT_T_END), progress=False)
    finally:
        driver_log.setLevel(level)
    return clock.seconds, time.process_time() - cpu


def compile_kernels(
    sets: list[KernelSet] | None = None, note: Callable[[str], None] | None = None, cpu: dict | None = None
) -> dict[str, float]:
    """Compile the kernel sets not yet cached (default: every missing one), one line each
    through `note` (default: the "granplate" logger at INFO) with the measured estimate,
    scaled after the first set by how this machine's compile times compare with the
    measured ones. {set name: seconds compiled}; cpu, when given, gets the CPU seconds."""
    todo = missing() if sets is None else list(sets)
    say = note or log.info
    done: dict[str, float] = {}
    if not todo:
        return done
    scale = machine_slowdown()
    total = scale * estimate(todo)
    busy = f", this machine busy {scale:.1f}x" if scale > 1.2 else ""
    say(
        f"compiling every scheme's kernels once, in the plane and in space: {len(todo)} sets, about "
        f"{describe_seconds(total)} ({describe_seconds(estimate(todo))} of CPU measured on a cold cache{busy}; "
        f"`granplate compile` does this ahead; cached afterwards)"
    )
    spent = expected = 0.0
    for i, k in enumerate(todo, 1):
        left = scale * estimate(todo[i - 1 :])
        say(
            f"compiling {i}/{len(todo)}: {k.what} (about {describe_seconds(scale * estimate([k]))}; "
            f"{describe_seconds(left)} left in all) ..."
        )
        try:
            done[k.name], cpu_s = compile_set(k)
        except Exception as err:  # noqa: BLE001 - a set that cannot compile must not stop the run asked for
            say(f"could not compile {k.what} ({type(err).__name__}: {err}); its first run compiles what it needs")
            continue
        if cpu is not None:
            cpu[k.name] = cpu_s
        spent += done[k.name]
        expected += estimate([k])
        scale = spent / expected if expected > 0 else 1.0
    say(f"compiled {len(todo)} kernel sets in {describe_seconds(spent)} (estimated {describe_seconds(total)})")
    return done


def measure(path: Path, note: Callable[[str], None] | None = None) -> dict:
    """Compile every kernel set in order and write the seconds each took to `path` (JSON,
    the format of solver/compile_seconds.json). Meant for an empty numba cache
    (NUMBA_CACHE_DIR pointing at a new folder): a set found cached measures its load only."""
    import numba

    t0 = time.perf_counter()
    cpu: dict[str, float] = {}
    wall = compile_kernels(list(KERNEL_SETS), note, cpu=cpu)
    data = {
        "about": "CPU seconds each kernel set takes to compile on a cold numba cache (compiling is "
        "single-threaded: the wall time on an idle core), the sets compiled in this order in "
        "one process (later sets reuse earlier ones' callees); wall_seconds: the wall time "
        "numba compiled, which a shared machine inflates; written by `granplate compile --measure`",
        "machine": f"{platform.machine()}, {platform.processor() or platform.system()}, "
        f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the end",
        "numba": numba.__version__,
        "order": [k.name for k in KERNEL_SETS],
        "seconds": {k: round(v, 1) for k, v in cpu.items()},
        "wall_seconds": {k: round(v, 1) for k, v in wall.items()},
        "total_wall_s": round(time.perf_counter() - t0, 1),
    }
    Path(path).write_text(json.dumps(data, indent=2) + "\n")
    return data
