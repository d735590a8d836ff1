"""`granplate bench`: CLI glue for the benchmark harness in the repository's benchmarks/.

benchmarks/ is not part of the installed package; it is found next to the granplate
package (a source checkout / editable install).
"""
from __future__ import annotations

import sys
from pathlib import Path


def _load_harness():
    root = Path(__file__).resolve().parent.parent
    if not (root / "benchmarks" / "harness.py").is_file():
        return None
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    import benchmarks.harness as harness

    return harness


def _cmd_bench(args) -> int:
    harness = _load_harness()
    if harness is None:
        print("granplate: bench needs the source checkout: benchmarks/harness.py was not found "
              f"next to the granplate package ({Path(__file__).resolve().parent.parent}); "
              "install granplate editable from a git checkout (pip install -e .)", file=sys.stderr)
        return 2
    return int(harness.main(args))


def register(subparsers) -> None:
    b = subparsers.add_parser("bench", help="benchmark speed and accuracy of every scheme (issue 5)")
    b.add_argument("--quick", action="store_true",
                   help="a subset of presets, shortened, 1 repeat (under a minute)")
    b.add_argument("--json", metavar="FILE", help="write the report as JSON to FILE")
    b.add_argument("--cases", help="comma-separated preset names (default: all six; quick: a subset)")
    b.add_argument("--repeats", type=int, default=None,
                   help="timed repeats per case; the median is reported (default 3, quick 1)")
    b.add_argument("--t-end", dest="t_end", type=float, default=None,
                   help="simulated time [s] for every case (overrides the mode's)")
    b.set_defaults(func=_cmd_bench)
