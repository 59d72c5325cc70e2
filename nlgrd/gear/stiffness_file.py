"""Mesh stiffness k(θ) over the mesh cycle from a file: the ``stiffness_file`` of a gear pair.

The file gives the *shape* ρ(θ) = k(θ) / mean(k) of the mesh stiffness; the dynamics use
k(θ) = k_h ρ(θ) with the model's k_h (``mesh_stiffness``, or computed from the geometry),
exactly as they use the Fourier harmonics of ``stiffness_variation`` (which the file
becomes: :func:`read_stiffness_file`). A file in N/m also states its mean: the model check
refuses it when it is more than :data:`MEAN_FACTOR` times off k_h (a unit slip), and
``nlgrd lste`` prints it beside the k_h used.

Phase convention: θ = 2π φ = ω t, φ the mesh phase in cycles, the same as the LSTE files'
(:mod:`nlgrd.gear.lste_file`) and the computed LSTE's (φ = 0 where a tooth pair comes into
contact at the start of the path of contact, :mod:`nlgrd.gear.transmission_error`;
``nlgrd lste`` writes it as ``phase [cycles]``), so ρ(θ) = 1 + Σ a_k cos kθ + b_k sin kθ in
the convention of ``stiffness_variation``.

File formats (CSV, one header row, ``#`` starts a comment, names case-insensitive;
:mod:`nlgrd.gear.sample_tables`):

- Samples of one mesh cycle: a phase column, ``phase`` (mesh phase φ in cycles, e.g.
  0 .. 1) or ``roll_angle`` (pinion roll angle in rad, one cycle being 2π / z1), and a
  value column, ``stiffness_n_per_m`` (k in N/m, ρ = k / mean k) or ``rho`` (ρ itself,
  mean 1 within :data:`RHO_MEAN_RTOL`). The phase increases strictly and the samples fill
  one cycle (an endpoint one cycle after the first sample must repeat its value and is
  dropped); every value is positive. Equally spaced samples give the harmonics by the
  discrete Fourier transform, exact for a ρ with fewer than n / 2 harmonics; unequally
  spaced ones are first resampled by a periodic cubic spline onto 8 n equal steps. The
  analysis takes H harmonics of ρ (30, as from the load sharing), so the file needs at
  least 2 H + 1 samples.
- Fourier coefficients: ``harmonic`` (integers m >= 0) with ``a_n_per_m`` and ``b_n_per_m``
  (k in N/m: harmonic 0, the mean, is needed and divides the others) or ``a_rho`` and
  ``b_rho`` (harmonic 0, if given, is 1); harmonics not listed are zero, all listed are
  used.

ρ must stay positive over the cycle (checked on the Fourier series used). Every bad input
raises one :class:`~nlgrd.errors.ModelError` naming the column and the file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.gear.lste_file import fourier_fit, resample
from nlgrd.gear.sample_tables import (
    number_column,
    read_harmonic_table,
    read_periodic_samples,
    read_table,
)

#: Value columns of a sample file and their factor to SI (ρ is dimensionless).
SAMPLE_COLUMNS = {"stiffness_n_per_m": 1.0, "rho": 1.0}
#: Units of a coefficient file (suffixes of ``a_`` and ``b_``).
COEFFICIENT_UNITS = {"n_per_m": 1.0, "rho": 1.0}
#: How far the mean of a ``rho`` file may be from 1 [-] (samples written to 4 digits).
RHO_MEAN_RTOL = 1e-3
#: A file mean this many times above or below the model's k_h is refused: a unit slip
#: (N/mm, N/um read as N/m) is a factor 1e3 or more, a stiffness from another method 0.5-2.
MEAN_FACTOR = 10.0
#: Resampling of unequally spaced samples: points of the uniform grid per sample.
RESAMPLE_FACTOR = 8


@dataclass(frozen=True, eq=False)
class StiffnessShape:
    """The mesh-stiffness shape of a ``stiffness_file``.

    Attributes
    ----------
    rho : tuple of float
        Real harmonics [1, a_1, b_1, ...] of ρ(θ) = k(θ) / mean(k) in the mesh angle [-].
    mean : float or None
        The file's mean stiffness [N/m]; None for a file of ρ.
    path : str
        The file.
    """

    rho: tuple[float, ...]
    mean: float | None
    path: str

    @property
    def extremes(self) -> tuple[float, float]:
        """Smallest and largest ρ over the cycle (:func:`rho_samples`) [-]."""
        r = rho_samples(self.rho)
        return float(r.min()), float(r.max())


def rho_samples(rho: ArrayLike) -> NDArray:
    """ρ(θ) of real harmonics [1, a_1, b_1, ...] at 64 equal steps per harmonic over the cycle.

    Parameters
    ----------
    rho : array_like
        Real harmonics of ρ [-].

    Returns
    -------
    ndarray
        ρ at θ = 2π j / n, n = 64 × (the number of harmonics) [-].
    """
    rho = np.asarray(rho, dtype=float).reshape(-1)
    theta = np.linspace(0, 2 * np.pi, 64 * rho.size, endpoint=False)
    k = np.arange(1, rho.size // 2 + 1)[:, None] * theta
    return rho[0] + rho[1::2] @ np.cos(k) + rho[2::2] @ np.sin(k)


def read_stiffness_file(path: str | Path, H: int = 30, teeth_pinion: int | None = None) -> StiffnessShape:
    """The shape ρ of the mesh stiffness from a file (module notes).

    Parameters
    ----------
    path : str or Path
        CSV of samples or of Fourier coefficients.
    H : int
        Harmonics of ρ taken from samples [-]; a coefficient file gives all it lists.
    teeth_pinion : int, optional
        z1, for a ``roll_angle`` column.

    Returns
    -------
    StiffnessShape
        ρ's harmonics, the file's mean stiffness [N/m] (None for ρ) and the file.

    Raises
    ------
    ModelError
        Naming the column and the file: a missing file or column, a value that is not a
        number, a stiffness not positive, phases not increasing or not filling one cycle,
        fewer than 2 H + 1 samples, a ``rho`` mean other than 1, a ρ that does not stay
        positive.
    """
    path = Path(path)
    if not path.is_file():
        raise ModelError("", "no such file" if not path.exists() else "not a file", file=str(path))
    frame = read_table(path)
    if "harmonic" in frame.columns:
        a, b, unit = read_harmonic_table(path, COEFFICIENT_UNITS)
        column = f"a_{unit}"
        if not np.any(number_column(frame, "harmonic", path) == 0):
            if unit != "rho":
                raise ModelError(column, "harmonic 0 (the mean stiffness) is needed", file=str(path))
            a[0] = 1.0
        mean = float(a[0])
    else:
        phase, k, column = read_periodic_samples(path, SAMPLE_COLUMNS, "stiffness", teeth_pinion)
        if np.any(k <= 0):
            row = int(np.flatnonzero(k <= 0)[0]) + 1
            raise ModelError(
                column, f"row {row}: must be positive, got {float(k[row - 1])!r}", file=str(path)
            )
        H = int(H)
        if k.size < 2 * H + 1:
            raise ModelError(
                column,
                f"{k.size} samples give at most {(k.size - 1) // 2} harmonics; the analysis takes {H} "
                f"harmonics of k(θ): give at least {2 * H + 1} samples over the mesh cycle (or Fourier "
                "coefficients, a harmonic column)",
                file=str(path),
            )
        steps = np.diff(np.append(phase, phase[0] + 1.0)) * k.size
        if np.max(np.abs(steps - 1)) > 1e-6:  # unequal steps
            phase, k = resample(phase, k, RESAMPLE_FACTOR * k.size)
        ex = fourier_fit(phase, k, H)
        a, b = np.concatenate([[ex.e0], ex.a]), np.concatenate([[0.0], ex.b])
        mean = float(a[0])
        unit = "rho" if column == "rho" else "n_per_m"
    if not mean > 0:
        raise ModelError(column, f"the mean stiffness must be positive, got {mean!r}", file=str(path))
    if unit == "rho" and abs(mean - 1) > RHO_MEAN_RTOL:
        raise ModelError(
            column,
            f"the mean of rho over the cycle is {mean:.6g}, not 1 (k_h is the mean; within "
            f"{RHO_MEAN_RTOL:g}): give k in N/m (stiffness_n_per_m) to have it normalised",
            file=str(path),
        )
    rho = np.empty(2 * a.size - 1)
    rho[0], rho[1::2], rho[2::2] = 1.0, a[1:] / mean, b[1:] / mean
    low = float(np.min(rho_samples(rho)))
    if low <= 0:
        raise ModelError(
            column,
            f"k(θ) must stay positive over the mesh cycle, but the Fourier series of {a.size - 1} "
            f"harmonics dips to ρ = {low:.3g}",
            file=str(path),
        )
    return StiffnessShape(tuple(float(r) for r in rho), None if unit == "rho" else mean, str(path))
