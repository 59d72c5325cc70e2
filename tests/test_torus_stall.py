"""A failed torus try made cheap without changing a torus that converges (issue 35 item 2,
issue 34 item 4): the stall stop of :func:`nlgrd.nonlinear.hb.quasi_periodic.solve_torus`
and κ(Ω) with its Ω-derivative from one factorisation per frequency
(:func:`nlgrd.nonlinear.tracing.torus_outputs.kappa_and_slope`), on the link torus of the
one-mesh models (:class:`nlgrd.nonlinear.tracing.link_torus.LinkTorus`).

References: Kahraman & Blankenship's rig at 3620 Hz (data/case_studies/
kahraman_blankenship.toml), a Neimark-Sacker point of its fast report where the motion is
chaotic (docs/verification.md, "Time-domain answers") and no torus converges; Kubo's rig at
13 750 rpm, whose torus tests/test_quasi_periodic.py checks against the HHT-α integration of
the full FE model. The derivative is checked against central differences of κ itself.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.hb import quasi_periodic as qp
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.nonlinear.tracing import torus_sweep as ts
from nlgrd.nonlinear.tracing.link_torus import LinkTorus

ROOT = Path(__file__).resolve().parent.parent


def _recording(monkeypatch):
    """Every solve_torus call of a torus sweep: (args, kwargs, solution)."""
    calls, original = [], qp.solve_torus

    def record(*args, **kwargs):
        sol = original(*args, **kwargs)
        calls.append((args, kwargs, sol))
        return sol

    monkeypatch.setattr(qp, "solve_torus", record)
    return calls, original


def _counting(target):
    """Count the frequencies at which the target's torus model factorises Z."""
    tm, count = target.torus_model, {"freqs": 0}
    plain, slope = tm.kappa_at, getattr(tm, "kappa_slope_at", None)

    def kappa_at(freqs, omega):
        count["freqs"] += len(freqs)
        return plain(freqs, omega)

    def kappa_slope_at(freqs, omega):
        count["freqs"] += len(freqs)
        return slope(freqs, omega)

    tm.kappa_at, tm.kappa_slope_at = kappa_at, None if slope is None else kappa_slope_at
    return count


def test_a_try_without_a_torus_stops_when_newton_stalls(monkeypatch):
    """K&B at 3620 Hz with a sweep's settings (H₁ 13, H₂ 4, 25 iterations, two start
    sizes): no torus converges. Before this change both tries ran all 25 iterations and
    factorised Z at 3 x 108 frequencies per iteration (κ and its central differences):
    16 227 LUs with the critical mode's 27 (measured on the old code, which fails here at
    ``iterations < 25``). Now each stops when its residual stalls (measured: after 11 and
    16 iterations, at relative residual 0.93 and 0.98, far above any converging try's,
    <= 0.1) and factorises Z once per frequency and iteration: 2 943 LUs."""
    system = load_model(ROOT / "data" / "case_studies" / "kahraman_blankenship.toml")
    w = 2 * np.pi * 3620.3
    target = LinkTorus(build_link_model(system))
    count = _counting(target)
    calls, _ = _recording(monkeypatch)
    res = ts.torus_sweep(
        target.model,
        [w],
        H=13,
        check=False,
        tol=ts.ANSWER_TOL,
        max_iter=ts.ANSWER_MAX_ITER,
        start_sizes=ts.ANSWER_START_SIZES,
        target=target,
    )
    assert not res.converged[0] and abs(res.multiplier[0]) > 1  # unstable orbit, no torus
    sols = [c[2] for c in calls]
    assert len(sols) == len(ts.ANSWER_START_SIZES)
    for sol in sols:
        assert not sol.converged
        assert sol.iterations < ts.ANSWER_MAX_ITER
        assert sol.stalled
        assert sol.residual > 10 * qp.STALL_FLOOR  # stopped far from any torus
    per_iteration = 27 * 4  # the (k₁, k₂ >= 1) combination frequencies at (13, 4)
    critical = 27  # the critical mode's κ at k₁ ω₁ + ω₂
    assert count["freqs"] == per_iteration * sum(s.iterations for s in sols) + critical


@pytest.fixture(scope="module")
def kubo():
    """Kubo's model and the torus solve at 13 750 rpm started from its critical mode."""
    system = load_model(ROOT / "data" / "case_studies" / "kubo.toml")
    model = build_link_model(system)
    target = LinkTorus(model)
    with pytest.MonkeyPatch.context() as mp:
        calls, original = _recording(mp)
        res = ts.torus_sweep(model, rpm=[13750.0], H=13, check=False, target=target)
    assert res.converged[0]
    return target, calls[-1], original


def test_the_stall_stop_leaves_a_converging_solve_as_it_was(kubo):
    """The Kubo torus solved again with the stall stop off: the same iterates, bit for bit
    (the stop only ends a solve, never changes a step), so every torus found before is
    found with the same numbers."""
    _, (args, kwargs, sol), original = kubo
    free = original(*args, **{**kwargs, "stall": False})
    assert not sol.stalled and free.converged
    assert free.iterations == sol.iterations
    assert np.array_equal(free.Y, sol.Y) and free.secondary == sol.secondary


def test_the_derivative_of_kappa_gives_the_torus_of_central_differences(kubo):
    """The same solve with dR/dω₂ by central differences of κ (the former Jacobian, step
    1e-6 ω₂): the same torus to the solve's tolerance. Both stop at a relative residual
    below 1e-8 (measured 1.2e-9, 7 iterations each), so their harmonics may differ by
    ~1e-8 of the largest; measured 9e-16 (ω₂ 1e-15): Newton's last step squares the error,
    and the ω₂ column of its Jacobian changes only at the differences' error (~1e-10)."""
    target, (args, kwargs, sol), original = kubo
    tm = target.torus_model
    fd_model = qp.TorusModel(tm.kappa_at, tm.periodic_kappa, tm.periodic_force, tm.nonlinearities)
    fd = original(fd_model, *args[1:], **kwargs)
    assert fd.converged
    scale = np.abs(sol.Y).max()
    assert np.abs(fd.Y - sol.Y).max() <= 1e-8 * scale, np.abs(fd.Y - sol.Y).max() / scale
    assert abs(fd.secondary / sol.secondary - 1) <= 1e-8


def test_the_derivative_of_kappa_against_central_differences(kubo):
    """dκ/dΩ of one factorisation against central differences of κ at steps h = 1e-3 and
    1e-5 of Ω: their error falls as h² (measured 1.0e-5 and 1.0e-9 of the largest entry,
    a ratio of 1e4), so the bound 1e-6 at 1e-5 has a margin of 1e3 and the ratio bound 1e3
    tells the formula from rounding; κ itself is the same numbers as ``kappa_at`` gives."""
    target, _, _ = kubo
    tm = target.torus_model
    w = target.omegas(np.array([13750.0]))[0]
    freqs = np.array([-3.3, -0.7, 0.4, 1.3, 5.2]) * w
    kap, slope = tm.kappa_slope_at(freqs, w)
    assert np.array_equal(kap, tm.kappa_at(freqs, w))
    errors = []
    for h in (1e-3, 1e-5):
        step = h * np.abs(freqs)[:, None, None]
        fd = (tm.kappa_at(freqs + step[:, 0, 0], w) - tm.kappa_at(freqs - step[:, 0, 0], w)) / (2 * step)
        errors.append(float(np.max(np.abs(fd - slope) / np.abs(slope).max(axis=(1, 2), keepdims=True))))
    assert errors[1] < 1e-6, errors
    assert errors[0] / errors[1] > 1e3, errors  # second order: the formula, not rounding
