"""Time-domain reference: direct integration of the full finite-element equations with the nonlinear links."""
