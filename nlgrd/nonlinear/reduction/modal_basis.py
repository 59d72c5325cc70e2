"""Reduction bases for large models: lowest undamped modes plus attachment vectors.

A Galerkin basis V for the receptances of a few coordinates W of a large linear model
(the links of :class:`~nlgrd.nonlinear.reduction.link_reduction.LinkReceptance`): the
undamped modes of K_r φ = λ M φ up to a cut-off frequency, the static attachment vectors (K_r + M)⁻¹ W and the
dynamic ones Z(iω)⁻¹ W at 1/4, 1/2 and 1 of the highest excitation frequency (modal
summation with residual correction, Craig & Kurdila 2006, Fundamentals of Structural
Dynamics, §17.3; here in projected form, so gyroscopic, non-proportional and circulatory
terms stay coupled). Rigid-body modes that no W moves and no damping couples are left
out: the receptances are M-orthogonal to them exactly.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

#: Mode counts at which the bases stop doubling (the last doubling may pass them).
MODE_CAP = 400
STABILITY_MODE_CAP = 300


class ModeCapWarning(UserWarning):
    """A modal basis reached its cap before its cut-off frequency."""


def lowest_modes(K, M, cutoff: float, start: int, cap: int, what: str) -> tuple[NDArray, NDArray]:
    """Lowest eigenpairs of K φ = λ M φ up to λ = cutoff² (at least), doubling the count.

    Shift-invert about -1 (rigid-body modes are fine); fixed start vector (reruns are
    byte-identical). Warns when the cap stops it short of the cut-off.

    Parameters
    ----------
    K, M : sparse matrix (n, n)
        Stiffness [N/m] and mass [kg] matrices.
    cutoff : float
        Highest natural frequency wanted [rad/s].
    start, cap : int
        First and largest mode count [-].
    what : str
        The basis's name, for the warning.

    Returns
    -------
    tuple of ndarray
        Eigenvalues λ = ω² [rad²/s²] and M-normalised modes (n, count).
    """
    n = K.shape[0]
    v0 = np.full(n, 1.0 / np.sqrt(n))
    k = min(n - 2, start)
    while True:
        lam, vec = spla.eigsh(K, k=k, M=M, sigma=-1.0, v0=v0)
        if np.max(lam) >= cutoff**2 or k >= n - 2:
            return lam, vec
        if k >= cap:
            warnings.warn(
                f"{what}: {k} modes reach {np.sqrt(max(np.max(lam), 0)) / (2 * np.pi):.4g} Hz, short of the "
                f"cut-off {cutoff / (2 * np.pi):.4g} Hz (cap {cap}); higher modes enter only through "
                "the attachment vectors",
                ModeCapWarning,
                stacklevel=3,
            )
            return lam, vec
        k = min(n - 2, 2 * k)


def rigid_decoupled(R: NDArray, couplings: list) -> bool:
    """Whether the rigid-body modes R are free of every coupling matrix in ``couplings``
    (damping, gyroscopic, circulatory, hysteretic): then the receptances of coordinates
    that R does not move are M-orthogonal to R, and R can leave the basis.

    Parameters
    ----------
    R : ndarray (n, r)
        Rigid-body modes [-].
    couplings : list of sparse matrix
        The matrices that could couple R to the rest.

    Returns
    -------
    bool
    """
    for A in couplings:
        if A.nnz and np.linalg.norm(A @ R) > 1e-9 * spla.norm(A) * np.linalg.norm(R):
            return False
    return True


def attachment_basis(
    Kr: sp.spmatrix,
    M: sp.spmatrix,
    W: NDArray,
    dynamic_stiffness: Callable[[float], sp.spmatrix],
    max_frequency: float,
    cutoff_factor: float,
    rigid: NDArray | None = None,
    fractions=(0.25, 0.5, 1.0),
) -> tuple[NDArray, int]:
    """An orthonormal basis V for the receptances Z(ω)⁻¹ W up to ``max_frequency``.

    Parameters
    ----------
    Kr : sparse matrix (n, n)
        Stiffness with the coordinates' linear stiffness in (no free mode but rigid-body
        ones) [N/m].
    M : sparse matrix (n, n)
        Mass matrix [kg].
    W : ndarray (n, a)
        The coordinates' projections and the loaded DOFs [-].
    dynamic_stiffness : callable (omega) -> sparse matrix
        Z at excitation frequency ``omega`` [rad/s] (the speed as the sweep sets it).
    max_frequency : float
        Highest excitation frequency [rad/s].
    cutoff_factor : float
        Modes up to ``cutoff_factor * max_frequency`` [-].
    rigid : ndarray (n, r), optional
        Rigid-body modes to leave out (only when :func:`rigid_decoupled`).
    fractions : sequence of float
        Frequencies of the dynamic attachment vectors, as fractions of ``max_frequency`` [-].

    Returns
    -------
    tuple
        V (n, m) with VᵀV = I, and the modes kept (n, count), M-normalised.
    """
    cutoff = cutoff_factor * max_frequency
    # lowest modes of the linear system with the coordinates in, shift-invert about -1
    lam, vec = lowest_modes(Kr, M, cutoff, start=40, cap=MODE_CAP, what="receptance basis")
    keep = lam <= cutoff**2
    vectors = [vec[:, keep]]
    vectors.append(spla.splu((Kr + M).tocsc()).solve(W))
    for frac in fractions:
        z = spla.splu(dynamic_stiffness(frac * max_frequency).tocsc()).solve(W.astype(complex))
        vectors += [z.real, z.imag]
    B = np.column_stack(vectors)
    B = B[:, np.linalg.norm(B, axis=0) > 0]  # e.g. Im Z⁻¹W of an undamped model
    deflate = rigid is not None and rigid.shape[1] > 0
    if deflate:
        MR = M @ rigid

        def off_rigid(X):  # the part of X M-orthogonal to R
            return X - rigid @ np.linalg.solve(rigid.T @ MR, MR.T @ X)

        n0 = np.linalg.norm(B, axis=0)
        B = off_rigid(B)
        B = B[:, np.linalg.norm(B, axis=0) > 1e-8 * n0]  # drop the rigid modes themselves
    V, s, _ = np.linalg.svd(B / np.linalg.norm(B, axis=0), full_matrices=False)
    V = V[:, s > 1e-10 * s[0]]
    if deflate:  # once more, against what the SVD's rounding brought back
        V = np.linalg.qr(off_rigid(V))[0]
    return V, vec[:, keep]


def m_orthonormal(B: NDArray, M: sp.spmatrix) -> NDArray:
    """A basis of the span of B with Vᵀ M V = I (dependent columns dropped): the reduced
    mass is the identity, which keeps the companion form of the reduced model well scaled.

    Parameters
    ----------
    B : ndarray (n, m)
        Vectors spanning the basis.
    M : sparse matrix (n, n)
        Mass matrix [kg], positive definite.

    Returns
    -------
    ndarray (n, r)

    Raises
    ------
    numpy.linalg.LinAlgError
        When Vᵀ M V is not positive definite (massless DOFs).
    """
    U, s, _ = np.linalg.svd(B / np.linalg.norm(B, axis=0), full_matrices=False)
    U = U[:, s > 1e-10 * s[0]]
    return sla.solve_triangular(np.linalg.cholesky(U.T @ (M @ U)), U.T, lower=True).T


def modes_then_attachments(modes: NDArray, attachments: NDArray, M: sp.spmatrix) -> NDArray:
    """An M-orthonormal basis [Φ, A'] of the modes Φ and the attachment vectors, the latter
    made M-orthogonal to the modes (twice, classical Gram-Schmidt) before their own
    orthonormalisation. Unlike :func:`m_orthonormal` of all columns, it does not mix the
    modes: a mode that no link moves and no damping couples (an axial mode of a spur-gear
    model) stays a coordinate of its own, which the Floquet analysis then splits off
    (:func:`nlgrd.nonlinear.reduction.linear_algebra.mesh_block`) instead of carrying it in every
    matrix exponential.

    Parameters
    ----------
    modes : ndarray (n, m)
        M-orthonormal modes (:func:`lowest_modes`).
    attachments : ndarray (n, a)
        Attachment vectors.
    M : sparse matrix (n, n)
        Mass matrix [kg], positive definite.

    Returns
    -------
    ndarray (n, m + r)
        Vᵀ M V = I; the first m columns are the modes (to rounding).
    """
    gram = modes.T @ (M @ modes)
    Phi = sla.solve_triangular(np.linalg.cholesky(gram), modes.T, lower=True).T  # gram ~ I: no mixing
    A = attachments
    for _ in range(2):
        A = A - Phi @ (Phi.T @ (M @ A))
    keep = np.linalg.norm(A, axis=0) > 1e-8 * np.linalg.norm(attachments, axis=0)
    return np.column_stack([Phi, m_orthonormal(A[:, keep], M)]) if keep.any() else Phi
