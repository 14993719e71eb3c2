"""Forward simulation (layer 4): the integrator registry and contract, compiled kernels, the
time loop, its results and the diagnostics of a state."""
