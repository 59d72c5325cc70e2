"""Real harmonics of periodic signals, and orbits of period ν written on the base ω/ν."""
