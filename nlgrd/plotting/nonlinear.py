"""Plots of nonlinear mesh responses: sweeps (up/down), continuation curves, time histories.

Sweeps and curves follow the conventions of :mod:`nlgrd.plotting.common`: up and down in
different colours and markers, stable filled/solid, unstable open/dashed, unknown
stability half-filled and stated in the legend, non-converged points as crosses on the
bottom edge counted in the legend, values beyond ``ylim`` as carets on the edge.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from nlgrd.plotting.common import (
    DIRECTION_MARKERS,
    NO_RESPONSE_GID,
    UNKNOWN,
    answer_marker_style,
    axis_label,
    clip_to_scale,
    direction_colours,
    draw_points,
    flags,
    get_ax,
    mark_jumps,
    mark_not_converged,
    place_legend,
    stability_codes,
)
from nlgrd.units import hz

#: Default abscissa of the sweep figures: (label, factor from the mesh frequency [Hz]).
MESH_HZ = ("mesh frequency [Hz]", 1.0)

_LABELS = {
    "dte_rms": ("RMS of alternating DTE [µm]", 1e6),
    "dte_mean": ("mean DTE [µm]", 1e6),
    "dte_p2p": ("peak-to-peak DTE [µm]", 1e6),
    "force_max": ("max mesh force [N]", 1.0),
    "force_min": ("min mesh force [N]", 1.0),
    "dslr": ("DSLR = max W / W0 [-]", 1.0),
    "contact_loss_fraction": ("contact-loss fraction [-]", 1.0),
}
#: Column of the largest Floquet multiplier in sweep tables (finite where stability is known).
FLOQUET = "floquet_max [-]"


#: The "response" column's value at a point with a periodic response (any other value,
#: nlgrd.nonlinear.results.metrics.NO_STABLE in the written tables, marks a point without one).
PERIODIC = "periodic"
#: ... of a point whose period-1 orbit lost stability to a complex pair of multipliers.
QUASI_PERIODIC = "quasi-periodic"
#: ... of a point where no stable periodic response was found.
NO_STABLE = "no stable mesh-periodic response"
#: ... of points answered by time integration: (value, marker), drawn with error bars.
TIME_ANSWERS = (("time domain", "D"), ("chaotic", "*"))
#: Marker size of each kind drawn apart, per marker size of the stable points: a star's ink
#: is thin, so it is drawn larger than a diamond or a square to read as well.
ANSWER_SIZES = {"quasi-periodic (torus HB)": 1.4, "time domain": 1.5, "chaotic": 1.8}
#: Diameters of the period-ν rings per marker size: up outside, down inside it.
RING_SIZES = {"up": 2.4, "down": 1.7}
#: The ``verdict`` of a point whose stability was not computed (a torus answer's).
NOT_COMPUTED = "not computed"
#: The legend's name of a quasi-periodic point answered by the torus harmonic balance (a
#: "quasi-periodic" row whose verdict is "not computed"), drawn as an open square, not joined.
TORUS_ANSWER = ("quasi-periodic (torus HB)", "s")


def _stability(frame: pd.DataFrame) -> np.ndarray:
    """Stability codes of a sweep table: its ``stable`` column where ``floquet_max`` is finite.

    Without a ``stable`` column every point is unknown; without ``floquet_max`` the
    ``stable`` column alone decides (NaN/None: unknown).
    """
    if "stable" not in frame.columns:
        return np.full(len(frame), UNKNOWN, dtype=int)
    known = None
    if FLOQUET in frame.columns:
        known = np.isfinite(pd.to_numeric(frame[FLOQUET], errors="coerce").to_numpy(float))
    return stability_codes(frame["stable"].to_numpy(object), known)


def plot_sweep_frame(
    frame: pd.DataFrame,
    x: str = "base_frequency [Hz]",
    y: str = "dte_rms [um]",
    ax=None,
    label: str | None = None,
    series: int | tuple | dict | None = None,
    *,
    ylim: tuple[float | None, float | None] | None = None,
    lines: bool = True,
    markers: bool = True,
    sort: bool = True,
    ms: float = 3.5,
    lw: float = 1.0,
    alpha: float = 1.0,
    not_converged: str = "not converged",
    jumps: pd.DataFrame | None = None,
):
    """Sweep table(s) with a ``direction`` column: ``y`` against ``x``, one branch per direction.

    Columns used besides ``x`` and ``y``: ``direction``, ``converged`` (missing: finite
    ``y``), ``stable`` and ``floquet_max [-]`` (missing: stability unknown). Non-converged
    rows are never drawn as values (their numbers may be NaN or stale): they are crosses
    on the bottom edge, labelled ``"{label} {direction}: {not_converged} (n)"``.

    Parameters
    ----------
    frame : pandas.DataFrame
        The sweep table(s), e.g. :func:`sweep_table` or a written sweep table, several
        concatenated. Rows with an optional ``response`` column other than "periodic" that
        converged are marked apart on the bottom edge ("no stable periodic response"),
        but "time domain" and "chaotic" rows at their value as open diamonds and stars with
        error bars of 2 x the ``<y>_uncertainty`` column when there is one.
    x : str
        Column of the abscissa (its :func:`~nlgrd.plotting.common.axis_label` is the x label).
    y : str
        Column of the values drawn (its axis label is the y label).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    label : str, optional
        Name of the series in the legend (entries "{label} up", "{label} down", ...).
    series : int, (up, down) colours or {direction: colour}
        Colours (default: series 0 of :data:`~nlgrd.plotting.common.SERIES_COLOURS`).
    ylim : (low, high), optional
        The scale: values beyond it become carets on the edge, noted in the legend.
    lines : bool
        Join consecutive converged points (False: markers only).
    markers : bool
        Draw markers (False: lines only, the line style telling the stability; for
        dense curves such as continuations).
    sort : bool
        Draw each direction in order of ``x`` (False: in the table's order, e.g. along
        the arc length of a continuation curve).
    ms : float
        Marker size of the stable points [pt] (:func:`~nlgrd.plotting.common.draw_points`).
    lw : float
        Line width [pt].
    alpha : float
        Opacity of the lines and markers.
    not_converged : str
        Legend wording of the crosses of the non-converged rows.
    jumps : pandas.DataFrame, optional
        The sweep's jumps, columns ``direction``, ``from`` and ``to`` (the last point on
        the branch left and the first on the new one, in the unit of ``x``): dotted
        vertical arrows between the values drawn there
        (:func:`~nlgrd.plotting.common.mark_jumps`).

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = get_ax(ax)
    colours = direction_colours(series)
    for d in dict.fromkeys(frame["direction"].astype(str).tolist()):
        part = frame[frame["direction"].astype(str) == d]
        if sort:
            part = part.sort_values(x, kind="stable")
        xv = pd.to_numeric(part[x], errors="coerce").to_numpy(float)
        yv = pd.to_numeric(part[y], errors="coerce").to_numpy(float)
        conv = flags(part["converged"].to_numpy(object)) if "converged" in part else np.isfinite(yv)
        codes = _stability(part)
        yv = np.where(conv, yv, np.nan)
        resp = part["response"].astype(str).to_numpy() if "response" in part else np.full(len(part), "")
        # a torus answer: quasi-periodic, its stability "not computed"; in a table written
        # without the verdict (the reports' CSVs), a quasi-periodic row with a value
        if "verdict" in part:
            torus = (resp == QUASI_PERIODIC) & (part["verdict"].astype(str).to_numpy() == NOT_COMPUTED)
        else:
            torus = (resp == QUASI_PERIODIC) & np.isfinite(yv)
        resp = np.where(torus & conv, TORUS_ANSWER[0], resp)
        timed = np.isin(resp, [k for k, _ in (*TIME_ANSWERS, TORUS_ANSWER)]) & conv
        yt, yv = np.where(timed, yv, np.nan), np.where(timed, np.nan, yv)  # never drawn as periodic
        colour = colours.get(d, next(iter(colours.values())))
        name = f"{label} {d}" if label else d
        yv, _ = clip_to_scale(ax, xv, yv, ylim, colour, name, codes)
        draw_points(
            ax,
            xv,
            yv,
            codes,
            colour,
            DIRECTION_MARKERS.get(d, "o"),
            name,
            lines=lines,
            markers=markers,
            ms=ms,
            lw=lw,
            alpha=alpha,
        )
        inner = d == "down"  # its answers inside the up sweep's, its edge marks a row above
        mark_not_converged(ax, xv[~conv], colour, name, not_converged, row=int(inner))
        if "response" in part:
            _mark_responses(ax, resp, conv, xv, yv, colour, name, ms, inner)
            err = _uncertainty_column(y)
            ev = pd.to_numeric(part[err], errors="coerce").to_numpy(float) if err in part else None
            _mark_time_answers(ax, resp, xv, yt, ev, colour, name, ms, inner, _nonnegative(y))
        if jumps is not None and len(jumps):
            _draw_jumps(ax, jumps[jumps["direction"].astype(str) == d], xv, np.fmax(yv, yt), colour, name)
    if ylim is not None:
        ax.set_ylim(*[lim if lim is not None else cur for lim, cur in zip(ylim, ax.get_ylim(), strict=True)])
    ax.set_xlabel(axis_label(x))
    ax.set_ylabel(axis_label(y))
    return ax


