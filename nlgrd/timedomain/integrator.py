"""Direct time integration of the full linear FE model with the nonlinear gear mesh.

    M q'' + D q' + K q = F0 - w W(t),   W = k_h f(wᵀq - e) + c_m (wᵀq' - e')

with D containing the mesh damping c_m w wᵀ and K excluding the mesh stiffness, so the
right-hand side is F0 - w k_h f(δ - e) + w c_m e'(t); a parametric mesh
(:class:`~nlgrd.nonlinear.laws.force_laws.ParametricMesh`) has k_h ρ(θ) in place of k_h.

Method: HHT-α (Hilber, Hughes & Taylor 1977), implicit, unconditionally stable and
second order for -1/3 <= α <= 0, with γ = (1 - 2α)/2, β = (1 - α)²/4. Why: an FE rotor
is stiff (bearing and bending modes far above the mesh frequency), so an explicit
scheme would need tiny steps; α < 0 damps the spurious high-frequency FE modes excited
at every contact change (the trapezoidal rule, α = 0, would let them ring forever and
spoil the periodicity test), while the dissipation at the mesh frequency is
O((ωΔt)³). With a fixed step Δt = T / steps_per_period the effective stiffness
K_eff = M/(βΔt²) + (1+α)(γ/(βΔt) D + K) is factorised once (sparse LU). The mesh force
enters through the single coordinate δ = wᵀq, so with z = K_eff⁻¹ w precomputed each
step needs one sparse solve and the exact solution of the scalar monotone
piecewise-linear equation x + c f(x) = p (c = (1+α) k_h wᵀz > 0): no Newton iterations.
Up to a few hundred DOFs the linear part of a whole period is precomputed
(:class:`nlgrd.timedomain.period_map.PeriodMap`), so that a step costs a dot product and
that scalar equation; the last period is stepped again with all DOFs to record them.

The integration starts from the static solution with the mesh at k_h in drive-side
contact, (K + k_h w wᵀ) q_s = F0 + k_h w (e_0 + b) (least squares: a free torsional
rigid-body mode of the whole train is left at zero; F0 must be self-equilibrated).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import differentiate, sample
from nlgrd.nonlinear.laws.force_laws import BacklashMesh
from nlgrd.nonlinear.results.metrics import MeshMetrics, TimeHistory, metrics_from_history
from nlgrd.rotor.assembly import mesh_matrix
from nlgrd.rotor.rigid_body import check_balanced, rigid_body_modes
from nlgrd.timedomain.period_map import MAX_STATE, PeriodMap


@dataclass(frozen=True)
class FETimeResponse:
    """Time integration of the FE model to periodic steady state at one mesh frequency.

    Attributes
    ----------
    omega : float
        Mesh frequency [rad/s].
    history : TimeHistory
        δ, δ', e, e', W over the last period (one sample per time step).
    converged : bool
        Periodic steady state reached (criterion in :func:`integrate_fe`).
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


def _csc(a) -> sp.csc_matrix:
    return sp.csc_matrix(a) if not sp.issparse(a) else a.tocsc()


@dataclass(frozen=True)
class HHTStep:
    """The fixed matrices of an HHT-α step of size dt (Hilber, Hughes & Taylor 1977).

    With β = (1 - α)²/4, γ = 1/2 - α, the step solves K_eff q_{n+1} = A [q_n; v_n; a_n] +
    (forces), K_eff = a1 M + (1 + α)(b1 D + K), and updates a_{n+1} = a1 (q_{n+1} - q_n) -
    a2 v_n - a3 a_n, v_{n+1} = b1 (q_{n+1} - q_n) + b2 v_n + b3 a_n.

    Attributes
    ----------
    gamma : float
        γ [-].
    a1, a2, a3, b1, b2, b3 : float
        The Newmark coefficients above [1/s², 1/s, -, 1/s, -, s].
    ap : float
        1 + α [-].
    lu : scipy.sparse.linalg.SuperLU
        The factors of K_eff.
    A_all : scipy.sparse.csr_matrix (N, 3N)
        A, acting on the state [q_n; v_n; a_n].
    """

    gamma: float
    a1: float
    a2: float
    a3: float
    b1: float
    b2: float
    b3: float
    ap: float
    lu: object
    A_all: sp.csr_matrix


