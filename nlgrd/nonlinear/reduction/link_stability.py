"""The linear state space of a link model for Floquet stability, on a truncated basis.

Where every link of a model is a gear mesh or a bearing clearance (:func:`truncatable`),
Floquet multipliers are taken on the modes of (K + K_L, M) below
:data:`STABILITY_CUTOFF` times the highest base harmonic a mesh or an unbalance sits at
plus the static attachment vectors (K + K_L + M)⁻¹ P of the link coordinates (the
single-mesh path's basis; K_L the links' linear stiffness). Each state space carries the
one on twice the cut-off and the full one, with which
:func:`nlgrd.nonlinear.stability.floquet.floquet_analysis` checks the truncation where the
orbit's tangent varies over the period (docs/conventions.md, "Stability state space"):
a clearance's contact varies the tangent at every point, so every point of a clearance
model is checked, and the full state decides where the check fails.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cached_property

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from nlgrd.cache import BoundedCache
from nlgrd.nonlinear.links.contract import BearingClearance, GearMeshLink
from nlgrd.nonlinear.reduction.modal_basis import STABILITY_MODE_CAP, lowest_modes, modes_then_attachments
from nlgrd.nonlinear.reduction.state_space import FloquetCache, LinearStateSpace
from nlgrd.rotor.assembly import LinearModel

#: Modes below this times the highest mesh frequency, with the static attachment vectors.
STABILITY_CUTOFF = 3.0
#: State spaces kept per model, one per frequency (a sweep's passes come back to them).
SPACES_KEPT = 64
#: Up to this many DOFs the modes come from a dense generalised eigenproblem (faster
#: than ARPACK's shift-invert there).
DENSE_MODES_LIMIT = 300


def truncatable(links) -> bool:
    """Whether a model with ``links`` takes the truncated basis: at least one link, each a
    gear mesh or a bearing clearance (the laws whose checks on twice the cut-off and the
    full state are measured: docs/conventions.md, "Stability state space").

    Parameters
    ----------
    links : sequence
        The model's nonlinear links.

    Returns
    -------
    bool
    """
    return bool(links) and all(isinstance(lk, (GearMeshLink, BearingClearance)) for lk in links)


class TruncatedStability:
    """Stability state spaces of a link model on the truncated basis (module docstring).

    Parameters
    ----------
    model : LinearModel
        The linear model without the links' stiffness and damping.
    P : ndarray (n_dofs, d)
        The links' projections.
    K_link, C_link : sparse matrix (n_dofs, n_dofs)
        The links' linear stiffness [N/m] and damping [N s/m] on the DOFs.
    top_order : int
        The highest base harmonic a mesh sits at [-].

    Attributes
    ----------
    top : float or None
        The highest base frequency the basis serves [rad/s] (:meth:`prepare`).
    """

    def __init__(self, model: LinearModel, P: NDArray, K_link, C_link, top_order: int = 1):
        self.model, self.P, self.K_link, self.C_link = model, P, K_link, C_link
        self.top_order, self.top = int(top_order), None
        # per frequency the state spaces (a sweep's grid: each pass comes back to them), those
        # on twice the cut-off and the full ones (larger: fewer kept); the bases per cut-off;
        # one store of Floquet work
        self._spaces, self._larger, self._full = BoundedCache(SPACES_KEPT), BoundedCache(16), BoundedCache(4)
        self._bases, self._floquet = BoundedCache(8), FloquetCache(4096)
        self._kept_modes: tuple = (0.0, None)  # (up to [rad/s], eigenpairs) of the dense case
        self._rates = BoundedCache(8)  # the dropped modes' decay rates per cut-off (and speed)

    def prepare(self, top: float) -> None:
        """Size the basis for base frequencies up to ``top`` [rad/s] (a sweep's highest):
        modes below :data:`STABILITY_CUTOFF` x ``top_order`` x ``top``. A basis already that
        large is kept.

        Parameters
        ----------
        top : float
            Highest base frequency [rad/s].
        """
        top = float(top)
        if np.isfinite(top) and top > 0 and (self.top is None or top > self.top):
            self.top = top

    def basis(self, cutoff: float) -> tuple[NDArray, tuple]:
        """Modes of (K + K_L, M) below ``cutoff`` [rad/s] and the static attachment vectors
        (K + K_L + M)⁻¹ P, M-orthonormal, modes first, with the matrices' parts linear in the
        speed projected on it (M, C, G, K, K_c, P); tabulated bearings at rest.

        Parameters
        ----------
        cutoff : float
            Highest natural frequency kept [rad/s].

        Returns
        -------
        tuple
            The basis (n_dofs, m) and the projected parts.
        """

        def make():
            m = self.model
            Kr = (m.stiffness(0.0) + self.K_link).tocsc()
            lam, vec = self._modes(Kr, cutoff)
            att = spla.splu((Kr + m.M).tocsc()).solve(self.P)
            S = modes_then_attachments(vec[:, lam <= cutoff**2], att, m.M)
            parts = (m.M, m.C + m.Ci + self.C_link, m.G, m.K, m.Kc)
            return S, tuple(S.T @ (A @ S) for A in parts) + (S.T @ self.P,)

        return self._bases.get(float(cutoff), make)

    def _modes(self, Kr, cutoff: float) -> tuple[NDArray, NDArray]:
        """Eigenpairs of (K_r, M) up to ``cutoff`` at least [rad/s]: dense ones up to twice
        it, kept (the check's basis takes them too), or ARPACK's."""
        m = self.model
        if m.n_dofs > DENSE_MODES_LIMIT:
            return lowest_modes(Kr, m.M, cutoff, start=30, cap=STABILITY_MODE_CAP, what="stability basis")
        top, pairs = self._kept_modes
        if top < cutoff:
            top = 2 * cutoff
            pairs = sla.eigh(Kr.toarray(), m.M.toarray(), subset_by_value=(-np.inf, top**2))
            self._kept_modes = (top, pairs)
        return pairs

    def dropped(self, cutoff: float, speed: float, omega: float) -> float:
        """Largest multiplier modulus of the modes of (K + K_L, M) above ``cutoff``, which
        the basis drops, to first order in their damping: exp(-φⱼᵀ D φⱼ T / 2) of the
        M-normalised modes φⱼ at the period T = 2π/ω (Rayleigh's first-order decay rate; the
        gyroscopic part of D is skew and adds nothing). 1 for an undamped dropped mode (a
        rotor's torsion without damping), which no check on the kept modes sees.

        Parameters
        ----------
        cutoff : float
            The basis's cut-off [rad/s].
        speed : float
            Reference shaft speed [rad/s] (tabulated bearings' damping).
        omega : float
            Base frequency [rad/s].

        Returns
        -------
        float
            The estimate [-], 0 when no mode is dropped.
        """

        def rates():
            lam, vec = self._all_modes
            V = vec[:, lam > cutoff**2]
            m = self.model
            C = m.C + m.Ci + self.C_link
            if m.tabulated_bearings:
                C = C + m._bearing_matrices(speed)[1]
            return 0.5 * np.einsum("ij,ij->j", V, C @ V)

        key = (float(cutoff), float(speed) if self.model.tabulated_bearings else None)
        sigma = self._rates.get(key, rates)
        return float(np.exp(-sigma.min() * 2 * np.pi / omega)) if sigma.size else 0.0

    @cached_property
    def _all_modes(self) -> tuple[NDArray, NDArray]:
        """Every eigenpair of (K + K_L, M), M-normalised (dense, once per model)."""
        m = self.model
        return sla.eigh((m.stiffness(0.0) + self.K_link).toarray(), m.M.toarray())

    def state_space(self, omega: float, speed: float) -> LinearStateSpace:
        """The state space at base frequency ``omega`` on the basis of the top frequency
        (:meth:`prepare`, or ``omega`` when higher), with its ``larger`` and ``full`` ones.

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].
        speed : float
            Reference shaft speed at ``omega`` [rad/s].

        Returns
        -------
        LinearStateSpace
        """
        self.prepare(omega)
        cutoff = STABILITY_CUTOFF * self.top_order * self.top
        key = (float(omega), float(speed), cutoff)

        def make():  # larger and full are built where a tangent varies
            def larger():
                return self._larger.get(
                    key,
                    lambda: self._on_basis(
                        self.basis(2 * cutoff), speed, dropped=self.dropped(2 * cutoff, speed, omega)
                    ),
                )

            def full():
                return self._full.get(key, lambda: self.full_state(speed, shared=True))

            dropped = self.dropped(cutoff, speed, omega)
            return self._on_basis(self.basis(cutoff), speed, larger, full, dropped)

        return self._spaces.get(key, make)

    def full_state(self, speed: float, shared: bool = False) -> LinearStateSpace:
        """The full (dense) state space at reference speed ``speed`` [rad/s].

        Parameters
        ----------
        speed : float
            Reference shaft speed [rad/s].
        shared : bool
            Give it the model's store of Floquet work (the check of a truncated basis):
            what does not depend on the speed (M⁻¹K, M⁻¹W, the null spaces of K and of
            K + W K_t Wᵀ, keyed by content) is computed once per model, and a frequency
            the sweep comes back to reuses its multipliers within ``REVISIT_RTOL``
            (:func:`nlgrd.nonlinear.stability.floquet.floquet_multipliers`).

        Returns
        -------
        LinearStateSpace
        """
        m = self.model
        mats = (m.M, m.damping(speed) + self.C_link, m.stiffness(speed))
        return LinearStateSpace(*(A.toarray() for A in mats), self.P, cache=self._floquet if shared else None)

    def _on_basis(
        self,
        basis: tuple,
        speed: float,
        larger: Callable | None = None,
        full: Callable | None = None,
        dropped: float = 0.0,
    ) -> LinearStateSpace:
        S, (M, C, G, K, Kc, Ps) = basis
        D, K = C + speed * G, K + speed * Kc
        if self.model.tabulated_bearings:
            Kb, Cb = self.model._bearing_matrices(speed)
            D, K = D + S.T @ (Cb @ S), K + S.T @ (Kb @ S)
        return LinearStateSpace(M, D, K, Ps, cache=self._floquet, larger=larger, full=full, dropped=dropped)
