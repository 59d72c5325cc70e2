"""The kinds of response a sweep's point has, as its ``response`` column says: a periodic
orbit (of the mesh period or ν of them), a quasi-periodic point (its orbit lost stability
to a complex pair), no stable periodic response, or the answer of a time integration
(:mod:`nlgrd.timedomain.time_answer`): "time domain" or "chaotic", its values with their
sampling uncertainty in the ``<value>_uncertainty`` columns.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from nlgrd.nonlinear.results.metrics import NO_STABLE

#: The response where an orbit lost stability to a complex pair (a torus). Answered by the
#: torus harmonic balance (:func:`nlgrd.timedomain.sweep_answers.with_torus_answers`:
#: ``time_kind`` this kind, the torus's values and ``secondary_frequency``, its stability not
#: computed, ``verdict`` "not computed"); else without values, not drawn.
QUASI_PERIODIC = "quasi-periodic"
#: The response of a point answered by time integration (:mod:`nlgrd.timedomain.time_answer`):
#: its statistics carry a sampling uncertainty; "chaotic" when its largest Lyapunov
#: exponent is positive.
TIME_DOMAIN = "time domain"
CHAOTIC = "chaotic"
#: A converged orbit whose stability verdict did not converge (:mod:`nlgrd.nonlinear.stability.verdicts`):
#: neither stable nor unstable, so not the response; its values are not written.
STABILITY_NOT_CONVERGED = "stability not converged"


def response_kind(result) -> NDArray:
    """Per point: "periodic" (the mesh period), "period ν", "quasi-periodic" (lost to a
    complex pair, ``secondary_frequency`` known), :data:`NO_STABLE` or
    :data:`STABILITY_NOT_CONVERGED`; where a time integration answered (``time_kind``),
    :data:`TIME_DOMAIN` or :data:`CHAOTIC`; where a torus harmonic balance did,
    :data:`QUASI_PERIODIC` with values.

    Parameters
    ----------
    result : SweepResult
        The sweep.

    Returns
    -------
    ndarray of str (object)
    """
    period = np.asarray(result.period, dtype=int)
    out = np.array(["periodic" if p == 1 else f"period {p}" for p in period], dtype=object).reshape(-1)
    out[result.no_stable] = NO_STABLE
    out[result.no_stable & np.isfinite(result.secondary_frequency)] = QUASI_PERIODIC
    out[~np.asarray(result.verdict_converged, dtype=bool)] = STABILITY_NOT_CONVERGED
    timed = result.time_answered
    out[timed] = np.asarray(result.time_kind, dtype=object)[timed]
    return out


def uncertainty_column(column: str) -> str:
    """The column of a value's sampling uncertainty: "dte_rms [um]" -> "dte_rms_uncertainty [um]".

    Parameters
    ----------
    column : str
        A value's column, its unit in brackets.

    Returns
    -------
    str
    """
    stem, sep, unit = column.partition(" [")
    return f"{stem}_uncertainty{sep}{unit}"
