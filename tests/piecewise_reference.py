"""Brute-force reference for the two-DOF chain with a stiff one-sided spring (issue 35, part 1).

The chain (SI, but every value is 1 but the stop and the damping):

    m x₁'' + c (2 x₁' - x₂') + k (2 x₁ - x₂)            = 0
    m x₂'' + c (x₂' - x₁')   + k (x₂ - x₁) + k_c (x₂ - u(t) - g)⁺ = 0,    u(t) = a cos ωt

m = 1 kg, k = 1 N/m (mass 1 tied to ground and to mass 2 by k), damping D = c K with
c = :data:`C` (stiffness proportional: ζ = c ω_i / 2, 0.6 % and 1.6 % at the free chain's
modes), a stop of stiffness k_c = 100 k acting on mass 2 whose seat moves as u(t) = a cos ωt
(base excitation of the stop, no gap g = :data:`GAP` = 0, no preload; a = :data:`SEAT` = 1 m: with no gap
the equations are positively homogeneous, so a only scales the orbit). The stop's force
k_c (x₂ - u)⁺ is continuous, so the vector field is continuous across the switching
surface x₂ = u(t), and the saltation matrix S = I + (f⁺ - f⁻) nᵀ / (nᵀ f⁻) at a contact
change is the identity (Leine & Nijmeijer, Dynamics and Bifurcations of Non-Smooth
Mechanical Systems, 2004, §3.5: f⁺ = f⁻ on the surface): the monodromy is the ordered
product of the flows' Jacobians. The same setting as the one-sided-spring two-DOF
oscillators of e.g. Shaw & Holmes 1983 (J. Sound Vib. 90:129; one DOF, a stiff stop)
extended to a chain, with the excitation through the stop's seat (``ContactStop``'s
seat motion).

A variant of the stop (:class:`Stop`, the ``stop`` argument of every function; default
the module's :data:`GAP` and :data:`PRELOAD`) has a gap g > 0 or a static force P on mass 2
towards the stop (the preloaded chain of tests/test_folds.py: P = 12 N, whose lifted-off
branch folds at 1.2895493815 rad/s); both enter z' = A z through its constant column.

The exact flow: between contact changes the equations are linear with harmonic forcing;
with the augmented state z = (x₁, x₂, v₁, v₂, cos ωt, sin ωt, 1) they are z' = A z, so
z(t + τ) = expm(A τ) z(t) (scipy's expm; no time stepping error). Contact changes are
found by sampling the gap h = x₂ - u(t) at :data:`SAMPLES` points per period (with a
Hermite test for a double crossing inside a sample interval) and located by safeguarded
Newton on the exact flow to 1e-13 of the period.

Periodic orbits by shooting: Newton on r(s₀, ω) = φ_{νT}(s₀) - s₀ with the monodromy
Φ - I as Jacobian; branches followed by pseudo-arc-length continuation in (s₀, ω) (∂r/∂ω
by central differences); Floquet multipliers the eigenvalues of Φ; bifurcations located
by bisection on the arc length of a test function: max |μ| - 1 over complex pairs
(Neimark-Sacker), -1 - min real μ (period doubling), the largest real μ - 1 (fold).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

MASS, STIFF, KC, C, SEAT, GAP, PRELOAD = 1.0, 1.0, 100.0, 0.02, 1.0, 0.0, 0.0
# GAP: the stop closes where x₂ - u(t) > GAP (0 in the chain; a large negative value keeps
# it closed all period: the linear check of test_piecewise_reference)
M = MASS * np.eye(2)
K = STIFF * np.array([[2.0, -1.0], [-1.0, 1.0]])
D = C * K
W = np.array([[0.0], [1.0]])  # the stop acts on x₂
SAMPLES = 256  # gap samples per forcing period
EVENT_RTOL = 1e-13  # contact changes located to this fraction of the period


@dataclass(frozen=True)
class Stop:
    """A variant of the stop: its gap g [m] (closed where x₂ - u(t) > g) and a static
    force P [N] on mass 2 towards the stop (a preload when g = 0)."""

    gap: float = 0.0
    preload: float = 0.0


def _stop(stop: Stop | None) -> Stop:
    """``stop``, or the module's :data:`GAP` and :data:`PRELOAD` when None (read at call time)."""
    return Stop(GAP, PRELOAD) if stop is None else stop


