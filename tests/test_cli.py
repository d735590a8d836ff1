"""Command line: runs a preset and a custom file, writes the JSON summary, lists and
prints presets, and refuses bad input with one clear line (no traceback)."""
from __future__ import annotations

import json

import pytest

from granplate.cli import main
from granplate.setup.io import load

SUMMARY_KEYS = {
    "e_shock", "ep_max_fraction", "ep_final_fraction", "eg_final_fraction", "dissipated_fraction",
    "max_von_mises", "max_eps_yy", "energy_residual_max", "n_steps", "wall_time_s",
}


def test_run_preset_writes_result_and_summary(tmp_path, capsys):
    """`granplate run steel-r1 --t-end 2e-5`: netCDF, summary table and JSON with the keys."""
    out, js = tmp_path / "r.nc", tmp_path / "s.json"
    assert main(["run", "steel-r1", "--t-end", "2e-5", "-o", str(out), "--summary", str(js), "-q"]) == 0
    text = capsys.readouterr().out
    assert "E_shock" in text and "max von Mises" in text and "MPa" in text
    s = json.loads(js.read_text())
    assert SUMMARY_KEYS <= set(s)
    assert s["e_shock"] == pytest.approx(7.48e-4, rel=0.01)
    assert out.exists()


def test_preset_as_toml_runs_like_the_preset(tmp_path, capsys):
    """`granplate preset NAME -o f.toml` then `granplate run f.toml` gives the same numbers."""
    f = tmp_path / "p.toml"
    assert main(["preset", "ptfe-r05-weak", "-o", str(f)]) == 0
    assert load(f).load.q0 == 2000.0
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert main(["run", str(f), "--t-end", "1e-5", "-o", str(tmp_path / "a.nc"), "--summary", str(a), "-q"]) == 0
    assert main(["run", "ptfe-r05-weak", "--t-end", "1e-5", "-o", str(tmp_path / "b.nc"), "--summary", str(b), "-q"]) == 0
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


def test_unknown_preset_and_bad_t_end(capsys):
    """Unknown preset or a non-positive --t-end: exit 2 with the allowed values named."""
    assert main(["run", "no-such-case"]) == 2
    assert "presets are" in capsys.readouterr().err
    assert main(["run", "steel-r1", "--t-end", "-1"]) == 2
    assert "must be > 0" in capsys.readouterr().err
