"""Folds located on the exact flow (issue 35 item 1, the period-1 fold of the stiff stop chain).

The gap-free chain of tests/piecewise_reference.py is positively homogeneous in the seat
amplitude and has no fold in its band; the variant here presses mass 2 on the stop with a
static force of 12 N (0.12 of k_c a, :data:`PRELOAD`). Below about 1.38 rad/s the stop
stays closed (the linear closed chain); near the closed chain's resonance it lifts off, and
the lifted-off branch bends to lower frequencies (softening) and folds at :data:`FOLD`.

The independent reference is tests/piecewise_reference.py on the exact flow: the fold is
a zero of the test function Π(1 - μ) along a pseudo-arc-length continuation, bisected to
1e-12 in arc length (tests/test_piecewise_reference.py::test_preloaded_fold: two
continuation steps agree to 1e-9, a multiplier at +1 to 1e-6, the orbit beside it checked
by DOP853). The same reference gives the lifted-off branch's Neimark-Sacker point and
period doubling and the fold of the period-2 branch born there (:data:`NS_LIFTED`,
:data:`PD_LIFTED`, :data:`P2_FOLD`); the tests below start the library from the
reference's exact orbits (rows of a sweep) and compare what it locates. The library's fold locator
(:func:`nlgrd.nonlinear.stability.verdicts.locate_fold`) follows the branch on its own
shooting code and finds the zero of |μ - 1|² by secant steps, so the two share nothing
but the equations.
"""

from __future__ import annotations

import numpy as np
import piecewise_reference as pr
import pytest

from nlgrd.nonlinear.fourier.periods import spread
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.laws.force_laws import ContactStop
from nlgrd.nonlinear.results.metrics import MeshMetrics
from nlgrd.nonlinear.results.sweep_results import assemble_result
from nlgrd.nonlinear.stability.verdicts import _branch_ends, locate_bifurcations, locate_fold
from nlgrd.nonlinear.tracing.continuation import continuation, refine_turning_points
from nlgrd.nonlinear.tracing.sweep import sweep

#: Static force on mass 2 towards the stop [N].
PRELOAD = 12.0
#: The reference's period-1 fold of the lifted-off branch [rad/s] (piecewise_reference.locate
#: to 1e-9; tests/test_piecewise_reference.py::test_preloaded_fold).
FOLD = 1.2895493815
#: The reference's other bifurcations of the preloaded chain's period-1 branches [rad/s]
#: (piecewise_reference.locate to 1e-9 in ω; not yet asserted by a library test).
#: The lifted-off branch from its fold up (pr.continue_branch(LIFTED, 1.55, ds=0.1,
#: max_points=300) to 1.3886 rad/s; 2827 s on the shared machine): unstable (a complex
#: pair 1.13 ± 0.17i) up to a Neimark-Sacker point, stable, then flip-unstable past a
#: period doubling (a real μ down to -15 at 1.3886).
NS_LIFTED, PD_LIFTED = 1.3195461123, 1.3648663814
#: The closed-stop branch from 1.20 rad/s up (pr.continue_branch from the closed orbit,
#: ds=0.05, 400 points; 284 s): stable (|μ| 0.95) to past its grazing near 1.3845, folds,
#: unstable (a real μ up to 2.7) back to a second fold, then stable again.
FOLDS_CLOSED = (1.3845452317, 1.3698130028)
#: The upper branch, the stable orbit both default sweeps reach at 1.43 rad/s: followed down
#: it loses stability at a Neimark-Sacker point and folds 4e-6 rad/s below it
#: (tests/test_piecewise_reference.py::test_preloaded_upper_fold: pr.locate to 1e-9, two
#: continuation steps agree to 1e-9).
UPPER_NS, UPPER_FOLD = 1.4297863185, 1.4297822766
#: Followed up from 1.43 rad/s, the upper branch folds between 1.4324095 and 1.4324096 rad/s
#: (tests/test_piecewise_reference.py::test_preloaded_upper_branch_folds_above: the
#: reference's orbits exist up to the first, a real μ at 0.9979, none near at the second).
TOP_FOLD = (1.4324095, 1.4324096)


def preloaded_chain(nu: int = 1) -> ReducedModel:
    """The chain of tests/piecewise_reference.py with the stop preloaded by :data:`PRELOAD`;
    ``nu`` = 2: the period-2 model (base ω/2, the seat at harmonic 2)."""
    seat = np.array([0.0, pr.SEAT, 0.0])
    stop = ContactStop(pr.KC, 0.0, spread(seat, nu) if nu > 1 else seat)
    return ReducedModel.from_matrices(pr.M, pr.D, pr.K, pr.W, np.array([0.0, PRELOAD]), (stop,))


