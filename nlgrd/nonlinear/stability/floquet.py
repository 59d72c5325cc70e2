"""Floquet stability of harmonic-balance solutions: the exact monodromy (Hill's method:
:mod:`nlgrd.nonlinear.stability.hill`).

The variational equation M η'' + D η' + (K + W K_t(θ) Wᵀ) η = 0 (θ = ω t) has a
piecewise constant tangent K_t for the backlash law (k_h in contact, 0 in separation):
its monodromy matrix is the ordered product of matrix exponentials over the contact
intervals, exact because the backlash force is continuous (no saltation).

:func:`floquet_multipliers` has three methods:

- ``"expm"``: the reference (the method before issue 10): scipy's ``expm`` of the
  unscaled state matrix per interval and every eigenvalue of the product, or exp(λ T)
  for the eigenvalues λ of the state matrix when one contact state holds all period.
- ``"dense"``: every multiplier of the same product built with less work: coordinates
  the model decouples from the mesh exactly (axial modes of a spur-gear drive) split off
  (:func:`~nlgrd.nonlinear.reduction.linear_algebra.mesh_block`), the state scaled to
  (w_s η, η') so that a Padé exponential (:func:`~nlgrd.nonlinear.reduction.linear_algebra.expm`)
  needs few squarings, M⁻¹ by one Cholesky solve per state space, the last interval
  merged with the first (cyclic shifts of a product have its eigenvalues), the intervals
  of one contact state from its state matrix's powers formed once
  (:func:`~nlgrd.nonlinear.reduction.linear_algebra.expm_times`).
- ``"auto"`` (default): ``"dense"`` up to a state dimension of ``DENSE_STATE_LIMIT`` (of
  the state space, or of its mesh block in step 2), above it the *dominant* multipliers
  only, those that decide stability:

  1. One contact state all period, M symmetric positive definite, K_t symmetric
     positive semi-definite, D + Dᵀ positive semi-definite (gyroscopic terms allowed):
     every eigenvalue has Re λ <= 0 (eigenvector x, m = xᴴMx, d = xᴴDx, k = xᴴK_t x:
     λ m + d + k/λ = 0, so Re λ (m + k/|λ|²) = -Re d <= 0). A null vector φ of K_t gives
     [φ; 0] with λ = 0 exactly, so max |μ| = 1: ``ones(r)`` is returned, r = dim ker K_t
     less the free rigid-body modes (deflated), with no eigenvalue computed. This is the
     torsional rotation of a drive train damped by its motor (``two_shaft.toml``) in full
     contact. Otherwise (no null vector, circulatory stiffness, ...) step 2.
  2. The monodromy Φ of ``"dense"``, then squarings (Φ^8192, Φ^32768, ... Φ^524288,
     rescaled) isolate its dominant invariant subspace Q (numerical range, pivoted QR).
     The Ritz values on Q within a factor 1 - ``BAND`` of the largest are returned once
     their Schur vectors X satisfy ‖Φ X - X T‖_F <= ``RITZ_RTOL`` ‖Φ‖_F: they are then
     exact eigenvalues of a matrix that close to Φ. Else, or when the largest lies
     within ``NEAR_CRITICAL`` above 1, every eigenvalue of Φ.

Caches live on objects, never in module globals: each state space has a bounded
:class:`~nlgrd.nonlinear.reduction.state_space.FloquetCache` of its own (M⁻¹ products, the reference's
eigenvalues), and state
spaces built with ``cache=`` share one, keyed by content: the certificate's null space
(the same at every speed) and the multipliers per frequency, reused when a sweep comes
back to it with the same contact states and intervals (:func:`_revisit`).
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.reduction.linear_algebra import (
    _moved,
    expm,
    expm_times,
    mesh_block,
    psd_null_space,
    psd_to_tolerance,
)
from nlgrd.nonlinear.stability.magnus_steps import interaction_piece, set_distance
from nlgrd.nonlinear.stability.tangent import smooth_pieces, state_sequence, tangent_pieces, time_invariant
from nlgrd.rotor.rigid_body import CONSTRAINT_RTOL

if TYPE_CHECKING:  # pragma: no cover
    from nlgrd.nonlinear.reduction.state_space import LinearStateSpace

#: A truncated basis is kept where max |μ| moves by at most this to twice its cut-off.
TRUNCATION_ATOL = 1e-7
#: Up to this state dimension 2N, ``method="auto"`` returns every multiplier (dense).
DENSE_STATE_LIMIT = 48
#: Squarings of the monodromy matrix after which its dominant subspace is tried (Φ^8192 ...).
SQUARING_CHECKS = (13, 15, 17, 19)
#: The dominant multipliers returned: within a factor 1 - BAND of the largest modulus.
BAND = 6e-4
#: Numerical rank of the powers of Φ, relative to the largest pivot of their QR.
RANK_RTOL = 1e-13
#: Accepted invariance residual ‖Φ Q - Q B‖_F / ‖Φ‖_F of the dominant subspace.
RITZ_RTOL = 1e-10
#: Dominant multipliers within this above 1 are checked by every eigenvalue of Φ: a Jordan
#: block at μ = 1 (an undeflated free mode) moves by the square root of the backward error.
NEAR_CRITICAL = 1e-3
#: A revisited frequency reuses its multipliers when the monodromy moved less than this (relative).
REVISIT_RTOL = 1e-8

METHODS = ("auto", "dense", "expm")
#: Smooth tangents (laws with ``tangent_function``): Magnus steps per period of the first
#: product; doubled until the largest multiplier modulus is converged to ``MAGNUS_ATOL``.
MAGNUS_FIRST_STEPS = 8
#: The largest Magnus step count per period tried; its result is returned with its estimate.
MAGNUS_MAX_STEPS = 4096
#: Accepted error estimate of max |μ| [-] (a tenth of the stability band STABLE_RTOL = 1e-6
#: of nlgrd.nonlinear.results.sweep_results: a verdict can only change within 1e-7 of that band).
MAGNUS_ATOL = 1e-7
#: A Magnus step is halved until its commutator term √3 h²/12 ‖S₂ - S₁‖₁ (S = M⁻¹(K + W K_t
#: Wᵀ)) is at most this: the second term of the series must stay a correction of the first,
#: or the step's exponential is meaningless (it overflowed on a stiff contact at 8 steps).
MAGNUS_COMMUTATOR = 1.0
#: The estimate also compares, as sets, the multipliers within this fraction of the largest
#: modulus (their position, not only max |μ|: a complex pair that is still turning).
MAGNUS_LEADING = 0.1


def _magnus_monodromy(
    prep: _Prepared,
    breaks,
    K0,
    active,
    omega: float,
    steps: int,
    least: NDArray | None = None,
    memo: dict | None = None,
) -> tuple[NDArray, NDArray]:
    """Φ by the fourth-order Magnus method with two Gauss points per step (Iserles & Nørsett
    1999, Phil. Trans. R. Soc. A 357:983; Blanes, Casas, Oteo & Ros 2009, Phys. Rep.
    470:151, §5), in the interaction picture of each piece's mean state matrix A₀
    (the modified Magnus method of Iserles 2002, BIT 42:561):
    about ``steps`` steps per period spread over the pieces by length (at least one each,
    at least ``least[i]`` on piece i, and halved until the commutator term is below
    ``MAGNUS_COMMUTATOR``); one exact exponential on a piece where no tangent varies.
    ``memo`` keeps, from one step count to the next, the scaling w_s, those exponentials
    and each piece's A₀ (the state matrix of its mean tangent K̄) with the exponentials of the
    next step count.
    Returns Φ and the steps per piece (:func:`~nlgrd.nonlinear.stability.magnus_steps.interaction_piece`)."""
    N = prep.N
    g = np.sqrt(3.0) / 6.0
    lengths = np.diff(breaks)
    plan = []
    for i, L in enumerate(lengths):
        if not active[i]:
            plan.append((i, None))
            continue
        m = max(1, int(np.ceil(steps * L / (2 * np.pi))), 0 if least is None else int(least[i]))
        while True:
            h = L / m
            a = breaks[i] + h * np.arange(m)
            th = np.concatenate([a + h * (0.5 - g), a + h * (0.5 + g)])
            Kt = np.broadcast_to(K0[i], (th.size, *K0[i].shape)).copy()
            for idx, fn in active[i]:
                Kt[np.ix_(np.arange(th.size), idx, idx)] += fn(th)
            dK = np.abs(Kt[m:] - Kt[:m]).sum(axis=1).max(axis=1)  # ‖ΔK_t‖₁ per step
            bound = np.sqrt(3.0) / 12.0 * (h / omega) ** 2 * prep.coupling * float(dK.max())
            if bound <= MAGNUS_COMMUTATOR or m >= MAGNUS_MAX_STEPS:
                break
            m *= 2
        plan.append((i, (m, h, Kt)))
    counts = np.array([1 if p is None else p[0] for _, p in plan])
    memo = {} if memo is None else memo
    if "ws" not in memo:
        stiff_mid = [prep.stiffness(K0[i]) if p is None else prep.stiffness(p[2][0]) for i, p in plan]
        memo["ws"] = np.sqrt(max(max(float(np.linalg.norm(k, 1)) for k in stiff_mid), 1e-300))
    ws = memo["ws"]
    base = np.zeros((2 * N, 2 * N))
    base[:N, N:] = ws * np.eye(N)
    base[N:, N:] = -prep.MD
    Es = []
    for i, p in plan:
        if p is None:
            if ("exact", i) not in memo:
                C = base.copy()
                C[N:, :N] = -prep.stiffness(K0[i]) / ws
                memo["exact", i] = expm(C * (lengths[i] / omega))
            Es.append(memo["exact", i])
        else:
            piece = memo.setdefault(i, {})
            if "A0" not in piece:  # the mean tangent of the first step count, kept for the next
                piece["Kbar"] = p[2].mean(axis=0)
                piece["A0"] = base.copy()
                piece["A0"][N:, :N] = -prep.stiffness(piece["Kbar"]) / ws
            U0, V0t = np.zeros((2 * N, prep.Wt.shape[0])), np.zeros((prep.Wt.shape[0], 2 * N))
            U0[N:], V0t[:, :N] = prep.MW, prep.Wt / ws
            Es.append(interaction_piece(piece["A0"], U0, V0t, piece["Kbar"], p[2], p[1] / omega, piece))
    return _product(Es), counts


class _Prepared:
    """M⁻¹K, M⁻¹D, M⁻¹W of the mesh block of one state space (Cholesky solves, once),
    and the eigenvalues of the decoupled rest
    (:func:`nlgrd.nonlinear.reduction.linear_algebra.mesh_block`)."""

    def __init__(self, ss: LinearStateSpace):
        b = mesh_block(ss.M, ss.D, ss.K, ss.W)
        M, D, K, W = ss.M[np.ix_(b, b)], ss.D[np.ix_(b, b)], ss.K[np.ix_(b, b)], ss.W[b]
        N = M.shape[0]

        def solver():  # M⁻¹ with M⁻¹K, M⁻¹W: the same at every speed of a sweep (shared cache)
            try:
                cf = sla.cho_factor(M, check_finite=False)
                solve = lambda B: sla.cho_solve(cf, B, check_finite=False)  # noqa: E731
                X = solve(np.column_stack([K, W]))
            except (np.linalg.LinAlgError, sla.LinAlgError):
                solve = lambda B: np.linalg.solve(M, B)  # noqa: E731
                X = solve(np.column_stack([K, W]))
            return solve, X[:, :N], X[:, N:]

        if ss.cache is None:
            solve, self.MK, self.MW = solver()
        else:
            h = hashlib.blake2b(b.tobytes(), digest_size=20)
            for A in (M, K, W):
                h.update(np.ascontiguousarray(A).tobytes())
            solve, self.MK, self.MW = ss.cache.get(("m-solve", h.digest()), solver)
        self.N, self.Wt = N, W.T
        self.MD = solve(D)
        self.side = np.zeros(0, dtype=complex)
        if not b.all():
            r = ~b
            n = int(r.sum())
            A = np.zeros((2 * n, 2 * n))
            A[:n, n:] = np.eye(n)
            Mr, Kr, Dr = (Y[np.ix_(r, r)] for Y in (ss.M, ss.K, ss.D))
            A[n:] = -np.linalg.solve(Mr, np.column_stack([Kr, Dr]))
            self.side = np.linalg.eigvals(A)

    @property
    def coupling(self) -> float:
        """‖M⁻¹W‖₁ ‖Wᵀ‖₁: bounds ‖M⁻¹ W ΔK Wᵀ‖₁ by it times ‖ΔK‖₁."""
        return float(np.linalg.norm(self.MW, 1) * np.linalg.norm(self.Wt, 1))

    def stiffness(self, kt: NDArray) -> NDArray:
        """M⁻¹ (K + W K_t Wᵀ) on the mesh block."""
        return self.MK + self.MW @ kt @ self.Wt


def _prepared(ss: LinearStateSpace) -> _Prepared:
    return ss.floquet_cache.get("prepared", lambda: _Prepared(ss))


def _spd(M: NDArray) -> bool:
    """M symmetric positive definite."""
    if np.max(np.abs(M - M.T)) > 1e-12 * np.max(np.abs(M)):
        return False
    return sla.lapack.dpotrf(M, lower=0, clean=0)[1] == 0


def _neutral_count(ss: LinearStateSpace, kt: NDArray, deflate: bool) -> int | None:
    """r > 0 exact neutral multipliers when the energy certificate of the module docstring
    (step 1) holds for the tangent ``kt``, else None. With ``deflate`` the null vectors
    that are free rigid-body modes (K φ = D φ = Wᵀ φ = 0 to CONSTRAINT_RTOL, the test of
    ``rigid_body_modes``) are not counted. The null space of K_t and the check of M do not
    depend on the speed: a shared cache keeps them across a sweep."""
    Kt = ss.K + ss.W @ kt @ ss.W.T
    store = ss.cache if ss.cache is not None else ss.floquet_cache

    def null_space():
        ok, Z = psd_null_space(Kt)
        return Z if ok and _spd(ss.M) else None

    Z = store.get(("psd-null", Kt.tobytes(), ss.M.tobytes()), null_space)
    if Z is None or Z.shape[1] == 0 or not psd_to_tolerance(ss.D):
        return None
    r = Z.shape[1]
    if deflate:
        r -= int(np.sum(_moved(Z, ss.K, ss.D, ss.W) <= CONSTRAINT_RTOL))
    return r if r > 0 else None


def _dominant(Phi: NDArray) -> NDArray[np.complex128]:
    """The dominant eigenvalues of Φ (module docstring, step 2), or all of them."""
    n = Phi.shape[0]
    nrm = np.linalg.norm(Phi)
    R = Phi / np.max(np.abs(Phi))
    done = 0
    for target in SQUARING_CHECKS:
        for _ in range(target - done):
            R = R @ R
            m = max(float(R.max()), -float(R.min()))  # max |R| without a temporary
            if not (m > 0 and np.isfinite(m)):
                return np.linalg.eigvals(Phi)
            R *= 2.0 ** -np.frexp(m)[1]  # a power of 2: the scaling adds no rounding
        done = target
        Q, Rq, _ = sla.qr(R, pivoting=True, mode="economic", check_finite=False)
        dd = np.abs(np.diag(Rq))
        k = int(np.sum(dd > RANK_RTOL * dd[0]))
        if not 0 < k <= n // 3:
            continue
        Qk = Q[:, :k]
        B = Qk.T @ (Phi @ Qk)
        top = float(np.max(np.abs(np.linalg.eigvals(B))))
        cut = (1 - BAND) * top
        T, Z, sdim = sla.schur(B, output="complex", sort=lambda x, cut=cut: abs(x) >= cut)
        X = Qk @ Z[:, :sdim]
        if np.linalg.norm(Phi @ X - X @ T[:sdim, :sdim]) <= RITZ_RTOL * nrm:
            return np.diag(T)[:sdim].copy()
    return np.linalg.eigvals(Phi)


def _state_matrix(ss: LinearStateSpace) -> tuple[NDArray, NDArray]:
    """M⁻¹ and the state matrix of (q, q') with the stiffness block still empty."""
    N = ss.M.shape[0]
    Minv = np.linalg.inv(ss.M)
    A = np.zeros((2 * N, 2 * N))
    A[:N, N:] = np.eye(N)
    A[N:, N:] = -Minv @ ss.D
    return Minv, A


def expm_monodromy(ss: LinearStateSpace, breaks: NDArray, Kt: NDArray, omega: float) -> NDArray:
    """Π exp(A_i Δt_i) over the pieces from ``breaks[0]`` (the first acts first) in the
    unscaled state (q, q'), by scipy's ``expm``: the reference product (``method="expm"``).

    Parameters
    ----------
    ss : LinearStateSpace
        The linear part M, D, K, W (N DOFs), used as given (no deflation, no mesh block).
    breaks : ndarray (n+1,)
        Angles θ [rad] bounding the n pieces of one period.
    Kt : ndarray (n, n_nl, n_nl)
        Tangent stiffness of the nonlinear coordinates on each piece [N/m].
    omega : float
        Mesh frequency [rad/s]: piece i lasts (breaks[i+1] - breaks[i]) / omega [s].

    Returns
    -------
    ndarray (2N, 2N)
        The monodromy matrix Φ: (q, q') at θ = ``breaks[0]`` to (q, q') at ``breaks[-1]``.
    """
    Minv, A = _state_matrix(ss)
    N = ss.M.shape[0]
    Phi = np.eye(2 * N)
    cache: dict = {}
    for i in range(Kt.shape[0]):
        dt = (breaks[i + 1] - breaks[i]) / omega
        key = Kt[i].tobytes()
        if key not in cache:
            Ai = A.copy()
            Ai[N:, :N] = -Minv @ (ss.K + ss.W @ Kt[i] @ ss.W.T)
            cache[key] = Ai
        Phi = sla.expm(cache[key] * dt) @ Phi
    return Phi


def _expm_reference(ss: LinearStateSpace, breaks: NDArray, Kt: NDArray, omega: float) -> NDArray:
    """The library's method before issue 10 (``method="expm"``), kept for comparison."""
    if all(np.array_equal(Kt[i], Kt[0]) for i in range(1, Kt.shape[0])):
        Minv, A = _state_matrix(ss)
        N = ss.M.shape[0]
        A[N:, :N] = -Minv @ (ss.K + ss.W @ Kt[0] @ ss.W.T)
        key = ("expm-eig", hashlib.blake2b(A.tobytes(), digest_size=20).digest())
        lam = ss.floquet_cache.get(key, lambda: np.linalg.eigvals(A))
        return np.exp(lam * (breaks[-1] - breaks[0]) / omega)
    return np.linalg.eigvals(expm_monodromy(ss, breaks, Kt, omega))


@dataclass(frozen=True)
class FloquetResult:
    """Multipliers with the work that gave them (:func:`floquet_analysis`).

    Attributes
    ----------
    multipliers : ndarray of complex
        As :func:`floquet_multipliers` returns them [-].
    exponentials : int
        Matrix exponentials in the accepted monodromy product [-]: one per contact
        interval between the union of all laws' crossings for piecewise-linear laws, the
        Magnus steps for smooth ones (each a rank-2 n_nl update; a piece with steps takes
        two full exponentials per new step count: :mod:`nlgrd.nonlinear.stability.magnus_steps`), 0 when the
        multipliers came without a product (one state all period, a certificate, a
        revisited frequency).
    error : float
        Estimated error of max |μ| [-]: 0 for the exact piecewise product, the step-doubling
        estimate |m₂ₙ - mₙ| of the Magnus product (or the larger distance between the
        sets of multipliers within ``MAGNUS_LEADING`` of the largest modulus): an upper
        bound of the error of m₂ₙ when the error falls at least as h (order 4 where the
        tangent is smooth, less next to a Hertzian contact change, where its derivative is
        unbounded; so not Richardson's /15).
    converged : bool
        ``error`` <= ``MAGNUS_ATOL`` (always True for the exact product).
    steps : ndarray of int or None
        The accepted Magnus product's steps per piece (None without one).
    """

    multipliers: NDArray[np.complex128]
    exponentials: int = 0
    error: float = 0.0
    converged: bool = True
    steps: NDArray | None = None

    def to_frame(self):
        """One row per multiplier, largest modulus first: its real and imaginary parts and
        modulus [-].

        Returns
        -------
        pandas.DataFrame
        """
        import pandas as pd

        mu = np.asarray(self.multipliers, dtype=complex).reshape(-1)
        mu = mu[np.argsort(-np.abs(mu), kind="stable")]
        return pd.DataFrame(
            {"multiplier_re [-]": mu.real, "multiplier_im [-]": mu.imag, "multiplier_abs [-]": np.abs(mu)}
        )

    def plot(self, ax=None):
        """The multipliers on the unit circle (:func:`nlgrd.plotting.result_figures.plot_multipliers`).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure when None.

        Returns
        -------
        matplotlib.axes.Axes
        """
        from nlgrd.plotting.result_figures import plot_multipliers

        return plot_multipliers(self.multipliers, ax=ax)


def floquet_multipliers(
    state_space: LinearStateSpace,
    nonlinearities: Sequence,
    harmonics: ArrayLike,
    omega: float,
    deflate: bool = True,
    method: str = "auto",
) -> NDArray[np.complex128]:
    """Floquet multipliers of a periodic solution from the exact monodromy matrix.

    The variational equation M η'' + D η' + (K + W K_t(θ) Wᵀ) η = 0 has a piecewise
    constant tangent K_t (k_h in contact, 0 in separation for the backlash law), so the
    monodromy matrix is the ordered product of matrix exponentials exp(A_i Δt_i) over
    the contact intervals. The backlash force is continuous, so the saltation matrices
    at the switching instants are the identity and this product is exact. Free
    rigid-body modes (neutral multipliers μ = 1 in a Jordan block, which rounding splits
    into 1 ± sqrt(eps)) are removed first when ``deflate`` (:meth:`LinearStateSpace.deflated`).

    ``method``: ``"auto"`` (default) returns every multiplier for state dimensions up to
    ``DENSE_STATE_LIMIT`` and above it the dominant ones only (those within a factor
    1 - ``BAND`` of the largest modulus, or the exact neutral ones of a certified stable
    time-invariant state; see the module docstring): what max |μ| and the stability
    verdict need. ``"dense"``: every multiplier. ``"expm"``: every multiplier by the
    reference method (unscaled state matrix, scipy ``expm``), for comparisons. State
    spaces built with a shared ``cache`` reuse the multipliers of a frequency met before
    with the same contact states and intervals (:func:`_revisit`).

    Parameters
    ----------
    state_space : LinearStateSpace
        The linear part M, D, K and the projection W (N x n_nl) onto the nonlinear coordinates.
    nonlinearities : sequence of LocalNonlinearity
        The force laws; their ``tangent_segments`` give K_t(θ).
    harmonics : array_like (n_nl, 2H+1)
        Real harmonics [y_0, a_1, b_1, ..., a_H, b_H] of the nonlinear coordinates of the
        periodic solution (δ [m] for a mesh); 1-D for one coordinate.
    omega : float
        Mesh frequency ω [rad/s]; the period is 2π/ω.
    deflate : bool
        Remove the free rigid-body modes first.
    method : {"auto", "dense", "expm"}
        See above and the module docstring.

    Returns
    -------
    ndarray of complex
        Floquet multipliers μ [-]: every one (2N, less 2 per deflated mode), or with
        ``"auto"`` above ``DENSE_STATE_LIMIT`` the dominant ones only.

    Raises
    ------
    ModelError
        When ``method`` is not one of ``METHODS``.
    """
    return floquet_analysis(state_space, nonlinearities, harmonics, omega, deflate, method).multipliers


def floquet_analysis(
    state_space: LinearStateSpace,
    nonlinearities: Sequence,
    harmonics: ArrayLike,
    omega: float,
    deflate: bool = True,
    method: str = "auto",
) -> FloquetResult:
    """:func:`floquet_multipliers` with the number of exponentials and the error estimate.

    Laws with a smooth tangent (``tangent_function``: a Hertzian or radial clearance, a
    parametric mesh k(θ)) take the fourth-order Magnus product (:func:`_magnus_monodromy`)
    on the pieces between the union of all laws' contact changes, ``MAGNUS_FIRST_STEPS``
    (at least H + 1, rounded up to a power of 2) steps per period doubled until the
    step-doubling estimate of max |μ| is within ``MAGNUS_ATOL`` (at most
    ``MAGNUS_MAX_STEPS``; ``converged`` says if it got there).
    Piecewise-constant tangents keep the exact product, one exponential per interval.

    A truncated basis with ``larger`` and ``full``: where the tangent varies, the multipliers
    on ``larger`` when max |μ| moved by at most :data:`TRUNCATION_ATOL` (the basis at the same
    Magnus steps), else on ``full`` (docs/conventions.md, "Stability state space"; a constant
    tangent keeps the basis); a basis only where its dropped modes' exceed its max |μ| by no more.
    A ``larger`` with no more vectors than the basis (no mode between the two cut-offs: Kubo's
    rig sized for 12 kHz) checks nothing, and ``full`` decides.
    Its result is kept in the basis's shared ``cache`` per (state space, ω, orbit), and
    returned again for the same orbit (the H' lift after the verdicts' check).

    Parameters
    ----------
    state_space, nonlinearities, harmonics, deflate, method
        As :func:`floquet_multipliers`.
    omega : float
        Base frequency ω of the orbit [rad/s].

    Returns
    -------
    FloquetResult
        The multipliers, the exponentials of the accepted product and its error estimate.

    Raises
    ------
    ModelError
        When ``method`` is not one of ``METHODS``.
    """
    if method not in METHODS:
        raise ModelError("method", f"one of {', '.join(map(repr, METHODS))}, got {method!r}")
    Y = np.atleast_2d(np.asarray(harmonics, dtype=float))
    full = state_space.full
    if full is None or method == "expm":
        return _analysis(state_space, nonlinearities, Y, omega, deflate, method)
    # a truncated basis: the model's store keeps each orbit's result (lift repeats converge_verdicts)
    laws, memo = tuple(nonlinearities), state_space.cache
    key = ("analysis", state_space.digest, float(omega), Y.shape, Y.tobytes(), bool(deflate), method)
    hit = None if memo is None else memo.peek(key)
    if hit is None or len(hit[0]) != len(laws) or any(a is not b for a, b in zip(hit[0], laws, strict=True)):
        hit = (laws, _checked(state_space, laws, Y, omega, deflate, method))
        if memo is not None:
            memo.put(key, hit)
    return replace(hit[1], multipliers=hit[1].multipliers.copy())


def _checked(state_space, nonlinearities, Y: NDArray, omega: float, deflate: bool, method: str):
    """:func:`floquet_analysis` on a truncated basis: the basis, twice its cut-off or the full state."""
    full, n = state_space.full, state_space.W.shape[1]
    if time_invariant(nonlinearities, Y, n):
        res = _analysis(state_space, nonlinearities, Y, omega, deflate, method)
        if state_space.keeps(float(np.max(np.abs(res.multipliers))), TRUNCATION_ATOL):
            return res
    elif state_space.larger is not None:  # the truncation checked by twice the cut-off
        larger = state_space.larger()
        if larger.M.shape[0] <= state_space.M.shape[0]:  # no vector added: no check
            return _analysis(full(), nonlinearities, Y, omega, deflate, method)
        big = _analysis(larger, nonlinearities, Y, omega, deflate, method)
        res = _analysis(state_space, nonlinearities, Y, omega, deflate, method, big.steps)  # same steps
        top = [float(np.max(np.abs(r.multipliers))) for r in (res, big)]
        if abs(top[1] - top[0]) <= TRUNCATION_ATOL and larger.keeps(top[1], TRUNCATION_ATOL):
            return big
    return _analysis(full(), nonlinearities, Y, omega, deflate, method)


def _analysis(state_space, nonlinearities, Y: NDArray, omega: float, deflate: bool, method: str, at=None):
    """:func:`floquet_analysis` on ``state_space`` as it is (not its ``full`` one); a
    Magnus product at ``at`` steps per piece alone when given (no refinement)."""
    if method != "expm":
        pieces = smooth_pieces(nonlinearities, Y, state_space.W.shape[1])
        if pieces is not None:
            dominant = method == "auto" and 2 * state_space.M.shape[0] > DENSE_STATE_LIMIT
            ss = state_space.deflated if deflate else state_space
            return _magnus(ss, pieces, omega, dominant, (Y.shape[1] - 1) // 2, at)
    if method == "expm":
        ss = state_space.deflated if deflate else state_space
        breaks, Kt = tangent_pieces(nonlinearities, Y, ss.W.shape[1])
        return FloquetResult(_expm_reference(ss, breaks, Kt, omega), Kt.shape[0])
    breaks, Kt = tangent_pieces(nonlinearities, Y, state_space.W.shape[1])
    period = (breaks[-1] - breaks[0]) / omega
    states, seq = state_sequence(breaks, Kt)
    dominant = method == "auto" and 2 * state_space.M.shape[0] > DENSE_STATE_LIMIT
    if dominant and len(states) == 1:
        r = _neutral_count(state_space, states[0], deflate)
        if r is not None:
            return FloquetResult(np.ones(r, dtype=complex))
    shared = state_space.cache if dominant and len(states) > 1 else None
    if shared is not None:
        key = ("monodromy", state_space.digest, bool(deflate), tuple(kt.tobytes() for kt in states))
        key = (*key, tuple(i for i, _ in seq))
        mu = _revisit(shared.peek(key), np.array([dth for _, dth in seq]) / omega)
        if mu is not None:
            return FloquetResult(mu)
    ss = state_space.deflated if deflate else state_space
    prep = _prepared(ss)
    N = prep.N
    dense = not (dominant and 2 * N > DENSE_STATE_LIMIT)  # a small mesh block: every multiplier
    if len(states) == 1 and dense:
        A = np.zeros((2 * N, 2 * N))
        A[:N, N:] = np.eye(N)
        A[N:, :N] = -prep.stiffness(states[0])
        A[N:, N:] = -prep.MD
        lam = ss.floquet_cache.get(("eig", states[0].tobytes()), lambda: np.linalg.eigvals(A))
        return FloquetResult(np.exp(np.concatenate([lam, prep.side]) * period), 1)
    times = np.array([dth for _, dth in seq]) / omega
    Es, Cs = _exponentials(prep, states, seq, times)
    Phi = _product(Es)
    side = np.exp(prep.side * period)
    mu = _eigen(Phi, side, dense)
    if shared is not None:
        shared.put(key, (times, _sensitivity(Es, Cs, Phi), mu))
    return FloquetResult(mu, len(Es))


def _eigen(Phi: NDArray, side: NDArray, dense: bool) -> NDArray[np.complex128]:
    """Every eigenvalue of Φ with the decoupled rest's multipliers ``side``, or the dominant ones."""
    if dense:
        return np.concatenate([np.linalg.eigvals(Phi), side])
    mu = _dominant(Phi)
    top = float(np.max(np.abs(mu)))
    if 1 + 1e-7 < top < 1 + NEAR_CRITICAL:  # a defective μ = 1 would be split by ~sqrt(1e-10)
        mu = np.linalg.eigvals(Phi)
    return np.concatenate([mu, side[np.abs(side) >= (1 - BAND) * np.max(np.abs(mu))]])


def _magnus(ss: LinearStateSpace, pieces, omega: float, dominant: bool, H: int, at=None) -> FloquetResult:
    """The Magnus product refined by step doubling (:func:`floquet_analysis`), from at
    least H + 1 steps per period (rounded up to a power of 2): 2H + 2 Gauss points, more
    than the 2H + 1 samples that resolve the orbit's H harmonics. With ``at`` (steps per
    piece), that product alone, its error not estimated (NaN)."""
    breaks, K0, active = pieces
    prep = _prepared(ss)
    dense = not (dominant and 2 * prep.N > DENSE_STATE_LIMIT)
    side = np.exp(prep.side * (breaks[-1] - breaks[0]) / omega)
    if at is not None:
        Phi, counts = _magnus_monodromy(prep, breaks, K0, active, omega, 1, at)
        mu = _eigen(Phi, side, dense) if np.all(np.isfinite(Phi)) else np.array([np.inf + 0j])
        return FloquetResult(mu, int(counts.sum()), float("nan"), False, counts)
    steps, prev = max(MAGNUS_FIRST_STEPS, 1 << int(np.ceil(np.log2(H + 1)))), None
    least, memo = None, {}
    while True:  # every piece's step count doubles from one product to the next
        Phi, counts = _magnus_monodromy(prep, breaks, K0, active, omega, steps, least, memo)
        mu = _eigen(Phi, side, dense) if np.all(np.isfinite(Phi)) else np.array([np.inf + 0j])
        top = float(np.max(np.abs(mu)))
        lead = mu[np.abs(mu) >= (1 - MAGNUS_LEADING) * top]
        if prev is not None:
            err = max(abs(top - prev[0]), set_distance(lead, prev[1]))
            if not err > MAGNUS_ATOL or 2 * steps > MAGNUS_MAX_STEPS:
                return FloquetResult(mu, int(counts.sum()), err, bool(err <= MAGNUS_ATOL), counts)
        active_counts = counts[[bool(a) for a in active]]
        prev, steps, least = (top, lead), 2 * steps, 2 * counts
        if active_counts.size and active_counts.min() > MAGNUS_MAX_STEPS:
            return FloquetResult(mu, int(counts.sum()), float("inf"), False, counts)


def _exponentials(prep: _Prepared, states, seq, times: NDArray) -> tuple[list[NDArray], list[NDArray]]:
    """exp(C_i t_i) per interval and C_i, in the scaled state (w_s η, η') of the mesh block:
    exp(C t) = S exp(A t) S⁻¹, ‖C‖ ~ w_s where ‖A‖ ~ w_s²."""
    N = prep.N
    stiff = [prep.stiffness(kt) for kt in states]
    ws = np.sqrt(max(max(float(np.linalg.norm(k, 1)) for k in stiff), 1e-300))
    base = np.zeros((2 * N, 2 * N))
    base[:N, N:] = ws * np.eye(N)
    base[N:, N:] = -prep.MD
    Cs = []
    for k in stiff:
        C = base.copy()
        C[N:, :N] = -k / ws
        Cs.append(C)
    Es: list = [None] * len(seq)
    for j, C in enumerate(Cs):  # a state's intervals share its powers (expm_times)
        at = [k for k, (i, _) in enumerate(seq) if i == j]
        for k, E in zip(at, expm_times(C, times[at]), strict=True):
            Es[k] = E
    return Es, [Cs[i] for i, _ in seq]


def monodromy(
    state_space: LinearStateSpace, nonlinearities: Sequence, harmonics: ArrayLike, omega: float
) -> NDArray[np.float64]:
    """The monodromy of :func:`floquet_multipliers`: deflated, mesh block, scaled state, the
    period from a contact change (similar to the one from θ = 0).

    Parameters
    ----------
    state_space : LinearStateSpace
        The linear part M, D, K and the projection W (N x n_nl) onto the nonlinear coordinates.
    nonlinearities : sequence of LocalNonlinearity
        The force laws; their ``tangent_segments`` give K_t(θ).
    harmonics : array_like (n_nl, 2H+1)
        Real harmonics [y_0, a_1, b_1, ..., a_H, b_H] of the nonlinear coordinates of the
        periodic solution (δ [m] for a mesh); 1-D for one coordinate.
    omega : float
        Mesh frequency ω [rad/s]; the period is 2π/ω.

    Returns
    -------
    ndarray (2n_b, 2n_b)
        Φ in the scaled state (w_s η, η') of the n_b coordinates of the deflated mesh block.
    """
    ss = state_space.deflated
    Y = np.atleast_2d(np.asarray(harmonics, dtype=float))
    states, seq = state_sequence(*tangent_pieces(nonlinearities, Y, ss.W.shape[1]))
    times = np.array([dth for _, dth in seq]) / omega
    return _product(_exponentials(_prepared(ss), states, seq, times)[0])


def _sensitivity(Es: list[NDArray], Cs: list[NDArray], Phi: NDArray) -> NDArray:
    """g with ‖dΦ‖₁ <= ‖Φ‖₁ Σ g_i |δ_i| to first order in interval changes δ_i: dΦ =
    Σ (E_m..E_i+1) C_i (E_i..E_1) δ_i (C_i, E_i commute), g_1 = ‖C_1‖, g_m = ‖C_m‖."""
    m = len(Es)
    nrm = np.linalg.norm(Phi, 1)
    g = np.array([np.linalg.norm(C, 1) for C in Cs])
    right, left = [Es[0]], [Es[-1]]  # E_i..E_1 and E_m..E_i+1, one product each
    for i in range(1, m - 1):
        right.append(Es[i] @ right[-1])
        left.append(left[-1] @ Es[m - 1 - i])
    for i in range(1, m - 1):
        g[i] *= np.linalg.norm(left[m - 2 - i], 1) * np.linalg.norm(right[i], 1) / nrm
    return g


def _revisit(entry, times: NDArray) -> NDArray | None:
    """The stored multipliers if the intervals moved so little that ‖Φ' - Φ‖₁ <= ‖Φ‖₁ x e^x
    <= REVISIT_RTOL ‖Φ‖₁ (x = Σ g_i |δ_i|, :func:`_sensitivity`), else None. They are
    then exact eigenvalues of a matrix within ~RITZ_RTOL + REVISIT_RTOL of Φ'. A sweep
    back at a frequency finds the crossings again to ~1e-10 rad (x ~ 1e-9): the same
    monodromy to the accuracy of the harmonic-balance solution it comes from."""
    if entry is None:
        return None
    t0, g, mu = entry
    if t0.shape != times.shape:
        return None
    x = float(np.sum(g * np.abs(times - t0)))
    return mu if x <= REVISIT_RTOL and x * np.exp(x) <= REVISIT_RTOL else None


def _product(Es: list[NDArray]) -> NDArray:
    """E_m ... E_2 E_1 (the first interval acts first)."""
    Phi = Es[0]
    for E in Es[1:]:
        Phi = E @ Phi
    return Phi
