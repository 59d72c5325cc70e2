"""Time integration of the full geared finite-element model, the independent reference
of its harmonic balance (:class:`nlgrd.nonlinear.geared.GearedModel`): one frequency
(:func:`time_response`) and sweeps, each point continuing from the last
(:func:`time_sweep`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.geared import GearedModel
from nlgrd.nonlinear.harmonics import analyse
from nlgrd.nonlinear.results import SweepResult, assemble_result
from nlgrd.nonlinear.sweep import sweep_orders
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
):
    """Direct time integration of the full FE model with the nonlinear mesh at one frequency.

    The same equations as the harmonic balance (M, D(Ω) with c_m w wᵀ, K(Ω) without k_h,
    static torques, LSTE), integrated by :func:`nlgrd.timedomain.integrator.integrate_fe`
    (HHT-α) to a periodic steady state. Hysteretic damping has no time-domain form and
    must be absent.

    Parameters
    ----------
    model : GearedModel
        The model (:func:`nlgrd.nonlinear.geared.build_geared_model`).
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
    )


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

    The independent reference for :func:`nlgrd.nonlinear.geared.geared_sweep`: the same
    equations integrated by HHT-α (:func:`time_response`) to a periodic steady state at
    every frequency, starting from the final state of the previous frequency, so the
    sweep stays on its branch and jumps where it must; the down sweep starts where the up
    sweep ended.

    Parameters
    ----------
    model : GearedModel
        The model (:func:`nlgrd.nonlinear.geared.build_geared_model`).
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
