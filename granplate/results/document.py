"""A small document model rendered two ways: Markdown (figures linked) and one HTML
page (PNG figures and animations embedded as base64 unless asked not to), so a page
opens in a browser with no server and no other files. The reproduction report and the
verification page are both written with it.

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
    "quote", "code" or "markdown".

    text: heading / paragraph text (markdown-lite: **bold**, `code`, [links](#x), "- "
    list lines), a quote, a code listing or raw Markdown (tables, #### headings);
    header/rows: a table (a "holds" or "result" column is coloured in HTML); path: a
    figure PNG (captioned with text), an image linked as given (alt text: text) or an
    animation file; anchor: the id of an "h3" heading.
    """

    kind: str
    text: str = ""
    header: tuple[str, ...] = ()
    rows: tuple[tuple[str, ...], ...] = ()
    path: Path | None = None
    anchor: str = ""


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
        if b.kind in ("h1", "h2", "h3"):
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


_CSS = """
body { font-family: system-ui, sans-serif; max-width: 1200px; margin: 2em auto; padding: 0 1em; color: #222; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.3em 0.5em; text-align: left; vertical-align: top; }
th { background: #f2f2f2; }
td.yes { background: #e6f4e6; } td.no { background: #fbe4e4; font-weight: bold; }
img { max-width: 100%; border: 1px solid #ddd; }
figure { margin: 1.5em 0; } figcaption { font-style: italic; color: #555; }
blockquote { border-left: 3px solid #ccc; margin: 0.5em 0; padding-left: 0.8em; color: #444; }
code { background: #f4f4f4; }
video { max-width: 600px; }
"""


def _html_table(b: Block) -> str:
    """A table; cells of a verdict column get the class of their verdict."""
    verdict = next((b.header.index(c) for c in VERDICT_COLUMNS if c in b.header), -1)
    head = "".join(f"<th>{html.escape(h)}</th>" for h in b.header)
    body = []
    for r in b.rows:
        cells = []
        for j, c in enumerate(r):
            cls = VERDICT_CLASSES.get(c, "") if j == verdict else ""
            cells.append(f"<td class='{cls}'>" if cls else "<td>")
            cells[-1] += f"{_html_inline(c.replace('**', '') if cls else c)}</td>"
        body.append("<tr>" + "".join(cells) + "</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def markdown_to_html(text: str) -> str:
    """Raw Markdown of the verification tables: #### headings, | tables |, paragraphs."""
    out, rows = [], []
    for ln in (line.strip() for line in text.strip().splitlines()):
        if ln.startswith("|"):
            if not ln.startswith("|---"):
                cells = [c.strip() for c in ln.strip("|").split("|")]
                rows.append("<tr>" + "".join(f"<td>{_html_inline(c)}</td>" for c in cells) + "</tr>")
            continue
        if rows:
            out.append("<table>" + "".join(rows) + "</table>")
            rows = []
        if ln.startswith("#"):
            out.append(f"<h4>{_html_inline(ln.lstrip('#').strip())}</h4>")
        elif ln:
            out.append(f"<p>{_html_inline(ln)}</p>")
    if rows:
        out.append("<table>" + "".join(rows) + "</table>")
    return "\n".join(out)


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
        return (f"<figure><video controls loop src='data:video/mp4;base64,{data}'></video>"
                f"<figcaption>{alt}</figcaption></figure>")
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
    if b.kind in ("figure", "image", "media") and b.path is not None:
        return _html_media(b, base, embed, embed_limit)
    return ""


def to_html(blocks: list[Block], base: Path, embed: bool = True, embed_limit: int = 20_000_000) -> str:
    """Render blocks as one HTML page; figures and animations embedded when `embed`
    (animations over embed_limit bytes are linked), else linked relative to `base`."""
    parts = ["<!DOCTYPE html>", "<html lang='en'><head><meta charset='utf-8'>",
             f"<title>{html.escape(blocks[0].text if blocks else 'granplate report')}</title>",
             f"<style>{_CSS}</style></head><body>"]
    parts += [h for h in (_html_block(b, base, embed, embed_limit) for b in blocks) if h]
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
