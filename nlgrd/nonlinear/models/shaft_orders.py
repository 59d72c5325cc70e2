"""Shaft-order excitation: the response of a gear pair whose teeth differ (issue 12, item 4).

Spacing and profile errors that differ from tooth to tooth make the loaded transmission
error repeat only after N mesh cycles (:attr:`nlgrd.gear.mesh.GearMesh.error_period`: a
revolution of the member whose teeth differ, or the hunting period). The frequency plan's
base is then ω/N, a shaft order
(:meth:`~nlgrd.nonlinear.links.frequency_plan.FrequencyPlan.for_system`): the LSTE over
the N cycles (:meth:`~nlgrd.gear.mesh.GearMesh.lste_harmonics`) has harmonics at every
shaft order, the mesh harmonics at the multiples of N, and the response holds the mesh
harmonics with their sidebands at k ω ± j ω/N. Every analysis runs such a model on the link
engine as any other, H counting harmonics of that base; :func:`link_spectra` gives the DTE
and bearing-force spectra of one point of its sweep, :func:`sideband_amplitudes` its
largest sideband per point.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from nlgrd.nonlinear.results.bearing_loads import bearing_names, link_bearing_harmonics


def link_spectra(model, res, index: int, link: str) -> tuple[NDArray, NDArray, NDArray, list[str]]:
    """The DTE spectrum of a mesh and the force spectrum of every linear bearing at one
    point of a link sweep, from its harmonics (any model; one whose teeth differ has its
    sidebands and shaft orders between the mesh harmonics).

    Parameters
    ----------
    model : nlgrd.nonlinear.models.link_model.LinkModel
        The model swept.
    res : nlgrd.nonlinear.results.sweep_results.SweepResult
        The sweep (``LinkSweepResult.result``); its harmonics are of ω/``base``.
    index : int
        The point.
    link : str
        The mesh's name.

    Returns
    -------
    omegas : ndarray
        j ω/ν, j = 1 .. H', ν the sweep's ``base`` [rad/s].
    dte : ndarray
        |δ_j| of the mesh [m].
    force : ndarray (H', n_bearings)
        The larger of the y and z force amplitudes of each bearing [N].
    names : list of str
        The bearings' names.
    """
    from nlgrd.nonlinear.models.link_model import period_model

    nu = int(res.base)
    m = model if nu == 1 else period_model(model, nu)
    w = float(res.omega[index]) / nu
    z = np.asarray(res.harmonics[index], dtype=float)
    d = m.link_harmonics(z, link)[0]
    j = np.arange(1, (d.size - 1) // 2 + 1)
    if model.system.bearings:
        _, f = link_bearing_harmonics(m, w, z)
        force = np.maximum(np.abs(f[1:, 0::2]), np.abs(f[1:, 1::2]))
    else:
        force = np.zeros((j.size, 0))
    return j * w, np.hypot(d[1::2], d[2::2]), force, bearing_names(model.system)


def sideband_amplitudes(model, res, link: str, every: int) -> NDArray:
    """Per point of a link sweep, the largest DTE line of a mesh between its mesh
    harmonics: the sidebands and shaft orders of errors that repeat every ``every`` base
    harmonics (the mesh's order; NaN where the point has no harmonics).

    Parameters
    ----------
    model : nlgrd.nonlinear.models.link_model.LinkModel
        The model swept.
    res : nlgrd.nonlinear.results.sweep_results.SweepResult
        The sweep (``LinkSweepResult.result``).
    link : str
        The mesh's name.
    every : int
        Base harmonics per mesh harmonic [-].

    Returns
    -------
    ndarray
        [m].
    """
    from nlgrd.nonlinear.models.link_model import period_model

    nu = int(res.base)
    m = model if nu == 1 else period_model(model, nu)
    out = np.full(len(res), np.nan)
    for i, z in enumerate(res.harmonics):
        z = np.asarray(z, dtype=float)
        if not np.all(np.isfinite(z)):
            continue
        d = m.link_harmonics(z, link)[0]
        a = np.hypot(d[1::2], d[2::2])
        out[i] = float(np.max(a[np.arange(1, a.size + 1) % (every * nu) != 0], initial=0.0))
    return out