def _point(H: int = 2) -> MeshMetrics:
    return MeshMetrics(0.0, 1e-6, 2e-6, np.full(H + 1, 1e-6), 1.0, 0.0, 1.0, 0.0, False)


def _ended_sweep():
    """Up 1.0-1.4 rad/s converged throughout on a smooth curve; down without an orbit
    below 1.2 rad/s."""
    w = np.array([1.0, 1.1, 1.2, 1.3, 1.4])
    n = w.size
    z = np.zeros((2 * n, 1, 5))
    z[:, 0, 0] = np.concatenate([np.linspace(0.1, 0.2, n), np.linspace(0.2, 0.1, n)])
    conv = [True] * n + [True, True, True, False, False]
    return assemble_result(
        np.concatenate([w, w[::-1]]), ["up"] * n + ["down"] * n, z, conv, [0.0] * 2 * n,
        [1] * 2 * n, [0.5] * 2 * n, [_point() for _ in range(2 * n)], "test",
    )  # fmt: skip


def test_branch_ends_are_jumps_and_points_without_an_orbit():
    """The last converged point of the down sweep is a branch end towards the first point
    without an orbit (row 7 at 1.2 rad/s, towards 1.1); the up sweep has none."""
    res = _ended_sweep()
    assert _branch_ends(res, "up") == []
    assert _branch_ends(res, "down") == [(7, 1.1)]


def test_a_model_without_exact_flow_has_no_exact_fold():
    """locate_fold answers only on the exact flow: a smooth (AFT) law gives None."""
    from nlgrd.nonlinear.laws.force_laws import AFTNonlinearity

    cubic = AFTNonlinearity(lambda u: u**3, lambda u: 3 * u**2, 0, np.array([0.0, 0.1, 0.0]), 64)
    model = ReducedModel.from_matrices(
        np.eye(1), 0.02 * np.eye(1), np.eye(1), np.eye(1), np.zeros(1), (cubic,)
    )
    assert locate_fold(model, np.zeros((1, 5)), 1.0, 1.1) is None
    assert locate_bifurcations(model, _ended_sweep()) == []


@pytest.fixture(scope="module")
def lifted_sweep():
    """A down sweep 1.44-1.28 rad/s at H = 13 that follows the lifted-off branch (stability
    off: the branch is unstable next to its fold, where the stable-seeking default sweep
    leaves it) until Newton finds no orbit (1.29 -> 1.28 rad/s); ~30 s."""
    model = preloaded_chain()
    return model, sweep(model, np.arange(1.44, 1.2749, -0.01), 13, "down", stability=False)


@pytest.mark.slow  # the sweep and ~15 shots near the fold (~45 s)
def test_period_one_fold_of_the_preloaded_chain(lifted_sweep):
    """Acceptance for the period-1 fold: the sweep's branch end (1.29 -> 1.28 rad/s) is one
    of locate_bifurcations' candidates, and the fold located from it is within 1e-8 of the
    reference (abs, rad/s; the locator's tolerance is 1e-9 relative, the reference's 1e-9,
    both exact up to contact times located to 1e-13 of the period), far inside the issue's
    1e-3. (locate_bifurcations also tries the sweep's three jumps at 1.40-1.43 rad/s, ~2
    min more.)"""
    model, res = lifted_sweep
    i, w_off = _branch_ends(res, "down")[-1]
    assert res.omega[i] == pytest.approx(1.29) and w_off == pytest.approx(1.28)
    w = locate_fold(model, res.harmonics[i], float(res.omega[i]), w_off, rtol=1e-9)
    print(f"fold {w:.12f} rad/s, reference {FOLD}")
    assert abs(w - FOLD) < 1e-8


@pytest.mark.slow  # a continuation at H = 13 (~2 s) and its refinement (~45 s)
def test_continuation_turning_point_refined_on_the_exact_flow(lifted_sweep):
    """The continuation at H = 13 from the lifted-off orbit at 1.30 rad/s turns at 1.2831
    rad/s, 6.4e-3 below the exact fold (the truncation: the exact branch has no orbit
    there); refine_turning_points locates it on the exact flow within 1e-8 of the
    reference (abs, rad/s; tolerances as above)."""
    model, res = lifted_sweep
    i = int(np.argmin(np.abs(res.omega - 1.30)))
    c = continuation(model, 1.30, 1.28, 13, res.harmonics[i], stability=False)
    assert c.turning_omegas.size == 1 and abs(c.turning_omegas[0] - FOLD) > 1e-3  # the HB fold is off
    w, exact = refine_turning_points(model, c)
    print(f"H = 13 turning point {c.turning_omegas[0]:.6f}, refined {w[0]:.12f}, reference {FOLD}")
    assert exact.tolist() == [True] and abs(w[0] - FOLD) < 1e-8


