"""Sphinx extension of granplate's site: reference pages generated from the code, and a
check that every relative link of the Markdown sources resolves.

Generated before the sources are read (``builder-inited``), into docs/reference/generated/
(not under version control):

- ``scenario-fields.md``: every table and key of a scenario file from the dataclasses of
  ``granplate.setup.scenario`` (names, types, defaults), the units of
  ``granplate.study.table.FIELD_UNITS`` and, as "refused when", the messages the
  validator itself gives for out-of-range values (probed on a valid base scenario), so the
  page cannot disagree with what a run accepts;
- ``dataset-variables.md``: the result Dataset's variables, from
  ``granplate.results.dataset.VARIABLES``, and the summary's units, from ``SUMMARY_UNITS``.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
from pathlib import Path
from typing import Any

from docutils import nodes
from sphinx import addnodes
from sphinx.transforms.post_transforms import SphinxPostTransform
from sphinx.util import logging

LOG = logging.getLogger(__name__)
DOCS = Path(__file__).resolve().parents[1]
GENERATED = DOCS / "reference" / "generated"

#: the probe values per kind of field: each out of range for some field
NUMBER_PROBES = (-1.0, 0.0, 1e300)
INTEGER_PROBES = (-1, 0)
STRING_PROBE = "?"

#: a small 3D scenario with explicit granules and a [box] (the [box] table's base)
BOX_BASE = """
name = "box-base"
dimension = 3
[box]
lower = [0.0, 0.0, 0.0]
upper = [0.1, 0.1, 0.1]
[[granules]]
x = 0.03
y = 0.05
z = 0.05
radius = 0.01
material = "steel"
vx = 1.0
[[granules]]
x = 0.06
y = 0.05
z = 0.05
radius = 0.01
material = "steel"
[load]
kind = "none"
[time]
t_end = 1e-4
[solver]
scheme = "verlet"
"""


#: The Scenario fields that are tables of their own (each gets its own section).
SCENARIO_TABLES = ("materials", "layout", "granules", "walls", "plate", "load", "contact", "time", "solver", "box")


def _tables() -> list[tuple[str, str, type, str, Any, str]]:
    """(title, anchor, dataclass, dotted prefix, base scenario, what the base is)."""
    import granplate as gp
    from granplate.setup import scenario as S
    from granplate.setup.geometry import resolve
    from granplate.setup.materials import Material

    steel = gp.preset("steel-r1")
    ex = DOCS / "examples"
    resolved = resolve(steel)
    twin = gp.preset("3d-steel-r1")
    patched = gp.with_changes(
        twin,
        {
            "plate.rigid_layers": False,
            "plate.rigid_patches": [
                {"centre": [0.0305, 0.05, 0.0], "radius": 0.003, "axis": [0.0, 0.0, 1.0], "rotates": False}
            ],
        },
    )
    return [
        ("Top level", "top-level", S.Scenario, "", steel, "the preset steel-r1"),
        ("[materials.NAME]", "materials", Material, "materials.steel", steel, "steel-r1's steel"),
        ('[layout] kind = "paper"', "layout-paper", S.Layout, "layout", steel, "steel-r1"),
        (
            '[layout] kind = "hexagonal" or "square"',
            "layout-lattice",
            S.LatticeLayout,
            "layout",
            gp.load_scenario(ex / "hexagonal.toml"),
            "docs/examples/hexagonal.toml",
        ),
        (
            '[layout] kind = "chain"',
            "layout-chain",
            S.ChainLayout,
            "layout",
            gp.load_scenario(ex / "chain.toml"),
            "docs/examples/chain.toml",
        ),
        (
            '[layout] kind = "sc", "bcc", "fcc" or "hcp" (3D)',
            "layout-space",
            S.SpaceLattice,
            "layout",
            gp.load_scenario(ex / "3d-fcc.toml"),
            "docs/examples/3d-fcc.toml",
        ),
        (
            "[[layout.layers]] (3D lattices)",
            "layout-layers",
            S.Layer,
            "layout.layers[0]",
            gp.load_scenario(ex / "3d-fcc.toml"),
            "docs/examples/3d-fcc.toml",
        ),
        (
            "[layout.imperfections]",
            "imperfections",
            S.Imperfections,
            "layout.imperfections",
            gp.load_scenario(ex / "imperfect.toml"),
            "docs/examples/imperfect.toml",
        ),
        ("[[granules]]", "granules", S.Granule, "granules[0]", resolved, "steel-r1 written out"),
        ("[[walls]]", "walls", S.Wall, "walls[0]", resolved, "steel-r1 written out"),
        ("[box] (3D)", "box", S.Box, "box", gp.loads(BOX_BASE), "two spheres in a box"),
        ("[plate] (2D): the plate", "plate", S.Plate, "plate", steel, "steel-r1"),
        ("[plate] (3D): the elastic solid", "solid", S.Solid, "plate", twin, "the preset 3d-steel-r1"),
        (
            "[[plate.rigid_patches]] (3D)",
            "rigid-patches",
            S.RigidPatch,
            "plate.rigid_patches[0]",
            patched,
            "3d-steel-r1 with one rigid strip",
        ),
        ("[load]", "load", S.Load, "load", steel, "steel-r1"),
        ("[contact]", "contact", S.Contact, "contact", steel, "steel-r1"),
        ("[[contact.pairs]]", "contact-pairs", S.PairCoefficients, "contact.pairs[0]", steel, "steel-r1"),
        ("[time]", "time", S.TimeSettings, "time", steel, "steel-r1"),
        ("[solver]", "solver", S.Solver, "solver", steel, "steel-r1"),
    ]


def toml_type(annotation: str) -> str:
    """A field's annotation in the words of a TOML file ("float | None" -> "number or none")."""
    a = str(annotation).replace(" ", "")
    if a.startswith("tuple[") or a.startswith("dict["):
        return "list" if a.startswith("tuple[") else "table"
    words = {"float": "number", "int": "integer", "str": "string", "bool": "boolean", "None": "none"}
    parts = [words.get(p, "table") for p in a.split("|") if not p.startswith("tuple")]
    if "tuple[" in a:
        parts.insert(1, "list")
    return " or ".join(dict.fromkeys(parts))


