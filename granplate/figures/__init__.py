"""Figures of any assembly and any run (between `results` and `paper`).

- `assembly`: what `granplate show` draws, as plain arrays: granules, walls, the plate
  and its mesh, the load, the contact network (and its forces at one time of a result);
- `show`: draws an `Assembly` (granules to scale, coloured by material, walls, plate,
  load arrows, contact lines);
- `space`: the same for an assembly in space (dimension = 3): three orthogonal
  projections, spheres depth-sorted and depth-shaded, walls as their traces, contact
  lines with width by force, an elastic body deformed; the frames of `granplate animate`;
- `drawing`: either dimension's assembly drawn (`DRAWINGS`, by the dimension's name);
- `run`: the generic figures of any result (energies, plate contact forces, plate
  stress and strain, a 3D body's stress and contact forces, granule speeds), each
  skipped when the run lacks its quantities;
- `common`: the Figure factory, saving as PNG + PDF, time axes;
- `cli`: the `granplate show` command and the generic `granplate plot RESULT`.

Figures are `matplotlib.figure.Figure` objects on the Agg canvas (no pyplot, no global
state). Every drawn quantity carries a `gid` naming it, for the tests.
"""
