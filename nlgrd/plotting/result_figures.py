"""Figures of the results that are not a sweep: Floquet multipliers on the unit circle,
bearing loads per point, tori over speed, orbits found by a search.

Each takes the result's table (``to_frame()``) or arrays, never an analysis object, and
draws in the conventions of :mod:`nlgrd.plotting.common` (stable filled, unstable open,
a point that did not converge a cross on the bottom edge).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from nlgrd.errors import ModelError
from nlgrd.plotting.common import (
    STABLE,
    UNKNOWN,
    UNSTABLE,
    axis_label,
    draw_points,
    get_ax,
    mark_not_converged,
    place_legend,
)

#: Markers of orbits by period (ν = 1, 2, 3, more) in :func:`plot_found_orbits`.
PERIOD_MARKERS = ("o", "s", "D", "p")
#: The torus answer's marker (as the sweeps draw a torus: an open square).
TORUS_MARKER = "s"


def plot_multipliers(multipliers, ax=None, title: str | None = None):
    """Floquet multipliers in the complex plane with the unit circle: inside stable
    (filled), outside unstable (open).

    Parameters
    ----------
    multipliers : array_like of complex
        The multipliers μ [-].
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    title : str, optional
        Title of the axes.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = get_ax(ax, figsize=(5, 5))
    mu = np.asarray(multipliers, dtype=complex).reshape(-1)
    t = np.linspace(0.0, 2 * np.pi, 721)
    ax.plot(np.cos(t), np.sin(t), color="0.5", lw=0.8, label="unit circle |μ| = 1", gid="unit circle")
    outside = np.abs(mu) > 1.0
    for keep, kw, lab in (
        (~outside, {"mfc": "C0"}, "|μ| <= 1"),
        (outside, {"mfc": "none", "mew": 1.0}, "|μ| > 1: unstable"),
    ):
        if np.any(keep):
            ax.plot(
                mu.real[keep],
                mu.imag[keep],
                "o",
                color="C0",
                ms=5,
                ls="none",
                label=lab,
                gid="multipliers",
                **kw,
            )
    ax.axhline(0.0, color="0.85", lw=0.5, zorder=0)
    ax.axvline(0.0, color="0.85", lw=0.5, zorder=0)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("Re μ [-]")
    ax.set_ylabel("Im μ [-]")
    if title:
        ax.set_title(title)
    place_legend(ax)
    return ax


def plot_tori(frame: pd.DataFrame, quantity: str = "dte_rms", ax=None, title: str | None = None):
    """Tori over speed (:meth:`~nlgrd.nonlinear.tracing.torus_sweep.TorusResult.to_frame`):
    each converged torus an open square at its value against the reference shaft speed
    (``shaft_speed [rpm]``), as a sweep
    draws a torus answer; a speed without a torus a cross on the bottom edge.

    Parameters
    ----------
    frame : pandas.DataFrame
        The tori's table.
    quantity : str
        A column's quantity: ``MESH.QUANTITY`` or a bare one, the first mesh's
        (``dte_rms``, ``force_max``, ``secondary_frequency``, ...).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    title : str, optional
        Title of the axes.

    Returns
    -------
    matplotlib.axes.Axes

    Raises
    ------
    ModelError
        (``quantity``) No column of that quantity.
    """
    names = [c.split(" [")[0] for c in frame.columns]
    cols = [c for c, n in zip(frame.columns, names, strict=True) if quantity in (n, n.split(".", 1)[-1])]
    if not cols:
        raise ModelError(
            "quantity", f"no torus column {quantity!r}; the columns are {', '.join(frame.columns)}"
        )
    col = cols[0]
    ax = get_ax(ax)
    x = frame["shaft_speed [rpm]"].to_numpy(float)
    ok = frame["converged"].to_numpy(bool)
    y = np.where(ok, frame[col].to_numpy(float), np.nan)
    if np.any(ok):
        ax.plot(
            x[ok],
            y[ok],
            TORUS_MARKER,
            mfc="none",
            color="C0",
            ms=6,
            ls="none",
            label="quasi-periodic (torus HB)",
        )
    mark_not_converged(ax, x[~ok], "C0", "torus HB", "no torus")
    ax.set_xlabel(axis_label("shaft_speed [rpm]"))
    ax.set_ylabel(axis_label(col))
    if title:
        ax.set_title(title)
    place_legend(ax)
    return ax


def plot_found_orbits(frame: pd.DataFrame, ax=None, title: str | None = None):
    """Orbits found by a search (``OrbitSearchResult.to_frame``): each orbit's largest
    alternating amplitude against the base frequency, a marker per period, stable filled,
    unstable open, stability not computed half-filled.

    Parameters
    ----------
    frame : pandas.DataFrame
        One row per orbit: ``base_frequency [Hz]``, ``period``, ``amplitude [um]``,
        ``stable`` (tri-state).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    title : str, optional
        Title of the axes.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = get_ax(ax)
    stable = frame["stable"]
    codes = np.where(stable.isna(), UNKNOWN, np.where(stable.fillna(False).to_numpy(bool), STABLE, UNSTABLE))
    for i, p in enumerate(sorted(set(frame["period"].tolist()))):
        rows = (frame["period"] == p).to_numpy()
        marker = PERIOD_MARKERS[min(int(p), len(PERIOD_MARKERS)) - 1]
        draw_points(
            ax,
            frame["base_frequency [Hz]"].to_numpy(float)[rows],
            frame["amplitude [um]"].to_numpy(float)[rows],
            codes[rows],
            f"C{i % 10}",
            marker,
            f"period {p}",
            lines=False,
            ms=5,
        )
    ax.set_xlabel(axis_label("base_frequency [Hz]"))
    ax.set_ylabel("largest alternating amplitude [µm]")
    if title:
        ax.set_title(title)
    place_legend(ax)
    return ax
