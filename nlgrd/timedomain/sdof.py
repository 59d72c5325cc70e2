"""Time integration of the single-DOF gear pair (:class:`nlgrd.nonlinear.models.sdof.SDOFGearPair`),
the independent reference of its harmonic balance.

The equation of motion is integrated with :func:`scipy.integrate.solve_ivp` in segments
of constant contact state, each ended exactly at a contact event, to a periodic steady
state (:func:`integrate`); :func:`time_sweep` continues each frequency from the last.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp

from nlgrd.nonlinear.fourier.harmonics import analyse, differentiate, evaluate
from nlgrd.nonlinear.laws.describing_functions import deadzone
from nlgrd.nonlinear.models.sdof import SDOFGearPair
from nlgrd.nonlinear.results.metrics import LastPeriod, TimeHistory, metrics_from_history
from nlgrd.nonlinear.results.sweep_results import SweepResult, assemble_result
from nlgrd.nonlinear.tracing.sweep import sweep_orders


@dataclass(frozen=True)
class TimeResponse(LastPeriod):
    """Result of a time integration to periodic steady state at one mesh frequency.

    Attributes
    ----------
    omega : float
        Mesh frequency [rad/s].
    history : TimeHistory
        The last simulated period.
    converged : bool
        Periodic steady state reached (criterion in :func:`integrate`).
    periods : int
        Periods simulated.
    difference : float
        Last relative period-to-period difference [-].
    state : ndarray
        [δ, δ'] at the end (for continuing a sweep) [m, m/s].
    """

    omega: float
    history: TimeHistory
    converged: bool
    periods: int
    difference: float
    state: NDArray

    def harmonics(self, H: int) -> NDArray:
        """Real harmonics 0..H of δ over the last period (FFT of the samples)."""
        return analyse(self.history.delta, H)


def _segment_rhs(mode: int, zeta2: float, w0: float, bt: float, ecoef: tuple, rho: NDArray):
    """RHS u'' = -2ζ u' - |m| ρ(θ) (u - ẽ - m b̃) + w0 + 2ζ ẽ' in the scaled variables
    (ρ: real harmonics of k(θ)/k_h, [1.0] for a constant mesh stiffness)."""
    k, a, bb, e0, s = ecoef
    stiff = float(abs(mode))
    parametric = rho.size > 1

    def rhs(tau, y):
        th = s * tau * k
        c, sn = np.cos(th), np.sin(th)
        e = e0 + a @ c + bb @ sn
        de = s * ((bb * k) @ c - (a * k) @ sn)
        kt = stiff * (evaluate(rho, s * tau) if parametric else rho[0])
        return np.array([y[1], -zeta2 * y[1] - kt * (y[0] - e - mode * bt) + w0 + zeta2 * de])

    return rhs


def _events(mode: int, bt: float, ecoef: tuple) -> list:
    k, a, bb, e0, s = ecoef

    def x_of(tau, y):
        th = s * tau * k
        return y[0] - (e0 + a @ np.cos(th) + bb @ np.sin(th))

    def make(level: float, direction: int):
        def ev(tau, y):
            return x_of(tau, y) - level

        ev.terminal = True
        ev.direction = direction
        return ev

    if mode == 1:
        return [make(bt, -1)]
    if mode == -1:
        return [make(-bt, 1)]
    return [make(bt, 1), make(-bt, -1)]


def integrate(
    model: SDOFGearPair,
    omega: float,
    state0: ArrayLike | None = None,
    *,
    tol: float = 1e-7,
    max_periods: int = 3000,
    min_periods: int = 5,
    samples_per_period: int = 1024,
    method: str = "DOP853",
    rtol: float = 1e-10,
) -> TimeResponse:
    """Integrate the SDOF gear pair to a periodic steady state at mesh frequency ``omega``
    (with its mesh stiffness k_h ρ(θ) when ``model.stiffness_variation`` varies).

    The equation is scaled (τ = ω_n t, δ = L u with L = max(b, W_0/k_h, max|e|)) and
    integrated with :func:`scipy.integrate.solve_ivp` in segments of constant contact
    state: terminal ``events`` stop the integration where x = δ - e crosses ±b, and it
    restarts with the other linear law, so no step straddles a kink. The SDOF has one
    natural frequency and is not stiff; the default is the explicit 8th-order DOP853
    (``method="LSODA"`` or ``"Radau"`` also work, slower).

    Steady-state criterion: with d_p = max_j |δ_p(t_j) - δ_{p-1}(t_j)| / s over the
    ``samples_per_period`` samples of period p (s = peak-to-peak of δ + W_0/k_h) and
    ρ = d_p / d_{p-1}, stop when d_p < tol and the geometric remainder d_p ρ/(1-ρ) < tol.

    Parameters
    ----------
    model : SDOFGearPair
    omega : float
        Mesh frequency [rad/s].
    state0 : array_like, optional
        Initial [δ, δ'] [m, m/s]; default the static deflection δ = b + W_0/k_h + e_0.
    tol : float
        Relative steady-state tolerance.
    max_periods, min_periods : int
    samples_per_period : int
        Samples of the returned period (also used by the criterion).
    method : str
        solve_ivp method.
    rtol : float
        solve_ivp relative tolerance (atol = rtol · 1e-2 in scaled units).

    Returns
    -------
    TimeResponse
        The last period, convergence and the end state.
    """
    k_h, m = model.mesh_stiffness, model.mass
    wn = np.sqrt(k_h / m)
    zeta2 = model.mesh_damping / (m * wn)
    b = model.half_backlash
    E = model.lste
    L = max(b, abs(model.static_load) / k_h, float(np.max(np.abs(E))), 1e-12)
    s = omega / wn
    Hn = (E.size - 1) // 2
    ecoef = (np.arange(1, Hn + 1, dtype=float), E[1::2] / L, E[2::2] / L, E[0] / L, s)
    w0 = model.static_load / (k_h * L)
    bt = b / L
    T = 2 * np.pi / s
    ns = samples_per_period
    if state0 is None:
        y = np.array([(b + model.static_load / k_h + E[0]) / L, 0.0])
    else:
        y = np.array([state0[0] / L, state0[1] / (L * wn)], dtype=float)
    kvar = np.atleast_1d(np.asarray(model.stiffness_variation, dtype=float))
    rhs = {md: _segment_rhs(md, zeta2, w0, bt, ecoef, kvar) for md in (-1, 0, 1)}
    evs = {md: _events(md, bt, ecoef) for md in (-1, 0, 1)}

    def mode_of(tau, yy):
        th = s * tau * ecoef[0]
        x = yy[0] - (ecoef[3] + ecoef[1] @ np.cos(th) + ecoef[2] @ np.sin(th))
        return 1 if x > bt else (-1 if x < -bt else 0)

    tau = 0.0
    mode = mode_of(tau, y)
    prev = None
    diffs: list[float] = []
    converged = False
    p = 0
    samples = np.empty((2, ns))
    for p in range(1, max_periods + 1):
        t_end = p * T
        t_grid = (p - 1) * T + T * np.arange(ns) / ns
        filled = 0
        while tau < t_end - 1e-12 * T:
            sol = solve_ivp(
                rhs[mode],
                (tau, t_end),
                y,
                method=method,
                events=evs[mode],
                rtol=rtol,
                atol=rtol * 1e-2,
                dense_output=True,
            )
            if sol.status == -1:
                raise RuntimeError(f"solve_ivp failed at omega={omega}: {sol.message}")
            t_stop = sol.t[-1]
            sel = (t_grid >= tau) & (t_grid <= t_stop)
            idx = np.nonzero(sel)[0]
            if idx.size:
                samples[:, idx] = sol.sol(t_grid[idx])
                filled = max(filled, idx[-1] + 1)
            y = sol.y[:, -1]
            if sol.status == 1:
                hit = next(i for i, te in enumerate(sol.t_events) if te.size)
                if mode == 0:
                    mode = 1 if hit == 0 else -1
                else:
                    mode = 0
            tau = t_stop
        tau = t_end
        cur = samples[0].copy()
        if prev is not None:
            scale = np.ptp(cur) + w0
            d = float(np.max(np.abs(cur - prev)) / scale)
            diffs.append(d)
            if p >= min_periods and d < tol:
                rho = d / diffs[-2] if len(diffs) > 1 and diffs[-2] > 0 else 0.0
                if rho < 1 and d * rho / (1 - rho) < tol:
                    converged = True
                    break
        prev = cur
    t = T * np.arange(ns) / ns
    theta = s * t
    delta = samples[0] * L
    ddot = samples[1] * L * wn
    e = evaluate(E, theta)
    edot = omega * evaluate(differentiate(E), theta)
    force = k_h * evaluate(kvar, theta) * deadzone(delta - e, b) + model.mesh_damping * (ddot - edot)
    hist = TimeHistory(t / wn, delta, ddot, e, edot, force)
    return TimeResponse(
        omega, hist, converged, p, diffs[-1] if diffs else float("nan"), np.array([y[0] * L, y[1] * L * wn])
    )


def time_sweep(
    model: SDOFGearPair,
    omegas: ArrayLike,
    directions: str | Sequence[str] = "both",
    *,
    H: int = 15,
    state0: ArrayLike | None = None,
    **kwargs,
) -> SweepResult:
    """Time-domain sweeps: each frequency starts from the final state of the previous one.

    Parameters
    ----------
    model : SDOFGearPair
        The gear pair.
    omegas : array_like
        Mesh frequencies [rad/s].
    directions : {"both", "up", "down"} or sequence of them
        Sweep directions.
    H : int
        Harmonics of δ kept (FFT of the last period) [-].
    state0 : array_like, optional
        [δ, δ'] starting each direction [m, m/s] (default: static deflection at rest,
        which may be attracted to either branch inside a multivalued range).
    **kwargs
        Passed to :func:`integrate`.

    Returns
    -------
    SweepResult
        Metrics from the sampled last period; ``iterations`` = periods simulated,
        ``residual`` = last period difference (``residual_kind`` "period difference"),
        ``converged`` = steady state reached; stability not computed (NA): only
        attracting solutions survive a time integration.
    """
    mesh = model.mesh()
    rows: dict[str, list] = {k: [] for k in "wdzcrim"}
    for direction, order in sweep_orders(np.asarray(omegas, dtype=float), directions):
        state = state0
        for w in order:
            res = integrate(model, float(w), state, **kwargs)
            state = res.state
            met = metrics_from_history(res.history, mesh, H)
            for k, v in zip(
                "wdzcrim",
                (w, direction, res.harmonics(H)[None, :], res.converged, res.difference, res.periods, met),
                strict=False,
            ):
                rows[k].append(v)
    n = len(rows["w"])
    return assemble_result(
        rows["w"],
        rows["d"],
        rows["z"],
        rows["c"],
        rows["r"],
        rows["i"],
        [np.nan] * n,
        rows["m"],
        "time integration (SDOF)",
        residual_kind="period difference",
    )
