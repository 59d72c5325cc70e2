"""Sweeps that answer beyond mesh-periodic motion (issue 12, items 2 and 6): the stable
period-1 orbit where there is one, the stable period-2 orbit where period 1 has lost
stability by period doubling, and where neither exists the point marked quasi-periodic
(a complex pair left the unit circle) or as having no stable response.

:func:`merge_periods` walks each sweep direction like the rig would: it stays on the
period-2 branch while that branch is stable (a subcritical period-2 branch outlives the
flip point, so the sweep keeps it until it ends, then falls back to period 1), and leaves
period 1 only where period 1 is unstable. :func:`transitions` lists the changes of
response along each sweep with their kind: period doubling, the end of a period-2
branch, a Neimark-Sacker (torus) bifurcation, the loss of every stable response.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.periods import amplitudes, period_of, spread, subharmonic_mask
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.results.sweep_results import SweepResult, response_kind
from nlgrd.nonlinear.stability.verdicts import converge_verdicts
from nlgrd.nonlinear.tracing.harmonic_convergence import check_harmonics, with_harmonic_error
from nlgrd.nonlinear.tracing.subharmonic import period_sweep

#: The values of ``period`` a sweep takes (orbits of 3 or more periods are searched for).
PERIODS = (1, 2, "auto")


@dataclass(frozen=True)
class Transition:
    """A change of the kind of response between two consecutive points of a sweep.

    Attributes
    ----------
    direction : str
        "up" or "down".
    omega_from, omega_to : float
        The last point of the old response and the first of the new [rad/s].
    response_from, response_to : str
        The response column's values at the two points.
    kind : str
        "period doubling", "period-2 branch ends", "Neimark-Sacker" (the orbit's complex
        pair left the unit circle), "fold" (a real multiplier > 1: the branch ends) or
        "stable again".
    """

    direction: str
    omega_from: float
    omega_to: float
    response_from: str
    response_to: str
    kind: str


def flip_unstable(result: SweepResult) -> NDArray:
    """Points whose orbit lost stability by period doubling (dominant real μ < -1).

    Parameters
    ----------
    result : SweepResult
        A sweep with stability.

    Returns
    -------
    ndarray of bool
    """
    mu = np.asarray(result.dominant_multiplier, dtype=complex)
    with np.errstate(invalid="ignore"):
        real = np.abs(mu.imag) <= 1e-6 * np.abs(mu)
        return result.converged & ~result.stable & real & (mu.real < -1)


def check_period(period, stability: bool) -> None:
    """Raise ModelError unless ``period`` is 1, 2 or "auto", and 2 has ``stability``.

    Parameters
    ----------
    period : object
        The ``period`` option of a sweep.
    stability : bool
        Whether the sweep computes Floquet multipliers.
    """
    if period not in PERIODS or isinstance(period, bool):
        more = isinstance(period, int) and not isinstance(period, bool) and period >= 3
        raise ModelError(
            "period",
            "orbits of 3 or more mesh periods are not reached by a sweep: search for them with "
            "nlgrd.nonlinear.tracing.orbit_search.search_orbits and follow them with follow_orbit (as nlgrd "
            f"sweep --period N does), got {period!r}"
            if more
            else f"1, 2 or 'auto', got {period!r}",
        )
    if period == 2 and not stability:
        raise ModelError("period", "period doubling is found from the Floquet multipliers: needs stability")


def beyond_period_one(
    p1: SweepResult,
    period: int | str,
    period_two_model: Callable[[], ReducedModel],
    omegas: ArrayLike,
    directions: str,
    H_check: int,
    rtol: float,
    *,
    tol: float = 1e-10,
    max_iter: int = 50,
) -> tuple[SweepResult, SweepResult | None]:
    """The period-2 sweep where ``p1`` is flip-unstable, merged with it or alone.

    The period-2 branches start from the critical mode where a period-1 orbit has a real
    multiplier < -1 (:func:`~nlgrd.nonlinear.tracing.subharmonic.period_sweep`, 2 H₁ harmonics of
    ω/2: as fine as period 1), with their own harmonic error estimate against
    ``H_check`` harmonics of ω/2 (points above ``rtol`` are not converged); with
    ``period`` "auto" they are merged with ``p1`` (:func:`merge_periods`). The same for
    every model: the single-mesh FE model, a link model, the single-DOF pair.

    Parameters
    ----------
    p1 : SweepResult
        The period-1 sweep with stability (frequencies of the base ω).
    period : {"auto", 2}
        "auto": merged, and ``p1`` itself when no point is flip-unstable; 2: the period-2
        branches alone (:func:`period_only`).
    period_two_model : callable () -> ReducedModel
        The model on the base ω/2 (every excitation at even harmonics), built only when needed.
    omegas : array_like
        The base frequencies ω of ``p1`` [rad/s].
    directions : {"both", "up", "down"}
        Sweep directions.
    H_check : int
        Harmonics of ω/2 of the error estimate [-] (> 2 H₁).
    rtol : float
        Largest accepted estimated relative error of the period-2 outputs [-].
    tol, max_iter : float, int
        Newton's tolerance (relative residual) and iteration limit.

    Returns
    -------
    result : SweepResult
        The answer: ``p1``, the merged sweep, or the period-2 branches alone.
    p2 : SweepResult or None
        The period-2 sweep (frequencies ω, harmonics of ω/2, its error estimate), None when
        not run.
    """
    if period == "auto" and not np.any(flip_unstable(p1)):
        return p1, None
    model2 = period_two_model()
    p2 = period_sweep(model2, omegas, 2 * p1.H, 2, p1, directions, tol=tol, max_iter=max_iter)
    on_base = replace(p2, omega=p2.omega / 2)  # the frequencies model2 takes
    check = check_harmonics(model2, on_base, H_check, tol=tol, jumps=False)
    on_base = converge_verdicts(model2, with_harmonic_error(on_base, check, rtol), check.solutions, tol=tol)
    p2 = replace(on_base, omega=p2.omega)
    return (period_only(p2) if period == 2 else merge_periods(p1, p2)), p2


def rows_of(p1: SweepResult, p2: SweepResult) -> NDArray:
    """For each point of ``p1``, the row of ``p2`` at the same frequency and direction.

    Parameters
    ----------
    p1, p2 : SweepResult
        Sweeps on the same grid and directions.

    Returns
    -------
    ndarray of int
    """
    index2 = {(d, float(w)): i for i, (d, w) in enumerate(zip(p2.direction, p2.omega, strict=True))}
    return np.array([index2[(d, float(w))] for d, w in zip(p1.direction, p1.omega, strict=True)], dtype=int)


def merge_periods(p1: SweepResult, p2: SweepResult) -> SweepResult:
    """One response per point from a period-1 sweep and a period-2 sweep on the same grid.

    Parameters
    ----------
    p1 : SweepResult
        Period-1 sweep with stability (harmonics of ω, H₁ of them).
    p2 : SweepResult
        Period-2 sweep (:func:`nlgrd.nonlinear.tracing.subharmonic.period_sweep`) at the same
        frequencies and directions, harmonics of ω/2.

    Returns
    -------
    SweepResult
        Harmonics of ω/2 for every point (period-1 orbits spread onto it), ``period`` 1 or 2,
        ``subharmonic_amplitude`` the ω/2 content, ``amplitudes`` and metrics those of the
        chosen orbit (amplitudes at the mesh harmonics); ``no_stable`` where neither is
        stable (:attr:`SweepResult.secondary_frequency` then marks a torus).
    """
    H2 = p2.H_stored
    n = len(p1)
    rows2 = rows_of(p1, p2)
    found2 = np.array([c and period_of(z, 2) == 2 for z, c in zip(p2.harmonics, p2.converged, strict=True)])
    found2 = found2[rows2]
    ok1 = p1.converged & p1.stable & ~p1.no_stable
    ok2 = found2 & p2.stable[rows2]
    pick2 = np.zeros(n, dtype=bool)
    for d in dict.fromkeys(p1.direction.tolist()):
        on2 = prev2 = False
        for i in np.nonzero(p1.direction == d)[0]:
            on2 = bool(ok2[i] and (on2 or not ok1[i]))
            # neither stable: the row answers with the orbit the sweep was on, the period-2
            # one only where the point before answered with it (what grows from it: a torus,
            # period 4); elsewhere the period-1 orbit and its own multipliers
            pick2[i] = prev2 = on2 or bool(prev2 and not ok1[i] and found2[i])
    no_stable = np.where(pick2, ~ok2, p1.no_stable | (p1.converged & ~p1.stable))

    def rows(a1, a2):
        return np.where(pick2.reshape((-1,) + (1,) * (np.ndim(a1) - 1)), a2[rows2], a1)

    width = max(p1.amplitudes.shape[1], (p2.amplitudes.shape[1] + 1) // 2)
    amps = rows(_pad_columns(p1.amplitudes, width), _pad_columns(p2.amplitudes[:, ::2], width))
    sub = np.zeros(n)
    odd = subharmonic_mask(H2, 2)[1::2]  # the cosine slots of ω/2, 3ω/2, ...
    for i in np.nonzero(pick2 & ~no_stable)[0]:
        sub[i] = float(np.max(amplitudes(p2.harmonics[rows2[i]])[:, odd]))
    return SweepResult(
        p1.omega,
        p1.direction,
        rows(np.array([_on_base(z, H2) for z in p1.harmonics]), p2.harmonics),
        rows(p1.converged, p2.converged),
        rows(p1.residual, p2.residual),
        rows(p1.iterations, p2.iterations),
        rows(p1.stable, p2.stable),
        rows(p1.floquet_max, p2.floquet_max),
        {k: rows(v, p2.metrics[k]) for k, v in p1.metrics.items()},
        amps,
        f"{p1.source}; period 2 where period 1 is flip-unstable ({p2.source})",
        rows(p1.branch_switch, p2.branch_switch),
        rows(p1.harmonic_error, p2.harmonic_error),
        p1.H_check,
        no_stable,
        rows(p1.dominant_multiplier, p2.dominant_multiplier),
        p1.residual_kind,
        np.where(pick2, 2, 1),
        sub,
        2,
        verdict_converged=rows(p1.verdict_converged, p2.verdict_converged),
    )


def _pad_columns(a: NDArray, width: int) -> NDArray:
    return np.pad(a, ((0, 0), (0, width - a.shape[1])), constant_values=np.nan)


def _on_base(z: NDArray, H2: int) -> NDArray:
    """Period-1 harmonics (n, 2H₁+1) of ω as H2 harmonics of ω/2 (cut or padded)."""
    s = spread(z, 2)[:, : 2 * H2 + 1]
    return np.pad(s, ((0, 0), (0, 2 * H2 + 1 - s.shape[1])))


def transitions(result: SweepResult) -> list[Transition]:
    """The changes of response along each sweep direction, in sweep order, with their kind.

    Parameters
    ----------
    result : SweepResult
        A sweep with stability (e.g. from :func:`merge_periods`).

    Returns
    -------
    list of Transition
    """
    kinds = response_kind(result)
    out = []
    for d in dict.fromkeys(result.direction.tolist()):
        # a point whose stability verdict did not converge tells no change: skipped
        idx = np.nonzero((result.direction == d) & result.converged & result.verdict_converged)[0]
        for i, j in zip(idx[:-1], idx[1:], strict=True):
            if kinds[i] == kinds[j]:
                continue
            out.append(
                Transition(
                    d,
                    float(result.omega[i]),
                    float(result.omega[j]),
                    kinds[i],
                    kinds[j],
                    _kind(result, kinds, i, j),
                )
            )
    return out


def _kind(result: SweepResult, kinds: NDArray, i: int, j: int) -> str:
    if result.period[j] > result.period[i] and not result.no_stable[j]:
        return "period doubling"
    stable_i, stable_j = not result.no_stable[i], not result.no_stable[j]
    if stable_i and stable_j and result.period[j] < result.period[i]:
        return "period-2 branch ends"
    if not result.no_stable[j]:
        return "stable again"
    mu = complex(result.dominant_multiplier[j])
    if np.isfinite(result.secondary_frequency[j]):
        return "Neimark-Sacker"
    return "period doubling" if mu.real < -1 else "fold"


def period_only(p2: SweepResult, nu: int = 2) -> SweepResult:
    """A period-ν sweep as a response: its period-ν orbits, every other point not found.

    Parameters
    ----------
    p2 : SweepResult
        From :func:`nlgrd.nonlinear.tracing.subharmonic.period_sweep` or
        :func:`~nlgrd.nonlinear.tracing.subharmonic.follow_period` with this ν.
    nu : int
        Mesh periods of its orbits [-].

    Returns
    -------
    SweepResult
        ``period`` ν, ``base`` ν (``H_check`` counted as ``H``, of ω), ``amplitudes`` at the
        mesh harmonics, ``subharmonic_amplitude`` the largest component at a base harmonic
        that is not a multiple of ν; a point whose orbit fell back to a shorter period or
        was not found is not converged; an unstable one has ``no_stable``.
    """
    found = np.array([c and period_of(z, nu) == nu for z, c in zip(p2.harmonics, p2.converged, strict=True)])
    odd = subharmonic_mask(p2.H_stored, nu)[1::2]
    sub = np.array(
        [
            float(np.max(amplitudes(z)[:, odd], initial=0.0)) if f else np.nan
            for z, f in zip(p2.harmonics, found, strict=True)
        ]
    )
    return replace(
        p2,
        converged=found,
        stable=p2.stable & found,
        amplitudes=p2.amplitudes[:, ::nu],
        no_stable=found & ~p2.stable,
        period=np.full(len(p2), nu),
        subharmonic_amplitude=sub,
        base=nu,
        H_check=None if p2.H_check is None else p2.H_check * p2.base // nu,  # of ω, as H
    )
