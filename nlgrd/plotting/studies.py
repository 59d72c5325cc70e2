"""Figures of studies, from their summary tables (:mod:`nlgrd.studies.study_runner`).

- :func:`study_map`: a summary quantity over two axes, one cell per task (heat map,
  each cell labelled with its value; failed tasks hatched).
- :func:`study_curves`: a quantity against one axis, one curve per value of another.
- :func:`study_distribution`: histogram and empirical distribution of a quantity over
  the draws of a Monte-Carlo study, with its 5, 50 and 95 % quantiles.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.plotting.common import axis_label, get_ax, place_legend

__all__ = ["study_curves", "study_distribution", "study_map"]


def _edges(values: NDArray) -> NDArray:
    """Cell edges around sorted axis values (geometric midpoints on a log-spaced axis)."""
    v = np.asarray(values, dtype=float)
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5]) if v[0] == 0 else v[0] * np.array([0.9, 1.1])
    ratios = v[1:] / v[:-1] if np.all(v > 0) else None
    if ratios is not None and np.ptp(ratios) < 1e-9 * ratios.mean() and abs(ratios[0] - 1) > 1e-3:
        mid = np.sqrt(v[1:] * v[:-1])
        return np.concatenate([[v[0] ** 2 / mid[0]], mid, [v[-1] ** 2 / mid[-1]]])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])


def _short(column: str) -> str:
    """``gear_pairs[0].geometry.backlash [m]`` -> ``mesh backlash 2b [m]`` (:func:`axis_label`)."""
    return axis_label(column)


def _value(value) -> str:
    return f"{value:.4g}" if isinstance(value, float | np.floating) else str(value)


def study_map(
    summary: pd.DataFrame,
    x: str,
    y: str,
    quantity: str,
    ax=None,
    cmap: str = "viridis",
    fmt: str = ".3g",
    highlight=None,
    highlight_label: str | None = None,
):
    """Heat map of ``quantity`` over axes ``x`` and ``y`` (one cell per grid point).

    Parameters
    ----------
    summary : pandas.DataFrame
        A study's summary table (several rows per cell, e.g. draws, are averaged).
    x, y : str
        Axis columns.
    quantity : str
        Summary column.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on.
    cmap : str
        Colour map.
    fmt : str
        Format of the cell labels.
    highlight : array_like of bool, optional
        Rows of ``summary`` whose cells are outlined (e.g. the best design per load).
    highlight_label : str, optional
        Legend entry of the outlined cells.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.patches import Rectangle

    ax = get_ax(ax, figsize=(6.5, 4.5))
    table = summary.pivot_table(index=y, columns=x, values=quantity, aggfunc="mean", dropna=False)
    table = table.sort_index().sort_index(axis=1)
    xs, ys = table.columns.to_numpy(dtype=float), table.index.to_numpy(dtype=float)
    z = np.ma.masked_invalid(table.to_numpy(dtype=float))
    ex, ey = _edges(xs), _edges(ys)
    mesh = ax.pcolormesh(ex, ey, z, cmap=cmap, shading="flat")
    ax.figure.colorbar(mesh, ax=ax, label=axis_label(quantity))
    for i, yv in enumerate(ys):
        for j, xv in enumerate(xs):
            if z.mask is not np.ma.nomask and z.mask[i, j]:
                ax.text(xv, yv, "failed", ha="center", va="center", fontsize=7, color="0.3")
                continue
            r, g, b, _ = mesh.cmap(mesh.norm(z[i, j]))
            dark = 0.299 * r + 0.587 * g + 0.114 * b < 0.5  # luminance of the cell's colour
            ax.text(
                xv, yv, format(z[i, j], fmt), ha="center", va="center", fontsize=7, color="w" if dark else "k"
            )
    if highlight is not None:
        for _, row in summary[np.asarray(highlight, dtype=bool)].iterrows():
            i, j = int(np.searchsorted(ys, row[y])), int(np.searchsorted(xs, row[x]))
            box = Rectangle((ex[j], ey[i]), ex[j + 1] - ex[j], ey[i + 1] - ey[i], fill=False, ec="w", lw=2.5)
            ax.add_patch(box)
            ax.add_patch(
                Rectangle(box.get_xy(), box.get_width(), box.get_height(), fill=False, ec="k", lw=0.8)
            )
        if highlight_label:
            ax.legend(
                handles=[Rectangle((0, 0), 1, 1, fill=False, ec="k", lw=1.5)],
                labels=[highlight_label],
                loc="upper left",
                fontsize=8,
            )
    if np.all(xs > 0) and xs.size > 2 and np.ptp(np.diff(np.log(xs))) < 1e-9:
        ax.set_xscale("log")
    if np.all(ys > 0) and ys.size > 2 and np.ptp(np.diff(np.log(ys))) < 1e-9:
        ax.set_yscale("log")
    ax.set_xlabel(axis_label(x))
    ax.set_ylabel(axis_label(y))
    return ax


def study_curves(
    summary: pd.DataFrame, x: str, quantity: str, family: str | None = None, ax=None, style: str = ".-"
):
    """``quantity`` against axis ``x``; one curve per value of axis ``family``.

    Parameters
    ----------
    summary : pandas.DataFrame
        A study's summary table.
    x : str
        Axis column on the horizontal axis.
    quantity : str
        Summary column.
    family : str, optional
        Axis column whose values label the curves.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on.
    style : str
        Line style.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = get_ax(ax)
    groups = [(None, summary)] if family is None else list(summary.groupby(family, sort=True))
    for value, part in groups:
        part = part.sort_values(x)
        label = None if family is None else f"{_short(family)} = {_value(value)}"
        ax.plot(part[x], part[quantity], style, label=label)
    ax.set_xlabel(axis_label(x))
    ax.set_ylabel(axis_label(quantity))
    if family is not None:
        place_legend(ax)
    return ax


def study_distribution(summary: pd.DataFrame, quantity: str, ax=None, bins: int | str = "auto"):
    """Histogram and empirical distribution function of ``quantity`` over a study's tasks.

    Parameters
    ----------
    summary : pandas.DataFrame
        A study's summary table (failed tasks, NaN, are left out and counted in the title).
    quantity : str
        Summary column.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on.
    bins : int or str
        Histogram bins (:func:`numpy.histogram_bin_edges`).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = get_ax(ax)
    v = summary[quantity].to_numpy(dtype=float)
    ok = np.sort(v[np.isfinite(v)])
    ax.hist(ok, bins=np.histogram_bin_edges(ok, bins=bins), color="0.75", edgecolor="0.4")
    ax.set_xlabel(axis_label(quantity))
    ax.set_ylabel("tasks")
    twin = ax.twinx()
    twin.step(ok, np.arange(1, ok.size + 1) / ok.size, where="post", color="C0")
    twin.set_ylim(0, 1.02)
    twin.set_ylabel("fraction below", color="C0")
    for q in (0.05, 0.5, 0.95):
        value = float(np.quantile(ok, q))
        ax.axvline(value, color="C3", lw=0.8, ls="--")
        ax.text(value, ax.get_ylim()[1], f" {q:.0%}", color="C3", fontsize=7, va="top")
    missing = v.size - ok.size
    ax.set_title(
        f"{ok.size} tasks" + (f", {missing} without a value (failed)" if missing else ""), fontsize=9
    )
    return ax
