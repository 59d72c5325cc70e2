"""Results of harmonic-balance sweeps, continuation curves and time-domain sweeps.

One family: :class:`SweepResult` holds one row per point of a sweep, of a continuation
curve (``direction`` "curve") or of a time-integration sweep, with the same columns and
flags; :class:`ContinuationResult` adds the arc length and the turning points to a
curve. The per-point output metrics are in :mod:`nlgrd.nonlinear.results.metrics`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.results.jumps import Jump, find_jumps
from nlgrd.nonlinear.results.metrics import METRIC_NAMES, METRIC_UNITS, MeshMetrics
from nlgrd.nonlinear.results.response_kinds import QUASI_PERIODIC, response_kind, uncertainty_column  # noqa: F401
from nlgrd.units import WRITTEN, column, hz, um

#: A point is stable when max |μ| < 1 + STABLE_RTOL.
STABLE_RTOL = 1e-6

#: What ``residual`` means, by kind of result, and its column in :meth:`SweepResult.to_frame`.
RESIDUAL_COLUMNS = {
    "relative residual": "residual [-]",  # harmonic balance: max|R| / max(|L z|, |B G|, |F|)
    "period difference": "period_difference [-]",  # time integration: last period to the one before
}

#: Each metric's column and the factor from SI to it (None: a flag).
_UNITS = {
    name: (column(name, WRITTEN[si][0]), WRITTEN[si][1]) if si else (column(name, None), None)
    for name, si in METRIC_UNITS.items()
}


#: Significant digits of the written Floquet multiplier modulus, and the band around 1
#: written as exactly 1 (a neutral mode: an undamped mode or the drift of a free one).
FLOQUET_DIGITS = 10
NEUTRAL_BAND = 1e-9


def floquet_output(values: NDArray, signed: bool = False) -> NDArray:
    """max |μ| as written: 10 significant digits, neutral multipliers as exactly 1.

    ``signed``: a multiplier's real or imaginary part, written to the same quantum 1e-9
    absolute (a part much smaller than |μ| carries |μ|'s rounding, not its own).

    The monodromy's eigenvalues carry rounding noise of ~1e-13 that also depends on the
    alignment of the arrays in memory (it changes between runs of the same command); a
    neutral multiplier would otherwise be written as 1 ± noise. Rounded to 10 digits
    (quantum 1e-9, far above the noise, far below the stability margin 1e-6) the column
    is the same from run to run and machine to machine.

    Parameters
    ----------
    values : ndarray
        Multiplier moduli, or real or imaginary parts with ``signed`` [-].
    signed : bool
        Round to the absolute quantum 1e-9 instead of 10 significant digits.

    Returns
    -------
    ndarray
        The rounded values (NaN kept).
    """
    v = np.asarray(values, dtype=float).copy()
    if signed:
        return np.round(v, FLOQUET_DIGITS - 1) + 0.0  # + 0.0: no "-0.0"
    ok = np.isfinite(v) & (v > 0)
    v[ok & (np.abs(v - 1.0) <= NEUTRAL_BAND)] = 1.0
    e = np.floor(np.log10(v[ok]))
    v[ok] = np.round(v[ok] / 10**e, FLOQUET_DIGITS - 1) * 10**e
    return v


def instability_kind(mu: NDArray, stable: NDArray) -> NDArray:
    """Per point: "" (stable), or the dominant multiplier's kind where unstable: "real > 1"
    (a fold: saddle-node), "real < -1" (period doubling), "complex" (a torus, Neimark-
    Sacker); a pair counts as complex when |Im μ| > 1e-6 |μ| (rounding leaves ~1e-15).

    Parameters
    ----------
    mu : ndarray of complex
        Dominant multiplier per point [-] (NaN where not computed).
    stable : ndarray of bool
        Stability per point.

    Returns
    -------
    ndarray of str (object)
        "", "real > 1", "real < -1" or "complex" per point.
    """
    mu = np.asarray(mu, dtype=complex)
    out = np.full(mu.shape, "", dtype=object)
    with np.errstate(invalid="ignore"):
        cplx = np.abs(mu.imag) > 1e-6 * np.abs(mu)
        unstable = ~np.asarray(stable, dtype=bool) & np.isfinite(mu.real)
        out[unstable & cplx] = "complex"
        out[unstable & ~cplx & (mu.real > 0)] = "real > 1"
        out[unstable & ~cplx & (mu.real < 0)] = "real < -1"
    return out


def _per_point(value) -> bool:
    return isinstance(value, np.ndarray) and value.ndim >= 1


def _significant(values: NDArray, digits: int) -> NDArray:
    """``values`` rounded to ``digits`` significant digits (an estimate's noise not written)."""
    v = np.asarray(values, dtype=float).copy()
    ok = np.isfinite(v) & (v != 0)
    e = np.floor(np.log10(np.abs(v[ok])))
    v[ok] = np.round(v[ok] / 10**e, digits - 1) * 10**e
    return v


def check_quantity(quantity: str) -> None:
    """Raise ModelError("quantity") unless ``quantity`` is one of :data:`METRIC_NAMES`.

    Parameters
    ----------
    quantity : str
        A metric name, e.g. "dte_rms".
    """
    if quantity not in METRIC_NAMES:
        raise ModelError("quantity", f"must be one of {', '.join(METRIC_NAMES)}, got {quantity!r}")


@dataclass(frozen=True)
class SweepResult:
    """A frequency sweep: one row per point, in sweep order (up points first, then down).

    Attributes
    ----------
    omega : ndarray
        Mesh frequency [rad/s].
    direction : ndarray of str
        "up" or "down" (or "curve" for a continuation).
    harmonics : ndarray (n_points, n_nl, 2H+1)
        Real harmonics of the nonlinear coordinates [m]; NaN where not converged.
    converged : ndarray of bool
    residual : ndarray
        What ``residual_kind`` says [-]: the relative residual of the harmonic balance, or
        the last relative period-to-period difference of a time integration.
    iterations : ndarray of int
        Solver iterations (HB) or simulated periods (time domain).
    stable : ndarray of bool
        Floquet stability (|μ| < 1 + 1e-6); False where unknown (see ``floquet_max``).
    floquet_max : ndarray
        Largest Floquet multiplier modulus [-]; NaN where not computed.
    metrics : dict of str -> ndarray
        The :data:`~nlgrd.nonlinear.results.metrics.METRIC_NAMES` per point (SI).
    amplitudes : ndarray (n_points, H+1)
        DTE harmonic amplitudes |δ_k| [m].
    source : str
        "harmonic balance (H=5, exact)", "time integration", ...
    branch_switch : ndarray of bool
        The point was reached only after the previous branch folded (Newton failed
        from the previous solution and the arc-length jump found the new branch).
    harmonic_error : ndarray, optional
        Estimated relative error of the outputs from the truncation to H harmonics
        (:func:`nlgrd.nonlinear.tracing.harmonic_convergence.check_harmonics`); NaN where not estimated.
    H_check : int, optional
        The H the estimate was made against, counted as :attr:`H` (harmonics of ω).
    no_stable : ndarray of bool
        No stable mesh-periodic response was found at the point: the harmonics are those of
        the unstable orbit the sweep reached (kept for the analysis of what grows from
        it), the metrics are NaN, never drawn as the response.
    dominant_multiplier : ndarray of complex
        The Floquet multiplier of largest modulus (NaN where not computed): real > 1 (a
        fold), real < -1 (period doubling) or a complex pair (a torus) at an instability.
    residual_kind : str
        A key of :data:`RESIDUAL_COLUMNS`: "relative residual" (harmonic balance, curves)
        or "period difference" (time integration).
    period : ndarray of int, optional
        Mesh periods after which the point's orbit repeats (1: mesh-periodic; 2: period
        doubled; :mod:`nlgrd.nonlinear.tracing.subharmonic`). The harmonics and metrics of a
        point of period ν are those of its whole period, on the base ω/ν.
    subharmonic_amplitude : ndarray, optional
        Largest DTE amplitude at a frequency j ω/ν, j not a multiple of ν [m] (0 for
        mesh-periodic points).
    base : int
        The harmonics are of ω/base (2 when some point has period 2, N for a shaft-order
        sweep): :attr:`H_stored` = base · :attr:`H` of them (docs/conventions.md, "H").
    time_kind : ndarray of str (object), optional
        Per point: "" or, where no stable periodic response exists and a time integration
        answered (:mod:`nlgrd.timedomain.time_answer`), :data:`TIME_DOMAIN` or
        :data:`CHAOTIC`; the metrics there are its statistics.
    uncertainty : dict of str -> ndarray, optional
        Standard uncertainty of each metric of the time-answered points (SI; NaN elsewhere).
    verdict_converged : ndarray of bool, optional
        The stability verdict converged (:mod:`nlgrd.nonlinear.stability.verdicts`; default True);
        where False neither ``stable`` nor the response's values are written.
    torus_frequency : ndarray, optional
        The secondary frequency ω₂ of the torus that answered a quasi-periodic point
        (:func:`nlgrd.timedomain.sweep_answers.with_torus_answers`) [rad/s]; NaN elsewhere.
    """

    omega: NDArray
    direction: NDArray
    harmonics: NDArray
    converged: NDArray
    residual: NDArray
    iterations: NDArray
    stable: NDArray
    floquet_max: NDArray
    metrics: dict
    amplitudes: NDArray
    source: str = ""
    branch_switch: NDArray | None = None
    harmonic_error: NDArray | None = None
    H_check: int | None = None
    no_stable: NDArray | None = None
    dominant_multiplier: NDArray | None = None
    residual_kind: str = "relative residual"
    period: NDArray | None = None
    subharmonic_amplitude: NDArray | None = None
    base: int = 1
    time_kind: NDArray | None = None
    uncertainty: dict | None = None
    verdict_converged: NDArray | None = None
    torus_frequency: NDArray | None = None

    def __post_init__(self):
        if self.residual_kind not in RESIDUAL_COLUMNS:
            raise ModelError("residual_kind", f"must be one of {', '.join(RESIDUAL_COLUMNS)}")
        n = self.omega.size
        defaults = {  # the columns a result may leave out
            "period": np.ones(n, dtype=int),
            "subharmonic_amplitude": np.zeros(n),
            "branch_switch": np.zeros(n, dtype=bool),
            "no_stable": np.zeros(n, dtype=bool),
            "dominant_multiplier": np.full(n, np.nan + 0j),
            "harmonic_error": np.full(n, np.nan),
            "time_kind": np.full(n, "", dtype=object),
            "verdict_converged": np.ones(n, dtype=bool),
            "torus_frequency": np.full(n, np.nan),
        }
        for name, default in defaults.items():
            if getattr(self, name) is None:
                object.__setattr__(self, name, default)

    @property
    def time_answered(self) -> NDArray:
        """Points without a stable periodic response that a time integration answered."""
        return np.asarray(self.time_kind != "", dtype=bool) & np.asarray(self.no_stable, dtype=bool)

    @property
    def H(self) -> int:
        """H of docs/conventions.md: the harmonics of ω (the sweep's frequency) resolved,
        H ω the highest frequency; what the ``H`` column, the figures and the command line
        report, whatever the period of the points."""
        return self.H_stored // self.base

    @property
    def H_stored(self) -> int:
        """The harmonics of ω/``base`` the arrays hold (``harmonics``: 2 H_stored + 1 per
        coordinate), base · :attr:`H`."""
        return (self.harmonics.shape[-1] - 1) // 2

    @property
    def max_harmonic_error(self) -> float:
        """The largest estimated harmonic error over the accepted points (converged, with
        a stable response: the values written) [-]; NaN where none was estimated. A point
        above the estimate's tolerance is not converged and does not count."""
        keep = np.asarray(self.converged, dtype=bool) & ~np.asarray(self.no_stable, dtype=bool)
        e = np.asarray(self.harmonic_error, dtype=float)[keep]
        e = e[np.isfinite(e)]
        return float(e.max()) if e.size else math.nan

    def __len__(self) -> int:
        return self.omega.size

    @property
    def secondary_frequency(self) -> NDArray:
        """Per point without a stable response whose orbit lost stability to a complex pair
        of multipliers μ (Neimark-Sacker: the motion near it is quasi-periodic), the
        frequency of the secondary oscillation |arg μ| ω/(2π ν), in (0, ω/2ν] [rad/s]; where
        the torus harmonic balance answered (``torus_frequency``), its ω₂; NaN elsewhere."""
        mu = np.asarray(self.dominant_multiplier, dtype=complex)
        with np.errstate(invalid="ignore"):
            torus = self.no_stable & (np.abs(mu.imag) > 1e-6 * np.abs(mu)) & (np.abs(mu) > 1)
        f = np.abs(np.angle(mu)) * self.omega / (2 * np.pi * self.period)
        solved = np.isfinite(self.torus_frequency)  # the torus balance's own ω₂ where it answered
        return np.where(solved, self.torus_frequency, np.where(torus, f, np.nan))

    @property
    def stability_known(self) -> NDArray:
        """Where Floquet multipliers were computed."""
        return np.isfinite(self.floquet_max)

    def __getattr__(self, name: str):
        metrics = self.__dict__.get("metrics", {})
        if name in metrics:
            return metrics[name]
        raise AttributeError(name)

    def select(self, direction: str) -> SweepResult:
        """The points of one sweep direction."""
        keep = self.direction == direction
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        rows = {name: v[keep] for name, v in values.items() if _per_point(v)}
        per_point = {"metrics": {k: v[keep] for k, v in self.metrics.items()}}
        if self.uncertainty is not None:
            per_point["uncertainty"] = {k: v[keep] for k, v in self.uncertainty.items()}
        return replace(self, **per_point, **rows)

    def failures(self) -> NDArray:
        """Frequencies [rad/s] of the points that did not converge."""
        return self.omega[~self.converged]

    def jumps(
        self,
        quantities: str | Sequence[str] = ("dte_rms", "contact_loss_fraction", "force_max"),
        rtol: float = 0.1,
        ratio: float = 3.0,
    ) -> list[Jump]:
        """Jumps of each sweep direction, in sweep order.

        A step is a jump when any of ``quantities`` jumps by the test of
        :func:`~nlgrd.nonlinear.results.jumps.find_jumps` (a jump onto or off a contact-loss
        branch shows most clearly in the contact-loss fraction), when the solver had to
        leave the folded branch (``branch_switch``), or where the sweep enters or leaves
        a range with no stable response (``no_stable``; its values are NaN), or changes
        period (``period``). The reported values are those of the first quantity.
        """
        qs = (quantities,) if isinstance(quantities, str) else tuple(quantities)
        return self.jumps_of({q: self.metrics[q] for q in qs}, rtol, ratio)

    def jumps_of(self, values: dict[str, NDArray], rtol: float = 0.1, ratio: float = 3.0) -> list[Jump]:
        """:meth:`jumps` of quantities given per point (``values``: name -> one value per
        point, in the order of the points; e.g. a link's outputs).

        Parameters
        ----------
        values : dict of str to ndarray
            The quantities; the reported values are those of the first.
        rtol, ratio : float
            As :func:`~nlgrd.nonlinear.results.jumps.find_jumps` [-].

        Returns
        -------
        list of Jump
        """
        out = []
        for d in dict.fromkeys(self.direction.tolist()):
            keep = self.direction == d
            part = self.select(d)
            steps: set[int] = set(np.nonzero(part.branch_switch[1:])[0].tolist())
            steps |= set(np.nonzero(np.diff(part.no_stable.astype(int)) != 0)[0].tolist())
            steps |= set(np.nonzero(np.diff(part.period) != 0)[0].tolist())
            for q in values:
                for j in find_jumps(part.omega, np.asarray(values[q])[keep], d, rtol, ratio):
                    steps.add(int(np.nonzero(part.omega == j.omega_from)[0][0]))
            v = np.asarray(next(iter(values.values())))[keep]
            for i in sorted(steps):
                if i + 1 < part.omega.size:
                    out.append(
                        Jump(d, float(part.omega[i]), float(part.omega[i + 1]), float(v[i]), float(v[i + 1]))
                    )
        return out

    def to_frame(self) -> pd.DataFrame:
        """Tidy table, one row per point, units in the column names.

        Says only what is known: a point that did not converge has NA in every numeric
        and flag column (``stable`` and ``back_contact`` included); ``stable`` is NA where
        stability was not computed, never False.
        """
        ok = np.asarray(self.converged, dtype=bool)

        def num(v):
            return np.where(ok, np.asarray(v, dtype=float), np.nan)

        def flag(v, known):
            out = pd.array(np.asarray(v, dtype=bool), dtype="boolean")
            out[~(ok & known)] = pd.NA
            return out

        settled = np.asarray(self.verdict_converged, dtype=bool)
        verdict = np.where(~settled, "not converged", np.where(self.stable, "stable", "unstable"))
        torus = self.time_answered & (np.asarray(self.time_kind, dtype=object) == QUASI_PERIODIC)
        verdict = np.where(torus, "not computed", verdict)  # a torus's stability: never computed
        iterations = pd.array(np.asarray(self.iterations), dtype="Int64")
        iterations[~ok] = pd.NA
        data = {
            "base_frequency [Hz]": hz(self.omega),
            "direction": self.direction,
            "converged": ok,
            RESIDUAL_COLUMNS[self.residual_kind]: num(self.residual),
            "iterations": iterations,
            "stable": flag(self.stable, self.stability_known & settled & ~torus),
            "verdict": pd.array(verdict, dtype="string"),
            "floquet_max [-]": floquet_output(num(self.floquet_max)),
            "H": pd.array(np.where(ok, self.H, 0), dtype="Int64"),
            "harmonic_error [-]": _significant(num(self.harmonic_error), 3),
            "response": pd.array(response_kind(self), dtype="string"),
            "period": pd.array(np.asarray(self.period, dtype=int), dtype="Int64"),
            "subharmonic_amp [um]": um(num(self.subharmonic_amplitude)),
            "secondary_frequency [Hz]": _significant(hz(num(self.secondary_frequency)), 8),
            "instability": pd.array(instability_kind(self.dominant_multiplier, self.stable), dtype="string"),
            "dominant_multiplier_re [-]": floquet_output(num(self.dominant_multiplier.real), signed=True),
            "dominant_multiplier_im [-]": floquet_output(num(self.dominant_multiplier.imag), signed=True),
        }
        timed = self.time_answered
        data["verdict"][~ok | ~self.stability_known] = pd.NA
        data["H"][~ok] = pd.NA
        data["response"][~ok] = pd.NA
        data["period"][~ok | self.no_stable | ~settled] = pd.NA
        data["subharmonic_amp [um]"][self.no_stable | ~settled] = np.nan
        data["instability"][~ok | ~self.stability_known] = pd.NA
        ok = ok & ((~self.no_stable & settled) | timed)  # the metrics: of the response only
        for name in METRIC_NAMES:
            col, scale = _UNITS[name]
            v = self.metrics[name]
            data[col] = flag(v, ok) if scale is None else num(v) * scale
        if timed.any() and self.uncertainty is not None:  # the time answers' sampling uncertainty
            for name, u in self.uncertainty.items():
                col, scale = _UNITS[name]
                if scale is not None:
                    data[uncertainty_column(col)] = np.where(timed, np.asarray(u, float) * scale, np.nan)
        for k in range(self.amplitudes.shape[1]):
            data[f"dte_amp_{k} [um]"] = um(num(self.amplitudes[:, k]))
        return pd.DataFrame(data)

    def plot(self, quantity: str = "dte_rms", ax=None):
        """Plot ``quantity`` against mesh frequency (:func:`nlgrd.plotting.nonlinear.plot_sweep`)."""
        from nlgrd.plotting.nonlinear import plot_sweep

        check_quantity(quantity)

        return plot_sweep(self, quantity=quantity, ax=ax)


def assemble_result(
    omegas: Sequence[float],
    directions: Sequence[str],
    harmonics: Sequence[NDArray],
    converged: Sequence[bool],
    residual: Sequence[float],
    iterations: Sequence[int],
    multipliers_max: Sequence[float],
    metrics: Sequence[MeshMetrics],
    source: str,
    branch_switch: Sequence[bool] | None = None,
    no_stable: Sequence[bool] | None = None,
    dominant: Sequence[complex] | None = None,
    residual_kind: str = "relative residual",
) -> SweepResult:
    """Pack per-point lists into a :class:`SweepResult`.

    Parameters
    ----------
    omegas : sequence of float
        Frequencies [rad/s], in sweep order.
    directions : sequence of str
        Direction per point.
    harmonics : sequence of ndarray
        Real harmonics per point, shape (n_nl, 2H+1) [m].
    converged : sequence of bool
        Solver (or steady-state) success per point.
    residual : sequence of float
        Residual per point, of ``residual_kind`` [-].
    iterations : sequence of int
        Iterations (or periods) per point.
    multipliers_max : sequence of float
        Largest Floquet multiplier modulus per point (NaN: not computed) [-].
    metrics : sequence of MeshMetrics
        Output metrics per point.
    source : str
        What produced the points.
    branch_switch, no_stable : sequence of bool, optional
        Per-point flags (see :class:`SweepResult`).
    dominant : sequence of complex, optional
        Dominant multiplier per point [-].
    residual_kind : str
        A key of :data:`RESIDUAL_COLUMNS`.

    Returns
    -------
    SweepResult
        ``stable`` where converged and max |μ| < 1 + :data:`STABLE_RTOL`.
    """
    fm = np.asarray(multipliers_max, dtype=float)
    conv = np.asarray(converged, dtype=bool)
    with np.errstate(invalid="ignore"):
        stable = conv & np.isfinite(fm) & (fm < 1 + STABLE_RTOL)
    H = max((m.dte_amplitudes.size for m in metrics), default=1) - 1
    amps = np.array([np.resize(m.dte_amplitudes, H + 1) for m in metrics]).reshape(len(metrics), H + 1)
    mdict = {name: np.array([m.as_tuple()[i] for m in metrics]) for i, name in enumerate(METRIC_NAMES)}
    mdict["back_contact"] = mdict["back_contact"].astype(bool)
    return SweepResult(
        np.asarray(omegas, dtype=float),
        np.asarray(directions, dtype=str),
        np.asarray(harmonics, dtype=float),
        conv,
        np.asarray(residual, dtype=float),
        np.asarray(iterations, dtype=int),
        stable,
        fm,
        mdict,
        amps,
        source,
        None if branch_switch is None else np.asarray(branch_switch, dtype=bool),
        None,
        None,
        None if no_stable is None else np.asarray(no_stable, dtype=bool),
        None if dominant is None else np.asarray(dominant, dtype=complex),
        residual_kind,
    )


def without_rows(branch: SweepResult, drop: NDArray) -> SweepResult:
    """``branch`` with the rows ``drop`` marked off it: not converged, neither stable nor
    without a stable response, and with no verdict pending (a cut followed branch:
    :func:`~nlgrd.nonlinear.tracing.coexisting.cut_at_first_hop`, and its stand-in on a
    model without an exact flow).

    Parameters
    ----------
    branch : SweepResult
        The rows.
    drop : ndarray of bool
        Per row: whether it is off the branch.

    Returns
    -------
    SweepResult
        ``branch`` itself when nothing is dropped.
    """
    drop = np.asarray(drop, dtype=bool)
    if not drop.any():
        return branch
    keep = ~drop
    return replace(
        branch,
        converged=branch.converged & keep,
        stable=branch.stable & keep,
        no_stable=branch.no_stable & keep,
        verdict_converged=branch.verdict_converged | drop,
    )


@dataclass(frozen=True)
class ContinuationResult:
    """A solution curve in (ω, z) with stability per point.

    Attributes
    ----------
    curve : SweepResult
        Per-point data in curve order (``direction`` = "curve"); ``stable`` and
        ``floquet_max`` from the Floquet multipliers.
    arclength : ndarray
        Scaled arc length s at each point [-].
    turning_indices : ndarray of int
        Indices i where dω/ds changes sign between points i and i+1.
    turning_omegas : ndarray
        Frequencies of the turning points [rad/s] (parabolic interpolation of ω(s)).
    complete : bool
        The curve left the frequency range past ``omega_end`` (False: the step size
        collapsed, ``max_steps`` was reached, or the curve turned back and left the
        range at ``omega_start``).
    """

    curve: SweepResult
    arclength: NDArray
    turning_indices: NDArray
    turning_omegas: NDArray
    complete: bool

    @property
    def omega(self) -> NDArray:
        """Frequencies along the curve [rad/s]."""
        return self.curve.omega

    @property
    def stable(self) -> NDArray:
        """Stability per point."""
        return self.curve.stable

    def turning_points(self) -> NDArray:
        """Frequencies of the turning points [rad/s]."""
        return self.turning_omegas

    def to_frame(self):
        """Tidy table (see :meth:`SweepResult.to_frame`) with the arc length; an unstable
        orbit's ``response`` says so ("unstable periodic"): it is on the curve, not the response."""
        df = self.curve.to_frame()
        df.insert(1, "arclength [-]", self.arclength)
        unstable = df["stable"].eq(False).fillna(False).to_numpy(dtype=bool)
        df.loc[unstable, "response"] = "unstable " + df.loc[unstable, "response"]
        return df

    def plot(self, quantity: str = "dte_rms", ax=None):
        """Curve with stable parts solid and unstable parts dashed."""
        from nlgrd.plotting.nonlinear import plot_continuation

        return plot_continuation(self, quantity=quantity, ax=ax)


def dominant_multiplier(mu: NDArray) -> tuple[float, complex]:
    """max |μ| and the multiplier that has it (the one with Im >= 0 of a pair).

    Multipliers within ``STABLE_RTOL`` of the largest modulus count as tied (the
    monodromy's rounding moves a modulus near 1 by ~1e-9: an exact neutral μ = 1 of a
    rigid-body mode and a pair of an undamped mode at 1 - 2e-9 swapped places between
    OpenBLAS kernels with a 1e-12 window); of the tied ones the one with the largest
    imaginary part is reported, the same on every machine.

    Parameters
    ----------
    mu : ndarray of complex
        Floquet multipliers [-].

    Returns
    -------
    tuple of (float, complex)
        The largest modulus and its multiplier.
    """
    mu = np.asarray(mu, dtype=complex)
    top = float(np.max(np.abs(mu)))
    cand = mu[np.abs(mu) >= top * (1 - STABLE_RTOL)]
    return top, complex(cand[np.argmax(cand.imag)])
