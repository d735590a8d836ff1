"""`granplate modes SCENARIO [--count N] [--json FILE] [--figure FILE]`: the linear modes of
an assembly about its static state (docs/model.md section 3.13, `results.modes`): the
frequencies [Hz] printed, the numbers as JSON (`{"frequencies": [...], ...}`), the lowest
modes drawn."""

from __future__ import annotations

import json

from granplate.figures.cli import add_set_option


def granule_fraction(modes):
    """Each mode's share of its kinetic energy in the granules [-] (the rest in the plate):
    sum m u^2 of its M-orthonormal shape, 1 - |q|^2."""
    import numpy as np

    return 1.0 - np.sum(modes.plate**2, axis=1)


def modes_record(modes) -> dict:
    """The JSON of a Modes: frequencies [Hz], zero_modes, contacts; coupled to the plane's
    plate also plate_modes (the plate's modal coordinates) and granule_fraction (each mode's
    share of kinetic energy in the granules)."""
    record = {
        "frequencies": [float(f) for f in modes.frequencies],
        "zero_modes": modes.zero_modes,
        "contacts": modes.contacts,
        "units": {"frequencies": "Hz"},
    }
    if modes.plate.shape[1]:
        record["plate_modes"] = int(modes.plate.shape[1])
        record["granule_fraction"] = [float(v) for v in granule_fraction(modes)]
        record["units"]["granule_fraction"] = "-"
    return record


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
    if modes.plate.shape[1]:
        share = granule_fraction(modes)[modes.frequencies > 0.0]
        print(
            f"coupled to the plate's {modes.plate.shape[1]} modes; the granules' share of each mode's kinetic energy:"
        )
        for k, (f, e) in enumerate(zip(nonzero, share)):
            print(f"{k + 1:6d} {f:14.6g} Hz {e:10.3g}")
    else:
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
