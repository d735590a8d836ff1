"""A small document model rendered two ways: Markdown (figures linked) and one HTML
page (PNG figures and animations embedded as base64 unless asked not to), so a page
opens in a browser with no server and no other files. The reproduction report and the
verification page are both written with it.

In HTML every table sits in its own scrolling box (sticky header, long labels wrapped)
and sorts by any column: a click or Enter on a header sorts numerically where the
column's cells are numbers (units, percent, scientific notation), as text otherwise; an
arrow shows the order. The script and the style sheet are inlined (`TABLE_SCRIPT`,
`_CSS`): the page requests nothing. A "summary" block is a first-screen headline with
key figures as cards; a "details" block is a summary line whose content opens on click
(in Markdown: a `<details>` element, which GitHub renders the same way).

    >>> blocks = [Block("h1", "Title"), Block("p", "Some **bold** text."),
    ...           Block("table", header=("a", "b"), rows=(("1", "2"),))]
    >>> to_markdown(blocks, Path("."))
"""

from __future__ import annotations

import base64
import html
import re
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Block:
    """A piece of a page: kind "h1", "h2", "h3", "p", "table", "figure", "image", "media",
    "quote", "code", "markdown", "summary" or "details".

    text: heading / paragraph text (markdown-lite: **bold**, `code`, [links](#x), "- "
    list lines), a quote, a code listing or raw Markdown (tables, #### headings), a
    summary's headline or a details block's summary line;
    header/rows: a table (a "holds" or "result" column is coloured in HTML), or a
    summary's cards, one row each: (value, label) or (value, label, tone), tone "yes"
    (good), "no" (bad) or "" (neutral); path: a figure PNG (captioned with text), an
    image linked as given (alt text: text) or an animation file; anchor: the id of an
    "h3" heading; children: a details block's hidden content.
    """

    kind: str
    text: str = ""
    header: tuple[str, ...] = ()
    rows: tuple[tuple[str, ...], ...] = ()
    path: Path | None = None
    anchor: str = ""
    children: tuple["Block", ...] = ()


def summary(headline: str, cards: list[tuple[str, ...]]) -> Block:
    """A first-screen summary: a headline and key figures, (value, label[, tone]) each."""
    return Block("summary", headline, rows=tuple(tuple(c) for c in cards))


def details(line: str, content: list[Block]) -> Block:
    """A collapsible block: `line` shown, `content` hidden until opened."""
    return Block("details", line, children=tuple(content))


#: Table columns whose cells are verdicts, and the HTML class of each verdict.
VERDICT_COLUMNS = ("holds", "result")
VERDICT_CLASSES = {"yes": "yes", "pass": "yes", "no": "no", "FAIL": "no", "**FAIL**": "no"}


def _md_inline(text: str) -> str:
    """Escape table-cell pipes; a line break becomes a space."""
    return str(text).replace("|", "\\|").replace("\n", " ")


def to_markdown(blocks: list[Block], base: Path) -> str:
    """Render blocks as Markdown; figure and media paths relative to `base`."""
    out = []
    for b in blocks:
        if b.kind == "summary":
            out.append(f"**{b.text}**\n" if b.text else "")
            if b.rows:
                out.append("\n".join(f"- **{c[0]}** {c[1]}" for c in b.rows) + "\n")
        elif b.kind == "details":
            inner = to_markdown(list(b.children), base).rstrip()
            out.append(f"<details><summary>{html.escape(b.text)}</summary>\n\n{inner}\n\n</details>\n")
        elif b.kind in ("h1", "h2", "h3"):
            if b.anchor:
                out.append(f'<a id="{b.anchor}"></a>\n')
            out.append(f"{'#' * int(b.kind[1])} {b.text}\n")
        elif b.kind in ("p", "markdown"):
            out.append(b.text + "\n" if b.text else "")
        elif b.kind == "table":
            out.append("| " + " | ".join(b.header) + " |")
            out.append("|" + "|".join("---" for _ in b.header) + "|")
            for r in b.rows:
                out.append("| " + " | ".join(_md_inline(c) for c in r) + " |")
            out.append("")
        elif b.kind == "figure":
            rel = _relative(b.path, base)
            out.append(f"![{b.text}]({rel})\n\n*{b.text}*\n")
        elif b.kind == "image":
            out.append(f"![{b.text}]({Path(b.path).as_posix()})\n")
        elif b.kind == "media":
            out.append(f"- [{b.text}]({_relative(b.path, base)})")
        elif b.kind == "quote":
            out.append(f"> {b.text}\n")
        elif b.kind == "code":
            out.append(f"```\n{b.text.rstrip()}\n```\n")
    return "\n".join(out).rstrip() + "\n"


