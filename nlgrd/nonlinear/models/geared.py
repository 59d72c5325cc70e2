"""Nonlinear periodic response of a geared finite-element rotor (the NLGRD analysis).

Builds the receptance-reduced problem of :mod:`nlgrd.nonlinear.reduction.receptance` for
the system's gear pair (backlash law with the LSTE,
:class:`~nlgrd.nonlinear.laws.force_laws.BacklashMesh`), solves it by harmonic balance over
mesh frequency or pinion speed with the sweeps and continuation of
:mod:`nlgrd.nonlinear.tracing.sweep` and :mod:`nlgrd.nonlinear.tracing.continuation`, and
recovers the bearing displacements and forces of every converged point linearly
(Maliha, Doğruer & Özgüven 2004, §3). The reference speed follows the mesh frequency,
Ω = ω / N_p, so gyroscopic terms and tabulated bearings are rebuilt per point.
"""

from __future__ import annotations

import dataclasses as dc
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.cache import BoundedCache
from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import real_to_complex
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.laws.force_laws import BacklashMesh
from nlgrd.nonlinear.laws.mesh_law import gear_mesh_force
from nlgrd.nonlinear.models.link_model import check_stability_damping
from nlgrd.nonlinear.models.sdof import sdof_model  # noqa: F401  (moved; importers follow at the deletion)
from nlgrd.nonlinear.reduction.receptance import MeshReceptance
from nlgrd.nonlinear.reduction.state_space import FloquetCache, LinearStateSpace
from nlgrd.nonlinear.results.bearing_loads import (
    BearingResponse,
    bearing_names,
    bearing_node_dofs,
    bearing_response,
)
from nlgrd.nonlinear.results.metrics import PointMetrics
from nlgrd.nonlinear.results.response_kinds import uncertainty_column
from nlgrd.nonlinear.results.sweep_results import ContinuationResult, SweepResult
from nlgrd.nonlinear.tracing.auto_period import beyond_period_one, check_period, rows_of
from nlgrd.nonlinear.tracing.continuation import continuation
from nlgrd.nonlinear.tracing.harmonic_convergence import (
    LADDER,
    OUTPUT_RTOL,
    converged_continuation,
    converged_sweep,
    next_harmonics,
)
from nlgrd.nonlinear.tracing.sweep import sweep
from nlgrd.rotor.modal import gear_pair_mode  # noqa: F401  (moved; importers follow at the deletion)
from nlgrd.rotor.system import RotorSystem


@dataclass
class GearedModel:
    """The reduced nonlinear model of a geared rotor and what recovery needs.

    Attributes
    ----------
    system : RotorSystem
    receptance : MeshReceptance
    mesh : BacklashMesh
        k_h, b, LSTE harmonics (mean removed), c_m and W_0.
    reduced : ReducedModel
        κ_k(ω), F_k(ω) and the projected linear part for Floquet stability.
    bearing_dofs : ndarray of int
        The (uy, uz) DOFs of each bearing node, bearing by bearing.
    max_mesh_frequency : float
        Highest mesh frequency the model was built for [rad/s].
    H : int
        Largest number of harmonics the model was built for.
    """

    system: RotorSystem
    receptance: MeshReceptance
    mesh: BacklashMesh
    reduced: ReducedModel
    bearing_dofs: NDArray = field(repr=False)
    max_mesh_frequency: float = np.inf
    H: int = 10**9

    def check_range(self, omegas: NDArray, H: int) -> None:
        """Raise ModelError when ``omegas`` [rad/s] or ``H`` exceed what the model was built for
        (its modal bases and stability basis are sized by them)."""
        top = float(np.max(omegas))
        if top > self.max_mesh_frequency * (1 + 1e-9) or H > self.H:
            raise ModelError(
                "model",
                f"built for mesh frequencies up to {self.max_mesh_frequency / (2 * np.pi):.6g} Hz and "
                f"H <= {self.H}; asked for {top / (2 * np.pi):.6g} Hz and H = {H}: build it again "
                "with build_geared_model(system, max_mesh_frequency, H)",
            )

    @cached_property
    def cache(self) -> BoundedCache:
        """Models derived from this one (the period-2 model of ``period="auto"`` sweeps)."""
        return BoundedCache(4)

    def mesh_frequency(self, rpm: NDArray) -> NDArray:
        """Mesh frequency [rad/s] at pinion speeds ``rpm``."""
        return np.asarray(rpm, dtype=float) * np.pi / 30 / self.receptance.speed_per_mesh_frequency

    def pinion_rpm(self, omega: NDArray) -> NDArray:
        """Pinion speed [rpm] at mesh frequencies ``omega`` [rad/s]."""
        return np.asarray(omega, dtype=float) * self.receptance.speed_per_mesh_frequency * 30 / np.pi


