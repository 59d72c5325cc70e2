"""Floquet stability of harmonic-balance solutions: exact monodromy and Hill's method.

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
  (:func:`mesh_block`), the state scaled to (w_s η, η') so that a Padé exponential
  (:func:`expm`) needs few squarings, M⁻¹ by one Cholesky solve per state space, the last
  interval merged with the first (cyclic shifts of a product have its eigenvalues).
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
:class:`FloquetCache` of its own (M⁻¹ products, the reference's eigenvalues), and state
spaces built with ``cache=`` share one, keyed by content: the certificate's null space
(the same at every speed) and the multipliers per frequency, reused when a sweep comes
back to it with the same contact states and intervals (:func:`_revisit`).
"""

from __future__ import annotations

import hashlib
import math
from collections import OrderedDict
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.rigid_body import CONSTRAINT_RTOL, RIGID_BODY_RTOL

if TYPE_CHECKING:  # pragma: no cover
    from nlgrd.harmonic_balance import HarmonicSolution, LinearStateSpace, ReducedModel

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
#: Couplings above this (relative to each matrix's largest entry) join coordinates into one block.
BLOCK_RTOL = 1e-10
#: A block splits off only when every coupling to it is below this: rounding, not physics.
GAP_RTOL = 1e-11
#: Dominant multipliers within this above 1 are checked by every eigenvalue of Φ: a Jordan
#: block at μ = 1 (an undeflated free mode) moves by the square root of the backward error.
NEAR_CRITICAL = 1e-3
#: A revisited frequency reuses its multipliers when the monodromy moved less than this (relative).
REVISIT_RTOL = 1e-8
#: Symmetry and semi-definiteness tolerance of the energy certificate (Jacobi-scaled).
CERTIFICATE_RTOL = RIGID_BODY_RTOL

METHODS = ("auto", "dense", "expm")


class FloquetCache:
    """A bounded store (first in, first out) of Floquet work: one per state space, or one
    shared by the state spaces of a model (``LinearStateSpace(..., cache=...)``).

    Keys are tuples of hashables; :meth:`get` computes a missing entry with ``make``.
    """

    def __init__(self, maxsize: int = 16):
        self.maxsize = int(maxsize)
        self._data: OrderedDict = OrderedDict()

    def get(self, key, make: Callable[[], Any]):
        """The entry for ``key``, computed by ``make()`` when missing."""
        if key in self._data:
            return self._data[key]
        value = make()
        self.put(key, value)
        return value

    def peek(self, key):
        """The entry for ``key``, or None."""
        return self._data.get(key)

    def put(self, key, value) -> None:
        """Store ``value`` under ``key`` (the oldest entry goes when full)."""
        if key not in self._data and len(self._data) >= self.maxsize:
            self._data.popitem(last=False)
        self._data[key] = value

    def __len__(self) -> int:
        return len(self._data)


def _tangent_pieces(nonlinearities: Sequence, harmonics: NDArray, n: int) -> tuple[NDArray, NDArray]:
    """Common breaks over [0, 2π] and the n x n tangent stiffness on each piece."""
    segs = []
    for nl in nonlinearities:
        idx = list(nl.coords)
        br, kt = nl.tangent_segments(harmonics[idx])
        segs.append((idx, br, kt))
    if all(kt.shape[0] == 1 for _, _, kt in segs):  # one state all period: no breaks inside
        Kt = np.zeros((1, n, n))
        for idx, _, kt in segs:
            Kt[np.ix_([0], idx, idx)] += kt[:1]
        return np.array([0.0, 2 * np.pi]), Kt
    allb = [np.mod(br[:-1], 2 * np.pi) for _, br, _ in segs]
    breaks = np.unique(np.concatenate([[0.0, 2 * np.pi], *allb])) if allb else np.array([0.0, 2 * np.pi])
    breaks = breaks[np.append(True, np.diff(breaks) > 1e-14)]
    mids = 0.5 * (breaks[:-1] + breaks[1:])
    Kt = np.zeros((mids.size, n, n))
    for idx, br, kt in segs:
        rel = np.mod(mids - br[0], 2 * np.pi) + br[0]
        seg = np.clip(np.searchsorted(br, rel, side="right") - 1, 0, kt.shape[0] - 1)
        Kt[np.ix_(np.arange(mids.size), idx, idx)] += kt[seg]
    return breaks, Kt