def augmented(omega: float, closed: bool, stop: Stop | None = None) -> np.ndarray:
    """A (7 x 7) of z' = A z, z = (x₁, x₂, v₁, v₂, cos ωt, sin ωt, 1), in one contact state."""
    Kt = K + (KC * W @ W.T if closed else 0.0)
    A = np.zeros((7, 7))
    A[:2, 2:4] = np.eye(2)
    A[2:4, :2] = -np.linalg.solve(M, Kt)
    A[2:4, 2:4] = -np.linalg.solve(M, D)
    if closed:
        A[2:4, 4] = np.linalg.solve(M, KC * SEAT * W[:, 0])
        A[2:4, 6] = np.linalg.solve(M, KC * _stop(stop).gap * W[:, 0])
    A[2:4, 6] += np.linalg.solve(M, _stop(stop).preload * W[:, 0])
    A[4, 5], A[5, 4] = -omega, omega
    return A


def gap(z: np.ndarray, stop: Stop | None = None) -> float:
    """h = x₂ - u(t) - g: the stop is closed where h > 0."""
    return float(z[1] - SEAT * z[4] - _stop(stop).gap)


class Flow:
    """The exact flow of the chain at one forcing frequency ω [rad/s] with the gap g [m]
    (default :data:`GAP`)."""

    def __init__(self, omega: float, stop: Stop | None = None):
        self.omega = float(omega)
        self.stop = _stop(stop)
        self.T = 2 * np.pi / self.omega
        self.dt = self.T / SAMPLES
        self.A = {c: augmented(self.omega, c, self.stop) for c in (False, True)}
        self.E = {c: expm(self.A[c] * self.dt) for c in (False, True)}

    def h(self, z: np.ndarray) -> float:
        """The gap function h = x₂ - u(t) - g of this flow's gap."""
        return gap(z, self.stop)

    def slope(self, z: np.ndarray, closed: bool) -> float:
        dz = self.A[closed] @ z
        return float(dz[1] - SEAT * dz[4])

    def _locate(self, z: np.ndarray, closed: bool, a: float, b: float) -> float:
        """The first zero of the gap in (a, b] after z (at τ = 0), bracketed Newton."""
        A = self.A[closed]
        ga, gb = self.h(expm(A * a) @ z), self.h(expm(A * b) @ z)
        tau = a + (b - a) * ga / (ga - gb) if ga != gb else 0.5 * (a + b)
        for _ in range(100):
            zt = expm(A * tau) @ z
            g = self.h(zt)
            if (g > 0) == (ga > 0):
                a = tau
            else:
                b = tau
            new = tau - g / self.slope(zt, closed) if self.slope(zt, closed) != 0 else 0.5 * (a + b)
            if not a < new < b:
                new = 0.5 * (a + b)
            if abs(new - tau) < EVENT_RTOL * self.T or b - a < EVENT_RTOL * self.T:
                return new
            tau = new
        return tau

    def advance(self, s: np.ndarray, periods: int = 1, jacobian: bool = True, t_end: float | None = None):
        """Advance s = (x₁, x₂, v₁, v₂) at t = 0 by ``periods`` forcing periods (or to ``t_end``).

        Returns (s at the end, monodromy ∂s_end/∂s₀ (4 x 4), contact-change times)."""
        t_end = periods * self.T if t_end is None else t_end
        z = np.concatenate([s, [1.0, 0.0, 1.0]])
        closed = self.h(z) > 0 or (self.h(z) == 0 and self.slope(z, True) > 0)
        Phi = np.eye(4)
        t, events = 0.0, []
        while t < t_end - 1e-15 * self.T:
            step = min(self.dt, t_end - t)
            E = self.E[closed] if step == self.dt else expm(self.A[closed] * step)
            zn = E @ z
            h0, h1 = self.h(z), self.h(zn)
            side = 1.0 if closed else -1.0
            crossed = side * h1 < 0
            d0 = self.slope(z, closed) * step if not crossed else 0.0
            d1 = self.slope(zn, closed) * step if not crossed else 0.0
            if not crossed and side * d0 < 0 < side * d1:  # h turns inside: a double crossing?
                ts = np.linspace(0, 1, 33)[1:-1]
                hh = (
                    (2 * ts**3 - 3 * ts**2 + 1) * h0
                    + (ts**3 - 2 * ts**2 + ts) * d0
                    + (-2 * ts**3 + 3 * ts**2) * h1
                    + (ts**3 - ts**2) * d1
                )
                bad = np.nonzero(side * hh < 0)[0]
                if bad.size:
                    crossed, step = True, float(ts[bad[0]] * step)
                    zn = expm(self.A[closed] * step) @ z
            if crossed:
                tau = self._locate(z, closed, 0.0, step)
                E = expm(self.A[closed] * tau)
                z = E @ z
                if jacobian:
                    Phi = E[:4, :4] @ Phi  # saltation = identity (continuous force)
                t += tau
                events.append(t)
                closed = not closed
                continue
            if jacobian:
                Phi = E[:4, :4] @ Phi
            z, t = zn, t + step
        return z[:4], Phi, np.array(events)


