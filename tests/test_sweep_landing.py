"""Where a sweep lands after a fold: against time integration (issue 10, items 3 and 4).

Kubo's single-DOF model (data/case_studies/kubo.toml, the notebook 01 grid of 80 speeds
over 2000-16000 rpm). Between 10 329 and 10 506 rpm the up sweep's low branch
(contact-loss fraction 0.13) folds. Arc-length continuation from it passes two turning
points and crosses 10 506 rpm on a stable orbit with back-side impacts, DSLR 26.4 and DTE
RMS 190 um (the "spike" of the old golden curve, 10 x its neighbours). Time integration
settles on that orbit when started on it, so it exists and attracts; but a slow
time-domain up sweep from the 10 329 rpm orbit falls to the down sweep's branch (DTE RMS
12.0 um) instead. The sweep (``jump="auto"``, the default of ``nlgrd.sweep``,
``link_sweep`` and the notebooks) lands on the stable solution nearest the departed orbit, the other
directions' solutions at that speed included, and so does what the slow sweep does.

Time integration: nlgrd.timedomain.sdof.time_sweep (the paper's DYTE, all LSTE harmonics), periodic
steady state to 1e-4 of the DTE range, as in the notebooks; its DTE RMS agrees with
harmonic balance at H >= 9 to about 1e-4 where both hold the same orbit, hence 0.5 %.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.fourier.harmonics import differentiate, evaluate
from nlgrd.nonlinear.models.sdof import sdof_model
from nlgrd.nonlinear.tracing.sweep import sweep
from nlgrd.timedomain.sdof import time_sweep

KUBO = Path(__file__).resolve().parent.parent / "data" / "case_studies" / "kubo.toml"

TD = dict(tol=1e-4, samples_per_period=256, rtol=1e-7)


@pytest.fixture(scope="module")
def kubo_sdof():
    system = load_model(KUBO)
    n_p = system.gear_pairs[0].geometry.teeth_pinion
    sd = sdof_model(system)
    rpm = np.linspace(2000.0, 16000.0, 80)
    return sd, 2 * np.pi * rpm / 60 * n_p


def _state(branch, i):
    z, w = branch.harmonics[i, 0], branch.omega[i]
    return [evaluate(z, 0.0), w * evaluate(differentiate(z), 0.0)]


def test_back_side_impact_orbit_exists_and_attracts(kubo_sdof):
    """The far branch of arc length at 10 506 rpm: time integration started on it stays
    (DTE RMS and DSLR within 0.5 %), so the old golden's spike is a real stable orbit."""
    sd, om = kubo_sdof
    arc = sweep(sd.reduced_model(), om[:50], H=13, directions="up", jump="arclength")
    assert arc.metrics["dte_rms"][48] > 150e-6 and arc.stable[48]
    td = time_sweep(sd, [om[48]], "up", state0=_state(arc, 48), **TD)
    assert td.converged[0]
    assert td.metrics["dte_rms"][0] == pytest.approx(arc.metrics["dte_rms"][48], rel=5e-3)
    assert td.metrics["dslr"][0] == pytest.approx(arc.metrics["dslr"][48], rel=5e-3)


@pytest.mark.slow  # a time-domain sweep, about 15 s
def test_up_sweep_lands_where_a_slow_time_domain_sweep_does(kubo_sdof):
    """A slow up sweep in time (from the 10 329 rpm orbit, five steps to 10 506 rpm, each
    from the last state) ends on the 12 um orbit, not on the back-side impact orbit; the
    default sweep's up branch at 10 506 rpm is that orbit (DTE RMS within 0.5 %)."""
    sd, om = kubo_sdof
    res = sweep(sd.reduced_model(), om, H=13, directions="both", jump="auto")
    up = res.select("up")
    i = int(np.argmin(np.abs(up.omega - om[47])))
    td = time_sweep(sd, np.linspace(om[47], om[48], 6), "up", state0=_state(up, i), **TD)
    assert td.converged[-1]
    assert td.metrics["dte_rms"][-1] < 20e-6  # not the 190 um orbit
    assert up.metrics["dte_rms"][i + 1] == pytest.approx(td.metrics["dte_rms"][-1], rel=5e-3)
    assert up.stable[i + 1]
