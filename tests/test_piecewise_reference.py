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
  length), and at each one the critical multiplier is on the unit circle to 1e-6;
- the preloaded variant (a static force on mass 2): its closed-stop linear limit, and the
  fold of its lifted-off branch (two steps agree to 1e-9, a multiplier at +1, the orbit
  beside it under DOP853);
- the preloaded variant's upper branch (the orbit the default sweeps reach at 1.43 rad/s):
  its fold 1.4297822766 and the Neimark-Sacker point 4e-6 rad/s above it (two steps agree
  to 1e-9, a multiplier at +1, a complex pair on the unit circle);
- the period-2 branch born at the period doubling: it ends its stable part at a second
  period doubling (two steps agree to 1e-9, a multiplier at -1) and has no fold up to
  1.80 rad/s.
"""

from __future__ import annotations

import numpy as np
import piecewise_reference as pr
import pytest
from scipy.integrate import solve_ivp


def rhs(omega, stop=None):
    stop = pr.Stop(pr.GAP, pr.PRELOAD) if stop is None else stop

    def f(t, s):
        x, v = s[:2], s[2:]
        u = pr.SEAT * np.cos(omega * t)
        force = -pr.K @ x - pr.D @ v
        force[1] += stop.preload - pr.KC * max(x[1] - u - stop.gap, 0.0)
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


#: The preloaded variant of tests/test_folds.py: a static force of 12 N presses mass 2 on
#: the stop (0.12 of k_c a), which lifts off only near the closed chain's resonance.
PRELOADED = pr.Stop(0.0, 12.0)
#: A start on its lifted-off branch next to the fold (the H = 13 harmonic-balance orbit at
#: 1.2896 rad/s, shot once; Newton converges from it): a start, not a result.
LIFTED = (1.28958517, np.array([3.6362, -0.9591, 1.9417, 3.656]))


def test_preloaded_linear_limit():
    """Below the lift-off (1.0 rad/s) the preloaded stop stays closed all period: the orbit
    is the static deflection under the preload plus the linear response of the closed chain
    to the seat (the same algebra as test_linear_limit), and the contact force stays
    positive. Checks the preload's place in the augmented system."""
    w = 1.0
    Kc = pr.K + pr.KC * pr.W @ pr.W.T
    mean = np.linalg.solve(Kc, PRELOADED.preload * pr.W[:, 0])
    X = np.linalg.solve(Kc - w**2 * pr.M + 1j * w * pr.D, pr.KC * pr.SEAT * pr.W[:, 0])
    exact = np.concatenate([mean + X.real, (1j * w * X).real])
    start = np.concatenate([mean + 0.9 * X.real, 0.9 * (1j * w * X).real])  # Newton from 10 % off
    s0, Phi, ok = pr.shoot(start, w, stop=PRELOADED)
    assert ok
    np.testing.assert_allclose(s0, exact, rtol=0, atol=1e-10 * np.max(np.abs(exact)))
    mu = np.sort_complex(np.exp(np.linalg.eigvals(pr.augmented(w, True, PRELOADED)[:4, :4]) * 2 * np.pi / w))
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(Phi)), mu, rtol=0, atol=1e-10)
    theta = np.linspace(0, 2 * np.pi, 64)
    assert np.min(mean[1] + (X[1] * np.exp(1j * theta)).real - pr.SEAT * np.cos(theta)) > 0  # closed


@pytest.fixture(scope="module")
def preloaded_fold():
    """The fold of the lifted-off branch with two continuation steps (through it)."""
    w, s = LIFTED
    return [
        pr.locate(pr.continue_branch(s, w, 1.0, ds=ds, max_points=n, stop=PRELOADED), stop=PRELOADED)
        for ds, n in ((0.1, 6), (0.07, 8))
    ]


