"""Search for periodic orbits that no sweep reaches (issue 12, item 2).

A sweep follows a branch from its start and leaves it only at a fold or a bifurcation:
an orbit on an isolated branch, born with its unstable twin in a saddle-node and not
connected to the mesh-periodic branch by period doubling (the 1/3 subharmonic resonance
of an impact oscillator is the classic one: Shaw & Holmes 1983, J. Sound Vib. 90:129;
Kahraman & Singh 1990, J. Sound Vib. 142:49), is never met. :func:`search_orbits` looks
for them at one frequency from many starts, for each period ν asked for: Newton on the
period-ν harmonic balance (base ω/ν, :mod:`nlgrd.nonlinear.tracing.subharmonic`) from

- perturbed starts (:data:`N_STARTS` per period by default): the linear response's mean
  with an alternating part whose amplitudes lie, on a log scale, between
  :data:`START_RANGE` times the model's length scales, from a tenth of the smallest to ten
  times the largest: each law's own length (``scale()``: a backlash, a gap, a radial
  clearance), the static deflection (the linear response's mean) and the linear response's
  amplitude at the frequency searched (or ``amplitude`` alone). An isolated branch lives
  where the nonlinearity acts, on the scale of its gap, however small the linear response
  is (a rotor's rub orbit: tests/test_orbit_search_scales.py). Every
  :data:`SHAPED_EVERY`-th start is the linear response's own alternating part scaled to an
  amplitude of a golden-ratio sequence over the range (the shape the forcing drives: a
  forward whirl under unbalance); the others have a component of random phase and
  log-uniform amplitude at each base harmonic 1..ν and coordinate, drawn from a seeded
  generator: the same starts on every machine;
- user starts: harmonics of ω/ν, typically the last ν mesh periods of a time integration
  from an arbitrary initial state (:meth:`nlgrd.timedomain.sdof.TimeResponse.harmonics`
  of ``integrate(pair.subharmonic(nu), omega / nu, state0)``);
- flips: a period-ν orbit born in a period doubling sits beside a period-ν/2 orbit whose
  dominant Floquet multiplier is real and below -1
  (:func:`~nlgrd.nonlinear.tracing.subharmonic.flip_unstable`), and leaves it along that
  orbit's critical mode. From each such orbit found, Newton starts from the starts of
  :func:`~nlgrd.nonlinear.tracing.subharmonic.branch_off` (the mode scaled to
  :data:`~nlgrd.nonlinear.tracing.subharmonic.BRANCH_OFF_SCALES` times the orbit's size
  (:func:`~nlgrd.nonlinear.tracing.subharmonic.orbit_size`; the laws' length for an orbit
  at rest at zero), + then - the mode, smallest first, up to the first size that reaches
  period ν): found
  by construction, not by a lucky perturbed start whose Newton path rounding decides
  (Kubo's rig at 3055.6 Hz, tests/test_period_doubling_fe.py). Only with ``stability``:
  the flip needs the multipliers.

The periods are searched in ascending order, so the period-ν/2 orbits are known when
period ν is sought. For each period the starts are tried in this order: the user starts,
the flips of the period-ν/2 orbits found so far, the perturbed starts, and the flips of the
period-ν/2 orbits that these found (listed with their shorter period).

Each converged orbit is classified by its minimal period p
(:func:`~nlgrd.nonlinear.fourier.periods.period_of`): its components at base harmonics that
are not multiples of ν/p are below :data:`PERIOD_TOL_FACTOR` times Newton's tolerance
relative to the orbit's size (its amplitude, its mean, the laws' lengths, whichever is
largest), so a constant orbit or a period-1 orbit found on the period-2 model is never a
period-2 orbit: it is listed as period p (solved again on the period-p model) or, with
``shorter_periods=False``, dropped. Each orbit is kept once: a period-p orbit shifted by
one mesh period (base harmonic j turned by 2πj/p) is the same motion. Its Floquet
multipliers over p mesh periods say whether a rig can settle on it. :func:`follow_orbit`
follows a found orbit over frequency.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import n_harmonics
from nlgrd.nonlinear.fourier.periods import SUBHARMONIC_RTOL, amplitudes, on_shorter_period, period_of
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.results.metrics import METRIC_NAMES, METRIC_UNITS, MeshMetrics
from nlgrd.nonlinear.results.sweep_results import STABLE_RTOL, SweepResult, dominant_multiplier
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.tracing.auto_period import period_only
from nlgrd.nonlinear.tracing.landing import SAME_ORBIT_RTOL
from nlgrd.nonlinear.tracing.subharmonic import (
    BRANCH_OFF_SCALES,
    critical_mode,
    flip_unstable,
    follow_period,
    orbit_size,
)
from nlgrd.units import column, floor_rounding, hz, um, written, written_frame

#: Perturbed starts per period by default.
N_STARTS = 40
#: Range of the perturbed starts' amplitudes: from this multiple of the model's smallest
#: length scale to this multiple of its largest [-].
START_RANGE = (0.1, 10.0)
#: Subharmonic content below this multiple of Newton's tolerance (relative to the orbit's
#: size) is solver error, not motion: the orbit has the shorter period [-]. The harmonics of
#: a converged orbit are known to about the tolerance times the Jacobian's conditioning.
PERIOD_TOL_FACTOR = 1e4
#: Every SHAPED_EVERY-th perturbed start is the linear response's shape scaled [-].
SHAPED_EVERY = 4
#: The owner of a single-DOF model's mesh metrics in :meth:`OrbitSearchResult.to_frame`
#: (a one-mesh model's mesh link name).
ONE_MESH = "mesh0"
#: The golden ratio's fractional part: the step of the starts' amplitude sequence.
_GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0


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
    columns : dict of str to float
        Every link's and linear bearing's outputs over the whole orbit,
        ``<link>.<quantity> [SI unit]`` (the search's ``outputs``: a link model's
        :func:`~nlgrd.nonlinear.results.link_results.point_outputs`); empty when the search
        was not given them.
    """

    omega: float
    period: int
    harmonics: NDArray
    floquet_max: float
    dominant_multiplier: complex
    start: str
    metrics: MeshMetrics | None = None
    columns: dict = field(default_factory=dict)

    @property
    def stable(self) -> bool:
        """Floquet-stable: max |μ| < 1 + ``STABLE_RTOL`` (the neutral multipliers of
        undamped modes that the mesh does not reach sit on the unit circle)."""
        return bool(self.floquet_max < 1 + STABLE_RTOL)

    @property
    def amplitude(self) -> float:
        """Largest alternating amplitude of any base harmonic of any coordinate [m]."""
        return float(np.max(amplitudes(self.harmonics)))

    def to_frame(self) -> pd.DataFrame:
        """This orbit as a one-row table (:meth:`OrbitSearchResult.to_frame`).

        Returns
        -------
        pandas.DataFrame
        """
        return OrbitSearchResult([self]).to_frame()

    def plot(self, ax=None):
        """This orbit's amplitude at its frequency (:meth:`OrbitSearchResult.plot`).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure when None.

        Returns
        -------
        matplotlib.axes.Axes
        """
        return OrbitSearchResult([self]).plot(ax=ax)