def default_text(f: dataclasses.Field) -> str:
    """The default as written in TOML, "required" for a field without one."""
    if f.default is dataclasses.MISSING:
        return "the library's materials" if f.default_factory is not dataclasses.MISSING else "required"
    v = f.default
    if v is None:
        return "none"
    if dataclasses.is_dataclass(v):
        return "a default table"
    if isinstance(v, bool):
        return "`true`" if v else "`false`"
    if isinstance(v, str):
        return f'`"{v}"`'
    if isinstance(v, tuple):
        if v and dataclasses.is_dataclass(v[0]):
            return f"{len(v)} table(s)"
        return "`[" + ", ".join(f'"{x}"' if isinstance(x, str) else f"{x:g}" for x in v) + "]`"
    return f"`{v:g}`" if isinstance(v, float) else f"`{v}`"


def probes(annotation: str) -> tuple:
    """Values that some field of this type refuses (numbers out of range, an unknown name)."""
    a = str(annotation).replace(" ", "")
    if a.startswith("tuple[str"):
        return ([STRING_PROBE],)
    if a.startswith("tuple") or a.startswith("dict") or a == "bool" or "Imperfections" in a:
        return ()
    if a.startswith("int"):
        return INTEGER_PROBES
    if a.startswith("float"):
        return NUMBER_PROBES
    if a.startswith("str"):
        return (STRING_PROBE,)
    return ()


def refusals(base, path: str, values: tuple) -> list[str]:
    """What the validator says, in its own words, when `path` of `base` is set to each value
    (the messages about this field only; type errors and machine-dependent limits left out)."""
    import granplate as gp
    from granplate.setup.validate import validate

    said: list[str] = []
    for v in values:
        try:
            validate(gp.with_changes(base, {path: v}))
        except gp.ScenarioError as err:
            own = err.field == path or err.field.startswith(path + "[")
            if not own or "wrong type" in err.allowed:
                continue
            text = err.allowed
            if "this machine" in text:
                text = "the outputs must fit in this machine's memory (the message gives the estimate)"
            if text not in said:
                said.append(text)
    return said


