"""Spur gears: involute geometry, tooth stiffness, load sharing and the loaded static
transmission error (LSTE), LSTE files, and the gear mesh of a rotor model."""
