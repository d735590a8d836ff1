"""Physics layer: contact laws (one function per equation), the energy balance, the shock.

Compiled (numba) scalar laws that the solver calls; imports only set-up."""
