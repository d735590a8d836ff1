"""`granplate optimize`: multi-objective search of a study's parameters with Optuna, the
trials evaluated on Dask (docs/studies.md).

The study file is a sweep's (base, [set], [parameters]) with an [objectives] table:

    [parameters]
    "layout.R2_ratio" = {range = [0.5, 1.0]}        # continuous (log = true: log scale;
    "contact.mu" = [0.05, 0.099, 0.2]               #   integer ends: an integer); a list:
    [objectives]                                    #   categorical
    "ep_max_fraction" = "minimize"
    "granular_mass" = "minimize"
    [constraints]                                   # optional: bounds on metrics
    "granular_mass" = {max = 0.02}

Optuna's ask/tell interface drives the search: the driver asks for trials, one per free
worker, runs each as a design on the cluster and tells its metrics back. The Optuna study
lives in DIR/optuna.db (SQLite), so a rerun continues it up to --trials; each design also
gets its record in DIR/designs (a trial whose design was already computed, here or by a
sweep into the same folder, is not computed again). Trials cut short by an interruption
are marked failed on the next run and their parameters queued again. Constraints
(granplate.study.constraints) are told to Optuna with the trial: `Trial.set_constraint`
from Optuna 5 on, the sampler's `constraints_func` before (deprecated in 5); an
infeasible trial is complete but marked infeasible, and the Pareto front is that of the
feasible trials.
"""

from __future__ import annotations

import csv
import math
import numbers
import os
import sys
import time
from contextlib import nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import granplate as gp
from granplate.errors import ScenarioError
from granplate.study import design as D
from granplate.study.constraints import Bound, is_feasible, parse_constraints, violations
from granplate.study.spec import Value, base_and_fixed, check_document, range_values

#: Top-level keys of an optimisation's study file ([zip] and sampled parameters are a sweep's).
OPTIMIZE_KEYS: tuple[str, ...] = ("base", "set", "parameters", "objectives", "constraints", "report")
#: Directions of an objective.
DIRECTIONS: tuple[str, ...] = ("minimize", "maximize")
#: Files in the output folder.
DATABASE = "optuna.db"
TRIALS_CSV = "trials.csv"
PARETO_CSV = "pareto.csv"
PARETO_PNG = "pareto.png"
#: Name of the Optuna study inside the database.
STUDY_NAME = "granplate"
#: Least seconds between two writes of trials.csv while the search runs (for
#: `granplate study report --watch`).
PROGRESS_EVERY_S = 10.0


@dataclass(frozen=True)
class Optimization:
    """What to search: the base, fixed changes, the search space {dotted path: Optuna
    distribution}, the objectives {metric: "minimize" | "maximize"}, in file order, and
    the constraints (bounds on metrics; none: every completed trial is feasible)."""

    base_name: str
    raw_base: Any
    fixed: dict[str, Value]
    space: dict[str, Any]
    objectives: dict[str, str]
    constraints: tuple[Bound, ...] = field(default=())

    def scenario(self, params: dict[str, Value]):
        """The scenario of a trial's parameters (shape-checked, not validated)."""
        return gp.with_changes(self.raw_base, {**self.fixed, **params})


@dataclass
class OptimizeReport:
    """Trials finished before this run, computed now, told from existing records, failed;
    the trials computed now whose run warned (n_warned) and the first of their warnings."""

    n_trials: int
    n_before: int
    n_computed: int = 0
    n_reused: int = 0
    n_failed: int = 0
    elapsed_s: float = 0.0
    warm_up_s: float = 0.0
    n_warned: int = 0
    first_warning: str = ""
    out: Path = Path(".")


