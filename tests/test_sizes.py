"""Sizes (docs/architecture.md): no function of the package over MAX_FUNCTION_LINES lines and no
module of its numerical core (physics, model, solver, plate, solid) over MAX_MODULE_LINES lines,
read from the source (every def, nested ones too, decorators left out), apart from the files of
ALLOWED and the compiled kernels of KEPT_WHOLE, each with the reason it is there (a kernel's, the
measured cost of splitting it). The lists are meant to shrink: once a file is split, its entry goes."""

from __future__ import annotations

import ast
from pathlib import Path

import granplate

PACKAGE = Path(granplate.__file__).parent

MAX_FUNCTION_LINES = 100
MAX_MODULE_LINES = 600
#: the numerical core: its modules are held to MAX_MODULE_LINES
CORE = ("physics", "model", "solver", "plate", "solid")

#: files exempt from both limits, relative to the package, with why
ALLOWED: dict[str, str] = {}

#: functions kept whole for speed ("file:function"), with the measured cost of splitting them
KEPT_WHOLE = {
    "solver/granular.py:granular_rhs": "the plane's derivative (205 lines): split into one loop per contact kind "
    "(inline or not) it took 2.81 us per call against 2.65 us whole (+6%, ptfe-r05, in a compiled loop)",
    "solver/granular.py:normal_forces": "the plane's velocity-Verlet force pass (105 lines): split, 1.28 us per "
    "call against 1.155 us whole (+10%, ptfe-r05, in a compiled loop)",
}


def long_functions(path: Path, root: Path = PACKAGE) -> list[str]:
    """'path:line name (n lines)' of every function in a file longer than MAX_FUNCTION_LINES
    (path relative to root)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            n = node.end_lineno - node.lineno + 1
            if n > MAX_FUNCTION_LINES:
                out.append(f"{path.relative_to(root)}:{node.lineno} {node.name} ({n} lines)")
    return out


def checked_files() -> list[Path]:
    """The package's modules outside ALLOWED."""
    return [p for p in sorted(PACKAGE.rglob("*.py")) if p.relative_to(PACKAGE).as_posix() not in ALLOWED]


def test_allowed_files_exist():
    """Every ALLOWED and KEPT_WHOLE entry names a file of the package and gives a reason."""
    assert all((PACKAGE / name).is_file() and reason for name, reason in ALLOWED.items())
    assert all((PACKAGE / key.split(":")[0]).is_file() and reason for key, reason in KEPT_WHOLE.items())


def test_long_functions_are_found(tmp_path):
    """The function measure finds a function of MAX_FUNCTION_LINES + 1 lines and passes one of
    MAX_FUNCTION_LINES (a file written here, read as the package's are)."""
    body = "".join(f"    x{k} = {k}\n" for k in range(MAX_FUNCTION_LINES - 1))
    probe = tmp_path / "probe.py"
    probe.write_text(f"def fits():\n{body}\n\ndef too_long():\n{body}    x = 0\n")
    assert [s.split()[1] for s in long_functions(probe, tmp_path)] == ["too_long"]


def test_no_function_over_the_limit():
    """No function of the package (outside ALLOWED) is longer than MAX_FUNCTION_LINES lines."""
    found = [
        line
        for path in checked_files()
        for line in long_functions(path)
        if f"{line.split(':')[0]}:{line.split()[1]}" not in KEPT_WHOLE
    ]
    assert not found, f"functions over {MAX_FUNCTION_LINES} lines (split them into named steps):\n" + "\n".join(found)


def test_no_core_module_over_the_limit():
    """No module of the numerical core (outside ALLOWED) is longer than MAX_MODULE_LINES lines."""
    found = []
    for path in checked_files():
        rel = path.relative_to(PACKAGE)
        n = len(path.read_text().splitlines())
        if rel.parts[0] in CORE and n > MAX_MODULE_LINES:
            found.append(f"{rel} ({n} lines)")
    assert not found, f"core modules over {MAX_MODULE_LINES} lines (split them by concept):\n" + "\n".join(found)