#: A start on the lifted-off branch (tests/test_piecewise_reference.py::LIFTED): the H = 13
#: orbit at 1.2896 rad/s shot once; a start for the reference's Newton, not a result.
LIFTED = (1.28958517, np.array([3.6362, -0.9591, 1.9417, 3.656]))


#: Starts on the lifted-off branch from the reference's continuation above (rounded to 5
#: digits: starts for its Newton, not results): unstable below the NS, stable, flip-unstable.
LIFTED_STARTS = {
    1.30987: np.array([3.70482, -1.20486, 2.30538, -0.76426]),
    1.335167: np.array([4.74581, -0.72782, 3.19143, -3.37074]),
    1.370112: np.array([7.43603, 0.77422, 7.19412, -8.01593]),
}


def reference_harmonics(omega: float, H: int = 13, n: int = 128, start=None, nu: int = 1) -> np.ndarray:
    """The reference's exact orbit of period ν at ``omega`` (Newton from ``start``, default
    :data:`LIFTED`), its x₂ sampled at ``n`` angles over ν periods on the exact flow, as ν H
    real harmonics of ω/ν (1, 2νH+1): an orbit independent of the library's harmonic
    balance."""
    from nlgrd.nonlinear.fourier.harmonics import analyse

    stop = pr.Stop(0.0, PRELOAD)
    s0, _, ok = pr.shoot(LIFTED[1] if start is None else start, omega, nu, stop=stop)
    assert ok, omega
    flow = pr.Flow(omega, stop)
    x2 = [s0[1]] + [flow.advance(s0, jacobian=False, t_end=j * nu * flow.T / n)[0][1] for j in range(1, n)]
    return analyse(np.array(x2), nu * H)[None, :]


def test_a_branch_that_turns_unstable_is_followed_to_its_fold():
    """A down sweep whose last row is the lifted-off orbit at 1.30 rad/s, unstable (the
    reference: a real multiplier 1.19 next to the fold), after a stable row (a stable-seeking
    sweep would leave this branch there): locate_bifurcations follows it on the exact flow
    past the sweep's end and finds the reference's fold :data:`FOLD` within 1e-6 rad/s
    (its fold tolerance 1e-3 x rtol = 1e-6 relative; the reference to 1e-9). The rows'
    orbits come from the reference's exact flow, not from the library's harmonic balance;
    the stable row is the closed-stop orbit of the same chain (the linear response), on
    another branch: its branch is still stable at 1.30 rad/s, so no crossing is reported
    between the two rows."""
    model = preloaded_chain()
    z_closed = model.at(1.31, 13).linear_solution().reshape(1, -1)
    z = np.stack([z_closed, reference_harmonics(1.30)])
    res = assemble_result(
        np.array([1.31, 1.30]), ["down", "down"], z, [True, True], [0.0, 0.0], [1, 1], [0.95, 1.19],
        [_point(13), _point(13)], "test", None, None, [0.95 + 0.1j, 1.19 + 0j],
    )  # fmt: skip
    found = locate_bifurcations(model, res, rtol=1e-3)
    print(found)
    assert len(found) == 1 and found[0][1] == "fold" and abs(found[0][2] - FOLD) < 1e-6, found


def test_a_period_two_model_reports_at_the_base_frequency():
    """``nu`` must be a positive integer: one line naming it."""
    from nlgrd.errors import ModelError

    with pytest.raises(ModelError, match="nu"):
        locate_bifurcations(preloaded_chain(), _ended_sweep(), nu=0)


def test_neimark_sacker_and_period_doubling_of_the_lifted_branch():
    """An up sweep of three rows on the lifted-off branch (the reference's exact orbits at
    1.310, 1.335 and 1.370 rad/s: unstable with a complex pair, stable, flip-unstable):
    locate_bifurcations bisects the NS and the PD on the library's exact flow to within
    2e-5 rad/s of the reference's :data:`NS_LIFTED` and :data:`PD_LIFTED` (bisection to
    rtol = 1e-5 relative, 1.4e-5 rad/s; the reference to 1e-9; the issue asks 1e-3)."""
    model = preloaded_chain()
    ws = sorted(LIFTED_STARTS)
    z = np.stack([reference_harmonics(w, start=LIFTED_STARTS[w]) for w in ws])
    res = assemble_result(
        np.array(ws), ["up"] * 3, z, [True] * 3, [0.0] * 3, [1] * 3, [1.12, 0.96, 2.87],
        [_point(13) for _ in ws], "test", None, None, [1.06 + 0.52j, 0.96 + 0.1j, -2.87 + 0j],
    )  # fmt: skip
    found = locate_bifurcations(model, res, rtol=1e-5, folds=False)
    print(found, NS_LIFTED, PD_LIFTED)
    assert [k for _, k, _ in found] == ["Neimark-Sacker", "period doubling"], found
    assert abs(found[0][2] - NS_LIFTED) < 2e-5 and abs(found[1][2] - PD_LIFTED) < 2e-5


