"""Real harmonics of periodic signals of the mesh angle θ = ω t (the solver's layout).

A signal is held as its *real harmonics*

    z = [x_0, a_1, b_1, a_2, b_2, ..., a_H, b_H]        (length 2H + 1)
    x(θ) = x_0 + Σ_k a_k cos kθ + b_k sin kθ

with the complex amplitude X_k = a_k - i b_k, so that x = Re Σ_k X_k e^{ikθ}
(:func:`real_to_complex`, :func:`complex_to_real`); sampling, analysis by FFT,
differentiation, and the Toeplitz form of the Jacobian of a force's harmonics.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError


def n_harmonics(z: ArrayLike) -> int:
    """Number of harmonics H of a real-harmonic vector of length 2H + 1.

    Parameters
    ----------
    z : array_like
        Real harmonics [x_0, a_1, b_1, ..., a_H, b_H] on the last axis (length 2H + 1), any
        leading shape (e.g. (n_nl, 2H+1)), in any unit.

    Returns
    -------
    int
        H [-].

    Raises
    ------
    ModelError
        When the last axis has an even length.
    """
    n = np.shape(z)[-1]
    if n % 2 != 1:
        raise ModelError("harmonics", f"a real-harmonic vector has odd length 2H+1, got {n}")
    return (n - 1) // 2


def resize_harmonics(z: ArrayLike, H: int) -> NDArray[np.float64]:
    """Truncate or zero-pad real harmonics (last axis) to ``H`` harmonics.

    Parameters
    ----------
    z : array_like
        Real harmonics [x_0, a_1, b_1, ...] on the last axis (odd length), any leading shape
        (e.g. (n_nl, 2H'+1)), in any unit.
    H : int
        Number of harmonics of the result.

    Returns
    -------
    ndarray (..., 2H+1)
        A new array in the unit of ``z``: its first 2H + 1 entries, or ``z`` followed by
        zeros.
    """
    z = np.asarray(z, dtype=float)
    n = 2 * H + 1
    if z.shape[-1] >= n:
        return z[..., :n].copy()
    out = np.zeros(z.shape[:-1] + (n,))
    out[..., : z.shape[-1]] = z
    return out


def real_to_complex(z: ArrayLike) -> NDArray[np.complex128]:
    """Complex amplitudes X_k = a_k - i b_k, k = 0..H, of real harmonics ``z`` (last axis).

    Parameters
    ----------
    z : array_like
        Real harmonics [x_0, a_1, b_1, ..., a_H, b_H] on the last axis (length 2H + 1), any
        leading shape, in any unit.

    Returns
    -------
    ndarray of complex (..., H+1)
        X_0 = x_0 and X_k = a_k - i b_k, in the unit of ``z``.

    Raises
    ------
    ModelError
        When the last axis has an even length.
    """
    z = np.asarray(z, dtype=float)
    H = n_harmonics(z)
    out = np.empty(z.shape[:-1] + (H + 1,), dtype=complex)
    out[..., 0] = z[..., 0]
    out[..., 1:] = z[..., 1::2] - 1j * z[..., 2::2]
    return out


def complex_to_real(X: ArrayLike) -> NDArray[np.float64]:
    """Real harmonics [x_0, a_1, b_1, ...] of complex amplitudes X_k, k = 0..H (last axis).

    The imaginary part of X_0 is discarded (a mean is real).

    Parameters
    ----------
    X : array_like of complex
        Complex amplitudes X_k = a_k - i b_k, k = 0..H, on the last axis (length H + 1),
        any leading shape, in any unit.

    Returns
    -------
    ndarray (..., 2H+1)
        Real harmonics [x_0, a_1, b_1, ..., a_H, b_H] in the unit of ``X``.
    """
    X = np.asarray(X, dtype=complex)
    H = X.shape[-1] - 1
    out = np.empty(X.shape[:-1] + (2 * H + 1,))
    out[..., 0] = X[..., 0].real
    out[..., 1::2] = X[..., 1:].real
    out[..., 2::2] = -X[..., 1:].imag
    return out


def evaluate(z: ArrayLike, theta: ArrayLike) -> NDArray[np.float64]:
    """Value of the trigonometric polynomial with real harmonics ``z`` (1-D) at angles ``theta`` [rad].

    Parameters
    ----------
    z : array_like
        Real harmonics [x_0, a_1, b_1, ..., a_H, b_H] (1-D, length 2H + 1), in any unit.
    theta : array_like
        Angles θ [rad], any shape.

    Returns
    -------
    ndarray
        x(θ) = x_0 + Σ_k a_k cos kθ + b_k sin kθ, shaped like ``theta``, in the unit of ``z``.
    """
    z = np.asarray(z, dtype=float)
    theta = np.asarray(theta, dtype=float)
    H = n_harmonics(z)
    if H == 0:
        return np.full(theta.shape, z[0])
    kt = np.multiply.outer(theta, np.arange(1, H + 1))
    return z[0] + np.cos(kt) @ z[1::2] + np.sin(kt) @ z[2::2]


def differentiate(z: ArrayLike, order: int = 1) -> NDArray[np.float64]:
    """Real harmonics of d^order x / dθ^order (multiply by ω^order for time derivatives).

    Parameters
    ----------
    z : array_like
        Real harmonics [x_0, a_1, b_1, ...] of x on the last axis (odd length), any leading
        shape, in any unit.
    order : int
        Order of the derivative, >= 0.

    Returns
    -------
    ndarray
        Real harmonics of d^order x / dθ^order, shaped like ``z``, in the unit of ``z`` per
        rad^order; times ω^order they are those of the time derivative (per s^order).
    """
    X = real_to_complex(z)
    k = np.arange(X.shape[-1])
    return complex_to_real(X * (1j * k) ** order)


def sample(z: ArrayLike, n_samples: int) -> NDArray[np.float64]:
    """Values at θ_j = 2πj/N, j = 0..N-1, by inverse FFT (N > 2H required).

    Parameters
    ----------
    z : array_like
        Real harmonics [x_0, a_1, b_1, ..., a_H, b_H] on the last axis (length 2H + 1), any
        leading shape (e.g. (n_nl, 2H+1)), in any unit.
    n_samples : int
        N, samples per period; more than 2H.

    Returns
    -------
    ndarray (..., N)
        x(θ_j) in the unit of ``z``.

    Raises
    ------
    ModelError
        When ``n_samples`` <= 2H.
    """
    z = np.asarray(z, dtype=float)
    H = n_harmonics(z)
    if n_samples <= 2 * H:
        raise ModelError("n_samples", f"needs more than 2H = {2 * H} samples, got {n_samples}")
    spec = np.zeros(z.shape[:-1] + (n_samples // 2 + 1,), dtype=complex)
    spec[..., : H + 1] = real_to_complex(z) * (n_samples / 2)
    spec[..., 0] = z[..., 0] * n_samples
    return np.fft.irfft(spec, n=n_samples, axis=-1)


def analyse(samples: ArrayLike, H: int) -> NDArray[np.float64]:
    """Real harmonics 0..H of equally spaced samples over one period (forward FFT).

    Parameters
    ----------
    samples : array_like
        x(θ_j) at θ_j = 2πj/N, j = 0..N-1, on the last axis, any leading shape, in any unit.
    H : int
        Number of harmonics returned; N must exceed 2H.

    Returns
    -------
    ndarray (..., 2H+1)
        Real harmonics [x_0, a_1, b_1, ..., a_H, b_H] in the unit of ``samples``.

    Raises
    ------
    ModelError
        When N <= 2H.
    """
    samples = np.asarray(samples, dtype=float)
    N = samples.shape[-1]
    if N <= 2 * H:
        raise ModelError("H", f"{N} samples resolve at most {(N - 1) // 2} harmonics, asked {H}")
    spec = np.fft.rfft(samples, axis=-1)[..., : H + 1] * (2.0 / N)
    spec[..., 0] /= 2
    return complex_to_real(spec)


def real_complex_maps(H: int) -> tuple[NDArray, NDArray, NDArray]:
    """P: real (2H+1) -> complex c_m, m = -H..H; rows to pick Re/Im for G assembly.

    Parameters
    ----------
    H : int
        Number of harmonics.

    Returns
    -------
    P : ndarray of complex (2H+1, 2H+1)
        c = P z: the two-sided Fourier coefficients c_m (row H + m) of the real harmonics
        z = [x_0, a_1, b_1, ...]: c_0 = x_0, c_{±m} = (a_m ∓ i b_m) / 2.
    k : ndarray of int (H+1,)
        0..H, the one-sided harmonics of the rows of a force's coefficients ĝ_k.
    m : ndarray of int (2H+1,)
        -H..H, the harmonics of the rows of P; ``S[n0 + k[:, None] - m[None, :]]`` is the
        Toeplitz matrix S_{k-m} of :func:`toeplitz_jacobian`.
    """
    P = np.zeros((2 * H + 1, 2 * H + 1), dtype=complex)
    P[H, 0] = 1.0
    m = np.arange(1, H + 1)
    P[H + m, 2 * m - 1] = 0.5
    P[H + m, 2 * m] = -0.5j
    P[H - m, 2 * m - 1] = 0.5
    P[H - m, 2 * m] = 0.5j
    m = np.arange(-H, H + 1)
    k = np.arange(0, H + 1)
    return P, k, m


def complex_rows_to_real(rows: NDArray) -> NDArray:
    """Map complex coefficients ĝ_k, k = 0..H (first axis) to real rows [G_0, G_a1, G_b1, ...].

    Parameters
    ----------
    rows : ndarray of complex (H+1, ...)
        One-sided Fourier coefficients ĝ_k = (1/2π) ∫ g(θ) e^{-ikθ} dθ of a real g, k = 0..H
        on the first axis (a vector, or rows of a Jacobian), in any unit.

    Returns
    -------
    ndarray (2H+1, ...)
        Real harmonics [g_0, a_1, b_1, ...] = [Re ĝ_0, 2 Re ĝ_1, -2 Im ĝ_1, ...] on the first
        axis, in the unit of ``rows``.
    """
    H = rows.shape[0] - 1
    out = np.empty((2 * H + 1,) + rows.shape[1:])
    out[0] = rows[0].real
    out[1::2] = 2 * rows[1:].real
    out[2::2] = -2 * rows[1:].imag
    return out


def toeplitz_jacobian(S: NDArray, n0: int, H: int, gain: float) -> NDArray:
    """Real Jacobian gain · (Fourier projection of indicator × basis) from its spectrum.

    ``S[n0 + n]`` holds S_n = (1/2π) ∫ s(θ) e^{-inθ} dθ for n in [-2H, 2H] at least.

    Parameters
    ----------
    S : ndarray of complex (n0 + 2H + 1 at least,)
        Two-sided spectrum S_n of s(θ), S_0 at index ``n0``: of the contact indicator
        (dimensionless) or of a tangent stiffness dg/du [N/m].
    n0 : int
        Index of S_0 in ``S``.
    H : int
        Number of harmonics of the force and of the coordinate.
    gain : float
        Factor of the product: k_h [N/m] with the contact indicator, 1 with a tangent.

    Returns
    -------
    ndarray (2H+1, 2H+1)
        dG/dz of the real harmonics G of gain · s(θ) x(θ) with respect to the real harmonics
        z = [x_0, a_1, b_1, ..., a_H, b_H] of x, in the unit of ``gain`` times that of ``S``.
    """
    P, k, m = real_complex_maps(H)
    T = S[n0 + k[:, None] - m[None, :]]  # (H+1) x (2H+1): T[k, m] = S_{k-m}
    return gain * complex_rows_to_real(T @ P)
