"""The speed-ramp integrator (:mod:`nlgrd.timedomain.run_down`) against independent answers.

Model: Kubo's rig (data/case_studies/kubo.toml, 84 DOFs, gyroscopic terms present).

- Constant speed (rate 0): the ramp's recurrence is the steady-state integrator's
  (:func:`nlgrd.timedomain.links.link_time_response`) with the forcing folded into the
  mesh force and the steps grouped in blocks; from that integrator's periodic state it
  must stay on it, every mesh cycle's DTE mean and RMS equal to the steady state's to
  1e-9 (rounding only: the same operations in another order).
- A slow ramp without contact loss follows the linear frequency response: the DTE RMS of
  each cycle against the steady-state linear response at that cycle's speed, computed
  here by a direct solve of the FE matrices per LSTE harmonic (no harmonic balance, no
  time integration), within 0.5 % (measured 0.1 %: the 512-step integration error, 0.03 %
  at constant speed, and the ramp's lag of about the modal time constant 1/(ζ ω_n), 9 ms
  or 4 rpm at 400 rpm/s, on a response that changes by 0.3 % per 4 rpm there). The range
  6700-6420 rpm keeps clear of a narrow resonance of a high LSTE harmonic near 6380 rpm,
  which no ramp at this rate resolves (the ramp rounds its 6 % peak off).
- A jump: at mesh damping ratio 0.02 the down sweep's high branch ends near 7900 rpm
  (harmonic balance on a 25 rpm grid, :func:`nlgrd.nonlinear.models.link_model.link_sweep`, from
  8400 rpm, below a short quasi-periodic band); the ramp, started on the HB orbit at 8400
  rpm, must fall off it no earlier than the HB's last high-branch point and at most four
  grid steps later (a slow passage through a fold is delayed, never early), and halving
  the rate must move the jump by less than 0.5 % of its speed.
"""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest

from nlgrd.errors import ModelError
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.fourier.harmonics import real_to_complex
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.timedomain.links import link_time_response, start_from_harmonics
from nlgrd.timedomain.run_down import ramp_from, run_down

KUBO = Path(__file__).resolve().parent.parent / "data" / "case_studies" / "kubo.toml"
N_P = 25


def kubo(damping_ratio: float | None = None):
    s = load_model(KUBO)
    if damping_ratio is not None:
        s = dc.replace(s, gear_pairs=(dc.replace(s.gear_pairs[0], damping_ratio=damping_ratio),))
    return s, build_link_model(s)


def mesh_frequency(rpm: float) -> float:
    """Kubo's mesh frequency [rad/s] at pinion speed ``rpm`` (25 teeth on the reference shaft)."""
    return 2 * np.pi * rpm / 60 * N_P


@pytest.fixture(scope="module")
def model():
    return kubo()[1]


def linear_rms(model, omega: float) -> float:
    """RMS of the alternating DTE of the linear steady state (mesh at k_h) at ``omega`` [m]."""
    rec, mesh = model.receptance, model.links[0].mesh
    lm, w = rec.model, np.asarray(rec.P[:, 0], dtype=float)
    speed = rec.plan.speed(omega)
    M, D = lm.M.toarray(), (lm.damping(speed) + rec.C_link).toarray()
    K = lm.stiffness(speed).toarray() + mesh.stiffness * np.outer(w, w)
    E = real_to_complex(mesh.lste)
    total = 0.0
    for k in range(1, E.size):
        kw = k * omega
        Q = np.linalg.solve(K - kw**2 * M + 1j * kw * D, w * (mesh.stiffness + 1j * kw * mesh.damping) * E[k])
        total += abs(w @ Q) ** 2 / 2
    return float(np.sqrt(total))


def test_constant_speed_is_the_steady_state_integrator(model):
    omega = mesh_frequency(8000.0)
    tr = link_time_response(model, omega, steps_per_period=128, tol=1e-10)
    assert tr.converged
    res = ramp_from(model, tr.state, omega, 0.0, 300 * 2 * np.pi / omega, steps_per_period=128, block=100)
    d = tr.y[0]
    assert res.dte_rms.size >= 299
    np.testing.assert_allclose(res.omega, omega, rtol=1e-12)
    np.testing.assert_allclose(res.dte_rms, np.std(d), rtol=1e-9)
    np.testing.assert_allclose(res.dte_mean, np.mean(d), rtol=1e-9)
    assert np.all(res.contact_loss_fraction == 0.0)  # this low-branch orbit keeps contact
    frame = res.to_frame()
    assert len(frame) == res.dte_rms.size
    np.testing.assert_allclose(frame["mesh0.dte_rms [um]"], 1e6 * np.std(d), rtol=1e-9)
    np.testing.assert_allclose(frame["shaft_speed [rpm]"], 8000.0, rtol=1e-12)
    assert res.jump() is None  # nothing falls at constant speed
    ax = res.plot()
    assert ax.get_xlabel() == "pinion speed [rpm]" and len(ax.lines) == 1


def test_slow_linear_ramp_follows_the_frequency_response(model):
    top, bottom = mesh_frequency(6700.0), mesh_frequency(6420.0)
    res = run_down(model, top, bottom, 400.0 * mesh_frequency(1.0), steps_per_period=512)
    assert np.all(res.contact_loss_fraction == 0.0)  # the premise: linear throughout
    pick = slice(0, None, 40)
    ref = np.array([linear_rms(model, w) for w in res.omega[pick]])
    err = np.abs(res.dte_rms[pick] / ref - 1)
    print(
        f"DTE RMS {1e6 * ref.min():.3f} .. {1e6 * ref.max():.3f} um; "
        f"largest error against the FRF {err.max():.2e}"
    )
    assert ref.max() > 1.05 * ref.min()  # the response changes along the ramp
    assert err.max() < 5e-3


def test_ramp_jump_matches_the_fold_and_is_rate_converged():
    system, m = kubo(damping_ratio=0.02)
    rpm = np.arange(11000.0, 7600.0 - 1, -25.0)  # from above the resonance: on the high branch
    res = link_sweep(m, mesh_frequency(rpm), H=9, directions="down", period=1, stability=False)
    hb = res.result
    order = np.argsort(-hb.omega)
    x, y = hb.omega[order] / mesh_frequency(1.0), res.links["mesh0.dte_rms [m]"].to_numpy()[order]
    below = np.nonzero(x <= 8400.0 + 1e-6)[0]
    k = below[0] + int(np.nonzero(y[below][1:] < 0.5 * y[below][:-1])[0][0])
    fold = x[k]  # the last high-branch point of the HB down sweep
    i0 = below[0]
    s0 = start_from_harmonics(m, hb.omega[order][i0], 9, hb.harmonics[order][i0])
    per_rpm = mesh_frequency(1.0)
    jumps = []
    for rate_rpm in (400.0, 200.0):
        res = run_down(m, mesh_frequency(8400.0), mesh_frequency(7600.0), rate_rpm * per_rpm, state0=s0)
        jumps.append(res.jump() / per_rpm)
    print(f"HB fold between {x[k + 1]:.0f} and {fold:.0f} rpm; ramp jumps at 400 and 200 rpm/s: {jumps}")
    assert abs(jumps[0] - jumps[1]) < 0.005 * fold
    assert fold - 4 * 25.0 < jumps[1] <= fold + 1.0


def test_bad_ramps_are_refused(model):
    w = mesh_frequency(8000.0)
    with pytest.raises(ModelError, match="rate"):
        run_down(model, w, 0.5 * w, 0.0)
    with pytest.raises(ModelError, match="omega_stop"):
        run_down(model, w, 2 * w, 1.0)