def markdown_text(doc: str) -> str:
    """A docstring's plain text as Markdown paragraphs: backslashes and stars (E*, R*)
    escaped outside backticks, so that nothing turns into emphasis."""
    parts = re.split(r"(`[^`]*`)", doc)
    return "".join(
        s if i % 2 else s.replace("\\", "\\\\").replace("*", "\\*").replace("<", "&lt;") for i, s in enumerate(parts)
    )


def _title(title: str) -> str:
    """A table's title with its TOML name as code: '[load]' -> '`[load]`'."""
    return (
        re.sub(r"(\[+[^\]]+\]+(?: kind = [^(]+)?)", lambda m: f"`{m.group(1).strip()}` ", title)
        .replace("  ", " ")
        .strip()
    )


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def scenario_fields_page() -> str:
    """The Markdown of the scenario reference, generated from the code."""
    from granplate.study.table import field_unit

    out = [
        "# Scenario keys (generated)",
        "",
        "Every table and key of a scenario file, generated when the site is built from the code",
        "that reads it: names, types and defaults from the dataclasses of",
        "`granplate.setup.scenario`, units from `granplate.study.table.FIELD_UNITS`, and in the",
        "last column what the validator (`granplate.setup.validate`) answers when the key is set",
        "out of range on a valid base scenario, word for word: the same checks a scenario file",
        "and `granplate.with_changes` go through. Limits that depend on",
        "other keys are quoted for the base scenario named under each table. The meaning of",
        "each key, with the reasoning behind its default, is in [Scenario files](../../scenario.md).",
        "",
    ]
    for title, anchor, cls, prefix, base, what in _tables():
        out += [f"({anchor})=", f"## {_title(title)}", ""]
        doc = inspect.cleandoc(cls.__doc__ or "")
        if doc:
            out += [markdown_text(doc), ""]
        out += [
            f"Refusals probed on {what}.",
            "",
            "| key | type | unit | default | refused when |",
            "| --- | --- | --- | --- | --- |",
        ]
        for f in dataclasses.fields(cls):
            if (cls.__name__, f.name) == ("Material", "name"):  # the table's name, not a key
                continue
            if cls.__name__ == "Scenario" and f.name in SCENARIO_TABLES:
                continue
            if f.name == "pairs" or (f.name == "layers" and cls.__name__ == "SpaceLattice"):
                refused = []
            else:
                path = f"{prefix}.{f.name}" if prefix else f.name
                refused = refusals(base, path, probes(f.type))
            unit = field_unit(f.name) or ""
            unit = "-" if unit == "1" else unit
            out.append(
                f"| `{f.name}` | {toml_type(f.type)} | {unit} | {_cell(default_text(f))} | "
                f"{_cell('; '.join(refused))} |"
            )
        out.append("")
    return "\n".join(out)


def dataset_variables_page() -> str:
    """The Markdown of the Dataset's variables and the summary's units, from the code."""
    from granplate.results.dataset import SUMMARY_UNITS, VARIABLES

    out = [
        "# Result variables (generated)",
        "",
        "The data variables a run's Dataset (`granplate.simulate`, `granplate run -o FILE.nc`)",
        "can hold, with their units and descriptions, generated from",
        "`granplate.results.dataset.VARIABLES` (the table that writes the `units` and",
        "`description` attributes of the Dataset itself). A run holds the ones its scenario",
        "has (the plate's only with a plate, z, vz and the spin vector only in 3D); the",
        "coordinates, the attributes and how to read each are in",
        "[Result dataset](../../output.md).",
        "",
        "| variable | unit | description |",
        "| --- | --- | --- |",
    ]
    out += [f"| `{k}` | {_cell(u) or '-'} | {_cell(d)} |" for k, (u, d) in VARIABLES.items()]
    out += [
        "",
        "## The summary's numbers",
        "",
        "`granplate.summary(ds)` (and `granplate run --summary FILE.json`) gives these numbers;",
        "their units, from `granplate.results.dataset.SUMMARY_UNITS`, travel in",
        '`summary["units"]`.',
        "",
        "| key | unit |",
        "| --- | --- |",
    ]
    out += [f"| `{k}` | {_cell(str(u))} |" for k, u in SUMMARY_UNITS.items()]
    return "\n".join(out) + "\n"


