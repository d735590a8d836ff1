"""Gravity and drives (docs/model.md section 3.11) against closed forms: free fall and an
undamped bounce, Hertz's law at the overlap of a sphere squeezed by a moving wall and of
a sphere pair compressed by a velocity table, the recorded drive and wall forces equal to
the contact forces, eq. (11)'s balance with gravity and drives at every step; bad input
refused naming the field."""

from __future__ import annotations

import math

import numpy as np
import pytest

import granplate as gp
from granplate.errors import ScenarioError
from granplate.setup.io import dumps, from_dict, loads
from granplate.setup.materials import LIBRARY
from granplate.setup.presets import preset
from granplate.setup.validate import validate

R = 0.005
G = 9.81


def _steel():
    return LIBRARY["steel"]


def hertz_wall(r: float) -> float:
    """A = 4/3 E* sqrt(R) of a steel sphere on a rigid wall [N/m^1.5] (eq. 2)."""
    m = _steel()
    return 4.0 / 3.0 * m.E / (1.0 - m.nu**2) * math.sqrt(r)


def hertz_pair(r: float) -> float:
    """A = 4/3 E* sqrt(R*) of two equal steel spheres, E* = E / (2 (1 - nu^2)), R* = R/2."""
    m = _steel()
    return 4.0 / 3.0 * m.E / (2.0 * (1.0 - m.nu**2)) * math.sqrt(r / 2.0)


def base(**extra) -> dict:
    """A frictionless, undamped plane scenario without a load (extra: top-level tables)."""
    d = {
        "name": "drives",
        "load": {"kind": "none"},
        "contact": {"mu": 0.0, "alpha_n": 0.0, "pairs": []},
        "time": {"t_end": 2e-4, "dt_max": 1e-7, "dt_initial": 1e-7, "output_interval": 1e-5, "field_interval": 1e-5},
        "solver": {"scheme": "verlet"},
    }
    d.update(extra)
    return d


def test_free_fall_and_undamped_bounce_under_gravity():
    """Free fall y = y0 - g t^2 / 2 (closed form) until the ball touches the floor; without
    damping it bounces back to its starting height (energy conserved), and eq. (11) with
    gravity's work holds at every step."""
    gap = 2e-4
    d = base(
        granules=[{"label": "ball", "x": 0.0, "y": R + gap, "radius": R, "material": "steel"}],
        walls=[{"label": "floor", "normal": [0.0, -1.0], "offset": 0.0}],
        gravity={"g": [0.0, -G]},
    )
    t_fall = math.sqrt(2.0 * gap / G)
    d["time"].update(t_end=2.0 * t_fall + 2e-4, output_interval=5e-5, field_interval=5e-5, dt_max=2e-7, dt_initial=2e-7)
    ds = gp.simulate(from_dict(d))
    t, y = ds.time.values, ds.y.values[:, 0]
    free = t < 0.95 * t_fall
    np.testing.assert_allclose(y[free], R + gap - 0.5 * G * t[free] ** 2, rtol=0, atol=1e-12)
    assert y[t > 1.5 * t_fall].max() == pytest.approx(R + gap, abs=1e-4 * gap)
    assert float(np.abs(ds.energy_residual_max).max()) < 1e-4
    # gravity's work is the fall's kinetic energy while the ball flies
    m = float(ds.mass[0])
    np.testing.assert_allclose(ds.E_gravity.values[free], 0.5 * m * (G * t[free]) ** 2, rtol=1e-9)


def squeeze(scheme: str):
    """A sphere resting on the floor, a top wall moved down at 0.01 m/s from 0.1 um above it
    (steps of 20 ns: the squeezed sphere rings against two stiffening contacts)."""
    top = 2.0 * R + 1e-7
    d = base(
        granules=[{"label": "s", "x": 0.0, "y": R, "radius": R, "material": "steel"}],
        walls=[
            {"label": "floor", "normal": [0.0, -1.0], "offset": 0.0},
            {"label": "top", "normal": [0.0, 1.0], "offset": top},
        ],
        drives=[
            {"target": "wall top", "kind": "velocity", "direction": [0.0, -1.0], "profile": "constant", "value": 0.01}
        ],
    )
    d["solver"]["scheme"] = scheme
    d["time"].update(output_interval=1e-6, field_interval=1e-6, dt_max=2e-8, dt_initial=2e-8)
    if scheme == "implicit":
        d["solver"]["implicit_dt_max"] = 2e-8
    return gp.simulate(from_dict(d)), top


