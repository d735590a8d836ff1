"""Reproduce the paper: run the six presets (the sensitivity checks, the cases with
yielding contacts, `granplate.paper.plastic`, and on request their 3D twins,
`granplate.paper.space`) in parallel, reuse results that are still current, then draw
every figure, both animations and the report. Also the CLI commands `reproduce`, `plot`,
`animate` and `export`.

    granplate reproduce --out results            # everything (a few minutes on 2 cores)
    granplate reproduce --out results --no-plastic  # without the yielding-contact twins
    granplate reproduce --out results --3d       # and the six cases in 3D
    granplate reproduce --out quick --t-end 1e-4 # shortened runs (a smoke test)
    granplate plot results/steel-r1.nc --figure A.1
    granplate plot results --figure 3            # a directory holding the presets' results
    granplate animate results/ptfe-r05.nc -o ptfe.mp4
    granplate export results/steel-r1.nc --vtk vtk/

A result DIR/NAME.nc is reused when its attributes `scenario_toml` and
`granplate_version` equal those a new run would write; anything else is run again.
Runs, figures and animations are tasks of the distributed engine (`granplate.results.engine`:
a local cluster of `--workers` processes, or an existing one by `--scheduler ADDRESS`);
each figure or animation starts as soon as the results it needs are there.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, NamedTuple

from granplate.errors import ScenarioError

#: Default output directory of `granplate reproduce`.
DEFAULT_OUT = "granplate-results"

#: The two runs animated (paper Appendix B: steel and PTFE intruders, R2 = 0.5 R1).
ANIMATED = ("steel-r05", "ptfe-r05")

#: Default number of animation frames.
DEFAULT_FRAMES = 120

CHECK_MODES = ("fast", "all", "none")

#: A 3D twin's cost per element against a 2D run's, for ordering the runs (a full-length
#: twin takes about twice as long as its preset, writing its result included).
SPACE_COST = 2.0


# --------------------------------------------------------------------------------------
# What to run
# --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Job:
    """One simulation: `scenario` written to `path`; kind "preset", "check", "plastic"
    (a preset's twin with yielding contacts, named "plastic/PRESET") or "space" (a
    preset's 3D twin, named "3d/PRESET")."""

    name: str
    scenario: object
    path: Path
    kind: str = "preset"


@dataclass
class RunRecord:
    """What happened to a job: status "reused", "ran" or "failed", wall time [s]."""

    name: str
    path: Path
    status: str
    seconds: float = 0.0
    message: str = ""
    kind: str = "preset"


@dataclass
class Outcome:
    """Everything `reproduce` made: run records, figure and animation files, report."""

    out_dir: Path
    runs: list[RunRecord] = field(default_factory=list)
    figures: dict[str, list[Path]] = field(default_factory=dict)
    animations: list[Path] = field(default_factory=list)
    report: list[Path] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return not self.problems


def shortened(scenario, t_end: float | None):
    """The scenario ending at t_end [s] (None: unchanged); output intervals shrink to fit."""
    from granplate.setup.io import with_changes

    if t_end is None:
        return scenario
    changes: dict[str, object] = {"time.t_end": float(t_end)}
    if scenario.time.output_interval > t_end:
        changes["time.output_interval"] = float(t_end)
        changes["time.field_interval"] = float(t_end)
    elif scenario.time.field_interval > t_end:
        changes["time.field_interval"] = scenario.time.output_interval
    return with_changes(scenario, changes)


def preset_scenario(name: str, t_end: float | None = None):
    """Preset `name`, shortened to t_end [s] when given."""
    from granplate.setup.presets import preset

    return shortened(preset(name), t_end)


#: The run store's kind of reproduce's results and their format version: the store's key
#: is the identity rule; the results themselves are the files DIR/NAME.nc.
RESULT_KIND = "reproduce"
RESULT_FORMAT = 1


def expected_identity(scenario) -> tuple[str, str]:
    """(scenario_toml, granplate_version) a run of `scenario` would write."""
    from granplate.version import __version__
    from granplate.setup.geometry import resolve
    from granplate.setup.io import dumps

    return dumps(resolve(scenario)), __version__


def stored_identity(path: Path) -> tuple[str, str] | None:
    """(scenario_toml, granplate_version) stored in a result file; None if unreadable."""
    import xarray as xr

    try:
        with xr.open_dataset(path) as ds:
            return str(ds.attrs.get("scenario_toml", "")), str(ds.attrs.get("granplate_version", ""))
    except Exception:  # noqa: BLE001 - missing, partial or foreign file: not current
        return None


def result_key(scenario_toml: str, version: str) -> str:
    """The run store's key of a result made from scenario_toml by granplate `version`."""
    from granplate import store

    return store.key(RESULT_KIND, {"scenario_toml": scenario_toml}, RESULT_FORMAT, version)


def is_current(path: str | Path, scenario) -> bool:
    """Whether the result at path was made from `scenario` by this granplate version."""
    path = Path(path)
    stored = stored_identity(path) if path.is_file() else None
    return stored is not None and result_key(*stored) == result_key(*expected_identity(scenario))


def plan(
    out_dir: Path, t_end: float | None = None, checks: str = "fast", plastic: bool = True, space: bool = False
) -> list[Job]:
    """The presets (DIR/NAME.nc), the sensitivity checks (DIR/checks/NAME.nc), with
    `plastic` the presets' twins with yielding contacts (Thornton's: DIR/plastic/NAME.nc,
    the law "johnson": DIR/johnson/NAME.nc; each job's kind is its folder) and with
    `space` their 3D twins (DIR/3d/NAME.nc) to run."""
    from granplate.paper import plastic as pl
    from granplate.paper import space as sp
    from granplate.paper.checks import CHECKS, check_scenario
    from granplate.setup.presets import preset_names

    if checks not in CHECK_MODES:
        raise ScenarioError("--checks", checks, f"allowed: {', '.join(CHECK_MODES)}")
    jobs = [Job(n, preset_scenario(n, t_end), out_dir / f"{n}.nc") for n in preset_names()]
    if checks != "none":
        for c in CHECKS:
            if c.slow and checks != "all":
                continue
            jobs.append(Job(c.name, check_scenario(c, t_end), out_dir / "checks" / f"{c.name}.nc", "check"))
    if plastic:
        for law, folder in pl.TWIN_LAWS.items():
            for n in pl.twin_presets():
                jobs.append(
                    Job(pl.twin_name(n, law), pl.twin_scenario(n, t_end, law), out_dir / folder / f"{n}.nc", folder)
                )
    if space:
        for n in sp.twin_presets():
            jobs.append(Job(sp.twin_name(n), sp.twin_scenario(n, t_end), out_dir / sp.TWIN_DIR / f"{n}.nc", "space"))
    return jobs


# --------------------------------------------------------------------------------------
# Work done in the worker processes (top-level functions, so they pickle)
# --------------------------------------------------------------------------------------
def run_job(job: Job) -> RunRecord:
    """Simulate one job and write its result atomically; a failed run keeps its partial
    result as NAME.partial.nc (never reused) and reports why."""
    from granplate import store
    from granplate.errors import SimulationError, YieldWarning
    from granplate.results.dataset import write
    from granplate.results.run import simulate

    t0 = time.perf_counter()
    job.path.parent.mkdir(parents=True, exist_ok=True)
    try:
        with warnings.catch_warnings():
            # the report says it for every run (the run table's p0 / 1.6 Y, the section
            # "Contacts that yield"), so the workers' logs need not
            warnings.simplefilter("ignore", YieldWarning)
            ds = simulate(job.scenario, progress=False)
    except SimulationError as err:
        if err.result is not None:
            write(err.result, job.path.with_name(job.path.stem + ".partial.nc"))
        return RunRecord(job.name, job.path, "failed", time.perf_counter() - t0, str(err), job.kind)
    store.atomic_write(job.path, lambda tmp: write(ds, tmp))
    return RunRecord(job.name, job.path, "ran", time.perf_counter() - t0, "", job.kind)


def make_figure(key: str, paths: list[Path], out_dir: Path) -> list[Path]:
    """Draw figure `key` (a paper figure, or one of the report's own: plots.EXTRA_FIGURES)
    from the result files (in the figure's preset order); PNG + PDF."""
    from granplate.paper import plots
    from granplate.results.dataset import read

    spec = plots.figure_spec(key)
    fig = spec.function(*[read(p) for p in paths])
    return plots.save_figure(fig, out_dir, plots.figure_stem(key))


def make_animation(path: Path, target: Path, frames: int | None) -> Path:
    """Animate the result at path into target (.mp4, or .gif as a fallback)."""
    from granplate.paper.animate import animate
    from granplate.results.dataset import read

    return animate(read(path), target, frames=frames)


def _products(figures: bool, animations: bool, plastic: bool = True, space: bool = False) -> list:
    """The figures (each with the runs it takes; with `plastic`, the yielding-contact
    figure too, with `space` the 3D twins') and the Appendix B animations."""
    from granplate.paper import plots
    from granplate.paper.runner import Product

    specs = plots.report_figures(plastic, space)
    out = [Product("figure", k, spec.presets) for k, spec in specs.items()] if figures else []
    return out + ([Product("animation", n, (n,)) for n in ANIMATED] if animations else [])


def reproduce(
    out_dir: str | Path = DEFAULT_OUT,
    *,
    t_end: float | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    client=None,
    force: bool = False,
    checks: str = "fast",
    plastic: bool = True,
    space: bool = False,
    figures: bool = True,
    animations: bool = True,
    frames: int | None = DEFAULT_FRAMES,
    quiet: bool = False,
) -> Outcome:
    """Run (or reuse) every preset and check, then write figures, animations and report.

    out_dir: results, figures, animations and report go here; t_end: shorten every run
    to this time [s]; workers: worker processes of the local cluster (default: the
    cores; at most one per task); scheduler: the address of an existing Dask cluster
    instead (its workers must see out_dir); client: an open Dask Client instead of
    either; force: run everything again; checks: "fast", "all" or "none" sensitivity
    runs; plastic: also run the presets with yielding contacts (the report's section
    "Contacts that yield", granplate.paper.plastic); space: also run the presets' 3D twins
    (the report's section "The paper in 3D", granplate.paper.space); figures: draw the
    figures; animations / frames: the Appendix B animations and their frame count; quiet:
    no progress.
    """
    from contextlib import nullcontext

    from granplate.paper.report import write_report
    from granplate.paper.runner import Driver, Progress
    from granplate.results import engine

    t_start = time.perf_counter()
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise ScenarioError("--workers", workers, "allowed: an integer >= 1")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    outcome = Outcome(out)
    available: dict[str, Path] = {}
    to_run: list[Job] = []
    for job in plan(out, t_end, checks, plastic, space):
        if not force and is_current(job.path, job.scenario):
            outcome.runs.append(RunRecord(job.name, job.path, "reused", 0.0, "", job.kind))
            available[job.name] = job.path
        else:
            to_run.append(job)
    products = _products(figures, animations, plastic, space)
    progress = Progress(len(to_run) + len(products), quiet)
    for rec in outcome.runs:
        progress.note(f"reused {rec.name} ({rec.path})")
    n_workers = min(workers or engine.available_cores(), max(1, len(to_run) + len(products)))
    try:
        if to_run or products:
            own = client is None
            if own:
                progress.note(
                    f"connecting to the cluster at {scheduler}"
                    if scheduler
                    else f"starting {n_workers} local Dask workers"
                )
            with engine.dask_client(n_workers, scheduler) if own else nullcontext(client) as c:
                if to_run:
                    progress.note(
                        "warming the workers up (compiling the kernels where they are not cached "
                        "yet, building the plates)"
                    )
                    seconds = engine.warm_workers(c, warm_up_scenarios(to_run))
                    progress.note(f"workers warm after {seconds:.1f} s; running {len(to_run)} runs")
                Driver(c, outcome, products, available, progress, frames).run(to_run)
    finally:
        progress.close()
    if not figures:
        outcome.figures.update(_earlier_figures(out / "figures", available, plastic, space))
    if not animations:
        outcome.animations += _earlier_animations(out / "animations", available)
    outcome.seconds = time.perf_counter() - t_start
    outcome.report = write_report(out, outcome)
    outcome.seconds = time.perf_counter() - t_start
    return outcome


def _up_to_date(target: Path, inputs: list[Path]) -> bool:
    """Whether target exists and is newer than every input file."""
    return target.is_file() and all(target.stat().st_mtime >= p.stat().st_mtime for p in inputs)


def _earlier_figures(
    fig_dir: Path, available: dict[str, Path], plastic: bool = True, space: bool = False
) -> dict[str, list[Path]]:
    """Figures drawn by an earlier reproduce from the same result files (for the report)."""
    from granplate.paper import plots

    found = {}
    specs = plots.report_figures(plastic, space)
    for key, spec in specs.items():
        files = [fig_dir / f"{plots.figure_stem(key)}{ext}" for ext in (".png", ".pdf")]
        if all(n in available for n in spec.presets) and all(
            _up_to_date(f, [available[n] for n in spec.presets]) for f in files
        ):
            found[key] = files
    return found


def _earlier_animations(anim_dir: Path, available: dict[str, Path]) -> list[Path]:
    """Animations made by an earlier reproduce from the same result files."""
    found = []
    for name in ANIMATED:
        for ext in (".mp4", ".gif"):
            f = anim_dir / f"{name}{ext}"
            if name in available and _up_to_date(f, [available[name]]):
                found.append(f)
                break
    return found


class JobCost(NamedTuple):
    """How a dimension's jobs are ordered and warmed up for: `factor`, its cost per element
    against the plane's; `elements(plate)`, the elements of its [plate]; `granules_apart`:
    whether a body with granules and one without warm up apart (their kernels and bodies
    differ)."""

    factor: float
    elements: Callable[[Any], int]
    granules_apart: bool


#: the jobs' costs by the dimension's name (model.dimension): the plane's plate of nx x ny
#: elements; space's solid of its box's elements (1 for a mesh file), each at SPACE_COST
JOB_COSTS: dict[str, JobCost] = {
    "plane": JobCost(1.0, lambda plate: plate.nx * plate.ny, False),
    "space": JobCost(SPACE_COST, lambda plate: math.prod(plate.elements) if plate.elements else 1, True),
}


def job_cost(s) -> JobCost:
    """The `JobCost` of scenario `s`'s dimension."""
    from granplate.model.dimension import of_number

    return JOB_COSTS[of_number(getattr(s, "dimension", 2)).name]


def expected_cost(job: Job) -> float:
    """A rough cost of a job for ordering: elements x simulated time, steel > PTFE; a 3D
    twin (velocity Verlet at a fixed step) by SPACE_COST per element (`JOB_COSTS`)."""
    s = job.scenario
    plate = getattr(s, "plate", None)
    cost = job_cost(s)
    elements = cost.factor * (cost.elements(plate) if plate is not None else 1)
    stiff = 2.0 if (getattr(s, "layout", None) is not None and s.layout.intruder_material == "steel") else 1.0
    return elements * s.time.t_end * stiff


def warm_up_scenarios(jobs: list[Job]) -> list[str]:
    """TOML texts to warm the workers up on: the cheapest job of each coupling scheme
    (each scheme has its own compiled kernels); in space, of each scheme with granules
    and without (the bare slab's load and the spheres' contacts are kernels of their own,
    and the two build different bodies)."""
    from granplate.setup.io import dumps

    first: dict[tuple, Job] = {}
    for job in sorted(jobs, key=expected_cost):
        s = job.scenario
        apart = job_cost(s).granules_apart
        key: tuple = (s.solver.scheme,) + ((s.dimension, s.layout is not None or bool(s.granules)) if apart else ())
        first.setdefault(key, job)
    return [dumps(j.scenario) for j in first.values()]


# --------------------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------------------
def _existing(path: str, what: str = "file") -> Path:
    p = Path(path)
    if not p.exists():
        raise ScenarioError(what, path, "no such file or directory")
    return p


def _read(path: Path):
    from granplate.results.dataset import read

    try:
        return read(path)
    except Exception as exc:  # noqa: BLE001 - not a result file: a user's mistake
        raise ScenarioError("file", str(path), f"not a granplate result ({exc.__class__.__name__}: {exc})") from None


def figure_inputs(key: str, inputs: list[str]) -> list[Path]:
    """The result files figure `key` takes, in its preset order, from files or a directory.

    A directory is searched for PRESET.nc; files are matched to the figure's presets by
    their scenario name, or else taken in the order given (when the count is right).
    """
    from granplate.paper import plots

    need = plots.FIGURES[key].presets
    files: list[Path] = []
    for item in inputs:
        p = _existing(item)
        if p.is_dir():
            for name in need:
                f = p / f"{name}.nc"
                if f.is_file():
                    files.append(f)
        else:
            files.append(p)
    by_name: dict[str, Path] = {}
    for f in files:
        ident = stored_identity(f)
        if ident is None:
            raise ScenarioError("file", str(f), "not a readable granplate result (netCDF)")
        import xarray as xr

        with xr.open_dataset(f) as ds:
            by_name.setdefault(str(ds.attrs.get("scenario_name", "")), f)
    if all(n in by_name for n in need):
        return [by_name[n] for n in need]
    if len(files) == len(need):
        return files
    raise ScenarioError(
        "--figure",
        key,
        f"figure {key} takes {len(need)} result(s): {', '.join(need)} (files named by their scenario, "
        f"in this order, or a directory holding NAME.nc); got {len(files)}",
    )


def _cmd_reproduce(args) -> int:
    outcome = reproduce(
        args.out,
        t_end=args.t_end,
        workers=args.workers,
        scheduler=args.scheduler,
        force=args.force,
        checks=args.checks,
        plastic=not args.no_plastic,
        space=args.space,
        figures=not args.no_figures,
        animations=not args.no_animations,
        frames=args.frames,
        quiet=args.quiet,
    )
    reused = sum(r.status == "reused" for r in outcome.runs)
    ran = sum(r.status == "ran" for r in outcome.runs)
    print(
        f"runs: {ran} ran, {reused} reused; figures: {len(outcome.figures)}; "
        f"animations: {len(outcome.animations)}; {outcome.seconds:.1f} s"
    )
    for p in outcome.report:
        print(f"report: {p}")
    for line in outcome.problems:
        print(f"granplate: {line}", file=sys.stderr)
    return 0 if outcome.ok else 3


def _cmd_plot(args) -> int:
    from granplate.paper import plots

    if args.figure is None:  # the generic figures of any run
        from granplate.figures.cli import plot_results

        return plot_results(args.results, args.out)
    if args.figure == "spectrum":  # the spectra of any run's recorded signals
        from granplate.figures.cli import result_paths
        from granplate.figures.spectrum import plot_spectra

        return plot_spectra(result_paths(args.results), args.signal or [], args.reference, args.out)
    names = list(plots.FIGURES) if args.figure.lower() == "all" else [args.figure]
    for name in names:
        try:
            key = plots.figure_key(name)
        except KeyError:
            raise ScenarioError(
                "--figure", name, "allowed: " + ", ".join(plots.FIGURES) + " (or 'all'; 'fig3', 'A.1' also work)"
            ) from None
        paths = figure_inputs(key, args.results)
        plots.check_inputs(key, [_read(p) for p in paths])  # clear errors for unfit files
        for written in make_figure(key, paths, Path(args.out)):
            print(f"written {written}")
    return 0


def _cmd_animate(args) -> int:
    from granplate.paper.animate import animate, animation_of

    ds = _read(_existing(args.result))
    target = Path(args.output) if args.output else Path(f"{ds.attrs.get('scenario_name', 'result')}.mp4")
    if target.suffix.lower() not in (".mp4", ".gif"):
        raise ScenarioError("-o", str(target), "allowed: a .mp4 or .gif file name")
    if not animation_of(ds).ready(ds):  # (in space: every output time)
        raise ScenarioError("result", args.result, "has no plate-field snapshots to animate")
    written = animate(ds, target, frames=args.frames, fps=args.fps, magnify=args.magnify, progress=not args.quiet)
    print(f"written {written}")
    return 0


def _cmd_export(args) -> int:
    from granplate.results.export import export_vtk, vtk_kind

    ds = _read(_existing(args.result))
    kind = vtk_kind(ds)
    if not kind.ready(ds):
        raise ScenarioError("result", args.result, "has no plate to export")
    print(kind.written(ds, export_vtk(ds, args.vtk)))
    return 0


def _positive_int(text: str) -> int:
    v = int(text)
    if v < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: must be an integer >= 1")
    return v


def register(subparsers) -> None:
    """Add the `reproduce`, `plot`, `animate` and `export` commands."""
    register_reproduce(subparsers)
    register_plot(subparsers)
    register_animate(subparsers)
    register_export(subparsers)


def register_reproduce(subparsers) -> None:
    """`granplate reproduce`: the paper's cases, figures, animations and report."""
    r = subparsers.add_parser(
        "reproduce",
        help="run the paper's six cases (and again with yielding "
        "contacts; with --3d in 3D too), draw every figure, both animations and the "
        "report (reusing unchanged results)",
    )
    r.add_argument("--out", default=DEFAULT_OUT, help=f"output directory (default {DEFAULT_OUT})")
    r.add_argument("--t-end", type=float, default=None, help="shorten every run to this time [s]")
    r.add_argument(
        "--workers",
        "--jobs",
        dest="workers",
        type=_positive_int,
        default=None,
        help="worker processes of the local Dask cluster (default: the number of cores)",
    )
    r.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        default=None,
        help="run on an existing Dask cluster (e.g. tcp://host:8786) instead; its "
        "workers must see the output directory",
    )
    r.add_argument("--force", action="store_true", help="run everything again, even unchanged results")
    r.add_argument(
        "--checks",
        choices=CHECK_MODES,
        default="fast",
        help="sensitivity runs for the report's discussion: fast (default, ~1 min on "
        "2 cores), all (adds finer meshes, ~3 min), none",
    )
    r.add_argument(
        "--no-plastic",
        action="store_true",
        help="leave out the cases rerun with yielding contacts (the report's section "
        "'Contacts that yield'; 5 more runs, about 10 s on 2 cores)",
    )
    r.add_argument(
        "--3d",
        dest="space",
        action="store_true",
        help="also run the six cases' 3D twins (the presets 3d-NAME, into DIR/3d/NAME.nc) and "
        "set 2D and 3D side by side in the report's section 'The paper in 3D' and the "
        "figure fig-3d",
    )
    r.add_argument("--frames", type=_positive_int, default=DEFAULT_FRAMES, help="animation frames (at most)")
    r.add_argument("--no-figures", action="store_true", help="skip the figures (runs and report only)")
    r.add_argument("--no-animations", action="store_true", help="skip the animations")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress output")
    r.set_defaults(func=_cmd_reproduce)