#: the figures of docs/figures/ (committed PNGs, redrawn by the command given): file ->
#: (what it shows, the command that made it, the scenarios it was made from: a preset's
#: name, or a TOML file under docs/)
FIGURES: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "fig3.png": (
        "Paper Fig. 3: the largest von Mises stress without and with granules, and the energies normalised by E_shock",
        "`granplate reproduce --out results` (the presets at their 2 ms)",
        ("bare-plate", "steel-r1"),
    ),
    "fig6.png": (
        "Paper Fig. 6: horizontal velocity maps, steel against PTFE intruders",
        "`granplate reproduce --out results`, then `granplate plot results --figure 6`",
        ("steel-r05", "ptfe-r05"),
    ),
    "show-steel-r1.png": (
        "An assembly before a run: the paper's steel packing, granules by material, walls, "
        "the plate and its rigid layers, the load",
        "`granplate show steel-r1 --dpi 80`",
        ("steel-r1",),
    ),
    "show-steel-r1-result.png": (
        "A result: the contact forces and the deformed plate at the largest plate energy",
        "`granplate run steel-r1 -o steel-r1.nc`, then `granplate show steel-r1.nc --dpi 80`",
        ("steel-r1",),
    ),
    "show-box-3d.png": (
        "A run in space: three depth-shaded projections, walls and contact forces",
        "`granplate run docs/gallery/box-3d.toml -o box-3d.nc`, then `granplate show box-3d.nc --time 3e-5 --dpi 80`",
        ("gallery/box-3d.toml",),
    ),
}
#: where the gallery writes the presets' scenarios as TOML (beside the generated page)
GALLERY_SCENARIOS = "scenarios"


def scenario_block(source: str, generated: Path = GENERATED, docs: Path = DOCS) -> list[str]:
    """The Markdown that shows one scenario of a figure, folded: a TOML file of docs/ as it
    is, or a preset as `granplate preset NAME` writes it (written now, beside the page)."""
    if source.endswith(".toml"):
        path, label = f"../../{source}", f"<code>docs/{source}</code>"
    else:
        from granplate.setup.io import dumps
        from granplate.setup.presets import preset

        _write_if_changed(generated / GALLERY_SCENARIOS / f"{source}.toml", dumps(preset(source)))
        path = f"{GALLERY_SCENARIOS}/{source}.toml"
        label = f"the preset <code>{source}</code> (<code>granplate preset {source}</code>)"
    return [
        f"<details><summary>The scenario: {label}</summary>",
        "",
        f"```{{literalinclude}} {path}",
        ":language: toml",
        "```",
        "",
        "</details>",
        "",
    ]


