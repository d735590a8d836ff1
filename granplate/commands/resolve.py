"""`granplate resolve FILE_OR_PRESET_OR_RESULT [-o FILE] [--granules-file FILE]`: a
scenario's explicit [[granules]]/[[walls]] form.

Prints (or writes) the scenario as TOML with its layout expanded by `geometry.resolve`:
every granule and wall written out, `plate.x0` set, labels filled. Running the printed
file builds the same model as the layout. `--granules-file F` (.csv, .npz or .nc) writes
the granules to F instead, and the TOML names it (`granules_file`, relative to the TOML
written, or to the working directory when printed). A result (a granplate netCDF file)
gives its scenario with the granules at its last output time (`results.seed`).
"""

from __future__ import annotations

import os

from granplate.commands import emit_text
from granplate.figures.cli import add_set_option


def is_result(path: str) -> bool:
    """Whether `path` is a result file of granplate (a netCDF file, not a scenario or preset)."""
    return os.path.isfile(path) and path.lower().endswith((".nc", ".nc4", ".cdf"))


def resolved_scenario(name_or_path: str, changes: dict | None = None):
    """The validated scenario `name_or_path` (preset, TOML file, or a result's scenario
    seeded by its granules at the last output time; with `changes` by dotted path),
    resolved."""
    from granplate.setup.geometry import resolve
    from granplate.setup.io import load_scenario
    from granplate.setup.validate import validate

    if is_result(name_or_path):
        from granplate.results.dataset import read
        from granplate.results.seed import seeded_scenario

        s = seeded_scenario(read(name_or_path))
        if changes:
            from granplate.setup.io import with_changes

            s = with_changes(s, changes)
        validate(s)
        return s
    return resolve(load_scenario(name_or_path, changes))


def resolved_toml(
    name_or_path: str, granules_file: str | None = None, toml_path: str | None = None, changes: dict | None = None
) -> str:
    """The resolved scenario `name_or_path` (with `changes` by dotted path) as TOML text;
    with `granules_file`, its granules
    written to that file and named by the TOML (relative to the folder of `toml_path`, the
    file the TOML goes to, or else to the working directory)."""
    from granplate.setup.io import dumps, dumps_with_granules_file

    s = resolved_scenario(name_or_path, changes)
    if granules_file is None:
        return dumps(s)
    return dumps_with_granules_file(
        s, granules_file, os.path.dirname(os.path.abspath(toml_path)) if toml_path else None
    )


def _cmd_resolve(args) -> int:
    import sys

    from granplate.setup.io import parse_settings

    text = resolved_toml(args.scenario, args.granules_file, args.output, parse_settings(args.settings))
    if args.granules_file:
        print(f"written {args.granules_file}", file=sys.stdout if args.output else sys.stderr)
    emit_text(text, args.output)
    return 0


def register(sub) -> None:
    """Add the `resolve` subcommand."""
    p = sub.add_parser(
        "resolve", help="print a scenario with its layout written out as [[granules]] and [[walls]] (TOML)"
    )
    p.add_argument(
        "scenario",
        help="a scenario TOML file, a preset name, or a result (.nc: its scenario "
        "with the granules at its last output time)",
    )
    p.add_argument("-o", "--output", help="write to this file instead of stdout")
    add_set_option(p)
    p.add_argument(
        "--granules-file",
        help="write the granules to this file (.csv, .npz or .nc) and name it "
        "in the TOML (granules_file) instead of [[granules]] tables",
    )
    p.set_defaults(func=_cmd_resolve)
