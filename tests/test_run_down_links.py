"""The speed ramp on models of several links and with unbalance (issue 33, "every analysis
works on any model"), against independent answers.

- The general step (Newton on the link coordinates, :func:`nlgrd.timedomain.links.newton_links`,
  the forcing from :class:`nlgrd.timedomain.ramp_links.RampForcing`) against the one-mesh
  closed form on Kubo's rig, under a ramp: the same recurrence, so the same numbers to
  rounding (1e-12 relative).
- Rate 0 on the idler train (two meshes, 198 DOFs) and on the geared two-shaft model with a
  bearing clearance: every base cycle equals a period of the constant-speed integrator
  (:class:`nlgrd.timedomain.links.LinkIntegrator`, which samples the forcing from the
  model's harmonics instead of the ramp's polynomial in ω), and the stable harmonic-balance
  orbit at that speed within the time step's error, measured as the change from 128 to
  256 steps per period.
- Unbalance (the rub rotor, its ring moved out of reach: a linear rotor): at rate 0 the
  ramp equals the directly solved unbalance response; run down slowly through the first
  critical speed, the largest whirl radius comes just below the linear frequency
  response's peak (a ramp lags) and halving the rate moves it towards the peak. Had the
  unbalance's phase been ω(t) t instead of ∫ω dt, its frequency would be ω - 2 rate t and
  the peak would come at the wrong speed.
"""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from link_comparison import damped

from nlgrd.errors import ModelError
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.rotor.assembly import assemble
from nlgrd.timedomain.links import LinkIntegrator, link_time_response, start_from_harmonics
from nlgrd.timedomain.run_down import ramp_from, run_down

ROOT = Path(__file__).resolve().parents[1]
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
RUB = ROOT / "data" / "models" / "rub_rotor.toml"


#: harmonics of the harmonic-balance orbit (the LSTE holds 30) and steps per period of the ramp
H_HB, STEPS = 30, (128, 256, 512)


def per_period(model, omega: float, state: tuple, ns: int, periods: int) -> list:
    """The link coordinates of ``periods`` periods of the constant-speed integrator from
    ``state`` (the reference recurrence)."""
    integ = LinkIntegrator(model, omega, steps_per_period=ns)
    s, out = integ.start(state), []
    for _ in range(periods):
        y, s = integ.period(s)
        out.append(y)
    return out


def cycle_metrics(model, y: np.ndarray) -> dict:
    """The ramp's per-cycle outputs of one period of link coordinates (d, ns)."""
    out = {}
    for lk, sl in zip(model.links, model.receptance.slices, strict=True):
        if lk.kind == "gear mesh":
            out[lk.name] = {"dte_rms [m]": np.std(y[sl][0]), "dte_mean [m]": np.mean(y[sl][0])}
        else:
            r = np.hypot(*y[sl])
            out[lk.name] = {"displacement_rms [m]": np.sqrt(np.mean(r * r)), "displacement_max [m]": r.max()}
    return out


def test_general_step_is_the_closed_form_step_on_one_mesh():
    """Kubo's rig, 400 rpm/s from the steady state at 8000 rpm for 150 mesh cycles: the
    Newton step with the forcing in harmonics of ω equals the closed-form scalar step with
    the LSTE forcing c_m ω de/dθ to 1e-12 (measured 1.8e-13 on the DTE RMS): the same recurrence, so the
    closed form is kept as the fast path."""
    model = build_link_model(load_model(KUBO))
    per_rpm = 2 * np.pi / 60 * 25
    omega = 8000.0 * per_rpm
    tr = link_time_response(model, omega, steps_per_period=128, tol=1e-8)
    args = (model, tr.state, omega, 400.0 * per_rpm, 150 * 2 * np.pi / omega)
    fast = ramp_from(*args, block=100)
    newton = ramp_from(*args, block=100, link_solve="newton")
    for q in ("dte_rms [m]", "dte_mean [m]", "elastic_force_max [N]"):
        a, b = fast.outputs["mesh0"][q], newton.outputs["mesh0"][q]
        print(q, np.max(np.abs(a / b - 1)))
        np.testing.assert_allclose(a, b, rtol=1e-12)
    np.testing.assert_array_equal(fast.omega, newton.omega)
    assert fast.rpm[-1] < 8000.0 - 0.5 * 400.0 * fast.time[-1]  # the speed did fall


