"""`--set PATH=VALUE` on the command line: the changed scenario is exactly
`gp.with_changes` of the base (the Python API's one implementation), values are read as
TOML literals, and a mistake gets the very message the same mistake in a file gets."""

from __future__ import annotations

import dataclasses
import tomllib

import pytest

import granplate as gp
from granplate.cli import main
from granplate.errors import ScenarioError
from granplate.setup.io import parse_settings

CHANGES = {"load.q0": 3e4, "layout.R2_ratio": 0.7}
ARGS = ["--set", "load.q0=3e4", "--set", "layout.R2_ratio=0.7"]


def _error(capsys) -> str:
    return capsys.readouterr().err.strip()


@pytest.mark.parametrize(
    "text, value",
    [
        ("load.q0=3e4", 3e4),
        ("load.q0 = 30000", 30000),
        ("load.q0=.5", 0.5),
        ('layout.intruder_material="steel"', "steel"),
        ("layout.intruder_material=steel", "steel"),
        ("plate.size=[1, 2.5]", [1, 2.5]),
        ("solver.adaptive=true", True),
        ('description="a=b"', "a=b"),  # split at the first '='
    ],
)
def test_values_are_toml_literals(text, value):
    """Each value is what TOML reads (numbers, "strings", [arrays], booleans); a bare word
    is a string, a number TOML refuses (.5) still a number."""
    ((path, got),) = parse_settings([text]).items()
    assert path == text.partition("=")[0].strip()
    assert got == value and type(got) is type(value)


@pytest.mark.parametrize(
    "text, field, words",
    [
        ("load.q0", "--set", "expected PATH=VALUE"),
        ("=3", "--set", "expected PATH=VALUE"),
        ("load.q0=[1,", "load.q0", "not a TOML value"),
        ("load.q0=3\nx = 1", "load.q0", "one TOML value"),
        ("load..q0=3", "load..q0", "not a dotted field path"),
    ],
)
def test_malformed_settings_are_refused_by_name(text, field, words):
    with pytest.raises(ScenarioError) as err:
        parse_settings([text])
    assert err.value.field == field and words in err.value.allowed


def test_run_with_set_runs_the_changed_scenario(tmp_path, capsys):
    """`granplate run ptfe-r05 --set load.q0=3e4 --set layout.R2_ratio=0.7`: the result's
    scenario is with_changes of the preset (and the run's summary heads with the changes)."""
    from granplate.results.dataset import read, scenario_of
    from granplate.setup.geometry import resolve

    out = tmp_path / "r.nc"
    assert main(["run", "ptfe-r05", *ARGS, "--t-end", "1e-5", "-o", str(out), "-q"]) == 0
    assert "changed: load.q0 = 30000, layout.R2_ratio = 0.7" in capsys.readouterr().out
    ran = scenario_of(read(out))
    expected = resolve(gp.with_changes(gp.preset("ptfe-r05"), CHANGES))  # a result keeps it resolved
    assert ran.load.q0 == 3e4 and sorted({g.radius for g in ran.granules}) == pytest.approx([0.007, 0.01])
    assert ran.time.t_end == 1e-5 and dataclasses.replace(ran, time=expected.time) == expected


@pytest.mark.parametrize(
    "field, text, in_file",
    [
        ("load.q00", "3e4", "[load]\nq00 = 3e4\n"),  # unknown field: the closest suggested
        ("load.q0", "-3e4", "[load]\nq0 = -3e4\n"),  # outside its range (validate)
        ("plate.nx", "3.5", "[plate]\nnx = 3.5\n"),  # wrong type
        ("layout.intruder_material", '"stel"', '[layout]\nintruder_material = "stel"\n'),
    ],
)
def test_a_mistake_gets_the_message_it_gets_in_a_file(tmp_path, capsys, field, text, in_file):
    """The same mistake written in a scenario file and given by --set: the same one line,
    exit status 2, before anything runs."""
    base = tomllib.loads(gp.dumps(gp.preset("ptfe-r05")))
    table, key = field.split(".")
    base[table][key] = tomllib.loads(in_file)[table][key]
    import tomli_w

    bad = tmp_path / "bad.toml"
    bad.write_text(tomli_w.dumps(base))
    assert main(["show", str(bad), "-o", str(tmp_path / "a.png")]) == 2
    from_file = _error(capsys)
    assert from_file.startswith(f"granplate: error: scenario field '{field}'")
    for command in (
        ["run", "ptfe-r05", "-q"],
        ["show", "ptfe-r05", "-o", str(tmp_path / "b.png")],
        ["preset", "ptfe-r05"],
        ["resolve", "ptfe-r05"],
    ):
        assert main([*command, "--set", f"{field}={text}"]) == 2
        assert _error(capsys) == from_file, command
    assert not list(tmp_path.glob("*.png"))


