"""The step of a speed ramp on a link model of any links and loads (:mod:`nlgrd.timedomain.run_down`).

Every excitation of a link model sits at a harmonic of the base frequency ω
(:class:`~nlgrd.nonlinear.links.frequency_plan.FrequencyPlan`): the links' own forcing on
their coordinates (a mesh's LSTE through its damping, c_m e') and the harmonic forces on
the DOFs (unbalance). At a constant ω their harmonics are X_k(ω) = A_k + B_k ω + C_k ω²
(:class:`RampForcing` finds A, B, C from the model at ω = 0, ω_0, 2ω_0 and checks the
fit at 3ω_0). Under a ramp the phase is the integral of the speed, θ(t) = ∫ω dt, and each
part keeps its physical form:

- B: a rate, B_k ω e^{ikθ} = (B_k / ik) d/dt e^{ikθ} (c_m de/dt of the mesh), exact for
  any ω(t) as it stands;
- C: an inertial force, -(C_k / k²) d²/dt² e^{ikθ} = C_k (ω² - i ω'/k) e^{ikθ} (the
  unbalance m e φ'² radially and m e φ'' tangentially, φ the shaft angle);
- A: a force of fixed amplitude at the phase kθ.

The HHT-α step is that of :class:`nlgrd.timedomain.links.LinkIntegrator`: the link
forces g and the harmonic forces enter along the extended directions [P, U] (U the unit
vectors of the loaded DOFs) as one input g_e = (g - φ, -f), the link forcing φ with the
opposite sign of the link forces, so that a block of fixed steps is the affine
:class:`~nlgrd.timedomain.period_map.PeriodMap` and a step solves the links' own equation
by :func:`~nlgrd.timedomain.links.newton_links` (the one link solve of nlgrd's
integrators), the known forcing moved to its right-hand side.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.models.link_model import LinkModel
from nlgrd.timedomain.integrator import hht_step
from nlgrd.timedomain.links import newton_links, pointwise_forces
from nlgrd.timedomain.period_map import PeriodMap

#: Relative mismatch of the quadratic fit of the forcing at 3 ω_0 above which a model's
#: forcing is not a polynomial of degree 2 in ω (rounding of the fit is ~1e-15).
FIT_RTOL = 1e-9


def block_map(lm, c_link, P: NDArray, F0: NDArray, speed: float, dt: float, alpha: float, block: int):
    """The HHT step and the :class:`PeriodMap` of ``block`` steps at reference speed ``speed``.

    Parameters
    ----------
    lm : LinearModel
        The linear FE model (M, D(Ω), K(Ω)).
    c_link : sparse (N, N)
        The links' viscous damping on the DOFs [N s/m].
    P : ndarray (N, d_e)
        The input directions (the links' and the loaded DOFs') [-].
    F0 : ndarray (N,)
        Static loads [N, N m].
    speed : float
        Reference shaft speed of the matrices [rad/s].
    dt, alpha : float
        Time step [s] and HHT-α parameter [-].
    block : int
        Steps of the map [-].

    Returns
    -------
    tuple
        (HHTStep, PeriodMap).
    """
    step = hht_step(lm.M, lm.damping(speed) + c_link, lm.stiffness(speed), dt, alpha)
    return step, PeriodMap(step, alpha, P, np.tile(F0, (block, 1)))


class RampForcing:
    """The excitation of a link model at a time-varying base frequency (module docstring).

    Parameters
    ----------
    model : LinkModel
        The model.
    omega0 : float
        Reference base frequency of the fit [rad/s] (the ramp's start).

    Attributes
    ----------
    d : int
        Link coordinates [-].
    dofs : ndarray of int
        The DOFs the harmonic forces load (U's columns).

    Raises
    ------
    ModelError
        (``model``) The forcing is not a polynomial of degree 2 in ω.
    """

    def __init__(self, model: LinkModel, omega0: float):
        rec = model.receptance
        self.H = max([30] + [int(getattr(lk, "excitation_harmonics", 0)) for lk in model.links])
        self.d = rec.P.shape[1]
        self._links, self._hf = tuple(zip(model.links, rec.slices, strict=True)), rec.harmonic_force
        dofs = np.zeros(0, dtype=int)
        if self._hf is not None:
            dofs = rec.force_dofs
            if not dofs.size:  # every DOF a harmonic force loads at some frequency
                dofs = np.flatnonzero(np.any(self._hf(omega0, self.H)[1:] != 0, axis=0))
        self.dofs = np.asarray(dofs, dtype=int)
        w0 = float(omega0)
        X0, X1, X2, X3 = (self._harmonics(f * w0) for f in (0.0, 1.0, 2.0, 3.0))
        D1, D2 = X1 - X0, X2 - X0
        self.C = (D2 - 2 * D1) / 2  # C ω_0²
        self.B = D1 - self.C  # B ω_0
        self.A, self.omega0 = X0, w0
        miss = np.abs(X0 + 3 * self.B + 9 * self.C - X3).max()
        if miss > FIT_RTOL * (np.abs(X3).max() + 1e-300):
            raise ModelError(
                "model",
                f"its forcing is not of the form A + B ω + C ω² in the base frequency (mismatch "
                f"{miss:.2e} N at 3 ω_0): a speed ramp cannot follow it",
            )
        k = np.arange(self.H + 1)
        self._k = k
        self._tangential = np.zeros_like(self.C)
        self._tangential[1:] = -1j * self.C[1:] / k[1:, None]  # -i C_k / k (ω'/ω_0² per unit)

    def _harmonics(self, omega: float) -> NDArray:
        """X_k(ω), (H+1, d + len(dofs)) complex [N]: the links' forcing, then the DOFs'."""
        X = np.zeros((self.H + 1, self.d + self.dofs.size), dtype=complex)
        for link, sl in self._links:
            X[:, sl] = link.forcing(omega, self.H)
        if self.dofs.size:
            X[:, self.d :] = np.asarray(self._hf(omega, self.H), dtype=complex)[:, self.dofs]
        return X

    def at(self, theta: NDArray, omega: NDArray, omega_dot: float) -> NDArray:
        """The forcing (φ, f) at phases ``theta`` and base frequencies ``omega``.

        Parameters
        ----------
        theta, omega : ndarray (n,)
            θ [rad] and ω [rad/s] at n instants.
        omega_dot : float
            dω/dt [rad/s²].

        Returns
        -------
        ndarray (n, d + len(dofs))
            φ on the link coordinates, then f on the loaded DOFs [N].
        """
        E = np.exp(1j * np.multiply.outer(theta, self._k))
        r = (np.asarray(omega, dtype=float) / self.omega0)[:, None]
        out = np.real(E @ self.A) + r * np.real(E @ self.B) + r * r * np.real(E @ self.C)
        if omega_dot:
            out = out + (omega_dot / self.omega0**2) * np.real(E @ self._tangential)
        return out


def multi_link_ramp(
    model: LinkModel,
    state: tuple,
    w0: float,
    rate: float,
    dt: float,
    n_blocks: int,
    alpha: float,
    block: int,
    speed_rtol: float,
    record: Callable[[NDArray, NDArray, NDArray, NDArray], None],
) -> None:
    """Integrate ``n_blocks`` blocks of the ramp ω = w0 - rate t, θ = w0 t - rate t²/2
    from ``state`` at θ = 0, handing each block's steps to ``record``.

    Parameters
    ----------
    model : LinkModel
        The model (any links; harmonic forces on the DOFs).
    state : tuple (q, q', q'')
        State at θ = 0 [m, m/s, m/s²].
    w0, rate, dt : float
        Start base frequency [rad/s], -dω/dt [rad/s²] and the time step [s].
    n_blocks, block : int
        Blocks and steps per block [-].
    alpha, speed_rtol : float
        HHT-α parameter; relative change of speed that rebuilds the matrices [-].
    record : callable
        ``record(t, y, g)`` with the times at the start of the block's steps (n,) [s],
        the link coordinates (d, n) [m] and the link forces (d, n) [N] there.
    """
    rec = model.receptance
    lm, P = rec.model, np.asarray(rec.P, dtype=float)
    links, slices = tuple(model.links), tuple(rec.slices)
    force = RampForcing(model, w0)
    d, n = P.shape[1], P.shape[0]
    U = np.zeros((n, force.dofs.size))
    U[force.dofs, np.arange(force.dofs.size)] = 1.0
    Pe = np.hstack([P, U])
    de = Pe.shape[1]
    F0 = np.asarray(rec.static_force, dtype=float).reshape(-1)
    speed_of = rec.plan.speed
    speed_built = speed_of(w0)
    step, pmap = block_map(lm, rec.C_link, Pe, F0, speed_built, dt, alpha, block)

    def load(t):
        return force.at(w0 * t - 0.5 * rate * t * t, w0 - rate * t, -rate)

    u = np.asarray(state[0], dtype=float)
    x0 = load(np.zeros(1))[0]
    g_prev = pointwise_forces(links, slices, P.T @ u, 0.0)[0]
    ge0 = np.concatenate([g_prev - x0[:d], -x0[d:]])
    s = np.concatenate([u, state[1], state[2], ge0])
    g_buf = np.empty((block, d))
    for nb in range(n_blocks):
        t_next = dt * (nb * block + 1 + np.arange(block))  # the ends of the block's steps
        om_mid = w0 - rate * dt * (nb + 0.5) * block
        if abs(speed_of(om_mid) - speed_built) > speed_rtol * speed_built:
            speed_built = speed_of(om_mid)
            step, pmap = block_map(lm, rec.C_link, Pe, F0, speed_built, dt, alpha, block)
        ap, S = step.ap, pmap.S
        X = load(t_next)  # (block, de): φ, f at the steps' ends
        th_next = (w0 * t_next - 0.5 * rate * t_next**2).tolist()
        shift = ap * (X @ S.T)  # the known forcing's share of each step's y
        S_l, S_xl, ge_known = S[:d, :d], ap * S[:, :d], -X  # g_e = (g - φ, -f)

        def solve(y_lin, j, shift=shift, S_l=S_l, S_xl=S_xl, ge_known=ge_known, th=th_next, ap=ap):
            y_eff = np.atleast_1d(y_lin) + shift[j]
            yl, g = newton_links(lambda y: pointwise_forces(links, slices, y, th[j]), ap, S_l, y_eff[:d])
            g_buf[j] = g
            ge = ge_known[j].copy()
            ge[:d] += g
            y_all = y_eff - S_xl @ g
            y_all[:d] = yl
            return (float(y_all[0]), float(ge[0])) if de == 1 else (y_all, ge)

        ys, s = pmap.run(s, solve)
        g_start = np.vstack([g_prev[None, :], g_buf[:-1]]).T
        g_prev = g_buf[-1].copy()
        record(t_next - dt, ys[:d], g_start)