class OrbitSearchResult(list):
    """The orbits :func:`search_orbits` found: a list of :class:`FoundOrbit` with their
    table and figure.

    Attributes
    ----------
    (the list's items) : FoundOrbit
        Each distinct orbit once, by period and then by amplitude.
    """

    def to_frame(self) -> pd.DataFrame:
        """One row per orbit: ``base_frequency [Hz]``, ``period``, ``stable`` (NA where not
        computed), ``floquet_max [-]`` and the dominant multiplier [-], the largest
        alternating amplitude ``amplitude [um]``, the ``start`` that reached it, and every
        link's and linear bearing's outputs ``<link>.<quantity> [unit]`` in written units
        (:attr:`FoundOrbit.columns`, as a link sweep's table writes them); an orbit search
        on a model without link names (a single-DOF pair) writes its one mesh's metrics
        as ``mesh0``'s (NaN without a mesh).

        Returns
        -------
        pandas.DataFrame
        """
        fmax = np.array([o.floquet_max for o in self], dtype=float)
        stable = pd.array([o.stable for o in self], dtype="boolean")
        stable[~np.isfinite(fmax)] = pd.NA
        mu = np.array([o.dominant_multiplier for o in self], dtype=complex)
        data = {
            "base_frequency [Hz]": hz(np.array([o.omega for o in self], dtype=float)),
            "period": pd.array([o.period for o in self], dtype="Int64"),
            "stable": stable,
            "floquet_max [-]": fmax,
            "dominant_multiplier_re [-]": mu.real,
            "dominant_multiplier_im [-]": mu.imag,
            "amplitude [um]": um(np.array([o.amplitude for o in self], dtype=float)),
            "start": [o.start for o in self],
        }
        if any(o.columns for o in self):  # every link's, as a link sweep writes them
            links = pd.DataFrame([o.columns for o in self], dtype=float)
            return pd.concat([pd.DataFrame(data), floor_rounding(written_frame(links))], axis=1)
        for i, name in enumerate(METRIC_NAMES):
            si = METRIC_UNITS[name]
            values = np.array(
                [np.nan if o.metrics is None else o.metrics.as_tuple()[i] for o in self], dtype=float
            )
            if si is None:  # a flag: tri-state, NA without a mesh
                flag = pd.array(values == 1.0, dtype="boolean")
                flag[np.isnan(values)] = pd.NA
                data[column(name, None, ONE_MESH)] = flag
            else:
                unit, scaled = written(values, si)
                data[column(name, unit, ONE_MESH)] = scaled
        return pd.DataFrame(data)

    def plot(self, ax=None):
        """Each orbit's largest alternating amplitude against the base frequency, a marker per
        period, stable filled and unstable open (:func:`nlgrd.plotting.result_figures.plot_found_orbits`).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure when None.

        Returns
        -------
        matplotlib.axes.Axes
        """
        from nlgrd.plotting.result_figures import plot_found_orbits

        return plot_found_orbits(self.to_frame(), ax=ax)


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
    shorter_periods: bool = True,
    outputs: Callable[[NDArray, float, int], dict] | None = None,
) -> OrbitSearchResult:
    """Periodic orbits of the given periods at one mesh frequency, from many starts.

    Parameters
    ----------
    model_of : callable
        ``model_of(nu)``: the period-ν model on the base ω/ν (e.g.
        ``lambda nu: pair.subharmonic(nu).reduced_model()``, or the ``reduced`` model of
        :func:`nlgrd.nonlinear.models.link_model.period_model`); also asked for the divisors of
        each ν when an orbit of a shorter period is found (``shorter_periods``).
    omega : float
        Mesh frequency [rad/s].
    H : int
        Mesh harmonics of each orbit: a period-ν orbit is solved with ν H base harmonics [-].
    periods : sequence of int
        The periods ν sought [-], searched in ascending order.
    starts : sequence of (int, array_like)
        User starts: (ν, real harmonics of ω/ν of the nonlinear coordinates [m]), e.g. from
        a time integration; tried first (then the flips, then the perturbed starts: module
        notes).
    n_starts : int
        Perturbed starts per period [-] (module notes).
    amplitude : float, optional
        The one length scale of the perturbed starts [m]; default the model's
        (:func:`start_scales`).
    seed : int
        Seed of the starts' phases.
    stability : bool
        Floquet multipliers of each orbit found (needs the model's linear state space);
        without them no period-2ν orbit is started from a flip-unstable period-ν one.
    tol, max_iter : float, int
        Newton's tolerance (relative residual) and iteration limit per start.
    shorter_periods : bool
        An orbit found on the period-ν model whose minimal period p is shorter is listed
        as period p (True; once, with the period-p orbits) or dropped (False).
    outputs : callable, optional
        ``outputs(harmonics, omega, p)``: every link's outputs of a period-p orbit at mesh
        frequency ω, ``<link>.<quantity> [SI unit]`` (a link model's:
        :meth:`nlgrd.nonlinear.models.model_views.LinkView.values`); each orbit's
        :attr:`FoundOrbit.columns`.

    Returns
    -------
    OrbitSearchResult
        A list of :class:`FoundOrbit`: each distinct orbit once, by period and then by
        amplitude.

    Raises
    ------
    ModelError
        A period below 1 or not whole, ``n_starts`` negative, ``amplitude`` not positive,
        or a user start of a period not in ``periods``.
    """
    periods = _periods(periods)
    if int(n_starts) != n_starts or n_starts < 0:
        raise ModelError("n_starts", f"a whole number >= 0, got {n_starts!r}")
    if amplitude is not None and not (np.isfinite(amplitude) and amplitude > 0):
        raise ModelError("amplitude", f"a length > 0 [m], got {amplitude!r}")
    for nu, _ in starts:
        if nu not in periods:
            raise ModelError("starts", f"a start of period {nu!r}, not one of the periods sought {periods}")
    rng = np.random.default_rng(seed)
    rtol = max(SUBHARMONIC_RTOL, PERIOD_TOL_FACTOR * tol)
    found: list[FoundOrbit] = []

    def keep(z: NDArray, p: int, model: ReducedModel, label: str) -> None:
        if any(o.period == p and same_motion(o.harmonics, z, p) for o in found):
            return
        base = omega / p
        fmax, dom = np.nan, complex(np.nan, np.nan)
        ss = model.linear_state_space(base) if stability else None
        if ss is not None:
            fmax, dom = dominant_multiplier(floquet_multipliers(ss, model.nonlinearities, z, base))
        met = model.metrics.of(z, base)
        cols = {} if outputs is None else dict(outputs(z, float(omega), p))
        found.append(FoundOrbit(float(omega), p, z, float(fmax), complex(dom), label, met, cols))

    def attempt(problem, z0: NDArray, nu: int, model: ReducedModel, label: str) -> bool:
        """Newton from z0 on the period-ν problem; whether it reached a period-ν orbit."""
        sol = solve(problem, z0, tol=tol, max_iter=max_iter, fallback=False, stall=True)
        if not sol.converged:
            return False
        z = sol.harmonics
        p = period_of(z, nu, rtol, size=max(own, float(np.max(np.abs(z[:, 0])))))
        if p == nu:
            keep(z, nu, model, label)
        elif shorter_periods:
            keep(*_on_period(model_of(p), omega, p, H, on_shorter_period(z, nu, p), tol, max_iter), label)
        return p == nu

    flipped: set[int] = set()  # id() of the orbits whose flip was tried

    def from_flips(problem, nu: int, model: ReducedModel) -> None:
        """Branch-off starts from each flip-unstable period-ν/2 orbit found and not yet tried."""
        for o in [o for o in found if 2 * o.period == nu and id(o) not in flipped]:
            flipped.add(id(o))
            if not flip_unstable(o.dominant_multiplier):
                continue
            zs, phi = critical_mode(problem, o.harmonics, 2)
            a = orbit_size(o.harmonics) or own
            tag = f"flip of the period-{o.period} orbit from {o.start}"
            for s in BRANCH_OFF_SCALES if a > 0 else ():
                hits = [
                    attempt(
                        problem,
                        (zs + sign * s * a * phi).reshape(o.harmonics.shape[0], -1),
                        nu,
                        model,
                        f"{tag}, start {sign * s:+g} x its size",
                    )
                    for sign in (1.0, -1.0)
                ]
                if any(hits):  # the smallest start that reaches period ν, both signs
                    break

    for nu in periods:
        model = model_of(nu)
        problem = model.at(omega / nu, nu * H)
        own = max((nl.scale() for nl in model.nonlinearities), default=0.0)
        for i, (p, z) in enumerate(starts):
            if p == nu:
                attempt(problem, np.asarray(z, dtype=float), nu, model, f"user start {i}")
        from_flips(problem, nu, model)
        if n_starts:  # the linear response's harmonics, one row per nonlinear coordinate
            z_lin = problem.linear_solution().reshape(problem.n_coords, -1)
            scales = [amplitude] if amplitude is not None else start_scales(model.nonlinearities, z_lin)
            for z0, label in perturbed_starts(z_lin, nu, scales, int(n_starts), rng):
                attempt(problem, z0, nu, model, label)
        from_flips(problem, nu, model)  # period-ν/2 orbits found on the way (shorter_periods)
    return OrbitSearchResult(sorted(found, key=lambda o: (o.period, o.amplitude)))


