"""A branch of periodic orbits followed on the exact piecewise-linear flow, and its folds.

Pseudo-arc-length continuation (Keller 1977; Seydel 2010, Practical Bifurcation and
Stability Analysis, §4.5) of the period map r(s, ω) = φ_T(s; ω) - s = 0 in (s, ω), s the
state at θ = 0: the Jacobian is [Φ - I, ∂r/∂ω], Φ the exact monodromy
(:mod:`nlgrd.nonlinear.stability.shooting`), ∂r/∂ω by a central difference (the flow is
smooth in ω away from grazing). Each point is corrected on the hyperplane normal to the
last tangent, so the curve is followed through its turning points, and a step is taken
only when the corrected point stays within :data:`HOP_RTOL` of the step of its predictor:
where several orbits of like shape coexist (near a grazing), a march in ω alone hops
between them.

A fold (turning point in ω) is where the tangent's ω component changes sign; it is
located by regula falsi on that component along the arc length, ω there from the
quadratic ω(σ) through the bracket, and accepted only where a multiplier is at +1
(within :data:`FOLD_MU_ATOL`): Φ - I is singular at a smooth fold (Kuznetsov 2004,
Elements of Applied Bifurcation Theory, §10.2).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.stability.shooting import model_flow

if TYPE_CHECKING:  # pragma: no cover
    from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel

#: First arc-length step and its ceiling (of the scaled (s, ω): relative to the orbit's size).
FIRST_STEP, MAX_STEP = 0.01, 0.05
#: Steps below this give up (the branch is lost, e.g. at a grazing Newton cannot pass).
MIN_STEP = 1e-7
#: A corrected point farther than this fraction of the step from its predictor is another orbit.
HOP_RTOL = 0.2
#: Newton's tolerance on the relative period-map residual, and its iterations per step.
TOL, CORRECTOR_ITER = 1e-11, 8
#: A located turning point is a fold when a multiplier is within this of +1.
FOLD_MU_ATOL = 1e-3
#: Relative step of the central difference ∂r/∂ω.
D_OMEGA = 1e-6


class _Branch:
    """The period map of a model in scaled variables v = (s / σ_s, ω / ω₀)."""

    def __init__(self, model: ReducedModel, state: NDArray, omega: float):
        self.model, self.w0 = model, float(omega)
        n = state.size // 2
        vel = np.concatenate([np.ones(n), np.full(n, 1 / omega)])  # velocities / ω
        self.size = max(float(np.max(np.abs(state * vel))), 1e-300)
        self.c = np.concatenate([vel / self.size, [1 / self.w0]])  # v = c u

    def unpack(self, v: NDArray) -> tuple[NDArray, float]:
        u = v / self.c
        return u[:-1], float(u[-1])

    def residual(self, v: NDArray) -> tuple[NDArray, NDArray, float]:
        """(r, Φ, relative residual) at v."""
        s, w = self.unpack(v)
        end, Phi, _ = model_flow(self.model, w).period(s)
        r = end - s
        return r, Phi, float(np.max(np.abs(r * self.c[:-1])))

    def jacobian(self, v: NDArray, Phi: NDArray) -> NDArray:
        """[Φ - I, ∂r/∂ω] in the scaled variables (2N x 2N+1)."""
        s, w = self.unpack(v)
        rp = model_flow(self.model, w * (1 + D_OMEGA)).period(s)[0]
        rm = model_flow(self.model, w * (1 - D_OMEGA)).period(s)[0]
        dr = (rp - rm) / (2 * D_OMEGA * w)
        return np.column_stack([Phi - np.eye(s.size), dr]) / self.c

    @staticmethod
    def tangent(J: NDArray, prev: NDArray | None) -> NDArray:
        t = np.linalg.svd(J)[2][-1]
        return -t if prev is not None and t @ prev < 0 else t

    def correct(self, v_pred: NDArray, t: NDArray, J: NDArray):
        """Newton on (r = 0, t·(v - v_pred) = 0) with the chord ∂r/∂ω of J; (v, Φ) or None."""
        v = v_pred.copy()
        for _ in range(CORRECTOR_ITER):
            r, Phi, err = self.residual(v)
            if not np.all(np.isfinite(r)):
                return None
            if err <= TOL:
                return v, Phi
            A = np.vstack([np.column_stack([(Phi - np.eye(r.size)) / self.c[:-1], J[:, -1]]), t])
            try:
                v = v - np.linalg.solve(A, np.concatenate([r, [t @ (v - v_pred)]]))
            except np.linalg.LinAlgError:
                return None
        return None


def _point(branch, v, Phi, prev_t):
    """(v, Φ, J, tangent) at a corrected point, or None where the flow beside it is stuck
    (:data:`~nlgrd.nonlinear.stability.shooting.STILL_EVENTS`: a NaN ∂r/∂ω)."""
    J = branch.jacobian(v, Phi)
    if not np.all(np.isfinite(J)):
        return None
    return v, Phi, J, branch.tangent(J, prev_t)


def fold_on_branch(
    model: ReducedModel,
    state: NDArray,
    omega_on: float,
    omega_off: float,
    *,
    rtol: float = 1e-9,
    max_steps: int = 80,
) -> float | None:
    """The first fold of the branch through an exact orbit, followed from ``omega_on``
    towards ``omega_off`` by pseudo-arc-length continuation (module docstring).

    Parameters
    ----------
    model : ReducedModel
        A :func:`~nlgrd.nonlinear.stability.shooting.shootable` model.
    state : ndarray (2N,)
        (q, q') at θ = 0 of an exact periodic orbit at ``omega_on`` [m, m/s].
    omega_on : float
        Its base frequency [rad/s].
    omega_off : float
        The branch is followed towards this frequency and no further [rad/s].
    rtol : float
        Relative tolerance of the fold frequency [-].
    max_steps : int
        Continuation steps at most.

    Returns
    -------
    float or None
        The fold's base frequency [rad/s]; None when the branch reaches ``omega_off``, is
        lost (steps below :data:`MIN_STEP`) or turns without a multiplier at +1.
    """
    if omega_off == omega_on:
        raise ModelError("omega_off", "must differ from omega_on")
    sign = 1.0 if omega_off > omega_on else -1.0
    br = _Branch(model, np.asarray(state, dtype=float), omega_on)
    v0 = np.concatenate([np.asarray(state, dtype=float), [omega_on]]) * br.c
    r, Phi, err = br.residual(v0)
    if not err <= 1e3 * TOL:
        return None
    first = _point(br, v0, Phi, None)
    if first is None:
        return None
    v, Phi, J, t = first
    if t[-1] * sign < 0:
        t = -t
    h = FIRST_STEP
    for _ in range(max_steps):
        if h < MIN_STEP:
            return None
        got = br.correct(v + h * t, t, J)
        hop = got is None or np.linalg.norm(got[0] - (v + h * t)) > HOP_RTOL * h
        point = None if hop else _point(br, got[0], got[1], t)
        if point is None:
            h *= 0.5
            continue
        vn, Phin, Jn, tn = point
        if tn @ t < 0.5:  # the tangent turned too far for one step: smaller steps
            h *= 0.5
            continue
        wn = br.unpack(vn)[1]
        if tn[-1] * sign <= 0:  # the branch turned between v and vn
            return _locate(br, (v, J, t), (vn, tn), rtol)
        if sign * (wn - omega_off) >= 0:
            return None  # the branch goes on
        v, J, t = vn, Jn, tn
        h = min(1.5 * h, MAX_STEP)
    return None


def _locate(br: _Branch, start, end, rtol: float) -> float | None:
    """The turning point between ``start`` (v, J, t) and ``end`` (v, t): regula falsi
    (Illinois) on d = dv_ω/dσ, σ the distance along the start's tangent (the hyperplanes
    of the corrector), which is linear in σ near a smooth fold; ω there from the quadratic
    ω(σ) through the bracket's ends."""
    v0, J0, t0 = start
    lo, hi = 0.0, float(t0 @ (end[0] - v0))
    d_lo, d_hi = t0[-1], end[1][-1] / (end[1] @ t0)
    w_lo, w_hi = br.unpack(v0)[1], br.unpack(end[0])[1]
    f_lo, f_hi, side = d_lo, d_hi, 0  # the falsi's (Illinois-halved) values

    def estimate():
        b = (d_hi - d_lo) / (hi - lo)
        return b, (w_lo - br.w0 * d_lo**2 / (2 * b), w_hi - br.w0 * d_hi**2 / (2 * b))

    for _ in range(60):
        b, ests = estimate()
        if abs(ests[0] - ests[1]) <= rtol * abs(ests[0]) or hi - lo < 1e-13:
            break
        mid = lo - f_lo * (hi - lo) / (f_hi - f_lo)
        if not lo < mid < hi:
            mid = 0.5 * (lo + hi)
        got = br.correct(v0 + mid * t0, t0, J0)
        J = None if got is None else br.jacobian(got[0], got[1])
        if J is None or not np.all(np.isfinite(J)):
            return None
        t = br.tangent(J, t0)
        d, w = t[-1] / (t @ t0), br.unpack(got[0])[1]
        if d * d_lo > 0:
            lo, d_lo, f_lo, w_lo = mid, d, d, w
            f_hi = 0.5 * f_hi if side == -1 else f_hi
            side = -1
        else:
            hi, d_hi, f_hi, w_hi = mid, d, d, w
            f_lo = 0.5 * f_lo if side == 1 else f_lo
            side = 1
    # a fold when a multiplier is at +1 at the corrected point of the turning point
    got = br.correct(v0 + float(np.clip(lo - d_lo / b, lo, hi)) * t0, t0, J0)
    if got is None:
        return None
    mu = np.linalg.eigvals(got[1])
    return 0.5 * (ests[0] + ests[1]) if np.min(np.abs(mu - 1)) <= FOLD_MU_ATOL else None
