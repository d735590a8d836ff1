"""A small document model rendered two ways: Markdown (figures linked) and one
self-contained HTML page (PNG figures and animations embedded as base64), so the
report opens in a browser with no server and no other files.

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
    """A piece of the report: kind "h1", "h2", "p", "table", "figure" or "media".

    text: heading / paragraph text (markdown-lite: **bold**, `code`, "- " list lines);
    header/rows: a table; path/caption: a figure PNG or an animation file.
    """

    kind: str
    text: str = ""
    header: tuple[str, ...] = ()
    rows: tuple[tuple[str, ...], ...] = ()
    path: Path | None = None


def _md_inline(text: str) -> str:
    """Escape table-cell pipes."""
    return text.replace("|", "\\|")


def to_markdown(blocks: list[Block], base: Path) -> str:
    """Render blocks as Markdown; figure and media paths relative to `base`."""
    out = []
    for b in blocks:
        if b.kind == "h1":
            out.append(f"# {b.text}\n")
        elif b.kind == "h2":
            out.append(f"## {b.text}\n")
        elif b.kind == "p":
            out.append(b.text + "\n")
        elif b.kind == "table":
            out.append("| " + " | ".join(b.header) + " |")
            out.append("|" + "|".join("---" for _ in b.header) + "|")
            for r in b.rows:
                out.append("| " + " | ".join(_md_inline(c) for c in r) + " |")
            out.append("")
        elif b.kind == "figure":
            rel = _relative(b.path, base)
            out.append(f"![{b.text}]({rel})\n\n*{b.text}*\n")
        elif b.kind == "media":
            out.append(f"- [{b.text}]({_relative(b.path, base)})")
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
    """Escape HTML; **bold** and `code` become tags."""
    s = html.escape(text)
    s = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", s)
    return re.sub(r"`(.+?)`", r"<code>\1</code>", s)


_CSS = """
body { font-family: system-ui, sans-serif; max-width: 1200px; margin: 2em auto; padding: 0 1em; color: #222; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.3em 0.5em; text-align: left; vertical-align: top; }
th { background: #f2f2f2; }
td.yes { background: #e6f4e6; } td.no { background: #fbe4e4; }
img { max-width: 100%; border: 1px solid #ddd; }
figure { margin: 1.5em 0; } figcaption { font-style: italic; color: #555; }
video { max-width: 600px; }
"""


def to_html(blocks: list[Block], base: Path, embed_limit: int = 20_000_000) -> str:
    """Render blocks as one self-contained HTML page (PNGs and animations embedded)."""
    parts = ["<!DOCTYPE html>", "<html><head><meta charset='utf-8'>",
             f"<title>{html.escape(blocks[0].text if blocks else 'granplate report')}</title>",
             f"<style>{_CSS}</style></head><body>"]
    for b in blocks:
        if b.kind == "h1":
            parts.append(f"<h1>{_html_inline(b.text)}</h1>")
        elif b.kind == "h2":
            parts.append(f"<h2>{_html_inline(b.text)}</h2>")
        elif b.kind == "p":
            lines = b.text.split("\n")
            if all(line.startswith("- ") for line in lines):
                parts.append("<ul>" + "".join(f"<li>{_html_inline(line[2:])}</li>" for line in lines) + "</ul>")
            else:
                parts.append(f"<p>{_html_inline(b.text)}</p>")
        elif b.kind == "table":
            holds_col = b.header.index("holds") if "holds" in b.header else -1
            head = "".join(f"<th>{html.escape(h)}</th>" for h in b.header)
            body = []
            for r in b.rows:
                cells = []
                for j, c in enumerate(r):
                    cls = f" class='{c}'" if j == holds_col and c in ("yes", "no") else ""
                    cells.append(f"<td{cls}>{_html_inline(c)}</td>")
                body.append("<tr>" + "".join(cells) + "</tr>")
            parts.append(f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>")
        elif b.kind == "figure" and b.path is not None and Path(b.path).is_file():
            data = base64.b64encode(Path(b.path).read_bytes()).decode("ascii")
            parts.append(f"<figure><img alt='{html.escape(b.text)}' src='data:image/png;base64,{data}'>"
                         f"<figcaption>{_html_inline(b.text)}</figcaption></figure>")
        elif b.kind == "media" and b.path is not None and Path(b.path).is_file():
            p = Path(b.path)
            size = p.stat().st_size
            if size <= embed_limit:
                data = base64.b64encode(p.read_bytes()).decode("ascii")
                if p.suffix.lower() == ".gif":
                    parts.append(f"<figure><img alt='{html.escape(b.text)}' src='data:image/gif;base64,{data}'>"
                                 f"<figcaption>{html.escape(b.text)}</figcaption></figure>")
                else:
                    parts.append(f"<figure><video controls loop src='data:video/mp4;base64,{data}'></video>"
                                 f"<figcaption>{html.escape(b.text)}</figcaption></figure>")
            else:
                parts.append(f"<p><a href='{html.escape(_relative(p, base))}'>{html.escape(b.text)}</a></p>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
