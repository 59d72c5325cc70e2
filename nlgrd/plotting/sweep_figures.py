"""The composed figures of ``nlgrd sweep``: a link model's sweep with the branches its orbit
search followed, and the spectra of one point of a sweep over a gear revolution."""

from __future__ import annotations

import matplotlib.pyplot as plt
import pandas as pd

from nlgrd.plotting.common import axis_label, place_legend
from nlgrd.plotting.nonlinear import plot_spectrum, plot_sweep_frame

__all__ = ["draw_branches", "plot_link_sweep", "plot_spectra"]


def draw_branches(ax, branches: pd.DataFrame, x: str, quantity: str) -> None:
    """The followed branches on the sweep's axes (one colour pair per branch).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The sweep's axes.
    branches : DataFrame
        The followed branches, a column "branch" naming each (``nlgrd sweep --search-at``).
    x : str
        Abscissa column ("base_frequency [Hz]" or "shaft_speed [rpm]").
    quantity : str
        The plotted metric (its column is named "<quantity> [unit]").
    """
    column = next((c for c in branches.columns if c.split(" [")[0] == quantity), None)
    if column is None:
        return
    for k, (name, part) in enumerate(branches.groupby("branch", sort=False)):
        plot_sweep_frame(part, x, column, ax=ax, label=name, series=2 + k % 3)


def plot_link_sweep(
    frame: pd.DataFrame,
    x: str,
    column: str,
    title: str | None,
    branches=None,
    ax=None,
    jumps: pd.DataFrame | None = None,
):
    """A link sweep's ``column`` against ``x``, with the followed branches when given.

    Parameters
    ----------
    frame : DataFrame
        The sweep's table (``LinkSweepResult.to_frame()`` with the range's column ``x``);
        with a ``branch`` column, the rows of each coexisting branch (all but "sweep") are
        drawn as the followed branches are (:func:`draw_branches`).
    x : str
        Abscissa column ("shaft_speed [rpm]" or "base_frequency [Hz]").
    column : str
        The drawn column ``<link>.<quantity> [unit]``.
    title : str or None
        The axes' title (None: none).
    branches : DataFrame, optional
        Branches followed by an orbit search (:func:`draw_branches`).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure (laid out tight) when None.
    jumps : pandas.DataFrame, optional
        The sweep's jumps in the unit of ``x`` (:func:`~nlgrd.plotting.nonlinear.plot_sweep_frame`).

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    new = ax is None
    if new:
        _, ax = plt.subplots(figsize=(7, 4))
    coexisting = None
    if "branch" in frame.columns:
        mine = (frame["branch"] == "sweep").to_numpy(dtype=bool)
        frame, coexisting = frame[mine], frame[~mine]
    plot_sweep_frame(frame, x, column, ax, label="sweep", jumps=jumps)
    ax.set_xlabel(axis_label(x))
    ax.set_ylabel(axis_label(column))
    if title:
        ax.set_title(title, fontsize=9)
    for part in (branches, coexisting):
        if part is not None and len(part):
            draw_branches(ax, part, x, column.split(" [")[0])
    place_legend(ax, fontsize=7)
    if new:
        ax.figure.tight_layout()
    return ax


def plot_spectra(dte, bearing, omega: float, title: str):
    """The DTE spectrum above a bearing's force spectrum, at one point of a sweep.

    Parameters
    ----------
    dte : (array_like, array_like)
        The DTE lines: frequencies [rad/s] and amplitudes [m].
    bearing : (array_like, array_like, str)
        The bearing force lines: frequencies [rad/s], amplitudes [N] and the bearing's name.
    omega : float
        The mesh frequency of the point [rad/s].
    title : str
        The upper axes' title.

    Returns
    -------
    numpy.ndarray of matplotlib.axes.Axes
        The two axes of the new figure.
    """
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    plot_spectrum(*dte, omega, ax=axes[0])
    frequencies, amplitudes, name = bearing
    plot_spectrum(
        frequencies,
        amplitudes,
        omega,
        ax=axes[1],
        ylabel="bearing force amplitude [N]",
        scale=1.0,
        label=name,
    )
    axes[0].set_title(title)
    fig.tight_layout()
    return axes