def distribution(field: str, spec: Any):
    """The Optuna distribution of a parameter: a list -> categorical; {range = [a, b]}
    -> continuous (log = true: log-uniform; integer ends: integers)."""
    from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution

    where = f"parameters.{field}"
    if isinstance(spec, list):
        if not spec:
            raise ScenarioError(where, spec, "empty list: give at least one value")
        for k, v in enumerate(spec):
            if not isinstance(v, (numbers.Real, str, bool)):
                raise ScenarioError(f"{where}[{k}]", v, "expected a number, a string or true/false")
        return CategoricalDistribution(spec)
    if not isinstance(spec, dict) or "range" not in spec:
        raise ScenarioError(
            where, spec, "to optimize: a list of values (categorical) or {range = [a, b], log = false} (continuous)"
        )
    if "num" in spec:
        raise ScenarioError(
            f"{where}.num", spec["num"], "not used by optimize: a range is searched continuously (remove num)"
        )
    ends = range_values(where, {**spec, "num": 2})  # checks the range and log
    log = bool(spec.get("log", False))
    if all(isinstance(e, int) and not isinstance(e, bool) for e in spec["range"]):
        return IntDistribution(int(ends[0]), int(ends[1]), log=log)
    if not ends[0] < ends[1]:
        raise ScenarioError(f"{where}.range", spec["range"], "expected a < b")
    return FloatDistribution(float(ends[0]), float(ends[1]), log=log)


def parse_optimization(doc: dict, folder: str | os.PathLike = ".") -> Optimization:
    """An Optimization from a study file's table; every mistake named before anything runs."""
    check_document(doc, OPTIMIZE_KEYS)
    raw, fixed = base_and_fixed(doc, folder)
    parameters = doc.get("parameters", {})
    if not isinstance(parameters, dict) or not parameters:
        raise ScenarioError(
            "parameters", parameters, "expected a table of dotted path = list or {range = [a, b]}, at least one"
        )
    space = {f: distribution(f, spec) for f, spec in parameters.items()}
    for f in space:
        if f in fixed:
            raise ScenarioError(f, "set and varied", "a field is either fixed in [set] or varied")
    objectives = doc.get("objectives")
    units = D.metric_units()
    if not isinstance(objectives, dict) or not objectives:
        raise ScenarioError(
            "objectives",
            objectives,
            'expected a table of metric = "minimize" | "maximize", at least one; metrics: ' + ", ".join(units),
        )
    for name, direction in objectives.items():
        if name not in units:
            raise ScenarioError(f"objectives.{name}", direction, "unknown metric; allowed: " + ", ".join(units))
        if direction not in DIRECTIONS:
            raise ScenarioError(f"objectives.{name}", direction, "allowed: " + ", ".join(DIRECTIONS))
    constraints = parse_constraints(doc.get("constraints"), units)
    from granplate.study.targets import parse_report_table

    parse_report_table(doc.get("report"), tuple(space))
    opt = Optimization(str(doc["base"]), raw, fixed, space, dict(objectives), constraints)
    for f, dist in space.items():  # an unknown path or a value of the wrong type, now
        values = dist.choices if hasattr(dist, "choices") else (dist.low, dist.high)
        for v in values:
            try:
                opt.scenario({f: v})
            except ScenarioError as err:
                raise ScenarioError(err.field, err.value, f"{err.allowed} [parameters.{f}]") from None
    return opt


def load_optimization(path: str | os.PathLike, changes: dict[str, Value] | None = None) -> Optimization:
    """The Optimization of a TOML file, with `changes` added to its [set] table."""
    from granplate.study.spec import read_document, with_settings

    return parse_optimization(with_settings(read_document(path), changes), Path(path).parent)


# ------------------------------------------------------------------------- the search


def objective_values(opt: Optimization, record: dict) -> list[float] | None:
    """The objectives of a design's record, or None when it failed or one is missing."""
    if record["status"] != "ok" or not record.get("summary"):
        return None
    values = [record["summary"].get(name) for name in opt.objectives]
    if any(v is None or not math.isfinite(v) for v in values):
        return None
    return [float(v) for v in values]


def stored_constraints(trial) -> list[float]:
    """The sampler's constraints_func: the constraint values `tell` stored on the trial."""
    return list(trial.user_attrs.get("constraints", []))


def trial_constraints() -> bool:
    """Whether Optuna takes constraints from the trial (Trial.set_constraint, Optuna >= 5)
    rather than from the sampler's constraints_func."""
    from optuna.trial import Trial

    return hasattr(Trial, "set_constraint")