@pytest.mark.parametrize("scheme", ["verlet", "implicit", "paper"])
def test_wall_moved_into_a_sphere_gives_hertz_at_the_overlap(scheme):
    """The moving wall's position is offset - v t (the prescribed motion); its force and
    the floor's equal Hertz's A delta^1.5 at their overlaps (wall_force is the contact
    force sum), the drive's force is the top wall's (pushing along its direction), and the
    drive's work keeps eq. (11)."""
    ds, top = squeeze(scheme)
    t = ds.time.values
    np.testing.assert_allclose(ds.drive_displacement.values[:, 0], 0.01 * t, rtol=1e-12, atol=1e-18)
    y = ds.y.values[:, 0]
    a = hertz_wall(R)
    d_top = np.maximum(y + R - (top - 0.01 * t), 0.0)
    d_floor = np.maximum(R - y, 0.0)
    wf = ds.wall_force.sel(wall="top").values
    assert wf.max() > 1.0  # squeezed
    np.testing.assert_allclose(wf, a * d_top**1.5, rtol=1e-9, atol=1e-9 * wf.max())
    np.testing.assert_allclose(
        ds.wall_force.sel(wall="floor").values, a * d_floor**1.5, rtol=1e-9, atol=1e-9 * wf.max()
    )
    np.testing.assert_allclose(ds.drive_force.values[:, 0], wf, rtol=1e-12, atol=1e-12 * wf.max())
    assert float(np.abs(ds.energy_residual_max).max()) < 1e-4
    # the drive's work: int F v dt from the recorded force (trapezoid over the outputs)
    work = np.concatenate([[0.0], np.cumsum(0.5 * (wf[1:] + wf[:-1]) * np.diff(t))]) * 0.01
    assert float(ds.E_drive[-1]) == pytest.approx(work[-1], rel=1e-2)


def pair(dimension: int, table_v: float = 0.05, scheme: str = "verlet"):
    """Two equal steel spheres touching along x: A held (velocity 0), B pushed towards A by
    a velocity table (0 -> table_v over 20 us, held to 120 us, back to 0 at 140 us)."""
    z = {"z": 0.0} if dimension == 3 else {}
    vec = lambda *c: list(c[:dimension])
    d = base(
        granules=[
            {"label": "A", "x": 0.0, "y": 0.0, "radius": R, "material": "steel", **z},
            {"label": "B", "x": 2.0 * R, "y": 0.0, "radius": R, "material": "steel", **z},
        ],
        drives=[
            {
                "target": "granule A",
                "kind": "velocity",
                "direction": vec(1.0, 0.0, 0.0),
                "profile": "constant",
                "value": 0.0,
            },
            {
                "target": "granule B",
                "kind": "velocity",
                "direction": vec(-1.0, 0.0, 0.0),
                "profile": "table",
                "times": [0.0, 2e-5, 1.2e-4, 1.4e-4],
                "values": [0.0, table_v, table_v, 0.0],
            },
        ],
    )
    if dimension == 3:
        d["dimension"] = 3
        d["time"]["t_end"] = 1.6e-4
    else:
        d["time"]["t_end"] = 1.6e-4
    d["time"]["output_interval"] = 2e-6
    d["time"]["field_interval"] = 2e-6
    d["solver"].update(scheme=scheme, implicit_dt_max=1e-7)
    return gp.simulate(from_dict(d))


def table_displacement(t: np.ndarray, v: float) -> np.ndarray:
    """The integral of the velocity table of `pair` [m] (closed form)."""
    return np.where(
        t < 2e-5,
        0.5 * v * t**2 / 2e-5,
        np.where(
            t < 1.2e-4,
            v * (t - 1e-5),
            np.where(t < 1.4e-4, v * 1.2e-4 - 0.5 * v * (1.4e-4 - t) ** 2 / 2e-5, v * 1.2e-4),
        ),
    )


