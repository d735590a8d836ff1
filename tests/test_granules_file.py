"""Granules from a file (granules_file: CSV, NPZ, netCDF): the truth is the same scenario
given as [[granules]] tables (equal scenario, the same run bit for bit, the same messages
with the row and column named), and a result's state at its last output time."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.cli import main
from granplate.errors import ScenarioError
from granplate.setup.geometry import resolve
from granplate.setup.granules_file import read_granules, write_granules
from granplate.setup.io import load, load_scenario, loads
from granplate.setup.validate import validate

#: Three steel spheres in space in a box: one flies at the others, spins on every axis.
TABLES_3D = """
name = "three"
dimension = 3
[box]
lower = [0.0, 0.0, 0.0]
upper = [0.05, 0.02, 0.02]
[[granules]]
x = 0.005
y = 0.01
z = 0.01
radius = 0.002
material = "steel"
vx = 1.5
omega = [10.0, -20.0, 30.0]
[[granules]]
x = 0.0095
y = 0.0101
z = 0.0099
radius = 0.0025
material = "ptfe"
label = "b"
[[granules]]
x = 0.02
y = 0.01
z = 0.01
radius = 0.003
material = "steel"
vy = -0.25
vz = 0.125
[solver]
scheme = "verlet"
[time]
t_end = 2e-5
dt_initial = 1e-8
dt_max = 1e-8
output_interval = 1e-6
field_interval = 1e-6
"""
HEAD_3D, _, TAIL_3D = TABLES_3D.partition("[[granules]]")
TAIL_3D = "[solver]" + TAIL_3D.partition("[solver]")[2]

#: Two discs in the plane, the second spinning.
TABLES_2D = """
name = "two"
[[walls]]
normal = [-1.0, 0.0]
offset = 0.0
[[granules]]
x = 0.01
y = 0.01
radius = 0.01
material = "steel"
vx = -0.5
[[granules]]
x = 0.03
y = 0.01
radius = 0.01
material = "steel"
omega = 3.0
label = "spin"
"""


def _with_file(tmp_path, text: str, ext: str, dimension: int) -> str:
    """The scenario `text` with its [[granules]] written to granules.EXT beside the TOML."""
    s = loads(text)
    write_granules(s.granules, tmp_path / f"granules.{ext}", dimension)
    head, _, _ = text.partition("[[granules]]")
    rest = text.partition("[solver]")[2]
    body = head.replace("name = ", f'granules_file = "granules.{ext}"\nname = ', 1)
    return body + ("[solver]" + rest if rest else "")


@pytest.mark.parametrize("ext", ["csv", "npz", "nc"])
@pytest.mark.parametrize("text,dimension", [(TABLES_3D, 3), (TABLES_2D, 2)])
def test_a_file_gives_the_scenario_of_its_tables(tmp_path, ext, text, dimension):
    path = tmp_path / "s.toml"
    path.write_text(_with_file(tmp_path, text, ext, dimension))
    from_file, from_tables = load_scenario(path), loads(text)
    validate(from_tables)
    assert resolve(from_file) == resolve(from_tables)
    if dimension == 2:  # (in 3D a file's row gives its spin vector, resolve a table's default spin 0)
        assert from_file == from_tables
    assert from_file.granules_file == f"granules.{ext}"


@pytest.mark.filterwarnings("ignore::granplate.errors.YieldWarning")  # the PTFE sphere yields: Hertz is timed
def test_a_run_from_a_file_is_the_run_from_tables(tmp_path):
    import granplate as gp

    path = tmp_path / "s.toml"
    path.write_text(_with_file(tmp_path, TABLES_3D, "csv", 3))
    a = gp.simulate(load_scenario(path), progress=False)
    b = gp.simulate(loads(TABLES_3D), progress=False)
    assert a.sizes["time"] == 21 and float(np.abs(a.vx.values[-1] - a.vx.values[0]).max()) > 0.0  # they collided
    for k in ("x", "y", "z", "vx", "vy", "vz", "omega_x", "omega_y", "omega_z", "E_granular"):
        np.testing.assert_array_equal(a[k].values, b[k].values)


def _error(fn) -> ScenarioError:
    with pytest.raises(ScenarioError) as e:
        fn()
    return e.value


def _csv(
    tmp_path, rows: list[str], header="x,y,z,radius,material,label,vx,vy,vz,omega_x,omega_y,omega_z", dimension=3
) -> str:
    (tmp_path / "g.csv").write_text("\n".join([header] + rows) + "\n")
    text = HEAD_3D if dimension == 3 else 'name = "two"\n'
    return text.replace("name = ", 'granules_file = "g.csv"\nname = ', 1) + (TAIL_3D if dimension == 3 else "")


GOOD = [
    "0.005,0.01,0.01,0.002,steel,a,0,0,0,0,0,0",
    "0.0095,0.0101,0.0099,0.0025,ptfe,b,0,0,0,0,0,0",
    "0.02,0.01,0.01,0.003,steel,c,0,0,0,0,0,0",
]


def _bad(row: int, cell: int, value: str) -> list[str]:
    rows = [r.split(",") for r in GOOD]
    rows[row][cell] = value
    return [",".join(r) for r in rows]


@pytest.mark.parametrize(
    "row,cell,value,column,allowed",
    [
        (2, 3, "-0.001", "radius", "must be > 0"),
        (1, 0, "abc", "x", "wrong type: expected a number"),
        (0, 4, "", "material", None),  # missing required cell
        (2, 4, "stel", "material", "unknown material; defined materials are: "),
        (1, 6, "1e9", "vx", "allowed: |vx| < sqrt(E / rho)"),
        (2, 9, "nan", "omega_x", "must be a finite number"),
        (1, 5, "a", "label", "labels must be unique; "),
    ],
)
def test_a_bad_row_is_named_as_its_table_would_be(tmp_path, row, cell, value, column, allowed):
    rows = _bad(row, cell, value)
    (tmp_path / "s.toml").write_text(_csv(tmp_path, rows))
    err = _error(lambda: load_scenario(tmp_path / "s.toml"))
    assert err.field == f"g.csv, row {row + 1}, column {column}"
    if allowed is None:
        assert err.allowed == f"missing required field 'g.csv, row {row + 1}, column {column}'"
        return
    assert err.allowed.startswith(allowed)
    # the [[granules]] tables of the same rows: the same message, naming granules[i].field
    toml_field = {"omega_x": "omega[0]"}.get(column, column)
    tables = _tables_of(rows)
    t_err = _error(lambda: validate(loads(HEAD_3D + tables + TAIL_3D)))
    assert t_err.field == f"granules[{row}].{toml_field}"
    assert err.allowed == t_err.allowed.replace("granules[0]", "g.csv, row 1")


def _tables_of(rows: list[str]) -> str:
    """The rows of GOOD's columns as [[granules]] tables (numbers that parse as numbers)."""
    out = []
    for r in rows:
        x, y, z, rad, mat, lab, vx, vy, vz, ox, oy, oz = r.split(",")

        def num(v):
            try:
                return repr(float(v)) if v.strip().lower() != "nan" else "nan"
            except ValueError:
                return f'"{v}"'

        out.append(
            f"[[granules]]\nx = {num(x)}\ny = {num(y)}\nz = {num(z)}\nradius = {num(rad)}\n"
            f'material = "{mat}"\nlabel = "{lab}"\nvx = {num(vx)}\nvy = {num(vy)}\nvz = {num(vz)}\n'
            f"omega = [{num(ox)}, {num(oy)}, {num(oz)}]\n"
        )
    return "\n".join(out)