def constraint_texts(opt: Optimization) -> list[str]:
    """The constraints as text with units ('granular_mass <= 0.02 kg')."""
    units = D.metric_units()
    return [b.text(units.get(b.metric, "")) for b in opt.constraints]


def open_study(opt: Optimization, out: Path, seed: int):
    """The Optuna study in out/optuna.db (created, or loaded to continue it)."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    by_sampler = bool(opt.constraints) and not trial_constraints()
    sampler = optuna.samplers.TPESampler(seed=seed, constraints_func=stored_constraints if by_sampler else None)
    study = optuna.create_study(
        storage=f"sqlite:///{out / DATABASE}",
        study_name=STUDY_NAME,
        directions=list(opt.objectives.values()),
        load_if_exists=True,
        sampler=sampler,
    )
    for name, value in (("objectives", list(opt.objectives)), ("constraints", constraint_texts(opt))):
        stored = study.user_attrs.get(name)
        if stored is None:
            study.set_user_attr(name, value)
        elif stored != value:
            raise ScenarioError(
                name,
                value,
                f"{out / DATABASE} was made with {name} {stored}: use another --out folder for other {name}",
            )
    return study


def requeue_interrupted(study) -> int:
    """Fail the trials a killed run left running and queue their parameters again."""
    from optuna.trial import TrialState

    stale = study.get_trials(deepcopy=False, states=(TrialState.RUNNING,))
    for t in stale:
        study.tell(t.number, state=TrialState.FAIL, skip_if_finished=True)
        study.enqueue_trial(t.params, skip_if_exists=False)
    return len(stale)


def finished(study) -> int:
    """Trials that count towards --trials: completed or failed with their design's status
    (not those an interruption cut short, whose parameters run again)."""
    from optuna.trial import TrialState

    return sum(
        1
        for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE, TrialState.FAIL))
        if "status" in t.user_attrs
    )


def tell(study, opt: Optimization, trial, record: dict) -> bool:
    """Tell a trial its design's objectives (or that it failed); True when it completed."""
    from optuna.trial import TrialState

    trial.set_user_attr("key", record["key"])
    trial.set_user_attr("status", record["status"])
    values = objective_values(opt, record)
    if values is not None and opt.constraints:
        summary = record["summary"]
        values_c = violations(opt.constraints, summary)
        trial.set_user_attr("constraints", values_c)
        trial.set_user_attr("constrained", {b.metric: summary.get(b.metric) for b in opt.constraints})
        if trial_constraints():
            for k, v in enumerate(values_c):
                trial.set_constraint(f"c{k}", v)
    if values is None:
        study.tell(trial, state=TrialState.FAIL)
        return False
    study.tell(trial, values)
    return True


def optimize(
    opt: Optimization,
    out: str | Path,
    trials: int,
    *,
    client=None,
    workers: int | None = None,
    scheduler: str | None = None,
    seed: int = 0,
    progress: bool = True,
) -> OptimizeReport:
    """Run the Optuna study in out/optuna.db until it has `trials` finished trials (those
    of earlier runs count), the designs on Dask; then write trials.csv, pareto.csv and
    pareto.png."""
    from granplate.study.sweep import dask_client, warm_workers

    t0 = time.perf_counter()
    out = Path(out)
    (out / D.DESIGNS).mkdir(parents=True, exist_ok=True)
    study = open_study(opt, out, seed)
    requeue_interrupted(study)
    report = OptimizeReport(trials, finished(study), out=out)
    try:
        if report.n_before < trials:
            with dask_client(workers, scheduler) if client is None else nullcontext(client) as c:
                report.warm_up_s = warm_workers(c, gp.dumps(opt.scenario({})))
                _search(c, study, opt, out, trials, progress, report)
    finally:
        write_outputs(study, opt, out)
        report.elapsed_s = time.perf_counter() - t0
    return report