def residual(s0: np.ndarray, omega: float, nu: int, stop: Stop | None = None):
    """(φ_{νT}(s₀) - s₀, Φ) at ω."""
    s, Phi, _ = Flow(omega, stop).advance(s0, nu)
    return s - s0, Phi


def d_omega(s0: np.ndarray, omega: float, nu: int, h: float = 1e-6, stop: Stop | None = None) -> np.ndarray:
    """∂r/∂ω by a central difference (the flow is smooth in ω away from grazing)."""
    rp = Flow(omega * (1 + h), stop).advance(s0, nu, jacobian=False)[0]
    rm = Flow(omega * (1 - h), stop).advance(s0, nu, jacobian=False)[0]
    return (rp - rm) / (2 * h * omega)


def shoot(
    s0: np.ndarray,
    omega: float,
    nu: int = 1,
    tol: float = 1e-12,
    max_iter: int = 40,
    stop: Stop | None = None,
):
    """Periodic orbit of period ν T at fixed ω by Newton; (s₀, Φ, converged)."""
    s0 = np.array(s0, dtype=float)
    for _ in range(max_iter):
        r, Phi = residual(s0, omega, nu, stop)
        if np.linalg.norm(r) <= tol * max(np.linalg.norm(s0), SEAT):
            return s0, Phi, True
        s0 = s0 - np.linalg.solve(Phi - np.eye(4), r)
    r, Phi = residual(s0, omega, nu, stop)
    return s0, Phi, bool(np.linalg.norm(r) <= tol * max(np.linalg.norm(s0), SEAT))


@dataclass
class Point:
    s0: np.ndarray
    omega: float
    mu: np.ndarray
    tangent: np.ndarray


def _tangent(s0, omega, nu, Phi, prev=None, stop=None):
    J = np.column_stack([Phi - np.eye(4), d_omega(s0, omega, nu, stop=stop)])
    t = np.linalg.svd(J)[2][-1]
    if prev is not None and t @ prev < 0:
        t = -t
    return t


def _correct(u_pred, tangent, nu, tol=1e-12, max_iter=30, stop=None):
    u = u_pred.copy()
    for _ in range(max_iter):
        r, Phi = residual(u[:4], u[4], nu, stop)
        g = tangent @ (u - u_pred)
        if np.linalg.norm(r) <= tol * max(np.linalg.norm(u[:4]), SEAT) and abs(g) < 1e-12:
            return u, Phi
        J = np.vstack([np.column_stack([Phi - np.eye(4), d_omega(u[:4], u[4], nu, stop=stop)]), tangent])
        u = u - np.linalg.solve(J, np.concatenate([r, [g]]))
    return None, None


