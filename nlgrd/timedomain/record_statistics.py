"""Statistics of a per-period record and their sampling uncertainty: the transient cut
(MSER-5), the mean of a correlated series with its standard error from the integrated
autocorrelation time, and a record's extreme with its Gumbel uncertainty.

- **Transient cut** by MSER-5 (White 1997, Simulation 69:323; White, Cobb & Spratt 2000,
  Proc. Winter Simulation Conf. 755): on the means of 5 periods b_j, j < m, the cut d
  minimises (1/(m - d)²) Σ_{j>=d} (b_j - b̄_d)², d <= m/2. A minimum on the bound m/2
  says the record is too short.
- **Mean** of n correlated values: its standard error by overlapping batch means
  (Meketon & Schmeiser 1984, Proc. Winter Simulation Conf. 227: var(x̄) = b/(n - b) x
  the mean square of the n - b + 1 means of b consecutive values about x̄, times
  n/(n - b + 1)), the batch length b the series' correlation window by Sokal's automatic
  windowing (Madras & Sokal 1988, J. Stat. Phys. 50:109, App. C; Sokal 1997, Monte Carlo
  methods in statistical mechanics, in Functional Integration, Plenum, §3) on the
  absolute autocorrelations: the smallest M with M >= :data:`WINDOW` (1 + 2 Σ_{t<=M}
  |ρ(t)|), at most :data:`MAX_WINDOW` of the record. The overlapping batches are the
  Bartlett lag window (a smooth cut of the autocorrelation sum, also where it
  oscillates), and the estimate moves with the data without a gate (the former lag-1
  gate of 20 batch means stepped it by 1.7 where a batch correlation crossed 0.447).
  With ν = 1.5 (n/b - 1) degrees of freedom (Meketon & Schmeiser) it is raised by
  t_ν/z at :data:`COVERAGE` (GUM, JCGM 100:2008, G.3), so that two standard
  uncertainties cover the mean 95 % of the time also when the record holds few
  correlation times.
- **Extreme** from the :data:`BATCHES` batch extremes as Gumbel variates (Gumbel 1958,
  Statistics of Extremes, ch. 6): the record's extreme is Gumbel with the batches' scale
  β = √6 s/π, so its standard deviation is s, the standard deviation of the batch
  extremes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.stats import norm
from scipy.stats import t as student_t

#: Batches of an extreme's Gumbel uncertainty (Schmeiser 1982, Oper. Res. 30:556: 10 to 30).
BATCHES = 20
#: Periods a batch of MSER-5 averages (White 1997).
MSER_BATCH = 5
#: Sokal's window factor on 1 + 2 Σ|ρ| (at least twice the integrated autocorrelation
#: time; Sokal advises 4-10 of that time): 8 covered 93-96 % on AR(1) and telegraph
#: records of 1024 periods, 5 only 90 % (tests/test_record_statistics.py) [-].
WINDOW = 8.0
#: The coverage of ±2 standard uncertainties the t factor keeps for few degrees of freedom [-].
COVERAGE = 0.9545
#: The window never exceeds this fraction of the record [-].
MAX_WINDOW = 0.25


@dataclass(frozen=True)
class Estimate:
    """A statistic and its standard uncertainty.

    Attributes
    ----------
    value : float
        The statistic (SI).
    uncertainty : float
        Its standard uncertainty (k = 1), same unit.
    """

    value: float
    uncertainty: float


def mser5(x: NDArray, batch: int = MSER_BATCH) -> tuple[int, bool]:
    """MSER-5 truncation of a series (White 1997; White, Cobb & Spratt 2000).

    Parameters
    ----------
    x : ndarray
        One value per period [any unit].
    batch : int
        Values averaged per batch [-].

    Returns
    -------
    cut : int
        Values to discard from the start [-].
    ok : bool
        The minimum is inside the admissible half (False: the record is too short).
    """
    x = np.asarray(x, dtype=float)
    m = x.size // batch
    if m < 4:
        return 0, False
    b = x[x.size - m * batch :].reshape(m, batch).mean(axis=1)  # align on the end
    offset = x.size - m * batch
    tail = b[::-1]
    n = np.arange(1, m + 1)
    s1 = np.cumsum(tail)[::-1]  # sums of b[d:]
    s2 = np.cumsum(tail * tail)[::-1]
    k = n[::-1]  # m - d
    sse = np.maximum(s2 - s1 * s1 / k, 0.0)
    dmax = m // 2
    crit = sse[: dmax + 1] / k[: dmax + 1] ** 2
    scale = float(np.max(np.abs(b))) or 1.0
    crit = np.where(crit <= (1e-14 * scale) ** 2, 0.0, crit)  # a settled series: no cut beyond rounding
    d = int(np.argmin(crit))
    return offset + batch * d, d < dmax


def correlation_window(x: NDArray) -> int:
    """The window of a series' correlation by Sokal's automatic windowing on the
    absolute autocorrelations: the smallest M with M >= :data:`WINDOW` (1 + 2 Σ_{t<=M}
    |ρ(t)|), at most :data:`MAX_WINDOW` of the record (module docstring). The absolute
    values make it the time the correlation takes to die out, also where ρ oscillates
    (the twin's logarithms, a motion near a period-k orbit), where the plain sum's
    window cuts it at a phase.

    Parameters
    ----------
    x : ndarray
        One value per period [any unit].

    Returns
    -------
    int
        The window M [-] (1 for a constant series).
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    dev = x - x.mean()
    den = float(dev @ dev)
    top = max(int(MAX_WINDOW * n), 1)
    if n < 4 or den <= 0:
        return 1
    size = 1 << (2 * n - 1).bit_length()
    f = np.fft.rfft(dev, size)
    rho = np.fft.irfft(f * np.conj(f), size)[1 : top + 1] / den  # ρ(t), the biased estimate
    tau = 1 + 2 * np.cumsum(np.abs(rho))
    ok = np.nonzero(np.arange(1, top + 1) >= WINDOW * tau)[0]
    return int(ok[0]) + 1 if ok.size else top


def sample_mean(x: NDArray) -> Estimate:
    """The mean of a per-period series and its standard uncertainty by overlapping batch
    means of the correlation window's length (module docstring).

    Parameters
    ----------
    x : ndarray
        One value per kept period [any unit].

    Returns
    -------
    Estimate
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    if n < 4:
        return Estimate(float(np.mean(x)), math.inf)
    b = correlation_window(x)
    mean = float(np.mean(x))
    c = np.concatenate(([0.0], np.cumsum(x - mean)))
    y = (c[b:] - c[:-b]) / b  # the n - b + 1 overlapping batch means, less the mean
    var = n * b / ((n - b) * (n - b + 1)) * float(y @ y) / n  # Meketon & Schmeiser 1984
    dof = 1.5 * (n / b - 1)  # of the OBM variance (Meketon & Schmeiser 1984)
    k = float(student_t.ppf(0.5 + COVERAGE / 2, dof)) / float(norm.ppf(0.5 + COVERAGE / 2))
    return Estimate(mean, k * math.sqrt(max(var, 0.0)))


def _batches(n: int) -> tuple[int, int]:
    """(start, batch length) of BATCHES equal batches ending at n."""
    size = max(n // BATCHES, 1)
    return n - size * min(BATCHES, n), size


def record_max(x: NDArray) -> Estimate:
    """The largest of per-period maxima and its Gumbel standard uncertainty.

    Parameters
    ----------
    x : ndarray
        Per-period maxima over the kept periods [any unit].

    Returns
    -------
    Estimate
        The record maximum; uncertainty the standard deviation of the batch maxima.
    """
    x = np.asarray(x, dtype=float)
    start, size = _batches(x.size)
    b = x[start:].reshape(-1, size).max(axis=1)
    u = float(np.std(b, ddof=1)) if b.size >= 3 else math.inf
    return Estimate(float(np.max(x)), u)
