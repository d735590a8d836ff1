"""A result's granules as the start of a new scenario (docs/scenario.md, "granules_file").

`seeded_scenario(ds, time=-1)`: the scenario the result `ds` was made from (resolved, its
`scenario_toml`), its granules moved to their centres, velocities and spins at one output
time (by default the last); radii, materials and labels are the result's, and so is
everything else (walls, plate, load, contact, time, solver). Only the granules carry
over: the plate or elastic body starts undeformed and at rest, the contacts' histories
(the largest overlap of a yielding contact) start afresh, and a 2D granule's rotation
angle (theta) is not part of a scenario. Granules that overlap at that time are refused
by `validate` as any scenario's (they may touch but not overlap at t = 0): seed from a
time when they are apart, or let them part first.

`granules_at(ds, time=-1)`: those granules alone, for `setup.granules_file.write_granules`
(`granplate resolve RESULT.nc --granules-file FILE` writes them with the scenario).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from granplate.setup.scenario import Granule, Scenario


def _row(ds, name: str, time: int) -> list[float]:
    return np.asarray(ds[name].values[time], float).tolist()


def granules_at(ds, time: int = -1) -> tuple[Granule, ...]:
    """The result's granules at output time index `time` (default: the last): centres,
    velocities and spins from the Dataset, radius, material and label from its scenario."""
    from granplate.model.dimension import of_number
    from granplate.results.dataset import scenario_of
    from granplate.setup.geometry import resolve

    s = resolve(scenario_of(ds))
    n = ds.sizes["time"]
    if not -n <= time < n:
        raise IndexError(f"output time index {time} out of range: the result has {n} output times")
    dim = of_number(s.dimension)
    rows = [_row(ds, k, time) for k in dim.positions]
    zero = [0.0] * len(rows[0])  # z and vz beyond the plane's
    centre = dict(zip(("x", "y", "z"), rows + [zero]))
    velocity = dict(zip(("vx", "vy", "vz"), [_row(ds, k, time) for k in dim.velocities] + [zero]))
    spins = [dim.spin(c) for c in zip(*(_row(ds, k, time) for k in dim.spins))]
    return tuple(
        dataclasses.replace(g, **{k: v[i] for k, v in (centre | velocity).items()}, omega=spins[i])
        for i, g in enumerate(s.granules)
    )


def seeded_scenario(ds, time: int = -1) -> Scenario:
    """The result's scenario (resolved) starting from its granules at output time index
    `time` (`granules_at`); not validated (see the module's note on overlaps)."""
    from granplate.results.dataset import scenario_of
    from granplate.setup.geometry import resolve

    s = resolve(scenario_of(ds))
    t = float(ds.time.values[time])
    note = f"; granules from its result at t = {t:.6g} s"
    return dataclasses.replace(s, granules=granules_at(ds, time), description=s.description + note)
