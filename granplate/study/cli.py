"""`granplate sweep STUDY.toml --out DIR`: run a study's designs on Dask;
`granplate optimize STUDY.toml --out DIR --trials N`: search its parameters with Optuna;
`granplate study report DIR [--watch]`: the study's report page, or followed while the
study runs (docs/studies.md). Sweep and
optimize keep the study file as DIR/study.toml and end by writing the report."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from granplate.figures.cli import add_set_option

#: Lost designs listed one by one (a lost scheduler loses every design not done).
MAX_LOST_LINES = 5


def keep_study_file(study_file: str, out: str, changes: dict | None = None) -> None:
    """Copy the study file into the output folder (DIR/study.toml) for the report; with
    `changes` (--set), the study as run: its table with them in [set], under a comment."""
    import tomli_w

    from granplate.study.outcome import STUDY_FILE
    from granplate.study.spec import read_document, with_settings

    Path(out).mkdir(parents=True, exist_ok=True)
    target = Path(out) / STUDY_FILE
    if changes:
        doc = with_settings(read_document(study_file), changes)
        target.write_text(
            f"# {Path(study_file).name} with --set " + ", ".join(changes) + " (in [set] below)\n" + tomli_w.dumps(doc)
        )
    elif Path(study_file).resolve() != target.resolve():
        shutil.copyfile(study_file, target)


def _report(out: str, enabled: bool, progress: bool) -> None:
    """Write the study report (unless --no-report) and say where it is."""
    if not enabled:
        return
    from granplate.study.report import write_report

    page = write_report(out, progress=progress)
    print(f"report: {page}")


def _warned(report, computed: str) -> None:
    """One line on stderr when designs computed now warned: how many, and the first warning
    (each design's record, DIR/designs/KEY.json, lists its own)."""
    if report.n_warned:
        print(
            f"granplate: {report.n_warned} of the {report.n_computed} {computed} warned (each record in "
            f"designs/ lists its warnings); the first, {report.first_warning}",
            file=sys.stderr,
        )


def _verdict(n_failed: int, n_lost: int, n_total: int, what: str) -> int:
    """The exit status of a study command, 1 when any design failed or was lost, 0 else;
    that case is said on the last line (stderr)."""
    if not n_failed and not n_lost:
        return 0
    lost = f" and {n_lost} lost (a rerun retries them)" if n_lost else ""
    print(f"granplate: {n_failed} of {n_total} {what} failed{lost}", file=sys.stderr)
    return 1


def _cmd_sweep(args) -> int:
    from granplate.setup.io import parse_settings
    from granplate.study.spec import load_study
    from granplate.study.sweep import RESULTS_CSV, RESULTS_NC, sweep

    changes = parse_settings(args.settings)
    study = load_study(args.study, changes)
    keep_study_file(args.study, args.out, changes)
    if args.workers is not None and args.workers < 1:
        print(f"granplate: error: --workers = {args.workers}: must be >= 1", file=sys.stderr)
        return 2
    print(
        f"{len(study.designs)} designs of {study.base_name} "
        f"({', '.join(study.names) or 'no parameters'}) -> {args.out}",
        file=sys.stderr,
    )
    try:
        report = sweep(
            study,
            args.out,
            workers=args.workers,
            scheduler=args.scheduler,
            full=args.full,
            limit=args.limit,
            progress=not args.quiet,
        )
    except KeyboardInterrupt:
        print(
            f"granplate: sweep interrupted; the finished designs are kept in {args.out}/designs "
            'and the table lists the others as "not run": rerun the same command to compute '
            "only those",
            file=sys.stderr,
        )
        raise
    print(
        f"designs: {report.n_designs}, already done: {report.n_done_before}, computed: "
        f"{report.n_computed}, failed: {report.n_failed}, lost: {len(report.lost)}; "
        f"{report.elapsed_s:.1f} s"
    )
    for line in report.lost[:MAX_LOST_LINES]:
        print(f"lost (a rerun retries it): {line}", file=sys.stderr)
    if len(report.lost) > MAX_LOST_LINES:
        print(f"... and {len(report.lost) - MAX_LOST_LINES} more lost designs", file=sys.stderr)
    print(f"table: {report.out / RESULTS_NC}, {report.out / RESULTS_CSV}")
    _report(args.out, args.report, not args.quiet)
    _warned(report, "designs computed now")
    return _verdict(report.n_failed, len(report.lost), report.n_designs, "designs")


def _cmd_optimize(args) -> int:
    from granplate.study.optimize import DATABASE, PARETO_CSV, PARETO_PNG, TRIALS_CSV, load_optimization, optimize

    from granplate.setup.io import parse_settings

    changes = parse_settings(args.settings)
    opt = load_optimization(args.study, changes)
    for name, value in (("--trials", args.trials), ("--workers", args.workers)):
        if value is not None and value < 1:
            print(f"granplate: error: {name} = {value}: must be >= 1", file=sys.stderr)
            return 2
    keep_study_file(args.study, args.out, changes)
    print(
        f"optimize {', '.join(f'{k} ({v})' for k, v in opt.objectives.items())} over "
        f"{', '.join(opt.space)} of {opt.base_name} -> {args.out}",
        file=sys.stderr,
    )
    try:
        report = optimize(
            opt,
            args.out,
            args.trials,
            workers=args.workers,
            scheduler=args.scheduler,
            seed=args.seed,
            progress=not args.quiet,
        )
    except KeyboardInterrupt:
        print(
            f"granplate: optimize interrupted; rerun the same command to continue the study in {args.out}/{DATABASE}",
            file=sys.stderr,
        )
        raise
    print(
        f"trials: {args.trials}, finished before: {report.n_before}, computed: {report.n_computed}, "
        f"from existing designs: {report.n_reused}, failed: {report.n_failed}; {report.elapsed_s:.1f} s"
    )
    out = report.out
    print(f"study: {out / DATABASE}; trials: {out / TRIALS_CSV}; Pareto front: {out / PARETO_CSV}, {out / PARETO_PNG}")
    _report(args.out, args.report, not args.quiet)
    _warned(report, "trials computed now")
    return _verdict(report.n_failed, 0, args.trials - report.n_before, "trials of this run")


def _cmd_report(args) -> int:
    if not args.watch:
        _report(args.dir, True, not args.quiet)
        return 0
    from granplate.study.watch import watch

    if not args.every > 0:
        print(f"granplate: error: --every = {args.every}: must be > 0 (seconds)", file=sys.stderr)
        return 2
    try:
        c = watch(args.dir, every=args.every)
    except KeyboardInterrupt:
        print(f"watch stopped; the page is {Path(args.dir) / 'report.html'}", file=sys.stderr)
        return 0
    print(f"report: {Path(args.dir) / 'report.html'} ({c['done']} done, {c['failed']} failed)")
    return 0


def _cluster_options(p) -> None:
    p.add_argument(
        "--workers", type=int, default=None, help="worker processes of the local cluster (default: the machine's cores)"
    )
    p.add_argument(
        "--scheduler",
        default=None,
        help="address of an existing Dask scheduler (e.g. tcp://host:8786) instead of a local cluster",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--no-report",
        dest="report",
        action="store_false",
        help="do not write the report page at the end (granplate study report DIR does)",
    )
    add_set_option(p, "the base scenario, as the study's [set] table does (overriding it there)")


def register(sub) -> None:
    """Add the `sweep` and `optimize` subcommands."""
    p = sub.add_parser("sweep", help="run a design study (a grid or sample of scenario changes) on Dask")
    p.add_argument("study", help="the study TOML file (docs/studies.md)")
    p.add_argument("--out", required=True, help="output folder: results.nc, results.csv, designs/")
    _cluster_options(p)
    p.add_argument("--full", action="store_true", help="keep each design's full result (designs/KEY.nc)")
    p.add_argument(
        "--limit", type=int, default=None, help="compute at most this many of the missing designs (a rerun continues)"
    )
    p.set_defaults(func=_cmd_sweep)
    o = sub.add_parser("optimize", help="search a study's parameters for its [objectives] with Optuna, on Dask")
    o.add_argument("study", help="the study TOML file, with an [objectives] table (docs/studies.md)")
    o.add_argument(
        "--out", required=True, help="output folder: optuna.db, trials.csv, pareto.csv, pareto.png, designs/"
    )
    o.add_argument(
        "--trials", type=int, required=True, help="finished trials to reach (those of earlier runs into --out count)"
    )
    o.add_argument("--seed", type=int, default=0, help="seed of the sampler (TPE)")
    _cluster_options(o)
    o.set_defaults(func=_cmd_optimize)
    st = sub.add_parser("study", help="about a study's output folder: its report page")
    sst = st.add_subparsers(dest="study_command", required=True)
    r = sst.add_parser(
        "report",
        help="write DIR/report.html (and its PNG figures in DIR/report/) from a sweep's or an optimisation's folder",
    )
    r.add_argument("dir", help="the study's output folder (--out of granplate sweep / optimize)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress messages")
    r.add_argument(
        "--watch",
        action="store_true",
        help="follow a running study: rewrite the page as designs arrive (it says how many are "
        "done, failed and left, and reloads itself), the full report once none is left; Ctrl-C stops",
    )
    r.add_argument("--every", type=float, default=5.0, help="seconds between two looks with --watch (default 5)")
    r.set_defaults(func=_cmd_report)
