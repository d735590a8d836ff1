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
    points at a file that exists, and at an anchor of that page where it names one (the
    check the site build runs, and the README's, which the site does not build)."""
    mod = _ext()
    mod.generate()  # the reference pages the build generates, which pages link to
    assert mod.broken_links(DOCS) == []
    text = mod.FENCE.sub("", (ROOT / "README.md").read_text())
    assert [t for t in mod.LINK.findall(text) if not re.match(r"^[a-z]+:", t)]
    assert mod.broken_targets(ROOT / "README.md") == []


def test_broken_link_is_found(tmp_path):
    """The link check finds a link to a missing file or to a missing anchor (and ignores
    web links and code); headings, repeated headings, labels and HTML ids are anchors."""
    mod = _ext()
    (tmp_path / "a.md").write_text(
        '# A\n\n## Step 1: `run` it\n\n## Step 1: `run` it\n\n(my-label)=\n<a id="case-x"></a>\n\n'
        "[ok](b.md) [web](https://example.org) [bad](missing.md) [sec](b.md#the-section-31)\n"
        "[here](#step-1-run-it) [again](#step-1-run-it-1) [label](#my-label) [html](#case-x)\n"
        "[no anchor](#nowhere) [no anchor there](b.md#nowhere) [too deep](b.md#deep)\n"
        "```\n[in code](nowhere.md)\n```\n"
    )
    (tmp_path / "b.md").write_text("# b\n\n### The section (3.1)\n\n#### Deep\n")
    assert mod.broken_links(tmp_path) == [
        ("a.md", "missing.md"),
        ("a.md", "#nowhere"),
        ("a.md", "b.md#nowhere"),
        ("a.md", "b.md#deep"),
    ]


#: where the package and the tests name a page of docs/, and a numbered section of the model
DOC_PATH = re.compile(r"docs/([A-Za-z0-9_/-]+\.(?:md|toml|json|py))")
MODEL_SECTION = re.compile(r"docs/model\.md,? sections? (\d+(?:\.\d+)?)")


def test_pages_the_package_names_exist():
    """Every docs/ file that the package's messages and docstrings (and the tests) name
    exists, and every "docs/model.md section N.M" they cite is a numbered heading there."""
    headings = set(re.findall(r"^#{2,4} (\d+(?:\.\d+)?)[. ]", (DOCS / "model.md").read_text(), re.M))
    assert {"3.6", "4.4", "7"} <= headings
    missing_files, missing_sections = set(), set()
    for source in [*(ROOT / "granplate").rglob("*.py"), *(ROOT / "tests").glob("*.py")]:
        text = source.read_text()
        missing_files |= {f"{source.name}: docs/{m}" for m in DOC_PATH.findall(text) if not (DOCS / m).exists()}
        missing_sections |= {f"{source.name}: section {m}" for m in MODEL_SECTION.findall(text) if m not in headings}
    assert sorted(missing_files) == []
    assert sorted(missing_sections) == []


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


def test_gallery_shows_each_figure_with_its_scenario(tmp_path):
    """Every committed figure of docs/figures/ is in the gallery with the command that drew
    it and each scenario it was made from (a preset written as TOML, or a file of docs/);
    the 3D box's file is the scenario the 3D figure tests draw (`BOX`)."""
    import copy

    from granplate.setup import io
    from granplate.setup.presets import preset

    mod = _ext()
    page = mod.gallery_page(DOCS, tmp_path)
    for name in sorted(p.name for p in (DOCS / "figures").glob("*.png")):
        what, made, sources = mod.FIGURES[name]
        assert f"](../../figures/{name})" in page and made and sources, name
        for source in sources:
            if source.endswith(".toml"):
                assert f"```{{literalinclude}} ../../{source}" in page and (DOCS / source).is_file()
            else:
                written = tmp_path / mod.GALLERY_SCENARIOS / f"{source}.toml"
                assert io.loads(written.read_text()) == preset(source)
    sys.path.insert(0, str(ROOT / "tests"))
    from test_figures_3d import BOX

    assert io.dumps(io.load_scenario(DOCS / "gallery" / "box-3d.toml")) == io.dumps(io.from_dict(copy.deepcopy(BOX)))


#: a MyST include of part of a page: its file, and the text after which and before which it cuts
INCLUDE_PART = re.compile(r"```\{include\} (\S+)\n((?::[a-z-]+:.*\n)*)```")


def test_included_parts_are_found_in_their_pages():
    """Every part of a long page that an explanation or how-to includes (by the headings it
    starts after and ends before) is found there, start before end, and is not empty: a
    heading renamed in docs/model.md or docs/scenario.md is caught here before the build."""
    parts = 0
    for page in sorted(DOCS.rglob("*.md")):
        if "_build" in page.parts:
            continue
        for target, options in INCLUDE_PART.findall(page.read_text()):
            opts = dict(re.findall(r"^:([a-z-]+):\s*(.*)$", options, re.M))
            text = (page.parent / target).read_text()
            start, end = (opts.get(k, "").strip().strip("'\"") for k in ("start-after", "end-before"))
            i = text.find(start) if start else 0
            assert i >= 0, f"{page.relative_to(DOCS)}: {start!r} is not in {target}"
            rest = text[i + len(start) :]
            j = rest.find(end) if end else len(rest)
            assert j >= 0, f"{page.relative_to(DOCS)}: {end!r} is not after {start!r} in {target}"
            assert rest[:j].strip(), f"{page.relative_to(DOCS)}: the part of {target} is empty"
            parts += 1
    assert parts >= 9
