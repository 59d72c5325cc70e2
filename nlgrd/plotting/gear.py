"""Plots of the gear mesh: loaded static transmission error, mesh stiffness, load sharing."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np


def _ax(ax):
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    return ax


def _periodic(result, values, cycles):
    """Repeat one period of samples to cover ``cycles`` mesh cycles."""
    period = result.n_cycles
    reps = int(np.ceil(cycles / period))
    phase = np.concatenate([result.phase + k * period for k in range(reps)] + [[reps * period]])
    vals = np.concatenate([np.tile(values, reps), values[:1]])
    keep = phase <= cycles + 1e-12
    return phase[keep], vals[keep]


def plot_lste(result, ax=None, cycles: float = 2):
    """LSTE [µm] against the mesh phase over ``cycles`` mesh cycles (cf. Maliha et al. 2004, Fig. 4).

    The unloaded (no-load) transmission error is drawn dashed when it is not zero.

    Parameters
    ----------
    result : nlgrd.gear.transmission_error.LSTEResult
        The LSTE over one period of the mesh.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    cycles : float
        Number of mesh cycles shown [-]; the period of ``result`` is repeated to cover them.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = _ax(ax)
    phase, lste = _periodic(result, result.lste, cycles)
    ax.plot(phase, lste * 1e6, label=f"LSTE, W = {result.mesh_load:.4g} N")
    nlte = result.unloaded_ste
    if np.any(nlte != 0):
        p2, n2 = _periodic(result, nlte, cycles)
        ax.plot(p2, n2 * 1e6, "--", label="unloaded STE")
    ax.set_xlabel("mesh phase [cycles]")
    ax.set_ylabel("transmission error along LOA [µm]")
    ax.set_title(f"peak-to-peak {result.fluctuation_pp * 1e6:.3f} µm, mean {result.mean * 1e6:.3f} µm")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return ax


def plot_mesh_stiffness(result, ax=None, cycles: float = 2):
    """Tangent mesh stiffness k(t) = dW/dδ [N/m] over ``cycles`` mesh cycles, with its mean.

    Parameters
    ----------
    result : nlgrd.gear.transmission_error.LSTEResult
        The LSTE over one period of the mesh.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    cycles : float
        Number of mesh cycles shown [-]; the period of ``result`` is repeated to cover them.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = _ax(ax)
    phase, k = _periodic(result, result.mesh_stiffness, cycles)
    ax.plot(phase, k, label="k(t)")
    ax.axhline(result.k_mean, color="k", ls=":", label=f"mean {result.k_mean:.4g} N/m")
    ax.set_xlabel("mesh phase [cycles]")
    ax.set_ylabel("mesh stiffness [N/m]")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return ax


def plot_load_sharing(result, ax=None):
    """Load on one tooth pair [N] against its pinion roll angle [rad] through the mesh.

    Slot j of each sample is the pair that entered j cycles earlier, so the slots laid
    end to end trace one pair from the start to the end of contact (over the first
    mesh cycles of the result).

    Parameters
    ----------
    result : nlgrd.gear.transmission_error.LSTEResult
        The load sharing over one period of the mesh.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = _ax(ax)
    n_pc = result.points_per_cycle
    pos = result.pair_roll_angles[:n_pc]
    loads = result.pair_loads[:n_pc]
    for j in range(pos.shape[1]):
        ok = np.isfinite(pos[:, j])
        ax.plot(pos[ok, j], loads[ok, j], color="C0")
    g = result.geometry
    for s, name in (
        (g.lowest_single_contact, "LPSTC"),
        (g.highest_single_contact, "HPSTC"),
        (g.pitch_point, "pitch"),
    ):
        ax.axvline(s / g.base_radius_pinion, color="0.6", ls=":", lw=0.8)
        ax.text(
            s / g.base_radius_pinion, 0.02, name, rotation=90, fontsize=7, transform=ax.get_xaxis_transform()
        )
    ax.axhline(result.mesh_load, color="k", ls="--", lw=0.8, label=f"W = {result.mesh_load:.4g} N")
    ax.set_xlabel("pinion roll angle [rad]")
    ax.set_ylabel("tooth pair load [N]")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return ax


def plot_tip_relief_sweep(sweep, ax=None, design_deflection: float | None = None):
    """Peak-to-peak LSTE against the tip-relief amount (µm), with the optimum marked.

    Parameters
    ----------
    sweep : nlgrd.gear.transmission_error.TipReliefSweep
        The LSTE summaries over the tip-relief amounts.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.
    design_deflection : float, optional
        Deflection W / k_pair of one tooth pair under the load [m]
        (:func:`~nlgrd.gear.transmission_error.single_pair_deflection`), marked by a dotted
        line; not marked when None.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = _ax(ax)
    ax.plot(sweep.amounts * 1e6, sweep.fluctuation_pp * 1e6, "-o", ms=3, label=f"{sweep.shape} tip relief")
    ax.axvline(sweep.optimum * 1e6, color="C1", ls="--", label=f"minimum at {sweep.optimum * 1e6:.1f} µm")
    if design_deflection is not None:
        ax.axvline(
            design_deflection * 1e6, color="k", ls=":", label=f"W / k_pair = {design_deflection * 1e6:.1f} µm"
        )
    ax.set_xlabel("tip relief on pinion and gear [µm]")
    ax.set_ylabel("LSTE peak-to-peak [µm]")
    ax.set_title(f"tip-relief sweep at W = {sweep.mesh_load:.0f} N")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return ax


def plot_lste_panels(result):
    """The LSTE, the mesh stiffness and the load sharing of a gear pair, one above the
    other: the figure of ``nlgrd lste``.

    Parameters
    ----------
    result : nlgrd.gear.transmission_error.LSTEResult
        The LSTE over one period of the mesh.

    Returns
    -------
    numpy.ndarray of matplotlib.axes.Axes
        The three axes of the new figure.
    """
    fig, axes = plt.subplots(3, 1, figsize=(7, 9))
    plot_lste(result, ax=axes[0])
    plot_mesh_stiffness(result, ax=axes[1])
    plot_load_sharing(result, ax=axes[2])
    fig.tight_layout()
    return axes


def plot_lste_file(phase, lste, name: str, computed=None, ax=None):
    """The LSTE of a gear pair's ``lste_file`` (the one the dynamics use) over one mesh
    cycle, with the LSTE computed from the geometry dashed beside it.

    Parameters
    ----------
    phase : array_like
        Mesh phase [cycles].
    lste : array_like
        The file's LSTE at ``phase`` [m].
    name : str
        The file's name, for the legend.
    computed : nlgrd.gear.transmission_error.LSTEResult, optional
        The LSTE computed from the geometry (not used by the dynamics).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure when None.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 3.5))
    ax.plot(phase, np.asarray(lste) * 1e6, "k-", label=f"lste_file {name} (used)")
    if computed is not None:
        ax.plot(
            computed.phase, computed.lste * 1e6, "C0--", lw=1, label="computed from the geometry (not used)"
        )
    ax.set_xlabel("mesh phase [cycles]")
    ax.set_ylabel("LSTE [µm]")
    ax.legend(fontsize=8)
    ax.figure.tight_layout()
    return ax
