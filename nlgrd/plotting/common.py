"""Conventions shared by every nlgrd figure (saving one with its caption: :mod:`.figure_files`).

Sweeps and curves (:mod:`.nonlinear`, and the notebooks through it):

- Direction by colour *and* marker: up ▲ in the first colour of the series' pair, down ▼
  in the second (:data:`SERIES_COLOURS`), so two directions never share a colour.
- Stability: stable points filled, joined by solid lines; unstable points open (marker
  face 'none'), joined by dashed lines; points whose stability was not computed
  half-filled (``fillstyle="bottom"``), joined by solid lines, and the legend says
  "stability not computed".
- Points that did not converge: a cross on the bottom edge of the axes at their
  frequency, counted in the legend ("... not converged (n)"), never a value; the down
  sweep's a row above the up sweep's (:data:`NC_ROW`), so that both show at one speed.
- Jumps of a sweep (where it leaves one branch for another between two points): a dotted
  vertical arrow at the midpoint of the two frequencies, from the value left to the value
  reached, counted in the legend ("... jump (n)"; :func:`mark_jumps`, gid :data:`JUMP_GID`).
- Values beyond a given scale (``ylim``): a caret on the edge of the axes at their
  frequency, with the count and the largest value in the legend; the line breaks there
  instead of running off the axes.
- Dense curves (continuation, ``markers=False`` of :func:`draw_points`): no markers, the
  line style alone tells stable (solid), unstable (dashed) and not computed (dotted).
- Axis labels are words with units, never raw table columns (:func:`axis_label`).
- Legends with more than :data:`LEGEND_INSIDE` entries go outside the axes, on the right
  (:func:`place_legend`), so that they never cover the curves.
- A legend names only what is drawn (:func:`drawn_entries`): an artist without a finite
  point gets no entry, and a count in an entry is that of the points drawn.
- Up and down answers at the same speed both stay visible: the up sweep's answer markers
  (not joined: torus, time domain, chaotic) are open and large, the down sweep's filled,
  :data:`DOWN_INSET` of that size and drawn above them, so that a coinciding pair reads
  as a filled core in an open outline of the other colour (:func:`answer_marker_style`);
  period-ν rings likewise, the down ring inside the up one.
- A figure of a case the paper compared with measurements says on it when no measured
  curve is loaded (:func:`note_no_measurement`).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from numpy.typing import NDArray

#: (up, down) colours of series 0, 1, ...: distinct hues within and across pairs.
SERIES_COLOURS = (("C0", "C3"), ("C2", "C1"), ("C4", "C6"), ("C9", "C8"), ("C5", "C7"))
#: Markers of the sweep directions.
DIRECTION_MARKERS = {"up": "^", "down": "v", "curve": "o"}
#: Stability codes of :func:`stability_codes`.
STABLE, UNSTABLE, UNKNOWN = 1, 0, -1
#: Legend wording of points whose stability was not computed.
UNKNOWN_TEXT = "stability not computed"
#: Height of the not-converged crosses (axes fraction).
NC_HEIGHT = 0.015
#: Distance between rows of such marks [pt] (a mark is 5 pt wide).
NC_ROW = 6.0
#: Most legend entries drawn inside the axes (:func:`place_legend`).
LEGEND_INSIDE = 8
#: Smallest marker size in a legend [pt] (:func:`readable_markers`).
LEGEND_MARKER_MIN = 4.5
#: Size of the down sweep's answer markers per the up sweep's (:func:`answer_marker_style`).
DOWN_INSET = 0.65
#: Note of :func:`note_no_measurement`.
NO_MEASUREMENT_TEXT = "no measured curve shipped\n(to add one: data/experimental/README.md)"

#: gid of the jumps' shafts and heads (:func:`mark_jumps`).
JUMP_GID = "jump"
#: gids of the markers and segments of :func:`draw_points`, per stability code.
STABILITY_GIDS = {STABLE: "stable", UNSTABLE: "unstable", UNKNOWN: "stability unknown"}
#: gid of the marks on the bottom edge (:func:`mark_not_converged`): no value drawn.
NOT_CONVERGED_GID = "not converged"
#: gid of the edge marks of converged points without a stable periodic response.
NO_RESPONSE_GID = "no response"

#: Axis labels of the columns not worded by their quantity (:func:`axis_label`; else :data:`_WORDS`).
COLUMN_LABELS = {
    "force_max [N]": "max mesh force [N]",
    "force_min [N]": "min mesh force [N]",
    "dslr [-]": "DSLR = max W / W0 [-]",
    "contact_loss_fraction [-]": "contact-loss fraction [-]",
    "floquet_max [-]": "largest Floquet multiplier |μ| [-]",
}
#: Words of the last part of a column name (the parameter), with their symbol.
_WORDS = {
    "damping_ratio": "damping ratio ζ",
    "backlash": "backlash 2b",
    "half_backlash": "half backlash b",
    "static_load": "static load W0",
    "torque": "torque T",
    "stiffness": "stiffness k",
    "damping": "damping c",
    "mass": "mass m",
    "dte_rms": "RMS of alternating DTE",
    "dte_p2p": "peak-to-peak DTE",
    "dte_mean": "mean DTE",
    "dslr": "DSLR",
    "delta": "DTE δ",
    "lste": "LSTE e",
    "deflection": "mesh deflection δ - e",
    "force": "mesh force W",
    "dte_rms_change": "change of the RMS DTE",
    "force_max_change": "change of the max force",
    "modal_floor": "modal damping floor ζ_min",
    "rayleigh_alpha": "Rayleigh α",
    "rayleigh_beta": "Rayleigh β",
}
#: Owners of a model key (``gear_pairs[0].x``): the word that names them on an axis.
_OWNERS = {"gear_pairs": "mesh", "bearings": "bearing", "shafts": "shaft", "bearing_clearances": "clearance"}
#: Units written as in print.
_UNITS = {"um": "µm", "-": "-"}


def axis_label(column: str) -> str:
    """A readable axis label with its unit for a table column or model key.

    Known columns (:data:`COLUMN_LABELS`) get their words; a model key such as
    ``gear_pairs[0].damping_ratio [-]`` becomes "mesh damping ratio ζ [-]" (the second
    mesh "mesh 2 ...", link columns "LINK: ..."); underscores become spaces, "um" "µm".

    Parameters
    ----------
    column : str
        A column name, "name [unit]" or a bare name.

    Returns
    -------
    str
        The label.
    """
    import re

    column = str(column)
    if column in COLUMN_LABELS:
        return COLUMN_LABELS[column]
    name, _, unit = column.partition(" [")
    unit = unit[:-1] if unit.endswith("]") else unit
    unit = _UNITS.get(unit, unit)
    parts = name.split(".")
    leaf = parts[-1]
    words = _WORDS.get(leaf, leaf.replace("_", " "))
    amp = re.fullmatch(r"dte_amp_(\d+)", leaf)
    words = f"DTE harmonic {amp.group(1)} amplitude" if amp else words
    owner = ""
    for part in parts[:-1]:
        m = re.fullmatch(r"(\w+)\[(\d+)\]", part)
        if m and m.group(1) in _OWNERS:
            k = int(m.group(2))
            owner = _OWNERS[m.group(1)] + (f" {k + 1}" if k else "")
        elif not m and part not in ("geometry", "material", "links", "damping") and len(parts) == 2:
            owner = f"{part}:"  # a link's column: "LINK.quantity"
    text = f"{owner} {words}".strip()
    return f"{text} [{unit}]" if unit else text


def _shows_something(artist) -> bool:
    """Whether a legend handle draws anything on the axes: a line or marker with a finite
    point, a patch, a collection with an element; a note (no marker, no line) counts."""
    from matplotlib.collections import Collection, PathCollection
    from matplotlib.container import Container
    from matplotlib.lines import Line2D

    if isinstance(artist, Container):
        return any(_shows_something(a) for a in artist.get_children() if a is not None)
    if isinstance(artist, Line2D):
        marker = artist.get_marker()
        no_marker = marker in (None, "", " ", "None", "none")
        if no_marker and artist.get_linestyle() in ("None", "none", "", " "):
            return True  # a text entry (note_no_measurement)
        xy = np.column_stack([np.asarray(artist.get_xdata(), float), np.asarray(artist.get_ydata(), float)])
        return bool(np.all(np.isfinite(xy), axis=1).any()) if xy.size else False
    if isinstance(artist, PathCollection):  # scatter: one marker path, a point per offset
        off = np.asarray(artist.get_offsets(), float).reshape(-1, 2)
        return bool(np.all(np.isfinite(off), axis=1).any())
    if isinstance(artist, Collection):
        return len(artist.get_paths()) > 0
    return True


def drawn_entries(ax) -> tuple[list, list]:
    """The legend entries of ``ax`` whose artists draw something: a kind that was not drawn
    (e.g. a series with no finite point) gets no entry.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes whose labelled artists make the legend.

    Returns
    -------
    handles : list
        The artists (lines, containers, patches) with at least one drawn element.
    labels : list of str
        Their labels.
    """
    from matplotlib.container import Container

    handles, labels = ax.get_legend_handles_labels()
    keep = [i for i, h in enumerate(handles) if _shows_something(h)]
    # in the order drawn (matplotlib lists containers, e.g. error bars, after every line)
    children = {id(a): k for k, a in enumerate(ax.get_children())}

    def drawn_at(h):
        parts = [a for a in h.get_children() if a is not None] if isinstance(h, Container) else [h]
        return min((children.get(id(a), len(children)) for a in parts), default=len(children))

    keep.sort(key=lambda i: drawn_at(handles[i]))
    return [handles[i] for i in keep], [labels[i] for i in keep]


def plot_counted(ax, x, y, fmt: str, label: str, **kwargs):
    """The points of one kind at their finite (x, y), not joined, labelled ``"{label} (n)"``
    with n the points drawn; nothing (no legend entry either) when there is none.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    x, y : array_like
        Coordinates; points with a non-finite one are left out.
    fmt : str
        Matplotlib marker (format string of one marker).
    label : str
        What the points are, in the legend.
    **kwargs
        Other options of ``ax.plot`` (colour, ``ms``, ``mfc`` ...).

    Returns
    -------
    matplotlib.lines.Line2D or None
        The points, or None when none is finite.
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y)
    if not ok.any():
        return None
    (line,) = ax.plot(x[ok], y[ok], fmt, ls="none", label=f"{label} ({int(ok.sum())})", **kwargs)
    return line


