"""The linear response of a precompressed chain driven by a wall (the reference solution of
the case `driven-chain`, written from the equations, not from the time loop).

A chain of N beads (masses m_i [kg]) lies between two walls along x, every contact pressed
by the static force F0 [N] (docs/model.md section 3.12). About that state a contact of
Hertz coefficient A [N/m^1.5] and damping coefficient alpha_n (eq. 3) is a spring and a
dashpot in parallel (eq. 2 linearised at the static overlap delta0 = (F0 / A)^(2/3)):

    k = dN/d delta = (3/2) A^(2/3) F0^(1/3),   c = alpha_n sqrt(m* A) delta0^(1/4)     (L1)

(m* the pair's reduced mass, a bead's own mass against a wall). Contact 0 joins the
driven wall to bead 1, contact j beads j and j + 1, contact N bead N to the far wall. The
driven wall's displacement s(t) into the chain and the beads' displacements u_i obey

    M u'' + C u' + K u = e_1 (k_0 s + c_0 s'),   F(t) = F0 + k_N u_N + c_N u_N'          (L2)

with K, C tridiagonal (each contact's k or c between its two beads, a wall contact on its
bead's diagonal) and F the force on the far wall. For s = Re(S e^{i omega t}) the steady
state is U = D(omega)^-1 e_1 z_0 S with D = K + i omega C - omega^2 M and z_j = k_j + i
omega c_j: the transmission T(omega) = z_N U_N / S [N/m] (`transmission`). From rest, the
whole response adds the free decay of the state-space modes (`linear_history`).

An infinite periodic chain whose contacts all have the impedance z carries u_{n+p} =
lambda u_n over a cell of p beads, lambda + 1/lambda the trace of the cell's transfer
matrix prod_j [[2 - m_j omega^2 / z, -1], [1, 0]] (`bloch_ratio`; Brillouin, Wave
Propagation in Periodic Structures, 1946). Inside a pass band |lambda| = 1 without
damping; outside (above the monatomic cut-off (1/pi) sqrt(k/m), or in the diatomic gap
between sqrt(2k/m_heavy) / (2 pi) and sqrt(2k/m_light) / (2 pi)) lambda is real and
negative, and the motion decays by e^{-mu} per cell, mu = -ln|lambda|: the evanescent wave.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np


class LinearChain(NamedTuple):
    """A chain linearised about its static state (L1): masses (N,) [kg]; stiffness and
    dashpot (N + 1,) [N/m], [N s/m] of contact 0 (driven wall - bead 1) to N (bead N - far wall)."""

    masses: np.ndarray
    stiffness: np.ndarray
    dashpot: np.ndarray


def contact_stiffness(a: float, force: float) -> float:
    """k = dN/d delta = (3/2) A delta0^(1/2) = (3/2) A^(2/3) F0^(1/3) [N/m] of a Hertz
    contact of coefficient A [N/m^1.5] carrying F0 [N] (eq. L1)."""
    return 1.5 * a ** (2.0 / 3.0) * force ** (1.0 / 3.0)


def contact_dashpot(alpha_n: float, m_star: float, a: float, force: float) -> float:
    """c = alpha_n sqrt(m* A) delta0^(1/4) [N s/m], delta0 = (F0 / A)^(2/3): eq. (3)'s damping
    at the static overlap (eq. L1)."""
    return alpha_n * math.sqrt(m_star * a) * (force / a) ** (1.0 / 6.0)


def linear_chain(masses, pair_a, wall_a: tuple[float, float], alpha_n: float, force: float) -> LinearChain:
    """The chain of bead masses (N,) [kg], pair coefficients pair_a (N - 1,) [N/m^1.5] and the
    two walls' (driven, far), every contact carrying `force` [N] (no gravity)."""
    m = np.asarray(masses, dtype=float)
    a = np.concatenate([[wall_a[0]], np.asarray(pair_a, dtype=float), [wall_a[1]]])
    m_star = np.concatenate([[m[0]], m[:-1] * m[1:] / (m[:-1] + m[1:]), [m[-1]]])
    k = np.array([contact_stiffness(x, force) for x in a])
    c = np.array([contact_dashpot(alpha_n, ms, x, force) for ms, x in zip(m_star, a)])
    return LinearChain(m, k, c)


