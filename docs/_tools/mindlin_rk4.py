"""Draw docs/model.md section 3.16's figures of Mindlin's law under RK4 (the paper's scheme)
against velocity Verlet: the order of convergence (a sticking sphere against its closed form,
an oblique pair against a fine-step Verlet run), eq. (11)'s residual against the step, and
the oblique pair's velocities under both schemes. Run from the repository root:

    python docs/_tools/mindlin_rk4.py

(writes docs/validation-figures/mindlin-rk4-order.png, -energy.png, -verlet.png).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from granplate.physics.mindlin import tangential_compliance  # noqa: E402
from granplate.setup.materials import LIBRARY  # noqa: E402
from granplate.setup.scenario import Solver  # noqa: E402
from granplate.verification import lammps as L  # noqa: E402
from granplate.verification.base import simulate  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "validation-figures"
R = 1e-3
STEEL = LIBRARY["steel"]
MASS = 4.0 / 3.0 * math.pi * R**3 * STEEL.rho
PAIR_STEPS = (8e-9, 4e-9, 2e-9)
STICK_STEPS = (2e-7, 1e-7, 5e-8)


def run(s, scheme: str):
    """The scenario s under `scheme`, warnings off."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate(dataclasses.replace(s, solver=Solver(scheme=scheme)))


def sticking_error(scheme: str, dt: float) -> float:
    """The nudged resting sphere's largest departure from v0 cos(w_t t), over v0."""
    v0 = 1e-3
    s, d0 = L.mindlin_floor(vx=v0, vy=0.0, t_end=8e-5, n_out=80, dt=dt)
    ds = run(s, scheme)
    w_t = math.sqrt(3.5 * 8.0 / tangential_compliance(STEEL.E, STEEL.nu) * math.sqrt(R * d0) / MASS)
    v = ds["vx"].values[:, 0] - R * ds["omega_y"].values[:, 0]
    return float(np.abs(v - v0 * np.cos(w_t * ds.time.values)).max() / v0)


def main() -> None:
    """Run the cases and draw the three figures."""
    ref = run(L.mindlin_pair(dt=2.5e-10, arm="radius"), "verlet")
    keys = ("vx", "vy", "vz")
    dev: dict[str, list[float]] = {"verlet": [], "paper": []}
    res: dict[str, list[float]] = {"verlet": [], "paper": []}
    last = {}
    for scheme in dev:
        for dt in PAIR_STEPS:
            ds = run(L.mindlin_pair(dt=dt, arm="radius"), scheme)
            dev[scheme].append(max(float(np.abs(ds[k].values - ref[k].values).max()) for k in keys) / 0.2)
            res[scheme].append(float(np.abs(ds["energy_residual"].values).max()))
            last[scheme] = ds
    stick = [sticking_error("paper", dt) for dt in STICK_STEPS]
    stick_v = [sticking_error("verlet", dt) for dt in STICK_STEPS]

    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].loglog(STICK_STEPS, stick, "o-", label="paper (RK4)")
    ax[0].loglog(STICK_STEPS, stick_v, "s-", label="verlet")
    h = np.array(STICK_STEPS)
    ax[0].loglog(h, stick[-1] * (h / h[-1]) ** 4, "k:", label="slope 4")
    ax[0].loglog(h, stick_v[-1] * (h / h[-1]) ** 2, "k--", label="slope 2")
    ax[0].set(xlabel="step h [s]", ylabel="max |v_c - v0 cos(w_t t)| / v0", title="sticking sphere on a floor")
    ax[0].legend()
    h = np.array(PAIR_STEPS)
    for scheme, mark in (("verlet", "s-"), ("paper", "o-")):
        ax[1].loglog(h, dev[scheme], mark, label=scheme)
    ax[1].loglog(h, dev["paper"][-1] * h / h[-1], "k--", label="slope 1")
    ax[1].set(xlabel="step h [s]", ylabel="max |v - v_ref| / 0.2 m/s", title="oblique pair vs Verlet at 0.25 ns")
    ax[1].legend()
    fig.tight_layout()
    fig.savefig(OUT / "mindlin-rk4-order.png", dpi=110)

    fig, ax = plt.subplots(figsize=(5, 4))
    for scheme, mark in (("verlet", "s-"), ("paper", "o-")):
        ax.loglog(h, res[scheme], mark, label=scheme)
    ax.set(xlabel="step h [s]", ylabel="max |eq. (11) residual|", title="oblique pair: energy balance")
    ax.legend()
    fig.tight_layout()
    fig.savefig(OUT / "mindlin-rk4-energy.png", dpi=110)

    fig, ax = plt.subplots(figsize=(6, 4))
    t = ref.time.values * 1e6
    for k in ("vy", "vz"):
        ax.plot(t, ref[k].values[:, 0], "k-", lw=1)
        ax.plot(t, last["paper"][k].values[:, 0], "o", ms=4, label=f"{k} paper, 2 ns")
        ax.plot(t, last["verlet"][k].values[:, 0], "x", ms=5, label=f"{k} verlet, 2 ns")
    ax.set(xlabel="t [us]", ylabel="velocity of sphere a [m/s]", title="oblique pair (line: Verlet 0.25 ns)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "mindlin-rk4-verlet.png", dpi=110)
    for name, values in (("dev", dev), ("res", res)):
        print(name, values)
    print("stick paper", stick, "verlet", stick_v)


if __name__ == "__main__":
    main()
