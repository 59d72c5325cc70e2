"""Frequency sweeps up and down by natural continuation (each point starts from the last).

Up and down sweeps land on different branches where the response is multivalued;
the difference between them shows the jumps (model.md §3). Non-converged points are
kept, flagged and listed (:meth:`SweepResult.failures`), with NaN outputs.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.hb.harmonic_balance import HarmonicSolution, ReducedModel
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.results.metrics import MeshMetrics
from nlgrd.nonlinear.results.sweep_results import (
    STABLE_RTOL,
    SweepResult,
    assemble_result,
    dominant_multiplier,
    instability_kind,
)
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.stability.shooting import shooting_start
from nlgrd.nonlinear.tracing import landing
from nlgrd.nonlinear.tracing.arclength import jump_to_branch
from nlgrd.nonlinear.tracing.landing import WANDER_ITER
from nlgrd.threads import single_blas_thread

#: How a sweep lands on the other branch after a fold (see :func:`sweep`).
JUMP_STRATEGIES = ("arclength", "restart", "auto", "none")


def sweep_orders(omegas: NDArray, directions: str | Sequence[str]) -> list[tuple[str, NDArray]]:
    """The frequency grid in the order of each sweep direction.

    Parameters
    ----------
    omegas : ndarray
        Mesh frequencies [rad/s], in any order.
    directions : "up", "down", "both" or a sequence of "up" and "down"
        The sweeps, in the order they are run ("both": up, then down).

    Returns
    -------
    list of (str, ndarray)
        (direction, frequencies [rad/s] sorted ascending for "up", descending for "down").

    Raises
    ------
    ModelError
        A direction other than "up", "down" or "both".
    """
    if isinstance(directions, str):
        directions = ("up", "down") if directions == "both" else (directions,)
    out = []
    for d in directions:
        if d not in ("up", "down"):
            raise ModelError("directions", f"must be 'up', 'down' or 'both', got {d!r}")
        out.append((d, np.sort(omegas) if d == "up" else np.sort(omegas)[::-1]))
    return out


@single_blas_thread
def sweep(
    model: ReducedModel,
    omegas: ArrayLike,
    H: int = 5,
    directions: str | Sequence[str] = "both",
    *,
    method: str = "newton",
    tol: float = 1e-10,
    max_iter: int = 50,
    fallback: bool = True,
    stability: bool = True,
    n_samples: int = 2048,
    z0: ArrayLike | None = None,
    jump: str = "arclength",
    chain: bool = True,
    leave_unstable: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> SweepResult:
    """Harmonic-balance sweeps up and/or down in frequency by natural continuation.

    Each point starts from the last converged solution of the same sweep (the first
    from the full-contact linear response, or ``z0``), so up and down sweeps follow
    their branch until it folds and then jump.

    Parameters
    ----------
    model : ReducedModel
        The harmonic-balance model as a function of the mesh frequency.
    omegas : array_like
        Mesh frequencies [rad/s] (sorted internally per direction).
    H : int
        Number of harmonics.
    directions : "up", "down", "both" or a sequence of them
        The sweeps, in the order they are run ("both": up, then down).
    method, tol, max_iter, fallback : str, float, int, bool
        Passed to :func:`nlgrd.nonlinear.hb.solvers.solve` (``tol``: convergence tolerance,
        relative residual).
    stability : bool
        Floquet multipliers per point (needs ``model.state_space``).
    n_samples : int
        Samples per period for the force extremes.
    z0 : array_like, optional
        Start of a sweep's first point (of the first sweep only, with ``chain``): real
        harmonics [x0, a1, b1, ...] of the nonlinear coordinates, shape (n_nl, 2H+1) or
        flat [m]; default the full-contact linear response.
    chain : bool
        With several directions, start each sweep from the last solution of the one
        before (as a rig is swept up and then back down), instead of afresh.
    jump : {"arclength", "restart", "auto", "none"}
        When Newton fails from the previous point (its branch folded between the two
        frequencies), "arclength" follows the curve through the fold by pseudo-arc-length
        continuation to its first stable crossing of the new frequency
        (:func:`nlgrd.nonlinear.tracing.arclength.jump_to_branch`): the branch a slow sweep jumps to on an
        S-shaped response curve. "restart" instead restarts Newton from the full-contact
        linear response and keeps the result if it converges (and is stable, when
        stability is computed): much cheaper, but it may pick another coexisting stable
        branch than a slow sweep would. "auto" takes, of the arc-length landing (or
        "restart"'s when arc length fails) and the other sweep directions' stable
        solutions at that frequency, the one nearest the orbit that folded (a second pass
        when another direction's is nearer): where the curve folds more than once, the far
        branch of arc length can be an orbit a slow sweep does not reach; where both fail
        (a branch that ends at a non-smooth grazing of a contact), the nearest of the other
        directions' stable solutions (a second pass). "none" leaves the point flagged as
        not converged.
    leave_unstable : bool
        With stability: at a point where the branch followed is unstable (by a fold or
        not), do what a slow physical sweep does. A real multiplier > 1 (the orbit
        departs along one direction, as past a fold): leave for a stable mesh-periodic
        solution at that frequency (Newton from the full-contact response and from the
        unstable orbit with its alternating part scaled by 1/4 .. 4, and with
        ``jump="auto"`` the other directions' stable solutions there; the nearest one,
        :func:`nlgrd.nonlinear.tracing.landing.restart`), listed as a jump. A complex pair or a real
        multiplier < -1 (a torus or a period-2 orbit grows around the orbit; time
        integration stays near it where the multiplier has just crossed,
        tests/test_geared_time_domain.py; see docs/verification.md, "Leaving an unstable
        orbit", for stronger instabilities), or no stable solution found: flag the point
        ``no_stable`` with NaN metrics and its dominant multiplier, and go on from the
        unstable orbit. False: stay on the branch and flag its points unstable. The
        arc-length search has a ceiling of corrector evaluations
        (:data:`nlgrd.nonlinear.tracing.arclength.LANDING_EVALUATIONS`); where one cut by it met no
        crossing and Newton from the previous point fails too, the point reports the
        nearest unstable orbit of the restarts (``jump="auto"``),
        and a failed search is not walked again from the same start
        (:class:`FailedSearches`).
    progress : callable, optional
        ``progress(i, n)`` once after each of the n points of all directions (a second
        pass of ``jump="auto"`` counts its points again from 1).

    Returns
    -------
    SweepResult
        One row per point and direction; points that did not converge are kept, flagged,
        with NaN outputs.

    Raises
    ------
    ModelError
        An unknown ``jump`` or direction.
    """
    if jump not in JUMP_STRATEGIES:
        raise ModelError("jump", f"must be one of {', '.join(map(repr, JUMP_STRATEGIES))}, got {jump!r}")
    omegas = np.asarray(omegas, dtype=float)
    kw = dict(
        method=method,
        tol=tol,
        max_iter=max_iter,
        fallback=fallback,
        stability=stability,
        n_samples=n_samples,
        z0=z0,
        jump=jump,
        chain=chain,
        leave_unstable=leave_unstable,
        progress=progress,
    )
    kw["searches"] = FailedSearches()  # shared by both passes of "auto"
    result, landings = _sweep_pass(model, omegas, H, directions, **kw)
    if jump != "auto" or len({d for d, _ in sweep_orders(omegas, directions)}) < 2:
        return result
    # a second pass where another direction's stable solution is a nearer landing
    pool = _pool(result, stability)
    nearer_landing = any(
        landing.nearer(z, z_land, z_prev)
        for direction, w, z_prev, z_land in landings
        for d, z in pool.get(w, ())
        if d != direction
    )
    # or a point of fold kind whose restarts found nothing stable, where another direction did
    fold = instability_kind(result.dominant_multiplier, result.stable) == "real > 1"
    missed = any(
        d != result.direction[i]
        for i in np.nonzero(result.no_stable & fold)[0]
        for d, _ in pool.get(float(result.omega[i]), ())
    )
    # or a point that did not converge where another direction has a stable orbit (a
    # branch ending at a non-smooth grazing, where neither arc length nor restarts land)
    failed = any(
        d != result.direction[i]
        for i in np.nonzero(~result.converged)[0]
        for d, _ in pool.get(float(result.omega[i]), ())
    )
    if nearer_landing or missed or failed:
        return _sweep_pass(model, omegas, H, directions, pool=pool, **kw)[0]
    return result


class FailedSearches:
    """The landing searches of a sweep (:func:`~nlgrd.nonlinear.tracing.arclength.jump_to_branch`)
    that found no stable crossing, so that the same search is not walked again.

    A search is a deterministic function of its start (harmonics, frequency), target and
    options: one with the same start, bit for bit, and the same target returns the stored
    result. That is the case in the second pass of ``jump="auto"``, which reaches the
    same failed search from the same orbit. A search from the same start to another
    frequency (a run of points without an orbit, each searched from the last converged
    one) replays the stored walk when that ended on its own (``walks`` of
    :func:`~nlgrd.nonlinear.tracing.arclength.jump_to_branch`): the walk does not depend on the
    target, and its crossings of the new one are checked as on a fresh walk, so a stable
    branch at the next frequency is found as before. A search from another start is
    walked afresh, within :data:`~nlgrd.nonlinear.tracing.arclength.LANDING_EVALUATIONS`.

    Attributes
    ----------
    _done : dict
        Per (model, H, start and target frequency, options): the starts' harmonics and the
        stored results of failed searches.
    _walks : dict
        Per start: the walk that ended on its own, replayed for another target.
    """

    def __init__(self):
        self._done: dict[tuple, list] = {}
        self._walks: dict[tuple, tuple] = {}

    def jump(self, model, H, z_prev, omega_prev, omega_target, *, exhausted, **options):
        """:func:`~nlgrd.nonlinear.tracing.arclength.jump_to_branch`, or the stored result of the
        same failed search (``exhausted`` as it was then)."""
        key = (id(model), H, float(omega_prev), float(omega_target), tuple(sorted(options.items())))
        z_prev = np.asarray(z_prev, dtype=float)
        for z0, out, ex in self._done.get(key, ()):
            if z0.shape == z_prev.shape and np.array_equal(z0, z_prev):
                exhausted.extend(ex)
                return out
        out = jump_to_branch(
            model, H, z_prev, omega_prev, omega_target, exhausted=exhausted, walks=self._walks, **options
        )
        if out[0] is None:
            self._done.setdefault(key, []).append((z_prev.copy(), out, list(exhausted)))
        return out


def _pool(result: SweepResult, stability: bool) -> dict[float, list]:
    """{frequency: [(direction, harmonics)]} of a sweep's stable response points."""
    ok = result.converged & ~result.no_stable
    if stability:
        ok &= result.stable.astype(bool)
    pool: dict[float, list] = {}
    for i in np.nonzero(ok)[0]:
        pool.setdefault(float(result.omega[i]), []).append((str(result.direction[i]), result.harmonics[i]))
    return pool


def _sweep_pass(
    model,
    omegas,
    H,
    directions,
    *,
    method,
    tol,
    max_iter,
    fallback,
    stability,
    n_samples,
    z0,
    jump,
    chain,
    leave_unstable,
    progress,
    searches,
    pool=None,
):
    """One pass of :func:`sweep`; returns (result, landings after folds: (direction, w,
    previous harmonics, landing harmonics)). ``pool``: other directions' solutions, also
    candidates for a landing."""
    landings = []
    rows: dict[str, list] = {k: [] for k in ("w", "d", "z", "c", "r", "i", "f", "m", "j", "n", "u")}
    todo: list[tuple] = []  # (row, harmonics, ω, what the metrics need) whose metrics are due
    z_end = None
    orders = sweep_orders(omegas, directions)
    total, done = sum(len(o) for _, o in orders), 0
    for direction, order in orders:
        z, last_w = (z0 if z_end is None or not chain else z_end), None
        for k, w in enumerate(order):
            problem = model.at(float(w), H)
            try_jump = jump in ("arclength", "auto") and z is not None and last_w is not None
            sol: HarmonicSolution = solve(
                problem,
                z,
                method=method,
                tol=tol,
                max_iter=max_iter,
                fallback=fallback and not try_jump,
                stall=try_jump,
            )
            switched, z_prev = False, z
            auto = jump == "auto"

            others = partial(landing.pool_candidates, model, problem, pool, w, direction, tol, max_iter)
            if auto and sol.converged and try_jump and sol.iterations > WANDER_ITER:
                sol, switched = landing.follow_branch(
                    model, problem, sol, z, last_w, float(w), H, method, tol, max_iter, stability, others()
                )
            if not sol.converged and z is None and (zs := shooting_start(model, float(w), H)) is not None:
                sol = solve(problem, zs, method=method, tol=tol, max_iter=max_iter, fallback=False)
            if not sol.converged and z is None and jump != "none":
                sol = (
                    landing.approach(
                        model, problem, order, k, H, method, tol, max_iter, stability, direction=direction
                    )
                    or sol
                )
            restarts: list[HarmonicSolution] | None = None  # the restarts' unstable orbits, once run
            if not sol.converged and jump == "restart" and z is not None:
                restarts = []
                cand = landing.restart(model, problem, z, w, H, method, tol, max_iter, unstable=restarts)
                if cand is not None:
                    sol, switched = cand, True
                    try_jump = False
            searched = False  # the landing search has already looked for a stable orbit here
            if not sol.converged and try_jump:
                exhausted: list[bool] = []
                zj, steps, folds, unstable = searches.jump(
                    model, H, z, last_w, float(w), tol=tol, require_stable=stability, exhausted=exhausted
                )
                if zj is not None:
                    switched = folds > 0
                    sol = solve(problem, zj, method="newton", tol=tol, max_iter=max_iter, fallback=False)
                    sol = HarmonicSolution(
                        sol.omega,
                        sol.harmonics,
                        sol.converged,
                        sol.residual,
                        sol.iterations + steps,
                        "newton after arc-length jump",
                        sol.iterate,
                        sol.message,
                    )
                    if switched and auto:
                        sol = landing.nearest_landing(sol, z, others())
                elif auto and (
                    cand := landing.restart(
                        model, problem, z, w, H, method, tol, max_iter, unstable=(restarts := [])
                    )
                ):
                    sol, switched = cand, True
                    sol = landing.nearest_landing(sol, z, others())
                elif unstable is not None:  # no stable orbit found: report the unstable crossing
                    sol = solve(
                        problem, unstable, method="newton", tol=tol, max_iter=max_iter, fallback=False
                    )
                    switched, searched = folds > 0, auto
                else:  # Newton from the previous point without giving up early, then hybr
                    sol = solve(problem, z, method=method, tol=tol, max_iter=max_iter, fallback=fallback)
                    if not sol.converged and exhausted and restarts:  # the ceiling came before a crossing
                        sol = min(restarts, key=lambda c: landing.distance(c, z))
                        switched, searched = True, True
            if not sol.converged and auto and pool:  # the branch ended: another direction's orbit
                cands = others()
                if cands:
                    sol = min(cands, key=lambda c: 0.0 if z is None else landing.distance(c, z))
                    switched = z is not None
            if not sol.converged and z is not None and jump != "none":  # past a branch's end
                cand = landing.fresh_start(
                    model, problem, z, w, H, method, tol, max_iter, stability, tried=restarts
                )
                if cand is not None:
                    sol, switched = cand, True
            fmax, dom, lost = np.nan, complex(np.nan, np.nan), False
            if sol.converged:
                z, last_w = sol.harmonics, float(w)
                z_end = z
                ss = model.linear_state_space(w) if stability else None
                if ss is not None:
                    fmax, dom = dominant_multiplier(
                        floquet_multipliers(ss, model.nonlinearities, sol.harmonics, w)
                    )
                    if leave_unstable and fmax >= 1 + STABLE_RTOL:
                        fold = abs(dom.imag) <= 1e-6 * abs(dom) and dom.real > 0
                        cand = (
                            landing.restart(model, problem, z, w, H, method, tol, max_iter)
                            if fold and not searched
                            else None
                        )
                        if fold and auto:
                            for c in others():
                                if cand is None or landing.distance(c, z) < landing.distance(cand, z):
                                    cand = c
                        if cand is None:
                            lost = True
                        else:
                            sol, switched = cand, True
                            z = z_end = sol.harmonics
                            fmax, dom = dominant_multiplier(
                                floquet_multipliers(ss, model.nonlinearities, z, w)
                            )
            met = MeshMetrics.nan(H)  # the model's metrics: all points at once below
            if not lost:
                met = None
                zm = np.asarray(sol.harmonics, dtype=float)
                todo.append((len(rows["m"]), zm, float(w), model.metrics.intervals(zm)))
            for k, v in zip(
                "wdzcrifm",
                (w, direction, sol.harmonics, sol.converged, sol.residual, sol.iterations, fmax, met),
                strict=False,
            ):
                rows[k].append(v)
            rows["j"].append(switched)
            if switched and sol.converged and z_prev is not None:
                landings.append((direction, float(w), z_prev, sol.harmonics))
            rows["n"].append(lost)
            rows["u"].append(dom)
            done += 1
            if progress is not None:
                progress(done, total)
    if todo:
        at, zs, ws, ivs = zip(*todo, strict=True)
        mets = model.metrics.of_points(np.array(zs), np.array(ws), n_samples, ivs)
        for i, met in zip(at, mets, strict=True):
            rows["m"][i] = met
    result = assemble_result(
        rows["w"],
        rows["d"],
        rows["z"],
        rows["c"],
        rows["r"],
        rows["i"],
        rows["f"],
        rows["m"],
        f"harmonic balance (H={H}, {method})",
        rows["j"],
        rows["n"],
        rows["u"],
    )
    return result, landings
