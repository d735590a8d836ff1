"""`granplate bench --solid`: what the 3D solid costs and how accurate its elements are.

Three tables, each row built by `build_solid` in a fresh subprocess with an empty run
store (set-up time; peak resident memory, ru_maxrss):
- the plate: 100 x 100 x 5 mm steel, clamped on its four sides (xmin, xmax, ymin, ymax),
  modes below 100 kHz, hex20 40 x 40 x 2 (50,895 free dofs), without and with the
  residual compliance over the top face's normal (z) dofs;
- the cost per dof of hex20, hex27 and tet10 on meshes of similar dofs (same plate);
- locking and accuracy: the first clamped frequency of a thin square plate (a = 100 mm,
  h = 2 mm) against Leissa's lambda^2 = 35.99, per element.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import time

#: The plate of the cost table [m] and its cut-off [Hz].
PLATE_SIZE = (0.1, 0.1, 0.005)
PLATE_CLAMPS = ("xmin", "xmax", "ymin", "ymax")
PLATE_MAX_FREQUENCY = 1.0e5
#: (element, elements, residual) rows of the plate table.
PLATE_ROWS = (("hex20", (40, 40, 2), False), ("hex20", (40, 40, 2), True))
#: (element, elements) of the cost-per-dof table (about 11,000 to 12,300 free dofs).
ELEMENT_ROWS = (("hex20", (20, 20, 2)), ("hex27", (17, 17, 1)), ("tet10", (17, 17, 1)))
#: The thin plate of the accuracy table [m] and its meshes per element.
THIN_SIZE = (0.1, 0.1, 0.002)
THIN_ROWS = (
    ("hex20", (10, 10, 1)),
    ("hex20", (20, 20, 1)),
    ("hex27", (10, 10, 1)),
    ("tet10", (10, 10, 1)),
    ("tet10", (20, 20, 1)),
)
LEISSA_CLAMPED = 35.99


def _worker(spec: dict) -> dict:
    """Runs in a fresh subprocess: one build_solid, its time and peak memory."""
    import resource

    from granplate.errors import ScenarioError
    from granplate.setup.scenario import Solid
    from granplate.solid.build import build_solid

    sd = Solid(
        size=tuple(spec["size"]),
        elements=tuple(spec["elements"]),
        element=spec["element"],
        clamped=tuple(spec["clamped"]),
        max_frequency=spec["max_frequency"],
    )
    t0 = time.perf_counter()
    try:
        m = build_solid(sd, surface="zmax" if spec["residual"] else None)
    except ScenarioError as err:
        return {"refused": str(err)}
    return {
        "setup_s": time.perf_counter() - t0,
        "rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "n_dofs": int(len(m.dofs)),
        "n_modes": int(m.n_modes),
        "n_surface": int(len(m.surface_dofs)),
        "f1_hz": float(m.frequencies[0]),
        "estimate_s": float(m.cost.seconds),
        "estimate_mib": float(m.cost.memory / 2**20),
    }


def bench_solid(
    element: str, elements, size=PLATE_SIZE, residual: bool = False, max_frequency: float = PLATE_MAX_FREQUENCY
) -> dict:
    """One build in a fresh subprocess with an empty run store."""
    spec = {
        "element": element,
        "elements": list(elements),
        "size": list(size),
        "clamped": list(PLATE_CLAMPS),
        "max_frequency": max_frequency,
        "residual": residual,
    }
    code = (
        "import sys, json; from granplate.bench.solid import _worker; "
        "print('@@RESULT ' + json.dumps(_worker(json.loads(sys.stdin.read()))))"
    )
    with tempfile.TemporaryDirectory(prefix="granplate-solid-bench-") as cache:
        p = subprocess.run(
            [sys.executable, "-c", code],
            input=json.dumps(spec),
            capture_output=True,
            text=True,
            env=dict(os.environ, GRANPLATE_CACHE=cache),
        )
    row = {"element": element, "mesh": " x ".join(str(n) for n in elements), "residual": residual}
    for line in p.stdout.splitlines():
        if line.startswith("@@RESULT "):
            return {**row, **json.loads(line[len("@@RESULT ") :])}
    return {**row, "failed": f"rc {p.returncode}: {p.stderr.strip().splitlines()[-1:] or ''}"}


def leissa_frequency(a: float, h: float, E: float = 200e9, nu: float = 0.3, rho: float = 7850.0) -> float:
    """First frequency [Hz] of a clamped square Kirchhoff plate: 35.99 / a^2 sqrt(D / (rho h)) / 2 pi."""
    D = E * h**3 / (12.0 * (1.0 - nu**2))
    return LEISSA_CLAMPED / a**2 * math.sqrt(D / (rho * h)) / (2.0 * math.pi)


def format_rows(rows: list[dict], accuracy: bool = False) -> str:
    """A table as Markdown."""
    head = "| element | mesh | free dofs | modes | residual dofs | set-up [s] | estimate [s] | peak memory [MiB] "
    head += "| estimate [MiB] | us per dof |" + (" f1 [Hz] | f1 / Leissa |" if accuracy else "")
    lines = [head, "|" + " --- |" * (head.count("|") - 1)]
    f_ref = leissa_frequency(THIN_SIZE[0], THIN_SIZE[2])
    for r in rows:
        if "refused" in r or "failed" in r:
            lines.append(f"| {r['element']} | {r['mesh']} | {r.get('refused') or r.get('failed')} |")
            continue
        line = (
            f"| {r['element']} | {r['mesh']} | {r['n_dofs']:,} | {r['n_modes']} | {r['n_surface']:,} "
            f"| {r['setup_s']:.1f} | {r['estimate_s']:.1f} | {r['rss_mib']:.0f} | {r['estimate_mib']:.0f} "
            f"| {1e6 * r['setup_s'] / r['n_dofs']:.0f} |"
        )
        if accuracy:
            line += f" {r['f1_hz']:.1f} | {r['f1_hz'] / f_ref:.4f} |"
        lines.append(line)
    return "\n".join(lines)


def main(args) -> int:
    """`granplate bench --solid [--quick] [--json FILE]` (quick: the element tables only)."""
    log = lambda line: print(line, file=sys.stderr)
    report: dict = {}
    if not getattr(args, "quick", False):
        report["plate"] = []
        for element, elements, residual in PLATE_ROWS:
            log(f"solid plate {element} {elements} residual={residual} ...")
            report["plate"].append(bench_solid(element, elements, residual=residual))
    report["elements"] = []
    for element, elements in ELEMENT_ROWS:
        log(f"solid cost per dof {element} {elements} ...")
        report["elements"].append(bench_solid(element, elements, residual=True))
    report["accuracy"] = []
    f_ref = leissa_frequency(THIN_SIZE[0], THIN_SIZE[2])
    for element, elements in THIN_ROWS:
        log(f"solid accuracy {element} {elements} ...")
        report["accuracy"].append(bench_solid(element, elements, THIN_SIZE, max_frequency=1.2 * f_ref))
    for name, rows in report.items():
        print(f"\n{name}\n")
        print(format_rows(rows, accuracy=name == "accuracy"))
    if getattr(args, "json", None):
        with open(args.json, "w") as fh:
            json.dump(report, fh, indent=2)
    return 0
