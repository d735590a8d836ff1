"""Plate layer: Q8 finite elements (scikit-fem), rigid layers, modes, edge load, stresses.

One module per concept: `fe` (mesh, Q8 basis, K and M, nodes, VTK element order),
`constraints` (edges, clamps, symmetry line, rigid layers, the reduction T), `modes`
(the eigenproblem and the mode sign rule), `load` (the half-sine edge load), `stress`
(plane-stress D, strain operator, stress recovery, the disc-averaged stress) and `build` (PlateModel, build_plate
and its entry in the run store).
"""

from granplate.plate.errors import PlateError  # noqa: F401
from granplate.plate.stress import (  # noqa: F401
    INTORDER,
    plane_stress_matrix,
    von_mises_plane_stress,
    voigt_strain,
    strain_operator,
    quadrature_points,
    gauss_point_strains,
    plane_stresses,
    disc_centres,
    disc_average_operator,
    max_disc_average,
)
from granplate.plate.fe import (  # noqa: F401
    plate_mesh,
    q8_basis,
    assemble_stiffness,
    assemble_mass,
    node_coordinates,
    vtk_elements,
)
from granplate.plate.constraints import (  # noqa: F401
    GEOMETRY_RTOL,
    EDGES,
    nodes_on_line,
    edge_nodes,
    clamped_dofs,
    symmetry_line_nodes,
    rigid_layer_nodes,
    rigid_layer_map,
    reduce_matrix,
)
from granplate.plate.modes import (  # noqa: F401
    modal_basis,
    sign_reference,
    fix_mode_signs,
    transverse_mode_frequencies,
)
from granplate.plate.load import EDGE_LOAD_POINTS, half_sine_line_load, edge_load_vector  # noqa: F401
from granplate.plate.build import (  # noqa: F401
    PLATE_FORMAT,
    STORE_KIND,
    PlateModel,
    cache_payload,
    build_plate,
)