#: The reference's period-2 fold [rad/s]: pr.shoot(nu=2) marched from :data:`P2_START` down
#: (1.3600, 1.3570, 1.3540, 1.3525, 1.3520, 1.3518, 1.35176, 1.35175, 1.351745 rad/s, each
#: from the last orbit; ~2 min) finds orbits to 1.351745 with a real multiplier of the
#: period-2 map falling to 1 (1.0468, 1.0294, 1.0123 at the last three), and the zero of
#: (μ - 1)² extrapolated linearly through the last two, 1.3517439 (through the two before:
#: 1.3517435; the branch exists above it, is unstable, and folds there).
P2_FOLD = 1.3517439
#: A start on the period-2 branch born at :data:`PD_LIFTED` (subcritical: it exists below,
#: unstable, a real multiplier 1.56 of the period-2 map): the reference's period-2 orbit at
#: PD_LIFTED - 2e-3 rad/s, shot from the PD orbit plus 0.05 of its flip eigenvector (5
#: digits: a start for its Newton, not a result).
P2_START = (1.3628663814, np.array([6.73395, 0.16199, 6.18303, -7.11646]))


def test_period_two_fold_of_the_preloaded_chain():
    """A period-2 down sweep whose branch ends after its first row (the reference's exact
    period-2 orbit at 1.36287 rad/s): locate_bifurcations(nu=2) on the period-2 model
    follows it on the exact flow to its fold, within 1e-5 rad/s of the reference's
    :data:`P2_FOLD` (the fold tolerance 1e-9 relative; the reference's extrapolated zero
    moves by 4e-7 between two secants: 1e-5 covers it with margin, and is 100 x inside the
    issue's 1e-3)."""
    w, start = P2_START
    z = reference_harmonics(w, start=start, nu=2)
    res = assemble_result(
        np.array([w, 1.30]), ["down", "down"], np.stack([z, z]), [True, False], [0.0, 0.0], [1, 1],
        [1.56, np.nan], [_point(26), _point(26)], "test", None, None, [1.56 + 0j, np.nan],
    )  # fmt: skip
    found = locate_bifurcations(preloaded_chain(2), res, nu=2)
    print(found, P2_FOLD)
    assert len(found) == 1 and found[0][1] == "fold" and abs(found[0][2] - P2_FOLD) < 1e-5, found


def test_closed_stop_fold_past_grazing_is_the_reference():
    """From the closed-stop orbit at 1.38 rad/s (the linear response: the stop closed all
    period) towards 1.40, locate_fold finds the closed branch's first fold past its grazing,
    :data:`FOLDS_CLOSED` [0] of the reference's pseudo-arc-length continuation, within 1e-8
    rad/s (both to 1e-9). The former march in ω, which took each orbit within 5 % of the
    last, hopped between the coexisting orbits there and returned 1.3865769 rad/s (2e-3
    off). ~8 s."""
    model = preloaded_chain()
    z = model.at(1.38, 13).linear_solution().reshape(1, -1)
    w = locate_fold(model, z, 1.38, 1.40, rtol=1e-9)
    print(f"closed-stop fold {w!r}, reference {FOLDS_CLOSED[0]}")
    assert w is not None and abs(w - FOLDS_CLOSED[0]) < 1e-8