def _state_sequence(breaks: NDArray, Kt: NDArray) -> tuple[list[NDArray], list[tuple[int, float]]]:
    """Distinct tangents and the cyclic sequence (state, angle) with equal neighbours merged.

    The last piece is merged into the first when both have the same tangent: the
    monodromy matrices of cyclic shifts of the period are similar.
    """
    states: list[NDArray] = []
    keys: dict[bytes, int] = {}
    seq: list[tuple[int, float]] = []
    for i in range(Kt.shape[0]):
        key = Kt[i].tobytes()
        if key not in keys:
            keys[key] = len(states)
            states.append(Kt[i])
        s, dth = keys[key], float(breaks[i + 1] - breaks[i])
        if seq and seq[-1][0] == s:
            seq[-1] = (s, seq[-1][1] + dth)
        else:
            seq.append((s, dth))
    if len(seq) > 1 and seq[0][0] == seq[-1][0]:
        seq[0] = (seq[0][0], seq[0][1] + seq[-1][1])
        seq.pop()
    return states, seq


# --- Linear algebra helpers ------------------------------------------------------------

# Padé [13/13] coefficients (2m - j)! m! / ((2m)! j! (m - j)!), m = 13, times 26!/13!
# (the scale cancels in (V - U)⁻¹ (V + U)), and the bound θ_13 (Higham 2005)
_PADE13 = tuple(
    float(math.factorial(26 - j) // (math.factorial(j) * math.factorial(13 - j))) for j in range(14)
)
_THETA13 = 5.371920351148152


def expm(X: NDArray) -> NDArray[np.float64]:
    """exp(X) by Padé [13/13] with scaling and squaring (Higham 2005), scaled by
    α₄ = max(‖X⁴‖^¼, ‖X⁵‖^⅕) <= 2^s θ₁₃ (Al-Mohy & Higham 2009, Thm 4.2; 27 >= 4 x 3),
    ‖X⁵‖₁ <= ‖X⁴‖₁ ‖X‖₁: fewer squarings than ‖X‖₁ for these non-normal matrices."""
    n = X.shape[0]
    X2 = X @ X
    X4 = X2 @ X2
    n1, n4 = float(np.linalg.norm(X, 1)), float(np.linalg.norm(X4, 1))
    alpha = max(n4**0.25, (n4 * n1) ** 0.2)
    s = max(0, int(np.ceil(np.log2(alpha / _THETA13)))) if alpha > _THETA13 else 0
    f = 2.0**-s
    A, A2, A4 = X * f, X2 * f**2, X4 * f**4
    A6 = A4 @ A2
    b = _PADE13
    ident = np.eye(n)
    U = A @ (A6 @ (b[13] * A6 + b[11] * A4 + b[9] * A2) + b[7] * A6 + b[5] * A4 + b[3] * A2 + b[1] * ident)
    V = A6 @ (b[12] * A6 + b[10] * A4 + b[8] * A2) + b[6] * A6 + b[4] * A4 + b[2] * A2 + b[0] * ident
    R = np.linalg.solve(V - U, V + U)
    for _ in range(s):
        R = R @ R
    return R


def _jacobi_scaled(A: NDArray, rtol: float) -> tuple[NDArray, NDArray] | None:
    """(S A S, 1/S), S = diag(A)^-½; None if A is asymmetric or has a diagonal below 0
    beyond ``rtol`` max|diag|. Rows whose diagonal is within that of 0 (free coordinates)
    are scaled by 1 and zeroed, so their rounding is not amplified, if they vanish too."""
    diag = A.diagonal().copy()
    scale = float(np.max(np.abs(diag)))
    if np.max(np.abs(A - A.T)) > rtol * scale or np.min(diag) < -rtol * scale:
        return None
    zero = diag <= rtol * scale
    d = np.sqrt(np.where(zero, 1.0, diag))
    As = (A + A.T) / 2 / np.outer(d, d)
    if np.any(zero):
        if np.max(np.abs(A[zero])) > rtol * scale:
            return None
        As[zero] = 0.0
        As[:, zero] = 0.0
    return As, d


def _pstrf_null(As: NDArray, tol: float) -> tuple[int, NDArray, float]:
    """Pivoted Cholesky Pᵀ Ã P = U₁ᵀ U₁ + [0 0; 0 S₂₂] of a symmetric Ã stopped at pivots
    <= ``tol``: rank r, the null basis P [-U₁₁⁻¹ U₁₂; I] (columns) and max |S₂₂|."""
    n = As.shape[0]
    c, piv, r, _ = sla.lapack.dpstrf(As, tol=tol)
    r, p = int(r), piv - 1
    U2 = c[:r, r:]
    S22 = As[p[r:]][:, p[r:]] - U2.T @ U2
    X = np.zeros((n, n - r))
    if r:
        X[p[:r]] = -sla.lapack.dtrtrs(c[:r, :r], U2, lower=0)[0]
    X[p[r:]] = np.eye(n - r)
    return r, X, float(np.max(np.abs(S22))) if S22.size else 0.0


def _moved(Z: NDArray, K: NDArray, D: NDArray, W: NDArray) -> NDArray:
    """Singular values of [K Z/‖K‖; D Z/‖D‖; Wᵀ Z/‖W‖] (Z unit columns), padded to Z's
    column count: how much each direction of span(Z) moves K, D or the nonlinear
    coordinates (zero for a free rigid-body mode; the test of ``rigid_body_modes``)."""
    blocks = [(A @ Z) / s for A in (K, D, W.T) if (s := float(np.linalg.norm(A))) > 0]
    sv = np.linalg.svd(np.vstack(blocks), compute_uv=False) if blocks else np.zeros(0)
    return np.concatenate([sv, np.zeros(max(0, Z.shape[1] - sv.size))])


def psd_null_space(A: NDArray, rtol: float = CERTIFICATE_RTOL) -> tuple[bool, NDArray | None]:
    """Is the symmetric matrix ``A`` positive semi-definite, and its null space if so.

    Pivoted Cholesky of Ã = S A S (:func:`_jacobi_scaled`) stopped at pivots <= ``rtol``;
    semi-definite when the rest of the Schur complement is within 10 ``rtol`` of zero.
    (False, None) if not, else (True, null-space basis with unit columns).
    """
    A = np.asarray(A, dtype=float)
    if not np.any(A.diagonal()):
        return (True, np.eye(A.shape[0])) if not np.any(A) else (False, None)
    scaled = _jacobi_scaled(A, rtol)
    if scaled is None:
        return False, None
    _, X, rest = _pstrf_null(scaled[0], rtol)
    if rest > 10 * rtol:
        return False, None
    X /= scaled[1][:, None]
    return True, X / np.linalg.norm(X, axis=0) if X.shape[1] else X


def psd_to_tolerance(A: NDArray, rtol: float = CERTIFICATE_RTOL) -> bool:
    """sym(A) is positive semi-definite to ``rtol``: S sym(A) S + rtol I (S as in
    :func:`_jacobi_scaled`) has a Cholesky factor."""
    A = np.asarray(A, dtype=float)
    A = (A + A.T) / 2
    scaled = _jacobi_scaled(A, rtol) if np.any(A.diagonal()) else None
    if scaled is None:
        return not np.any(A)
    S = scaled[0]
    S.flat[:: S.shape[0] + 1] += rtol
    return sla.lapack.dpotrf(S, lower=0, clean=0, overwrite_a=1)[1] == 0


def free_modes(K: NDArray, D: NDArray, W: NDArray) -> NDArray | None:
    """Orthonormal basis of the free rigid-body directions (K φ = D φ = Wᵀ φ = 0), or None
    when this fast test cannot decide (the caller runs ``rigid_body_modes``).

    None of them when no stiffness diagonal is rounding and the Jacobi-scaled K̃ minus
    τ I (τ = RIGID_BODY_RTOL max(1, Gershgorin bound) >= the null-space tolerance of
    ``rigid_body_modes``) has a Cholesky factor. Otherwise the null space of sym K by
    :func:`psd_null_space` (a coordinate whose diagonal is rounding counts as free)
    restricted, as ``rigid_body_modes`` does, to the directions with singular values of
    [K; D; Wᵀ] Z (each scaled by its norm) <= CONSTRAINT_RTOL; undecided when one lies
    within a factor 100 above that."""
    Ks = (K + K.T) / 2
    n = Ks.shape[0]
    diag = np.abs(np.diag(Ks))
    if diag.min() > RIGID_BODY_RTOL * diag.max():
        d = np.sqrt(diag)
        Kt = Ks / np.outer(d, d)
        tau = RIGID_BODY_RTOL * max(float(np.max(np.sum(np.abs(Kt), axis=1))), 1.0)
        if sla.lapack.dpotrf(Kt - tau * np.eye(n), lower=0, clean=0, overwrite_a=1)[1] == 0:
            return np.zeros((n, 0))
    ok, Z = psd_null_space(Ks, RIGID_BODY_RTOL)
    if not ok or Z.shape[1] == 0:
        return None
    Q = np.linalg.qr(Z)[0]
    blocks = [(A @ Q) / s for A in (K, D, W.T) if (s := float(np.linalg.norm(A))) > 0]
    _, sv, vt = np.linalg.svd(np.vstack(blocks))
    sv = np.concatenate([sv, np.zeros(vt.shape[0] - sv.size)])
    if np.any((sv > CONSTRAINT_RTOL) & (sv <= 100 * CONSTRAINT_RTOL)):
        return None
    return Q @ vt[sv <= CONSTRAINT_RTOL].T


def mesh_block(M: NDArray, D: NDArray, K: NDArray, W: NDArray) -> NDArray[np.bool_]:
    """The coordinates W touches and those connected to them in the coupling graph of M,
    D, K (entries above ``BLOCK_RTOL`` of each matrix's largest). The rest splits off
    (time-invariant in every contact state) only if all its couplings to the block and its
    W rows are below ``GAP_RTOL``: rounding of the basis projection (~1e-12 here)."""
    mask = np.zeros(M.shape, dtype=bool)
    for A in (M, D, K):
        mask |= np.abs(A) > BLOCK_RTOL * np.max(np.abs(A))
    wmax = np.max(np.abs(W))
    block = np.max(np.abs(W), axis=1) > BLOCK_RTOL * wmax
    while not block.all():  # grow the coordinates W touches by their couplings
        grown = block | mask[block].any(axis=0)
        if np.array_equal(grown, block):
            break
        block = grown
    if block.all():
        return block
    cross = [np.max(np.abs(A[np.ix_(block, ~block)])) / max(np.max(np.abs(A)), 1e-300) for A in (M, D, K)]
    if max(cross) > GAP_RTOL or np.max(np.abs(W[~block])) > GAP_RTOL * wmax:
        return np.ones_like(block)
    return block


class _Prepared:
    """M⁻¹K, M⁻¹D, M⁻¹W of the mesh block of one state space (Cholesky solves, once),
    and the eigenvalues of the decoupled rest (:func:`mesh_block`)."""

    def __init__(self, ss: LinearStateSpace):
        b = mesh_block(ss.M, ss.D, ss.K, ss.W)
        M, D, K, W = ss.M[np.ix_(b, b)], ss.D[np.ix_(b, b)], ss.K[np.ix_(b, b)], ss.W[b]
        N = M.shape[0]
        try:
            cf = sla.cho_factor(M, check_finite=False)
            X = sla.cho_solve(cf, np.column_stack([K, D, W]), check_finite=False)
        except (np.linalg.LinAlgError, sla.LinAlgError):
            X = np.linalg.solve(M, np.column_stack([K, D, W]))
        self.N, self.Wt = N, W.T
        self.MK, self.MD, self.MW = X[:, :N], X[:, N : 2 * N], X[:, 2 * N :]
        self.side = np.zeros(0, dtype=complex)
        if not b.all():
            r = ~b
            n = int(r.sum())
            A = np.zeros((2 * n, 2 * n))
            A[:n, n:] = np.eye(n)
            Mr, Kr, Dr = (Y[np.ix_(r, r)] for Y in (ss.M, ss.K, ss.D))
            A[n:] = -np.linalg.solve(Mr, np.column_stack([Kr, Dr]))
            self.side = np.linalg.eigvals(A)

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
            m = np.max(np.abs(R))
            if not (m > 0 and np.isfinite(m)):
                return np.linalg.eigvals(Phi)
            R /= m
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
    unscaled state (q, q'), by scipy's ``expm``: the reference product (``method="expm"``)."""
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
    """
    if method not in METHODS:
        raise ModelError("method", f"one of {', '.join(map(repr, METHODS))}, got {method!r}")
    Y = np.atleast_2d(np.asarray(harmonics, dtype=float))
    if method == "expm":
        ss = state_space.deflated if deflate else state_space
        return _expm_reference(ss, *_tangent_pieces(nonlinearities, Y, ss.W.shape[1]), omega)
    breaks, Kt = _tangent_pieces(nonlinearities, Y, state_space.W.shape[1])
    period = (breaks[-1] - breaks[0]) / omega
    states, seq = _state_sequence(breaks, Kt)
    dominant = method == "auto" and 2 * state_space.M.shape[0] > DENSE_STATE_LIMIT
    if dominant and len(states) == 1:
        r = _neutral_count(state_space, states[0], deflate)
        if r is not None:
            return np.ones(r, dtype=complex)
    shared = state_space.cache if dominant and len(states) > 1 else None
    if shared is not None:
        key = ("monodromy", state_space.digest, bool(deflate), tuple(kt.tobytes() for kt in states))
        key = (*key, tuple(i for i, _ in seq))
        mu = _revisit(shared.peek(key), np.array([dth for _, dth in seq]) / omega)
        if mu is not None:
            return mu
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
        return np.exp(np.concatenate([lam, prep.side]) * period)
    times = np.array([dth for _, dth in seq]) / omega
    Es, Cs = _exponentials(prep, states, seq, times)
    Phi = _product(Es)
    side = np.exp(prep.side * period)
    if dense:
        mu = np.concatenate([np.linalg.eigvals(Phi), side])
    else:
        mu = _dominant(Phi)
        top = float(np.max(np.abs(mu)))
        if 1 + 1e-7 < top < 1 + NEAR_CRITICAL:  # a defective μ = 1 would be split by ~sqrt(1e-10)
            mu = np.linalg.eigvals(Phi)
        mu = np.concatenate([mu, side[np.abs(side) >= (1 - BAND) * np.max(np.abs(mu))]])
    if shared is not None:
        shared.put(key, (times, _sensitivity(Es, Cs, Phi), mu))
    return mu


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
    Cs = [Cs[i] for i, _ in seq]
    return [expm(C * t) for C, t in zip(Cs, times, strict=True)], Cs


def monodromy(
    state_space: LinearStateSpace, nonlinearities: Sequence, harmonics: ArrayLike, omega: float
) -> NDArray[np.float64]:
    """The monodromy of :func:`floquet_multipliers`: deflated, mesh block, scaled state, the
    period from a contact change (similar to the one from θ = 0)."""
    ss = state_space.deflated
    Y = np.atleast_2d(np.asarray(harmonics, dtype=float))
    states, seq = _state_sequence(*_tangent_pieces(nonlinearities, Y, ss.W.shape[1]))
    times = np.array([dth for _, dth in seq]) / omega
    return _product(_exponentials(_prepared(ss), states, seq, times)[0])


def _sensitivity(Es: list[NDArray], Cs: list[NDArray], Phi: NDArray) -> NDArray:
    """g with ‖dΦ‖₁ <= ‖Φ‖₁ Σ g_i |δ_i| to first order in interval changes δ_i: dΦ =
    Σ (E_m..E_i+1) C_i (E_i..E_1) δ_i (C_i, E_i commute), g_1 = ‖C_1‖, g_m = ‖C_m‖."""
    m = len(Es)
    nrm = np.linalg.norm(Phi, 1)
    g = np.array([np.linalg.norm(C, 1) for C in Cs])
    for i in range(1, m - 1):
        left, right = _product(Es[i + 1 :]), _product(Es[: i + 1])
        g[i] *= np.linalg.norm(left, 1) * np.linalg.norm(right, 1) / nrm
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


def tangent_spectrum(nonlinearities: Sequence, harmonics: ArrayLike, n: int, n_max: int) -> NDArray:
    """Fourier coefficients T_m = (1/2π) ∫ K_t(θ) e^{-imθ} dθ, m = -n_max..n_max, shape (2n_max+1, n, n)."""
    Y = np.atleast_2d(np.asarray(harmonics, dtype=float))
    breaks, Kt = _tangent_pieces(nonlinearities, Y, n)
    m = np.arange(-n_max, n_max + 1)
    t1, t2 = breaks[:-1], breaks[1:]
    w = np.empty((m.size, t1.size), dtype=complex)
    nz = m != 0
    w[nz] = (np.exp(-1j * np.outer(m[nz], t2)) - np.exp(-1j * np.outer(m[nz], t1))) * 1j / (2 * np.pi)
    w[nz] /= m[nz][:, None]
    w[~nz] = (t2 - t1) / (2 * np.pi)
    return np.einsum("ms,sij->mij", w, Kt)


def hill_multipliers(
    state_space: LinearStateSpace,
    nonlinearities: Sequence,
    harmonics: ArrayLike,
    omega: float,
    n_hill: int = 30,
) -> NDArray[np.complex128]:
    """Floquet multipliers by Hill's method (quadratic eigenproblem in the Floquet exponent).

    With η = e^{λt} Σ_k p_k e^{ikωt}, k = -n_hill..n_hill, the variational equation gives
    [(λ + ikω)² M + (λ + ikω) D + K] p_k + Σ_m W T_{k-m} Wᵀ p_m = 0 (T: tangent Fourier
    coefficients; at λ = 0 this is the harmonic-balance Jacobian in complex form),
    linearised to a 2N(2n_hill+1) eigenproblem. The 2N exponents with the smallest
    |Im λ| are kept (fundamental strip) and μ = exp(λ 2π/ω) returned. Truncation error
    decays slowly for the discontinuous tangent of the backlash law; prefer
    :func:`floquet_multipliers`. This is the route when the linear part is polynomial.
    """
    ss = state_space.deflated
    N = ss.M.shape[0]
    nk = 2 * n_hill + 1
    T = tangent_spectrum(nonlinearities, harmonics, ss.W.shape[1], 2 * n_hill)
    k = np.arange(-n_hill, n_hill + 1)
    size = N * nk
    M2 = np.kron(np.eye(nk), ss.M).astype(complex)
    D1 = np.zeros((size, size), dtype=complex)
    K0 = np.zeros((size, size), dtype=complex)
    for a, ka in enumerate(k):
        sl = slice(a * N, (a + 1) * N)
        iw = 1j * ka * omega
        D1[sl, sl] = 2 * iw * ss.M + ss.D
        K0[sl, sl] = iw * iw * ss.M + iw * ss.D + ss.K
        for b, kb in enumerate(k):
            K0[sl, b * N : (b + 1) * N] += ss.W @ T[2 * n_hill + ka - kb] @ ss.W.T
    M2inv = np.linalg.inv(M2)
    A = np.block([[np.zeros((size, size)), np.eye(size)], [-M2inv @ K0, -M2inv @ D1]])
    lam = np.linalg.eigvals(A)
    lam = lam[np.argsort(np.abs(lam.imag))][: 2 * N]
    return np.exp(lam * 2 * np.pi / omega)


def harmonic_solution_stability(
    model: ReducedModel, solution: HarmonicSolution, method: str = "monodromy"
) -> HarmonicSolution:
    """Attach Floquet multipliers (``method`` "monodromy" or "hill") to a converged solution.

    "monodromy" is :func:`floquet_multipliers` with its default method: above
    ``DENSE_STATE_LIMIT`` only the dominant multipliers are attached.
    """
    ss = model.linear_state_space(solution.omega)
    if ss is None or not solution.converged:
        return solution
    if method == "hill":
        mu = hill_multipliers(ss, model.nonlinearities, solution.harmonics, solution.omega)
    else:
        mu = floquet_multipliers(ss, model.nonlinearities, solution.harmonics, solution.omega)
    return solution.with_multipliers(mu)
