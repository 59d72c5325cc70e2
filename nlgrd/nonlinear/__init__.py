"""Nonlinear analysis: describing functions, receptance reduction, harmonic balance,
Floquet stability, frequency sweeps and landings, continuation, harmonic convergence
and the per-point results."""