def test_a_sweep_past_its_branch_end_restarts():
    """A down sweep (stability off) from the reference's exact lifted-off orbit at 1.29 rad/s
    to 1.28, past the H = 13 branch's fold (1.2831 rad/s): the step from 1.29 has no orbit,
    and the point is solved from the sweep's fresh starts (the linear one). Before, it was
    left not converged (Newton from the ended branch only). Its orbit is the closed-stop
    chain's, checked against the analytic linear response with the stop closed all period
    (mean K_c⁻¹ F₀, first harmonic (K_c - ω² M + iω D)⁻¹ k_c a): to 1e-9 of the
    amplitude (both exact: the orbit is linear). ~5 s."""
    model = preloaded_chain()
    res = sweep(model, [1.29, 1.28], 13, "down", stability=False, z0=reference_harmonics(1.29))
    assert res.converged.tolist() == [True, True] and bool(res.branch_switch[1])
    Kc = pr.K + pr.KC * pr.W @ pr.W.T
    mean = np.linalg.solve(Kc, [0.0, PRELOAD])[1]
    first = np.linalg.solve(Kc - 1.28**2 * pr.M + 1j * 1.28 * pr.D, pr.KC * pr.SEAT * pr.W[:, 0])[1]
    z = res.harmonics[1, 0]
    assert abs(z[0] - mean) < 1e-9 and abs(complex(z[1], -z[2]) - first) < 1e-9 * abs(first)
    assert np.max(np.abs(z[3:])) < 1e-9  # the stop closed all period: no higher harmonics
    assert abs(first - pr.SEAT) < mean  # x₂ - u > 0 at every angle: closed all period


def _reference_max(model: ReducedModel, harmonics, omega: float) -> float | None:
    """max |μ| of the reference's exact orbit shot from the library's orbit (None: no orbit)."""
    from nlgrd.nonlinear.stability.shooting import initial_state

    ss = model.linear_state_space(omega)
    s = initial_state(ss, model.nonlinearities, harmonics, omega, model.static_force)
    _, Phi, ok = pr.shoot(s, omega, stop=pr.Stop(0.0, PRELOAD))
    return float(np.max(np.abs(np.linalg.eigvals(Phi)))) if ok else None


@pytest.fixture(scope="module")
def default_both():
    """The default converged sweep both ways 1.25-1.45 rad/s, 51 frequencies (H = 7 chosen;
    ~5 min on the shared machine)."""
    import warnings

    from nlgrd.nonlinear.tracing.harmonic_convergence import HarmonicsWarning, converged_sweep

    model = preloaded_chain()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HarmonicsWarning)
        return model, converged_sweep(model, np.linspace(1.25, 1.45, 51), "both")


@pytest.fixture(scope="module")
def default_up(default_both):
    """The up rows of the default converged sweep both ways (:func:`default_both`)."""
    model, res = default_both
    return model, res.select("up")


@pytest.mark.slow  # the default sweep (~50 s free, 94 s under load 7) and 39 reference shots
def test_preloaded_chain_with_defaults_verdicts(default_up):
    """Part of the issue's acceptance on the preloaded chain, with defaults: every orbit
    converges, and every settled verdict is the reference's (its exact orbit shot from the
    row's orbit, stable below 1 + 1e-6: both exact up to the contact times, 1e-13 T). The
    rows of 1.386-1.426 rad/s, where the sweep follows harmonic-balance orbits that have no
    exact orbit near them, are "not converged" (12 of 51 at 1.386-1.430 rad/s), never stable
    or unstable: the issue's >= 50 frequencies with a verdict are not met (39). ~110 s
    with the sweep on the shared machine."""
    model, res = default_up
    assert res.converged.all()
    settled = np.nonzero(res.verdict_converged)[0]
    refs = [_reference_max(model, res.harmonics[i], float(res.omega[i])) for i in settled]
    wrong = [
        float(res.omega[i])
        for i, r in zip(settled, refs, strict=True)
        if r is None or bool(res.stable[i]) != (r < 1 + 1e-6)
    ]
    print(f"{settled.size} of {len(res)} verdicts settled; wrong: {wrong}")
    assert wrong == [] and settled.size >= 39
    loose = res.omega[~res.verdict_converged]
    assert loose.min() > 1.3845 and loose.max() < 1.4301


@pytest.mark.slow  # with the sweep above; locate_fold 8 s free, 24 s under load 7
def test_preloaded_chain_with_defaults_closed_fold(default_up):
    """The default sweep up jumps after 1.382 rad/s, where the closed branch folds past its
    grazing: locate_fold from that row finds the reference's fold :data:`FOLDS_CLOSED` [0]
    within 1e-8 rad/s (both to 1e-9; the issue asks 1e-3)."""
    model, res = default_up
    i, w_off = _branch_ends(res, "up")[0]
    assert res.omega[i] == pytest.approx(1.382) and res.verdict_converged[i]
    w = locate_fold(model, res.harmonics[i], float(res.omega[i]), 1.40, rtol=1e-9)
    print(f"fold {w!r}, reference {FOLDS_CLOSED[0]}")
    assert w is not None and abs(w - FOLDS_CLOSED[0]) < 1e-8


