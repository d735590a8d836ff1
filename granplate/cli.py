"""Command line: `granplate run | presets | preset` (run, show, sweep, optimize, preset and
resolve take `--set PATH=VALUE` to change a field by its dotted path).

A user's mistake (bad scenario, unknown preset, missing file) prints one clear line and
exits with status 2, never a traceback; a run that goes numerically wrong prints why,
keeps what it computed (written to -o) and exits with status 3.
"""

from __future__ import annotations

import argparse
import importlib
import json
import logging
import os
import sys
import warnings
from pathlib import Path

from granplate.errors import ScenarioError, SimulationError
from granplate.figures.cli import add_set_option
from granplate.setup.fields import positive

#: modules that add subcommands: each defines register(subparsers), adding parsers whose
#: `func(args) -> int` runs the command (ScenarioError is reported as a user error).
COMMAND_MODULES = (
    "granplate.paper.reproduce",  # reproduce, plot, animate, export
    "granplate.figures.cli",  # show
    "granplate.verification",  # verify
    "granplate.study.cli",  # sweep, optimize
    "granplate.bench.cli",  # bench
    "granplate.commands.resolve",  # resolve
    "granplate.commands.modes",  # modes
)

#: (summary key, label, unit shown, format, scale to the unit shown). "{ref}" in a label
#: is the energy the fractions are of (`reference_name`); "-": a pure number.
SUMMARY_ROWS = (
    ("e_shock", "E_shock, work of the load", "J", "{:.4e}", 1.0),
    ("e_load_taken", "  of it taken back by the load", "J", "{:.4e}", 1.0),
    ("e_initial", "E_initial, energy at t = 0", "J", "{:.4e}", 1.0),
    ("e_gravity", "E_gravity, work of gravity", "J", "{:.4e}", 1.0),
    ("e_drive", "E_drive, work of the drives", "J", "{:.4e}", 1.0),
    ("e_in", "E_in, the energy put in (their sum)", "J", "{:.4e}", 1.0),
    ("ep_max_fraction", "plate energy, peak / {ref}", "-", "{:.4f}", 1.0),
    ("ep_final_fraction", "plate energy, final / {ref}", "-", "{:.4f}", 1.0),
    ("eg_max_fraction", "granular energy, peak / {ref}", "-", "{:.4f}", 1.0),
    ("eg_final_fraction", "granular energy, final / {ref}", "-", "{:.4f}", 1.0),
    ("dissipated_fraction", "dissipated, final / {ref}", "-", "{:.4f}", 1.0),
    ("plastic_fraction", "of which plastic, final / {ref}", "-", "{:.4f}", 1.0),
    ("max_contact_pressure", "max Hertz contact pressure p0", "MPa", "{:.4g}", 1e-6),
    ("yield_onset_ratio", "max p0 / (1.6 Y), yield onset", "-", "{:.3f}", 1.0),
    ("max_von_mises", "max von Mises stress", "MPa", "{:.2f}", 1e-6),
    ("max_von_mises_disc", "max von Mises, disc average", "MPa", "{:.2f}", 1e-6),
    ("max_von_mises_ball", "max von Mises, ball average", "MPa", "{:.2f}", 1e-6),
    ("max_displacement", "max displacement of the body", "um", "{:.4g}", 1e6),
    ("max_eps_yy", "max |eps_yy|", "-", "{:.3e}", 1.0),
    ("energy_residual_max", "max |energy residual|", "-", "{:.2e}", 1.0),
    ("n_steps", "time steps", "-", "{:d}", 1),
    ("wall_time_s", "wall time, compiling left out", "s", "{:.2f}", 1.0),
    ("compile_time_s", "wall time compiling the kernels", "s", "{:.2f}", 1.0),
)


#: An energy below this fraction of e_in is negligible (a run from rest has E_initial = 0).
NEGLIGIBLE = 1e-9


def _negligible(summary: dict, key: str) -> bool:
    return abs(summary.get(key) or 0.0) <= NEGLIGIBLE * abs(summary.get("e_in") or 0.0)


