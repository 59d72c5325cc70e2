"""The number of harmonics chosen by an error estimate (issue 10 item 1).

A harmonic-balance solution with H harmonics is in error by the harmonics it leaves out
and by what leaving them out does to those it keeps. For a piecewise-linear force law the
harmonics of the response decay algebraically, not exponentially (the force has kinks
where contact is lost), so no fixed H is converged everywhere: Kubo's rig at its Table 1
damping needs H >= 9 near its superharmonic peaks, while the paper's H = 5 suffices far
from them.

The estimate (:func:`check_harmonics`): every accepted point of a sweep at H is solved
again at the next H' of :data:`LADDER`, by Newton started from its own solution padded
with zero harmonics (a few iterations, and on the same branch). The relative change of
the model's outputs (``ReducedModel.outputs``: every mesh's RMS DTE and maximum force,
every clearance's largest force and displacement; each relative to max(|value|,
:data:`FLOOR` x its largest value over the sweep)) estimates the error of the H solution;
since the error falls fast with H it bounds the error of H' too (it is the error of H
minus that of H'). A point where Newton at H' fails or lands far away has no solution on
that branch at H': its error counts as infinite. Each jump is checked as well: the
branch the sweep left is continued one grid step further at H'; if it exists there and
is stable, H' would jump later and the jump is off by at least one grid step.

:func:`converged_sweep` climbs the ladder until the estimate is within ``rtol`` (default
0.5 %) at every accepted point and every jump holds, and returns that sweep with the
estimate stored per point. Only the first rung is swept point by point (with its jumps);
the next rung is the check's re-solved points (:func:`lift`) when they stay on the same
branches (the same branch signature, each contact's fractions of the period, to 0.05, or
else the orbit a sweep step at H' from the lifted point before reaches; the same
stability; every jump held), for every model, else a fresh sweep. Points still above
``rtol`` at the top of the ladder are returned as not converged (their outputs are not the
converged answer) with a :class:`HarmonicsWarning`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.results.metrics import MeshMetrics
from nlgrd.nonlinear.results.sweep_results import (
    STABLE_RTOL,
    SweepResult,
    assemble_result,
    dominant_multiplier,
)
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.stability.verdicts import converge_verdicts
from nlgrd.nonlinear.tracing.harmonic_ladder import LADDER, ladder_for
from nlgrd.nonlinear.tracing.landing import WANDER_ITER, same_orbit
from nlgrd.nonlinear.tracing.sweep import sweep

#: Default output tolerance: RMS DTE and maximum mesh force within 0.5 %.
OUTPUT_RTOL = 5e-3
#: A value below FLOOR x its sweep maximum is compared relative to that floor: an RMS DTE
#: of 1 % of the resonance peak, far from resonance, needs no 0.5 % of itself.
FLOOR = 1e-2
#: A continuation's fold is located to this relative frequency (see :func:`_fold_band`).
FOLD_RTOL = 1e-3
#: A point lifted to H' whose branch signature (contact fractions) moved by more than this
#: may be on another branch: it is kept only if a sweep step at H' reaches it
#: (:func:`lift`), else the next rung is swept afresh.
SIGNATURE_ATOL = 0.05
#: The check at H' polishes a solution that is already close: few Newton iterations.
CHECK_MAX_ITER = 30


class HarmonicsWarning(UserWarning):
    """The harmonic ladder ended before the estimate met the tolerance."""


@dataclass(frozen=True)
class HarmonicCheck:
    """The estimate of a sweep's harmonic truncation error against H' = ``H_check``.

    ``error`` per point (NaN where the point was not checked: not converged, or unstable);
    ``jumps_held`` whether every jump is also a jump at H'; ``history`` the ladder steps
    as (H, largest error, jumps held).

    Attributes
    ----------
    H : int
        Number of harmonics of the result checked.
    H_check : int
        The larger number of harmonics H' it was re-solved at.
    error : ndarray
        Estimated relative error of the outputs per point [-]: NaN where not checked, inf
        where no solution on the branch was found at H'.
    jumps_held : bool
        Every jump of the result is also a jump at H'.
    history : tuple
        The ladder steps as (H, largest error, jumps held).
    solutions : dict
        {row index: HarmonicSolution at H' or None} of every converged point re-solved.
    """

    H: int
    H_check: int
    error: NDArray
    jumps_held: bool
    history: tuple
    solutions: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def max_error(self) -> float:
        """Largest estimated relative error over the checked points (0 if none)."""
        e = self.error[np.isfinite(self.error) | np.isinf(self.error)]
        return float(np.max(e)) if e.size else 0.0

    def passed(self, rtol: float) -> bool:
        """Every checked point within ``rtol`` and every jump held."""
        return self.jumps_held and self.max_error <= rtol


def next_harmonics(H: int, ladder: Sequence[int] = LADDER) -> int:
    """The H' a solution with H harmonics is checked against: the next rung (1.5 H above the top).

    Parameters
    ----------
    H : int
        Number of harmonics of the solution.
    ladder : sequence of int
        Increasing harmonic counts (default :data:`LADDER`).

    Returns
    -------
    int
        The first rung above ``H``, or ceil(1.5 H) when ``H`` is at or above the top.
    """
    above = [h for h in ladder if h > H]
    return above[0] if above else int(np.ceil(1.5 * H))


def pad_harmonics(z: ArrayLike, H_new: int) -> NDArray:
    """Real harmonics (n, 2H+1) [c_0, a_1, b_1, ...] extended (zeros) or cut to H_new.

    Parameters
    ----------
    z : array_like
        Real harmonics [x0, a1, b1, ...], shape (n_nl, 2H+1) or (2H+1,) for one
        coordinate [m].
    H_new : int
        Number of harmonics of the result.

    Returns
    -------
    ndarray
        Shape (n_nl, 2 H_new + 1), same unit as ``z`` [m].
    """
    z = np.atleast_2d(np.asarray(z, dtype=float))
    out = np.zeros((z.shape[0], 2 * H_new + 1))
    m = min(z.shape[1], out.shape[1])
    out[:, :m] = z[:, :m]
    return out


def _resolve(model: ReducedModel, w: float, z: NDArray, H_new: int, tol: float):
    sol = solve(
        model.at(w, H_new),
        pad_harmonics(z, H_new),
        method="newton",
        tol=tol,
        max_iter=CHECK_MAX_ITER,
        fallback=False,
    )
    return sol if sol.converged else None


def _outputs(model: ReducedModel, z: NDArray, w: float) -> NDArray:
    return np.asarray(model.outputs(z, w), dtype=float)


def check_harmonics(
    model: ReducedModel,
    result: SweepResult,
    H_check: int | None = None,
    *,
    tol: float = 1e-10,
    rtol: float = OUTPUT_RTOL,
    jumps: bool = True,
    progress=None,
) -> HarmonicCheck:
    """Estimate the harmonic truncation error of ``result`` by re-solving at ``H_check``.

    See the module docstring. Points checked: converged, and stable where stability was
    computed (an unstable point is not the response). ``jumps=False`` skips the jump
    check (a continuation curve has folds, not jumps).

    Parameters
    ----------
    model : ReducedModel
        The model the result was solved on.
    result : SweepResult
        The sweep (or continuation curve) at H.
    H_check : int, optional
        The H' to re-solve at (> H); default :func:`next_harmonics` of H.
    tol : float
        Convergence tolerance of Newton at H' (relative residual).
    rtol : float
        Relative tolerance of the jump check: the branch left, continued at H', matches
        the point after the jump within ``rtol``.
    jumps : bool
        Check that every jump holds at H'.
    progress : callable, optional
        ``progress(done, total)`` after each converged point re-solved at H'.

    Returns
    -------
    HarmonicCheck
        The error estimate per point, the jump verdict and the H' solutions.

    Raises
    ------
    ModelError
        ``H_check`` not above the result's H.
    """
    H = (result.harmonics.shape[-1] - 1) // 2
    H2 = next_harmonics(H) if H_check is None else int(H_check)
    if H2 <= H:
        raise ModelError("H_check", f"must exceed the sweep's H = {H}, got {H2}")
    n = len(result)
    checked = result.converged & (result.stable | ~result.stability_known)
    # the model's outputs (every link's), NaN where not checked
    ref = next((i for i in np.nonzero(checked)[0]), None)
    m = 0 if ref is None else _outputs(model, result.harmonics[ref], float(result.omega[ref])).size
    values = np.full((n, m), np.nan)
    for i in np.nonzero(checked)[0]:
        values[i] = _outputs(model, result.harmonics[i], float(result.omega[i]))
    scale = (
        FLOOR * np.nanmax(np.where(checked[:, None], np.abs(values), np.nan), axis=0)
        if checked.any()
        else 1.0
    )
    error = np.full(n, np.nan)
    fine_values = np.full_like(values, np.nan, dtype=float)
    sols: dict = {}  # every converged point re-solved (the unstable ones for lifting only)
    rows = np.nonzero(result.converged)[0]
    for done, i in enumerate(rows, 1):
        w = float(result.omega[i])
        sols[i] = sol = _resolve(model, w, result.harmonics[i], H2, tol)
        if progress is not None:
            progress(done, rows.size)
        if not checked[i]:
            continue
        if sol is None:
            error[i] = np.inf
            continue
        fine_values[i] = _outputs(model, sol.harmonics, w)
    # an output that is zero over the whole sweep at H (a contact force where the journal
    # never touches) is measured against its values at H'; zero at both, it carries nothing
    top = np.max(np.where(np.isnan(fine_values), 0.0, np.abs(fine_values)), axis=0, initial=0.0)
    scale = np.maximum(np.where(np.asarray(scale) > 0, scale, FLOOR * top), np.finfo(float).tiny)
    if model.output_scales is not None and values.shape[1]:  # a physical scale: the clearance
        scale = np.maximum(scale, FLOOR * np.asarray(model.output_scales, dtype=float))
    for i in np.nonzero(~np.all(np.isnan(fine_values), axis=1))[0]:
        v2 = fine_values[i]
        error[i] = float(np.max(np.abs(v2 - values[i]) / np.maximum(np.abs(v2), scale)))
    fine = {i: sol.harmonics for i, sol in sols.items() if sol is not None and checked[i]}
    starts = _jump_starts(result) if jumps else []
    left = {i: sol.harmonics for i, sol in sols.items() if sol is not None}
    held = all(_jump_holds(model, result, i, left, fine, H2, tol, rtol) for i in starts)
    err_max = float(np.max(error[~np.isnan(error)])) if np.any(~np.isnan(error)) else 0.0
    return HarmonicCheck(H, H2, error, held, ((H, err_max, held),), sols)


def _jump_starts(result: SweepResult) -> list[int]:
    """Row indices i (in sweep order) with a jump from i to i + 1 of the same direction."""
    starts = []
    for j in result.jumps():
        rows = np.nonzero((result.direction == j.direction) & (result.omega == j.omega_from))[0]
        if rows.size and rows[0] + 1 < len(result) and result.direction[rows[0] + 1] == j.direction:
            starts.append(int(rows[0]))
    return starts


def _jump_holds(model, result, i, left, fine, H2, tol, rtol) -> bool:
    """False when the branch left at row i continues, stable, to row i + 1 at H2.

    ``left``: the H2 solutions of every converged row (the unstable ones too: a sweep
    leaving a range without a stable response jumps from an unstable orbit); ``fine``:
    those of the checked rows."""
    if i not in left:
        return True  # the point before the jump failed at H2 (counted there when checked)
    w = float(result.omega[i + 1])
    sol = _resolve(model, w, left[i], H2, tol)
    if sol is None:
        return True  # the branch folds at H2 too
    z = sol.harmonics
    ss = model.linear_state_space(w)
    if (
        ss is not None
        and np.max(np.abs(floquet_multipliers(ss, model.nonlinearities, z, w))) >= 1 + STABLE_RTOL
    ):
        return True  # it exists but is unstable: a slow sweep leaves it at H2 as well
    after = fine.get(i + 1)
    if after is None:
        return False
    v, v_after = _outputs(model, z, w), _outputs(model, after, w)
    return bool(np.all(np.abs(v - v_after) <= rtol * np.maximum(np.abs(v_after), 1e-300)))


def _swept_to(model: ReducedModel, w: float, z_before: NDArray | None, z: NDArray, tol: float) -> bool:
    """Whether the sweep step at ``w`` from the orbit ``z_before`` (the lifted point before,
    same direction) reaches ``z``: Newton converges within WANDER_ITER iterations (the sweep
    accepts it without a branch check) to the same orbit."""
    if z_before is None:
        return False
    sol = solve(model.at(w, (z.shape[-1] - 1) // 2), z_before, tol=tol, max_iter=WANDER_ITER, fallback=False)
    return bool(sol.converged and same_orbit(sol.harmonics, z))


def lift(
    model: ReducedModel, result: SweepResult, check: HarmonicCheck, stability: bool, tol: float = 1e-10
) -> SweepResult | None:
    """The sweep at ``check.H_check`` from the check's re-solved points, or None when a
    full sweep is needed: a converged point that has no solution near it at H', a point
    whose branch signature (``model.branch_signature``: each contact's fraction of the
    period in each state) moved by more than 0.05 and that the sweep step at H' from the
    lifted point before does not reach (:func:`_swept_to`: a contact fraction that grows
    with H on the same branch is kept, another branch is not), a point whose stability
    changed (the branch structure differs), or a jump that does not hold. Each point is
    then the H' solution on the branch the sweep chose, as a sweep at H' would find it.
    Serves every model.

    Parameters
    ----------
    model : ReducedModel
        The model the sweep was solved on.
    result : SweepResult
        The sweep at H.
    check : HarmonicCheck
        Its check against H' (:func:`check_harmonics`), with the re-solved points.
    stability : bool
        Compute Floquet multipliers at H' (and compare stability with ``result``).
    tol : float
        Convergence tolerance of the sweep step's Newton (relative residual).

    Returns
    -------
    SweepResult or None
        The sweep at H'; None when a full sweep at H' is needed.
    """
    if not check.jumps_held:
        return None
    H2 = check.H_check
    n = len(result)
    z = np.full((n, *pad_harmonics(result.harmonics[0], H2).shape), np.nan)
    residual, iterations, fmax = np.full(n, np.nan), np.zeros(n, dtype=int), np.full(n, np.nan)
    dominant = np.full(n, np.nan + 0j)
    metrics = []
    before: dict[str, int] = {}  # the last converged row of each direction
    for i in range(n):
        w = float(result.omega[i])
        if not result.converged[i]:
            metrics.append(MeshMetrics.nan(H2))
            continue
        sol = check.solutions.get(i)
        if sol is None:
            return None
        j = before.get(result.direction[i])
        before[result.direction[i]] = i
        if not result.no_stable[i]:  # the response's branch (an unstable orbit is not one)
            moved = model.branch_signature(sol.harmonics, w) - model.branch_signature(result.harmonics[i], w)
            if np.max(np.abs(moved), initial=0.0) > SIGNATURE_ATOL and not _swept_to(
                model, w, None if j is None else z[j], sol.harmonics, tol
            ):
                return None
        ss = model.linear_state_space(w) if stability else None
        if ss is not None:
            fmax[i], dominant[i] = dominant_multiplier(
                floquet_multipliers(ss, model.nonlinearities, sol.harmonics, w)
            )
            if result.stability_known[i] and (fmax[i] < 1 + STABLE_RTOL) != bool(result.stable[i]):
                return None
        z[i], residual[i], iterations[i] = sol.harmonics, sol.residual, sol.iterations
        metrics.append(MeshMetrics.nan(H2) if result.no_stable[i] else model.metrics.of(sol.harmonics, w))
    source = result.source.replace(f"H={result.H_stored},", f"H={H2},", 1)
    return assemble_result(
        result.omega,
        result.direction,
        z,
        result.converged,
        residual,
        iterations,
        fmax,
        metrics,
        source,
        result.branch_switch,
        result.no_stable,
        dominant,
    )


def with_harmonic_error(result: SweepResult, check: HarmonicCheck, rtol: float) -> SweepResult:
    """``result`` with the estimate stored per point; points above ``rtol`` not converged.

    Parameters
    ----------
    result : SweepResult
        The sweep checked.
    check : HarmonicCheck
        Its check (:func:`check_harmonics`).
    rtol : float
        Largest accepted estimated relative error.

    Returns
    -------
    SweepResult
        ``result`` with ``harmonic_error`` and ``H_check`` set; points above ``rtol`` are
        marked not converged and not stable.
    """
    with np.errstate(invalid="ignore"):
        bad = result.converged & (check.error > rtol)  # NaN compares False
    return replace(
        result,
        converged=result.converged & ~bad,
        stable=result.stable & ~bad,
        harmonic_error=check.error,
        H_check=check.H_check,
    )


def converged_sweep(
    model: ReducedModel,
    omegas: ArrayLike,
    directions: str | Sequence[str] = "both",
    *,
    rtol: float = OUTPUT_RTOL,
    ladder: Sequence[int] | None = None,
    tol: float = 1e-10,
    stability: bool = True,
    on_rung=None,
    **kwargs,
) -> SweepResult:
    """:func:`nlgrd.nonlinear.tracing.sweep.sweep` with H climbing ``ladder`` until :func:`check_harmonics`
    holds to ``rtol``; the returned result carries the estimate per point
    (``harmonic_error``) and the H it was checked against (``H_check``).

    The last rung only checks the one before (the highest H solved is ``ladder[-1]``).
    ``on_rung(H)`` is called before each sweep; ``kwargs`` go to :func:`sweep`.

    Parameters
    ----------
    model : ReducedModel
        The harmonic-balance model as a function of the mesh frequency.
    omegas : array_like
        Mesh frequencies [rad/s].
    directions : "up", "down", "both" or a sequence of them
        The sweeps (see :func:`nlgrd.nonlinear.tracing.sweep.sweep`).
    rtol : float
        Tolerance of the estimated relative error of RMS DTE and maximum mesh force, in
        (0, 1).
    ladder : sequence of int, optional
        Increasing harmonic counts tried, at least two; default :func:`ladder_for` the
        model (bounded by memory). Above :data:`LADDER` the climb stops where the
        estimate no longer falls (by 10 % a rung): more harmonics do not converge it.
    tol : float
        Convergence tolerance of the solver (relative residual).
    stability : bool
        Floquet multipliers per point.
    on_rung : callable, optional
        ``on_rung(H)``, called before each rung.
    **kwargs
        Further options of :func:`nlgrd.nonlinear.tracing.sweep.sweep`.

    Returns
    -------
    SweepResult
        The sweep at the chosen H, with ``harmonic_error`` and ``H_check``; points above
        ``rtol`` at the top of the ladder are marked not converged.

    Raises
    ------
    ModelError
        A ladder that is not increasing positive counts or has fewer than two, or
        ``rtol`` outside (0, 1).

    Warns
    -----
    HarmonicsWarning
        The ladder ended before the estimate met ``rtol``.
    """
    if ladder is None:
        ladder = ladder_for(model)
    if not ladder or any(int(h) < 1 for h in ladder) or list(ladder) != sorted(set(ladder)):
        raise ModelError("ladder", f"must be increasing positive harmonic counts, got {tuple(ladder)}")
    if not 0 < rtol < 1:
        raise ModelError("rtol", f"must lie in (0, 1), got {rtol}")
    if len(ladder) < 2:
        raise ModelError(
            "ladder", f"needs at least two harmonic counts (the last only checks), got {tuple(ladder)}"
        )
    history = []
    res = None
    shot: dict = {}  # exact orbits shot for the verdicts, kept across the rungs
    progress = kwargs.get("progress")
    label = getattr(progress, "label", None)  # a progress bar's label names the phase
    for H, H_check in zip(ladder[:-1], ladder[1:], strict=True):
        if on_rung is not None:
            on_rung(H)
        if res is None:
            res = sweep(model, omegas, H, directions, tol=tol, stability=stability, **kwargs)
        if label is not None:
            progress.label = f"check of H = {H} at H = {H_check}"
        check = check_harmonics(model, res, H_check, tol=tol, rtol=rtol, progress=progress)
        if stability:  # the error is over the response's points: known by converged verdicts
            if label is not None:
                progress.label = f"stability verdicts at H = {H}"
            settled = converge_verdicts(
                model, res, check.solutions, ladder=ladder, tol=tol, polished=shot, progress=progress
            )
            changed = np.any(settled.stable != res.stable)
            res = settled
            if changed:
                check = check_harmonics(model, res, H_check, tol=tol, rtol=rtol)
        if label is not None:
            progress.label = label
        history.append(check.history[0])
        if check.passed(rtol):
            break
        if H > LADDER[-1] and check.max_error > 0.9 * history[-2][1]:
            _warn_exhausted(check, rtol)
            break
        if H_check != ladder[-1]:  # the next rung: lifted from the check, else swept afresh
            res = lift(model, res, check, stability, tol)
    else:
        _warn_exhausted(check, rtol)
    return _finish(res, check, history, rtol)


def _warn_exhausted(check: HarmonicCheck, rtol: float) -> None:
    warnings.warn(
        f"harmonics: at H = {check.H} the estimated relative error is {check.max_error:.3g} "
        f"(tolerance {rtol:g}){'' if check.jumps_held else ', and a jump moves at higher H'}; "
        "points above the tolerance are marked not converged",
        HarmonicsWarning,
        stacklevel=3,
    )


def _finish(res: SweepResult, check: HarmonicCheck, history: list, rtol: float) -> SweepResult:
    """``res`` with the ladder's steps in its source and the estimate per point."""
    steps = ", ".join(f"H = {h}: {e:.2g}" + ("" if ok else " (a jump moves)") for h, e, ok in history)
    res = replace(res, source=f"{res.source}; H chosen by error estimate, tolerance {rtol:g} ({steps})")
    return with_harmonic_error(res, replace(check, history=tuple(history)), rtol)


def _fold_band(check: HarmonicCheck, res) -> HarmonicCheck:
    """Points within FOLD_RTOL (relative frequency) of a turning point that have no
    solution nearby at H' are not counted: the tracer crowds points at a fold, and any
    shift of the fold leaves one of them without a solution. A fold that moves further
    leaves points outside the band without one, and counts."""
    turns = np.asarray(res.turning_omegas, dtype=float)
    if turns.size == 0:
        return check
    w = res.curve.omega
    near = np.min(np.abs(w[:, None] - turns[None, :]), axis=1) <= FOLD_RTOL * w
    error = np.where(near & np.isinf(check.error), np.nan, check.error)
    finite = error[~np.isnan(error)]
    err_max = float(np.max(finite)) if finite.size else 0.0
    return replace(check, error=error, history=((check.H, err_max, check.jumps_held),))


def converged_continuation(
    model: ReducedModel,
    omega_start: float,
    omega_end: float,
    *,
    rtol: float = OUTPUT_RTOL,
    ladder: Sequence[int] = LADDER,
    **kwargs,
):
    """:func:`nlgrd.nonlinear.tracing.continuation.continuation` with H climbing ``ladder`` until the stable
    points of the curve pass :func:`check_harmonics` (a stable point next to a fold that
    moves at higher H has no solution there: the fold is not converged either).

    Returns the :class:`~nlgrd.nonlinear.tracing.continuation.ContinuationResult` with the estimate per point.

    Parameters
    ----------
    model : ReducedModel
        The harmonic-balance model as a function of the mesh frequency.
    omega_start, omega_end : float
        Frequency range of the curve [rad/s].
    rtol : float
        Tolerance of the estimated relative error of RMS DTE and maximum mesh force.
    ladder : sequence of int
        Increasing harmonic counts tried, at least two.
    **kwargs
        Further options of :func:`nlgrd.nonlinear.tracing.continuation.continuation` (its ``tol``,
        default 1e-9, is also that of the check).

    Returns
    -------
    ContinuationResult
        The curve at the chosen H, its points carrying ``harmonic_error`` and ``H_check``.

    Raises
    ------
    ModelError
        A ladder that is not increasing or has fewer than two counts.

    Warns
    -----
    HarmonicsWarning
        The ladder ended before the estimate met ``rtol``.
    """
    from nlgrd.nonlinear.tracing.continuation import continuation

    if len(ladder) < 2 or list(ladder) != sorted(set(ladder)):
        raise ModelError("ladder", f"must be at least two increasing harmonic counts, got {tuple(ladder)}")
    tol = kwargs.get("tol", 1e-9)
    history = []
    progress = kwargs.get("progress")
    label = getattr(progress, "label", None)  # a progress bar's label names the rung
    for H, H_check in zip(ladder[:-1], ladder[1:], strict=True):
        if label is not None:
            progress.label = f"{label} (H = {H})"
        res = continuation(model, omega_start, omega_end, H, **kwargs)
        if label is not None:
            progress.label = f"check of H = {H} at H = {H_check}"
        check = check_harmonics(model, res.curve, H_check, tol=tol, rtol=rtol, jumps=False, progress=progress)
        check = _fold_band(check, res)
        history.append(check.history[0])
        if check.passed(rtol):
            break
    else:
        _warn_exhausted(check, rtol)
    curve = _finish(res.curve, check, history, rtol)
    if kwargs.get("stability", True):
        if label is not None:
            progress.label = f"{label}: stability verdicts"
        settled = converge_verdicts(model, curve, check.solutions, ladder=ladder, tol=tol, progress=progress)
        curve = replace(settled, no_stable=curve.no_stable)  # a curve draws its unstable parts
    return replace(res, curve=curve)
