"""Period-2 orbits of the geared FE model (issue 12, items 1-2): Kubo's rig at its Table 1
damping (data/case_studies/kubo.toml), H = 13 per mesh period, on the link engine
(``nlgrd.sweep``'s path: ``build_link_model``, ``period_model``).

1. The period-ν model (``period_model(model, 2)``: receptances at the base ω/2
   with the speed of the mesh frequency, the LSTE at the even harmonics) holds the period-1
   orbits: spread onto ω/2 they solve it, and its Floquet multipliers are the squares of
   the period-1 ones (the monodromy over 2T is the square of that over T).
2. On the down sweep at 3055.6 Hz the period-1 orbit has a real multiplier -1.19 (the same
   on the full 84-DOF state space). The period-2 orbit started from the critical mode is
   checked against the HHT-α integration of the full FE model over cycles of two mesh
   periods, started on it: the integration keeps period 2 (δ(t + T) - δ(t) about 7 % of the
   range) and its ω/2 and ω components converge to the harmonic-balance ones as the step
   shrinks: 2.3 % and 0.7 % off at 4096 and 8192 steps per mesh period, 0.17 % after
   Richardson extrapolation (second order), the ω component within 3e-5. With 512 steps
   per period (the default of the main-resonance checks) the integration instead settles
   on a period-1 orbit 4.7 % from the harmonic-balance one, which the harmonic balance
   itself rejects (residual 1.4 %): in this regime, 70 % of the period in separation, the
   time step decides, so the reference is taken converged in it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.fourier.harmonics import analyse
from nlgrd.nonlinear.fourier.periods import amplitudes, period_of, spread
from nlgrd.nonlinear.models.link_model import build_link_model, period_model
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.tracing.orbit_search import same_motion, search_orbits
from nlgrd.nonlinear.tracing.subharmonic import branch_off
from nlgrd.nonlinear.tracing.sweep import sweep
from nlgrd.timedomain.links import link_time_response, start_from_harmonics

KUBO = Path(__file__).resolve().parent.parent / "data" / "case_studies" / "kubo.toml"
TWO_PI = 2 * np.pi


@pytest.fixture(scope="module")
def kubo_down():
    """Kubo's down sweep (H = 13) from 16 000 rpm to 3000 Hz, its period-1 and period-2 models."""
    kubo = load_model(KUBO)
    m1 = build_link_model(kubo)
    m2 = period_model(m1, 2)

    def mesh_frequency(rpm):
        return np.asarray(rpm) * np.pi / 30 / m1.receptance.plan.speed_per_base

    top = float(mesh_frequency(16000.0))
    m1.receptance.prepare(13 * top)
    m1.receptance.prepare_stability(top)
    m2.receptance.prepare(26 * top / 2)
    m2.receptance.prepare_stability(top / 2)
    om = mesh_frequency(np.linspace(2000.0, 16000.0, 85))
    low = om[(om <= TWO_PI * 3400) & (om >= TWO_PI * 3000)][::-1]
    grid = np.concatenate([mesh_frequency(np.linspace(16000.0, 6900.0, 50)), low])
    p1 = sweep(m1.reduced, grid, 13, "down", jump="auto", leave_unstable=False)
    return m1, m2, p1


def test_period_two_model_holds_the_period_one_orbits(kubo_down):
    m1, m2, p1 = kubo_down
    i = int(np.argmin(np.abs(p1.omega - TWO_PI * 3125.0)))  # stable, complex pair
    w, z1 = float(p1.omega[i]), p1.harmonics[i]
    assert p1.stable[i]
    z2 = spread(z1, 2)
    P = m2.reduced.at(w / 2, 26)
    R, _, scale = P.residual_jacobian(z2.reshape(-1))
    assert np.max(np.abs(R)) / scale < 1e-8  # the period-1 orbit solves the period-2 problem
    r1, r2 = m1.reduced, m2.reduced
    mu1 = floquet_multipliers(r1.linear_state_space(w), r1.nonlinearities, z1, w, method="dense")
    mu2 = floquet_multipliers(r2.linear_state_space(w / 2), r2.nonlinearities, z2, w / 2, method="dense")
    top1, top2 = np.sort(np.abs(mu1))[::-1], np.sort(np.abs(mu2))[::-1]
    np.testing.assert_allclose(top2[:6], top1[:6] ** 2, rtol=1e-6)


@pytest.mark.slow  # two time integrations of 8192 and 16384 steps per cycle, about 90 s
def test_period_two_orbit_against_converged_time_integration(kubo_down):
    _, m2, p1 = kubo_down
    i = int(np.argmin(np.abs(p1.omega - TWO_PI * 3055.6)))
    w = float(p1.omega[i])
    mu = complex(p1.dominant_multiplier[i])
    assert abs(mu.imag) < 1e-9 and mu.real < -1.1  # flip-unstable period-1 orbit
    s2 = branch_off(m2.reduced.at(w / 2, 26), p1.harmonics[i], 2)
    assert s2 is not None and period_of(s2.harmonics, 2) == 2
    hb = amplitudes(s2.harmonics)[0][:2]
    start = start_from_harmonics(m2, w / 2, 26, s2.harmonics)
    td = []
    for steps in (8192, 16384):  # per cycle of two mesh periods
        tr = link_time_response(m2, w / 2, state0=start, tol=1e-8, steps_per_period=steps, max_periods=800)
        d = tr.y[0]
        assert tr.converged
        assert np.max(np.abs(d[: d.size // 2] - d[d.size // 2 :])) / np.ptp(d) > 1e-2  # period 2
        td.append(amplitudes(analyse(d, 2)))
    extrapolated = td[1] + (td[1] - td[0]) / 3  # second order in the step
    print("HB", hb, "TD", td, "Richardson", extrapolated)
    assert abs(td[1][0] / hb[0] - 1) < 1e-2 and abs(extrapolated[0] / hb[0] - 1) < 5e-3
    assert abs(td[1][1] / hb[1] - 1) < 1e-4


@pytest.mark.slow  # 40 perturbed starts for each period, about 14 s (one BLAS thread)
def test_search_from_perturbed_starts_finds_the_orbits_of_the_down_sweep(kubo_down):
    """At 3055.6 Hz the orbit search finds, from its perturbed starts, the down sweep's
    flip-unstable period-1 orbit (real multiplier -1.19) and, from that orbit's critical
    Floquet mode, the period-2 orbit that :func:`branch_off` starts (checked against time
    integration above), each as the same motion: the two constructions agree to Newton's
    tolerance. Before the search tried the flip, the period-2 orbit came from 1 of the 40
    perturbed starts by a Newton path that rounding decides: found under the default
    OpenBLAS kernel, missed under OPENBLAS_CORETYPE=Haswell, Sandybridge and Prescott."""
    m1, m2, p1 = kubo_down
    i = int(np.argmin(np.abs(p1.omega - TWO_PI * 3055.6)))
    w = float(p1.omega[i])
    found = search_orbits(lambda nu: m1.reduced if nu == 1 else m2.reduced, w, 13, (1, 2))
    s2 = branch_off(m2.reduced.at(w / 2, 26), p1.harmonics[i], 2)
    one = [o for o in found if o.period == 1 and same_motion(o.harmonics, p1.harmonics[i], 1)]
    two = [o for o in found if o.period == 2 and same_motion(o.harmonics, s2.harmonics, 2)]
    assert len(one) == 1 and not one[0].stable and one[0].dominant_multiplier.real < -1.1
    assert len(two) == 1 and two[0].start.startswith(f"flip of the period-1 orbit from {one[0].start}, ")
    assert all(o.period in (1, 2) for o in found)
