"""The three-dimensional elastic solid (scikit-fem): a box or a Gmsh mesh, quadratic
elements (hex20, hex27, tet10), clamps and rollers on named faces, the modes below a
cut-off (the rigid-body modes of a free body exact), the static residual compliance the
kept modes miss over a set of surface dofs, the cost of a build checked before it starts,
and `build_solid` with its arrays kept in the run store (docs/model.md section "The 3D
solid")."""
