"""The reduction onto the nonlinear coordinates: receptances and the linear state space."""
