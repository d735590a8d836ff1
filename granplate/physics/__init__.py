"""Physics layer: contact laws (one function per equation), the shock load, energies.

Compiled (numba) scalar laws that the solver kernels call; imports only set-up."""
