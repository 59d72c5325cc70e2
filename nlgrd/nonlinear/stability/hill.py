"""Hill's method: Floquet multipliers from the harmonic-balance Jacobian's quadratic
eigenvalue problem, for a linear part given as matrices (polynomial in the frequency);
the cross-check of :func:`nlgrd.nonlinear.stability.floquet.floquet_multipliers`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.nonlinear.stability.tangent import tangent_pieces

if TYPE_CHECKING:  # pragma: no cover
    from nlgrd.nonlinear.reduction.state_space import LinearStateSpace


def tangent_spectrum(nonlinearities: Sequence, harmonics: ArrayLike, n: int, n_max: int) -> NDArray:
    """Fourier coefficients T_m = (1/2π) ∫ K_t(θ) e^{-imθ} dθ, m = -n_max..n_max, shape (2n_max+1, n, n).

    Parameters
    ----------
    nonlinearities : sequence of LocalNonlinearity
        The force laws; their ``tangent_segments`` give K_t(θ).
    harmonics : array_like (n_nl, 2H+1)
        Real harmonics [y_0, a_1, b_1, ..., a_H, b_H] of the nonlinear coordinates of the
        periodic solution (δ [m] for a mesh); 1-D for one coordinate.
    n : int
        Number of nonlinear coordinates n_nl (the size of K_t).
    n_max : int
        Highest harmonic |m| returned.

    Returns
    -------
    ndarray of complex (2n_max+1, n, n)
        T_m at index n_max + m [N/m].
    """
    Y = np.atleast_2d(np.asarray(harmonics, dtype=float))
    breaks, Kt = tangent_pieces(nonlinearities, Y, n)
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

    Parameters
    ----------
    state_space : LinearStateSpace
        The linear part M, D, K and the projection W (N x n_nl) onto the nonlinear
        coordinates; its free rigid-body modes are deflated first.
    nonlinearities : sequence of LocalNonlinearity
        The force laws; their ``tangent_segments`` give K_t(θ).
    harmonics : array_like (n_nl, 2H+1)
        Real harmonics [y_0, a_1, b_1, ..., a_H, b_H] of the nonlinear coordinates of the
        periodic solution (δ [m] for a mesh); 1-D for one coordinate.
    omega : float
        Mesh frequency ω [rad/s]; the period is 2π/ω.
    n_hill : int
        Harmonics of the Floquet ansatz: k = -n_hill..n_hill.

    Returns
    -------
    ndarray of complex (2N_d,)
        Floquet multipliers μ [-] of the deflated system (N_d DOFs).
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
