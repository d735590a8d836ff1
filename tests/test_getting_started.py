"""Every getting-started page runs as written: each command of its ```bash blocks, and each
```python block, in the pages' order (a later page reads what an earlier one wrote), in an
empty directory where `docs` is the repository's docs/ (the pages are typed from a clone's
root), and each ends well: exit status 0, no exception, the files it was told to write.

Truth: the command line and the Python API themselves, and the file system.

Run as written, at the pages' own lengths (every run there is short: the whole takes
about 30 s with the kernels compiled, most of it the study's Dask workers starting), except
the set-up commands (`python3 -m venv`, `pip install`, the test command): the environment
running this test is that installation, and the test command is this suite. The granplate
commands run in this process (`granplate.cli.main`), which saves starting Python and
loading the kernels for each; other commands (`sed`), and any with a pipe or a
redirection, run in bash. Only the kernels the
pages' runs need are compiled here (GRANPLATE_COMPILE=own).
"""

from __future__ import annotations

import contextlib
import io
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = ROOT / "docs" / "getting-started"
#: commands of the pages that set up the environment this test runs in (not run here)
SET_UP = ("python3 -m venv", ". .venv/bin/activate", "python -m pip install", "python -m pytest")
#: what only a shell does: a command with these runs through bash
SHELL = re.compile(r"[|;<>$`*]")


def page_order() -> list[Path]:
    """The getting-started pages in the order of their index's toctree."""
    index = (PAGES / "index.md").read_text()
    lines = re.search(r"```\{toctree\}\n(.*?)```", index, re.S).group(1).splitlines()
    return [PAGES / f"{n.strip()}.md" for n in lines if n.strip() and not n.startswith(":")]


def blocks(page: Path) -> list[tuple[str, str]]:
    """The page's ```bash and ```python blocks, as (language, text), in order."""
    return re.findall(r"^```(bash|python)\n(.*?)^```", page.read_text(), re.S | re.M)


def bash_commands(text: str) -> list[str]:
    """The commands of a bash block: a line each, `&&` chains split, comments dropped."""
    out = []
    for line in text.splitlines():
        for part in line.split("&&"):
            part = part.strip()
            if part and not part.startswith("#"):
                out.append(part)
    return out


def written_files(words: list[str]) -> list[str]:
    """The files a granplate command is told to write (-o, --output, --summary, --out)."""
    return [words[k + 1] for k, w in enumerate(words[:-1]) if w in ("-o", "--output", "--summary", "--out")]


def run_granplate(words: list[str]) -> tuple[int, str]:
    """`granplate WORDS` in this process: (exit status, what it printed)."""
    from granplate.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        try:
            code = main(words)
        except SystemExit as stop:  # argparse's end of --help, or its refusal
            code = stop.code if isinstance(stop.code, int) else 1
    return int(code or 0), out.getvalue()


@pytest.fixture
def clone(tmp_path, monkeypatch):
    """An empty directory standing for a clone's root: docs/ is the repository's."""
    (tmp_path / "docs").symlink_to(ROOT / "docs")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("GRANPLATE_COMPILE", "own")  # compile only what these runs need
    monkeypatch.setenv("MPLBACKEND", "Agg")
    return tmp_path


def test_the_pages_have_commands():
    """The pages are found in their order and hold commands (else the test below checks
    nothing): every page has a bash block, and the first run, the 3D run and the study run."""
    pages = page_order()
    assert [p.stem for p in pages[:2]] == ["install", "first-run"] and all(p.exists() for p in pages)
    commands = [c for p in pages for lang, text in blocks(p) if lang == "bash" for c in bash_commands(text)]
    assert all(any(lang == "bash" for lang, _ in blocks(p)) for p in pages)
    for expected in ("granplate run steel-r1", "granplate run docs/examples/3d-fcc.toml", "granplate sweep"):
        assert any(c.startswith(expected) for c in commands), expected


@pytest.mark.filterwarnings("ignore")  # what a run warns (yield, friction's step) is the pages' to say
def test_every_getting_started_page_runs_as_written(clone):
    """Every command and Python block of the getting-started pages, in order, succeeds and
    writes the files it names."""
    import matplotlib

    matplotlib.use("Agg")
    for page in page_order():
        for lang, text in blocks(page):
            if lang == "python":
                exec(compile(text, f"{page.name} (python block)", "exec"), {"__name__": "__page__"})
                continue
            for command in bash_commands(text):
                if command.startswith(SET_UP):
                    continue
                words = shlex.split(command)
                if words[0] == "granplate" and not SHELL.search(command):
                    words = words[1:]
                    code, printed = run_granplate(words)
                    assert code == 0, f"{page.name}: granplate {' '.join(words)} exited {code}:\n{printed[-3000:]}"
                    for name in written_files(words):
                        assert (clone / name).exists(), f"{page.name}: granplate {' '.join(words)} wrote no {name}"
                else:  # through bash, `granplate` being this Python's command line
                    script = f'granplate() {{ "{sys.executable}" -m granplate.cli "$@"; }}\n{command}'
                    proc = subprocess.run(["bash", "-c", script], capture_output=True, text=True, cwd=clone)
                    assert proc.returncode == 0, f"{page.name}: {command}:\n{proc.stderr}"
