"""Solver layer: the compiled time loop, its schemes and the driver (`simulate`)."""
