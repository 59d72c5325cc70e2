"""The pseudo-arc-length stepper for harmonic-balance solutions in the mesh frequency.

Follows the solution curve {(z, ω): R(z, ω) = 0} through turning points (folds), so
the unstable middle branch between the two stable branches of a jump is traced too
(Keller's pseudo-arc-length method; e.g. Nayfeh & Balachandran 1995, §6.1; Seydel 2010,
§4.4). Unknowns are scaled, u = (z / L_z, ω / L_ω), and the residual by a force scale,
so the arc length is dimensionless:

    predictor   u_p = u_i + Δs t_i,       t_i the unit tangent, [R_u] t_i = 0,
    corrector   R(u) = 0,  t_iᵀ (u - u_p) = 0   (Newton, bordered Jacobian),

with step-size adaptation (grow after quick convergence, halve on failure). It serves
whole curves (:func:`nlgrd.nonlinear.tracing.continuation.continuation`) and the jumps of sweeps
(:func:`jump_to_branch`).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.results.sweep_results import STABLE_RTOL
from nlgrd.nonlinear.stability.floquet import floquet_multipliers

#: Ceiling of corrector evaluations (residual, Jacobian and dR/dω at one point: the unit
#: of :attr:`Tracer.evaluations`) of one :func:`jump_to_branch` search, after which it ends
#: as one that found no stable crossing. Set above the longest landing the tests and
#: references find (1579, the Kahraman-Blankenship down sweep checked against time
#: integration; 588 the FE parametric-mesh load sharing; the rest at most 523) and below the
#: failed searches of the idler train (4237-4422 at H = 9). A count, not a time: the
#: result does not depend on the machine. Issue 34 item 2 and benchmarks/README.md.
LANDING_EVALUATIONS = 2000


@dataclass(frozen=True)
class CurvePoint:
    """A point of the curve: harmonics, frequency [rad/s], unit tangent (scaled), corrector
    iterations and relative residual.

    Attributes
    ----------
    z : ndarray
        Real harmonics [x0, a1, b1, ...] of the nonlinear coordinates, flattened
        coordinate-major from shape (n_nl, 2H+1) [m].
    omega : float
        Mesh frequency of the point [rad/s].
    tangent : ndarray
        Unit tangent of the curve in the scaled unknowns u = (z / L_z, ω / L_ω), size
        n_nl (2H+1) + 1, frequency last [-].
    iterations : int
        Corrector (Newton) iterations (0 at the start).
    residual : float
        Relative residual max|R| / max(|L z|, |B G|, |F|) at the point [-].
    """

    z: NDArray
    omega: float
    tangent: NDArray
    iterations: int
    residual: float


class Tracer:
    """The scaled pseudo-arc-length stepper shared by continuation and sweep jumps.

    Parameters
    ----------
    model : ReducedModel
        The harmonic-balance model as a function of the mesh frequency.
    H : int
        Number of harmonics.
    z0 : ndarray
        Harmonics at the start: real harmonics [x0, a1, b1, ...] of the nonlinear
        coordinates, shape (n_nl, 2H+1) or flattened coordinate-major [m]; they set the
        scales.
    omega0 : float
        Mesh frequency at the start [rad/s]; sets the frequency scale.
    tol : float
        Convergence tolerance of the corrector (relative residual).

    Attributes
    ----------
    Lz : float
        Harmonics scale max |z0| (1 if zero) [m].
    Lw : float
        Frequency scale |omega0| (1 if zero) [rad/s].
    Fs : float
        Force scale of the residual, max(|L z0|, |B G|, |F|) at the start [N].
    evaluations : int
        Corrector evaluations (calls of :meth:`system`) so far [-].
    """

    def __init__(self, model: ReducedModel, H: int, z0: NDArray, omega0: float, tol: float = 1e-9):
        self.model, self.H, self.tol = model, H, tol
        z0 = np.asarray(z0, dtype=float).reshape(-1)
        self.Lz = float(np.max(np.abs(z0))) or 1.0
        self.Lw = float(abs(omega0)) or 1.0
        self.Fs = model.at(omega0, H).force_scale(z0)
        self.evaluations = 0

    def system(self, u: NDArray) -> tuple[NDArray, NDArray, float]:
        """Scaled residual, Jacobian [dR/dz̃, dR/dω̃] and the relative residual at u.

        The relative residual max|R| / max(|L z|, |B G|, |F|) at the point itself is the
        measure :func:`nlgrd.nonlinear.hb.solvers.solve` converges on, so curve points and
        sweep points carry residuals on one scale."""
        self.evaluations += 1
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
        max_evaluations: int | None = None,
    ) -> Iterator[CurvePoint]:
        """Yield successive curve points (the start first), until the step size collapses
        or :attr:`evaluations` reaches ``max_evaluations`` (None: no limit).

        The step grows by 1.5 after a corrector that needed at most ``grow_below``
        iterations and halves after one that needed 8 or more."""
        u = np.append(np.asarray(z0, dtype=float).reshape(-1) / self.Lz, omega0 / self.Lw)
        prev = np.zeros(u.size)
        prev[-1] = float(np.sign(direction) or 1)
        _, A, res0 = self.system(u)
        t = self.tangent(A, prev)
        yield CurvePoint(u[:-1] * self.Lz, u[-1] * self.Lw, t, 0, res0)
        for _ in range(max_steps):
            while True:
                if max_evaluations is not None and self.evaluations >= max_evaluations:
                    return
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
            yield CurvePoint(u[:-1] * self.Lz, u[-1] * self.Lw, t, its, res)
            if its <= grow_below:
                ds = min(ds * 1.5, ds_max)
            elif its >= 8:
                ds = max(ds / 2, ds_min)


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
    max_overshoot: float = 20.0,
    max_evaluations: int | None = LANDING_EVALUATIONS,
    exhausted: list | None = None,
    walks: dict | None = None,
) -> tuple[NDArray | None, int, int, NDArray | None]:
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

    Parameters
    ----------
    model : ReducedModel
        The harmonic-balance model as a function of the mesh frequency.
    H : int
        Number of harmonics.
    z_prev : ndarray
        The solution at ``omega_prev``: real harmonics [x0, a1, b1, ...] of the nonlinear
        coordinates, shape (n_nl, 2H+1) or flattened coordinate-major [m].
    omega_prev : float
        Mesh frequency of the last point on the branch [rad/s].
    omega_target : float
        Mesh frequency to land at [rad/s].
    max_steps : int
        Limit of continuation steps.
    tol : float
        Convergence tolerance of Newton at ``omega_target`` (relative residual); the
        corrector of the continuation converges to 1e-9.
    require_stable : bool
        Accept only a Floquet-stable crossing (when the model has a state space).
    max_excursion : float
        Give up when the curve strays from ``omega_prev`` by more than ``max_excursion``
        times |omega_target - omega_prev| plus half of |omega_prev| [-].
    max_overshoot : float
        Give up when the curve has passed ``omega_target`` by more than ``max_overshoot``
        times |omega_target - omega_prev| plus 2 % of |omega_target| [-]: it crossed the
        target without a stable landing and runs on along a branch away from it (a
        slow sweep does not reach an orbit that only a far fold brings back).
    max_evaluations : int or None
        Ceiling of corrector evaluations (:attr:`Tracer.evaluations`, the start's
        included); the search then ends as one that found no stable crossing
        (:data:`LANDING_EVALUATIONS`; None: only ``max_steps`` limits it).
    exhausted : list, optional
        Receives True when the ceiling ended the search (a caller may then look for an
        orbit otherwise).
    walks : dict, optional
        Walks that ended on their own (ceiling, ``max_steps`` or step collapse), by start
        and direction, of the same ``model`` (a sweep's): the walk does not depend on
        ``omega_target`` until it stops, so one from the same start, bit for bit, is
        replayed from here, its crossings of the new target checked as on a fresh walk.

    Returns
    -------
    harmonics : ndarray or None
        The landing at ``omega_target``, shape (n_nl, 2H+1) [m]; None when none was found.
    steps : int
        Continuation steps taken.
    folds : int
        Turning points passed.
    unstable : ndarray or None
        With ``require_stable``, when no stable landing was found: the first crossing of
        ``omega_target`` that converged but is unstable (harmonics as above), the orbit a
        sweep reports as "no stable mesh-periodic response"; otherwise None.
    """
    direction = 1 if omega_target > omega_prev else -1
    tracer = Tracer(model, H, z_prev, omega_prev, 1e-9)
    span = abs(omega_target - omega_prev)
    prev: CurvePoint | None = None
    steps = 0
    folds = 0
    unstable = None
    z_flat = np.asarray(z_prev, dtype=float).reshape(-1)
    key = (H, float(omega_prev), direction, z_flat.tobytes(), max_steps, max_evaluations)
    stored = None if walks is None else walks.get(key)
    if stored is None:
        points = tracer.trace(z_prev, omega_prev, direction, 0.01, 1e-8, 0.2, max_steps, 4, max_evaluations)
    else:
        points = iter(stored[0])
    record: list | None = [] if walks is not None and stored is None else None
    for p in points:
        if record is not None:
            record.append(p)
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
                    ok = bool(np.max(np.abs(mu)) < 1 + STABLE_RTOL)
                if ok:
                    return sol.harmonics, steps, folds, None
                if unstable is None:
                    unstable = sol.harmonics
        if abs(p.omega - omega_prev) > max_excursion * span + 0.5 * abs(omega_prev):
            break
        if direction * (p.omega - omega_target) > max_overshoot * span + 0.02 * abs(omega_target):
            break
        prev = p
    else:  # the walk ended on its own, not on this target's limits
        if record is not None:
            walks[key] = (record, tracer.evaluations)
    evaluations = tracer.evaluations if stored is None else stored[1]
    if exhausted is not None and max_evaluations is not None and evaluations >= max_evaluations:
        exhausted.append(True)
    return None, steps, folds, unstable
