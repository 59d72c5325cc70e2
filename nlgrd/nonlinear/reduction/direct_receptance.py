"""Direct receptances h_k = Wᵀ Z_k⁻¹ W of a geared rotor: one factorisation per harmonic
and frequency (the ``"direct"`` method of :class:`~nlgrd.nonlinear.reduction.receptance.MeshReceptance`).

Z_k holds the mesh damping c_m w wᵀ, which couples the shafts and widens Z's band. The
factorisation is made of Z'_k = Z_k - i kω W diag(c_m) Wᵀ instead: its sparsity graph is
the shafts' own, which a reverse Cuthill-McKee ordering turns into a narrow band (half
bandwidth 7 on the two-shaft example against 26 with the mesh damping), factorised by
LAPACK's banded LU (``zgbtrf``, O(n b²)). The mesh damping comes back by the
Sherman-Morrison-Woodbury identity (Golub & Van Loan, Matrix Computations, 4th ed., §2.1.4),
with D = i kω diag(c_m), h' = Wᵀ Z'⁻¹ W and S = (I + D h')⁻¹:

    h = h' S,   Z⁻¹ W = Z'⁻¹ W S,
    dh/dω = (I - h D) (dh'/dω) S - h (dD/dω) h,   dh'/dω = -(Z'⁻ᵀ W)ᵀ (dZ'/dω) (Z'⁻¹ W).

Z' can be nearly singular where Z is not (a shaft mode that only the mesh damps). The
banded LU is backward stable, so the computed h' is exact for Z' + E with E of rounding
size, and the identity then gives h exactly for Z + E: with one mesh (S a scalar) the
result is as accurate as a factorisation of Z. With several meshes the small matrix
I + D h' amplifies rounding by its condition number (dh/dω by its square); above
``COND_MAX`` (``COND_MAX_DERIVATIVE`` when dh/dω is asked for), or when the band
is wider than ``BAND_LIMIT`` or Z' exactly singular, Z itself is factorised by sparse LU
(SuperLU), as it always was. Both paths agree to rounding (tests/test_direct_receptance.py)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray
from scipy.linalg.lapack import zgbtrf, zgbtrs
from scipy.sparse.csgraph import reverse_cuthill_mckee

from nlgrd.rotor.assembly import LinearModel, plain_dynamic_stiffness

#: Widest half bandwidth factorised as a band (wider: sparse LU of the whole Z).
BAND_LIMIT = 64
#: Above this condition number of I + D h' (several meshes), sparse LU of Z instead; for
#: dh/dω, whose rounding grows as its square, above ``COND_MAX_DERIVATIVE``.
COND_MAX = 1e6
COND_MAX_DERIVATIVE = 1e3


def dynamic_stiffness_derivative(parts, harmonic, omega: float, speed_per: float):
    """dZ_k/dω along a sweep (Ω = ``speed_per`` ω) of the parts given (hysteresis held fixed;
    speed-tabulated bearings: :func:`model_stiffness_derivative`).

    Z_k = K + Ω K_c - (kω)² M + i kω (C + C_i + Ω G), so dZ_k/dω = s K_c - 2k²ω M
    + i k (C + C_i + Ω G) + i kω s G with s = ``speed_per``.

    Parameters
    ----------
    parts : mapping
        The matrices (or their non-zeros on one pattern) under the keys "Kc", "M", "C",
        "G" and optionally "Ci" (``LinearModel._pattern``, or a model reduced on a basis).
    harmonic : int or ndarray
        k, the harmonic of the mesh frequency (an array broadcasts against the parts).
    omega : float
        Mesh frequency ω [rad/s].
    speed_per : float
        Reference speed per mesh frequency, Ω = ``speed_per`` ω [-].

    Returns
    -------
    ndarray of complex
        dZ_k/dω in the layout of ``parts`` [N s/m].
    """
    k, s = harmonic, speed_per
    w, speed = k * omega, s * omega
    damping = parts["C"] + parts.get("Ci", 0.0) + speed * parts["G"]
    return s * parts["Kc"] - 2 * k * w * parts["M"] + 1j * k * damping + 1j * w * s * parts["G"]


def model_stiffness_derivative(model: LinearModel, harmonic: int, omega: float, speed_per: float) -> NDArray:
    """dZ_k/dω of a model along a sweep, speed-tabulated bearings included.

    :func:`dynamic_stiffness_derivative` of the model's matrices plus, for each bearing
    tabulated against speed (Ω_b = r s ω, r its shaft's speed ratio), the derivative of
    K_b(Ω_b) + i kω C_b(Ω_b): i k C_b + r s (dK_b/dΩ + i kω dC_b/dΩ), the slopes those of
    the table's linear interpolation (:meth:`nlgrd.rotor.bearing.Bearing.K_slope`).

    Parameters
    ----------
    model : LinearModel
        The linear model.
    harmonic : int
        k, the harmonic of the mesh frequency.
    omega : float
        Mesh frequency ω [rad/s].
    speed_per : float
        Reference speed per mesh frequency, Ω = ``speed_per`` ω [-].

    Returns
    -------
    ndarray of complex
        The non-zeros of dZ_k/dω on ``model._pattern`` (CSC order) [N s/m].
    """
    pat = model._pattern
    data = dynamic_stiffness_derivative(pat, harmonic, omega, speed_per)
    for (bearing, ratio, _), pos in zip(model.tabulated_bearings, pat["bear"], strict=True):
        spin, per = ratio * speed_per * omega, ratio * speed_per
        slope = per * (bearing.K_slope(spin) + 1j * harmonic * omega * bearing.C_slope(spin))
        np.add.at(data, pos, (1j * harmonic * bearing.C(spin) + slope).ravel())
    return data


class _Restriction:
    """A model's pattern restricted to the DOFs ``keep``: selected non-zeros, their rows and
    columns in the restricted numbering, and a CSC matrix whose data a solve replaces."""

    def __init__(self, model: LinearModel, keep: NDArray):
        pat = model._pattern
        n = model.n_dofs
        new = np.full(n, -1)
        new[keep] = np.arange(len(keep))
        col = model.pattern_entries[1]
        self.sel = np.flatnonzero((new[pat["indices"]] >= 0) & (new[col] >= 0))
        nk = len(keep)
        indptr = np.concatenate([[0], np.cumsum(np.bincount(new[col[self.sel]], minlength=nk))])
        self.rows, self.cols = new[pat["indices"][self.sel]], new[col[self.sel]]
        self.Z = sp.csc_matrix((np.zeros(len(self.sel), dtype=complex), self.rows, indptr), shape=(nk, nk))
        self.model, self.new = model, new


class _Band:
    """Reverse Cuthill-McKee ordering and LAPACK band storage of a restricted pattern."""

    def __init__(self, r: _Restriction):
        nk = r.Z.shape[0]
        g = sp.csr_matrix((np.ones(len(r.rows)), (r.rows, r.cols)), shape=(nk, nk))
        self.perm = reverse_cuthill_mckee((g + g.T).tocsr(), symmetric_mode=True)
        inv = np.empty_like(self.perm)
        inv[self.perm] = np.arange(nk)
        self.inv = inv
        self.ri, self.ci = inv[r.rows], inv[r.cols]
        self.kl = int(max(0, np.max(self.ri - self.ci, initial=0)))
        self.ku = int(max(0, np.max(self.ci - self.ri, initial=0)))
        self.ld = 2 * self.kl + self.ku + 1
        self.flat = (self.kl + self.ku + self.ri - self.ci) + self.ld * self.ci  # Fortran order
        self.n = nk

    @property
    def half_width(self) -> int:
        return max(self.kl, self.ku)

    def factor(self, data: NDArray):
        """(LU, pivots) of the matrix with non-zeros ``data``; None when exactly singular."""
        buf = np.zeros(self.ld * self.n, dtype=complex)
        buf[self.flat] = data
        ab = buf.reshape((self.ld, self.n), order="F")
        lu, piv, info = zgbtrf(ab, self.kl, self.ku, overwrite_ab=1)
        return None if info != 0 else (lu, piv)

    def solve(self, fac, rhs_perm: NDArray, trans: int = 0) -> NDArray:
        x, _ = zgbtrs(fac[0], self.kl, self.ku, rhs_perm, fac[1], trans=trans)
        return x


class DirectSolver:
    """h_k, Z_k⁻¹ W at output DOFs and dh_k/dω, by a factorisation per harmonic and frequency.

    Parameters
    ----------
    model : LinearModel
        The linear model with the mesh damping and without the mesh stiffness.
    bare : LinearModel
        The same without the mesh damping (the band's pattern).
    W : ndarray (n, n_nl)
        The meshes' projection vectors.
    c_m : ndarray (n_nl,)
        The meshes' damping coefficients [N s/m].
    keep : ndarray of int
        DOFs of the connected components holding a mesh or an output DOF.
    output_dofs : ndarray of int
        DOFs whose responses Z_k⁻¹ W are returned.
    speed_per : float
        Reference speed per mesh frequency (Ω = ``speed_per`` ω).
    """

    def __init__(self, model, bare, W, c_m, keep, output_dofs, speed_per: float):
        self.keep = np.asarray(keep, dtype=int)
        self.full = _Restriction(model, self.keep)
        self.bare = _Restriction(bare, self.keep)
        self.c_m = np.asarray(c_m, dtype=float)
        self.speed_per = float(speed_per)
        self.W = np.ascontiguousarray(W[keep], dtype=complex)
        self.out = self.full.new[np.asarray(output_dofs, dtype=int)]
        band = _Band(self.bare) if self.keep.size else None
        self.band = band if band is not None and band.half_width <= BAND_LIMIT else None
        if self.band is not None:
            self.W_perm = np.asfortranarray(self.W[band.perm])
            pat, sel = bare._pattern, self.bare.sel
            # the pattern's parts on the band's non-zeros (the plain case: no hysteresis
            # and no tabulated bearings, whose data the model computes per frequency)
            plain = not (bare.hysteretic_parts or bare.tabulated_bearings)
            self._parts = {k: pat[k][sel] for k in ("K", "Kc", "M", "C", "Ci", "G")} if plain else None
        #: harmonics solved by band (Woodbury) and by sparse LU of Z
        self.n_band = self.n_sparse = 0

    @property
    def banded(self) -> bool:
        """True when Z' is factorised as a band."""
        return self.band is not None

    def _band_data(self, ks: NDArray, omega: float) -> NDArray:
        """Non-zeros of Z'_k on the band's pattern, one row per harmonic in ``ks``."""
        speed = self.speed_per * omega
        p = self._parts
        if p is None:
            m, sel = self.bare.model, self.bare.sel
            return np.stack([m.dynamic_stiffness_data(k * omega, speed)[sel] for k in ks])
        return plain_dynamic_stiffness(p, (ks * omega)[:, None], speed)

    def _band_derivative(self, ks: NDArray, omega: float) -> NDArray:
        """dZ'_k/dω on the band's pattern, one row per harmonic in ``ks``."""
        p, s = self._parts, self.speed_per
        if p is None:
            m, sel = self.bare.model, self.bare.sel
            return np.stack([model_stiffness_derivative(m, int(k), omega, s)[sel] for k in ks])
        return dynamic_stiffness_derivative(p, ks[:, None].astype(float), omega, s)

    def solve(self, harmonics, omega: float, derivative: bool) -> tuple[NDArray, NDArray, NDArray | None]:
        """Receptances of the given harmonics at one mesh frequency.

        Parameters
        ----------
        harmonics : array_like of int
            The harmonics k of the mesh frequency.
        omega : float
            Mesh frequency ω [rad/s].
        derivative : bool
            Also return dh_k/dω.

        Returns
        -------
        h : ndarray (K, n_nl, n_nl)
            h_k = Wᵀ Z_k⁻¹ W [m/N].
        U : ndarray (K, n_out, n_nl)
            Z_k⁻¹ W at the output DOFs [m/N, rad/N].
        dh : ndarray (K, n_nl, n_nl) or None
            dh_k/dω [m s/N] when ``derivative``.
        """
        ks = np.asarray(harmonics, dtype=int)
        nc = self.W.shape[1]
        h = np.empty((len(ks), nc, nc), dtype=complex)
        U = np.empty((len(ks), len(self.out), nc), dtype=complex)
        dh = np.empty((len(ks), nc, nc), dtype=complex) if derivative else None
        if self.keep.size == 0:  # no DOF a mesh reaches
            h[:], U[:] = 0.0, 0.0
            if derivative:
                dh[:] = 0.0
            return h, U, dh
        todo = np.ones(len(ks), dtype=bool)
        if self.band is not None:
            done = self._woodbury(ks, omega, derivative, h, U, dh)
            todo = ~done
            self.n_band += int(np.sum(done))
        for i in np.flatnonzero(todo):
            self.n_sparse += 1
            h[i], U[i], d = self._sparse(int(ks[i]), omega, derivative)
            if derivative:
                dh[i] = d
        return h, U, dh

    def _woodbury(self, ks, omega, derivative, h, U, dh) -> NDArray:
        """Band solves of Z'_k and the identity, in place; which harmonics succeeded."""
        b, Wp = self.band, self.W_perm
        data = self._band_data(ks, omega)
        nc = Wp.shape[1]
        ok = np.zeros(len(ks), dtype=bool)
        Y = np.zeros((len(ks), b.n, nc), dtype=complex)
        V = np.zeros_like(Y) if derivative else None
        for i in range(len(ks)):
            fac = b.factor(data[i])
            if fac is None:
                continue
            ok[i] = True
            Y[i] = b.solve(fac, Wp)  # Z'⁻¹ W in the band's order
            if derivative:
                V[i] = b.solve(fac, Wp, trans=1)
        hp = Wp.T.real @ Y
        D = 1j * omega * ks[:, None] * self.c_m  # (K, n_nl): the diagonals of D_k
        A = np.eye(nc) + D[:, :, None] * hp
        if nc > 1:
            with np.errstate(all="ignore"):
                ok &= np.linalg.cond(A) <= (COND_MAX_DERIVATIVE if derivative else COND_MAX)
        A[~ok] = np.eye(nc)
        S = np.linalg.inv(A)
        hk = hp @ S
        h[ok] = hk[ok]
        U[ok] = (Y[:, b.inv[self.out], :] @ S)[ok]
        if derivative:
            dZ = self._band_derivative(ks, omega)
            dhp = -np.einsum("kri,kr,krj->kij", V[:, b.ri], dZ, Y[:, b.ci])
            dD = 1j * ks[:, None] * self.c_m
            left = np.eye(nc) - hk * D[:, None, :]  # I - h D
            dh[ok] = (left @ dhp @ S - (hk * dD[:, None, :]) @ hk)[ok]
        return ok

    def _sparse(self, k: int, omega: float, derivative: bool):
        r = self.full
        r.Z.data = r.model.dynamic_stiffness_data(k * omega, self.speed_per * omega)[r.sel]
        lu = spla.splu(r.Z, permc_spec="MMD_AT_PLUS_A")
        u = lu.solve(self.W)
        h = self.W.T.real @ u
        dh = None
        if derivative:  # dh = -vᵀ dZ u, summed over the non-zeros of dZ
            v = lu.solve(self.W, trans="T")
            d = model_stiffness_derivative(r.model, k, omega, self.speed_per)[r.sel]
            dh = -np.einsum("ri,r,rj->ij", v[r.rows], d, u[r.cols])
        return h, u[self.out], dh


__all__ = [
    "DirectSolver",
    "dynamic_stiffness_derivative",
    "model_stiffness_derivative",
    "BAND_LIMIT",
    "COND_MAX",
    "COND_MAX_DERIVATIVE",
]
