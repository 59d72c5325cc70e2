"""Local nonlinearities for the harmonic-balance solver.

They follow the small protocol of :class:`LocalNonlinearity`: the gear mesh is
:class:`BacklashMesh`; any other scalar force law (a bearing clearance, a cubic spring)
can be plugged in with :class:`AFTNonlinearity` without touching the solver.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from nlgrd.cache import BoundedCache
from nlgrd.errors import ModelError, check_finite, check_positive
from nlgrd.nonlinear.fourier.harmonics import (
    analyse,
    differentiate,
    evaluate,
    n_harmonics,
    real_to_complex,
    resize_harmonics,
    sample,
    toeplitz_jacobian,
)
from nlgrd.nonlinear.laws.describing_functions import (
    ContactIntervals,
    contact_intervals,
    deadzone,
    fourier_aft,
    fourier_exact,
)


@runtime_checkable
class LocalNonlinearity(Protocol):
    """What the harmonic-balance solver asks of a local nonlinearity.

    It acts on the nonlinear coordinates ``coords`` (indices into the solver's
    n_nl-vector y of nonlinear coordinates, e.g. y_0 = δ, the mesh relative
    displacement) and adds the force vector g(y(θ), θ) to their equations.

    Attributes
    ----------
    coords : tuple of int
        Indices of the m coordinates it acts on among the n_nl nonlinear coordinates; its
        harmonics, forces and tangents are ordered like them.
    """

    coords: tuple[int, ...]

    def harmonics(self, y: NDArray, jacobian: bool = False) -> NDArray | tuple[NDArray, NDArray]:
        """Force harmonics (m, 2H+1) for y harmonics (m, 2H+1); Jacobian (m(2H+1))²."""
        ...

    def offset(self, H: int) -> NDArray:
        """Real harmonics (m, 2H+1) of the excitation offset inside the force law (e.g. LSTE)."""
        ...

    def tangent_segments(self, y: NDArray) -> tuple[NDArray, NDArray]:
        """Breaks θ (n+1,) covering one period and piecewise-constant tangent (n, m, m) [N/m]."""
        ...

    def force_time(self, y: NDArray, theta: NDArray) -> NDArray:
        """Force samples (m, N) for coordinate samples y (m, N) at angles θ (N,)."""
        ...

    def scale(self) -> float:
        """The law's own length [m]: the displacement at which its behaviour changes (a
        gap, a clearance); 0 when it has none. Orbit searches size their starts by it."""
        ...


@dataclass(frozen=True)
class BacklashMesh:
    """Spur-gear mesh with backlash along the line of action (Maliha et al. 2004, Eq. 9-10).

    W(t) = k_h f(δ - e) + c_m (δ' - e'), f the backlash function of :func:`deadzone`.
    Only the elastic part k_h f is the nonlinearity; the damping c_m must also be part
    of the linear receptance (κ_k contains i kω c_m) and the LSTE damping forcing
    i kω c_m E_k part of the equivalent forcing f_k. ``damping`` here is only used to
    report W(t).

    Parameters
    ----------
    stiffness : float
        Average mesh stiffness k_h [N/m].
    half_backlash : float
        b [m]; the total backlash is 2b.
    lste : array_like
        Real harmonics [e_0, a_1, b_1, ...] of the loaded static transmission error e(θ)
        in the mesh angle θ = ω t [m]; may have more harmonics than the solver's H.
    damping : float
        Mesh damping c_m [N s/m] (output only, see above).
    static_load : float, optional
        W_0 [N] for the dynamic-to-static load ratio; default: the mean mesh force.
    coord : int
        Index of δ among the nonlinear coordinates.
    method : {"exact", "aft"}
        How the force harmonics are computed.
    n_samples : int, optional
        AFT samples (default :func:`default_aft_samples`).
    """

    stiffness: float
    half_backlash: float
    lste: NDArray = field(default_factory=lambda: np.zeros(1))
    damping: float = 0.0
    static_load: float | None = None
    coord: int = 0
    method: str = "exact"
    n_samples: int | None = None

    def __post_init__(self):
        check_positive("stiffness", self.stiffness)
        check_positive("half_backlash", self.half_backlash, allow_zero=True)
        check_positive("damping", self.damping, allow_zero=True)
        lste = np.atleast_1d(np.asarray(self.lste, dtype=float))
        check_finite("lste", lste)
        if lste.ndim != 1 or lste.size % 2 != 1:
            raise ModelError("lste", f"real harmonics [e0, a1, b1, ...] of odd length, got {lste.shape}")
        object.__setattr__(self, "lste", lste)
        if self.method not in ("exact", "aft"):
            raise ModelError("method", f"'exact' or 'aft', got {self.method!r}")

    @property
    def coords(self) -> tuple[int, ...]:
        """Nonlinear coordinates this element acts on."""
        return (self.coord,)

    def offset(self, H: int) -> NDArray:
        """LSTE harmonics truncated/padded to H, shape (1, 2H+1) [m]."""
        return resize_harmonics(self.lste, H)[None, :]

    def scale(self) -> float:
        """The half backlash b (a stop's gap g) [m]: where contact begins or ends.

        Returns
        -------
        float
        """
        return float(self.half_backlash)

    def full_contact(self, H: int) -> tuple[float, NDArray]:
        """The linear law k_h (δ - e - b) of drive-side contact throughout: its stiffness
        k_h [N/m] and the forcing k_h (E_k + b δ_k0), (1, H+1) complex [N], that it moves to
        the right-hand side (the first guess of :meth:`ReducedProblem.linear_solution`)."""
        shift = self.stiffness * real_to_complex(self.offset(H)[0])
        shift[0] += self.stiffness * self.half_backlash
        return self.stiffness, shift[None, :]

    def relative(self, delta: NDArray) -> NDArray:
        """Real harmonics of x = δ - e with all LSTE harmonics kept."""
        delta = np.asarray(delta, dtype=float).reshape(-1)
        H = max(n_harmonics(delta), n_harmonics(self.lste))
        return resize_harmonics(delta, H) - resize_harmonics(self.lste, H)

    def harmonics(self, y: NDArray, jacobian: bool = False):
        """Harmonics of k_h f(δ - e), shape (1, 2H+1), and optionally dG/dδ."""
        y = np.asarray(y, dtype=float).reshape(1, -1)
        H = n_harmonics(y)
        x = self.relative(y[0])
        if self.method == "exact":  # intervals through the cache: metrics and Floquet reuse them
            iv = self._intervals(x)
            out = fourier_exact(x, self.half_backlash, H, self.stiffness, jacobian, intervals=iv)
        else:
            out = fourier_aft(x, self.half_backlash, H, self.stiffness, self.n_samples, jacobian)
        if jacobian:
            return out[0][None, :], out[1]
        return out[None, :]

    def intervals(self, delta: NDArray) -> ContactIntervals:
        """Contact intervals of x = δ - e over one period (the last few are cached)."""
        return self._intervals(self.relative(delta))

    @cached_property
    def cache(self) -> BoundedCache:
        """The last contact intervals and LSTE samples of this mesh (16 entries)."""
        return BoundedCache(16)

    def _intervals(self, x: NDArray) -> ContactIntervals:
        key = ("intervals", x.tobytes())
        return self.cache.get(key, lambda: contact_intervals(x, self.half_backlash))

    def tangent_segments(self, y: NDArray) -> tuple[NDArray, NDArray]:
        """Exact contact intervals as breaks and tangent k_h or 0 per interval."""
        iv = self.intervals(np.asarray(y, dtype=float).reshape(-1))
        breaks = np.append(iv.start, iv.end[-1])
        kt = self.stiffness * np.abs(iv.state).astype(float)
        return breaks, kt[:, None, None]

    def force_time(self, y: NDArray, theta: NDArray) -> NDArray:
        """Elastic mesh force k_h f(δ - e) at angles θ for δ samples y (1, N)."""
        e = evaluate(self.lste, theta)
        return self.stiffness * deadzone(np.asarray(y).reshape(1, -1) - e, self.half_backlash)

    def stiffness_time(self, theta: NDArray) -> NDArray:
        """Contact stiffness at angles θ (N,) [N/m]: k_h throughout."""
        return np.full(np.shape(theta), float(self.stiffness))

    def lste_samples(self, n_samples: int) -> tuple[NDArray, NDArray]:
        """e(θ) and de/dθ at θ_j = 2πj/n_samples, read-only (kept in the cache)."""

        def make():
            out = (sample(self.lste, n_samples), sample(differentiate(self.lste), n_samples))
            for a in out:
                a.setflags(write=False)
            return out

        return self.cache.get(("lste samples", int(n_samples)), make)

    def elastic_samples(self, delta: NDArray) -> NDArray:
        """Elastic force at θ_j = 2πj/N for N equally spaced δ samples (..., N) [N]."""
        e = self.lste_samples(delta.shape[-1])[0]
        return self.stiffness * deadzone(delta - e, self.half_backlash)


@dataclass(frozen=True)
class ContactStop(BacklashMesh):
    """A one-sided contact: k (x - g) while x = y - e(θ) exceeds the gap g, nothing below it
    (an impact oscillator's stop, a gear mesh whose back flank never engages).

    The backlash law with its back-side contact removed: the same exact contact
    intervals, with the intervals of x < -g counted as separation, so its exact Fourier
    coefficients, Jacobian and Floquet segments are those of :class:`BacklashMesh`
    restricted to drive-side contact.

    Parameters
    ----------
    stiffness : float
        Contact stiffness k [N/m].
    half_backlash : float
        The gap g [m], >= 0.
    lste : array_like
        Real harmonics of the seat's motion e(θ) [m].
    Other parameters as :class:`BacklashMesh` (``method`` "exact" only).
    """

    def __post_init__(self):
        super().__post_init__()
        if self.method != "exact":
            raise ModelError("method", f"a contact stop has exact coefficients only, got {self.method!r}")

    def _intervals(self, x: NDArray) -> ContactIntervals:
        iv = super()._intervals(x)
        if not np.any(iv.state < 0):
            return iv
        return ContactIntervals(iv.start, iv.end, np.maximum(iv.state, 0))

    def force_time(self, y: NDArray, theta: NDArray) -> NDArray:
        """Contact force k (x - g)⁺ at angles θ for coordinate samples y (1, N)."""
        x = np.asarray(y).reshape(1, -1) - evaluate(self.lste, theta)
        return self.stiffness * np.maximum(x - self.half_backlash, 0.0)

    def elastic_samples(self, delta: NDArray) -> NDArray:
        """Contact force at θ_j = 2πj/N for N equally spaced samples (..., N) [N]."""
        e = self.lste_samples(delta.shape[-1])[0]
        return self.stiffness * np.maximum(delta - e - self.half_backlash, 0.0)


@dataclass(frozen=True)
class ParametricMesh(BacklashMesh):
    """A mesh whose stiffness varies over the mesh cycle: W = k_h ρ(θ) f(δ - e(θ)) + c_m (δ' - e').

    ρ(θ) = k(θ) / k_h (mean 1) is the tooth-pair stiffness variation (from the load
    sharing, a Fourier series or a file) and e(θ) the *unloaded* transmission error
    (profile and spacing errors, relief); with constant ρ = 1 the law is the paper's
    :class:`BacklashMesh` with e the loaded STE. This is the parametric formulation of
    Kahraman & Singh (1991, J. Sound Vib. 146:135) and Özgüven & Houser (1988, J. Sound
    Vib. 125:71). Its exact harmonics are the product of ρ's with those of the backlash
    force, taken to the harmonics the product reaches (a sampled product of two band-limited
    signals, exact). Floquet takes its tangent as a function of θ (:meth:`tangent_function`,
    Magnus steps refined to a tolerance); :meth:`tangent_segments` (Hill's method, the
    ``"expm"`` reference) splits each contact interval into cells with ρ at their midpoints
    (``n_cells`` per period, second order in the cell width).

    Parameters
    ----------
    stiffness_variation : array_like
        Real harmonics [ρ_0, a_1, b_1, ...] of ρ(θ) = k(θ)/k_h [-]; ρ_0 = 1 by convention.
    n_cells : int
        Cells per period of :meth:`tangent_segments`.
    Other parameters as :class:`BacklashMesh` (``method`` "exact" only).
    """

    stiffness_variation: NDArray = field(default_factory=lambda: np.ones(1))
    n_cells: int = 256

    def __post_init__(self):
        super().__post_init__()
        rho = np.atleast_1d(np.asarray(self.stiffness_variation, dtype=float))
        check_finite("stiffness_variation", rho)
        if rho.ndim != 1 or rho.size % 2 != 1:
            raise ModelError("stiffness_variation", f"real harmonics of odd length, got {rho.shape}")
        object.__setattr__(self, "stiffness_variation", rho)
        if self.method != "exact":
            raise ModelError("method", f"a parametric mesh has exact coefficients only, got {self.method!r}")

    def _product_map(self, L: int, H: int) -> NDArray:
        """The real (2H+1) x (2L+1) matrix of ρ(θ) g(θ) for g with L harmonics, cut at H."""
        key = ("product", L, H)

        def make():
            P = n_harmonics(self.stiffness_variation)
            N = int(2 ** np.ceil(np.log2(2 * (L + P + H) + 2)))
            basis = sample(np.eye(2 * L + 1), N)  # row i: samples of real harmonic i
            rho = sample(self.stiffness_variation, N)
            return analyse(basis * rho, H).T

        return self.cache.get(key, make)

    def harmonics(self, y: NDArray, jacobian: bool = False):
        """Harmonics of k_h ρ f(δ - e), shape (1, 2H+1), and optionally dG/dδ."""
        y = np.asarray(y, dtype=float).reshape(1, -1)
        H = n_harmonics(y)
        L = H + n_harmonics(self.stiffness_variation)
        x = self.relative(y[0])
        out = fourier_exact(x, self.half_backlash, L, self.stiffness, jacobian, intervals=self._intervals(x))
        Mr = self._product_map(L, H)
        if jacobian:
            return (Mr @ out[0])[None, :], Mr @ out[1][:, : 2 * H + 1]
        return (Mr @ out)[None, :]

    def tangent_segments(self, y: NDArray) -> tuple[NDArray, NDArray]:
        """Contact intervals cut into ``n_cells`` cells per period, tangent k_h ρ(mid) or 0."""
        iv = self.intervals(np.asarray(y, dtype=float).reshape(-1))
        start = iv.start[0]
        grid = start + np.arange(self.n_cells + 1) * (2 * np.pi / self.n_cells)
        breaks = np.unique(np.concatenate([np.append(iv.start, iv.end[-1]), grid]))
        breaks = breaks[np.append(True, np.diff(breaks) > 1e-13)]
        mid = 0.5 * (breaks[:-1] + breaks[1:])
        where = np.clip(np.searchsorted(iv.start, mid, side="right") - 1, 0, iv.state.size - 1)
        kt = self.stiffness * np.abs(iv.state[where]) * evaluate(self.stiffness_variation, mid)
        return breaks, kt[:, None, None]

    def tangent_function(self, y: NDArray) -> tuple[NDArray, object, NDArray]:
        """The tangent as a function of θ for a Magnus product (:mod:`nlgrd.nonlinear.stability.floquet`).

        Parameters
        ----------
        y : ndarray (1, 2H+1)
            Real harmonics of δ [m].

        Returns
        -------
        breaks : ndarray (n+1,)
            The exact contact changes over one period [rad]; the tangent is smooth between them.
        tangent : callable
            θ (k,) [rad] -> k_h ρ(θ) |state| (k, 1, 1) [N/m].
        varies : ndarray of bool (n,)
            Whether the tangent varies on each piece (False: constant there, zero in separation).
        """
        iv = self.intervals(np.asarray(y, dtype=float).reshape(-1))
        breaks = np.append(iv.start, iv.end[-1])
        state = np.abs(iv.state).astype(float)

        def tangent(theta):
            theta = np.asarray(theta, dtype=float)
            rel = np.mod(theta - breaks[0], 2 * np.pi) + breaks[0]
            seg = np.clip(np.searchsorted(breaks, rel, side="right") - 1, 0, state.size - 1)
            k = self.stiffness * state[seg] * evaluate(self.stiffness_variation, theta)
            return k[:, None, None]

        return breaks, tangent, state > 0

    def force_time(self, y: NDArray, theta: NDArray) -> NDArray:
        """Elastic mesh force k_h ρ(θ) f(δ - e) at angles θ for δ samples y (1, N)."""
        return super().force_time(y, theta) * evaluate(self.stiffness_variation, theta)

    def stiffness_time(self, theta: NDArray) -> NDArray:
        """Contact stiffness k_h ρ(θ) at angles θ (N,) [N/m]."""
        return self.stiffness * evaluate(self.stiffness_variation, np.asarray(theta, dtype=float))

    def elastic_samples(self, delta: NDArray) -> NDArray:
        """Elastic force k_h ρ f(δ - e) at θ_j = 2πj/N for N equally spaced δ samples (..., N) [N]."""
        n = delta.shape[-1]
        rho = self.cache.get(("rho samples", n), lambda: sample(self.stiffness_variation, n))
        return super().elastic_samples(delta) * rho


@dataclass(frozen=True)
class AFTNonlinearity:
    """Any scalar local force law g = force(y - offset(θ)) by AFT: plug-in example.

    Use it for a bearing clearance (``force = lambda u: k * deadzone(u, c)``), a cubic
    spring, etc., acting on nonlinear coordinate ``coord``.

    Parameters
    ----------
    force, tangent : callable
        Vectorised g(u) [N] and dg/du [N/m].
    coord : int
        Index of the coordinate among the nonlinear coordinates.
    offset_harmonics : array_like
        Real harmonics of a known excitation subtracted inside the law [m].
    n_samples : int
        AFT samples per period.
    length_scale : float
        The law's own length (a clearance, the amplitude where a cubic term matters) [m];
        0 when it has none (:meth:`scale`).
    """

    force: object
    tangent: object
    coord: int = 0
    offset_harmonics: NDArray = field(default_factory=lambda: np.zeros(1))
    n_samples: int = 256
    length_scale: float = 0.0

    def __post_init__(self):
        check_positive("length_scale", self.length_scale, allow_zero=True)

    def scale(self) -> float:
        """``length_scale`` [m] (the law is a black box: it says its own).

        Returns
        -------
        float
        """
        return float(self.length_scale)

    @property
    def coords(self) -> tuple[int, ...]:
        """Nonlinear coordinates this element acts on."""
        return (self.coord,)

    def offset(self, H: int) -> NDArray:
        """Offset harmonics (1, 2H+1)."""
        return resize_harmonics(np.asarray(self.offset_harmonics, dtype=float), H)[None, :]

    def _samples(self, y: NDArray) -> tuple[NDArray, int]:
        y = np.asarray(y, dtype=float).reshape(-1)
        H = n_harmonics(y)
        off = np.asarray(self.offset_harmonics, dtype=float)
        D = max(H, n_harmonics(off))
        u = resize_harmonics(y, D) - resize_harmonics(off, D)
        return sample(u, self.n_samples), H

    def harmonics(self, y: NDArray, jacobian: bool = False):
        """AFT harmonics (1, 2H+1) of the force and optionally their Jacobian."""
        us, H = self._samples(y)
        G = analyse(np.asarray(self.force(us), dtype=float), H)[None, :]
        if not jacobian:
            return G
        N = self.n_samples
        spec = np.fft.fft(np.asarray(self.tangent(us), dtype=float)) / N
        n = np.arange(-2 * H, 2 * H + 1)
        return G, toeplitz_jacobian(spec[np.mod(n, N)], 2 * H, H, 1.0)

    def tangent_segments(self, y: NDArray) -> tuple[NDArray, NDArray]:
        """Tangent sampled at the AFT points, piecewise constant on the sample cells."""
        us, _ = self._samples(y)
        N = self.n_samples
        breaks = (np.arange(N + 1) - 0.5) * 2 * np.pi / N
        return breaks, np.asarray(self.tangent(us), dtype=float)[:, None, None]

    def force_time(self, y: NDArray, theta: NDArray) -> NDArray:
        """Force at angles θ for coordinate samples y (1, N)."""
        off = evaluate(np.asarray(self.offset_harmonics, dtype=float), theta)
        return np.asarray(self.force(np.asarray(y).reshape(1, -1) - off), dtype=float)
