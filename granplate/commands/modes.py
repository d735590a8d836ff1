"""`granplate modes SCENARIO [--count N] [--json FILE] [--figure FILE]`: the linear modes of
an assembly about its static state (docs/model.md section 3.13, `results.modes`): the
frequencies [Hz] printed, the numbers as JSON (`{"frequencies": [...], ...}`), the lowest
modes drawn."""

from __future__ import annotations

import json

from granplate.figures.cli import add_set_option


def modes_record(modes) -> dict:
    """The JSON of a Modes: frequencies [Hz], zero_modes, contacts."""
    return {
        "frequencies": [float(f) for f in modes.frequencies],
        "zero_modes": modes.zero_modes,
        "contacts": modes.contacts,
        "units": {"frequencies": "Hz"},
    }


def _cmd_modes(args) -> int:
    from granplate.model.arrays import build_model
    from granplate.results.modes import linear_modes
    from granplate.setup.io import load_scenario, parse_settings

    s = load_scenario(args.scenario, parse_settings(args.settings))
    modes = linear_modes(build_model(s), args.count)
    nonzero = modes.frequencies[modes.frequencies > 0.0]
    print(
        f"{s.name}: {len(modes.frequencies)} modes, {modes.zero_modes} without stiffness (free directions), "
        f"{modes.contacts} contacts in touch"
    )
    for k, f in enumerate(nonzero):
        print(f"{k + 1:6d} {f:14.6g} Hz")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(modes_record(modes), fh, indent=1)
        print(f"written {args.json}")
    if args.figure:
        from granplate.figures.modes import draw_modes

        fig = draw_modes(modes, s.name)
        fig.savefig(args.figure, dpi=120)
        print(f"written {args.figure}")
    return 0


def register(sub) -> None:
    """Add the `modes` subcommand."""
    p = sub.add_parser("modes", help="the linear modes of an assembly about its static state (frequencies in Hz)")
    p.add_argument("scenario", help="a scenario TOML file or a preset name")
    p.add_argument("--count", type=int, default=None, help="only the lowest N modes")
    p.add_argument("--json", help='write {"frequencies": [...], ...} to this file')
    p.add_argument("--figure", help="draw the frequencies and the lowest mode shapes to this PNG/PDF")
    add_set_option(p)
    p.set_defaults(func=_cmd_modes)
