"""Stability verdicts reported only when converged (issue 35 item 1).

The Floquet multipliers of a harmonic-balance orbit take the contact times from its
truncated Fourier series. With a stiff contact these are off by far more than the orbit's
amplitudes: on the two-DOF chain with a stop of 100 x its stiffness the orbit at H = 17 is
within a few per cent, but its largest multiplier is -2.24 where the exact orbit is stable
with |μ| = 0.86. The error estimate of the outputs (:mod:`nlgrd.nonlinear.tracing.harmonic_convergence`)
does not see this, so each verdict is checked on its own (:func:`converge_verdicts`):

1. Every point with multipliers is also evaluated at H', the harmonics its error was
   estimated against (the check's re-solved orbit): the verdict (stable or not) and the
   largest modulus max |μ| must agree to :data:`MULTIPLIER_RTOL`.
2. Where the model's exact flow is known (:func:`nlgrd.nonlinear.stability.shooting.shootable`:
   piecewise-linear laws of constant stiffness and the static force given), a point whose
   verdict is doubtful (max |μ| within a factor :data:`DOUBT_BAND` of 1, or step 1 did not
   agree) is polished by shooting (:func:`~nlgrd.nonlinear.stability.shooting.polish`); when the exact
   orbit is the harmonic-balance orbit (the nonlinear coordinates within
   :data:`ORBIT_RTOL` of their range over the period) its multipliers, from the exact
   monodromy, are the verdict (exact up to the contact times' 1e-13 T; Leine & Nijmeijer
   2004, Dynamics and Bifurcations of Non-Smooth Mechanical Systems, §3.5 for the monodromy
   of a continuous piecewise-linear flow).
3. Elsewhere (smooth laws, or no exact flow) a point whose verdict disagrees between H and
   H' is solved at the next rungs above H' (up to :data:`EXTRA_RUNGS` of them, within what
   the model was built for) until two successive rungs agree as in step 1; the higher
   rung's multipliers are then the verdict.

A point whose verdict did not converge keeps its orbit but has ``verdict_converged``
False: the ``verdict`` column says "not converged", and neither ``stable`` nor the
response's values are written.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import evaluate
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.results.metrics import METRIC_NAMES
from nlgrd.nonlinear.results.sweep_results import STABLE_RTOL, SweepResult, dominant_multiplier
from nlgrd.nonlinear.stability.exact_branch import fold_on_branch
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.stability.shooting import orbit_harmonics, polish, shootable

#: A verdict whose largest multiplier modulus lies within this factor of 1 is polished by
#: shooting where the exact flow is known (the H = 17 chain: -2.24 where exact 0.86).
DOUBT_BAND = 10.0
#: Two harmonic counts agree on a verdict when their max |μ| differ by at most this
#: fraction (and both are on the same side of 1 + STABLE_RTOL).
MULTIPLIER_RTOL = 1e-2
#: A shot orbit is the harmonic-balance orbit when its nonlinear coordinates differ from the
#: orbit's by at most this fraction of their peak-to-peak range over the period.
ORBIT_RTOL = 0.05
#: Rungs above H' tried for a verdict that disagrees (no exact flow).
EXTRA_RUNGS = 3


def _floquet(model: ReducedModel, z: NDArray, w: float) -> tuple[float, complex]:
    ss = model.linear_state_space(w)
    return dominant_multiplier(floquet_multipliers(ss, model.nonlinearities, z, w))


def agree(a: float, b: float) -> bool:
    """Whether two largest multiplier moduli give the same converged verdict.

    Parameters
    ----------
    a, b : float
        max |μ| at two harmonic counts [-].

    Returns
    -------
    bool
        The same side of 1 + STABLE_RTOL and within :data:`MULTIPLIER_RTOL` of each other.
    """
    same = (a < 1 + STABLE_RTOL) == (b < 1 + STABLE_RTOL)
    return bool(same and abs(a - b) <= MULTIPLIER_RTOL * max(abs(a), abs(b)))


def same_orbit(shot: NDArray, harmonics: NDArray) -> bool:
    """Whether a shot orbit's harmonics are those of the harmonic-balance orbit.

    Parameters
    ----------
    shot, harmonics : ndarray (n_nl, 2H+1)
        Real harmonics of the nonlinear coordinates of the two orbits [m].

    Returns
    -------
    bool
        max |y_shot - y_HB| <= :data:`ORBIT_RTOL` x the peak-to-peak of y_shot, per coordinate.
    """
    theta = np.linspace(0, 2 * np.pi, 512, endpoint=False)
    a = np.array([evaluate(row, theta) for row in np.atleast_2d(shot)])
    b = np.array([evaluate(row, theta) for row in np.atleast_2d(harmonics)])
    span = np.ptp(a, axis=-1) + 1e-300
    return bool(np.all(np.max(np.abs(a - b), axis=-1) <= ORBIT_RTOL * span))


def _pad(z: NDArray, H: int) -> NDArray:
    z = np.atleast_2d(z)
    out = np.zeros((z.shape[0], 2 * H + 1))
    m = min(z.shape[1], out.shape[1])
    out[:, :m] = z[:, :m]
    return out


def _escalate(model, w, z_check, mu_check, rungs, tol):
    """max |μ| and dominant μ from the first two successive rungs above H' that agree, or None."""
    zc, prev = z_check, mu_check
    for H in rungs[:EXTRA_RUNGS]:
        try:
            sol = solve(model.at(w, H), _pad(zc, H), method="newton", tol=tol, fallback=False)
        except ModelError:  # beyond what the model was built for
            return None
        if not sol.converged:
            return None
        zc = sol.harmonics
        cur = _floquet(model, zc, w)
        if agree(prev[0], cur[0]):
            return cur
        prev = cur
    return None


