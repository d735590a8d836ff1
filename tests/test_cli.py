"""Command line: runs a preset and a custom file, writes the JSON summary, lists and
prints presets, and refuses bad input with one clear line (no traceback)."""

from __future__ import annotations

import json
import math

import pytest

from granplate.cli import main
from granplate.setup.io import load

SUMMARY_KEYS = {
    "e_shock",
    "e_initial",
    "e_in",
    "e_in_max",
    "ep_max_fraction",
    "ep_final_fraction",
    "ep_dynamic_max_fraction",
    "eg_max_fraction",
    "eg_final_fraction",
    "dissipated_fraction",
    "max_von_mises",
    "max_von_mises_disc",
    "max_eps_yy",
    "energy_residual_max",
    "n_steps",
    "threads",
    "wall_time_s",
    "loop_time_s",
    "t_end",
    "plastic_fraction",
    "max_contact_pressure",
    "yield_onset_ratio",
    "contact_pairs",
    "e_load_taken",
    "e_gravity",
    "e_drive",
    "compile_time_s",
}

#: Two steel spheres (R = 1 cm) 0.4 mm apart closing at 2 m/s: no plate, no load.
TWO_SPHERES = """name = "two-spheres"
[[granules]]
x = 0.0
y = 0.0
radius = 0.01
material = "steel"
vx = 1.0
[[granules]]
x = 0.0204
y = 0.0
radius = 0.01
material = "steel"
vx = -1.0
[load]
kind = "none"
[time]
t_end = 4e-4
output_interval = 1e-7
field_interval = 1e-6
"""


def test_run_preset_writes_result_and_summary(tmp_path, capsys):
    """`granplate run steel-r1 --t-end 2e-5`: netCDF, summary table and JSON with the keys."""
    out, js = tmp_path / "r.nc", tmp_path / "s.json"
    assert main(["run", "steel-r1", "--t-end", "2e-5", "-o", str(out), "--summary", str(js), "-q"]) == 0
    text = capsys.readouterr().out
    assert "E_shock" in text and "max von Mises" in text and "MPa" in text
    # a run from rest: the fractions are of E_shock, and the table says so
    assert "plate energy, peak / E_shock" in text and "E_initial" not in text
    s = json.loads(js.read_text())
    assert SUMMARY_KEYS <= set(s)
    assert set(s["units"]) == SUMMARY_KEYS  # every number has its unit
    assert (s["units"]["e_shock"], s["units"]["max_von_mises"], s["units"]["t_end"]) == ("J", "Pa", "s")
    assert s["units"]["contact_pairs"]["max_contact_pressure"] == "Pa"
    assert {p["pair"] for p in s["contact_pairs"]} == {"steel-plate", "steel-steel", "steel-wall"}
    assert s["max_contact_pressure"] == max(p["max_contact_pressure"] for p in s["contact_pairs"])
    assert s["e_shock"] == pytest.approx(7.48e-4, rel=0.01)
    assert s["e_in"] == s["e_shock"] + s["e_initial"] and s["e_initial"] == 0.0  # from rest: exactly
    assert out.exists()


def test_summary_fractions_are_of_e_in(tmp_path):
    """Each *_fraction is the stated energy divided by e_in = E_shock(t_end) + E_initial."""
    from granplate.results.dataset import read, summary

    out = tmp_path / "r.nc"
    assert main(["run", "steel-r1", "--t-end", "2e-5", "-o", str(out), "-q"]) == 0
    ds = read(out)
    s = summary(ds)
    e_in = float(ds.E_shock[-1]) + float(ds.attrs["E_initial"])
    assert s["e_in"] == e_in
    assert s["ep_max_fraction"] == float(ds.E_plate.max()) / e_in
    assert s["eg_final_fraction"] == float(ds.E_granular[-1]) / e_in
    assert s["dissipated_fraction"] == float(ds.D_viscous[-1] + ds.D_friction[-1]) / e_in


def test_run_without_plate_or_load(tmp_path, capsys):
    """No load: the fractions are of the initial kinetic energy m v^2 (two spheres of mass m
    at 1 m/s) and say so; no plate: plate metrics are null in the JSON and "-" in the table;
    granular energy + dissipated = E_initial (eq. 11)."""
    f, js = tmp_path / "two.toml", tmp_path / "s.json"
    f.write_text(TWO_SPHERES)
    assert main(["run", str(f), "-o", str(tmp_path / "r.nc"), "--summary", str(js), "-q"]) == 0
    text = capsys.readouterr().out
    s = json.loads(js.read_text())
    mass = 4.0 / 3.0 * math.pi * 0.01**3 * 7850.0
    assert s["e_shock"] == 0.0
    assert s["e_initial"] == pytest.approx(mass * 1.0**2, rel=1e-12)
    assert s["e_in"] == s["e_initial"]
    for k in ("ep_max_fraction", "ep_final_fraction", "max_von_mises", "max_von_mises_disc", "max_eps_yy"):
        assert s[k] is None, k
    assert s["eg_final_fraction"] + s["dissipated_fraction"] == pytest.approx(1.0, abs=1e-6)
    assert s["dissipated_fraction"] > 0.001  # the spheres did collide (damped contact)
    rows = {line[:36].strip(): line[36:].split() for line in text.splitlines()}
    assert rows["max von Mises stress"] == ["-", "MPa"]
    assert rows["plate energy, peak / E_initial"] == ["-", "-"]
    assert rows["granular energy, peak / E_initial"][0] == "1.0000"
    assert "E_shock" not in "".join(k for k in rows if "/" in k)