def answer_marker_style(ms: float, scale: float, inner: bool) -> dict:
    """Marker options of an answer drawn as a point (torus, time domain, chaotic): the up
    sweep's (``inner`` False) open, ``scale * ms`` wide; the down sweep's (``inner``) filled,
    :data:`DOWN_INSET` of that and drawn above, so that both stay visible where they coincide.

    Parameters
    ----------
    ms : float
        Marker size of the sweep's stable points [pt].
    scale : float
        The answer kind's size per ``ms`` [-].
    inner : bool
        The down sweep's marker (filled, smaller, on top).

    Returns
    -------
    dict
        ``ms``, ``mew``, ``zorder``, ``filled`` (whether the face takes the colour) and the
        error bars' ``elinewidth`` (the down sweep's thinner, on top of the up sweep's).
    """
    size = scale * ms
    if inner:
        return {"ms": DOWN_INSET * size, "mew": 0.6, "zorder": 3.2, "filled": True, "elinewidth": 0.7}
    return {"ms": size, "mew": 1.4, "zorder": 3.0, "filled": False, "elinewidth": 1.5}


def place_legend(ax, fontsize: float = 8, inside: int = LEGEND_INSIDE, **kwargs):
    """The legend of ``ax``: inside (best place) up to ``inside`` entries if it covers no drawn
    point there, else outside on the right; only the entries of artists that draw something
    (:func:`drawn_entries`).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes whose labelled artists make the legend.
    fontsize : float
        Font size [pt].
    inside : int
        Most entries drawn inside the axes.
    **kwargs
        Passed to ``ax.legend`` (e.g. ``handles``); ``loc`` is used only inside.

    Returns
    -------
    matplotlib.legend.Legend or None
        The legend, or None when no artist is labelled.
    """
    handles, labels = kwargs.pop("handles", None), kwargs.pop("labels", None)
    if handles is None:
        handles, labels = drawn_entries(ax)
    elif labels is None:
        labels = [h.get_label() for h in handles]
    if not handles:
        return None
    ax.get_xlim(), ax.get_ylim()  # autoscale now: the data's pixels below are those drawn, not (0, 1)'s
    if len(handles) <= inside:
        legend = ax.legend(handles, labels, fontsize=fontsize, **kwargs)
        if kwargs.get("loc", "best") in ("best", 0) and "bbox_to_anchor" not in kwargs:
            # "best" is chosen again at each draw: after tight_layout it may move onto points
            kwargs["loc"] = _where(ax, legend)
            legend = ax.legend(handles, labels, fontsize=fontsize, **kwargs)
        if not _covers_points(ax, legend):
            return readable_markers(legend)
    kwargs.pop("loc", None)
    kwargs.pop("bbox_to_anchor", None)
    outside = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "borderaxespad": 0}
    legend = ax.legend(handles, labels, fontsize=fontsize, **outside, **kwargs)
    _widen_for(ax, legend)
    return readable_markers(legend)


