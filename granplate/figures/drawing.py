"""An assembly drawn in either dimension (`granplate show`, a study's design pages): the
plane's `assembly` drawn by `show`, space's by `space`, keyed by the dimension's name
(`model.dimension`) in `DRAWINGS`, the one place the figures choose by dimension.

    >>> from granplate.figures.drawing import result_figure, scenario_figure
    >>> fig, name = scenario_figure(gp.preset("steel-r1"))
    >>> fig, name = result_figure(gp.read("steel-r1.nc"), time=2e-5)
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

import xarray as xr
from matplotlib.figure import Figure

from granplate.figures import assembly, show, space
from granplate.model.dimension import of_number
from granplate.results.dataset import dimension_spec
from granplate.setup.scenario import Scenario


class Drawing(NamedTuple):
    """One dimension's assembly drawing: the assembly of a scenario before its run and of a
    result at a time [s] (None: the module's default), the figure of an assembly at a
    width [in], and the width of a figure in a page's column [in]."""

    of_scenario: Callable[[Scenario], Any]
    of_result: Callable[[xr.Dataset, float | None], Any]
    draw: Callable[[Any, float], Figure]
    column_width: float


#: the drawings by the dimension's name
DRAWINGS: dict[str, Drawing] = {
    "plane": Drawing(assembly.of_scenario, assembly.of_result, show.draw, 5.0),
    "space": Drawing(space.of_scenario, space.of_result, space.draw, 13.0),
}


def scenario_figure(scenario: Scenario, column: bool = False) -> tuple[Figure, str]:
    """The drawing of a scenario before its run and its default file name; `column`: at
    the width of a page's column."""
    d = DRAWINGS[of_number(scenario.dimension).name]
    a = d.of_scenario(scenario)
    return (d.draw(a, d.column_width) if column else d.draw(a)), f"{a.name}.png"


def result_figure(ds: xr.Dataset, time: float | None = None) -> tuple[Figure, str]:
    """The drawing of result `ds` at `time` [s] (None: the drawing's default) and its
    default file name."""
    d = DRAWINGS[dimension_spec(ds).name]
    a = d.of_result(ds, time)
    return d.draw(a), f"{a.name}.png"
