"""The figure of `granplate modes`: the frequencies [kHz] against the mode number, and the
lowest modes' shapes (each granule's displacement along the assembly's main axis)."""

from __future__ import annotations

import numpy as np


def draw_modes(modes, name: str, shown: int = 4):
    """(a) every frequency [kHz] by mode number; (b) the `shown` lowest non-zero modes'
    shapes: each granule's displacement along the axis of largest motion, normalised."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10.0, 3.8))
    f = modes.frequencies
    a.plot(np.arange(1, len(f) + 1), f / 1e3, ".", ms=4)
    a.set_xlabel("mode number")
    a.set_ylabel("frequency [kHz]")
    a.set_title(f"(a) {name}: {len(f)} modes, {modes.zero_modes} without stiffness", loc="left", fontsize=9)
    live = np.flatnonzero(f > 0.0)[:shown]
    for k in live:
        shape = modes.shapes[k]
        axis = int(np.argmax(np.sum(shape**2, axis=0)))
        u = shape[:, axis]
        scale = float(np.max(np.abs(u))) or 1.0
        b.plot(np.arange(1, len(u) + 1), u / scale, "-o", ms=3, label=f"{f[k] / 1e3:.3g} kHz")
    b.set_xlabel("granule")
    b.set_ylabel("displacement along the main axis [-]")
    part = " (the granules' part)" if modes.plate.shape[1] else ""
    b.set_title(f"(b) the lowest modes' shapes{part}", loc="left", fontsize=9)
    if len(live):
        b.legend(fontsize=7)
    fig.tight_layout()
    return fig