def test_overlaps_and_columns_are_named_by_row(tmp_path):
    rows = _bad(1, 0, "0.0065")  # b's centre 0.0035 from a's: radii 0.002 + 0.0025 overlap
    (tmp_path / "s.toml").write_text(_csv(tmp_path, rows))
    err = _error(lambda: load_scenario(tmp_path / "s.toml"))
    assert err.field == "g.csv, row 1" and "(g.csv, row 2) by " in err.allowed
    assert "placed by g.csv, row 1, column x, g.csv, row 1, column y" in err.allowed
    (tmp_path / "s.toml").write_text(
        _csv(tmp_path, GOOD, header="x,y,z,raduis,material,label,vx,vy,vz,omega_x,omega_y,omega_z")
    )
    err = _error(lambda: load_scenario(tmp_path / "s.toml"))
    assert err.field == "g.csv, column raduis" and "did you mean 'radius'?" in err.allowed
    (tmp_path / "s.toml").write_text(
        _csv(tmp_path, [",".join(r.split(",")[:3] + r.split(",")[4:6]) for r in GOOD], header="x,y,z,material,label")
    )
    err = _error(lambda: load_scenario(tmp_path / "s.toml"))
    assert err.field == "g.csv, column radius" and "missing required column" in err.allowed


def test_the_plane_takes_omega_z_and_refuses_the_third_dimension(tmp_path):
    rows = ["0.01,0.01,0.01,steel,,0,0,0,0,2.5", "0.03,0.01,0.01,steel,,0,0,0,0,0"]
    header = "x,y,radius,material,label,vx,vy,z,omega_x,omega_z"
    (tmp_path / "s.toml").write_text(_csv(tmp_path, rows, header=header, dimension=2))
    s = load(tmp_path / "s.toml")
    assert s.granules[0].omega == 2.5 and s.dimension == 2
    (tmp_path / "s.toml").write_text(
        _csv(tmp_path, [rows[0], rows[1].replace(",0,0,0,0,0", ",0,0,0.5,0,0")], header=header, dimension=2)
    )
    err = _error(lambda: load_scenario(tmp_path / "s.toml"))
    assert err.field == "g.csv, row 2, column z" and err.allowed.startswith("must be 0 in 2D")
    (tmp_path / "s.toml").write_text(
        _csv(tmp_path, [rows[0].replace(",0,0,0,0,2.5", ",0,0,0,1,2.5"), rows[1]], header=header, dimension=2)
    )
    err = _error(lambda: load(tmp_path / "s.toml"))
    assert err.field == "g.csv, row 1, column omega_x" and "omega_z" in err.allowed


