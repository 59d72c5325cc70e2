"""Multi-harmonic balance of the receptance-reduced nonlinear problem.

The reduced problem
-------------------
After receptance reduction (Maliha, Doğruer & Özgüven 2004, Eq. 26-37) the periodic
steady state at the mesh frequency ω lives on the n_nl nonlinear coordinates y(θ)
(y_0 = δ, the mesh relative displacement along the line of action; more for other
local nonlinearities), θ = ω t. For each harmonic k = 0..H

    κ_k Y_k + B_k G_k(y) = F_k                                   (1)

with Y_k, G_k, F_k complex n_nl-vectors (convention X_k = a_k - i b_k of
:mod:`nlgrd.nonlinear.fourier.harmonics`), κ_k the n_nl x n_nl dynamic stiffness seen by the
nonlinear coordinates (κ_k = h_k⁻¹, h_k = Wᵀ Z_k⁻¹ W with Z_k the linear dynamic
stiffness at kω *without* the mesh stiffness but *with* the mesh damping), F_k the
equivalent forcing and B_k = I by default. The receptance form B_k = h_k, κ_k = I,
F_k = δ_k^lin is also accepted (:meth:`ReducedProblem.from_receptance`).

On the 2H+1 real harmonics per coordinate, (1) reads R(z) = L z + B G(z) - c = 0 with
L, B real block matrices; the Jacobian L + B dG/dz is exact (analytic dG/dz of the
force laws, :mod:`nlgrd.nonlinear.laws.force_laws`). Unknowns are laid out coordinate-major:
z[i (2H+1) + r] is real harmonic r of coordinate i.

Solvers: :mod:`nlgrd.nonlinear.hb.solvers` (damped Newton, MINPACK ``hybr``, the paper's
quasi-linear iteration). Stability: :mod:`nlgrd.nonlinear.stability.floquet` (Floquet multipliers
of the exact monodromy matrix, Hill's method) on the linear part of
:mod:`nlgrd.nonlinear.reduction.state_space`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import complex_to_real, real_to_complex
from nlgrd.nonlinear.reduction.state_space import LinearStateSpace
from nlgrd.nonlinear.results.metrics import PointMetrics

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

    Parameters
    ----------
    A : array_like of complex
        A_k, k = 0..H: shape (H+1,) for one coordinate or (H+1, n, n), in any unit (κ_k
        [N/m], h_k [m/N]); only the real part of A_0 is used.

    Returns
    -------
    ndarray (n(2H+1), n(2H+1))
        The real matrix on coordinate-major real harmonics z[i (2H+1) + r], in the unit of
        ``A``.

    Raises
    ------
    ModelError
        When ``A`` is not (H+1,) or (H+1, n, n).
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
        """A linear first guess for Newton.

        A law with a full-contact linear form (``full_contact(H)``, e.g.
        :class:`BacklashMesh`: k_h (δ - e - b), drive-side contact throughout) enters with
        it: with only such laws this is the linear frequency response. When another law
        is present (a clearance), the static problem (k = 0) is first solved with every
        law nonlinear (damped Newton), and the dynamic part is the linear response about
        that static state, each such law at its tangent there. ``stiffness[i]`` is the
        start of law i in the static solve (default its ``guess_stiffness()``, or 0), and a
        law's ``static_start`` moves that start into its contact.

        Parameters
        ----------
        stiffness : sequence of float, optional
            Tangent stiffness of each law without a full-contact form, for the start of the
            static solve [N/m].

        Returns
        -------
        ndarray (n_nl (2H+1),)
            Real harmonics, flat [m].
        """
        H, n = self.H, self.n_coords
        kt = np.zeros((H + 1, n, n), dtype=complex)
        shift = np.zeros((H + 1, n), dtype=complex)
        others = []
        for i, nl in enumerate(self.nonlinearities):
            full = getattr(nl, "full_contact", None)
            if full is not None:
                k, sh = full(H)
                for j, c in enumerate(nl.coords):
                    kt[:, c, c] += k
                    shift[:, c] += sh[j]
            else:
                others.append(nl)
                k = stiffness[i] if stiffness is not None else getattr(nl, "guess_stiffness", lambda: 0.0)()
                for c in nl.coords:
                    kt[:, c, c] += k
        B = np.broadcast_to(np.eye(n), kt.shape) if self.nl_gain is None else self.nl_gain
        rhs = self.force + np.einsum("kij,kj->ki", B, shift)
        Y = np.linalg.solve(self.kappa + B @ kt, rhs[..., None])[..., 0]
        if others:
            y0 = Y[0].real.copy()
            for nl in others:
                if hasattr(nl, "static_start"):
                    y0[list(nl.coords)] = nl.static_start(y0[list(nl.coords)])
            Y0, T = self._static_state(y0)
            if Y0 is not None:
                Y[0] = Y0
                for nl in others:
                    idx = np.asarray(nl.coords)
                    off = real_to_complex(np.asarray(nl.offset(H), dtype=float).reshape(len(idx), -1)).T
                    kt[:, idx[:, None], idx[None, :]] = T[np.ix_(idx, idx)]
                    shift[:, idx] = off @ T[np.ix_(idx, idx)].T
                rhs = self.force + np.einsum("kij,kj->ki", B, shift)
                Y[1:] = np.linalg.solve(self.kappa[1:] + B[1:] @ kt[1:], rhs[1:, :, None])[..., 0]
        return complex_to_real(Y.T).reshape(-1)

    def _static_state(self, y0: NDArray, max_iter: int = 100) -> tuple[NDArray | None, NDArray | None]:
        """Damped Newton on the mean problem (k = 0) with every law nonlinear, from ``y0``;
        returns the static state and the laws' tangent there, or (None, None)."""
        gain = None if self.nl_gain is None else self.nl_gain[:1].real
        p0 = ReducedProblem(self.omega, self.kappa[:1].real, self.force[:1].real, self.nonlinearities, gain)
        y = np.asarray(y0, dtype=float).copy()
        R, J, scale = p0.residual_jacobian(y)
        for _ in range(max_iter):
            if np.max(np.abs(R)) <= 1e-12 * scale:
                T = p0.nonlinear_forces(y)[1]
                return y, T
            step = np.linalg.lstsq(J, -R, rcond=None)[0]
            t, norm = 1.0, np.linalg.norm(R)
            while t > 1e-6:
                R_new, J_new, scale_new = p0.residual_jacobian(y + t * step)
                if np.linalg.norm(R_new) < norm:
                    break
                t /= 2
            else:
                return None, None
            y, R, J, scale = y + t * step, R_new, J_new, scale_new
        return None, None


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
    message : str
        The solver's message ("converged", or why it stopped).
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


