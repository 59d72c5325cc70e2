"""Shaft-order excitation: the response of a gear pair whose teeth differ (issue 12, item 4).

Spacing and profile errors that differ from tooth to tooth make the loaded transmission
error repeat only after N mesh cycles (:attr:`nlgrd.gear.mesh.GearMesh.error_period`: a
revolution of the member whose teeth differ, or the hunting period). The frequency plan's
base is then ω/N, a shaft order: the LSTE over the N cycles
(:meth:`~nlgrd.gear.mesh.GearMesh.lste_harmonics`) has harmonics at every shaft order, the
mesh harmonics at the multiples of N, and the response holds the mesh harmonics with their
sidebands at k ω ± j ω/N. The receptances, force law, Floquet stability and bearing
recovery are those of the period-N model (:func:`nlgrd.nonlinear.models.geared.build_geared_model`
with ``period=N``), solved with N H harmonics of the base for H mesh harmonics.

Every analysis (``nlgrd sweep``, the studies, :func:`nlgrd.sweep`) now runs such a model on
the link engine, as every other model: its frequency plan's base is already ω/N
(:meth:`~nlgrd.nonlinear.links.frequency_plan.FrequencyPlan.for_system`) and H counts
harmonics of that base. :func:`link_spectra` gives the DTE and bearing-force spectra of one
point of such a sweep; :func:`shaft_order_sweep` and its spectra on the single-mesh engine
stay until that engine is deleted.
"""

from __future__ import annotations

import dataclasses as dc
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.periods import amplitudes, subharmonic_mask
from nlgrd.nonlinear.models.geared import GearedModel, GearedSweepResult, build_geared_model
from nlgrd.nonlinear.results.bearing_loads import (
    bearing_harmonics,
    bearing_names,
    bearing_response,
    link_bearing_harmonics,
)
from nlgrd.nonlinear.tracing.harmonic_convergence import LADDER, OUTPUT_RTOL, converged_sweep
from nlgrd.nonlinear.tracing.sweep import sweep
from nlgrd.rotor.system import RotorSystem

#: Mesh harmonics of the default ladder of a shaft-order sweep: N times each rung is solved.
SHAFT_ORDER_LADDER = LADDER[:4]


def shaft_order_model(system: RotorSystem, max_mesh_frequency: float, H: int = 5, **kwargs) -> GearedModel:
    """The period-N model of ``system``'s gear pair, N its error period.

    Parameters
    ----------
    system : RotorSystem
        With one gear pair.
    max_mesh_frequency : float
        Highest mesh frequency to be solved [rad/s].
    H : int
        Largest number of *mesh* harmonics (the model takes N H of the base).
    **kwargs
        Further options of :func:`~nlgrd.nonlinear.models.geared.build_geared_model`.

    Returns
    -------
    GearedModel
        Its receptances take the base ω/N.
    """
    N = _error_period(system)
    return build_geared_model(system, max_mesh_frequency, N * H, period=N, **kwargs)


def _error_period(system: RotorSystem) -> int:
    if len(system.gear_pairs) != 1:
        raise ModelError(
            "gear_pairs", f"a shaft-order sweep needs one gear pair, got {len(system.gear_pairs)}"
        )
    return system.gear_pairs[0].error_period


