"""The harmonic-balance problem (residual, Jacobian), its solvers, and torus (quasi-periodic) HB."""
