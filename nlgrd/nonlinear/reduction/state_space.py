"""The linear part of a harmonic-balance model as dense matrices, for Floquet stability.

:class:`LinearStateSpace` holds M, D, K and the projection W onto the nonlinear
coordinates, its rigid-body modes and the deflated system without them
(:mod:`nlgrd.nonlinear.stability.floquet` computes the multipliers).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from nlgrd.cache import BoundedCache
from nlgrd.errors import ModelError
from nlgrd.nonlinear.reduction.linear_algebra import free_modes as _free_modes
from nlgrd.nonlinear.reduction.linear_algebra import stiffness_null_space
from nlgrd.rotor.rigid_body import complement, rigid_body_modes

#: Why a model with hysteretic damping (a loss factor) has no Floquet stability, on every
#: path (docs/conventions.md, "Hysteretic damping"): said in one line, under ``loss_factor``.
HYSTERETIC_REFUSAL = (
    "hysteretic damping has no time-domain form, so no Floquet stability (nor time integration): "
    "give viscous damping instead, or sweep without stability"
)


class FloquetCache(BoundedCache):
    """A bounded store (first in, first out) of Floquet work: one per state space, or one
    shared by the state spaces of a model (``LinearStateSpace(..., cache=...)``).

    Keys are tuples of hashables; :meth:`get` computes a missing entry with ``make``.

    Parameters
    ----------
    maxsize : int
        Most entries kept (default 16); the oldest goes first.
    """


@dataclass(frozen=True)
class LinearStateSpace:
    """Linear part M q'' + D q' + K q = -W g(Wᵀq, t) + forcing, for stability analysis.

    Dense matrices (N x N) and the projection W (N x n_nl) onto the nonlinear
    coordinates y = Wᵀ q. K excludes the nonlinear elements' stiffness (the mesh k_h);
    D includes the mesh damping. For the single-DOF gear pair M = [[m_eq]], D = [[c_m]],
    K = [[0]], W = [[1]].

    ``cache``: an optional :class:`nlgrd.nonlinear.reduction.state_space.FloquetCache` shared by the state
    spaces of one model (one per mesh frequency): Floquet work is then found again when
    a sweep comes back to a frequency (the down sweep after the up sweep), keyed by the
    matrices' :attr:`digest`. Without it each state space keeps its own
    (:attr:`floquet_cache`).

    Parameters
    ----------
    M : array_like or sparse matrix (N, N)
        Mass matrix [kg, kg m²] (per DOF: translation, rotation); stored dense.
    D : array_like or sparse matrix (N, N)
        Damping matrix with the mesh damping [N s/m, N m s/rad]; stored dense.
    K : array_like or sparse matrix (N, N)
        Stiffness matrix without the nonlinear elements' stiffness [N/m, N m/rad]; stored dense.
    W : array_like (N, n_nl)
        Projection onto the nonlinear coordinates y = Wᵀ q (a mesh's projection vector w:
        [-] on translations, base radii [m] on rotations).
    cache : FloquetCache, optional
        Shared store of Floquet work (see above).
    larger, full : callable () -> LinearStateSpace, optional
        For a state space on a truncated modal basis: the one on the basis with twice its
        cut-off and the whole model's, with which Floquet analysis checks the truncation
        where the orbit's tangent varies over the period
        (:func:`nlgrd.nonlinear.stability.floquet.floquet_analysis`).
    dropped : float, optional
        For a state space on a truncated basis: the largest multiplier modulus of the modes
        it drops, to first order in their damping [-] (0: none); Floquet analysis takes
        ``full`` where it exceeds the kept result's max |μ| by more than ``TRUNCATION_ATOL``.

    Raises
    ------
    ModelError
        When M, D, K are not N x N or W has not N rows.
    """

    M: NDArray
    D: NDArray
    K: NDArray
    W: NDArray
    cache: FloquetCache | None = field(default=None, compare=False, repr=False)
    larger: Callable[[], LinearStateSpace] | None = field(default=None, compare=False, repr=False)
    full: Callable[[], LinearStateSpace] | None = field(default=None, compare=False, repr=False)
    dropped: float = field(default=0.0, compare=False, repr=False)

    def __post_init__(self):
        for name in ("M", "D", "K", "W"):
            val = getattr(self, name)
            val = val.toarray() if hasattr(val, "toarray") else np.asarray(val, dtype=float)
            object.__setattr__(self, name, np.atleast_2d(val))
        N = self.M.shape[0]
        if self.D.shape != (N, N) or self.K.shape != (N, N) or self.W.shape[0] != N:
            raise ModelError("state_space", "M, D, K must be N x N and W N x n_nl")

    def keeps(self, top: float, atol: float) -> bool:
        """Whether max |μ| = ``top`` on this state space stands for the whole model's: its
        dropped modes' multiplier :attr:`dropped` is at most ``top`` + ``atol``, so none
        of them can raise max |μ| by more (always where none are dropped).

        Parameters
        ----------
        top : float
            Largest multiplier modulus on this state space [-].
        atol : float
            Required margin [-].

        Returns
        -------
        bool
        """
        return self.dropped <= 0 or self.dropped <= top + atol

    def rigid_body_modes(self) -> NDArray:
        """M-orthonormal basis (N, r) of the free modes: K φ = 0, D φ = 0 and Wᵀ φ = 0.

        These move no nonlinear element and are neither restrained nor damped (the
        torsional rigid-body rotation of a whole free drive train); they give neutral
        Floquet multipliers μ = 1 in a Jordan block. Decided by the fast
        :func:`nlgrd.nonlinear.reduction.linear_algebra.free_modes` when it can (the tolerances of
        :func:`nlgrd.rotor.rigid_body.rigid_body_modes`), else by ``rigid_body_modes``. Both
        see a free mode that a projected basis holds as one of its vectors (the stability
        basis of a free drive train, Kubo's rig), whose stiffness diagonal is rounding.
        """
        null = None
        if self.cache is not None:  # K alone: the same at every speed of a sweep
            key = ("k-null", hashlib.blake2b(np.ascontiguousarray(self.K).tobytes(), digest_size=20).digest())
            null = self.cache.get(key, lambda: stiffness_null_space(self.K))
        F = _free_modes(self.K, self.D, self.W, null)
        if F is None:
            Ksym = (self.K + self.K.T) / 2
            return rigid_body_modes(Ksym, self.M, constraints=(self.K, self.D, self.W.T))
        if F.shape[1] == 0:
            return F
        L = np.linalg.cholesky(F.T @ self.M @ F)
        return np.linalg.solve(L, F.T).T  # M-orthonormal: Rᵀ M R = I

    @cached_property
    def deflated(self) -> LinearStateSpace:
        """The same system in the M-orthogonal complement of :meth:`rigid_body_modes`.

        With q = Φ η + P r, Pᵀ M Φ = 0, the rigid-body coordinates η decouple exactly
        (KΦ = DΦ = 0, WᵀΦ = 0), so the stability of the periodic solution is that of r.
        """
        if self.cache is None:
            phi = self.rigid_body_modes()
        else:
            phi = self.cache.get(("rigid", self.digest), self.rigid_body_modes)
        if phi.shape[1] == 0:
            return self
        P = complement(phi, self.M)
        return LinearStateSpace(
            P.T @ self.M @ P, P.T @ self.D @ P, P.T @ self.K @ P, P.T @ self.W, cache=self.cache
        )

    @cached_property
    def digest(self) -> bytes:
        """Hash of M, D, K, W (the key of this state space's entries in a shared cache)."""
        h = hashlib.blake2b(digest_size=20)
        for a in (self.M, self.D, self.K, self.W):
            a = np.ascontiguousarray(a)
            h.update(str(a.shape).encode())
            h.update(a.tobytes())
        return h.digest()

    @cached_property
    def floquet_cache(self) -> FloquetCache:
        """This state space's own bounded store of Floquet work (factorisations, certificates)."""
        return FloquetCache()


# --------------------------------------------------------------------------------------
# Solution object and solvers
# --------------------------------------------------------------------------------------
