"""Every speed of a report's sweep answered, or marked "not found".

A harmonic-balance sweep leaves gaps where no stable periodic orbit exists. The reports
answer a Neimark-Sacker point by the torus harmonic balance where it converges, each
direction on a process of its own (a direction's tori are followed along it only:
:func:`torus_answers_in_parallel`), and every other gap in the time domain
(:func:`nlgrd.timedomain.sweep_answers.with_time_answers`: "time domain" or "chaotic",
each value with its sampling uncertainty), here on several processes: each point's
answer depends on that point alone (its own unstable orbit as the start, a fixed seed for
the Lyapunov twin, one BLAS thread), so the rows are split among the workers and put back
in place, the same numbers as one process gives.

The table of a report then says for every point what answers it (its ``response``):
"periodic", "period ν", "time domain", "chaotic" (or "quasi-periodic" where that kind
carries values) or :data:`NOT_FOUND` where no value was found (the harmonic balance did
not converge, or the time integration did not settle within its cap); the harmonic
balance's own kind (its Floquet verdict) stays in :data:`HB_RESPONSE`.
"""

from __future__ import annotations

import dataclasses as dc
import multiprocessing
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed

import numpy as np
import pandas as pd

from nlgrd.nonlinear.models.link_model import LinkModel, build_link_model
from nlgrd.nonlinear.results.link_results import LinkSweepResult
from nlgrd.nonlinear.results.sweep_results import SweepResult
from nlgrd.rotor.system import RotorSystem
from nlgrd.timedomain.sweep_answers import OUTPUT_RTOL, with_time_answers, with_torus_answers

__all__ = [
    "HB_RESPONSE",
    "NOT_FOUND",
    "answer_gaps_in_parallel",
    "answered_table",
    "torus_answers_in_parallel",
    "gap_rows",
    "plot_answered",
    "response_counts",
]

#: A report's sweep: a link model's (``nlgrd.sweep``, every model).
Sweep = LinkSweepResult

#: The ``response`` of a point without any answer.
NOT_FOUND = "not found"
#: Column of the harmonic balance's own kind of response (before the time answers).
HB_RESPONSE = "hb_response"
#: Order of the kinds in the counts (any "period ν" after "periodic").
KIND_ORDER = ("periodic", "period", "quasi-periodic", "time domain", "chaotic", NOT_FOUND)


def _points(result: Sweep | SweepResult) -> SweepResult:
    """The harmonic-balance points of a sweep."""
    return result.result if isinstance(result, LinkSweepResult) else result


def _with_points(result: Sweep, points: SweepResult) -> Sweep:
    """``result`` with its harmonic-balance points replaced."""
    return dc.replace(result, result=points)


def _speed_kept(result: Sweep, answered: Sweep) -> Sweep:
    """``answered`` with ``result``'s speed column settings (a link sweep's answers are built
    anew, without them)."""
    if isinstance(result, LinkSweepResult):
        return dc.replace(answered, speed_per_base=result.speed_per_base, speed_unit=result.speed_unit)
    return answered


def _put_link_rows(links: pd.DataFrame, part: pd.DataFrame, rows: np.ndarray) -> pd.DataFrame:
    """``links`` with ``part``'s values at ``rows`` (every column of ``part``: the
    uncertainty columns a time answer adds too, NaN elsewhere)."""
    out = links.copy()
    for c in part.columns:
        if c not in out:
            out[c] = np.nan
        col = out.columns.get_loc(c)
        out.iloc[rows, col] = part.iloc[rows][c].to_numpy()
    return out


def gap_rows(result: Sweep | SweepResult) -> np.ndarray:
    """Rows the time domain is asked to answer: converged, no stable periodic response, not
    answered by a torus.

    Parameters
    ----------
    result : LinkSweepResult or SweepResult
        The sweep.

    Returns
    -------
    ndarray of int
    """
    res = _points(result)
    gaps = np.asarray(res.converged, bool) & np.asarray(res.no_stable, bool)
    return np.nonzero(gaps & ~np.asarray(res.time_answered, bool))[0]  # a torus's answer stays


def _only_rows(res: SweepResult, rows: np.ndarray) -> SweepResult:
    """The sweep with ``no_stable`` kept at ``rows`` only: the other gaps are not asked."""
    keep = np.zeros(len(res), bool)
    keep[rows] = True
    return dc.replace(res, no_stable=np.asarray(res.no_stable, bool) & keep)


def _answer_rows(result: Sweep, system: RotorSystem, rows: np.ndarray, options: dict) -> Sweep:
    """A worker's task: the time answers at ``rows`` (module docstring), on the link model
    built here from ``system`` (a link model does not pickle; the build is deterministic)."""
    part = _with_points(result, _only_rows(_points(result), rows))
    return with_time_answers(part, build_link_model(system), **options)


