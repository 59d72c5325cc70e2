"""Plots of the linear rotor model: mode shapes, Campbell diagram, frequency response, deflection."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from nlgrd.system import DOFS_PER_NODE


def _ax(ax):
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    return ax


def plot_mode_shape(result, mode: int = 0, ax=None):
    """Amplitudes of one mode along each shaft, each DOF family scaled to its own maximum.

    Lateral (|uy|, |uz|), torsional (|θx|) and axial (|ux|) amplitudes are drawn for the
    families holding at least 5 % of the mode's kinetic energy.
    """
    ax = _ax(ax)
    system = result.model.system
    phi = result.shapes[:, mode]
    families = [("lateral", (1, 2), ("uy", "uz")), ("torsional", (3,), ("θx",)), ("axial", (0,), ("ux",))]
    styles = ["-o", "--", ":", "-."]
    for kind, locs, names in families:
        if result.fractions[kind][mode] < 0.05:
            continue
        peak = max(np.max(np.abs(phi[d::DOFS_PER_NODE])) for d in locs) or 1.0
        for s, shaft in enumerate(system.shafts):
            dofs = np.array([system.dofs.node_dofs(s, n) for n in range(shaft.n_nodes)])
            for d, name in zip(locs, names, strict=True):
                amp = np.abs(phi[dofs[:, d]]) / peak
                ax.plot(shaft.node_positions, amp, styles[s % 4], ms=3, label=f"shaft {s} |{name}|")
    f = result.natural_frequencies[mode]
    ax.set_title(f"mode {mode + 1}: {f:.1f} Hz, {result.kinds[mode]}, {result.whirl[mode]}")
    ax.set_xlabel("axial position [m]")
    ax.set_ylabel("amplitude / family maximum [-]")
    ax.set_ylim(0, 1.08)
    ax.legend(fontsize=7)
    return ax


def plot_campbell(result, ax=None):
    """Damped natural frequencies against speed, order lines and critical speeds."""
    ax = _ax(ax)
    rpm = result.speeds * 30 / np.pi
    colours = {"forward": "C0", "backward": "C3", "planar": "C2", "-": "k", "": "k"}
    for j in range(result.frequencies.shape[1]):
        w = result.whirl[:, j]
        for label, c in colours.items():
            y = np.where(w == label, result.frequencies[:, j], np.nan)
            if np.any(np.isfinite(y)):
                ax.plot(rpm, y, ".", ms=3, color=c)
    for label, order in result.orders.items():
        ax.plot(rpm, order * result.speeds / (2 * np.pi), "k--", lw=0.8)
        ax.annotate(label, (rpm[-1], order * result.speeds[-1] / (2 * np.pi)), fontsize=7)
    for c in result.critical_speeds:
        ax.plot(c["speed [rpm]"], c["frequency [Hz]"], "ko", mfc="none")
    ax.set_ylim(0, np.nanmax(result.frequencies) * 1.05)
    ax.set_xlabel("speed [rpm]")
    ax.set_ylabel("damped natural frequency [Hz]")
    ax.set_title("Campbell diagram (blue forward, red backward, black torsional/axial)")
    return ax


def plot_frequency_response(result, output: int = 0, input: int = 0, ax=None):
    """Magnitude of one receptance against frequency (log scale)."""
    ax = _ax(ax)
    ax.semilogy(result.omega / (2 * np.pi), np.abs(result.H[:, output, input]))
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("|receptance| [m/N]")
    ax.set_title(f"{result.outputs[output]} / {result.inputs[input]}")
    return ax


def plot_static(result, ax=None):
    """Lateral deflection uy, uz along each shaft."""
    ax = _ax(ax)
    system = result.model.system
    for s, shaft in enumerate(system.shafts):
        first = DOFS_PER_NODE * system.dofs.first_node[s]
        q = result.q[first : first + DOFS_PER_NODE * shaft.n_nodes].reshape(-1, DOFS_PER_NODE)
        ax.plot(shaft.node_positions, q[:, 1], "-o", ms=3, label=f"shaft {s} uy")
        ax.plot(shaft.node_positions, q[:, 2], "--", label=f"shaft {s} uz")
    ax.set_xlabel("axial position [m]")
    ax.set_ylabel("deflection [m]")
    ax.legend(fontsize=7)
    return ax