def readable_markers(legend, size: float = LEGEND_MARKER_MIN):
    """Draw the legend's markers at least ``size`` wide (a dense curve's 1.5 pt dots cannot be
    told apart in a legend); the markers on the axes keep their size.

    Parameters
    ----------
    legend : matplotlib.legend.Legend or None
        The legend (None: nothing to do).
    size : float
        Smallest marker size in the legend [pt].

    Returns
    -------
    matplotlib.legend.Legend or None
        ``legend``.
    """
    from matplotlib.lines import Line2D

    if legend is None:
        return None
    for handle in legend.legend_handles:
        if isinstance(handle, Line2D) and 0 < handle.get_markersize() < size:
            handle.set_markersize(size)
    return legend


def _where(ax, legend) -> str:
    """The named location (of the nine "best" chooses from) of ``legend`` as placed now."""
    renderer = ax.figure.canvas.get_renderer()
    box, axes = legend.get_window_extent(renderer), ax.get_window_extent(renderer)
    col = int(np.clip(3 * ((box.x0 + box.x1) / 2 - axes.x0) / axes.width, 0, 2))
    row = int(np.clip(3 * ((box.y0 + box.y1) / 2 - axes.y0) / axes.height, 0, 2))
    name = f"{('lower', 'center', 'upper')[row]} {('left', 'center', 'right')[col]}"
    return "center" if name == "center center" else name