def register_plot(subparsers) -> None:
    """`granplate plot`: the figures of any run, or one of the paper's."""
    p = subparsers.add_parser("plot", help="draw the figures of any run, or one paper figure (--figure)")
    p.add_argument("results", nargs="+", help="result .nc file(s), or a directory holding PRESET.nc files")
    p.add_argument(
        "--figure",
        default=None,
        help="a paper figure: 3, 4, 5, 6, 7, 8, A1 (or 'all'); 'spectrum': the amplitude spectra of "
        "any result's recorded signals (with --signal, --reference), drawn and written as CSV; without "
        "it: energies, contact forces, stress and strain (a 3D body's: body stress, body contact forces), "
        "granule speeds of each result",
    )
    p.add_argument(
        "--signal",
        action="append",
        default=None,
        metavar="VARIABLE:LABEL",
        help="--figure spectrum: a signal, e.g. wall_force:bottom, drive_displacement:piston or "
        "sensor_force:NAME (repeatable, on one time axis; default every wall and drive signal, or "
        "every sensor of a run with no walls or drives)",
    )
    p.add_argument(
        "--reference",
        default=None,
        metavar="VARIABLE:LABEL",
        help="--figure spectrum: the input signal; adds each signal's transmission abs(X / X_ref)",
    )
    p.add_argument("--out", default=".", help="directory for the PNG and PDF (default .)")
    p.set_defaults(func=_cmd_plot)


