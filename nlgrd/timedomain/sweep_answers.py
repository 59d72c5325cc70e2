"""A sweep's gaps answered: :func:`answer_sweep` is the rule every sweep follows. On a
sweep (any model) a point whose orbit lost stability to a complex pair is first answered
by the torus harmonic balance where it converges within the sweep's tolerance
(:func:`with_torus_answers`: "quasi-periodic", its stability not computed); then in the
time domain (:func:`with_time_answers`): every point where the harmonic balance
converged on an orbit but no stable periodic response exists (``no_stable``: quasi-periodic
or none) gets the statistics of :func:`nlgrd.timedomain.time_answer.time_answer`, started
from that unstable orbit (its mesh-periodic part), and its ``response`` becomes
"time domain" or "chaotic" with the values' sampling uncertainty beside them. A record
that settled on a period-1 motion (its last period
repeats the one before to 1e-3 of each link coordinate's range; its transient cut in the
first half or not: a slow approach to an orbit) is polished
(:mod:`nlgrd.timedomain.settled_orbits`): the harmonic balance at the sweep's H solved
from the last period's harmonics, its Floquet verdict, and, where the sweep chose H, its
truncation estimate; where it converges, is stable, meets the sweep's tolerance and lies
within 0.1 of each coordinate's range of the record (the integrator's step error), the
row is that orbit ("periodic", its values and multipliers, no uncertainty), else the
time answer stands (or the point stays unanswered). So a speed is answered by a stable
periodic orbit wherever the integration from the sweep's unstable one finds it
(two_shaft at 1730.8 Hz: tests/test_moved_verdicts.py).

A point whose harmonic balance did not converge stays "not converged" (no orbit to start
from); a point whose transient outlasts the record (its MSER-5 cut in the record's
second half at ``max_periods``, or at twice that where a decision sat within noise of its
threshold) stays unanswered, unless that record settled on a stable orbit (above). The
linear bearings' displacements and forces are recorded along the integration
(:mod:`nlgrd.timedomain.bearing_record`), so a time-answered row has the same bearing
columns as a periodic one, each with its uncertainty.
"""

from __future__ import annotations

import dataclasses as dc
from collections.abc import Callable

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.models.link_model import LinkModel
from nlgrd.nonlinear.results.link_results import LinkSweepResult
from nlgrd.nonlinear.results.metrics import METRIC_NAMES
from nlgrd.nonlinear.results.response_kinds import QUASI_PERIODIC, uncertainty_column
from nlgrd.nonlinear.results.sweep_results import SweepResult
from nlgrd.nonlinear.tracing.harmonic_convergence import OUTPUT_RTOL
from nlgrd.timedomain.settled_orbits import polish, with_orbits
from nlgrd.timedomain.time_answer import TimeAnswer, time_answer

__all__ = ["answer_gaps", "answer_sweep", "base_harmonics", "with_time_answers", "with_torus_answers"]


def base_harmonics(harmonics: NDArray, base: int) -> NDArray:
    """The harmonics of ω from harmonics of ω/``base`` (the orbit's mesh-periodic part).

    Parameters
    ----------
    harmonics : ndarray (n, 2 H base + 1)
        Real harmonics of ω/base [m].
    base : int
        The base divisor [-].

    Returns
    -------
    ndarray (n, 2H + 1)
    """
    z = np.atleast_2d(np.asarray(harmonics, dtype=float))
    Hs = (z.shape[-1] - 1) // 2
    keep = [0] + [c for k in range(base, Hs + 1, base) for c in (2 * k - 1, 2 * k)]
    return z[:, keep]