def _relative(path: Path | None, base: Path) -> str:
    """path relative to base (as given when it is elsewhere)."""
    if path is None:
        return ""
    try:
        return Path(path).resolve().relative_to(base.resolve()).as_posix()
    except ValueError:
        return Path(path).as_posix()


def _html_inline(text: str) -> str:
    """Escape HTML; **bold**, `code` and [text](url) become tags."""
    s = html.escape(text)
    s = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", s)
    s = re.sub(r"`(.+?)`", r"<code>\1</code>", s)
    return re.sub(r"\[([^\]]+)\]\(([^)\s]+)\)", r"<a href='\2'>\1</a>", s)


_CSS = r"""
body { font-family: system-ui, sans-serif; max-width: 1200px; margin: 2em auto; padding: 0 1em; color: #222; }
h1, h2, h3, h4, p, li, figcaption, summary { overflow-wrap: anywhere; }
.table-box { max-width: 100%; max-height: 75vh; overflow: auto; margin: 1em 0; border: 1px solid #ddd; }
table { border-collapse: separate; border-spacing: 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; border-width: 0 1px 1px 0; padding: 0.3em 0.5em; text-align: left;
         vertical-align: top; overflow-wrap: break-word; max-width: 32em; }
tr > :first-child { border-left-width: 1px; } thead th, table > tbody:first-child td { border-top-width: 1px; }
td.num { white-space: nowrap; }
th { background: #f2f2f2; position: sticky; top: 0; z-index: 1; }
th button.sort { all: unset; cursor: pointer; display: block; width: 100%; font-weight: bold; }
th button.sort:focus-visible { outline: 2px solid #2a6ebb; outline-offset: 2px; }
th button.sort::after { content: "\00a0\2195"; color: #999; }
th[aria-sort='ascending'] button.sort::after { content: "\00a0\25B2"; color: #222; }
th[aria-sort='descending'] button.sort::after { content: "\00a0\25BC"; color: #222; }
td.yes { background: #e6f4e6; } td.no { background: #fbe4e4; font-weight: bold; }
img { max-width: 100%; border: 1px solid #ddd; }
figure { margin: 1.5em 0; } figcaption { font-style: italic; color: #555; }
blockquote { border-left: 3px solid #ccc; margin: 0.5em 0; padding-left: 0.8em; color: #444; }
code { background: #f4f4f4; overflow-wrap: anywhere; }
pre { overflow-x: auto; background: #f8f8f8; padding: 0.5em; }
video { max-width: 600px; }
.summary { border: 1px solid #ccc; border-radius: 6px; padding: 0.8em 1em; margin: 1em 0; background: #fafafa; }
.summary .headline { font-size: 1.2em; font-weight: bold; margin: 0 0 0.6em 0; }
.cards { display: flex; flex-wrap: wrap; gap: 0.6em; }
.card { border: 1px solid #ddd; border-radius: 6px; padding: 0.5em 0.8em; min-width: 8em; max-width: 18em; background: #fff; }
.card .value { display: block; font-size: 1.5em; font-weight: bold; }
.card .label { display: block; color: #555; font-size: 0.9em; overflow-wrap: anywhere; }
.card.yes { background: #e6f4e6; border-color: #9c9; } .card.no { background: #fbe4e4; border-color: #d99; }
details { border: 1px solid #ddd; border-radius: 4px; padding: 0.3em 0.8em; margin: 0.8em 0; }
details > summary { cursor: pointer; font-weight: bold; }
"""

