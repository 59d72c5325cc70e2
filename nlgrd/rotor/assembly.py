"""Assembly of the global linear matrices of a rotor system.

The linear equations of motion are

    M q'' + (C + C_i + Ω G) q' + (K + Ω K_c) q = f(t)

with Ω the reference (pinion) speed; each shaft's gyroscopic and circulatory terms
are scaled by its speed ratio. Internal hysteretic damping enters the frequency
domain at frequency ω through :meth:`LinearModel.hysteretic`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from nlgrd.rotor.structural_damping import structural_damping_matrix
from nlgrd.rotor.system import DOFS_PER_NODE, RotorSystem


class _Builder:
    """Collects COO triplets for one sparse matrix."""

    def __init__(self, n: int):
        self.n = n
        self.rows: list[NDArray] = []
        self.cols: list[NDArray] = []
        self.vals: list[NDArray] = []

    def add(self, dofs: NDArray, mat: NDArray) -> None:
        r, c = np.meshgrid(dofs, dofs, indexing="ij")
        keep = mat != 0
        self.rows.append(r[keep])
        self.cols.append(c[keep])
        self.vals.append(mat[keep])

    def build(self) -> sp.csc_matrix:
        if not self.rows:
            return sp.csc_matrix((self.n, self.n))
        return sp.csc_matrix(
            (np.concatenate(self.vals), (np.concatenate(self.rows), np.concatenate(self.cols))),
            shape=(self.n, self.n),
        )


@dataclass(frozen=True)
class HystereticPart:
    """One shaft's internal hysteretic damping: loss factor, speed ratio and its bending matrices.

    Attributes
    ----------
    loss_factor : float
        Factor applied to both matrices, the hysteretic loss factor eta_h [-];
        :func:`assemble` folds eta_h into the matrices and stores 1.0 here.
    speed_ratio : float
        Spin speed of the shaft divided by the reference speed [-], signed.
    Kb : scipy.sparse.csc_matrix, (n_dofs, n_dofs)
        Bending stiffness of the shaft in global DOFs [N/m, N m/rad].
    Kx : scipy.sparse.csc_matrix, (n_dofs, n_dofs)
        The same stiffness cross-coupled between the bending planes [N/m, N m/rad].
    """

    loss_factor: float
    speed_ratio: float
    Kb: sp.csc_matrix
    Kx: sp.csc_matrix


@dataclass(frozen=True)
class MeshLink:
    """A linear spring-damper along a projection vector w (a gear mesh at k_h, c_m).

    Attributes
    ----------
    w : ndarray, (n_dofs,)
        Projection vector, δ = wᵀ q the compression along the line of action: unit-vector
        components on the lateral DOFs [-], base radii on the torsional ones [m].
    stiffness : float
        Average mesh stiffness k_h [N/m].
    damping : float
        Mesh damping coefficient c_m [N s/m].
    """

    w: NDArray
    stiffness: float
    damping: float


@dataclass(frozen=True)
class LinearModel:
    """Global sparse matrices of a rotor system, SI units.

    Attributes
    ----------
    system : RotorSystem or None
        The system assembled; None for a model built from bare matrices.
    M, K, C, G : scipy.sparse.csc_matrix
        Mass [kg, kg m^2], speed-independent stiffness [N/m] and damping [N s/m]
        (bearings without speed table, couplings, mesh if included), gyroscopic per
        unit reference speed [kg m^2].
    Ci : csc_matrix
        Internal viscous damping sum of eta_v Kb over the shafts [N s/m].
    Kc : csc_matrix
        Circulatory stiffness per unit reference speed, sum of ratio eta_v Kx [N s/m].
    hysteretic_parts : tuple of HystereticPart
        Internal hysteretic damping, shaft by shaft.
    tabulated_bearings : tuple
        (bearing, shaft speed ratio, dofs) of speed-dependent bearings, rebuilt per speed.
    meshes : tuple of MeshLink
        Gear meshes, with their projection vectors.
    """

    system: RotorSystem | None
    M: sp.csc_matrix
    K: sp.csc_matrix
    C: sp.csc_matrix
    G: sp.csc_matrix
    Ci: sp.csc_matrix
    Kc: sp.csc_matrix
    hysteretic_parts: tuple[HystereticPart, ...] = ()
    tabulated_bearings: tuple = ()
    meshes: tuple[MeshLink, ...] = field(default=())

    @property
    def n_dofs(self) -> int:
        """Number of DOFs."""
        return self.M.shape[0]

    @classmethod
    def from_matrices(cls, M, K, C=None, G=None, system: RotorSystem | None = None) -> LinearModel:
        """A linear model from given matrices (dense or sparse), for lumped-parameter models.

        Parameters
        ----------
        M, K : array_like
            Mass [kg] and stiffness [N/m] matrices, n x n.
        C, G : array_like, optional
            Damping [N s/m] and gyroscopic (per unit speed) matrices; zero when omitted.
        system : RotorSystem, optional
            The system the matrices belong to (for DOF names); None by default.

        Returns
        -------
        LinearModel
            Without internal damping, tabulated bearings or meshes.
        """
        M = sp.csc_matrix(M, dtype=float)
        n = M.shape[0]
        zero = sp.csc_matrix((n, n))
        return cls(
            system=system,
            M=M,
            K=sp.csc_matrix(K, dtype=float),
            C=zero if C is None else sp.csc_matrix(C, dtype=float),
            G=zero if G is None else sp.csc_matrix(G, dtype=float),
            Ci=zero,
            Kc=zero,
        )

    def _bearing_matrices(self, speed: float) -> tuple[sp.csc_matrix, sp.csc_matrix]:
        kb, cb = _Builder(self.n_dofs), _Builder(self.n_dofs)
        for bearing, ratio, dofs in self.tabulated_bearings:
            kb.add(dofs, bearing.K(ratio * speed))
            cb.add(dofs, bearing.C(ratio * speed))
        return kb.build(), cb.build()

    def stiffness(self, speed: float = 0.0) -> sp.csc_matrix:
        """Total stiffness at reference speed ``speed`` [rad/s], circulatory terms included."""
        k = self.K + speed * self.Kc
        if self.tabulated_bearings:
            k = k + self._bearing_matrices(speed)[0]
        return k.tocsc()

    def damping(self, speed: float = 0.0) -> sp.csc_matrix:
        """Total velocity matrix C + C_i + Ω G at reference speed ``speed`` [rad/s]."""
        c = self.C + self.Ci + speed * self.G
        if self.tabulated_bearings:
            c = c + self._bearing_matrices(speed)[1]
        return c.tocsc()

    def hysteretic(self, omega: float, speed: float = 0.0) -> sp.csc_matrix:
        """Dynamic stiffness of internal hysteretic damping at frequency ``omega`` [rad/s].

        In the rotating frame the force is -K (1 + i eta sgn(ω_r)) u for a whirl
        component of rotating-frame frequency ω_r. A fixed-frame harmonic at ω has a
        forward part (ω_r = ω - Ω_s) and a backward part (ω_r = -ω - Ω_s); collecting
        both gives i eta a Kb - eta c Kx with a = (s1 - s2)/2, c = (s1 + s2)/2,
        s1 = sgn(ω - Ω_s), s2 = sgn(-ω - Ω_s) (Özgüven & Özkan 1984 give the same
        split into a direct and a circulatory part).
        """
        n = self.n_dofs
        out = sp.csc_matrix((n, n), dtype=complex)
        for part in self.hysteretic_parts:
            spin = part.speed_ratio * speed
            s1, s2 = np.sign(omega - spin), np.sign(-omega - spin)
            a, c = (s1 - s2) / 2, (s1 + s2) / 2
            out = out + part.loss_factor * (1j * a * part.Kb - c * part.Kx)
        return out.tocsc()

    def dynamic_stiffness(self, omega: float, speed: float = 0.0) -> sp.csc_matrix:
        """Z(ω) = K + Ω K_c - ω² M + i ω (C + C_i + Ω G) + bearings(Ω) + hysteretic, complex sparse [N/m].

        Built as a linear combination of data arrays aligned on one sparsity pattern
        (set up once), so a sweep pays microseconds per matrix, not a sparse sum.
        """
        pat = self._pattern
        data = self.dynamic_stiffness_data(omega, speed)
        return sp.csc_matrix((data, pat["indices"], pat["indptr"]), shape=self.M.shape)

    def dynamic_stiffness_data(self, omega: float, speed: float = 0.0) -> NDArray:
        """The non-zeros of :meth:`dynamic_stiffness` on the pattern ``_pattern`` (CSC order)."""
        pat = self._pattern
        data = plain_dynamic_stiffness(pat, omega, speed)
        for part, (kb, kx) in zip(self.hysteretic_parts, pat["hyst"], strict=True):
            spin = part.speed_ratio * speed
            s1, s2 = np.sign(omega - spin), np.sign(-omega - spin)
            data = data + part.loss_factor * (1j * (s1 - s2) / 2 * kb - (s1 + s2) / 2 * kx)
        for (bearing, ratio, _), pos in zip(self.tabulated_bearings, pat["bear"], strict=True):
            blk = bearing.K(ratio * speed) + 1j * omega * bearing.C(ratio * speed)
            np.add.at(data, pos, blk.ravel())
        return data

    def dynamic_stiffness_slope_data(self, omega: float, speed: float = 0.0) -> NDArray:
        """dZ/dω at a fixed speed on the pattern ``_pattern`` (CSC order): -2ω M
        + i (C + C_i + Ω G) + i C_b(Ω) of the tabulated bearings (the hysteretic part is
        constant between its whirl-sign changes) [N s/m]."""
        pat = self._pattern
        data = -2 * omega * pat["M"] + 1j * (pat["C"] + pat["Ci"] + speed * pat["G"])
        for (bearing, ratio, _), pos in zip(self.tabulated_bearings, pat["bear"], strict=True):
            np.add.at(data, pos, (1j * bearing.C(ratio * speed)).ravel())
        return data

    @cached_property
    def _pattern(self) -> dict:
        """The union sparsity pattern and every matrix's data aligned on it."""
        mats = {"K": self.K, "Kc": self.Kc, "M": self.M, "C": self.C, "Ci": self.Ci, "G": self.G}
        n = self.n_dofs
        union = sum((abs(m) for m in mats.values()), sp.csc_matrix((n, n)))
        extra = [abs(h.Kb) + abs(h.Kx) for h in self.hysteretic_parts]
        rows, cols = [], []
        for _, _, dofs in self.tabulated_bearings:
            r, c = np.meshgrid(dofs, dofs, indexing="ij")
            rows.append(r.ravel())
            cols.append(c.ravel())
        if rows:
            extra.append(
                sp.csc_matrix(
                    (np.ones(sum(map(len, rows))), (np.concatenate(rows), np.concatenate(cols))), (n, n)
                )
            )
        for e in extra:
            union = union + e
        union = sp.csc_matrix(union)
        union.sum_duplicates()
        union.sort_indices()
        col = np.repeat(np.arange(n), np.diff(union.indptr))
        keys = col.astype(np.int64) * n + union.indices

        def align(A) -> NDArray:
            A = sp.csc_matrix(A)
            A.sum_duplicates()
            c = np.repeat(np.arange(n), np.diff(A.indptr))
            out = np.zeros(len(keys), dtype=complex)
            out[np.searchsorted(keys, c.astype(np.int64) * n + A.indices)] = A.data
            return out

        pat = {k: align(m) for k, m in mats.items()}
        pat["hyst"] = [(align(h.Kb), align(h.Kx)) for h in self.hysteretic_parts]
        pat["bear"] = []
        for _, _, dofs in self.tabulated_bearings:
            r, c = np.meshgrid(dofs, dofs, indexing="ij")
            pat["bear"].append(np.searchsorted(keys, c.ravel().astype(np.int64) * n + r.ravel()))
        pat["indices"], pat["indptr"], pat["cols"] = union.indices.copy(), union.indptr.copy(), col
        return pat

    @property
    def pattern_entries(self) -> tuple[NDArray, NDArray]:
        """Row and column of each non-zero of :meth:`dynamic_stiffness_data` (CSC order) [-]."""
        return self._pattern["indices"], self._pattern["cols"]


