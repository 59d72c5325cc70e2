"""What a sweep does where a fold leads into a range without a stable orbit (issue 10,
item 3): the arc-length search stops once it has run past the target frequency, and the
point is reported as "no stable mesh-periodic response" on the unstable crossing it
found, with its dominant multiplier, instead of failing (the 252-DOF benchmark model of
benchmarks/bench_nonlinear.py, 2564 Hz up), on the link engine (``nlgrd.sweep``'s path).
The multiplier is checked against the reference monodromy (``method="expm"`` on the full
state) and the orbit against the harmonic-balance equations: the point is what it says
it is.
"""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.fourier.harmonics import evaluate
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.nonlinear.results.sweep_results import STABLE_RTOL
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.tracing.arclength import jump_to_branch
from nlgrd.rotor.system import refined
from nlgrd.timedomain.links import link_time_response, start_from_harmonics

ROOT = Path(__file__).resolve().parent.parent
TWO_SHAFT = ROOT / "data" / "models" / "two_shaft.toml"
TWO_PI = 2 * np.pi


@pytest.fixture(scope="module")
def benchmark_model():
    """two_shaft.toml with every shaft element split in two (252 DOFs), mesh damping 0.1."""
    base = load_model(TWO_SHAFT)
    system = refined(base, 2)
    g = dc.replace(system.gear_pairs[0], damping_ratio=0.1)
    system = dc.replace(system, gear_pairs=(g,))
    om = TWO_PI * np.linspace(1825.5, 5476.5, 500)
    return system, build_link_model(system), om


def test_fold_without_a_stable_landing_is_reported_on_its_unstable_crossing(benchmark_model):
    system, model, om = benchmark_model
    sel = om[(om > TWO_PI * 2500) & (om < TWO_PI * 2600)]
    res = link_sweep(model, sel, H=5, directions="up", period=1).result
    i = int(np.argmin(np.abs(res.omega - TWO_PI * 2564.48)))
    assert res.branch_switch[i - 1] == 0 and res.stable[i - 1]  # the branch before the fold
    assert res.converged[i] and res.no_stable[i] and res.branch_switch[i]
    assert np.isnan(res.metrics["dte_rms"][i])  # never drawn as the response
    mu = complex(res.dominant_multiplier[i])
    assert abs(mu.imag) > 0.5 and abs(mu) > 1 + STABLE_RTOL
    # the multiplier reported is that of the stored orbit, by the reference monodromy on
    # the full state (the sweep's stability basis is truncated, checked against it)
    w = float(res.omega[i])
    full = model.reduced.linear_state_space(w).full()
    ref = floquet_multipliers(full, model.reduced.nonlinearities, res.harmonics[i], w, method="expm")
    assert abs(np.max(np.abs(ref)) - abs(mu)) < 1e-8
    # and it is a harmonic-balance solution there
    again = solve(model.reduced.at(w, 5), res.harmonics[i], fallback=False)
    assert again.converged and again.iterations <= 1

    # the search passed the small S (two folds), crossed 2564 Hz unstable, and stopped
    # once past it instead of following the branch for 1600 Hz (318 steps before)
    zj, steps, folds, unstable = jump_to_branch(
        model.reduced, 5, res.harmonics[i - 1], float(res.omega[i - 1]), w, require_stable=True
    )
    assert zj is None and folds == 2 and unstable is not None and steps < 100


def test_time_integration_started_on_a_stable_orbit_stays_on_it():
    """start_from_harmonics recovers every DOF of an HB orbit (Kubo's rig, H = 13, 2000 Hz,
    stable): the first integrated period follows the HB orbit to 1.6 % of the DTE range
    (the settled orbit differs from HB at H = 13 by 0.34 %; the truncated harmonics start
    transients of the lightly damped modes, ζ 0.005, that decay over ~100 periods), while one
    started from the static deflection is far from it."""
    kubo = load_model(ROOT / "data" / "case_studies" / "kubo.toml")
    w = TWO_PI * 2000.0
    model = build_link_model(kubo)
    hb = link_sweep(model, np.array([w]), H=13, directions="up", period=1).result
    assert hb.converged[0] and hb.stable[0]
    z = hb.harmonics[0].reshape(-1)

    def first_period(state0):
        tr = link_time_response(model, w, state0=state0, tol=0.0, max_periods=1, min_periods=1)
        ref = evaluate(z, w * tr.t)
        return np.max(np.abs(tr.y[0] - ref)) / np.ptp(ref)

    on, rest = first_period(start_from_harmonics(model, w, 13, hb.harmonics[0])), first_period(None)
    assert on < 0.03 and rest > 10 * on
