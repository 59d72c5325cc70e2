"""The statistics of a per-period record (nlgrd.timedomain.record_statistics; issue 35,
item 3), against series whose answer is known in closed form:

- MSER-5 (White 1997) on an exponential transient (20 σ, time constant τ) plus AR(1)
  noise: the cut lies past τ and in the first half, and what is left of the transient
  biases the kept mean by less than its standard error (MSER minimises the sum of the two).
- The standard uncertainty of a mean covers: on AR(1) series x_n = φ x_{n-1} + e_n (the
  mean is 0) and on a two-state telegraph signal plus noise (mean 1/2; its switching is
  the intermittency of a chaotic record: laminar phases of ~1/p periods), the fraction of
  300 seeded records whose mean lies within 2 standard uncertainties of the truth is
  95.45 % for an honest uncertainty; 300 records scatter that fraction by 1.2 % (binomial),
  so the band [0.91, 0.99] is 3.5 of those either side. Measured (n = 1024): white 95.7 %,
  φ = 0.5 94.7 %, φ = -0.5 95.3 %, φ = 0.9 96.0 %, φ = 0.98 (50 correlation times in
  the record) 94.0 %, telegraph p = 0.01 92.7 %. The former batch means (20 batches,
  lag-1 gate at 2/√20) covered 82.3 % at φ = 0.98 and 85.3 % on the telegraph.
- The uncertainty has no step like the former gate's: along a path from a strongly correlated
  series to white noise (401 points) its logarithm never steps by more than 0.25
  (measured 0.15, where the integer correlation window jumps on a steep stretch), where
  the former gate at a batch correlation of 0.447 stepped it by 0.52 (a factor 1.7).
- The record maximum of i.i.d. Gumbel variates: the batch maxima are Gumbel with the same
  scale β, so their standard deviation is πβ/√6 (Gumbel 1958, ch. 6), within 35 %
  (20 batches, the sample standard deviation of a Gumbel sample of 20 scatters ~20 %).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from nlgrd.timedomain.record_statistics import correlation_window, mser5, record_max, sample_mean


def _ar1(n: int, phi: float, rng) -> np.ndarray:
    e = rng.standard_normal(n)
    x = np.empty(n)
    x[0] = e[0] / math.sqrt(1 - phi * phi)  # stationary start
    for i in range(1, n):
        x[i] = phi * x[i - 1] + e[i]
    return x


def _telegraph(n: int, p: float, rng) -> np.ndarray:
    """0/1 switching with probability p per period, plus noise of sd 0.5; mean 1/2."""
    state = np.cumsum(rng.random(n) < p) % 2
    return (state if rng.random() < 0.5 else 1 - state) + 0.5 * rng.standard_normal(n)


def test_mser5_cuts_an_exponential_transient():
    rng = np.random.default_rng(1)
    n, tau, phi = 2000, 40.0, 0.5
    sigma = 1 / math.sqrt(1 - phi * phi)
    transient = 20 * sigma * np.exp(-np.arange(n) / tau)
    cut, ok = mser5(transient + _ar1(n, phi, rng))
    assert ok
    assert tau <= cut <= n // 2, cut
    # what MSER trades: the transient's bias of the kept mean against its standard error
    bias = float(np.mean(transient[cut:]))
    se = sigma * math.sqrt((1 + phi) / (1 - phi) / n)
    assert bias <= se, (bias, se)


def test_mser5_does_not_cut_a_settled_series():
    cut, ok = mser5(np.full(400, 3.0))
    assert (cut, ok) == (0, True)


def test_standard_error_of_ar1_against_the_closed_form():
    """σ_x sqrt((1 + φ)/(1 - φ)/n) asymptotically (Priestley 1981, Spectral Analysis and
    Time Series, §5.3); OBM with a window of 5 autocorrelation times is biased low by
    about 2φ/((1 - φ²) M g) (10 % here) and scatters by sqrt(2/(1.5 n/M)) (13 %), and the t
    factor of its degrees of freedom raises it 1-2 %: within 40 %."""
    rng = np.random.default_rng(2)
    n, phi = 20000, 0.8
    est = sample_mean(_ar1(n, phi, rng))
    exact = math.sqrt((1 + phi) / (1 - phi) / n) / math.sqrt(1 - phi * phi)
    assert 0.6 < est.uncertainty / exact < 1.4, est.uncertainty / exact
    assert abs(est.value) < 3 * est.uncertainty


@pytest.mark.parametrize(
    "name, n, make, truth",
    [
        ("white", 1024, lambda n, rng: rng.standard_normal(n), 0.0),
        ("AR(1) 0.5", 1024, lambda n, rng: _ar1(n, 0.5, rng), 0.0),
        ("AR(1) -0.5", 1024, lambda n, rng: _ar1(n, -0.5, rng), 0.0),
        ("AR(1) 0.9", 1024, lambda n, rng: _ar1(n, 0.9, rng), 0.0),
        ("AR(1) 0.98", 1024, lambda n, rng: _ar1(n, 0.98, rng), 0.0),
        ("telegraph 0.01", 1024, lambda n, rng: _telegraph(n, 0.01, rng), 0.5),
    ],
)
def test_two_standard_uncertainties_cover_the_mean(name, n, make, truth):
    rng = np.random.default_rng(5)
    hits = []
    for _ in range(300):
        e = sample_mean(make(n, rng))
        hits.append(abs(e.value - truth) <= 2 * e.uncertainty)
    assert 0.91 <= np.mean(hits) <= 0.99, (name, np.mean(hits))


def test_the_uncertainty_has_no_step():
    rng = np.random.default_rng(7)
    a, b = _ar1(2000, 0.995, rng), rng.standard_normal(2000)
    u = [sample_mean((1 - s) * a + s * a.std() * b).uncertainty for s in np.linspace(0, 1, 401)]
    assert np.max(np.abs(np.diff(np.log(u)))) < 0.25


def test_the_window_of_an_oscillating_correlation():
    """A noisy period-5 signal (the twin's logarithms near a period-5 orbit: ρ(5) ≈ 1)
    never decorrelates: the window is the cap, a quarter of the record, and the mean's
    uncertainty that of overlapping batches of that length (the period-5 part averages
    out in them), not the plain sum's, which oscillates about 0."""
    rng = np.random.default_rng(9)
    x = np.tile([1.0, -0.5, 0.3, -1.2, 0.4], 400) + 0.05 * rng.standard_normal(2000)
    assert correlation_window(x) == 500
    e = sample_mean(x)
    assert 0 < e.uncertainty < 10 * 0.05 / math.sqrt(2000)
    assert abs(e.value) < 3 * e.uncertainty + 0.2 / 2000  # the tile's mean is 0


def test_record_max_of_gumbel_variates():
    rng = np.random.default_rng(3)
    beta = 2.0
    x = rng.gumbel(0.0, beta, 20000)
    est = record_max(x)
    assert est.value == x.max()
    assert 0.65 < est.uncertainty / (math.pi * beta / math.sqrt(6)) < 1.35
