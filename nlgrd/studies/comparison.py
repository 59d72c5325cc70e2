"""Model curves against experimental ones: RMS differences and landmark errors per
direction (:func:`compare`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.studies.experimental import (
    QUANTITIES,
    X_UNITS,
    CurveLandmarks,
    ExperimentalSet,
    curve_landmarks,
    directions_of,
)


def frame_columns(data: ExperimentalSet, frame: pd.DataFrame) -> tuple[str, str]:
    """The columns of ``frame`` a data set is compared with: its abscissa and its quantity,
    as a one-mesh table names them or as a link table does (``shaft_speed [rpm]``,
    ``base_frequency [Hz]``, the first mesh's ``<mesh>.<quantity> [unit]``;
    docs/conventions.md, "Column names").

    Parameters
    ----------
    data : ExperimentalSet
        The measured data set.
    frame : pandas.DataFrame
        The sweep table.

    Returns
    -------
    (str, str)
        The abscissa's and the quantity's column (as the data set names them when the table
        has neither form: :func:`directions_of` then names the missing one).
    """
    x, q = data.frame_x_column, data.frame_column
    if q not in frame:
        q = next((c for c in frame.columns if c.endswith(f".{q}") and "_uncertainty" not in c), q)
    return x, q


def _model_curve(curves: dict, direction: str) -> tuple[NDArray, NDArray] | None:
    """Model curve for a measured direction: the same direction, or for "unknown" the
    upper envelope of all directions (None when there is none)."""
    if direction in curves:
        return curves[direction]
    if direction != "unknown" or not curves:
        return None
    xs = np.unique(np.concatenate([c[0] for c in curves.values()]))
    ys = []
    for cx, cy in curves.values():
        ok = np.isfinite(cy)
        ys.append(np.interp(xs, cx[ok], cy[ok], left=np.nan, right=np.nan) if ok.sum() > 1 else xs * np.nan)
    return xs, np.nanmax(np.vstack(ys), axis=0) if len(ys) > 1 else ys[0]


def _rms_difference(curves: dict, direction: str, x: NDArray, y: NDArray) -> tuple[float, int]:
    """RMS of model - measurement on the measured points inside the model's range."""
    branches = [curves[direction]] if direction in curves else list(curves.values())
    if direction not in curves and direction != "unknown":
        return float("nan"), 0
    diffs = []
    for cx, cy in branches:
        ok = np.isfinite(cy)
        if ok.sum() < 2:
            diffs.append(np.full(x.shape, np.nan))
            continue
        m = np.interp(x, cx[ok], cy[ok], left=np.nan, right=np.nan)
        diffs.append(m - y)
    D = np.vstack(diffs)
    # "unknown": each measured point is compared with the nearest computed branch
    with np.errstate(all="ignore"):
        idx = np.nanargmin(np.where(np.isfinite(D), np.abs(D), np.inf), axis=0)
    d = D[idx, np.arange(D.shape[1])]
    d = d[np.isfinite(d)]
    if d.size == 0:
        return float("nan"), 0
    return float(np.sqrt(np.mean(d**2))), int(d.size)


def _percent(computed: float, measured: float) -> float:
    """100 (computed - measured) / |measured|; NaN when measured is 0 or NaN."""
    if not np.isfinite(measured) or measured == 0:
        return float("nan")
    return 100.0 * (computed - measured) / abs(measured)


def compare(data: ExperimentalSet, frame: pd.DataFrame) -> pd.DataFrame:
    """Score a sweep table against a measured data set, one row per measured direction.

    The model curve of a direction is the sweep of the same direction; a direction
    "unknown" is compared with the upper envelope of the sweeps (peak, jump) and, point by
    point, with the nearest computed branch (RMS difference). Columns (units in names):
    peak location and value, measured and computed, and their relative errors; location of
    the largest jump, measured and computed; RMS difference and the number of measured
    points inside the computed range. Non-converged (NaN) sweep points are skipped.

    Parameters
    ----------
    data : ExperimentalSet
        The measured data set.
    frame : pandas.DataFrame
        The sweep table (``nlgrd.sweep(...).to_frame()`` or ``SweepResult.to_frame()``),
        with the data set's abscissa and
        quantity columns (:func:`frame_columns`) and ``direction``.

    Returns
    -------
    pandas.DataFrame
        One row per measured direction, units in the column names (the abscissa's rpm or
        Hz, the quantity's unit, [%] for the errors).

    Raises
    ------
    ModelError
        When the table lacks a column the comparison needs.
    """
    curves = directions_of(frame, *frame_columns(data, frame))
    xu, vu = X_UNITS[data.x_column], QUANTITIES[data.quantity][1]
    rows = []
    for d in data.directions():
        x, y = data.select(d)
        meas = curve_landmarks(x, y, "down" if d == "down" else "up")
        model = _model_curve(curves, d)
        if model is None:
            comp = CurveLandmarks(*(float("nan"),) * 5)
        else:
            comp = curve_landmarks(model[0], model[1], "down" if d == "down" else "up")
        rms, n = _rms_difference(curves, d, x, y)
        rows.append(
            {
                "data set": Path(data.path).name,
                "quantity": data.quantity,
                "direction": d,
                f"peak location measured [{xu}]": meas.peak_x,
                f"peak location computed [{xu}]": comp.peak_x,
                "peak location error [%]": _percent(comp.peak_x, meas.peak_x),
                f"peak value measured [{vu}]": meas.peak_value,
                f"peak value computed [{vu}]": comp.peak_value,
                "peak value error [%]": _percent(comp.peak_value, meas.peak_value),
                f"jump measured [{xu}]": meas.jump_x,
                f"jump computed [{xu}]": comp.jump_x,
                f"rms difference [{vu}]": rms,
                "points compared": n,
            }
        )
    return pd.DataFrame(rows)