@pytest.mark.parametrize(
    ("name", "hz"),
    [("idler_train", 1000.0), ("two_shaft_clearance", 700.0)],
)
def test_rate_zero_is_the_steady_state_and_the_harmonic_balance(name, hz):
    """Rate 0 on a model of several links: (1) each base cycle is the constant-speed
    integrator's period from the same state to 1e-9 (rounding; measured 1e-11 over 5
    periods); (2) after 20 periods from the harmonic-balance orbit (H 15, Floquet-stable),
    the ramp's last cycle equals the orbit's outputs within twice the time step's error
    estimate |r_128 - r_256| (second order: the 256-step error is a third of it) plus 2e-3
    (the orbit's residual drift over 20 periods, tests/link_comparison.py)."""
    model = build_link_model(damped(name))
    w = 2 * np.pi * hz
    hb = link_sweep(model, np.array([w]), H=H_HB, directions="up", jump="none", period=1)
    assert hb.result.converged[0] and hb.result.stable[0]
    s0 = start_from_harmonics(model, w, H_HB, hb.result.harmonics[0])
    got = {}
    for ns in STEPS:
        tr = link_time_response(
            model, w, state0=s0, steps_per_period=ns, tol=1e-14, max_periods=20, min_periods=20
        )
        res = ramp_from(model, tr.state, w, 0.0, 5 * 2 * np.pi / w, steps_per_period=ns, block=ns)
        ref = [cycle_metrics(model, y) for y in per_period(model, w, tr.state, ns, 5)]
        assert res.omega.size >= 4
        for k in range(res.omega.size):
            for lk, outs in ref[k].items():
                for q, v in outs.items():
                    np.testing.assert_allclose(res.outputs[lk][q][k], v, rtol=1e-9, err_msg=f"{lk}.{q}")
        got[ns] = {lk: {q: v[-1] for q, v in outs.items()} for lk, outs in res.outputs.items()}
    row = hb.links.iloc[0]
    for lk in got[256]:
        for q in ("dte_rms [m]", "displacement_max [m]"):
            if q not in got[256][lk]:
                continue
            r = [got[ns][lk][q] for ns in STEPS]
            h = row[f"{lk}.{q}"]
            print(
                f"{name} {hz} Hz {lk}.{q}: HB {h:.6g}, ramp {[f'{v:.6g}' for v in r]}; "
                f"|HB/r_512 - 1| {abs(h / r[2] - 1):.2e}, |r_256/r_512 - 1| {abs(r[1] / r[2] - 1):.2e}"
            )
            gaps = [abs(h / v - 1) for v in r]
            assert gaps[0] > gaps[1] > gaps[2] or gaps[2] < 1e-3  # converging on the orbit
            assert gaps[2] <= 2 * abs(r[1] / r[2] - 1) + 2e-3


def unbalance_rotor():
    """The rub rotor with its ring at 5 mm: the clearance never closes, a linear rotor."""
    s = load_model(RUB)
    return s, build_link_model(
        dc.replace(s, bearing_clearances=(dc.replace(s.bearing_clearances[0], clearance=5e-3),))
    )


