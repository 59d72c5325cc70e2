"""Orbits over frequency: sweeps, landings, continuation, the choice of H and period, orbit search."""