def reference_name(summary: dict) -> str:
    """The energy the summary's fractions are of, by name: e_in = e_shock + e_initial +
    e_gravity + e_drive is "E_shock" when only the load puts energy in (the paper's cases),
    "E_initial" when only the state at t = 0 does, else "E_in"."""
    terms = [k for k in ("e_shock", "e_initial", "e_gravity", "e_drive") if not _negligible(summary, k)]
    if terms == ["e_initial"]:
        return "E_initial"
    if terms in (["e_shock"], []):
        return "E_shock"
    return "E_in"


#: The fractions of the summary (shares of e_in) and their names in a note.
SHARES = (
    "ep_max_fraction",
    "ep_final_fraction",
    "eg_max_fraction",
    "eg_final_fraction",
    "dissipated_fraction",
    "plastic_fraction",
)


def stride_notes(summary: dict) -> list[str]:
    """The note of a run of many granules whose outputs were strided (setup.output_stride)."""
    k = summary.get("output_stride")
    if not k:
        return []
    from granplate.setup.output_stride import GRANULE_VALUES_MAX

    given = summary["output_interval_given"]
    return [
        f"note: {summary['n_granules']:,} granules: the outputs are kept at one output time in {k}, "
        f"time.output_interval {given:.4g} s raised to {k * given:.4g} s, so that each granule variable "
        f"holds at most {GRANULE_VALUES_MAX:,} values (docs/output.md); time.field_interval sets it."
    ]


def summary_notes(summary: dict) -> list[str]:
    """What a reader needs to trust the energies: why the load's work taken back lowers
    the energies' sum, and any share above 1 (only by round-off: the energy residual)."""
    notes = stride_notes(summary)
    taken = summary.get("e_load_taken") or 0.0
    if not _negligible(summary, "e_load_taken") and taken > 0:
        notes.append(
            f"note: the load put in E_shock = {summary['e_shock']:.4e} J and took {taken:.4e} J back: "
            f"its force opposed the velocity of granules moving toward it (negative power F . v), so "
            f"the energies at t_end add up to E_in - {taken:.4e} J = {summary['e_in'] - taken:.4e} J."
        )
    over = {k: summary[k] for k in SHARES if (summary.get(k) or 0.0) > 1.0}
    if over:
        excess = max(over.values()) - 1.0
        residual = summary.get("energy_residual_max") or 0.0
        e_in, e_max = summary.get("e_in") or 0.0, summary.get("e_in_max") or 0.0
        lent = max(e_max / e_in - 1.0, 0.0) if e_in > 0 else 0.0  # put in, then taken back by t_end
        if excess <= 1.01 * residual:
            why = "within the energy residual, the balance's round-off"
        elif excess <= 1.01 * (lent + residual):
            why = (
                f"within the energy put in at its largest, E_in_max = {e_max:.4e} J (gravity or a drive "
                "put in more before t_end than by t_end, and took it back)"
            )
        else:
            why = "beyond the energy residual: the balance does not close"
        notes.append(f"note: {', '.join(over)} above 1 by {excess:.1e}, {why} (max |residual| {residual:.1e}).")
    return notes