def plain_dynamic_stiffness(parts, omega, speed: float) -> NDArray:
    """K + Ω K_c - ω² M + i ω (C + C_i + Ω G) of the parts given (matrices, or their
    non-zeros on one pattern, under those keys); ``omega`` may be an array that broadcasts
    against them. Hysteretic parts and speed-tabulated bearings are not included
    (:meth:`LinearModel.dynamic_stiffness_data` adds them).

    Parameters
    ----------
    parts : mapping
        "K", "Kc", "M", "C", "Ci", "G" [SI].
    omega : float or ndarray
        Excitation frequency ω [rad/s].
    speed : float
        Reference speed Ω [rad/s].

    Returns
    -------
    ndarray of complex
        The dynamic stiffness in the layout of ``parts`` [N/m].
    """
    return (
        parts["K"]
        + speed * parts["Kc"]
        - omega**2 * parts["M"]
        + 1j * omega * (parts["C"] + parts["Ci"] + speed * parts["G"])
    )


def mesh_matrix(W: NDArray, gains: NDArray) -> sp.csc_matrix:
    """Σ_j g_j w_j w_jᵀ for the columns w_j of W (n x n_nl) as a sparse matrix [N/m].

    The meshes' stiffness (or damping) along their lines of action; W has a dozen
    non-zeros per mesh, so the n x n outer products are never formed densely.

    Parameters
    ----------
    W : ndarray, (n,) or (n, n_nl)
        Projection vectors w_j of the meshes as columns (see :class:`MeshLink`).
    gains : array_like, (n_nl,)
        Gain g_j of each mesh: a stiffness [N/m] or a damping coefficient [N s/m].

    Returns
    -------
    scipy.sparse.csc_matrix, (n, n)
        Σ_j g_j w_j w_jᵀ, in the unit of the gains (times m² on the torsional DOFs).
    """
    W = np.asarray(W, dtype=float).reshape(W.shape[0], -1)
    idx = np.flatnonzero(np.any(W != 0, axis=1))
    Wi = W[idx]
    block = (Wi * np.asarray(gains, dtype=float).reshape(1, -1)) @ Wi.T
    r, c = np.meshgrid(idx, idx, indexing="ij")
    n = W.shape[0]
    return sp.csc_matrix((block.ravel(), (r.ravel(), c.ravel())), shape=(n, n))