def _draw_jumps(ax, jumps: pd.DataFrame, xv, yv, colour: str, name: str) -> None:
    """The jumps of one direction at the midpoints of their two points, between the values
    drawn there (NaN where a point is not drawn as a value: that jump is left out)."""
    if not len(jumps):
        return

    def at(xs):  # the value drawn at each abscissa (the same number, to rounding)
        near = np.isclose(xv[None, :], xs[:, None], rtol=1e-12, atol=0.0)
        return np.where(near.any(axis=1), yv[np.argmax(near, axis=1)], np.nan)

    a = jumps["from"].to_numpy(float)
    b = jumps["to"].to_numpy(float)
    mark_jumps(ax, (a + b) / 2, at(a), at(b), colour, name)


#: Legend wording of the edge marks of converged points without a stable periodic response.
NO_RESPONSE_TEXT = "no stable periodic response"


def _mark_responses(ax, resp, conv, xv, yv, colour, name, ms, inner=False) -> None:
    """Period-ν points ringed where they are drawn (the down sweep's ring inside the up
    sweep's, ``inner``); points without a stable periodic response (quasi-periodic, or none
    found) and no time answer marked on the bottom edge (the down sweep's a row above),
    each kind counted."""
    resp = np.asarray(resp, dtype=str)
    period = np.char.startswith(resp, "period ")
    ring = RING_SIZES["down" if inner else "up"] * ms
    for kind in sorted(set(resp[conv & period])):
        at = conv & (resp == kind) & np.isfinite(yv)
        if not at.any():  # all beyond the scale: counted by the carets, no empty entry
            continue
        ax.plot(xv[at], yv[at], "o", ms=ring, mfc="none", mec=colour, mew=0.8, ls="none", zorder=3,
                label=f"{name}: {kind} ({int(at.sum())})")  # fmt: skip
    answered = (*(k for k, _ in TIME_ANSWERS), TORUS_ANSWER[0])
    lost = conv & ~period & ~np.isin(resp, (PERIODIC, "<NA>", "nan", *answered))
    quasi = resp == QUASI_PERIODIC
    row = int(inner)
    for at, text, marker in ((lost & quasi, "quasi-periodic", "2"), (lost & ~quasi, NO_RESPONSE_TEXT, "1")):
        marks = mark_not_converged(ax, xv[at], colour, name, text, marker=marker, row=row)
        if marks is not None:
            marks.set_gid(NO_RESPONSE_GID)


