"""A time answer settled on a periodic orbit, polished into it (nlgrd.timedomain.settled_orbits).

The rule against signals whose periodicity is known in closed form, and a quasi-periodic
record that must keep its time answer: Kahraman & Blankenship's rig at 3600 Hz up, where
the mesh-periodic orbit lost stability to a complex pair (tests/test_time_answer.py). The
stable orbit found this way on two_shaft at 1730.8 Hz is in tests/test_moved_verdicts.py.
"""

from __future__ import annotations

import numpy as np
import pytest

import nlgrd
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.timedomain.settled_orbits import SETTLED_RTOL, gap, polish, settled
from nlgrd.timedomain.sweep_answers import answer_gaps

KB = "data/case_studies/kahraman_blankenship.toml"


def tail_of(eps: float, ratio: float = np.sqrt(2), periods: int = 4, n: int = 64) -> np.ndarray:
    """(periods, 2, n) samples of a period-1 signal (range 2) plus ``eps`` times a tone at
    ``ratio`` times the base frequency on the second coordinate."""
    t = np.arange(periods * n) / n
    y = np.stack([np.cos(2 * np.pi * t) + 0.3 * np.sin(6 * np.pi * t), np.sin(2 * np.pi * t) + 5.0])
    y[1] += eps * np.cos(2 * np.pi * ratio * t)
    return y.reshape(2, periods, n).transpose(1, 0, 2)


@pytest.mark.parametrize(
    ("eps", "ratio", "expected"),
    [
        (0.0, np.sqrt(2), True),  # exactly periodic
        (0.1 * SETTLED_RTOL, np.sqrt(2), True),  # a remnant below the tolerance
        (10 * SETTLED_RTOL, np.sqrt(2), False),  # a torus's modulation
        (1.0, 0.5, False),  # period 2: not polished as period 1
    ],
)
def test_settled_against_signals_of_known_period(eps, ratio, expected):
    """A tone at √2 ω of amplitude ε changes the period-to-period samples by up to
    2 ε |sin(π √2)| ≈ 1.93 ε, 0.97 ε of the coordinate's range 2: 0.1 and 10 x the
    tolerance sit a decade from it each side; a period-2 tone changes them by its
    double amplitude."""
    assert settled(tail_of(eps, ratio)) is expected


def test_a_constant_coordinate_does_not_block_the_rule():
    """A coordinate with no range (a clearance at rest) whose periods differ by rounding
    (1e-15 of it) is judged at its magnitude's rounding, not its zero range."""
    y = tail_of(0.0)
    rng = np.random.default_rng(0)
    y[:, 1] = 5.0 * (1 + 1e-15 * rng.standard_normal(y[:, 1].shape))
    assert settled(y)
    y[-1, 1] += 1e-6  # a change far above rounding on a coordinate without range
    assert not settled(y)


@pytest.fixture(scope="module")
def kb_answer():
    model = build_link_model(nlgrd.load(KB))
    res = link_sweep(model, 2 * np.pi * np.array([3500.0, 3600.0]), 5, directions="up")
    assert list(np.asarray(res.result.no_stable)) == [False, True]
    return model, res.result, answer_gaps(model, res.result, periods=80, max_periods=80)[1]


def test_a_quasi_periodic_record_is_not_polished(kb_answer):
    """K&B at 3600 Hz up (a complex pair lost; quasi-periodic): the record's last period
    differs from the one before by far more than SETTLED_RTOL (measured 1.08 of a
    coordinate's range, 1000 x), so :func:`polish` leaves the time answer (80 periods, the budget of
    tests/test_time_answer.py, whose test_link_sweep_answers_its_gaps checks the row)."""
    model, res, answers = kb_answer
    a = answers[1]
    g = gap(a.tail[-2], a.tail[-1])
    print(f"period-to-period gap {g:.3f} of the range")
    assert g > 10 * SETTLED_RTOL
    assert polish(model, float(res.omega[1]), a.tail, int(res.H), "up") is None