def assemble(system: RotorSystem, mesh_stiffness: bool = True, mesh_damping: bool = True) -> LinearModel:
    """Assemble the global sparse matrices of ``system``.

    Parameters
    ----------
    system : RotorSystem
        The model.
    mesh_stiffness : bool
        Add each gear mesh's average stiffness k_h w wᵀ (linear analyses). The
        nonlinear solver leaves it out and treats the mesh force itself.
    mesh_damping : bool
        Add each gear mesh's damping c_m w wᵀ.

    The system's :class:`~nlgrd.rotor.structural_damping.StructuralDamping` (``damping``)
    is added to C whatever the flags: it is built from the model at rest with every mesh
    at k_h and c_m.

    Returns
    -------
    LinearModel
        The global matrices in SI units.
    """
    dm = system.dofs
    n = dm.n_dofs
    M, K, C, G, Ci, Kc = (_Builder(n) for _ in range(6))
    hyst = []
    for s, shaft in enumerate(system.shafts):
        Kb_s, Kx_s = _Builder(n), _Builder(n)
        eta_h_values = set()
        for e, el in enumerate(shaft.elements):
            dofs = np.concatenate([dm.node_dofs(s, e), dm.node_dofs(s, e + 1)])
            M.add(dofs, el.M())
            K.add(dofs, el.K())
            G.add(dofs, shaft.speed_ratio * el.G())
            eta_v = el.material.viscous_damping
            if eta_v > 0:
                Ci.add(dofs, eta_v * el.Kb())
                Kc.add(dofs, shaft.speed_ratio * eta_v * el.Kx())
            if el.material.loss_factor > 0:
                eta = el.material.loss_factor
                eta_h_values.add(eta)
                Kb_s.add(dofs, eta * el.Kb())
                Kx_s.add(dofs, eta * el.Kx())
        if eta_h_values:
            # loss factor folded into the matrices, so the part carries 1.0
            hyst.append(HystereticPart(1.0, shaft.speed_ratio, Kb_s.build(), Kx_s.build()))
    for d in system.disks:
        dofs = dm.node_dofs(d.shaft, d.node)
        M.add(dofs, d.M())
        G.add(dofs, system.shafts[d.shaft].speed_ratio * d.G())
    tabulated = []
    for b in system.bearings:
        dofs = dm.node_dofs(b.shaft, b.node)
        if b.speed_dependent:
            tabulated.append((b, system.shafts[b.shaft].speed_ratio, dofs))
        else:
            K.add(dofs, b.K())
            C.add(dofs, b.C())
    for c in system.couplings:
        a = dm.node_dofs(c.shaft_a, c.node_a)
        if c.grounded:
            K.add(a, c.K()[:6, :6])
            C.add(a, c.C()[:6, :6])
        else:
            dofs = np.concatenate([a, dm.node_dofs(c.shaft_b, c.node_b)])
            K.add(dofs, c.K())
            C.add(dofs, c.C())
    meshes = []
    K_mesh, C_mesh = _Builder(n), _Builder(n)
    for g in system.gear_pairs:
        w = g.projection(system)
        link = MeshLink(w, g.stiffness(), g.damping_coefficient(system))
        meshes.append(link)
        idx = np.flatnonzero(w)
        ww = np.outer(w[idx], w[idx])
        if mesh_stiffness:
            K.add(idx, link.stiffness * ww)
        else:
            K_mesh.add(idx, link.stiffness * ww)
        if mesh_damping:
            C.add(idx, link.damping * ww)
        else:
            C_mesh.add(idx, link.damping * ww)
    M_, K_, C_, Ci_ = M.build(), K.build(), C.build(), Ci.build()
    if system.damping is not None and system.damping.active:
        # the whole rotor's damping, from the model at rest with the meshes at k_h and
        # c_m whatever the flags say, so every analysis adds the same matrix
        K0, C0 = K_ + K_mesh.build(), C_ + C_mesh.build() + Ci_
        for b, _, dofs in tabulated:
            r, cc = np.meshgrid(dofs, dofs, indexing="ij")
            K0 = K0 + sp.csc_matrix((b.K(0.0).ravel(), (r.ravel(), cc.ravel())), shape=(n, n))
            C0 = C0 + sp.csc_matrix((b.C(0.0).ravel(), (r.ravel(), cc.ravel())), shape=(n, n))
        C_ = C_ + structural_damping_matrix(system.damping, M_, K0, C0)
    return LinearModel(
        system=system,
        M=M_,
        K=sp.csc_matrix(K_),
        C=sp.csc_matrix(C_),
        G=G.build(),
        Ci=Ci_,
        Kc=Kc.build(),
        hysteretic_parts=tuple(hyst),
        tabulated_bearings=tuple(tabulated),
        meshes=tuple(meshes),
    )


__all__ = ["assemble", "mesh_matrix", "plain_dynamic_stiffness", "LinearModel", "MeshLink", "DOFS_PER_NODE"]