@pytest.mark.parametrize("dimension, scheme", [(2, "verlet"), (3, "verlet"), (2, "implicit")])
def test_sphere_pair_compressed_by_a_velocity_table(dimension, scheme):
    """The pushed sphere's displacement is the table's integral; the held one stays put;
    the held sphere's drive force is the contact force on it, Hertz's A delta^1.5 at the
    overlap delta = B's displacement, and the pushing drive's is that plus m a (its
    acceleration, v / 20 us on the ramps); eq. (11) holds with the drives' work."""
    v = 0.05
    ds = pair(dimension, v, scheme)
    t = ds.time.values
    s_b = ds.drive_displacement.sel(drive="granule B").values
    # (to within a h^2 per corner of the table: a step's end may fall a round-off short of a corner)
    np.testing.assert_allclose(s_b, table_displacement(t, v), rtol=0, atol=3 * (v / 2e-5) * 1e-7**2)
    np.testing.assert_allclose(ds.drive_displacement.sel(drive="granule A").values, 0.0, atol=1e-15)
    xyz = np.stack([ds[c].values for c in ("x", "y", "z")[:dimension]], axis=-1)
    overlap = np.maximum(2.0 * R - np.linalg.norm(xyz[:, 1] - xyz[:, 0], axis=-1), 0.0)
    n = hertz_pair(R) * overlap**1.5
    f_a = ds.drive_force.sel(drive="granule A").values
    assert f_a.max() > 10.0
    np.testing.assert_allclose(f_a, n, rtol=1e-6, atol=1e-6 * n.max())
    accel = np.where(t < 2e-5, v / 2e-5, np.where(t < 1.2e-4, 0.0, np.where(t < 1.4e-4, -v / 2e-5, 0.0)))
    m = float(ds.mass[1])
    inner = np.min(np.abs(t[:, None] - np.array([0.0, 2e-5, 1.2e-4, 1.4e-4])[None, :]), axis=1) > 1e-6
    np.testing.assert_allclose(
        ds.drive_force.sel(drive="granule B").values[inner], (n + m * accel)[inner], rtol=1e-6, atol=1e-6 * n.max()
    )
    assert float(np.abs(ds.energy_residual_max).max()) < 1e-4
    # all the work the drives did is stored in the contact once B stops: 2/5 A delta^2.5 at the
    # recorded overlap, to within the run's energy tolerance
    assert float(ds.E_drive[-1]) == pytest.approx(0.4 * hertz_pair(R) * overlap[-1] ** 2.5, rel=1e-4)


def test_force_drive_pushes_a_free_granule():
    """A constant force F on a free granule: x = F t^2 / (2 m), and its work F x is the
    drive's (E_drive)."""
    d = base(
        granules=[{"label": "p", "x": 0.0, "y": 0.0, "radius": R, "material": "steel"}],
        drives=[{"target": "granule p", "kind": "force", "direction": [0.6, 0.8], "profile": "constant", "value": 2.0}],
    )
    ds = gp.simulate(from_dict(d))
    t, m = ds.time.values, float(ds.mass[0])
    s = 2.0 * t**2 / (2.0 * m)
    np.testing.assert_allclose(ds.drive_displacement.values[:, 0], s, rtol=1e-9, atol=1e-18)
    np.testing.assert_allclose(ds.x.values[:, 0], 0.6 * s, rtol=1e-9, atol=1e-18)
    np.testing.assert_allclose(ds.E_drive.values, 2.0 * s, rtol=1e-9, atol=1e-18)
    np.testing.assert_allclose(ds.drive_force.values[:, 0], 2.0)


def test_scenario_with_drives_round_trips_and_reads_a_csv_table(tmp_path):
    """Gravity and drives survive TOML writing and reading; a table from a CSV file equals
    the inline one; a scenario without them is written as before (no new keys)."""
    d = base(
        granules=[{"label": "a", "x": 0.0, "y": R, "radius": R, "material": "steel"}],
        walls=[{"label": "floor", "normal": [0.0, -1.0], "offset": 0.0}],
        gravity={"g": [0.0, -G]},
        drives=[
            {
                "target": "granule a",
                "kind": "displacement",
                "direction": [1.0, 0.0],
                "profile": "table",
                "times": [0.0, 1e-4],
                "values": [0.0, 1e-6],
            }
        ],
    )
    s = from_dict(d)
    assert loads(dumps(s)) == s
    (tmp_path / "t.csv").write_text("time,value\n0,0\n1e-4,1e-6\n")
    d2 = {**d, "drives": [{**d["drives"][0], "times": None, "values": None, "file": "t.csv"}]}
    d2["drives"][0] = {k: v for k, v in d2["drives"][0].items() if v is not None}
    assert from_dict(d2, base=tmp_path).drives == s.drives
    plain = dumps(from_dict(base(granules=d["granules"])))
    assert "[gravity]" not in plain and "[[drives]]" not in plain


