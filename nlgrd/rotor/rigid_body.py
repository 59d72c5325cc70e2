"""Rigid-body (free) modes and the balanced-load check, decided with scaled tolerances.

A rigid-body mode is a null vector of the assembled stiffness K (with the gear meshes,
couplings and bearings in it): the free rotation of a drive train with no torsional
ground, say, shaped by the speed ratios and the meshes. Whether a vector is in the
null space is decided on the Jacobi-scaled stiffness K̃ = D⁻¹ K D⁻¹, D = diag(K)^½,
whose diagonal is 1 and whose norm is at most the largest row count. Its rounding
noise is then a few n ε ‖K̃‖ (about 1e-15 on the shipped models, whose lowest
flexible K̃ eigenvalue is 4e-4 or more), whatever the units or the stiffness range of
the elements, so a relative tolerance of 1e-10 separates null vectors from flexible
modes by orders of magnitude on either side. Comparing eigenvalues of K φ = λ M φ
with an absolute threshold does not: their noise is ε λ_max, about 1 (rad/s)² on
Kubo's rig, where stiff axial bars reach λ_max ~ 1e16 (rad/s)².

The basis returned is M-orthonormal and canonical (pivots at fixed DOFs, positive
there), so it does not depend on the BLAS kernel beyond rounding.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from nlgrd.errors import ModelError

#: Null-space tolerance on the eigenvalues of the Jacobi-scaled stiffness, relative to ‖K̃‖.
RIGID_BODY_RTOL = 1e-10
#: Tolerance on the singular values of an extra constraint A restricted to the null space of K,
#: relative to ‖A‖ (the rounding of A N is ~ε ‖A‖; any physical coupling is far larger).
CONSTRAINT_RTOL = 1e-8
#: A load balances when |Rᵀ f| <= BALANCE_RTOL ‖R_j‖ ‖f‖ for every rigid-body mode R_j.
BALANCE_RTOL = 1e-8
#: Above this many DOFs the null space comes from a sparse shift-invert eigensolver.
DENSE_LIMIT = 1500


def _dense(A) -> NDArray:
    return A.toarray() if sp.issparse(A) else np.asarray(A)


def _scaled_null_space(K, rtol: float) -> NDArray:
    """Null vectors of K (symmetric positive semi-definite), columns in DOF space."""
    n = K.shape[0]
    diag = np.abs(np.asarray(K.diagonal(), dtype=float))
    d = np.sqrt(diag)
    # Diagonals at rounding level (a free rotation projected onto a basis, ~1e-20 of the
    # largest) are zeros: scaling them up to 1 would make noise look like stiffness.
    # With d = sqrt(max) their scaled rows stay <= sqrt(n eps), far inside rtol's reach.
    dmax = float(diag.max()) if n else 0.0
    d[diag <= n * np.finfo(float).eps * dmax] = np.sqrt(dmax) if dmax > 0 else 1.0
    Dinv = sp.diags(1.0 / d)
    if n <= DENSE_LIMIT:
        Ks = _dense(Dinv @ (sp.csr_matrix(K) if not sp.issparse(K) else K) @ Dinv)
        Ks = (Ks + Ks.T) / 2
        lam, V = sla.eigh(Ks)
        tol = rtol * max(lam[-1], 1.0)
        return V[:, np.abs(lam) <= tol] / d[:, None]
    Ks = (Dinv @ sp.csc_matrix(K) @ Dinv).tocsc()
    Ks = ((Ks + Ks.T) / 2).tocsc()
    norm = max(float(abs(Ks).sum(axis=1).max()), 1.0)  # Gershgorin bound on ‖K̃‖
    tol = rtol * norm
    v0 = np.full(n, 1.0 / np.sqrt(n))  # fixed start: byte-identical reruns
    k = min(12, n - 2)
    while True:
        lam, V = spla.eigsh(Ks, k=k, sigma=-1e-3, which="LM", v0=v0)
        if np.max(np.abs(lam)) > tol or k >= n - 2:
            break
        k = min(n - 2, 2 * k)
    return V[:, np.abs(lam) <= tol] / d[:, None]


def _restrict(N: NDArray, constraints: Sequence) -> NDArray:
    """The part of span(N) on which every A in ``constraints`` vanishes."""
    if N.shape[1] == 0 or not constraints:
        return N
    Nn = N / np.linalg.norm(N, axis=0)
    blocks = []
    for A in constraints:
        scale = float(spla.norm(A) if sp.issparse(A) else np.linalg.norm(A))
        if scale > 0:
            blocks.append(_dense(A @ Nn) / scale)
    if not blocks:
        return N
    _, s, vt = np.linalg.svd(np.vstack(blocks))
    s = np.concatenate([s, np.zeros(vt.shape[0] - s.size)])
    return Nn @ vt[s <= CONSTRAINT_RTOL].T


def _canonical(N: NDArray, M) -> NDArray:
    """M-orthonormal basis of span(N) in a fixed form.

    Pivots are chosen greedily as the first DOF whose entry is within 0.1 % of the largest
    (ties are common: a free rotation has equal θx on every node), each column is made 1
    at its pivot and 0 at the earlier pivots, then Gram-Schmidt in the M inner product in
    that order, positive at the pivot.
    """
    r = N.shape[1]
    if r == 0:
        return N
    B = N.copy()
    pivots = []
    for j in range(r):
        rows = np.linalg.norm(B[:, j:], axis=1)
        p = int(np.argmax(rows >= (1 - 1e-3) * rows.max()))
        # bring the column with the largest entry at p first, unit there, eliminate it
        c = j + int(np.argmax(np.abs(B[p, j:])))
        B[:, [j, c]] = B[:, [c, j]]
        B[:, j] /= B[p, j]
        for i in range(r):
            if i != j:
                B[:, i] -= B[p, i] * B[:, j]
        pivots.append(p)
    R = np.empty_like(B)
    for j in range(r):
        v = B[:, j].copy()
        for i in range(j):
            v -= (R[:, i] @ (M @ v)) * R[:, i]
        v /= np.sqrt(v @ (M @ v))
        R[:, j] = v if v[pivots[j]] >= 0 else -v
    return R


def rigid_body_modes(K, M, constraints: Sequence = (), rtol: float = RIGID_BODY_RTOL) -> NDArray:
    """M-orthonormal basis (n, r) of the rigid-body modes: K φ = 0 and A φ = 0 for each A.

    Parameters
    ----------
    K : (n, n) array or sparse matrix
        Symmetric stiffness [N/m, N m/rad] as assembled (meshes, couplings and bearings
        included as the caller wants them); its null vectors are the candidates. A
        non-symmetric stiffness goes in as its symmetric part here and whole in
        ``constraints``.
    M : (n, n) array or sparse matrix
        Mass matrix [kg, kg m²], positive definite.
    constraints : sequence of (m, n) arrays, optional
        Further operators the modes must not excite (damping D, mesh projections Wᵀ):
        a mode of K that moves any of them is not free.
    rtol : float
        Null-space tolerance relative to the norm of the Jacobi-scaled stiffness.

    Returns
    -------
    ndarray (n, r)
        Rᵀ M R = I, canonical basis (see :func:`_canonical`).
    """
    N = _scaled_null_space(K, rtol)
    N = _restrict(N, constraints)
    return _canonical(N, M)


def check_balanced(R: NDArray, load: NDArray, key: str, what: str = "the static loads") -> None:
    """Raise ModelError(key) when ``load`` [N, N m] has a net component on a rigid-body mode.

    The measure |R_jᵀ f| / (‖R_j‖ ‖f‖) lies in [0, 1] and is independent of the units of f
    and M; rounding gives ~1e-16, so BALANCE_RTOL = 1e-8 rejects only real imbalance.

    Parameters
    ----------
    R : ndarray, (n, r)
        Rigid-body modes as columns (:func:`rigid_body_modes`); r = 0 accepts any load.
    load : array_like, (n,)
        Generalised force vector f [N, N m].
    key : str
        Field named by the ModelError.
    what : str
        What the loads are, for the message.

    Raises
    ------
    ModelError
        When some |R_jᵀ f| / (‖R_j‖ ‖f‖) exceeds BALANCE_RTOL.
    """
    f = np.asarray(load, dtype=float)
    if R.shape[1] == 0 or not np.any(f):
        return
    ratio = np.abs(R.T @ f) / (np.linalg.norm(R, axis=0) * np.linalg.norm(f))
    if np.any(ratio > BALANCE_RTOL):
        raise ModelError(
            key,
            f"{what} have a net component on a free rigid-body mode (relative {ratio.max():.2e}): "
            "the loads are not balanced (not self-equilibrated) and the system would drift",
        )


def complement(R: NDArray, M) -> NDArray:
    """Orthonormal basis (n, n - r) of the M-orthogonal complement of span(R).

    Parameters
    ----------
    R : ndarray, (n, r)
        Basis of the subspace, e.g. the rigid-body modes of :func:`rigid_body_modes`.
    M : (n, n) array or sparse matrix
        Mass matrix [kg, kg m²] of the M inner product.

    Returns
    -------
    ndarray, (n, n - r)
        Columns orthonormal in the Euclidean inner product, spanning {v : Rᵀ M v = 0};
        the identity when r = 0.
    """
    n = R.shape[0]
    if R.shape[1] == 0:
        return np.eye(n)
    MR = _dense(M @ R)
    _, _, vt = np.linalg.svd(MR.T)
    return vt[R.shape[1] :].T