def format_summary(summary: dict) -> str:
    """The summary as an aligned text table; "-" where a value does not apply (None);
    then the notes (`summary_notes`), where there are any.

    The E_initial row shows only when the run does not start at rest, the E_in row only
    when both E_shock and E_initial count, the load's work taken back only when there is
    some (E_shock is then the work it put in).
    """
    ref = reference_name(summary)
    hidden = {k for k in ("e_initial", "e_gravity", "e_drive") if _negligible(summary, k)}
    if ref != "E_in":
        hidden.add("e_in")
    if _negligible(summary, "e_load_taken"):
        hidden.add("e_load_taken")
    width = 36
    lines = [f"{'quantity':{width}s} {'value':>14s}  unit", "-" * (width + 22)]
    for key, label, unit, fmt, scale in SUMMARY_ROWS:
        if key not in summary or key in hidden:
            continue
        v = summary[key]
        text = "-" if v is None else fmt.format(v * scale)
        if key == "e_shock" and "e_load_taken" not in hidden:
            label = "E_shock, work the load put in"
        lines.append(f"{label.format(ref=ref):{width}s} {text:>14s}  {unit}")
    pairs = summary.get("contact_pairs") or []
    if pairs:
        lines += ["", f"{'material pair (normal law)':{width}s} {'max p0 [MPa]':>14s}  p0 / (1.6 Y)   contact, time"]
        for p in pairs:
            ratio = "unknown Y" if p["yield_onset_ratio"] is None else f"{p['yield_onset_ratio']:.3f}"
            lines.append(
                f"{p['pair'] + ' (' + p['normal_law'] + ')':{width}s} {p['max_contact_pressure'] * 1e-6:>14.4g}"
                f"  {ratio:>12s}   {p['contact']}, {p['time']:.4g} s"
            )
    notes = summary_notes(summary)
    return "\n".join(lines + ([""] + notes if notes else []))


def _write_result(ds, out: Path) -> bool:
    """Write the result to out, finishing even when SIGINT/SIGTERM arrives meanwhile;
    whether one did (the caller then exits with 130)."""
    from granplate.results.dataset import write
    from granplate.solver.driver import stop_on_signals

    with stop_on_signals() as stop_requested:
        write(ds, out)
    return stop_requested()


def keep_dask_out() -> None:
    """Mark Dask absent in this process (`import dask` then raises ImportError): a single
    run needs none of it, but xarray imports dask.array when it is installed (and netCDF
    writes import distributed), which costs a fresh `granplate run` process about as much
    as its other imports together (docs/benchmarks.md, "Start-up"). Only for commands that
    never use Dask, and only where no Dask module is loaded yet."""
    if not any(m == "dask" or m.startswith(("dask.", "distributed")) for m in sys.modules):
        for name in ("dask", "distributed"):
            sys.modules.setdefault(name, None)


def result_path(output: str | None, name: str) -> Path:
    """The result file of `granplate run`: -o's path (an existing folder: NAME.nc in it),
    else NAME.nc here. Its folder must exist and be writable, checked before the run so that
    no run's result is lost at the end (ValueError with the reason otherwise)."""
    out = Path(output) if output else Path(f"{name}.nc")
    if out.is_dir():
        out = out / f"{name}.nc"
    folder = out.parent
    if not folder.is_dir():
        raise ValueError(f"-o {output}: the folder {folder} does not exist (create it first)")
    if not os.access(folder, os.W_OK) or (out.exists() and not os.access(out, os.W_OK)):
        raise ValueError(f"-o {output or out}: {out} cannot be written (permissions)")
    return out


def _cmd_run(args) -> int:
    from granplate.results.dataset import summary
    from granplate.results.kernels import compile_all_wanted
    from granplate.setup.io import load_scenario, parse_settings
    from granplate.results.run import interrupted, simulate

    scenario = load_scenario(args.scenario, parse_settings(args.settings))
    try:
        out = result_path(args.output, scenario.name)
    except ValueError as err:
        print(f"granplate: error: {err}", file=sys.stderr)
        return 2
    start = None
    if args.start_from:
        from granplate.results.restart import read_result

        start = read_result(args.start_from, "from")
    try:
        ds = simulate(
            scenario,
            t_end=args.t_end,
            progress=not args.quiet,
            compile_all=compile_all_wanted(),
            start_from=start,
            start_time=args.from_time,
        )
    except SimulationError as err:
        print(f"granplate: run stopped: {err}", file=sys.stderr)
        if err.result is None:
            return 3
        stopped = _write_result(err.result, out)
        print(
            f"granplate: the result so far is written to {out} (its 'status' attribute says why the run stopped)",
            file=sys.stderr,
        )
        return 130 if stopped or interrupted(err.result) else 3
    if _write_result(ds, out):
        print(f"granplate: interrupted while writing the result; it is written in full to {out}", file=sys.stderr)
        return 130
    s = summary(ds)
    print(f"{scenario.name}: {scenario.description}".rstrip(": "))
    print(format_summary(s))
    print(f"result: {out}")
    if args.summary:
        Path(args.summary).write_text(json.dumps(s, indent=2) + "\n")
        print(f"summary: {args.summary}")
    return 0


