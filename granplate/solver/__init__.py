"""Solver layer: the compiled time loop (loop.py), its coupling schemes (schemes/) and
the Python driver that runs it in interruptible chunks (driver.py); see
docs/architecture.md. `simulate`, which builds the Dataset, is in granplate.results.run."""