def register_animate(subparsers) -> None:
    """`granplate animate`: a result's animation."""
    a = subparsers.add_parser(
        "animate",
        help="animate a result: in the plane the granules and the deformed "
        "plate (x125); in space the three projections of granplate show, "
        "the body deformed and coloured by stress",
    )
    a.add_argument("result", help="a result .nc file")
    a.add_argument("-o", "--output", help="output .mp4 (or .gif) (default SCENARIO.mp4)")
    a.add_argument("--frames", type=_positive_int, default=DEFAULT_FRAMES, help="at most this many frames")
    a.add_argument("--fps", type=_positive_int, default=15, help="frames per second")
    a.add_argument(
        "--magnify",
        type=float,
        default=125.0,
        help="the plate's displacement magnification "
        "(in the plane; in space an elastic body is magnified as `granplate show` does)",
    )
    a.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    a.set_defaults(func=_cmd_animate)


def register_export(subparsers) -> None:
    """`granplate export`: a result as a ParaView time series."""
    e = subparsers.add_parser("export", help="write a ParaView time series (VTK, .pvd) of a result")
    e.add_argument("result", help="a result .nc file")
    e.add_argument("--vtk", required=True, help="output directory for the .vtu and .pvd files")
    e.set_defaults(func=_cmd_export)