def tridiagonal(values: np.ndarray) -> np.ndarray:
    """The (N, N) matrix of N + 1 contact coefficients (stiffnesses, dashpots or impedances)
    of a chain between two walls: contact j couples beads j and j + 1 (1-based), contacts
    0 and N hold beads 1 and N to the walls (eq. L2)."""
    n = len(values) - 1
    out = np.zeros((n, n), dtype=np.asarray(values).dtype)
    idx = np.arange(n)
    out[idx, idx] = values[:-1] + values[1:]
    out[idx[:-1], idx[1:]] = -values[1:-1]
    out[idx[1:], idx[:-1]] = -values[1:-1]
    return out


def steady_displacements(chain: LinearChain, omega: float) -> np.ndarray:
    """U (N,) [m per m]: the beads' complex amplitudes per unit amplitude of the driven
    wall's displacement at omega [rad/s] in the steady state, D(omega) U = e_1 z_0 (eq. L2)."""
    z = chain.stiffness + 1j * omega * chain.dashpot
    d = tridiagonal(z) - omega**2 * np.diag(chain.masses).astype(complex)
    rhs = np.zeros(len(chain.masses), dtype=complex)
    rhs[0] = z[0]
    return np.linalg.solve(d, rhs)


def transmission(chain: LinearChain, omega: float) -> complex:
    """T(omega) [N/m]: the far wall's force amplitude per unit amplitude of the driven wall's
    displacement in the steady state, z_N U_N (eq. L2)."""
    z_far = chain.stiffness[-1] + 1j * omega * chain.dashpot[-1]
    return complex(z_far * steady_displacements(chain, omega)[-1])


def bloch_ratio(cell_masses, impedance: complex, omega: float) -> complex:
    """lambda, the ratio u_{n+p} / u_n over one cell of p beads (masses cell_masses [kg]) of
    an infinite chain whose contacts all have the impedance z = k + i omega c [N/m]: the root
    of lambda + 1/lambda = trace of the cell's transfer matrix with |lambda| <= 1 (the wave
    that decays, or travels, away from the drive)."""
    p = np.eye(2, dtype=complex)
    for m in cell_masses:
        p = np.array([[2.0 - m * omega**2 / impedance, -1.0], [1.0, 0.0]], dtype=complex) @ p
    tr = p[0, 0] + p[1, 1]
    root = np.sqrt(tr * tr - 4.0 + 0j)
    lam = (tr - root) / 2.0
    return complex(lam if abs(lam) <= 1.0 else (tr + root) / 2.0)


def linear_history(chain: LinearChain, omega: float, amplitude: float, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The exact linear response (L2) to s(t) = amplitude sin(omega t) [m] from rest at t = 0:
    the far wall's force change F - F0 [N] at the times t [s] and the beads' displacements
    (len(t), N) [m]; the steady state plus the state-space modes' free decay from the
    difference between rest and the steady state at t = 0."""
    n = len(chain.masses)
    u_ss = amplitude * steady_displacements(chain, omega)  # s = Im(amplitude e^{i omega t})
    minv = 1.0 / chain.masses
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -minv[:, None] * tridiagonal(chain.stiffness)
    a[n:, n:] = -minv[:, None] * tridiagonal(chain.dashpot)
    lam, vec = np.linalg.eig(a)
    x0 = -np.concatenate([u_ss.imag, (1j * omega * u_ss).imag])  # rest minus the steady state at t = 0
    coef = np.linalg.solve(vec, x0.astype(complex))
    phase = np.exp(1j * omega * t)[:, None]
    free = (np.exp(np.outer(t, lam)) * coef[None, :]) @ vec.T
    u = (u_ss[None, :] * phase).imag + free[:, :n].real
    v = (1j * omega * u_ss[None, :] * phase).imag + free[:, n:].real
    return chain.stiffness[-1] * u[:, -1] + chain.dashpot[-1] * v[:, -1], u


def lock_in(t: np.ndarray, y: np.ndarray, omega: float) -> float:
    """The amplitude of the component of y at omega [rad/s] over the samples t [s]: the
    Hann-weighted projection 2 |sum w y e^{-i omega t}| / sum w (exact for a sine at omega over
    whole periods; other frequencies leak by the window's side lobes, falling as 1 /
    (df T)^3 at df T periods of difference over the record's length T)."""
    w = 0.5 - 0.5 * np.cos(2.0 * math.pi * (t - t[0]) / (t[-1] - t[0]))
    y = np.asarray(y, dtype=float)
    return float(2.0 * abs(np.sum(w * (y - np.sum(w * y) / np.sum(w)) * np.exp(-1j * omega * t))) / np.sum(w))