def test_tables_and_a_file_are_exclusive(tmp_path):
    write_granules(loads(TABLES_2D).granules, tmp_path / "g.npz", 2)
    (tmp_path / "s.toml").write_text('granules_file = "g.npz"\n' + TABLES_2D)
    err = _error(lambda: load(tmp_path / "s.toml"))
    assert err.field == "granules_file" and "not both" in err.allowed
    err = _error(lambda: read_granules(tmp_path / "g.txt", 2))
    assert err.field == "granules_file" and "no such file" in err.allowed


def test_resolve_writes_a_file_that_gives_the_resolved_scenario_back(tmp_path):
    out = tmp_path / "sub"
    out.mkdir()
    assert main(["resolve", "steel-r1", "--granules-file", str(out / "g.csv"), "-o", str(out / "s.toml")]) == 0
    text = (out / "s.toml").read_text()
    assert 'granules_file = "g.csv"' in text and "[[granules]]" not in text
    assert load_scenario(out / "s.toml") == resolve(load_scenario("steel-r1"))


def test_a_result_seeds_a_scenario_at_its_last_output_time(tmp_path):
    import granplate as gp
    from granplate.results.seed import seeded_scenario

    # two spheres flying apart with spins: never in contact, so the seed is a valid start
    text = TABLES_3D.replace("vx = 1.5", "vx = -1.5").replace('material = "ptfe"', 'material = "ptfe"\nvz = 0.5')
    from granplate.results.dataset import write

    ds = gp.simulate(loads(text), progress=False)
    write(ds, tmp_path / "r.nc")
    seed = seeded_scenario(ds)
    validate(seed)
    for i, g in enumerate(seed.granules):
        for k, v in (("x", g.x), ("y", g.y), ("z", g.z), ("vx", g.vx), ("vy", g.vy), ("vz", g.vz)):
            assert v == float(ds[k].values[-1, i])
        assert g.omega == tuple(float(ds[f"omega_{c}"].values[-1, i]) for c in "xyz")
    assert seed.granules[0].omega == (10.0, -20.0, 30.0) and seed.granules[0].x < 0.005  # free flight
    assert (
        main(
            [
                "resolve",
                str(tmp_path / "r.nc"),
                "--granules-file",
                str(tmp_path / "g.nc"),
                "-o",
                str(tmp_path / "s.toml"),
            ]
        )
        == 0
    )
    assert load_scenario(tmp_path / "s.toml") == seed


