"""Multi-harmonic balance of the receptance-reduced nonlinear problem.

The reduced problem
-------------------
After receptance reduction (Maliha, Doğruer & Özgüven 2004, Eq. 26-37) the periodic
steady state at the mesh frequency ω lives on the n_nl nonlinear coordinates y(θ)
(y_0 = δ, the mesh relative displacement along the line of action; more for other
local nonlinearities), θ = ω t. For each harmonic k = 0..H

    κ_k Y_k + B_k G_k(y) = F_k                                   (1)

with Y_k, G_k, F_k complex n_nl-vectors (convention X_k = a_k - i b_k of
:mod:`nlgrd.describing_functions`), κ_k the n_nl x n_nl dynamic stiffness seen by the
nonlinear coordinates (κ_k = h_k⁻¹, h_k = Wᵀ Z_k⁻¹ W with Z_k the linear dynamic
stiffness at kω *without* the mesh stiffness but *with* the mesh damping), F_k the
equivalent forcing and B_k = I by default. The receptance form B_k = h_k, κ_k = I,
F_k = δ_k^lin is also accepted (:meth:`ReducedProblem.from_receptance`).

On the 2H+1 real harmonics per coordinate, (1) reads R(z) = L z + B G(z) - c = 0 with
L, B real block matrices; the Jacobian L + B dG/dz is exact (analytic dG/dz of
:mod:`nlgrd.describing_functions`). Unknowns are laid out coordinate-major:
z[i (2H+1) + r] is real harmonic r of coordinate i.

Solvers: damped Newton (Armijo backtracking) with scipy's MINPACK ``hybr`` as fallback,
or the paper's quasi-linear receptance iteration (``method="quasi-linear"``).

Stability: Floquet multipliers of the exact monodromy matrix of the piecewise-linear
variational equation (:func:`floquet_multipliers`; exact for the backlash law since f
is continuous, so no saltation terms), or Hill's method (:func:`hill_multipliers`)
for a linear part given as matrices (polynomial in the frequency). Both live in
:mod:`nlgrd.floquet` and are re-exported here.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.optimize as so
from numpy.typing import ArrayLike, NDArray

from nlgrd.describing_functions import (
    BacklashMesh,
    complex_to_real,
    real_to_complex,
)
from nlgrd.errors import ModelError
from nlgrd.floquet import (  # noqa: F401  (re-exported: the stability code lives in nlgrd.floquet)
    FloquetCache,
    _tangent_pieces,
    floquet_multipliers,
    harmonic_solution_stability,
    hill_multipliers,
    tangent_spectrum,
)
from nlgrd.floquet import free_modes as _free_modes
from nlgrd.rigid_body import complement, rigid_body_modes

# --------------------------------------------------------------------------------------
# Real block matrices
# --------------------------------------------------------------------------------------


def _as_matrices(a: ArrayLike, n: int | None = None) -> NDArray[np.complex128]:
    """Promote (H+1,) or (H+1, n, n) to complex (H+1, n, n)."""
    a = np.asarray(a, dtype=complex)
    if a.ndim == 1:
        a = a[:, None, None]
    if a.ndim != 3 or a.shape[1] != a.shape[2] or (n is not None and a.shape[1] != n):
        raise ModelError("kappa", f"expected shape (H+1,) or (H+1, n, n), got {a.shape}")
    return a


def _as_vectors(a: ArrayLike) -> NDArray[np.complex128]:
    """Promote (H+1,) or (H+1, n) to complex (H+1, n)."""
    a = np.asarray(a, dtype=complex)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2:
        raise ModelError("force", f"expected shape (H+1,) or (H+1, n), got {a.shape}")
    return a


def real_block_matrix(A: ArrayLike) -> NDArray[np.float64]:
    """Real (n(2H+1))² matrix of the harmonic-wise complex map Y_k -> A_k Y_k.

    With Y_k = a - i b and A_k = p + i q: Re(A Y) = p a + q b, -Im(A Y) = -q a + p b.
    """
    A = _as_matrices(A)
    H, n = A.shape[0] - 1, A.shape[1]
    nh = 2 * H + 1
    out = np.zeros((n, nh, n, nh))
    out[:, 0, :, 0] = A[0].real
    for k in range(1, H + 1):
        re, im = A[k].real, A[k].imag
        out[:, 2 * k - 1, :, 2 * k - 1] = re
        out[:, 2 * k - 1, :, 2 * k] = im
        out[:, 2 * k, :, 2 * k - 1] = -im
        out[:, 2 * k, :, 2 * k] = re
    return out.reshape(n * nh, n * nh)


# --------------------------------------------------------------------------------------
# Problem definitions
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ReducedProblem:
    """The reduced harmonic-balance problem (1) at one frequency.

    Parameters
    ----------
    omega : float
        Fundamental (mesh) frequency ω [rad/s].
    kappa : array_like
        κ_k, k = 0..H: shape (H+1,) for one coordinate or (H+1, n, n) [N/m]. κ_0 must be real.
    force : array_like
        F_k, k = 0..H: shape (H+1,) or (H+1, n) [N] (F_0 = static load W_0 for the mesh).
    nonlinearities : sequence of LocalNonlinearity
        Force laws acting on the nonlinear coordinates (e.g. :class:`BacklashMesh`).
    nl_gain : array_like, optional
        B_k (H+1, n, n); identity when None.
    """

    omega: float
    kappa: NDArray
    force: NDArray
    nonlinearities: tuple = ()
    nl_gain: NDArray | None = None
    _L: NDArray = field(init=False, repr=False, compare=False)
    _B: NDArray | None = field(init=False, repr=False, compare=False)
    _c: NDArray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        kappa = _as_matrices(self.kappa)
        force = _as_vectors(self.force)
        if force.shape != kappa.shape[:2]:
            raise ModelError("force", f"shape {force.shape} does not match kappa {kappa.shape}")
        if not (np.all(np.isfinite(kappa)) and np.all(np.isfinite(force))):
            raise ModelError("kappa", f"kappa and force must be finite at omega = {self.omega}")
        scale = np.max(np.abs(kappa)) + 1e-300
        if np.max(np.abs(kappa[0].imag)) > 1e-8 * scale:
            raise ModelError("kappa", "κ_0 (the mean) must be real")
        nls = tuple(self.nonlinearities)
        for nl in nls:
            if not all(hasattr(nl, a) for a in ("coords", "harmonics", "offset", "tangent_segments")):
                raise ModelError("nonlinearities", f"{nl!r} does not implement LocalNonlinearity")
            if max(nl.coords) >= kappa.shape[1]:
                raise ModelError("nonlinearities", f"coordinate {max(nl.coords)} out of range")
        object.__setattr__(self, "kappa", kappa)
        object.__setattr__(self, "force", force)
        object.__setattr__(self, "nonlinearities", nls)
        object.__setattr__(self, "_L", real_block_matrix(kappa))
        gain = None if self.nl_gain is None else _as_matrices(self.nl_gain, kappa.shape[1])
        object.__setattr__(self, "nl_gain", gain)
        object.__setattr__(self, "_B", None if gain is None else real_block_matrix(gain))
        object.__setattr__(self, "_c", complex_to_real(force.T).reshape(-1))

    @classmethod
    def from_receptance(
        cls,
        omega: float,
        receptance: ArrayLike,
        linear_response: ArrayLike,
        nonlinearities: Sequence,
        mean_kappa: ArrayLike | None = None,
        mean_force: ArrayLike | None = None,
    ) -> ReducedProblem:
        """Receptance form Y_k + h_k G_k = Y_k^lin, k = 0..H.

        ``receptance`` h_k (H+1,) or (H+1, n, n) [m/N], ``linear_response`` Y_k^lin [m].
        When the k = 0 receptance is infinite (free rigid-body mode moving the mesh),
        give the mean equation in stiffness form instead: ``mean_kappa`` κ_0 (0 for a free
        drive train) and ``mean_force`` F_0 (the static load W_0).
        """
        h = _as_matrices(receptance)
        ylin = _as_vectors(linear_response)
        n = h.shape[1]
        kappa = np.broadcast_to(np.eye(n, dtype=complex), h.shape).copy()
        gain = h.copy()
        force = ylin.copy()
        if mean_kappa is not None:
            kappa[0] = np.asarray(mean_kappa, dtype=complex).reshape(n, n)
            gain[0] = np.eye(n)
            force[0] = np.asarray(mean_force, dtype=complex).reshape(n)
        return cls(omega, kappa, force, tuple(nonlinearities), gain)

    @property
    def H(self) -> int:
        """Number of harmonics."""
        return self.kappa.shape[0] - 1

    @property
    def n_coords(self) -> int:
        """Number of nonlinear coordinates n_nl."""
        return self.kappa.shape[1]

    @property
    def size(self) -> int:
        """Number of real unknowns n_nl (2H + 1)."""
        return self.n_coords * (2 * self.H + 1)

    def nonlinear_forces(self, z: NDArray, jacobian: bool = True) -> tuple[NDArray, NDArray | None]:
        """Real harmonics of the nonlinear forces (flat) and their Jacobian dG/dz."""
        nh = 2 * self.H + 1
        Z = np.asarray(z, dtype=float).reshape(self.n_coords, nh)
        G = np.zeros((self.n_coords, nh))
        J = np.zeros((self.size, self.size)) if jacobian else None
        for nl in self.nonlinearities:
            idx = list(nl.coords)
            out = nl.harmonics(Z[idx], jacobian=jacobian)
            if jacobian:
                g, jg = out
                flat = (np.asarray(idx)[:, None] * nh + np.arange(nh)[None, :]).reshape(-1)
                J[np.ix_(flat, flat)] += jg
            else:
                g = out
            G[idx] += g
        return G.reshape(-1), J

    def residual(self, z: NDArray) -> NDArray:
        """R(z) = L z + B G(z) - c (units of the forcing)."""
        G, _ = self.nonlinear_forces(z, jacobian=False)
        BG = G if self._B is None else self._B @ G
        return self._L @ z + BG - self._c

    def residual_jacobian(self, z: NDArray) -> tuple[NDArray, NDArray, float]:
        """R(z), dR/dz and the force scale max(|L z|, |B G|, |c|) for relative norms."""
        G, JG = self.nonlinear_forces(z)
        if self._B is not None:
            G, JG = self._B @ G, self._B @ JG
        Lz = self._L @ z
        R = Lz + G - self._c
        scale = max(np.max(np.abs(Lz)), np.max(np.abs(G)), np.max(np.abs(self._c)), 1e-300)
        return R, self._L + JG, scale

    def force_scale(self, z: NDArray) -> float:
        """max(|L z|, |B G|, |c|): the residual is reported relative to this."""
        G, _ = self.nonlinear_forces(z, jacobian=False)
        BG = G if self._B is None else self._B @ G
        return max(np.max(np.abs(self._L @ z)), np.max(np.abs(BG)), np.max(np.abs(self._c)), 1e-300)

    def linear_solution(self, stiffness: Sequence[float] | None = None) -> NDArray:
        """Solution with every nonlinearity replaced by its full-contact linear law.

        For :class:`BacklashMesh` this is k_h (δ - e - b) (drive-side contact throughout),
        i.e. the linear frequency response; other nonlinearities use the tangent
        ``stiffness[i]`` (default 0) about zero. Used as the first Newton guess.
        """
        H, n = self.H, self.n_coords
        kt = np.zeros((H + 1, n, n), dtype=complex)
        shift = np.zeros((H + 1, n), dtype=complex)
        for i, nl in enumerate(self.nonlinearities):
            if isinstance(nl, BacklashMesh):
                c = nl.coord
                kt[:, c, c] += nl.stiffness
                shift[:, c] += nl.stiffness * real_to_complex(nl.offset(H)[0])
                shift[0, c] += nl.stiffness * nl.half_backlash
            elif stiffness is not None:
                for c in nl.coords:
                    kt[:, c, c] += stiffness[i]
        B = np.broadcast_to(np.eye(n), kt.shape) if self.nl_gain is None else self.nl_gain
        rhs = self.force + np.einsum("kij,kj->ki", B, shift)
        Y = np.linalg.solve(self.kappa + B @ kt, rhs[..., None])[..., 0]
        return complex_to_real(Y.T).reshape(-1)


@dataclass(frozen=True)
class LinearStateSpace:
    """Linear part M q'' + D q' + K q = -W g(Wᵀq, t) + forcing, for stability analysis.

    Dense matrices (N x N) and the projection W (N x n_nl) onto the nonlinear
    coordinates y = Wᵀ q. K excludes the nonlinear elements' stiffness (the mesh k_h);
    D includes the mesh damping. For the single-DOF gear pair M = [[m_eq]], D = [[c_m]],
    K = [[0]], W = [[1]].

    ``cache``: an optional :class:`nlgrd.floquet.FloquetCache` shared by the state
    spaces of one model (one per mesh frequency): Floquet work is then found again when
    a sweep comes back to a frequency (the down sweep after the up sweep), keyed by the
    matrices' :attr:`digest`. Without it each state space keeps its own
    (:attr:`floquet_cache`).
    """

    M: NDArray
    D: NDArray
    K: NDArray
    W: NDArray
    cache: FloquetCache | None = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        for name in ("M", "D", "K", "W"):
            val = getattr(self, name)
            val = val.toarray() if hasattr(val, "toarray") else np.asarray(val, dtype=float)
            object.__setattr__(self, name, np.atleast_2d(val))
        N = self.M.shape[0]
        if self.D.shape != (N, N) or self.K.shape != (N, N) or self.W.shape[0] != N:
            raise ModelError("state_space", "M, D, K must be N x N and W N x n_nl")

    def rigid_body_modes(self) -> NDArray:
        """M-orthonormal basis (N, r) of the free modes: K φ = 0, D φ = 0 and Wᵀ φ = 0.

        These move no nonlinear element and are neither restrained nor damped (the
        torsional rigid-body rotation of a whole free drive train); they give neutral
        Floquet multipliers μ = 1 in a Jordan block. Decided by the fast
        :func:`nlgrd.floquet.free_modes` when it can (the tolerances of
        :func:`nlgrd.rigid_body.rigid_body_modes`), else by ``rigid_body_modes``. Both
        see a free mode that a projected basis holds as one of its vectors (the stability
        basis of a free drive train, Kubo's rig), whose stiffness diagonal is rounding.
        """
        F = _free_modes(self.K, self.D, self.W)
        if F is None:
            Ksym = (self.K + self.K.T) / 2
            return rigid_body_modes(Ksym, self.M, constraints=(self.K, self.D, self.W.T))
        if F.shape[1] == 0:
            return F
        L = np.linalg.cholesky(F.T @ self.M @ F)
        return np.linalg.solve(L, F.T).T  # M-orthonormal: Rᵀ M R = I

    @cached_property
    def deflated(self) -> LinearStateSpace:
        """The same system in the M-orthogonal complement of :meth:`rigid_body_modes`.

        With q = Φ η + P r, Pᵀ M Φ = 0, the rigid-body coordinates η decouple exactly
        (KΦ = DΦ = 0, WᵀΦ = 0), so the stability of the periodic solution is that of r.
        """
        if self.cache is None:
            phi = self.rigid_body_modes()
        else:
            phi = self.cache.get(("rigid", self.digest), self.rigid_body_modes)
        if phi.shape[1] == 0:
            return self
        P = complement(phi, self.M)
        return LinearStateSpace(
            P.T @ self.M @ P, P.T @ self.D @ P, P.T @ self.K @ P, P.T @ self.W, cache=self.cache
        )

    @cached_property
    def digest(self) -> bytes:
        """Hash of M, D, K, W (the key of this state space's entries in a shared cache)."""
        h = hashlib.blake2b(digest_size=20)
        for a in (self.M, self.D, self.K, self.W):
            a = np.ascontiguousarray(a)
            h.update(str(a.shape).encode())
            h.update(a.tobytes())
        return h.digest()

    @cached_property
    def floquet_cache(self) -> FloquetCache:
        """This state space's own bounded store of Floquet work (factorisations, certificates)."""
        return FloquetCache()


# --------------------------------------------------------------------------------------
# Solution object and solvers
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class HarmonicSolution:
    """Harmonic-balance solution at one frequency.

    Attributes
    ----------
    omega : float
        Mesh frequency [rad/s].
    harmonics : ndarray (n_nl, 2H+1)
        Real harmonics of the nonlinear coordinates [m]; NaN when not converged.
    converged : bool
        Relative residual below the tolerance.
    residual : float
        max|R| / max(|L z|, |B G|, |F|) at the last iterate [-].
    iterations : int
        Newton (or quasi-linear) iterations, fallback iterations included.
    method : str
        Solver that produced the last iterate.
    iterate : ndarray
        The last iterate, kept for diagnostics even when not converged.
    multipliers : ndarray or None
        Floquet multipliers, when stability was computed.
    """

    omega: float
    harmonics: NDArray
    converged: bool
    residual: float
    iterations: int
    method: str
    iterate: NDArray
    message: str = ""
    multipliers: NDArray | None = None

    @property
    def H(self) -> int:
        """Number of harmonics."""
        return (self.harmonics.shape[-1] - 1) // 2

    @property
    def floquet_max(self) -> float:
        """Largest Floquet multiplier modulus (NaN when not computed)."""
        if self.multipliers is None or self.multipliers.size == 0:
            return float("nan")
        return float(np.max(np.abs(self.multipliers)))

    @property
    def stable(self) -> bool | None:
        """True if all Floquet multipliers satisfy |μ| < 1 + 1e-6; None when unknown."""
        if self.multipliers is None or not self.converged:
            return None
        return bool(self.floquet_max < 1 + 1e-6)

    def with_multipliers(self, multipliers: NDArray | None) -> HarmonicSolution:
        """Copy with Floquet multipliers attached."""
        return HarmonicSolution(
            self.omega,
            self.harmonics,
            self.converged,
            self.residual,
            self.iterations,
            self.method,
            self.iterate,
            self.message,
            multipliers,
        )


#: Damped Newton gives up after this many failed line searches in a row, or when ||R||
#: fell by less than 10 % over the last ``STALL_WINDOW`` iterations.
STALL_LIMIT = 8
STALL_WINDOW = 25


def _newton(
    problem: ReducedProblem, z: NDArray, tol: float, max_iter: int, stall: bool = False
) -> tuple[NDArray, float, int, str]:
    """Damped Newton with Armijo backtracking on ||R||²; returns (z, relres, iterations, msg).

    With ``stall``, gives up early when the line search has failed (no sufficient
    decrease even at the smallest step) ``STALL_LIMIT`` times in a row, or when ||R||
    fell by less than 10 % over ``STALL_WINDOW`` iterations: Newton is then stuck near a
    minimum of ||R|| that is not a root, as when started from a branch that has folded
    away. Without it, slow progress at grazing points is given all ``max_iter``.
    """
    R, J, scale = problem.residual_jacobian(z)
    rel = np.max(np.abs(R)) / scale
    nrm = np.linalg.norm(R)
    it = 0
    stalled = 0
    history = [nrm]
    msg = "converged"
    while rel > tol:
        if it >= max_iter:
            msg = f"no convergence in {max_iter} Newton iterations"
            break
        if stall and stalled >= STALL_LIMIT:
            msg = f"Newton stalled ({STALL_LIMIT} failed line searches in a row)"
            break
        it += 1
        try:
            dz = -np.linalg.solve(J, R)
        except np.linalg.LinAlgError:
            dz = -np.linalg.lstsq(J, R, rcond=None)[0]
        if not np.all(np.isfinite(dz)):
            msg = "singular Jacobian"
            break
        step = 1.0
        while True:
            zt = z + step * dz
            Rt, Jt, st = problem.residual_jacobian(zt)
            nt = np.linalg.norm(Rt)
            if nt <= (1 - 1e-4 * step) * nrm or step < 1 / 64:
                break
            step /= 2
        stalled = stalled + 1 if nt > (1 - 1e-4 * step) * nrm else 0
        z, R, J, scale, nrm = zt, Rt, Jt, st, nt
        history.append(nrm)
        if stall and len(history) > STALL_WINDOW and nrm > 0.9 * history[-1 - STALL_WINDOW]:
            msg = f"Newton stalled (||R|| fell by less than 10 % in {STALL_WINDOW} iterations)"
            rel = np.max(np.abs(R)) / scale
            break
        rel = np.max(np.abs(R)) / scale
    return z, rel, it, msg


def _hybr(problem: ReducedProblem, z: NDArray, tol: float, max_iter: int) -> tuple[NDArray, float, int, str]:
    """MINPACK hybrid Powell method with the analytic Jacobian (scaled unknowns)."""
    zs = np.maximum(np.abs(z), 1e-3 * np.max(np.abs(z)) + 1e-300)
    fs = problem.force_scale(z)

    def fun(u):
        R, J, _ = problem.residual_jacobian(u * zs)
        return R / fs, J * zs[None, :] / fs

    sol = so.root(
        fun, z / zs, jac=True, method="hybr", options={"maxfev": 50 * max(max_iter, 4), "xtol": 1e-13}
    )
    zn = sol.x * zs
    R = problem.residual(zn)
    return zn, float(np.max(np.abs(R)) / problem.force_scale(zn)), int(sol.nfev), f"hybr: {sol.message}"


def _quasi_linear(
    problem: ReducedProblem, z: NDArray, tol: float, max_iter: int, relaxation: float
) -> tuple[NDArray, float, int, str]:
    """The paper's quasi-linear receptance iteration (Maliha et al. 2004, Eq. 24-25, 32).

    Each nonlinear force harmonic is written G_k = ν_k (Y_k - O_k) with the describing
    gain ν_k = G_k / (Y_k - O_k) of the current iterate (O: the excitation offset inside
    the force law, e.g. the LSTE), and the now linear harmonic equations
    (κ_k + B_k N_k) Y_k = F_k + B_k N_k O_k are solved; relaxation blends old and new.
    A harmonic whose secant gain would exceed twice the largest tangent gain (a harmonic
    absent or nearly absent from Y - O, generated by the others rather than by itself)
    gets the tangent gain instead and the remaining force G_k - ν_k (Y_k - O_k) on the
    right-hand side; with the pure secant gain such harmonics never appear or stall
    the iteration (observed: residual stuck at 2 % with contact loss).
    The plain iteration (relaxation 1) diverges whenever the secant gain of the mean is
    too far from its tangent (e.g. b > W_0/k_h: the map of the mean has slope
    -b k_h/W_0); the relaxation factor is therefore halved whenever the residual grows
    (a negative ``relaxation`` fixes it at |relaxation|).
    """
    H, n = problem.H, problem.n_coords
    nh = 2 * H + 1
    B = np.broadcast_to(np.eye(n), (H + 1, n, n)) if problem.nl_gain is None else problem.nl_gain
    msg = f"no convergence in {max_iter} quasi-linear iterations"
    adaptive = relaxation > 0
    relaxation = abs(relaxation)
    r = relaxation
    rel = np.max(np.abs(problem.residual(z))) / problem.force_scale(z)
    it = 0
    while it < max_iter:
        it += 1
        Z = z.reshape(n, nh)
        N = np.zeros((H + 1, n, n), dtype=complex)
        O = np.zeros((H + 1, n), dtype=complex)
        Rf = np.zeros((H + 1, n), dtype=complex)
        for nl in problem.nonlinearities:
            if len(nl.coords) != 1:
                raise ModelError("method", "quasi-linear iteration needs single-coordinate nonlinearities")
            c = nl.coords[0]
            g, jg = nl.harmonics(Z[[c]], jacobian=True)
            off = nl.offset(H)[0]
            U = real_to_complex(Z[c] - off)
            Gc = real_to_complex(g[0])
            Jdiag = np.concatenate([[jg[0, 0]], 0.5 * (np.diag(jg)[1::2] + np.diag(jg)[2::2])])
            big = np.abs(U) * (np.max(np.abs(Jdiag)) + 1e-300) > 0.5 * np.abs(Gc)
            nu = np.where(big, Gc / np.where(big, U, 1), Jdiag)
            N[:, c, c] += nu
            O[:, c] = real_to_complex(off)
            Rf[:, c] += Gc - nu * U  # zero where the secant gain is used
        BN = B @ N
        rhs = problem.force + np.einsum("kij,kj->ki", BN, O) - np.einsum("kij,kj->ki", B, Rf)
        try:
            Y = np.linalg.solve(problem.kappa + BN, rhs[..., None])[..., 0]
        except np.linalg.LinAlgError:  # e.g. full separation: zero gain and κ_0 = 0
            Y = np.array(
                [np.linalg.lstsq(a, r, rcond=None)[0] for a, r in zip(problem.kappa + BN, rhs, strict=True)]
            )
        znew = complex_to_real(Y.T).reshape(-1)
        # adaptive under-relaxation: halve when the residual grows, regrow slowly otherwise
        while True:
            zc = (1 - r) * z + r * znew
            rel_c = np.max(np.abs(problem.residual(zc))) / problem.force_scale(zc)
            if rel_c < rel or r <= 1 / 256 or not adaptive:
                break
            r /= 2
        z, rel = zc, rel_c
        r = min(relaxation, 1.25 * r)
        if rel <= tol:
            msg = "converged"
            break
    rel = np.max(np.abs(problem.residual(z))) / problem.force_scale(z)
    return z, float(rel), it, msg


def solve(
    problem: ReducedProblem,
    z0: ArrayLike | None = None,
    *,
    method: str = "newton",
    tol: float = 1e-10,
    max_iter: int = 50,
    fallback: bool = True,
    relaxation: float = 1.0,
    stall: bool = False,
) -> HarmonicSolution:
    """Solve the reduced harmonic-balance problem at one frequency.

    Parameters
    ----------
    problem : ReducedProblem
    z0 : array_like, optional
        Start (n_nl, 2H+1) or flat; default :meth:`ReducedProblem.linear_solution`.
        Harmonics beyond the problem's H are dropped, missing ones set to zero.
    method : {"newton", "quasi-linear", "hybr"}
        Damped Newton with analytic Jacobian; the paper's quasi-linear receptance
        iteration; or MINPACK hybr directly.
    tol : float
        Convergence: max|R| <= tol · max(|L z|, |B G|, |F|).
    max_iter : int
        Iteration limit of the chosen method.
    fallback : bool
        If Newton (or the quasi-linear iteration) fails, retry with hybr from the start.
    relaxation : float
        Largest under-relaxation of the quasi-linear iteration (1 = the paper's plain
        iteration), reduced adaptively when the residual grows; negative: fixed at |value|.
    stall : bool
        Let Newton give up early when it stalls (see ``_newton``): for sweeps that have a
        better move than grinding on, such as following the curve through a fold.

    Returns
    -------
    HarmonicSolution
        ``converged`` False (and harmonics NaN) when the tolerance was not met.
    """
    n, nh = problem.n_coords, 2 * problem.H + 1
    if z0 is None:
        z = problem.linear_solution()
    else:
        z0 = np.atleast_2d(np.asarray(z0, dtype=float))
        if z0.size == problem.size and z0.shape != (n, nh):
            z0 = z0.reshape(n, nh)
        z = np.zeros((n, nh))
        m = min(nh, z0.shape[1])
        z[:, :m] = z0[:, :m]
        z = z.reshape(-1)
    if not np.all(np.isfinite(z)):
        z = problem.linear_solution()
    if method == "newton":
        zr, rel, it, msg = _newton(problem, z, tol, max_iter, stall)
    elif method == "quasi-linear":
        zr, rel, it, msg = _quasi_linear(problem, z, tol, max_iter, relaxation)
    elif method == "hybr":
        zr, rel, it, msg = _hybr(problem, z, tol, max_iter)
    else:
        raise ModelError("method", f"'newton', 'quasi-linear' or 'hybr', got {method!r}")
    used = method
    if (not rel <= tol) and fallback and method != "hybr":
        zh, relh, ith, msgh = _hybr(problem, z, tol, max_iter)
        it += ith
        if relh < rel or not np.isfinite(rel):
            zr, rel, msg, used = zh, relh, msgh, "hybr"
        if rel <= tol:
            zr, rel2, it2, _ = _newton(problem, zr, tol, 5)  # polish to Newton accuracy
            rel, it = min(rel, rel2), it + it2
    converged = bool(rel <= tol and np.all(np.isfinite(zr)))
    harm = zr.reshape(n, nh) if converged else np.full((n, nh), np.nan)
    return HarmonicSolution(problem.omega, harm, converged, float(rel), int(it), used, zr.reshape(n, nh), msg)


# --------------------------------------------------------------------------------------
# Frequency-dependent model
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ReducedModel:
    """The reduced problem as a function of the mesh frequency ω (for sweeps, continuation).

    Parameters
    ----------
    kappa : callable (omega [rad/s], H) -> (H+1,) or (H+1, n, n) complex [N/m]
    force : callable (omega, H) -> (H+1,) or (H+1, n) complex [N]
    nonlinearities : sequence of LocalNonlinearity
    nl_gain : callable (omega, H) -> (H+1, n, n), optional
        B_k; identity when None.
    state_space : LinearStateSpace, optional
        Time-domain linear part, needed for Floquet stability.
    state_space_at : callable (omega) -> LinearStateSpace, optional
        Frequency-dependent linear part (speed-dependent gyroscopic terms and bearings of
        an FE model); overrides ``state_space`` when given.
    kappa_derivative, force_derivative, nl_gain_derivative : callable, optional
        d/dω of the above; central finite differences when None.
    """

    kappa: Callable[[float, int], ArrayLike]
    force: Callable[[float, int], ArrayLike]
    nonlinearities: tuple = ()
    nl_gain: Callable[[float, int], ArrayLike] | None = None
    state_space: LinearStateSpace | None = None
    state_space_at: Callable[[float], LinearStateSpace] | None = None
    kappa_derivative: Callable[[float, int], ArrayLike] | None = None
    force_derivative: Callable[[float, int], ArrayLike] | None = None
    nl_gain_derivative: Callable[[float, int], ArrayLike] | None = None

    def __post_init__(self):
        object.__setattr__(self, "nonlinearities", tuple(self.nonlinearities))

    def at(self, omega: float, H: int) -> ReducedProblem:
        """The reduced problem at frequency ``omega`` with ``H`` harmonics."""
        gain = None if self.nl_gain is None else self.nl_gain(omega, H)
        return ReducedProblem(omega, self.kappa(omega, H), self.force(omega, H), self.nonlinearities, gain)

    def linear_state_space(self, omega: float) -> LinearStateSpace | None:
        """The linear part for stability at mesh frequency ``omega`` (None if unknown)."""
        if self.state_space_at is not None:
            return self.state_space_at(float(omega))
        return self.state_space

    @property
    def mesh(self) -> BacklashMesh | None:
        """The first :class:`BacklashMesh` among the nonlinearities."""
        return next((nl for nl in self.nonlinearities if isinstance(nl, BacklashMesh)), None)

    def omega_derivative(self, omega: float, H: int, z: NDArray) -> NDArray:
        """dR/dω at fixed harmonics z: (dL/dω) z + (dB/dω) G - dc/dω."""
        have = self.kappa_derivative is not None and self.force_derivative is not None
        if have and (self.nl_gain is None or self.nl_gain_derivative is not None):
            dk = _as_matrices(self.kappa_derivative(omega, H))
            df = _as_vectors(self.force_derivative(omega, H))
            out = real_block_matrix(dk) @ z - complex_to_real(df.T).reshape(-1)
            if self.nl_gain is not None:
                G, _ = self.at(omega, H).nonlinear_forces(z, jacobian=False)
                out = out + real_block_matrix(_as_matrices(self.nl_gain_derivative(omega, H))) @ G
            return out
        h = 1e-6 * max(abs(omega), 1.0)
        return (self.at(omega + h, H).residual(z) - self.at(omega - h, H).residual(z)) / (2 * h)

    @classmethod
    def from_matrices(
        cls,
        M: ArrayLike,
        D: ArrayLike,
        K: ArrayLike,
        W: ArrayLike,
        static_force: ArrayLike,
        nonlinearities: Sequence,
        regularization: ArrayLike | None = None,
    ) -> ReducedModel:
        """Dense reference reduction of a small linear model (tests; FE models build their own).

        M q'' + D q' + K q = F0 - W g(y, θ) + Σ_mesh w c_m e'(t), y = Wᵀ q. D must include
        each mesh's damping c_m w wᵀ; K excludes k_h. Then per harmonic k >= 1
        h_k = Wᵀ Z_k⁻¹ W, κ_k = h_k⁻¹, F_k = κ_k Wᵀ Z_k⁻¹ (i kω c_m w E_k). For the mean, with
        K_r = K + W diag(k_r) Wᵀ (k_r = ``regularization``, default the mesh stiffness),
        κ_0 = (Wᵀ K_r⁺ W)⁻¹ - diag(k_r), F_0 = (Wᵀ K_r⁺ W)⁻¹ Wᵀ K_r⁺ F0 (K_r⁺: least squares,
        valid when F0 is self-equilibrated); κ_0 = 0 when a free rigid-body mode moves the mesh.
        """
        M, D, K = (np.asarray(a.toarray() if hasattr(a, "toarray") else a, dtype=float) for a in (M, D, K))
        W = np.asarray(W, dtype=float)
        W = W[:, None] if W.ndim == 1 else W
        F0 = np.asarray(static_force, dtype=float).reshape(-1)
        nls = tuple(nonlinearities)
        n = W.shape[1]
        if regularization is None:
            kr = np.zeros(n)
            for nl in nls:
                if isinstance(nl, BacklashMesh):
                    kr[nl.coord] = nl.stiffness
            kr[kr == 0] = np.max(np.abs(np.diag(K))) if np.any(K) else 1.0
        else:
            kr = np.broadcast_to(np.asarray(regularization, dtype=float), (n,))
        Kr = K + W @ np.diag(kr) @ W.T
        sol = np.linalg.lstsq(Kr, np.column_stack([W, F0]), rcond=None)[0]
        Hr = W.T @ sol[:, :n]
        Hr_inv = np.linalg.inv(Hr)
        kappa0 = Hr_inv - np.diag(kr)
        f0 = Hr_inv @ (W.T @ sol[:, n])

        def _lste_forcing(omega: float, H: int) -> NDArray:
            F = np.zeros((H + 1, M.shape[0]), dtype=complex)
            for nl in nls:
                if isinstance(nl, BacklashMesh) and nl.damping > 0:
                    E = real_to_complex(nl.offset(H)[0])
                    k = np.arange(H + 1)
                    F += np.outer(1j * k * omega * nl.damping * E, W[:, nl.coord])
            return F

        cache: dict = {}

        def _reduce(omega: float, H: int):
            key = (float(omega), int(H))
            if key not in cache:
                kap = np.empty((H + 1, n, n), dtype=complex)
                frc = np.empty((H + 1, n), dtype=complex)
                kap[0], frc[0] = kappa0, f0
                Fk = _lste_forcing(omega, H)
                for k in range(1, H + 1):
                    w = k * omega
                    Z = K - w * w * M + 1j * w * D
                    s = np.linalg.solve(Z, np.column_stack([W, Fk[k]]))
                    hk = W.T @ s[:, :n]
                    kap[k] = np.linalg.inv(hk)
                    frc[k] = kap[k] @ (W.T @ s[:, n])
                if len(cache) > 4:
                    cache.clear()
                cache[key] = (kap, frc)
            return cache[key]

        return cls(
            kappa=lambda omega, H: _reduce(omega, H)[0],
            force=lambda omega, H: _reduce(omega, H)[1],
            nonlinearities=nls,
            state_space=LinearStateSpace(M, D, K, W),
        )
