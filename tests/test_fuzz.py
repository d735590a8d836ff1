"""Bad numbers anywhere in a scenario: a clean run or one line naming the field, never a
traceback or a hang (docs/scenario.md, "Reading and checking")."""

from __future__ import annotations

import itertools
import math
import os
import re
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest
import tomli_w

import granplate as gp
from granplate.errors import ScenarioError, SimulationError
from granplate.setup.io import from_dict
from granplate.setup.validate import validate
from field_paths import mutated, numeric_fields

#: Three granules in a row between a left wall and the plate (the middle one of a user
#: material, moving), a bottom wall, a pair override and a 2 x 8 plate; 2 us of a shock.
BASE: dict = {
    "name": "fuzz",
    "description": "three granules against a small plate",
    "materials": {"soft": {"E": 1e9, "nu": 0.3, "rho": 1200.0}},
    "granules": [
        {"label": "a", "x": 0.005, "y": 0.02, "radius": 0.005, "material": "steel"},
        {"label": "b", "x": 0.015, "y": 0.02, "radius": 0.005, "material": "soft", "vx": 0.1},
        {"label": "c", "x": 0.025, "y": 0.02, "radius": 0.005, "material": "steel"},
    ],
    "walls": [
        {"label": "left", "normal": [-1.0, 0.0], "offset": 0.0},
        {"label": "bottom", "normal": [0.0, -1.0], "offset": 0.0, "material": "soft"},
    ],
    "plate": {
        "width": 0.005,
        "height": 0.04,
        "thickness": 0.001,
        "x0": 0.03,
        "y0": 0.0,
        "nx": 2,
        "ny": 8,
        "rigid_layer_width": 0.004,
        "n_modes": 0,
        "max_frequency": 1e6,
        "stress_radius": 0.002,
    },
    "load": {"q0": 5e4, "duration": 1e-5, "length": 0.04, "y0": 0.0},
    "contact": {
        "mu": 0.1,
        "k_s": 1000.0,
        "alpha_n": 6e-3,
        "neighbour_gap": 0.05,
        "skin": 0.1,
        "overlap_warn": 0.05,
        "overlap_stop": 0.2,
        "pairs": [{"materials": ["steel", "soft"], "alpha_n": 0.01, "mu": 0.2, "k_s": 500.0}],
    },
    "time": {
        "t_end": 2e-6,
        "dt_initial": 4e-8,
        "dt_max": 4e-8,
        "dt_min": 1e-13,
        "output_interval": 1e-6,
        "field_interval": 2e-6,
    },
    "solver": {
        "lambda_target": 0.5,
        "iteration_rtol": 1e-9,
        "iteration_atol": 1e-10,
        "max_iterations": 60,
        "energy_tol": 1e-4,
        "error_tol": 1e-3,
        "implicit_dt_max": 1e-6,
    },
}
#: The bad values every numeric field is tried with.
BAD_VALUES: tuple = (-1, 0, math.nan, math.inf, 1e300, "x")
SEED = 20240601
N_CASES = 45
#: Cases always tried: a granule far out (the neighbour search's overflow), outputs that
#: cannot fit, a snapshot stride no integer holds, a damping that overflows the forces.
ALWAYS: tuple = (
    ("granules[1].y", 1e300),
    ("time.t_end", 1e300),
    ("time.field_interval", 1e300),
    ("contact.pairs[0].alpha_n", 1e300),
)
N_CLI_CASES = 3
#: A run of 2 us of this scenario takes well under a second once the kernels are compiled;
#: the limit also covers their first compilation (1-3 min on a loaded machine).
RUN_TIMEOUT_S = 600.0


def cases(n: int, seed: int) -> list[tuple[str, object]]:
    """n (field, bad value) pairs drawn without replacement by a seeded RNG."""
    product = list(itertools.product(numeric_fields(BASE), BAD_VALUES))
    rng = np.random.default_rng(seed)
    return [product[k] for k in rng.choice(len(product), size=n, replace=False)]