@pytest.mark.parametrize("text, dimension", [(TABLES_3D, 3), (TABLES_2D, 2)])
def test_a_result_of_many_granules_keeps_them_beside_its_toml(tmp_path, monkeypatch, text, dimension):
    """A scenario of more granules than GRANULES_IN_TOML_MAX keeps them out of the result's
    scenario_toml, in variables: read back through netCDF, `scenario_of` is the scenario run (the
    one given, resolved), and the TOML's comment (count, digest) changes when a granule does."""
    import dataclasses

    import granplate as gp
    from granplate.results import dataset as D

    monkeypatch.setattr(D, "GRANULES_IN_TOML_MAX", 1)
    s = loads(text)
    ds = gp.simulate(s, progress=False)
    assert ds.attrs["scenario_granules"] == "variables" and "[[granules]]" not in ds.attrs["scenario_toml"]
    path = tmp_path / "r.nc"
    D.write(ds, path)
    assert D.scenario_of(D.read(path)) == resolve(s)
    moved = dataclasses.replace(s, granules=(dataclasses.replace(s.granules[0], vx=0.5), *s.granules[1:]))
    other = gp.simulate(moved, t_end=1e-6, progress=False)
    assert other.attrs["scenario_toml"] != ds.attrs["scenario_toml"]
    assert D.scenario_of(other).granules == resolve(moved).granules


@pytest.mark.filterwarnings("ignore::granplate.errors.YieldWarning")  # the PTFE sphere yields: Hertz is timed
def test_a_result_of_many_granules_from_a_file_restarts_and_seeds(tmp_path, monkeypatch):
    """A granules_file scenario of more granules than GRANULES_IN_TOML_MAX, run from the
    command line: its result keeps the granules as variables, and from that file
    `run --from --from-time` continues the run bit for bit as one straight run, and
    `resolve RESULT.nc` writes the granules at the result's last output time."""
    from granplate.results import dataset as D

    monkeypatch.setattr(D, "GRANULES_IN_TOML_MAX", 1)
    # flying apart with spins (the seed at t_end is then a valid start), a restart state at 10 us
    text = TABLES_3D.replace("vx = 1.5", "vx = -1.5").replace('material = "ptfe"', 'material = "ptfe"\nvz = 0.5')
    text = text.replace("field_interval = 1e-6", "field_interval = 1e-6\nrestart_interval = 1e-5")
    (tmp_path / "s.toml").write_text(_with_file(tmp_path, text, "npz", 3))
    straight = tmp_path / "straight.nc"
    assert main(["run", str(tmp_path / "s.toml"), "-o", str(straight), "-q"]) == 0
    ds = D.read(straight)
    assert ds.attrs["scenario_granules"] == "variables" and "[[granules]]" not in ds.attrs["scenario_toml"]
    assert D.scenario_of(ds).granules == resolve(load_scenario(tmp_path / "s.toml")).granules
    late = tmp_path / "late.nc"
    assert (
        main(["run", str(tmp_path / "s.toml"), "--from", str(straight), "--from-time", "1e-5", "-o", str(late), "-q"])
        == 0
    )
    after = D.read(late)
    assert float(after.time[0]) == pytest.approx(1e-5, rel=1e-12) and after.sizes["time"] == 11
    for k in ("x", "y", "z", "vx", "vy", "vz", "omega_x", "omega_y", "omega_z"):
        np.testing.assert_array_equal(after[k].values, ds[k].values[10:], err_msg=k)
    assert (
        main(["resolve", str(straight), "--granules-file", str(tmp_path / "g.csv"), "-o", str(tmp_path / "seed.toml")])
        == 0
    )
    seed = load_scenario(tmp_path / "seed.toml")
    for i, g in enumerate(seed.granules):
        assert (g.x, g.y, g.z, g.vx) == tuple(float(ds[k].values[-1, i]) for k in ("x", "y", "z", "vx"))
