"""Harmonic balance of the geared FE model against direct time integration: the 1/2
superharmonic resonance and the back-side contact regime.

The model, the reference, the tolerances and the checks are those of
tests/test_geared_time_domain.py (its module docstring); this file only holds the other
two regimes, so that the test workers of ``make test`` (pytest-xdist, one file per worker)
run them beside the main resonance.
"""

from __future__ import annotations

import pytest
from test_geared_time_domain import check_case


@pytest.mark.slow
@pytest.mark.parametrize("case", ["superharmonic", "back-side contact"])
def test_harmonic_balance_matches_time_integration(case):
    check_case(case)