def hht_step(M, D, K, dt: float, alpha: float) -> HHTStep:
    """The matrices of an HHT-α step (shared by every time integrator of nlgrd).

    Parameters
    ----------
    M, D, K : sparse (N, N)
        Mass [kg], velocity [N s/m] and stiffness [N/m] matrices.
    dt : float
        Time step [s].
    alpha : float
        HHT-α parameter in [-1/3, 0] [-].

    Returns
    -------
    HHTStep
    """
    gamma, beta = 0.5 - alpha, (1 - alpha) ** 2 / 4
    a1, a2, a3 = 1 / (beta * dt * dt), 1 / (beta * dt), 1 / (2 * beta) - 1
    b1, b2, b3 = gamma / (beta * dt), 1 - gamma / beta, dt * (1 - gamma / (2 * beta))
    ap = 1 + alpha
    lu = spla.splu((a1 * M + ap * (b1 * D + K)).tocsc())
    A_all = sp.hstack(
        [a1 * M + ap * b1 * D + alpha * K, a2 * M - ap * b2 * D + alpha * D, a3 * M - ap * b3 * D]
    ).tocsr()
    return HHTStep(gamma, a1, a2, a3, b1, b2, b3, ap, lu, A_all)


def static_solution(K, projection: ArrayLike, mesh: BacklashMesh, static_force: ArrayLike, M=None) -> NDArray:
    """Static deflection with the mesh at k_h in drive-side contact (minimum norm).

    Solves (K + k_h w wᵀ) q = F0 + k_h w (e_0 + b) by a sparse LU of the system bordered
    with its null space R (the rigid-body modes of (K + k_h w wᵀ, M) from
    :func:`nlgrd.rotor.rigid_body.rigid_body_modes`; M = I when not given) and the constraint
    Rᵀ q = 0: the minimum-norm solution. Raises ModelError when F0 has a net component
    on a rigid-body mode or the residual is not small.

    Parameters
    ----------
    K : sparse or dense (N, N)
        Stiffness without the mesh [N/m].
    projection : array_like (N,)
        The projection w onto the line of action, δ = wᵀ q [-].
    mesh : BacklashMesh
        k_h, b and the LSTE mean e_0.
    static_force : array_like (N,)
        F0, self-equilibrated static loads [N, N m].
    M : sparse or dense (N, N), optional
        Mass [kg], the metric of the rigid-body modes (identity when None).

    Returns
    -------
    ndarray (N,)
        The static displacements q [m, rad].
    """
    w = np.asarray(projection, dtype=float).reshape(-1)
    F0 = np.asarray(static_force, dtype=float).reshape(-1)
    n = w.size
    Ks = (_csc(K) + mesh_matrix(w, [mesh.stiffness])).tocsc()
    rhs = F0 + mesh.stiffness * w * (mesh.lste[0] + mesh.half_backlash)
    Mm = sp.identity(n, format="csc") if M is None else _csc(M)
    R = rigid_body_modes(Ks, Mm)
    check_balanced(R, F0, "static_force", "the static forces")
    if R.shape[1]:
        Rq = sp.csc_matrix(np.linalg.qr(R)[0])
        A = sp.bmat([[Ks, Rq], [Rq.T, None]], format="csc")
        q = spla.splu(A).solve(np.concatenate([rhs, np.zeros(R.shape[1])]))[:n]
    else:
        q = spla.splu(Ks).solve(rhs)
    res = np.linalg.norm(Ks @ q - rhs)
    if res > 1e-8 * (np.linalg.norm(rhs) + 1e-300):
        raise ModelError("static_force", f"not self-equilibrated: static residual {res:.3e} N")
    return q


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
    """Integrate the FE model with the nonlinear mesh to a periodic steady state.

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
        Fixed steps per mesh period (Δt = 2π / (ω steps_per_period)).
    alpha : float
        HHT-α parameter in [-1/3, 0].
    tol : float
        Steady-state tolerance: with d_p = max |δ_p - δ_{p-1}| over the period relative to
        (peak-to-peak δ + W_0/k_h), ρ = d_p/d_{p-1}, stop when d_p < tol and
        d_p ρ/(1-ρ) < tol.
    max_periods, min_periods : int
    state0 : tuple (q, q', q''), optional
        Start (e.g. the end state of the previous frequency); default the static solution
        at rest.
    store_dofs : bool
        Keep all DOFs over the last period.

    Returns
    -------
    FETimeResponse
        The last period, convergence and the end state.
    """
    if not -1 / 3 <= alpha <= 0:
        raise ModelError("alpha", f"HHT-α needs -1/3 <= alpha <= 0, got {alpha}")
    M, D, K = _csc(M), _csc(D), _csc(K)
    N = M.shape[0]
    w = np.asarray(projection, dtype=float).reshape(-1)
    F0 = np.asarray(static_force, dtype=float).reshape(-1)
    if w.size != N or F0.size != N:
        raise ModelError("projection", f"projection and static force need {N} entries")
    k_h, b, c_m = mesh.stiffness, mesh.half_backlash, mesh.damping
    ns = int(steps_per_period)
    T = 2 * np.pi / omega
    dt = T / ns
    step = hht_step(M, D, K, dt, alpha)
    a1, a2, a3, b1, b2, b3, ap = step.a1, step.a2, step.a3, step.b1, step.b2, step.b3, step.ap
    lu, A_all = step.lu, step.A_all
    zvec = lu.solve(w)
    cw = float(w @ zvec)
    apcw = ap * cw
    e_s = sample(mesh.lste, ns)
    k_s = mesh.stiffness_time(2 * np.pi * np.arange(ns) / ns)  # k_h, or k_h ρ(θ) of a parametric mesh
    edot_s = omega * sample(differentiate(mesh.lste), ns)
    force_w = c_m * edot_s  # coefficient of w in F(t) - F0

    def g_of(delta: float, n: int) -> float:
        x, k = delta - e_s[n % ns], k_s[n % ns]
        return k * (x - b) if x > b else (k * (x + b) if x < -b else 0.0)

    if state0 is None:
        u = static_solution(K, w, mesh, F0, M=M)
        v = np.zeros(N)
    else:
        u, v = np.array(state0[0], dtype=float), np.array(state0[1], dtype=float)
    g = g_of(w @ u, 0)
    if state0 is not None and len(state0) > 2:
        acc = np.array(state0[2], dtype=float)
    else:
        rhs0 = F0 + w * (force_w[0] - g) - D @ v - K @ u
        acc = spla.splu(M).solve(rhs0)
    loads = F0[None, :] + np.outer(ap * np.roll(force_w, -1) - alpha * force_w, w)

    def solve_mesh(pv: float, k: float) -> float:
        """The mesh force g given the prediction pv of δ - e with g = 0, contact stiffness k."""
        cc = apcw * k
        if pv > b:
            return k * ((pv + cc * b) / (1 + cc) - b)
        if pv < -b:
            return k * ((pv - cc * b) / (1 + cc) + b)
        return 0.0

    def step_period(state, g, hist):
        """One period step by step (all DOFs); fills ``hist`` = (δ, δ', g, q or None)."""
        for j in range(ns):
            if hist[3] is not None:
                hist[3][:, j] = state[:N]
            hist[0][j] = w @ state[:N]
            hist[1][j] = w @ state[N : 2 * N]
            hist[2][j] = g
            jn = (j + 1) % ns
            rhs = A_all @ state + F0 + w * (ap * force_w[jn] - alpha * force_w[j] + alpha * g)
            y = lu.solve(rhs)
            g = solve_mesh(w @ y - e_s[jn], k_s[jn])
            un = y - ap * g * zvec
            u0, v0, acc0 = state[:N], state[N : 2 * N], state[2 * N :]
            an = a1 * (un - u0) - a2 * v0 - a3 * acc0
            vn = b1 * (un - u0) + b2 * v0 + b3 * acc0
            state = np.concatenate([un, vn, an])
        return state, g

    hist = (np.empty(ns), np.empty(ns), np.empty(ns), np.empty((N, ns)) if store_dofs else None)
    pmap = PeriodMap(step, alpha, w[:, None], loads) if 3 * N + 1 <= MAX_STATE else None

    e_next = np.roll(e_s, -1).tolist()
    k_next = np.roll(k_s, -1).tolist()

    def solve_link(y_lin: float, j: int) -> tuple[float, float]:
        g1 = solve_mesh(y_lin - e_next[j], k_next[j])
        return y_lin - apcw * g1, g1

    prev = None
    section: list[float] = []
    diffs: list[float] = []
    converged = False
    scale0 = abs(F0 @ w) / (k_h * (w @ w)) if np.any(F0) else 0.0
    p = 0
    state = np.concatenate([u, v, acc])
    for p in range(1, max_periods + 1):
        start = (state, g)
        if pmap is None:
            state, g = step_period(state, g, hist)
            cur = hist[0].copy()
        else:
            ys, s_end = pmap.run(np.append(state, g), solve_link)
            state, g, cur = s_end[: 3 * N], float(s_end[-1]), ys[0]
        section.append(float(cur[0]))
        if prev is not None:
            d = float(np.max(np.abs(cur - prev)) / (np.ptp(cur) + scale0 + 1e-300))
            diffs.append(d)
            if p >= min_periods and d < tol:
                rho = d / diffs[-2] if len(diffs) > 1 and diffs[-2] > 0 else 0.0
                if rho < 1 and d * rho / (1 - rho) < tol:
                    converged = True
                    break
        prev = cur
    if pmap is not None and p:
        state, g = step_period(*start, hist)  # the last period again, to record every history
    delta_hist, ddot_hist, g_hist, q_hist = hist
    t = dt * np.arange(ns)
    force = g_hist + c_m * (ddot_hist - edot_s)
    hist = TimeHistory(t, delta_hist.copy(), ddot_hist.copy(), e_s.copy(), edot_s.copy(), force)
    final = (state[:N].copy(), state[N : 2 * N].copy(), state[2 * N :].copy())
    last = diffs[-1] if diffs else float("nan")
    return FETimeResponse(omega, hist, converged, p, last, q_hist, final, np.array(section))
