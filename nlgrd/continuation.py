"""Pseudo-arc-length continuation of harmonic-balance solutions in the mesh frequency.

Follows the solution curve {(z, ω): R(z, ω) = 0} through turning points (folds), so
the unstable middle branch between the two stable branches of a jump is traced too
(Keller's pseudo-arc-length method; e.g. Nayfeh & Balachandran 1995, §6.1; Seydel 2010,
§4.4). Unknowns are scaled, u = (z / L_z, ω / L_ω), and the residual by a force scale,
so the arc length is dimensionless:

    predictor   u_p = u_i + Δs t_i,       t_i the unit tangent, [R_u] t_i = 0,
    corrector   R(u) = 0,  t_iᵀ (u - u_p) = 0   (Newton, bordered Jacobian),

with step-size adaptation (grow after quick convergence, halve on failure). Every point
carries Floquet stability; turning points are where dω/ds changes sign, located by a
parabola through the three points around the extremum of ω(s).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.describing_functions import BacklashMesh
from nlgrd.harmonic_balance import ReducedModel, floquet_multipliers, solve
from nlgrd.nonlinear_results import MeshMetrics, metrics_from_harmonics
from nlgrd.sweep import SweepResult, assemble_result


@dataclass(frozen=True)
class _Point:
    z: NDArray
    omega: float
    tangent: NDArray
    iterations: int
    residual: float


class _Tracer:
    """The scaled pseudo-arc-length stepper shared by continuation and sweep jumps."""

    def __init__(self, model: ReducedModel, H: int, z0: NDArray, omega0: float, tol: float = 1e-9):
        self.model, self.H, self.tol = model, H, tol
        z0 = np.asarray(z0, dtype=float).reshape(-1)
        self.Lz = float(np.max(np.abs(z0))) or 1.0
        self.Lw = float(abs(omega0)) or 1.0
        self.Fs = model.at(omega0, H).force_scale(z0)

    def system(self, u: NDArray) -> tuple[NDArray, NDArray, float]:
        """Scaled residual, Jacobian [dR/dz̃, dR/dω̃] and the relative residual at u.

        The relative residual max|R| / max(|L z|, |B G|, |F|) at the point itself is the
        measure :func:`nlgrd.harmonic_balance.solve` converges on, so curve points and
        sweep points carry residuals on one scale."""
        z, w = u[:-1] * self.Lz, u[-1] * self.Lw
        Rw = self.model.omega_derivative(w, self.H, z)  # first: receptances and derivatives in one pass
        problem = self.model.at(w, self.H)
        R, J, scale = problem.residual_jacobian(z)
        A = np.column_stack([J * self.Lz, Rw * self.Lw]) / self.Fs
        return R / self.Fs, A, float(np.max(np.abs(R)) / scale)

    def tangent(self, A: NDArray, previous: NDArray) -> NDArray:
        """Unit tangent (null vector of A) oriented along ``previous``."""
        B = np.vstack([A, previous])
        rhs = np.zeros(B.shape[0])
        rhs[-1] = 1.0
        try:
            t = np.linalg.solve(B, rhs)
        except np.linalg.LinAlgError:
            t = np.linalg.svd(A)[2][-1]
        t /= np.linalg.norm(t)
        return t if t @ previous >= 0 else -t

    def correct(
        self, u_pred: NDArray, t: NDArray, max_iter: int = 12
    ) -> tuple[NDArray | None, int, float, NDArray | None]:
        """Newton on [R(u); tᵀ(u - u_pred)] = 0; returns (u or None, Newton updates,
        residual, the Jacobian at u).

        Converged when, after at least one update, the relative residual is below ``tol``
        and the arc-length constraint holds to 1e-12."""
        u = u_pred.copy()
        res = np.inf
        for it in range(max_iter + 1):
            R, A, res = self.system(u)
            if it > 0 and res < self.tol and abs(t @ (u - u_pred)) < 1e-12:
                return u, it, res, A
            if it == max_iter:
                break
            B = np.vstack([A, t])
            try:
                du = -np.linalg.solve(B, np.append(R, t @ (u - u_pred)))
            except np.linalg.LinAlgError:
                return None, it + 1, np.inf, None
            if not np.all(np.isfinite(du)):
                return None, it + 1, np.inf, None
            u = u + du
        return None, max_iter, res, None

    def trace(
        self,
        z0: NDArray,
        omega0: float,
        direction: int,
        ds: float,
        ds_min: float,
        ds_max: float,
        max_steps: int,
        grow_below: int = 3,
    ) -> Iterator[_Point]:
        """Yield successive curve points (the start first), until the step size collapses.

        The step grows by 1.5 after a corrector that needed at most ``grow_below``
        iterations and halves after one that needed 8 or more."""
        u = np.append(np.asarray(z0, dtype=float).reshape(-1) / self.Lz, omega0 / self.Lw)
        prev = np.zeros(u.size)
        prev[-1] = float(np.sign(direction) or 1)
        _, A, res0 = self.system(u)
        t = self.tangent(A, prev)
        yield _Point(u[:-1] * self.Lz, u[-1] * self.Lw, t, 0, res0)
        for _ in range(max_steps):
            while True:
                u_pred = u + ds * t
                un, its, res, A = self.correct(u_pred, t)
                if un is not None:
                    tn = self.tangent(A, t)
                    # accept only small corrections and tangent turns (< ~25 degrees)
                    if ds <= 2 * ds_min or (tn @ t > 0.9 and np.linalg.norm(un - u_pred) < 0.5 * ds):
                        break
                ds /= 2
                if ds < ds_min:
                    return
            u, t = un, tn
            yield _Point(u[:-1] * self.Lz, u[-1] * self.Lw, t, its, res)
            if its <= grow_below:
                ds = min(ds * 1.5, ds_max)
            elif its >= 8:
                ds = max(ds / 2, ds_min)


@dataclass(frozen=True)
class ContinuationResult:
    """A solution curve in (ω, z) with stability per point.

    Attributes
    ----------
    curve : SweepResult
        Per-point data in curve order (``direction`` = "curve"); ``stable`` and
        ``floquet_max`` from the Floquet multipliers.
    arclength : ndarray
        Scaled arc length s at each point [-].
    turning_indices : ndarray of int
        Indices i where dω/ds changes sign between points i and i+1.
    turning_omegas : ndarray
        Frequencies of the turning points [rad/s] (parabolic interpolation of ω(s)).
    complete : bool
        The curve left the frequency range past ``omega_end`` (False: the step size
        collapsed, ``max_steps`` was reached, or the curve turned back and left the
        range at ``omega_start``).
    """

    curve: SweepResult
    arclength: NDArray
    turning_indices: NDArray
    turning_omegas: NDArray
    complete: bool

    @property
    def omega(self) -> NDArray:
        """Frequencies along the curve [rad/s]."""
        return self.curve.omega

    @property
    def stable(self) -> NDArray:
        """Stability per point."""
        return self.curve.stable

    def turning_points(self) -> NDArray:
        """Frequencies of the turning points [rad/s]."""
        return self.turning_omegas

    def to_frame(self):
        """Tidy table (see :meth:`SweepResult.to_frame`) with the arc length."""
        df = self.curve.to_frame()
        df.insert(1, "arclength [-]", self.arclength)
        return df

    def plot(self, quantity: str = "dte_rms", ax=None):
        """Curve with stable parts solid and unstable parts dashed."""
        from nlgrd.plotting.nonlinear import plot_continuation

        return plot_continuation(self, quantity=quantity, ax=ax)


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
    mesh: BacklashMesh | None = None,
    n_samples: int = 2048,
) -> ContinuationResult:
    """Trace the harmonic-balance solution curve from ``omega_start`` towards ``omega_end``.

    Parameters
    ----------
    model : ReducedModel
    omega_start, omega_end : float
        Frequency range [rad/s]; the curve starts at ``omega_start`` (solved by Newton
        from ``z0`` or the linear response) and stops when ω leaves the range.
    H : int
        Harmonics.
    ds, ds_min, ds_max : float
        Initial, minimum and maximum scaled arc-length step.
    max_steps : int
    tol : float
        Scaled residual tolerance of the corrector.
    stability : bool
        Floquet multipliers per point (needs ``model.state_space``).
    mesh : BacklashMesh, optional
        For the output metrics (default the model's mesh).
    """
    mesh = mesh or model.mesh
    first = solve(model.at(omega_start, H), z0)
    if not first.converged:
        raise RuntimeError(f"no converged starting solution at omega = {omega_start}: {first.message}")
    lo, hi = sorted((omega_start, omega_end))
    span = hi - lo
    tracer = _Tracer(model, H, first.harmonics, omega_start, tol)
    direction = 1 if omega_end >= omega_start else -1
    pts: list[_Point] = []
    complete = False
    for p in tracer.trace(first.harmonics, omega_start, direction, ds, ds_min, ds_max, max_steps):
        pts.append(p)
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
        mets.append(metrics_from_harmonics(z[mesh.coord], w, mesh, n_samples) if mesh else MeshMetrics.nan(H))
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


def jump_to_branch(
    model: ReducedModel,
    H: int,
    z_prev: NDArray,
    omega_prev: float,
    omega_target: float,
    *,
    max_steps: int = 600,
    tol: float = 1e-10,
    require_stable: bool = True,
    max_excursion: float = 50.0,
) -> tuple[NDArray | None, int, int]:
    """Find the solution at ``omega_target`` reached after the branch through ``omega_prev`` folded.

    Follows the curve from (z_prev, ω_prev) towards ω_target by arc-length continuation
    (through the fold and the unstable branch of an S-shaped response curve) and returns
    the first curve crossing of ω_target (solved there by Newton) that is stable
    (``require_stable``; Floquet, when the model has a state space) or, with
    ``require_stable=False`` or without a state space, the first crossing after an even
    number of turning points (each fold flips the sign of the Jacobian's determinant, so
    that crossing has the stability of the start: on an S-shaped curve, the far stable
    branch). Returns (harmonics or None, continuation steps, turning points passed); no
    turning point means Newton had failed on the same branch (e.g. at grazing), not a
    jump.
    """
    direction = 1 if omega_target > omega_prev else -1
    tracer = _Tracer(model, H, z_prev, omega_prev, 1e-9)
    span = abs(omega_target - omega_prev)
    prev: _Point | None = None
    steps = 0
    folds = 0
    for p in tracer.trace(z_prev, omega_prev, direction, 0.01, 1e-8, 0.2, max_steps, grow_below=4):
        steps += 1
        if prev is not None and np.sign(p.tangent[-1]) != np.sign(prev.tangent[-1]):
            folds += 1
        crossed = prev is not None and (p.omega - omega_target) * (prev.omega - omega_target) <= 0
        floquet = crossed and require_stable and model.linear_state_space(omega_target) is not None
        if crossed and (floquet or folds % 2 == 0):
            a = (omega_target - prev.omega) / (p.omega - prev.omega) if p.omega != prev.omega else 0.5
            guess = (1 - a) * prev.z + a * p.z
            sol = solve(model.at(omega_target, H), guess, tol=tol, fallback=False)
            if sol.converged:
                ok = True
                if floquet:
                    mu = floquet_multipliers(
                        model.linear_state_space(omega_target),
                        model.nonlinearities,
                        sol.harmonics,
                        omega_target,
                    )
                    ok = bool(np.max(np.abs(mu)) < 1 + 1e-6)
                if ok:
                    return sol.harmonics, steps, folds
        if abs(p.omega - omega_prev) > max_excursion * span + 0.5 * abs(omega_prev):
            break
        prev = p
    return None, steps, folds
