"""Converged stability verdicts (issue 35 item 1): nlgrd.nonlinear.stability.verdicts, the shooting start
of a contact stop without preload, the memory-bounded H ladder and the stability columns of
merged period-1/period-2 rows.

The independent reference is tests/piecewise_reference.py: the exact flow of the two-DOF
chain with a stiff one-sided spring through scipy's expm, its own event search, shooting and
Floquet; its bifurcations NS 1.364089063, NS 1.432756685, PD 1.618338501 rad/s. The library's
verdicts are compared with the reference multipliers of the orbit the row answers (the
reference Newton started from the library's orbit: the same orbit when it converges there).
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import piecewise_reference as pr
import pytest
from test_shooting import reference_orbit

from nlgrd.nonlinear.fourier.periods import spread
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.laws.force_laws import ContactStop
from nlgrd.nonlinear.results.metrics import MeshMetrics
from nlgrd.nonlinear.results.sweep_results import SweepResult, assemble_result
from nlgrd.nonlinear.stability.shooting import initial_state
from nlgrd.nonlinear.stability.verdicts import agree, converge_verdicts, locate_bifurcations
from nlgrd.nonlinear.tracing.auto_period import beyond_period_one, merge_periods, transitions
from nlgrd.nonlinear.tracing.harmonic_convergence import (
    LADDER,
    HarmonicsWarning,
    check_harmonics,
    converged_sweep,
    ladder_for,
    next_harmonics,
)
from nlgrd.nonlinear.tracing.harmonic_ladder import harmonics_memory, max_harmonics
from nlgrd.nonlinear.tracing.sweep import sweep

#: The reference's bifurcations (tests/piecewise_reference.py, located to 1e-9).
NS = (1.364089063, 1.432756685)
PD = 1.618338501
#: The reference's second period doubling, of the period-2 branch born at :data:`PD` (its
#: multiplier of the period-2 map at -1; tests/test_piecewise_reference.py::test_period_two_branch:
#: two continuation steps agree to 1e-9, and the orbits shot 1e-6 rad/s either side have
#: that multiplier at -0.999804 and -1.000195, so the crossing is within 1e-9 of this). The
#: branch is stable from PD to here and has no fold up to 1.80 rad/s (the same test), so the
#: band 1.30-1.70 rad/s has no period-2 fold: its bifurcations are NS, PD and this one.
PD2 = 1.6708020066


def chain(nu: int = 1) -> ReducedModel:
    """The chain as an nlgrd model; ``nu`` = 2: the period-2 model (base ω/2, seat at harmonic 2)."""
    seat = np.array([0.0, pr.SEAT, 0.0])
    stop = ContactStop(pr.KC, pr.GAP, spread(seat, nu) if nu > 1 else seat)
    return ReducedModel.from_matrices(pr.M, pr.D, pr.K, pr.W, np.zeros(2), (stop,))


def reference_max(model: ReducedModel, harmonics, omega: float, nu: int = 1) -> float:
    """max |μ| of the reference orbit shot (period ν T) from the library's orbit."""
    base = omega / nu
    s = initial_state(model.linear_state_space(base), model.nonlinearities, harmonics, base)
    s0, Phi, ok = pr.shoot(s, omega, nu)
    assert ok, omega
    return float(np.max(np.abs(np.linalg.eigvals(Phi))))


def test_a_contact_stop_without_preload_converges_from_its_first_point():
    """The full-contact linear start of a stop with no gap and no preload sits at the stop
    (x̄ = 0), where Newton never converged: 0 of 81 points at H = 17 before; the start shot
    on the exact flow from it converges at every point (and in about a second)."""
    res = sweep(chain(), np.linspace(1.2, 1.8, 81), 17, "up")
    assert res.converged.all()
    # the orbit's mean is far below the stop: the reference's x₂ mean at 1.2 rad/s (its
    # 256 samples' mean, -4.013), to the H = 17 truncation's 1 %
    x2 = reference_orbit(1.2)[2]
    assert res.harmonics[0, 0, 0] == pytest.approx(np.mean(x2), rel=0.01)


def test_agree():
    assert agree(0.86, 0.861)
    assert not agree(0.99999, 1.001)  # the two sides of 1 + STABLE_RTOL
    assert not agree(-2.24, 0.86) and not agree(2.24, 0.86)
    assert not agree(0.86, 0.90)  # 4 % apart: not converged to MULTIPLIER_RTOL


