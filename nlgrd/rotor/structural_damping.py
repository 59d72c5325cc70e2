"""Damping of the whole FE rotor: a modal damping floor and Rayleigh damping.

The model file's ``[damping]`` table (:class:`StructuralDamping`) adds a viscous damping
matrix to the assembled C, so that every analysis (modes, frequency response, harmonic
balance, Floquet stability, time integration) sees it:

- Rayleigh damping C_R = α M + β K (Rayleigh 1877; Clough & Penzien, Dynamics of
  Structures, 2003, §12.4): a mode of K φ = ω² M φ gets ζ = α / (2 ω) + β ω / 2.
- A modal floor ζ_min: with Φ the mass-normalised elastic modes (Φᵀ M Φ = I) and
  ζ_i = φ_iᵀ C φ_i / (2 ω_i) the modal damping ratio the model already has (C with
  Rayleigh included), C_F = M Φ diag(2 ω_i max(0, ζ_min - ζ_i)) Φᵀ M adds to each mode
  what it lacks (the modal damping matrix of Clough & Penzien §12.5, restricted to the
  shortfall): φ_iᵀ (C + C_F) φ_i = 2 ω_i max(ζ_i, ζ_min). It is exact where C is modal.

Both act on the linear model at rest, linearised about the loaded mesh: M and K with
the bearings (tabulated ones at speed 0), the couplings and every gear mesh at its
mean stiffness k_h, C with the bearings, couplings, mesh damping c_m and the internal
viscous damping. The mesh stiffness is in because the modes a sweep excites are those
of the gears in contact: Kahraman & Blankenship's weakly damped 741 Hz mode exists only
with k_h (without it each shaft turns freely). Rigid-body modes
(:func:`nlgrd.rotor.rigid_body.rigid_body_modes`, the scaled null-space test) get no
floor: C_F is built on their M-orthogonal complement, so C_F R = 0. The matrix is built
per connected component of the sparsity graph of M, K and C, so DOF groups that are
exactly uncoupled (axial bars, say) stay uncoupled. The floor is a dense eigenproblem
per component: it is refused above :data:`FLOOR_DENSE_LIMIT` DOFs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import connected_components

from nlgrd.errors import ModelError
from nlgrd.rotor.rigid_body import complement, rigid_body_modes

#: Largest component (DOFs) on which the modal floor's dense eigenproblem is solved.
FLOOR_DENSE_LIMIT = 3000


@dataclass(frozen=True)
class StructuralDamping:
    """Viscous damping of the whole FE rotor, the model file's ``[damping]`` table.

    Parameters
    ----------
    modal_floor : float
        Smallest modal damping ratio ζ_min of every elastic mode [-], 0 <= ζ_min < 1;
        0: no floor.
    rayleigh_alpha : float
        Mass-proportional coefficient α [1/s], >= 0.
    rayleigh_beta : float
        Stiffness-proportional coefficient β [s], >= 0.
    """

    modal_floor: float = 0.0
    rayleigh_alpha: float = 0.0
    rayleigh_beta: float = 0.0

    def __post_init__(self):
        for key in ("modal_floor", "rayleigh_alpha", "rayleigh_beta"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ModelError(key, f"must be a finite number, got {value!r}")
            if value < 0:
                raise ModelError(key, f"must be >= 0, got {value!r}")
        if self.modal_floor >= 1:
            raise ModelError("modal_floor", f"must be below 1 (critical damping), got {self.modal_floor!r}")

    @property
    def active(self) -> bool:
        """Whether it adds anything."""
        return self.modal_floor > 0 or self.rayleigh_alpha > 0 or self.rayleigh_beta > 0


def _dense(A) -> NDArray:
    return A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)


def elastic_modes(M, K) -> tuple[NDArray, NDArray]:
    """Undamped elastic modes of K φ = ω² M φ, rigid-body modes excluded exactly.

    Parameters
    ----------
    M, K : (n, n) array or sparse matrix
        Mass [kg] and symmetric stiffness [N/m].

    Returns
    -------
    omega : ndarray
        Natural frequencies ω_i [rad/s], ascending.
    Phi : ndarray, (n, n - r)
        Mass-normalised modes (Φᵀ M Φ = I), M-orthogonal to the r rigid-body modes.
    """
    R = rigid_body_modes(K, M)
    T = complement(R, M)
    Md, Kd = _dense(M), _dense(K)
    Kd = (Kd + Kd.T) / 2
    Mt, Kt = T.T @ Md @ T, T.T @ Kd @ T
    w2, V = sla.eigh((Kt + Kt.T) / 2, (Mt + Mt.T) / 2)
    return np.sqrt(np.clip(w2, 0.0, None)), T @ V


def modal_floor_matrix(M, K, C, floor: float) -> sp.csc_matrix:
    """C_F = M Φ diag(2 ω_i max(0, ζ_min - ζ_i)) Φᵀ M, block by connected component.

    Parameters
    ----------
    M, K, C : (n, n) sparse matrices
        Mass [kg], stiffness [N/m] and damping [N s/m] of the model at rest.
    floor : float
        ζ_min [-].

    Returns
    -------
    scipy.sparse.csc_matrix
        The added damping [N s/m]; zero on rigid-body modes.

    Raises
    ------
    ModelError
        ``damping.modal_floor`` when a coupled component exceeds :data:`FLOOR_DENSE_LIMIT` DOFs.
    """
    n = M.shape[0]
    graph = (abs(sp.csr_matrix(M)) + abs(sp.csr_matrix(K)) + abs(sp.csr_matrix(C))).tocsr()
    n_comp, label = connected_components(graph, directed=False)
    rows, cols, vals = [], [], []
    for c in range(n_comp):
        idx = np.flatnonzero(label == c)
        if len(idx) > FLOOR_DENSE_LIMIT:
            raise ModelError(
                "damping.modal_floor",
                f"the floor needs a dense eigenproblem of {len(idx)} coupled DOFs "
                f"(limit {FLOOR_DENSE_LIMIT}); "
                "use rayleigh_alpha and rayleigh_beta on a model this large",
            )
        Mc, Kc, Cc = (_dense(A[idx][:, idx]) for A in (sp.csr_matrix(M), sp.csr_matrix(K), sp.csr_matrix(C)))
        omega, Phi = elastic_modes(Mc, Kc)
        if not len(omega):
            continue
        zeta = np.einsum("ij,ij->j", Phi, ((Cc + Cc.T) / 2) @ Phi) / (2 * np.where(omega > 0, omega, 1.0))
        gain = 2 * omega * np.clip(floor - zeta, 0.0, None)
        if not np.any(gain):
            continue
        MPhi = Mc @ Phi
        block = (MPhi * gain) @ MPhi.T
        r, cc = np.meshgrid(idx, idx, indexing="ij")
        rows.append(r.ravel())
        cols.append(cc.ravel())
        vals.append(((block + block.T) / 2).ravel())
    if not rows:
        return sp.csc_matrix((n, n))
    return sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))


def structural_damping_matrix(option: StructuralDamping, M, K, C) -> sp.csc_matrix:
    """The damping ``option`` adds to a model at rest: α M + β K, then the modal floor.

    Parameters
    ----------
    option : StructuralDamping
        The model's ``[damping]`` table.
    M, K, C : (n, n) sparse matrices
        Mass [kg], stiffness [N/m] (gear meshes at k_h) and damping [N s/m] at rest.

    Returns
    -------
    scipy.sparse.csc_matrix
        The added damping [N s/m].
    """
    n = M.shape[0]
    added = sp.csc_matrix((n, n))
    if option.rayleigh_alpha > 0:
        added = added + option.rayleigh_alpha * sp.csc_matrix(M)
    if option.rayleigh_beta > 0:
        added = added + option.rayleigh_beta * sp.csc_matrix(K)
    if option.modal_floor > 0:
        added = added + modal_floor_matrix(M, K, sp.csc_matrix(C) + added, option.modal_floor)
    return sp.csc_matrix(added)


__all__ = [
    "FLOOR_DENSE_LIMIT",
    "StructuralDamping",
    "elastic_modes",
    "modal_floor_matrix",
    "structural_damping_matrix",
]
