"""The options of ``nlgrd sweep --search-at`` and ``--period N``, parsed and checked: the
speeds and periods of the orbit search (done by
:mod:`nlgrd.nonlinear.models.model_views` over
:mod:`nlgrd.nonlinear.tracing.period_branches`, whose notes say what is written).

``--period N``, N >= 3: no period-1 sweep; the period-N orbits are searched for at the
``--search-at`` speeds, or at :data:`DEFAULT_SEARCH_POINTS` speeds of the grid evenly spread
over the range, with ``--harmonics`` (default
:data:`~nlgrd.nonlinear.tracing.period_branches.PERIOD_HARMONICS`) mesh harmonics, N H of ω/N.
When no period-N orbit is found at all, nothing is written and the command exits with status 1.
"""

from __future__ import annotations

import numpy as np

from nlgrd.errors import ModelError

#: Periods searched by default [mesh periods].
DEFAULT_PERIODS = "1,2,3"
#: Longest period searched [mesh periods]: the period-ν model has ν H harmonics.
MAX_PERIOD = 6
#: ``--period N`` without ``--search-at``: search at this many grid speeds, evenly spread.
DEFAULT_SEARCH_POINTS = 5


def parse_search(args, values: np.ndarray) -> tuple[np.ndarray, tuple[int, ...]]:
    """``--search-at`` speeds (the unit of the range) and ``--search-periods``, checked.

    Parameters
    ----------
    args : argparse.Namespace
        ``search_at`` (comma-separated numbers) and ``search_periods``.
    values : ndarray
        The sweep's grid, in the same unit.

    Returns
    -------
    (ndarray, tuple of int)
        The speeds and the periods.

    Raises
    ------
    ModelError
        Not numbers, outside the sweep's range, or periods not whole numbers 1-6.
    """
    try:
        at = np.array([float(t) for t in str(args.search_at).split(",")])
    except ValueError:
        raise ModelError("--search-at", f"comma-separated numbers, got {args.search_at!r}") from None
    lo, hi = float(np.min(values)), float(np.max(values))
    if not np.all(np.isfinite(at)) or np.any(at < lo) or np.any(at > hi):
        raise ModelError(
            "--search-at", f"speeds within the sweep's range {lo:g}-{hi:g}, got {args.search_at!r}"
        )
    text = DEFAULT_PERIODS if args.search_periods is None else args.search_periods
    try:
        periods = tuple(int(t) for t in str(text).split(","))
    except ValueError:
        raise ModelError("--search-periods", f"comma-separated whole numbers, got {text!r}") from None
    if any(not 1 <= p <= MAX_PERIOD for p in periods):
        raise ModelError("--search-periods", f"periods from 1 to {MAX_PERIOD}, got {text!r}")
    return at, periods


def parse_period(text: str) -> str | int:
    """The ``--period`` option: "auto" or a whole number of mesh periods from 1 to :data:`MAX_PERIOD`.

    Parameters
    ----------
    text : str
        The option's value.

    Returns
    -------
    str or int
        "auto", or the period [mesh periods].

    Raises
    ------
    ModelError
        Anything else.
    """
    if text == "auto":
        return text
    try:
        nu = int(text)
    except ValueError:
        nu = 0
    if not 1 <= nu <= MAX_PERIOD or str(nu) != str(text).strip():
        raise ModelError(
            "--period", f"auto or a whole number of mesh periods 1 to {MAX_PERIOD}, got {text!r}"
        )
    return nu


def none_of(period: str) -> str:
    """What a sweep where no point converged means for ``--period`` (appended to its line).

    Parameters
    ----------
    period : str
        The ``--period`` option as given.

    Returns
    -------
    str
        The explanation, or "".
    """
    if str(period).strip() == "2":
        return ": no period-2 orbit in the range (period-2 branches exist only beyond a period doubling)"
    return ""


def default_search(values: np.ndarray, count: int = DEFAULT_SEARCH_POINTS) -> np.ndarray:
    """Speeds of the grid at which ``--period N`` searches without ``--search-at``.

    Parameters
    ----------
    values : ndarray
        The sweep's grid (the range's unit).
    count : int
        How many, evenly spread from the lowest to the highest [-].

    Returns
    -------
    ndarray
        ``count`` grid values (all when the grid has fewer), ascending.
    """
    grid = np.unique(np.asarray(values, dtype=float))
    return grid[np.unique(np.round(np.linspace(0, grid.size - 1, min(count, grid.size))).astype(int))]