def _widen_for(ax, legend) -> None:
    """Widen the figure by the width of an outside legend, so that the axes keep their size.

    The widths added are kept on the figure, per column of axes (their right edge): a legend
    redrawn on the same axes, or beside another panel of the same column, widens the figure
    only by what it adds to the widest legend of that column."""
    fig = ax.figure
    width = legend.get_window_extent(fig.canvas.get_renderer()).width / fig.dpi + 0.3  # [in], with the gap
    added = fig.__dict__.setdefault("_nlgrd_legend_widths", {})
    column = round(float(ax.get_position().x1), 3)
    if width > added.get(column, 0.0):
        fig.set_size_inches(fig.get_figwidth() + width - added.get(column, 0.0), fig.get_figheight())
        added[column] = width


def _covers_points(ax, legend) -> bool:
    """Whether ``legend`` (as placed now) lies over a point of a line drawn in data coordinates."""
    box = legend.get_window_extent(ax.figure.canvas.get_renderer())
    for line in ax.get_lines():
        if line.get_transform() != ax.transData:
            continue
        xy = np.column_stack([np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)])
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if xy.size == 0:
            continue
        px = ax.transData.transform(xy)
        inside = (px[:, 0] > box.x0) & (px[:, 0] < box.x1) & (px[:, 1] > box.y0) & (px[:, 1] < box.y1)
        if np.any(inside):
            return True
    return False


def note_no_measurement(ax, text: str = NO_MEASUREMENT_TEXT):
    """State on ``ax``, as an entry of its legend (no symbol), that no measured curve is shipped.

    A legend entry rather than a text on the curves: the legend is placed where it covers
    nothing (:func:`place_legend`). Call it before drawing the legend.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes of a figure the paper compared with measurements.
    text : str
        The note.

    Returns
    -------
    matplotlib.lines.Line2D
        The empty artist that carries the note.
    """
    (note,) = ax.plot([], [], ls="none", marker="", label=text)
    return note


