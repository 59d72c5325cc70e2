"""Direct receptances h_k = Wᵀ Z_k⁻¹ W of a geared rotor: one factorisation per harmonic
and frequency (the ``"banded"`` strategy of
:class:`~nlgrd.nonlinear.reduction.link_reduction.LinkReceptance`).

Z_k holds the mesh damping c_m w wᵀ, which couples the shafts and widens Z's band. The
factorisation is made of Z'_k = Z_k - i kω W diag(c_m) Wᵀ instead: its sparsity graph is
the shafts' own, which a reverse Cuthill-McKee ordering turns into a narrow band (half
bandwidth 7 on the two-shaft example against 26 with the mesh damping), factorised by
LAPACK's banded LU (``zgbtrf``, O(n b²)). The mesh damping comes back by the
Sherman-Morrison-Woodbury identity (Golub & Van Loan, Matrix Computations, 4th ed., §2.1.4),
with D = i kω C_W (C_W = diag(c_m) for meshes, any damping matrix on the coordinates of
links: :class:`~nlgrd.nonlinear.reduction.link_reduction.LinkReceptance`'s ``"banded"``),
h' = Wᵀ Z'⁻¹ W, S = (I + D h')⁻¹ and T = I - h D = (I + h' D)⁻¹:

    h = h' S,   Z⁻¹ W = Z'⁻¹ W S,
    dh/dω = T (dh'/dω) S - h (dD/dω) h,   dh'/dω = -(Z'⁻ᵀ W)ᵀ (dZ'/dω) (Z'⁻¹ W),

and for a forcing f (``rhs``), with x' = Z'⁻¹ f and g' = Wᵀ x':

    x = Z⁻¹ f = x' - Z'⁻¹ W S D g',   g = Wᵀ x = T g',
    dg/dω = T (Z'⁻ᵀ W)ᵀ (df/dω - (dZ'/dω) x) - h (dD/dω) g.

A solver keeps the band LUs and Z'⁻¹ [W f] of its last solve: the derivatives asked at the
same harmonics, frequency and forcing (κ_k, then dκ_k/dω in a corrector) need no new
factorisation, only the transposed solves Z'⁻ᵀ W.

Z' can be nearly singular where Z is not (a shaft mode that only the mesh damps). The
banded LU is backward stable, so the computed h' is exact for Z' + E with E of rounding
size, and the identity then gives h exactly for Z + E: with one mesh (S a scalar) the
result is as accurate as a factorisation of Z. With several meshes the small matrix
I + D h' amplifies rounding by its condition number (dh/dω by its square); above
``COND_MAX`` (``COND_MAX_DERIVATIVE`` when dh/dω is asked for), or when the band
is wider than ``BAND_LIMIT`` or Z' exactly singular, Z itself is factorised by sparse LU
(SuperLU), as it always was. Both paths agree to rounding (tests/test_direct_receptance.py)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray
from scipy.linalg.lapack import zgbtrf, zgbtrs
from scipy.sparse.csgraph import connected_components, reverse_cuthill_mckee

from nlgrd.cache import BoundedCache
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


def coupled_dofs(model: LinearModel, W: NDArray, extra=()) -> NDArray:
    """DOFs in the connected components of Z's sparsity graph (``model``'s pattern) that
    hold a DOF ``W`` loads (a non-zero row) or one of ``extra``: the rest is decoupled from
    them exactly.

    Parameters
    ----------
    model : LinearModel
        The linear model.
    W : ndarray (n, n_nl)
        Projection vectors.
    extra : sequence of int
        More DOFs whose components are kept.

    Returns
    -------
    ndarray of int
    """
    pat = model._pattern
    n = model.n_dofs
    g = sp.csc_matrix((np.ones(len(pat["indices"])), pat["indices"], pat["indptr"]), shape=(n, n))
    _, label = connected_components(g, directed=False)
    need = np.concatenate([np.flatnonzero(np.any(W != 0, axis=1)), np.asarray(extra, dtype=int)])
    return np.flatnonzero(np.isin(label, label[need]))


class DirectSolution(NamedTuple):
    """What :meth:`DirectSolver.solve_forced` returns (K harmonics, n_nl coordinates).

    Attributes
    ----------
    h : ndarray (K, n_nl, n_nl)
        h_k = Wᵀ Z_k⁻¹ W [m/N].
    U : ndarray (K, n_out, n_nl)
        Z_k⁻¹ W at the output DOFs [m/N, rad/N].
    dh : ndarray (K, n_nl, n_nl) or None
        dh_k/dω [m s/N].
    g : ndarray (K, n_nl) or None
        Wᵀ Z_k⁻¹ f_k [m].
    Ug : ndarray (K, n_out) or None
        Z_k⁻¹ f_k at the output DOFs [m, rad].
    dg : ndarray (K, n_nl) or None
        d(Wᵀ Z_k⁻¹ f_k)/dω [m s].
    """

    h: NDArray
    U: NDArray
    dh: NDArray | None
    g: NDArray | None
    Ug: NDArray | None
    dg: NDArray | None


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
    """h_k, Z_k⁻¹ W at output DOFs and dh_k/dω, by a factorisation per harmonic and frequency;
    with a forcing f_k also Wᵀ Z_k⁻¹ f_k, Z_k⁻¹ f_k at the output DOFs and d(Wᵀ Z_k⁻¹ f_k)/dω.

    Parameters
    ----------
    model : LinearModel
        The linear model with the damping W C_W Wᵀ and without the stiffness on W.
    bare : LinearModel
        The same without the damping W C_W Wᵀ (the band's pattern).
    W : ndarray (n, n_nl)
        The projection vectors (meshes' or links').
    c_m : ndarray (n_nl,) or (n_nl, n_nl)
        C_W: the meshes' damping coefficients, or the links' damping matrix [N s/m].
    keep : ndarray of int
        DOFs of the connected components holding a DOF of W, a forced or an output DOF
        (:func:`coupled_dofs`).
    output_dofs : ndarray of int
        DOFs whose responses Z_k⁻¹ W (and Z_k⁻¹ f_k) are returned.
    speed_per : float
        Reference speed per mesh frequency (Ω = ``speed_per`` ω).
    """

    def __init__(self, model, bare, W, c_m, keep, output_dofs, speed_per: float):
        self.keep = np.asarray(keep, dtype=int)
        self.full = _Restriction(model, self.keep)
        self.bare = _Restriction(bare, self.keep)
        c = np.asarray(c_m, dtype=float)
        self.c_w = np.diag(c) if c.ndim == 1 else c
        self.speed_per = float(speed_per)
        self.W = np.ascontiguousarray(W[keep], dtype=complex)
        self.out = self.full.new[np.asarray(output_dofs, dtype=int)]
        self.outside = np.flatnonzero(self.full.new < 0)
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
        # the last frequency's band LUs and Z'⁻¹ [W f] (:meth:`_factored`)
        self._last = BoundedCache(1)

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
        return self.solve_forced(harmonics, omega, derivative)[:3]

    def solve_forced(
        self,
        harmonics,
        omega: float,
        derivative: bool,
        rhs: NDArray | None = None,
        drhs: NDArray | None = None,
    ) -> DirectSolution:
        """:meth:`solve`, and with a forcing f_k (``rhs``) its responses too.

        Parameters
        ----------
        harmonics : array_like of int
            The harmonics k.
        omega : float
            Base frequency ω [rad/s].
        derivative : bool
            Also return dh_k/dω (and dg_k/dω, which needs ``drhs``).
        rhs : ndarray (K, n), optional
            f_k on the DOFs, zero outside ``keep`` [N].
        drhs : ndarray (K, n), optional
            df_k/dω [N s], with ``derivative``.

        Returns
        -------
        DirectSolution
        """
        ks = np.asarray(harmonics, dtype=int)
        nc, K = self.W.shape[1], len(ks)
        forced = rhs is not None
        f = df = None
        if forced:
            rhs = np.asarray(rhs, dtype=complex)
            if self.outside.size and np.any(rhs[:, self.outside] != 0):
                raise ValueError("a forcing outside the components kept")
            f = rhs[:, self.keep]
            if derivative:
                df = np.asarray(drhs, dtype=complex)[:, self.keep]
        h = np.zeros((K, nc, nc), dtype=complex)
        U = np.zeros((K, len(self.out), nc), dtype=complex)
        dh = np.zeros((K, nc, nc), dtype=complex) if derivative else None
        g = np.zeros((K, nc), dtype=complex) if forced else None
        Ug = np.zeros((K, len(self.out)), dtype=complex) if forced else None
        dg = np.zeros((K, nc), dtype=complex) if forced and derivative else None
        out = DirectSolution(h, U, dh, g, Ug, dg)
        if self.keep.size == 0:  # no DOF a mesh reaches
            return out
        todo = np.ones(K, dtype=bool)
        if self.band is not None:
            done = self._woodbury(ks, omega, derivative, out, f, df)
            todo = ~done
            self.n_band += int(np.sum(done))
        for i in np.flatnonzero(todo):
            self.n_sparse += 1
            self._sparse(i, int(ks[i]), omega, derivative, out, f, df)
        return out

    def _factored(self, ks: NDArray, omega: float, f: NDArray | None) -> tuple[list, NDArray]:
        """Band LUs of Z'_k (None where exactly singular) and Y = Z'_k⁻¹ [W f_k] in the
        band's order, (K, n, n_nl [+1]); those of the last call are reused when ``ks``, ``omega``
        and ``f`` are the same (κ_k and then dκ_k/dω at one frequency: one factorisation)."""
        b, Wp = self.band, self.W_perm
        key = (ks.tobytes(), float(omega))
        last = self._last.peek(key)
        if last is not None and (last[0] is None) == (f is None):
            if f is None or np.array_equal(last[0], f):
                return last[1], last[2]
        data = self._band_data(ks, omega)
        nc = Wp.shape[1]
        forced = f is not None
        B = np.asfortranarray(np.column_stack([Wp, np.zeros(b.n)])) if forced else Wp
        Y = np.zeros((len(ks), b.n, B.shape[1]), dtype=complex)
        facs = [b.factor(d) for d in data]
        for i, fac in enumerate(facs):
            if fac is None:
                continue
            if forced:
                B[:, nc] = f[i, b.perm]
            Y[i] = b.solve(fac, B)
        self._last.put(key, (f, facs, Y))
        return facs, Y

    def _woodbury(self, ks, omega, derivative, out: DirectSolution, f, df) -> NDArray:
        """Band solves of Z'_k and the identity, in place; which harmonics succeeded."""
        b, Wp = self.band, self.W_perm
        nc = Wp.shape[1]
        forced = f is not None
        facs, Y = self._factored(ks, omega, f)
        ok = np.array([fac is not None for fac in facs], dtype=bool)
        V = np.zeros((len(ks), b.n, nc), dtype=complex) if derivative else None
        if derivative:
            for i in np.flatnonzero(ok):
                V[i] = b.solve(facs[i], Wp, trans=1)
        Yw = Y[:, :, :nc]
        hp = Wp.T.real @ Yw
        D = 1j * omega * ks[:, None, None] * self.c_w  # (K, n_nl, n_nl)
        A = np.eye(nc) + D @ hp
        if nc > 1:
            with np.errstate(all="ignore"):
                ok &= np.linalg.cond(A) <= (COND_MAX_DERIVATIVE if derivative else COND_MAX)
        A[~ok] = np.eye(nc)
        S = np.linalg.inv(A)
        hk = hp @ S
        out.h[ok] = hk[ok]
        out.U[ok] = (Yw[:, b.inv[self.out], :] @ S)[ok]
        left = np.eye(nc) - hk @ D  # T = I - h D
        if forced:
            gp = np.einsum("ri,kr->ki", Wp.real, Y[:, :, nc])
            x = Y[:, :, nc] - (Yw @ (S @ (D @ gp[:, :, None])))[:, :, 0]
            g = (left @ gp[:, :, None])[:, :, 0]
            out.g[ok] = g[ok]
            out.Ug[ok] = x[:, b.inv[self.out]][ok]
        if derivative:
            dZ = self._band_derivative(ks, omega)
            dhp = -np.einsum("kri,kr,krj->kij", V[:, b.ri], dZ, Yw[:, b.ci])
            dD = 1j * ks[:, None, None] * self.c_w
            hdD = hk @ dD
            out.dh[ok] = (left @ dhp @ S - hdD @ hk)[ok]
            if forced:
                r = np.einsum("kri,kr->ki", V, df[:, b.perm])
                r -= np.einsum("kri,kr,kr->ki", V[:, b.ri], dZ, x[:, b.ci])
                dg = (left @ r[:, :, None])[:, :, 0] - (hdD @ g[:, :, None])[:, :, 0]
                out.dg[ok] = dg[ok]
        return ok

    def _sparse(self, i: int, k: int, omega: float, derivative: bool, out: DirectSolution, f, df) -> None:
        """Harmonic ``k`` (row ``i``) by sparse LU of Z_k, in place."""
        r = self.full
        nc = self.W.shape[1]
        r.Z.data = r.model.dynamic_stiffness_data(k * omega, self.speed_per * omega)[r.sel]
        lu = spla.splu(r.Z, permc_spec="MMD_AT_PLUS_A")
        forced = f is not None
        u = lu.solve(np.column_stack([self.W, f[i]]) if forced else self.W)
        out.h[i] = self.W.T.real @ u[:, :nc]
        out.U[i] = u[self.out, :nc]
        if forced:
            out.g[i] = self.W.T.real @ u[:, nc]
            out.Ug[i] = u[self.out, nc]
        if derivative:  # dh = -vᵀ dZ u, summed over the non-zeros of dZ
            v = lu.solve(self.W, trans="T")
            d = model_stiffness_derivative(r.model, k, omega, self.speed_per)[r.sel]
            out.dh[i] = -np.einsum("ri,r,rj->ij", v[r.rows], d, u[r.cols, :nc])
            if forced:
                out.dg[i] = v.T @ df[i] - np.einsum("ri,r,r->i", v[r.rows], d, u[r.cols, nc])


__all__ = [
    "DirectSolver",
    "DirectSolution",
    "coupled_dofs",
    "dynamic_stiffness_derivative",
    "model_stiffness_derivative",
    "BAND_LIMIT",
    "COND_MAX",
    "COND_MAX_DERIVATIVE",
]
