"""The documentation site builds with no warning, and what its pages tell a newcomer to type
is real: every relative link points at a file, every `granplate ...` line of the
getting-started and how-to pages parses with the command's own parser and names files
that exist, every README link resolves.

Truth: Sphinx itself (-W: any warning fails, nitpicky cross-references, the tutorials
executed), the package's argparse parser, the file system.
"""

from __future__ import annotations

import importlib.util
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: pages whose shell blocks a newcomer types as written
COMMAND_PAGES = sorted([*(DOCS / "getting-started").glob("*.md"), *(DOCS / "how-to").glob("*.md")])
#: files a command of those pages writes before a later command reads it
WRITTEN_BY_AN_EARLIER_COMMAND = {
    "steel-r1.nc",
    "my.toml",
    "softer.toml",
    "fcc.nc",
    "ptfe-r05.nc",
    "results",
    "my-assembly.toml",
    "q0-r2",
}


def _ext():
    spec = importlib.util.spec_from_file_location("granplate_docs", DOCS / "_ext" / "granplate_docs.py")
    mod = importlib.util.module_from_spec(spec)
    if importlib.util.find_spec("sphinx") is None:
        pytest.skip("sphinx is not installed (python -m pip install '.[docs]')")
    spec.loader.exec_module(mod)
    return mod


def shell_commands(page: Path) -> list[list[str]]:
    """The `granplate ...` command lines of a page's ```bash blocks, split as a shell would
    (comments dropped, `&&` chains split)."""
    lines = []
    for block in re.findall(r"```bash\n(.*?)```", page.read_text(), re.S):
        for line in block.splitlines():
            for part in line.split("&&"):
                words = shlex.split(part, comments=True)
                for k, w in enumerate(words):  # a redirection or a pipe ends the command
                    if w in (">", ">>", "|", "2>"):
                        words = words[:k]
                        break
                if words and words[0] == "granplate":
                    lines.append(words[1:])
    return lines


def test_pages_have_commands():
    """The getting-started pages show commands (else the test below checks nothing)."""
    assert sum(len(shell_commands(p)) for p in COMMAND_PAGES) >= 20


