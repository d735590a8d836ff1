"""`granplate bench --solid --coupled`'s pure parts: the scenarios it builds validate and
put the plate where the stack ends, its tables and its choice of cut-off (no run)."""

from __future__ import annotations

import math

import pytest

from granplate.bench import solid_coupled as C
from granplate.setup.validate import validate


def test_protector_validates_and_touches_the_plate():
    """300 spheres of R = 5 mm; the plate's face xmin at the last plane's surfaces, centred on the stack."""
    s = C.protector()
    validate(s)
    assert len(s.granules) == 300
    assert s.plate.origin[0] == pytest.approx(max(g.x + g.radius for g in s.granules))
    ys = [g.y for g in s.granules]
    assert s.plate.origin[1] + 0.5 * C.PLATE_SPAN == pytest.approx(0.5 * (min(ys) + max(ys)))
    assert len(s.load.granules) == 50 and all(label.startswith("x1y") for label in s.load.granules)
    assert s.time.dt_initial == s.time.dt_max == C.DT


def test_sphere_drop_validates_and_touches_the_plate():
    """One sphere whose surface touches the plate's centre at t = 0, moving into it."""
    s = C.sphere_drop(max_frequency=5e4)
    validate(s)
    (g,) = s.granules
    assert g.x + g.radius == pytest.approx(s.plate.origin[0]) and g.vx > 0.0
    assert s.plate.max_frequency == 5e4


def test_spec_names_its_scenario():
    """A row's spec (lists, as JSON has them) builds the scenario it names."""
    s = C.scenario_of(C.spec_of(cells=(3, 1, 1), mesh=(1, 10, 10), t_end=1e-5))
    assert len(s.granules) == 12 and s.plate.elements == (1, 10, 10) and s.time.t_end == 1e-5
    assert C.scenario_of(C.spec_of("drop")).name == "sphere-drop"


def _row(f, share, force, **kw):
    return {
        "case": "drop",
        "max_frequency": f,
        "n_modes": 10,
        "plate_share": share,
        "peak_force_n": force,
        "n_steps": 100,
        "loop_s": 0.5,
        "loop_cpu_s": 0.25,
        **kw,
    }


def test_chosen_cutoff_is_the_lowest_within_on_both():
    """Within 1% on share and force, at this cut-off and every higher one; none when none is."""
    ref = _row(4e5, 0.05, 100.0)
    rows = [_row(5e4, 0.040, 99.9), _row(1e5, 0.0499, 99.5), _row(2e5, 0.04999, 100.2)]
    assert C.chosen_cutoff(rows, ref) == 1e5
    rows[1] = _row(1e5, 0.0499, 97.0)
    assert C.chosen_cutoff(rows, ref) == 2e5
    assert C.chosen_cutoff([_row(5e4, 0.01, 10.0)], ref) is None


def test_tables_format():
    """The cost and cut-off tables: a header, a separator and one line per row."""
    ref = _row(4e5, 0.05, 100.0)
    text = C.format_cutoffs([_row(1e5, 0.0495, 101.0)], ref)
    lines = text.splitlines()
    assert len(lines) == 4 and "| drop | 1e+05 | 10 | 4.950% | -1.00% | 101.00 | +1.00% | 5000 |" in lines
    cost = {
        **_row(1e5, 0.3, 13.0),
        "case": "protector",
        "granules": 300,
        "mesh": [2, 20, 20],
        "n_dofs": 12255,
        "dt": 2e-7,
        "setup_first_s": 9.6,
        "setup_uncached_s": 9.6,
        "setup_cached_s": 0.38,
        "in_touch": 50,
        "energy_residual": 3.5e-5,
    }
    line = C.format_cost([cost, {"case": "protector", "mesh": [2, 40, 40], "failed": "rc 1"}]).splitlines()
    assert (
        "| protector | 300 | 2 x 20 x 20 | 12,255 | 10 | 1e+05 | 2e-07 | 9.6 | 0.38 | 100 | 0.5 | 5000 | 2500 | 50 |"
    ) in line[2]
    assert "rc 1" in line[3]
    assert math.isclose(C.us_per_step(cost), 5000.0)


def test_median_row_of_repeats():
    """Timings are the repeats' median; a failed repeat is reported as it is."""
    rows = [{"loop_s": t, "setup_first_s": 1.0, "setup_cached_s": 0.1, "loop_cpu_s": t} for t in (3.0, 1.0, 2.0)]
    assert C.median_row(rows)["loop_s"] == 2.0
    assert "failed" in C.median_row([{"failed": "x"}, rows[0]])


def test_cli_routes_coupled(monkeypatch):
    """`bench --solid --coupled` runs this module's main."""
    from granplate import cli

    seen = []
    monkeypatch.setattr(C, "main", lambda args: seen.append(args.coupled) or 0)
    assert cli.main(["bench", "--solid", "--coupled"]) == 0
    assert seen == [True]


def test_profile_table_and_route(monkeypatch):
    """The profile's table has a column per sub-pass; `--solid --coupled --profile` runs its main."""
    from granplate import cli
    from granplate.bench import solid_profile as P

    row = {
        "mesh": [2, 20, 20],
        "n_dofs": 12255,
        "n_resid": 1121,
        "n_touch": 50,
        "step_cpu_us": 2341.0,
        **{p + "_us": 10.0 for p in P.PASSES},
    }
    lines = P.format_profile([row]).splitlines()
    assert len(lines) == 3 and lines[0].count("[us]") == len(P.PASSES) + 1
    assert lines[2].startswith("| 2 x 20 x 20 | 12,255 | 1,121 | 50 | 10 |") and lines[2].endswith("| 2,341 |")
    seen = []
    monkeypatch.setattr(P, "main", lambda args: seen.append(args.profile) or 0)
    assert cli.main(["bench", "--solid", "--coupled", "--profile"]) == 0
    assert seen == [True]
