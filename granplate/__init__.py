"""granplate: ordered granular media (Hertz, friction, rotations) against a
finite-element plate, driven by a shock.

Data flow: Scenario -> Model (arrays) -> compiled time loop -> xarray Dataset -> figures.

    >>> import granplate as gp
    >>> s = gp.preset("ptfe-r05")
    >>> s = gp.with_changes(s, {"load.q0": 2e4})
    >>> ds = gp.simulate(s, t_end=2e-4)
    >>> gp.summary(ds)["ep_max_fraction"]
"""

from __future__ import annotations

from granplate.version import __version__  # noqa: E402,F401

from granplate.errors import GranplateError, ScenarioError, SimulationError  # noqa: E402
from granplate.setup.materials import LIBRARY, Material  # noqa: E402
import granplate.results.pouring  # noqa: E402,F401  (registers the settling of poured layouts with setup.pouring)
from granplate.setup.scenario import (  # noqa: E402
    Contact,
    Granule,
    Layout,
    Load,
    PairCoefficients,
    Plate,
    Scenario,
    Solver,
    TimeSettings,
    Wall,
)

#: The public API: the names above, and those loaded on first use below.
__all__ = [
    "__version__",
    "GranplateError",
    "ScenarioError",
    "SimulationError",
    "LIBRARY",
    "Material",
    "Contact",
    "Granule",
    "Layout",
    "Load",
    "PairCoefficients",
    "Plate",
    "Scenario",
    "Solver",
    "TimeSettings",
    "Wall",
    "simulate",
    "build_model",
    "preset",
    "preset_names",
    "load_scenario",
    "loads",
    "dumps",
    "load",
    "dump",
    "with_changes",
    "write",
    "read",
    "summary",
]


def __getattr__(name: str):
    # heavy modules (numba, scikit-fem, xarray) load on first use
    if name in ("simulate",):
        from granplate.results.run import simulate

        return simulate
    if name in ("build_model",):
        from granplate.model.arrays import build_model

        return build_model
    if name in ("preset", "preset_names"):
        from granplate.setup import presets

        return getattr(presets, name)
    if name in ("load_scenario", "loads", "dumps", "load", "dump", "with_changes"):
        from granplate.setup import io as scenario_io

        return getattr(scenario_io, name)
    if name in ("write", "read", "summary"):
        from granplate.results import dataset

        return getattr(dataset, name)
    raise AttributeError(f"module 'granplate' has no attribute {name!r}")
