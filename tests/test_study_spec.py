"""Study files expand to the designs they describe (each parameter form, checked against
hand-written or scipy-computed values) and refuse mistakes before anything runs, naming
the field and what is allowed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import granplate as gp
from granplate.errors import ScenarioError
from granplate.study.spec import load_study, parse_study

DOCS = Path(__file__).resolve().parent.parent / "docs"
BASE = {"base": "ptfe-r05", "set": {"time.t_end": 2e-5}}


def study(**tables):
    return parse_study({**BASE, **tables})


def test_smallest_study_as_written_is_the_full_grid():
    # the study of docs/studies.md, as written: 3 x 3 designs, first axis slowest
    s = load_study(DOCS / "studies" / "smallest.toml")
    assert s.names == ("load.q0", "layout.R2_ratio")
    assert s.designs == tuple((q, r) for q in (2e3, 1e4, 5e4) for r in (0.5, 0.75, 1.0))
    sc = s.scenario(4)
    assert (sc.load.q0, sc.layout.R2_ratio, sc.time.t_end) == (1e4, 0.75, 5e-4)
    # the file in the docs page is this one
    assert (DOCS / "studies" / "smallest.toml").read_text().strip() in (DOCS / "studies.md").read_text()


@pytest.mark.parametrize("name", ["forms.toml", "optimize.toml"])
def test_documented_study_files_are_the_ones_shown_and_valid(name):
    # the page shows each example file as written (after its first comment line)
    body = (DOCS / "studies" / name).read_text().split("\n", 1)[1].strip()
    assert body in (DOCS / "studies.md").read_text()
    if name == "forms.toml":  # 3 loads x 2 plates (zip) x 4 sampled points
        s = load_study(DOCS / "studies" / name)
        assert len(s.designs) == 24
        assert s.names == ("load.q0", "plate.thickness", "plate.ny", "contact.mu", "materials.ptfe.E")
    else:
        from granplate.study.optimize import load_optimization

        assert list(load_optimization(DOCS / "studies" / name).objectives) == ["ep_max_fraction", "granular_mass"]


def test_range_linear_and_log():
    s = study(parameters={"load.q0": {"range": [1e3, 5e3], "num": 5}})
    assert [d[0] for d in s.designs] == [1e3, 2e3, 3e3, 4e3, 5e3]
    s = study(parameters={"load.q0": {"range": [1e2, 1e4], "num": 3, "log": True}})
    assert np.allclose([d[0] for d in s.designs], [1e2, 1e3, 1e4], rtol=1e-14, atol=0)
    # integer ends and integer steps stay integers (an integer field accepts them)
    s = study(parameters={"plate.ny": {"range": [20, 40], "num": 3}})
    assert [d[0] for d in s.designs] == [20, 30, 40] and all(type(d[0]) is int for d in s.designs)


def test_zip_varies_together_and_multiplies_the_grid():
    s = study(
        parameters={"load.q0": [1e3, 2e3]}, zip={"layout.R2_ratio": [0.5, 1.0, 0.75], "contact.mu": [0.1, 0.2, 0.3]}
    )
    assert s.names == ("load.q0", "layout.R2_ratio", "contact.mu")
    assert s.designs == (
        (1e3, 0.5, 0.1),
        (1e3, 1.0, 0.2),
        (1e3, 0.75, 0.3),
        (2e3, 0.5, 0.1),
        (2e3, 1.0, 0.2),
        (2e3, 0.75, 0.3),
    )


def test_latin_hypercube_is_seeded_and_stratified():
    form = {"sample": "latin_hypercube", "n": 8, "seed": 3}
    s = study(
        parameters={"load.q0": {**form, "low": 1e3, "high": 9e3}, "contact.mu": {**form, "low": 0.0, "high": 0.4}}
    )
    again = study(
        parameters={"load.q0": {**form, "low": 1e3, "high": 9e3}, "contact.mu": {**form, "low": 0.0, "high": 0.4}}
    )
    assert s.designs == again.designs and len(s.designs) == 8
    from scipy.stats import qmc

    u = qmc.LatinHypercube(d=2, rng=np.random.default_rng(3)).random(8)
    assert np.allclose(np.array(s.designs), [1e3, 0.0] + u * [8e3, 0.4], rtol=1e-15, atol=0)
    # one point per stratum in each dimension
    q = np.array(s.designs)[:, 0]
    assert sorted(np.floor((q - 1e3) / 1e3).astype(int)) == list(range(8))
    other = study(parameters={"load.q0": {**form, "seed": 4, "low": 1e3, "high": 9e3}})
    assert [d[0] for d in other.designs] != [d[0] for d in s.designs]


def test_uniform_sample_and_log_bounds():
    s = study(parameters={"load.q0": {"sample": "uniform", "n": 5, "seed": 0, "low": 1e2, "high": 1e4, "log": True}})
    u = np.random.default_rng(0).random((5, 1))[:, 0]
    assert np.allclose([d[0] for d in s.designs], 1e2 * 100.0**u, rtol=1e-12, atol=0)


def test_relative_base_file_is_found_beside_the_study(tmp_path):
    gp.dump(gp.with_changes(gp.preset("ptfe-r05"), {"load.q0": 123.0}), tmp_path / "case.toml")
    (tmp_path / "s.toml").write_text('base = "case.toml"\n[parameters]\n"contact.mu" = [0.1]\n')
    s = load_study(tmp_path / "s.toml")
    assert s.base.load.q0 == 123.0 and s.scenario(0).contact.mu == 0.1


@pytest.mark.parametrize(
    "doc, field, words",
    [
        ({"base": "nope"}, "base", "no such preset or scenario file"),
        ({"base": 3}, "base", "preset name or a scenario file"),
        ({"parameters": {"load.q0": []}}, "parameters.load.q0", "empty list"),
        ({"parameters": {"load.qq": [1.0]}}, "load.qq", "unknown field 'load.qq'"),
        ({"parameters": {"load.q0": ["a"]}}, "load.q0", "expected a number"),
        ({"zip": {"load.q0": [1.0, 2.0], "contact.mu": [0.1]}}, "zip", "same length"),
        ({"parameters": {"load.q0": {"range": [1.0], "num": 3}}}, "parameters.load.q0.range", "two numbers"),
        ({"parameters": {"load.q0": {"range": [1.0, 2.0], "num": 0}}}, "parameters.load.q0.num", ">= 1"),
        (
            {"parameters": {"load.q0": {"range": [0.0, 2.0], "num": 2, "log": True}}},
            "parameters.load.q0.range",
            "a > 0",
        ),
        (
            {"parameters": {"load.q0": {"range": [1.0, 2.0], "nun": 2}}},
            "parameters.load.q0.nun",
            "allowed: range, num, log",
        ),
        (
            {"parameters": {"load.q0": {"sample": "sobol", "low": 0, "high": 1, "n": 2, "seed": 0}}},
            "parameters.load.q0.sample",
            "uniform, latin_hypercube",
        ),
        (
            {"parameters": {"load.q0": {"sample": "uniform", "low": 0, "high": 1, "n": 2}}},
            "parameters.load.q0.seed",
            "integer >= 0",
        ),
        (
            {"parameters": {"load.q0": {"sample": "uniform", "low": 2, "high": 1, "n": 2, "seed": 0}}},
            "parameters.load.q0.high",
            "must be > low",
        ),
        (
            {
                "parameters": {
                    "load.q0": {"sample": "uniform", "low": 0, "high": 1, "n": 2, "seed": 0},
                    "contact.mu": {"sample": "uniform", "low": 0, "high": 1, "n": 3, "seed": 0},
                }
            },
            "parameters.contact.mu",
            "drawn together",
        ),
        ({"set": {"time.t_end": 2e-5}, "parameters": {"time.t_end": [1e-5]}}, "time.t_end", "either fixed"),
        ({"set": {"load.nope": 1.0}}, "set: load.nope", "unknown field"),
        ({"sets": {}}, "sets", "allowed: base, set, parameters, zip"),
    ],
)
def test_validation_names_the_field(doc, field, words):
    with pytest.raises(ScenarioError) as err:
        parse_study({"base": "ptfe-r05", **doc})
    assert err.value.field == field, str(err.value)
    assert words in str(err.value)


def test_study_file_errors(tmp_path):
    with pytest.raises(ScenarioError, match="no such file"):
        load_study(tmp_path / "missing.toml")
    (tmp_path / "bad.toml").write_text("base = \n")
    with pytest.raises(ScenarioError, match="not valid TOML"):
        load_study(tmp_path / "bad.toml")


# ------------------------------------------------------------------------- optimize


def test_optimize_search_space():
    from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution

    from granplate.study.optimize import parse_optimization

    opt = parse_optimization(
        {
            **BASE,
            "parameters": {
                "load.q0": {"range": [1e3, 5e4], "log": True},
                "plate.ny": {"range": [20, 40]},
                "contact.mu": [0.05, 0.2],
            },
            "objectives": {"ep_max_fraction": "minimize", "granular_mass": "minimize"},
        }
    )
    assert opt.space["load.q0"] == FloatDistribution(1e3, 5e4, log=True)
    assert opt.space["plate.ny"] == IntDistribution(20, 40)
    assert opt.space["contact.mu"] == CategoricalDistribution([0.05, 0.2])
    assert opt.scenario({"load.q0": 2e3}).load.q0 == 2e3 and opt.scenario({}).time.t_end == 2e-5


@pytest.mark.parametrize(
    "doc, field, words",
    [
        ({"parameters": {"load.q0": [1.0]}}, "objectives", "at least one"),
        ({"parameters": {"load.q0": [1.0]}, "objectives": {"nope": "minimize"}}, "objectives.nope", "unknown metric"),
        (
            {"parameters": {"load.q0": [1.0]}, "objectives": {"ep_max_fraction": "least"}},
            "objectives.ep_max_fraction",
            "minimize, maximize",
        ),
        (
            {"parameters": {"load.q0": {"range": [1.0, 2.0], "num": 3}}, "objectives": {"e_in": "maximize"}},
            "parameters.load.q0.num",
            "searched continuously",
        ),
        (
            {"parameters": {"load.q0": {"sample": "uniform"}}, "objectives": {"e_in": "maximize"}},
            "parameters.load.q0",
            "categorical",
        ),
        ({"parameters": {"load.qq": [1.0]}, "objectives": {"e_in": "maximize"}}, "load.qq", "unknown field"),
        ({"zip": {"load.q0": [1.0]}, "objectives": {"e_in": "maximize"}}, "zip", "allowed: base, set"),
    ],
)
def test_optimize_validation_names_the_field(doc, field, words):
    from granplate.study.optimize import parse_optimization

    with pytest.raises(ScenarioError) as err:
        parse_optimization({"base": "ptfe-r05", **doc})
    assert err.value.field == field, str(err.value)
    assert words in str(err.value)