def test_format_summary_names_the_reference_energy():
    """With both a load and initial motion the fractions are of E_in, shown as a row."""
    from granplate.cli import format_summary

    s = {"e_shock": 1e-3, "e_initial": 3e-3, "e_in": 4e-3, "ep_max_fraction": 0.25, "max_von_mises": 2.5e7}
    text = format_summary(s)
    assert "E_in, the energy put in (their sum)" in text and "4.0000e-03" in text
    assert "plate energy, peak / E_in" in text and "0.2500" in text
    assert "25.00" in text  # Pa shown in MPa


def test_preset_as_toml_runs_like_the_preset(tmp_path, capsys):
    """`granplate preset NAME -o f.toml` then `granplate run f.toml` gives the same numbers."""
    f = tmp_path / "p.toml"
    assert main(["preset", "ptfe-r05-weak", "-o", str(f)]) == 0
    assert load(f).load.q0 == 2000.0
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert main(["run", str(f), "--t-end", "1e-5", "-o", str(tmp_path / "a.nc"), "--summary", str(a), "-q"]) == 0
    assert (
        main(["run", "ptfe-r05-weak", "--t-end", "1e-5", "-o", str(tmp_path / "b.nc"), "--summary", str(b), "-q"]) == 0
    )
    sa, sb = json.loads(a.read_text()), json.loads(b.read_text())
    for k in ("e_shock", "ep_max_fraction", "max_von_mises", "n_steps"):
        assert sa[k] == sb[k]


def test_presets_lists_six(capsys):
    """`granplate presets` lists the paper's six cases."""
    assert main(["presets"]) == 0
    out = capsys.readouterr().out
    for name in ("bare-plate", "steel-r1", "steel-r05", "ptfe-r05", "ptfe-r05-moderate", "ptfe-r05-weak"):
        assert name in out


