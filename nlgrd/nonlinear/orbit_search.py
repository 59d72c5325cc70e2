"""Search for periodic orbits that no sweep reaches (issue 12, item 2).

A sweep follows a branch from its start and leaves it only at a fold or a bifurcation:
an orbit on an isolated branch, born with its unstable twin in a saddle-node and not
connected to the mesh-periodic branch by period doubling (the 1/3 subharmonic resonance
of an impact oscillator is the classic one: Shaw & Holmes 1983, J. Sound Vib. 90:129;
Kahraman & Singh 1990, J. Sound Vib. 142:49), is never met. :func:`search_orbits` looks
for them at one frequency from many starts, for each period ν asked for: Newton on the
period-ν harmonic balance (base ω/ν, :mod:`nlgrd.nonlinear.subharmonic`) from

- perturbed starts: the linear response's mean with a random component at each base
  harmonic 1..ν, amplitudes log-uniform between 0.05 and 5 times the size of the orbit
  scale (the larger of the linear response's alternating amplitude and its mean, or
  ``amplitude``), drawn from a seeded generator: the same starts on every machine;
- user starts: harmonics of ω/ν, typically the last ν mesh periods of a time integration
  from an arbitrary initial state (:meth:`nlgrd.timedomain.sdof.TimeResponse.harmonics`
  of ``integrate(pair.subharmonic(nu), omega / nu, state0)``).

Each converged orbit of exactly period ν is kept once: a period-ν orbit shifted by one
mesh period (base harmonic j turned by 2πj/ν) is the same motion. Its Floquet
multipliers over ν mesh periods say whether a rig can settle on it.
:func:`follow_orbit` follows a found orbit over frequency.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.auto_period import period_only
from nlgrd.nonlinear.floquet import floquet_multipliers
from nlgrd.nonlinear.geared import GearedModel, build_geared_model
from nlgrd.nonlinear.harmonic_balance import ReducedModel
from nlgrd.nonlinear.landing import SAME_ORBIT_RTOL
from nlgrd.nonlinear.metrics import MeshMetrics
from nlgrd.nonlinear.results import STABLE_RTOL, SweepResult, dominant_multiplier
from nlgrd.nonlinear.solvers import solve
from nlgrd.nonlinear.subharmonic import amplitudes, follow_period, period_of

#: Perturbed starts per period by default.
N_STARTS = 24
#: Range of the perturbed starts' amplitudes, as multiples of the orbit scale [-].
START_RANGE = (0.05, 5.0)


@dataclass(frozen=True)
class FoundOrbit:
    """A periodic orbit found by :func:`search_orbits`.

    Attributes
    ----------
    omega : float
        Mesh frequency [rad/s].
    period : int
        ν, mesh periods per period of the orbit [-].
    harmonics : ndarray (n, 2H+1)
        Real harmonics of the base ω/ν of the nonlinear coordinates [m].
    floquet_max : float
        Largest Floquet multiplier modulus over ν mesh periods (NaN: not computed) [-].
    dominant_multiplier : complex
        The multiplier of that modulus [-].
    start : str
        Which start reached it first.
    metrics : MeshMetrics or None
        Output metrics of the model's first mesh over the whole orbit (None without a mesh).
    """

    omega: float
    period: int
    harmonics: NDArray
    floquet_max: float
    dominant_multiplier: complex
    start: str
    metrics: MeshMetrics | None = None

    @property
    def stable(self) -> bool:
        """Floquet-stable: max |μ| < 1 + ``STABLE_RTOL`` (the neutral multipliers of
        undamped modes that the mesh does not reach sit on the unit circle)."""
        return bool(self.floquet_max < 1 + STABLE_RTOL)

    @property
    def amplitude(self) -> float:
        """Largest alternating amplitude of any base harmonic of any coordinate [m]."""
        return float(np.max(amplitudes(self.harmonics)))


def shifted(z: ArrayLike, nu: int, s: int) -> NDArray:
    """A period-ν orbit's harmonics after a time shift of ``s`` mesh periods.

    Parameters
    ----------
    z : array_like (..., 2H+1)
        Real harmonics [x0, a1, b1, ...] of the base ω/ν (any unit).
    nu : int
        Mesh periods per base period [-].
    s : int
        The shift in mesh periods [-].

    Returns
    -------
    ndarray
        Harmonics of x(t + s T) (unit of z).
    """
    z = np.array(z, dtype=float)
    H = (z.shape[-1] - 1) // 2
    phi = 2 * np.pi * s * np.arange(1, H + 1) / nu
    a, b = z[..., 1::2].copy(), z[..., 2::2].copy()
    z[..., 1::2] = a * np.cos(phi) + b * np.sin(phi)
    z[..., 2::2] = b * np.cos(phi) - a * np.sin(phi)
    return z


def same_motion(a: ArrayLike, b: ArrayLike, nu: int) -> bool:
    """Whether two period-ν orbits are one motion up to a shift by whole mesh periods.

    Parameters
    ----------
    a, b : array_like (n, 2H+1)
        Real harmonics of the base ω/ν [m].
    nu : int
        Mesh periods per base period [-].

    Returns
    -------
    bool
        Some shift of ``a`` within ``SAME_ORBIT_RTOL`` of ``b`` (relative to the larger norm).
    """
    scale = max(float(np.linalg.norm(a)), float(np.linalg.norm(b)))
    return any(
        np.linalg.norm(shifted(a, nu, s) - np.asarray(b)) <= SAME_ORBIT_RTOL * scale for s in range(nu)
    )


def search_orbits(
    model_of: Callable[[int], ReducedModel],
    omega: float,
    H: int,
    periods: Sequence[int] = (1, 2, 3),
    *,
    starts: Sequence[tuple[int, ArrayLike]] = (),
    n_starts: int = N_STARTS,
    amplitude: float | None = None,
    seed: int = 0,
    stability: bool = True,
    tol: float = 1e-10,
    max_iter: int = 80,
) -> list[FoundOrbit]:
    """Periodic orbits of the given periods at one mesh frequency, from many starts.

    Parameters
    ----------
    model_of : callable
        ``model_of(nu)``: the period-ν model on the base ω/ν (e.g.
        ``lambda nu: pair.subharmonic(nu).reduced_model()``, or the ``reduced`` model of
        :func:`nlgrd.nonlinear.geared.build_geared_model` with ``period=nu``).
    omega : float
        Mesh frequency [rad/s].
    H : int
        Mesh harmonics of each orbit: a period-ν orbit is solved with ν H base harmonics [-].
    periods : sequence of int
        The periods ν sought [-].
    starts : sequence of (int, array_like)
        User starts: (ν, real harmonics of ω/ν of the nonlinear coordinates [m]), e.g. from
        a time integration; tried before the perturbed ones.
    n_starts : int
        Perturbed starts per period [-].
    amplitude : float, optional
        Orbit scale of the perturbed starts [m]; default the larger of the linear
        response's largest alternating amplitude and its mean.
    seed : int
        Seed of the starts' generator.
    stability : bool
        Floquet multipliers of each orbit found (needs the model's linear state space).
    tol, max_iter : float, int
        Newton's tolerance (relative residual) and iteration limit per start.

    Returns
    -------
    list of FoundOrbit
        Each distinct orbit once, by period and then by amplitude.

    Raises
    ------
    ModelError
        A period below 1 or not whole, ``n_starts`` negative, or a user start of a period
        not in ``periods``.
    """
    periods = _periods(periods)
    if int(n_starts) != n_starts or n_starts < 0:
        raise ModelError("n_starts", f"a whole number >= 0, got {n_starts!r}")
    for nu, _ in starts:
        if nu not in periods:
            raise ModelError("starts", f"a start of period {nu!r}, not one of the periods sought {periods}")
    rng = np.random.default_rng(seed)
    found: list[FoundOrbit] = []
    for nu in periods:
        model = model_of(nu)
        base, Hb = omega / nu, nu * H
        problem = model.at(base, Hb)
        tries = [
            (np.asarray(z, dtype=float), f"user start {i}") for i, (p, z) in enumerate(starts) if p == nu
        ]
        if n_starts:  # the linear response's harmonics, one row per nonlinear coordinate
            z_lin = problem.linear_solution().reshape(problem.n_coords, -1)
            tries += _perturbed(z_lin, nu, Hb, int(n_starts), amplitude, rng)
        mine: list[FoundOrbit] = []
        for z0, label in tries:
            sol = solve(problem, z0, tol=tol, max_iter=max_iter, fallback=False, stall=True)
            if not sol.converged or period_of(sol.harmonics, nu) != nu:
                continue
            if any(same_motion(o.harmonics, sol.harmonics, nu) for o in mine):
                continue
            fmax, dom = np.nan, complex(np.nan, np.nan)
            ss = model.linear_state_space(base) if stability else None
            if ss is not None:
                fmax, dom = dominant_multiplier(
                    floquet_multipliers(ss, model.nonlinearities, sol.harmonics, base)
                )
            met = model.metrics.of(sol.harmonics, base)
            mine.append(FoundOrbit(float(omega), nu, sol.harmonics, float(fmax), complex(dom), label, met))
        found += sorted(mine, key=lambda o: o.amplitude)
    return found


def _periods(periods) -> tuple[int, ...]:
    out = []
    for p in periods:
        if int(p) != p or p < 1:
            raise ModelError("periods", f"whole numbers of mesh periods >= 1, got {p!r}")
        out.append(int(p))
    if not out:
        raise ModelError("periods", "at least one period")
    return tuple(dict.fromkeys(out))


def _perturbed(z_lin: NDArray, nu: int, H: int, n: int, amplitude, rng) -> list[tuple[NDArray, str]]:
    """``n`` starts: the linear response's mean with random components at base harmonics 1..ν."""
    z_lin = np.atleast_2d(np.asarray(z_lin, dtype=float))
    scale = amplitude or max(
        float(np.max(amplitudes(z_lin), initial=0.0)), float(np.max(np.abs(z_lin[:, 0])))
    )
    lo, hi = np.log(START_RANGE[0]), np.log(START_RANGE[1])
    out = []
    for i in range(n):
        z = np.zeros((z_lin.shape[0], 2 * H + 1))
        z[:, 0] = z_lin[:, 0]
        for j in range(1, min(nu, H) + 1):
            a = scale * np.exp(rng.uniform(lo, hi, z.shape[0]))
            ph = rng.uniform(0.0, 2 * np.pi, z.shape[0])
            z[:, 2 * j - 1], z[:, 2 * j] = a * np.cos(ph), a * np.sin(ph)
        out.append((z, f"perturbed start {i}"))
    return out


def geared_model_of(model: GearedModel) -> Callable[[int], ReducedModel]:
    """``model_of`` for :func:`search_orbits` on a geared FE model: ν → its period-ν model,
    built once per ν and H (kept in ``model.cache``) with as many base harmonics as
    ``model`` has mesh harmonics, ν times over.

    Parameters
    ----------
    model : GearedModel
        From :func:`nlgrd.nonlinear.geared.build_geared_model` (period 1).

    Returns
    -------
    callable
        ``model_of(nu)`` -> ReducedModel on the base ω/ν.
    """

    def model_of(nu: int) -> ReducedModel:
        if nu == 1:
            return model.reduced
        key = ("period", nu, nu * model.H)
        return model.cache.get(
            key,
            lambda: build_geared_model(
                model.system,
                model.max_mesh_frequency,
                nu * model.H,
                model.receptance.requested_method,
                period=nu,
            ),
        ).reduced

    return model_of


def follow_orbit(
    model_of: Callable[[int], ReducedModel],
    orbit: FoundOrbit,
    omegas: ArrayLike,
    H: int,
    directions: str = "both",
    *,
    stability: bool = True,
) -> SweepResult:
    """The branch of a found orbit over a grid of mesh frequencies, up and/or down from it
    (:func:`nlgrd.nonlinear.subharmonic.follow_period`), as a response of its period.

    Parameters
    ----------
    model_of : callable
        ``model_of(nu)`` -> the period-ν model, as for :func:`search_orbits`.
    orbit : FoundOrbit
        The start.
    omegas : array_like
        Mesh frequencies [rad/s].
    H : int
        Mesh harmonics (ν H of the base), as for :func:`search_orbits` [-].
    directions : {"both", "up", "down"}
        From the orbit's frequency up, down, or both.
    stability : bool
        Floquet multipliers over ν mesh periods.

    Returns
    -------
    SweepResult
        ``period`` ν (:func:`nlgrd.nonlinear.auto_period.period_only`): converged where the
        branch exists, ``no_stable`` where it is unstable.
    """
    nu = orbit.period
    res = follow_period(
        model_of(nu), omegas, nu * H, nu, orbit.omega, orbit.harmonics, directions, stability=stability
    )
    return period_only(res, nu)