def build_geared_model(
    system: RotorSystem,
    max_mesh_frequency: float,
    H: int = 5,
    receptance: str = "auto",
    lste_harmonics: int = 30,
    aft: bool = False,
    period: int = 1,
) -> GearedModel:
    """Reduce ``system`` onto its gear mesh.

    Parameters
    ----------
    system : RotorSystem
        With exactly one gear pair (a single stage).
    max_mesh_frequency : float
        Highest mesh frequency to be solved [rad/s]; sizes the modal bases.
    H : int
        Largest number of harmonics to be used (for the modal basis).
    receptance : {"auto", "poles", "direct", "modal"}
        See :class:`~nlgrd.nonlinear.reduction.receptance.MeshReceptance`.
    lste_harmonics : int
        Harmonics kept of the LSTE (solutions use the first H).
    aft : bool
        Fourier coefficients of the mesh force by AFT instead of exact integration.
    period : int
        ν: the model of orbits of ν mesh periods, solved at the base ω/ν with ``H``
        harmonics of it (the LSTE at the harmonics νk, the speed still that of the mesh
        frequency ν ω_b; :mod:`nlgrd.nonlinear.tracing.subharmonic`). ``max_mesh_frequency`` stays
        the highest *mesh* frequency.

    Returns
    -------
    GearedModel
        The reduced model, valid up to ``max_mesh_frequency`` and ``H``.

    Raises
    ------
    ModelError
        Not exactly one gear pair, or ``max_mesh_frequency`` not positive and finite.
    """
    if len(system.gear_pairs) != 1:
        raise ModelError(
            "gear_pairs", f"the nonlinear analysis needs exactly one gear pair, got {len(system.gear_pairs)}"
        )
    if not (np.isfinite(max_mesh_frequency) and max_mesh_frequency > 0):
        raise ModelError("max_mesh_frequency", f"must be positive and finite, got {max_mesh_frequency!r}")
    gp = system.gear_pairs[0]
    mr = MeshReceptance(
        system, method=receptance, max_frequency=H * max_mesh_frequency / period, period=period
    )
    mesh = gear_mesh_force(
        gp, mr.k_h[0], mr.c_m[0], lste_harmonics, order=period, method="aft" if aft else "exact"
    )
    bearing_dofs = bearing_node_dofs(system)
    mr.set_output_dofs(bearing_dofs)

    def force(omega: float, H_: int) -> NDArray:
        E = real_to_complex(mesh.offset(H_)[0])
        return mr.force(omega, H_, E[:, None])

    def force_derivative(omega: float, H_: int) -> NDArray:
        E = real_to_complex(mesh.offset(H_)[0])
        return mr.force_derivative(omega, H_, E[:, None])

    # one store for the model's state spaces: a down sweep finds the up sweep's Floquet work
    floquet_cache = FloquetCache(maxsize=4096)

    @lru_cache(maxsize=4)
    def state_space_at(omega: float) -> LinearStateSpace:
        # modes to 3x the highest mesh frequency: Floquet verdicts as with modes to 3H x
        # (tests/test_geared_response.py), at a tenth of the size
        return LinearStateSpace(*mr.state_space(omega, max_mesh_frequency), cache=floquet_cache)

    metrics = PointMetrics(mesh)
    reduced = ReducedModel(
        kappa=mr.kappa,
        force=force,
        nonlinearities=(mesh,),
        state_space_at=state_space_at,
        kappa_derivative=mr.kappa_derivative,
        force_derivative=force_derivative,
        outputs=metrics.outputs,
        branch_signature=metrics.signature,
        metrics=metrics,
    )
    return GearedModel(system, mr, mesh, reduced, bearing_dofs, float(max_mesh_frequency), int(H))


