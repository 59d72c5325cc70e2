"""A time-domain answer at a speed where no periodic orbit is stable: the steady
statistics of a long integration, each with its sampling uncertainty, and whether the
motion is chaotic.

The reduced model's equations are integrated (:class:`nlgrd.timedomain.links.LinkIntegrator`:
HHT-α on the precomputed period map) from a start near the unstable orbit, period by
period. From the per-period values of every output:

- **Transient cut** by MSER-5 (:func:`nlgrd.timedomain.record_statistics.mser5`); the
  largest cut over the outputs is taken. A minimum on the bound (half the record) says
  the record is too short.
- **Statistics** over the kept periods: the mean DTE, the RMS of its alternating part,
  the contact fractions (means of per-sample values) and the extremes (largest mesh
  force, DTE peak-to-peak, largest clearance force and displacement) over the record;
  every linear bearing's outputs as a harmonic-balance row has them (its node's radial
  displacement and force, -(K_b q + C_b q'), recorded step by step:
  :mod:`nlgrd.timedomain.bearing_record`): the largest, the RMS of the alternating
  part, the magnitude of the mean, and the base harmonic of the synchronous average.
- **Sampling uncertainty** (standard uncertainty, k = 1): a mean's by overlapping batch
  means as long as the series' correlation window (Sokal's automatic windowing), raised
  by the t factor of their degrees of freedom
  (:func:`nlgrd.timedomain.record_statistics.sample_mean`); the RMS by the delta method
  (ms - m² linearised about the record's mean). An extreme's from 20 batch extremes as
  Gumbel variates (:func:`~nlgrd.timedomain.record_statistics.record_max`). An extreme
  only grows with the record: a 4x longer one is on average β ln 4 ≈ 1.1 s higher (for
  a bounded attractor less).
- **Classification**: "chaotic" when the largest Lyapunov exponent, from a twin
  trajectory started d₀ away and renormalised every period (Benettin et al. 1980,
  Meccanica 15:9; the separation measured on (q, q'/ω) without its rigid-body part, a
  free mode's drift being neutral), is positive beyond 3 of its standard uncertainties
  and above 1e-3 per period (e-folding in under 1000 periods); else "time domain" (a
  torus, whose exponent is 0, or a periodic attractor no harmonic balance was run for).
  A clear two-frequency spectrum is thus "time domain".

The record grows by doubling from ``periods`` while the transient cut lies beyond
:data:`NEAR_BOUND` (40 %) of the record, a statistic drifts between the record's halves
(beyond 3 uncertainties: its uncertainty is then that drift, or Aitken's tail of its
thirds), a relative uncertainty of an RMS exceeds ``rtol`` (absolute for fractions) or
the exponent is above the floor and within :data:`LYAPUNOV_BAND` (2) standard
uncertainties of the chaotic threshold, up to ``max_periods``; where at the cap the cut
is still near its bound or the exponent in that band, once more to 2 ``max_periods``.
Such a decision hinges on the record's noise: another BLAS kernel rounds the reduced
model in its last bits, a chaotic record then follows another trajectory of the same
attractor, and its statistics differ by their sampling error (the exponent's by about
√2 σ); the longer record moves the exponent away from the threshold (its σ falls as
1/√n) and a transient that ended inside the cap's record into the longer record's first
half (benchmarks/bench_time_answer_kernels.py, benchmarks/README.md). ``settled`` says
whether the targets were met, ``transient_over`` whether the cut lies in the first half.
The cost is 2 x the periods integrated (the twin): 2-4 ms a period on Kubo's 84-DOF and
K&B's 60-DOF models at 256 steps (docs/verification.md, "Time-domain answers"), and the
bearing record on the first trajectory (about 1 ms a period for K&B's four bearings);
at most 2 ``max_periods`` periods. A bearing's statistics do not lengthen the record;
their drift raises their uncertainty.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import analyse
from nlgrd.nonlinear.models.link_model import LinkModel
from nlgrd.nonlinear.results.response_kinds import CHAOTIC, TIME_DOMAIN
from nlgrd.rotor.rigid_body import rigid_body_modes
from nlgrd.threads import single_blas_thread
from nlgrd.timedomain.bearing_record import BearingRecord
from nlgrd.timedomain.links import LinkIntegrator, start_from_harmonics
from nlgrd.timedomain.record_statistics import BATCHES, Estimate, mser5, record_max, sample_mean

#: Chaotic: the Lyapunov exponent per base period above this and above
#: :data:`LYAPUNOV_SIGMAS` standard uncertainties.
LYAPUNOV_FLOOR = 1e-3
LYAPUNOV_SIGMAS = 3.0
#: Undecided: the exponent within this many standard uncertainties of the threshold
#: (another record's exponent differs by about √2 of them) [-].
LYAPUNOV_BAND = 2.0
#: A transient cut beyond this fraction of the record is near MSER's bound (one half) [-].
NEAR_BOUND = 0.4
#: Fewest periods of a record [-].
MIN_PERIODS = 4 * BATCHES
#: Periods at the record's end a :class:`TimeAnswer` keeps (``tail``) [-].
TAIL = 4


@dataclass(frozen=True)
class TimeAnswer:
    """The steady statistics of a long integration at one base frequency.

    Attributes
    ----------
    omega : float
        Base frequency [rad/s].
    kind : str
        "chaotic" or "time domain" (:mod:`nlgrd.nonlinear.results.response_kinds`).
    links : dict of str to Estimate
        ``<link>.<quantity>`` with the units of the links' own outputs (the columns of a
        link sweep): a mesh's ``dte_mean [m]``, ``dte_rms [m]``, ``dte_p2p [m]``,
        ``force_max [N]``, ``force_min [N]``, ``dslr [-]``,
        ``contact_loss_fraction [-]``, ``back_contact``; a clearance's
        ``contact_fraction [-]``, ``force_max [N]``, ``displacement_max [m]``.
    mesh : dict of str to Estimate
        The first mesh's :data:`~nlgrd.nonlinear.results.metrics.METRIC_NAMES` (SI; empty without a mesh).
    lyapunov : Estimate
        Largest Lyapunov exponent [1/s].
    transient : int
        Periods cut as transient [-].
    periods : int
        Periods integrated (each twice: the twin trajectory) [-].
    settled : bool
        The transient cut and the uncertainty targets were met within the record.
    harmonics : ndarray (d, 2H+1)
        Harmonics of the synchronous average of the link coordinates over the kept
        periods (the part of the motion locked to the base frequency) [m].
    seconds : float
        Wall time [s].
    state : tuple of ndarray
        (q, q', q'') at the end, to continue from.
    transient_over : bool
        Every MSER-5 cut lies inside the record's first half: the transient ended within
        it (False: it outlasts the record; the statistics are not the steady ones).
    bearings : dict of str to Estimate
        Every linear bearing's ``<bearing>.<quantity>``: the
        :data:`~nlgrd.nonlinear.results.bearing_loads.BEARING_OUTPUTS` of a link sweep's
        row (radial magnitudes over the record: the largest displacement and force, the
        RMS of their alternating parts, the mean force's magnitude) and
        ``displacement_mean [m]`` and ``force_amplitude [N]`` (the base harmonic of the
        synchronous average, the larger of y and z).
    tail : ndarray (p, d, steps)
        The link coordinates over the record's last :data:`TAIL` periods (whether the
        motion settled on a periodic orbit: :mod:`nlgrd.timedomain.settled_orbits`) [m].
    """

    omega: float
    kind: str
    links: dict
    mesh: dict
    lyapunov: Estimate
    transient: int
    periods: int
    settled: bool
    harmonics: NDArray
    seconds: float
    state: tuple = field(repr=False, default=())
    transient_over: bool = True
    bearings: dict = field(default_factory=dict)
    tail: NDArray = field(repr=False, default_factory=lambda: np.empty((0, 0, 0)))


def _rms(mean: NDArray, msq: NDArray) -> Estimate:
    """RMS of the alternating part from per-period means and mean squares (delta method)."""
    m = sample_mean(mean).value
    ms = float(np.mean(msq))
    rms = math.sqrt(max(ms - m * m, 0.0))
    u = sample_mean(np.asarray(msq) - 2 * m * np.asarray(mean)).uncertainty
    return Estimate(rms, u / (2 * rms) if rms > 0 else 0.0)


class _Recorder:
    """Per-period values of every link's outputs (the raw material of the statistics)."""

    def __init__(self, integ: LinkIntegrator):
        self.integ = integ
        self.bearings = BearingRecord(integ)
        self.rows: list[dict[str, float]] = []
        self.y_sums: list[NDArray] = []
        th = 2 * np.pi * np.arange(integ.ns) / integ.ns
        self._c, self._s = 2 * np.cos(th) / integ.ns, 2 * np.sin(th) / integ.ns

    def period(self, s: NDArray) -> NDArray:
        """One period of the integration from ``s``, recorded; the state at its end."""
        N = self.integ.N
        P = self.integ.P
        vy, ay = P.T @ s[N : 2 * N], P.T @ s[2 * N : 3 * N]
        y, q, s_new = self.bearings.period(s)
        self.add(y, vy, ay)
        if q.size:
            self._bearings(q, self.bearings.forces(q, self.bearings.velocities(q, s)))
        return s_new

    def _bearings(self, q: NDArray, f: NDArray) -> None:
        """Each bearing's per-period values: the means, mean squares and maxima of its
        node's radial displacement and force, and the force's base harmonic."""
        row = self.rows[-1]
        for j, name in enumerate(self.bearings.names):
            qy, qz, fy, fz = q[2 * j], q[2 * j + 1], f[2 * j], f[2 * j + 1]
            row.update(
                {
                    f"{name}.qy": float(np.mean(qy)),
                    f"{name}.qz": float(np.mean(qz)),
                    f"{name}.qsq": float(np.mean(qy * qy + qz * qz)),
                    f"{name}.qmax": float(np.max(np.hypot(qy, qz))),
                    f"{name}.fy": float(np.mean(fy)),
                    f"{name}.fz": float(np.mean(fz)),
                    f"{name}.fsq": float(np.mean(fy * fy + fz * fz)),
                    f"{name}.fmax": float(np.max(np.hypot(fy, fz))),
                    f"{name}.fya": float(fy @ self._c),
                    f"{name}.fyb": float(fy @ self._s),
                    f"{name}.fza": float(fz @ self._c),
                    f"{name}.fzb": float(fz @ self._s),
                }
            )

    def add(self, y: NDArray, v0: NDArray, a0: NDArray) -> None:
        integ, st = self.integ, self.integ.step
        row: dict[str, float] = {}
        for link, sl in zip(integ.model.links, integ.model.receptance.slices, strict=True):
            yl = y[sl]
            if hasattr(link, "mesh"):
                row.update(self._mesh(link, yl[0], _link_velocity(yl[0], v0[sl][0], a0[sl][0], st)))
            else:
                law = link.law((0, 1))
                r = np.hypot(yl[0], yl[1])
                f = law.force_at(yl)
                row[f"{link.name}.contact"] = float(np.mean(r > link.clearance))
                row[f"{link.name}.fmax"] = float(np.max(np.hypot(f[0], f[1])))
                row[f"{link.name}.rmax"] = float(np.max(r))
        self.rows.append(row)
        self.y_sums.append(y.copy())

    def _mesh(self, link, delta: NDArray, ddot: NDArray) -> dict[str, float]:
        mesh, w = link.mesh, self.integ.omega
        e, de = mesh.lste_samples(delta.size)
        force = mesh.elastic_samples(delta) + mesh.damping * (ddot - w * de)
        x = delta - e
        n = link.name
        return {
            f"{n}.mean": float(np.mean(delta)),
            f"{n}.msq": float(np.mean(delta * delta)),
            f"{n}.dmax": float(np.max(delta)),
            f"{n}.dmin": float(np.min(delta)),
            f"{n}.fmax": float(np.max(force)),
            f"{n}.fmin": float(np.min(force)),
            f"{n}.fmean": float(np.mean(force)),
            f"{n}.loss": float(np.mean(np.abs(x) <= mesh.half_backlash)),
            f"{n}.back": float(np.any(x < -mesh.half_backlash)),
        }

    def series(self, key: str, cut: int = 0, stop: int | None = None) -> NDArray:
        return np.array([r[key] for r in self.rows[cut:stop]])

    def cut_series(self) -> list[NDArray]:
        """The series MSER-5 is run on: each mesh's per-period mean square about the record's
        mean and largest force, each clearance's largest displacement."""
        out = []
        for link in self.integ.model.links:
            n = link.name
            if hasattr(link, "mesh"):
                m = self.series(f"{n}.mean")
                out += [self.series(f"{n}.msq") - 2 * np.mean(m) * m, self.series(f"{n}.fmax")]
            else:
                out.append(self.series(f"{n}.rmax"))
        return out


def _link_velocity(y: NDArray, v0: float, a0: float, st) -> NDArray:
    """ẏ at the steps of a period from y and the start's ẏ, ÿ: the Newmark update of the
    HHT-α step (v' = b1 Δq + b2 v + b3 a, a' = a1 Δq - a2 v - a3 a) projected on the link
    direction, exact for y = Pᵀ q since the update is linear."""
    v = np.empty(y.size)
    v[0], a = v0, a0
    dq = np.diff(y)
    for j in range(y.size - 1):
        v[j + 1], a = st.b1 * dq[j] + st.b2 * v[j] + st.b3 * a, st.a1 * dq[j] - st.a2 * v[j] - st.a3 * a
    return v


def _free_part(ds: NDArray, R: NDArray, MR: NDArray, N: int) -> NDArray:
    """An extended state difference without its rigid-body part (q, q', q'' each less
    R Rᵀ M of it): a free mode's drift is neutral, not a divergence of trajectories."""
    out = ds.copy()
    for k in range(3):
        part = out[k * N : (k + 1) * N]
        part -= R @ (MR.T @ part)
    return out


def _wnorm(ds: NDArray, N: int, omega: float) -> float:
    """‖(Δq, Δq'/ω)‖ of an extended state difference [m]."""
    return math.sqrt(float(ds[:N] @ ds[:N]) + float(ds[N : 2 * N] @ ds[N : 2 * N]) / omega**2)


#: A drift between the record's halves below this relative size is rounding, not a trend;
#: no uncertainty is stated below it.
DRIFT_FLOOR = 1e-9


def _statistics(rec: _Recorder, cut: int) -> tuple[dict, dict, dict, bool]:
    """Every link's statistics over the periods after ``cut``, the first mesh's metrics,
    the linear bearings' outputs, and whether a link's drifts: the statistic over the
    record's first half and over its second differ by more than 3 of their combined
    uncertainties (and :data:`DRIFT_FLOOR`
    relative), a two-part stationarity test in the manner of Geweke 1992 (Bayesian
    Statistics 4:169) that catches the slow end of a transient batch means miss. A
    drifting statistic's uncertainty is raised to that difference, every one to at least
    :data:`DRIFT_FLOOR` of its value. A bearing's drift raises its uncertainty alike but
    does not lengthen the record (the links' statistics decide it, as before bearings
    were recorded)."""
    n = len(rec.rows) - cut
    links, mesh, bearings = _statistics_of(rec, cut, None)
    halves = _statistics_of(rec, cut, cut + n // 2), _statistics_of(rec, cut + n // 2, None)
    thirds = [_statistics_of(rec, cut + j * n // 3, cut + (j + 1) * n // 3) for j in range(3)]
    drift = False
    for w, full in enumerate((links, mesh, bearings)):
        a, b = halves[0][w], halves[1][w]
        for k, e in full.items():
            gap = abs(a[k].value - b[k].value)
            floor = DRIFT_FLOOR * abs(e.value)
            drifts = gap > 3 * math.hypot(a[k].uncertainty, b[k].uncertainty) and gap > floor
            drift = drift or (drifts and w < 2)  # the links' drift extends the record
            full[k] = Estimate(
                e.value,
                max(e.uncertainty, _tail(gap, [t[w][k].value for t in thirds]) if drifts else 0.0, floor),
            )
    return links, mesh, bearings, drift


def _tail(gap: float, thirds: list[float]) -> float:
    """What a drifting statistic may still move: the gap between the record's halves, or
    more, the geometric tail d₂ r/(1 - r) of its thirds' steps d₁, d₂ (r = d₂/d₁: a
    transient decaying exponentially, Aitken's extrapolation) when it decays that way."""
    d1, d2 = thirds[1] - thirds[0], thirds[2] - thirds[1]
    r = d2 / d1 if d1 != 0 else 0.0
    return max(gap, abs(d2) * r / (1 - r)) if 0 < r < 1 else gap


def _vector_mean(x: NDArray, y: NDArray) -> Estimate:
    """|(mean x, mean y)| of per-period means, its uncertainty that of the per-period
    values projected on the mean's direction (the magnitude linearised there)."""
    mx, my = sample_mean(x).value, sample_mean(y).value
    r = math.hypot(mx, my)
    if r == 0:
        return Estimate(0.0, math.hypot(sample_mean(x).uncertainty, sample_mean(y).uncertainty))
    return Estimate(r, sample_mean((mx * x + my * y) / r).uncertainty)


def _vector_rms(x: NDArray, y: NDArray, msq: NDArray) -> Estimate:
    """RMS of the alternating part of a plane vector from its per-period means and mean
    squares of the magnitude (the delta method of :func:`_rms` on both components)."""
    mx, my = sample_mean(x).value, sample_mean(y).value
    rms = math.sqrt(max(float(np.mean(msq)) - mx * mx - my * my, 0.0))
    u = sample_mean(np.asarray(msq) - 2 * mx * np.asarray(x) - 2 * my * np.asarray(y)).uncertainty
    return Estimate(rms, u / (2 * rms) if rms > 0 else 0.0)


def _bearing_statistics(rec: _Recorder, cut: int, stop: int | None) -> dict[str, Estimate]:
    """Every linear bearing's outputs over the periods ``cut:stop``."""
    out: dict[str, Estimate] = {}
    if not rec.bearings.dofs.size:
        return out
    for name in rec.bearings.names:

        def s(key, name=name):
            return rec.series(f"{name}.{key}", cut, stop)

        amps = [_vector_mean(s(f"f{c}a"), -s(f"f{c}b")) for c in "yz"]  # |a - i b| of X_1
        out.update(
            {
                f"{name}.displacement_max [m]": record_max(s("qmax")),
                f"{name}.displacement_rms [m]": _vector_rms(s("qy"), s("qz"), s("qsq")),
                f"{name}.force_mean [N]": _vector_mean(s("fy"), s("fz")),
                f"{name}.force_rms [N]": _vector_rms(s("fy"), s("fz"), s("fsq")),
                f"{name}.force_max [N]": record_max(s("fmax")),
                f"{name}.displacement_mean [m]": _vector_mean(s("qy"), s("qz")),
                f"{name}.force_amplitude [N]": max(amps, key=lambda e: e.value),
            }
        )
    return out


def _statistics_of(rec: _Recorder, cut: int, stop: int | None) -> tuple[dict, dict, dict]:
    """Every link's statistics over the periods ``cut:stop``, the first mesh's metrics and
    the linear bearings' outputs."""
    links: dict[str, Estimate] = {}
    mesh: dict[str, Estimate] = {}
    for link in rec.integ.model.links:
        n = link.name

        def s(key, n=n):
            return rec.series(f"{n}.{key}", cut, stop)

        if hasattr(link, "mesh"):
            hi, lo = record_max(s("dmax")), record_max(-s("dmin"))
            fmax, fmin = record_max(s("fmax")), record_max(-s("fmin"))
            W0 = float(link.mesh.static_load) if link.mesh.static_load else sample_mean(s("fmean")).value
            m = {
                "dte_mean": sample_mean(s("mean")),
                "dte_rms": _rms(s("mean"), s("msq")),
                "dte_p2p": Estimate(hi.value + lo.value, math.hypot(hi.uncertainty, lo.uncertainty)),
                "force_max": fmax,
                "force_min": Estimate(-fmin.value, fmin.uncertainty),
                "dslr": Estimate(fmax.value / W0, fmax.uncertainty / abs(W0)),
                "contact_loss_fraction": sample_mean(s("loss")),
                "back_contact": Estimate(float(np.any(s("back") > 0)), 0.0),
            }
            if not mesh:
                mesh = m
            for k, unit in (
                ("dte_mean", " [m]"),
                ("dte_rms", " [m]"),
                ("dte_p2p", " [m]"),
                ("force_max", " [N]"),
                ("force_min", " [N]"),
                ("dslr", " [-]"),
                ("contact_loss_fraction", " [-]"),
                ("back_contact", ""),
            ):
                links[f"{n}.{k}{unit}"] = m[k]
        else:
            links[f"{n}.contact_fraction [-]"] = sample_mean(s("contact"))
            links[f"{n}.force_max [N]"] = record_max(s("fmax"))
            links[f"{n}.displacement_max [m]"] = record_max(s("rmax"))
    return links, mesh, _bearing_statistics(rec, cut, stop)


def _targets_met(links: dict, rtol: float) -> bool:
    """Every RMS within ``rtol`` relative and every fraction within ``rtol`` absolute."""
    for key, e in links.items():
        if "dte_rms" in key and e.uncertainty > rtol * abs(e.value):
            return False
        if "fraction" in key and e.uncertainty > rtol:
            return False
    return True


class _Run:
    """An integration and its Lyapunov twin (started d₀ = 1e-7 of the state away in a
    seeded random direction without rigid-body part), recorded period by period."""

    def __init__(self, model: LinkModel, omega: float, state0, steps: int, alpha: float):
        self.integ = integ = LinkIntegrator(model, omega, steps_per_period=steps, alpha=alpha)
        self.N, self.omega = N, omega = integ.N, float(omega)
        self.s = s = integ.start(state0)
        rec_ = model.receptance
        self.R = rigid_body_modes(rec_.model.K + rec_.K_link, rec_.model.M)
        self.MR = rec_.model.M @ self.R
        self.d0 = 1e-7 * max(_wnorm(s, N, omega), 1e-12)
        rng = np.random.default_rng(0)
        direction = np.zeros_like(s)
        direction[: 2 * N] = rng.standard_normal(2 * N) * np.repeat([1.0, omega], N)
        self.direction = direction = _free_part(direction, self.R, self.MR, N)
        self.s2 = s + self.d0 * direction / _wnorm(direction, N, omega)
        self.rec, self.logs = _Recorder(integ), []

    def extend(self, target: int, progress: Callable[[int, int], None] | None = None) -> None:
        """Integrate (both trajectories) until ``target`` periods are recorded."""
        N, omega, d0 = self.N, self.omega, self.d0
        while len(self.rec.rows) < target:
            s_new = self.rec.period(self.s)
            _, s2_new = self.integ.period(self.s2)
            ds = _free_part(s2_new - s_new, self.R, self.MR, N)
            gap = _wnorm(ds, N, omega)
            self.logs.append(math.log(max(gap, 1e-300) / d0))
            self.s2 = s_new + ds * (d0 / gap) if gap > 0 else s_new + d0 * self.direction
            self.s = s_new
            if progress is not None:
                progress(len(self.rec.rows), target)


def _judge(rec: _Recorder, logs: list):
    """The record's transient cut, whether every cut lies in its first half, its
    statistics (:func:`_statistics`), whether a link's drifts, and the Lyapunov exponent
    per period."""
    cuts = [mser5(x) for x in rec.cut_series()]
    cut = max(c for c, _ in cuts)
    links, mesh, bearings, drift = _statistics(rec, cut)
    lam = sample_mean(np.array(logs[max(cut, 10) :]))
    return cut, all(ok for _, ok in cuts), links, mesh, bearings, drift, lam


@dataclass(frozen=True)
class _Verdict:
    """What a record says (:func:`_settle`)."""

    cut: int
    cuts_ok: bool
    links: dict
    mesh: dict
    bearings: dict
    lam: Estimate
    settled: bool
    kind: str


def _settle(run, periods: int, max_periods: int, rtol: float, progress=None) -> _Verdict:
    """Extend ``run`` (a :class:`_Run`: ``rec``, ``logs``, ``extend``) from ``periods`` by
    doubling up to ``max_periods`` until its targets are met, and once more, to
    2 ``max_periods``, where a decision would hinge on the record's noise (the transient
    cut beyond :data:`NEAR_BOUND` of it, the exponent in the band of :func:`_undecided`);
    its verdict."""
    target, cap = periods, max_periods
    while True:
        run.extend(target, progress)
        cut, cuts_ok, links, mesh, bearings, drift, lam = _judge(run.rec, run.logs)
        near = cut > NEAR_BOUND * target or not cuts_ok
        undecided = _undecided(lam)
        settled = not near and _targets_met(links, rtol) and not (undecided or drift)
        if settled:
            break
        if target >= cap:
            if cap > max_periods or not (near or undecided):
                break
            cap = 2 * max_periods  # once: a threshold decision on rounding-level noise
        target = min(2 * target, cap)
    chaotic = lam.value > max(LYAPUNOV_SIGMAS * lam.uncertainty, LYAPUNOV_FLOOR)
    kind = CHAOTIC if chaotic else TIME_DOMAIN
    return _Verdict(cut, cuts_ok, links, mesh, bearings, lam, bool(settled), kind)


def _undecided(lam: Estimate) -> bool:
    """The exponent above the floor and within :data:`LYAPUNOV_BAND` standard
    uncertainties of the chaotic threshold: another realisation of the record (another
    BLAS kernel's rounding) may fall either side."""
    if lam.value <= LYAPUNOV_FLOOR:
        return False
    return abs(lam.value - LYAPUNOV_SIGMAS * lam.uncertainty) <= LYAPUNOV_BAND * lam.uncertainty


#: HHT-α steps per base period of a time answer when the forcing needs no more [-].
STEPS = 256


def answer_steps(model: LinkModel) -> int:
    """Steps per base period of a time answer: :data:`STEPS`, or the next power of two above
    twice the highest base harmonic of any link's excitation (the forcing is sampled at the
    steps, so it must hold more than 2H samples: a two-stage train on the base 5 Ω carries
    150 base harmonics of its LSTE and needs 512) [-].

    Parameters
    ----------
    model : LinkModel
        The model; its links' ``excitation_harmonics`` (0 for a link without one).

    Returns
    -------
    int
    """
    top = max([30] + [int(getattr(lk, "excitation_harmonics", 0)) for lk in model.links])
    return max(STEPS, 1 << (2 * top).bit_length())


@single_blas_thread
def time_answer(
    model: LinkModel,
    omega: float,
    *,
    harmonics: NDArray | None = None,
    state0: tuple | None = None,
    periods: int = 512,
    max_periods: int = 4096,
    steps_per_period: int | None = None,
    alpha: float = -0.05,
    rtol: float = 0.01,
    H: int = 15,
    perturbation: float = 1e-3,
    progress: Callable[[int, int], None] | None = None,
) -> TimeAnswer:
    """The steady statistics of the response at ``omega`` by time integration (module docstring).

    Parameters
    ----------
    model : LinkModel
        The model (a single mesh too: :func:`nlgrd.nonlinear.models.link_model.build_link_model`).
    omega : float
        Base frequency [rad/s].
    harmonics : ndarray (d, 2H'+1), optional
        Harmonics of the link coordinates of the nearest computed orbit (the unstable
        orbit at ``omega``, or a neighbour's) to start from; its velocities are scaled by
        1 + ``perturbation`` to leave an unstable orbit at once.
    state0 : tuple of ndarray, optional
        (q, q'[, q'']) to start from instead (a previous answer's ``state``).
    periods : int
        Periods of the first record [-].
    max_periods : int
        Cap on the doubling of the record; a decision near its threshold at the cap
        doubles it once more (module docstring) [-].
    steps_per_period : int, optional
        HHT-α steps per base period [-]; None: :func:`answer_steps` (256, or more where a
        link's excitation has more base harmonics than 256 steps sample).
    alpha : float
        HHT-α parameter [-].
    rtol : float
        Target standard uncertainty: relative for an RMS, absolute for a fraction [-].
    H : int
        Harmonics of the synchronous average kept [-].
    perturbation : float
        Relative velocity perturbation of a start from ``harmonics`` [-].
    progress : callable, optional
        ``progress(done, total)`` after every period.

    Returns
    -------
    TimeAnswer

    Raises
    ------
    ModelError
        ``periods`` or ``max_periods`` too small for the statistics.
    """
    if periods < MIN_PERIODS or max_periods < periods:
        raise ModelError("periods", f"needs {MIN_PERIODS} <= periods <= max_periods, got {periods}")
    t0 = time.perf_counter()
    steps = answer_steps(model) if steps_per_period is None else int(steps_per_period)
    if state0 is None and harmonics is not None:
        z = np.asarray(harmonics, dtype=float)
        q0, v0 = start_from_harmonics(model, omega, (z.shape[-1] - 1) // 2, z)
        state0 = (q0, (1 + perturbation) * v0)
    run = _Run(model, omega, state0, steps, alpha)
    v = _settle(run, int(periods), int(max_periods), rtol, progress)
    rec, s, N, cut, lam = run.rec, run.s, run.N, v.cut, v.lam
    T = 2 * np.pi / omega
    avg = np.mean(np.array(rec.y_sums[cut:]), axis=0)
    return TimeAnswer(
        float(omega),
        v.kind,
        v.links,
        v.mesh,
        Estimate(lam.value / T, lam.uncertainty / T),
        int(cut),
        len(rec.rows),
        v.settled,
        analyse(avg, H),
        time.perf_counter() - t0,
        (s[:N].copy(), s[N : 2 * N].copy(), s[2 * N : 3 * N].copy()),
        v.cuts_ok,
        v.bearings,
        np.array(rec.y_sums[-TAIL:]),
    )
