"""The package's layers import only downward (docs/architecture.md): read every import of
every module, top-level and inside functions, and fail on an arrow that points up."""

from __future__ import annotations

import ast
from pathlib import Path

import granplate

PACKAGE = Path(granplate.__file__).parent

#: bottom to top; a module may import its own layer and the layers below it.
LAYERS = (
    ("version", "errors", "store", "jit", "dense"),
    ("setup",),
    ("physics",),
    ("plate", "solid"),
    ("model",),
    ("solver",),
    ("results",),
    ("figures",),
    ("paper",),
    ("verification",),
    ("study",),
    ("bench",),
    ("cli", "commands"),
)
RANK = {name: rank for rank, names in enumerate(LAYERS) for name in names}


def layer_of(module: str) -> str | None:
    """'granplate.solver.driver' -> 'solver'; the package root itself -> None."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[0] == "granplate" else None


def imports_of(path: Path, module: str) -> list[tuple[int, str]]:
    """(line, absolute module) of every granplate import in a file."""
    tree = ast.parse(path.read_text())
    package = module.rsplit(".", 1)[0] if path.name != "__init__.py" else module
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names if a.name.startswith("granplate")]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module or ""
            if name == "granplate":  # from granplate import x: x is the module
                found += [(node.lineno, f"granplate.{a.name}") for a in node.names]
            elif name.startswith("granplate"):
                found.append((node.lineno, name))
    return found


def all_modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE.parent).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        yield path, ".".join(parts)


def test_every_module_belongs_to_a_layer():
    """Every subpackage and top-level module of granplate is placed in LAYERS."""
    missing = {layer_of(m) for _, m in all_modules()} - set(RANK) - {None}
    assert not missing, f"modules outside the layer picture: {sorted(missing)}"


def test_imports_point_downward():
    """No module imports a layer above its own."""
    wrong = []
    for path, module in all_modules():
        own = layer_of(module)
        if own is None:  # granplate/__init__.py: the public API, may import anything
            continue
        for line, target in imports_of(path, module):
            to = layer_of(target)
            if to is not None and to in RANK and RANK[to] > RANK[own]:
                wrong.append(f"{path.relative_to(PACKAGE.parent)}:{line}: {own} -> {to} ({target})")
    assert not wrong, "imports that point up a layer:\n" + "\n".join(wrong)


def test_architecture_lists_every_module():
    """docs/architecture.md's layer table names every module of the package (a module in a
    folder below a subpackage, such as solver/schemes/, through its folder)."""
    table = [
        line
        for line in (PACKAGE.parent / "docs" / "architecture.md").read_text().splitlines()
        if line.startswith("| `")
    ]
    rows = {name.strip(" `"): line for line in table for name in line.split("|")[1].split(",")}
    missing = []
    for path, module in all_modules():
        parts = module.split(".")[1:]
        if not parts:
            continue
        if len(parts) == 1:  # a top-level module, or a subpackage's __init__
            if path.name != "__init__.py" and not any(f"`{parts[0]}.py`" in r or f"`{parts[0]}`" in r for r in table):
                missing.append(module)
            continue
        row = rows.get(parts[0], "")
        named = (
            f"`{parts[1]}`" in row
            or f"`{parts[1]}.py`" in row
            or f"`{parts[1]}/`" in row
            or any(f"`{parts[0]}/{parts[1]}.py`" in r for r in table)
        )
        if path.name != "__init__.py" or len(parts) > 2:
            if not (named or f"{parts[1]}/" in row):
                missing.append(module)
    assert not missing, f"modules docs/architecture.md does not list: {missing}"