def continue_branch(s0, omega, omega_stop, nu=1, ds=0.02, max_points=4000, stop=None):
    """Pseudo-arc-length continuation from the orbit (s₀, ω) towards ``omega_stop``."""
    s0, Phi, ok = shoot(s0, omega, nu, stop=stop)
    assert ok, "no orbit to start from"
    t = _tangent(s0, omega, nu, Phi, stop=stop)
    if np.sign(t[4]) != np.sign(omega_stop - omega):
        t = -t
    pts = [Point(s0, omega, np.linalg.eigvals(Phi), t)]
    while len(pts) < max_points:
        p = pts[-1]
        u0 = np.concatenate([p.s0, [p.omega]])
        h = ds
        while True:
            u, Phi = _correct(u0 + h * p.tangent, p.tangent, nu, stop=stop)
            if u is not None and np.linalg.norm(u - u0) < 3 * h:
                break
            h /= 2
            assert h > 1e-8 * ds, "continuation stalled"
        t = _tangent(u[:4], u[4], nu, Phi, p.tangent, stop)
        pts.append(Point(u[:4], u[4], np.linalg.eigvals(Phi), t))
        if (u[4] - omega_stop) * (omega - omega_stop) <= 0:
            break
    return pts


def test_functions(mu: np.ndarray) -> dict:
    """Scalar tests, real and continuous along a branch, whose zeros are the bifurcations:
    Π(1 - μ) (fold), Π(1 + μ) (period doubling), Π_{i<j}(1 - μ_i μ_j) (Neimark-Sacker, also
    zero at a neutral saddle μ_i μ_j = 1, told apart by :func:`kind_of`) (Kuznetsov,
    Elements of Applied Bifurcation Theory, 3rd ed. 2004, §10.2-10.3)."""
    mu = np.asarray(mu, dtype=complex)
    iu = np.triu_indices(mu.size, 1)
    return {
        "fold": float(np.prod(1 - mu).real),
        "period doubling": float(np.prod(1 + mu).real),
        "Neimark-Sacker": float(np.prod(1 - mu[iu[0]] * mu[iu[1]]).real),
    }


def kind_of(mu: np.ndarray, kind: str, atol: float = 1e-6) -> bool:
    """Whether the multipliers at a located zero are that bifurcation's (a critical μ)."""
    mu = np.asarray(mu, dtype=complex)
    if kind == "fold":
        return bool(np.min(np.abs(mu - 1)) < atol)
    if kind == "period doubling":
        return bool(np.min(np.abs(mu + 1)) < atol)
    pair = mu[np.abs(mu.imag) > atol]
    return bool(pair.size and np.min(np.abs(np.abs(pair) - 1)) < atol)


def locate(pts: list, nu: int = 1, rtol: float = 1e-9, stop: Stop | None = None) -> list:
    """Bifurcations between consecutive points of a branch: [(kind, ω, multipliers)].

    A sign change of a test function between two points is bisected on the arc length
    (predictor from the first point along its tangent, corrected on the hyperplane normal
    to it) until the test function is below ``rtol`` or the step below 1e-12."""
    out = []
    for p, q in zip(pts[:-1], pts[1:], strict=True):
        fp, fq = test_functions(p.mu), test_functions(q.mu)
        for kind in fp:
            a, b = fp[kind], fq[kind]
            if a * b > 0:
                continue
            u0 = np.concatenate([p.s0, [p.omega]])
            lo, hi = 0.0, float(p.tangent @ (np.concatenate([q.s0, [q.omega]]) - u0))
            flo = a
            for _ in range(80):
                mid = 0.5 * (lo + hi)
                u, Phi = _correct(u0 + mid * p.tangent, p.tangent, nu, stop=stop)
                f = test_functions(np.linalg.eigvals(Phi))[kind]
                if hi - lo < 1e-12:
                    break
                if f * flo > 0:
                    lo, flo = mid, f
                else:
                    hi = mid
            mu = np.linalg.eigvals(Phi)
            if kind_of(mu, kind):
                out.append((kind, float(u[4]), mu, u[:4]))
    return out
