"""Command line: `granplate run | presets | preset`.

A user's mistake (bad scenario, unknown preset, missing file) prints one clear line and
exits with status 2, never a traceback; a run that goes numerically wrong prints why,
keeps what it computed (written to -o) and exits with status 3.
"""
from __future__ import annotations

import argparse
import importlib
import json
import sys
from pathlib import Path

from granplate.errors import ScenarioError, SimulationError

#: modules that add subcommands: each defines register(subparsers), adding parsers whose
#: `func(args) -> int` runs the command (ScenarioError is reported as a user error).
COMMAND_MODULES = (
    "granplate.paper.reproduce",     # reproduce, plot, animate, export
    "granplate.verification",   # verify
    "granplate.bench.cli",      # bench
)

SUMMARY_ROWS = (
    ("e_shock", "E_shock", "J", "{:.4e}"),
    ("ep_max_fraction", "plate energy, peak / E_shock", "-", "{:.4f}"),
    ("ep_final_fraction", "plate energy, final / E_shock", "-", "{:.4f}"),
    ("eg_max_fraction", "granular energy, peak / E_shock", "-", "{:.4f}"),
    ("eg_final_fraction", "granular energy, final / E_shock", "-", "{:.4f}"),
    ("dissipated_fraction", "dissipated, final / E_shock", "-", "{:.4f}"),
    ("max_von_mises", "max von Mises stress", "MPa", "{:.2f}"),
    ("max_eps_yy", "max |eps_yy|", "-", "{:.3e}"),
    ("energy_residual_max", "max |energy residual|", "-", "{:.2e}"),
    ("n_steps", "time steps", "-", "{:d}"),
    ("wall_time_s", "wall time", "s", "{:.2f}"),
)


def format_summary(summary: dict) -> str:
    """The summary as an aligned text table (stresses in MPa)."""
    lines = [f"{'quantity':34s} {'value':>14s}  unit", "-" * 56]
    for key, label, unit, fmt in SUMMARY_ROWS:
        v = summary[key]
        if key == "max_von_mises":
            v = v / 1e6
        lines.append(f"{label:34s} {fmt.format(v):>14s}  {unit}")
    return "\n".join(lines)


def _cmd_run(args) -> int:
    from granplate.results.dataset import summary, write
    from granplate.setup.io import load_scenario
    from granplate.results.run import interrupted, simulate

    scenario = load_scenario(args.scenario)
    out = Path(args.output) if args.output else Path(f"{scenario.name}.nc")
    try:
        ds = simulate(scenario, t_end=args.t_end, progress=not args.quiet)
    except SimulationError as err:
        print(f"granplate: run stopped: {err}", file=sys.stderr)
        if err.result is None:
            return 3
        write(err.result, out)
        print(f"granplate: the result so far is written to {out} (its 'status' attribute says why "
              f"the run stopped)", file=sys.stderr)
        return 130 if interrupted(err.result) else 3
    write(ds, out)
    s = summary(ds)
    print(f"{scenario.name}: {scenario.description}".rstrip(": "))
    print(format_summary(s))
    print(f"result: {out}")
    if args.summary:
        Path(args.summary).write_text(json.dumps(s, indent=2) + "\n")
        print(f"summary: {args.summary}")
    return 0


def _cmd_presets(args) -> int:
    from granplate.setup.presets import preset, preset_names

    for name in preset_names():
        print(f"{name:20s} {preset(name).description}")
    return 0


def _cmd_preset(args) -> int:
    from granplate.setup.presets import preset
    from granplate.setup.io import dumps

    text = dumps(preset(args.name))
    if args.output:
        Path(args.output).write_text(text)
        print(f"written {args.output}")
    else:
        sys.stdout.write(text)
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="granplate", description="Granular media against an elastic plate: shock-mitigation simulator.")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run a scenario file or a preset")
    r.add_argument("scenario", help="a scenario TOML file or a preset name (see 'granplate presets')")
    r.add_argument("-o", "--output", help="result netCDF file (default NAME.nc)")
    r.add_argument("--summary", help="also write the summary as JSON to this file")
    r.add_argument("--t-end", type=float, default=None, help="simulated time [s] (overrides the scenario)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=_cmd_run)
    ps = sub.add_parser("presets", help="list the built-in presets")
    ps.set_defaults(func=_cmd_presets)
    pr = sub.add_parser("preset", help="print a preset as TOML (to edit and run)")
    pr.add_argument("name")
    pr.add_argument("-o", "--output", help="write to this file instead of stdout")
    pr.set_defaults(func=_cmd_preset)
    for module in COMMAND_MODULES:
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as err:  # an optional command module not present
            if err.name != module:
                raise
            continue
        mod.register(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if getattr(args, "t_end", None) is not None and not args.t_end > 0:
        print(f"granplate: error: --t-end = {args.t_end!r}: must be > 0 (seconds)", file=sys.stderr)
        return 2
    try:
        return int(args.func(args))
    except ScenarioError as err:
        print(f"granplate: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # pragma: no cover
        print("granplate: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
