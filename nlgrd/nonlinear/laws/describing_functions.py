"""Fourier coefficients of the backlash force law: exact, by AFT, and its describing function.

The backlash (dead-zone) function of Maliha, Doğruer & Özgüven (2004, Eq. 9-10) and
Özgüven & Houser (1988) with total backlash 2b is

    f(x) = x - b  (x > b),   0  (|x| <= b),   x + b  (x < -b)

and the nonlinear mesh force is g(θ) = k_h f(δ(θ) - e(θ)). Its harmonics G (the
layout of :mod:`nlgrd.nonlinear.fourier.harmonics`) are computed either exactly
(:func:`fourier_exact`: the crossings of x = δ - e with ±b are the unit-circle roots of
a polynomial, polished by Newton, and the linear pieces are integrated in closed form)
or by alternating frequency-time sampling (:func:`fourier_aft`). Both give the Jacobian
dG/dz in closed form: it is the Toeplitz matrix of the Fourier coefficients of k_h
times the contact indicator; the terms from moving crossing points vanish because f is
continuous.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import check_positive
from nlgrd.nonlinear.fourier.harmonics import (
    analyse,
    complex_rows_to_real,
    differentiate,
    evaluate,
    n_harmonics,
    real_complex_maps,
    real_to_complex,
    resize_harmonics,
    sample,
    toeplitz_jacobian,
)


def deadzone(x: ArrayLike, b: float) -> NDArray[np.float64]:
    """Backlash function f(x) = x - b (x > b), 0 (|x| <= b), x + b (x < -b); 2b total backlash [m].

    Parameters
    ----------
    x : array_like
        Argument, the mesh deflection x = δ - e [m], any shape.
    b : float
        Half backlash [m] (total backlash 2b), >= 0.

    Returns
    -------
    ndarray
        f(x) [m], shaped like ``x``.
    """
    x = np.asarray(x, dtype=float)
    return np.where(x > b, x - b, np.where(x < -b, x + b, 0.0))


def _companion_crossings(z: NDArray, level: float, tol_circle: float = 1e-3) -> NDArray:
    """Angles in [0, 2π) where the trig polynomial ``z`` equals ``level`` (companion matrix).

    Roots of z^D (x(θ) - level) as a polynomial in z = e^{iθ} (eigenvalues of the
    companion matrix), kept when within ``tol_circle`` of the unit circle and polished
    by Newton on the real function. Spurious extra angles (near-tangencies) are
    harmless: they only split an interval, whose state is decided at its midpoint.
    """
    X = real_to_complex(z)
    scale = np.max(np.abs(X))
    if scale == 0:
        return np.empty(0)
    nz = np.nonzero(np.abs(X[1:]) > 1e-14 * scale)[0]
    if nz.size == 0:
        return np.empty(0)
    D = int(nz[-1]) + 1
    c = np.empty(2 * D + 1, dtype=complex)
    c[D + 1 :] = X[1 : D + 1] / 2  # c_m, m = 1..D
    c[:D] = np.conj(X[D:0:-1]) / 2  # c_{-m}, m = D..1
    c[D] = X[0].real - level
    roots = np.roots(c[::-1])  # highest power first: c_D z^{2D} + ... + c_{-D}
    near = np.abs(np.abs(roots) - 1.0) < tol_circle
    theta = np.angle(roots[near])
    if theta.size == 0:
        return theta
    zz = np.asarray(z[: 2 * D + 1], dtype=float)
    dz = differentiate(zz)
    for _ in range(4):
        val = evaluate(zz, theta) - level
        der = evaluate(dz, theta)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(np.abs(der) > 0, val / der, 0.0)
        step = np.where(np.abs(step) < 0.05, step, 0.0)  # keep unpolished if Newton wanders
        theta = theta - step
        if np.all(np.abs(step) < 1e-15):
            break
    return np.mod(theta, 2 * np.pi)


def _trig(z: NDArray) -> tuple:
    """(x_0, k, a_k, b_k, k b_k, k a_k) of real harmonics ``z``, for :func:`_value_and_slope`."""
    k = np.arange(1, n_harmonics(z) + 1)
    a, b = z[1::2], z[2::2]
    return z[0], k, a, b, k * b, k * a


def _value_and_slope(tr: tuple, theta: NDArray) -> tuple[NDArray, NDArray]:
    """x(θ) and dx/dθ at angles ``theta`` of the polynomial ``tr`` (:func:`_trig`)."""
    x0, k, a, b, kb, ka = tr
    kt = np.multiply.outer(theta, k)
    c, s = np.cos(kt), np.sin(kt)
    return x0 + c @ a + s @ b, c @ kb - s @ ka


#: Finest grid of the sampled crossing search; the companion matrix (of size 2D for D
#: harmonics: seconds above D ~ 500) only when it cannot certify a near-tangency.
MAX_CROSSING_SAMPLES = 2**20


def _plain_newton(tr: tuple, t: NDArray, level: NDArray, lo: NDArray, hi: NDArray) -> NDArray | None:
    """Three unguarded Newton steps from the chord estimates ``t`` of crossings bracketed in
    [lo, hi]; the roots when every last step is below 1e-9 (quadratic convergence: the
    error is then at the root's conditioning, as the safeguarded loop's) and inside its
    bracket, else None (the safeguarded loop)."""
    step = np.zeros_like(t)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for _ in range(3):
            val, der = _value_and_slope(tr, t)
            step = (val - level) / der
            t = t - step
    if np.all(np.abs(step) <= 1e-9) and np.all((t >= lo) & (t <= hi)):
        return t
    return None


def _sampled_crossings(
    z: NDArray, levels: tuple[float, ...], refine: int = 1, xs: NDArray | None = None
) -> NDArray | None:
    """Crossings of ``levels`` by sign changes on a dense grid, polished by safeguarded Newton.

    Returns None when a grid cell might hide two crossings. Certificate: with
    |x''| <= M2 = Σ k² |X_k| the function departs from its chord by at most M2 h²/8 over
    a cell of width h, so a cell without a sign change is crossing-free when both end
    values are farther than that from the level; failing that, when x' keeps one sign
    over the cell (same test on x' with M3 = Σ k³ |X_k|), x is monotone there and
    cannot cross twice. Otherwise (a near-tangency) the caller uses the companion matrix.
    """
    H = n_harmonics(z)
    N = refine * default_aft_samples(H)
    h = 2 * np.pi / N
    if xs is None or xs.size != N:
        xs = sample(z, N)
    k = np.arange(1, H + 1)
    amp = np.hypot(z[1::2], z[2::2])
    tiny = 1e-14 * (np.max(np.abs(xs)) + 1e-300)
    lev = np.asarray(levels, dtype=float)[:, None]
    d = xs[None, :] - lev  # (n_levels, N)
    dn = np.concatenate([d[:, 1:], d[:, :1]], axis=1)
    change = (d > 0) != (dn > 0)
    margin = float(np.sum(k**2 * amp)) * h * h / 8 * (1 + 1e-9) + tiny
    quiet = ~change & (np.minimum(np.abs(d), np.abs(dn)) <= margin)
    if np.any(quiet):
        dmargin = float(np.sum(k**3 * amp)) * h * h / 8 * (1 + 1e-9) + tiny
        slope = sample(differentiate(z), N)
        sn = np.concatenate([slope[1:], slope[:1]])
        cells = np.nonzero(quiet)[1]
        sq, sn = slope[cells], sn[cells]
        if not np.all(((sq > 0) == (sn > 0)) & (np.minimum(np.abs(sq), np.abs(sn)) > dmargin)):
            return None
    li, j = np.nonzero(change)
    if j.size == 0:
        return np.empty(0)
    level = lev[li, 0]
    lo, hi = j * h, (j + 1) * h
    dlo, dhi = d[li, j], dn[li, j]
    t = lo + h * dlo / (dlo - dhi)
    tr = _trig(z)
    fast = _plain_newton(tr, t, level, lo, hi)
    if fast is not None:
        return np.mod(fast, 2 * np.pi)
    for _ in range(40):
        val, der = _value_and_slope(tr, t)
        val = val - level
        left = (val > 0) == (dlo > 0)
        lo, dlo = np.where(left, t, lo), np.where(left, val, dlo)
        hi = np.where(left, hi, t)
        with np.errstate(divide="ignore", invalid="ignore"):
            tn = t - val / der
        bad = ~np.isfinite(tn) | (tn < lo) | (tn > hi)
        tn = np.where(bad, 0.5 * (lo + hi), tn)
        done = np.all((np.abs(tn - t) <= 1e-15 * (1 + np.abs(t))) | (val == 0))
        t = tn
        if done:
            break
    return np.mod(t, 2 * np.pi)


@dataclass(frozen=True)
class ContactIntervals:
    """Partition of one period [θ_0, θ_0 + 2π) into intervals of constant contact state.

    Attributes
    ----------
    start, end : ndarray
        Interval bounds [rad], ``end[i] == start[i + 1]``, covering exactly 2π.
    state : ndarray of int
        +1 drive-side contact (x > b), 0 separation (|x| <= b), -1 back-side contact (x < -b).
    """

    start: NDArray[np.float64]
    end: NDArray[np.float64]
    state: NDArray[np.int64]

    @property
    def contact_fraction(self) -> float:
        """Fraction of the period in contact on either flank."""
        return float(np.sum((self.end - self.start)[self.state != 0]) / (2 * np.pi))

    @property
    def back_contact(self) -> bool:
        """True when back-side contact (x < -b) occurs anywhere."""
        return bool(np.any(self.state == -1))

    def spectrum(self, n_max: int, weights: NDArray | None = None) -> NDArray[np.complex128]:
        """S_n = (1/2π) Σ_i w_i ∫_{interval i} e^{-inθ} dθ for n = -n_max..n_max.

        ``weights`` default to the contact indicator |state|.
        """
        w = np.abs(self.state).astype(float) if weights is None else np.asarray(weights, dtype=float)
        keep = w != 0
        t1, t2, w = self.start[keep], self.end[keep], w[keep]
        n = np.arange(1, n_max + 1)
        pos = ((np.exp(-1j * np.outer(n, t2)) - np.exp(-1j * np.outer(n, t1))) @ w) * 1j / (2 * np.pi * n)
        s0 = np.sum(w * (t2 - t1)) / (2 * np.pi)
        return np.concatenate([np.conj(pos[::-1]), [s0], pos])


def contact_intervals(x: ArrayLike, b: float, crossings: str = "auto") -> ContactIntervals:
    """Contact states of x(θ) (real harmonics ``x``) against the backlash ±b over one period.

    The crossings of x = b and x = -b are found by sign changes on a dense grid with a
    certificate that no cell hides a pair of crossings, polished by safeguarded Newton
    (``crossings="auto"``); when the certificate fails (near-tangency) or with
    ``crossings="companion"``, they are the unit-circle roots of the associated
    polynomials (companion matrix), polished by Newton. Before that the grid is refined
    8 and 64 fold (up to ``MAX_CROSSING_SAMPLES`` samples; cheaper than the companion
    matrix, of size 2D for D harmonics). Each interval's state is decided at its midpoint.

    Parameters
    ----------
    x : array_like
        Real harmonics [x_0, a_1, b_1, ..., a_D, b_D] of x = δ - e (1-D, length 2D + 1) [m].
    b : float
        Half backlash [m] (total backlash 2b), >= 0; with b = 0 the state is +1 where
        x >= 0 and -1 elsewhere.
    crossings : {"auto", "companion"}
        How the crossings are found: dense grid with the companion matrix as the fallback,
        or the companion matrix only.

    Returns
    -------
    ContactIntervals
        Intervals from one crossing to the next around the period (one interval [0, 2π)
        when the state never changes), each with its contact state.
    """
    x = np.asarray(x, dtype=float)
    amp = np.hypot(x[1::2], x[2::2])
    bound = float(np.sum(amp))  # |x(θ) - x_0| <= Σ |X_k|
    lo, hi = x[0] - bound, x[0] + bound
    xs = None
    if amp.size and lo <= b and hi >= -b:
        # tighter: on the crossing search's grid, x departs from its chords by at most
        # Σ k² |X_k| h² / 8
        n = default_aft_samples(amp.size)
        xs = sample(x, n)
        margin = float(np.sum(np.arange(1, amp.size + 1) ** 2 * amp)) * (2 * np.pi / n) ** 2 / 8
        lo, hi = max(lo, float(np.min(xs)) - margin), min(hi, float(np.max(xs)) + margin)
    for state, inside in ((1, lo > b), (-1, hi < -b), (0, lo > -b and hi < b)):
        if inside:  # no crossing possible: one state over the whole period
            return ContactIntervals(np.array([0.0]), np.array([2 * np.pi]), np.array([state]))
    levels = (b, -b) if b > 0 else (0.0,)
    breaks = None
    if crossings == "auto":  # a near-tangency usually clears on a finer grid
        n0 = default_aft_samples(n_harmonics(x))
        for refine in (1, 8, 64):
            if refine > 1 and n0 * refine > MAX_CROSSING_SAMPLES:
                break
            breaks = _sampled_crossings(x, levels, refine=refine, xs=xs if refine == 1 else None)
            if breaks is not None:
                break
    if breaks is None:
        breaks = np.concatenate([_companion_crossings(x, lv) for lv in levels])
    breaks = np.sort(breaks)
    if breaks.size:
        keep = np.append(True, np.diff(breaks) > 1e-13)
        breaks = breaks[keep]
        if breaks.size > 1 and breaks[0] + 2 * np.pi - breaks[-1] <= 1e-13:
            breaks = breaks[:-1]
    if breaks.size == 0:
        start, end = np.array([0.0]), np.array([2 * np.pi])
    else:
        start = breaks
        end = np.append(breaks[1:], breaks[0] + 2 * np.pi)
    mid = evaluate(x, 0.5 * (start + end))
    state = np.where(mid > b, 1, np.where(mid < -b, -1, 0)).astype(np.int64)
    if b == 0:
        state = np.where(mid >= 0, 1, -1).astype(np.int64)
    return ContactIntervals(start, end, state)


def _x_complex_full(x: NDArray) -> tuple[NDArray, int]:
    """Complex coefficients c_m, m = -D..D, of real harmonics x of degree D."""
    D = n_harmonics(x)
    P, _, _ = real_complex_maps(D)
    return P @ x, D


def fourier_exact(
    x: ArrayLike,
    b: float,
    H: int,
    stiffness: float = 1.0,
    jacobian: bool = False,
    intervals: ContactIntervals | None = None,
) -> NDArray | tuple[NDArray, NDArray]:
    """Exact harmonics 0..H of stiffness · f(x(θ)) by piecewise integration.

    Parameters
    ----------
    x : array_like
        Real harmonics of x = δ - e (any number of harmonics, may exceed ``H``) [m].
    b : float
        Half backlash [m] (total backlash 2b), >= 0.
    H : int
        Number of harmonics returned.
    stiffness : float
        k_h [N/m]; the result is in N.
    jacobian : bool
        Also return dG/dx, the (2H+1) x (2H+1) derivative with respect to the first
        2H + 1 real harmonics of x (which equals dG/dδ since x = δ - e).
    intervals : ContactIntervals, optional
        ``contact_intervals(x, b)`` when the caller has it already.

    Returns
    -------
    G : ndarray (2H+1,)
        Real harmonics [G_0, a_1, b_1, ..., a_H, b_H] of stiffness · f(x(θ)) [N] (in m with
        the default ``stiffness`` 1).
    dG : ndarray (2H+1, 2H+1)
        dG/dx [N/m], only when ``jacobian``.

    Notes
    -----
    With s(θ) the contact indicator and β(θ) = ±b on drive/back contact, g = k_h s (x - β),
    so ĝ_k = k_h (Σ_m c_m S_{k-m} - B_k) with S_n, B_n the exact Fourier integrals of s and
    s β over the contact intervals (closed form: ∫ e^{-inθ} dθ). dĝ_k/dc_m = k_h S_{k-m}:
    the Toeplitz matrix of the indicator, no crossing-point terms since f is continuous.
    """
    x = np.asarray(x, dtype=float)
    if intervals is None:
        intervals = contact_intervals(x, b)
    if intervals.state.size == 1:  # one contact state all period: g is linear in x
        s = float(intervals.state[0])
        G = stiffness * abs(s) * resize_harmonics(x, H)
        G[0] -= stiffness * s * b
        if not jacobian:
            return G
        return G, stiffness * abs(s) * np.eye(2 * H + 1)
    c, D = _x_complex_full(x)
    nmax = H + D + H
    beta = b * intervals.state.astype(float)
    S = intervals.spectrum(nmax)
    B = intervals.spectrum(H, weights=beta)
    k = np.arange(0, H + 1)
    m = np.arange(-D, D + 1)
    T = S[nmax + k[:, None] - m[None, :]]
    g = stiffness * (T @ c - B[H + k])
    G = complex_rows_to_real(g)
    if not jacobian:
        return G
    return G, toeplitz_jacobian(S, nmax, H, stiffness)


def default_aft_samples(H: int) -> int:
    """Default AFT sample count: a power of two >= 16 (H + 1), at least 64.

    Parameters
    ----------
    H : int
        Number of harmonics to resolve.

    Returns
    -------
    int
        Samples per period N [-].
    """
    return int(max(64, 2 ** np.ceil(np.log2(16 * (H + 1)))))


def fourier_aft(
    x: ArrayLike,
    b: float,
    H: int,
    stiffness: float = 1.0,
    n_samples: int | None = None,
    jacobian: bool = False,
) -> NDArray | tuple[NDArray, NDArray]:
    """Harmonics 0..H of stiffness · f(x(θ)) by alternating frequency-time (AFT) sampling.

    x is sampled at N equally spaced angles (inverse FFT), f applied pointwise, and the
    samples analysed by FFT. The Jacobian is the exact derivative of this discrete map:
    the Toeplitz matrix of the DFT of the sampled contact indicator. For the kinked f the
    error decays as N^-2 (see :func:`aft_convergence`).

    Parameters
    ----------
    x : array_like
        Real harmonics [x_0, a_1, b_1, ..., a_D, b_D] of x = δ - e (1-D, any number D of
        harmonics, may exceed ``H``) [m].
    b : float
        Half backlash [m] (total backlash 2b), >= 0.
    H : int
        Number of harmonics returned.
    stiffness : float
        k_h [N/m]; the result is in N.
    n_samples : int, optional
        N, samples per period, more than 2 max(H, D); default
        :func:`default_aft_samples` (max(H, D)).
    jacobian : bool
        Also return dG/dx, the (2H+1) x (2H+1) derivative with respect to the first
        2H + 1 real harmonics of x (which equals dG/dδ since x = δ - e).

    Returns
    -------
    G : ndarray (2H+1,)
        Real harmonics [G_0, a_1, b_1, ..., a_H, b_H] of stiffness · f(x(θ)) [N] (in m with
        the default ``stiffness`` 1).
    dG : ndarray (2H+1, 2H+1)
        dG/dx [N/m], only when ``jacobian``.

    Raises
    ------
    ModelError
        When ``n_samples`` <= 2 max(H, D).
    """
    x = np.asarray(x, dtype=float)
    D = n_harmonics(x)
    N = n_samples or default_aft_samples(max(H, D))
    xs = sample(x, N)
    G = analyse(stiffness * deadzone(xs, b), H)
    if not jacobian:
        return G
    s = (np.abs(xs) > b).astype(float)
    spec = np.fft.fft(s) / N
    n = np.arange(-2 * H, 2 * H + 1)
    S = spec[np.mod(n, N)]
    return G, toeplitz_jacobian(S, 2 * H, H, stiffness)


def aft_convergence(
    x: ArrayLike, b: float, H: int, n_samples: ArrayLike = (16, 32, 64, 128, 256, 512, 1024, 2048)
) -> dict[str, NDArray]:
    """Error of the AFT harmonics against the exact ones as the sample count N grows.

    Parameters
    ----------
    x : array_like
        Real harmonics [x_0, a_1, b_1, ..., a_D, b_D] of x = δ - e (1-D) [m].
    b : float
        Half backlash [m] (total backlash 2b), >= 0.
    H : int
        Number of harmonics compared.
    n_samples : array_like of int
        Sample counts N to try; those <= 2 max(H, D) are skipped.

    Returns
    -------
    dict of str to ndarray
        A dict with ``n_samples``, ``error`` (max-norm of the harmonic error, in the
        units of x) and ``order`` (the observed log-log slope between successive N; ≈ -2
        for the kinked backlash function).
    """
    x = np.asarray(x, dtype=float)
    exact = fourier_exact(x, b, H)
    ns = np.asarray([n for n in n_samples if n > 2 * max(H, n_harmonics(x))], dtype=int)
    err = np.array([np.max(np.abs(fourier_aft(x, b, H, n_samples=int(n)) - exact)) for n in ns])
    with np.errstate(divide="ignore", invalid="ignore"):
        order = np.diff(np.log(err)) / np.diff(np.log(ns))
    return {"n_samples": ns, "error": err, "order": order}


def one_sided_describing_function(x0: float, A: float, b: float) -> tuple[float, float]:
    """Closed-form mean and first cosine harmonic of h(x) = max(0, x - b) for x = x0 + A cos θ.

    With cos α = (b - x0)/A, α in [0, π] (outside |cos α| < 1 the contact is never
    lost, mean x0 - b and 1st harmonic A, or always lost, both 0):

        mean     = (A/π) (sin α - α cos α)
        1st harm = (A/π) (α - sin α cos α)      (coefficient of cos θ)

    Derivation: contact for |θ| < α, so mean = (1/2π) ∫_{-α}^{α} (x0 - b + A cos θ) dθ with
    x0 - b = -A cos α, and a_1 = (1/π) ∫_{-α}^{α} A (cos θ - cos α) cos θ dθ.
    h equals the backlash function f of :func:`deadzone` whenever x0 - A >= -b (no
    back-side contact); this is the one-sided contact-loss describing function.

    Parameters
    ----------
    x0 : float
        Mean of x [m].
    A : float
        Amplitude of the cosine of x [m], > 0.
    b : float
        Threshold of h: the half backlash [m].

    Returns
    -------
    mean : float
        Mean of h(x(θ)) [m].
    a1 : float
        Coefficient of cos θ in h(x(θ)) [m].

    Raises
    ------
    ModelError
        When ``A`` is not positive.
    """
    check_positive("A", A)
    ca = (b - x0) / A
    if ca <= -1:  # always in contact: h = x - b
        return x0 - b, A
    if ca >= 1:  # never in contact
        return 0.0, 0.0
    alpha = float(np.arccos(ca))
    sa = np.sin(alpha)
    return A / np.pi * (sa - alpha * ca), A / np.pi * (alpha - sa * ca)


def describing_gains(x: ArrayLike, b: float, H: int, method: str = "exact") -> NDArray[np.complex128]:
    """The paper's describing functions ν_k = F_k / X_k (Maliha et al. 2004, Eq. 18-22).

    F_k and X_k are the complex amplitudes of f(x(θ)) and x(θ) at harmonic k = 0..H, so
    that the nonlinear force is k_h Σ ν_k X_k e^{ikθ}. Harmonics with X_k = 0 get NaN.

    Parameters
    ----------
    x : array_like
        Real harmonics [x_0, a_1, b_1, ...] of x = δ - e (1-D) [m].
    b : float
        Half backlash [m] (total backlash 2b), >= 0.
    H : int
        Highest harmonic k.
    method : {"exact", "aft"}
        F_k by :func:`fourier_exact` ("exact") or by :func:`fourier_aft` (any other value).

    Returns
    -------
    ndarray of complex (H+1,)
        ν_k, k = 0..H [-]; NaN where X_k = 0.
    """
    x = resize_harmonics(x, max(H, n_harmonics(x)))
    G = fourier_exact(x, b, H) if method == "exact" else fourier_aft(x, b, H)
    Xk = real_to_complex(resize_harmonics(x, H))
    Gk = real_to_complex(G)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(Xk) > 0, Gk / np.where(Xk == 0, 1, Xk), np.nan)
