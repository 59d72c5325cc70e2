"""Checks of the brute-force reference (tests/piecewise_reference.py) for the two-DOF chain
with a stiff one-sided spring (issue 35, part 1), before anything is compared with it.

- the exact flow (expm of the augmented linear system, contact changes located by Newton)
  against scipy's DOP853 at rtol 1e-12 on the same piecewise equations: DOP853 steps over
  the kinks of the force without locating them, which costs it accuracy at each contact
  change (the force's derivative jumps by k_c = 100 k), so the tolerance is 1e-7 of the
  displacement range, well above DOP853's 1e-12 per step and well below any difference
  that would matter (a misplaced contact time of 1e-4 T moves the state by ~1e-4);
- the monodromy (product of the flows' Jacobians, saltation = identity) against central
  differences of the period map: this checks the saltation claim itself (a jump of the
  vector field would add a rank-one term of size |f⁺ - f⁻| / |nᵀf| at every contact change);
- the linear limit: with the stop closed all period (a gap of -1e4 a) the shooting orbit
  is the linear frequency response, and the multipliers are exp(λ T) of the closed state;
- the bifurcations located along the period-1 branch do not depend on the continuation's
  step (two step sizes agree to 1e-9 in ω, the location's own tolerance is 1e-12 in arc
  length), and at each one the critical multiplier is on the unit circle to 1e-6.
"""

from __future__ import annotations

import numpy as np
import piecewise_reference as pr
import pytest
from scipy.integrate import solve_ivp


def rhs(omega):
    def f(t, s):
        x, v = s[:2], s[2:]
        u = pr.SEAT * np.cos(omega * t)
        force = -pr.K @ x - pr.D @ v
        force[1] -= pr.KC * max(x[1] - u - pr.GAP, 0.0)
        return np.concatenate([v, np.linalg.solve(pr.M, force)])

    return f


def settled(omega, periods=400):
    f, s = pr.Flow(omega), np.zeros(4)
    for _ in range(periods):
        s = f.advance(s, 1, jacobian=False)[0]
    return s


def test_exact_flow_against_dop853():
    w = 1.5
    s0 = settled(w, 50)
    flow = pr.Flow(w)
    s, _, events = flow.advance(s0, 3)
    assert events.size >= 6  # the stop opens and closes in every period
    ref = solve_ivp(rhs(w), (0, 3 * flow.T), s0, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
    scale = np.ptp(s0[:2]) + pr.SEAT
    err = np.max(np.abs(s - ref)) / scale
    print(f"exact flow vs DOP853 over 3 periods: {err:.1e} of the range")
    assert err < 1e-7


def test_monodromy_is_the_derivative_of_the_period_map():
    w = 1.5
    s0 = settled(w, 50)
    _, Phi, _ = pr.Flow(w).advance(s0, 1)
    h = 1e-6
    flow = pr.Flow(w)
    ends = [[flow.advance(s0 + sg * h * e, 1, False)[0] for sg in (1, -1)] for e in np.eye(4)]
    fd = np.column_stack([(p - m) / (2 * h) for p, m in ends])
    err = np.max(np.abs(fd - Phi)) / np.max(np.abs(Phi))
    print(f"monodromy vs central differences: {err:.1e}")
    assert err < 1e-7  # central differences: O(h²) ~ 1e-12 plus rounding / h ~ 1e-10


def test_linear_limit(monkeypatch):
    monkeypatch.setattr(pr, "GAP", -1e4)  # compressed by ~50 a: closed all period
    w = 1.5
    Kc = pr.K + pr.KC * pr.W @ pr.W.T
    mean = np.linalg.solve(Kc, pr.KC * pr.GAP * pr.W[:, 0])
    s0, Phi, ok = pr.shoot(np.concatenate([mean, [0.0, 0.0]]), w)  # from the static state
    assert ok
    X = np.linalg.solve(Kc - w**2 * pr.M + 1j * w * pr.D, pr.KC * pr.SEAT * pr.W[:, 0])
    moving = s0 - np.concatenate([mean, [0.0, 0.0]])
    exact = np.concatenate([X.real, (1j * w * X).real])
    # rounding of the mean (1e4 a) is 1e-12 a: the oscillating part to 1e-9 of its size
    np.testing.assert_allclose(moving, exact, rtol=0, atol=1e-9 * np.max(np.abs(exact)))
    lam = np.linalg.eigvals(pr.augmented(w, True)[:4, :4])
    mu = np.sort_complex(np.exp(lam * 2 * np.pi / w))
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(Phi)), mu, rtol=0, atol=1e-10)


@pytest.fixture(scope="module")
def period_one():
    """The period-1 branch over 1.30-1.70 rad/s with two continuation steps, its bifurcations."""
    s = settled(1.30)
    return [pr.locate(pr.continue_branch(s, 1.30, 1.70, ds=ds)) for ds in (0.05, 0.03)]


def test_period_one_bifurcations(period_one):
    coarse, fine = period_one
    kinds = [k for k, *_ in coarse]
    assert kinds == ["Neimark-Sacker", "Neimark-Sacker", "period doubling"], kinds
    assert [k for k, *_ in fine] == kinds
    for (k, w, mu, _), (_, w2, _, _) in zip(coarse, fine, strict=True):
        print(f"{k}: omega {w:.9f} rad/s (other step {w2:.9f}), multipliers {np.round(mu, 6)}")
        assert abs(w - w2) < 1e-9
        assert pr.kind_of(mu, k)


def test_orbit_stays_under_dop853(period_one):
    """The period-1 orbit just below the period doubling (stable, |μ| 0.97), integrated by
    DOP853 over 20 periods, returns to its start within 1e-7 of the range (the DOP853
    tolerance of the first test, accumulated over the contact changes)."""
    (_, w_pd, _, _) = period_one[0][-1]
    w = w_pd - 0.01
    s0, _, ok = pr.shoot(settled(w), w)
    assert ok
    T = 2 * np.pi / w
    ref = solve_ivp(rhs(w), (0, 20 * T), s0, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
    assert np.max(np.abs(ref - s0)) < 1e-7 * (np.ptp(s0[:2]) + pr.SEAT)
