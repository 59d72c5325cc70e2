"""Receptance reduction of a geared rotor onto its mesh coordinates.

For harmonic k of the mesh frequency ω, with Z_k the linear dynamic stiffness at kω
(mesh stiffness left out, mesh damping kept) and W the projection vectors of the
meshes (one column per mesh), the nonlinear problem reduces to

    κ_k Y_k + G_k = F_k,   κ_k = (Wᵀ Z_k⁻¹ W)⁻¹,   F_k = i kω c_m E_k  (k >= 1)

on the mesh coordinates Y = Wᵀ q only (Maliha, Doğruer & Özgüven 2004, Eq. 26-37, in
the compact form of model.md §3); every other coordinate follows linearly as
Q_k = Z_k⁻¹ W (F_k - G_k).

Mean (k = 0): with K_r = Z_0 + W diag(k_h) Wᵀ (the meshes at k_h), κ_0 = (Wᵀ K_r⁻¹
W)⁻¹ - diag(k_h) and F_0 = (Wᵀ K_r⁻¹ W)⁻¹ Wᵀ K_r⁻¹ F_static; κ_0 = 0 when a free
torsional rigid-body mode moves the mesh (the mean mesh force is the static load).
Rigid-body modes that move no mesh (a closed four-square loop) are removed by a bordered
solve with Rᵀ M q = 0; a static load with a component on such a mode is an error.

Three ways to get h_k = Wᵀ Z_k⁻¹ W:

- ``"direct"``: a factorisation per harmonic and frequency (exact), restricted to the
  connected components of Z's sparsity graph that hold a mesh or an output DOF (axial
  bars, say, never couple to a spur mesh): banded LU of Z_k without the mesh damping,
  which is added back by the Sherman-Morrison-Woodbury identity, or sparse LU of Z_k
  when its band is wide (:mod:`nlgrd.nonlinear.reduction.direct_receptance`);
- ``"poles"`` (the default up to ``POLES_LIMIT`` DOFs, and up to ``POLES_LATE_LIMIT``
  after ``POLES_AFTER`` frequencies solved directly by sparse LU): the pole-residue form below of
  the whole model (no truncation), made of Z'_k = Z_k + W diag(k_h) Wᵀ, which is
  regular at ω = 0 where a mesh is a shaft's only torsional support, and turned back by
  the Sherman-Morrison-Woodbury identity h_k = h'_k (I - K h'_k)⁻¹ (the shift of
  :mod:`nlgrd.nonlinear.reduction.link_poles`); rigid-body modes that move no mesh leave the basis
  as in ``"modal"``. A harmonic whose form fails its check is solved directly;
- ``"modal"``: Galerkin projection on the lowest undamped modes (meshes at k_h) up to a
  cut-off frequency and the attachment vectors K_r⁻¹ W and Z(iω_j)⁻¹ W (modal summation
  with residual correction, projected so that gyroscopic, non-proportional, circulatory
  and hysteretic terms stay coupled); rigid-body modes that move no mesh are left out.

Along a sweep the speed follows the mesh frequency (Ω = s ω), so without tabulated
bearings the reduced Z_k(ω) = A_0 + ω A_1 + ω² A_2 is a quadratic matrix polynomial in ω
(A_0 = K + hysteretic part, whose whirl signs are constant for ω > 0; A_1 = s K_c + i k
C; A_2 = -k² M + i k s G). One eigendecomposition of its companion linearisation per
harmonic then gives the pole-residue form h_k(ω) = Σ_j R_j / (ω - λ_j) and dh_k/dω =
-Σ_j R_j / (ω - λ_j)² (Tisseur & Meerbergen 2001, SIAM Rev. 43:235, §3.4): per point a
few vector products, independent of the model size."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.reduction.direct_receptance import (
    DirectSolver,
    coupled_dofs,
    dynamic_stiffness_derivative,
)
from nlgrd.nonlinear.reduction.link_reduction import POLES_LIMIT
from nlgrd.nonlinear.reduction.modal_basis import (
    STABILITY_MODE_CAP,
    attachment_basis,
    lowest_modes,
    rigid_decoupled,
)
from nlgrd.nonlinear.reduction.pole_residue import POLE_CHECK_RTOL, PoleResidue
from nlgrd.nonlinear.reduction.state_space import HYSTERETIC_REFUSAL
from nlgrd.rotor.assembly import LinearModel, assemble, mesh_matrix
from nlgrd.rotor.rigid_body import check_balanced, rigid_body_modes
from nlgrd.rotor.system import RotorSystem

#: Above this many DOFs ``method="auto"`` uses the modal basis.
DIRECT_LIMIT = 3000
#: POLES_LIMIT (link_reduction's): up to this many DOFs reached by a mesh, ``method="auto"``
#: uses the pole-residue form of the whole model (one eigendecomposition per harmonic: 60 ms
#: at 83 DOFs, 250 ms at 210).
#: Up to this many, "auto" solves POLES_AFTER new frequencies by sparse LU (a short sweep),
#: then turns to the pole-residue form (a long sweep: cheaper than the solves it replaces).
#: A narrow band (direct_receptance.BAND_LIMIT) stays direct: 0.05 ms per harmonic at 210
#: DOFs against 230 ms for the set-up.
POLES_LATE_LIMIT = 300
POLES_AFTER = 200


@dataclass(frozen=True)
class MeanTerms:
    """Mean (k = 0) reduction at one speed: κ_0, F_0 and what recovery needs.

    Attributes
    ----------
    kappa : ndarray (n_nl, n_nl)
        κ_0 = (Wᵀ K_r⁻¹ W)⁻¹ - diag(k_h) [N/m].
    force : ndarray (n_nl,)
        F_0 = (Wᵀ K_r⁻¹ W)⁻¹ Wᵀ K_r⁻¹ F_static [N].
    x_static : ndarray (n,)
        K_r⁻¹ F_static, the static deflection of every DOF [m, rad].
    x_mesh : ndarray (n, n_nl)
        K_r⁻¹ W, the deflection per unit mesh force [m/N, rad/N].
    """

    kappa: NDArray  # (n_nl, n_nl)
    force: NDArray  # (n_nl,)
    x_static: NDArray  # K_r⁻¹ F_static (n,)
    x_mesh: NDArray  # K_r⁻¹ W (n, n_nl)


class MeshReceptance:
    """Receptances of a geared :class:`RotorSystem` seen from its mesh coordinates.

    Parameters
    ----------
    system : RotorSystem
        Model with at least one gear pair; the first pair's pinion sets the speed:
        the reference speed is Ω = ω / (N_p |s_p|) for mesh frequency ω, s_p the
        pinion shaft's speed ratio.
    method : {"auto", "poles", "direct", "modal"}
        How h_k is computed (see module docstring); "auto": "poles" up to
        ``POLES_LIMIT`` DOFs (those a mesh reaches) without tabulated bearings, "direct"
        up to ``DIRECT_LIMIT`` (with a wide band, turning to "poles" after ``POLES_AFTER``
        frequencies up to ``POLES_LATE_LIMIT`` DOFs), "modal" above.
    max_frequency : float, optional
        Highest excitation frequency the modal basis must serve [rad/s] (H times the
        highest mesh frequency); required for ``"modal"``.
    cutoff_factor : float
        Modal basis: keep modes up to ``cutoff_factor * max_frequency``.
    period : int
        Receptances taken at the base ω_mesh / ``period`` (orbits of that many mesh
        periods) with the speed of the mesh frequency.
    """

    def __init__(
        self,
        system: RotorSystem,
        method: str = "auto",
        max_frequency: float | None = None,
        cutoff_factor: float = 3.0,
        period: int = 1,
    ):
        if not system.gear_pairs:
            raise ModelError("gear_pairs", "the model has no gear pair: nothing to reduce onto")
        if system.bearing_clearances:
            raise ModelError(
                "bearing_clearances",
                "the mesh receptance models no bearing clearance: use nlgrd.nonlinear.models.link_model",
            )
        if system.unbalance:
            raise ModelError(
                "unbalance", "the mesh receptance models no unbalance: use nlgrd.nonlinear.models.link_model"
            )
        self.system = system
        self.model: LinearModel = assemble(system, mesh_stiffness=False, mesh_damping=True)
        self.W = np.column_stack([m.w for m in self.model.meshes])
        self.k_h = np.array([m.stiffness for m in self.model.meshes])
        self.c_m = np.array([m.damping for m in self.model.meshes])
        self.static_force = sum(g.static_torques(system) for g in system.gear_pairs)
        g0 = system.gear_pairs[0]
        s_p = abs(system.shafts[g0.pinion_shaft].speed_ratio)
        self.period = int(period)  # they are taken at ω_mesh / period
        self.speed_per_mesh_frequency = period / (g0.geometry.teeth_pinion * s_p)
        #: the method asked for (derived models are built with it), the frequencies solved
        #: directly, and how many more before "auto" turns to the pole-residue form
        self.requested_method, self.n_direct, self._poles_after = method, 0, None
        self.output_dofs = np.zeros(0, dtype=int)
        self._direct_solver = None
        if method == "auto":
            n = self.model.n_dofs
            n_mesh = 0 if self.model.tabulated_bearings else len(self._mesh_component())
            method = "poles" if 0 < n_mesh <= POLES_LIMIT else ("direct" if n <= DIRECT_LIMIT else "modal")
            late = method == "direct" and 0 < n_mesh <= POLES_LATE_LIMIT
            if late and not self._direct().banded:  # a band solve is cheaper than the poles' set-up
                self._poles_after = POLES_AFTER
        if method not in ("poles", "direct", "modal"):
            raise ModelError("method", f"must be 'auto', 'poles', 'direct' or 'modal', got {method!r}")
        self.method = method
        self._speed_dependent = bool(
            self.model.tabulated_bearings or self.model.hysteretic_parts or self.model.Kc.nnz
        )
        self._rigid = self._rigid_body_split()
        self._mean_cache: dict[float, MeanTerms] = {}
        self._solve_cache: dict[float, list] = {}
        self._poles: dict[int, tuple[NDArray, NDArray, NDArray, NDArray] | None] = {}
        self._stacks: dict[tuple[int, int], tuple | None] = {}
        #: relative difference of the pole-residue h_k from a direct solve, per harmonic k
        self.pole_check: dict[int, float] = {}
        self.max_frequency = None if max_frequency is None else float(max_frequency)
        self._stability_basis: dict[float, tuple] = {}
        self._shift = None
        if method == "poles":
            self._build_full_basis()
        if method == "modal":
            if max_frequency is None:
                raise ModelError("max_frequency", "the modal method needs the highest excitation frequency")
            self._build_basis(float(max_frequency), cutoff_factor)

    # speeds
    def speed(self, omega: float) -> float:
        """Reference speed Ω [rad/s] at mesh frequency ``omega`` [rad/s]."""
        return float(omega) * self.speed_per_mesh_frequency

    @property
    def n_coords(self) -> int:
        """Number of mesh coordinates."""
        return self.W.shape[1]

    # mean problem
    def _rigid_body_split(self) -> NDArray:
        """Rigid-body modes of the linear system with the meshes in (none move a mesh)."""
        R = rigid_body_modes(self.model.stiffness(0.0) + self._mesh_stiffness(), self.model.M)
        check_balanced(R, self.static_force, "torque", "the static torques")
        return R

    def _mesh_stiffness(self) -> sp.csc_matrix:
        return mesh_matrix(self.W, self.k_h)

    def _bordered_solve(self, Kr: sp.csc_matrix, rhs: NDArray) -> NDArray:
        R = self._rigid
        n = Kr.shape[0]
        if R.shape[1] == 0:
            return spla.splu(Kr.tocsc()).solve(rhs)
        MR = sp.csc_matrix(self.model.M @ R)
        A = sp.bmat([[Kr, MR], [MR.T, None]], format="csc")
        pad = np.zeros((R.shape[1],) + rhs.shape[1:])
        return spla.splu(A).solve(np.concatenate([rhs, pad]))[:n]

    def mean_terms(self, speed: float = 0.0) -> MeanTerms:
        """κ_0, F_0 and the static solution pieces at reference speed ``speed`` [rad/s]."""
        key = float(speed) if self._speed_dependent else 0.0
        if key not in self._mean_cache:
            Z0 = self.model.dynamic_stiffness(0.0, key)
            Kr = (Z0 + self._mesh_stiffness()).tocsc()
            if np.iscomplexobj(Kr.data) and np.all(Kr.data.imag == 0):
                Kr = sp.csc_matrix(
                    (np.ascontiguousarray(Kr.data.real), Kr.indices, Kr.indptr), shape=Kr.shape
                )
            x = self._bordered_solve(Kr, np.column_stack([self.W, self.static_force]))
            if np.iscomplexobj(x):
                x = x.real
            hr = self.W.T @ x[:, : self.n_coords]
            hr_inv = np.linalg.inv(hr)
            self._mean_cache[key] = MeanTerms(
                kappa=hr_inv - np.diag(self.k_h),
                force=hr_inv @ (self.W.T @ x[:, -1]),
                x_static=x[:, -1],
                x_mesh=x[:, : self.n_coords],
            )
        return self._mean_cache[key]

    # harmonics k >= 1
    def _build_basis(self, max_frequency: float, cutoff_factor: float) -> None:
        m = self.model
        Kr = (m.K + self._mesh_stiffness()).tocsc()
        R = self._rigid
        V, modes = attachment_basis(
            Kr,
            m.M,
            self.W,
            lambda w: m.dynamic_stiffness(w, self.speed(w)),
            max_frequency,
            cutoff_factor,
            rigid=R if R.shape[1] > 0 and self._rigid_decoupled() else None,
        )
        self._project(V, modes.shape[1])

    def _project(self, V: NDArray, n_modes: int) -> None:
        """Take ``V`` as the basis: the model's matrices projected on it."""
        m = self.model
        self.basis, self.n_modes = V, n_modes
        P = lambda A: V.T @ (A @ V)  # noqa: E731
        self._red = {"M": P(m.M), "K": P(m.K), "C": P(m.C + m.Ci), "G": P(m.G), "Kc": P(m.Kc)}
        self._red_hyst = [(h.speed_ratio, P(h.Kb), P(h.Kx)) for h in m.hysteretic_parts]
        self._red_bear = [(b, r, V[dofs]) for b, r, dofs in m.tabulated_bearings]
        self._W_red = V.T @ self.W
        self._poles.clear()
        self._stacks.clear()

    def _build_full_basis(self) -> None:
        """The whole model as the basis of the pole-residue form (``"poles"``): the
        M-orthogonal complement of the rigid-body modes when they are decoupled, else
        every DOF."""
        m = self.model
        R = self._rigid
        keep = self._mesh_component()
        N = np.eye(len(keep))
        if R.shape[1] > 0 and self._rigid_decoupled():
            N = sla.null_space((m.M @ R)[keep].T)
        V = np.zeros((m.n_dofs, N.shape[1]))
        V[keep] = N  # DOFs no mesh reaches respond exactly 0
        self._project(V, V.shape[1])
        self._shift = self._W_red @ np.diag(self.k_h) @ self._W_red.T

    def _rigid_decoupled(self) -> bool:
        """True when the rigid-body modes R (which move no mesh) are free of damping,
        gyroscopic, circulatory and hysteretic coupling: then Z_k⁻¹ W is M-orthogonal to
        R and R can leave the basis."""
        m = self.model
        if m.tabulated_bearings:
            return False
        mats = [m.C + m.Ci, m.G, m.Kc] + [A for h in m.hysteretic_parts for A in (h.Kb, h.Kx)]
        return rigid_decoupled(self._rigid, mats)

    def _reduced_Z(self, w: float, speed: float) -> NDArray:
        r = self._red
        Z = r["K"] + speed * r["Kc"] - w * w * r["M"] + 1j * w * (r["C"] + speed * r["G"])
        for ratio, Kb, Kx in self._red_hyst:
            spin = ratio * speed
            s1, s2 = np.sign(w - spin), np.sign(-w - spin)
            Z = Z + 1j * (s1 - s2) / 2 * Kb - (s1 + s2) / 2 * Kx
        for b, ratio, Vb in self._red_bear:
            Z = Z + Vb.T @ (b.K(ratio * speed) + 1j * w * b.C(ratio * speed)) @ Vb
        return Z

    def set_output_dofs(self, dofs) -> None:
        """DOFs whose responses are kept for every frequency solved (for :meth:`recover`)."""
        self.output_dofs = np.asarray(dofs, dtype=int)
        self._solve_cache.clear()
        self._poles.clear()
        self._stacks.clear()
        self._direct_solver = None

    def _mesh_component(self, extra=()) -> NDArray:
        """DOFs in the connected components of Z's sparsity graph that hold a mesh DOF
        (or one of ``extra``): the rest is decoupled from every mesh exactly."""
        return coupled_dofs(self.model, self.W, extra)

    def _direct(self) -> DirectSolver:
        """The per-frequency factorisation (:mod:`nlgrd.nonlinear.reduction.direct_receptance`) on
        the connected components of Z's sparsity graph that hold a mesh or an output DOF
        (axial DOFs, say, are decoupled from the mesh; leaving them out is exact)."""
        if self._direct_solver is None:
            bare = assemble(self.system, mesh_stiffness=False, mesh_damping=False)
            keep = self._mesh_component(self.output_dofs)
            self._direct_solver = DirectSolver(
                self.model, bare, self.W, self.c_m, keep, self.output_dofs, self.speed_per_mesh_frequency
            )
        return self._direct_solver

    def _dZ(self, k: int, omega: float) -> NDArray:
        """dZ_k/dω of the reduced model along a sweep (Ω = ω / N_p): hysteresis and the
        coefficients of speed-tabulated bearings held fixed (their i kω C_b term is not)."""
        dZ = dynamic_stiffness_derivative(self._red, k, omega, self.speed_per_mesh_frequency)
        speed = self.speed(omega)
        for b, ratio, Vb in self._red_bear:
            dZ = dZ + 1j * k * (Vb.T @ b.C(ratio * speed) @ Vb)
        return dZ

    def _pole_residues(self, k: int) -> tuple[NDArray, NDArray, NDArray, NDArray] | None:
        """Poles λ_j and residue factors of harmonic k in the modal basis (see module docstring).

        Returns (λ (2m,), Wᵀ X_top (n_nl, 2m), X_top at the output DOFs (n_out, 2m),
        L Wᵣ (2m, n_nl)) of :class:`~nlgrd.nonlinear.reduction.pole_residue.PoleResidue`, so that
        Z_k(ω)⁻¹ Wᵣ = X_top diag(1 / (ω - λ)) L Wᵣ. None when
        the a-posteriori check against a direct solve fails (relative difference in
        :attr:`pole_check` above :data:`POLE_CHECK_RTOL`): the caller then solves directly.
        """
        if k in self._poles:
            return self._poles[k]
        r = self._red
        s = self.speed_per_mesh_frequency
        A0 = r["K"].astype(complex)
        if self._shift is not None:
            A0 = A0 + self._shift
        for ratio, Kb, Kx in self._red_hyst:
            s1, s2 = np.sign(k - ratio * s), np.sign(-k - ratio * s)
            A0 = A0 + 1j * (s1 - s2) / 2 * Kb - (s1 + s2) / 2 * Kx
        A1 = s * r["Kc"] + 1j * k * r["C"]
        A2 = -(k**2) * r["M"] + 1j * k * s * r["G"]
        pr = PoleResidue.of(A0, A1, A2)  # the companion eigenproblem, scaled
        Xt = pr.X_top
        out = (pr.poles, self._W_red.T @ Xt, self.basis[self.output_dofs] @ Xt, pr.L @ self._W_red)
        if self.max_frequency is None:  # a posteriori, across the poles' range
            err = pr.check(A0, A1, A2, self._W_red, pr.check_frequencies())
        else:  # a posteriori: against a direct solve at one frequency (kω at 0.618 of the basis range)
            wc = 0.6180339887 * self.max_frequency / k
            h_pr = out[1] @ (out[3] / (wc - out[0])[:, None])
            Zc = self._reduced_Z(k * wc, self.speed(wc))
            if self._shift is not None:
                Zc = Zc + self._shift
            h_d = self._W_red.T @ sla.solve(Zc, self._W_red.astype(complex))
            err = np.linalg.norm(h_pr - h_d) / np.linalg.norm(h_d)
        self.pole_check[k] = float(err)
        if not err <= POLE_CHECK_RTOL:
            out = None  # this harmonic is solved directly on the reduced basis
        self._poles[k] = out
        return out

    def _pole_stack(self, start: int, H: int) -> tuple | None:
        """The pole-residue forms of harmonics start..H stacked, (λ, Wᵀ X_top, output rows
        of X_top, L W) with a leading harmonic axis; None when any harmonic has none."""
        key = (start, H)
        if key not in self._stacks:
            forms = [self._pole_residues(k) for k in range(start, H + 1)]
            if any(f is None for f in forms) or len({f[0].size for f in forms}) > 1:
                self._stacks[key] = None
            else:
                self._stacks[key] = tuple(np.stack([f[i] for f in forms]) for i in range(4))
            if len(self._stacks) > 64:
                self._stacks.pop(next(iter(self._stacks)))
        return self._stacks[key]

    def _unshift(self, rows: slice, h: NDArray, U: NDArray, dh: NDArray | None) -> None:
        """In place on ``rows``: h', U', dh' of Z + W K Wᵀ (``"poles"``) to those of Z:
        h = h' (I - K h')⁻¹, U = U' (I - K h')⁻¹, dh = (I - h' K)⁻¹ dh' (I - K h')⁻¹."""
        if self._shift is None:
            return
        eye, kd = np.eye(self.n_coords), np.diag(self.k_h)
        hs = h[rows]
        left = np.linalg.inv(eye - kd @ hs)
        if dh is not None:
            dh[rows] = np.linalg.inv(eye - hs @ kd) @ dh[rows] @ left
        h[rows] = hs @ left
        U[rows] = U[rows] @ left

    def _solve(self, omega: float, H: int, derivative: bool = False) -> list:
        """[h_k, U_k at the output DOFs, dh_k/dω or None] for k = 1..H, cached per frequency.

        One entry per frequency serves every H (harmonic k's solve does not depend on H):
        a request for more harmonics than stored computes only the missing ones.
        dh_k/dω (continuation, jumps) is computed only when ``derivative`` is asked for.
        """
        key = float(omega)
        hit = self._solve_cache.get(key)
        if hit is None and self._poles_after is not None and self._poles_after <= 0:
            self._poles_after, self.method = None, "poles"  # at the next new frequency
            self._build_full_basis()
            self._solve_cache.clear()  # one form per frequency
        if hit is not None and (hit[2] is not None or not derivative):
            if hit[0].shape[0] >= H:
                return [hit[0][:H], hit[1][:H], None if hit[2] is None else hit[2][:H]]
            start, (h0, U0, dh0) = hit[0].shape[0] + 1, hit
        else:
            start, h0, U0, dh0 = 1, None, None, None
        speed = self.speed(omega)
        nc = self.n_coords
        h = np.empty((H, nc, nc), dtype=complex)
        dh = np.empty((H, nc, nc), dtype=complex) if derivative or dh0 is not None else None
        U = np.empty((H, len(self.output_dofs), nc), dtype=complex)
        if start > 1:
            h[: start - 1], U[: start - 1] = h0, U0
            if dh is not None:
                dh[: start - 1] = dh0
        derivative = dh is not None
        poles = self.method in ("modal", "poles") and not self._red_bear and omega > 0
        stack = self._pole_stack(start, H) if poles else None
        if stack is not None:  # every harmonic in pole-residue form: all at once
            lam, cw, co, Y = stack
            g = 1.0 / (omega - lam)  # (K, 2m)
            Yg = Y * g[:, :, None]
            h[start - 1 :] = cw @ Yg
            U[start - 1 :] = co @ Yg
            if derivative:
                dh[start - 1 :] = -cw @ (Yg * g[:, :, None])
            self._unshift(slice(start - 1, H), h, U, dh if derivative else None)
            start = H + 1
        if self.method == "direct" and start <= H:  # every harmonic at once
            if hit is None:  # a new frequency
                self.n_direct += 1
                if self._poles_after is not None:
                    self._poles_after -= 1
            rows = slice(start - 1, H)
            h[rows], U[rows], d = self._direct().solve(np.arange(start, H + 1), omega, derivative)
            if derivative:
                dh[rows] = d
            start = H + 1
        for k in range(start, H + 1):
            w = k * omega
            pr = self._pole_residues(k) if poles else None
            if pr is not None:
                lam, cw, co, Y = pr
                g = 1.0 / (omega - lam)
                Yg = Y * g[:, None]
                h[k - 1] = cw @ Yg
                U[k - 1] = co @ Yg
                if derivative:
                    dh[k - 1] = -cw @ (Yg * g[:, None])
                self._unshift(slice(k - 1, k), h, U, dh if derivative else None)
            else:
                Z = self._reduced_Z(w, speed)
                Wr = self._W_red.astype(complex)
                lu = sla.lu_factor(Z)
                y = sla.lu_solve(lu, Wr)
                h[k - 1] = self._W_red.T @ y
                U[k - 1] = self.basis[self.output_dofs] @ y
                if derivative:
                    x = sla.lu_solve(lu, Wr, trans=1)
                    dh[k - 1] = -x.T @ (self._dZ(k, omega) @ y)
        if len(self._solve_cache) > 20000:
            self._solve_cache.clear()
        out = self._solve_cache[key] = [h, U, dh]
        return out

    def receptance(self, omega: float, H: int) -> NDArray:
        """h_k = Wᵀ Z_k⁻¹ W for k = 1..H: shape (H, n_nl, n_nl) [m/N]."""
        return self._solve(omega, H)[0]

    def kappa(self, omega: float, H: int) -> NDArray:
        """κ_k, k = 0..H, shape (H+1, n_nl, n_nl) [N/m]."""
        out = np.empty((H + 1, self.n_coords, self.n_coords), dtype=complex)
        out[0] = self.mean_terms(self.speed(omega)).kappa
        if H:
            out[1:] = np.linalg.inv(self.receptance(omega, H))
        return out

    def kappa_derivative(self, omega: float, H: int) -> NDArray:
        """dκ_k/dω = -κ_k (dh_k/dω) κ_k along a sweep (κ_0 taken speed-independent)."""
        out = np.zeros((H + 1, self.n_coords, self.n_coords), dtype=complex)
        if H:
            h, _, dh = self._solve(omega, H, derivative=True)
            kap = np.linalg.inv(h)
            out[1:] = -kap @ dh @ kap
        return out

    def force_derivative(self, omega: float, H: int, lste: NDArray) -> NDArray:
        """dF_k/dω = i k c_m E_k (k >= 1), 0 for the mean."""
        out = np.zeros((H + 1, self.n_coords), dtype=complex)
        k = np.arange(1, H + 1)[:, None]
        out[1:] = 1j * k * self.c_m[None, :] * lste[1:]
        return out

    def force(self, omega: float, H: int, lste: NDArray) -> NDArray:
        """F_k, k = 0..H, shape (H+1, n_nl) [N], for LSTE harmonics ``lste`` (H+1, n_nl) complex."""
        F = np.empty((H + 1, self.n_coords), dtype=complex)
        F[0] = self.mean_terms(self.speed(omega)).force
        k = np.arange(1, H + 1)[:, None]
        F[1:] = 1j * k * omega * self.c_m[None, :] * lste[1:]
        return F

    def recover(
        self, omega: float, Y: NDArray, G: NDArray, F: NDArray, dofs: NDArray | None = None
    ) -> NDArray:
        """Complex harmonics Q_k (k = 0..H) of ``dofs`` (default: the output DOFs) from the mesh solution.

        Y, G, F: (H+1, n_nl) complex harmonics of the mesh coordinates, of the nonlinear
        forces and of the reduced forcing. Q_0 = K_r⁻¹ (F_static - W (G_0 - k_h Y_0)),
        Q_k = Z_k⁻¹ W (F_k - G_k).
        """
        if dofs is not None and not np.array_equal(np.asarray(dofs), self.output_dofs):
            self.set_output_dofs(dofs)
        dofs = self.output_dofs
        H = Y.shape[0] - 1
        mt = self.mean_terms(self.speed(omega))
        Q = np.empty((H + 1, len(dofs)), dtype=complex)
        Q[0] = mt.x_static[dofs] - mt.x_mesh[dofs] @ (G[0] - self.k_h * Y[0]).real
        if H:
            U = self._solve(omega, H)[1]
            Q[1:] = np.einsum("kdj,kj->kd", U, F[1:] - G[1:])
        return Q

    def state_space(self, omega: float, max_frequency: float) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """Dense (M, D, K, W) of the linear part projected on a modal basis, for stability.

        Basis: the rigid-body and lowest modes of the linear system (meshes at k_h) up to
        3 x ``max_frequency`` [rad/s] plus the static attachment vectors K_r⁻¹ W; D holds
        C, internal damping, Ω G, bearing damping and c_m w wᵀ at the speed of mesh
        frequency ``omega``; K leaves out k_h. Hysteretic damping has no time-domain form:
        ModelError (``loss_factor``, :data:`~nlgrd.nonlinear.reduction.state_space.HYSTERETIC_REFUSAL`;
        it was left out, the multipliers those of the model without it).
        """
        if self.model.hysteretic_parts:
            raise ModelError("loss_factor", HYSTERETIC_REFUSAL)
        key = float(max_frequency)
        entry = self._stability_basis.get(key)
        if entry is None:
            m = self.model
            Kr = (m.K + self._mesh_stiffness()).tocsc()
            cutoff = 3.0 * key
            lam, vec = lowest_modes(Kr, m.M, cutoff, start=30, cap=STABILITY_MODE_CAP, what="stability basis")
            att = spla.splu((Kr + m.M).tocsc()).solve(self.W)
            V, _ = np.linalg.qr(np.column_stack([vec[:, lam <= cutoff**2], att]))
            if len(self._stability_basis) >= 8:
                self._stability_basis.pop(next(iter(self._stability_basis)))
            P = lambda A: V.T @ (A @ V)  # noqa: E731
            # the parts linear in the speed, projected once (tabulated bearings per speed)
            parts = (P(m.M), P(m.C + m.Ci), P(m.G), P(m.K), P(m.Kc), V.T @ self.W)
            entry = self._stability_basis[key] = (V, parts)
        V, (Mr, Cr, Gr, Kr_, Kcr, Wr) = entry
        speed = self.speed(omega)
        D, K = Cr + speed * Gr, Kr_ + speed * Kcr
        if self.model.tabulated_bearings:
            Kb, Cb = self.model._bearing_matrices(speed)
            D, K = D + V.T @ (Cb @ V), K + V.T @ (Kb @ V)
        return Mr, D, K, Wr