def _uncertainty_column(column: str) -> str:
    """ "dte_rms [um]" -> "dte_rms_uncertainty [um]" (the tables' rule,
    :func:`nlgrd.nonlinear.results.response_kinds.uncertainty_column`; plotting imports no analysis)."""
    stem, sep, unit = column.partition(" [")
    return f"{stem}_uncertainty{sep}{unit}"


#: Stems of the quantities that cannot be negative (RMS, peak-to-peak, amplitudes, ratios of
#: magnitudes, fractions): their error bars stop at zero.
NONNEGATIVE_STEMS = ("_rms", "_p2p", "_amplitude", "dslr", "_fraction")


def _nonnegative(column: str) -> bool:
    """ "dte_rms [um]" -> True: a quantity of :data:`NONNEGATIVE_STEMS`."""
    stem = column.partition(" [")[0]
    return stem.endswith(NONNEGATIVE_STEMS)


def _mark_time_answers(ax, resp, xv, yt, ev, colour, name, ms, inner=False, nonnegative=False) -> None:
    """Time-domain answers: diamonds ("time domain") or stars ("chaotic") at their value,
    not joined, with error bars of 2 standard uncertainties (cut at zero for a quantity
    that cannot be negative, ``nonnegative``), each kind counted; the torus
    harmonic balance's quasi-periodic answers as squares (no sampling error). Sizes from
    :data:`ANSWER_SIZES`; the up sweep's open, the down sweep's (``inner``) filled and
    smaller, on top, with thinner bars (:func:`~nlgrd.plotting.common.answer_marker_style`)."""
    for kind, marker in ((TORUS_ANSWER[0], TORUS_ANSWER[1]), *TIME_ANSWERS):
        at = (resp == kind) & np.isfinite(yt)
        if not at.any():
            continue
        style = answer_marker_style(ms, ANSWER_SIZES[kind], inner)
        face = colour if style["filled"] else "none"
        if kind == TORUS_ANSWER[0]:  # no sampling error
            ax.plot(xv[at], yt[at], marker, ms=style["ms"], mfc=face, mec=colour, mew=style["mew"], ls="none",
                    zorder=style["zorder"], label=f"{name}: {kind} ({int(at.sum())})")  # fmt: skip
            continue
        yerr = None if ev is None else 2 * np.where(np.isfinite(ev[at]), ev[at], 0.0)
        if yerr is not None and nonnegative:  # an RMS or a ratio has no negative values
            yerr = np.vstack([np.minimum(yerr, np.maximum(yt[at], 0.0)), yerr])
        ax.errorbar(xv[at], yt[at], yerr=yerr, fmt=marker, ms=style["ms"], mfc=face, mec=colour,
                    mew=style["mew"], ecolor=colour, elinewidth=style["elinewidth"], capsize=1.5,
                    ls="none", zorder=style["zorder"],
                    label=f"{name}: {kind} ({int(at.sum())}; ±2σ)")  # fmt: skip


