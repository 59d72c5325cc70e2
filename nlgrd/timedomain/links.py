"""Time integration of a rotor model with any number of nonlinear links: the independent
reference of :mod:`nlgrd.nonlinear.models.link_model`.

The same equations as the harmonic balance,

    M q'' + D(Ω) q' + K(Ω) q + P g(Pᵀ q, θ) = f(t),   θ = ω t,

(D with the links' viscous damping, K without their stiffness, f the static loads,
unbalance and the links' own forcing) are integrated by the HHT-α method (Hilber,
Hughes & Taylor 1977, Earthq. Eng. Struct. Dyn. 5:283; β = (1 - α)²/4, γ = 1/2 - α) with
a fixed step. Each step is linear in q except through the link coordinates y = Pᵀ q:
with K_eff factorised once and S = Pᵀ K_eff⁻¹ P (d x d), the step solves
y = y_lin - (1 + α) S g(y) by Newton on the d link coordinates only, with the links'
pointwise tangents, then q follows (up to a few hundred DOFs through the precomputed
:class:`nlgrd.timedomain.period_map.PeriodMap`, as in
:func:`nlgrd.timedomain.integrator.integrate_fe`). Integration runs period by period to a
periodic steady state (the criterion of :func:`nlgrd.timedomain.integrator.integrate_fe`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import analyse, evaluate
from nlgrd.nonlinear.links.contract import GearMeshLink
from nlgrd.nonlinear.models.link_model import LinkModel
from nlgrd.nonlinear.results.metrics import MeshMetrics
from nlgrd.nonlinear.results.sweep_results import SweepResult, assemble_result
from nlgrd.nonlinear.tracing.sweep import sweep_orders
from nlgrd.threads import single_blas_thread
from nlgrd.timedomain.integrator import hht_step
from nlgrd.timedomain.period_map import MAX_STATE, PeriodMap


@dataclass(frozen=True)
class LinkTimeResponse:
    """The last period of a time integration of a link model.

    Attributes
    ----------
    omega : float
        Base frequency [rad/s].
    y : ndarray (d, steps_per_period)
        Link coordinates over the last period [m].
    converged : bool
        A periodic steady state was reached.
    periods : int
        Periods simulated.
    difference : float
        Last relative period-to-period difference of y [-].
    state : tuple of ndarray
        (q, q', q'') at the end, to continue a sweep.
    q : ndarray (len(output_dofs), steps_per_period)
        The requested DOFs over the last period [m, rad].
    """

    omega: float
    y: NDArray
    converged: bool
    periods: int
    difference: float
    state: tuple
    q: NDArray

    def harmonics(self, H: int) -> NDArray:
        """Real harmonics (d, 2H+1) of the link coordinates over the last period [m].

        Parameters
        ----------
        H : int
            Number of harmonics [-].

        Returns
        -------
        ndarray (d, 2H+1)
        """
        return analyse(self.y, H)


def _forcing_samples(model: LinkModel, omega: float, ns: int, H: int) -> NDArray:
    """f(t_j) on the DOFs at the ns steps of one period, (ns, n) [N]."""
    f = model.receptance.forces(omega, H)  # (H+1, n) complex, k = 0..H
    theta = 2 * np.pi * np.arange(ns) / ns
    k = np.arange(H + 1)
    return np.real(np.exp(1j * np.outer(theta, k)) @ f)


class LinkIntegrator:
    """Fixed-step HHT-α integration of a link model at one base frequency, period by period.

    The state is the extended one of :class:`~nlgrd.timedomain.period_map.PeriodMap`,
    s = (q, q', q'', g) with g the link forces of the last step. Up to
    :data:`~nlgrd.timedomain.period_map.MAX_STATE` a period runs on the precomputed period
    map; above, step by step on all DOFs.

    Parameters
    ----------
    model : LinkModel
        From :func:`nlgrd.nonlinear.models.link_model.build_link_model`.
    omega : float
        Base frequency [rad/s].
    steps_per_period : int
        Fixed time steps per period [-].
    alpha : float
        HHT-α parameter in [-1/3, 0] [-].
    forcing_harmonics : int, optional
        Harmonics of the forcing kept [-]; default all the links' excitation holds (at
        least 30).

    Attributes
    ----------
    N, d, ns : int
        DOFs, link coordinates and steps per period [-].
    dt : float
        Time step [s].
    step : HHTStep
        The step matrices (their Newmark coefficients give the link velocities).

    Raises
    ------
    ModelError
        ``alpha`` outside [-1/3, 0].
    """

    def __init__(
        self,
        model: LinkModel,
        omega: float,
        *,
        steps_per_period: int = 512,
        alpha: float = -0.05,
        forcing_harmonics: int | None = None,
    ):
        if not -1 / 3 <= alpha <= 0:
            raise ModelError("alpha", f"HHT-α needs -1/3 <= alpha <= 0, got {alpha}")
        rec = model.receptance
        self.model, self.omega, self.alpha = model, float(omega), float(alpha)
        speed = rec.plan.speed(omega)
        self.M = rec.model.M.tocsc()
        self.D = (rec.model.damping(speed) + rec.C_link).tocsc()
        self.K = rec.model.stiffness(speed).tocsc()
        self.P = rec.P
        self.N, self.d = self.P.shape
        self.ns = int(steps_per_period)
        self.dt = 2 * np.pi / omega / self.ns
        self.step = hht_step(self.M, self.D, self.K, self.dt, alpha)
        self.Zp = self.step.lu.solve(self.P)  # K_eff⁻¹ P
        self.S = self.P.T @ self.Zp
        if forcing_harmonics is None:
            forcing_harmonics = max([30] + [getattr(lk, "excitation_harmonics", 0) for lk in model.links])
        self.F = _forcing_samples(model, omega, self.ns, forcing_harmonics)
        self.theta = 2 * np.pi * np.arange(self.ns) / self.ns
        self._eye = np.eye(self.d)
        self._mesh_law = None
        link0 = model.links[0]
        if self.d == 1 and isinstance(link0, GearMeshLink):  # one mesh: the step's exact solution
            th = self.theta
            self._mesh_law = (
                evaluate(link0.mesh.lste, th),
                link0.mesh.stiffness_time(th),
                float(link0.mesh.half_backlash),
                self.step.ap * float(self.S[0, 0]),
            )
        self.pmap = None
        if 3 * self.N + self.d <= MAX_STATE:
            ap = self.step.ap
            self.pmap = PeriodMap(self.step, alpha, self.P, ap * np.roll(self.F, -1, axis=0) - alpha * self.F)

    def link_forces(self, y: NDArray, th: float) -> tuple[NDArray, NDArray]:
        """The links' forces g(y, θ) (d,) [N] and their tangent (d, d) [N/m]."""
        d = self.d
        g = np.zeros(d)
        T = np.zeros((d, d))
        for link, sl in zip(self.model.links, self.model.receptance.slices, strict=True):
            gi, ti = link.pointwise(y[sl], th)
            g[sl] = gi
            T[sl, sl] = ti
        return g, T

    def start(self, state0: tuple | None = None) -> NDArray:
        """The extended state from (q, q'[, q'']); default at rest at the static position of
        the linear system with the links at their linear stiffness.

        Parameters
        ----------
        state0 : tuple of ndarray, optional
            (q, q') or (q, q', q'') [m, m/s, m/s²].

        Returns
        -------
        ndarray (3N + d,)
        """
        rec = self.model.receptance
        N = self.N
        if state0 is None:
            u = rec.mean.solve(rec.plan.speed(self.omega), rec.static_force[:, None])[:, 0]
            v = np.zeros(N)
        else:
            u, v = np.array(state0[0], dtype=float), np.array(state0[1], dtype=float)
        g, _ = self.link_forces(self.P.T @ u, 0.0)
        if state0 is not None and len(state0) > 2:
            acc = np.array(state0[2], dtype=float)
        else:
            acc = spla.splu(self.M).solve(self.F[0] - self.P @ g - self.D @ v - self.K @ u)
        return np.concatenate([u, v, acc, g])

    def _solve_y(self, y_lin: NDArray, jn: int) -> tuple[NDArray, NDArray]:
        """Link coordinates and forces at phase jn from the prediction with g = 0 (Newton on d)."""
        y = y_lin.copy()
        ap, eye = self.step.ap, self._eye
        for _ in range(50):
            gy, Ty = self.link_forces(y, self.theta[jn])
            res = y - y_lin + ap * (self.S @ gy)
            if abs(res).max() <= 1e-13 * (abs(y).max() + 1e-12):
                return y, gy
            y = y - np.linalg.solve(eye + ap * (self.S @ Ty), res)
        return y, self.link_forces(y, self.theta[jn])[0]

    def _solve_link(self, y_lin, j):
        if self._mesh_law is not None:
            # y + c k f(y - e) = y_lin with the dead zone f: piecewise linear, solved exactly
            e, k, b, c = self._mesh_law
            jn = (j + 1) % self.ns
            x_lin, ck = y_lin - e[jn], c * k[jn]
            if x_lin > b:
                x = (x_lin + ck * b) / (1 + ck)
                return x + e[jn], k[jn] * (x - b)
            if x_lin < -b:
                x = (x_lin - ck * b) / (1 + ck)
                return x + e[jn], k[jn] * (x + b)
            return float(y_lin), 0.0
        if self.d == 1:
            y1, g1 = self._solve_y(np.array([y_lin]), (j + 1) % self.ns)
            return float(y1[0]), float(g1[0])
        return self._solve_y(y_lin, (j + 1) % self.ns)

    def stepped(self, s: NDArray, output_dofs=()) -> tuple[NDArray, NDArray, NDArray]:
        """One period step by step on all DOFs from the extended state ``s``.

        Parameters
        ----------
        s : ndarray (3N + d,)
            The extended state at the start of the period.
        output_dofs : sequence of int
            DOFs recorded.

        Returns
        -------
        y : ndarray (d, ns)
            Link coordinates at the start of each step [m].
        q : ndarray (len(output_dofs), ns)
            The output DOFs at the start of each step [m, rad].
        s : ndarray (3N + d,)
            The extended state at the end of the period.
        """
        N, ns, st, alpha = self.N, self.ns, self.step, self.alpha
        state, g = s[: 3 * N], s[3 * N :]
        out = np.asarray(output_dofs, dtype=int)
        y_hist, q_hist = np.empty((self.d, ns)), np.empty((out.size, ns))
        for j in range(ns):
            y_hist[:, j] = self.P.T @ state[:N]
            q_hist[:, j] = state[out]
            jn = (j + 1) % ns
            rhs = st.A_all @ state + st.ap * self.F[jn] - alpha * self.F[j] + alpha * (self.P @ g)
            q_lin = st.lu.solve(rhs)
            _, g = self._solve_y(self.P.T @ q_lin, jn)
            q_new = q_lin - st.ap * (self.Zp @ g)
            u_old, v_old, acc_old = state[:N], state[N : 2 * N], state[2 * N :]
            acc_new = st.a1 * (q_new - u_old) - st.a2 * v_old - st.a3 * acc_old
            v_new = v_old + self.dt * ((1 - st.gamma) * acc_old + st.gamma * acc_new)
            state = np.concatenate([q_new, v_new, acc_new])
        return y_hist, q_hist, np.concatenate([state, g])

    def period(self, s: NDArray) -> tuple[NDArray, NDArray]:
        """One period from the extended state ``s``: on the period map when there is one.

        Parameters
        ----------
        s : ndarray (3N + d,)
            The extended state at the start of the period.

        Returns
        -------
        y : ndarray (d, ns)
            Link coordinates at the start of each step [m].
        s : ndarray (3N + d,)
            The extended state at the end of the period.
        """
        if self.pmap is None:
            y, _, s_end = self.stepped(s)
            return y, s_end
        return self.pmap.run(s, self._solve_link)

    def period_forces(self, s: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """One period on the period map (as :meth:`period`), with the link forces it solved.

        Parameters
        ----------
        s : ndarray (3N + d,)
            The extended state at the start of the period.

        Returns
        -------
        y : ndarray (d, ns)
            Link coordinates at the start of each step [m].
        g : ndarray (ns, d)
            Link forces at the end of each step [N].
        s : ndarray (3N + d,)
            The extended state at the end of the period.

        Raises
        ------
        ModelError
            The model is too large for a period map (use :meth:`stepped`).
        """
        if self.pmap is None:
            raise ModelError("model", f"{self.N} DOFs: no period map, step it (LinkIntegrator.stepped)")
        g = np.empty((self.ns, self.d))

        def solve(y_lin, j):
            yj, gj = self._solve_link(y_lin, j)
            g[j] = gj
            return yj, gj

        y, s_end = self.pmap.run(s, solve)
        return y, g, s_end


@single_blas_thread
def link_time_response(
    model: LinkModel,
    omega: float,
    *,
    steps_per_period: int = 512,
    tol: float = 1e-6,
    alpha: float = -0.05,
    max_periods: int = 4000,
    min_periods: int = 5,
    state0: tuple | None = None,
    forcing_harmonics: int | None = None,
    output_dofs=(),
) -> LinkTimeResponse:
    """Integrate a link model to a periodic steady state at base frequency ``omega``.

    Parameters
    ----------
    model : LinkModel
        From :func:`nlgrd.nonlinear.models.link_model.build_link_model`.
    omega : float
        Base frequency [rad/s].
    steps_per_period : int
        Fixed time steps per period [-].
    tol : float
        Steady state: the largest change of y from one period to the next, relative to
        its peak-to-peak range (and the links' clearances), below ``tol`` and the
        geometric remainder too [-].
    alpha : float
        HHT-α parameter in [-1/3, 0] [-].
    max_periods, min_periods : int
        Limits on the periods simulated [-].
    state0 : tuple (q, q', q''), optional
        Start state; default at rest at the static position of the linear system with
        the links at their linear stiffness.
    forcing_harmonics : int, optional
        Harmonics of the forcing kept [-]; default all the links' excitation holds (at
        least 30).
    output_dofs : sequence of int
        DOFs recorded over the last period.

    Returns
    -------
    LinkTimeResponse
    """
    integ = LinkIntegrator(
        model, omega, steps_per_period=steps_per_period, alpha=alpha, forcing_harmonics=forcing_harmonics
    )
    N = integ.N
    scale_c = max((getattr(lk, "clearance", 0.0) for lk in model.links), default=0.0)
    prev, diffs, converged, p = None, [], False, 0
    s = integ.start(state0)
    start = s
    for p in range(1, max_periods + 1):
        start = s
        cur, s = integ.period(s)
        if prev is not None:
            scale = float(np.max(np.ptp(cur, axis=1))) + scale_c + 1e-300
            diffs.append(float(np.max(np.abs(cur - prev))) / scale)
            if p >= min_periods and len(diffs) >= 2:
                rho = diffs[-1] / diffs[-2] if diffs[-2] > 0 else 0.0
                tail = diffs[-1] * rho / (1 - rho) if rho < 1 else np.inf
                if diffs[-1] < tol and tail < tol:
                    converged = True
                    break
        prev = cur
    y_hist, q_hist, s_end = integ.stepped(start, output_dofs)  # the last period, all DOFs recorded
    if integ.pmap is not None:
        s = s_end
    return LinkTimeResponse(
        float(omega),
        y_hist,
        converged,
        p,
        diffs[-1] if diffs else np.inf,
        (s[:N].copy(), s[N : 2 * N].copy(), s[2 * N : 3 * N].copy()),
        q_hist,
    )


def start_from_harmonics(model: LinkModel, omega: float, H: int, harmonics: NDArray) -> tuple:
    """The state (q, q') at t = 0 of a harmonic-balance solution, to start an integration on it.

    Every DOF is recovered from the link harmonics (:meth:`LinkReceptance.recover`); the
    integration then checks, independently, that the orbit is a periodic solution of the
    full equations that attracts: a wrong or unstable orbit drifts away.

    Parameters
    ----------
    model : LinkModel
        The model.
    omega : float
        Base frequency [rad/s].
    H : int
        Number of harmonics of ``harmonics`` [-].
    harmonics : ndarray (d, 2H+1)
        Real harmonics of the link coordinates [m].

    Returns
    -------
    tuple of ndarray
        (q, q') at θ = 0 [m, m/s].
    """
    z = np.asarray(harmonics, dtype=float)
    G = model.reduced.at(omega, H).nonlinear_forces(z.ravel(), jacobian=False)[0].reshape(z.shape)
    q = model.receptance.recover(omega, H, z, G, np.arange(model.system.n_dofs))
    k = np.arange(1, H + 1)
    q0 = q[:, 0] + q[:, 1::2].sum(axis=1)
    v0 = omega * (q[:, 2::2] @ k)  # d/dt of a_k cos kθ + b_k sin kθ at θ = 0
    return q0, v0


def link_time_sweep(
    model: LinkModel,
    omegas: NDArray,
    directions: str = "both",
    *,
    H: int = 15,
    **options,
) -> SweepResult:
    """Time-domain sweeps of a link model, each frequency continuing from the last.

    Parameters
    ----------
    model : LinkModel
        From :func:`nlgrd.nonlinear.models.link_model.build_link_model`.
    omegas : array_like
        Base frequencies [rad/s].
    directions : {"both", "up", "down"}
        Sweep directions.
    H : int
        Harmonics of the link coordinates kept (FFT of the last period) [-].
    **options
        Passed to :func:`link_time_response`.

    Returns
    -------
    SweepResult
        ``harmonics`` of all link coordinates; ``residual_kind`` "period difference";
        stability not computed (NA).
    """
    rows: dict[str, list] = {k: [] for k in "wdzcrim"}
    state = options.pop("state0", None)
    for direction, order in sweep_orders(np.asarray(omegas, dtype=float), directions):
        for w in order:
            tr = link_time_response(model, float(w), state0=state, **options)
            state = tr.state
            vals = (
                w,
                direction,
                tr.harmonics(H),
                tr.converged,
                tr.difference,
                tr.periods,
                MeshMetrics.nan(H),
            )
            for k, v in zip("wdzcrim", vals, strict=True):
                rows[k].append(v)
    return assemble_result(
        rows["w"],
        rows["d"],
        rows["z"],
        rows["c"],
        rows["r"],
        rows["i"],
        [np.nan] * len(rows["w"]),
        rows["m"],
        "time integration (links, HHT-α)",
        residual_kind="period difference",
    )
