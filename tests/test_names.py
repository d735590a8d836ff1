"""Names that say what they are: durations in readable units, the granules touching a 3D
solid listed before a run, distinct run captions, radius vs diameter in every example.
Truth: unit arithmetic, the examples' own geometry (the last plane of spheres rests on the
plate's face), and the scenarios the runs were made from."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "docs" / "examples").glob("*.toml"))


@pytest.mark.parametrize(
    "seconds, text",
    [(0.1, "100 ms"), (2e-5, "20 µs"), (1.5, "1.5 s"), (1e-3, "1 ms"), (3e-10, "0.3 ns"), (1.25e-4, "125 µs")],
)
def test_durations_are_written_in_the_largest_unit_they_reach(seconds, text):
    """0.1 s is 100 ms (it used to read "1e+05 µs")."""
    from granplate.figures.common import readable_duration

    assert readable_duration(seconds) == text


def test_show_in_space_lists_the_granules_touching_the_plate():
    """3d-fcc-on-plate: its second plane of 8 spheres rests on the plate's face xmin, so
    `show` lists 8 granule-body contacts, each line from a centre to the face (R long)."""
    import matplotlib

    matplotlib.use("Agg")
    from granplate.figures import space
    from granplate.setup.io import load_scenario

    s = load_scenario(ROOT / "docs" / "examples" / "3d-fcc-on-plate.toml")
    a = space.of_scenario(s)
    body = a.segments[[k == "body" for k in a.kinds]]
    assert len(body) == 8
    x_face = s.plate.origin[0]
    assert np.allclose(body[:, 1, 0], x_face) and np.allclose(body[:, 1, 0] - body[:, 0, 0], s.layout.radius)
    labels = [h.get_label() for h in space.legend_handles(a, {"steel": "0.5"}, [])]
    assert "contact granule-body (8)" in labels


def test_show_lists_no_body_contact_for_a_packing_off_the_plate():
    """The same packing moved 1 mm away from the plate touches it nowhere."""
    from granplate.figures import space
    from granplate.setup.io import load_scenario, with_changes

    s = load_scenario(ROOT / "docs" / "examples" / "3d-fcc-on-plate.toml")
    far = with_changes(s, {"plate.origin": [s.plate.origin[0] + 1e-3, *s.plate.origin[1:]]})
    assert "body" not in space.of_scenario(far).kinds


def test_runs_of_one_name_are_told_apart_by_their_contact_law():
    """A preset and its twin with yielding contacts share a name: the caption names the law
    of each (it read "ptfe-r05 (t_end = 2 ms), ptfe-r05 (t_end = 2 ms)")."""
    import xarray as xr

    from granplate.paper.plots import run_labels
    from granplate.setup.io import dumps, with_changes
    from granplate.setup.presets import preset

    def result(s):
        return xr.Dataset(coords={"time": [0.0, 2e-3]}, attrs={"scenario_name": s.name, "scenario_toml": dumps(s)})

    elastic = preset("ptfe-r05")
    plastic = with_changes(elastic, {"contact.normal_law": "thornton"})
    labels = run_labels([result(elastic), result(plastic)])
    assert labels == ["ptfe-r05 (Hertz contacts, t_end = 2 ms)", "ptfe-r05 (Thornton contacts, t_end = 2 ms)"]
    assert run_labels([result(elastic), result(preset("steel-r1"))]) == [
        "ptfe-r05 (t_end = 2 ms)",
        "steel-r1 (t_end = 2 ms)",
    ]


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_example_says_radius_or_diameter(path):
    """Each radius written in an example says in its comment that it is a radius and gives
    the diameter, in mm from the value itself."""
    for line in path.read_text().splitlines():
        m = re.match(r"^\s*(?:\{.*)?\b(radius|R1) = ([0-9.e-]+)", line)
        if m and not line.lstrip().startswith("#"):
            r_mm = float(m.group(2)) * 1e3
            assert "radius" in line.split("#", 1)[1], line
            assert f"diameter {2 * r_mm:g} mm" in line and f"{r_mm:g} mm" in line, line