@pytest.mark.parametrize(
    "old, new, field",
    [
        ("R2_ratio = 0.5", "R2_ratio = 0.2", "layout.R2_ratio"),
        ("thickness = 0.001", "thickness = 0.0", "plate.thickness"),
        ("nu = 0.42", "nu = 0.5", "materials.ptfe.nu"),
        ("nx = 4", "nxx = 4", "plate.nxx"),
        ("q0 = 50000.0", "q0 = -1.0", "load.q0"),
    ],
)
def test_bad_file_is_refused_with_field_name(tmp_path, capsys, old, new, field):
    """A bad scenario file: exit 2 before running, one line naming the field, no traceback."""
    src = tmp_path / "s.toml"
    main(["preset", "ptfe-r05", "-o", str(src)])
    text = src.read_text()
    assert old in text
    src.write_text(text.replace(old, new))
    capsys.readouterr()
    assert main(["run", str(src), "-q", "-o", str(tmp_path / "x.nc")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert f"'{field}'" in err
    assert not (tmp_path / "x.nc").exists()


def test_run_output_folder_is_checked_before_the_run(tmp_path, capsys, monkeypatch):
    """`-o` naming an existing folder writes NAME.nc in it; a folder that does not exist is
    refused before the run (exit 2, one line naming -o), so no result is lost at its end."""
    assert main(["run", "steel-r1", "--t-end", "2e-6", "-o", str(tmp_path), "-q"]) == 0
    assert (tmp_path / "steel-r1.nc").exists()
    capsys.readouterr()
    ran = []
    monkeypatch.setattr("granplate.results.run.simulate", lambda *a, **k: ran.append(1))
    assert main(["run", "steel-r1", "-o", str(tmp_path / "no" / "r.nc"), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("granplate: error: -o ") and "does not exist" in err and err.count("\n") == 1
    assert not ran


def test_unknown_preset_and_bad_t_end(capsys):
    """Unknown preset or a non-positive --t-end: exit 2 with the allowed values named."""
    assert main(["run", "no-such-case"]) == 2
    assert "presets are" in capsys.readouterr().err
    assert main(["run", "steel-r1", "--t-end", "-1"]) == 2
    assert "must be > 0" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["-1e-4", "-1E-4", "-inf", "0", "nan", "1e300"])
def test_bad_t_end_is_the_time_t_end_field_error(tmp_path, capsys, value):
    """`--t-end -1e-4` (a negative number in exponent form, which argparse alone takes for
    an option) and other bad values: exit 2 with the field error of time.t_end."""
    assert main(["run", "steel-r1", "--t-end", value, "-q", "-o", str(tmp_path / "x.nc")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("granplate: error: scenario field 'time.t_end'") and err.count("\n") == 1
    assert "expected one argument" not in err and not (tmp_path / "x.nc").exists()


def test_negative_values_reach_their_options():
    """Every option that takes a value gets a negative number written after it as its value;
    flags, positionals and other dashes are left alone."""
    from granplate.cli import build_parser, join_negative_values

    p = build_parser()
    assert join_negative_values(p, ["run", "x", "--t-end", "-1e-4", "-q"]) == ["run", "x", "--t-end=-1e-4", "-q"]
    assert join_negative_values(p, ["run", "x", "-q", "-1e-4"]) == ["run", "x", "-q", "-1e-4"]
    assert join_negative_values(p, ["run", "x", "--t-end", "-q"]) == ["run", "x", "--t-end", "-q"]
    assert p.parse_args(join_negative_values(p, ["run", "x", "--t-end", "-2.5e-3"])).t_end == -2.5e-3


def test_cache_info_and_clear(tmp_path, monkeypatch, capsys):
    """`granplate cache info` lists the entries a plate build stored; `clear` removes them."""
    import granplate as gp

    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path))
    gp.build_model(gp.preset("bare-plate"))
    assert main(["cache", "info"]) == 0
    lines = {line.split()[0]: line.split()[1:] for line in capsys.readouterr().out.splitlines()[2:]}
    assert int(lines["plate"][0]) == 1 and float(lines["plate"][1]) > 0
    assert main(["cache", "clear", "--kind", "plate"]) == 0
    assert "removed 1 entries" in capsys.readouterr().out
    assert main(["cache", "info"]) == 0
    assert "plate" not in capsys.readouterr().out.split("total")[0].split("MiB")[-1]


#: Modules only some subcommands need: none may load to parse the command line.
HEAVY_MODULES = ("matplotlib", "dask", "distributed", "optuna")


@pytest.mark.parametrize(
    "code",
    [
        "import granplate",
        "import granplate.cli",
        "import granplate.cli, contextlib, io\n"
        "with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):\n"
        "    granplate.cli.main(['--help'])",
    ],
)
def test_start_up_imports_no_heavy_module(code):
    """Truth: a fresh interpreter's sys.modules after `import granplate`, `import
    granplate.cli` and `granplate --help` holds none of matplotlib, dask, distributed, optuna."""
    import subprocess
    import sys

    probe = code + "\nimport sys\nprint(' '.join(m for m in sys.modules if m.split('.')[0] in %r))" % (HEAVY_MODULES,)
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    loaded = done.stdout.strip().splitlines()[-1] if done.stdout.strip() else ""
    assert loaded == "", f"loaded at start-up: {loaded}"


def test_a_run_process_writes_its_result_without_loading_dask(tmp_path):
    """Truth: with Dask marked absent (`keep_dask_out`, as `granplate run` does in its own
    process), xarray builds and writes a netCDF result that reads back equal, and neither
    dask nor distributed is loaded."""
    import subprocess
    import sys

    path = tmp_path / "r.nc"
    probe = (
        "import sys\nfrom granplate.cli import keep_dask_out\nkeep_dask_out()\n"
        "import numpy as np, xarray as xr\n"
        f"xr.Dataset({{'a': ('t', np.arange(3.0))}}).to_netcdf({str(path)!r})\n"
        f"back = xr.load_dataset({str(path)!r})\nassert back.a.values.tolist() == [0.0, 1.0, 2.0]\n"
        "print(' '.join(m for m, v in sys.modules.items() if v is not None and m.split('.')[0] in "
        "('dask', 'distributed')))"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "", f"loaded: {done.stdout.strip()}"


def test_the_library_warnings_print_as_one_line():
    """Truth: in the command line's own process, a warning raised from a granplate module
    prints as the single line `granplate: warning: MESSAGE` (no file, line or source line),
    and a warning from elsewhere as Python prints it."""
    import subprocess
    import sys

    probe = (
        "import warnings\nfrom granplate.cli import show_warnings\nshow_warnings()\n"
        "import granplate.setup.fields as f\n"
        "warnings.warn_explicit('the library says so', UserWarning, f.__file__, 1)\n"
        "warnings.warn_explicit('another package says so', UserWarning, '/elsewhere/x.py', 3)\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    assert lines[0] == "granplate: warning: the library says so"
    assert lines[1] == "/elsewhere/x.py:3: UserWarning: another package says so"