def converge_verdicts(
    model: ReducedModel,
    result: SweepResult,
    solutions: dict,
    *,
    ladder: Sequence[int] = (),
    tol: float = 1e-10,
    polished: dict | None = None,
    progress=None,
) -> SweepResult:
    """``result`` with every verdict checked (module docstring) and ``verdict_converged`` set.

    Parameters
    ----------
    model : ReducedModel
        The model the result was solved on (its base frequency is ``result.omega``).
    result : SweepResult
        A sweep with stability.
    solutions : dict
        {row: HarmonicSolution at H' or None}: the check's re-solved points
        (:attr:`~nlgrd.nonlinear.tracing.harmonic_convergence.HarmonicCheck.solutions`).
    ladder : sequence of int
        Harmonic counts (of the model's base) for step 3: those above H' are tried.
    tol : float
        Newton's tolerance at the higher rungs (relative residual).
    polished : dict, optional
        {ω: [(harmonics of an exact orbit, max |μ|, dominant μ)]}, filled and reused: the
        exact orbit does not depend on H, so a sweep's rungs shoot each orbit once.
    progress : callable, optional
        ``progress(done, total)`` after each point whose verdict was checked.

    Returns
    -------
    SweepResult
        ``floquet_max``, ``dominant_multiplier``, ``stable`` and ``no_stable`` of the
        converged verdicts; ``verdict_converged`` False where none converged.
    """
    n = len(result)
    fmax = np.array(result.floquet_max, dtype=float)
    dom = np.array(result.dominant_multiplier, dtype=complex)
    ok = np.ones(n, dtype=bool)
    known = result.converged & result.stability_known
    exact = shootable(model)
    rows = np.nonzero(known)[0]
    for done, i in enumerate(rows):
        if progress is not None:  # before each point: its verdict may end early (continue)
            progress(done, rows.size)
        w, z = float(result.omega[i]), result.harmonics[i]
        sol = solutions.get(i)
        fine = None if sol is None else _floquet(model, sol.harmonics, w)
        agreed = fine is not None and agree(fmax[i], fine[0])
        doubtful = not agreed or 1 / DOUBT_BAND < fmax[i] < DOUBT_BAND
        if exact and doubtful:
            found = _exact(model, z, w, {} if polished is None else polished)
            if found is None:
                ok[i] = False
            else:
                fmax[i], dom[i] = found
            continue
        if agreed:
            fmax[i], dom[i] = fine
            continue
        rungs = [h for h in ladder if sol is not None and h > _H(sol)]
        top = None if fine is None else _escalate(model, w, sol.harmonics, fine, rungs, tol)
        if top is None:
            ok[i] = False
        else:
            fmax[i], dom[i] = top
    if progress is not None and rows.size:
        progress(rows.size, rows.size)
    with np.errstate(invalid="ignore"):
        stable = result.converged & np.isfinite(fmax) & (fmax < 1 + STABLE_RTOL)
    changed = known & ok & (stable != result.stable)  # the sweep's verdict was wrong
    no_stable = np.where(changed, ~stable, result.no_stable)
    out = replace(result, floquet_max=fmax, dominant_multiplier=dom, stable=stable & ok, verdict_converged=ok)
    return _refresh_metrics(model, out, no_stable)