def _search(client, study, opt: Optimization, out: Path, trials: int, progress: bool, report: OptimizeReport) -> None:
    """Keep one trial per worker thread in flight until `trials` are finished."""
    from distributed import as_completed

    from granplate.study.sweep import progress_bar

    slots = max(1, sum(client.nthreads().values()))
    pending = as_completed()
    running: dict[Any, tuple[Any, str, str, dict]] = {}
    done = report.n_before
    bar = progress_bar(trials, done, progress, desc="optimize", unit="trial")

    written = time.monotonic()

    def finish(trial, record) -> None:
        nonlocal done, written
        if not tell(study, opt, trial, record):
            report.n_failed += 1
            bar.write(f"trial {trial.number} failed: {record['status']}", file=sys.stderr)
        done += 1
        bar.update(1)
        if time.monotonic() - written >= PROGRESS_EVERY_S:
            write_progress(study, opt, out, trials)
            written = time.monotonic()

    try:
        while done < trials:
            while len(running) < slots and done + len(running) < trials:
                trial = study.ask(opt.space)
                changes = {f: trial.params[f] for f in opt.space}
                text = gp.dumps(opt.scenario(changes))
                key = D.design_key(text)
                record = D.read_record(out, key)
                if record is not None:  # computed before (this study or a sweep)
                    report.n_reused += 1
                    finish(trial, record)
                    continue
                fut = client.submit(D.run_design, text, False, key=f"trial-{trial.number}-{key}", pure=False)
                running[fut] = (trial, key, text, {**opt.fixed, **changes})
                pending.add(fut)
            if not running:
                continue
            fut = next(pending)
            trial, key, text, changes = running.pop(fut)
            try:
                outcome = fut.result()
            except Exception as err:  # noqa: BLE001 - a lost task: the trial fails, no record
                from optuna.trial import TrialState

                trial.set_user_attr("status", f"lost: {D.failure_message(err)}")
                study.tell(trial, state=TrialState.FAIL)
                report.n_failed += 1
                done += 1
                bar.update(1)
                bar.write(f"trial {trial.number} lost: {D.failure_message(err)}", file=sys.stderr)
                continue
            record = D.make_record(key, changes, text, outcome)
            D.write_record(out, record)
            report.n_computed += 1
            D.note_warnings(report, f"trial {trial.number}", outcome)
            finish(trial, record)
    finally:
        bar.close()
        if running:
            client.cancel(list(running))


# ------------------------------------------------------------------------- outputs


def constrained_only(opt: Optimization) -> list[str]:
    """The constrained metrics that are not objectives (their own columns in the CSVs)."""
    return list(dict.fromkeys(b.metric for b in opt.constraints if b.metric not in opt.objectives))


def feasible_text(trial) -> str:
    """ "yes" / "no" for a completed trial of a constrained study, "" otherwise."""
    ok = is_feasible(trial.user_attrs.get("constraints")) if trial.values is not None else None
    return "" if ok is None else ("yes" if ok else "no")


def _rows(study, opt: Optimization, trials) -> tuple[list[str], list[list[Any]]]:
    extra = constrained_only(opt)
    header = (
        ["trial", "state"]
        + list(opt.space)
        + list(opt.objectives)
        + extra
        + (["feasible"] if opt.constraints else [])
        + ["status", "key"]
    )
    rows = []
    for t in trials:
        values = list(t.values) if t.values is not None else [None] * len(opt.objectives)
        constrained = t.user_attrs.get("constrained", {})
        rows.append(
            [t.number, t.state.name]
            + [t.params.get(f) for f in opt.space]
            + values
            + [constrained.get(m) for m in extra]
            + ([feasible_text(t)] if opt.constraints else [])
            + [t.user_attrs.get("status", ""), t.user_attrs.get("key", "")]
        )
    return header, rows


def _write_csv(path: Path, header: list[str], rows: list[list[Any]]) -> None:
    from granplate.store import atomic_write

    def write(tmp: Path) -> None:
        with open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(header)
            for row in rows:
                w.writerow([repr(v) if isinstance(v, float) else ("" if v is None else v) for v in row])

    atomic_write(path, write)