def linear_radius(system, rpm: float) -> float:
    """Largest whirl radius of the disk of the linear unbalance response at ``rpm`` [m],
    solved directly from the assembled matrices (as tests/test_shipped_clearance_models.py)."""
    lin = assemble(system, mesh_stiffness=False, mesh_damping=False)
    u = system.unbalance[0]
    dofs = system.dofs.node_dofs(u.shaft, u.node)
    speed = rpm * np.pi / 30
    F = np.zeros(lin.n_dofs, dtype=complex)
    amp = u.amount * speed**2 * np.exp(1j * u.phase)
    F[dofs[1]], F[dofs[2]] = amp, -1j * amp
    q = spla.spsolve((lin.stiffness(speed) + 1j * speed * lin.damping(speed) - speed**2 * lin.M).tocsc(), F)
    th = np.linspace(0, 2 * np.pi, 4096, endpoint=False)
    return float(
        np.max(np.hypot(np.real(q[dofs[1]] * np.exp(1j * th)), np.real(q[dofs[2]] * np.exp(1j * th))))
    )


def test_unbalance_at_rate_zero_is_the_linear_response():
    """Rate 0 at 3000 rpm: every revolution equals the constant-speed integrator's period
    (1e-9) and the direct linear solve's whirl radius within 1e-3 (the 256-step HHT-α
    error, measured 1e-4)."""
    system, model = unbalance_rotor()
    w = 3000.0 * np.pi / 30
    tr = link_time_response(model, w, steps_per_period=256, tol=1e-10)
    assert tr.converged
    res = ramp_from(model, tr.state, w, 0.0, 6 * 2 * np.pi / w, steps_per_period=256, block=256)
    ref = [cycle_metrics(model, y) for y in per_period(model, w, tr.state, 256, 6)]
    r = res.outputs["rub"]["displacement_max [m]"]
    for k in range(r.size):
        np.testing.assert_allclose(r[k], ref[k]["rub"]["displacement_max [m]"], rtol=1e-9)
    lin = linear_radius(system, 3000.0)
    print(f"whirl radius {r[0]:.6e} m, linear {lin:.6e} m")
    np.testing.assert_allclose(r, lin, rtol=1e-3)
    assert res.link == "rub" and res.kinds["rub"] == "bearing clearance"
    assert "rub.displacement_max [um]" in res.to_frame()
    assert res.jump() is None and "rub" in res.plot().get_ylabel()  # per link, no mesh needed
    with pytest.raises(ModelError, match="not a gear mesh"):
        res.dte_rms  # noqa: B018


def test_unbalance_against_the_rub_ring_at_rate_zero_is_the_integrator():
    """The rub rotor as shipped at 4100 rpm, the disk rubbing its 0.2 mm ring (the unbalance
    and the contact act on the same node; started on the harmonic-balance up sweep's
    stable orbit of full annular rub, H 13): every revolution equals the constant-speed
    integrator's period from the same state to 1e-9 (rounding)."""
    model = build_link_model(load_model(RUB))
    rpm = np.arange(3800.0, 4101.0, 50.0)  # up the resonance onto the rubbing branch
    hb = link_sweep(model, rpm * np.pi / 30, H=13, directions="up", jump="none", period=1)
    w = hb.result.omega[-1]
    assert hb.links["rub.contact_fraction [-]"].iloc[-1] == 1.0 and hb.result.stable[-1]
    s0 = start_from_harmonics(model, w, 13, hb.result.harmonics[-1])
    tr = link_time_response(model, w, state0=s0, steps_per_period=128, max_periods=20, min_periods=20)
    res = ramp_from(model, tr.state, w, 0.0, 6 * 2 * np.pi / w, steps_per_period=128, block=128)
    ref = [cycle_metrics(model, y) for y in per_period(model, w, tr.state, 128, 6)]
    out = res.outputs["rub"]
    assert np.all(out["contact_fraction [-]"] > 0.5)  # the premise: in contact
    for k in range(out["displacement_max [m]"].size):
        for q in ("displacement_max [m]", "displacement_rms [m]"):
            np.testing.assert_allclose(out[q][k], ref[k]["rub"][q], rtol=1e-9)