#: The table script: sortable headers (numeric where every filled cell starts with a
#: number, text otherwise; "-", "nan" and empty cells last), inlined in every page.
TABLE_SCRIPT = r"""
(function () {
  "use strict";
  var NUM = /^\s*[-+\u2212]?(\d[\d,]*(\.\d*)?|\.\d+)(e[-+\u2212]?\d+)?/i;
  function value(cell) {
    var text = cell.textContent.trim();
    var m = NUM.exec(text);
    if (!m) { return null; }
    return parseFloat(m[0].replace(/,/g, "").replace(/\u2212/g, "-"));
  }
  function blank(cell) {
    var text = cell.textContent.trim().toLowerCase();
    return text === "" || text === "-" || text === "nan" || text === "\u2014";
  }
  function isNumeric(rows, col) {
    var filled = rows.filter(function (r) { return r.cells[col] && !blank(r.cells[col]); });
    return filled.length > 0 && filled.every(function (r) { return value(r.cells[col]) !== null; });
  }
  function sortBy(table, col, th) {
    var body = table.tBodies[0];
    if (!body) { return; }
    var rows = Array.prototype.slice.call(body.rows);
    var numeric = isNumeric(rows, col);
    var down = th.getAttribute("aria-sort") === "ascending";
    var sign = down ? -1 : 1;
    var keyed = rows.map(function (r, i) {
      var c = r.cells[col];
      var empty = !c || blank(c);
      return { row: r, i: i, empty: empty, key: empty ? null : (numeric ? value(c) : c.textContent.trim()) };
    });
    keyed.sort(function (a, b) {
      if (a.empty !== b.empty) { return a.empty ? 1 : -1; }
      var d = 0;
      if (!a.empty) {
        d = numeric ? a.key - b.key : a.key.localeCompare(b.key, undefined, { numeric: true, sensitivity: "base" });
      }
      return d !== 0 ? sign * d : a.i - b.i;
    });
    keyed.forEach(function (k) { body.appendChild(k.row); });
    Array.prototype.forEach.call(th.parentNode.cells, function (h) { h.setAttribute("aria-sort", "none"); });
    th.setAttribute("aria-sort", down ? "descending" : "ascending");
  }
  function sortable(table) {
    var head = table.tHead;
    if (!head || !head.rows.length) { return; }
    Array.prototype.forEach.call(head.rows[0].cells, function (th, col) {
      var button = document.createElement("button");
      button.type = "button";
      button.className = "sort";
      button.title = "sort by this column";
      while (th.firstChild) { button.appendChild(th.firstChild); }
      th.appendChild(button);
      th.setAttribute("aria-sort", "none");
      button.addEventListener("click", function () { sortBy(table, col, th); });
      var rows = table.tBodies.length ? Array.prototype.slice.call(table.tBodies[0].rows) : [];
      if (isNumeric(rows, col)) {
        rows.forEach(function (r) { if (r.cells[col]) { r.cells[col].classList.add("num"); } });
      }
    });
  }
  Array.prototype.forEach.call(document.querySelectorAll("table"), sortable);
})();
"""


def _table_box(head_cells: list[str], body_rows: list[str]) -> str:
    """A table in its own scrolling box: header row, then the body rows (HTML)."""
    head = f"<thead><tr>{''.join(head_cells)}</tr></thead>" if head_cells else ""
    return f"<div class='table-box'><table>{head}<tbody>{''.join(body_rows)}</tbody></table></div>"


def _html_table(b: Block) -> str:
    """A table; cells of a verdict column get the class of their verdict."""
    verdict = next((b.header.index(c) for c in VERDICT_COLUMNS if c in b.header), -1)
    head = [f"<th scope='col'>{html.escape(h)}</th>" for h in b.header]
    body = []
    for r in b.rows:
        cells = []
        for j, c in enumerate(r):
            cls = VERDICT_CLASSES.get(c, "") if j == verdict else ""
            cells.append(f"<td class='{cls}'>" if cls else "<td>")
            cells[-1] += f"{_html_inline(c.replace('**', '') if cls else c)}</td>"
        body.append("<tr>" + "".join(cells) + "</tr>")
    return _table_box(head, body)