def names_field(message: str, path: str) -> bool:
    """The message names the field; a conflict between bodies (an overlap, a crossed wall)
    may name the body instead (granules[1] for granules[1].y), a vector its whole
    (walls[0].normal for walls[0].normal[1])."""
    if re.search(re.escape(path) + r"(?![\w\[.])", message):
        return True
    body = re.match(r"^((?:granules|walls)\[\d+\])\.(?:x|y|radius|offset)$", path)
    if body and body.group(1) in message:
        return True
    vector = re.match(r"^(.*\])\.normal\[\d\]$", path)
    return bool(vector) and f"'{vector.group(1)}.normal'" in message


def run_with_timeout(scenario, seconds: float):
    """simulate(scenario), stopped as a Ctrl-C does (SIGINT, the driver's stop request)
    when it runs longer than `seconds`."""
    timer = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        return gp.simulate(scenario, progress=False)
    finally:
        timer.cancel()


def test_base_scenario_runs():
    """The unmutated scenario is valid and runs 2 us with finite energies and a plate
    contact (the fuzz starts from a case that works)."""
    ds = run_with_timeout(from_dict(BASE), RUN_TIMEOUT_S)
    assert float(ds.time[-1]) == pytest.approx(2e-6)
    assert float(ds.E_shock[-1]) > 0.0
    assert len(numeric_fields(BASE)) * len(BAD_VALUES) >= 200


@pytest.mark.parametrize(
    "path,value", [*ALWAYS, *(c for c in cases(N_CASES, SEED) if c not in ALWAYS)], ids=lambda v: repr(v)
)
def test_bad_number_is_refused_by_name_or_runs(path, value):
    """Any field set to -1, 0, NaN, inf, 1e300 or a string: a one-line ScenarioError naming
    the field before anything runs, or a 2 us run that ends with finite energies."""
    d = mutated(BASE, path, value)
    try:
        validate(from_dict(d))
    except ScenarioError as err:
        assert names_field(str(err), path), str(err)
        assert "\n" not in str(err)
        return
    try:
        ds = run_with_timeout(from_dict(d), RUN_TIMEOUT_S)
    except SimulationError as err:  # pragma: no cover - what the test exists to catch
        pytest.fail(f"{path} = {value!r} passed validation but the run failed: {err}")
    for var in ("E_shock", "E_granular", "E_plate", "D_viscous", "D_friction", "energy_residual"):
        assert np.isfinite(ds[var].values).all(), var
    assert float(ds.time[-1]) == pytest.approx(d["time"]["t_end"])


def _refused_cases() -> list[tuple[str, object]]:
    """A few of the seeded cases that validation refuses (for the command line)."""
    found = []
    for path, value in cases(3 * N_CASES, SEED + 1):
        try:
            validate(from_dict(mutated(BASE, path, value)))
        except ScenarioError:
            found.append((path, value))
        if len(found) == N_CLI_CASES:
            break
    return found