#: Harmonics kept of a shot orbit for the comparison with later rungs' orbits.
KEPT_HARMONICS = 64


def _exact(model, z, w, polished) -> tuple[float, complex] | None:
    """(max |μ|, dominant μ) of the exact orbit that is the HB orbit ``z``, or None."""
    for y, fm, mu in polished.get(w, ()):
        if same_orbit(y, z):
            return fm, mu
    orbit = polish(model, z, w)
    if orbit is None:
        return None
    y = orbit_harmonics(model, orbit, w, KEPT_HARMONICS)
    if not same_orbit(y, z):
        return None
    fm, mu = dominant_multiplier(orbit.multipliers)
    polished.setdefault(w, []).append((y, fm, mu))
    return fm, mu


def _H(sol) -> int:
    return (np.asarray(sol.harmonics).shape[-1] - 1) // 2


def _refresh_metrics(model: ReducedModel, result: SweepResult, no_stable: NDArray) -> SweepResult:
    """Metrics of the points that became a stable response (the sweep left them NaN)."""
    gained = np.nonzero(result.no_stable & ~no_stable & result.converged)[0]
    metrics = {k: np.array(v, copy=True) for k, v in result.metrics.items()}
    amps = np.array(result.amplitudes, dtype=float, copy=True)
    for i in gained:
        met = model.metrics.of(result.harmonics[i], float(result.omega[i]))
        for name, value in zip(METRIC_NAMES, met.as_tuple(), strict=True):
            metrics[name][i] = value
        amps[i] = np.resize(met.dte_amplitudes, amps.shape[1])
    return replace(result, no_stable=no_stable, metrics=metrics, amplitudes=amps)


