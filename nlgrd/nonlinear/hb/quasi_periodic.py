"""Quasi-periodic (two-frequency) harmonic balance of the receptance-reduced problem.

Beyond a Neimark-Sacker point the response is a torus
y(t) = u(θ₁, θ₂), θ₁ = ω₁ t (the mesh or base angle), θ₂ = ω₂ t (the secondary angle), with
u 2π-periodic in both. Its 2-D Fourier series on an index set 𝒦,

    y(t) = Re Σ_{k ∈ 𝒦} Y_k e^{i (k₁ θ₁ + k₂ θ₂)},

(Y_(0,0) real; X_k = a - i b as in :mod:`nlgrd.nonlinear.fourier.harmonics`) turns the reduced
equations of :mod:`nlgrd.nonlinear.hb.harmonic_balance` into one balance per combination
frequency Ω_k = k₁ ω₁ + k₂ ω₂:

    κ(Ω_k) Y_k + G_k(Y) = F_k,                                   (1)

κ(Ω) = h(Ω)⁻¹ the dynamic stiffness seen by the link coordinates at the frequency Ω (the
speed held at that of ω₁), F_k the reduced forcing (only at k₂ = 0: the excitation is
ω₁-periodic, or a given secondary force) and G_k the 2-D Fourier coefficients of the link
forces g(y(θ₁, θ₂), θ₁), computed by the multi-dimensional alternating frequency-time
scheme (Kim & Noah 1996, J. Appl. Mech. 63:375): samples on an N₁ x N₂ grid of the torus,
the law evaluated pointwise, a 2-D discrete Fourier transform back.

Truncation: 𝒦 = {(k₁, 0): 0 <= k₁ <= H₁} ∪ {(k₁, k₂): |k₁| <= H₁, 1 <= k₂ <= H₂} (the half of
the rectangle |k₁| <= H₁, |k₂| <= H₂ that the reality of y leaves; its k₂ = 0 row is the
periodic harmonic balance's set). The grid must resolve it: N₁ > 2 H₁, N₂ > 2 H₂.

Unknowns: the Y_k and, for an autonomous torus (one born at a Neimark-Sacker point), ω₂.
The torus is invariant under a shift of θ₂, so one phase condition is added (Schilder,
Osinga & Vogt 2005, SIAM J. Appl. Dyn. Syst. 4:459): the solution is orthogonal
to the θ₂-derivative of a reference torus (the previous point of a continuation),

    Σ_{k ∈ 𝒦, k₂ > 0} k₂ Im(conj(Y_k^ref) · Y_k) = 0.

The two-frequency harmonic balance with ω₂ unknown and a phase condition is that of
Guillot, Vergez & Cochelin 2017 (J. Sound Vib. 394:434); the start from the critical
Floquet mode solves the Floquet problem in Hill's form (Guillot, Lazarus, Thomas, Vergez &
Cochelin 2020, J. Comput. Phys. 416:109477), here on the receptance-reduced coordinates.
Every periodic orbit also solves (1) (its k₂ > 0 part zero) for any ω₂; Newton
is kept off that trivial family by deflation (Farrell, Birkisson & Funke 2015, SIAM J.
Sci. Comput. 37:A2026): the residual is multiplied by 1/‖Y_{k₂>0}‖² + 1, which leaves the
torus a root and makes the periodic orbits poles.

A forced torus (a second excitation at a given ω₂) is the same balance with ω₂ fixed and
no phase condition.

A try that cannot converge is stopped early (:data:`STALL_STEPS`): near a regular root
Newton's residual falls superlinearly, each step squaring the error (Kantorovich; Deuflhard
2004, Newton Methods for Nonlinear Problems, Springer, ch. 2), so a relative residual that
moves by less than :data:`STALL_RATIO` at each of :data:`STALL_STEPS` steps, far above the
tolerance, marks iterates with no root near them. Where no torus exists
(a chaotic band) the deflated steps run off that way: the undeflated step points back to
the periodic orbit, deflation turns it outward, the k₂ > 0 part doubles each step and the
relative residual stays put.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.hb.torus_grid import TorusGrid

#: A Newton solve stops when its relative residual has changed by less than this fraction
#: at each of the last :data:`STALL_STEPS` iterations while above :data:`STALL_FLOOR`
#: (module docstring). Measured (benchmarks/README.md, "`bench_torus_fail.py`"): the 98
#: failed tries of the Kahraman & Blankenship fast report sit on such a plateau from
#: iteration 5-20 on (94 of them meet the test); none of its 40 converged tries, nor of
#: Kubo's 6, moved by less than 10 % at two consecutive steps.
STALL_RATIO = 0.05
#: Consecutive iterations of a stalled residual before the solve stops [-].
STALL_STEPS = 3
#: Relative residual above which a stalled solve is stopped: 10⁵ x the default tolerance [-].
STALL_FLOOR = 1e-3


@dataclass
class TorusModel:
    """What the torus balance (1) needs of a reduced model.

    Parameters
    ----------
    kappa_at : callable (frequencies [rad/s] (n,), omega [rad/s]) -> (n, n_c, n_c) complex
        κ(Ω) at any non-zero frequencies Ω with the shaft speed of base frequency ``omega``
        [N/m].
    periodic_kappa : callable (omega, H) -> (H+1, n_c, n_c) complex
        κ_k at k ω, k = 0..H (the periodic model's own; its k = 0 entry is the mean) [N/m].
    periodic_force : callable (omega, H) -> (H+1, n_c) complex
        F_k, k = 0..H: the reduced forcing at the base harmonics [N].
    nonlinearities : sequence of LocalNonlinearity
        The link laws; ``force_time(y, θ₁)`` gives their forces.
    secondary_force : ndarray (n_c,) complex, optional
        A forced torus: the reduced force at (k₁, k₂) = (0, 1) [N]; None for an autonomous
        torus.
    kappa_slope_at : callable (frequencies, omega) -> (κ, dκ/dΩ), optional
        κ(Ω) as ``kappa_at`` gives it (the same numbers) and its derivative in Ω at the same
        speed, both (n, n_c, n_c) [N/m, N s/m], from one factorisation per frequency; None:
        dR/dω₂ by central differences of ``kappa_at`` (two more κ per frequency).
    """

    kappa_at: Callable[[NDArray, float], NDArray]
    periodic_kappa: Callable[[float, int], NDArray]
    periodic_force: Callable[[float, int], NDArray]
    nonlinearities: tuple = ()
    secondary_force: NDArray | None = None
    kappa_slope_at: Callable[[NDArray, float], tuple[NDArray, NDArray]] | None = None

    def __post_init__(self):
        self.nonlinearities = tuple(self.nonlinearities)

    @classmethod
    def from_reduced(cls, reduced, secondary_force: NDArray | None = None) -> TorusModel:
        """A reduced model whose κ depends on the frequency only (no speed-dependent parts:
        :meth:`~nlgrd.nonlinear.hb.harmonic_balance.ReducedModel.from_matrices`): κ(Ω) is its
        first harmonic at Ω.

        Parameters
        ----------
        reduced : ReducedModel
            Without ``nl_gain`` (κ form).
        secondary_force : ndarray (n_c,) complex, optional
            See the class [N].

        Returns
        -------
        TorusModel

        Raises
        ------
        ModelError
            When the model is in receptance form (``nl_gain`` set).
        """
        if reduced.nl_gain is not None:
            raise ModelError("nl_gain", "the torus balance takes a reduced model in κ form")

        nc = int(round(np.sqrt(np.asarray(reduced.kappa(1.0, 0)).size)))

        def kappa_at(freqs: NDArray, omega: float) -> NDArray:
            rows = [
                np.asarray(reduced.kappa(float(f), 1), dtype=complex).reshape(2, nc, nc)[1] for f in freqs
            ]
            return np.stack(rows) if rows else np.zeros((0, nc, nc), dtype=complex)

        return cls(
            kappa_at=kappa_at,
            periodic_kappa=lambda w, H: np.asarray(reduced.kappa(w, H), dtype=complex).reshape(H + 1, nc, nc),
            periodic_force=lambda w, H: np.asarray(reduced.force(w, H), dtype=complex).reshape(H + 1, nc),
            nonlinearities=reduced.nonlinearities,
            secondary_force=secondary_force,
        )


@dataclass(frozen=True)
class TorusSolution:
    """A solved torus at one base frequency.

    Attributes
    ----------
    omega : float
        Base frequency ω₁ [rad/s].
    secondary : float
        Secondary frequency ω₂ [rad/s].
    Y : ndarray (n_c, |𝒦|) complex
        The 2-D harmonics of the link coordinates [m] (NaN when not converged).
    grid : TorusGrid
        The index set and grid it was solved on.
    converged : bool
        Relative residual below the tolerance and the k₂ > 0 part not vanished.
    residual : float
        max|R| / max(|κ Y|, |G|, |F|) [-].
    iterations : int
        Newton iterations [-].
    amplitude : float
        ‖Y_{k₂>0}‖ / ‖Y_{k₂=0, k₁>0}‖: how far the torus is from the periodic orbit [-].
    stalled : bool
        Newton was stopped early: its residual stalled (:data:`STALL_STEPS`).
    """

    omega: float
    secondary: float
    Y: NDArray
    grid: TorusGrid
    converged: bool
    residual: float
    iterations: int
    amplitude: float
    stalled: bool = False


class TorusProblem:
    """The balance (1) at one base frequency on one index set and grid.

    Parameters
    ----------
    model : TorusModel
        The reduced model.
    omega : float
        Base frequency ω₁ [rad/s].
    grid : TorusGrid
        Index set and samples.
    """

    def __init__(self, model: TorusModel, omega: float, grid: TorusGrid):
        self.model, self.omega, self.grid = model, float(omega), grid
        H1 = grid.H1
        kap = np.asarray(model.periodic_kappa(self.omega, H1), dtype=complex)
        self.n_coords = kap.shape[1]
        self._kappa_row0 = kap  # (H1+1, n, n): k₂ = 0
        F = np.zeros((grid.n_terms, self.n_coords), dtype=complex)
        F[: H1 + 1] = np.asarray(model.periodic_force(self.omega, H1), dtype=complex).reshape(H1 + 1, -1)
        if model.secondary_force is not None and grid.H2 >= 1:
            j = H1 + 1 + H1  # (0, 1)
            F[j] = np.asarray(model.secondary_force, dtype=complex).reshape(-1)
        self.force = F
        self._kappa_cache: dict[float, NDArray] = {}

    @property
    def size(self) -> int:
        """Real unknowns of the harmonics, n_c (2|𝒦| - 1)."""
        return self.n_coords * self.grid.n_real

    def kappa(self, secondary: float) -> NDArray[np.complex128]:
        """κ(Ω_k) for every k ∈ 𝒦, (|𝒦|, n_c, n_c) [N/m]; Ω_(0,0) gives the mean κ_0."""
        key = float(secondary)
        hit = self._kappa_cache.get(key)
        if hit is None:
            g, H1 = self.grid, self.grid.H1
            out = np.empty((g.n_terms, self.n_coords, self.n_coords), dtype=complex)
            out[: H1 + 1] = self._kappa_row0
            if g.n_terms > H1 + 1:
                freqs = g.k1[H1 + 1 :] * self.omega + g.k2[H1 + 1 :] * key
                out[H1 + 1 :] = self.model.kappa_at(freqs, self.omega)
            if len(self._kappa_cache) > 8:
                self._kappa_cache.clear()
            hit = self._kappa_cache[key] = out
        return hit

    def kappa_slope(self, secondary: float) -> tuple[NDArray, NDArray]:
        """κ(Ω_k) (:meth:`kappa`) and dκ(Ω_k)/dω₂ = k₂ κ'(Ω_k), each (|𝒦|, n_c, n_c), by the
        model's ``kappa_slope_at`` [N/m, N s/m]."""
        key = float(secondary)
        g, H1 = self.grid, self.grid.H1
        kap = np.empty((g.n_terms, self.n_coords, self.n_coords), dtype=complex)
        slope = np.zeros_like(kap)
        kap[: H1 + 1] = self._kappa_row0
        if g.n_terms > H1 + 1:
            freqs = g.k1[H1 + 1 :] * self.omega + g.k2[H1 + 1 :] * key
            kap[H1 + 1 :], d = self.model.kappa_slope_at(freqs, self.omega)
            slope[H1 + 1 :] = g.k2[H1 + 1 :, None, None] * d
        if len(self._kappa_cache) > 8:
            self._kappa_cache.clear()
        self._kappa_cache[key] = kap
        return kap, slope

    def _laws(self, y: NDArray, jacobian: bool) -> tuple[NDArray, NDArray | None]:
        """Link forces on the grid (n_c, N) and their tangents (n_c, n_c, N) by central
        differences (exact for piecewise-linear laws away from the kinks)."""
        th = self.grid.theta1
        g = np.zeros_like(y)
        dg = np.zeros((self.n_coords, self.n_coords, y.shape[1])) if jacobian else None
        for nl in self.model.nonlinearities:
            idx = list(nl.coords)
            yi = y[idx]
            g[idx] += nl.force_time(yi, th)
            if jacobian:
                scale = max(float(np.max(np.abs(yi))), float(nl.scale()), 1e-30)
                h = 1e-7 * scale
                for a, ca in enumerate(idx):
                    yp, ym = yi.copy(), yi.copy()
                    yp[a] += h
                    ym[a] -= h
                    col = (nl.force_time(yp, th) - nl.force_time(ym, th)) / (2 * h)
                    for b, cb in enumerate(idx):
                        dg[cb, ca] += col[b]
        return g, dg

    def _linear(self, Y: NDArray, kap: NDArray) -> NDArray:
        return np.einsum("kij,jk->ik", kap, Y)

    def residual(self, z: NDArray, secondary: float, jacobian: bool = True):
        """R (flat, real), dR/dz, dR/dω₂ and the force scale.

        Parameters
        ----------
        z : ndarray
            Real unknowns of the harmonics [m].
        secondary : float
            ω₂ [rad/s].
        jacobian : bool
            Also return the derivatives.

        Returns
        -------
        R : ndarray
            The residual of (1), real, flat [N].
        J : ndarray or None
            dR/dz [N/m].
        dR : ndarray or None
            dR/dω₂ [N s/rad] (the model's κ'(Ω), else central differences of κ).
        scale : float
            max(|κ Y|, |G|, |F|) [N].
        """
        g_ = self.grid
        n = self.n_coords
        Y = g_.to_complex(z, n)
        slope = jacobian and self.model.secondary_force is None and self.model.kappa_slope_at is not None
        kap, dk = self.kappa_slope(secondary) if slope else (self.kappa(secondary), None)
        KY = self._linear(Y, kap)
        y = g_.samples(Y)
        gs, dg = self._laws(y, jacobian)
        G = (g_.forward @ gs.T).T  # (n, n_real)
        Gc = g_.to_complex(G.reshape(-1), n)
        R = g_.to_real(KY + Gc - self.force.T)
        scale = max(np.max(np.abs(KY)), np.max(np.abs(Gc)), np.max(np.abs(self.force)), 1e-300)
        if not jacobian:
            return R, None, None, scale
        m, nr = g_.n_terms, g_.n_real
        J = np.zeros((n * nr, n * nr))
        for a in range(n):  # linear part: per k the 2x2 real blocks of κ_k
            for b in range(n):
                blk = np.zeros((nr, nr))
                re, im = kap[:, a, b].real, kap[:, a, b].imag
                d = np.arange(m)
                blk[d, d] = re
                di = np.arange(1, m)
                blk[di, m + di - 1] = -im[1:]
                blk[m + di - 1, di] = im[1:]
                blk[m + di - 1, m + di - 1] = re[1:]
                J[a * nr : (a + 1) * nr, b * nr : (b + 1) * nr] += blk
                if dg is not None and np.any(dg[a, b]):
                    J[a * nr : (a + 1) * nr, b * nr : (b + 1) * nr] += g_.tangent_block(dg[a, b])
        dR = None
        if self.model.secondary_force is None:
            if dk is None:  # central differences of κ
                step = 1e-6 * max(abs(secondary), 1e-3 * self.omega)
                dk = (self.kappa(secondary + step) - self.kappa(secondary - step)) / (2 * step)
            dR = g_.to_real(self._linear(Y, dk))
        return R, J, dR, scale


def _deflation(z: NDArray, mask: NDArray) -> tuple[float, NDArray]:
    """M(z) = 1/‖z_mask‖² + 1 and its gradient (Farrell et al. 2015, Eq. 3.3 with p = 2)."""
    d = np.where(mask, z, 0.0)
    r2 = float(d @ d)
    if r2 == 0:
        return np.inf, np.zeros_like(z)
    return 1.0 / r2 + 1.0, -2.0 * d / r2**2


def phase_row(Y_ref: NDArray, grid: TorusGrid) -> NDArray[np.float64]:
    """The phase condition of the module docstring as a row on the real unknowns.

    Parameters
    ----------
    Y_ref : ndarray (n_c, |𝒦|) complex
        The reference torus [m].
    grid : TorusGrid
        Its index set.

    Returns
    -------
    ndarray (n_c (2|𝒦| - 1),)
        c with c · z = Σ k₂ Im(conj(Y_ref,k) Y_k) [m].
    """
    Y_ref = np.atleast_2d(Y_ref)
    w = grid.k2.astype(float)
    rows = []
    for yr in Y_ref:  # Im(conj(a) Y) = a_r Y_i - a_i Y_r
        rows.append(np.concatenate([-w * yr.imag, (w * yr.real)[1:]]))
    return np.concatenate(rows)


def solve_torus(
    model: TorusModel,
    omega: float,
    grid: TorusGrid,
    Y0: NDArray,
    secondary: float,
    *,
    Y_ref: NDArray | None = None,
    tol: float = 1e-8,
    max_iter: int = 60,
    stall: bool = True,
) -> TorusSolution:
    """Newton's method on (1), with ω₂ and the phase condition for an autonomous torus and
    deflation of the periodic family, stopped early when its residual stalls.

    Parameters
    ----------
    model : TorusModel
        The reduced model.
    omega : float
        Base frequency ω₁ [rad/s].
    grid : TorusGrid
        Index set and samples.
    Y0 : ndarray (n_c, |𝒦|) complex
        Start on ``grid``'s index set [m] (a torus of another set is moved onto it by
        :func:`nlgrd.nonlinear.hb.torus_grid.resize`).
    secondary : float
        ω₂ [rad/s]: the start (autonomous torus) or the forcing's (forced torus).
    Y_ref : ndarray, optional
        The reference of the phase condition (default ``Y0``) [m].
    tol : float
        max|R| <= tol · max(|κ Y|, |G|, |F|) [-].
    max_iter : int
        Newton iterations [-].
    stall : bool
        Stop when the relative residual stalls (:data:`STALL_STEPS` iterations within
        :data:`STALL_RATIO` above :data:`STALL_FLOOR`); False: run to ``max_iter``.

    Returns
    -------
    TorusSolution
        ``converged`` False when the tolerance was not met or Newton fell onto the periodic
        orbit; ``stalled`` True when stopped early.
    """
    prob = TorusProblem(model, omega, grid)
    n = prob.n_coords
    z = grid.to_real(np.asarray(Y0, dtype=complex).reshape(n, grid.n_terms))
    autonomous = model.secondary_force is None
    mask = np.tile(np.concatenate([grid.k2 > 0, (grid.k2 > 0)[1:]]), n)
    w2 = float(secondary)
    c = phase_row(Y_ref if Y_ref is not None else grid.to_complex(z, n), grid) if autonomous else None
    res, it, ok, stalled, flat = np.inf, 0, False, False, 0
    while it < max_iter:
        it += 1
        R, J, dR, scale = prob.residual(z, w2)
        last, res = res, float(np.max(np.abs(R)) / scale)
        if res <= tol:
            ok = True
            break
        flat = flat + 1 if res > STALL_FLOOR and abs(res / last - 1) < STALL_RATIO else 0
        if stall and flat >= STALL_STEPS:
            stalled = True
            break
        if autonomous:
            R = np.append(R, c @ z)
            J = np.block([[J, dR[:, None]], [c[None, :], np.zeros((1, 1))]])
        try:
            step = np.linalg.solve(J, -R)
        except np.linalg.LinAlgError:
            step = np.linalg.lstsq(J, -R, rcond=None)[0]
        if autonomous:
            Mz, gM = _deflation(z, mask)
            if np.isfinite(Mz):
                denom = 1.0 - float(gM @ step[:-1]) / Mz
                step = step / denom if abs(denom) > 1e-3 else step
        # damping: no step that moves ω₂ by more than a tenth of itself
        t = 1.0
        if autonomous and abs(step[-1]) > 0.1 * abs(w2):
            t = 0.1 * abs(w2) / abs(step[-1])
        z = z + t * step[: z.size]
        if autonomous:
            w2 = w2 + t * step[-1]
        if not np.all(np.isfinite(z)):
            break
    Y = grid.to_complex(z, n)
    base = np.linalg.norm(Y[:, 1 : grid.H1 + 1])
    amp = float(np.linalg.norm(Y[:, grid.H1 + 1 :]) / max(base, 1e-300))
    if autonomous and amp < 1e-6:
        ok = False  # the periodic orbit, not a torus
    if not ok:
        Y = np.full_like(Y, np.nan)
    return TorusSolution(float(omega), w2, Y, grid, ok, res, it, amp, stalled)


def periodic_start(Y_periodic: NDArray, grid: TorusGrid, shape: NDArray | None = None, size: float = 0.0):
    """A start on ``grid``: periodic harmonics on the k₂ = 0 row, ``size`` x ``shape`` on
    the (k₁, 1) column (the Floquet mode of :func:`critical_shape`).

    Parameters
    ----------
    Y_periodic : ndarray (n_c, H₁+1) complex
        Complex harmonics X_k = a_k - i b_k of the periodic orbit [m].
    grid : TorusGrid
        The index set.
    shape : ndarray (n_c, 2H₁+1) complex, optional
        Amplitudes of e^{i(k₁ θ₁ + θ₂)}, k₁ = -H₁..H₁ [-].
    size : float
        Scale of ``shape`` [m].

    Returns
    -------
    ndarray (n_c, |𝒦|) complex
        [m].
    """
    Yp = np.atleast_2d(Y_periodic)
    out = np.zeros((Yp.shape[0], grid.n_terms), dtype=complex)
    h = min(grid.H1, Yp.shape[1] - 1)
    out[:, : h + 1] = Yp[:, : h + 1]
    if shape is not None and grid.H2 >= 1:
        out[:, grid.H1 + 1 : grid.H1 + 1 + 2 * grid.H1 + 1] = size * np.atleast_2d(shape)
    return out


def critical_shape(
    model: TorusModel, omega: float, Y_periodic: NDArray, secondary: float, H1: int
) -> NDArray:
    """The shape of the first secondary harmonics at the onset of the torus: the null vector
    of the linearised balance at the frequencies k₁ ω₁ + ω₂ about the periodic orbit (Hill's
    form of the Floquet problem, Guillot et al. 2020, in the receptance coordinates). The
    right singular vector of the smallest singular value, unit 2-norm.

    Parameters
    ----------
    model : TorusModel
        The reduced model.
    omega : float
        ω₁ [rad/s].
    Y_periodic : ndarray (n_c, H₁+1) complex
        The periodic orbit's complex harmonics [m].
    secondary : float
        ω₂ [rad/s] (from the critical multiplier's angle).
    H1 : int
        Harmonics of ω₁ [-].

    Returns
    -------
    ndarray (n_c, 2H₁+1) complex
        Amplitudes of e^{i(k₁ θ₁ + θ₂)}, k₁ = -H₁..H₁ [-].
    """
    grid = TorusGrid(H1, 0, max(4 * H1 + 4, 64), 1)
    Yp = periodic_start(Y_periodic, grid)
    prob = TorusProblem(model, omega, grid)
    n = prob.n_coords
    y = grid.samples(Yp)
    _, dg = prob._laws(y, True)
    N = grid.N1
    th = grid.theta1
    ks = np.arange(-H1, H1 + 1)
    kap = model.kappa_at(ks * omega + secondary, omega)  # (2H1+1, n, n)
    E = np.exp(1j * np.outer(th, ks))  # (N, 2H1+1)
    A = np.zeros((n * ks.size, n * ks.size), dtype=complex)
    for a in range(n):
        for b in range(n):
            T = (E.conj().T * dg[a, b][None, :]) @ E / N + np.diag(kap[:, a, b])
            A[a * ks.size : (a + 1) * ks.size, b * ks.size : (b + 1) * ks.size] = T
    _, _, Vh = np.linalg.svd(A)
    v = Vh[-1].conj()
    return (v / np.linalg.norm(v)).reshape(n, ks.size)


def secondary_from_multiplier(multiplier: complex, omega: float) -> float:
    """ω₂ = |arg μ| ω₁ / 2π from the critical Floquet multiplier μ (modulo ω₁: the
    representative in (0, ω₁/2]).

    Parameters
    ----------
    multiplier : complex
        μ [-].
    omega : float
        ω₁ [rad/s].

    Returns
    -------
    float
        ω₂ [rad/s].
    """
    return abs(np.angle(multiplier)) * omega / (2 * np.pi)
