"""Progress of the long phases (issue 34, item 4): a continuation, a harmonic check and the
torus answers report once per point, and reporting moves no number; the fine torus grid a
torus's outputs are sampled on is built once per grid and is the grid built afresh."""

import numpy as np

from nlgrd.nonlinear.hb.torus_grid import TorusGrid
from nlgrd.nonlinear.models.sdof import SDOFGearPair
from nlgrd.nonlinear.tracing.continuation import PROGRESS_STEPS, continuation
from nlgrd.nonlinear.tracing.harmonic_convergence import check_harmonics
from nlgrd.nonlinear.tracing.sweep import sweep

LSTE = np.array([0.0, 1.24e-6, 0.0, 0.50e-6, 0.30e-6, 0.10e-6, -0.05e-6])
PAIR = SDOFGearPair(0.261, 0.2587e9, 50e-6, 2295.0, LSTE, damping_ratio=0.02)


class Calls:
    def __init__(self):
        self.calls = []

    def __call__(self, i, n):
        self.calls.append((i, n))


def test_continuation_reports_its_range_then_each_point_and_moves_no_number():
    rm = PAIR.reduced_model()
    w = PAIR.natural_frequency
    plain = continuation(rm, 1.2 * w, 0.6 * w, 5)
    seen = Calls()
    shown = continuation(rm, 1.2 * w, 0.6 * w, 5, progress=seen)
    assert np.array_equal(plain.curve.harmonics, shown.curve.harmonics)
    assert np.array_equal(plain.omega, shown.omega)
    n = len(shown.omega)
    traced = [c for c in seen.calls if c[1] == PROGRESS_STEPS]
    assert len(traced) == n  # once per point traced
    done = [i for i, _ in traced]
    assert done == sorted(done) and done[-1] == PROGRESS_STEPS  # never back, the range reached
    assert seen.calls[-n:] == [(k, n) for k in range(1, n + 1)]  # then each point's outputs


def test_harmonic_check_reports_each_point_and_moves_no_number():
    rm = PAIR.reduced_model()
    grid = np.linspace(0.7, 1.1, 9) * PAIR.natural_frequency
    res = sweep(rm, grid, 5, "up", stability=False)
    plain = check_harmonics(rm, res, 7)
    seen = Calls()
    shown = check_harmonics(rm, res, 7, progress=seen)
    assert np.array_equal(plain.error, shown.error, equal_nan=True)
    m = int(np.sum(res.converged))
    assert seen.calls == [(k, m) for k in range(1, m + 1)]


def test_refined_grid_is_built_once_and_equals_a_fresh_one():
    g = TorusGrid(5, 2, 11, 5)
    fine = g.refined((64, 16))
    assert g.refined((64, 16)) is fine
    fresh = TorusGrid(5, 2, 64, 16)
    for name in ("theta1", "theta2", "inverse", "forward", "k1", "k2"):
        assert np.array_equal(getattr(fine, name), getattr(fresh, name))
    assert g.refined((3, 1)).N1 == 11 and g.refined((3, 1)).N2 == 5  # at least 2 H + 1


def test_converged_sweep_reports_its_phases_and_moves_no_number():
    from nlgrd.nonlinear.tracing.harmonic_convergence import converged_sweep

    rm = PAIR.reduced_model()
    grid = np.linspace(0.8, 1.05, 6) * PAIR.natural_frequency
    plain = converged_sweep(rm, grid, "up", ladder=(5, 7, 9))
    seen = Calls()
    seen.label = "sweep"
    shown = converged_sweep(rm, grid, "up", ladder=(5, 7, 9), progress=seen)
    assert np.array_equal(plain.harmonics, shown.harmonics)
    assert np.array_equal(plain.floquet_max, shown.floquet_max, equal_nan=True)
    assert seen.label == "sweep"  # the phases' labels are put back
    assert (6, 6) in seen.calls and max(i for i, _ in seen.calls) == 6