def markdown_to_html(text: str) -> str:
    """Raw Markdown of the verification tables: #### headings, | tables | (the first row
    the header), paragraphs."""
    out: list[str] = []
    rows: list[list[str]] = []

    def flush() -> None:
        if rows:
            head = [f"<th scope='col'>{_html_inline(c)}</th>" for c in rows[0]]
            body = ["<tr>" + "".join(f"<td>{_html_inline(c)}</td>" for c in r) + "</tr>" for r in rows[1:]]
            out.append(_table_box(head, body))
            rows.clear()

    for ln in (line.strip() for line in text.strip().splitlines()):
        if ln.startswith("|"):
            if not ln.startswith("|---"):
                rows.append([c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", ln.strip().strip("|"))])
            continue
        flush()
        if ln.startswith("#"):
            out.append(f"<h4>{_html_inline(ln.lstrip('#').strip())}</h4>")
        elif ln:
            out.append(f"<p>{_html_inline(ln)}</p>")
    flush()
    return "\n".join(out)


def _html_summary(b: Block) -> str:
    """A summary: its headline and one card per key figure."""
    cards = []
    for c in b.rows:
        tone = c[2] if len(c) > 2 and c[2] in ("yes", "no") else ""
        cls = f"card {tone}" if tone else "card"
        cards.append(
            f"<div class='{cls}'><span class='value'>{_html_inline(c[0])}</span>"
            f"<span class='label'>{_html_inline(c[1])}</span></div>"
        )
    headline = f"<p class='headline'>{_html_inline(b.text)}</p>" if b.text else ""
    return f"<section class='summary'>{headline}<div class='cards'>{''.join(cards)}</div></section>"


def _html_media(b: Block, base: Path, embed: bool, embed_limit: int) -> str:
    """A figure, image or animation: embedded as base64 when asked and small enough."""
    p = Path(b.path)
    alt = html.escape(b.text)
    if b.kind == "image" or not embed:
        src = html.escape(p.as_posix() if b.kind == "image" else _relative(p, base))
        if b.kind == "media":
            return f"<p><a href='{src}'>{alt}</a></p>"
        caption = f"<figcaption>{_html_inline(b.text)}</figcaption>" if b.kind == "figure" else ""
        return f"<figure><img alt='{alt}' src='{src}'>{caption}</figure>"
    if not p.is_file():
        return ""
    if b.kind == "media" and p.stat().st_size > embed_limit:
        return f"<p><a href='{html.escape(_relative(p, base))}'>{alt}</a></p>"
    data = base64.b64encode(p.read_bytes()).decode("ascii")
    if b.kind == "media" and p.suffix.lower() != ".gif":
        return (
            f"<figure><video controls loop src='data:video/mp4;base64,{data}'></video>"
            f"<figcaption>{alt}</figcaption></figure>"
        )
    mime = "image/gif" if p.suffix.lower() == ".gif" else "image/png"
    caption = _html_inline(b.text) if b.kind == "figure" else alt
    return f"<figure><img alt='{alt}' src='data:{mime};base64,{data}'><figcaption>{caption}</figcaption></figure>"


def _html_block(b: Block, base: Path, embed: bool, embed_limit: int) -> str:
    """One block as HTML."""
    if b.kind in ("h1", "h2", "h3"):
        anchor = f" id='{html.escape(b.anchor)}'" if b.anchor else ""
        return f"<{b.kind}{anchor}>{_html_inline(b.text)}</{b.kind}>"
    if b.kind == "p":
        if not b.text:
            return ""
        lines = b.text.split("\n")
        if all(line.startswith("- ") for line in lines):
            return "<ul>" + "".join(f"<li>{_html_inline(line[2:])}</li>" for line in lines) + "</ul>"
        return f"<p>{_html_inline(b.text)}</p>"
    if b.kind == "table":
        return _html_table(b)
    if b.kind == "quote":
        return f"<blockquote>{_html_inline(b.text)}</blockquote>"
    if b.kind == "code":
        return f"<pre>{html.escape(b.text)}</pre>"
    if b.kind == "markdown":
        return markdown_to_html(b.text)
    if b.kind == "summary":
        return _html_summary(b)
    if b.kind == "details":
        inner = "\n".join(h for h in (_html_block(c, base, embed, embed_limit) for c in b.children) if h)
        return f"<details><summary>{_html_inline(b.text)}</summary>\n{inner}\n</details>"
    if b.kind in ("figure", "image", "media") and b.path is not None:
        return _html_media(b, base, embed, embed_limit)
    return ""


def to_html(blocks: list[Block], base: Path, embed: bool = True, embed_limit: int = 20_000_000) -> str:
    """Render blocks as one HTML page; figures and animations embedded when `embed`
    (animations over embed_limit bytes are linked), else linked relative to `base`."""
    parts = [
        "<!DOCTYPE html>",
        "<html lang='en'><head><meta charset='utf-8'>",
        f"<title>{html.escape(blocks[0].text if blocks else 'granplate report')}</title>",
        "<meta name='viewport' content='width=device-width, initial-scale=1'>",
        "<link rel='icon' href='data:,'>",
        f"<style>{_CSS}</style></head><body>",
    ]
    parts += [h for h in (_html_block(b, base, embed, embed_limit) for b in blocks) if h]
    parts.append(f"<script>{TABLE_SCRIPT}</script>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
