"""Sweeps beyond mesh-periodic motion on the geared FE model (issue 12, items 2 and 6):
Kubo's rig at its Table 1 damping (data/case_studies/kubo.toml), H = 13, on the link
engine (``nlgrd.sweep``'s path: ``link_sweep``, time integration by ``LinkIntegrator``).

``link_sweep(..., period="auto")`` answers every speed: the stable mesh-periodic orbit,
the stable period-2 orbit where period 1 is flip-unstable (the down sweep at 9800 rpm),
or "quasi-periodic" where a complex pair of Floquet multipliers has left the unit circle
(13 750-14 000 rpm: |μ| to 1.049), with the secondary frequency |arg μ| f_mesh / 2π.

Independent check of the quasi-periodic marking: the HHT-α integration of the full FE
model, started on the harmonic-balance orbit and run 3000 mesh periods, sampled once per
period (the Poincaré section). Where Floquet says stable the samples converge to a
fixed point (their spread shrinks from one 1000-period block to the next and is below
0.01 µm); where it says torus they keep circling (a spread of micrometres that does not
shrink), and the rotation per period of that circling, from the spectrum of the samples
(resolution 1/2000), is the multiplier's angle: measured within 0.0025 of arg μ / 2π at
13 750, 13 850 and 13 950 rpm (0.2255, 0.2070, 0.1900 against 0.2246, 0.2077, 0.1923).
The tolerance, 0.004, is the resolution plus the shift of the rotation number as the
torus grows away from the bifurcation. The onset of the torus falls in the same grid
interval (13 700-13 750 rpm) in both.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.nonlinear.results.metrics import NO_STABLE
from nlgrd.nonlinear.results.sweep_results import QUASI_PERIODIC
from nlgrd.nonlinear.tracing.auto_period import transitions
from nlgrd.timedomain.links import LinkIntegrator, settle, start_from_harmonics

KUBO = Path(__file__).resolve().parent.parent / "data" / "case_studies" / "kubo.toml"


@pytest.fixture(scope="module")
def kubo():
    system = load_model(KUBO)
    return system, build_link_model(system)


def mesh_frequencies(model, rpm):
    """Mesh frequencies [rad/s] of pinion speeds ``rpm`` (the base of a one-mesh model)."""
    return np.asarray(rpm) * np.pi / 30 / model.receptance.plan.speed_per_base


def table(model, res):
    """The sweep's table with ``shaft_speed [rpm]`` (as ``nlgrd.sweep(rpm=...)`` writes it)."""
    import dataclasses as dc

    return dc.replace(res, speed_per_base=model.receptance.plan.speed_per_base, speed_unit="rpm").to_frame()


@pytest.mark.slow  # two sweeps of 111 speeds each way, about 30 s
def test_every_speed_has_an_answer(kubo):
    system, model = kubo
    rpm = np.arange(9000.0, 14501.0, 50.0)
    om = mesh_frequencies(model, rpm)
    res = link_sweep(model, om, H=13)  # period "auto" by default
    one = link_sweep(model, om, H=13, period=1)
    m, df = res.result, table(model, res)
    assert m.converged.all()
    kinds = set(df["response"])
    assert kinds == {"periodic", "period 2", QUASI_PERIODIC}, kinds
    drawn = df[df["response"].isin(["periodic", "period 2"])]
    assert drawn["stable"].all() and drawn["mesh0.dte_rms [um]"].notna().all()
    assert drawn["bearing 0 (shaft 0, node 1).force_max [N]"].notna().all()
    # period 2 where period 1 is flip-unstable, with its ω/2 content
    two = df[df["response"] == "period 2"]
    assert list(two["direction"]) == ["down"]
    np.testing.assert_allclose(two["shaft_speed [rpm]"], [9800.0], rtol=1e-12)
    assert two["subharmonic_amplitude [um]"].iloc[0] > 0.1 * two["mesh0.dte_rms [um]"].iloc[0]
    assert (two["period"] == 2).all() and (two["harmonic_error [-]"] <= 5e-3).all()
    row = np.nonzero((m.direction == "down") & np.isclose(df["shaft_speed [rpm]"], 9800.0, rtol=1e-12))[0][0]
    assert one.result.no_stable[row] and one.to_frame()["instability"].iloc[row] == "real < -1"
    # the torus band: no values, its secondary frequency from the complex pair
    qp = df[df["response"] == QUASI_PERIODIC]
    assert qp["mesh0.dte_rms [um]"].isna().all() and (qp["instability"] == "complex").all()
    mu = m.dominant_multiplier[m.no_stable]
    f2 = np.abs(np.angle(mu)) / (2 * np.pi) * m.omega[m.no_stable] / (2 * np.pi)
    np.testing.assert_allclose(qp["secondary_frequency [Hz]"], f2, rtol=1e-7)  # written to 8 digits
    assert NO_STABLE not in kinds  # every speed answered here
    found = {(t.direction, t.kind) for t in transitions(m)}
    assert {("down", "period doubling"), ("down", "period-2 branch ends"), ("up", "Neimark-Sacker")} <= found


@pytest.mark.slow  # five time integrations of 3000 periods, about 25 s
def test_quasi_periodic_band_against_time_integration(kubo):
    system, model = kubo
    rpm = np.arange(13700.0, 14051.0, 50.0)
    m = link_sweep(model, mesh_frequencies(model, rpm), H=13, directions="up").result
    torus = np.isfinite(m.secondary_frequency)
    np.testing.assert_array_equal(torus, [False, True, True, True, True, True, True, False])
    for i in (0, 1, 3, 5, 7):
        w = float(m.omega[i])
        integ = LinkIntegrator(model, w, steps_per_period=512)  # the former time_response's steps
        start = integ.start(start_from_harmonics(model, w, 13, m.harmonics[i]))
        poincare = settle(integ, start, tol=0, max_periods=3000, min_periods=3000).section[0]
        x = poincare[1000:] - np.mean(poincare[1000:])
        early, late = np.ptp(x[:1000]) * 1e6, np.ptp(x[1000:]) * 1e6
        print(f"{rpm[i]:.0f} rpm: spread {early:.2e} then {late:.2e} um")
        if not torus[i]:  # converging on a fixed point of the section
            assert late < 0.5 * early and late < 1e-2, (rpm[i], early, late)
            continue
        assert late > 0.5 and late > 0.8 * early, (rpm[i], early, late)  # circling, not decaying
        spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))
        rotation = np.fft.rfftfreq(x.size)[1 + np.argmax(spec[1:])]
        expected = m.secondary_frequency[i] / m.omega[i]
        print(f"{rpm[i]:.0f} rpm: rotation {rotation:.4f} per period, Floquet {expected:.4f}")
        assert abs(rotation - expected) < 4e-3
