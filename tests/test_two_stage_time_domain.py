"""The two-stage reduction against time integration (issue 11); the method and its
tolerances: tests/link_comparison.py."""

from __future__ import annotations

import numpy as np
import pytest
from link_comparison import compare, damped, mesh_losses, report

from nlgrd.nonlinear.models.link_model import build_link_model

#: the two-stage train's up sweep (ζ = 0.05, H = 45: 9 harmonics of the faster mesh) has
#: both meshes losing contact on stable orbits at base frequencies near 359 and 483 Hz
#: (2 Hz map of 40-600 Hz); base = 5 x the input speed, meshes at its 5th and 2nd harmonic
TWO_STAGE_HZ = np.concatenate([np.arange(357.0, 361.01, 0.25), np.arange(481.0, 485.01, 0.25)])


@pytest.mark.slow
def test_two_stage_against_time_integration():
    """Both meshes of the two-stage reduction losing contact, >= 20 stable frequencies of
    the common period: RMS DTE and largest mesh force of each mesh within 1 %. The period
    change is held to 1e-2, the accepted output error: at 358.75 Hz, between unstable
    neighbours (358.5 and 359 Hz), the orbit attracts slowly (5.9e-3 after 4 base
    periods, 5.1e-3 after 8) while its outputs agree to 2.6e-3."""
    model = build_link_model(damped("two_stage"))
    rows, skipped = compare(model, TWO_STAGE_HZ, H=45, active=mesh_losses)
    worst, drift = report("two-stage", rows, skipped)
    assert len(rows) >= 20
    assert worst < 0.01
    assert drift < 1e-2