def _put_rows(out: dict, part: SweepResult, rows: np.ndarray, n: int) -> None:
    """Copy every per-point field of ``part`` at ``rows`` into ``out`` (field -> value)."""
    for f in dc.fields(part):
        if f.name == "no_stable":  # cleared outside the task's rows; the original is kept
            continue
        v = getattr(part, f.name)
        if isinstance(v, dict):
            target = dict(out[f.name] or {})
            for k, a in v.items():
                a = np.asarray(a)
                base = target.get(k)
                base = np.full(n, np.nan, dtype=a.dtype) if base is None else np.array(base, copy=True)
                base[rows] = a[rows]
                target[k] = base
            out[f.name] = target
        elif isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == n:
            a = np.array(out[f.name], copy=True)
            a[rows] = v[rows]
            out[f.name] = a


def _torus_rows(result: Sweep, system: RotorSystem, rows: np.ndarray, rtol: float) -> Sweep:
    """A worker's task: the torus answers of one direction (``rows``), followed along it as
    :func:`~nlgrd.timedomain.sweep_answers.with_torus_answers` follows each direction."""
    return with_torus_answers(_with_points(result, _only_rows(_points(result), rows)), system, rtol=rtol)


def _merged(result: Sweep, parts: list[tuple[Sweep, np.ndarray]]) -> Sweep:
    """A link sweep with each worker's rows put back: its points' per-point fields and its
    links' columns (:func:`_put_rows`, :func:`_put_link_rows`)."""
    res, n = result.result, len(result.result)
    merged = {f.name: getattr(res, f.name) for f in dc.fields(res)}
    links = result.links
    for part, rows in parts:
        _put_rows(merged, part.result, rows, n)
        links = _put_link_rows(links, part.links, rows)
    return dc.replace(result, result=dc.replace(res, **merged), links=links)


def torus_answers_in_parallel(
    result: Sweep, system: RotorSystem, *, workers: int = 1, rtol: float = OUTPUT_RTOL
) -> Sweep:
    """The sweep's Neimark-Sacker points answered by the torus harmonic balance
    (:func:`~nlgrd.timedomain.sweep_answers.with_torus_answers`), each direction on its own
    process: a direction's tori are followed from point to point along it and never from the
    other direction's, so its rows put back are the numbers one process gives
    (tests/test_answered_link_sweeps.py). Spawned workers, as :func:`answer_gaps_in_parallel`.

    Parameters
    ----------
    result : LinkSweepResult
        The sweep (``nlgrd.sweep``).
    system : RotorSystem
        The rotor swept.
    workers : int
        Processes [-] (1: this one; at most one per direction is used).
    rtol : float
        The sweep's tolerance, which a torus's convergence estimate must meet [-].

    Returns
    -------
    The same type as ``result``.
    """
    res = _points(result)
    direction = np.asarray(res.direction).astype(str)
    groups = [np.nonzero(direction == d)[0] for d in dict.fromkeys(direction.tolist())]
    workers = max(1, min(int(workers), len(groups)))
    if workers == 1:
        return _speed_kept(result, with_torus_answers(result, system, rtol=rtol))
    context = multiprocessing.get_context("spawn")  # no fork of a threaded kernel
    with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
        futures = {pool.submit(_torus_rows, result, system, g, rtol): g for g in groups}
        return _merged(result, [(fut.result(), futures[fut]) for fut in as_completed(futures)])


def answer_gaps_in_parallel(
    result: Sweep,
    system: RotorSystem,
    *,
    model: LinkModel | None = None,
    workers: int = 1,
    torus: bool = True,
    rtol: float = OUTPUT_RTOL,
    progress: Callable[[int, int], None] | None = None,
    **options,
) -> Sweep:
    """The sweep with its gaps answered as every sweep answers them
    (:func:`~nlgrd.timedomain.sweep_answers.answer_sweep`), the time answers on ``workers``
    processes: first the Neimark-Sacker points by the torus harmonic balance where it
    converges within ``rtol`` (:func:`~nlgrd.timedomain.sweep_answers.with_torus_answers`),
    then every other gap in the time domain.

    The tori of each direction on a process of their own (:func:`torus_answers_in_parallel`).
    ``workers`` = 1 is :func:`~nlgrd.timedomain.sweep_answers.answer_sweep` itself;
    more split the time-domain rows among processes (interleaved, so that each gets points from
    every part of the range) and put every per-point field back at its rows: the same
    numbers (module docstring; tests/test_answered_link_sweeps.py). The workers are spawned,
    not forked (a notebook's kernel runs threads): a script that calls this with
    ``workers`` > 1 keeps its work under ``if __name__ == "__main__":``, as
    :mod:`multiprocessing` requires of a spawned child's parent module.

    Parameters
    ----------
    result : LinkSweepResult
        The sweep (``nlgrd.sweep``).
    system : RotorSystem
        The rotor swept.
    model : LinkModel, optional
        Its link model (:func:`nlgrd.nonlinear.models.link_model.build_link_model`), if built
        already; each worker builds its own.
    workers : int
        Processes [-] (1: this one).
    torus : bool
        Try the torus harmonic balance first.
    rtol : float
        The sweep's tolerance, which a torus's convergence estimate must meet [-].
    progress : callable, optional
        ``progress(done, total)``: points answered (one process) or tasks done (several).
    **options
        Options of :func:`nlgrd.timedomain.time_answer.time_answer` (``periods``,
        ``max_periods``, ...).

    Returns
    -------
    The same type as ``result``.
    """
    if torus:  # the torus first, along the sweep (each from its neighbour's): a process a direction
        result = torus_answers_in_parallel(result, system, workers=workers, rtol=rtol)
    rows = gap_rows(result)
    workers = max(1, min(int(workers), rows.size))
    if workers == 1 or rows.size == 0:
        model = build_link_model(system) if model is None else model
        return _speed_kept(result, with_time_answers(result, model, progress=progress, **options))
    tasks = [rows[i::workers] for i in range(workers)]
    context = multiprocessing.get_context("spawn")  # no fork of a threaded kernel
    parts = []
    with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
        futures = {pool.submit(_answer_rows, result, system, t, options): t for t in tasks}
        for done, fut in enumerate(as_completed(futures), 1):
            parts.append((fut.result(), futures[fut]))
            if progress is not None:
                progress(done, len(tasks))
    return _merged(result, parts)