@pytest.mark.parametrize("omega", [1.35, 1.40, 1.55, 1.64])  # stable, NS band, stable, flip
def test_polished_verdict_is_the_exact_orbits(omega):
    """At H = 9 the HB multipliers are far off; the converged verdict is the reference's
    max |μ| to 1e-6 (both exact up to the contact times, located to 1e-13 T)."""
    model = chain()
    res = sweep(model, [omega], 9, "up")
    check = check_harmonics(model, res, 13)
    out = converge_verdicts(model, res, check.solutions)
    ref = reference_max(model, res.harmonics[0], omega)
    assert out.verdict_converged[0]
    assert out.floquet_max[0] == pytest.approx(ref, abs=1e-6)
    assert bool(out.stable[0]) == (ref < 1 + 1e-6)


def _point(mu: float, dte: float, H: int = 2) -> MeshMetrics:
    return MeshMetrics(0.0, dte, 2 * dte, np.full(H + 1, dte), 1.0, 0.0, 1.0, 0.0, False)


def test_a_verdict_not_converged_is_written_as_such():
    res = assemble_result(
        [1.0, 2.0], ["up", "up"], np.ones((2, 1, 5)), [True, True], [0.0, 0.0], [1, 1],
        [0.5, 0.5], [_point(0.5, 1e-6), _point(0.5, 1e-6)], "test",
    )  # fmt: skip
    out = replace(res, verdict_converged=np.array([True, False]))
    df = out.to_frame()
    assert list(df["verdict"]) == ["stable", "not converged"]
    assert df["stable"].iloc[0] and df["stable"].isna().iloc[1]
    assert df["response"].iloc[1] == "stability not converged" and np.isnan(df["dte_rms [um]"].iloc[1])
    assert df["period"].isna().iloc[1]  # not an answer: no period either
    assert df["dte_rms [um]"].iloc[0] == pytest.approx(1.0)


def _sweep(fmax, dominant, period_tag, H=2):
    n = len(fmax)
    z = np.full((n, 1, 2 * H + 1), period_tag, dtype=float)
    z[:, 0, 1::2] = 0.0  # a pure mean: period_of gives 1 unless odd harmonics are set
    return assemble_result(
        np.arange(1.0, n + 1), ["up"] * n, z, [True] * n, [0.0] * n, [1] * n, fmax,
        [_point(m, 1e-6, H) for m in fmax], "test", None, None, dominant,
    )  # fmt: skip


def test_merged_rows_carry_the_multipliers_of_their_own_orbit():
    """Rows 0-1: period 1 stable; 2: period 1 flip-unstable, period 2 stable (period 2);
    3: both unstable after a period-2 row (the period-2 orbit, what grows from it);
    4: period 1 stable again; 5: both unstable, no period-2 row before: the period-1 orbit
    (before, its multiplier was that of the unstable period-2 orbit)."""
    f1 = [0.9, 0.95, 1.5, 1.6, 0.9, 1.7]
    d1 = [0.9, 0.95, -1.5, -1.6, 0.9, -1.7]
    p1 = _sweep(f1, d1, 1.0)
    H2 = 4
    f2 = [0.8, 0.8, 0.9, 1.3, 0.8, 1.4]
    d2 = [0.8, 0.8, 0.9, -1.3 + 0.2j, 0.8, 1.4j]
    z2 = np.zeros((6, 1, 2 * H2 + 1))
    z2[:, 0, 1] = 1.0  # cos(θ/2): period 2
    p2 = assemble_result(
        p1.omega, p1.direction, z2, [True] * 6, [0.0] * 6, [1] * 6, f2,
        [_point(m, 1e-6, H2) for m in f2], "p2", None, None, d2,
    )  # fmt: skip
    merged = merge_periods(p1, p2)
    assert list(merged.period) == [1, 1, 2, 2, 1, 1]
    for i, p in enumerate(merged.period):
        src = p2 if p == 2 else p1
        assert merged.floquet_max[i] == src.floquet_max[i]
        assert merged.dominant_multiplier[i] == src.dominant_multiplier[i]
        assert np.array_equal(merged.harmonics[i, 0, 1] != 0, p == 2)  # the row's own orbit


