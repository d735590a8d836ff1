"""Where the dimension lives in the time loop: the granular medium's derivative, its
split-off friction, the velocity-Verlet force pass, its kinetic energies and its error
terms, taken from solver.granular (the plane: model.inputs.Granular, state x, y, theta,
vx, vy, omega) or solver.granular3d (space: model.inputs.Granular3, state x, y, z, vx,
vy, vz, wx, wy, wz), chosen at compile time from the type of the granular arrays `g`
(as solver.schemes picks a scheme from its scratch). The RK4 step (solver.rk4), the
schemes and the loop call only these (and `plate_friction_held`: whether a held
plate-contact friction changes a step's first stage), so the same compiled code serves
both dimensions and nothing else asks which one it is.

The dimension is the granular arrays' (model.dimension: `Dimension.arrays`); a hook whose
two implementations are more than the two modules' function of the same name has a
factory per dimension in `_OWN`. Adding a dimension-specific granular function: write it
in both modules with the same signature and add a stub and its overload here.
"""

from __future__ import annotations

from numba.extending import overload

from granplate.model import inputs
from granplate.model.dimension import DIMENSIONS
from granplate.solver import (
    blocks,
    friction_space,
    granular as plane,
    granular3d as space,
    mindlin_plane,
    mindlin_space,
)

#: the dimension's name (model.dimension) by the class of its granular arrays
_ARRAYS = {getattr(inputs, d.arrays): d.name for d in DIMENSIONS.values()}

#: each dimension's module of granular kernels, by the dimension's name
_MODULES = {"plane": plane, "space": space}
#: each dimension's split friction (`friction_flow`), by the dimension's name
_FRICTION = {"plane": plane, "space": friction_space}


def _dimension_of(g) -> str | None:
    """The dimension's name for the numba type of the granular arrays g (None: not theirs)."""
    return _ARRAYS.get(getattr(g, "instance_class", None))


def _module_of(g):
    """solver.granular or solver.granular3d for the numba type of the granular arrays g."""
    return _MODULES.get(_dimension_of(g))


def granular_rhs(t, y, up, vp, g, cfg, dy, fplate, normal, slip, hold, fbar, split, record):
    """The granular derivative and ForceSums (solver.granular.granular_rhs)."""
    raise NotImplementedError("compiled use only")


def friction_flow(y, dt, g, cfg, forward):
    """Friction alone over dt at every pair and wall contact (solver.granular.friction_flow)."""
    raise NotImplementedError("compiled use only")


def normal_forces(t, y, g, cfg, acc, fdamp, fload, commit_t, forces=True, damp=True, loads=True, divide=True):
    """The velocity-Verlet force pass: shock and normal forces alone, the damping force and
    load of each granule apart, the pairs' overlaps committed at commit_t [s] (< 0: not;
    solver.granular.normal_forces), the rows of acc, fdamp, fload cleared first where
    `forces`, `damp`, `loads` (solver.clearing.clear_rows), the forces made accelerations
    where `divide` (else the closing kick does: solver.kicks.divide_kick)."""
    raise NotImplementedError("compiled use only")


def normal_forces_blocks(t, y, g, cfg, acc, fdamp, fload, fpar, spar, commit_t):
    """The velocity-Verlet force pass with the granule pairs in blocks on every core
    (solver.blocks) in space; the plane's serial pass (its pairs are not cut into blocks)."""
    raise NotImplementedError("compiled use only")


def mindlin_force_pass(
    t, yv, yn, h, g, cfg, acc, fdamp, fload, fpar, spar, commit_t, forces=True, damp=True, loads=True
):
    """The velocity-Verlet force pass with Mindlin's tangential law in it: (ForceSums,
    the springs' stored energy [J], their losses [J]) (solver.mindlin_plane.normal_mindlin_forces
    in the plane; in space solver.mindlin_space.normal_mindlin_forces, or
    solver.blocks.mindlin_forces_blocks on every core when spar has blocks, which read
    what to clear from spar); the serial passes clear as `normal_forces`."""
    raise NotImplementedError("compiled use only")


