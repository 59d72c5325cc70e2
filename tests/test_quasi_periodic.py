"""Two-frequency harmonic balance (nlgrd.nonlinear.hb.quasi_periodic) against time integration.

The reference is independent: scipy's DOP853 integration of the single-DOF gear pair with
backlash, m δ'' + c (δ' - e') + k f(δ - e) = W_0 + F₂ cos ω₂ t, e = e₁ cos ω₁ t, ω₂/ω₁
irrational, from rest to t = 100 T₂ (the transient decays as e^{-ζ ω_n t}: e^{-0.05 · 100 · 11} ≈ 1e-24,
so only the torus is left), then compared over 40 T₂. A forced torus has its phases fixed
by the forcing (θ₁ = ω₁ t, θ₂ = ω₂ t), so the harmonic balance gives δ(t) itself.
The contact is lost 11 % of the time: the law is non-smooth on the torus.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nlgrd.errors import ModelError
from nlgrd.nonlinear.hb import quasi_periodic as qp
from nlgrd.nonlinear.hb import torus_grid as tg
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.laws.force_laws import BacklashMesh

M, K, ZETA, B, W0, E1, F2 = 1.0, 1.0, 0.05, 0.5, 1.0, 0.25, 0.7
C = 2 * ZETA
W1, W2 = 1.6, 0.4 * np.sqrt(2)


def _model():
    law = BacklashMesh(K, B, np.array([0.0, E1, 0.0]), damping=C)
    red = ReducedModel.from_matrices([[M]], [[C]], [[0.0]], [[1.0]], [W0], [law])
    return qp.TorusModel.from_reduced(red, secondary_force=np.array([F2])), law


def _solve(model, H, start=None):
    grid = tg.TorusGrid(H, H, *tg.default_grid(H, H))
    if start is None:
        Y0 = np.zeros((1, grid.n_terms), dtype=complex)
        Y0[0, 0] = W0 / K + B
    else:
        Y0 = tg.resize(start.Y, start.grid, grid)
    sol = qp.solve_torus(model, W1, grid, Y0, W2)
    assert sol.converged, sol
    return sol


@pytest.fixture(scope="module")
def reference():
    def rhs(t, u):
        d, v = u
        e, ed = E1 * np.cos(W1 * t), -E1 * W1 * np.sin(W1 * t)
        x = d - e
        f = K * (x - B) if x > B else (K * (x + B) if x < -B else 0.0)
        return [v, (W0 + F2 * np.cos(W2 * t) - C * (v - ed) - f) / M]

    T2 = 2 * np.pi / W2
    t0, t1 = 100 * T2, 140 * T2
    sol = solve_ivp(
        rhs,
        (0, t1),
        [W0 / K + B, 0],
        method="DOP853",
        rtol=1e-10,
        atol=1e-12,
        dense_output=True,
        max_step=0.2,
    )
    ts = np.linspace(t0, t1, 20001)
    return ts, sol.sol(ts)[0]


def test_tangent_block_is_the_aft_jacobian():
    # the O(|K|²) assembly against the plain product forward · diag(t) · inverse
    g = tg.TorusGrid(3, 2, 16, 8)
    t = np.random.default_rng(0).standard_normal(g.theta1.size)
    plain = (g.forward * t[None, :]) @ g.inverse
    assert np.max(np.abs(g.tangent_block(t) - plain)) < 1e-13 * np.max(np.abs(plain))


def test_forced_torus_matches_time_integration(reference):
    ts, y = reference
    model, _ = _model()
    coarse = _solve(model, 12)
    sol = _solve(model, 16, coarse)
    g = sol.grid
    yh = np.real(np.exp(1j * (np.outer(ts, g.k1) * W1 + np.outer(ts, g.k2) * W2)) @ sol.Y[0])
    x = y - E1 * np.cos(W1 * ts)
    assert 0.05 < np.mean(np.abs(x) <= B) < 0.3  # the contact is lost: the case is nonlinear
    # measured: 0.07 % of the peak-to-peak at H = 16 (the truncation of a non-smooth law)
    assert np.max(np.abs(y - yh)) < 5e-3 * np.ptp(y)
    assert abs(np.std(yh) - np.std(y)) < 2e-3 * np.std(y)  # measured 4e-4
    # the torus average (grid) against the window's: the 40 T₂ window itself is off by ~3e-4
    assert abs(np.std(g.samples(sol.Y)) - np.std(y)) < 2e-3 * np.std(y)


def test_grid_too_coarse_is_refused():
    with pytest.raises(ModelError, match="does not resolve"):
        tg.TorusGrid(8, 4, 16, 9)


# --------------------------------------------------------------------------------------
# An autonomous torus: the two-DOF oscillator with a contact stop of
# tests/test_two_dof_torus.py, beyond its Neimark-Sacker points (2.62-2.64 and 3.32-3.34 ω_1).
# Reference: the exact piecewise-linear flow of that test (its own check against DOP853),
# started from the static state at the frequency itself, 1500 periods, the last 500 states
# at the period's end (the Poincaré section θ₁ = 0) kept. The torus's section is the curve
# x₂(0, θ₂); its rotation number is ω₂/ω₁. Measured at H = (9, 4):
#   2.64 ω_1: ρ 0.300041 (flow 0.300063), section min/mean/max -32.21/-14.421/4.06 µm
#             (flow -32.36/-14.427/4.22), spread 36.27 µm (flow 36.58);
#   3.32 ω_1: ρ 0.298981 (flow 0.298971), spread 7.311 µm (flow 7.348), mean -4.1131 (-4.1196).
# At H = (15, 6) the spread at 2.64 moves to 36.43 µm: toward the flow, by the size of the
# remaining difference (truncation, not a different torus).
# --------------------------------------------------------------------------------------


def _rotation(x: np.ndarray) -> float:
    """Rotation per sample of Poincaré samples: Hann-windowed spectral peak refined by a
    parabola through the log-amplitudes (accurate to ~1e-2 of a bin, 1/500 here)."""
    x = x - np.mean(x)
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))
    j = 2 + int(np.argmax(spec[2:-1]))
    a, b, c = np.log(spec[j - 1 : j + 2])
    return float((j + 0.5 * (a - c) / (a - 2 * b + c)) / x.size)


@pytest.mark.parametrize("ratio", [2.64, 3.32])
def test_autonomous_torus_matches_exact_flow(ratio):
    from test_period_doubling import two_dof_model  # noqa: PLC0415
    from test_two_dof_torus import W1, poincare_sweep  # noqa: PLC0415

    from nlgrd.nonlinear.fourier.harmonics import real_to_complex  # noqa: PLC0415
    from nlgrd.nonlinear.hb.solvers import solve  # noqa: PLC0415
    from nlgrd.nonlinear.stability.floquet_mode import dominant_floquet_mode  # noqa: PLC0415

    red = two_dof_model(1)
    model = qp.TorusModel.from_reduced(red)
    w = ratio * W1
    H1, H2 = 9, 4
    orbit = solve(red.at(w, H1))
    assert orbit.converged
    mu = dominant_floquet_mode(red.linear_state_space(w), red.nonlinearities, orbit.harmonics, w).multiplier
    assert abs(mu) > 1 and abs(mu.imag) > 0.1  # a complex pair outside: a torus is born
    Yp = real_to_complex(orbit.harmonics[0])[None, :]
    w2 = qp.secondary_from_multiplier(mu, w)
    grid = tg.TorusGrid(H1, H2, *tg.default_grid(H1, H2))
    shape = qp.critical_shape(model, w, Yp, w2, H1)
    start = qp.periodic_start(Yp, grid, shape, 0.02 * np.abs(Yp[0, 1:]).max())
    sol = qp.solve_torus(model, w, grid, start, w2)
    assert sol.converged and sol.amplitude > 0.1  # a torus, not the periodic orbit

    th2 = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    section = np.real(np.exp(1j * np.outer(th2, grid.k2)) @ sol.Y[0])
    flow = poincare_sweep([ratio])[-1][1000:, 1]
    # ρ: measured differences 2e-5 and 1e-5; the spectral estimate is good to ~2e-5
    assert abs(sol.secondary / w - _rotation(flow)) < 2e-4
    # the section curve: spread within 2 % (measured 0.8 and 0.5 %, the truncation at H (9, 4)),
    # its mean within 0.5 % (measured 0.04 and 0.16 %)
    assert abs(np.ptp(section) / np.ptp(flow) - 1) < 0.02
    assert abs(np.mean(section) - np.mean(flow)) < 5e-3 * abs(np.mean(flow))
    assert abs(section.min() - flow.min()) < 0.02 * np.ptp(flow)


def test_kubo_torus_against_stored_time_integration():
    """Kubo's FE rig (Table 1 damping) at 13 750 and 13 850 rpm, up sweep, H = 13: the
    periodic orbit is Neimark-Sacker unstable (|μ| 1.018 and 1.049). The torus of its link
    model (one mesh: :class:`nlgrd.nonlinear.tracing.link_torus.LinkTorus`, the default of
    ``torus_sweep``). Reference: the HHT-α integration of the full FE model by
    benchmarks/torus_kubo_reference.py (3000 periods of transient, then 500 blocks of 6
    periods; its CSV holds every column), not a harmonic balance. Tolerances: the issue's
    1 % (RMS DTE, largest mesh force) and 0.5 % (ω₂); measured 1.4e-5 and 2.9e-4, -2.9e-4
    and -1.8e-3, 2.0e-3 and 2.2e-3."""
    from pathlib import Path  # noqa: PLC0415

    from nlgrd.io.model_file import load_model  # noqa: PLC0415
    from nlgrd.nonlinear.models.link_model import build_link_model  # noqa: PLC0415
    from nlgrd.nonlinear.tracing.torus_sweep import torus_sweep  # noqa: PLC0415

    kubo = Path(__file__).resolve().parent.parent / "data" / "case_studies" / "kubo.toml"
    model = build_link_model(load_model(kubo))
    res = torus_sweep(model, rpm=[13750.0, 13850.0], H=13, H2=4, check=False)
    assert res.converged.all()
    frame = res.to_frame()
    reference = {  # time integration: RMS DTE [um], largest W [N], ω₂ [Hz]
        "mesh0.dte_rms [um]": [5.028608, 4.847337],
        "mesh0.force_max [N]": [4970.716546, 5040.116261],
        "secondary_frequency [Hz]": [1292.366492, 1194.422354],
    }
    for column, rtol in (
        ("mesh0.dte_rms [um]", 0.01),
        ("mesh0.force_max [N]", 0.01),
        ("secondary_frequency [Hz]", 0.005),
    ):
        np.testing.assert_allclose(frame[column], reference[column], rtol=rtol, err_msg=column)
    assert (frame["response"] == "quasi-periodic").all()
    assert 0.05 < frame["mesh0.contact_loss_fraction [-]"].min() < 0.5  # the teeth separate on the torus
    # bearing 0's largest radial force at 13 850 rpm: the integration's (q of its DOFs, q' by
    # central differences) 5520.88 N; measured -0.57 %
    bearing = frame["bearing 0 (shaft 0, node 1).force_max [N]"].iloc[1]
    assert abs(bearing / 5520.880924 - 1) < 0.01


def test_bearing_recovery_of_a_periodic_orbit_matches_the_sweep():
    """A periodic orbit written as a torus (its k₂ > 0 part zero): the bearing forces of
    :func:`nlgrd.nonlinear.tracing.link_torus.torus_link_bearings` (Z(Ω)⁻¹ P κ(Ω) Y per
    frequency beyond the k₂ = 0 row) against the link sweep's
    (:func:`nlgrd.nonlinear.results.bearing_loads.link_bearing_outputs`, the periodic
    recovery). Measured 4e-6: the sampled maximum (1024 samples) against the sweep's
    refined one."""
    from pathlib import Path  # noqa: PLC0415

    from nlgrd.io.model_file import load_model  # noqa: PLC0415
    from nlgrd.nonlinear.fourier.harmonics import real_to_complex  # noqa: PLC0415
    from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep  # noqa: PLC0415
    from nlgrd.nonlinear.results.bearing_loads import bearing_names  # noqa: PLC0415
    from nlgrd.nonlinear.tracing.link_torus import torus_link_bearings  # noqa: PLC0415

    kubo = Path(__file__).resolve().parent.parent / "data" / "case_studies" / "kubo.toml"
    system = load_model(kubo)
    model = build_link_model(system)
    w = 2 * np.pi * 13600.0 / 60 * 25
    sw = link_sweep(model, [w], H=13, directions="up", period=1, stability=False)
    frame = sw.to_frame()
    grid = tg.TorusGrid(13, 2, 60, 12)
    Y = np.zeros((1, grid.n_terms), dtype=complex)
    Y[0, :14] = real_to_complex(sw.result.harmonics[0][0])
    sol = qp.TorusSolution(float(sw.result.omega[0]), 1000.0, Y, grid, True, 0.0, 0, 0.0)
    mine = torus_link_bearings(model, sol, (1024, 12))["force_max"]
    cols = [f"{name}.force_max [N]" for name in bearing_names(system)]
    ref = frame[cols].iloc[0].to_numpy(dtype=float)
    assert ref[0] > 1000
    np.testing.assert_allclose(mine, ref, rtol=1e-4, atol=1e-9 * ref.max())
