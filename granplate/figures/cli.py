"""`granplate show` and the generic `granplate plot RESULT` (no --figure).

    granplate show steel-r1 -o steel-r1.png          # a preset, before the run
    granplate show my.toml                           # a scenario file
    granplate show ptfe-r05 --set layout.R2_ratio=0.7  # a preset with a field changed
    granplate show steel-r1.nc --time 8e-5 -o t.png  # a result at t = 0.08 ms
    granplate plot steel-r1.nc --out figs            # figs/steel-r1-energies.png, ...

A user's mistake (no such file, --time outside the run) is a ScenarioError: the command
line prints one line and exits with status 2.
"""

from __future__ import annotations

from pathlib import Path

from granplate.errors import ScenarioError
from granplate.figures.common import PNG_DPI, save_figure

#: Suffixes read as a result (anything else: a scenario TOML file or a preset name).
RESULT_SUFFIXES = (".nc", ".nc4", ".netcdf")


def _read_result(path: str):
    from granplate.results.dataset import read

    if not Path(path).is_file():
        raise ScenarioError("result", path, "no such file")
    try:
        return read(path)
    except Exception as err:  # noqa: BLE001 - any unreadable file is the user's to fix
        raise ScenarioError("result", path, f"not a readable netCDF result ({type(err).__name__})") from None


def add_set_option(parser, what: str = "the scenario") -> None:
    """The repeatable `--set PATH=VALUE` option (its texts in `args.settings`)."""
    parser.add_argument(
        "--set",
        dest="settings",
        action="append",
        default=[],
        metavar="PATH=VALUE",
        help=f"change a field of {what} by its dotted path, the value written as in "
        'TOML (load.q0=3e4, layout.intruder_material="steel", '
        "granules[0].vx=1.5); repeatable; checked as the file is",
    )


def show_figure(target: str, time: float | None = None, changes: dict | None = None):
    """The figure of a scenario (TOML file or preset name, with `changes` by dotted path) or
    of a result file at `time` [s]; (figure, default output name)."""
    from granplate.figures.drawing import result_figure, scenario_figure
    from granplate.setup.io import load_scenario

    if Path(target).suffix.lower() in RESULT_SUFFIXES:
        if changes:
            raise ScenarioError("--set", ", ".join(changes), "allowed only with a scenario, not a result file (.nc)")
        return result_figure(_read_result(target), time)
    if time is not None:
        raise ScenarioError("--time", time, "allowed only with a result file (.nc), not a scenario")
    return scenario_figure(load_scenario(target, changes))


def _cmd_show(args) -> int:
    from granplate.setup.io import parse_settings

    fig, default = show_figure(args.target, args.time, parse_settings(args.settings))
    out = Path(args.output) if args.output else Path(default)
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise ScenarioError("-o", str(out), "allowed: a .png, .pdf or .svg file name")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=args.dpi, bbox_inches="tight")
    print(f"written {out}")
    return 0


def result_paths(items: list[str]) -> list[Path]:
    """Result files named directly, or every *.nc in a named directory (sorted)."""
    out = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            found = sorted(p.glob("*.nc"))
            if not found:
                raise ScenarioError("results", item, "a directory without .nc result files")
            out += found
        elif p.is_file():
            out.append(p)
        else:
            raise ScenarioError("result", item, "no such file or directory")
    return out


def plot_results(items: list[str], out_dir: str) -> int:
    """Draw the generic figures of each result into out_dir as NAME-FIGURE.png and .pdf;
    figures a run cannot have are skipped with a printed note, one line per reason
    (`skipped_notes`). Returns the exit status 0."""
    from granplate.figures import run

    for path in result_paths(items):
        ds = _read_result(str(path))
        stem = ds.attrs.get("scenario_name") or path.stem
        skipped = {}
        for name in run.FIGURES:
            why = run.missing(name, ds)
            if why is not None:
                skipped[name] = why
                continue
            for written in save_figure(run.FIGURES[name](ds), out_dir, f"{stem}-{name}"):
                print(f"written {written}")
        for line in skipped_notes(skipped):
            print(f"{path}: {line}")
    return 0


def skipped_notes(skipped: dict[str, str]) -> list[str]:
    """One note per reason of the figures skipped ({figure: why}, in figure order):
    "no stress-strain figure: the run has no plate", "no body-stress, body-contact-forces
    figures: the run has no 3D elastic body"."""
    by_reason: dict[str, list[str]] = {}
    for name, why in skipped.items():
        by_reason.setdefault(why, []).append(name)
    return [f"no {', '.join(names)} figure{'s' if len(names) > 1 else ''}: {why}" for why, names in by_reason.items()]


def _time(text: str) -> float:
    import argparse

    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: must be a time in seconds, e.g. 8e-5") from None


def _dpi(text: str) -> int:
    import argparse

    try:
        v = int(text)
    except ValueError:
        v = 0
    if not 20 <= v <= 1200:
        raise argparse.ArgumentTypeError(f"{text!r}: must be an integer from 20 to 1200 (dots per inch)")
    return v


def register(subparsers) -> None:
    """Add the `show` command."""
    s = subparsers.add_parser("show", help="draw an assembly: a scenario, a preset or a result at one time")
    s.add_argument(
        "target", metavar="SCENARIO_OR_RESULT", help="a scenario TOML file, a preset name, or a result .nc file"
    )
    s.add_argument("-o", "--output", help="image file (.png, .pdf or .svg; default NAME.png)")
    s.add_argument(
        "--time",
        type=_time,
        default=None,
        help="result only: the time shown [s] (default: the largest plate energy, or the largest granular "
        "energy where the plate never moved; a 3D body: its "
        "snapshot of the largest von Mises stress; else the last output)",
    )
    s.add_argument(
        "--dpi", type=_dpi, default=PNG_DPI, help=f"resolution of a .png [dots per inch] (default {PNG_DPI})"
    )
    add_set_option(s, "a scenario")
    s.set_defaults(func=_cmd_show)
