"""`granplate sweep STUDY.toml --out DIR`: run a study's designs on Dask (docs/studies.md)."""
from __future__ import annotations

import sys


def _cmd_sweep(args) -> int:
    from granplate.study.spec import load_study
    from granplate.study.sweep import RESULTS_CSV, RESULTS_NC, sweep

    study = load_study(args.study)
    if args.workers is not None and args.workers < 1:
        print(f"granplate: error: --workers = {args.workers}: must be >= 1", file=sys.stderr)
        return 2
    print(f"{len(study.designs)} designs of {study.base_name} "
          f"({', '.join(study.names) or 'no parameters'}) -> {args.out}", file=sys.stderr)
    report = sweep(study, args.out, workers=args.workers, scheduler=args.scheduler,
                   full=args.full, limit=args.limit, progress=not args.quiet)
    print(f"designs: {report.n_designs}, already done: {report.n_done_before}, computed: "
          f"{report.n_computed}, failed: {report.n_failed}, lost: {len(report.lost)}; "
          f"{report.elapsed_s:.1f} s")
    for line in report.lost:
        print(f"lost (a rerun retries it): {line}", file=sys.stderr)
    print(f"table: {report.out / RESULTS_NC}, {report.out / RESULTS_CSV}")
    return 0 if not report.lost else 1


def register(sub) -> None:
    """Add the `sweep` subcommand."""
    p = sub.add_parser("sweep", help="run a design study (a grid or sample of scenario changes) on Dask")
    p.add_argument("study", help="the study TOML file (docs/studies.md)")
    p.add_argument("--out", required=True, help="output folder: results.nc, results.csv, designs/")
    p.add_argument("--workers", type=int, default=None,
                   help="worker processes of the local cluster (default: the machine's cores)")
    p.add_argument("--scheduler", default=None,
                   help="address of an existing Dask scheduler (e.g. tcp://host:8786) instead of a local cluster")
    p.add_argument("--full", action="store_true", help="keep each design's full result (designs/KEY.nc)")
    p.add_argument("--limit", type=int, default=None,
                   help="compute at most this many of the missing designs (a rerun continues)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_sweep)
