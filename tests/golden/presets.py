"""The regression guard: a fingerprint of every preset under both coupling schemes.

    python tests/golden/presets.py          # rewrite presets.json (only after a change
                                            # that is meant to move results, stated in
                                            # the commit)

The fingerprint is the run summary (without wall time) plus the energies at ten output
times and the granules' final centres, so a refactoring that moves any result shows.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

GOLDEN = Path(__file__).with_name("presets.json")
SCHEMES = ("paper", "implicit")
#: The summary's numbers in the fingerprint (not the wall time; keys added to the summary
#: later join only when presets.json is regenerated).
FINGERPRINT_SUMMARY_KEYS = (
    "t_end",
    "e_shock",
    "ep_max_fraction",
    "ep_final_fraction",
    "eg_max_fraction",
    "eg_final_fraction",
    "dissipated_fraction",
    "max_von_mises",
    "max_eps_yy",
    "energy_residual_max",
    "n_steps",
)


def fingerprint(ds) -> dict:
    """Summary metrics and a few time-series samples of one result."""
    from granplate.results.dataset import summary

    out = {k: v for k, v in summary(ds).items() if k in FINGERPRINT_SUMMARY_KEYS}
    idx = np.linspace(0, ds.sizes["time"] - 1, 10).round().astype(int)
    for name in ("E_plate", "E_granular", "D_friction", "D_viscous", "E_shock"):
        out[name] = [float(v) for v in ds[name].values[idx]]
    if ds.sizes.get("granule", 0):
        out["x_final"] = [float(v) for v in ds.x.values[-1]]
        out["y_final"] = [float(v) for v in ds.y.values[-1]]
    return out


def run(name: str, scheme: str) -> dict:
    """Fingerprint of preset `name` run with `scheme`."""
    import granplate as gp

    s = gp.with_changes(gp.preset(name), {"solver.scheme": scheme})
    return fingerprint(gp.simulate(s, progress=False))


def main() -> None:
    import granplate as gp

    table = {f"{name}/{scheme}": run(name, scheme) for name in gp.preset_names() for scheme in SCHEMES}
    GOLDEN.write_text(json.dumps(table, indent=1) + "\n")
    print(f"wrote {GOLDEN} ({len(table)} runs)")


if __name__ == "__main__":
    sys.exit(main())