def answered_table(hb: pd.DataFrame, answered: pd.DataFrame, value: str = "dte_rms [um]") -> pd.DataFrame:
    """The table of a sweep whose every point is answered or marked :data:`NOT_FOUND`.

    Parameters
    ----------
    hb : pandas.DataFrame
        ``to_frame()`` of the harmonic-balance sweep.
    answered : pandas.DataFrame
        ``to_frame()`` of the same sweep with its gaps answered (same rows, same order).
    value : str
        A column every answer carries a value in.

    Returns
    -------
    pandas.DataFrame
        ``answered`` with ``response`` :data:`NOT_FOUND` where the point has no value (or
        did not converge) and the harmonic balance's ``response`` in :data:`HB_RESPONSE`,
        beside it.
    """
    freq = "base_frequency [Hz]"
    if (
        len(hb) != len(answered)
        or freq not in hb
        or freq not in answered
        or not np.array_equal(hb[freq].to_numpy(float), answered[freq].to_numpy(float))
    ):
        raise ValueError("answered_table: the two tables are not the same sweep's rows")
    out = answered.copy()
    ok = out["converged"].astype(bool).to_numpy() & np.isfinite(pd.to_numeric(out[value]).to_numpy(float))
    out["response"] = np.where(ok, out["response"].astype(object), NOT_FOUND)
    out.insert(list(out.columns).index("response") + 1, HB_RESPONSE, hb["response"].astype(object).to_numpy())
    return out


def _kind(response: str) -> str:
    return "period" if response.startswith("period ") else response


def response_counts(frame: pd.DataFrame) -> pd.DataFrame:
    """Points of each kind of response, per direction and in all (from the table itself).

    Parameters
    ----------
    frame : pandas.DataFrame
        A table of :func:`answered_table`.

    Returns
    -------
    pandas.DataFrame
        One row per direction and one "both"; a column per kind present (in the order
        periodic, period ν, quasi-periodic, time domain, chaotic, not found) and "points".
    """
    resp = frame["response"].astype(str)
    kinds = sorted(set(resp), key=lambda k: (KIND_ORDER.index(_kind(k)) if _kind(k) in KIND_ORDER else 99, k))
    rows = []
    for d in [*dict.fromkeys(frame["direction"].astype(str)), "both"]:
        sel = resp if d == "both" else resp[frame["direction"].astype(str) == d]
        rows.append({"direction": d, **{k: int((sel == k).sum()) for k in kinds}, "points": len(sel)})
    return pd.DataFrame(rows)


def plot_answered(frame: pd.DataFrame, x: str, y: str, ax=None, label: str | None = None, series=0, **kw):
    """A table of :func:`answered_table` drawn by :func:`nlgrd.plotting.nonlinear.plot_sweep_frame`:
    periodic lines, period-ν rings, torus answers as squares, time answers as diamonds or
    stars with ±2σ bars (the up sweep's open, the down sweep's filled inside them: both show
    where they coincide), and the points :data:`NOT_FOUND` as crosses on the bottom edge,
    "not found (n)" in the legend.

    Parameters
    ----------
    frame : pandas.DataFrame
        The table.
    x, y : str
        Columns of the abscissa and the values.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on.
    label : str, optional
        Name of the series in the legend.
    series : int, (up, down) colours or {direction: colour}
        Colours.
    **kw
        Other options of ``plot_sweep_frame``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from nlgrd.plotting.nonlinear import plot_sweep_frame

    drawn = frame.assign(converged=frame["response"].astype(str) != NOT_FOUND)
    return plot_sweep_frame(drawn, x, y, ax=ax, label=label, series=series, not_converged=NOT_FOUND, **kw)
