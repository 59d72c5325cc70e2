"""Pole-residue form of the link receptance, shifted by the links' linear stiffness.

Z_k (the links left out) is singular at ω = 0 wherever a link is the only connection (a
shaft's torsion behind a mesh, a journal in a clearance bearing): a cluster of poles at
zero with ill-conditioned eigenvectors, so that the form's error, and whether it passes
its check, would depend on rounding. The form is therefore made of the shifted
Z'_k = Z_k + P K Pᵀ (K = diag(k_j) the links' linear stiffness, K > 0, which leaves only
the rigid-body modes of the linearised system, the shift the mean problem uses), and by
the Sherman-Morrison-Woodbury identity, with h' = Pᵀ Z'⁻¹ P,

    κ_k = h'⁻¹ - K,    F_k = κ_k Pᵀ Z⁻¹ f_k = h'⁻¹ Pᵀ Z'⁻¹ f_k,

exact for any K. A solve with Z_k itself follows from one with Z'_k:
x = x' + Z'⁻¹ P K y with y = Pᵀ x = (I - h' K)⁻¹ Pᵀ x' and x' = Z'⁻¹ b.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nlgrd.nonlinear.reduction.pole_residue import PoleResidue


@dataclass(frozen=True)
class LinkPoleForm:
    """One harmonic's shifted pole-residue form on the link coordinates.

    Attributes
    ----------
    pr : PoleResidue
        The form of Z'_k = Z_k + P K Pᵀ in the solve coordinates.
    CP : ndarray (d, 2n)
        Pᵀ X_top.
    LP : ndarray (2n, d)
        L P.
    k_link : ndarray (d, d)
        K, the links' linear stiffness [N/m].
    """

    pr: PoleResidue
    CP: NDArray
    LP: NDArray
    k_link: NDArray

    def _shifted_kappa(self, w: NDArray) -> NDArray:
        return np.linalg.inv(self.CP @ (w[:, None] * self.LP))

    def terms(self, omega: float, Lf: NDArray) -> tuple[NDArray, NDArray]:
        """κ_k (d, d) [N/m] and F_k (d,) [N] at base frequency ``omega`` [rad/s].

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].
        Lf : ndarray (2n,)
            L f_k, the form's left factor applied to the harmonic's forces.

        Returns
        -------
        tuple of ndarray
        """
        w = self.pr.weights(omega)
        kp = self._shifted_kappa(w)
        return kp - self.k_link, kp @ (self.CP @ (w * Lf))

    def derivatives(self, omega: float, Lf: NDArray, dLf: NDArray) -> tuple[NDArray, NDArray]:
        """dκ_k/dω (d, d) [N s/m] and dF_k/dω (d,) [N s]; d/dω of 1/(ω - λ) is -1/(ω - λ)².

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].
        Lf, dLf : ndarray (2n,)
            L f_k and its ω-derivative.

        Returns
        -------
        tuple of ndarray
        """
        w = self.pr.weights(omega)
        kp = self._shifted_kappa(w)
        dkap = kp @ (self.CP @ ((w * w)[:, None] * self.LP)) @ kp
        du = self.CP @ (w * dLf - w * w * Lf)
        return dkap, dkap @ (self.CP @ (w * Lf)) + kp @ du

    def solve(self, omega: float, rhs: NDArray, rows=None) -> NDArray:
        """Z_k(ω)⁻¹ rhs (the unshifted dynamic stiffness), on ``rows`` (all by default).

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].
        rhs : ndarray (n,)
            Right-hand side in the solve coordinates [N].
        rows : index, optional
            Rows of the solution wanted.

        Returns
        -------
        ndarray
        """
        w = self.pr.weights(omega)
        wy = w * (self.pr.L @ rhs)
        y = np.linalg.solve(
            np.eye(self.k_link.shape[0]) - self.CP @ (w[:, None] * self.LP) @ self.k_link, self.CP @ wy
        )
        Xt = self.pr.X_top if rows is None else self.pr.X_top[rows]
        return Xt @ (wy + w * (self.LP @ (self.k_link @ y)))