def sensor_loads(y, g, cfg, load):
    """Every granule's sensor reading [N]: half the sum of its pair and wall contacts'
    normal forces (solver.granular.sensor_loads)."""
    raise NotImplementedError("compiled use only")


def plate_friction_held(hold, g):
    """Whether a step holds plate-contact friction that changes its first stage: `hold` in
    the plane; never in space (no plate contacts there yet), so that the step reuses the
    derivative at t_n (solver.rk4)."""
    raise NotImplementedError("compiled use only")


def kinetic_energies(y, g):
    """(KE_x, KE_y, KE_z, KE_rot) [J] of the granules (KE_z = 0 in the plane)."""
    raise NotImplementedError("compiled use only")


def kinetic_energies_part(y, g, lo, hi, sums):
    """(KE_x, KE_y, KE_z, KE_rot) [J] of granules lo..hi-1 added in granule order to sums
    (those four of the granules before: (0.0, 0.0, 0.0, 0.0) to start; `kinetic_energies`
    of a range, carried over consecutive ranges bit for bit the whole range's)."""
    raise NotImplementedError("compiled use only")


def force_error(k1, k0, kend, ratio, g, sc, err):
    """The implicit scheme's granule error terms: (scale, error) [N]."""
    raise NotImplementedError("compiled use only")


@overload(granular_rhs, inline="always")
def _granular_rhs(t, y, up, vp, g, cfg, dy, fplate, normal, slip, hold, fbar, split, record):
    m = _module_of(g)
    if m is not None:
        fn = m.granular_rhs
        return lambda t, y, up, vp, g, cfg, dy, fplate, normal, slip, hold, fbar, split, record: fn(
            t, y, up, vp, g, cfg, dy, fplate, normal, slip, hold, fbar, split, record
        )


@overload(friction_flow, inline="always")
def _friction_flow(y, dt, g, cfg, forward):
    m = _FRICTION.get(_dimension_of(g))
    if m is not None:
        fn = m.friction_flow
        return lambda y, dt, g, cfg, forward: fn(y, dt, g, cfg, forward)


@overload(normal_forces, inline="always")
def _normal_forces(t, y, g, cfg, acc, fdamp, fload, commit_t, forces=True, damp=True, loads=True, divide=True):
    m = _module_of(g)
    if m is not None:
        fn = m.normal_forces

        def dimension_pass(t, y, g, cfg, acc, fdamp, fload, commit_t, forces=True, damp=True, loads=True, divide=True):
            return fn(t, y, g, cfg, acc, fdamp, fload, commit_t, forces, damp, loads, divide)

        return dimension_pass


@overload(normal_forces_blocks, inline="always")
def _normal_forces_blocks(t, y, g, cfg, acc, fdamp, fload, fpar, spar, commit_t):
    return _own(g, "normal_forces_blocks")


@overload(mindlin_force_pass, inline="always")
def _mindlin_force_pass(
    t, yv, yn, h, g, cfg, acc, fdamp, fload, fpar, spar, commit_t, forces=True, damp=True, loads=True
):
    return _own(g, "mindlin_force_pass")


@overload(sensor_loads, inline="always")
def _sensor_loads(y, g, cfg, load):
    m = _module_of(g)
    if m is not None:
        fn = m.sensor_loads
        return lambda y, g, cfg, load: fn(y, g, cfg, load)


@overload(plate_friction_held, inline="always")
def _plate_friction_held(hold, g):
    return _own(g, "plate_friction_held")


@overload(kinetic_energies, inline="always")
def _kinetic_energies(y, g):
    return _own(g, "kinetic_energies")


@overload(kinetic_energies_part, inline="always")
def _kinetic_energies_part(y, g, lo, hi, sums):
    return _own(g, "kinetic_energies_part")


@overload(force_error, inline="always")
def _force_error(k1, k0, kend, ratio, g, sc, err):
    m = _module_of(g)
    if m is not None:
        fn = m.force_error
        return lambda k1, k0, kend, ratio, g, sc, err: fn(k1, k0, kend, ratio, g.mass, g.inertia, g.radius, sc, err)


