"""The benchmark harness on one tiny case: the JSON report has every documented key."""
from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def documented_keys() -> dict[str, set[str]]:
    """Keys of the docs/benchmarks.md's JSON tables, per section ('top', 'compile', 'results')."""
    text = (ROOT / "docs" / "benchmarks.md").read_text()
    keys: dict[str, set[str]] = {}
    section = None
    for line in text.splitlines():
        m = re.match(r"^###\s+JSON:\s+(\w+)", line)
        if m:
            section = m.group(1)
            keys[section] = set()
            continue
        if line.startswith("## "):
            section = None
        m = re.match(r"^\|\s*`([A-Za-z_0-9]+)`", line)
        if section and m:
            keys[section].add(m.group(1))
    return keys


def main(argv: list[str]) -> int:
    """`granplate bench ARGV` through granplate.bench's own parser (independent of cli.py)."""
    import argparse

    from granplate.bench import cli as bench

    parser = argparse.ArgumentParser(prog="granplate")
    bench.register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return int(args.func(args))


def test_bench_json_has_documented_keys(tmp_path, monkeypatch):
    from granplate.bench import harness as h

    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path))
    out = tmp_path / "bench.json"
    rc = main(["bench", "--cases", "bare-plate", "--t-end", "1e-5", "--repeats", "1", "--json", str(out)])
    assert rc == 0
    report = json.loads(out.read_text())
    keys = documented_keys()
    assert set(keys) == {"top", "compile", "results", "study"}
    assert keys["top"] <= set(report), keys["top"] - set(report)
    assert set(report["compile"]) == set(report["schemes"])
    for c in report["compile"].values():
        assert keys["compile"] <= set(c), keys["compile"] - set(c)
    assert len(report["results"]) == len(report["schemes"])
    for r in report["results"]:
        assert keys["results"] <= set(r), keys["results"] - set(r)
        assert set(r["rel_error"]) == set(h.METRICS)
        assert r["n_steps"] > 0 and r["dt_min_s"] > 0
    # the reference was cached on disk, keyed by the scenario
    assert list((tmp_path / "bench-reference").glob("bare-plate-*.json"))


def test_bench_unknown_case_is_a_user_error(capsys):
    assert main(["bench", "--cases", "no-such-preset"]) == 2
    assert "unknown case" in capsys.readouterr().err


def test_bench_study_json_has_documented_keys(tmp_path):
    """`granplate bench --study` on a tiny study: every design computed, the JSON has every
    documented key, and the shares are consistent (loop + overhead = the whole)."""
    out = tmp_path / "study.json"
    assert main(["bench", "--study", "--designs", "4", "--workers", "2", "--t-end", "1e-5",
                 "--json", str(out)]) == 0
    report = json.loads(out.read_text())
    keys = documented_keys()["study"]
    assert keys == set(report), keys ^ set(report)
    assert report["designs"] == report["designs_ok"] == 4 and report["workers"] == 2
    assert report["loop_share"] * (1.0 + report["overhead_vs_loop"]) == pytest.approx(1.0)
    assert 0.0 < report["loop_vs_task_median"] <= 1.0 and report["task_cpu_s_median"] > 0
