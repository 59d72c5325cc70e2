"""A time answer that settled on a periodic orbit, polished into that orbit.

A sweep answers a point without a stable periodic response by integrating from its
unstable orbit (:mod:`nlgrd.timedomain.sweep_answers`). Where the motion goes to a stable
mesh-periodic orbit the sweep's landing missed (two_shaft at 1730.8 Hz up:
tests/test_moved_verdicts.py), the record's last periods repeat. Such a record is
polished, whether its transient cut lies in its first half (an answer) or not (a slow
approach to the orbit, at 1730.8 Hz down):

1. **Settled**: every link coordinate over the record's last period equals that over the
   period before to :data:`SETTLED_RTOL` of its range (:func:`settled`).
2. **Polished**: the harmonic balance at the sweep's H is Newton-solved from the last
   period's harmonics, with the sweep's own Floquet verdict
   (:func:`nlgrd.nonlinear.models.link_model.link_sweep` on that one point, no jump, no
   search) and, where the sweep chose H by its estimate, the truncation estimate at its
   ``H_check`` (:func:`nlgrd.nonlinear.tracing.harmonic_convergence.check_harmonics`,
   within the sweep's ``rtol``).
3. **The motion**: the solved orbit lies within :data:`MATCH_RTOL` of each coordinate's
   range of the record's last period.

Where all hold and the orbit is stable, the row is that orbit (``response`` "periodic",
its values, multipliers and ``harmonic_error``, no uncertainty); else the time answer
stands. The cost: one Newton solve, one Floquet analysis and one check solve per settled
answer. Only period-1 records are polished (a record repeating after two periods keeps
its time answer), and only on the link engine's results (``nlgrd.sweep``).
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.nonlinear.fourier.harmonics import analyse, sample
from nlgrd.nonlinear.fourier.periods import spread
from nlgrd.nonlinear.models.link_model import LinkModel, link_sweep
from nlgrd.nonlinear.results.link_results import LinkSweepResult
from nlgrd.nonlinear.results.sweep_results import SweepResult
from nlgrd.nonlinear.tracing.harmonic_convergence import OUTPUT_RTOL, check_harmonics

__all__ = ["MATCH_RTOL", "SETTLED_RTOL", "gap", "polish", "settled", "with_orbits"]

#: Settled: the last period repeats the one before to this fraction of each coordinate's
#: range [-]. A periodic attractor repeats to its remaining transient (two_shaft 1730.8 Hz:
#: 4e-7 after 8192 periods); a torus or chaos differs by its modulation, O(range).
SETTLED_RTOL = 1e-3
#: The solved orbit is the record's motion within this fraction of each coordinate's range
#: [-]: the record carries the integrator's step error (1.2 % at 256 steps, two_shaft
#: 1730.8 Hz; second order in the step, and a time answer takes at least 256), while two
#: distinct orbits lie O(range) apart (there 2.5 ranges).
MATCH_RTOL = 0.1
#: Below this fraction of a coordinate's magnitude a difference is rounding [-].
ROUNDING = 1e-9


def gap(a: NDArray, b: NDArray) -> float:
    """The largest difference of ``a`` from ``b`` ((d, n) samples each) over each
    coordinate's range in ``b``, a coordinate's rounding (:data:`ROUNDING` of its
    magnitude) not counted [-].

    Parameters
    ----------
    a, b : ndarray (d, n)
        Samples of the link coordinates over a period [m].

    Returns
    -------
    float
    """
    diff = np.max(np.abs(a - b), axis=-1) - ROUNDING * np.max(np.abs(b), axis=-1)
    rng = np.ptp(b, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(diff > 0, diff / rng, 0.0)
    return float(np.max(rel))


def settled(tail: NDArray) -> bool:
    """Whether the record's last period repeats the one before (:data:`SETTLED_RTOL`).

    Parameters
    ----------
    tail : ndarray (p, d, n)
        The link coordinates over the record's last p periods (``TimeAnswer.tail``) [m].

    Returns
    -------
    bool
    """
    y = np.asarray(tail, dtype=float)
    return y.ndim == 3 and len(y) >= 2 and gap(y[-2], y[-1]) <= SETTLED_RTOL


def polish(
    model: LinkModel,
    omega: float,
    tail: NDArray,
    H: int,
    direction: str,
    *,
    H_check: int | None = None,
    rtol: float = OUTPUT_RTOL,
) -> LinkSweepResult | None:
    """The stable orbit a settled record shows, as a one-point link sweep; None where the
    record has not settled, Newton fails, the orbit is unstable or its verdict undecided,
    its truncation estimate exceeds ``rtol``, or it is not the record's motion.

    Parameters
    ----------
    model : LinkModel
        The sweep's model.
    omega : float
        Base frequency [rad/s].
    tail : ndarray (p, d, n)
        The record's last periods (``TimeAnswer.tail``) [m].
    H : int
        The sweep's harmonics of ω [-].
    direction : str
        The point's sweep direction.
    H_check : int, optional
        The sweep's check H (its ``H_check``); None: no estimate (``harmonic_error`` NaN).
    rtol : float
        The sweep's tolerance on the estimate [-].

    Returns
    -------
    LinkSweepResult or None
    """
    if not settled(tail):
        return None
    y = np.asarray(tail, dtype=float)[-1]
    one = link_sweep(
        model, [omega], H, directions=direction, z0=analyse(y, H), jump="none", leave_unstable=False, period=1
    )
    r = one.result
    if not (r.converged[0] and r.stable[0] and r.verdict_converged[0]):
        return None
    if gap(sample(r.harmonics[0], y.shape[-1]), y) > MATCH_RTOL:
        return None
    if H_check is not None:
        error = check_harmonics(model.reduced, r, H_check, rtol=rtol, jumps=False).error
        if not error[0] <= rtol:  # NaN or inf: no estimate
            return None
        r = dc.replace(r, harmonic_error=error, H_check=int(H_check))
    return LinkSweepResult(r, one.links, one.bearings)


def _row(res: SweepResult, i: int, p: SweepResult) -> dict:
    """``res``'s per-point fields with row ``i`` from the one-point ``p``."""
    n, out = len(res), {}
    for f in dc.fields(res):
        v, w = getattr(res, f.name), getattr(p, f.name)
        if f.name == "harmonics":
            v = np.array(v, copy=True)
            v[i] = spread(w[0], int(res.base))
        elif f.name == "uncertainty" and v is not None:
            v = {k: np.array(a, copy=True) for k, a in v.items()}
            for a in v.values():
                a[i] = np.nan
        elif isinstance(v, dict):
            v = {k: np.array(a, copy=True) for k, a in v.items()}
            for k in v:
                v[k][i] = w[k][0]
        elif isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == n and w is not None:
            v = np.array(v, copy=True)
            if v.ndim > 1:  # amplitudes: a wider row padded with NaN
                k = min(v.shape[-1], np.shape(w)[-1])
                v[i] = np.nan
                v[i, :k] = w[0, :k]
            else:
                v[i] = w[0]
        else:
            continue
        out[f.name] = v
    return out


def with_orbits(result: LinkSweepResult, orbits: dict[int, LinkSweepResult]) -> LinkSweepResult:
    """``result`` with each row of ``orbits`` (:func:`polish`) in place: its harmonics
    (spread onto the sweep's base), verdict, multipliers, values and link and bearing
    columns, ``response`` "periodic", no uncertainty.

    Parameters
    ----------
    result : LinkSweepResult
        The answered sweep.
    orbits : dict of int to LinkSweepResult
        One-point sweeps by row.

    Returns
    -------
    LinkSweepResult
    """
    res, links = result.result, result.links.copy()
    for i, one in orbits.items():
        res = dc.replace(res, **_row(res, i, one.result))
        for col in links.columns:
            links.loc[i, col] = one.links[col].iloc[0] if col in one.links.columns else np.nan
    return LinkSweepResult(res, pd.DataFrame(links), result.bearings)