def test_command_line_reports_bad_numbers_in_one_line(tmp_path):
    """`granplate run FILE` with a bad number: exit status 2 and one line
    'granplate: error: ...' naming the field on stderr, no traceback, no result file."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    for k, (path, value) in enumerate(_refused_cases()):
        f = tmp_path / f"case{k}.toml"
        f.write_text(tomli_w.dumps(mutated(BASE, path, value)))
        out = tmp_path / f"case{k}.nc"
        p = subprocess.run(
            [sys.executable, "-m", "granplate.cli", "run", str(f), "-q", "-o", str(out)],
            capture_output=True,
            text=True,
            timeout=120,
            env=env,
        )
        lines = p.stderr.strip().splitlines()
        assert p.returncode == 2, (path, value, p.stderr)
        assert len(lines) == 1 and lines[0].startswith("granplate: error: "), p.stderr
        assert "Traceback" not in p.stderr and names_field(lines[0], path), lines[0]
        assert not out.exists()


#: Every layout kind, from its worked example (docs/examples) and the paper's preset.
LAYOUT_SOURCES: tuple[str, ...] = (
    "paper",
    "hexagonal",
    "square",
    "chain",
    "imperfect",
    "intruder-lattice",
    "3d-sc",
    "3d-bcc",
    "3d-fcc",
    "3d-hcp",
    "3d-chain",
)
LAYOUT_BAD_VALUES: tuple = (-1.0, 0.0, math.nan, math.inf, 1e300, 1e-300, "x")


def _layout_scenario(name: str):
    from pathlib import Path

    from granplate.setup.io import load_scenario

    if name == "paper":
        return gp.preset("steel-r1")
    return load_scenario(Path(__file__).resolve().parents[1] / "docs" / "examples" / f"{name}.toml")


@pytest.mark.parametrize("name", LAYOUT_SOURCES)
def test_layout_fields_refused_by_name(name):
    """Each numeric field of a layout (and of its imperfections) set to a bad value is either
    accepted by validation or refused naming that field: never an overflow in the layout's
    expansion, never a derived granule field blamed instead."""
    import dataclasses

    s = _layout_scenario(name)
    lay = s.layout
    tables = [("layout", lay, lambda v: dataclasses.replace(lay, **v))]
    if lay.imperfections is not None:
        imp = lay.imperfections
        tables.append(
            (
                "layout.imperfections",
                imp,
                lambda v: dataclasses.replace(lay, imperfections=dataclasses.replace(imp, **v)),
            )
        )
    tried = 0
    for prefix, table, rebuild in tables:
        for f in dataclasses.fields(table):
            v0 = getattr(table, f.name)
            if not isinstance(v0, (int, float)) or isinstance(v0, bool) or f.name == "y" and v0 is None:
                continue
            for bad in LAYOUT_BAD_VALUES:
                changed = dataclasses.replace(s, layout=rebuild({f.name: bad}))
                tried += 1
                try:
                    validate(changed)
                except ScenarioError as err:
                    if f"{prefix}.{f.name}" in str(err) or "plate.clamped_edges" in str(err):
                        continue  # named; a granule placed on a clamp names the clamp
                    pytest.fail(f"{prefix}.{f.name} = {bad!r}: the error names another field: {err}")
    assert tried > 0


#: How many of the 3D solid scenario's mutations that validation accepts are run.
N_SOLID_RUNS = 6


def _solid_cases_that_validate() -> list[tuple[str, object]]:
    """Seeded (field, bad value) pairs of the 3D solid scenario (tests/test_scenario_3d.py)
    that validation accepts: the ones that must then run."""
    from test_scenario_3d import BAD_VALUES as BAD_3D, BASE_SOLID

    product = list(itertools.product(numeric_fields(BASE_SOLID), BAD_3D))
    order = np.random.default_rng(SEED + 2).permutation(len(product))
    found = []
    for k in order:
        path, value = product[k]
        try:
            validate(from_dict(mutated(BASE_SOLID, path, value)))
        except ScenarioError:
            continue
        found.append((path, value))
        if len(found) == N_SOLID_RUNS:
            break
    return found


def test_bad_numbers_a_solid_scenario_accepts_run():
    """The 3D solid scenario's mutations that pass validation (a granule moved off the
    plate, a friction or damping of 0, a yield stress of 1e300, ...) run 0.2 us with finite
    energies: never a traceback or a hang after validation."""
    from test_scenario_3d import BASE_SOLID

    accepted = _solid_cases_that_validate()
    assert len(accepted) == N_SOLID_RUNS
    for path, value in accepted:
        d = mutated(BASE_SOLID, path, value)
        try:
            ds = run_with_timeout(from_dict(d), RUN_TIMEOUT_S)
        except SimulationError as err:  # pragma: no cover - what the test exists to catch
            pytest.fail(f"{path} = {value!r} passed validation but the run failed: {err}")
        for var in ("E_shock", "E_granular", "E_plate", "energy_residual"):
            assert np.isfinite(ds[var].values).all(), (path, value, var)
        assert float(ds.time[-1]) == pytest.approx(d["time"]["t_end"]), (path, value)