def answer_gaps(
    model: LinkModel,
    result: SweepResult,
    *,
    progress: Callable[[int, int], None] | None = None,
    unfinished: dict[int, TimeAnswer] | None = None,
    **options,
) -> tuple[SweepResult, dict[int, TimeAnswer]]:
    """Time answers at the points of ``result`` without a stable periodic response.

    Parameters
    ----------
    model : LinkModel
        The sweep's model as a link model (one mesh too:
        :func:`nlgrd.nonlinear.models.link_model.build_link_model`).
    result : SweepResult
        The sweep (its harmonics of ω/``base`` on the link coordinates of ``model``).
    progress : callable, optional
        ``progress(done, total)`` after each point answered.
    unfinished : dict, optional
        Filled with the answers whose transient outlasts the record, by row (not
        written: the settled orbit they may show is :func:`with_time_answers`'s).
    **options
        Options of :func:`~nlgrd.timedomain.time_answer.time_answer` (``max_periods``, ...).

    Returns
    -------
    SweepResult
        ``time_kind``, the first mesh's metrics and their ``uncertainty`` set at the
        answered points, the DTE amplitudes those of the synchronous average.
    dict of int to TimeAnswer
        The answers by row.
    """
    gaps = np.asarray(result.converged, bool) & np.asarray(result.no_stable, bool)
    rows = np.nonzero(gaps & ~np.asarray(result.time_answered, bool))[0]  # a torus's stays
    answers: dict[int, TimeAnswer] = {}
    if progress is not None and rows.size:  # the bar from the start: a point takes seconds
        progress(0, rows.size)
    for n, i in enumerate(rows):
        z = base_harmonics(result.harmonics[i], int(result.base))
        a = time_answer(model, float(result.omega[i]), harmonics=z, **options)
        if a.transient_over:  # else not answered: the transient outlasts the cap
            answers[int(i)] = a
        elif unfinished is not None:
            unfinished[int(i)] = a
        if progress is not None:
            progress(n + 1, rows.size)
    if not answers:
        return result, answers
    kind = np.array(result.time_kind, dtype=object)
    metrics = {k: np.array(v, copy=True) for k, v in result.metrics.items()}
    unc = {k: np.full(len(result), np.nan) for k in METRIC_NAMES if k != "back_contact"}
    if result.uncertainty is not None:
        unc.update({k: np.array(v, dtype=float) for k, v in result.uncertainty.items()})
    amps = np.array(result.amplitudes, dtype=float, copy=True)
    H = amps.shape[1] - 1
    for i, a in answers.items():
        kind[i] = a.kind
        for name, e in a.mesh.items():
            metrics[name][i] = e.value
            if name in unc:
                unc[name][i] = e.uncertainty
        if a.mesh:
            z = a.harmonics[0]
            k = min(H, (z.size - 1) // 2)
            amps[i] = np.nan
            amps[i, 0] = abs(z[0])
            amps[i, 1 : k + 1] = np.hypot(z[1 : 2 * k : 2], z[2 : 2 * k + 1 : 2])
    metrics["back_contact"] = metrics["back_contact"].astype(bool)
    return dc.replace(result, time_kind=kind, metrics=metrics, uncertainty=unc, amplitudes=amps), answers


def _link_frame(links: pd.DataFrame, answers: dict[int, TimeAnswer]) -> pd.DataFrame:
    """A link sweep's columns with the answered rows' values and their uncertainty columns
    (the linear bearings' too, where the frame has their columns)."""
    out = links.copy()
    for i, a in answers.items():
        bearings = {k: e for k, e in a.bearings.items() if k in out.columns}
        for key, e in {**a.links, **bearings}.items():
            out.loc[i, key] = e.value
            if key.rsplit(".", 1)[-1] != "back_contact":
                col = uncertainty_column(key)
                if col not in out:
                    out[col] = np.nan
                out.loc[i, col] = e.uncertainty
    return out


def _settled_orbits(model: LinkModel, res: SweepResult, answers: dict, rtol: float) -> dict:
    """The polished stable orbits (:func:`nlgrd.timedomain.settled_orbits.polish`) of the
    answers whose record settled on one, by row."""
    H_check = None if res.H_check is None else int(res.H_check)
    found = {}
    for i, a in answers.items():
        d = str(res.direction[i])
        one = polish(model, float(res.omega[i]), a.tail, int(res.H), d, H_check=H_check, rtol=rtol)
        if one is not None:
            found[i] = one
    return found


def with_time_answers(
    result,
    model: LinkModel,
    *,
    progress: Callable[[int, int], None] | None = None,
    orbit_rtol: float = OUTPUT_RTOL,
    **options,
):
    """A sweep's result (a link sweep or the bare points) with its gaps answered
    in the time domain (:func:`answer_gaps`); on a link sweep a record (answered, or its
    transient outlasting it) that settled on a stable period-1 orbit is that orbit
    (:mod:`nlgrd.timedomain.settled_orbits`).

    Parameters
    ----------
    result : LinkSweepResult or SweepResult
        The sweep.
    model : LinkModel
        Its model.
    progress : callable, optional
        ``progress(done, total)`` after each point answered.
    orbit_rtol : float
        The sweep's tolerance on a polished orbit's truncation estimate [-].
    **options
        Options of :func:`~nlgrd.timedomain.time_answer.time_answer`.

    Returns
    -------
    The same type as ``result``.
    """
    if isinstance(result, LinkSweepResult):
        unfinished: dict[int, TimeAnswer] = {}
        res, answers = answer_gaps(model, result.result, progress=progress, unfinished=unfinished, **options)
        orbits = _settled_orbits(model, res, {**answers, **unfinished}, orbit_rtol)
        timed = {i: a for i, a in answers.items() if i not in orbits}
        answered = dc.replace(result, result=res, links=_link_frame(result.links, timed))
        return dc.replace(
            with_orbits(answered, orbits), speed_per_base=result.speed_per_base, speed_unit=result.speed_unit
        )
    return answer_gaps(model, result, progress=progress, **options)[0]


#: Significant digits a torus answer's values are written to: its Newton stops at a
#: relative residual of 1e-10, and its start (the critical Floquet mode, whose last bits
#: vary from process to process) moves the converged values by up to 3e-13 relative
#: (measured on Kubo; at 1e-8 residual), far below the torus's own truncation estimate
#: (>= 1e-4); 8 digits keep a rerun's table byte-identical.
TORUS_DIGITS = 8


def _digits(values):
    """``values`` rounded to :data:`TORUS_DIGITS` significant digits."""
    v = np.array(values, dtype=float, ndmin=1)
    ok = np.isfinite(v) & (v != 0)
    e = np.floor(np.log10(np.abs(v[ok])))
    v[ok] = np.round(v[ok] / 10**e, TORUS_DIGITS - 1) * 10**e
    return v if np.ndim(values) else float(v[0])


def _ns_points(res: SweepResult) -> NDArray:
    """The rows whose periodic orbit lost stability to a complex pair (finite
    ``secondary_frequency``), converged, verdict converged, not answered yet."""
    return (
        np.asarray(res.converged, bool)
        & np.asarray(res.no_stable, bool)
        & np.asarray(res.verdict_converged, bool)
        & np.isfinite(res.secondary_frequency)
        & ~np.asarray(res.time_answered, bool)
    )


def _tori(res: SweepResult, model, target, rtol: float, step: int, progress=None) -> dict:
    """The accepted tori (:func:`~nlgrd.nonlinear.tracing.torus_sweep.converged_tori`) at the
    Neimark-Sacker rows of ``res``, each direction's in the sweep's order, by row."""
    from nlgrd.nonlinear.tracing.torus_sweep import converged_tori

    ns = _ns_points(res)
    found = {}
    for d in dict.fromkeys(np.asarray(res.direction)[ns].tolist()):
        rows = np.nonzero(ns & (np.asarray(res.direction) == d))[0]
        z = np.array([base_harmonics(res.harmonics[i], int(res.base)) for i in rows])
        z = z.reshape(rows.size, -1, z.shape[-1])
        tori = converged_tori(
            model, res.omega[rows], z, H=int(res.H), rtol=rtol, target=target, step=step, progress=progress
        )
        for i, a in zip(rows, tori, strict=True):
            if a is not None:
                found[int(i)] = a
    return found


def _with_tori(res: SweepResult, found: dict, coord: int) -> SweepResult:
    """``res`` with the accepted tori's ``response``, metrics, DTE amplitudes (the k₂ = 0
    part of the metrics' coordinate ``coord``), ``secondary_frequency`` and
    ``harmonic_error`` at their rows."""
    kind = np.array(res.time_kind, dtype=object)
    metrics = {k: np.array(v, copy=True) for k, v in res.metrics.items()}
    amps = np.array(res.amplitudes, dtype=float, copy=True)
    secondary = np.array(res.torus_frequency, dtype=float, copy=True)
    error = np.array(res.harmonic_error, dtype=float, copy=True)
    for i, a in found.items():
        kind[i] = QUASI_PERIODIC
        for name in metrics:
            metrics[name][i] = a.outputs[name] if name == "back_contact" else _digits(a.outputs[name])
        Y = a.solution.Y[coord]
        k = min(amps.shape[1] - 1, a.H)
        amps[i] = np.nan
        amps[i, : k + 1] = _digits(np.abs(Y[: k + 1]))
        secondary[i] = _digits(a.solution.secondary)
        error[i] = a.error
    metrics["back_contact"] = metrics["back_contact"].astype(bool)
    return dc.replace(
        res,
        time_kind=kind,
        metrics=metrics,
        amplitudes=amps,
        torus_frequency=secondary,
        harmonic_error=error,
    )


def with_torus_answers(
    result,
    system=None,
    *,
    model: LinkModel | None = None,
    rtol: float = OUTPUT_RTOL,
    progress: Callable[[int, int], None] | None = None,
):
    """A sweep with its Neimark-Sacker points answered by the torus harmonic balance
    where it converges within ``rtol`` (:func:`nlgrd.nonlinear.tracing.torus_sweep.converged_tori`):
    every converged point whose period-1 orbit lost stability to a complex pair
    (finite ``secondary_frequency``), each direction's in the sweep's order so that a torus
    is followed from the previous point's. An accepted point's ``response`` is
    "quasi-periodic" (``time_kind``), its metrics (the first mesh's), DTE amplitudes (the
    k₂ = 0 part), bearing columns, every link's columns (a link sweep's:
    :func:`nlgrd.nonlinear.tracing.link_torus.torus_link_columns`) and
    ``secondary_frequency`` the torus's, ``harmonic_error`` its convergence estimate; the
    torus's stability is not computed (``verdict`` "not computed", ``stable`` not written).
    The other points are left as they were. Every model takes one path: the link torus
    (:class:`~nlgrd.nonlinear.tracing.link_torus.LinkTorus`) of the sweep's link model,
    through :func:`~nlgrd.nonlinear.tracing.torus_sweep.converged_tori`.

    Parameters
    ----------
    result : LinkSweepResult
        The sweep (another result is returned as it is).
    system : RotorSystem, optional
        Its model (its link model is built from it when ``model`` is None).
    model : LinkModel, optional
        The link model the sweep was made on, or of its system.
    rtol : float
        The sweep's tolerance on its outputs [-].
    progress : callable, optional
        ``progress(done, total)`` after each point of each direction and rung.

    Returns
    -------
    The same type as ``result``.

    Raises
    ------
    ModelError
        A link sweep without ``model`` or ``system``.
    """
    if isinstance(result, LinkSweepResult):
        return _link_torus_answers(result, system, model, rtol, progress)
    return result


def _torus_link_model(system, model: LinkModel | None) -> LinkModel:
    """``model``, or the link model of ``system`` when None."""
    if model is not None:
        return model
    if system is None:
        raise ModelError("model", "the torus answers of a sweep need its link model or system")
    from nlgrd.nonlinear.models.link_model import build_link_model

    return build_link_model(system)


def _link_tori(res: SweepResult, model: LinkModel, rtol: float, progress=None) -> dict:
    """The accepted link tori (:class:`~nlgrd.nonlinear.tracing.link_torus.LinkTorus`) at
    the Neimark-Sacker rows of ``res`` (:func:`_tori`), its receptance prepared for the
    top rung's check."""
    from nlgrd.nonlinear.tracing.link_torus import LinkTorus
    from nlgrd.nonlinear.tracing.torus_sweep import TORUS_LADDER, TORUS_MAX_H

    step = int(model.top_order)
    H = int(res.H)
    top = min(max(H, step * TORUS_MAX_H), H + step * max(TORUS_LADDER)) + 4 * step
    model.receptance.prepare(top * float(np.max(np.abs(res.omega))) * 1.0001)
    return _tori(res, model, LinkTorus(model), rtol, step, progress)


def _link_torus_answers(result: LinkSweepResult, system, model: LinkModel | None, rtol: float, progress=None):
    """:func:`with_torus_answers` of a link sweep."""
    res = result.result
    if not _ns_points(res).any():
        return result
    model = _torus_link_model(system, model)
    found = _link_tori(res, model, rtol, progress)
    if not found:
        return result
    mesh = getattr(model.reduced.metrics, "mesh", None)
    links = result.links.copy()
    for i, a in found.items():
        for key, v in a.columns.items():
            if key in links.columns:
                links.loc[i, key] = v if key.endswith("back_contact") else _digits(v)
    res = _with_tori(res, found, 0 if mesh is None else int(mesh.coord))
    return LinkSweepResult(res, links, result.bearings)


def answer_sweep(
    result,
    *,
    system=None,
    model: LinkModel | None = None,
    period: int | str = "auto",
    stability: bool = True,
    time_domain: bool = True,
    torus: bool = True,
    rtol: float = OUTPUT_RTOL,
    progress: Callable[[int, int], None] | None = None,
    torus_progress: Callable[[int, int], None] | None = None,
    **options,
):
    """The one rule of every sweep (``nlgrd.sweep``, ``nlgrd sweep``, a study's task): when
    stability is on, ``period`` is "auto" and ``time_domain`` is set, the points without a
    stable periodic response are answered: first the points whose orbit lost stability
    to a complex pair by the torus harmonic balance where it converges within ``rtol``
    (:func:`with_torus_answers`), then every other one by
    time integration (:func:`with_time_answers`); otherwise ``result`` is returned as it
    is.

    Parameters
    ----------
    result : LinkSweepResult or SweepResult
        The sweep.
    system : RotorSystem, optional
        The model; its link model is built from it when ``model`` is None.
    model : LinkModel, optional
        The sweep's link model.
    period : int or str
        The sweep's ``period``: only "auto" tells a period doubling from a gap.
    stability : bool
        Whether the sweep computed Floquet stability (without it no point is a gap).
    time_domain : bool
        Whether the gaps are to be answered at all.
    torus : bool
        Try the torus harmonic balance first.
    rtol : float
        The sweep's tolerance on its outputs, which a torus's convergence estimate must
        meet [-].
    progress : callable, optional
        ``progress(done, total)`` after each point answered in the time domain.
    torus_progress : callable, optional
        ``progress(done, total)`` after each torus tried (:func:`with_torus_answers`).
    **options
        Options of :func:`~nlgrd.timedomain.time_answer.time_answer` (``periods``,
        ``max_periods``, ...).

    Returns
    -------
    The same type as ``result``.

    Raises
    ------
    ModelError
        Neither ``system`` nor ``model`` given while the rule applies.
    """
    if not (time_domain and stability and period == "auto"):
        return result
    if torus and (system is not None or model is not None):
        result = with_torus_answers(result, system, model=model, rtol=rtol, progress=torus_progress)
    if model is None:
        if system is None:
            raise ModelError("system", "answer_sweep needs the model or its system")
        from nlgrd.nonlinear.models.link_model import build_link_model

        model = build_link_model(system)
    return with_time_answers(result, model, progress=progress, orbit_rtol=rtol, **options)
