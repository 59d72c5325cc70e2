"""The mean (k = 0) problem of the link reduction: the static stiffness with the links'
linear stiffness in, K_r = Z_0 + K_L, solved with a border that holds the rigid-body modes
R (a drive line's free rotation) M-orthogonal, R M x = 0, and the reduced terms that do
not change along a sweep unless the stiffness depends on the speed."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from nlgrd.cache import BoundedCache
from nlgrd.rotor.assembly import LinearModel


class MeanProblem:
    """K_r x = b with x M-orthogonal to the rigid-body modes, factorised once per speed.

    Parameters
    ----------
    model : LinearModel
        The linear model, links left out.
    K_link : sparse matrix (n, n)
        The links' linear stiffness on the DOFs [N/m].
    P : ndarray (n, d)
        The links' projection [-].
    static_force : ndarray (n,)
        Static loads [N, N m].
    rigid : ndarray (n, r)
        Rigid-body modes of K_r [-].
    speed_dependent : bool
        Whether K_r depends on the speed (tabulated bearings, circulatory terms).
    """

    def __init__(
        self,
        model: LinearModel,
        K_link,
        P: NDArray,
        static_force: NDArray,
        rigid: NDArray,
        speed_dependent: bool,
    ):
        self.model, self.K_link, self.P, self.static_force = model, K_link, P, static_force
        self.rigid, self.speed_dependent = rigid, speed_dependent
        self._cache = BoundedCache(16)

    def _key(self, what: str, speed: float) -> tuple:
        return (what, float(speed) if self.speed_dependent else 0.0)

    def _factor(self, speed: float):
        def make():
            Kr = (self.model.dynamic_stiffness(0.0, speed) + self.K_link).tocsc()
            Kr = sp.csc_matrix((np.ascontiguousarray(Kr.data.real), Kr.indices, Kr.indptr), shape=Kr.shape)
            R = self.rigid
            if R.shape[1] == 0:
                return spla.splu(Kr), 0
            MR = sp.csc_matrix(self.model.M @ R)
            return spla.splu(sp.bmat([[Kr, MR], [MR.T, None]], format="csc")), R.shape[1]

        return self._cache.get(self._key("factor", speed), make)

    def solve(self, speed: float, rhs: NDArray) -> NDArray:
        """x with K_r x = rhs, M-orthogonal to the rigid-body modes.

        Parameters
        ----------
        speed : float
            Reference shaft speed [rad/s].
        rhs : ndarray (n_dofs, m)
            Right-hand sides [N].

        Returns
        -------
        ndarray (n_dofs, m)
        """
        lu, r = self._factor(speed)
        n = self.model.n_dofs
        pad = np.zeros((r,) + rhs.shape[1:])
        return lu.solve(np.concatenate([rhs, pad]))[:n]

    def terms(self, speed: float) -> tuple[NDArray, NDArray, NDArray]:
        """h_0 = Pᵀ K_r⁻¹ P, its inverse and Pᵀ K_r⁻¹ f_s (f_s the static loads), kept per
        speed: by linearity the mean problem then costs O(d²) per point, whatever the
        model's size.

        Parameters
        ----------
        speed : float
            Reference shaft speed [rad/s].

        Returns
        -------
        tuple of ndarray
            (d, d) [m/N], (d, d) [N/m], (d,) [m].
        """

        def make():
            d = self.P.shape[1]
            x = self.solve(speed, np.column_stack([self.P, self.static_force]))
            h0 = self.P.T @ x[:, :d]
            return h0, np.linalg.inv(h0), self.P.T @ x[:, d]

        return self._cache.get(self._key("terms", speed), make)
