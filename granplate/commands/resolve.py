"""`granplate resolve FILE_OR_PRESET [-o FILE]`: a scenario's explicit [[granules]]/[[walls]] form.

Prints (or writes) the scenario as TOML with its layout expanded by `geometry.resolve`:
every granule and wall written out, `plate.x0` set, labels filled. Running the printed
file builds the same model as the layout.
"""
from __future__ import annotations

from granplate.commands import emit_text
from granplate.figures.cli import add_set_option


def resolved_toml(name_or_path: str, changes: dict | None = None) -> str:
    """The validated scenario `name_or_path` (preset or TOML file, with `changes` by dotted
    path), resolved, as TOML text."""
    from granplate.setup.geometry import resolve
    from granplate.setup.io import dumps, load_scenario

    return dumps(resolve(load_scenario(name_or_path, changes)))


def _cmd_resolve(args) -> int:
    from granplate.setup.io import parse_settings

    emit_text(resolved_toml(args.scenario, parse_settings(args.settings)), args.output)
    return 0


def register(sub) -> None:
    """Add the `resolve` subcommand."""
    p = sub.add_parser("resolve", help="print a scenario with its layout written out as "
                       "[[granules]] and [[walls]] (TOML)")
    p.add_argument("scenario", help="a scenario TOML file or a preset name")
    p.add_argument("-o", "--output", help="write to this file instead of stdout")
    add_set_option(p)
    p.set_defaults(func=_cmd_resolve)
