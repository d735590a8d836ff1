"""A drive's time profile and the motion it prescribes (docs/model.md section 3.11), as
compiled functions of arrays: a profile id, its parameters (PAR_* columns) and a table.

The profile P(t) [m, m/s or N] is one of the registered profiles (one module each in
physics/profiles/, setup.drive_profiles.DRIVE_PROFILE_REGISTRY), today
    constant   P = value
    ramp       P = value min(t / T, 1)
    half-sine  P = amplitude sin(pi t / T) for t <= T, 0 after
    harmonic   P = value + amplitude sin(2 pi f t)
    table      linear between the points (t_k, P_k); P_0 before them, the last after
    chirp      P = amplitude sin(phi(t)) for t <= T, P(T) after, phi = 2 pi (f0 t + (f1 - f0) t^2 / (2 T)):
               the frequency phi' / (2 pi) swept linearly from f0 to f1 (no integral: a
               displacement or a force drive only)
and `profile_terms` gives its integral from 0, its value, slope and curvature at t (the
profile's module's own, dispatched on the profile id). A
displacement drive moves its body by s = P(t) - P(0) (velocity P', acceleration P''); a
velocity drive by s = int_0^t P (velocity P, acceleration P'); a force drive pushes with P
(a granule, or a wall that it makes a piston of mass PAR_MASS, solver.drives).
"""

from __future__ import annotations

from types import ModuleType

from granplate.jit import njit
from granplate.physics.dispatch import checked_module, pick_of
from granplate.physics.profiles import N_PAR as N_PAR
from granplate.physics.profiles import PAR_MASS as PAR_MASS
from granplate.physics.profiles import PAR_VALUE as PAR_VALUE
from granplate.setup.drive_profiles import DRIVE_PROFILE_REGISTRY

#: drive kinds (the order of setup.scenario.DRIVE_KINDS)
KIND_DISPLACEMENT, KIND_VELOCITY, KIND_FORCE = range(3)
#: the profile "constant"'s id (a held precompression's piston pushes with one)
PROFILE_CONSTANT = list(DRIVE_PROFILE_REGISTRY).index("constant")


def profile_module(name: str) -> ModuleType:
    """The module of the registered drive profile `name`, checked to give `profile_terms`."""
    return checked_module(f"drive profile {name!r}", DRIVE_PROFILE_REGISTRY[name].module, ("profile_terms",))


_TERMS = pick_of(tuple(profile_module(name).profile_terms for name in DRIVE_PROFILE_REGISTRY), 4)


@njit(entry=True, cache=True)
def profile_terms(t, pid, par, tab, n):
    """(int_0^t P, P(t), P'(t), P''(t)) of the profile of id pid (its position in
    setup.drive_profiles.DRIVE_PROFILE_REGISTRY) with parameters par (PAR_*) and table
    tab[:n] (profile "table" only), t >= 0 [s]."""
    return _TERMS(pid, t, par, tab, n)


@njit(entry=True, cache=True)
def drive_motion(t, kind, pid, par, tab, n):
    """What a drive prescribes at t [s]: (s, v, a) the displacement [m] from t = 0,
    velocity [m/s] and acceleration [m/s^2] of a displacement or velocity drive along its
    direction, or (0, 0, F) with the force F [N] of a force drive."""
    integral, p, dp, ddp = profile_terms(t, pid, par, tab, n)
    if kind == KIND_VELOCITY:
        return integral, p, dp
    if kind == KIND_DISPLACEMENT:
        _, p0, _, _ = profile_terms(0.0, pid, par, tab, n)
        return p - p0, dp, ddp
    return 0.0, 0.0, p