def sweep_table(result, quantity: str = "dte_rms") -> pd.DataFrame:
    """The columns :func:`plot_sweep_frame` reads, from a
    :class:`~nlgrd.nonlinear.results.sweep_results.SweepResult`.

    ``quantity`` (a metric name) becomes column "value" in the units of the axis label;
    frequencies are mesh frequencies [Hz].

    Parameters
    ----------
    result : nlgrd.nonlinear.results.sweep_results.SweepResult
        The sweep; its ``floquet_max`` and ``no_stable`` are used when it has them.
    quantity : str
        A metric name (:data:`~nlgrd.nonlinear.results.metrics.METRIC_NAMES`); the DTE metrics are
        scaled to µm, the others kept as they are.

    Returns
    -------
    pandas.DataFrame
        One row per point: "base_frequency [Hz]", "direction", "converged", "stable",
        "floquet_max [-]" (NaN when not computed), "value" and "response" ("periodic", or
        "no stable response" where no stable periodic response was found).
    """
    _, scale = _LABELS.get(quantity, (quantity, 1.0))
    n = len(result.omega)
    fm = getattr(result, "floquet_max", None)
    unc = getattr(result, "uncertainty", None) or {}
    return pd.DataFrame(
        {
            "base_frequency [Hz]": hz(np.asarray(result.omega, dtype=float)),
            "direction": np.asarray(result.direction).astype(str),
            "converged": np.asarray(result.converged, dtype=object),
            "stable": np.asarray(result.stable, dtype=object),
            FLOQUET: np.full(n, np.nan) if fm is None else np.asarray(fm, dtype=float),
            "value": np.asarray(result.metrics[quantity], dtype=float) * scale,
            "value_uncertainty": np.asarray(unc.get(quantity, np.full(n, np.nan)), dtype=float) * scale,
            "response": _responses(result),
        }
    )