def pareto_trials(study) -> list:
    """The completed trials no other completed trial dominates (the best one for a single
    objective), by trial number; with constraints, among the feasible trials only."""
    return sorted(study.best_trials, key=lambda t: t.number)


def excluded_trials(study, complete: list) -> list:
    """The infeasible trials that no other completed trial dominates, feasible or not: the
    better compromises the constraints rule out (none without constraints), by number."""
    from optuna.study._multi_objective import _get_pareto_front_trials_by_trials

    front = _get_pareto_front_trials_by_trials(complete, study.directions, consider_constraint=False)
    return sorted((t for t in front if feasible_text(t) == "no"), key=lambda t: t.number)


def write_progress(study, opt: Optimization, out: Path, trials: int) -> None:
    """trials.csv while the search runs: the trials so far, then one row per trial still
    to come (state WAITING, no parameters: "not run" on the report's page)."""
    from optuna.trial import TrialState

    all_trials = study.get_trials(deepcopy=False)
    header, rows = _rows(study, opt, all_trials)
    n = len(rows)
    running = sum(1 for t in all_trials if t.state == TrialState.RUNNING)
    left = max(0, trials - finished(study) - running)
    rows += [[n + k, "WAITING"] + [None] * (len(header) - 2) for k in range(left)]
    _write_csv(out / TRIALS_CSV, header, rows)


def write_outputs(study, opt: Optimization, out: Path) -> None:
    """trials.csv (every trial), pareto.csv (the Pareto front) and pareto.png."""
    from optuna.trial import TrialState

    all_trials = study.get_trials(deepcopy=False)
    _write_csv(out / TRIALS_CSV, *_rows(study, opt, all_trials))
    complete = [t for t in all_trials if t.state == TrialState.COMPLETE]
    front = pareto_trials(study) if complete else []
    excluded = excluded_trials(study, complete) if complete and opt.constraints else []
    _write_csv(out / PARETO_CSV, *_rows(study, opt, front + excluded))
    if complete:
        plot_front(opt, complete, front, out / PARETO_PNG)


def axis_label(metric: str) -> str:
    unit = D.metric_units().get(metric, "")
    return f"{metric} [{unit}]" if unit and unit != "1" else f"{metric} [-]"


def plot_front(opt: Optimization, complete: list, front: list, path: Path) -> None:
    """The trials and their Pareto front in the plane of the first two objectives (one
    objective: its value per trial, the best marked)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from granplate.store import atomic_write

    names = list(opt.objectives)
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    bad = [t for t in complete if feasible_text(t) == "no"]
    complete = [t for t in complete if feasible_text(t) != "no"]
    if len(names) >= 2:
        ax.scatter([t.values[0] for t in complete], [t.values[1] for t in complete], s=14, color="0.7", label="trials")
        if bad:
            ax.scatter(
                [t.values[0] for t in bad],
                [t.values[1] for t in bad],
                s=18,
                marker="x",
                color="0.45",
                label="infeasible (constraints)",
            )
        pts = sorted((t.values[0], t.values[1]) for t in front)
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", color="C3", ms=5, label="Pareto front")
        ax.set_xlabel(f"{axis_label(names[0])} ({opt.objectives[names[0]]})")
        ax.set_ylabel(f"{axis_label(names[1])} ({opt.objectives[names[1]]})")
    else:
        ax.plot([t.number for t in complete], [t.values[0] for t in complete], "o", color="0.6", ms=4, label="trials")
        if bad:
            ax.plot(
                [t.number for t in bad], [t.values[0] for t in bad], "x", color="0.45", label="infeasible (constraints)"
            )
        ax.plot([t.number for t in front], [t.values[0] for t in front], "o", color="C3", label="best")
        ax.set_xlabel("trial")
        ax.set_ylabel(f"{axis_label(names[0])} ({opt.objectives[names[0]]})")
    ax.set_title(f"{opt.base_name}: {len(complete) + len(bad)} trials", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=120, format="png"))
    plt.close(fig)