def test_a_point_past_a_branch_end_runs_the_restarts_once(monkeypatch):
    """``jump="restart"``, stability off, down 1.44 -> 1.21 rad/s (24 points, H 13): where the
    restarts found no stable orbit and the point is past its branch's end, the fresh start
    takes the restarts' orbits instead of running the same five Newton solves again (before:
    twice at 1.42, 1.41 and 1.40 rad/s). ~10 s."""
    from collections import Counter

    from nlgrd.nonlinear.tracing import landing

    calls: Counter = Counter()
    original = landing.restart

    def counted(model, problem, z_prev, omega, *args, **kwargs):
        calls[round(float(omega), 9)] += 1
        return original(model, problem, z_prev, omega, *args, **kwargs)

    monkeypatch.setattr(landing, "restart", counted)
    res = sweep(preloaded_chain(), np.linspace(1.44, 1.21, 24), 13, "down", stability=False, jump="restart")
    assert res.converged.sum() == 22 and calls  # the restarts ran (22 of 24 as before the change)
    assert max(calls.values()) == 1, calls


@pytest.mark.slow  # the sweep above and locate_bifurcations (~20 s CPU; 110 s under load 10)
def test_preloaded_chain_with_defaults_bifurcations(default_both):
    """locate_bifurcations with defaults on the default sweep both ways, bounded: each branch
    end followed for at most FOLD_STEPS arc-length steps (before, the branch from the row
    at 1.43 rad/s up hung at a grazing touch near 1.4324 rad/s: > 9 min before it was
    stopped; see test_a_flow_passes_a_grazing_touch). It reports three folds, each the
    reference's (the issue asks 1e-3): the closed-stop fold :data:`FOLDS_CLOSED` [0] from
    the up sweep's jump at 1.382 and the upper branch's fold :data:`UPPER_FOLD` from the
    down sweep's jump at 1.43 rad/s, within 1e-8 rad/s (both to 1e-9), and the upper
    branch's fold above, from the up sweep's jump at 1.43, inside the reference's 1e-7
    bracket :data:`TOP_FOLD` (widened by the locator's 1e-9 tolerance). Nothing else: no
    row of the down sweep settled on the closed branch's unstable middle, so its second
    fold (FOLDS_CLOSED [1]) is out of reach, and the Neimark-Sacker point 4e-6 above
    UPPER_FOLD (:data:`UPPER_NS`) is no verdict change between rows (the issue's 1e-3 does
    not tell the two apart)."""
    import time

    model, res = default_both
    t0 = time.process_time()
    found = locate_bifurcations(model, res)
    print(f"{found}: {time.process_time() - t0:.1f} s CPU")
    assert [(d, k) for d, k, _ in found] == [("up", "fold"), ("up", "fold"), ("down", "fold")], found
    assert abs(found[0][2] - FOLDS_CLOSED[0]) < 1e-8 and abs(found[2][2] - UPPER_FOLD) < 1e-8
    assert TOP_FOLD[0] - 1e-8 < found[1][2] < TOP_FOLD[1] + 1e-8


#: A state at θ = 0 near the upper branch (the corrector's iterate at 1.4323 rad/s of the
#: continuation from the default sweep's row at 1.43 up, full digits: the case itself) whose
#: orbit touches the stop at t = 0.794979 T (a grazing, its margin's slope zero there).
GRAZING = (
    1.432336625583852,
    np.array([-8.586779900864656, 1.0609701108303236, 12.051341372227704, 0.14352451848658895]),
)


def test_a_flow_passes_a_grazing_touch():
    """The orbit from :data:`GRAZING` enters the stop at 0.794979 T and leaves it within the
    same sampling step of the flow: the event search, which took the zero the step starts
    on for the exit, flipped the contact state at that instant forever (the fold search from
    the row at 1.43 rad/s never returned). It now brackets the exit after the entry, and the
    period map is the reference's (its own event search: one or three changes at 0.794979 T,
    as the kernel rounds) to 1e-10 of the state (both exact up to contact times located to
    1e-13 T; 1.4e-13 here), in well under 5 s of CPU time (0.03 s here)."""
    import time

    from nlgrd.nonlinear.stability.shooting import model_flow

    w, s = GRAZING
    ref, _, events = pr.Flow(w, pr.Stop(0.0, PRELOAD)).advance(s, 1)
    # the touch: one change there, or three at the same instant (in, out, in) — which, the
    # kernel's rounding decides (Haswell 3, Sandybridge and Prescott 1); the map is the same
    assert np.sum(np.abs(events * w / (2 * np.pi) - 0.794979) < 1e-6) in (1, 3)
    t0 = time.process_time()
    end, Phi, _ = model_flow(preloaded_chain(), w).period(s)
    assert time.process_time() - t0 < 5.0
    assert np.max(np.abs(end - ref)) < 1e-10 * np.max(np.abs(ref))