def test_preset_with_set_writes_the_changed_scenario(tmp_path):
    """`granplate preset NAME --set ... -o FILE`: the file reads back as with_changes."""
    out = tmp_path / "mine.toml"
    assert main(["preset", "ptfe-r05", *ARGS, "-o", str(out)]) == 0
    assert gp.load(out) == gp.with_changes(gp.preset("ptfe-r05"), CHANGES)


def test_show_with_set_draws_the_changed_scenario(tmp_path, capsys):
    """show takes --set on a scenario; on a result file it is refused by name."""
    out = tmp_path / "s.png"
    assert main(["show", "ptfe-r05", "--set", "layout.R2_ratio=0.7", "-o", str(out)]) == 0
    assert out.stat().st_size > 0
    capsys.readouterr()
    (tmp_path / "r.nc").write_bytes(b"")
    assert main(["show", str(tmp_path / "r.nc"), "--set", "load.q0=1"]) == 2
    assert "'--set'" in _error(capsys)


STUDY = 'base = "ptfe-r05"\n[set]\n"time.t_end" = 2e-4\n[parameters]\n"contact.mu" = [0.1, 0.2]\n'
OPTIMIZE = STUDY + '[objectives]\nep_max_fraction = "minimize"\n'


def test_study_set_adds_to_its_set_table(tmp_path):
    """sweep/optimize --set: the changes join the study's [set] (overriding it there), every
    design carries them, and the study file kept with the results says so."""
    from granplate.study.cli import keep_study_file
    from granplate.study.optimize import load_optimization
    from granplate.study.spec import load_study

    path = tmp_path / "s.toml"
    path.write_text(STUDY)
    changes = {"load.q0": 3e4, "time.t_end": 1e-4}
    study = load_study(path, changes)
    assert study.fixed == {"time.t_end": 1e-4, "load.q0": 3e4}
    assert all(study.scenario(i).load.q0 == 3e4 for i in range(2))
    assert study.scenario(1) == gp.with_changes(gp.preset("ptfe-r05"), {**changes, "contact.mu": 0.2})
    path.write_text(OPTIMIZE)
    assert load_optimization(path, changes).fixed == study.fixed
    keep_study_file(str(path), str(tmp_path / "out"), changes)
    kept = (tmp_path / "out" / "study.toml").read_text()
    assert kept.startswith("# s.toml with --set load.q0, time.t_end")
    assert load_study(tmp_path / "out" / "study.toml").fixed == study.fixed
    with pytest.raises(ScenarioError, match="either fixed"):
        load_study(path, {"contact.mu": 0.3})


@pytest.mark.parametrize("command, doc", [("sweep", STUDY), ("optimize", OPTIMIZE)])
def test_study_set_mistake_gets_the_message_of_its_set_table(tmp_path, capsys, command, doc):
    """A wrong path by --set on sweep/optimize: exit 2 with the message the same line in
    the study's [set] table gets, before any design runs."""
    path = tmp_path / "s.toml"
    path.write_text(doc.replace("[set]\n", '[set]\n"load.q00" = 1\n'))
    extra = ["--trials", "1"] if command == "optimize" else []
    assert main([command, str(path), "--out", str(tmp_path / "a"), *extra]) == 2
    from_file = _error(capsys)
    assert "unknown field 'load.q00'" in from_file
    path.write_text(doc)
    assert main([command, str(path), "--out", str(tmp_path / "b"), *extra, "--set", "load.q00=1"]) == 2
    assert _error(capsys) == from_file
    assert not (tmp_path / "b" / "designs").exists()
