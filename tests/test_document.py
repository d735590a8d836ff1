"""One renderer for the report and the verification page: every block kind comes out in
Markdown and HTML, verdict cells are coloured, links and anchors survive, and figures are
embedded or linked as asked."""
from __future__ import annotations

from pathlib import Path

from granplate.results.document import Block, to_html, to_markdown


def _blocks(png: Path) -> list[Block]:
    return [
        Block("h1", "Title"), Block("h3", "A case", anchor="case-a"),
        Block("p", "See [case](#case-a) and **this** `code`."),
        Block("table", header=("case", "result"), rows=(("a | b", "pass"), ("c", "**FAIL**"))),
        Block("quote", "a note"), Block("code", "Traceback\n  x"),
        Block("markdown", "#### Study\n\n| h | e |\n|---|---|\n| 1 | 2 |"),
        Block("figure", "Fig. 1", path=png), Block("image", "linked", path=Path("figs/x.png")),
    ]


def test_markdown_of_every_kind(tmp_path):
    png = tmp_path / "f.png"
    png.write_bytes(b"\x89PNG fake")
    md = to_markdown(_blocks(png), tmp_path)
    for piece in ('<a id="case-a"></a>\n\n### A case', "| a \\| b | pass |", "| c | **FAIL** |", "> a note",
                  "```\nTraceback\n  x\n```", "#### Study", "![Fig. 1](f.png)", "![linked](figs/x.png)"):
        assert piece in md, piece


def test_html_embeds_or_links(tmp_path):
    png = tmp_path / "f.png"
    png.write_bytes(b"\x89PNG fake")
    embedded = to_html(_blocks(png), tmp_path)
    assert "data:image/png;base64," in embedded and "<td class='yes'>pass</td>" in embedded
    assert "<td class='no'>FAIL</td>" in embedded and "<h3 id='case-a'>" in embedded
    assert "<a href='#case-a'>case</a>" in embedded and "<blockquote>" in embedded and "<pre>" in embedded
    assert "<h4>Study</h4>" in embedded and "src='figs/x.png'" in embedded
    linked = to_html(_blocks(png), tmp_path, embed=False)
    assert "base64" not in linked and "src='f.png'" in linked
