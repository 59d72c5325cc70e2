"""Mesh metrics of many points at once (``metrics_of_points``, what sweeps use) against
each point's time history (``time_history``: the samples of δ, δ', e, e' and W one point at
a time) and the exact contact intervals.

The batch takes the same samples (one inverse FFT of all points instead of one per
point), so extremes, peak-to-peak and the RMS agree to rounding (1e-12 relative); the
contact-loss fraction is that of the exact intervals."""

from __future__ import annotations

import numpy as np
import pytest

from nlgrd.nonlinear.laws.force_laws import BacklashMesh, ContactStop, ParametricMesh
from nlgrd.nonlinear.results.metrics import metrics_of_points, time_history

H = 5
B = 20e-6


def meshes():
    lste = np.zeros(2 * H + 1)
    lste[1], lste[4] = 3e-6, -1e-6
    rho = np.zeros(2 * H + 1)
    rho[0], rho[1], rho[2] = 1.0, 0.2, -0.05
    kw = dict(stiffness=2e8, half_backlash=B, lste=lste, damping=300.0, static_load=1500.0)
    return [
        BacklashMesh(**kw),
        BacklashMesh(**{**kw, "static_load": None}),
        ContactStop(**kw),
        ParametricMesh(**kw, stiffness_variation=rho),
    ]


@pytest.mark.parametrize("mesh", meshes(), ids=lambda m: type(m).__name__ + ("" if m.static_load else "-W0"))
def test_batch_equals_point_by_point_time_histories(mesh):
    rng = np.random.default_rng(7)
    Z = rng.normal(scale=2e-6, size=(40, 2 * H + 1)) / np.arange(1, 2 * H + 2) ** 0.5
    Z[:, 0] = B + 8e-6 + rng.normal(scale=4e-6, size=40)  # drive side, some points lose contact
    Z[3] = np.nan  # an unconverged point
    w = 2 * np.pi * rng.uniform(800.0, 5000.0, size=40)
    out = metrics_of_points(Z, w, mesh, 1024)
    assert np.isnan(out[3].dte_rms) and np.isnan(out[3].force_max)
    lost = 0
    for i in np.flatnonzero(np.all(np.isfinite(Z), axis=1)):
        th = time_history(Z[i], w[i], mesh, 1024)
        m = out[i]
        W0 = mesh.static_load or np.mean(th.force)
        scale = np.max(np.abs(th.force))
        assert m.force_max == pytest.approx(np.max(th.force), abs=1e-12 * scale)
        assert m.force_min == pytest.approx(np.min(th.force), abs=1e-12 * scale)
        assert m.dslr == pytest.approx(np.max(th.force) / W0, rel=1e-12)
        assert m.dte_p2p == pytest.approx(np.ptp(th.delta), rel=1e-12)
        assert m.dte_rms == pytest.approx(np.std(th.delta), rel=1e-12)
        iv = mesh.intervals(Z[i])
        assert m.contact_loss_fraction == 1.0 - iv.contact_fraction
        lost += m.contact_loss_fraction > 0
    assert 5 <= lost <= 35  # both kinds of point are compared
