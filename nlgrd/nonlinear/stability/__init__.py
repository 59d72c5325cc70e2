"""Stability of orbits: Floquet monodromy, Hill's method, Floquet modes, shooting, verdicts."""