def gallery_page(docs: Path = DOCS, generated: Path = GENERATED) -> str:
    """The Markdown of the gallery: every figure of docs/figures/ with the command and the
    scenarios that made it, and every figure of docs/validation-figures/ with its case."""
    import json

    out = [
        "# Gallery",
        "",
        "Every figure shipped with the documentation (committed PNGs, small), with the",
        "command that drew it and the scenario it was made from (open it below the figure):",
        "run the command to draw it again. The verification figures are drawn by",
        "`granplate verify` from the numbers of each case; their cases, references and",
        "tolerances are in [Verification and validation](../../validation.md).",
        "",
        "## Runs and assemblies",
        "",
    ]
    for name in sorted(p.name for p in (docs / "figures").glob("*.png")):
        what, made, sources = FIGURES.get(name, ("", "", ()))
        head, _, rest = (what or name).partition(": ")
        out += [f"### {head}", "", f"![{what or name}](../../figures/{name})", ""]
        out += [f"{rest[:1].upper() + rest[1:]}." if rest else "", ""]
        out += [f"Made by {made}.", ""] if made else []
        for source in sources:
            out += scenario_block(source, generated, docs)
    cases = {c["figure"]: c for c in json.loads((docs / "validation.json").read_text())["cases"] if c.get("figure")}
    out += ["## Verification cases", ""]
    for name in sorted(p.name for p in (docs / "validation-figures").glob("*.png")):
        case = cases.get(name)
        title = case["title"] if case else name
        out += [f"### {title}", "", f"![{title}](../../validation-figures/{name})", ""]
        if case:
            out += [
                f"The verification case `{case['name']}` (`granplate verify --case {case['name']}`), "
                f"{'passing' if case.get('passed') else 'failing'}.",
                "",
            ]
    return "\n".join(out) + "\n"


def _write_if_changed(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def generate(app=None) -> None:
    """Write the generated reference pages (only what changed, so rebuilds stay incremental)."""
    _write_if_changed(GENERATED / "scenario-fields.md", scenario_fields_page())
    _write_if_changed(GENERATED / "dataset-variables.md", dataset_variables_page())
    _write_if_changed(GENERATED / "gallery.md", gallery_page())


#: a Markdown link or image target: ](target) or ](target "title")
LINK = re.compile(r"\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
#: fenced code blocks, whose text is not Markdown
FENCE = re.compile(r"^(```|~~~|:::).*?^\1", re.M | re.S)


#: a heading of a Markdown page, with its level
HEADING = re.compile(r"^(#{1,6})[ \t]+(.*?)[ \t]*#*[ \t]*$", re.M)
#: an explicit MyST target, ``(name)=`` on a line of its own
MYST_LABEL = re.compile(r"^\(([^)\s]+)\)=[ \t]*$", re.M)
#: an ``{include}`` directive's file
INCLUDE = re.compile(r"^(?:```|:::)\{include\}[ \t]+(\S+)", re.M)
#: the deepest heading level that gets an anchor (conf.py's myst_heading_anchors)
ANCHOR_LEVELS = 3


def anchors(page: Path) -> set[str]:
    """The anchors a link `page#name` may name: the slugs MyST gives headings of levels 1
    to ANCHOR_LEVELS (GitHub's rule: lowercased, punctuation dropped, spaces as dashes, a
    repeat numbered -1, -2, ...), explicit ``(name)=`` targets, raw HTML ``<a id=...>``, and
    those of the files the page includes (all of them: a superset of an included range)."""
    from myst_parser.slugs import github_slugify

    raw = page.read_text()
    found: set[str] = set()
    for included in INCLUDE.findall(raw):
        if (page.parent / included).is_file():
            found |= anchors(page.parent / included)
    text = FENCE.sub("", raw)
    found |= set(HTML_ID.findall(text)) | set(MYST_LABEL.findall(text))
    counts: dict[str, int] = {}
    for level, title in HEADING.findall(text):
        if len(level) > ANCHOR_LEVELS:
            continue
        title = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", title)  # a link's text
        slug = github_slugify(title)
        found.add(f"{slug}-{counts[slug]}" if counts.get(slug) else slug)
        counts[slug] = counts.get(slug, 0) + 1
    return found


def broken_targets(page: Path) -> list[str]:
    """The relative links and images of one Markdown page (code left out) whose file does
    not exist, or whose `#anchor` in a Markdown page (this one for a bare `#anchor`) is no
    anchor there (see `anchors`); web and mail links are not checked (no network)."""
    text = FENCE.sub("", page.read_text())
    text = re.sub(r"`[^`\n]*`", "", text)
    bad = []
    for target in LINK.findall(text):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target):
            continue
        file, _, anchor = target.partition("#")
        path = page.parent / file if file else page
        if not path.exists():
            bad.append(target)
        elif anchor and path.suffix == ".md" and anchor not in anchors(path):
            bad.append(target)
    return bad


def broken_links(docs: Path = DOCS, exclude: tuple[str, ...] = ("_build",)) -> list[tuple[str, str]]:
    """Every relative link or image of the Markdown pages under `docs` whose target file or
    anchor does not exist, as (page, target) (`broken_targets`); the site build checks
    them too (MyST warns for an anchor it cannot find), this check also runs without it."""
    bad = []
    for page in sorted(docs.rglob("*.md")):
        rel = page.relative_to(docs)
        if rel.parts[0] in exclude or rel.parts[0] == "studies":
            continue
        bad += [(str(rel), target) for target in broken_targets(page)]
    return bad


def check_links(app, env) -> None:
    """Warn (an error under -W) for every relative link that points at no file."""
    for page, target in broken_links(Path(app.srcdir)):
        LOG.warning("broken relative link in %s: %s", page, target, type="granplate", subtype="link")


#: an HTML anchor written in a page, as the pages granplate generates write them
HTML_ID = re.compile(r"<a\s+(?:id|name)=\"([^\"]+)\"")


class HtmlAnchors(SphinxPostTransform):
    """Links to `#id` where the same page defines `<a id="id">` in raw HTML (the pages the
    package writes, e.g. validation.md, anchor their cases so for any Markdown viewer):
    resolved to that anchor, before MyST looks for a heading of that name and warns."""

    default_priority = 8  # before MyST's reference resolver (9)

    def run(self, **kwargs) -> None:
        ids = set()
        for raw in self.document.findall(nodes.raw):
            ids.update(HTML_ID.findall(raw.astext()))
        if not ids:
            return
        for node in list(self.document.findall(addnodes.pending_xref)):
            if node.get("reftype") == "myst" and node.get("reftarget") in ids:
                ref = nodes.reference("", "", internal=True, refuri="#" + node["reftarget"])
                ref += node[0].deepcopy() if node.children else nodes.Text(node["reftarget"])
                node.replace_self(ref)


#: worked studies whose explorer page the site carries (linked from the study tutorial)
EXPLORERS = ("intruder-map",)


def copy_explorers(app, exception) -> None:
    """Copy the explorer pages of EXPLORERS (report.html and its report_assets/) into the
    built site, under studies/NAME/, where the pages link to them."""
    import shutil

    if exception is not None or app.builder.format != "html":
        return
    for name in EXPLORERS:
        src, dst = DOCS / "studies" / name, Path(app.outdir) / "studies" / name
        dst.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src / "report.html", dst / "report.html")
        shutil.copytree(src / "report_assets", dst / "report_assets", dirs_exist_ok=True)