def _responses(result) -> np.ndarray:
    """The "response" column of a sweep's table (periodic, period ν, quasi-periodic, no
    stable response), "periodic" for results without one."""
    if hasattr(result, "period") and hasattr(result, "to_frame"):
        frame = result.to_frame()
        resp = frame["response"].astype(str).to_numpy(object)
        torus = (resp == QUASI_PERIODIC) & (frame["verdict"].astype(str).to_numpy() == NOT_COMPUTED)
        return np.where(torus, TORUS_ANSWER[0], resp)
    no_stable = getattr(result, "no_stable", np.zeros(len(result.omega), dtype=bool))
    return np.where(no_stable, NO_STABLE, PERIODIC)


def plot_sweep(
    result,
    quantity: str = "dte_rms",
    ax=None,
    label: str | None = None,
    series: int | tuple | dict | None = None,
    ylim: tuple[float | None, float | None] | None = None,
    *,
    xaxis: tuple[str, float] = MESH_HZ,
    title: str | None = None,
):
    """Sweep curve(s) of a :class:`~nlgrd.nonlinear.results.sweep_results.SweepResult` against mesh frequency
    (or the speed the range was given in, ``xaxis``).

    Up ▲ and down ▼ in different colours; stable filled/solid, unstable open/dashed,
    unknown stability half-filled and stated in the legend; non-converged points as
    crosses on the bottom edge, counted in the legend (see :func:`plot_sweep_frame`).

    Parameters
    ----------
    result : nlgrd.nonlinear.results.sweep_results.SweepResult
        The sweep.
    quantity : str
        The metric drawn (:data:`~nlgrd.nonlinear.results.metrics.METRIC_NAMES`), in the units of
        its axis label (see :func:`sweep_table`).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    label : str, optional
        Name of the series in the legend (entries "{label} up", "{label} down", ...).
    series : int, (up, down) colours or {direction: colour}, optional
        Colours (default: series 0 of :data:`~nlgrd.plotting.common.SERIES_COLOURS`).
    ylim : (low, high), optional
        The scale, in the units of the axis label: values beyond it become carets on the
        edge, noted in the legend.
    xaxis : (str, float)
        The abscissa's label and its value per mesh frequency [Hz] (e.g. ("pinion speed
        [rpm]", 60 / (N_p |s_p|)) for a range given in rpm).
    title : str, optional
        Title of the axes (e.g. the model's name).

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    table = _in_unit(sweep_table(result, quantity), xaxis)
    jumps = jump_table(result.jumps(), float(xaxis[1])) if hasattr(result, "jumps") else None
    ax = plot_sweep_frame(table, "x", "value", ax, label, series, ylim=ylim, jumps=jumps)
    _finish(ax, quantity, xaxis, title)
    return ax


def jump_table(jumps, per_hz: float = 1.0) -> pd.DataFrame:
    """The ``jumps`` argument of :func:`plot_sweep_frame` from a sweep's jumps.

    Parameters
    ----------
    jumps : sequence of nlgrd.nonlinear.results.jumps.Jump
        Each with ``direction``, ``omega_from`` and ``omega_to`` [rad/s].
    per_hz : float
        The abscissa's value per frequency [Hz] (1: frequency in Hz).

    Returns
    -------
    pandas.DataFrame
        Columns ``direction``, ``from`` and ``to`` in the abscissa's unit.
    """
    rows = [(j.direction, hz(j.omega_from) * per_hz, hz(j.omega_to) * per_hz) for j in jumps]
    return pd.DataFrame(rows, columns=["direction", "from", "to"])


def _in_unit(table: pd.DataFrame, xaxis: tuple[str, float]) -> pd.DataFrame:
    """``table`` with column "x": its mesh frequency [Hz] in the unit of ``xaxis``."""
    table = table.copy()
    table["x"] = table["base_frequency [Hz]"] * float(xaxis[1])
    return table


def _finish(ax, quantity: str, xaxis: tuple[str, float], title: str | None) -> None:
    ax.set_xlabel(xaxis[0])
    ax.set_ylabel(_LABELS.get(quantity, (axis_label(quantity), 1.0))[0])
    if title:
        ax.set_title(title, fontsize=9)
    place_legend(ax)


def plot_continuation(
    result,
    quantity: str = "dte_rms",
    ax=None,
    color: str = "k",
    label: str = "HB",
    ylim: tuple[float | None, float | None] | None = None,
    *,
    xaxis: tuple[str, float] = MESH_HZ,
    title: str | None = None,
):
    """Continuation curve along its arc length, lines only: stable solid, unstable dashed.

    Parts of unknown stability are dotted and stated in the legend; turning points are
    marked with stars. No marker per point: a curve has hundreds to thousands of them.

    Parameters
    ----------
    result : nlgrd.nonlinear.results.sweep_results.ContinuationResult
        The curve (its ``curve``, drawn in the order of the arc length) and its turning
        points.
    quantity : str
        The metric drawn (:data:`~nlgrd.nonlinear.results.metrics.METRIC_NAMES`), in the units of
        its axis label (see :func:`sweep_table`).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    color : str
        Matplotlib colour of the curve and its turning points.
    label : str
        Name of the curve in the legend.
    ylim : (low, high), optional
        The scale, in the units of the axis label: values beyond it become carets on the
        edge, noted in the legend.
    xaxis : (str, float)
        The abscissa's label and its value per mesh frequency [Hz] (see :func:`plot_sweep`).
    title : str, optional
        Title of the axes.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = get_ax(ax)
    table = _in_unit(sweep_table(result.curve, quantity), xaxis)
    plot_sweep_frame(
        table, "x", "value", ax, label, {"curve": color}, ylim=ylim, sort=False, markers=False, lw=1.2
    )
    f, y = table["x"].to_numpy(), table["value"].to_numpy()
    turning = np.asarray(result.turning_indices, dtype=int)
    if turning.size:
        ax.plot(f[turning], y[turning], "*", color=color, ms=8, ls="none", label=f"{label} turning points")
    _finish(ax, quantity, xaxis, title)
    return ax