#: The bifurcations of the preloaded chain's period-1 branches that no library test starts
#: from (ω [rad/s], the reference's): each from a march in ω on the exact flow (pr.shoot,
#: steps of at most 5e-4 rad/s from the secant predictor, kept within 1e-2 of the state),
#: from the exact orbit shot from the branch's last row before it, to where a test
#: function changes sign (within one step: the period doubling 1.4310718 in (1.43102,
#: 1.43152)) or, for a fold, where the march ends (1.4506266) with a real multiplier at 1 to
#: 1e-3 (0.9997; 2026-12-07). The lifted-off branch followed up (the reference's
#: continuation from LIFTED_STARTS passes the library's rows at 1.402-1.434 rad/s to
#: 1e-2 of the state) regains stability by a period doubling and folds; BRANCH_END: the
#: branch through the unstable orbit at 1.394 rad/s (max |μ| 12.7) exists on the
#: reference's flow up to 1.3952 and not at 1.3953 (Newton from the last orbit); no
#: multiplier is near 1 at 1.3952 and the reference's event search does not return
#: closer to that end (a grazing touch), so only the end, within 1e-4, is checked.
LIFTED_UP = {"period doubling": 1.4310716, "fold": 1.4506266}
BRANCH_END = (1.3952, 1.3953)


@pytest.fixture(scope="module")
def first_jump(default_both):
    """coexisting_branches beside the default sweep's first jump (the up sweep leaving the
    closed stop at 1.382 rad/s): two searches, three branches (~60 s of CPU)."""
    import time

    from nlgrd.nonlinear.tracing.coexisting import coexisting_branches

    model, res = default_both
    before = res.harmonics.copy()
    t0 = time.process_time()
    branches = coexisting_branches(model, res, max_jumps=1)
    print(f"{len(branches)} branches, {time.process_time() - t0:.1f} s CPU")
    np.testing.assert_array_equal(res.harmonics, before)  # the sweep's rows are not changed
    return model, branches


# The lifted-off branch beside this first jump, its PD, NS and fold against the reference and
# every other bifurcation reported against the checked ones: tests/test_coexisting_flow.py
# (test_the_default_flow_reports_the_lifted_off_branch, through the flow's with_coexisting).


@pytest.mark.slow  # on top of first_jump: the period-2 branches (~20 s) and their
# bifurcations (~10-40 s)
def test_period_two_fold_from_the_default_path(first_jump):
    """The period-2 branch born at the lifted-off branch's period doubling (subcritical:
    it exists below, unstable) from defaults: period_two_branches on the branches of
    first_jump starts it from the exact flow beside each period doubling, follows it and
    settles its verdicts; locate_bifurcations on it (the period-2 model) reports its fold,
    the reference's :data:`P2_FOLD` within 1e-3 rad/s (the issue's acceptance; the fold
    located to 1e-9 relative, the reference's extrapolated zero to 4e-7: 1e-5 checked
    too), and nothing else. Before, branching from the harmonic-balance critical mode
    (flip-unstable rows only) and the orbit search at 1.362 rad/s found only orbits with
    max |μ| 16-190 and unsettled verdicts."""
    from nlgrd.nonlinear.tracing.coexisting import period_two_branches

    model, branches = first_jump
    model2 = preloaded_chain(2)
    p2 = period_two_branches(model, model2, branches)
    import re

    def birth(b):  # the period doubling it was started beside, from its source [rad/s]
        return float(re.search(r"period doubling at ([0-9.]+) rad/s", b.source).group(1))

    born = [b for b in p2 if abs(birth(b) - PD_LIFTED) < 1e-3]
    for b in p2:
        print(b.source, b.omega[b.converged], b.dominant_multiplier[b.converged])
    assert len(born) == 1, [b.source for b in p2]
    found = locate_bifurcations(model2, born[0], nu=2)
    print(found, P2_FOLD)
    assert [k for _, k, _ in found] == ["fold"] and abs(found[0][2] - P2_FOLD) < 1e-5, found