#: text in backticks, kept as written
CODE = re.compile(r"(``?[^`]+``?)")


#: line openings reStructuredText reads as a list, a doctest or a literal block
MARKUP_START = re.compile(r"^(\s*)([-*+] |\d+[.)] |>>>|[a-z]\) )")


def plain_docstring(app, what, name, obj, options, lines: list[str]) -> None:
    """The package's docstrings are plain text with formulas (|v|, E*, 2 x R) and hanging
    indents: read them as plain paragraphs. Outside backticks, the characters
    reStructuredText would read as markup are escaped; a docstring without reST fields
    (napoleon's sections become `:param ...:` lines) loses its indentation and its
    list-like openings are escaped, so that no docstring can break the build."""
    fields = any(line.lstrip().startswith((":", "..")) for line in lines)
    for k, line in enumerate(lines):
        if not fields:
            line = MARKUP_START.sub(lambda m: "\\" + m.group(2), line.strip())
            if line.endswith("::"):
                line = line[:-1]
        parts = CODE.split(line)
        lines[k] = "".join(p if i % 2 else p.replace("|", "\\|").replace("*", "\\*") for i, p in enumerate(parts))


def setup(app):
    app.connect("autodoc-process-docstring", plain_docstring)
    app.connect("build-finished", copy_explorers)
    app.add_post_transform(HtmlAnchors)
    app.connect("builder-inited", generate)
    app.connect("env-check-consistency", check_links)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
