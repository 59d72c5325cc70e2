"""The two-dimensional alternating frequency-time scheme on a torus (Kim & Noah 1996,
J. Appl. Mech. 63:375): the index set of the truncation, the N₁ x N₂ grid of samples and the
real transforms between the harmonics and the samples, with the Jacobian of a pointwise law
assembled from the 2-D discrete Fourier transform of its tangent.

y(θ₁, θ₂) = Re Σ_{k ∈ 𝒦} Y_k e^{i (k₁ θ₁ + k₂ θ₂)}, Y_(0,0) real (X_k = a - i b as in
:mod:`nlgrd.nonlinear.fourier.harmonics`), 𝒦 = {(k₁, 0): 0 <= k₁ <= H₁} ∪ {(k₁, k₂): |k₁| <= H₁,
1 <= k₂ <= H₂}: the half of the rectangle |k₁| <= H₁, |k₂| <= H₂ that the reality of y
leaves, its k₂ = 0 row the periodic harmonic balance's set.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from nlgrd.cache import BoundedCache
from nlgrd.errors import ModelError


def torus_indices(H1: int, H2: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The index set 𝒦 of the module docstring, k₂ = 0 row first.

    Parameters
    ----------
    H1 : int
        Harmonics of θ₁ (the base frequency ω₁) [-].
    H2 : int
        Harmonics of θ₂ (the secondary frequency ω₂) [-].

    Returns
    -------
    k1, k2 : ndarray of int
        The indices, (0, 0) first, then (1..H₁, 0), then k₂ = 1..H₂ with k₁ = -H₁..H₁.

    Raises
    ------
    ModelError
        When ``H1`` or ``H2`` is negative.
    """
    if H1 < 0 or H2 < 0:
        raise ModelError("H", f"H1 and H2 must be >= 0, got {H1}, {H2}")
    k1 = [np.arange(H1 + 1)]
    k2 = [np.zeros(H1 + 1, dtype=int)]
    for j in range(1, H2 + 1):
        k1.append(np.arange(-H1, H1 + 1))
        k2.append(np.full(2 * H1 + 1, j))
    return np.concatenate(k1).astype(np.int64), np.concatenate(k2).astype(np.int64)


