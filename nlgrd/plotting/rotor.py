"""Plots of the linear rotor model: mode shapes, Campbell diagram, frequency response, deflection."""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from nlgrd.plotting.common import STABLE, UNSTABLE, get_ax

_ax = get_ax


def plot_mode_shape(result, mode: int = 0, ax=None):
    """Amplitudes of one mode along each shaft, each DOF family scaled to its own maximum.

    Lateral (|uy|, |uz|), torsional (|θx|) and axial (|ux|) amplitudes are drawn for the
    families holding at least 5 % of the mode's kinetic energy.

    Parameters
    ----------
    result : nlgrd.rotor.modal.ModalResult
        Modes of a model with a rotor system (``result.model`` set).
    mode : int
        Index of the mode, from 0 (the title counts from 1).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = _ax(ax)
    system = result.model.system
    phi = result.shapes[:, mode]
    families = [("lateral", (1, 2), ("uy", "uz")), ("torsional", (3,), ("θx",)), ("axial", (0,), ("ux",))]
    styles = ["-o", "--", ":", "-."]
    node_dofs = [
        np.array([system.dofs.node_dofs(s, n) for n in range(shaft.n_nodes)])
        for s, shaft in enumerate(system.shafts)
    ]
    every = np.vstack(node_dofs)  # (all nodes, 6)
    for kind, locs, names in families:
        if result.fractions[kind][mode] < 0.05:
            continue
        peak = max(np.max(np.abs(phi[every[:, d]])) for d in locs) or 1.0
        for s, shaft in enumerate(system.shafts):
            dofs = node_dofs[s]
            for d, name in zip(locs, names, strict=True):
                amp = np.abs(phi[dofs[:, d]]) / peak
                ax.plot(shaft.node_positions, amp, styles[s % 4], ms=3, label=f"shaft {s} |{name}|")
    f = result.natural_frequencies[mode]
    zeta = float(np.asarray(result.damping_ratios)[mode])
    verdict = "unstable" if zeta < 0 else "stable" if getattr(result, "damped", True) else "undamped analysis"
    ax.set_title(
        f"mode {mode + 1}: {f:.1f} Hz, ζ = {zeta:.3g} ({verdict}), "
        f"{result.kinds[mode]}, {result.whirl[mode]}",
        fontsize=9,
    )
    ax.set_xlabel("axial position [m]")
    ax.set_ylabel("amplitude / family maximum [-]")
    ax.set_ylim(0, 1.08)
    ax.legend(fontsize=7)
    return ax


#: Colours of the whirl directions in the Campbell diagram ("-": no lateral motion).
WHIRL_COLOURS = {"forward": "C0", "backward": "C3", "planar": "C2", "-": "k"}
_WHIRL_NAMES = {
    "forward": "forward whirl",
    "backward": "backward whirl",
    "planar": "planar (lateral, no whirl)",
    "-": "torsional/axial (no lateral motion)",
}


def campbell_breaks(result, crossing_gap: float = 0.01):
    """Where a Campbell mode curve must not be joined: mask (n_speeds - 1, n_modes).

    ``breaks[i, j]`` is True when mode slot j (the j-th lowest frequency at each speed)
    may change identity between speeds i and i+1: its whirl or kind changes, a value is
    missing, or a neighbouring slot comes within ``crossing_gap`` (relative) at either
    speed, so that the frequency ordering may swap (a crossing or veering).

    Parameters
    ----------
    result : nlgrd.rotor.modal.CampbellResult
        Frequencies, whirl and kind of each mode slot at each speed.
    crossing_gap : float
        Relative frequency gap [-] within which two neighbouring mode slots may cross.

    Returns
    -------
    breaks : ndarray of bool, shape (n_speeds - 1, n_modes)
        True where the curve of a slot must be broken between two speeds.
    """
    F = np.asarray(result.frequencies, dtype=float)
    W = np.asarray(result.whirl, dtype=object)
    K = np.asarray(result.kinds, dtype=object)
    breaks = (W[1:] != W[:-1]) | (K[1:] != K[:-1]) | ~np.isfinite(F[1:]) | ~np.isfinite(F[:-1])
    with np.errstate(invalid="ignore"):
        near = np.zeros(F.shape, dtype=bool)
        gap = np.abs(np.diff(F, axis=1)) <= crossing_gap * np.abs(F[:, 1:])
        near[:, 1:] |= gap
        near[:, :-1] |= gap
    return breaks | near[1:] | near[:-1]


def _label_order(ax, label: str, rpm, f_order, top) -> None:
    """The name of an excitation order at the end of its line inside the axes: at the right
    edge, or where the line leaves through the top (right-aligned, below the edge)."""
    x, y = float(rpm[-1]), float(f_order[-1])
    va = "bottom"
    if top is not None and y > top:
        inside = np.nonzero(np.asarray(f_order) <= top)[0]
        if inside.size == 0:
            return
        i = int(inside[-1])
        # the line crosses f = top between rpm[i] and rpm[i + 1] (linear in speed)
        x = (
            float(np.interp(top, [f_order[i], f_order[i + 1]], [rpm[i], rpm[i + 1]]))
            if i + 1 < len(rpm)
            else x
        )
        y, va = top, "top"
    ax.annotate(label, (x, y), xytext=(-2, -2 if va == "top" else 2), textcoords="offset points",
                ha="right", va=va, fontsize=7)  # fmt: skip


def plot_campbell(result, ax=None, crossing_gap: float = 0.01):
    """Damped natural frequencies against speed, order lines and critical speeds.

    Each mode slot is drawn as points coloured by whirl (:data:`WHIRL_COLOURS`), joined
    only where its identity is unambiguous (:func:`campbell_breaks`): never across a
    change of whirl or kind or a near-crossing with a neighbouring slot. Stability is
    the sign of the damping ratio: stable points filled and joined solid, unstable
    (ζ < 0) open and joined dashed; the legend says which occur.

    Parameters
    ----------
    result : nlgrd.rotor.modal.CampbellResult
        Frequencies [Hz] against speed (drawn in rpm), excitation orders and critical speeds.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    crossing_gap : float
        Relative frequency gap [-] within which two neighbouring mode slots may cross
        (:func:`campbell_breaks`).

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = get_ax(ax, figsize=(9.5, 4.5))
    rpm = result.speeds * 30 / np.pi
    F = np.asarray(result.frequencies, dtype=float)
    Z = np.asarray(result.damping_ratios, dtype=float)
    W = np.asarray(result.whirl, dtype=object)
    breaks = campbell_breaks(result, crossing_gap)
    with np.errstate(invalid="ignore"):
        unstable = Z < 0
    for j in range(F.shape[1]):
        for whirl, c in WHIRL_COLOURS.items():
            on = W[:, j] == whirl
            for code, keep in ((STABLE, on & ~unstable[:, j]), (UNSTABLE, on & unstable[:, j])):
                if np.any(keep & np.isfinite(F[:, j])):
                    ax.plot(
                        rpm[keep],
                        F[keep, j],
                        ls="none",
                        marker="o",
                        ms=2.5 if code == STABLE else 4,
                        color=c,
                        mfc=c if code == STABLE else "none",
                    )
            join = ~breaks[:, j] & on[:-1] & on[1:]
            for ls, m in (
                ("-", join & ~unstable[:-1, j] & ~unstable[1:, j]),
                ("--", join & (unstable[:-1, j] | unstable[1:, j])),
            ):
                if np.any(m):
                    xs = np.column_stack([rpm[:-1][m], rpm[1:][m], np.full(m.sum(), np.nan)]).ravel()
                    ys = np.column_stack([F[:-1, j][m], F[1:, j][m], np.full(m.sum(), np.nan)]).ravel()
                    ax.plot(xs, ys, ls=ls, color=c, lw=1)
    handles = [
        Line2D([], [], color=c, marker="o", ms=3, lw=1, label=_WHIRL_NAMES[w])
        for w, c in WHIRL_COLOURS.items()
        if np.any(W == w)
    ]
    n_unstable = int(np.sum(unstable & np.isfinite(F)))
    handles.append(Line2D([], [], color="0.3", marker="o", ms=3, lw=1, label="stable (ζ ≥ 0): filled, solid"))
    if n_unstable:
        handles.append(
            Line2D(
                [],
                [],
                color="0.3",
                marker="o",
                ms=4,
                mfc="none",
                ls="--",
                lw=1,
                label=f"unstable (ζ < 0): open, dashed ({n_unstable} points)",
            )
        )
    top = np.nanmax(F) * 1.05 if np.any(np.isfinite(F)) else None
    for label, order in result.orders.items():
        f_order = order * result.speeds / (2 * np.pi)
        ax.plot(rpm, f_order, "k:", lw=0.8)
        _label_order(ax, label, rpm, f_order, top)
    if result.orders:
        handles.append(Line2D([], [], color="k", ls=":", lw=0.8, label="excitation orders"))
    crit = list(result.critical_speeds)
    if crit:
        ax.plot(
            [c["speed [rpm]"] for c in crit],
            [c["frequency [Hz]"] for c in crit],
            "kD",
            ms=4,
            ls="none",
        )
        handles.append(
            Line2D([], [], color="k", marker="D", ms=4, ls="none", label=f"critical speeds ({len(crit)})")
        )
    if top is not None:
        ax.set_ylim(0, top)
    ax.set_xlim(rpm[0], rpm[-1])
    ax.set_xlabel("speed [rpm]")
    ax.set_ylabel("damped natural frequency [Hz]")
    ax.set_title(
        "Campbell diagram (curves broken where the mode's whirl or kind changes or modes cross)", fontsize=9
    )
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    return ax