def plot_time_history(history, quantity: str = "delta", ax=None, label: str | None = None):
    """One period of a :class:`~nlgrd.nonlinear.results.metrics.TimeHistory`.

    ``quantity``: "delta" (DTE δ and LSTE e, µm), "deflection" (δ - e, µm) or "force" (W, N).

    Parameters
    ----------
    history : nlgrd.nonlinear.results.metrics.TimeHistory
        The period, drawn against time [ms].
    quantity : str
        "delta", "deflection" or "force" (any other value: "delta").
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    label : str, optional
        Legend label of the main line (default "δ (DTE)", "δ - e" or "W").

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = get_ax(ax)
    t = history.t * 1e3
    if quantity == "force":
        ax.plot(t, history.force, label=label or "W")
        ax.set_ylabel("mesh force W [N]")
    elif quantity == "deflection":
        ax.plot(t, history.mesh_deflection * 1e6, label=label or "δ - e")
        ax.set_ylabel("mesh deflection δ - e [µm]")
    else:
        ax.plot(t, history.delta * 1e6, label=label or "δ (DTE)")
        ax.plot(t, history.lste * 1e6, ":", label="e (LSTE)")
        ax.set_ylabel("displacement [µm]")
    ax.set_xlabel("time [ms]")
    ax.legend(fontsize=8)
    return ax


def plot_link_history(frame: pd.DataFrame, ax=None):
    """Every column of a link time response's table but ``time [s]`` against time [ms]
    (:meth:`nlgrd.timedomain.link_response.LinkTimeResponse.to_frame`).

    Parameters
    ----------
    frame : pandas.DataFrame
        ``time [s]`` and the link coordinates ``<link>.<coordinate> [um]``.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = get_ax(ax)
    t = frame["time [s]"].to_numpy(float) * 1e3
    for column in frame.columns:
        if column != "time [s]":
            ax.plot(t, frame[column].to_numpy(float), label=column.split(" [")[0])
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("link coordinate [µm]")
    ax.legend(fontsize=8)
    return ax