class TorusGrid:
    """The N₁ x N₂ sampling grid of the torus and the real transforms on 𝒦.

    The real unknowns of one coordinate are [Re Y_k for all k, Im Y_k for k ≠ (0, 0)]
    (length 2|𝒦| - 1); several coordinates are laid out coordinate-major.

    Parameters
    ----------
    H1, H2 : int
        The index set :func:`torus_indices` [-].
    N1, N2 : int
        Samples along θ₁ and θ₂; at least 2 H₁ + 1 and 2 H₂ + 1 [-].

    Attributes
    ----------
    k1, k2 : ndarray of int
        The index set.
    theta1, theta2 : ndarray (N₁ N₂,)
        The grid angles, θ₁ varying slowest [rad].
    inverse : ndarray (N₁ N₂, 2|𝒦| - 1)
        Real unknowns of one coordinate to samples.
    forward : ndarray (2|𝒦| - 1, N₁ N₂)
        Samples to real unknowns (exact on trigonometric polynomials on 𝒦).
    """

    def __init__(self, H1: int, H2: int, N1: int, N2: int):
        if N1 < 2 * H1 + 1 or N2 < 2 * H2 + 1:
            raise ModelError("n_samples", f"the grid {N1} x {N2} does not resolve H1 = {H1}, H2 = {H2}")
        self.H1, self.H2, self.N1, self.N2 = int(H1), int(H2), int(N1), int(N2)
        self.k1, self.k2 = torus_indices(H1, H2)
        t1, t2 = np.meshgrid(2 * np.pi * np.arange(N1) / N1, 2 * np.pi * np.arange(N2) / N2, indexing="ij")
        self.theta1, self.theta2 = t1.reshape(-1), t2.reshape(-1)
        phase = np.outer(self.theta1, self.k1) + np.outer(self.theta2, self.k2)
        c, s = np.cos(phase), np.sin(phase)
        self.inverse = np.hstack([c, -s[:, 1:]])
        weight = np.full(self.n_real, 2.0 / (N1 * N2))
        weight[0] = 1.0 / (N1 * N2)
        self.forward = weight[:, None] * self.inverse.T
        self.cache = BoundedCache(4)

    def refined(self, n_samples: tuple[int, int]) -> TorusGrid:
        """The grid of the same index set on ``n_samples`` (at least 2 H + 1 each way), built
        once per grid: a torus's outputs, its bearings' and its back contact are sampled on
        it, at every torus of a sweep that shares this grid.

        Parameters
        ----------
        n_samples : tuple of int
            Samples along θ₁ and θ₂ asked for [-].

        Returns
        -------
        TorusGrid
            Not to be modified (shared).
        """
        N1, N2 = max(int(n_samples[0]), 2 * self.H1 + 1), max(int(n_samples[1]), 2 * self.H2 + 1)
        return self.cache.get((N1, N2), lambda: TorusGrid(self.H1, self.H2, N1, N2))

    @staticmethod
    def n_real_of(H1: int, H2: int) -> int:
        """2|𝒦| - 1 of the index set (H₁, H₂) without building a grid [-].

        Parameters
        ----------
        H1, H2 : int
            The index set [-].

        Returns
        -------
        int
        """
        return 2 * (H1 + 1 + H2 * (2 * H1 + 1)) - 1

    @property
    def n_terms(self) -> int:
        """|𝒦|, the number of complex terms per coordinate."""
        return self.k1.size

    @property
    def n_real(self) -> int:
        """2|𝒦| - 1, the number of real unknowns per coordinate."""
        return 2 * self.k1.size - 1

    def to_complex(self, z: NDArray, n_coords: int) -> NDArray[np.complex128]:
        """Real unknowns (flat) to Y, shape (n_coords, |𝒦|) complex."""
        Z = np.asarray(z, dtype=float).reshape(n_coords, self.n_real)
        m = self.n_terms
        Y = Z[:, :m].astype(complex)
        Y[:, 1:] += 1j * Z[:, m:]
        return Y

    def to_real(self, Y: NDArray) -> NDArray[np.float64]:
        """Y (n_coords, |𝒦|) complex to the real unknowns, flat."""
        Y = np.atleast_2d(Y)
        return np.hstack([Y.real, Y[:, 1:].imag]).reshape(-1)

    def tangent_block(self, tangent: NDArray) -> NDArray[np.float64]:
        """forward · diag(tangent) · inverse, the AFT Jacobian of a pointwise product, from the
        2-D DFT c of the tangent samples (dG_k/dY_j = c_(k-j) + c_(k+j) conj, indices modulo
        the grid): O(|𝒦|²) instead of O(|𝒦|² N₁ N₂).

        Parameters
        ----------
        tangent : ndarray (N₁ N₂,)
            dg/dy on the grid [N/m].

        Returns
        -------
        ndarray (2|𝒦| - 1, 2|𝒦| - 1)
            [N/m].
        """
        N1, N2 = self.N1, self.N2
        c = np.fft.fft2(np.asarray(tangent, dtype=float).reshape(N1, N2)) / (N1 * N2)
        k1, k2 = self.k1, self.k2
        cm = c[np.mod(k1[:, None] - k1[None, :], N1), np.mod(k2[:, None] - k2[None, :], N2)]
        cp = c[np.mod(k1[:, None] + k1[None, :], N1), np.mod(k2[:, None] + k2[None, :], N2)]
        # G_k = f_k Σ_j [c_(k-j) Y_j + c_(k+j) conj(Y_j)] / 2 (f_0 = 1, else 2; Y_0 real)
        f = np.where(np.arange(k1.size) == 0, 0.5, 1.0)[:, None]
        dre = f * (cm + cp)
        dim = f * 1j * (cm - cp)
        dre[:, 0] = f[:, 0] * cm[:, 0] * 2  # Y_0 enters once: c_k Y_0
        m = k1.size
        out = np.empty((2 * m - 1, 2 * m - 1))
        out[:m, :m] = dre.real
        out[:m, m:] = dim[:, 1:].real
        out[m:, :m] = dre[1:].imag
        out[m:, m:] = dim[1:, 1:].imag
        return out

    def samples(self, Y: NDArray, derivative: tuple[float, float] | None = None) -> NDArray[np.float64]:
        """y on the grid, (n_coords, N₁ N₂); with ``derivative`` (ω₁, ω₂) [rad/s], dy/dt."""
        Y = np.atleast_2d(Y)
        if derivative is not None:
            Y = Y * (1j * (self.k1 * derivative[0] + self.k2 * derivative[1]))[None, :]
        return (self.inverse @ self.to_real(Y).reshape(Y.shape[0], self.n_real).T).T


def default_grid(H1: int, H2: int) -> tuple[int, int]:
    """Default samples N₁ = 4 H₁ + 4, N₂ = 4 H₂ + 4: twice the minimum, so that the aliasing
    of a non-smooth law's higher harmonics onto 𝒦 stays small (checked by the convergence
    estimate of :func:`solve_torus` callers, never assumed).

    Parameters
    ----------
    H1, H2 : int
        The index set [-].

    Returns
    -------
    N1, N2 : int
        Samples along θ₁ and θ₂ [-].
    """
    return 4 * H1 + 4, 4 * H2 + 4


def resize(Y: NDArray, old: TorusGrid, new: TorusGrid) -> NDArray[np.complex128]:
    """Harmonics on ``old``'s index set moved onto ``new``'s (missing ones zero).

    Parameters
    ----------
    Y : ndarray (n_c, |𝒦_old|) complex
        Harmonics [m].
    old, new : TorusGrid
        The index sets.

    Returns
    -------
    ndarray (n_c, |𝒦_new|) complex
        [m].
    """
    Y = np.atleast_2d(Y)
    pos = {(int(a), int(b)): i for i, (a, b) in enumerate(zip(old.k1, old.k2, strict=True))}
    out = np.zeros((Y.shape[0], new.n_terms), dtype=complex)
    for j, (a, b) in enumerate(zip(new.k1, new.k2, strict=True)):
        i = pos.get((int(a), int(b)))
        if i is not None:
            out[:, j] = Y[:, i]
    return out