def _cmd_compile(args) -> int:
    from granplate.results.kernels import KERNEL_SETS, compile_kernels, measure, missing

    if args.measure:
        data = measure(Path(args.measure), note=print)
        print(f"measured: {args.measure} ({', '.join(f'{k} {v:.0f} s' for k, v in data['seconds'].items())})")
        return 0
    todo = missing()
    if not todo:
        print(f"every scheme's kernels are compiled, in the plane and in space ({len(KERNEL_SETS)} sets)")
        return 0
    compile_kernels(todo, note=print)
    return 0


def _cmd_presets(args) -> int:
    from granplate.setup.presets import preset, preset_names

    for name in preset_names(True):
        print(f"{name:20s} {preset(name).description}")
    return 0


def _cmd_preset(args) -> int:
    from granplate.setup.presets import preset
    from granplate.setup.io import dumps, parse_settings, with_changes
    from granplate.setup.validate import validate

    from granplate.commands import emit_text

    scenario = preset(args.name)
    changes = parse_settings(args.settings)
    if changes:
        scenario = with_changes(scenario, changes)
        validate(scenario)
    emit_text(dumps(scenario), args.output)
    return 0


def _cmd_cache(args) -> int:
    from granplate import store

    if args.action == "clear":
        n = store.clear(args.kind)
        print(f"removed {n} entries from {store.cache_directory()}")
        return 0
    table = store.info()
    print(
        f"cache directory: {store.cache_directory()} (cap {store.max_bytes() / 2**20:.0f} MiB, ${store.MAX_BYTES_ENV})"
    )
    print(f"{'kind':20s} {'entries':>8s} {'MiB':>10s}")
    for kind, row in sorted(table.items()):
        print(f"{kind:20s} {row['entries']:8d} {row['bytes'] / 2**20:10.2f}")
    total = sum(row["bytes"] for row in table.values())
    print(f"{'total':20s} {sum(row['entries'] for row in table.values()):8d} {total / 2**20:10.2f}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="granplate", description="Granular media against an elastic plate: shock-mitigation simulator."
    )
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run a scenario file or a preset")
    r.add_argument("scenario", help="a scenario TOML file or a preset name (see 'granplate presets')")
    r.add_argument("-o", "--output", help="result netCDF file (default NAME.nc)")
    r.add_argument("--summary", help="also write the summary as JSON to this file")
    r.add_argument("--t-end", type=float, default=None, help="simulated time [s] (overrides the scenario)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    r.add_argument(
        "--from",
        dest="start_from",
        metavar="RESULT",
        default=None,
        help="restart from this result's last output time, or --from-time (a result netCDF file of the same "
        "granules; overrides the scenario's [restart])",
    )
    r.add_argument(
        "--from-time",
        type=float,
        default=None,
        help="the restart time [s]: one at which the result stores the loop's state (its end, and every "
        "time.restart_interval before)",
    )
    add_set_option(r)
    r.set_defaults(func=_cmd_run)
    co = sub.add_parser(
        "compile",
        help="compile every scheme's kernels once, in the plane and in space (the first run does it otherwise)",
    )
    co.add_argument(
        "--measure",
        metavar="FILE",
        default=None,
        help="compile every kernel set and write the seconds each took to FILE (JSON; "
        "point NUMBA_CACHE_DIR at an empty folder first)",
    )
    co.set_defaults(func=_cmd_compile)
    ps = sub.add_parser("presets", help="list the built-in presets")
    ps.set_defaults(func=_cmd_presets)
    pr = sub.add_parser("preset", help="print a preset as TOML (to edit and run)")
    pr.add_argument("name")
    pr.add_argument("-o", "--output", help="write to this file instead of stdout")
    add_set_option(pr, "the preset (the file written is the changed scenario)")
    pr.set_defaults(func=_cmd_preset)
    ca = sub.add_parser("cache", help="show or clear the on-disk cache (plate models, reused runs)")
    ca.add_argument("action", choices=("info", "clear"), help="info: entries and size per kind; clear: remove")
    ca.add_argument("--kind", default=None, help="with clear: only this kind (e.g. plate, reproduce)")
    ca.set_defaults(func=_cmd_cache)
    for module in COMMAND_MODULES:
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as err:  # an optional command module not present
            if err.name != module:
                raise
            continue
        mod.register(sub)
    return p