def plot_spectrum(
    omegas,
    amplitude,
    omega_mesh: float,
    ax=None,
    ylabel: str = "DTE amplitude [µm]",
    scale: float = 1e6,
    label: str | None = None,
):
    """A line spectrum against frequency [Hz], the mesh harmonics told from the sidebands
    and shaft orders between them (:func:`nlgrd.nonlinear.models.shaft_orders.link_spectra`).

    Parameters
    ----------
    omegas : array_like
        Frequencies of the lines [rad/s].
    amplitude : array_like
        Their amplitudes (SI, multiplied by ``scale`` for the axis).
    omega_mesh : float
        The mesh frequency [rad/s]: lines at its multiples are drawn as mesh harmonics.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    ylabel : str
        The amplitude axis label, with its unit.
    scale : float
        Factor from SI to the axis unit.
    label : str, optional
        Legend prefix (e.g. a bearing's name).

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = get_ax(ax)
    w = np.asarray(omegas, dtype=float)
    f = w / (2 * np.pi)
    a = np.asarray(amplitude, dtype=float) * scale
    order = w / omega_mesh
    mesh = np.abs(order - np.round(order)) < 1e-6
    prefix = f"{label}: " if label else ""
    ax.vlines(f[~mesh], 0, a[~mesh], color="C1", lw=1.0, label=f"{prefix}sidebands and shaft orders")
    ax.vlines(f[mesh], 0, a[mesh], color="C0", lw=2.0, label=f"{prefix}mesh harmonics")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(ylabel)
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=8)
    return ax


def plot_ramp(rpm, dte_rms, rpm_jump=None, ax=None, label: str | None = None, ylabel: str | None = None):
    """DTE RMS per cycle of a speed ramp (or another link's level) against shaft speed, its
    jump marked.

    Parameters
    ----------
    rpm : array_like
        Pinion speed of each mesh cycle [rpm].
    dte_rms : array_like
        RMS of the alternating DTE of each cycle [µm].
    rpm_jump : float, optional
        Pinion speed of the jump [rpm], drawn as a vertical line.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    label : str, optional
        Legend label of the curve (default "run-down (time integration)").
    ylabel : str, optional
        Label of the y axis (default "RMS of alternating DTE [µm]").

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = get_ax(ax)
    text = label or "run-down (time integration)"
    (line,) = ax.plot(rpm, dte_rms, "-", lw=0.6, color="0.25", label=text, rasterized=True)
    if rpm_jump is not None:
        ax.axvline(
            rpm_jump, color=line.get_color(), ls="--", lw=1, label=f"{text}: jump at {rpm_jump:.0f} rpm"
        )
    ax.set_xlabel("pinion speed [rpm]")
    ax.set_ylabel(ylabel or "RMS of alternating DTE [µm]")
    return ax
