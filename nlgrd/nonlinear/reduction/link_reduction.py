"""Receptance reduction of a rotor model onto the coordinates of all its nonlinear links.

With P = [P_1 ... P_m] the projections of the links (n x d, d = Σ d_j), Z_k the linear
dynamic stiffness at the k-th harmonic of the base frequency ω (links' stiffness left
out, their viscous damping kept) and f_k the harmonics of the external forces on the
DOFs (unbalance, the links' own forcing P_j φ_j,k), the problem reduces to

    κ_k Y_k + G_k = F_k,   κ_k = (Pᵀ Z_k⁻¹ P)⁻¹,   F_k = κ_k Pᵀ Z_k⁻¹ f_k      (k >= 1)

on the link coordinates Y = Pᵀ q (Maliha, Doğruer & Özgüven 2004, Eq. 26-37, for one
mesh; the same algebra for any number of links). The mean problem regularises with the
links' linear stiffness K_L = P diag(k_j) Pᵀ: with K_r = Z_0 + K_L, κ_0 = (Pᵀ K_r⁻¹ P)⁻¹ -
diag(k_j) and F_0 = (Pᵀ K_r⁻¹ P)⁻¹ Pᵀ K_r⁻¹ f_0 (static loads and gravity), exact for any
k_j > 0; rigid-body modes of K_r (a drive line's rotation) are removed by a bordered solve.
Any DOF follows as Q_k = Z_k⁻¹ (f_k - P G_k) (mean: K_r⁻¹ (f_0 - P (G_0 - diag(k_j) Y_0))).

Four ways to solve with Z_k (``method``; "auto" as the single-mesh path decides:
:meth:`LinkReceptance._auto_method`):

- ``"poles"`` (the default up to :data:`POLES_LIMIT` DOFs coupled to a link, without
  tabulated bearings or hysteretic damping): Z_k(ω) is a quadratic polynomial in ω, so one eigendecomposition
  per harmonic gives its pole-residue form (of Z_k + K_L, :mod:`nlgrd.nonlinear.reduction.link_poles`)
  and a point costs a few matrix-vector products; each harmonic is checked against a direct
  solve at five frequencies and solved directly when the check fails;
- ``"modal"`` (the default above it): the same on an M-orthonormal basis of modes and
  attachment vectors (:mod:`nlgrd.nonlinear.reduction.modal_basis`), checked against full sparse
  solves (:data:`MODAL_CHECK_RTOL`); the mean problem stays exact;
- ``"direct"``: Z_k factorised once per harmonic and frequency (dense LU up to
  :data:`DENSE_LIMIT` DOFs, sparse LU above), the factors kept, bounded, for the
  recovery of the same point;
- ``"banded"``: the single-mesh path's direct solver
  (:class:`~nlgrd.nonlinear.reduction.direct_receptance.DirectSolver`) on the links'
  coordinates: on the connected components of Z's sparsity graph that hold a link or a
  forced DOF, banded LU (reverse Cuthill-McKee order) of Z_k without the links' damping
  P C_L Pᵀ, which comes back by the Sherman-Morrison-Woodbury identity (sparse LU of Z_k
  where the band is wider than ``BAND_LIMIT`` or the identity ill-conditioned); all
  harmonics of a frequency at once, Z_k⁻¹ P and Z_k⁻¹ f_k kept at the DOFs recovered last
  (the default for one link coordinate above :data:`POLES_LIMIT` coupled DOFs, and with
  tabulated bearings or a loss factor, where the band is narrow). Where the pole-residue
  form applies, "auto" takes it after :data:`POLES_AFTER` n² banded frequencies (a long
  sweep or a landing search repays its set-up; a short run never pays it).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from nlgrd.cache import BoundedCache
from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import real_to_complex
from nlgrd.nonlinear.links.frequency_plan import FrequencyPlan
from nlgrd.nonlinear.reduction.direct_receptance import DirectSolution, DirectSolver, coupled_dofs
from nlgrd.nonlinear.reduction.link_mean import MeanProblem
from nlgrd.nonlinear.reduction.link_poles import LinkPoleForm
from nlgrd.nonlinear.reduction.link_stability import TruncatedStability, truncatable
from nlgrd.nonlinear.reduction.modal_basis import (
    ModeCapWarning,
    attachment_basis,
    m_orthonormal,
    modes_then_attachments,
    rigid_decoupled,
)
from nlgrd.nonlinear.reduction.pole_residue import POLE_CHECK_RTOL, PoleResidue
from nlgrd.nonlinear.reduction.state_space import HYSTERETIC_REFUSAL, LinearStateSpace
from nlgrd.rotor.assembly import LinearModel, assemble
from nlgrd.rotor.rigid_body import check_balanced, rigid_body_modes
from nlgrd.rotor.system import RotorSystem

#: Largest model whose stability basis is the full (dense) state space.
DENSE_STABILITY_LIMIT = 600
#: Up to this many DOFs Z_k is factorised as a dense matrix (faster than sparse LU there).
DENSE_LIMIT = 300
#: Up to this many DOFs coupled to a link or a forced DOF, ``method="auto"`` takes the
#: pole-residue form; above, the banded LU where the band is narrow (the single path's rule).
POLES_LIMIT = 100
#: Frequencies solved by the banded LU, per squared DOF of its band (n²), after which
#: ``method="auto"`` takes the pole-residue form where it applies: its set-up (one
#: eigendecomposition of the 2n companion per harmonic, ∝ n³) then costs about as many
#: banded solves (∝ n): measured 660-1060 at n 110 (two_shaft.toml), 2450-4160 at n 210
#: (its elements split in two), where 0.09 n² is 1089 and 3969; a point then costs
#: 7-9 against 67-165 µs per harmonic. A count, not a time: the switch does not depend on
#: the machine. Switching at break-even costs at most twice the better choice made in
#: advance (benchmarks/README.md, "the pole-residue form after 0.09 n² solves").
POLES_AFTER = 0.09
#: Dynamic attachment vectors at j / ATTACHMENT_POINTS of the top frequency (docs/verification.md).
ATTACHMENT_POINTS = 32
#: A modal basis farther than this from direct solves warns.
MODAL_CHECK_RTOL = 1e-6


@dataclass(frozen=True)
class _DenseLU:
    factors: tuple

    def solve(self, rhs: NDArray) -> NDArray:
        return sla.lu_solve(self.factors, rhs, check_finite=False)


class LinkReceptance:
    """Receptances of all link coordinates of ``system`` at once (see the module docstring).

    Parameters
    ----------
    system : RotorSystem
        The linear model. Its gear meshes enter only as links (their stiffness is left out
        of the assembly, like every link's).
    links : sequence of NonlinearLink
        The links, in the order of their coordinates.
    plan : FrequencyPlan
        Base frequency and shaft speed.
    static_force : ndarray (n_dofs,), optional
        Static loads on the DOFs (gravity, torques) [N, N m].
    harmonic_force : callable (omega, H) -> (H+1, n_dofs) complex, optional
        Harmonics of the external forces on the DOFs [N]: a polynomial of degree <= 2 in
        ω (an unbalance's m e Ω²), for the frequency derivatives.
    method : {"auto", "poles", "direct", "modal", "banded"}
        How Z_k is solved (module docstring); "auto": :meth:`_auto_method` (the single-mesh
        path's rule: "poles" up to :data:`POLES_LIMIT` coupled DOFs, "banded" above where
        the band is narrow, then "poles" after :data:`POLES_AFTER` n² banded frequencies where
        it applies; "poles" kept for several link coordinates). Before issue 33 it was "poles" up to
        :data:`DENSE_LIMIT` DOFs and "modal" above (once :meth:`prepare` knows the
        highest frequency; "direct" until then and with tabulated bearings or a loss
        factor).
    max_frequency : float, optional
        Highest excitation frequency the modal basis must serve [rad/s] (H times the
        highest base frequency); needed by "modal", else given to :meth:`prepare`.
    force_dofs : sequence of int, optional
        DOFs the harmonic forces load (the modal basis holds their attachment vectors);
        needed by "modal" with ``harmonic_force``.
    cutoff_factor : float
        Modal basis: modes up to ``cutoff_factor * max_frequency`` [-].
    top_order : int
        The highest base harmonic a mesh sits at (its excitation's fundamental): the
        stability basis serves ``top_order`` x the base frequency at least [-].

    Attributes
    ----------
    pole_check : dict
        Per harmonic k, the relative difference of the pole-residue receptance from a
        direct solve (harmonics above :data:`POLE_CHECK_RTOL` are solved directly).
    basis : ndarray (n_dofs, m) or None
        The modal basis ("modal": :mod:`nlgrd.nonlinear.reduction.modal_basis`), VᵀV = I.
    mean : MeanProblem
        The mean problem (:mod:`nlgrd.nonlinear.reduction.link_mean`), exact on the DOFs.
    """

    def __init__(
        self,
        system: RotorSystem,
        links: Sequence,
        plan: FrequencyPlan,
        static_force: NDArray | None = None,
        harmonic_force: Callable[[float, int], NDArray] | None = None,
        method: str = "auto",
        max_frequency: float | None = None,
        force_dofs: Sequence[int] | None = None,
        cutoff_factor: float = 3.0,
        top_order: int = 1,
    ):
        self.system, self.links, self.plan = system, tuple(links), plan
        self.model: LinearModel = assemble(system, mesh_stiffness=False, mesh_damping=False)
        n = self.model.n_dofs
        self.P = (
            np.hstack([link.projection(system) for link in self.links]) if self.links else np.zeros((n, 0))
        )
        # block_diag of nothing is (1, 0): a model without links has empty ones
        d = self.P.shape[1]
        self.k_link = sla.block_diag(*[link.linear_stiffness() for link in self.links]).reshape(d, d)
        self.c_link = sla.block_diag(*[link.linear_damping() for link in self.links]).reshape(d, d)
        self.C_link = sp.csc_matrix(self.P @ self.c_link @ self.P.T)
        self.K_link = sp.csc_matrix(self.P @ self.k_link @ self.P.T)
        self.static_force = np.zeros(n) if static_force is None else np.asarray(static_force, dtype=float)
        self.harmonic_force = harmonic_force
        self.slices = []
        start = 0
        for link in self.links:
            self.slices.append(slice(start, start + link.n_coords))
            start += link.n_coords
        self._speed_dependent = bool(
            self.model.tabulated_bearings or self.model.hysteretic_parts or self.model.Kc.nnz
        )
        self._dense = n <= DENSE_LIMIT and not self.model.tabulated_bearings
        self._mats = self._dense_matrices(lambda A: A.toarray()) if self._dense else None
        self.basis, self.max_frequency, self.cutoff_factor = None, None, float(cutoff_factor)
        self._Ps = self.P  # P in the coordinates the harmonics are solved in (DOFs or basis)
        self.force_dofs = np.zeros(0, dtype=int) if force_dofs is None else np.asarray(force_dofs, dtype=int)
        # the tabulated bearings at rest hold the structure too (as the mesh receptance's)
        self._rigid = rigid_body_modes(self.model.stiffness(0.0) + self.K_link, self.model.M)
        check_balanced(self._rigid, self.static_force, "static_force", "the static loads")
        self.mean = MeanProblem(
            self.model, self.K_link, self.P, self.static_force, self._rigid, self._speed_dependent
        )
        self._factors = BoundedCache(64)
        self._terms = BoundedCache(4096)
        # no tabulated bearing or hysteretic part: every method's derivatives are exact
        self._plain = not (self.model.tabulated_bearings or self.model.hysteretic_parts)
        poles_apply = self._dense and self._plain
        if method not in ("auto", "poles", "direct", "modal", "banded"):
            raise ModelError(
                "method", f"must be 'auto', 'poles', 'direct', 'modal' or 'banded', got {method!r}"
            )
        if method == "poles" and not poles_apply:
            raise ModelError(
                "method", f"'poles' needs at most {DENSE_LIMIT} DOFs, no tabulated bearing or loss factor"
            )
        if method == "modal" and not self._plain:
            raise ModelError("method", "'modal' needs a model without tabulated bearings or loss factor")
        if method == "modal" and harmonic_force is not None and force_dofs is None:
            raise ModelError("force_dofs", "the modal basis needs the DOFs the harmonic forces load")
        self._auto_modal = method == "auto" and not self._dense and self._plain
        self._auto_modal &= harmonic_force is None or force_dofs is not None
        self._poles = BoundedCache(256)
        self.stability = TruncatedStability(self.model, self.P, self.K_link, self.C_link, top_order)
        self._banded = BoundedCache(8)  # the banded solvers, per tuple of output DOFs
        # solves per (ω, H, DOFs out), 4096 for the recovery; out: the bearings' (u_y, u_z), then recovered
        self._band_sols, self._band_out, self._recovery = BoundedCache(64), (), BoundedCache(4096)
        self.method = self._auto_method(poles_apply) if method == "auto" else method
        # "auto" on the banded LU: the pole-residue form once POLES_AFTER n² frequencies were solved
        switch = method == "auto" and poles_apply and self.method == "banded"
        self._band_left = int(np.ceil(POLES_AFTER * self._band_solver(()).band.n ** 2)) if switch else None
        if self.method == "banded" and self.n_coords:
            out = tuple(int(i) for b in system.bearings for i in system.dofs.node_dofs(b.shaft, b.node)[1:3])
            same = np.array_equal(self._band_solver(out).keep, self._band_solver(()).keep)
            self._band_out = out if same else ()  # only where the links' solve reaches them
        self.pole_check: dict[int, float] = {}
        if method == "modal" and max_frequency is None:
            raise ModelError("max_frequency", "the modal method needs the highest excitation frequency")
        if max_frequency is not None:
            self.prepare(max_frequency)

    def _auto_method(self, poles_apply: bool) -> str:
        """What ``method="auto"`` takes: the pole-residue form
        up to :data:`POLES_LIMIT` DOFs coupled to a link or a forced DOF, else the banded LU
        where the band is narrow (``direct_receptance.BAND_LIMIT``), else the pole-residue
        form or direct LU as before; above :data:`DENSE_LIMIT` DOFs with exact derivatives,
        the modal basis once :meth:`prepare` knows the top frequency (direct LU until then).
        One difference: with more than one link coordinate the pole-residue form stays the
        default where it applies (per evaluation of κ, F and their derivatives, 2026-12-07:
        idler train H = 9 0.8-4.3 ms against 7.2-8.1 ms banded, two-stage H = 45 3.9-11.6
        ms against 24.5-35.4 ms, its set-up apart)."""
        if self._auto_modal:
            return "direct"
        if not self.n_coords:  # no link: nothing to reduce onto
            return "poles" if poles_apply else "direct"
        solver = self._band_solver(())
        if poles_apply and (solver.keep.size <= POLES_LIMIT or self.n_coords > 1):
            return "poles"
        if solver.banded:
            return "banded"
        return "poles" if poles_apply else "direct"

    def _poles_when_due(self) -> None:
        """``method="auto"`` on the banded LU: take the pole-residue form once
        :data:`POLES_AFTER` n² frequencies were solved (κ_k then differs by ~1e-13)."""
        if self._band_left is not None and self._band_left <= 0:
            self.method, self._band_left = "poles", None

    def _dense_matrices(self, dense: Callable) -> dict[str, NDArray]:
        m = self.model
        return {
            "K": dense(m.K),
            "Kc": dense(m.Kc),
            "M": dense(m.M),
            "C": dense(m.C + m.Ci + self.C_link),
            "G": dense(m.G),
            "KL": dense(self.K_link),
        }

    def prepare(self, max_frequency: float) -> None:
        """Build the modal basis for excitations up to ``max_frequency`` [rad/s] ("modal",
        or "auto" above :data:`DENSE_LIMIT` DOFs; otherwise nothing to do). A basis that
        already serves it is kept; a higher frequency rebuilds it (and empties the caches).

        Parameters
        ----------
        max_frequency : float
            Highest excitation frequency, H times the highest base frequency [rad/s].
        """
        top = float(max_frequency)
        if not (np.isfinite(top) and top > 0):
            raise ModelError("max_frequency", f"must be a positive finite frequency, got {max_frequency!r}")
        if not (self.method == "modal" or self._auto_modal):
            return
        if self.basis is not None and self.max_frequency >= top:
            return
        m = self.model
        n = m.n_dofs
        E = np.zeros((n, self.force_dofs.size))
        E[self.force_dofs, np.arange(self.force_dofs.size)] = 1.0
        R = self._rigid
        couplings = [m.C + m.Ci + self.C_link, m.G, m.Kc]
        Kr = (m.K + self.K_link).tocsc()
        V, modes = attachment_basis(
            Kr,
            m.M,
            np.hstack([self.P, E]),
            lambda w: self.model.dynamic_stiffness(w, self.plan.speed(w)) + 1j * w * self.C_link,
            top,
            self.cutoff_factor,
            rigid=R if R.shape[1] > 0 and rigid_decoupled(R, couplings) else None,
            fractions=np.arange(1, ATTACHMENT_POINTS + 1) / ATTACHMENT_POINTS,
        )
        S = np.column_stack([modes, spla.splu((Kr + m.M).tocsc()).solve(self.P)])
        try:
            V = m_orthonormal(V, m.M)
            S = modes_then_attachments(modes, S[:, modes.shape[1] :], m.M)
        except np.linalg.LinAlgError:  # massless DOFs: no pole form anyway
            pass
        self.basis, self.max_frequency, self.method, self.n_modes = V, top, "modal", modes.shape[1]
        self._Ps = V.T @ self.P
        self._mats = self._dense_matrices(lambda A: V.T @ (A @ V))
        self._stability = (self._dense_matrices(lambda A: S.T @ (A @ S)), S.T @ self.P)
        self._factors, self._terms, self._poles = BoundedCache(64), BoundedCache(4096), BoundedCache(256)
        self.pole_check = {}
        self.modal_check = self._check_basis()
        if not self.modal_check <= MODAL_CHECK_RTOL:
            warnings.warn(
                f"modal basis of {V.shape[1]} vectors: receptances differ from direct solves by "
                f"{self.modal_check:.2g} (more than {MODAL_CHECK_RTOL:g}); use method='direct'",
                ModeCapWarning,
                stacklevel=2,
            )

    def _check_basis(self) -> float:
        """Largest relative difference of the basis's Pᵀ Z⁻¹ P from full sparse solves, at
        three frequencies between attachment points and the speeds of harmonics 1 and 4."""
        a, err = self._mats, 0.0
        for frac in (3.5, 15.5, 31.5):
            w = frac / ATTACHMENT_POINTS * self.max_frequency
            for k in (1, 4):
                speed = self.plan.speed(w / k)
                Z = (self.model.dynamic_stiffness(w, speed) + 1j * w * self.C_link).tocsc()
                h = self.P.T @ spla.splu(Z).solve(self.P.astype(complex))
                Zr = a["K"] + speed * a["Kc"] - w * w * a["M"] + 1j * w * (a["C"] + speed * a["G"])
                hr = self._Ps.T @ np.linalg.solve(Zr, self._Ps.astype(complex))
                err = max(err, float(np.linalg.norm(hr - h) / np.linalg.norm(h)))
        return err

    def _proj(self, f: NDArray) -> NDArray:
        """Forces on the DOFs (..., n) in the solve coordinates."""
        if self.basis is None:
            return f
        return f.real @ self.basis + 1j * (f.imag @ self.basis) if np.iscomplexobj(f) else f @ self.basis

    @property
    def n_coords(self) -> int:
        """Number of link coordinates d."""
        return self.P.shape[1]

    def _Z(self, w: float, speed: float):
        if self._mats is not None and not self.model.hysteretic_parts:
            a = self._mats
            return a["K"] + speed * a["Kc"] - w * w * a["M"] + 1j * w * (a["C"] + speed * a["G"])
        return (self.model.dynamic_stiffness(w, speed) + 1j * w * self.C_link).tocsc()

    def forces(self, omega: float, H: int) -> NDArray:
        """f_k on the DOFs, k = 0..H: the static, external and the links' own forces.

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].
        H : int
            Number of harmonics [-].

        Returns
        -------
        ndarray (H+1, n_dofs) of complex
            [N, N m].
        """
        ext, phi = self._force_parts(omega, H)
        return ext + phi @ self.P.T

    def _force_parts(self, omega: float, H: int) -> tuple[NDArray, NDArray]:
        """The forces on the DOFs (static, external) (H+1, n) and the links' own (H+1, d)."""
        ext = np.zeros((H + 1, self.model.n_dofs), dtype=complex)
        ext[0] = self.static_force
        if self.harmonic_force is not None:
            ext += np.asarray(self.harmonic_force(omega, H), dtype=complex)
        phi = np.zeros((H + 1, self.n_coords), dtype=complex)
        for link, sl in zip(self.links, self.slices, strict=True):
            phi[:, sl] = link.forcing(omega, H)
        return ext, phi

    def _pole_forces(self, omega: float, H: int) -> NDArray:
        """L_k f_k (H+1, 2n) for the pole-residue harmonics (row 0 unused): the links' own
        forces through L_k P, the external ones through the columns of L_k they load."""
        ext, phi = self._force_parts(omega, H)
        nz = self.force_dofs if self.basis is not None else np.flatnonzero(np.any(ext[1:] != 0, axis=0))
        V = self.basis
        out = np.zeros((H + 1, 2 * (self.model.n_dofs if V is None else V.shape[1])), dtype=complex)
        for k in range(1, H + 1):
            pf = self._pole_form(k)
            if pf is not None:
                out[k] = pf.LP @ phi[k]
                if nz.size:
                    L = pf.pr.L
                    out[k] += L[:, nz] @ ext[k, nz] if V is None else L @ (V[nz].T @ ext[k, nz])
        return out

    def _factor(self, k: int, omega: float):
        """A solver of Z_k at ``omega``: ``solve(rhs)``."""
        speed = self.plan.speed(omega)

        def make():
            Z = self._Z(k * omega, speed)
            if sp.issparse(Z):
                return spla.splu(Z)
            return _DenseLU(sla.lu_factor(Z, check_finite=False))

        return self._factors.get(("k", k, float(omega)), make)

    def _band_solver(self, dofs=None) -> DirectSolver:
        """The ``"banded"`` solver (:mod:`nlgrd.nonlinear.reduction.direct_receptance`) on the
        components of Z's graph holding a link, a forced DOF (all DOFs when the harmonic
        forces' DOFs are not given) or one of ``dofs`` (default: the sweep's), Z_k⁻¹ returned there."""
        dofs = tuple(int(i) for i in (self._band_out if dofs is None else dofs))

        def make():
            m = self.model
            full = replace(m, C=(m.C + self.C_link).tocsc())
            out = np.asarray(dofs, dtype=int)
            forced = self.force_dofs
            if self.harmonic_force is not None and not forced.size:
                forced = np.arange(m.n_dofs)
            keep = coupled_dofs(full, self.P, np.concatenate([forced, out]))
            return DirectSolver(full, m, self.P, self.c_link, keep, out, self.plan.speed_per_base)

        return self._banded.get(dofs, make)

    def _band_solve(
        self,
        omega: float,
        H: int,
        dofs: tuple,
        f: NDArray | None = None,
        df: NDArray | None = None,
        derivative: bool = False,
    ) -> DirectSolution:
        """Harmonics 1..H of the ``"banded"`` solver for output ``dofs`` at ``omega``, with
        the forces f_k (default :meth:`forces`) when there are external harmonic forces
        (without, f_k = P φ_k and its solve is the links' Z_k⁻¹ P φ_k: no right-hand side of
        its own), kept per (ω, H, dofs). With ``derivative`` also dh_k/dω (and dg_k/dω,
        from ``df`` = df_k/dω, with external forces); this solution replaces the plain one
        only with one link coordinate, whose h_k, U_k and g_k are then the plain solve's bit
        for bit (no condition test; with several, its stricter condition limit may move a
        harmonic to sparse LU). Either way the solver reuses the band LUs of its last solve
        at the frequency: κ_k and dκ_k/dω take one factorisation."""
        key = (float(omega), int(H), dofs)
        sol = self._band_sols.peek(key)
        if sol is not None and (sol.dh is not None or not derivative):
            return sol
        rhs = drhs = None
        if self.harmonic_force is not None:
            rhs = self.forces(omega, H)[1:] if f is None else f
            drhs = df
        sol = self._band_solver(dofs).solve_forced(np.arange(1, H + 1), omega, derivative, rhs, drhs)
        if self._band_left is not None:
            self._band_left -= 1
        if not derivative or self.n_coords == 1:
            self._band_sols.put(key, sol)
            self._recovery.put(key, sol)  # Z_k⁻¹ P, Z_k⁻¹ f_k at the DOFs out, for recover
        return sol

    def _pole_form(self, k: int) -> LinkPoleForm | None:
        """The shifted pole-residue form of harmonic k (:mod:`nlgrd.nonlinear.reduction.link_poles`),
        or None (solve directly)."""

        def make():
            a, s_ = self._mats, self.plan.speed_per_base
            A = (a["K"] + a["KL"], s_ * a["Kc"] + 1j * k * a["C"], -(k * k) * a["M"] + 1j * k * s_ * a["G"])
            try:  # a singular mass matrix (massless DOFs) has no companion form: solve directly
                with warnings.catch_warnings():
                    warnings.simplefilter("error", sla.LinAlgWarning)
                    pr = PoleResidue.of(*A)
            except (np.linalg.LinAlgError, sla.LinAlgError, sla.LinAlgWarning, ValueError):
                self.pole_check[k] = np.inf
                return None
            if not np.all(np.isfinite(pr.poles)):
                self.pole_check[k] = np.inf
                return None
            Ps = self._Ps
            err = pr.check(*A, Ps, pr.check_frequencies())
            self.pole_check[k] = err
            # on a modal basis: a tenth of the basis's own tolerance (its truncation error)
            if not err <= (POLE_CHECK_RTOL if self.basis is None else MODAL_CHECK_RTOL / 10):
                return None
            return LinkPoleForm(pr, Ps.T @ pr.X_top, pr.L @ Ps, self.k_link)

        if self.method not in ("poles", "modal"):
            return None
        return self._poles.get(("poles", k), make)

    def _pole_stack(self, H: int) -> tuple[NDArray, NDArray, NDArray] | None:
        """The pole-residue forms of harmonics 1..H stacked (poles (H, 2n), Pᵀ X_top
        (H, d, 2n), L P (H, 2n, d)) for all harmonics at once, or None when one of them is
        solved directly."""

        def make():
            forms = [self._pole_form(k) for k in range(1, H + 1)]
            if any(pf is None for pf in forms):
                return None
            return (
                np.stack([pf.pr.poles for pf in forms]),
                np.stack([pf.CP for pf in forms]),
                np.stack([pf.LP for pf in forms]),
            )

        if self.method not in ("poles", "modal") or not H:
            return None
        return self._poles.get(("stack", int(H)), make)

    def terms(self, omega: float, H: int) -> tuple[NDArray, NDArray]:
        """κ_k (H+1, d, d) [N/m] and F_k (H+1, d) [N], k = 0..H.

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].
        H : int
            Number of harmonics [-].

        Returns
        -------
        tuple of ndarray
        """

        def make():
            self._poles_when_due()
            d, speed = self.n_coords, self.plan.speed(omega)
            ext, phi = self._force_parts(omega, H)
            kap = np.empty((H + 1, d, d), dtype=complex)
            frc = np.empty((H + 1, d), dtype=complex)
            # the mean: f_0 = f_s + ext_0 + P φ_0, by linearity from the kept solves
            h0, hr_inv, ps = self.mean.terms(speed)
            ph = ps + h0 @ phi[0].real
            if np.any(ext[0].real != self.static_force):
                ph = ph + self.P.T @ self.mean.solve(speed, (ext[0].real - self.static_force)[:, None])[:, 0]
            kap[0] = hr_inv - self.k_link
            frc[0] = hr_inv @ ph
            # no external harmonic forces: f_k = P φ_k, so F_k = κ_k Pᵀ Z_k⁻¹ P φ_k = φ_k
            own = self.harmonic_force is None
            poles = self.method in ("poles", "modal")
            Lf = self._pole_forces(omega, H) if poles and not own else None
            Ps, f = self._Ps, None
            stack = self._pole_stack(H) if own else None
            if stack is not None:  # every harmonic in pole-residue form: all at once
                lam, CP, LP = stack
                w = 1.0 / (omega - lam)
                kap[1:] = np.linalg.inv(CP @ (w[:, :, None] * LP)) - self.k_link
                frc[1:] = phi[1:]
                return kap, frc
            if self.method == "banded" and H:
                sol = self._band_solve(omega, H, self._band_out, ext[1:] + phi[1:] @ self.P.T)
                kap[1:] = np.linalg.inv(sol.h)
                # no external forces: F_k = κ_k Pᵀ Z_k⁻¹ P φ_k = φ_k
                frc[1:] = phi[1:] if sol.g is None else (kap[1:] @ sol.g[:, :, None])[:, :, 0]
                return kap, frc
            for k in range(1, H + 1):
                pf = self._pole_form(k)
                if pf is not None:
                    kap[k], frc[k] = pf.terms(omega, np.zeros(pf.LP.shape[0]) if own else Lf[k])
                    continue
                f = ext + phi @ self.P.T if f is None else f
                u = self._factor(k, omega).solve(np.column_stack([Ps.astype(complex), self._proj(f[k])]))
                kap[k] = np.linalg.inv(Ps.T @ u[:, :d])
                frc[k] = kap[k] @ (Ps.T @ u[:, d])
            if own:
                frc[1:] = phi[1:]
            return kap, frc

        return self._terms.get((float(omega), int(H)), make)

    @property
    def has_derivatives(self) -> bool:
        """Whether :meth:`derivatives` is exact: no tabulated bearing or hysteretic part, or
        the ``"banded"`` LU, whose dZ_k/dω holds the slopes of the bearings' tables
        (:func:`~nlgrd.nonlinear.reduction.direct_receptance.model_stiffness_derivative`) and
        the hysteretic part constant (its whirl signs, of k - r s, do not change with ω > 0)."""
        return self._plain or self.method == "banded"

    def derivatives(self, omega: float, H: int) -> tuple[NDArray, NDArray]:
        """dκ_k/dω (H+1, d, d) [N s/m] and dF_k/dω (H+1, d) [N s], k = 0..H, analytic.

        With h_k = Pᵀ Z_k⁻¹ P: dκ_k = κ_k Pᵀ Z_k⁻¹ Z_k' Z_k⁻¹ P κ_k and, with
        u_k = Z_k⁻¹ f_k, dF_k = dκ_k Pᵀ u_k + κ_k Pᵀ Z_k⁻¹ (f_k' - Z_k' u_k), where
        Z_k' = s K_c - 2 k² ω M + i k (C + Ω G) + i k ω s G (Ω = s ω the shaft speed).
        It reuses the factors of :meth:`terms` (no new factorisation), differentiates
        the pole-residue form, or (``"banded"``) takes the Woodbury identity's derivative
        (:mod:`nlgrd.nonlinear.reduction.direct_receptance`, tabulated bearings and loss
        factor included) on the band LUs of the frequency's solve, one factorisation for
        κ_k and dκ_k/dω in either order (:meth:`_band_solve`); f_k' by a central
        difference of the forces (exact for their degree <= 2 in ω), but without external
        harmonic forces, where F_k = φ_k (the links' own forcing, linear in ω),
        analytically: dF_k/dω = φ_k / ω. κ_0 and F_0 do not depend on ω unless the
        stiffness does on the speed (then by central differences).

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].
        H : int
            Number of harmonics [-].

        Returns
        -------
        tuple of ndarray
        """

        def make():
            self._poles_when_due()
            d, s_ = self.n_coords, self.plan.speed_per_base
            speed = s_ * omega
            m = self.model
            h = 1e-6 * max(abs(omega), 1.0)
            # the forces are polynomials of degree <= 2 in ω (the links' own ∝ ω, unbalance
            # ∝ ω²): a central difference with a wide step is exact but for rounding
            hf = 1e-3 * max(abs(omega), 1.0)
            poles = self.method in ("poles", "modal")
            Ps = self._Ps
            own = self.harmonic_force is None  # F_k = φ_k, the links' own forcing, ∝ ω
            if poles and not own:
                Lf_all = self._pole_forces(omega, H)
                dLf_all = (self._pole_forces(omega + hf, H) - self._pole_forces(omega - hf, H)) / (2 * hf)
            if own:  # κ alone is needed: no forces
                zero = np.zeros((H + 1, Ps.shape[0]), dtype=complex)
                f = df = zero
                if poles:
                    Lf_all = dLf_all = np.zeros((H + 1, 2 * Ps.shape[0]), dtype=complex)
            elif not poles or any(self._pole_form(k) is None for k in range(1, H + 1)):
                df = self._proj((self.forces(omega + hf, H) - self.forces(omega - hf, H)) / (2 * hf))
                f = self._proj(self.forces(omega, H))
            band = None
            if self.method == "banded" and H:  # first: κ_k takes this solve's h_k (one link)
                rhs = (None, None) if own else (f[1:], df[1:])
                band = self._band_solve(omega, H, self._band_out, *rhs, derivative=True)
            kap, frc = self.terms(omega, H)  # without external forces F_k = φ_k
            dkap = np.zeros((H + 1, d, d), dtype=complex)
            dfrc = np.zeros((H + 1, d), dtype=complex)
            if self._speed_dependent:
                (k1, f1), (k0, f0) = self.terms(omega + h, H), self.terms(omega - h, H)
                dkap[0], dfrc[0] = (k1[0] - k0[0]) / (2 * h), (f1[0] - f0[0]) / (2 * h)
            if self._mats is not None:
                a = self._mats
                Kc, M, C, G = a["Kc"], a["M"], a["C"], a["G"]
            else:
                Kc, M, G = m.Kc, m.M, m.G
                C = (m.C + m.Ci + self.C_link).tocsc()
            stack = self._pole_stack(H) if own else None
            if stack is not None:  # all harmonics at once: d/dω of 1/(ω - λ) is -1/(ω - λ)²
                lam, CP, LP = stack
                w = 1.0 / (omega - lam)
                kp = np.linalg.inv(CP @ (w[:, :, None] * LP))
                dkap[1:] = kp @ (CP @ ((w * w)[:, :, None] * LP)) @ kp
                dfrc[1:] = frc[1:] / omega
                return dkap, dfrc
            if band is not None:
                sol = band
                kh = kap[1:]
                dkap[1:] = -kh @ sol.dh @ kh
                if own:  # the links' own forcing is linear in ω (i k ω c_m E_k for a mesh)
                    dfrc[1:] = frc[1:] / omega
                else:
                    dfrc[1:] = (dkap[1:] @ sol.g[:, :, None] + kh @ sol.dg[:, :, None])[:, :, 0]
                return dkap, dfrc
            A = B = None
            for k in range(1, H + 1):
                pf = self._pole_form(k)
                if pf is not None:
                    dkap[k], dfrc[k] = pf.derivatives(omega, Lf_all[k], dLf_all[k])
                    continue
                if A is None:
                    A, B = -2 * omega * M, 1j * (C + speed * G) + 1j * omega * s_ * G
                dZ = s_ * Kc + (k * k) * A + k * B
                lu = self._factor(k, omega)
                u = lu.solve(np.column_stack([Ps.astype(complex), f[k]]))
                up, uf = u[:, :d], u[:, d]
                v = lu.solve(np.column_stack([dZ @ up, df[k] - dZ @ uf]))
                dkap[k] = kap[k] @ (Ps.T @ v[:, :d]) @ kap[k]
                dfrc[k] = dkap[k] @ (Ps.T @ uf) + kap[k] @ (Ps.T @ v[:, d])
            if own:
                dfrc[1:] = frc[1:] / omega
            return dkap, dfrc

        return self._terms.get(("d", float(omega), int(H)), make)

    def recover(self, omega: float, H: int, harmonics: NDArray, forces: NDArray, dofs) -> NDArray:
        """Real harmonics (len(dofs), 2H+1) of any DOFs at a solved point.

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].
        H : int
            Number of harmonics [-].
        harmonics : ndarray (d, 2H+1)
            Real harmonics of the link coordinates Y [m].
        forces : ndarray (d, 2H+1)
            Real harmonics of the link forces G [N].
        dofs : sequence of int
            DOFs to recover.

        Returns
        -------
        ndarray (len(dofs), 2H+1)
            [m] or [rad].
        """
        dofs = np.asarray(dofs, dtype=int)
        Y = real_to_complex(np.asarray(harmonics, dtype=float).reshape(self.n_coords, -1)).T  # (H+1, d)
        G = real_to_complex(np.asarray(forces, dtype=float).reshape(self.n_coords, -1)).T
        f = self.forces(omega, H)
        out = np.empty((H + 1, dofs.size), dtype=complex)
        speed = self.plan.speed(omega)
        rhs0 = f[0].real - self.P @ (G[0].real - self.k_link @ Y[0].real)
        out[0] = self.mean.solve(speed, rhs0[:, None])[dofs, 0]
        V = self.basis
        if self.method == "banded" and H:
            self._band_out = key = tuple(int(i) for i in dofs)
            sol = self._recovery.peek((float(omega), int(H), key)) or self._band_solve(omega, H, key)
            if sol.Ug is None:  # Z⁻¹ (f - P G), f = P φ: Z⁻¹ P (φ - G); else Z⁻¹ f - (Z⁻¹ P) G
                phi = self._force_parts(omega, H)[1]
                out[1:] = np.einsum("kij,kj->ki", sol.U, phi[1:] - G[1:])
            else:
                out[1:] = sol.Ug - np.einsum("kij,kj->ki", sol.U, G[1:])
        for k in range(1, H + 1 if self.method != "banded" else 1):
            pf = self._pole_form(k)
            rhs = f[k] - self.P @ G[k]
            if V is None:
                solved = pf.solve(omega, rhs, dofs) if pf is not None else None
                out[k] = solved if pf is not None else self._factor(k, omega).solve(rhs)[dofs]
                continue
            x = pf.solve(omega, V.T @ rhs) if pf is not None else self._factor(k, omega).solve(V.T @ rhs)
            out[k] = V[dofs] @ x
        real = np.empty((dofs.size, 2 * H + 1))
        real[:, 0] = out[0].real
        real[:, 1::2], real[:, 2::2] = out[1:].real.T, -out[1:].imag.T
        return real

    def linearised(self) -> LinearModel:
        """The linear model with every link at its linear stiffness and damping (a gear
        mesh at k_h and c_m, a clearance at its contact tangent): for modal analysis.

        Returns
        -------
        LinearModel
        """
        m = self.model
        return replace(m, K=(m.K + self.K_link).tocsc(), C=(m.C + self.C_link).tocsc(), meshes=())

    def prepare_stability(self, top: float) -> None:
        """Size the stability basis for base frequencies up to ``top`` [rad/s] (a sweep's
        highest: :meth:`~nlgrd.nonlinear.reduction.link_stability.TruncatedStability.prepare`).

        Parameters
        ----------
        top : float
            Highest base frequency [rad/s].
        """
        self.stability.prepare(top)

    @property
    def truncates_stability(self) -> bool:
        """Whether Floquet stability runs on the truncated basis of :meth:`state_space`:
        every link a gear mesh or a bearing clearance
        (:func:`~nlgrd.nonlinear.reduction.link_stability.truncatable`), at most
        :data:`DENSE_STABILITY_LIMIT` DOFs and no modal basis (whose own modes serve then)."""
        small = self.model.n_dofs <= DENSE_STABILITY_LIMIT and self.basis is None
        return small and truncatable(self.links)

    def state_space(self, omega: float) -> LinearStateSpace | None:
        """The linear part for Floquet stability at base frequency ``omega``.

        Where every link is a gear mesh or a clearance (:attr:`truncates_stability`), on the
        modes below 3x the highest mesh (or unbalance) frequency and the static attachment vectors of the link
        coordinates, checked by Floquet analysis where the orbit's tangent varies over the
        period (:mod:`nlgrd.nonlinear.reduction.link_stability`). Else on the modes and
        static attachment vectors of the modal basis when there is one, else dense up to
        :data:`DENSE_STABILITY_LIMIT` DOFs (None above it).

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].

        Returns
        -------
        LinearStateSpace or None

        Raises
        ------
        ModelError
            (``loss_factor``) With hysteretic damping, which has no time-domain form
            (:data:`~nlgrd.nonlinear.reduction.state_space.HYSTERETIC_REFUSAL`).
        """
        if self.model.n_dofs > DENSE_STABILITY_LIMIT and self.basis is None:
            return None
        if self.model.hysteretic_parts:
            raise ModelError("loss_factor", HYSTERETIC_REFUSAL)
        speed = self.plan.speed(omega)
        if self.basis is not None:  # on the stability basis
            a, Ps = self._stability
            return LinearStateSpace(a["M"], a["C"] + speed * a["G"], a["K"] + speed * a["Kc"], Ps)
        if not self.truncates_stability:
            return self.stability.full_state(speed)
        return self.stability.state_space(omega, speed)

    def check(self, omega: float) -> None:
        """Raise ModelError when Z_1 is singular at ``omega`` (a link-free rigid-body mode).

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].
        """
        if not np.isfinite(omega) or omega <= 0:
            raise ModelError("omega", f"must be a positive finite frequency, got {omega!r}")
