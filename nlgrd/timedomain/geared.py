"""Time integration of the full geared finite-element model, the independent reference
of its harmonic balance (:class:`nlgrd.nonlinear.models.geared.GearedModel`): one frequency
(:func:`time_response`) and sweeps, each point continuing from the last
(:func:`time_sweep`), or from a harmonic-balance orbit (:func:`start_from_harmonics`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import analyse, differentiate, real_to_complex, sample
from nlgrd.nonlinear.laws.force_laws import BacklashMesh
from nlgrd.nonlinear.models.geared import GearedModel
from nlgrd.nonlinear.results.metrics import LastPeriod, MeshMetrics, TimeHistory, metrics_from_history
from nlgrd.nonlinear.results.sweep_results import SweepResult, assemble_result
from nlgrd.nonlinear.tracing.sweep import sweep_orders
from nlgrd.threads import single_blas_thread
from nlgrd.timedomain.links import LinkIntegrator, settle


@dataclass(frozen=True)
class FETimeResponse(LastPeriod):
    """Time integration of the FE model to periodic steady state at one mesh frequency.

    Attributes
    ----------
    omega : float
        Mesh frequency [rad/s].
    history : TimeHistory
        δ, δ', e, e', W over the last period (one sample per time step).
    converged : bool
        Periodic steady state reached (criterion of :func:`nlgrd.timedomain.links.settle`).
    periods : int
        Periods simulated.
    difference : float
        Last relative period-to-period difference of δ [-].
    q : ndarray (N, steps_per_period) or None
        All DOFs over the last period [SI], when ``store_dofs``.
    state : tuple of ndarray
        (q, q', q'') at the end, to continue a sweep.
    poincare : ndarray (periods,)
        δ at the start of every period integrated (the Poincaré section θ = 0 mod 2π) [m]:
        a fixed point for a mesh-periodic orbit, ν points for period ν, a closed curve for
        a torus.
    """

    omega: float
    history: TimeHistory
    converged: bool
    periods: int
    difference: float
    q: NDArray | None
    state: tuple
    poincare: NDArray | None = None

    def dof(self, index: int) -> NDArray:
        """Time history of one DOF over the last period."""
        if self.q is None:
            raise ValueError("integrate with store_dofs=True to keep DOF histories")
        return self.q[index]

    def metrics(self, mesh: BacklashMesh, H: int = 15) -> MeshMetrics:
        """DTE and mesh-force metrics of the last period."""
        return metrics_from_history(self.history, mesh, H)


def integrate_fe(
    M,
    D,
    K,
    projection: ArrayLike,
    mesh: BacklashMesh,
    static_force: ArrayLike,
    omega: float,
    *,
    steps_per_period: int = 256,
    alpha: float = -0.05,
    tol: float = 1e-6,
    max_periods: int = 3000,
    min_periods: int = 5,
    state0: tuple | None = None,
    store_dofs: bool = True,
) -> FETimeResponse:
    """Integrate an FE model with one nonlinear gear mesh to a periodic steady state.

    The equations M q'' + D q' + K q = F0 - w W(t), W = k_h f(wᵀq - e) + c_m (wᵀq' - e')
    (c_m w wᵀ inside D; k_h ρ(θ) for a parametric mesh), integrated by
    :meth:`LinkIntegrator.of_mesh <nlgrd.timedomain.links.LinkIntegrator.of_mesh>` (HHT-α,
    the mesh's closed-form step) period by period (:func:`nlgrd.timedomain.links.settle`);
    the last period is stepped again on all DOFs to record it.

    Parameters
    ----------
    M, D, K : sparse or dense (N, N)
        Mass [kg], velocity matrix incl. c_m w wᵀ and gyroscopic terms [N s/m], stiffness
        without the mesh [N/m] (e.g. from :class:`nlgrd.rotor.assembly.LinearModel` assembled
        with ``mesh_stiffness=False``).
    projection : array_like (N,)
        The projection w onto the line of action, δ = wᵀ q [-] (the paper's w).
    mesh : BacklashMesh
        k_h, b, the LSTE harmonics in θ = ω t and c_m (used for the e' forcing and W).
    static_force : array_like (N,)
        F0, self-equilibrated static loads [N, N m].
    omega : float
        Mesh frequency [rad/s].
    steps_per_period : int
        Fixed steps per mesh period (Δt = 2π / (ω steps_per_period)) [-].
    alpha : float
        HHT-α parameter in [-1/3, 0] [-].
    tol : float
        Steady-state tolerance of :func:`~nlgrd.timedomain.links.settle`, the changes of δ
        relative to its peak-to-peak range plus W_0/k_h [-].
    max_periods, min_periods : int
        Most and fewest periods integrated [-].
    state0 : tuple (q, q', q''), optional
        Start (e.g. the end state of the previous frequency); default the static solution
        at rest (:func:`nlgrd.timedomain.integrator.static_solution`).
    store_dofs : bool
        Keep all DOFs over the last period.

    Returns
    -------
    FETimeResponse
        The last period, convergence and the end state.

    Raises
    ------
    ModelError
        ``alpha`` outside [-1/3, 0], ``projection`` of the wrong size, ``static_force`` not
        self-equilibrated.
    """
    integ = LinkIntegrator.of_mesh(
        M, D, K, projection, mesh, static_force, omega, steps_per_period=steps_per_period, alpha=alpha
    )
    N, ns, w = integ.N, integ.ns, integ.P[:, 0]
    F0 = np.asarray(static_force, dtype=float).reshape(-1)
    floor = abs(F0 @ w) / (mesh.stiffness * (w @ w))
    run = settle(
        integ, integ.start(state0), tol=tol, max_periods=max_periods, min_periods=min_periods, floor=floor
    )
    rec = integ.record(run.start, np.arange(N) if store_dofs else ())
    e, edot = sample(mesh.lste, ns), omega * sample(differentiate(mesh.lste), ns)
    force = rec.g[0] + mesh.damping * (rec.ydot[0] - edot)
    hist = TimeHistory(integ.dt * np.arange(ns), rec.y[0], rec.ydot[0], e, edot, force)
    s = rec.end
    return FETimeResponse(
        float(omega),
        hist,
        run.converged,
        run.periods,
        run.differences[-1] if run.differences else float("nan"),
        rec.q if store_dofs else None,
        (s[:N].copy(), s[N : 2 * N].copy(), s[2 * N : 3 * N].copy()),
        run.section[0],
    )


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
    static torques, LSTE), integrated by :func:`integrate_fe` (HHT-α) to a periodic
    steady state. Hysteretic damping has no time-domain form and
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
        See :class:`FETimeResponse`.

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