#: Bearing outputs below this fraction of the largest of their kind (over bearings and
#: points) are rounding of the recovery, not response.


@dataclass(frozen=True)
class GearedSweepResult:
    """Sweep of a geared FE model: mesh results (:class:`SweepResult`) plus bearings.

    Attributes
    ----------
    mesh : SweepResult
        Per point: harmonics of δ, convergence, stability and mesh metrics.
    bearings : BearingResponse
    rpm : ndarray
        Pinion speed of each point [rpm].
    bearing_names : list of str
        One name per bearing (its own, or shaft and node).
    H : int
        H of docs/conventions.md: harmonics of the mesh frequency, as ``mesh.H``.
    bearing_uncertainty : BearingResponse, optional
        The standard uncertainty of the bearing outputs at the time-answered points
        (:mod:`nlgrd.timedomain.sweep_answers`; NaN elsewhere), written beside them as
        ``<bearing> <quantity>_uncertainty [unit]``.
    """

    mesh: SweepResult
    bearings: BearingResponse
    rpm: NDArray
    bearing_names: list[str]
    H: int
    bearing_uncertainty: BearingResponse | None = None

    def to_frame(self) -> pd.DataFrame:
        """Tidy table: the mesh columns, pinion speed, and per-bearing columns (units in names)."""
        df = self.mesh.to_frame()
        df.insert(1, "pinion_speed [rpm]", self.rpm)
        b, u = self.bearings, self.bearing_uncertainty
        timed = self.mesh.time_answered
        ok = np.asarray(self.mesh.converged, dtype=bool) & (~self.mesh.no_stable | timed)
        columns = (
            ("displacement_max [um]", b.displacement_max, 1e6),
            ("displacement_rms [um]", b.displacement_rms, 1e6),
            ("force_mean [N]", b.force_mean, 1.0),
            ("force_rms [N]", b.force_rms, 1.0),
            ("force_max [N]", b.force_max, 1.0),
            ("force_amplitude [N]", b.force_amplitude, 1.0),
        )
        for j, name in enumerate(self.bearing_names):
            for col, values, scale in columns:
                df[f"{name} {col}"] = np.where(ok, values[:, j] * scale, np.nan)
                if u is not None and timed.any():
                    unc = getattr(u, col.split(" ")[0])[:, j] * scale
                    df[f"{name} {uncertainty_column(col)}"] = np.where(timed, unc, np.nan)
        return df

    def jumps(self):
        """Jumps of the up and down sweeps (see :meth:`SweepResult.jumps`)."""
        return self.mesh.jumps()

    def failures(self):
        """Points that did not converge."""
        return self.mesh.failures()

    def plot(self, quantity: str = "dslr", ax=None):
        """Plot a mesh quantity against mesh frequency (:func:`nlgrd.plotting.nonlinear.plot_sweep`)."""
        return self.mesh.plot(quantity=quantity, ax=ax)


