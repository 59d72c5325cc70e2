"""The linear bearings' outputs of a time answer (issue 35; nlgrd.timedomain.bearing_record
and time_answer's bearing statistics), on Kahraman & Blankenship's rig
(data/case_studies/kahraman_blankenship.toml, four linear bearings).

- The bearing record is the HHT-α recurrence itself: its displacements, taken from the
  period map's affine form after the period ran, are those of stepping every DOF
  (``LinkIntegrator.stepped``, the same recurrence summed in another order: rounding,
  measured 1e-11 relative, held to 1e-9), and its velocities, the Newmark update unrolled
  over the period, are the velocities of the stepped state (same tolerance).
- At a STABLE periodic point (3500 Hz, below the band where the orbit is lost) a time
  answer started on the harmonic-balance orbit settles on that orbit, so its bearing
  outputs must be the harmonic balance's row (recovered from the solved harmonics by
  ``bearing_response``, an independent path: receptances, not integration). The HB is
  solved at H = 20, its bearing outputs within 2e-4 of H = 10 (measured). The start
  leaves a slow transient (the discrete orbit differs from the HB's), which biases a
  record maximum: 80 periods are run first and the answer continues from their end. The
  discrepancy allowed at 256 steps a period is the integrator's discretisation error by
  step halving: HHT-α is second order, so the error at 256 steps is about a third of the
  difference between 128 and 256 steps; the bound is that whole difference (a factor 3
  of margin), plus two of the answer's own standard uncertainties and the HB's
  truncation error (H 10 against 20). Measured: every output within 1.5e-3 relative at
  256 steps (the RMS values converge as Δt²: 1.3e-3 at 256, 3.4e-4 at 512 steps), held
  to 3e-3.
"""

from __future__ import annotations

import numpy as np
import pytest

import nlgrd
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.timedomain.bearing_record import BearingRecord
from nlgrd.timedomain.links import LinkIntegrator
from nlgrd.timedomain.sweep_answers import base_harmonics
from nlgrd.timedomain.time_answer import time_answer

KB = "data/case_studies/kahraman_blankenship.toml"
FIELDS = {
    "displacement_max [m]": "displacement_max",
    "displacement_rms [m]": "displacement_rms",
    "displacement_mean [m]": "displacement_mean",
    "force_mean [N]": "force_mean",
    "force_rms [N]": "force_rms",
    "force_max [N]": "force_max",
    "force_amplitude [N]": "force_amplitude",
}


@pytest.fixture(scope="module")
def kb():
    system = nlgrd.load(KB)
    return system, build_link_model(system)


def test_bearing_record_is_the_full_dof_recurrence(kb):
    _, model = kb
    integ = LinkIntegrator(model, 2 * np.pi * 3600.0, steps_per_period=128)
    rec = BearingRecord(integ)
    assert rec.dofs.size == 8
    N = integ.N
    s = integ.start()
    for _ in range(3):
        y, q, s_end = rec.period(s)
        y_ref, q_ref, s_ref = integ.stepped(s, output_dofs=rec.dofs)
        scale = np.abs(q_ref).max()
        assert np.abs(q - q_ref).max() <= 1e-9 * scale
        assert np.abs(y - y_ref).max() <= 1e-9 * np.abs(y_ref).max()
        v = rec.velocities(q, s)
        _, v_ref, _ = integ.stepped(s, output_dofs=N + rec.dofs)  # the state's velocity part
        assert np.abs(v - v_ref).max() <= 1e-9 * np.abs(v_ref).max()
        f = rec.forces(q, v)
        assert f.shape == q.shape and np.all(np.isfinite(f))
        s = s_end


def test_time_answer_bearings_equal_the_harmonic_balance_at_a_stable_point(kb):
    system, model = kb
    # the mesh-coordinate sweep: its bearing table has displacement_mean, which the link
    # sweep's has not (its force_amplitude: tests/test_result_schema.py)
    from nlgrd.nonlinear.models.geared import geared_sweep

    hb = {H: geared_sweep(system, 2 * np.pi * np.array([3500.0]), H=H, directions="up") for H in (10, 20)}
    res = hb[20]
    assert not res.mesh.no_stable[0]  # stable: the time answer has an orbit to settle on
    z = base_harmonics(res.mesh.harmonics[0], int(res.mesh.base))
    w = float(res.mesh.omega[0])
    ta = {}
    for sp in (128, 256):  # 80 periods to let the start's slow transient decay, 80 recorded
        warm = time_answer(
            model, w, harmonics=z, periods=80, max_periods=80, steps_per_period=sp, perturbation=0.0
        )
        ta[sp] = time_answer(model, w, state0=warm.state, periods=80, max_periods=80, steps_per_period=sp)
    worst = 0.0
    for j, name in enumerate(res.bearing_names):
        for key, field in FIELDS.items():
            ref = float(getattr(res.bearings, field)[0, j])
            trunc = abs(ref - float(getattr(hb[10].bearings, field)[0, j]))
            fine, coarse = ta[256].bearings[f"{name}.{key}"], ta[128].bearings[f"{name}.{key}"]
            bound = abs(coarse.value - fine.value) + 2 * fine.uncertainty + trunc
            assert abs(fine.value - ref) <= bound, (name, key, fine, coarse, ref)
            worst = max(worst, abs(fine.value - ref) / ref)
    assert worst < 3e-3, worst  # the figure the docstring states (1.5e-3 measured)
