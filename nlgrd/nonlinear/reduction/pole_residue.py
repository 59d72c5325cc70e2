"""Pole-residue form of the inverse of a quadratic matrix polynomial in the frequency.

Along a sweep the speed follows the base frequency, so the dynamic stiffness at its k-th
harmonic is Z(ω) = A_0 + ω A_1 + ω² A_2. With the companion linearisation
C = [[0, I], [-A_2⁻¹ A_0, -A_2⁻¹ A_1]] = X diag(λ) X⁻¹ (Tisseur & Meerbergen 2001, SIAM
Rev. 43:235, §3.4), for any right-hand side b

    Z(ω)⁻¹ b = X_top diag(1 / (ω - λ)) L b,   L = (X⁻¹)[:, n:] A_2⁻¹,

and d/dω of it is -X_top diag(1 / (ω - λ)²) L b: after one eigendecomposition per
harmonic, a solve at any frequency costs a few matrix-vector products. The frequency is
scaled, ω = γ μ with γ² = ‖A_0‖ / ‖A_2‖, which balances the companion matrix (Fan, Lin &
Van Dooren 2004, SIAM J. Matrix Anal. Appl. 26:252).

The form is exact in exact arithmetic when C is diagonalisable; a defective or badly
conditioned X (an undamped rigid-body mode: a double pole at 0) shows in
:meth:`PoleResidue.check`, against a direct solve, and the caller solves directly then.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray

#: Largest relative difference from a direct solve at which the form is used.
POLE_CHECK_RTOL = 1e-8


@dataclass(frozen=True)
class PoleResidue:
    """Z(ω)⁻¹ = X_top diag(1 / (ω - λ)) L for Z(ω) = A_0 + ω A_1 + ω² A_2.

    Attributes
    ----------
    poles : ndarray (2n,)
        λ [rad/s] (the frequencies at which Z is singular).
    X_top : ndarray (n, 2n)
        The upper half of the companion eigenvectors.
    L : ndarray (2n, n)
        γ (X⁻¹)[:, n:] A_2⁻¹ [1/N].
    """

    poles: NDArray
    X_top: NDArray
    L: NDArray

    @classmethod
    def of(cls, A0: NDArray, A1: NDArray, A2: NDArray) -> PoleResidue:
        """Decompose Z(ω) = A0 + ω A1 + ω² A2 (dense, A2 invertible).

        Parameters
        ----------
        A0, A1, A2 : ndarray (n, n)
            The coefficients [N/m, N s/m, N s²/m].

        Returns
        -------
        PoleResidue
        """
        A0, A1, A2 = (np.asarray(a, dtype=complex) for a in (A0, A1, A2))
        g = float(np.sqrt(np.linalg.norm(A0) / np.linalg.norm(A2)))
        A1s, A2s = g * A1, g * g * A2
        n = A0.shape[0]
        lu = sla.lu_factor(A2s, check_finite=False)
        comp = np.zeros((2 * n, 2 * n), dtype=complex)
        comp[:n, n:] = np.eye(n)
        comp[n:, :n] = -sla.lu_solve(lu, A0, check_finite=False)
        comp[n:, n:] = -sla.lu_solve(lu, A1s, check_finite=False)
        mu, X = sla.eig(comp, overwrite_a=True, check_finite=False)
        Xi = sla.inv(X, check_finite=False)
        # 1 / (μ - μ_j) = γ / (ω - γ μ_j); A2s⁻¹ b on the lower block
        L = g * (sla.lu_solve(lu, Xi[:, n:].T, trans=1, check_finite=False).T)
        return cls(g * mu, np.ascontiguousarray(X[:n]), L)

    def weights(self, omega: float, power: int = 1) -> NDArray:
        """1 / (ω - λ)^power, (2n,) [s/rad]^power.

        Parameters
        ----------
        omega : float
            Frequency [rad/s].
        power : int
            1 for the solve, 2 for its derivative.

        Returns
        -------
        ndarray (2n,)
        """
        return (1.0 / (omega - self.poles)) ** power

    def solve(self, omega: float, rhs: NDArray, rows=None) -> NDArray:
        """Z(ω)⁻¹ rhs, on ``rows`` of the result (all by default).

        Parameters
        ----------
        omega : float
            Frequency [rad/s].
        rhs : ndarray (n,) or (n, m)
            Right-hand sides [N].
        rows : index, optional
            Rows of the solution wanted.

        Returns
        -------
        ndarray
        """
        Xt = self.X_top if rows is None else self.X_top[rows]
        w = self.weights(omega)
        y = self.L @ rhs
        return Xt @ (w[:, None] * y if y.ndim == 2 else w * y)

    def check_frequencies(self, count: int = 5) -> NDArray:
        """Frequencies for :meth:`check` across the poles' range, each midway (in log)
        between the two pole moduli around it: ``count`` targets log-spaced from the 5th to
        the 95th percentile of |λ|, moved off the poles (an undamped pole on the real axis
        makes Z singular there). Fixed by the model, not by the order of a sweep.

        Parameters
        ----------
        count : int
            Number of targets [-].

        Returns
        -------
        ndarray
            Distinct frequencies [rad/s].
        """
        mods = np.sort(np.abs(self.poles))
        mods = mods[mods > 1e-12 * mods[-1]]
        distinct = [mods[0]]
        for v in mods[1:]:  # ±λ of an undamped pair share a modulus
            if v > distinct[-1] * (1 + 1e-6):
                distinct.append(v)
        d = np.array(distinct)
        if d.size < 2:
            return np.array([2.0 * d[0]])
        targets = np.geomspace(*np.percentile(d, [5, 95]), count)
        i = np.clip(np.searchsorted(d, targets), 1, d.size - 1)
        return np.unique(np.sqrt(d[i - 1] * d[i]))

    def check(self, A0: NDArray, A1: NDArray, A2: NDArray, P: NDArray, omegas) -> float:
        """Largest relative difference of Pᵀ Z⁻¹ P from a direct solve at ``omegas``.

        Parameters
        ----------
        A0, A1, A2 : ndarray (n, n)
            The coefficients it was made from.
        P : ndarray (n, d)
            Projection.
        omegas : sequence of float
            Check frequencies [rad/s].

        Returns
        -------
        float
        """
        err = 0.0
        LP, CP = self.L @ P, P.T @ self.X_top
        for w in omegas:
            h = CP @ (self.weights(w)[:, None] * LP)
            try:
                hd = P.T @ np.linalg.solve(A0 + w * A1 + w * w * A2, P.astype(complex))
            except np.linalg.LinAlgError:
                return np.inf
            err = max(err, float(np.linalg.norm(h - hd) / np.linalg.norm(hd)))
        return err