# What differs between the dimensions beyond each module's function of the same name: one
# factory per hook and dimension, each giving the implementation numba compiles.
def _plane_normal_forces_blocks():
    fn = plane.normal_forces  # the plane's pairs are not cut into blocks: its serial pass

    def plane_pass(t, y, g, cfg, acc, fdamp, fload, fpar, spar, commit_t):  # (what to clear and divide: spar's row 0)
        forces, damp, loads = (
            spar[0, blocks.S_ZERO_ACC] == 0.0,
            spar[0, blocks.S_ZERO_DAMP] == 0.0,
            spar[0, blocks.S_ZERO_LOADS] == 0.0,
        )
        return fn(t, y, g, cfg, acc, fdamp, fload, commit_t, forces, damp, loads, spar[0, blocks.S_UNDIVIDED] == 0.0)

    return plane_pass


def _space_normal_forces_blocks():
    fb = blocks.normal_forces_blocks
    return lambda t, y, g, cfg, acc, fdamp, fload, fpar, spar, commit_t: fb(
        t, y, g, cfg, acc, fdamp, fload, fpar, spar, commit_t
    )


def _plane_mindlin_force_pass():
    fp = mindlin_plane.normal_mindlin_forces  # the plane's pairs are not cut into blocks

    def plane_pass(t, yv, yn, h, g, cfg, acc, fdamp, fload, fpar, spar, commit_t, forces=True, damp=True, loads=True):
        return fp(t, yv, yn, h, g, cfg, acc, fdamp, fload, commit_t, forces, damp, loads)

    return plane_pass


def _space_mindlin_force_pass():
    fs = mindlin_space.normal_mindlin_forces
    fb = blocks.mindlin_forces_blocks

    def space_pass(t, yv, yn, h, g, cfg, acc, fdamp, fload, fpar, spar, commit_t, forces=True, damp=True, loads=True):
        if spar.shape[0] > 0:
            return fb(t, yv, yn, h, g, cfg, acc, fdamp, fload, fpar, spar, commit_t)
        return fs(t, yv, yn, h, g, cfg, acc, fdamp, fload, commit_t, forces, damp, loads)

    return space_pass


def _plane_friction_held():
    return lambda hold, g: hold


def _space_friction_held():
    return lambda hold, g: False  # no plate contacts in space yet


def _plane_kinetic_energies():
    fn = plane.kinetic_energies

    def plane_energies(y, g):
        kx, ky, kr = fn(y, g.mass, g.inertia)
        return kx, ky, 0.0, kr

    return plane_energies


def _space_kinetic_energies():
    fn3 = space.kinetic_energies
    return lambda y, g: fn3(y, g.mass, g.inertia)


def _plane_kinetic_energies_part():
    fn = plane.kinetic_energies

    def plane_part(y, g, lo, hi, sums):
        kx, ky, kr = fn(y[lo:hi], g.mass[lo:hi], g.inertia[lo:hi], sums[0], sums[1], sums[3])
        return kx, ky, 0.0, kr

    return plane_part


def _space_kinetic_energies_part():
    fn3 = space.kinetic_energies
    return lambda y, g, lo, hi, sums: fn3(y[lo:hi], g.mass[lo:hi], g.inertia[lo:hi], sums[0], sums[1], sums[2], sums[3])


#: the factories of the hooks that differ, by the dimension's name and the hook's name
_OWN = {
    "plane": {
        "normal_forces_blocks": _plane_normal_forces_blocks,
        "mindlin_force_pass": _plane_mindlin_force_pass,
        "plate_friction_held": _plane_friction_held,
        "kinetic_energies": _plane_kinetic_energies,
        "kinetic_energies_part": _plane_kinetic_energies_part,
    },
    "space": {
        "normal_forces_blocks": _space_normal_forces_blocks,
        "mindlin_force_pass": _space_mindlin_force_pass,
        "plate_friction_held": _space_friction_held,
        "kinetic_energies": _space_kinetic_energies,
        "kinetic_energies_part": _space_kinetic_energies_part,
    },
}


def _own(g, hook: str):
    """The implementation of `hook` for the numba type of the granular arrays g (None: not
    theirs, so that numba looks further)."""
    make = _OWN.get(_dimension_of(g) or "", {}).get(hook)
    return make() if make is not None else None
