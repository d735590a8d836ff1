"""Plate layer: Q8 finite elements (scikit-fem), rigid layers, modes, edge load, stresses.

One module per concept: `fe` (mesh, Q8 basis, K and M, nodes, VTK element order),
`constraints` (edges, clamps, symmetry line, rigid layers, the reduction T), `modes`
(the eigenproblem and the mode sign rule), `load` (the half-sine edge load), `stress`
(plane-stress D, strain operator, stress recovery, the disc-averaged stress), `peaks` (the
plate maxima over the output times), `plate_model` (PlateModel: a built plate and its
fields) and `build` (build_plate and its entry in the run store).

Its members load on first use (module `__getattr__`): `from granplate.plate.peaks import
...` does not import scikit-fem, and `from granplate.plate import build_plate` imports
what a build needs.
"""

from __future__ import annotations

import importlib

#: module -> the names the package gives from it
_EXPORTS: dict[str, tuple[str, ...]] = {
    "errors": ("PlateError",),
    "stress": (
        "INTORDER",
        "plane_stress_matrix",
        "von_mises_plane_stress",
        "voigt_strain",
        "strain_operator",
        "quadrature_points",
        "gauss_point_strains",
        "plane_stresses",
        "disc_centres",
        "disc_average_operator",
        "max_disc_average",
    ),
    "fe": ("plate_mesh", "q8_basis", "assemble_stiffness", "assemble_mass", "node_coordinates", "vtk_elements"),
    "constraints": (
        "GEOMETRY_RTOL",
        "EDGES",
        "nodes_on_line",
        "edge_nodes",
        "clamped_dofs",
        "symmetry_line_nodes",
        "rigid_layer_nodes",
        "rigid_layer_map",
        "reduce_matrix",
    ),
    "modes": ("modal_basis", "sign_reference", "fix_mode_signs", "transverse_mode_frequencies"),
    "load": ("EDGE_LOAD_POINTS", "half_sine_line_load", "edge_load_vector"),
    "build": ("PLATE_FORMAT", "STORE_KIND", "PlateModel", "cache_payload", "build_plate"),
}
_MODULE_OF = {name: module for module, names in _EXPORTS.items() for name in names}
__all__ = list(sorted(_MODULE_OF))


def __getattr__(name: str):
    module = _MODULE_OF.get(name)
    if module is None:
        raise AttributeError(f"module 'granplate.plate' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"granplate.plate.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_MODULE_OF))
