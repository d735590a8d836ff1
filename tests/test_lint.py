"""The code passes its lint (ruff, the rules of [tool.ruff] in pyproject.toml) and the type
check of its public API (mypy, [tool.mypy]): each tool run as CI runs it, on the
repository, its findings printed when it fails."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run(tool: str, *args: str) -> None:
    """Run `python -m TOOL ARGS` in the repository; skip when the tool is not installed
    (it comes with the test extra: pip install ".[test]")."""
    if importlib.util.find_spec(tool) is None:
        pytest.skip(f'{tool} is not installed (pip install ".[test]" installs it)')
    done = subprocess.run([sys.executable, "-m", tool, *args], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f"{tool} {' '.join(args)} found:\n{done.stdout}{done.stderr}"


def test_ruff_lint():
    """`ruff check` finds nothing in the package, its tests and the docs' scripts."""
    _run("ruff", "check", "--no-cache", "granplate", "tests", "docs")


def test_mypy_public_api():
    """`mypy` finds no type error in the public API's modules (the files of [tool.mypy])."""
    _run("mypy")


def test_ruff_format():
    """`ruff format --check` finds every file already in the project's format
    ([tool.ruff.format]): the code is written as the formatter writes it."""
    _run("ruff", "format", "--check", "--no-cache", "granplate", "tests", "docs")