@pytest.mark.slow  # two short continuations on the exact flow (~1 min)
def test_preloaded_fold(preloaded_fold):
    """The period-1 fold of the preloaded chain: a zero of the fold test function Π(1 - μ)
    located to 1e-12 in arc length with two steps that agree to 1e-9 in ω, a multiplier at
    +1 to 1e-6 there; the orbit beside it (0.5 % of ω above, where the branch exists)
    returns under DOP853 after 3 periods within 1e-7 of the range (unstable, |μ| 1.2: an
    error of 1e-12 grows by 1.7 over 3 periods)."""
    (coarse, fine) = preloaded_fold
    assert [k for k, *_ in coarse] == ["fold"] and [k for k, *_ in fine] == ["fold"]
    (_, w, mu, s_fold), (_, w2, _, _) = coarse[0], fine[0]
    print(f"fold: omega {w:.10f} rad/s (other step {w2:.10f}), multipliers {np.round(mu, 6)}")
    assert abs(w - w2) < 1e-9 and pr.kind_of(mu, "fold")
    assert abs(w - 1.2895493815) < 1e-9  # tests/test_folds.py's FOLD
    wd = w * 1.005
    s0, _, ok = pr.shoot(s_fold, wd, stop=PRELOADED)
    assert ok
    T = 2 * np.pi / wd
    ref = solve_ivp(rhs(wd, PRELOADED), (0, 3 * T), s0, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
    assert np.max(np.abs(ref - s0)) < 1e-7 * (np.ptp(s0[:2]) + pr.SEAT)


#: A start on the gap-free chain's period-2 branch (born supercritically at the period
#: doubling 1.618338501 rad/s): the reference's period-2 orbit at 1.64 rad/s, shot from the
#: period-1 orbit there plus 0.3 of its flip eigenvector (5 digits: a start for its Newton,
#: not a result).
P2_START = (1.64, np.array([-1.93060, 0.88016, -0.72824, 0.64253]))


@pytest.fixture(scope="module")
def period_two():
    """The period-2 branch from 1.64 rad/s up: to the band's top, 1.70 rad/s, with one step,
    past its second period doubling with another, and the bifurcations located on each."""
    w, s = P2_START
    coarse = pr.continue_branch(s, w, 1.70, nu=2, ds=0.05, max_points=2000)
    fine = pr.continue_branch(s, w, 1.68, nu=2, ds=0.03, max_points=2000)
    return coarse, pr.locate(coarse, nu=2), pr.locate(fine, nu=2)


@pytest.mark.slow  # two continuations of the period-2 branch on the exact flow (~1 min)
def test_period_two_branch(period_two):
    """The gap-free chain's period-2 branch (tests/test_verdicts.py::PD2): stable from its
    birth at the period doubling up to a second period doubling at 1.6708020066 rad/s (a
    multiplier of the period-2 map at -1 to 1e-6, two continuation steps agree to 1e-9),
    flip-unstable past it (a real μ down to -2.25). No fold in the band: along the branch
    1.64-1.70 rad/s the fold test Π(1 - μ) keeps its sign, every multiplier stays at least
    0.05 from +1 (a fold needs one at +1) and ω grows at every point (the tangent's ω
    component > 0: no turning point). Measured once beyond the band (the same continuation
    to 1.80 rad/s, 612 points, ~4 min): a third period doubling at 1.7747604 rad/s, stable
    past it, still no fold (closest multiplier to +1: 0.107, at 1.707 rad/s)."""
    branch, coarse, fine = period_two
    assert [k for k, *_ in coarse] == ["period doubling"], coarse
    assert [k for k, *_ in fine] == ["period doubling"], fine
    (_, w, mu, _), (_, w2, _, _) = coarse[0], fine[0]
    print(f"second period doubling {w:.10f} (other step {w2:.10f})")
    assert abs(w - w2) < 1e-9 and pr.kind_of(mu, "period doubling")
    assert abs(w - 1.6708020066) < 1e-9  # tests/test_verdicts.py's PD2
    assert branch[-1].omega >= 1.70
    folds = np.array([pr.test_functions(p.mu)["fold"] for p in branch])
    assert np.all(folds > 0) or np.all(folds < 0)
    assert min(np.min(np.abs(p.mu - 1)) for p in branch) > 0.05
    assert all(p.tangent[4] > 0 for p in branch)


#: A start on the preloaded chain's upper branch: the reference's orbit at 1.43 rad/s shot
#: from the default sweep's row there (tests/test_folds.py::default_both; 5 digits: a start
#: for its Newton, not a result). Stable, |μ| 0.956 and 0.917 (two complex pairs).
UPPER = (1.43, np.array([-8.60016, 1.05191, 13.49172, 0.13198]))


@pytest.fixture(scope="module")
def upper_fold():
    """The upper branch from 1.43 rad/s down, with two continuation steps (through its fold)."""
    w, s = UPPER
    return [
        pr.locate(pr.continue_branch(s, w, 1.40, ds=ds, max_points=n, stop=PRELOADED), stop=PRELOADED)
        for ds, n in ((0.02, 20), (0.025, 16))
    ]


@pytest.mark.slow  # two short continuations on the exact flow (~10 s)
def test_preloaded_upper_fold(upper_fold):
    """The preloaded chain's upper branch (tests/test_folds.py::UPPER_FOLD): from 1.43 rad/s
    down it is stable to a Neimark-Sacker point at 1.4297863185 rad/s (a complex pair on the
    unit circle to 1e-6), then unstable to its fold at 1.4297822766 (a multiplier at +1 to
    1e-6), where it turns back up, unstable (a real μ up to 6.8); both located to 1e-12 in arc
    length, and the two steps agree to 1e-9 in ω."""
    coarse, fine = upper_fold
    assert [k for k, *_ in coarse] == ["Neimark-Sacker", "fold"] == [k for k, *_ in fine], (coarse, fine)
    for (k, w, mu, _), (_, w2, _, _) in zip(coarse, fine, strict=True):
        print(f"{k}: omega {w:.10f} rad/s (other step {w2:.10f}), multipliers {np.round(mu, 6)}")
        assert abs(w - w2) < 1e-9 and pr.kind_of(mu, k)
    assert abs(coarse[1][1] - 1.4297822766) < 1e-9 and abs(coarse[0][1] - 1.4297863185) < 1e-9


@pytest.mark.slow  # ~30 shots on the exact flow (~1 s)
def test_preloaded_upper_branch_folds_above():
    """The same upper branch followed up from 1.43 rad/s (Newton at fixed ω, each orbit from
    the last, 5e-4 then 1e-6 then 1e-7 rad/s apart): orbits up to 1.4324095 rad/s, where a
    real multiplier has risen to 0.9979 (0.9935 at 1.432409), and none near the last above
    it at 1.4324096: a fold (tests/test_folds.py::TOP_FOLD) inside that 1e-7 bracket (the
    zero of (1 - μ)² extrapolated through the last two: 1.43240956)."""
    w, s = UPPER
    steps = [
        *np.arange(1.4305, 1.4324, 5e-4),
        *(1.4324 + 1e-6 * np.arange(10)),
        *(1.432409 + 1e-7 * np.arange(1, 6)),
    ]
    for w in steps:
        s1, Phi, ok = pr.shoot(s, w, stop=PRELOADED)
        assert ok and np.linalg.norm(s1 - s) < 0.5, w
        s = s1
    mu = np.linalg.eigvals(Phi)
    real = mu[np.abs(mu.imag) < 1e-9].real
    assert w == pytest.approx(1.4324095, abs=1e-12) and 0.99 < real.max() < 1
    s1, _, ok = pr.shoot(s, w + 1e-7, stop=PRELOADED)
    assert not ok or np.linalg.norm(s1 - s) > 0.05  # no orbit near it: past the fold