def test_run_down_through_the_critical_speed_lags_by_the_rate():
    """A run-down 4400 -> 3600 rpm through the first critical speed (linear response peak
    near 3990 rpm on a 0.5 rpm grid): the largest whirl radius comes below the peak (the
    ramp lags) and halving the rate brings it closer, by about 1/√2: the delay of the
    largest response of a slow linear passage through a resonance grows as the square
    root of the rate (Lewis 1932, Trans. ASME 54:253; measured 107 and 70 rpm, ratio 0.65).
    64 steps per revolution: the HHT-α period error (ωΔt)²/12 = 8e-4 moves the resonance
    by 3 rpm, far below the lags. A phase ω(t) t instead of ∫ω dt would put the forcing at
    ω - 2 rate t and the peak above the resonance (measured: 4117 and 4142 rpm, a lead that grows
    as the rate falls)."""
    system, model = unbalance_rotor()
    rpm = np.arange(3900.0, 4100.0, 0.5)
    peak = rpm[np.argmax([linear_radius(system, x) for x in rpm])]
    per_rpm = np.pi / 30
    lags = []
    for rate in (200.0, 100.0):
        res = run_down(model, 4400.0 * per_rpm, 3600.0 * per_rpm, rate * per_rpm, steps_per_period=64)
        r = res.outputs["rub"]["displacement_max [m]"]
        lags.append(peak - res.rpm[np.argmax(r)])
        print(
            f"{rate} rpm/s: ramp peak at {res.rpm[np.argmax(r)]:.1f} rpm, "
            f"radius {r.max():.3e}; FRF peak {peak}"
        )
    assert 0 < lags[1] < lags[0] < 200.0
    assert 0.5 < lags[1] / lags[0] < 0.85


def test_hysteretic_damping_is_refused_in_one_line():
    """Hysteretic damping has no time-domain form: one ModelError naming the field."""
    s = load_model(KUBO)
    lossy = []
    for sh in s.shafts:
        els = tuple(dc.replace(e, material=dc.replace(e.material, loss_factor=0.01)) for e in sh.elements)
        lossy.append(dc.replace(sh, elements=els))
    model = build_link_model(dc.replace(s, shafts=tuple(lossy)))
    assert model.receptance.model.hysteretic_parts
    with pytest.raises(ModelError, match="hysteretic") as err:
        ramp_from(model, (None, None, None), 1000.0, 1.0, 0.1)
    assert err.value.key == "loss_factor" and "\n" not in str(err.value)


def test_ramp_jump_on_a_mesh_and_clearance_model_approaches_the_fold():
    """The geared two-shaft model with a journal clearance (two links), mesh damping ratio
    0.02: the harmonic-balance down sweep (H 9, 25 Hz grid from 4000 Hz) climbs the mesh
    resonance's high branch to 3325 Hz and does not converge below it down to 3200 Hz
    (the fold). Ramps from its orbit at 3400 Hz, after 10 periods at constant speed, at
    2000 and 1000 Hz/s of mesh frequency: each falls off the high branch after the last
    high-branch point, never before it (a slow passage through a fold is delayed, never
    early), within four grid steps at the slower rate, and the slower ramp falls nearer
    the fold (measured 3254 and 3286 Hz; 3279-3295 Hz at the slower rate across the
    OpenBLAS kernels: the passage ends in the band the harmonic balance does not resolve,
    where rounding moves the jump by a few cycles; 27 s)."""
    s = load_model(ROOT / "data" / "models" / "two_shaft_clearance.toml")
    model = build_link_model(dc.replace(s, gear_pairs=(dc.replace(s.gear_pairs[0], damping_ratio=0.02),)))
    hz = np.arange(4000.0, 3149.0, -25.0)
    hb = link_sweep(model, 2 * np.pi * hz, H=9, directions="down", period=1, stability=False, jump="none")
    order = np.argsort(-hb.result.omega)
    x = hb.result.omega[order] / (2 * np.pi)
    y = hb.links["mesh0.dte_rms [m]"].to_numpy()[order]
    k = int(np.nonzero(~(y[1:] > 0.5 * y[:-1]))[0][0])  # the last point before a fall or a failure
    fold = x[k]
    i0 = int(np.argmin(np.abs(x - 3400.0)))
    s0 = start_from_harmonics(model, hb.result.omega[order][i0], 9, hb.result.harmonics[order][i0])
    w0 = 2 * np.pi * x[i0]
    tr = link_time_response(model, w0, state0=s0, steps_per_period=128, max_periods=10, min_periods=10)
    jumps = []
    for rate in (2000.0, 1000.0):
        res = ramp_from(model, tr.state, w0, 2 * np.pi * rate, 2 * np.pi * 200.0 / (2 * np.pi * rate))
        assert res.outputs["B1"]["contact_fraction [-]"].min() > 0.5  # the journal on its clearance
        jumps.append(res.jump() / (2 * np.pi))
    print(f"HB last high-branch point {fold:.0f} Hz; ramp jumps at 2000 and 1000 Hz/s: {jumps}")
    assert jumps[0] < jumps[1] <= fold + 1.0
    assert fold - 4 * 25.0 < jumps[1]


