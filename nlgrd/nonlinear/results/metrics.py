"""Per-point outputs of a nonlinear mesh response: DTE statistics, mesh force, contact loss.

Definitions (model.md §4)
-------------------------
- DTE is the dynamic transmission error δ(t), the relative displacement of the two
  gears along the line of action [m] (not δ - e). Its mean, the RMS of its
  alternating part sqrt(Σ_k (a_k² + b_k²)/2), its peak-to-peak and the harmonic
  amplitudes |δ_k| are reported.
- Mesh force W(t) = k_h f(δ - e) + c_m (δ' - e') including the damping part [N];
  DSLR = max W / W_0 with W_0 the static load (the mean mesh force when not given).
- Contact loss: the fraction of the period with |δ - e| <= b (no elastic mesh force);
  back-side contact: δ - e < -b anywhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nlgrd.nonlinear.fourier.harmonics import (
    differentiate,
    n_harmonics,
    real_to_complex,
    sample,
)
from nlgrd.nonlinear.laws.force_laws import BacklashMesh
from nlgrd.units import column, um

#: What the CSV's ``response`` column says where a sweep found no stable periodic orbit.
NO_STABLE = "no stable mesh-periodic response"

#: Names of the scalar metrics, in the order of :meth:`MeshMetrics.as_tuple`.
METRIC_NAMES = (
    "dte_mean",
    "dte_rms",
    "dte_p2p",
    "force_max",
    "force_min",
    "dslr",
    "contact_loss_fraction",
    "back_contact",
)
#: SI unit of each metric (None: a flag): the typed description of what a sweep writes per
#: point; the tables convert and name them by :mod:`nlgrd.units`.
METRIC_UNITS = {
    "dte_mean": "m",
    "dte_rms": "m",
    "dte_p2p": "m",
    "force_max": "N",
    "force_min": "N",
    "dslr": "-",
    "contact_loss_fraction": "-",
    "back_contact": None,
}


@dataclass(frozen=True)
class MeshMetrics:
    """Scalar outputs of one periodic mesh response (SI units).

    Attributes
    ----------
    dte_mean, dte_rms, dte_p2p : float
        Mean, RMS of the alternating part and peak-to-peak of δ [m].
    dte_amplitudes : ndarray
        |δ_k|, k = 0..H [m] (k = 0: |mean|).
    force_max, force_min : float
        Extremes of W(t) over the period [N].
    dslr : float
        max W / W_0 [-].
    contact_loss_fraction : float
        Fraction of the period with |δ - e| <= b [-].
    back_contact : bool
        δ - e < -b somewhere.
    """

    dte_mean: float
    dte_rms: float
    dte_p2p: float
    dte_amplitudes: NDArray
    force_max: float
    force_min: float
    dslr: float
    contact_loss_fraction: float
    back_contact: bool

    def as_tuple(self) -> tuple:
        """Values in the order of :data:`METRIC_NAMES`."""
        return tuple(getattr(self, n) for n in METRIC_NAMES)

    @classmethod
    def nan(cls, H: int) -> MeshMetrics:
        """All-NaN metrics for a failed point."""
        nan = float("nan")
        return cls(nan, nan, nan, np.full(H + 1, nan), nan, nan, nan, nan, False)


@dataclass(frozen=True)
class TimeHistory:
    """One period of a periodic mesh response sampled in time (SI units).

    Attributes
    ----------
    t : ndarray
        Time from the start of the period [s].
    delta, delta_dot : ndarray
        δ [m] and δ' [m/s].
    lste, lste_dot : ndarray
        e [m] and e' [m/s].
    force : ndarray
        W = k_h f(δ - e) + c_m (δ' - e') [N].
    name : str
        The mesh's link name, the owner of its columns (a one-mesh model's: ``mesh0``).
    """

    t: NDArray
    delta: NDArray
    delta_dot: NDArray
    lste: NDArray
    lste_dot: NDArray
    force: NDArray
    name: str = "mesh0"

    @property
    def mesh_deflection(self) -> NDArray:
        """x = δ - e [m]."""
        return self.delta - self.lste

    def to_frame(self):
        """The period as a table: ``time [s]``, ``<mesh>.delta [um]`` (δ, as a link time
        response names the mesh coordinate), ``<mesh>.lste [um]`` (e),
        ``<mesh>.deflection [um]`` (δ - e) and ``<mesh>.force [N]`` (W).

        Returns
        -------
        pandas.DataFrame
        """
        import pandas as pd

        return pd.DataFrame(
            {
                "time [s]": self.t,
                column("delta", "um", self.name): um(self.delta),
                column("lste", "um", self.name): um(self.lste),
                column("deflection", "um", self.name): um(self.mesh_deflection),
                column("force", "N", self.name): self.force,
            }
        )

    def plot(self, ax=None, quantity: str = "delta"):
        """Plot one quantity over the period (see :func:`nlgrd.plotting.nonlinear.plot_time_history`)."""
        from nlgrd.plotting.nonlinear import plot_time_history

        return plot_time_history(self, quantity=quantity, ax=ax)


class LastPeriod:
    """What a time response tabulates and draws: its last simulated period.

    Attributes
    ----------
    history : TimeHistory
        The last simulated period (of the subclass's fields).
    """

    history: TimeHistory

    def to_frame(self):
        """The last period (:meth:`TimeHistory.to_frame`): ``time [s]``, the mesh's δ, e and
        δ - e [µm] and W [N] as ``<mesh>.delta``, ``.lste``, ``.deflection``, ``.force``.

        Returns
        -------
        pandas.DataFrame
        """
        return self.history.to_frame()

    def plot(self, quantity: str = "delta", ax=None):
        """The last period: "delta" (δ and e), "deflection" (δ - e) or "force" (W) against
        time (:func:`nlgrd.plotting.nonlinear.plot_time_history`).

        Parameters
        ----------
        quantity : str
            "delta", "deflection" or "force".
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure when None.

        Returns
        -------
        matplotlib.axes.Axes
        """
        return self.history.plot(ax=ax, quantity=quantity)


def time_history(harmonics, omega: float, mesh: BacklashMesh, n_samples: int = 1024) -> TimeHistory:
    """Reconstruct one period of δ, e and W from the harmonics of δ (1-D, real convention).

    Parameters
    ----------
    harmonics : array_like
        Real harmonics [δ_0, a_1, b_1, ..., a_H, b_H] of δ [m] (length 2H + 1, or (1, 2H+1)).
    omega : float
        Mesh frequency ω [rad/s] (θ = ω t).
    mesh : BacklashMesh
        The mesh: LSTE, k_h, b and c_m.
    n_samples : int
        Samples per period, more than twice the harmonics of δ and of the LSTE.

    Returns
    -------
    TimeHistory
        δ, δ', e, e' and W at t_j = 2πj / (N ω), j = 0..N-1.

    Raises
    ------
    ModelError
        When ``n_samples`` is too small for the harmonics.
    """
    z = np.asarray(harmonics, dtype=float).reshape(-1)
    theta = 2 * np.pi * np.arange(n_samples) / n_samples
    delta = sample(z, n_samples)
    ddot = omega * sample(differentiate(z), n_samples)
    e, de = mesh.lste_samples(n_samples)
    e, edot = e.copy(), omega * de
    force = mesh.elastic_samples(delta) + mesh.damping * (ddot - edot)
    return TimeHistory(theta / omega, delta, ddot, e, edot, force)


def _static_load(mesh: BacklashMesh, force: NDArray) -> float:
    return float(mesh.static_load) if mesh.static_load else float(np.mean(force))


def metrics_from_harmonics(harmonics, omega: float, mesh: BacklashMesh, n_samples: int = 2048) -> MeshMetrics:
    """Metrics of a harmonic-balance solution: moments and contact loss exact, extremes sampled.

    Mean, RMS and harmonic amplitudes come from the harmonics; the contact-loss
    fraction and back-side flag from the exact contact intervals; peak-to-peak and
    force extremes from ``n_samples`` samples per period (relative error of the extremes
    about (π k_max / n_samples)² / 2, below 1e-4 for k_max <= 9 at the default).

    Parameters
    ----------
    harmonics : array_like
        Real harmonics [δ_0, a_1, b_1, ..., a_H, b_H] of δ [m] (length 2H + 1, or (1, 2H+1)).
    omega : float
        Mesh frequency ω [rad/s] (θ = ω t).
    mesh : BacklashMesh
        The mesh: LSTE, k_h, b, c_m and W_0.
    n_samples : int
        Samples per period for the extremes, more than twice the harmonics of δ and of the
        LSTE.

    Returns
    -------
    MeshMetrics
        The metrics in SI units; all NaN when a harmonic is not finite.
    """
    z = np.asarray(harmonics, dtype=float).reshape(1, -1)
    return metrics_of_points(z, np.array([float(omega)]), mesh, n_samples)[0]


def metrics_of_points(
    harmonics, omegas, mesh: BacklashMesh, n_samples: int = 2048, intervals=None
) -> list[MeshMetrics]:
    """:func:`metrics_from_harmonics` of many points at once (one FFT of all of them).

    Parameters
    ----------
    harmonics : array_like (P, 2H+1)
        Real harmonics of δ per point [m].
    omegas : array_like (P,)
        Mesh frequency of each point [rad/s].
    mesh : BacklashMesh
        The mesh: LSTE, k_h, b, c_m and W_0.
    n_samples : int
        Samples per period for the extremes.
    intervals : sequence of ContactIntervals, optional
        The points' contact intervals (``mesh.intervals`` of each, which a sweep has at
        hand when it solves the point); computed when not given.

    Returns
    -------
    list of MeshMetrics
        One per point, all NaN where a harmonic is not finite.
    """
    Z = np.atleast_2d(np.asarray(harmonics, dtype=float))
    H = n_harmonics(Z)
    out: list[MeshMetrics | None] = [None] * Z.shape[0]
    ok = np.all(np.isfinite(Z), axis=1)
    for i in np.flatnonzero(~ok):
        out[i] = MeshMetrics.nan(H)
    omegas = np.asarray(omegas, dtype=float)
    for block in np.array_split(np.flatnonzero(ok), max(1, int(np.sum(ok)) // 64)):
        _metrics_block(Z, omegas, block, mesh, n_samples, intervals, out)
    return out


def _metrics_block(Z, omegas, rows, mesh, n_samples, intervals, out) -> None:
    """:func:`metrics_of_points` of the points ``rows`` (a block that fits the cache), in ``out``."""
    if rows.size:
        Zs, w = Z[rows], omegas[rows][:, None]
        amp = np.abs(real_to_complex(Zs))
        rms = np.sqrt(np.sum(amp[:, 1:] ** 2, axis=-1) / 2)
        delta = sample(Zs, n_samples)
        ddot = w * sample(differentiate(Zs), n_samples)
        de = mesh.lste_samples(n_samples)[1]
        force = mesh.elastic_samples(delta) + mesh.damping * (ddot - w * de)
        fmax, fmin, p2p = np.max(force, axis=-1), np.min(force, axis=-1), np.ptp(delta, axis=-1)
        W0 = np.full(rows.size, float(mesh.static_load)) if mesh.static_load else np.mean(force, axis=-1)
        for j, i in enumerate(rows):
            iv = mesh.intervals(Zs[j]) if intervals is None else intervals[i]
            out[i] = MeshMetrics(
                dte_mean=float(Zs[j, 0]),
                dte_rms=float(rms[j]),
                dte_p2p=float(p2p[j]),
                dte_amplitudes=amp[j].copy(),
                force_max=float(fmax[j]),
                force_min=float(fmin[j]),
                dslr=float(fmax[j] / W0[j]),
                contact_loss_fraction=1.0 - iv.contact_fraction,
                back_contact=iv.back_contact,
            )


@dataclass(frozen=True)
class PointMetrics:
    """The metrics a sweep writes per point (``SweepResult.metrics``) for one model.

    They are those of the coordinate ``mesh.coord`` under the law ``mesh`` (a gear mesh
    with backlash or a one-sided stop), or NaN when ``mesh`` is None (a model without
    one). A model supplies it (``ReducedModel.metrics``); the sweep, the continuation, the
    choice of H and the orbit search call it and never ask what the law is.

    Attributes
    ----------
    mesh : BacklashMesh or None
        The law whose metrics are written.
    """

    mesh: BacklashMesh | None = None

    def _coord(self, harmonics) -> NDArray:
        z = np.asarray(harmonics, dtype=float)
        z = z[self.mesh.coord] if z.ndim > 1 else z
        return z.reshape(-1)

    def intervals(self, harmonics) -> object | None:
        """What :meth:`of_points` needs of a point while it is solved (its contact
        intervals); None when the harmonics are not finite or there is no mesh.

        Parameters
        ----------
        harmonics : ndarray (n_nl, 2H+1)
            Real harmonics of the nonlinear coordinates [m].

        Returns
        -------
        ContactIntervals or None
        """
        if self.mesh is None:
            return None
        z = self._coord(harmonics)
        return self.mesh.intervals(z) if np.all(np.isfinite(z)) else None

    def of_points(self, harmonics, omegas, n_samples: int = 2048, intervals=None) -> list[MeshMetrics]:
        """The metrics of many points (:func:`metrics_of_points`), NaN without a mesh.

        Parameters
        ----------
        harmonics : array_like (P, n_nl, 2H+1)
            Real harmonics of the nonlinear coordinates per point [m].
        omegas : array_like (P,)
            Base frequency of each point [rad/s].
        n_samples : int
            Samples per period for the extremes.
        intervals : sequence, optional
            :meth:`intervals` of each point; computed when not given.

        Returns
        -------
        list of MeshMetrics
        """
        Z = np.asarray(harmonics, dtype=float)
        if self.mesh is None:
            return [MeshMetrics.nan((Z.shape[-1] - 1) // 2) for _ in range(len(Z))]
        zs = np.array([self._coord(z) for z in Z]).reshape(len(Z), -1)
        return metrics_of_points(zs, omegas, self.mesh, n_samples, intervals)

    def of(self, harmonics, omega: float, n_samples: int = 2048) -> MeshMetrics:
        """The metrics of one point (:meth:`of_points`).

        Parameters
        ----------
        harmonics : ndarray (n_nl, 2H+1)
            Real harmonics of the nonlinear coordinates [m].
        omega : float
            Base frequency [rad/s].
        n_samples : int
            Samples per period for the extremes.

        Returns
        -------
        MeshMetrics
        """
        return self.of_points(np.asarray(harmonics, dtype=float)[None], [float(omega)], n_samples)[0]

    def outputs(self, harmonics, omega: float) -> NDArray:
        """RMS DTE and largest mesh force [m, N]: what the choice of H compares.

        Parameters
        ----------
        harmonics : ndarray (n_nl, 2H+1)
            Real harmonics of the nonlinear coordinates [m].
        omega : float
            Base frequency [rad/s].

        Returns
        -------
        ndarray (2,)
        """
        m = self.of(harmonics, omega)
        return np.array([m.dte_rms, m.force_max])

    def signature(self, harmonics, omega: float) -> NDArray:
        """The contact-loss fraction [-]: what tells one branch from another.

        Parameters
        ----------
        harmonics : ndarray (n_nl, 2H+1)
            Real harmonics of the nonlinear coordinates [m].
        omega : float
            Base frequency [rad/s].

        Returns
        -------
        ndarray (1,)
        """
        return np.array([self.of(harmonics, omega).contact_loss_fraction])


def metrics_from_history(history: TimeHistory, mesh: BacklashMesh, H: int = 15) -> MeshMetrics:
    """Metrics from equally spaced samples over one period (time integration).

    Parameters
    ----------
    history : TimeHistory
        One period sampled at equal steps.
    mesh : BacklashMesh
        The mesh: b and W_0.
    H : int
        Harmonic amplitudes |δ_k| reported for k = 0..H (by FFT of the samples).

    Returns
    -------
    MeshMetrics
        The metrics in SI units, all from the samples.
    """
    d = history.delta
    n = d.size
    spec = np.fft.rfft(d) / n
    amp = 2 * np.abs(spec[: H + 1])
    amp[0] = abs(spec[0].real)
    rms = float(np.sqrt(np.mean((d - np.mean(d)) ** 2)))
    x = history.mesh_deflection
    W0 = _static_load(mesh, history.force)
    return MeshMetrics(
        dte_mean=float(np.mean(d)),
        dte_rms=rms,
        dte_p2p=float(np.ptp(d)),
        dte_amplitudes=amp,
        force_max=float(np.max(history.force)),
        force_min=float(np.min(history.force)),
        dslr=float(np.max(history.force) / W0),
        contact_loss_fraction=float(np.mean(np.abs(x) <= mesh.half_backlash)),
        back_contact=bool(np.any(x < -mesh.half_backlash)),
    )
