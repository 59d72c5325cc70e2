"""The dominant Floquet multiplier of a periodic solution and its eigenvector.

Where a sweep leaves an unstable orbit (``SweepResult.no_stable``, ``dominant_multiplier``)
the direction in which the orbit departs is the eigenvector v of the monodromy matrix Φ
(from θ = 0, in the state (q, q') of the state space) for its dominant multiplier μ:
a perturbation ε v grows as ε μ^j v over j periods. It is what a period-doubling branch
switch starts from (μ < -1). Computed on demand from the stored harmonics, not per point.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.nonlinear.results.sweep_results import instability_kind
from nlgrd.nonlinear.stability.floquet import expm_monodromy
from nlgrd.nonlinear.stability.tangent import tangent_pieces


@dataclass(frozen=True)
class FloquetMode:
    """Dominant multiplier ``multiplier`` and its unit eigenvector ``vector`` (2N: q then q',
    complex; for a real μ its phase makes it real) of the monodromy ``monodromy`` (from θ = 0).

    Attributes
    ----------
    multiplier : complex
        The multiplier μ of largest modulus [-] (imaginary part 0 when real).
    vector : ndarray of complex (2N,)
        Its eigenvector, unit 2-norm, in the state (q, q') of the state space.
    monodromy : ndarray (2N, 2N)
        Φ from θ = 0 in the state (q, q') (:func:`monodromy_from_zero`).
    """

    multiplier: complex
    vector: NDArray[np.complex128]
    monodromy: NDArray[np.float64]

    @property
    def kind(self) -> str:
        """The instability: "real > 1", "real < -1", "complex", or "stable" (|μ| <= 1)."""
        mu = self.multiplier
        return instability_kind(np.array([mu]), np.array([abs(mu) <= 1]))[0] or "stable"


def monodromy_from_zero(
    state_space, nonlinearities: Sequence, harmonics: ArrayLike, omega: float
) -> NDArray[np.float64]:
    """Φ = Π exp(A_i Δt_i) over the contact intervals from θ = 0 (the first acts first), in
    the state (q, q') of ``state_space``: :func:`nlgrd.nonlinear.stability.floquet.expm_monodromy` (scipy's
    ``expm``, no deflation, no scaling). A state space on a truncated basis with its
    ``full`` one: in the full one's state.

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
    ndarray (2N, 2N)
        Φ: (q, q') at θ = 0 to (q, q') one period later.
    """
    Y = np.atleast_2d(np.asarray(harmonics, dtype=float))
    if getattr(state_space, "full", None) is not None:  # a truncated basis: the whole model's
        state_space = state_space.full()
    breaks, Kt = tangent_pieces(nonlinearities, Y, state_space.W.shape[1])
    return expm_monodromy(state_space, breaks, Kt, omega)


def dominant_floquet_mode(
    state_space, nonlinearities: Sequence, harmonics: ArrayLike, omega: float
) -> FloquetMode:
    """The multiplier of largest modulus of :func:`monodromy_from_zero` and its eigenvector
    (unit 2-norm; a real μ gets a real vector, sign fixed by its largest entry positive).
    Free rigid-body modes give μ = 1; they do not hide an unstable multiplier.

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
    FloquetMode
        The multiplier, its eigenvector and the monodromy matrix.
    """
    Phi = monodromy_from_zero(state_space, nonlinearities, harmonics, omega)
    lam, V = np.linalg.eig(Phi)
    j = int(np.argmax(np.abs(lam) + 1e-12 * np.sign(lam.imag)))  # of a pair: Im >= 0
    mu, v = complex(lam[j]), V[:, j].astype(complex)
    if abs(mu.imag) <= 1e-6 * abs(mu):
        mu = complex(mu.real, 0.0)
        v = v * np.exp(-1j * np.angle(v[np.argmax(np.abs(v))]))
        v = v.real.astype(complex)
    return FloquetMode(mu, v / np.linalg.norm(v), Phi)