def _periods(periods) -> tuple[int, ...]:
    out = []
    for p in periods:
        if int(p) != p or p < 1:
            raise ModelError("periods", f"whole numbers of mesh periods >= 1, got {p!r}")
        out.append(int(p))
    if not out:
        raise ModelError("periods", "at least one period")
    return tuple(sorted(set(out)))


def _on_period(model: ReducedModel, omega: float, p: int, H: int, z: NDArray, tol: float, max_iter: int):
    """An orbit of period p written on ω/p, polished by Newton on the period-p model
    (its residual there is that on the long base): (harmonics, p, model)."""
    sol = solve(model.at(omega / p, p * H), z, tol=tol, max_iter=max_iter, fallback=False, stall=True)
    return (sol.harmonics if sol.converged else z), p, model


def start_scales(nonlinearities: Sequence, z_lin: ArrayLike) -> list[float]:
    """The model's length scales that size the perturbed starts [m]: each law's own length
    (``scale()``), the static deflection (largest |mean| of the linear response) and the
    linear response's largest alternating amplitude; those > 0.

    Parameters
    ----------
    nonlinearities : sequence of LocalNonlinearity
        The model's laws.
    z_lin : array_like (n, 2H+1)
        The linear response's real harmonics, one row per nonlinear coordinate [m].

    Returns
    -------
    list of float
        The positive scales [m] (empty for a model at rest with laws of no length).
    """
    z_lin = np.atleast_2d(np.asarray(z_lin, dtype=float))
    cands = [float(nl.scale()) for nl in nonlinearities]
    cands += [float(np.max(np.abs(z_lin[:, 0]))), float(np.max(amplitudes(z_lin), initial=0.0))]
    return [c for c in cands if np.isfinite(c) and c > 0]


