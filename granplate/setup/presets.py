"""The paper's six cases as ready scenarios (docs/model.md section 8).

    preset("steel-r1")  ->  Scenario
    preset_names()      ->  ["bare-plate", "steel-r1", "steel-r05", "ptfe-r05",
                             "ptfe-r05-moderate", "ptfe-r05-weak"]
    preset("3d-ptfe-r05")  ->  the 3D twin of ptfe-r05 (`twin_3d`; preset_names(True) lists them)

All use the default plate (4 x 40 Q8 elements, top and bottom clamped), contact
coefficients (mu 0.099, k_s 1000 s/m, alpha_n 6.313e-3, steel-PTFE 6.313e-2), time
settings (2 ms) and solver, except that the granules' friction stays inside RK4
(solver.granular_friction = "rk4", PRESET_SOLVER), the treatment their reference results
were computed with. `granplate preset NAME` prints a preset as TOML. Each
description names the paper figures the preset reproduces; a preset changed by
`with_changes` keeps its name, and its description gains "; changed: PATH = VALUE, ...".
"""

from __future__ import annotations

from typing import Callable

from granplate.errors import ScenarioError
import dataclasses

from granplate.setup.scenario import Layout, Load, Plate, Scenario, Solid, Solver

#: One line per preset, naming the paper figures it reproduces.
DESCRIPTIONS: dict[str, str] = {
    "bare-plate": "Bare plate, no granules, q0 = 50 kN/m on its left edge (paper Fig. 2a, 3)",
    "steel-r1": "Steel packing, R2 = R1, q0 = 50 kN/m on column 1 (paper Fig. 2b, 3, 4a, A.1)",
    "steel-r05": "Steel packing, R2 = 0.5 R1, q0 = 50 kN/m (paper Fig. 4b, 6a, 7a)",
    "ptfe-r05": "PTFE intruders, R2 = 0.5 R1, q0 = 50 kN/m (paper Fig. 5, 6b, 7b, 8c)",
    "ptfe-r05-moderate": "PTFE intruders, R2 = 0.5 R1, moderate shock q0 = 10 kN/m (paper Fig. 8b)",
    "ptfe-r05-weak": "PTFE intruders, R2 = 0.5 R1, weak shock q0 = 2 kN/m (paper Fig. 8a)",
}


#: The presets' solver settings: the defaults, with the granules' friction inside RK4.
PRESET_SOLVER = Solver(granular_friction="rk4")


def _bare_plate() -> Scenario:
    return Scenario(
        name="bare-plate",
        description=DESCRIPTIONS["bare-plate"],
        plate=Plate(x0=0.0),
        load=Load(target="plate", q0=50_000.0),
        solver=PRESET_SOLVER,
    )


def _packing(name: str, ratio: float, intruder: str, q0: float) -> Callable[[], Scenario]:
    def make() -> Scenario:
        return Scenario(
            name=name,
            description=DESCRIPTIONS[name],
            layout=Layout(R2_ratio=ratio, intruder_material=intruder),
            plate=Plate(),
            load=Load(target="granules", q0=q0),
            solver=PRESET_SOLVER,
        )

    make.__doc__ = DESCRIPTIONS[name]
    return make


_bare_plate.__doc__ = DESCRIPTIONS["bare-plate"]

#: name -> function building that preset's Scenario.
PRESETS: dict[str, Callable[[], Scenario]] = {
    "bare-plate": _bare_plate,
    "steel-r1": _packing("steel-r1", 1.0, "steel", 50_000.0),
    "steel-r05": _packing("steel-r05", 0.5, "steel", 50_000.0),
    "ptfe-r05": _packing("ptfe-r05", 0.5, "ptfe", 50_000.0),
    "ptfe-r05-moderate": _packing("ptfe-r05-moderate", 0.5, "ptfe", 10_000.0),
    "ptfe-r05-weak": _packing("ptfe-r05-weak", 0.5, "ptfe", 2_000.0),
}


#: The 3D twins' step [s]: velocity Verlet at a fixed step (docs/model.md section 6.5);
#: E_shock moves by 5e-4 and the plate's peak share by 2e-3 of theirs from 1e-7 s.
TWIN_DT = 2e-7
#: Longer steps where the contacts allow them (docs/model.md section 8.1): the largest
#: measured step that keeps the energy residual below a fifth of solver.energy_tol and
#: the twin within half its thin-limit targets (E_shock 0.5%, peak share 1%). The PTFE
#: intruders soften the packing's stiffest chains, and weaker shocks press every contact
#: less (Hertz's stiffness grows as the force to the 1/3). The bare plate has no contact:
#: its modes turn exactly whatever the step, and only the load's sampling at the kicks
#: moves E_shock (by 0.37% at 0.5 us).
TWIN_STEPS = {"bare-plate": 5e-7, "ptfe-r05": 4e-7, "ptfe-r05-moderate": 5e-7, "ptfe-r05-weak": 5e-7}
#: The 3D twins' modes [Hz]: the bare plate's load acts on the body directly, so more of
#: its modes are kept; with granules the rigid layers' residual compliance carries the rest.
TWIN_MAX_FREQUENCY = {"bare-plate": 1e6}


def twin_3d(plane: Scenario) -> Scenario:
    """The 3D twin of a paper preset (docs/model.md section 8): the same granules in the
    plane z = 0, the mid-plane of a 3D slab of the paper's plate (its width x height x
    thickness, its elements with one through the thickness, hex20), clamped on ymin and
    ymax, the rigid layers as translation-only rigid patches across the thickness, the same
    line load on each loaded granule (or on the slab's face xmin), velocity Verlet."""
    p = plane.plate
    assert isinstance(p, Plate), f"{plane.name} has no plane plate"
    name = "3d-" + plane.name
    solid = Solid(
        size=(p.width, p.height, p.thickness),
        elements=(p.nx, p.ny, 1),
        material=p.material,
        clamped=("ymin", "ymax"),
        rigid_layers=plane.layout is not None,
        max_frequency=TWIN_MAX_FREQUENCY.get(plane.name, Solid.max_frequency),
        origin=None if plane.layout is not None or p.x0 is None else (p.x0, p.y0, -0.5 * p.thickness),
    )
    return dataclasses.replace(
        plane,
        name=name,
        description=f"3D twin of {plane.name}: " + plane.description,
        dimension=3,
        plate=solid,
        time=dataclasses.replace(
            plane.time, dt_max=TWIN_STEPS.get(plane.name, TWIN_DT), dt_initial=TWIN_STEPS.get(plane.name, TWIN_DT)
        ),
        solver=Solver(scheme="verlet", granular_friction="split"),
    )


for _name in list(PRESETS):
    PRESETS["3d-" + _name] = (lambda n: lambda: twin_3d(PRESETS[n]()))(_name)
    DESCRIPTIONS["3d-" + _name] = "3D twin of " + _name + ": " + DESCRIPTIONS[_name]

#: The 2D presets (the paper's six cases), in order.
PLANE_PRESETS: tuple[str, ...] = tuple(n for n in PRESETS if not n.startswith("3d-"))


def preset_names(include_3d: bool = False) -> list[str]:
    """The preset names, in the order of docs/model.md section 8 (with their 3D twins
    "3d-NAME" after them when include_3d)."""
    return list(PRESETS) if include_3d else list(PLANE_PRESETS)


def preset(name: str) -> Scenario:
    """The preset called `name` (ScenarioError listing the names if there is none)."""
    try:
        make = PRESETS[name]
    except (KeyError, TypeError):
        raise ScenarioError("preset", name, "unknown preset; presets are: " + ", ".join(PRESETS)) from None
    return make()