class _StderrLines(logging.Handler):
    """The library's log lines on stderr (the stream of the moment), `granplate: ...`."""

    def emit(self, record: logging.LogRecord) -> None:
        print(f"granplate: {record.getMessage()}", file=sys.stderr, flush=True)


def show_notes(quiet: bool) -> None:
    """Print what the library announces (compiling the time loop, building a plate: INFO
    lines of the "granplate" logger) on stderr; with quiet, only its warnings."""
    logger = logging.getLogger("granplate")
    if not any(isinstance(h, _StderrLines) for h in logger.handlers):
        logger.addHandler(_StderrLines())
    logger.setLevel(logging.WARNING if quiet else logging.INFO)


#: The package's folder: a warning raised from one of its modules prints as one line.
_PACKAGE_DIR = Path(__file__).resolve().parent


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Show a warning the library raises as one line, `granplate: warning: ...`, on stderr
    (not the file, line and source that Python shows); any other warning as Python does."""
    if _PACKAGE_DIR in Path(filename).resolve().parents:
        print(f"granplate: warning: {message}", file=sys.stderr if file is None else file, flush=True)
    else:
        _PYTHON_SHOWWARNING(message, category, filename, lineno, file, line)


def show_warnings() -> None:
    """The library's warnings on stderr as one line each (this process's own command line)."""
    global _PYTHON_SHOWWARNING
    if warnings.showwarning is not _one_line_warning:
        _PYTHON_SHOWWARNING = warnings.showwarning
        warnings.showwarning = _one_line_warning


_PYTHON_SHOWWARNING = warnings.showwarning


def _value_options(parser: argparse.ArgumentParser) -> set[str]:
    """The option strings of `parser` and its subcommands that take a value (--t-end, -o...)."""
    found: set[str] = set()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                found |= _value_options(sub)
        elif action.option_strings and action.nargs != 0:
            found.update(action.option_strings)
    return found


def _is_negative_number(text: str) -> bool:
    """'-1e-4', '-inf', '-5': a value argparse would take for an option (its own test
    knows plain decimals only)."""
    if not text.startswith("-"):
        return False
    try:
        float(text)
    except ValueError:
        return False
    return True


def join_negative_values(parser: argparse.ArgumentParser, argv: list[str]) -> list[str]:
    """argv with "OPTION -1e-4" written "OPTION=-1e-4" for every option that takes a value,
    so that a negative number reaches the checks that name the field (argparse would
    read it as an option and answer "expected one argument")."""
    options = _value_options(parser)
    out: list[str] = []
    i = 0
    while i < len(argv):
        if argv[i] in options and i + 1 < len(argv) and _is_negative_number(argv[i + 1]):
            out.append(f"{argv[i]}={argv[i + 1]}")
            i += 2
            continue
        out.append(argv[i])
        i += 1
    return out


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(join_negative_values(parser, sys.argv[1:] if argv is None else list(argv)))
    show_notes(bool(getattr(args, "quiet", False)))

    if argv is None:  # this process is the command line's own
        show_warnings()
        if getattr(args, "func", None) is _cmd_run:
            keep_dask_out()
    try:
        if getattr(args, "t_end", None) is not None:
            positive("time.t_end", args.t_end)  # the field's own check, before any command runs
        return int(args.func(args))
    except ScenarioError as err:
        print(f"granplate: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # pragma: no cover
        print("granplate: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