def perturbed_starts(
    z_lin: ArrayLike, nu: int, scales: Sequence[float], n: int, rng: np.random.Generator
) -> list[tuple[NDArray, str]]:
    """``n`` starts of the period-ν search (module notes): the linear response's mean and an
    alternating part whose amplitudes lie from ``START_RANGE[0] * min(scales)`` to
    ``START_RANGE[1] * max(scales)`` on a log scale.

    Every :data:`SHAPED_EVERY`-th start is the linear response's alternating part scaled to
    an amplitude A of a golden-ratio sequence over that range (with random subharmonics
    1..ν-1 of amplitude A for ν > 1; the first is the static state itself when the linear
    response does not vibrate); the others have at each base harmonic 1..ν and each
    coordinate a component of random phase and a log-uniform amplitude of their own (a
    start mixing small and large harmonics, as an orbit near a subharmonic resonance does).

    Parameters
    ----------
    z_lin : array_like (n_nl, 2H+1)
        The linear response on the base ω/ν [m].
    nu : int
        Mesh periods per base period [-].
    scales : sequence of float
        Length scales [m] (:func:`start_scales`); none: the linear response alone.
    n : int
        Number of starts [-].
    rng : numpy.random.Generator
        Source of the phases and of the random starts' amplitudes.

    Returns
    -------
    list of (ndarray (n_nl, 2H+1), str)
        Starts and their labels.
    """
    z_lin = np.atleast_2d(np.asarray(z_lin, dtype=float))
    if not len(scales):
        return [(z_lin.copy(), "linear response")][:n]
    H = n_harmonics(z_lin[0])
    lo, hi = np.log(START_RANGE[0] * min(scales)), np.log(START_RANGE[1] * max(scales))
    alt = z_lin.copy()
    alt[:, 0] = 0.0
    size = float(np.max(amplitudes(z_lin), initial=0.0))
    out = []
    for i in range(n):
        z = np.zeros_like(z_lin)
        z[:, 0] = z_lin[:, 0]
        if i == 0 and size == 0:  # a state at rest: the static state itself first
            out.append((z, "static state"))
            continue
        shaped = i % SHAPED_EVERY == 0 and size > 0
        a = float(np.exp(lo + ((0.5 + (i // SHAPED_EVERY) * _GOLDEN) % 1.0) * (hi - lo)))
        if shaped:
            z += alt * (a / size)
        for j in range(1, min(nu - 1 if shaped else nu, H) + 1):
            aj = np.full(z.shape[0], a) if shaped else np.exp(rng.uniform(lo, hi, z.shape[0]))
            ph = rng.uniform(0.0, 2 * np.pi, z.shape[0])
            z[:, 2 * j - 1] += aj * np.cos(ph)
            z[:, 2 * j] += aj * np.sin(ph)
        label = f"scaled linear start {i} ({a:.3g} m)" if shaped else f"perturbed start {i}"
        out.append((z, label))
    return out


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
    (:func:`nlgrd.nonlinear.tracing.subharmonic.follow_period`), as a response of its period.

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
        ``period`` ν (:func:`nlgrd.nonlinear.tracing.auto_period.period_only`): converged where the
        branch exists, ``no_stable`` where it is unstable.
    """
    nu = orbit.period
    res = follow_period(
        model_of(nu), omegas, nu * H, nu, orbit.omega, orbit.harmonics, directions, stability=stability
    )
    return period_only(res, nu)
