"""Plots of nonlinear mesh responses: sweeps (up/down), continuation curves, time histories."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

_LABELS = {
    "dte_rms": ("RMS of alternating DTE [µm]", 1e6),
    "dte_mean": ("mean DTE [µm]", 1e6),
    "dte_p2p": ("peak-to-peak DTE [µm]", 1e6),
    "force_max": ("max mesh force [N]", 1.0),
    "force_min": ("min mesh force [N]", 1.0),
    "dslr": ("DSLR = max W / W0 [-]", 1.0),
    "contact_loss_fraction": ("contact-loss fraction [-]", 1.0),
}


def _ax(ax):
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    return ax


def _runs(mask: np.ndarray) -> list[slice]:
    """Slices of consecutive equal values of a boolean mask."""
    if mask.size == 0:
        return []
    edges = np.nonzero(mask[1:] != mask[:-1])[0] + 1
    bounds = np.concatenate([[0], edges, [mask.size]])
    return [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:], strict=False)]


def plot_sweep(result, quantity: str = "dte_rms", ax=None, label: str | None = None):
    """Sweep curve(s) against mesh frequency [Hz]: up ▲ solid, down ▼ dashed-dotted.

    Points flagged unstable (Floquet) are drawn as open markers; non-converged points
    are omitted (NaN).
    """
    ax = _ax(ax)
    ylabel, scale = _LABELS.get(quantity, (quantity, 1.0))
    styles = {"up": ("C0", "^", "-"), "down": ("C3", "v", "-."), "curve": ("k", "o", "-")}
    for d in dict.fromkeys(result.direction.tolist()):
        part = result.select(d)
        c, mk, ls = styles.get(d, ("C2", "o", "-"))
        f = part.omega / (2 * np.pi)
        y = part.metrics[quantity] * scale
        name = f"{label + ' ' if label else ''}{d}"
        ax.plot(f, y, ls, color=c, lw=1, marker=mk, ms=3, label=name)
        unstable = part.stability_known & ~part.stable & part.converged
        if np.any(unstable):
            ax.plot(f[unstable], y[unstable], mk, mfc="none", color=c, ms=6, label=f"{name} unstable")
    ax.set_xlabel("mesh frequency [Hz]")
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=8)
    return ax


def plot_continuation(result, quantity: str = "dte_rms", ax=None, color: str = "k", label: str = "HB"):
    """Continuation curve: stable parts solid, unstable parts dashed, turning points marked."""
    ax = _ax(ax)
    ylabel, scale = _LABELS.get(quantity, (quantity, 1.0))
    curve = result.curve
    f = curve.omega / (2 * np.pi)
    y = curve.metrics[quantity] * scale
    stable = curve.stable
    first = {True: True, False: True}
    for sl in _runs(stable):
        s = bool(stable[sl.start])
        ext = slice(max(sl.start - 1, 0), sl.stop)  # join the pieces
        lab = f"{label} {'stable' if s else 'unstable'}" if first[s] else None
        first[s] = False
        ax.plot(f[ext], y[ext], "-" if s else "--", color=color, lw=1.2, label=lab)
    for i in result.turning_indices:
        ax.plot(f[i], y[i], "x", color=color, ms=7)
    ax.set_xlabel("mesh frequency [Hz]")
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=8)
    return ax


def plot_time_history(history, quantity: str = "delta", ax=None, label: str | None = None):
    """One period of a :class:`~nlgrd.nonlinear_results.TimeHistory`.

    ``quantity``: "delta" (DTE δ and LSTE e, µm), "deflection" (δ - e, µm) or "force" (W, N).
    """
    ax = _ax(ax)
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
