"""Plotting: every matplotlib call of nlgrd lives in this package.

Each function takes ``ax=None`` (a new figure when None) and returns the axes.
Submodules: :mod:`.rotor` (modes, Campbell, frequency response, static deflection),
:mod:`.gear` (transmission error, mesh stiffness, load sharing),
:mod:`.nonlinear` (sweeps, time histories).
"""
