"""Pseudo-arc-length continuation of harmonic-balance solutions in the mesh frequency.

Follows the solution curve {(z, ω): R(z, ω) = 0} through turning points (folds), so
the unstable middle branch between the two stable branches of a jump is traced too
(the stepper: :mod:`nlgrd.nonlinear.tracing.arclength`). Every point carries Floquet stability;
turning points are where dω/ds changes sign, located by a parabola through the three
points around the extremum of ω(s).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.results.sweep_results import ContinuationResult, assemble_result
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.tracing.arclength import CurvePoint, Tracer
from nlgrd.threads import single_blas_thread


def _turning(omega: NDArray, s: NDArray, tangents_w: NDArray) -> tuple[NDArray, NDArray]:
    """Indices where dω/ds changes sign and the parabolic estimate of ω at the extremum."""
    sign = np.sign(tangents_w)
    idx = np.nonzero(sign[:-1] * sign[1:] < 0)[0]
    omegas = []
    for i in idx:
        seg = slice(max(i - 1, 0), min(i + 2, omega.size - 1) + 1)
        ss, ww = s[seg], omega[seg]
        est = float(omega[i] if abs(tangents_w[i]) < abs(tangents_w[i + 1]) else omega[i + 1])
        if ss.size >= 3:
            c = np.polyfit(ss - ss[0], ww, 2)
            if c[0] != 0:
                s_star = -c[1] / (2 * c[0])
                if 0 <= s_star <= ss[-1] - ss[0]:
                    est = float(np.polyval(c, s_star))
        omegas.append(est)
    return idx, np.asarray(omegas)


#: The steps of a continuation's progress over its range (:func:`continuation`).
PROGRESS_STEPS = 1000


@single_blas_thread
def continuation(
    model: ReducedModel,
    omega_start: float,
    omega_end: float,
    H: int = 5,
    z0: ArrayLike | None = None,
    *,
    ds: float = 0.01,
    ds_min: float = 1e-7,
    ds_max: float = 0.02,
    max_steps: int = 2000,
    tol: float = 1e-9,
    stability: bool = True,
    n_samples: int = 2048,
    progress=None,
) -> ContinuationResult:
    """Trace the harmonic-balance solution curve from ``omega_start`` towards ``omega_end``.

    Parameters
    ----------
    model : ReducedModel
        The harmonic-balance model as a function of the mesh frequency.
    omega_start, omega_end : float
        Frequency range [rad/s]; the curve starts at ``omega_start`` (solved by Newton
        from ``z0`` or the linear response) and stops when ω leaves the range.
    H : int
        Harmonics.
    z0 : array_like, optional
        Start of Newton at ``omega_start``: real harmonics [x0, a1, b1, ...] of the
        nonlinear coordinates, shape (n_nl, 2H+1) or flat [m]; default the full-contact
        linear response.
    ds, ds_min, ds_max : float
        Initial, minimum and maximum scaled arc-length step [-].
    max_steps : int
        Limit of continuation steps.
    tol : float
        Scaled residual tolerance of the corrector.
    stability : bool
        Floquet multipliers per point (needs ``model.state_space``).
    n_samples : int
        Samples per period for the force extremes of the metrics.
    progress : callable, optional
        ``progress(done, PROGRESS_STEPS)`` after each point traced, ``done`` the share of
        the range reached so far (in 1/PROGRESS_STEPS); then ``progress(k, n)`` after the
        stability and outputs of each of the n points.

    Returns
    -------
    ContinuationResult
        The curve (one row per point, ``direction`` "curve"), its arc length and turning
        points; ``complete`` tells whether it left the range past ``omega_end``.

    Raises
    ------
    RuntimeError
        No converged starting solution at ``omega_start``.
    """
    first = solve(model.at(omega_start, H), z0)
    if not first.converged:
        raise RuntimeError(f"no converged starting solution at omega = {omega_start}: {first.message}")
    lo, hi = sorted((omega_start, omega_end))
    span = hi - lo
    tracer = Tracer(model, H, first.harmonics, omega_start, tol)
    direction = 1 if omega_end >= omega_start else -1
    pts: list[CurvePoint] = []
    complete = False
    reached = 0
    for p in tracer.trace(first.harmonics, omega_start, direction, ds, ds_min, ds_max, max_steps):
        pts.append(p)
        if progress is not None and span > 0:
            share = (p.omega - omega_start) * direction / span
            reached = max(reached, min(PROGRESS_STEPS, int(PROGRESS_STEPS * share)))
            progress(reached, PROGRESS_STEPS)
        if len(pts) > 1 and not (lo - 1e-9 * span <= p.omega <= hi + 1e-9 * span):
            # left the range: complete only past omega_end (not back out at the start)
            complete = (p.omega - omega_start) * direction > 0
            break
    n = model.at(omega_start, H).n_coords
    zs = [p.z.reshape(n, -1) for p in pts]
    ws = np.array([p.omega for p in pts])
    fm, mets = [], []
    for z, w in zip(zs, ws, strict=False):
        f = np.nan
        if stability and model.linear_state_space(w) is not None:
            f = float(
                np.max(np.abs(floquet_multipliers(model.linear_state_space(w), model.nonlinearities, z, w)))
            )
        fm.append(f)
        mets.append(model.metrics.of(z, w, n_samples))
        if progress is not None:
            progress(len(mets), len(zs))
    curve = assemble_result(
        ws,
        ["curve"] * len(pts),
        zs,
        [p.residual <= tol for p in pts],
        [p.residual for p in pts],
        [p.iterations for p in pts],
        fm,
        mets,
        f"pseudo-arc-length continuation (H={H})",
    )
    U = np.array([np.append(p.z / tracer.Lz, p.omega / tracer.Lw) for p in pts])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(U, axis=0), axis=1))])
    tw = np.array([p.tangent[-1] for p in pts])
    idx, tom = _turning(ws, s, tw)
    return ContinuationResult(curve, s, idx, tom, complete)


#: Curve points tried before a turning point by :func:`refine_turning_points`: 1, 2, 4, ...
#: 2**(BACK_STEPS - 1) back, then the first after the previous turning point (the truncation
#: moves a fold; the exact branch may end before it).
BACK_STEPS = 6


def refine_turning_points(
    model: ReducedModel, result: ContinuationResult, *, rtol: float = 1e-9
) -> tuple[NDArray, NDArray]:
    """The turning points of a continuation, on the exact flow where it is known.

    A turning point of the harmonic-balance curve is a fold of the truncated problem, off
    the exact one by the truncation. On a :func:`~nlgrd.nonlinear.stability.shooting.shootable`
    model each is located again on the exact flow
    (:func:`~nlgrd.nonlinear.stability.verdicts.locate_fold`: from a curve point before it
    towards as far past it again, at least 1 % of ω), a fold whose multiplier reaches +1;
    the points 1, 2, 4, ... before it and the first after the previous turning point are
    tried in turn, since the truncated fold may lie
    beyond the exact one, where the exact branch has no orbit (6e-3 rad/s on the preloaded
    stiff-stop chain at H = 13).
    A turning point the exact branch does not have (a grazing corner: the branch ends
    with every multiplier off +1) or a model without an exact flow keeps the curve's
    parabolic estimate.

    Parameters
    ----------
    model : ReducedModel
        The model of the continuation.
    result : ContinuationResult
        From :func:`continuation`.
    rtol : float
        Relative tolerance of a refined fold frequency [-].

    Returns
    -------
    omegas : ndarray
        The turning points' frequencies [rad/s], in curve order.
    exact : ndarray of bool
        Which were located on the exact flow (a multiplier at +1).
    """
    from nlgrd.nonlinear.stability.verdicts import locate_fold

    w = result.omega
    out = np.array(result.turning_omegas, dtype=float)
    exact = np.zeros(out.size, dtype=bool)
    starts = [0, *(int(t) + 1 for t in result.turning_indices)]
    for k, (i, w_turn) in enumerate(zip(result.turning_indices, result.turning_omegas, strict=True)):
        # the exact fold may come before the curve's: points 1, 2, 4, ... back, then the
        # first point after the previous turning point
        tries = [int(i) - 2**b for b in range(BACK_STEPS) if int(i) - 2**b > starts[k]] + [starts[k]]
        for on in tries:
            ahead = w_turn - w[on]
            margin = np.sign(ahead) * max(abs(ahead), 0.01 * abs(w_turn))
            z = result.curve.harmonics[on]
            found = locate_fold(model, z, float(w[on]), float(w_turn + margin), rtol=rtol)
            if found is not None:
                out[k], exact[k] = found, True
                break
    return out, exact