def shaft_order_sweep(
    system: RotorSystem,
    omegas: ArrayLike | None = None,
    rpm: ArrayLike | None = None,
    H: int | None = None,
    directions: str = "both",
    *,
    stability: bool = True,
    model: GearedModel | None = None,
    progress: Callable[[int, int], None] | None = None,
    harmonic_rtol: float = OUTPUT_RTOL,
    receptance: str = "auto",
    jump: str = "restart",
) -> GearedSweepResult:
    """Up and/or down sweep of a gear pair whose teeth differ, over its error period.

    Parameters
    ----------
    system : RotorSystem
        With one gear pair.
    omegas, rpm : array_like, optional
        Mesh frequencies [rad/s] or pinion speeds [rpm] (one of them).
    H : int, optional
        Mesh harmonics (N H harmonics of ω/N are solved). Default: chosen by the error
        estimate of :func:`~nlgrd.nonlinear.tracing.harmonic_convergence.converged_sweep` on the
        rungs N x :data:`SHAFT_ORDER_LADDER`.
    directions : {"up", "down", "both"}
    stability : bool
        Floquet multipliers over the whole period.
    model : GearedModel, optional
        A model from :func:`shaft_order_model` to reuse.
    progress : callable, optional
        ``progress(i, n)`` after each point.
    harmonic_rtol : float
        Tolerance of the error estimate when ``H`` is chosen.
    receptance : str
        See :class:`~nlgrd.nonlinear.reduction.receptance.MeshReceptance` (when ``model`` is built here).
    jump : {"restart", "auto", "arclength", "none"}
        How a sweep lands after a fold (:func:`~nlgrd.nonlinear.tracing.sweep.sweep`). Default
        "restart": arc length over N H harmonics costs minutes per fold (each step
        re-solves every harmonic's receptance derivative), restarts a second or so.

    Returns
    -------
    GearedSweepResult
        ``omega`` the mesh frequencies; harmonics of ω/N; ``period`` N; ``amplitudes`` at the
        mesh harmonics and ``subharmonic_amplitude`` the largest sideband or shaft order;
        metrics and bearing forces over the whole period.
    """
    N = _error_period(system)
    if (rpm is None) == (omegas is None):
        raise ModelError("rpm", "give either pinion speeds (rpm) or mesh frequencies, not both")
    if omegas is None:
        gp = system.gear_pairs[0]
        s_p = abs(system.shafts[gp.pinion_shaft].speed_ratio)
        omegas = np.asarray(rpm, dtype=float) * np.pi / 30 * gp.geometry.teeth_pinion * s_p
    omegas = np.asarray(omegas, dtype=float)
    if omegas.ndim != 1 or omegas.size < 1 or not np.all(np.isfinite(omegas)) or np.any(omegas <= 0):
        raise ModelError("omegas", "must be a non-empty list of positive finite frequencies")
    top = H or SHAFT_ORDER_LADDER[-1]
    if model is None:
        model = shaft_order_model(system, float(omegas.max()), top, receptance=receptance)
    ladder = tuple(N * h for h in SHAFT_ORDER_LADDER if N * h <= model.H)
    if H is None and len(ladder) < 2:
        raise ModelError(
            "model", f"choosing H needs a model built for H >= {SHAFT_ORDER_LADDER[1]} mesh harmonics"
        )
    model.check_range(omegas, N * H if H is not None else ladder[-1])
    base = omegas / N
    reduced = model.reduced
    options = dict(directions=directions, stability=stability, jump=jump, progress=progress)
    if H is None:
        res = converged_sweep(reduced, base, ladder=ladder, rtol=harmonic_rtol, **options)
    else:
        res = sweep(reduced, base, H=N * H, **options)
    bearings = bearing_response(model, res)
    odd = subharmonic_mask(res.H_stored, N)[1::2]
    side = np.array([float(np.max(amplitudes(z)[:, odd], initial=0.0)) for z in res.harmonics])
    mesh = dc.replace(
        res,
        omega=res.omega * N,
        amplitudes=res.amplitudes[:, ::N],
        period=np.full(len(res), N),
        subharmonic_amplitude=np.where(res.converged, side, np.nan),
        base=N,
        H_check=None if res.H_check is None else res.H_check // N,
    )
    return GearedSweepResult(mesh, bearings, model.pinion_rpm(base), bearing_names(system), mesh.H)


def dte_spectrum(result: GearedSweepResult, index: int) -> tuple[NDArray, NDArray]:
    """The DTE spectrum of one point: amplitude at every harmonic of the base.

    Parameters
    ----------
    result : GearedSweepResult
        A sweep whose harmonics are of ω/ν (ν = its ``period``).
    index : int
        The point.

    Returns
    -------
    omegas : ndarray
        j ω / ν, j = 1 .. H [rad/s].
    amplitude : ndarray
        |δ_j| [m].
    """
    m = result.mesh
    nu = int(m.period[index])
    z = np.asarray(m.harmonics[index])[0]
    j = np.arange(1, (z.size - 1) // 2 + 1)
    return j * m.omega[index] / nu, np.hypot(z[1::2], z[2::2])


def bearing_force_spectrum(model: GearedModel, omega: float, harmonics: ArrayLike) -> tuple[NDArray, NDArray]:
    """The force spectrum of every bearing at one point.

    Parameters
    ----------
    model : GearedModel
        The model solved (its receptances take the base ω/ν).
    omega : float
        Mesh frequency [rad/s].
    harmonics : array_like (1, 2H+1)
        Real harmonics of δ on the base [m].

    Returns
    -------
    omegas : ndarray
        j ω / ν, j = 1 .. H [rad/s].
    amplitude : ndarray (H, n_bearings)
        The larger of the y and z force amplitudes at each harmonic [N].
    """
    w = float(omega) / model.receptance.period
    _, f = bearing_harmonics(model, w, harmonics)
    k = np.arange(1, f.shape[0])
    return k * w, np.maximum(np.abs(f[1:, 0::2]), np.abs(f[1:, 1::2]))


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
