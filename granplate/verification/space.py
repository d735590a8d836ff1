"""Granular assemblies in space (docs/model.md section 3.7) against truth written here
from the equations: `reference_motion_3d`, a scipy `solve_ivp` (DOP853, tight tolerances)
of the 3D contact laws over every pair and every (granule, wall), Hertz's normal force
with its damping and the tanh-Coulomb friction on the slip velocity vector
v_s = (v_i - v_j)_t + (R_i w_i + R_j w_j) x n, with torques R n x f, coefficients
computed here from the material constants (the paper's torque arm R).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from .dynamic import effective, normal_force

#: Source line of the independent integrator in space.
IVP_SOURCE_3D = (
    "scipy DOP853 of the 3D laws (Hertz with damping, tanh-Coulomb on the slip vector, "
    "torques R n x f) over every pair and wall (rtol 1e-11), written independently"
)


def reference_bodies_3d(s) -> dict:
    """Masses, inertias, radii and contact coefficients of every pair and (granule, wall)
    of the 3D scenario `s` (one set of coefficients: no contact.pairs)."""
    if s.contact.pairs:
        raise ValueError("reference_bodies_3d: contact.pairs must be empty (one set of coefficients)")
    mats = [s.materials[g.material] for g in s.granules]
    r = np.array([g.radius for g in s.granules])
    m = np.array([4.0 / 3.0 * math.pi * g.radius**3 * mt.rho for g, mt in zip(s.granules, mats)])
    ii, jj = np.triu_indices(len(r), 1)
    a_pair, c_pair = np.empty(len(ii)), np.empty(len(ii))
    for k, (i, j) in enumerate(zip(ii, jj)):
        e_star, r_star, mi, mj = effective(mats[i], mats[j], r[i], r[j])
        a_pair[k] = 4.0 / 3.0 * e_star * math.sqrt(r_star)
        c_pair[k] = s.contact.alpha_n * math.sqrt(mi * mj / (mi + mj) * a_pair[k])
    walls = [(np.array(w.normal, float) / np.linalg.norm(w.normal), float(w.offset)) for w in s.walls]
    a_wall = np.array([4.0 / 3.0 * effective(mt, None, ri, None)[0] * math.sqrt(ri) for mt, ri in zip(mats, r)])
    return {
        "r": r,
        "m": m,
        "inertia": 0.4 * m * r * r,
        "i": ii,
        "j": jj,
        "a": a_pair,
        "c": c_pair,
        "walls": walls,
        "a_wall": a_wall,
        "c_wall": s.contact.alpha_n * np.sqrt(m * a_wall),
        "mu": s.contact.mu,
        "k_s": s.contact.k_s,
        "clip": s.contact.clip_tensile,
    }


def _friction(mu, k_s, f_n, vs):
    """-mu |N| tanh(k_s |v_s|) v_s / |v_s| per row of vs (zero where v_s = 0)."""
    speed = np.linalg.norm(vs, axis=1)
    safe = np.where(speed > 0.0, speed, 1.0)
    return (-mu * f_n * np.tanh(k_s * speed) / safe)[:, None] * vs * (speed > 0.0)[:, None]


def reference_rhs_3d(b: dict):
    """d/dt of z = [positions (n, 3), velocities (n, 3), spins (n, 3)] (flattened)."""
    r, m, inertia, i, j = b["r"], b["m"], b["inertia"], b["i"], b["j"]
    n = len(r)

    def rhs(_t, z):
        s = z.reshape(3, n, 3)
        pos, vel, spin = s[0], s[1], s[2]
        force, torque = np.zeros((n, 3)), np.zeros((n, 3))
        d = pos[j] - pos[i]
        dist = np.linalg.norm(d, axis=1)
        delta = r[i] + r[j] - dist
        k = np.flatnonzero(delta > 0.0)
        if len(k):
            a_, b_ = i[k], j[k]
            nrm = d[k] / dist[k, None]
            rel = vel[a_] - vel[b_]
            rate = np.sum(rel * nrm, axis=1)
            f_n = normal_force(b["a"][k], b["c"][k], delta[k], rate, b["clip"])
            vs = rel - rate[:, None] * nrm + np.cross(r[a_, None] * spin[a_] + r[b_, None] * spin[b_], nrm)
            f_t = _friction(b["mu"], b["k_s"], f_n, vs)
            f_i = -f_n[:, None] * nrm + f_t
            np.add.at(force, a_, f_i)
            np.add.at(force, b_, -f_i)
            np.add.at(torque, a_, r[a_, None] * np.cross(nrm, f_t))
            np.add.at(torque, b_, r[b_, None] * np.cross(nrm, f_t))
        for wn, off in b["walls"]:
            delta_w = pos @ wn + r - off
            if (delta_w > 0.0).any():
                rate = vel @ wn
                f_n = normal_force(b["a_wall"], b["c_wall"], delta_w, rate, b["clip"])
                vs = vel - rate[:, None] * wn + np.cross(r[:, None] * spin, wn)
                f_t = _friction(b["mu"], b["k_s"], f_n, vs)
                force += -f_n[:, None] * wn + f_t
                torque += r[:, None] * np.cross(wn, f_t)
        return np.concatenate([vel.ravel(), (force / m[:, None]).ravel(), (torque / inertia[:, None]).ravel()])

    return rhs


def reference_motion_3d(s, times: np.ndarray, rtol: float = 1e-11, max_step: float = 1e-6) -> np.ndarray:
    """(len(times), 9, n) [x, y, z, vx, vy, vz, wx, wy, wz] of the 3D scenario `s`'s granules
    from the independent integrator (DOP853, rtol, atol 1e-15, steps of at most max_step
    [s]) at `times` [s]."""
    b = reference_bodies_3d(s)
    g = s.granules
    z0 = np.concatenate(
        [
            np.array([[q.x, q.y, q.z] for q in g]).ravel(),
            np.array([[q.vx, q.vy, q.vz] for q in g]).ravel(),
            np.array([q.spin() for q in g], float).ravel(),
        ]
    )
    sol = solve_ivp(
        reference_rhs_3d(b),
        (0.0, float(times[-1])),
        z0,
        method="DOP853",
        rtol=rtol,
        atol=1e-15,
        t_eval=times,
        max_step=max_step,
    )
    if not sol.success:
        raise RuntimeError(f"reference integrator failed: {sol.message}")
    n = len(g)
    return sol.y.T.reshape(len(times), 3, n, 3).transpose(0, 1, 3, 2).reshape(len(times), 9, n)
