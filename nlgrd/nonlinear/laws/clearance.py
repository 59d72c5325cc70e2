"""Radial clearance contact in a plane: the force law of a bearing with clearance.

With u = (u_y, u_z) the journal's displacement relative to its housing, r = |u| and
radial clearance c, the contact force on the journal is

    f(u) = -k (r - c)^p u / r   for r > c,      0 for r <= c

(a restoring force; the law returns +k (r - c)^p u / r, the force the journal exerts on
the support, as the mesh law does: the solver subtracts it). p = 1 is a linear contact
stiffness k [N/m]; p = 3/2 the Hertzian point contact of rolling elements, k in
[N/m^1.5] (Harris & Kotzalas 2007, Rolling Bearing Analysis, §6; Ehrich 1988, J. Vib.
Acoust. 110:9, for the rub and clearance models of rotordynamics). The tangent
stiffness is

    ∂f/∂u = k [ p (r - c)^(p-1) r̂ r̂ᵀ + ((r - c)^p / r) (I - r̂ r̂ᵀ) ],   r̂ = u / r,

continuous at r = c for p > 1 (for p = 1 the radial tangent steps from 0 to k there).
The law is smooth inside each contact state but not piecewise linear, so its harmonics
and their Jacobian come from alternating frequency-time sampling (AFT, Cameron &
Griffin 1989, J. Appl. Mech. 56:149): sample u on ``n_samples`` points of the period,
evaluate f and ∂f/∂u, transform back.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from nlgrd.cache import BoundedCache
from nlgrd.errors import ModelError, check_positive
from nlgrd.nonlinear.fourier.harmonics import analyse, evaluate, n_harmonics, sample, toeplitz_jacobian

#: Exponents of the contact law: linear spring, Hertzian point contact.
EXPONENTS = (1.0, 1.5)


@dataclass(frozen=True)
class RadialClearanceLaw:
    """Radial clearance contact on two nonlinear coordinates (a plane), by AFT.

    Parameters
    ----------
    stiffness : float
        Contact stiffness k [N/m] for ``exponent`` 1, [N/m^1.5] for 1.5.
    clearance : float
        Radial clearance c [m] (0: contact from the start).
    exponent : float
        p: 1 (linear contact) or 1.5 (Hertzian).
    coords : tuple of int
        The two nonlinear coordinates (u_y, u_z) of the law among the solver's.
    n_samples : int
        AFT samples per period [-] (at least 4H + 2 for an exact Jacobian spectrum).
    """

    stiffness: float
    clearance: float
    exponent: float = 1.0
    coords: tuple[int, int] = (0, 1)
    n_samples: int = 256

    def __post_init__(self):
        check_positive("stiffness", self.stiffness)
        check_positive("clearance", self.clearance, allow_zero=True)
        if float(self.exponent) not in EXPONENTS:
            raise ModelError("exponent", f"must be one of {EXPONENTS}, got {self.exponent!r}")
        if len(self.coords) != 2:
            raise ModelError("coords", f"a radial law acts on two coordinates, got {self.coords!r}")
        if int(self.n_samples) < 16:
            raise ModelError("n_samples", f"must be at least 16, got {self.n_samples!r}")

    @cached_property
    def cache(self) -> BoundedCache:
        """The last samples of this law (8 entries)."""
        return BoundedCache(8)

    def offset(self, H: int) -> NDArray:
        """No excitation inside the law: zeros (2, 2H+1) [m].

        Parameters
        ----------
        H : int
            Number of harmonics [-].

        Returns
        -------
        ndarray (2, 2H+1)
        """
        return np.zeros((2, 2 * H + 1))

    def scale(self) -> float:
        """The radial clearance c [m]: where contact begins.

        Returns
        -------
        float
        """
        return float(self.clearance)

    def guess_stiffness(self) -> float:
        """The tangent at a penetration of one clearance (at least 10 µm): the stiffness
        of the first linear guess [N/m].

        Returns
        -------
        float
        """
        delta = max(self.clearance, 1e-5)
        return float(self.exponent * self.stiffness * delta ** (self.exponent - 1.0))

    def static_start(self, u: NDArray) -> NDArray:
        """The start of the static solve from a linear guess ``u`` (2,): moved out radially
        by one clearance, so that Newton starts in contact (inside the clearance the force
        and its tangent are zero and a mechanism supported only by the contact gives
        Newton no direction) [m].

        Parameters
        ----------
        u : ndarray (2,)
            Linear guess of the mean displacement [m].

        Returns
        -------
        ndarray (2,)
        """
        u = np.asarray(u, dtype=float)
        r = float(np.hypot(u[0], u[1]))
        return u if r == 0 else u * (r + self.clearance) / r

    def force_at(self, u: NDArray) -> NDArray:
        """Contact force f(u) for displacement samples ``u`` (2, N) [m]; returns (2, N) [N].

        Parameters
        ----------
        u : ndarray (2, N)
            Journal displacement relative to the housing [m].

        Returns
        -------
        ndarray (2, N)
            Force the journal exerts on the support [N].
        """
        u = np.asarray(u, dtype=float)
        r = np.hypot(u[0], u[1])
        pen = np.maximum(r - self.clearance, 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            g = np.where(r > 0, self.stiffness * pen**self.exponent / np.where(r > 0, r, 1.0), 0.0)
        if self.clearance == 0 and self.exponent == 1.0:
            g = np.full_like(r, self.stiffness)  # f = k u exactly, also at r = 0
        return g * u

    def tangent_at(self, u: NDArray) -> NDArray:
        """Tangent stiffness ∂f/∂u for samples ``u`` (2, N) [m]; returns (N, 2, 2).

        Parameters
        ----------
        u : ndarray (2, N)
            Journal displacement relative to the housing [m].

        Returns
        -------
        ndarray (N, 2, 2)
            ∂f/∂u [N/m].
        """
        u = np.asarray(u, dtype=float)
        n = u.shape[1]
        if self.clearance == 0 and self.exponent == 1.0:
            return np.broadcast_to(self.stiffness * np.eye(2), (n, 2, 2)).copy()
        r = np.hypot(u[0], u[1])
        pen = np.maximum(r - self.clearance, 0.0)
        safe = np.where(r > 0, r, 1.0)
        nh = u / safe  # r̂ (2, N)
        radial = self.stiffness * self.exponent * pen ** (self.exponent - 1.0)
        radial = np.where(pen > 0, radial, 0.0)
        hoop = np.where(r > 0, self.stiffness * pen**self.exponent / safe, 0.0)
        outer = np.einsum("in,jn->nij", nh, nh)
        return radial[:, None, None] * outer + hoop[:, None, None] * (np.eye(2)[None] - outer)

    def _samples(self, y: NDArray) -> tuple[NDArray, int]:
        y = np.asarray(y, dtype=float).reshape(2, -1)
        H = n_harmonics(y[0])
        key = ("samples", y.tobytes())
        return self.cache.get(key, lambda: sample(y, int(self.n_samples))), H

    def harmonics(self, y: NDArray, jacobian: bool = False):
        """Force harmonics (2, 2H+1) [N] for coordinate harmonics ``y`` (2, 2H+1) [m].

        Parameters
        ----------
        y : ndarray (2, 2H+1)
            Real harmonics of (u_y, u_z) [m].
        jacobian : bool
            Also return dG/dy, shape (2 (2H+1), 2 (2H+1)) [N/m], coordinate-major.

        Returns
        -------
        ndarray or tuple of ndarray
            The force harmonics, and the Jacobian when asked.
        """
        us, H = self._samples(y)
        G = analyse(self.force_at(us), H)
        if not jacobian:
            return G
        N = int(self.n_samples)
        T = self.tangent_at(us)  # (N, 2, 2)
        spec = np.fft.fft(T, axis=0) / N
        idx = np.mod(np.arange(-2 * H, 2 * H + 1), N)
        nh = 2 * H + 1
        J = np.zeros((2 * nh, 2 * nh))
        for a in range(2):
            for b in range(2):
                J[a * nh : (a + 1) * nh, b * nh : (b + 1) * nh] = toeplitz_jacobian(
                    spec[idx, a, b], 2 * H, H, 1.0
                )
        return G, J

    def tangent_segments(self, y: NDArray) -> tuple[NDArray, NDArray]:
        """The tangent at the AFT samples, piecewise constant on the sample cells.

        Parameters
        ----------
        y : ndarray (2, 2H+1)
            Real harmonics of (u_y, u_z) [m].

        Returns
        -------
        breaks : ndarray (N+1,)
            Cell edges over one period [rad].
        tangent : ndarray (N, 2, 2)
            ∂f/∂u on each cell [N/m].
        """
        us, _ = self._samples(y)
        N = int(self.n_samples)
        T = self.tangent_at(us)
        if not np.any(T):  # no contact all period: one state
            return np.array([0.0, 2 * np.pi]), T[:1]
        breaks = (np.arange(N + 1) - 0.5) * 2 * np.pi / N
        return breaks, T

    def tangent_function(self, y: NDArray) -> tuple[NDArray, object, NDArray]:
        """The tangent as a function of θ for a Magnus product (:mod:`nlgrd.nonlinear.stability.floquet`).

        The contact changes (r = c) are found from the sign changes of r - c on 4 x
        ``n_samples`` points, refined by 60 bisections (to ~1e-18 rad): between them the
        tangent is smooth (for p = 1.5 its derivative is unbounded at the contact change
        itself, which the Magnus step control absorbs).

        Parameters
        ----------
        y : ndarray (2, 2H+1)
            Real harmonics of (u_y, u_z) [m].

        Returns
        -------
        breaks : ndarray (n+1,)
            Angles covering one period [rad], the contact changes among them.
        tangent : callable
            θ (k,) [rad] -> ∂f/∂u (k, 2, 2) [N/m].
        varies : ndarray of bool (n,)
            Whether the tangent varies on each piece (False: constant there, zero out of contact).
        """
        y = np.asarray(y, dtype=float).reshape(2, -1)

        def gap(theta):
            return np.hypot(evaluate(y[0], theta), evaluate(y[1], theta)) - self.clearance

        def tangent(theta):
            theta = np.asarray(theta, dtype=float)
            return self.tangent_at(np.vstack([evaluate(y[0], theta), evaluate(y[1], theta)]))

        n = 4 * int(self.n_samples)
        th = np.arange(n + 1) * (2 * np.pi / n)
        g = gap(th)
        cross = np.flatnonzero(np.sign(g[:-1]) != np.sign(g[1:]))
        if self.clearance == 0 or cross.size == 0:
            linear = self.clearance == 0 and self.exponent == 1.0  # k I throughout
            varies = bool(g[0] > 0 or self.clearance == 0) and not linear
            return np.array([0.0, 2 * np.pi]), tangent, np.array([varies])
        lo, hi = th[cross], th[cross + 1]
        glo = g[cross]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            same = np.sign(gap(mid)) == np.sign(glo)
            lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
        roots = 0.5 * (lo + hi)
        breaks = np.append(roots, roots[0] + 2 * np.pi)
        mids = 0.5 * (breaks[:-1] + breaks[1:])
        return breaks, tangent, gap(mids) > 0

    def force_time(self, y: NDArray, theta: NDArray) -> NDArray:
        """Force samples (2, N) [N] for coordinate samples ``y`` (2, N) [m] (θ unused).

        Parameters
        ----------
        y : ndarray (2, N)
            Samples of (u_y, u_z) [m].
        theta : ndarray (N,)
            Their angles [rad] (the law does not depend on θ).

        Returns
        -------
        ndarray (2, N)
        """
        return self.force_at(np.asarray(y, dtype=float).reshape(2, -1))