def geared_sweep(
    system: RotorSystem,
    omegas: NDArray | None = None,
    rpm: NDArray | None = None,
    H: int | None = None,
    directions: str = "both",
    *,
    method: str = "newton",
    stability: bool = True,
    receptance: str = "auto",
    tol: float = 1e-10,
    max_iter: int = 150,
    jump: str = "auto",
    model: GearedModel | None = None,
    progress: Callable[[int, int], None] | None = None,
    harmonic_rtol: float = OUTPUT_RTOL,
    period: int | str = "auto",
) -> GearedSweepResult:
    """Up and/or down harmonic-balance sweep of a geared FE model.

    Parameters
    ----------
    system : RotorSystem
        With one gear pair.
    omegas : array_like, optional
        Mesh frequencies [rad/s]; or
    rpm : array_like, optional
        pinion speeds [rpm].
    H : int, optional
        Number of harmonics. Default: chosen so that RMS DTE and maximum mesh force are
        within ``harmonic_rtol`` (0.5 %) of the H -> infinity answer and every jump stays
        put (:func:`nlgrd.nonlinear.tracing.harmonic_convergence.converged_sweep`; the estimate is stored
        per point). Give 5 for the paper's choice.
    directions : {"up", "down", "both"}
    method : {"newton", "quasi-linear", "hybr"}
        Solver (see :func:`nlgrd.nonlinear.hb.solvers.solve`).
    stability : bool
        Floquet multipliers of each point (projected linear part).
    receptance : {"auto", "poles", "direct", "modal"}
        See :class:`~nlgrd.nonlinear.reduction.receptance.MeshReceptance` (when ``model`` is built here).
    tol : float
        Convergence tolerance of the solver (relative residual).
    max_iter : int
        Newton iterations per point. The Jacobian jumps where contact is first lost
        (grazing), where damped Newton can need a hundred iterations; each costs little.
    jump : {"auto", "arclength", "restart", "none"}
        How a sweep lands on the other branch after a fold (:func:`nlgrd.nonlinear.tracing.sweep.sweep`);
        a point where every attempt fails is flagged, never guessed.
    model : GearedModel, optional
        Reuse a reduced model (e.g. across directions or harmonics).
    progress : callable, optional
        ``progress(i, n)`` after each point.
    harmonic_rtol : float
        Tolerance of the estimated relative error when ``H`` is chosen (``H`` None).
    period : {"auto", 1, 2}
        "auto" (default): the mesh-periodic orbits where they are stable, and where one has
        lost stability by period doubling the stable period-2 orbit
        (:func:`nlgrd.nonlinear.tracing.subharmonic.period_sweep` from the critical mode, with
        2 H_max harmonics of ω/2; :func:`nlgrd.nonlinear.tracing.auto_period.merge_periods`); without
        ``stability`` nothing is known of that, and it is 1. 1: mesh-periodic orbits only.
        2: the period-2 branches alone (needs ``stability``). Orbits of 3 or more mesh periods
        are found by :func:`nlgrd.nonlinear.tracing.orbit_search.search_orbits` instead.

    Returns
    -------
    GearedSweepResult
        Points that did not converge carry ``converged = False`` and NaN outputs. The
        ``period`` of each point; with ``period`` other than 1 the harmonics are of ω/2.

    Raises
    ------
    ModelError
        Both or neither of ``omegas`` and ``rpm``, frequencies not positive and finite, a
        ``period`` other than 1, 2 or "auto", or a ``model`` built for a lower frequency or H.
    """
    if (rpm is None) == (omegas is None):
        raise ModelError("rpm", "give either pinion speeds (rpm) or mesh frequencies, not both")
    check_period(period, stability)
    check_stability_damping(system, stability)
    if model is None:
        top = np.max(omegas) if omegas is not None else None
        if top is None:
            if not system.gear_pairs:
                raise ModelError("gear_pairs", "the model has no gear pair")
            gp = system.gear_pairs[0]
            s_p = abs(system.shafts[gp.pinion_shaft].speed_ratio)
            top = np.max(rpm) * np.pi / 30 * gp.geometry.teeth_pinion * s_p
        model = build_geared_model(system, float(top), H=H or LADDER[-1], receptance=receptance)
    omegas = np.asarray(omegas if omegas is not None else model.mesh_frequency(rpm), float)
    if omegas.ndim != 1 or len(omegas) < 1 or not np.all(np.isfinite(omegas)) or np.any(omegas <= 0):
        raise ModelError("omegas", "must be a non-empty list of positive finite frequencies")
    ladder = _ladder(model) if H is None else ()
    model.check_range(omegas, H if H is not None else ladder[-1])
    reduced = model.reduced
    options = dict(
        directions=directions,
        method=method,
        stability=stability,
        tol=tol,
        max_iter=max_iter,
        jump=jump,
        progress=progress,
    )
    if H is None:
        label = getattr(progress, "label", None)

        def on_rung(H_: int) -> None:
            if label is not None:
                progress.label = f"{label} (H = {H_})"

        res = converged_sweep(reduced, omegas, ladder=ladder, rtol=harmonic_rtol, on_rung=on_rung, **options)
    else:
        res = sweep(reduced, omegas, H=H, **options)
    if period == 1 or not stability:
        bearings = bearing_response(model, res)
    else:
        res, bearings = _beyond_period_one(model, res, omegas, directions, period, harmonic_rtol)
    return GearedSweepResult(res, bearings, model.pinion_rpm(res.omega), bearing_names(model.system), res.H)