BAD = [
    (
        {"drives": [{"target": "wall roof", "kind": "velocity", "direction": [0.0, -1.0], "profile": "constant"}]},
        "drives[0].target",
    ),
    (
        {"drives": [{"target": "granule zz", "kind": "velocity", "direction": [1.0, 0.0], "profile": "constant"}]},
        "drives[0].target",
    ),
    (
        {"drives": [{"target": "piston a", "kind": "velocity", "direction": [1.0, 0.0], "profile": "constant"}]},
        "drives[0].target",
    ),
    (
        {
            "drives": [
                {
                    "target": "granule a",
                    "kind": "velocity",
                    "direction": [1.0, 0.0],
                    "profile": "table",
                    "times": [0.0, 2e-5, 1e-5],
                    "values": [0.0, 1.0, 0.0],
                }
            ]
        },
        "drives[0].times",
    ),
    (
        {
            "drives": [
                {
                    "target": "granule a",
                    "kind": "velocity",
                    "direction": [1.0, 0.0],
                    "profile": "table",
                    "times": [0.0, 1e-5],
                    "values": [0.0],
                }
            ]
        },
        "drives[0].times",
    ),
    (
        {
            "drives": [
                {
                    "target": "granule a",
                    "kind": "force",
                    "direction": [1.0, 0.0],
                    "profile": "harmonic",
                    "amplitude": 1.0,
                    "frequency": 1e9,
                }
            ]
        },
        "drives[0].frequency",
    ),
    (
        {
            "drives": [
                {
                    "target": "granule a",
                    "kind": "force",
                    "direction": [1.0, 0.0],
                    "profile": "harmonic",
                    "amplitude": 1.0,
                    "frequency": 0.0,
                }
            ]
        },
        "drives[0].frequency",
    ),
    (
        {
            "drives": [
                {
                    "target": "granule a",
                    "kind": "displacement",
                    "direction": [1.0, 0.0],
                    "profile": "harmonic",
                    "amplitude": 1.0,
                    "frequency": 1e5,
                }
            ]
        },
        "drives[0].amplitude",
    ),
    (
        {
            "drives": [
                {
                    "target": "granule a",
                    "kind": "velocity",
                    "direction": [1.0, 0.0],
                    "profile": "half-sine",
                    "amplitude": 1e4,
                    "duration": 1e-5,
                }
            ]
        },
        "drives[0].amplitude",
    ),
    (
        {"drives": [{"target": "granule a", "kind": "velocity", "direction": [1.0, 1.0], "profile": "constant"}]},
        "drives[0].direction",
    ),
    (
        {"drives": [{"target": "granule a", "kind": "velocity", "direction": [1.0, 0.0, 0.0], "profile": "constant"}]},
        "drives[0].direction",
    ),
    (
        {"drives": [{"target": "wall floor", "kind": "force", "direction": [0.0, -1.0], "profile": "constant"}]},
        "drives[0].mass",
    ),
    (
        {"drives": [{"target": "wall floor", "kind": "velocity", "direction": [1.0, 0.0], "profile": "constant"}]},
        "drives[0].direction",
    ),
    (
        {
            "drives": [
                {"target": "granule a", "kind": "velocity", "direction": [1.0, 0.0], "profile": "ramp", "value": 0.1}
            ]
        },
        "drives[0].duration",
    ),
    (
        {
            "drives": [
                {
                    "target": "granule a",
                    "kind": "velocity",
                    "direction": [1.0, 0.0],
                    "profile": "constant",
                    "frequency": 10.0,
                }
            ]
        },
        "drives[0].frequency",
    ),
    (
        {
            "drives": [
                {"target": "granule a", "kind": "velocity", "direction": [1.0, 0.0], "profile": "constant"},
                {"target": "granule a", "kind": "force", "direction": [0.0, 1.0], "profile": "constant"},
            ]
        },
        "drives[1].target",
    ),
    (
        {"drives": [{"target": "granule a", "kind": "speed", "direction": [1.0, 0.0], "profile": "constant"}]},
        "drives[0].kind",
    ),
    (
        {
            "drives": [
                {
                    "target": "granule a",
                    "kind": "velocity",
                    "direction": [1.0, 0.0],
                    "profile": "table",
                    "file": "no-such-file.csv",
                }
            ]
        },
        "drives[0].file",
    ),
    ({"gravity": {"g": [0.0, -9.81, 0.0]}}, "gravity.g"),
    ({"gravity": {"g": [0.0, math.inf]}}, "gravity.g"),
]


