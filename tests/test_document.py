"""One renderer for the report and the verification page: every block kind comes out in
Markdown and HTML, verdict cells are coloured, links and anchors survive, figures are
embedded or linked as asked, summaries and details render in both, and every HTML table
is boxed and sortable by an inlined script (tests/test_pages_browser.py runs it)."""

from __future__ import annotations

from pathlib import Path

from granplate.results.document import TABLE_SCRIPT, Block, details, markdown_to_html, summary, to_html, to_markdown


def _blocks(png: Path) -> list[Block]:
    return [
        Block("h1", "Title"),
        Block("h3", "A case", anchor="case-a"),
        Block("p", "See [case](#case-a) and **this** `code`."),
        Block("table", header=("case", "result"), rows=(("a | b", "pass"), ("c", "**FAIL**"))),
        Block("quote", "a note"),
        Block("code", "Traceback\n  x"),
        Block("markdown", "#### Study\n\n| h | e |\n|---|---|\n| 1 | 2 |"),
        Block("figure", "Fig. 1", path=png),
        Block("image", "linked", path=Path("figs/x.png")),
    ]


def test_markdown_of_every_kind(tmp_path):
    png = tmp_path / "f.png"
    png.write_bytes(b"\x89PNG fake")
    md = to_markdown(_blocks(png), tmp_path)
    for piece in (
        '<a id="case-a"></a>\n\n### A case',
        "| a \\| b | pass |",
        "| c | **FAIL** |",
        "> a note",
        "```\nTraceback\n  x\n```",
        "#### Study",
        "![Fig. 1](f.png)",
        "![linked](figs/x.png)",
    ):
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


def test_summary_block_in_both_renderings(tmp_path):
    """A summary is its headline and one card per key figure, toned in HTML, a list in Markdown."""
    b = summary("3 of 4 checks pass.", [("3 / 4", "checks pass", "no"), ("12 s", "to run")])
    md = to_markdown([b], tmp_path)
    assert md == "**3 of 4 checks pass.**\n\n- **3 / 4** checks pass\n- **12 s** to run\n"
    page = to_html([b], tmp_path)
    assert "<section class='summary'><p class='headline'>3 of 4 checks pass.</p>" in page
    assert "<div class='card no'><span class='value'>3 / 4</span><span class='label'>checks pass</span></div>" in page
    assert "<div class='card'><span class='value'>12 s</span>" in page


def test_details_block_hides_its_content_until_opened(tmp_path):
    """A details block is a <details> element in both renderings, its content rendered inside."""
    b = details("Tolerances (2 checks)", [Block("p", "- a: why"), Block("table", header=("x",), rows=(("1",),))])
    md = to_markdown([Block("p", "before"), b], tmp_path)
    assert "<details><summary>Tolerances (2 checks)</summary>\n\n- a: why\n\n| x |\n|---|\n| 1 |\n\n</details>" in md
    page = to_html([b], tmp_path)
    assert page.count("<details>") == 1 and "<details open" not in page
    inside = page[page.index("<details>") : page.index("</details>")]
    assert "<summary>Tolerances (2 checks)</summary>" in inside and "<li>a: why</li>" in inside
    assert "<table>" in inside


def test_every_table_is_boxed_and_sortable_with_the_script_inlined(tmp_path):
    """Each table (blocks and raw Markdown) sits in a scrolling box with a header row, and
    the page carries its sorting script and style inline: nothing is fetched."""
    page = to_html(_blocks(tmp_path / "missing.png"), tmp_path, embed=False)
    assert page.count("<div class='table-box'><table><thead><tr><th scope='col'>") == 2
    assert "<th scope='col'>case</th><th scope='col'>result</th>" in page
    assert "<th scope='col'>h</th><th scope='col'>e</th></tr></thead><tbody><tr><td>1</td>" in page
    assert f"<script>{TABLE_SCRIPT}</script>" in page and "aria-sort" in TABLE_SCRIPT
    assert ".table-box {" in page and "overflow: auto" in page and "position: sticky" in page
    assert "<script src" not in page and "<link rel='stylesheet'" not in page and "http" not in page


def test_markdown_of_existing_blocks_is_unchanged(tmp_path):
    """The Markdown of a table, paragraph and heading is what the docs pages hold."""
    md = to_markdown(
        [Block("h2", "Results"), Block("table", header=("a", "b"), rows=(("1", "x | y"),)), Block("p", "text")],
        tmp_path,
    )
    assert md == "## Results\n\n| a | b |\n|---|---|\n| 1 | x \\| y |\n\ntext\n"


def test_escaped_pipes_in_raw_markdown_tables_stay_in_their_cell():
    """A \\| in a raw Markdown table is a pipe inside the cell, not a new column."""
    out = markdown_to_html("| q | v |\n|---|---|\n| \\|1 - e\\| | 2 |")
    assert "<td>|1 - e|</td><td>2</td>" in out