def get_ax(ax=None, figsize=(7, 4)):
    """``ax``, or the axes of a new figure when None.

    Parameters
    ----------
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    figsize : (float, float)
        Size of the new figure [in]; used only when ``ax`` is None.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``, or the axes of the new figure.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=figsize)
    return ax


def direction_colours(series: int | tuple | dict | None = None) -> dict[str, str]:
    """{direction: colour} for a series index, an (up, down) pair or a ready mapping.

    Parameters
    ----------
    series : int, (str, str), dict or None
        Index of a pair of :data:`SERIES_COLOURS` (modulo their number; None: 0), an
        (up, down) pair of matplotlib colours, or a {direction: colour} mapping.

    Returns
    -------
    dict of str to str
        The colours of "up", "down" and "curve" (the up colour); a copy of a given mapping.
    """
    if isinstance(series, dict):
        return dict(series)
    if series is None:
        series = 0
    if isinstance(series, int | np.integer):
        up, down = SERIES_COLOURS[int(series) % len(SERIES_COLOURS)]
    else:
        up, down = series
    return {"up": up, "down": down, "curve": up}


def flags(values, size: int | None = None, default: bool = False) -> NDArray:
    """Booleans from a flag column that may hold NaN, None or the strings 'True'/'False'.

    Missing entries become ``default``; ``values=None`` gives ``size`` of them.

    Parameters
    ----------
    values : array_like or None
        The flag column: booleans, 0/1, NaN, None, ``pd.NA`` or strings (see
        :func:`stability_codes`).
    size : int, optional
        Number of flags when ``values`` is None (None: 0).
    default : bool
        Value of the missing entries.

    Returns
    -------
    ndarray of bool
        One flag per entry of ``values`` (flattened).
    """
    if values is None:
        return np.full(size or 0, default, dtype=bool)
    codes = stability_codes(values)
    return np.where(codes == UNKNOWN, default, codes == STABLE)


def stability_codes(stable, known=None) -> NDArray:
    """:data:`STABLE`, :data:`UNSTABLE` or :data:`UNKNOWN` per point.

    ``stable`` may hold booleans, NaN, None or ``pd.NA`` (not computed), 0/1 or the
    strings of a CSV file; ``known`` (optional mask) marks where stability was computed, e.g. a finite
    largest Floquet multiplier, for results that store False where it is unknown.

    Parameters
    ----------
    stable : array_like
        Stability flag per point; the strings "true", "1", "1.0" (any case) are stable,
        "false", "0", "0.0" unstable, any other string unknown.
    known : array_like of bool, optional
        True where stability was computed; the other points are :data:`UNKNOWN` whatever
        ``stable`` holds.

    Returns
    -------
    ndarray of int
        One code per point (``stable`` flattened).
    """
    arr = np.asarray(stable, dtype=object).reshape(-1)
    out = np.full(arr.size, UNKNOWN, dtype=int)
    for i, v in enumerate(arr):
        if v is None or v is pd.NA or (isinstance(v, float | np.floating) and np.isnan(v)):
            continue
        if isinstance(v, str):
            s = v.strip().lower()
            if s in ("true", "1", "1.0"):
                out[i] = STABLE
            elif s in ("false", "0", "0.0"):
                out[i] = UNSTABLE
            continue
        out[i] = STABLE if bool(v) else UNSTABLE
    if known is not None:
        out[~np.asarray(known, dtype=bool).reshape(-1)] = UNKNOWN
    return out


def _pieces(x: NDArray, y: NDArray, keep: NDArray) -> tuple[NDArray, NDArray]:
    """The segments i -> i+1 with ``keep[i]``, as one NaN-separated polyline."""
    xs, ys = [], []
    for i in np.nonzero(keep)[0]:
        xs += [x[i], x[i + 1], np.nan]
        ys += [y[i], y[i + 1], np.nan]
    return np.array(xs, dtype=float), np.array(ys, dtype=float)


def draw_points(
    ax,
    x,
    y,
    codes,
    colour: str,
    marker: str,
    label: str,
    *,
    lines: bool = True,
    markers: bool = True,
    ms: float = 3.5,
    lw: float = 1.0,
    alpha: float = 1.0,
    zorder: float = 2,
) -> list:
    """One branch (points in drawing order; NaN y = a gap) in the stability conventions.

    Segments between two finite points are solid, or dashed when either end is unstable.
    Markers: filled (stable, labelled ``label``), open (unstable, ``label + ", unstable"``),
    half-filled (unknown, ``label + ", stability not computed"``). Returns the artists.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    x, y : array_like
        Coordinates of the points in drawing order; a NaN y is a gap (no marker, no
        segment to or from it).
    codes : array_like of int
        Stability code of each point (:func:`stability_codes`).
    colour : str
        Matplotlib colour of the lines and markers.
    marker : str
        Matplotlib marker (e.g. one of :data:`DIRECTION_MARKERS`).
    label : str
        Legend label of the stable markers; the others add the suffixes above.
    lines : bool
        Join consecutive finite points (False: markers only).
    markers : bool
        Draw the markers (False, for dense curves: lines only, labelled ``label`` solid
        (stable), ``label + ", unstable"`` dashed and ``label + ", stability not
        computed"`` dotted where both ends are unknown).
    ms : float
        Marker size of the stable points [pt] (unstable 1.4 times, unknown 1.3 times it).
    lw : float
        Line width [pt].
    alpha : float
        Opacity of the lines and markers.
    zorder : float
        Drawing order of the lines; the markers just above them.

    Returns
    -------
    list of matplotlib.lines.Line2D
        The artists drawn: line segments first, then markers.
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    codes = np.asarray(codes, dtype=int)
    artists = []
    if not markers:
        lines = True
    if lines and x.size > 1:
        ok = np.isfinite(x) & np.isfinite(y)
        seg = ok[:-1] & ok[1:]
        bad = (codes[:-1] == UNSTABLE) | (codes[1:] == UNSTABLE)
        unknown = (codes[:-1] == UNKNOWN) & (codes[1:] == UNKNOWN) & ~bad
        if markers:
            kinds = ((seg & ~bad, "-", None, STABLE), (seg & bad, "--", None, UNSTABLE))
        else:
            kinds = (
                (seg & ~bad & ~unknown, "-", label, STABLE),
                (seg & bad, "--", f"{label}, unstable", UNSTABLE),
                (seg & unknown, ":", f"{label}, {UNKNOWN_TEXT}", UNKNOWN),
            )
        for keep, ls, lab, code in kinds:
            if np.any(keep):
                px, py = _pieces(x, y, keep)
                style = {"ls": ls, "color": colour, "lw": lw, "alpha": alpha, "zorder": zorder}
                (ln,) = ax.plot(px, py, label=lab, gid=STABILITY_GIDS[code], **style)
                artists.append(ln)
    if not markers:
        return artists
    shown = np.isfinite(y)
    styles = (
        (STABLE, label, {"mfc": colour, "fillstyle": "full"}),
        (UNSTABLE, f"{label}, unstable", {"mfc": "none", "fillstyle": "none", "mew": 1.0}),
        (UNKNOWN, f"{label}, {UNKNOWN_TEXT}", {"fillstyle": "bottom", "mfc": colour, "mfcalt": "none"}),
    )
    for code, lab, kw in styles:
        m = shown & (codes == code)
        if np.any(m):
            size = ms * 1.4 if code == UNSTABLE else ms * 1.3 if code == UNKNOWN else ms
            (mk,) = ax.plot(
                x[m],
                y[m],
                ls="none",
                marker=marker,
                ms=size,
                color=colour,
                mec=colour,
                label=lab,
                alpha=alpha,
                zorder=zorder + 0.1,
                gid=STABILITY_GIDS[code],
                **{("markerfacecoloralt" if k == "mfcalt" else k): v for k, v in kw.items()},
            )
            artists.append(mk)
    return artists


def mark_not_converged(
    ax, x, colour: str, label: str, text: str = "not converged", marker: str = "x", row: int = 0
):
    """Crosses (``marker``) on the bottom edge of the axes at ``x``, labelled ``"{label}: {text} (n)"``.

    Returns the artist (None when ``x`` is empty). Row ``row`` lies :data:`NC_ROW` points
    above row 0, so that the marks of two series at one speed (up and down) both show.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    x : array_like
        Abscissae of the points, in data coordinates; non-finite ones are left out.
    colour : str
        Matplotlib colour of the marks.
    label : str
        Name of the series in the legend entry.
    text : str
        What the marks stand for, in the legend entry.
    marker : str
        Matplotlib marker.
    row : int
        The row of marks (0 on the edge; the sweeps put the down sweep's in row 1).

    Returns
    -------
    matplotlib.lines.Line2D or None
        The marks (gid :data:`NOT_CONVERGED_GID`), or None when ``x`` has no finite value.
    """
    from matplotlib.transforms import ScaledTranslation

    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    if x.size == 0:
        return None
    lift = ScaledTranslation(0.0, row * NC_ROW / 72.0, ax.figure.dpi_scale_trans)
    (ln,) = ax.plot(
        x,
        np.full(x.size, NC_HEIGHT),
        ls="none",
        marker=marker,
        ms=5,
        mew=1.2,
        color=colour,
        transform=ax.get_xaxis_transform() + lift,
        clip_on=False,
        zorder=5,
        label=f"{label}: {text} ({x.size})",
        gid=NOT_CONVERGED_GID,
    )
    # the lifted transform hides the data branch from autoscaling: include x by hand
    ax.update_datalim(np.column_stack([x, np.zeros_like(x)]), updatey=False)
    ax.autoscale_view(scaley=False)
    return ln


def clip_to_scale(ax, x, y, ylim, colour: str, label: str, codes=None) -> tuple[NDArray, list]:
    """Replace the values of ``y`` outside ``ylim = (low, high)`` by NaN; mark them.

    Each side with values beyond it gets carets on that edge of the axes (at the limit
    itself, in data coordinates) labelled with their count and extreme value; the caller
    sets the axes limits to ``ylim``. Returns (the clipped y, the marker artists).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw the carets on.
    x : array_like
        Abscissae of the points.
    y : array_like
        Values of the points; not modified (a copy is clipped).
    ylim : (float or None, float or None) or None
        The scale (low, high); None on one side: no limit there; None: nothing is clipped.
    colour : str
        Matplotlib colour of the carets.
    label : str
        Name of the series in the legend entries.
    codes : array_like of int, optional
        Stability codes of the points (:func:`stability_codes`): the carets of a side are
        open when all its points beyond the scale are unstable, filled otherwise.

    Returns
    -------
    y : ndarray
        Copy of ``y`` (float) with the values beyond the scale replaced by NaN.
    artists : list of matplotlib.lines.Line2D
        The carets, one artist per side with values beyond it.
    """
    y = np.asarray(y, dtype=float).copy()
    x = np.asarray(x, dtype=float)
    artists = []
    if ylim is None:
        return y, artists
    low, high = ylim
    for limit, side in ((high, "above"), (low, "below")):
        if limit is None:
            continue
        with np.errstate(invalid="ignore"):
            off = (y > limit) if side == "above" else (y < limit)
        if not np.any(off):
            continue
        if side == "above":
            i, word = int(np.argmax(np.where(off, y, -np.inf))), "max"
        else:
            i, word = int(np.argmin(np.where(off, y, np.inf))), "min"
        note = f"{label}: {int(off.sum())} {side} the scale ({word} {y[i]:.3g} at {x[i]:.5g})"
        open_ = codes is not None and np.all(np.asarray(codes)[off] == UNSTABLE)
        (mk,) = ax.plot(
            x[off],
            np.full(int(off.sum()), limit, dtype=float),
            ls="none",
            marker="^" if side == "above" else "v",
            ms=6,
            color=colour,
            mfc="none" if open_ else colour,
            clip_on=False,
            zorder=5,
            label=note,
        )
        artists.append(mk)
        y[off] = np.nan
    return y, artists


def mark_jumps(ax, x, y_from, y_to, colour: str, label: str) -> list:
    """Jumps as dotted vertical arrows at ``x`` from ``y_from`` to ``y_to``, labelled
    ``"{label}: jump (n)"``; a jump without a finite value at either end is left out (the
    point off the branch is marked as missing by the sweep's own marks).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    x : array_like
        Abscissa of each jump (the midpoint of the last point on the branch left and the
        first on the new one), in data coordinates.
    y_from, y_to : array_like
        The values at those two points.
    colour : str
        Matplotlib colour of the arrows.
    label : str
        Name of the series in the legend entry.

    Returns
    -------
    list of matplotlib.lines.Line2D
        The shafts (labelled) and the heads (gid :data:`JUMP_GID` both); empty when none
        is drawn.
    """
    x, a, b = (np.asarray(v, dtype=float).reshape(-1) for v in (x, y_from, y_to))
    ok = np.isfinite(x) & np.isfinite(a) & np.isfinite(b) & (a != b)
    if not ok.any():
        return []
    x, a, b = x[ok], a[ok], b[ok]
    nan = np.full(x.size, np.nan)
    (shaft,) = ax.plot(
        np.column_stack([x, x, nan]).ravel(),
        np.column_stack([a, b, nan]).ravel(),
        ls=":",
        lw=1.2,
        color=colour,
        zorder=4,
        gid=JUMP_GID,
        label=f"{label}: jump ({x.size})",
    )
    heads = []
    for up, marker in ((b > a, "^"), (b < a, "v")):
        if up.any():
            (h,) = ax.plot(x[up], b[up], ls="none", marker=marker, ms=4, color=colour, zorder=4, gid=JUMP_GID)
            heads.append(h)
    return [shaft, *heads]
