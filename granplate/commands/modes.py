"""`granplate modes SCENARIO [--count N] [--json FILE] [--figure FILE]`: the linear modes of
an assembly about its static state (docs/model.md section 3.13, `results.modes`): the
frequencies [Hz] printed, the numbers as JSON (`{"frequencies": [...], ...}`), the lowest
modes drawn."""

from __future__ import annotations

import json

from granplate.figures.cli import add_set_option


def piston_fraction(modes):
    """Each mode's share of its kinetic energy in the pistons [-]: sum M s^2 of its
    M-orthonormal shape (zeros without a piston)."""
    import numpy as np

    if not modes.pistons.shape[1]:
        return np.zeros(len(modes.frequencies))
    return np.sum(modes.piston_mass[None, :] * modes.pistons**2, axis=1)


def granule_fraction(modes):
    """Each mode's share of its kinetic energy in the granules [-] (the rest in the plate, or
    a 3D scenario's elastic solid, and the pistons): sum m u^2 of its M-orthonormal shape, 1 - |q|^2 - sum M s^2."""
    import numpy as np

    plate = np.sum(modes.plate**2, axis=1) if modes.plate.shape[1] else 0.0
    return 1.0 - plate - piston_fraction(modes)


def modes_record(modes, wall_labels=()) -> dict:
    """The JSON of a Modes: frequencies [Hz], zero_modes, contacts; coupled to the plane's
    plate or a 3D scenario's elastic solid (its [plate]) also plate_modes (how many of its
    modal coordinates) and granule_fraction (each mode's share of kinetic energy in the
    granules, the rest in the plate or solid and the pistons); with pistons (force-driven or held walls, each a
    degree of freedom) `pistons` (each one's wall, by its label in `wall_labels` where given,
    and mass [kg]), piston_fraction (each mode's share of kinetic energy in them) and
    granule_fraction."""
    record = {
        "frequencies": [float(f) for f in modes.frequencies],
        "zero_modes": modes.zero_modes,
        "contacts": modes.contacts,
        "units": {"frequencies": "Hz"},
    }
    if modes.plate.shape[1]:
        record["plate_modes"] = int(modes.plate.shape[1])
    if modes.pistons.shape[1]:
        labels = list(wall_labels)
        record["pistons"] = [
            {"wall": labels[w] if w < len(labels) else int(w), "mass": float(m)}
            for w, m in zip(modes.piston_walls, modes.piston_mass)
        ]
        record["piston_fraction"] = [float(v) for v in piston_fraction(modes)]
        record["units"]["piston_fraction"] = "-"
        record["units"]["pistons.mass"] = "kg"
    if modes.plate.shape[1] or modes.pistons.shape[1]:
        record["granule_fraction"] = [float(v) for v in granule_fraction(modes)]
        record["units"]["granule_fraction"] = "-"
    return record


def _cmd_modes(args) -> int:
    from granplate.model.arrays import build_model
    from granplate.results.modes import linear_modes
    from granplate.setup.io import load_scenario, parse_settings

    s = load_scenario(args.scenario, parse_settings(args.settings))
    model = build_model(s)
    modes = linear_modes(model, args.count)
    nonzero = modes.frequencies[modes.frequencies > 0.0]
    print(
        f"{s.name}: {len(modes.frequencies)} modes, {modes.zero_modes} without stiffness (free directions), "
        f"{modes.contacts} contacts in touch"
    )
    labels = [w.label or str(k + 1) for k, w in enumerate(model.scenario.walls)]  # the resolved walls
    if modes.pistons.shape[1]:
        named = ", ".join(f"wall {labels[w]} ({m:.4g} kg)" for w, m in zip(modes.piston_walls, modes.piston_mass))
        print(f"pistons moving with the granules: {named}")
    if modes.plate.shape[1] or modes.pistons.shape[1]:
        share = granule_fraction(modes)[modes.frequencies > 0.0]
        body = "solid" if modes.shapes.shape[2] == 3 else "plate"  # a 3D scenario's [plate] is an elastic solid
        where = f"coupled to the {body}'s {modes.plate.shape[1]} modes; " if modes.plate.shape[1] else ""
        print(f"{where}the granules' share of each mode's kinetic energy:")
        for k, (f, e) in enumerate(zip(nonzero, share)):
            print(f"{k + 1:6d} {f:14.6g} Hz {e:10.3g}")
    else:
        for k, f in enumerate(nonzero):
            print(f"{k + 1:6d} {f:14.6g} Hz")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(modes_record(modes, labels), fh, indent=1)
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
