"""Linear algebra of the stability analysis: a Padé matrix exponential for scaled state
matrices, null spaces of positive semi-definite matrices to a tolerance (the energy
certificate of :mod:`nlgrd.nonlinear.stability.floquet`), free modes and the mesh block.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray

from nlgrd.rotor.rigid_body import CONSTRAINT_RTOL, RIGID_BODY_RTOL

#: Symmetry and semi-definiteness tolerance of the energy certificate (Jacobi-scaled).
CERTIFICATE_RTOL = RIGID_BODY_RTOL
#: Couplings above this (relative to each matrix's largest entry) join coordinates into one block.
BLOCK_RTOL = 1e-10
#: A block splits off only when every coupling to it is below this: rounding, not physics.
GAP_RTOL = 1e-11


# Padé [13/13] coefficients (2m - j)! m! / ((2m)! j! (m - j)!), m = 13, times 26!/13!
# (the scale cancels in (V - U)⁻¹ (V + U)), and the bound θ_13 (Higham 2005)
_PADE13 = tuple(
    float(math.factorial(26 - j) // (math.factorial(j) * math.factorial(13 - j))) for j in range(14)
)
_THETA13 = 5.371920351148152


def expm(X: NDArray) -> NDArray[np.float64]:
    """exp(X) by Padé [13/13] with scaling and squaring (Higham 2005), scaled by
    α₄ = max(‖X⁴‖^¼, ‖X⁵‖^⅕) <= 2^s θ₁₃ (Al-Mohy & Higham 2009, Thm 4.2; 27 >= 4 x 3),
    ‖X⁵‖₁ <= ‖X⁴‖₁ ‖X‖₁: fewer squarings than ‖X‖₁ for these non-normal matrices.

    Parameters
    ----------
    X : ndarray (n, n)
        A real square matrix (a state matrix times a time: dimensionless).

    Returns
    -------
    ndarray (n, n)
        exp(X).
    """
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


def expm_times(C: NDArray, times) -> list[NDArray]:
    """exp(C t) for several times t: :func:`expm`'s Padé [13/13] and scaling of X = C t, its
    even powers X²ᵏ = t²ᵏ C²ᵏ (k <= 6) from those of C, formed once for all the times.
    A time then takes one product (U = X (...)), the solve and its squarings instead of six
    products and the squarings: a contact state that holds on two or three intervals of a
    period (the backlash's). The same approximant as :func:`expm` evaluated in another order:
    equal to rounding. One time, or powers of C that overflow: :func:`expm` per time.

    Parameters
    ----------
    C : ndarray (n, n)
        A real square matrix (a scaled state matrix [1/s]).
    times : sequence of float
        The times t [s].

    Returns
    -------
    list of ndarray (n, n)
        exp(C t) per time, in order.
    """
    if len(times) < 2:
        return [expm(C * t) for t in times]
    P = {1: C, 2: C @ C}
    P[4] = P[2] @ P[2]
    P[6], P[8] = P[4] @ P[2], P[4] @ P[4]
    P[10], P[12] = P[8] @ P[2], P[6] @ P[6]
    if not np.isfinite(P[12]).all():
        return [expm(C * t) for t in times]
    n = C.shape[0]
    n1c, n4c = float(np.linalg.norm(C, 1)), float(np.linalg.norm(P[4], 1))
    stack = np.stack([np.eye(n)] + [P[k] for k in range(2, 14, 2)]).reshape(7, n * n)
    b, k2, out = np.array(_PADE13), np.arange(0, 14, 2), []
    for t in times:
        t = float(t)
        n1, n4 = n1c * abs(t), n4c * t**4
        alpha = max(n4**0.25, (n4 * n1) ** 0.2)
        s = max(0, int(np.ceil(np.log2(alpha / _THETA13)))) if alpha > _THETA13 else 0
        tau = t * 2.0**-s
        even = ((b[k2] * tau**k2) @ stack).reshape(n, n)  # Σ b_2k X²ᵏ
        U = tau * (C @ ((b[k2 + 1] * tau**k2) @ stack).reshape(n, n))  # X Σ b_2k+1 X²ᵏ
        R = np.linalg.solve(even - U, even + U)
        for _ in range(s):
            R = R @ R
        out.append(R)
    return out


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

    Parameters
    ----------
    A : ndarray (n, n)
        A symmetric matrix, in any unit (a stiffness [N/m]).
    rtol : float
        Relative tolerance [-] of symmetry, of the pivots and of the Schur complement, on
        the Jacobi-scaled matrix.

    Returns
    -------
    ok : bool
        Whether ``A`` is positive semi-definite to ``rtol``.
    null_space : ndarray (n, r) or None
        Basis of its null space with unit columns when ``ok``, else None.
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
    :func:`_jacobi_scaled`) has a Cholesky factor.

    Parameters
    ----------
    A : ndarray (n, n)
        A square matrix, in any unit (a damping matrix [N s/m]); only sym(A) = (A + Aᵀ)/2
        counts.
    rtol : float
        Relative tolerance [-] on the Jacobi-scaled sym(A).

    Returns
    -------
    bool
        True when sym(A) is positive semi-definite to ``rtol`` (or A is zero).
    """
    A = np.asarray(A, dtype=float)
    A = (A + A.T) / 2
    scaled = _jacobi_scaled(A, rtol) if np.any(A.diagonal()) else None
    if scaled is None:
        return not np.any(A)
    S = scaled[0]
    S.flat[:: S.shape[0] + 1] += rtol
    return sla.lapack.dpotrf(S, lower=0, clean=0, overwrite_a=1)[1] == 0


def free_modes(K: NDArray, D: NDArray, W: NDArray, null: tuple | None = None) -> NDArray | None:
    """Orthonormal basis of the free rigid-body directions (K φ = D φ = Wᵀ φ = 0), or None
    when this fast test cannot decide (the caller runs ``rigid_body_modes``).

    None of them when no stiffness diagonal is rounding and the Jacobi-scaled K̃ minus
    τ I (τ = RIGID_BODY_RTOL max(1, Gershgorin bound) >= the null-space tolerance of
    ``rigid_body_modes``) has a Cholesky factor. Otherwise the null space of sym K by
    :func:`psd_null_space` (a coordinate whose diagonal is rounding counts as free)
    restricted, as ``rigid_body_modes`` does, to the directions with singular values of
    [K; D; Wᵀ] Z (each scaled by its norm) <= CONSTRAINT_RTOL; undecided when one lies
    within a factor 100 above that.

    Parameters
    ----------
    K : ndarray (N, N)
        Stiffness matrix of the linear part, without the nonlinear elements [N/m, N m/rad].
    D : ndarray (N, N)
        Damping matrix [N s/m, N m s/rad].
    W : ndarray (N, n_nl)
        Projection onto the nonlinear coordinates y = Wᵀ q.
    null : tuple, optional
        ``stiffness_null_space(K)`` when the caller has it (it depends on K alone).

    Returns
    -------
    ndarray (N, r) or None
        Orthonormal columns spanning the free modes (r = 0: none), or None when undecided.
    """
    ok, Q = stiffness_null_space(K) if null is None else null
    if not ok or Q.shape[1] == 0:
        return Q if ok else None
    blocks = [(A @ Q) / s for A in (K, D, W.T) if (s := float(np.linalg.norm(A))) > 0]
    _, sv, vt = np.linalg.svd(np.vstack(blocks))
    sv = np.concatenate([sv, np.zeros(vt.shape[0] - sv.size)])
    if np.any((sv > CONSTRAINT_RTOL) & (sv <= 100 * CONSTRAINT_RTOL)):
        return None
    return Q @ vt[sv <= CONSTRAINT_RTOL].T


def stiffness_null_space(K: NDArray) -> tuple[bool, NDArray | None]:
    """The first step of :func:`free_modes`, which depends on K alone (a sweep's state
    spaces share it): (True, orthonormal basis of the null space of sym K, possibly
    empty) or (False, None) when undecided.

    Parameters
    ----------
    K : ndarray (N, N)
        Stiffness matrix of the linear part, without the nonlinear elements [N/m, N m/rad].

    Returns
    -------
    ok : bool
        False when :func:`psd_null_space` cannot decide.
    basis : ndarray (N, r) or None
        Orthonormal columns (r = 0 when sym K is positive definite to the tolerance).
    """
    Ks = (K + K.T) / 2
    n = Ks.shape[0]
    diag = np.abs(np.diag(Ks))
    if diag.min() > RIGID_BODY_RTOL * diag.max():
        d = np.sqrt(diag)
        Kt = Ks / np.outer(d, d)
        tau = RIGID_BODY_RTOL * max(float(np.max(np.sum(np.abs(Kt), axis=1))), 1.0)
        if sla.lapack.dpotrf(Kt - tau * np.eye(n), lower=0, clean=0, overwrite_a=1)[1] == 0:
            return True, np.zeros((n, 0))
    ok, Z = psd_null_space(Ks, RIGID_BODY_RTOL)
    if not ok or Z.shape[1] == 0:
        return False, None
    return True, np.linalg.qr(Z)[0]


def mesh_block(M: NDArray, D: NDArray, K: NDArray, W: NDArray) -> NDArray[np.bool_]:
    """The coordinates W touches and those connected to them in the coupling graph of M,
    D, K (entries above ``BLOCK_RTOL`` of each matrix's largest). The rest splits off
    (time-invariant in every contact state) only if all its couplings to the block and its
    W rows are below ``GAP_RTOL``: rounding of the basis projection (~1e-12 here).

    Parameters
    ----------
    M, D, K : ndarray (N, N)
        Mass [kg, kg m²], damping [N s/m, N m s/rad] and stiffness [N/m, N m/rad] matrices.
    W : ndarray (N, n_nl)
        Projection onto the nonlinear coordinates y = Wᵀ q.

    Returns
    -------
    ndarray of bool (N,)
        The coordinates of the mesh block; all True when nothing splits off.
    """
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
