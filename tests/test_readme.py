"""The README cannot go stale: its Python blocks run as written, its sample summary is what
`granplate run steel-r1` prints, and its sample error is the one a bad R2/R1 gets; the same
for the copies in the getting-started page that reads them line by line.

Truth: the package itself, run on the README's own text.
"""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib
import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
TEXT = README.read_text()
#: the pages that show the sample summary and the sample error: the README and the first run
SAMPLE_PAGES = [README, README.parent / "docs" / "getting-started" / "first-run.md"]
PYTHON_BLOCKS = re.findall(r"```python\n(.*?)```", TEXT, re.S)


def test_readme_has_python_blocks():
    """The README shows Python (else the test below would check nothing)."""
    assert PYTHON_BLOCKS


@pytest.mark.parametrize("index", range(len(PYTHON_BLOCKS)))
def test_python_block_runs(index, tmp_path, monkeypatch, capsys):
    """Each ```python block of README.md runs as written, in an empty directory (Agg backend),
    and the files it says it writes are there."""
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    code = PYTHON_BLOCKS[index]
    exec(compile(code, f"README.md python block {index + 1}", "exec"), {"__name__": "readme"})
    for name in re.findall(r"""(?:savefig|write)\([^"]*"([^"]+)"\)""", code):
        assert (tmp_path / name).exists(), name
    out = capsys.readouterr().out
    for comment in re.findall(r'print\(.*?#\s*"\.\.\.(.+)"', code):
        assert comment.strip() in out


def _sample_summary(text: str) -> list[str]:
    m = re.search(r"<!-- summary: steel-r1 -->\n```\n(.*?)```", text, re.S)
    assert m, "the sample summary block is marked <!-- summary: steel-r1 -->"
    return m.group(1).splitlines()


def test_sample_summary_is_what_a_run_prints():
    """The sample summary of the README and of the first-run page equals the table of a
    steel-r1 run (all rows but the wall time, which depends on the machine)."""
    import granplate as gp
    from granplate.cli import format_summary

    got = format_summary(gp.summary(gp.simulate(gp.preset("steel-r1"), progress=False)))
    got = [line for line in got.splitlines() if not line.startswith("wall time")]
    for page in SAMPLE_PAGES:
        want = [line for line in _sample_summary(page.read_text()) if not line.startswith("wall time")]
        assert want == got, page.name


def test_sample_error_is_the_real_message():
    """The sample refusal of R2/R1 = 0.2 (README, first-run page) is the message validation gives."""
    import granplate as gp
    from granplate.setup.validate import validate

    with pytest.raises(gp.ScenarioError) as err:
        validate(gp.with_changes(gp.preset("ptfe-r05"), {"layout.R2_ratio": 0.2}))
    for page in SAMPLE_PAGES:
        m = re.search(r"granplate: error: (scenario field 'layout.R2_ratio' = 0.2: .*)", page.read_text())
        assert m, page.name
        assert str(err.value) == m.group(1), page.name


def test_model_citations_point_to_existing_sections():
    """Every "docs/model.md section N" (or "sections N-M", "section N.M") cited in the package,
    the docs, the README or the tests names a heading that docs/model.md has."""
    root = README.parent
    headings = set(re.findall(r"^#{2,3} (\d+(?:\.\d+)?)[. ]", (root / "docs" / "model.md").read_text(), re.M))
    assert {"1", "2", "3", "4", "5", "6", "7", "8"} <= headings
    files = [
        README,
        *(p for p in (root / "docs").rglob("*.md") if "_build" not in p.parts),
        *(root / "granplate").rglob("*.py"),
        *(root / "tests").glob("*.py"),
    ]
    cited = []
    for f in files:
        for m in re.finditer(r"docs/model\.md,? sections? (\d+(?:\.\d+)?)(?:-(\d+))?", f.read_text()):
            cited += [(f.name, n) for n in m.groups() if n]
    assert cited
    missing = [(name, n) for name, n in cited if n not in headings]
    assert not missing, missing