def locate_bifurcations(
    model: ReducedModel, result: SweepResult, *, rtol: float = 1e-6, folds: bool = True, nu: int = 1
) -> list[tuple]:
    """The bifurcations of a sweep on a :func:`~nlgrd.nonlinear.stability.shooting.shootable`
    model, located on the exact flow.

    Where the converged verdict changes between two consecutive points, the frequency at
    which max |μ| of the exact orbit crosses 1 + STABLE_RTOL, by bisection (each orbit shot
    from the harmonic-balance orbit of the stable side's point; none where that branch is
    still stable at the unstable point, which lies on another branch). Folds (:func:`locate_fold`):
    from every row where the sweep jumps
    (:meth:`~nlgrd.nonlinear.results.sweep_results.SweepResult.jumps`) or its branch ends
    (a row with a converged verdict: its orbit is an exact one),
    and from the first unstable row where a branch turns unstable, the branch is followed
    on the exact flow, stable or not, to :data:`FOLD_REACH` past the sweep's end and for
    at most :data:`FOLD_STEPS` arc-length steps (the bound on the cost of each); where it
    ends, the fold that ends it (a multiplier +1 no verdict change shows; a stable-seeking
    sweep leaves an unstable branch before its fold).

    Parameters
    ----------
    model : ReducedModel
        The model of the sweep (its base frequency is ``result.omega``).
    result : SweepResult
        A sweep with converged verdicts (:func:`converge_verdicts`).
    rtol : float
        Relative width of the final bracket [-] (a fold: to ``rtol`` x 1e-3).
    folds : bool
        Also locate the folds (each a few dozen shots: on a sweep with several jumps,
        minutes).
    nu : int
        The model's base is ω/ν (a period-ν model, ``result.omega`` the frequencies ω):
        the bifurcations of a period-ν sweep, reported at ω [-].

    Returns
    -------
    list of (str, str, float)
        (direction, kind, ω [rad/s]) in sweep order per direction: kind "Neimark-Sacker",
        "period doubling" or "fold" (the dominant multiplier on the unstable side), or
        "fold" where a branch ends; empty when the model is not shootable.
    """
    if not shootable(model):
        return []
    if int(nu) != nu or nu < 1:
        raise ModelError("nu", f"must be a positive integer, got {nu!r}")
    if nu > 1:
        found = locate_bifurcations(model, replace(result, omega=result.omega / nu), rtol=rtol, folds=folds)
        return [(d, k, nu * w) for d, k, w in found]
    out = []
    ok = result.converged & result.stability_known & result.verdict_converged
    for d in dict.fromkeys(result.direction.tolist()):
        found, starts = [], []
        sign = 1.0 if d != "down" else -1.0
        idx = np.nonzero((result.direction == d) & ok)[0]
        for i, j in zip(idx[:-1], idx[1:], strict=True):
            if result.stable[i] == result.stable[j]:
                continue
            s, u = (i, j) if result.stable[i] else (j, i)
            mu = complex(result.dominant_multiplier[u])
            kind = (
                "Neimark-Sacker"
                if abs(mu.imag) > 1e-6 * abs(mu)
                else ("period doubling" if mu.real < 0 else "fold")
            )
            w = _bisect(model, result.harmonics[s], float(result.omega[s]), float(result.omega[u]), rtol)
            if w is not None:
                found.append((d, kind, w))
            if u == j:  # the branch turns unstable: the sweep may leave it before its fold
                starts.append(j)
        rows = np.nonzero(result.direction == d)[0]
        end = float(result.omega[rows[-1]]) if rows.size else 0.0
        w_far = end + sign * FOLD_REACH * abs(end)  # each branch followed past the sweep's end
        ends = {i for i, _ in _branch_ends(result, d) if ok[i]}  # an exact orbit to start from
        for i in sorted(ends | set(starts)) if folds else ():
            z, w_on = result.harmonics[i], float(result.omega[i])
            w = locate_fold(model, z, w_on, w_far, rtol=1e-3 * rtol, max_steps=FOLD_STEPS)
            if w is not None and not any(k == "fold" and abs(w - v) <= rtol * abs(v) for _, k, v in found):
                found.append((d, "fold", w))
        out += sorted(found, key=lambda f: sign * f[2])
    return out


def _branch_ends(result: SweepResult, direction: str) -> list[tuple[int, float]]:
    """(row, next frequency) where a sweep direction's branch may end: a jump, or a
    converged point followed by one without an orbit."""
    rows = np.nonzero(result.direction == direction)[0]
    ends = {}
    for jump in result.jumps():
        if jump.direction == direction:
            i = rows[np.argmin(np.abs(result.omega[rows] - jump.omega_from))]
            ends[int(i)] = jump.omega_to
    for i, j in zip(rows[:-1], rows[1:], strict=True):
        if result.converged[i] and not result.converged[j]:
            ends[int(i)] = float(result.omega[j])
    return sorted(ends.items())


