"""Where a frequency sweep lands when the branch it follows ends (a fold) or turns unstable.

A slow physical sweep leaves a branch that folds or loses stability and settles on
another attractor at the same frequency. :func:`restart` searches by Newton from a few
starts, :func:`follow_branch` checks by arc-length continuation that a long Newton search
stayed on the branch, and :func:`nearest_landing` picks, of the stable candidates, the
one nearest the departed orbit. Candidates may include the solutions of the other sweep
directions at the same frequency (a ``pool``): an up sweep cannot find the down sweep's
branch by Newton from its own orbit where the curve is strongly nonsmooth.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from nlgrd.nonlinear.hb.harmonic_balance import HarmonicSolution
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.results.sweep_results import STABLE_RTOL
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.stability.shooting import shooting_start
from nlgrd.nonlinear.tracing.arclength import jump_to_branch

#: Newton iterations from the previous point beyond which a sweep checks by arc-length
#: continuation that the solution is on the branch followed (a warm start on a grid that
#: resolves the curve converges in a few; a long search can land on a coexisting orbit).
WANDER_ITER = 20


def distance(sol: HarmonicSolution, z_prev: NDArray) -> float:
    """Euclidean distance of a solution's harmonics from ``z_prev``.

    Parameters
    ----------
    sol : HarmonicSolution
        The solution whose harmonics are compared.
    z_prev : ndarray
        Harmonics to measure from: real harmonics [x0, a1, b1, ...] of the
        nonlinear coordinates, shape (n_nl, 2H+1) or flattened coordinate-major [m].

    Returns
    -------
    float
        ‖z - z_prev‖ over all harmonics of all coordinates [m].
    """
    return float(np.linalg.norm(sol.harmonics.reshape(-1) - np.asarray(z_prev).reshape(-1)))


def is_stable(model, sol: HarmonicSolution, omega: float) -> bool:
    """Floquet-stable (True also when the model has no linear state space to check).

    Parameters
    ----------
    model : ReducedModel
        The model solved (its linear state space at ``omega`` gives the multipliers).
    sol : HarmonicSolution
        The solution checked.
    omega : float
        Mesh frequency of the solution [rad/s].

    Returns
    -------
    bool
        max |μ| < 1 + ``STABLE_RTOL``, or True when ``model`` has no state space.
    """
    ss = model.linear_state_space(omega)
    if ss is None:
        return True
    mu = floquet_multipliers(ss, model.nonlinearities, sol.harmonics, omega)
    return bool(np.max(np.abs(mu)) < 1 + STABLE_RTOL)


def restart(model, problem, z_prev, omega, H, method, tol, max_iter, unstable=None):
    """Land on another branch after a fold without arc-length continuation.

    Newton is started from the full-contact linear response and from the previous
    solution with its alternating part scaled by 1/4, 1/2, 2 and 4, and gives up on a
    start where it stalls (``stall`` of :func:`nlgrd.nonlinear.hb.solvers.solve`). Of the converged
    solutions that are stable (checked whenever the model has a linear state space),
    the one nearest the previous solution is returned (None if there is none): after a
    fold a slow sweep falls to the nearest coexisting stable branch, in the usual case
    of an S-shaped curve the one the unstable branch leads to.

    Parameters
    ----------
    model : ReducedModel
        The model solved (for the stability check).
    problem : ReducedProblem
        The harmonic-balance problem at ``omega`` (``model.at(omega, H)``).
    z_prev : ndarray
        The previous solution: real harmonics [x0, a1, b1, ...] of the
        nonlinear coordinates, shape (n_nl, 2H+1) or flattened coordinate-major [m].
    omega : float
        Mesh frequency of the new point [rad/s].
    H : int
        Number of harmonics.
    method : str
        Solver of :func:`nlgrd.nonlinear.hb.solvers.solve` for each start.
    tol : float
        Convergence tolerance of the solver (relative residual).
    max_iter : int
        Iteration limit of the solver per start.
    unstable : list, optional
        Receives the converged solutions that are unstable (HarmonicSolution), for a
        sweep that reports an unstable orbit where no stable one is found.

    Returns
    -------
    HarmonicSolution or None
        The converged stable solution nearest ``z_prev``; None when no start gives one.
    """
    z_prev = np.asarray(z_prev, dtype=float)
    nh = 2 * H + 1
    guesses = [None]
    for scale in (0.25, 0.5, 2.0, 4.0):
        g = z_prev.reshape(-1, nh).copy()
        g[:, 1:] *= scale
        guesses.append(g.reshape(z_prev.shape))
    best, best_d = None, np.inf
    for guess in guesses:
        cand = solve(problem, guess, method=method, tol=tol, max_iter=max_iter, fallback=False, stall=True)
        if not cand.converged:
            continue
        if not is_stable(model, cand, omega):
            if unstable is not None:
                unstable.append(cand)
            continue
        d = distance(cand, z_prev)
        if d < best_d:
            best, best_d = cand, d
    return best


def fresh_start(model, problem, z_prev, omega, H, method, tol, max_iter, stability, tried=None):
    """A solution past the end of the branch a sweep followed, where every step from it
    failed: the starts of :func:`restart` (the full-contact linear response, the previous
    orbit's alternating part scaled) and the exact orbit shot from the linear response
    (:func:`~nlgrd.nonlinear.stability.shooting.shooting_start`); the stable solution nearest
    the previous one, else (the sweep leaves unstable points to its own rules) the nearest
    unstable one.

    Parameters
    ----------
    model, problem : ReducedModel, ReducedProblem
        As :func:`restart`.
    z_prev : ndarray
        The last orbit of the sweep: real harmonics (n_nl, 2H+1) or flattened [m].
    omega : float
        Mesh frequency of the point [rad/s].
    H, method, tol, max_iter : int, str, float, int
        As :func:`restart`.
    stability : bool
        The sweep computes stability: prefer a stable solution.
    tried : list of HarmonicSolution, optional
        The unstable orbits of a :func:`restart` the sweep already ran at this point (it found
        no stable one): that restart is not repeated. None: not run yet.

    Returns
    -------
    HarmonicSolution or None
        None when no start converges.
    """
    unstable: list[HarmonicSolution] = [] if tried is None else list(tried)
    best = (
        None
        if tried is not None
        else restart(model, problem, z_prev, omega, H, method, tol, max_iter, unstable=unstable)
    )
    if best is not None and stability:
        return best
    cands = [c for c in (best, *unstable) if c is not None]
    if not cands and (zs := shooting_start(model, float(omega), H)) is not None:
        sol = solve(problem, zs, method=method, tol=tol, max_iter=max_iter, fallback=False)
        cands = [sol] if sol.converged else []
    return min(cands, key=lambda c: distance(c, z_prev)) if cands else None


def pool_candidates(model, problem, pool, omega, direction, tol, max_iter) -> list[HarmonicSolution]:
    """Stable solutions at ``omega`` of the other sweep directions (``pool``: {omega: [(direction,
    harmonics)]}), re-solved by Newton on ``problem`` (they are solutions: one iteration).

    Parameters
    ----------
    model : ReducedModel
        The model solved (for the stability check).
    problem : ReducedProblem
        The harmonic-balance problem at ``omega``.
    pool : dict or None
        {omega [rad/s]: [(direction, harmonics)]}, the harmonics real [x0, a1, b1, ...] of
        the nonlinear coordinates, shape (n_nl, 2H+1) [m]; None: no candidates.
    omega : float
        Mesh frequency of the point [rad/s].
    direction : str
        The sweep's own direction ("up" or "down"), whose entries are skipped.
    tol : float
        Convergence tolerance of Newton (relative residual).
    max_iter : int
        Newton iteration limit.

    Returns
    -------
    list of HarmonicSolution
        The candidates that converged and are stable (empty when there are none).
    """
    out = []
    for d, z in (pool or {}).get(float(omega), ()):
        if d == direction:
            continue
        cand = solve(problem, z, method="newton", tol=tol, max_iter=max_iter, fallback=False)
        if cand.converged and is_stable(model, cand, omega):
            out.append(cand)
    return out


#: Two solutions closer than this (relative to the larger norm) are the same orbit.
SAME_ORBIT_RTOL = 1e-6


def same_orbit(a, b) -> bool:
    """Harmonics ``a`` and ``b`` within SAME_ORBIT_RTOL of the larger norm of the two.

    Parameters
    ----------
    a, b : array_like
        The two solutions: real harmonics [x0, a1, b1, ...] of the
        nonlinear coordinates, shape (n_nl, 2H+1) or flattened coordinate-major [m].

    Returns
    -------
    bool
        ‖a - b‖ <= ``SAME_ORBIT_RTOL`` max(‖a‖, ‖b‖).
    """
    a, b = np.ravel(a), np.ravel(b)
    scale = max(float(np.linalg.norm(a)), float(np.linalg.norm(b)))
    return bool(np.linalg.norm(a - b) <= SAME_ORBIT_RTOL * scale)


def nearer(cand, best, z_prev) -> bool:
    """``cand`` is another orbit than ``best`` and nearer ``z_prev`` (arrays of harmonics).

    Parameters
    ----------
    cand, best, z_prev : array_like
        The candidate, the landing so far and the departed orbit: real harmonics [x0, a1, b1, ...] of the
        nonlinear coordinates, shape (n_nl, 2H+1) or flattened coordinate-major [m].

    Returns
    -------
    bool
        True when ``cand`` is not :func:`same_orbit` as ``best`` and strictly nearer ``z_prev``.
    """
    if same_orbit(cand, best):
        return False
    c, b, p = (np.ravel(x) for x in (cand, best, z_prev))
    return float(np.linalg.norm(c - p)) < float(np.linalg.norm(b - p))


def nearest_landing(landing, z_prev, others=()):
    """After a fold: of the arc-length ``landing`` and the stable candidates ``others``
    (the other sweep directions' solutions at this frequency, Newton's own), the one
    nearest the departed orbit ``z_prev``.

    Arc length alone takes the far stable branch of an S. Where the curve folds twice
    more, as onto the back-side impact orbit of Kubo's single-DOF model near 10 500 rpm,
    a slow sweep falls to a nearer attractor (time integration:
    tests/test_sweep_landing.py).

    Parameters
    ----------
    landing : HarmonicSolution
        The arc-length landing.
    z_prev : ndarray
        The orbit that folded: real harmonics [x0, a1, b1, ...] of the
        nonlinear coordinates, shape (n_nl, 2H+1) or flattened coordinate-major [m].
    others : sequence of HarmonicSolution or None
        Further stable candidates at the same frequency (None entries are skipped).

    Returns
    -------
    HarmonicSolution
        ``landing``, or the candidate of ``others`` nearer ``z_prev`` (another orbit).
    """
    best = landing
    for cand in others:
        if cand is not None and nearer(cand.harmonics, best.harmonics, z_prev):
            best = cand
    return best


def follow_branch(
    model, problem, sol, z_prev, omega_prev, omega, H, method, tol, max_iter, stability, others=()
):
    """The solution at ``omega`` on the branch through (z_prev, omega_prev), when Newton from z_prev
    needed more than WANDER_ITER iterations and may have wandered onto another orbit.

    Arc-length continuation from the previous point (:func:`nlgrd.nonlinear.tracing.arclength.jump_to_branch`)
    follows the branch to ``omega``; if it folds on the way the point is a jump, landed by
    :func:`nearest_landing` with Newton's own solution and ``others`` as candidates.
    Newton's solution is kept when continuation does not reach ``omega``. Returns (solution,
    switched).

    Parameters
    ----------
    model : ReducedModel
        The model swept.
    problem : ReducedProblem
        The harmonic-balance problem at ``omega``.
    sol : HarmonicSolution
        Newton's solution at ``omega`` from ``z_prev``.
    z_prev : ndarray
        The previous point's solution: real harmonics [x0, a1, b1, ...] of the
        nonlinear coordinates, shape (n_nl, 2H+1) or flattened coordinate-major [m].
    omega_prev : float
        Mesh frequency of the previous point [rad/s].
    omega : float
        Mesh frequency of the new point [rad/s].
    H : int
        Number of harmonics.
    method : str
        Solver of the sweep (unused here: the polish after continuation is Newton).
    tol : float
        Convergence tolerance of Newton at ``omega`` (relative residual).
    max_iter : int
        Newton iteration limit.
    stability : bool
        Land only on a Floquet-stable crossing of ``omega`` (``require_stable`` of
        :func:`nlgrd.nonlinear.tracing.arclength.jump_to_branch`).
    others : sequence of HarmonicSolution
        Further stable candidates at ``omega`` (the other sweep directions' solutions).

    Returns
    -------
    solution : HarmonicSolution
        The solution on the branch followed (``sol`` when continuation fails or lands on
        the same orbit).
    switched : bool
        Continuation passed a fold on the way: the point is a jump.
    """
    zj, steps, folds, _ = jump_to_branch(
        model, H, z_prev, omega_prev, omega, tol=tol, require_stable=stability
    )
    if zj is None:
        return sol, False
    fol = solve(problem, zj, method="newton", tol=tol, max_iter=max_iter, fallback=False)
    if not fol.converged:
        return sol, False
    note = "newton after arc-length continuation (Newton from the previous point left the branch)"
    fol = HarmonicSolution(
        fol.omega,
        fol.harmonics,
        True,
        fol.residual,
        sol.iterations + steps + fol.iterations,
        note,
        fol.iterate,
        fol.message,
    )
    if folds:
        fol = nearest_landing(fol, z_prev, others=(sol, *others))
    if same_orbit(fol.harmonics, sol.harmonics):
        return sol, folds > 0
    return fol, folds > 0


#: Fractions of a first point's frequency the fallback of :func:`approach` starts from
#: (their reciprocals for a down sweep): close enough that the walk fits the landing
#: budget, far enough that the linear start converges there. data/models/rub_rotor.toml
#: at 4000 rpm (one point, up): from 0.9 and 0.75 the walk lands on the orbit a 21-point
#: run-up from 2000 rpm reaches (rub force 84.04 N); from 0.5 it exceeds the budget.
APPROACH_FRACTIONS = (0.9, 0.75)


def approach(model, problem, order, i, H, method, tol, max_iter, stability, lookahead=5, direction="up"):
    """A start for a sweep's first point ``order[i]`` when Newton from the full-contact
    linear response fails there: solve at the next frequencies of the sweep (up to
    ``lookahead``) and follow the curve back by arc-length continuation
    (:func:`nlgrd.nonlinear.tracing.arclength.jump_to_branch`); when none leads there (a
    one-point sweep has none), from :data:`APPROACH_FRACTIONS` of the frequency on the
    side the sweep comes from (below for "up", above for "down"), the orbit a slow run-up
    or run-down reaches. Returns a solution or None.

    Parameters
    ----------
    model : ReducedModel
        The model swept.
    problem : ReducedProblem
        The harmonic-balance problem at ``order[i]``.
    order : ndarray
        Mesh frequencies of the sweep in sweep order [rad/s].
    i : int
        Index in ``order`` of the point to start.
    H : int
        Number of harmonics.
    method : str
        Solver of :func:`nlgrd.nonlinear.hb.solvers.solve` at the next frequencies.
    tol : float
        Convergence tolerance of the solvers (relative residual).
    max_iter : int
        Iteration limit of the solvers.
    stability : bool
        Accept only a Floquet-stable crossing of ``order[i]`` (``require_stable``).
    lookahead : int
        Number of following frequencies tried.
    direction : {"up", "down"}
        The sweep's direction: the side the fallback starts are taken on.

    Returns
    -------
    HarmonicSolution or None
        The converged solution at ``order[i]``; None when no following frequency leads there.
    """
    omega = float(order[i])
    side = APPROACH_FRACTIONS if direction == "up" else tuple(1 / f for f in APPROACH_FRACTIONS)
    for wk in [*order[i + 1 : i + 1 + lookahead], *(f * omega for f in side)]:
        start = solve(model.at(float(wk), H), None, method=method, tol=tol, max_iter=max_iter, fallback=True)
        if not start.converged:
            continue
        zj, steps, _, _ = jump_to_branch(
            model, H, start.harmonics, float(wk), omega, tol=tol, require_stable=stability
        )
        if zj is None:
            continue
        sol = solve(problem, zj, method="newton", tol=tol, max_iter=max_iter, fallback=False)
        if sol.converged:
            note = f"newton after arc-length continuation from {float(wk):.6g} rad/s"
            return HarmonicSolution(
                sol.omega,
                sol.harmonics,
                True,
                sol.residual,
                start.iterations + steps + sol.iterations,
                note,
                sol.iterate,
                sol.message,
            )
    return None