def test_two_stage_train_cycles_are_base_periods():
    """The two-stage train (base a common divisor: mesh0 at base harmonic 5, mesh1 at 2;
    their LSTE up to harmonics 150 and 60): at rate 0 each cycle of the ramp is one base
    period of the constant-speed integrator from the same state, to 1e-9 (rounding), with
    128 steps per period of the faster mesh."""
    model = build_link_model(damped("two_stage"))
    w = 2 * np.pi * 358.75
    ns = 128 * 5
    tr = link_time_response(model, w, steps_per_period=ns, max_periods=4, min_periods=4)
    res = ramp_from(model, tr.state, w, 0.0, 4 * 2 * np.pi / w, steps_per_period=ns, block=ns)
    ref = [cycle_metrics(model, y) for y in per_period(model, w, tr.state, ns, 4)]
    assert res.omega.size >= 3 and set(res.outputs) == {"mesh0", "mesh1"}
    for k in range(res.omega.size):
        for lk in ("mesh0", "mesh1"):
            for q in ("dte_rms [m]", "dte_mean [m]"):
                np.testing.assert_allclose(res.outputs[lk][q][k], ref[k][lk][q], rtol=1e-9)
    np.testing.assert_allclose(res.rpm, 358.75 * 60 * 0.2, rtol=1e-12)  # the reference shaft
    frame = res.to_frame()
    assert {"mesh1.dte_rms [um]", "base_frequency [Hz]", "shaft_speed [rpm]"} <= set(frame)
    assert res.plot(link="mesh1").get_ylabel() == "RMS of alternating DTE [µm]"
    with pytest.raises(ModelError, match="no link"):
        res.jump(link="B9")


def test_unbalance_force_under_a_ramp_is_the_inertial_force_of_the_mass():
    """The ramp's unbalance force (:class:`nlgrd.timedomain.ramp_links.RampForcing`, found
    from the model's harmonics at constant speeds) against the inertial force of the mass
    itself, -m d²r/dt² with r = e (cos φ, sin φ), φ = θ + phase:
    m e (φ'² cos φ + φ'' sin φ, φ'² sin φ - φ'' cos φ), at a slow speed and a fast change
    (φ''/φ'² up to 0.5, so the tangential term is half the force) to 1e-12 of the force."""
    from nlgrd.timedomain.ramp_links import RampForcing

    system, model = unbalance_rotor()
    u = system.unbalance[0]
    force = RampForcing(model, 10.0)
    theta = np.linspace(0.0, 7.0, 29)
    omega = np.linspace(10.0, 14.0, 29)
    acc = -50.0
    f = force.at(theta, omega, acc)[:, force.d :]
    phi = theta + u.phase
    me = u.amount
    ref = me * np.stack(
        [omega**2 * np.cos(phi) + acc * np.sin(phi), omega**2 * np.sin(phi) - acc * np.cos(phi)], axis=1
    )
    assert list(force.dofs) == list(system.dofs.node_dofs(u.shaft, u.node)[1:3])
    np.testing.assert_allclose(f, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
