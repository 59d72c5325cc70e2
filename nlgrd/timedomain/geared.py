"""Time integration of the full geared finite-element model, the independent reference
of its harmonic balance (:class:`nlgrd.nonlinear.models.geared.GearedModel`): one frequency
(:func:`time_response`) and sweeps, each point continuing from the last
(:func:`time_sweep`), or from a harmonic-balance orbit (:func:`start_from_harmonics`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import analyse, real_to_complex
from nlgrd.nonlinear.models.geared import GearedModel
from nlgrd.nonlinear.results.sweep_results import SweepResult, assemble_result
from nlgrd.nonlinear.tracing.sweep import sweep_orders
from nlgrd.threads import single_blas_thread
from nlgrd.timedomain.integrator import integrate_fe


@single_blas_thread
def time_response(
    model: GearedModel,
    omega: float,
    *,
    steps_per_period: int = 512,
    tol: float = 1e-6,
    state0: tuple | None = None,
    store_dofs: bool = False,
    max_periods: int = 3000,
    min_periods: int = 5,
):
    """Direct time integration of the full FE model with the nonlinear mesh at one frequency.

    The same equations as the harmonic balance (M, D(Ω) with c_m w wᵀ, K(Ω) without k_h,
    static torques, LSTE), integrated by :func:`nlgrd.timedomain.integrator.integrate_fe`
    (HHT-α) to a periodic steady state. Hysteretic damping has no time-domain form and
    must be absent.

    Parameters
    ----------
    model : GearedModel
        The model (:func:`nlgrd.nonlinear.models.geared.build_geared_model`).
    omega : float
        Mesh frequency [rad/s].
    steps_per_period : int
        Time steps per mesh period [-].
    tol : float
        Relative period-to-period difference of δ taken as steady state [-].
    state0 : tuple (q, q', q''), optional
        Start state (the end of the previous frequency); default the static solution.
    store_dofs : bool
        Keep every DOF over the last period.
    max_periods, min_periods : int
        Most and fewest mesh periods integrated [-].

    Returns
    -------
    FETimeResponse
        See :class:`nlgrd.timedomain.integrator.FETimeResponse`.

    Raises
    ------
    ModelError
        ``loss_factor`` when the shafts have hysteretic damping.
    """
    lm = model.receptance.model
    if lm.hysteretic_parts:
        raise ModelError(
            "loss_factor", "hysteretic shaft damping has no time-domain form; use viscous damping"
        )
    speed = model.receptance.speed(omega)
    return integrate_fe(
        lm.M,
        lm.damping(speed),
        lm.stiffness(speed),
        model.receptance.W[:, 0],
        model.mesh,
        model.receptance.static_force,
        float(omega),
        steps_per_period=steps_per_period,
        tol=tol,
        state0=state0,
        store_dofs=store_dofs,
        max_periods=max_periods,
        min_periods=min_periods,
    )


def start_from_harmonics(model: GearedModel, omega: float, harmonics: NDArray) -> tuple:
    """The state (q, q', q'') at θ = 0 of a harmonic-balance solution, to integrate from it.

    Every DOF is recovered from the mesh harmonics (G_k = F_k - κ_k Y_k, the balance the
    solver met; :meth:`MeshReceptance.recover`). The integration then checks
    independently whether the orbit is a periodic solution of the full equations that
    attracts: an unstable one departs.

    Parameters
    ----------
    model : GearedModel
        The model solved.
    omega : float
        Mesh frequency [rad/s].
    harmonics : ndarray (2H+1,) or (1, 2H+1)
        Real harmonics [y_0, a_1, b_1, ...] of δ [m].

    Returns
    -------
    tuple of ndarray
        (q, q', q'') at θ = 0 [m, m/s, m/s²] (angles in rad).
    """
    z = np.asarray(harmonics, dtype=float).reshape(-1)
    H = (z.size - 1) // 2
    Y = real_to_complex(z)[:, None]
    F = np.asarray(model.reduced.force(omega, H), dtype=complex).reshape(H + 1, -1)
    kap = np.asarray(model.reduced.kappa(omega, H), dtype=complex).reshape(H + 1, -1)
    mr = model.receptance
    Q = mr.recover(omega, Y, F - kap * Y, F, np.arange(mr.model.n_dofs))
    kw = 1j * omega * np.arange(H + 1)[:, None]  # x(θ) = Re Σ_k Q_k e^{ikθ}
    return tuple(np.real(np.sum(Q * kw**p, axis=0)) for p in range(3))


def time_sweep(
    model: GearedModel,
    omegas: NDArray,
    directions: str = "both",
    *,
    steps_per_period: int = 256,
    tol: float = 1e-4,
    H: int = 15,
    progress: Callable[[int, int], None] | None = None,
) -> SweepResult:
    """Time-domain up and/or down sweep of the full FE model, each point continuing from the last.

    The independent reference for :func:`nlgrd.nonlinear.models.geared.geared_sweep`: the same
    equations integrated by HHT-α (:func:`time_response`) to a periodic steady state at
    every frequency, starting from the final state of the previous frequency, so the
    sweep stays on its branch and jumps where it must; the down sweep starts where the up
    sweep ended.

    Parameters
    ----------
    model : GearedModel
        The model (:func:`nlgrd.nonlinear.models.geared.build_geared_model`).
    omegas : array_like
        Mesh frequencies [rad/s], sorted here.
    directions : {"both", "up", "down"}
        Sweep directions.
    steps_per_period : int
        Time steps per mesh period [-].
    tol : float
        Relative period-to-period difference of δ taken as steady state [-].
    H : int
        Harmonics of the DTE kept in ``harmonics`` and ``amplitudes`` (FFT of the last
        period) [-].
    progress : callable, optional
        Called as ``progress(done, total)`` after each point.

    Returns
    -------
    SweepResult
        ``source`` "time integration (FE, HHT-α)"; ``converged``: a periodic steady state
        was reached; ``iterations``: periods simulated; ``residual``: the last period
        difference (``residual_kind`` "period difference"); metrics from the sampled last
        period; stability not computed (NA): only attracting orbits survive a time
        integration.
    """
    omegas = np.sort(np.asarray(omegas, dtype=float))
    orders = sweep_orders(omegas, directions)
    total = sum(len(o) for _, o in orders)
    rows: dict[str, list] = {k: [] for k in "wdzcrim"}
    state = None
    for name, order in orders:
        for w in order:
            tr = time_response(model, float(w), steps_per_period=steps_per_period, tol=tol, state0=state)
            state = tr.state
            met = tr.metrics(model.mesh, H)
            z = analyse(tr.history.delta, H)[None, :]
            for k, v in zip(
                "wdzcrim", (w, name, z, tr.converged, tr.difference, tr.periods, met), strict=True
            ):
                rows[k].append(v)
            if progress:
                progress(len(rows["w"]), total)
    return assemble_result(
        rows["w"],
        rows["d"],
        rows["z"],
        rows["c"],
        rows["r"],
        rows["i"],
        [np.nan] * len(rows["w"]),
        rows["m"],
        "time integration (FE, HHT-α)",
        residual_kind="period difference",
    )
