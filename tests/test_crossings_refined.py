"""Contact crossings of a high-degree signal at a near-tangency: found on the refined grid
(64 x), not by the companion matrix, whose eigenvalues at D harmonics cost seconds above
D ~ 500 (a shaft-order sweep over a gear revolution spent a minute in it at one grazing
point; benchmarks/README.md).

Independent check: 2^22 samples of x(θ) by FFT. A signal with 300 harmonics whose
maximum exceeds b by 5e-10 (relative to an amplitude of ~1) is a case that neither the
plain nor the 8 x grid can certify; the 64 x grid can. The contact fraction must agree
with the dense samples to the samples' resolution (one sample per crossing,
2 x 2π/2^22 per crossing pair) and the number of intervals with their sign changes.
"""

import numpy as np
import pytest

from nlgrd.nonlinear.fourier.harmonics import sample
from nlgrd.nonlinear.laws import describing_functions as dfm


def test_near_tangency_of_a_long_series_is_certified_on_the_refined_grid(monkeypatch):
    rng = np.random.default_rng(5)
    D, b = 300, 1.0
    k = np.arange(1, D + 1)
    phase = rng.uniform(0, 2 * np.pi, D)
    x = np.zeros(2 * D + 1)
    x[1::2], x[2::2] = np.cos(phase) / k**2, np.sin(phase) / k**2
    n = 2**22
    x[0] = b - sample(x, n).max() + 5e-10  # the maximum grazes b from above
    # the case this test is about: the plain and 8 x grids cannot certify it
    assert dfm._sampled_crossings(x, (b, -b)) is None
    assert dfm._sampled_crossings(x, (b, -b), refine=8) is None

    def companion(*args, **kwargs):
        pytest.fail("the companion matrix was used")

    monkeypatch.setattr(dfm, "_companion_crossings", companion)
    iv = dfm.contact_intervals(x, b)
    xs = sample(x, n)
    state = np.where(xs > b, 1, np.where(xs < -b, -1, 0))
    changes = int(np.sum(state != np.roll(state, 1)))
    assert iv.start.size == changes
    assert abs(iv.contact_fraction - np.mean(state != 0)) <= changes / n