@pytest.mark.parametrize("extra, field", BAD, ids=[f for _, f in BAD])
def test_bad_drive_or_gravity_refused_naming_the_field(extra, field):
    """Each bad [[drives]] or [gravity] entry is refused before anything runs, naming it."""
    d = base(
        granules=[{"label": "a", "x": 0.0, "y": R, "radius": R, "material": "steel"}],
        walls=[{"label": "floor", "normal": [0.0, -1.0], "offset": 0.0}],
        **extra,
    )
    with pytest.raises(ScenarioError) as e:
        validate(from_dict(d))
    assert e.value.field == field, str(e.value)


def test_gravity_with_the_planes_plate_accepted():
    """Gravity with the plane's plate validates (the plate carries its own weight, docs/model.md
    section 3.11; a 3D plate with gravity is refused: tests/test_gravity_plate.py)."""
    from granplate.setup.io import to_dict

    d = to_dict(preset("ptfe-r05"))
    d["gravity"] = {"g": [0.0, -9.81]}
    validate(from_dict(d))


def test_driven_chain_example_runs():
    """docs/examples/driven-chain.toml (a chain under gravity pressed by a piston) runs with
    eq. (11) holding; the piston's drive force is the normal force the piston receives
    (it moves against its outward normal), and its displacement the half-sine."""
    from pathlib import Path

    from granplate.setup.io import load_scenario, with_changes

    s = load_scenario(str(Path(__file__).resolve().parents[1] / "docs" / "examples" / "driven-chain.toml"))
    ds = gp.simulate(with_changes(s, {"time.t_end": 1e-4, "time.output_interval": 5e-6, "time.field_interval": 5e-6}))
    assert float(np.abs(ds.energy_residual_max).max()) < 1e-4
    piston = ds.wall_force.sel(wall="xmax").values
    assert piston.max() > 1.0
    np.testing.assert_allclose(ds.drive_force.values[:, 0], piston, rtol=1e-12, atol=1e-12 * piston.max())
    t = ds.time.values
    np.testing.assert_allclose(ds.drive_displacement.values[:, 0], 2e-6 * np.sin(np.pi * t / 1e-4), rtol=0, atol=1e-18)
    from granplate.figures import run as figures

    fig = figures.figures(ds)["wall-forces"]
    drawn = [ln.get_ydata() for ln in fig.axes[0].get_lines()]
    np.testing.assert_array_equal(drawn[list(ds.wall.values).index("xmax")], piston)


def test_bad_numbers_in_drives_and_gravity_refused_by_name():
    """NaN, infinity or a string in any number of [gravity] or [[drives]] is refused before
    anything runs, in one line naming the field (or its list: drives[1].times for
    drives[1].times[2])."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from field_paths import mutated, numeric_fields

    d = base(
        granules=[{"label": "a", "x": 0.0, "y": R, "radius": R, "material": "steel"}],
        walls=[{"label": "floor", "normal": [0.0, -1.0], "offset": 0.0}],
        gravity={"g": [0.0, -G]},
        drives=[
            {
                "target": "granule a",
                "kind": "force",
                "direction": [1.0, 0.0],
                "profile": "harmonic",
                "value": 1.0,
                "amplitude": 0.5,
                "frequency": 1e4,
            },
            {
                "target": "wall floor",
                "kind": "velocity",
                "direction": [0.0, 1.0],
                "profile": "table",
                "times": [0.0, 1e-5, 2e-5],
                "values": [0.0, -0.01, 0.0],
            },
        ],
    )
    validate(from_dict(d))
    paths = [p for p in numeric_fields(d) if p.startswith(("drives", "gravity"))]
    assert len(paths) >= 15
    for path in paths:
        for value in (math.nan, math.inf, "x"):
            with pytest.raises(ScenarioError) as e:
                validate(from_dict(mutated(d, path, value)))
            msg = str(e.value)
            assert path.split("[")[0] in msg and "\n" not in msg, (path, msg)
            assert e.value.field in (path, path.rsplit("[", 1)[0]), (path, msg)
