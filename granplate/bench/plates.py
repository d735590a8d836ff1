"""`granplate bench --plates`: how the plate's cost grows with its mesh.

For each mesh (steel-r1 with plate.nx x plate.ny changed, plate.modes as given, "auto" by
default) a fresh subprocess with an empty run store (a cold plate cache) builds the model
(set-up time), then runs it (run time); its peak resident memory (ru_maxrss) is read
after the set-up and after the run. A mesh whose plate is refused (too large for the
machine) is reported with the refusal instead of figures. The table also gives the run's
Gauss-point peak von Mises stress, which grows with the mesh (a singular point value), and
its disc-averaged stress, which converges (docs/model.md section 4.4).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

from granplate.bench.harness import parse_pairs
from granplate.bench import write_report

#: Meshes (nx, ny) of the table, the paper's first.
PLATE_MESHES: tuple[tuple[int, int], ...] = ((4, 40), (8, 80), (16, 160), (32, 320))
#: The preset whose plate is refined.
PLATE_CASE = "steel-r1"


def mesh_scenario(nx: int, ny: int, modes: str = "auto", t_end: float | None = None):
    """PLATE_CASE with an nx x ny plate of basis `modes`, run to t_end [s] (None: the preset's)."""
    import dataclasses

    from granplate.setup.presets import preset

    s = preset(PLATE_CASE)
    s = dataclasses.replace(s, plate=dataclasses.replace(s.plate, nx=nx, ny=ny, modes=modes))
    if t_end is not None:
        s = dataclasses.replace(s, time=dataclasses.replace(s.time, t_end=float(t_end)))
    return s


def _plate_worker(spec: dict) -> dict:
    """Runs in a fresh subprocess: build the model, then run it; times and peak memory."""
    import resource

    import granplate as gp
    from granplate.errors import ScenarioError
    from granplate.model.arrays import build_model

    s = mesh_scenario(spec["nx"], spec["ny"], spec["modes"], spec["t_end"])
    t0 = time.perf_counter()
    try:
        model = build_model(s)
    except ScenarioError as err:
        return {"refused": str(err)}
    setup = time.perf_counter() - t0
    rss_setup = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    out = {
        "setup_s": setup,
        "rss_setup_mib": rss_setup / 1024.0,
        "n_red": int(model.plate.n_red),
        "n_modes": int(model.plate.n_modes),
        "truncated": bool(model.plate.truncated),
    }
    if spec["run"]:
        t1 = time.perf_counter()
        ds = gp.simulate(s, model=model, progress=False)
        out["run_s"] = time.perf_counter() - t1
        out["loop_s"] = float(ds.attrs.get("loop_time_s", float("nan")))
        out["summary"] = gp.summary(ds)
    out["rss_peak_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return out


def bench_plate(nx: int, ny: int, modes: str = "auto", t_end: float | None = None, run: bool = True) -> dict:
    """One mesh in a fresh subprocess with an empty run store (see the module docstring)."""
    spec = {"nx": nx, "ny": ny, "modes": modes, "t_end": t_end, "run": run}
    code = (
        "import sys, json; from granplate.bench.plates import _plate_worker; "
        "print('@@RESULT ' + json.dumps(_plate_worker(json.loads(sys.stdin.read()))))"
    )
    with tempfile.TemporaryDirectory(prefix="granplate-plate-bench-") as cache:
        env = dict(os.environ, GRANPLATE_CACHE=cache)
        p = subprocess.run(
            [sys.executable, "-c", code], input=json.dumps(spec), capture_output=True, text=True, env=env
        )
    for line in p.stdout.splitlines():
        if line.startswith("@@RESULT "):
            return {"mesh": f"{nx} x {ny}", "modes": modes, **json.loads(line[len("@@RESULT ") :])}
    return {
        "mesh": f"{nx} x {ny}",
        "modes": modes,
        "failed": f"rc {p.returncode}: {p.stderr.strip().splitlines()[-1:] or ''}",
    }


def format_plate_table(rows: list[dict]) -> str:
    """The plate-scaling table as Markdown."""
    lines = [
        "| mesh | basis | reduced dofs | modes | set-up [s] | memory after set-up [MiB] "
        "| run [s] | peak memory [MiB] | peak von Mises [MPa] | disc-averaged [MPa] |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        if "refused" in r or "failed" in r:
            lines.append(f"| {r['mesh']} | {r['modes']} | | | | | | {r.get('refused') or r.get('failed')} |")
            continue
        basis = "truncated" if r["truncated"] else "all"
        run = f"{r['run_s']:.1f}" if "run_s" in r else "-"
        stress = [(r.get("summary") or {}).get(k) for k in ("max_von_mises", "max_von_mises_disc")]
        mpa = " | ".join("-" if v is None else f"{v / 1e6:.1f}" for v in stress)
        lines.append(
            f"| {r['mesh']} | {basis} | {r['n_red']:,} | {r['n_modes']} | {r['setup_s']:.1f} "
            f"| {r['rss_setup_mib']:.0f} | {run} | {r['rss_peak_mib']:.0f} | {mpa} |"
        )
    return "\n".join(lines)


def run_plates(
    meshes=PLATE_MESHES, modes: str = "auto", t_end: float | None = None, run: bool = True, log=print
) -> list[dict]:
    """The table's rows, one subprocess per mesh."""
    rows = []
    for nx, ny in meshes:
        log(f"plate {nx} x {ny} ({modes}) ...")
        rows.append(bench_plate(nx, ny, modes, t_end, run))
    return rows


def parse_meshes(text: str) -> list[tuple[int, int]]:
    """'4x40,8x80' -> [(4, 40), (8, 80)] (ValueError naming the bad item)."""
    return parse_pairs(text, "--meshes", "NXxNY", "8x80")


def main(args) -> int:
    """`granplate bench --plates [--meshes 4x40,8x80] [--modes auto] [--t-end T] [--json FILE]`."""
    try:
        meshes = parse_meshes(args.meshes) if getattr(args, "meshes", None) else PLATE_MESHES
    except ValueError as err:
        print(f"granplate: error: {err}", file=sys.stderr)
        return 2
    modes = getattr(args, "plate_modes", None) or "auto"
    rows = run_plates(meshes, modes, getattr(args, "t_end", None))
    print()
    print(format_plate_table(rows))
    write_report(args, rows)
    return 1 if any("failed" in r for r in rows) else 0
