"""Single-DOF gear pair with backlash (Özgüven & Houser 1988; the paper's DYTE model).

    m_eq δ'' + c_m (δ' - e') + k_h f(δ - e) = W_0

δ the relative displacement along the line of action [m], e(t) the LSTE, f the
backlash function (total backlash 2b), m_eq = I_p I_g / (I_p r_bg² + I_g r_bp²). The
model gives the reduced harmonic-balance problem directly,

    κ_k = -m_eq (kω)² + i kω c_m,   F_k = W_0 [k = 0] + i kω c_m E_k,

and is integrated in time (:func:`integrate`, :func:`time_sweep`) as the independent
reference. The LSTE mean e_0 is kept as given (it only shifts δ by e_0).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp

from nlgrd.describing_functions import (
    BacklashMesh,
    analyse,
    deadzone,
    differentiate,
    evaluate,
    real_to_complex,
    resize_harmonics,
)
from nlgrd.errors import ModelError, check_finite, check_positive
from nlgrd.harmonic_balance import LinearStateSpace, ReducedModel
from nlgrd.nonlinear_results import TimeHistory, metrics_from_history
from nlgrd.sweep import SweepResult, _sweep_orders, assemble_result


@dataclass(frozen=True)
class SDOFGearPair:
    """Single-DOF gear pair model (SI units).

    Parameters
    ----------
    mass : float
        Equivalent mass m_eq [kg].
    mesh_stiffness : float
        Average mesh stiffness k_h [N/m].
    half_backlash : float
        b [m] (total backlash 2b).
    static_load : float
        W_0 [N].
    lste : array_like
        Real harmonics [e_0, a_1, b_1, ...] of e(θ), θ = ω t [m].
    damping_ratio : float
        ζ, giving c_m = 2 ζ sqrt(k_h m_eq) unless ``damping`` is set.
    damping : float, optional
        Mesh damping c_m [N s/m].
    """

    mass: float
    mesh_stiffness: float
    half_backlash: float
    static_load: float
    lste: NDArray = field(default_factory=lambda: np.zeros(1))
    damping_ratio: float = 0.0
    damping: float | None = None

    def __post_init__(self):
        check_positive("mass", self.mass)
        check_positive("mesh_stiffness", self.mesh_stiffness)
        check_positive("half_backlash", self.half_backlash, allow_zero=True)
        check_positive("damping_ratio", self.damping_ratio, allow_zero=True)
        check_finite("static_load", self.static_load)
        lste = np.atleast_1d(np.asarray(self.lste, dtype=float))
        check_finite("lste", lste)
        if lste.size % 2 != 1:
            raise ModelError("lste", "real harmonics [e0, a1, b1, ...] of odd length")
        object.__setattr__(self, "lste", lste)
        if self.damping is not None:
            check_positive("damping", self.damping, allow_zero=True)

    @classmethod
    def from_gears(
        cls,
        pinion_inertia: float,
        gear_inertia: float,
        pinion_base_radius: float,
        gear_base_radius: float,
        mesh_stiffness: float,
        half_backlash: float,
        static_load: float,
        lste: ArrayLike,
        damping_ratio: float = 0.0,
    ) -> SDOFGearPair:
        """From I_p, I_g [kg m²] and base radii [m]: m_eq = I_p I_g / (I_p r_bg² + I_g r_bp²)."""
        m = (
            pinion_inertia
            * gear_inertia
            / (pinion_inertia * gear_base_radius**2 + gear_inertia * pinion_base_radius**2)
        )
        return cls(m, mesh_stiffness, half_backlash, static_load, np.asarray(lste), damping_ratio)

    @property
    def mesh_damping(self) -> float:
        """c_m [N s/m]."""
        if self.damping is not None:
            return float(self.damping)
        return 2 * self.damping_ratio * np.sqrt(self.mesh_stiffness * self.mass)

    @property
    def natural_frequency(self) -> float:
        """ω_n = sqrt(k_h / m_eq) [rad/s]."""
        return float(np.sqrt(self.mesh_stiffness / self.mass))

    def mesh(self, method: str = "exact", n_samples: int | None = None) -> BacklashMesh:
        """The mesh nonlinearity (acting on coordinate 0, δ)."""
        return BacklashMesh(
            self.mesh_stiffness,
            self.half_backlash,
            self.lste,
            self.mesh_damping,
            self.static_load,
            0,
            method,
            n_samples,
        )

    def kappa(self, omega: float, H: int) -> NDArray[np.complex128]:
        """κ_k = -m (kω)² + i kω c_m, k = 0..H [N/m]."""
        w = np.arange(H + 1) * omega
        return -self.mass * w**2 + 1j * w * self.mesh_damping

    def force(self, omega: float, H: int) -> NDArray[np.complex128]:
        """F_k = W_0 [k=0] + i kω c_m E_k [N]."""
        w = np.arange(H + 1) * omega
        F = 1j * w * self.mesh_damping * real_to_complex(resize_harmonics(self.lste, H))
        F[0] = self.static_load
        return F

    def state_space(self) -> LinearStateSpace:
        """M = [[m]], D = [[c_m]], K = [[0]], W = [[1]] for Floquet stability."""
        return LinearStateSpace([[self.mass]], [[self.mesh_damping]], [[0.0]], [[1.0]])

    def reduced_model(self, method: str = "exact", n_samples: int | None = None) -> ReducedModel:
        """The reduced harmonic-balance model with analytic ω-derivatives."""
        m, c = self.mass, self.mesh_damping

        def dkappa(omega: float, H: int) -> NDArray:
            k = np.arange(H + 1)
            return -2 * m * k**2 * omega + 1j * k * c

        def dforce(omega: float, H: int) -> NDArray:
            k = np.arange(H + 1)
            return 1j * k * c * real_to_complex(resize_harmonics(self.lste, H))

        return ReducedModel(
            self.kappa,
            self.force,
            (self.mesh(method, n_samples),),
            state_space=self.state_space(),
            kappa_derivative=dkappa,
            force_derivative=dforce,
        )

    def linear_response(self, omega: float, H: int) -> NDArray[np.float64]:
        """Real harmonics of δ with the mesh always in drive-side contact (linear response).

        (κ_k + k_h) δ_k = F_k + k_h E_k + k_h b [k = 0].
        """
        k_h = self.mesh_stiffness
        E = real_to_complex(resize_harmonics(self.lste, H))
        rhs = self.force(omega, H) + k_h * E
        rhs[0] += k_h * self.half_backlash
        Y = rhs / (self.kappa(omega, H) + k_h)
        out = np.empty(2 * H + 1)
        out[0] = Y[0].real
        out[1::2], out[2::2] = Y[1:].real, -Y[1:].imag
        return out


# --------------------------------------------------------------------------------------
# Time integration
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TimeResponse:
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


def _segment_rhs(mode: int, zeta2: float, w0: float, bt: float, ecoef: tuple):
    """RHS u'' = -2ζ u' - |m| (u - ẽ - m b̃) + w0 + 2ζ ẽ' in the scaled variables."""
    k, a, bb, e0, s = ecoef
    stiff = float(abs(mode))

    def rhs(tau, y):
        th = s * tau * k
        c, sn = np.cos(th), np.sin(th)
        e = e0 + a @ c + bb @ sn
        de = s * ((bb * k) @ c - (a * k) @ sn)
        return np.array([y[1], -zeta2 * y[1] - stiff * (y[0] - e - mode * bt) + w0 + zeta2 * de])

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
    """Integrate the SDOF gear pair to a periodic steady state at mesh frequency ``omega``.

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
    rhs = {md: _segment_rhs(md, zeta2, w0, bt, ecoef) for md in (-1, 0, 1)}
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
    force = k_h * deadzone(delta - e, b) + model.mesh_damping * (ddot - edot)
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

    Returns a :class:`~nlgrd.sweep.SweepResult` whose metrics come from the sampled last
    period (harmonics 0..H by FFT, ``iterations`` = periods simulated, ``residual`` =
    last period-to-period difference, ``converged`` = steady state reached; stability
    is not computed: only attracting solutions survive a time integration).
    ``state0`` [δ, δ'] starts each direction (default: static deflection at rest, which
    may be attracted to either branch inside a multivalued range); ``kwargs`` go to
    :func:`integrate`.
    """
    mesh = model.mesh()
    rows: dict[str, list] = {k: [] for k in "wdzcrim"}
    for direction, order in _sweep_orders(np.asarray(omegas, dtype=float), directions):
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
    )