def plot_frequency_response(result, output: int = 0, input: int = 0, ax=None):
    """Magnitude of one receptance against frequency (log scale).

    Parameters
    ----------
    result : nlgrd.rotor.frequency_response.FrequencyResponse
        The receptance matrix, drawn against frequency [Hz].
    output : int
        Index of the response DOF in ``result.outputs``.
    input : int
        Index of the forced DOF in ``result.inputs``.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = _ax(ax)
    ax.semilogy(result.omega / (2 * np.pi), np.abs(result.H[:, output, input]))
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("|receptance| [m/N]")
    ax.set_title(f"{result.outputs[output]} / {result.inputs[input]}")
    return ax


def plot_static(result, ax=None):
    """Lateral deflection uy, uz along each shaft.

    Parameters
    ----------
    result : nlgrd.rotor.frequency_response.StaticResult
        The static deflection; of a model of matrices without a rotor system, the value
        of each DOF against its index.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = _ax(ax)
    system = result.model.system
    if system is None:  # a model of matrices: the value of each DOF, as its table
        ax.plot(np.arange(len(result.q)), result.q, "o", ms=4, label="static deflection")
        ax.set_xlabel("DOF [-]")
        ax.set_ylabel("value [m or rad]")
        return ax
    for s, shaft in enumerate(system.shafts):
        dofs = np.array([system.dofs.node_dofs(s, n) for n in range(shaft.n_nodes)])
        q = result.q[dofs]
        ax.plot(shaft.node_positions, q[:, 1], "-o", ms=3, label=f"shaft {s} uy")
        ax.plot(shaft.node_positions, q[:, 2], "--", label=f"shaft {s} uz")
    ax.set_xlabel("axial position [m]")
    ax.set_ylabel("deflection [m]")
    ax.legend(fontsize=7)
    return ax


def plot_mode_shapes(result, n: int = 6):
    """The first ``n`` mode shapes, two to a row (:func:`plot_mode_shape` each): the figure
    of ``nlgrd modes``.

    Parameters
    ----------
    result : nlgrd.rotor.modal.ModalResult
        Modes of a model with a rotor system (``result.model`` set).
    n : int
        Most modes drawn [-].

    Returns
    -------
    numpy.ndarray of matplotlib.axes.Axes
        The axes of the new figure, (rows, 2); those past the last mode hidden.
    """
    import matplotlib.pyplot as plt

    n = min(n, len(result.eigenvalues))
    rows = (n + 1) // 2
    fig, axes = plt.subplots(rows, 2, figsize=(11, 3 * rows), squeeze=False)
    for i, ax in enumerate(axes.ravel()):
        if i < n:
            plot_mode_shape(result, i, ax=ax)
        else:
            ax.set_visible(False)
    fig.tight_layout()
    return axes