def test_ladder_is_bounded_by_memory():
    assert max_harmonics(2, 1, memory=2**30) > 1000  # a 2-DOF chain: thousands fit in 1 GiB
    top = max_harmonics(500, 3, memory=2**30)
    budget = 0.25 * 2**30
    assert harmonics_memory(top, 500, 3) <= budget < harmonics_memory(top + 1, 500, 3)
    ladder = ladder_for(chain(), memory=2**30)
    assert ladder[: len(LADDER)] == LADDER and ladder[-1] > 75  # H >= 75 is within reach
    assert all(b == int(np.ceil(1.5 * a)) for a, b in zip(ladder[5:-1], ladder[6:], strict=True))
    assert ladder_for(chain(), memory=1e5)[-1] < LADDER[-1]  # little memory: fewer rungs


@pytest.fixture(scope="module")
def default_chain():
    """The chain with defaults over 51 frequencies, 1.30-1.70 rad/s, up: the period-1 sweep,
    and ``beyond_period_one``'s answer and period-2 sweep (~2.5 min)."""
    omegas = np.linspace(1.30, 1.70, 51)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HarmonicsWarning)
        p1 = converged_sweep(chain(), omegas, "up")
    res, p2 = beyond_period_one(p1, "auto", lambda: chain(2), omegas, "up", 2 * next_harmonics(p1.H), 5e-3)
    return p1, res, p2


@pytest.mark.slow  # the default sweep over 51 frequencies (~3 min) and the reference at each
def test_stiff_stop_chain_with_defaults_against_the_reference(default_chain):
    """Acceptance (issue 35): the chain with defaults over 51 frequencies, 1.30-1.70 rad/s,
    up: every verdict settled and the same as the reference's at every point (0
    disagreements); the two NS and the PD located within 1e-3 (bisection on the exact flow:
    within 1e-5); the period-2 branch found by ``period="auto"`` past the PD."""
    model = chain()
    p1, res, p2 = default_chain
    assert p1.converged.all() and p1.verdict_converged.all()
    wrong = [
        float(w)
        for w, z, s in zip(p1.omega, p1.harmonics, p1.stable, strict=True)
        if bool(s) != (reference_max(model, z, float(w)) < 1 + 1e-6)
    ]
    assert wrong == []
    found = locate_bifurcations(model, p1)
    kinds = [k for _, k, _ in found]
    assert kinds == ["Neimark-Sacker", "Neimark-Sacker", "period doubling"], found
    for (_, _, w), ref in zip(found, (*NS, PD), strict=True):
        assert abs(w - ref) < 1e-5
    two = np.nonzero(res.period == 2)[0]
    assert two.size >= 3 and res.omega[two].min() > PD
    for i in two:
        assert bool(res.stable[i]) == (reference_max(chain(2), res.harmonics[i], float(res.omega[i]), 2) < 1)
    kinds = [t.kind for t in transitions(res)]
    assert "period doubling" in kinds and "Neimark-Sacker" in kinds


@pytest.mark.slow  # with the sweep above; the bisection and one bounded fold search (~1 min)
def test_period_two_branch_with_defaults(default_chain):
    """Acceptance (issue 35), the period-2 branch: locate_bifurcations on the period-2 rows of
    ``beyond_period_one`` (the base ω/2 model, ``nu`` = 2) finds where its stable part ends,
    the second period doubling :data:`PD2`, within 1e-5 rad/s (bisection to rtol = 1e-6
    relative, a 1.7e-6 rad/s bracket; the reference to 1e-9; the issue asks 1e-3), and
    nothing else: no fold (the reference has none on this branch), the verdicts of its rows
    the reference's (stable at 1.620-1.668, flip-unstable at 1.676-1.700 rad/s)."""
    _, _, p2 = default_chain
    settled = p2.converged & p2.verdict_converged
    for i in np.nonzero(settled)[0]:
        w = float(p2.omega[i])
        assert bool(p2.stable[i]) == (reference_max(chain(2), p2.harmonics[i], w, 2) < 1 + 1e-6), w
    assert p2.stable[settled & (p2.omega < PD2)].all() and not p2.stable[settled & (p2.omega > PD2)].any()
    found = locate_bifurcations(chain(2), p2, nu=2)
    print(found, PD2)
    assert [k for _, k, _ in found] == ["period doubling"], found
    assert abs(found[0][2] - PD2) < 1e-5


def test_result_default_verdict_is_converged():
    res = _sweep([0.5, 1.5], [0.5, 1.5], 1.0)
    assert isinstance(res, SweepResult) and res.verdict_converged.all()
    assert list(res.select("up").verdict_converged) == [True, True]