def _bisect(model, z, w_stable, w_unstable, rtol):
    """Where max |μ| of the branch through ``z`` crosses 1 + STABLE_RTOL, each orbit shot
    from the last stable one; None when that branch is stable up to ``w_unstable`` (the
    unstable row lies on another branch)."""
    a, b = w_stable, w_unstable
    while abs(b - a) > rtol * abs(a):
        mid = 0.5 * (a + b)
        orbit = polish(model, z, mid)
        if orbit is None:
            return None
        if np.max(np.abs(orbit.multipliers)) < 1 + STABLE_RTOL:  # the next shot from here
            a, z = mid, orbit_harmonics(model, orbit, mid, FOLD_HARMONICS)
        else:
            b = mid
    if b == w_unstable:  # every orbit was stable: is the branch's at w_unstable?
        orbit = polish(model, z, b)
        if orbit is None or np.max(np.abs(orbit.multipliers)) < 1 + STABLE_RTOL:
            return None
    return 0.5 * (a + b)


#: :func:`locate_bifurcations` follows a branch to this fraction of ω past the sweep's end.
FOLD_REACH = 0.01
#: ... and for at most this many arc-length steps (accepted or halved) from each row. The
#: fold it looks for ends the branch the sweep was on, next to the row (within the grid
#: step and the truncation's offset of the harmonic-balance fold, 0.5 % of ω at H = 13 on
#: the preloaded chain of tests/test_folds.py); the steps grow from FIRST_STEP to MAX_STEP
#: of :mod:`~nlgrd.nonlinear.stability.exact_branch` (a fraction of the orbit's size) in 4
#: steps, so 50 steps follow the branch over up to 2.4 times the orbit's size. The folds of the
#: preloaded chain take 7 (period 2, 1.36287 -> 1.35174 rad/s), 11 accepted (the closed stop,
#: 1.382 -> 1.38455) and 37 (the lifted-off branch from its unstable row at 1.30 to its fold
#: at 1.28955, 11 of them halved); a branch without a fold (the gap-free chain's period-2
#: branch from 1.676 rad/s) takes all, each a few period maps: the bound on the cost.
FOLD_STEPS = 50
#: Orbits kept as harmonics between the shots of the bisection (the next shot's start).
FOLD_HARMONICS = 64


def locate_fold(
    model: ReducedModel,
    harmonics: NDArray,
    omega_on: float,
    omega_off: float,
    *,
    rtol: float = 1e-9,
    max_steps: int = 80,
) -> float | None:
    """The fold (turning point) that ends the branch through an orbit, on the exact flow.

    The exact orbit shot from ``harmonics`` is followed from ``omega_on`` towards
    ``omega_off`` by pseudo-arc-length continuation on the exact flow, and the first
    turning point with a multiplier at +1 is the fold
    (:func:`~nlgrd.nonlinear.stability.exact_branch.fold_on_branch`). Each step is
    corrected on the hyperplane normal to the branch's tangent and kept only near its
    predictor, so the march does not hop between coexisting orbits of like shape (near a
    grazing: a march in ω that took each orbit within 5 % of the last one returned
    1.3865769 rad/s for the closed-stop fold of the preloaded chain at 1.3845452317).

    Parameters
    ----------
    model : ReducedModel
        A :func:`~nlgrd.nonlinear.stability.shooting.shootable` model.
    harmonics : ndarray (n_nl, 2H+1)
        A harmonic-balance orbit at ``omega_on`` [m].
    omega_on : float
        Base frequency where the branch exists [rad/s].
    omega_off : float
        Base frequency past the fold [rad/s] (above or below ``omega_on``).
    rtol : float
        Relative tolerance of the fold frequency [-].
    max_steps : int
        Continuation steps at most (accepted or halved).

    Returns
    -------
    float or None
        The fold's base frequency [rad/s]; None when the model is not shootable, no
        exact orbit is found at ``omega_on``, the branch reaches ``omega_off``, ends
        without a multiplier at +1, or has no fold within ``max_steps``.
    """
    if not shootable(model):
        return None
    first = polish(model, harmonics, omega_on)
    if first is None:
        return None
    return fold_on_branch(model, first.state, omega_on, omega_off, rtol=rtol, max_steps=max_steps)
