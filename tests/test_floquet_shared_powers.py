"""The exponentials of a contact state that holds on several intervals of a period, from
powers of its state matrix shared by the intervals
(:func:`nlgrd.nonlinear.reduction.linear_algebra.expm_times`), on the full 264-state space
of ``two_shaft.toml`` (the state space the truncation check falls back to).

Independent checks: scipy's ``expm`` of each interval (another implementation: Al-Mohy &
Higham's degree choice, the unscaled powers) and the reference ``method="expm"`` of
:func:`nlgrd.nonlinear.stability.floquet.floquet_multipliers` (scipy's exponentials of the
unscaled state, every eigenvalue of their product).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
from threadpoolctl import threadpool_limits

import nlgrd.nonlinear.stability.floquet as fl
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.nonlinear.reduction.linear_algebra import expm, expm_times
from nlgrd.nonlinear.stability.tangent import state_sequence, tangent_pieces

TWO_SHAFT = Path(__file__).resolve().parent.parent / "data" / "models" / "two_shaft.toml"
OMEGA = 2 * np.pi * 1731.0  # a base frequency of case (b) where the full state decides [rad/s]


def _orbit(mean: float, a1: float, a2: float, law) -> np.ndarray:
    """Harmonics [y0, a1, b1, a2, b2] of the mesh coordinate δ = mean + a1 cos θ + a2 cos 2θ
    [m], measured from the half backlash b: contact where δ - e > b (or < -b)."""
    return np.array([[law.half_backlash + mean, a1, 0.0, a2, 0.0]])


@pytest.fixture(scope="module")
def full_state():
    """two_shaft.toml's link model: its full state at the speed of ``OMEGA`` and its laws."""
    with threadpool_limits(limits=1):
        model = build_link_model(load_model(TWO_SHAFT))
        rec = model.receptance
        ss = rec.stability.full_state(rec.plan.speed(OMEGA))
    return ss, model.reduced.nonlinearities


def _cases(laws):
    """Contact loss twice per period (separation on two intervals, contact on two: each
    state's exponentials share its powers), contact loss with back-side contact (the
    separation on two intervals, front and back contact the same tangent), full contact."""
    law = laws[0]
    return {
        "loss twice": _orbit(2e-6, 1e-6, 5e-6, law),
        "back side": _orbit(-law.half_backlash, 2e-6, 1.2 * law.half_backlash, law),
        "full contact": _orbit(2e-5, 1e-6, 1e-6, law),
    }


def test_shared_powers_equal_scipy_expm_per_interval(full_state):
    """exp(C t) of each interval of the scaled state (w_s η, η') from the shared powers
    against scipy's ``expm`` of C t (Frobenius, relative to ‖exp(C t)‖): no farther than
    twice the distance of the library's one-time :func:`expm` (the product before the
    shared powers) from it, plus 1e-13, and within 1e-11. Seen: 1.1e-12 where ``expm`` is
    at 9.8e-13 and the two are 3.4e-13 apart: these exponentials (‖exp(C t)‖ ~ 2e4, non-normal)
    are that sensitive to rounding in any evaluation order. A wrong coefficient or power
    moves them by ~1e-3 and more."""
    ss, laws = full_state
    prep = fl._prepared(ss.deflated)
    Y = _cases(laws)["loss twice"]
    states, seq = state_sequence(*tangent_pieces(laws, Y, ss.W.shape[1]))
    times = np.array([dth for _, dth in seq]) / OMEGA
    assert len(states) == 2 and len(seq) == 4  # each state on two intervals
    with threadpool_limits(limits=1):
        Es, Cs = fl._exponentials(prep, states, seq, times)
        for E, C, t in zip(Es, Cs, times, strict=True):
            ref = sla.expm(C * t)
            err, before = (float(np.linalg.norm(X - ref) / np.linalg.norm(ref)) for X in (E, expm(C * t)))
            assert err <= min(2 * before + 1e-13, 1e-11)
        C = Cs[0]
        ts = np.array([0.3, 1.0, 2.5]) * times[0]  # also unequal lengths, one call
        for E, t in zip(expm_times(C, ts), ts, strict=True):
            ref = sla.expm(C * t)
            err, before = (float(np.linalg.norm(X - ref) / np.linalg.norm(ref)) for X in (E, expm(C * t)))
            assert err <= min(2 * before + 1e-13, 1e-11)


@pytest.mark.parametrize("case", ["loss twice", "back side", "full contact"])
def test_full_state_multipliers_equal_the_reference(full_state, case):
    """The default method's multipliers on the 264-state full space (the dominant ones:
    exponentials by shared powers, squarings, Ritz values) against the reference
    ``method="expm"`` (every eigenvalue): each returned multiplier within 1e-10 of one of
    the reference's, relative to max |μ|, the same max |μ| and verdict. On these orbits
    the dominant multipliers are separated (the band of 6e-4 holds a few): 1e-10 is then
    the Ritz check's tolerance (RITZ_RTOL) and a wrong exponential moves them by far more.
    (Where a cluster of ~15 multipliers lies within 4e-4 of |μ| = 1 the reference's own
    eigenvalues of the 4e4-norm product are off by ~7e-8: there no 1e-10 comparison with
    it is meaningful.) Full contact takes the energy certificate (μ = 1 exactly)."""
    ss, laws = full_state
    Y = _cases(laws)[case]
    with threadpool_limits(limits=1):
        mu = fl.floquet_multipliers(ss, laws, Y, OMEGA)
        ref = fl.floquet_multipliers(ss, laws, Y, OMEGA, method="expm")
    top = float(np.max(np.abs(ref)))
    dist = max(float(np.min(np.abs(ref - m))) for m in mu)
    assert dist <= 1e-10 * top
    assert abs(float(np.max(np.abs(mu))) - top) <= 1e-10 * top
    assert (np.max(np.abs(mu)) < 1 + 1e-6) == (top < 1 + 1e-6)
    if case == "full contact":
        np.testing.assert_array_equal(mu, np.ones(mu.size))
