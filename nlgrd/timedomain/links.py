"""Time integration of a rotor model with any number of nonlinear links: the independent
reference of :mod:`nlgrd.nonlinear.models.link_model`.

The same equations as the harmonic balance,

    M q'' + D(Ω) q' + K(Ω) q + P g(Pᵀ q, θ) = f(t),   θ = ω t,

(D with the links' viscous damping, K without their stiffness, f the static loads,
unbalance and the links' own forcing) are integrated by the HHT-α method (Hilber,
Hughes & Taylor 1977, Earthq. Eng. Struct. Dyn. 5:283; β = (1 - α)²/4, γ = 1/2 - α) with
a fixed step (:func:`nlgrd.timedomain.integrator.hht_step`). Each step is linear in q
except through the link coordinates y = Pᵀ q: with K_eff factorised once and
S = Pᵀ K_eff⁻¹ P (d x d), the step solves y = y_lin - (1 + α) S g(y) on the d link
coordinates only: by Newton with the links' pointwise tangents, or in closed form for a
single gear mesh (the scalar piecewise-linear equation of its dead zone); then q follows
(up to a few hundred DOFs through the precomputed
:class:`nlgrd.timedomain.period_map.PeriodMap`, so that a step costs a dot product and
that equation). Integration runs period by period to a periodic steady state
(:func:`settle`).

:class:`LinkIntegrator` is nlgrd's one HHT-α integrator of these equations: of a link
model (its constructor) and of the FE model of one gear mesh
(:meth:`LinkIntegrator.of_mesh`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import differentiate, evaluate, sample
from nlgrd.nonlinear.laws.force_laws import BacklashMesh
from nlgrd.nonlinear.links.contract import GearMeshLink
from nlgrd.nonlinear.models.link_model import LinkModel
from nlgrd.nonlinear.results.link_results import LinkSweepResult, bearing_columns, link_rows
from nlgrd.nonlinear.results.metrics import MeshMetrics
from nlgrd.nonlinear.results.sweep_results import assemble_result
from nlgrd.nonlinear.tracing.sweep import sweep_orders
from nlgrd.threads import single_blas_thread
from nlgrd.timedomain.integrator import hht_step, static_solution
from nlgrd.timedomain.link_response import LinkTimeResponse, coordinate_names
from nlgrd.timedomain.period_map import MAX_STATE, PeriodMap


def _forcing_samples(model: LinkModel, omega: float, ns: int, H: int) -> NDArray:
    """f(t_j) on the DOFs at the ns steps of one period, (ns, n) [N]."""
    f = model.receptance.forces(omega, H)  # (H+1, n) complex, k = 0..H
    theta = 2 * np.pi * np.arange(ns) / ns
    k = np.arange(H + 1)
    return np.real(np.exp(1j * np.outer(theta, k)) @ f)


@dataclass(frozen=True)
class PeriodRecord:
    """One period stepped on all DOFs, with the link histories recorded.

    Attributes
    ----------
    y, ydot, g : ndarray (d, ns)
        Link coordinates [m], their velocities [m/s] and the link forces [N] at the start
        of each step.
    q : ndarray (len(output_dofs), ns)
        The recorded DOFs at the start of each step [m, rad].
    end : ndarray (3N + d,)
        The extended state at the end of the period.
    """

    y: NDArray
    ydot: NDArray
    g: NDArray
    q: NDArray
    end: NDArray


@dataclass(frozen=True)
class Settled:
    """The periods integrated towards a periodic steady state (:func:`settle`).

    Attributes
    ----------
    start, end : ndarray (3N + d,)
        The extended state at the start and at the end of the last period.
    periods : int
        Periods integrated [-].
    differences : list of float
        The relative period-to-period differences of the link coordinates [-].
    converged : bool
        The steady-state criterion was met.
    section : ndarray (d, periods)
        The link coordinates at the start of every period (the Poincaré section θ = 0
        mod 2π) [m].
    """

    start: NDArray
    end: NDArray
    periods: int
    differences: list
    converged: bool
    section: NDArray


def backlash_force(x_lin: float, stiffness: float, b: float, compliance: float) -> float:
    """The mesh force g of an implicit step x + s g(x) = x_lin, g = k f(x), f the dead zone
    of half-width b, s >= 0: x lies on the branch of x_lin (the left side increases with
    x), where the equation is linear.

    Parameters
    ----------
    x_lin : float
        The step's x without the mesh force [m].
    stiffness : float
        k, the mesh stiffness at the step's end [N/m].
    b : float
        Half the backlash [m].
    compliance : float
        s, the step's compliance along the mesh, (1 + α) S [m/N].

    Returns
    -------
    float
        g [N].
    """
    k = stiffness
    ck = compliance * k
    if x_lin > b:
        return k * ((x_lin + ck * b) / (1 + ck) - b)
    if x_lin < -b:
        return k * ((x_lin - ck * b) / (1 + ck) + b)
    return 0.0


def pointwise_forces(links, slices, y: NDArray, th: float) -> tuple[NDArray, NDArray]:
    """The links' forces g(y, θ) (d,) [N] and their block-diagonal tangent (d, d) [N/m] at
    one instant, from each link's ``pointwise``.

    Parameters
    ----------
    links : sequence of NonlinearLink
        The links.
    slices : sequence of slice
        Each link's coordinates in y.
    y : ndarray (d,)
        Link coordinates [m].
    th : float
        Base angle θ [rad].

    Returns
    -------
    tuple of ndarray
        g (d,) [N] and ∂g/∂y (d, d) [N/m].
    """
    d = y.shape[0]
    g = np.zeros(d)
    T = np.zeros((d, d))
    for link, sl in zip(links, slices, strict=True):
        gi, ti = link.pointwise(y[sl], th)
        g[sl] = gi
        T[sl, sl] = ti
    return g, T


def newton_links(forces, ap: float, S: NDArray, y_lin) -> tuple[NDArray, NDArray]:
    """The implicit step of the links, y = y_lin - (1 + α) S g(y), by Newton
    with the links' pointwise tangents: the one link solve of every HHT-α integrator
    (:class:`LinkIntegrator`, the speed ramp of :mod:`nlgrd.timedomain.run_down`).

    Parameters
    ----------
    forces : callable
        ``forces(y)`` returns g(y) (d,) [N] and ∂g/∂y (d, d) [N/m] at the step's end.
    ap : float
        1 + α [-].
    S : ndarray (d, d)
        Pᵀ K_eff⁻¹ P [m/N].
    y_lin : float or ndarray (d,)
        The step's link coordinates without the link forces [m].

    Returns
    -------
    tuple of ndarray
        y (d,) [m] and g (d,) [N]; stops when the residual is below 1e-13 of |y| (50
        iterations at most).
    """
    y0 = np.atleast_1d(np.asarray(y_lin, dtype=float))
    y, eye = y0.copy(), np.eye(y0.size)
    for _ in range(50):
        gy, Ty = forces(y)
        res = y - y0 + ap * (S @ gy)
        if abs(res).max() <= 1e-13 * (abs(y).max() + 1e-12):
            break
        y = y - np.linalg.solve(eye + ap * (S @ Ty), res)
    else:
        gy = forces(y)[0]
    return y, gy


class LinkIntegrator:
    """Fixed-step HHT-α integration of the reduced equations at one base frequency, period
    by period: the one time integrator of nlgrd's FE and link models.

    The state is the extended one of :class:`~nlgrd.timedomain.period_map.PeriodMap`,
    s = (q, q', q'', g) with g the link forces of the last step. Up to
    :data:`~nlgrd.timedomain.period_map.MAX_STATE` a period runs on the precomputed period
    map; above, step by step on all DOFs. Each step solves the links' own equation
    y = y_lin - (1 + α) S g(y, θ) on the d link coordinates: by Newton with the links'
    pointwise tangents, or, for a single gear mesh (d = 1, the dead zone k f(x), x = y - e),
    in closed form: y + c k f(y - e) = y_lin with c = (1 + α) S > 0 is monotone and
    piecewise linear, so x = (x_lin ∓ c k b)/(1 + c k) beyond ±b and x = x_lin inside.

    Built from a link model (this constructor) or from the FE matrices of one mesh
    (:meth:`of_mesh`).

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
    model : LinkModel or None
        The link model (None when built by :meth:`of_mesh`).

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
        rec = model.receptance
        speed = rec.plan.speed(omega)
        if forcing_harmonics is None:
            forcing_harmonics = max([30] + [getattr(lk, "excitation_harmonics", 0) for lk in model.links])
        ns = int(steps_per_period)
        self._setup(
            rec.model.M,
            rec.model.damping(speed) + rec.C_link,
            rec.model.stiffness(speed),
            rec.P,
            tuple(model.links),
            tuple(rec.slices),
            (_forcing_samples(model, omega, ns, forcing_harmonics), np.zeros((ns, rec.P.shape[1]))),
            omega,
            alpha,
        )
        self.model = model

    @classmethod
    def of_mesh(
        cls,
        M,
        D,
        K,
        projection: ArrayLike,
        mesh: BacklashMesh,
        static_force: ArrayLike,
        omega: float,
        *,
        steps_per_period: int = 512,
        alpha: float = -0.05,
    ) -> LinkIntegrator:
        """The integrator of an FE model with one nonlinear gear mesh, given its matrices.

        The equations M q'' + D q' + K q = F0 - w W(t) with W = k_h f(wᵀq - e) +
        c_m (wᵀq' - e') and c_m w wᵀ inside D: the one link δ = wᵀ q with the forcing
        F0 + w c_m e'(t); the rest state is :func:`~nlgrd.timedomain.integrator.static_solution`.

        Parameters
        ----------
        M, D, K : sparse or dense (N, N)
            Mass [kg], velocity matrix incl. c_m w wᵀ [N s/m], stiffness without the mesh
            [N/m].
        projection : array_like (N,)
            The projection w onto the line of action, δ = wᵀ q [-].
        mesh : BacklashMesh
            k_h (k_h ρ(θ) of a parametric mesh), b, c_m and the LSTE in θ = ω t.
        static_force : array_like (N,)
            F0, self-equilibrated static loads [N, N m].
        omega : float
            Mesh frequency [rad/s].
        steps_per_period : int
            Fixed time steps per period [-].
        alpha : float
            HHT-α parameter in [-1/3, 0] [-].

        Returns
        -------
        LinkIntegrator

        Raises
        ------
        ModelError
            ``projection`` or ``static_force`` of the wrong size; ``alpha`` outside [-1/3, 0].
        """
        M = sp.csc_matrix(M)
        w = np.asarray(projection, dtype=float).reshape(-1)
        F0 = np.asarray(static_force, dtype=float).reshape(-1)
        if w.size != M.shape[0] or F0.size != M.shape[0]:
            raise ModelError("projection", f"projection and static force need {M.shape[0]} entries")
        ns = int(steps_per_period)
        dz = differentiate(mesh.lste)
        edot = omega * (sample(dz, ns) if ns > dz.size else evaluate(dz, 2 * np.pi * np.arange(ns) / ns))
        self = cls.__new__(cls)
        link = GearMeshLink("mesh", mesh, w)
        forcing = (F0[None, :], (mesh.damping * edot)[:, None])  # F0 and the LSTE's damping forcing along w
        self._setup(M, D, K, w[:, None], (link,), (slice(0, 1),), forcing, omega, alpha)
        self.model = None
        self._rest = (K, w, mesh, F0)
        return self

    def _setup(self, M, D, K, P, links, slices, forcing, omega, alpha) -> None:
        """The step matrices, the links' laws and the period map (shared by the constructors).

        ``forcing`` is f(t_j) = F_j + P φ_j at the ns steps, as the pair (F, φ) of shapes
        (ns, N) or (1, N) (a constant load) and (ns, d) [N]; a constant F enters the step's
        load term (1 + α) f_{j+1} - α f_j as itself.
        """
        if not -1 / 3 <= alpha <= 0:
            raise ModelError("alpha", f"HHT-α needs -1/3 <= alpha <= 0, got {alpha}")
        self.omega, self.alpha = float(omega), float(alpha)
        self.M, self.D, self.K = (sp.csc_matrix(a) for a in (M, D, K))
        self.P = np.asarray(P, dtype=float)
        self.links, self.slices = links, slices
        self.N, self.d = self.P.shape
        Fb, phi = (np.asarray(a, dtype=float) for a in forcing)
        self.ns = phi.shape[0]
        self.F = Fb + phi @ self.P.T  # f(t_j) (ns, N) [N]
        self.dt = 2 * np.pi / omega / self.ns
        self.step = hht_step(self.M, self.D, self.K, self.dt, alpha)
        self.Zp = self.step.lu.solve(self.P)  # K_eff⁻¹ P
        self.S = self.P.T @ self.Zp
        ap = self.step.ap
        self._forcing = (Fb, phi)
        self._loads = Fb if Fb.shape[0] == 1 else ap * np.roll(Fb, -1, axis=0) - alpha * Fb
        self._link_loads = ap * np.roll(phi, -1, axis=0) - alpha * phi
        self.theta = 2 * np.pi * np.arange(self.ns) / self.ns
        self._solve_link = self._newton_link
        if self.d == 1 and isinstance(links[0], GearMeshLink):  # one mesh: the closed-form step
            self._mesh = self._mesh_law(links[0].mesh)
            self._solve_link = self._mesh_step
        self.pmap, self._last = None, None
        if 3 * self.N + self.d <= MAX_STATE:
            full = self._loads + self._link_loads @ self.P.T
            self.pmap = PeriodMap(self.step, alpha, self.P, full)

    def _mesh_law(self, mesh: BacklashMesh) -> tuple:
        """e and k at the ends of the steps (phase j + 1 for step j), b and c = (1 + α) S, as
        Python floats: a step of :meth:`_mesh_step` is a few scalar operations."""
        ns, th = self.ns, np.roll(self.theta, -1)
        e = np.roll(sample(mesh.lste, ns), -1) if ns > mesh.lste.size else evaluate(mesh.lste, th)
        c = self.step.ap * float(self.P[:, 0] @ self.Zp[:, 0])
        return e.tolist(), mesh.stiffness_time(th).tolist(), float(mesh.half_backlash), c

    def _mesh_step(self, y_lin: float, j: int) -> tuple[float, float]:
        """The closed-form step of one gear mesh: (y, g) at phase j + 1.

        y + c k f(y - e) = y_lin with f the dead zone of half-width b and c > 0: the left
        side increases with y, so x = y - e lies on the branch of x_lin = y_lin - e, where
        the equation is linear: x = (x_lin ∓ c k b)/(1 + c k) beyond ±b, g = 0 inside.
        """
        e, k, b, c = self._mesh
        g = backlash_force(y_lin - e[j], k[j], b, c)
        return y_lin - c * g, g

    def _newton_link(self, y_lin, j: int):
        """Link coordinates and forces at phase j + 1 by Newton on d (floats when d = 1)."""
        th = self.theta[(j + 1) % self.ns]
        y, gy = newton_links(lambda y: self.link_forces(y, th), self.step.ap, self.S, y_lin)
        return (float(y[0]), float(gy[0])) if np.ndim(y_lin) == 0 else (y, gy)

    def link_forces(self, y: NDArray, th: float) -> tuple[NDArray, NDArray]:
        """The links' forces g(y, θ) (d,) [N] and their tangent (d, d) [N/m]
        (:func:`pointwise_forces`).

        Parameters
        ----------
        y : ndarray (d,)
            Link coordinates [m].
        th : float
            Base angle ω t [rad].

        Returns
        -------
        tuple of ndarray
            g (d,) [N] and ∂g/∂y (d, d) [N/m].
        """
        return pointwise_forces(self.links, self.slices, y, th)

    def start(self, state0: tuple | None = None) -> NDArray:
        """The extended state from (q, q'[, q'']); default at rest at the static position
        (of the linear system with the links at their linear stiffness; of
        :func:`~nlgrd.timedomain.integrator.static_solution` for :meth:`of_mesh`).

        Parameters
        ----------
        state0 : tuple of ndarray, optional
            (q, q') or (q, q', q'') [m, m/s, m/s²].

        Returns
        -------
        ndarray (3N + d,)
        """
        N = self.N
        if state0 is None:
            if self.model is None:
                K, w, mesh, F0 = self._rest
                u = static_solution(K, w, mesh, F0, M=self.M)
            else:
                rec = self.model.receptance
                u = rec.mean.solve(rec.plan.speed(self.omega), rec.static_force[:, None])[:, 0]
            v = np.zeros(N)
        else:
            u, v = np.array(state0[0], dtype=float), np.array(state0[1], dtype=float)
        g, _ = self.link_forces(self.P.T @ u, 0.0)
        if state0 is not None and len(state0) > 2:
            acc = np.array(state0[2], dtype=float)
        else:
            Fb, phi = self._forcing
            acc = spla.splu(self.M).solve(Fb[0] + self.P @ (phi[0] - g) - self.D @ v - self.K @ u)
        return np.concatenate([u, v, acc, g])

    def record(self, s: NDArray, output_dofs=()) -> PeriodRecord:
        """One period step by step on all DOFs from the extended state ``s``, recorded.

        Parameters
        ----------
        s : ndarray (3N + d,)
            The extended state at the start of the period.
        output_dofs : sequence of int
            Entries of the state [q, q', q''] recorded (i: DOF i; N + i: its velocity).

        Returns
        -------
        PeriodRecord
        """
        if self._last is not None and self._last[0] is s and len(output_dofs) == 0:
            return self._last[1]
        N, ns, st, alpha, d = self.N, self.ns, self.step, self.alpha, self.d
        P, Zp, A, lu, ap = self.P, self.Zp, self.step.A_all, self.step.lu, self.step.ap
        loads, link_loads, nl = self._loads, self._link_loads, self._loads.shape[0]
        state, g = s[: 3 * N], np.array(s[3 * N :], dtype=float)
        out = np.asarray(output_dofs, dtype=int)
        y_hist, v_hist, g_hist = np.empty((d, ns)), np.empty((d, ns)), np.empty((d, ns))
        q_hist = np.empty((out.size, ns))
        p1, z1, g1 = P[:, 0], Zp[:, 0], float(g[0])
        solve, lam = self._solve_link, link_loads[:, 0].tolist()
        for j in range(ns):
            u_old, v_old, acc_old = state[:N], state[N : 2 * N], state[2 * N :]
            if out.size:
                q_hist[:, j] = state[out]  # of the whole state: N + i is DOF i's velocity
            if d == 1:  # one link: floats and vectors
                y_hist[0, j], v_hist[0, j], g_hist[0, j] = p1 @ u_old, p1 @ v_old, g1
                q_lin = lu.solve(A @ state + loads[j % nl] + p1 * (lam[j] + alpha * g1))
                g1 = solve(float(p1 @ q_lin), j)[1]
                q_new = q_lin - z1 * (ap * g1)
            else:
                y_hist[:, j], v_hist[:, j], g_hist[:, j] = P.T @ u_old, P.T @ v_old, g
                q_lin = lu.solve(A @ state + loads[j % nl] + P @ (link_loads[j] + alpha * g))
                g = solve(P.T @ q_lin, j)[1]
                q_new = q_lin - Zp @ (ap * g)
            du = q_new - u_old
            acc_new = st.a1 * du - st.a2 * v_old - st.a3 * acc_old
            v_new = st.b1 * du + st.b2 * v_old + st.b3 * acc_old  # the period map's form
            state = np.concatenate((q_new, v_new, acc_new))
        if d == 1:
            g = np.array([g1])
        return PeriodRecord(y_hist, v_hist, g_hist, q_hist, np.concatenate([state, g]))

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
        rec = self.record(s, output_dofs)
        return rec.y, rec.q, rec.end

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
            rec = self.record(s)
            self._last = (s, rec)  # a recording of this period from s reuses it
            return rec.y, rec.end
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


def settle(
    integ: LinkIntegrator,
    s: NDArray,
    *,
    tol: float,
    max_periods: int,
    min_periods: int,
    floor: float = 0.0,
) -> Settled:
    """Integrate period by period from ``s`` to a periodic steady state.

    With d_p the largest change of the link coordinates from period p - 1 to p relative
    to their largest peak-to-peak range plus ``floor``, and ρ = d_p/d_{p-1}: stop at
    p >= ``min_periods`` when d_p < ``tol`` and the geometric remainder d_p ρ/(1 - ρ) <
    ``tol`` (ρ < 1), two differences being needed for ρ.

    Parameters
    ----------
    integ : LinkIntegrator
        The integrator.
    s : ndarray (3N + d,)
        The extended state at the start (:meth:`LinkIntegrator.start`).
    tol : float
        Steady-state tolerance [-].
    max_periods, min_periods : int
        Most and fewest periods integrated [-].
    floor : float
        Added to the peak-to-peak range of the criterion (a clearance, W_0/k_h) [m].

    Returns
    -------
    Settled
    """
    prev, diffs, section, converged, p = None, [], [], False, 0
    start = s
    for p in range(1, max_periods + 1):
        start = s
        cur, s = integ.period(s)
        section.append(cur[:, 0].copy())
        if prev is not None:
            scale = float(np.max(np.ptp(cur, axis=1))) + floor + 1e-300
            diffs.append(float(np.max(np.abs(cur - prev))) / scale)
            if p >= min_periods and len(diffs) >= 2:
                rho = diffs[-1] / diffs[-2] if diffs[-2] > 0 else 0.0
                tail = diffs[-1] * rho / (1 - rho) if rho < 1 else np.inf
                if diffs[-1] < tol and tail < tol:
                    converged = True
                    break
        prev = cur
    return Settled(start, s, p, diffs, converged, np.array(section).reshape(p, integ.d).T)


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
    run = settle(
        integ, integ.start(state0), tol=tol, max_periods=max_periods, min_periods=min_periods, floor=scale_c
    )
    y_hist, q_hist, s = integ.stepped(run.start, output_dofs)  # the last period, all DOFs recorded
    diffs, p, converged = run.differences, run.periods, run.converged
    return LinkTimeResponse(
        float(omega),
        y_hist,
        converged,
        p,
        diffs[-1] if diffs else np.inf,
        (s[:N].copy(), s[N : 2 * N].copy(), s[2 * N : 3 * N].copy()),
        q_hist,
        coordinate_names(model),
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
) -> LinkSweepResult:
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
    LinkSweepResult
        ``result``: ``harmonics`` of all link coordinates, ``residual_kind`` "period
        difference", stability not computed (NA); ``links``: every link's and linear
        bearing's outputs from those harmonics, as a harmonic-balance sweep has them
        (:func:`~nlgrd.nonlinear.results.link_results.link_rows`), NaN where no steady
        state was reached.
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
    res = assemble_result(
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
    converged = np.asarray(res.converged, dtype=bool)
    return LinkSweepResult(res, link_rows(model, res, converged), bearing_columns(model))