def _beyond_period_one(model: GearedModel, p1: SweepResult, omegas, directions, period, harmonic_rtol):
    """The period-2 sweep where ``p1`` is flip-unstable, merged (``period`` "auto") or alone
    (2), with its bearing recovery on the period-2 model."""
    H_check = 2 * next_harmonics(p1.H)  # the check of 2 H₁ harmonics of ω/2

    def model2() -> GearedModel:
        return model.cache.get(
            ("period 2", H_check),
            lambda: build_geared_model(
                model.system, model.max_mesh_frequency, H_check, model.receptance.requested_method, period=2
            ),
        )

    res, p2 = beyond_period_one(
        p1, period, lambda: model2().reduced, omegas, directions, H_check, harmonic_rtol
    )
    if p2 is None:
        return p1, bearing_response(model, p1)
    b2 = bearing_response(model2(), dc.replace(p2, omega=p2.omega / 2))  # on model2's base
    if period == 2:
        return res, b2
    merged = res
    b1 = bearing_response(model, p1)
    rows2 = rows_of(p1, p2)
    two = (merged.period == 2)[:, None]
    keys = BearingResponse.__dataclass_fields__
    return merged, BearingResponse(**{k: np.where(two, getattr(b2, k)[rows2], getattr(b1, k)) for k in keys})


def geared_continuation(
    system: RotorSystem,
    omega_start: float,
    omega_end: float,
    H: int | None = None,
    *,
    model: GearedModel | None = None,
    stability: bool = True,
    harmonic_rtol: float = OUTPUT_RTOL,
    **kwargs,
) -> ContinuationResult:
    """Pseudo-arc-length continuation of a geared FE model's response in mesh frequency.

    Returns the whole response curve, unstable branch included
    (:func:`nlgrd.nonlinear.tracing.continuation.continuation`; ``kwargs`` are passed on).
    ``H`` default: chosen by the error estimate
    (:func:`nlgrd.nonlinear.tracing.harmonic_convergence.converged_continuation`).

    Parameters
    ----------
    system : RotorSystem
        With one gear pair.
    omega_start, omega_end : float
        Frequency range of the curve [rad/s].
    H : int, optional
        Number of harmonics; default chosen by the error estimate.
    model : GearedModel, optional
        Reuse a reduced model.
    stability : bool
        Floquet multipliers of each point.
    harmonic_rtol : float
        Tolerance of the estimated relative error when ``H`` is chosen (``H`` None).
    **kwargs
        Further options of :func:`nlgrd.nonlinear.tracing.continuation.continuation`.

    Returns
    -------
    ContinuationResult
        The response curve of the mesh coordinate (no bearing recovery).

    Raises
    ------
    ModelError
        Not exactly one gear pair (when ``model`` is built here), or a ``model`` built for
        a lower frequency or H.
    """
    if model is None:
        model = build_geared_model(system, max(omega_start, omega_end), H=H or LADDER[-1])
    span = np.array([omega_start, omega_end])
    if H is not None:
        model.check_range(span, H)
        return continuation(model.reduced, omega_start, omega_end, H, stability=stability, **kwargs)
    ladder = _ladder(model)
    model.check_range(span, ladder[-1])
    return converged_continuation(
        model.reduced,
        omega_start,
        omega_end,
        ladder=ladder,
        rtol=harmonic_rtol,
        stability=stability,
        **kwargs,
    )


def _ladder(model: GearedModel) -> tuple[int, ...]:
    """The rungs of :data:`LADDER` the model was built for (at least two)."""
    ladder = tuple(h for h in LADDER if h <= model.H)
    if len(ladder) < 2:
        raise ModelError(
            "model",
            f"choosing H needs a model built for H >= {LADDER[1]} (ladder {LADDER}); it has H = {model.H}",
        )
    return ladder