@dataclass(frozen=True)
class ReducedModel:
    """The reduced problem as a function of the mesh frequency ω (for sweeps, continuation).

    Parameters
    ----------
    kappa : callable (omega [rad/s], H) -> (H+1,) or (H+1, n, n) complex [N/m]
        κ_k, k = 0..H, at mesh frequency omega (see :class:`ReducedProblem`).
    force : callable (omega, H) -> (H+1,) or (H+1, n) complex [N]
        F_k, k = 0..H.
    nonlinearities : sequence of LocalNonlinearity
        Force laws acting on the nonlinear coordinates (e.g. :class:`BacklashMesh`).
    nl_gain : callable (omega, H) -> (H+1, n, n), optional
        B_k; identity when None.
    state_space : LinearStateSpace, optional
        Time-domain linear part, needed for Floquet stability.
    state_space_at : callable (omega) -> LinearStateSpace, optional
        Frequency-dependent linear part (speed-dependent gyroscopic terms and bearings of
        an FE model); overrides ``state_space`` when given.
    kappa_derivative, force_derivative, nl_gain_derivative : callable, optional
        d/dω of the above; central finite differences when None.
    outputs : callable (harmonics, omega) -> ndarray
        The per-point outputs whose change with H estimates the truncation error
        (:mod:`nlgrd.nonlinear.tracing.harmonic_convergence`), e.g. every link's RMS DTE and
        largest force.
    branch_signature : callable (harmonics, omega) -> ndarray
        Per point, what tells one branch from another: the fractions of the period each
        contact spends in each state [-] (a point lifted to more harmonics whose signature
        moves by more than 0.05 is on another branch).
    metrics : PointMetrics
        What a sweep writes per point in ``SweepResult.metrics``
        (:class:`~nlgrd.nonlinear.results.metrics.PointMetrics`; NaN by default).
    output_scales : ndarray, optional
        Each output's physical scale in its unit (a clearance's displacement: the
        clearance), 0 where it has none: the H estimate measures a change against at least
        :data:`~nlgrd.nonlinear.tracing.harmonic_convergence.FLOOR` times it, so that a journal
        resting on its bearing, nanometres from the centre of a 1 mm clearance, does not
        decide H. None: zeros.
    static_force : ndarray (N,), optional
        F₀ of the state space's equations [N]: with it and piecewise-linear laws the exact
        flow is known (:mod:`nlgrd.nonlinear.stability.shooting`); None where the model does not give it.
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
    outputs: Callable[[NDArray, float], NDArray] = field(kw_only=True)
    branch_signature: Callable[[NDArray, float], NDArray] = field(kw_only=True)
    metrics: PointMetrics = field(default_factory=PointMetrics, kw_only=True)
    output_scales: NDArray | None = field(default=None, kw_only=True)
    static_force: NDArray | None = field(default=None, kw_only=True, repr=False, compare=False)

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
        metrics: PointMetrics | None = None,
    ) -> ReducedModel:
        """Dense reference reduction of a small linear model (tests; FE models build their own).

        A law's full-contact stiffness (``full_contact``: the default regularisation) and
        ``damping`` (the mesh damping through which the LSTE excites) are used where it has them.
        ``metrics`` (default: those of the first law, a gear mesh or a stop) also gives
        the model's outputs and branch signature.

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
        metrics = PointMetrics(nls[0]) if metrics is None and nls else (metrics or PointMetrics())
        n = W.shape[1]
        if regularization is None:
            kr = np.zeros(n)
            for nl in nls:  # a law with a full-contact linear form: at its stiffness
                if hasattr(nl, "full_contact"):
                    kr[list(nl.coords)] = nl.full_contact(0)[0]
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
                if getattr(nl, "damping", 0.0) > 0:
                    E = real_to_complex(nl.offset(H)[0])
                    k = np.arange(H + 1)
                    F += np.outer(1j * k * omega * nl.damping * E, W[:, nl.coords[0]])
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
            outputs=metrics.outputs,
            branch_signature=metrics.signature,
            metrics=metrics,
            static_force=F0,
        )
