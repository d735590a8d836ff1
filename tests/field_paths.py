"""Dotted field paths of a TOML-shaped scenario dict, for the fuzz tests (tests/test_fuzz.py,
tests/test_scenario_3d.py): every numeric field's path, and a copy with one field set."""

from __future__ import annotations

import copy
import re


def numeric_fields(d, prefix: str = "") -> list[str]:
    """Dotted paths of every number in a TOML-shaped dict (indices as in TOML: [i])."""
    if isinstance(d, dict):
        return [p for k, v in d.items() for p in numeric_fields(v, f"{prefix}.{k}" if prefix else k)]
    if isinstance(d, list):
        return [p for i, v in enumerate(d) for p in numeric_fields(v, f"{prefix}[{i}]")]
    return [prefix] if isinstance(d, (int, float)) and not isinstance(d, bool) else []


def mutated(base: dict, path: str, value) -> dict:
    """A deep copy of `base` with the field at dotted `path` set to `value`."""
    d = copy.deepcopy(base)
    steps = [int(s) if s.isdigit() else s for s in re.findall(r"[^.\[\]]+", path)]
    node = d
    for step in steps[:-1]:
        node = node[step]
    node[steps[-1]] = value
    return d