@pytest.mark.parametrize("page", COMMAND_PAGES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_commands_parse(page: Path):
    """Every granplate command of the page parses with granplate's own parser (an unknown
    option or subcommand exits), and every file it reads from the repository exists."""
    from granplate.cli import build_parser

    parser = build_parser()
    for words in shell_commands(page):
        try:
            parser.parse_args(words)
        except SystemExit as stop:  # argparse's way of refusing (and of ending --help)
            if stop.code == 0:
                continue
            pytest.fail(f"{page.name}: 'granplate {' '.join(words)}' does not parse (exit {stop.code})")
        for w in words:
            if re.match(r"^docs/.*\.(toml|md)$", w):
                assert (ROOT / w).exists(), f"{page.name}: {w}"


def test_relative_links_resolve():
    """Every relative link or image of every Markdown page under docs/ and of the README
    points at a file that exists (the check the site build runs, and the README's)."""
    mod = _ext()
    mod.generate()  # the reference pages the build generates, which pages link to
    assert mod.broken_links(DOCS) == []
    text = mod.FENCE.sub("", (ROOT / "README.md").read_text())
    targets = [t for t in mod.LINK.findall(text) if not re.match(r"^[a-z]+:", t)]
    assert targets
    assert [t for t in targets if not (ROOT / t.split("#")[0]).exists()] == []


def test_broken_link_is_found(tmp_path):
    """The link check finds a link to a missing file (and ignores web links and anchors)."""
    mod = _ext()
    (tmp_path / "a.md").write_text(
        "[ok](b.md) [web](https://example.org) [here](#x) [bad](missing.md)\n```\n[in code](nowhere.md)\n```\n"
    )
    (tmp_path / "b.md").write_text("# b\n")
    assert mod.broken_links(tmp_path) == [("a.md", "missing.md")]


def test_scenario_reference_covers_every_key():
    """The generated scenario reference has a row for every field of every scenario
    dataclass, and every number there has a unit (from the code's unit table)."""
    import dataclasses

    mod = _ext()
    page = mod.scenario_fields_page()
    for _, anchor, cls, *_ in mod._tables():
        section = re.split(r"\n\([a-z-]+\)=\n", page.split(f"({anchor})=")[1])[0]
        for f in dataclasses.fields(cls):
            if cls.__name__ == "Scenario" and f.name in mod.SCENARIO_TABLES:
                continue
            if (cls.__name__, f.name) == ("Material", "name"):
                continue
            row = re.search(rf"^\| `{f.name}` \| ([^|]*) \| ([^|]*) \|", section, re.M)
            assert row, f"{cls.__name__}.{f.name}"
            if row.group(1).startswith(("number", "integer")):
                assert row.group(2).strip(), f"{cls.__name__}.{f.name} has no unit"
    # the validator's words: a range shown is the message a bad value gets
    assert "must be in [0.41421356, 1] (sqrt(2)-1 <= R2/R1 <= 1)" in page


@pytest.mark.skipif(
    importlib.util.find_spec("sphinx") is None or importlib.util.find_spec("myst_nb") is None,
    reason="sphinx and myst-nb are not installed (python -m pip install '.[docs]')",
)
def test_site_builds_without_warnings(tmp_path):
    """`python -m sphinx -W --keep-going -b html docs OUT` succeeds: no warning (broken
    reference, missing file, docstring markup), every tutorial executed without error."""
    out = tmp_path / "html"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "sphinx",
            "-W",
            "--keep-going",
            "-q",
            "-b",
            "html",
            "-d",
            str(tmp_path / "doctrees"),
            str(DOCS),
            str(out),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    for page in (
        "index.html",
        "reference/api.html",
        "reference/cli.html",
        "reference/generated/scenario-fields.html",
        "tutorials/paper-energies.html",
        "studies/intruder-map/report.html",
    ):
        assert (out / page).exists(), page
    tutorial = (out / "tutorials" / "paper-energies.html").read_text()
    assert "largest |energy residual| over the run" in tutorial  # the cell's printed output is on the page
    assert "granplate.simulate" in (out / "reference" / "api.html").read_text()


def test_readme_is_short_and_names_the_commands():
    """The README stays what a newcomer reads in two minutes (at most 120 lines) and names
    the set-up, test and docs-build commands exactly as CI and the docs run them."""
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 120
    for command in (
        "python -m pip install . && granplate reproduce --out results",
        'python -m pip install ".[test]" && python -m pytest -q',
        'python -m pip install ".[docs]" && python -m sphinx -W --keep-going -b html docs docs/_build/html',
    ):
        assert f"```bash\n{command}\n```" in text, command


def test_plain_docstrings_render_without_warnings():
    """A docstring written as the package writes them (|v|, E*, hanging indents, a list,
    a doctest, a trailing '::') becomes reStructuredText that docutils reads without a
    warning once the site's docstring hook has passed over it."""
    import io

    from docutils.core import publish_doctree

    mod = _ext()
    lines = [
        "A sphere: |v| < sqrt(E* / rho), R* = R1 R2 / (R1 + R2).",
        '    kind: "line" or *none*; see `geometry.resolve` for |x|',
        "- a list item",
        "  continued with an indent",
        ">>> gp.preset('steel-r1')",
        "1. first",
        "ends with a colon::",
        "    indented again",
    ]
    mod.plain_docstring(None, "function", "f", None, {}, lines)
    errors = io.StringIO()
    publish_doctree("\n".join(lines), settings_overrides={"warning_stream": errors, "report_level": 2})
    assert errors.getvalue() == ""


def test_result_variables_page_matches_a_run():
    """Every data variable of a real (short) run appears on the generated result-variables
    page with the unit the Dataset itself carries."""
    import granplate as gp

    mod = _ext()
    page = mod.dataset_variables_page()
    ds = gp.simulate(gp.preset("steel-r1"), t_end=2e-5, progress=False)
    assert len(ds.data_vars) > 20
    # the plate's connectivity and contact positions are written outside VARIABLES (with
    # their own attributes; docs/output.md lists them): the page does not claim them; nor
    # the restart state (restart_*, one variable per loop array: docs/output.md "Restart state")
    inline = {"element_nodes", "contact_y"}
    for name, var in ds.data_vars.items():
        if name in inline or name.startswith("restart_"):
            continue
        unit = var.attrs.get("units") or "-"
        assert f"| `{name}` | {unit} |" in page, (name, unit)