def test_searches_only_beside_jumps_that_leave_a_settled_row():
    """search_frequencies takes the rows on either side of a jump only where the row left
    has a settled verdict (an exact orbit there), each frequency once, and at most
    ``max_jumps`` such jumps. An up sweep of six rows with jumps (branch switches) after
    1.1, 1.3 and 1.4 rad/s; 1.3 is not settled: its jump is skipped."""
    from dataclasses import replace

    from nlgrd.nonlinear.tracing.coexisting import search_frequencies

    w = np.array([1.0, 1.1, 1.2, 1.3, 1.4, 1.5])
    n = w.size
    res = assemble_result(
        w, ["up"] * n, np.zeros((n, 1, 5)), [True] * n, [0.0] * n, [1] * n, [0.5] * n,
        [_point() for _ in range(n)], "test", [False, False, True, False, True, True],
    )  # fmt: skip
    res = replace(res, verdict_converged=np.array([True, True, True, False, True, True]))
    assert search_frequencies(res) == [1.1, 1.2, 1.4, 1.5]
    assert search_frequencies(res, max_jumps=1) == [1.1, 1.2]
    assert search_frequencies(res, max_jumps=0) == []


#: A start on an unstable period-1 orbit at 1.43 rad/s, one of those the orbit search beside
#: the default sweep's jump at 1.43 finds (the exact orbit shot from it, 5 digits: a start
#: for Newton, not a result): max |μ| 6.81, a real multiplier.
HOP_START = (1.43, np.array([-8.61415, 1.06525, 13.39147, 0.12734]))


def _march(s, omega, omega_end, h=2e-4):
    """The reference's exact orbit followed in ω by pr.shoot, each step from the secant
    predictor and kept only within 1e-2 of the state's size of it (halved otherwise):
    [(ω, state)] from ``omega`` to ``omega_end``."""
    stop = pr.Stop(0.0, PRELOAD)
    s, _, ok = pr.shoot(s, omega, stop=stop)
    assert ok
    pts = [(omega, s)]
    sign = np.sign(omega_end - omega)
    while sign * (omega_end - pts[-1][0]) > 1e-12 and h > 1e-7:
        w, s = pts[-1]
        wn = w + sign * min(h, abs(omega_end - w))
        pred = s if len(pts) < 2 else s + (s - pts[-2][1]) * (wn - w) / (w - pts[-2][0])
        sn, _, ok = pr.shoot(pred, wn, stop=stop)
        if ok and np.linalg.norm(sn - pred) <= 1e-2 * np.linalg.norm(s):
            pts.append((wn, sn))
        else:
            h /= 2
    return pts


def test_a_followed_branch_stops_at_its_first_hop():
    """The branch followed by natural continuation (follow_period, H = 13) from the orbit
    :data:`HOP_START` up over 1.430, 1.434, 1.438, 1.442 rad/s runs smoothly at H = 13
    onto another exact branch: its rows above 1.430 are, shot on the reference's exact
    flow, stable orbits (|μ| 0.957) while the reference's branch through the start is
    unstable there (max |μ| 3.5-6.8). cut_at_first_hop keeps only the rows whose exact
    orbit is the reference's branch through the start (a march in ω on the exact flow,
    steps of at most 2e-4 rad/s), to 1e-6 of the state (both converged to 1e-11..1e-12):
    the start, and nothing past the hop. ~10 s."""
    from nlgrd.nonlinear.hb.solvers import solve
    from nlgrd.nonlinear.stability.shooting import initial_state
    from nlgrd.nonlinear.tracing.coexisting import cut_at_first_hop
    from nlgrd.nonlinear.tracing.subharmonic import follow_period

    model = preloaded_chain()
    w0, start = HOP_START
    z0 = solve(model.at(w0, 13), reference_harmonics(w0, start=start), tol=1e-10).harmonics
    res = follow_period(model, [1.430, 1.434, 1.438, 1.442], 13, 1, w0, z0, "up", stability=False)
    march = _march(start, w0, 1.442)
    assert march[-1][0] == pytest.approx(1.442)  # the reference's branch reaches 1.442

    def off(i):
        """The row's exact orbit's distance from the reference's branch, relative (inf: none)."""
        w = float(res.omega[i])
        s = initial_state(
            model.linear_state_space(w), model.nonlinearities, res.harmonics[i], w, model.static_force
        )
        s, _, ok = pr.shoot(s, w, stop=pr.Stop(0.0, PRELOAD))
        ref = min(march, key=lambda p: abs(p[0] - w))
        assert abs(ref[0] - w) < 1e-9
        return np.linalg.norm(s - ref[1]) / np.linalg.norm(ref[1]) if ok else np.inf

    before = {float(res.omega[i]): off(i) for i in np.nonzero(res.converged)[0]}
    print("rows followed, off the reference's branch:", before)
    assert max(before.values()) > 1e-2  # the case: natural continuation hops
    cut = cut_at_first_hop(model, res)
    kept = {float(cut.omega[i]): off(i) for i in np.nonzero(cut.converged)[0]}
    print("rows kept:", kept)
    assert w0 in kept and max(kept.values()) < 1e-6
