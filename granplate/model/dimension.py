"""The dimension: what differs between the plane (a scenario's `dimension = 2`) and space
(`dimension = 3`), stated once.

A `Dimension` names what a caller would otherwise branch on: the words for it, the
granules' state columns as the Dataset names them (centres, rotation angles, velocities,
spins), the kinetic energy of the translation out of the plane, the loop's granular
arrays class, and how a granule's spin is written in a scenario. It is chosen once, from
a scenario's `dimension` (`of_number`), the loop's granular arrays (`of_arrays`), the number of
state columns (`of_state`) or a result's attribute (`results.dataset.dimension_spec`);
callers ask it instead of testing the number. Where a layer has one implementation per
dimension (the model's build, the solver's granular kernels, a drawing, a VTK writer), it
keys them by `Dimension.name` in one table of that layer.

    >>> from granplate.model.dimension import of_number
    >>> of_number(3).state_variables
    ('x', 'y', 'z', 'vx', 'vy', 'vz', 'omega_x', 'omega_y', 'omega_z')
"""

from __future__ import annotations

import operator
from collections.abc import Callable, Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Dimension:
    """One dimension's names.

    n: 2 or 3; name: "plane" or "space" (the key of the layers' per-dimension tables);
    where: "in the plane" or "in space" (for messages); positions, angles, velocities,
    spins: the Dataset's state variables of each kind (their order is the loop's state
    columns: positions, angles, velocities, spins); depth_energies: the Dataset's kinetic
    energies of the translation out of the plane [J] (part of E_granular); arrays: the class
    name of the loop's granular arrays (model.inputs); spin: a granule's scenario `omega`
    [rad/s] from its spin components (a number in the plane, a vector in space).
    """

    n: int
    name: str
    where: str
    positions: tuple[str, ...]
    angles: tuple[str, ...]
    velocities: tuple[str, ...]
    spins: tuple[str, ...]
    depth_energies: tuple[str, ...]
    arrays: str
    spin: Callable[[Sequence[float]], float | tuple[float, ...]]

    @property
    def state_variables(self) -> tuple[str, ...]:
        """The Dataset's names of the granules' state columns, in the loop's order."""
        return self.positions + self.angles + self.velocities + self.spins

    @property
    def state_columns(self) -> int:
        """Columns of a granule's state in the loop (model.inputs.STATE_COLUMNS)."""
        return len(self.state_variables)

    def foreign(self, name: str) -> bool:
        """Whether Dataset variable `name` belongs to the other dimension alone."""
        return any(name in d.variables and name not in self.variables for d in DIMENSIONS.values())

    @property
    def variables(self) -> tuple[str, ...]:
        """The Dataset's variables named here: the state and the depth energies."""
        return self.state_variables + self.depth_energies


PLANE = Dimension(
    n=2,
    name="plane",
    where="in the plane",
    positions=("x", "y"),
    angles=("theta",),
    velocities=("vx", "vy"),
    spins=("omega",),
    depth_energies=(),
    arrays="Granular",
    spin=operator.itemgetter(0),
)

SPACE = Dimension(
    n=3,
    name="space",
    where="in space",
    positions=("x", "y", "z"),
    angles=(),
    velocities=("vx", "vy", "vz"),
    spins=("omega_x", "omega_y", "omega_z"),
    depth_energies=("KE_depth",),
    arrays="Granular3",
    spin=tuple,
)

#: the dimensions by their number
DIMENSIONS: dict[int, Dimension] = {d.n: d for d in (PLANE, SPACE)}


def of_number(n: int) -> Dimension:
    """The dimension numbered n (a scenario's `dimension`, 2 or 3)."""
    try:
        return DIMENSIONS[int(n)]
    except (KeyError, TypeError, ValueError):
        raise ValueError(f"dimension = {n!r}: allowed 2 (the plane) or 3 (space)") from None


def of_arrays(cls: type) -> Dimension:
    """The dimension of the loop's granular arrays of class `cls` (model.inputs.Granular or
    Granular3, or numba's instance_class of them)."""
    for d in DIMENSIONS.values():
        if cls.__name__ == d.arrays:
            return d
    raise ValueError(f"{cls.__name__}: not the granular arrays of a dimension")


def of_state(columns: int) -> Dimension:
    """The dimension of a granule state with this many columns (6 or 9)."""
    for d in DIMENSIONS.values():
        if columns == d.state_columns:
            return d
    raise ValueError(f"{columns} state columns: the plane has 6, space 9")
