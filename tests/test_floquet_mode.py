"""The dominant Floquet multiplier's eigenvector (:mod:`nlgrd.nonlinear.stability.floquet_mode`), the
direction
in which a sweep's unstable orbit departs (issue 10 item 3, kept for period-doubling
branch switching).

Independent reference: the variational equation M η'' + D η' + (K + W k_t(θ) Wᵀ) η = 0
integrated over one period by scipy's ``solve_ivp`` (DOP853, rtol 1e-11), with the contact
state k_t(θ) = k_h where |δ(θ) - e(θ)| > b taken from δ(θ) sampled from the harmonics and
its switching angles found by ``brentq``: neither the library's contact intervals nor its
matrix exponentials. Started from v, it must end at μ v. Tolerance 1e-6 relative to ‖v‖:
the integrator's rtol 1e-11 over ~10 oscillations of the stiffest retained mode and the
root finding (xtol 1e-14 rad) contribute < 1e-8; an eigenvector of a wrong monodromy (a
wrong interval, a wrong order of the product) misses by O(1).
"""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.fourier.harmonics import evaluate
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.stability.floquet_mode import dominant_floquet_mode
from nlgrd.nonlinear.tracing.sweep import sweep
from nlgrd.rotor.modal import gear_pair_mode

TWO_SHAFT = Path(__file__).resolve().parent.parent / "data" / "models" / "two_shaft.toml"


def _contact_breaks(mesh, y, n=4096):
    """Angles in [0, 2π] where |δ - e| crosses b, by brentq on a sampled sign change."""

    def u(t):
        return evaluate(y, np.array([t]))[0] - evaluate(mesh.lste, np.array([t]))[0]

    th = np.linspace(0, 2 * np.pi, n + 1)
    out = [0.0, 2 * np.pi]
    for side in (-1.0, 1.0):
        b = side * mesh.half_backlash
        v = np.array([u(t) - b for t in th])
        for i in np.nonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)[0]:
            out.append(brentq(lambda t, b=b: u(t) - b, th[i], th[i + 1], xtol=1e-14))
    return np.unique(out)


def _propagate(ss, mesh, y, omega, x0):
    """x(T) of the variational equation from x(0) = x0, piecewise by solve_ivp."""
    N = ss.M.shape[0]
    Minv = np.linalg.inv(ss.M)
    breaks = _contact_breaks(mesh, y)
    x = np.asarray(x0, dtype=complex)
    for a, b in zip(breaks[:-1], breaks[1:], strict=True):
        mid = 0.5 * (a + b)
        u = evaluate(y, np.array([mid]))[0] - evaluate(mesh.lste, np.array([mid]))[0]
        kt = mesh.stiffness if abs(u) > mesh.half_backlash else 0.0
        A = np.zeros((2 * N, 2 * N))
        A[:N, N:] = np.eye(N)
        A[N:, :N] = -Minv @ (ss.K + kt * ss.W @ ss.W.T)
        A[N:, N:] = -Minv @ ss.D
        parts = []
        for x_part in (x.real, x.imag):
            sol = solve_ivp(
                lambda t, s, A=A: A @ s,
                (a / omega, b / omega),
                x_part,
                method="DOP853",
                rtol=1e-11,
                atol=1e-14,
            )
            parts.append(sol.y[:, -1])
        x = parts[0] + 1j * parts[1]
    return x


@pytest.fixture(scope="module")
def unstable_points():
    """two_shaft.toml at mesh damping 0.02 (as tests/test_floquet.py), H = 5, a down sweep
    of 40 points over 0.7..1.3 x the gear-pair mode without stability (it stays on its
    branches): the unstable points."""
    s = load_model(TWO_SHAFT)
    s = dc.replace(s, gear_pairs=(dc.replace(s.gear_pairs[0], damping_ratio=0.02),))
    f0 = float(round(gear_pair_mode(s)[0]))
    om = 2 * np.pi * np.linspace(0.7 * f0, 1.3 * f0, 40)
    model = build_link_model(s)  # the link engine's model (nlgrd.sweep's path)
    model.receptance.prepare_stability(float(om.max()))
    red = model.reduced
    res = sweep(red, om, 5, "down", stability=False)

    def top(i):
        w = float(res.omega[i])
        mu = floquet_multipliers(red.linear_state_space(w), red.nonlinearities, res.harmonics[i], w)
        return np.max(np.abs(mu))

    rows = [i for i in range(len(res)) if res.converged[i] and top(i) > 1 + 1e-6]
    assert len(rows) >= 3
    return model, res, rows


def test_dominant_eigenvector_is_carried_to_mu_v_by_the_variational_equation(unstable_points):
    model, res, rows = unstable_points
    red = model.reduced
    mesh = red.metrics.mesh
    kinds = set()
    for i in rows[:4]:
        w = float(res.omega[i])
        ss = red.linear_state_space(w).full()  # the variational equation of the whole model
        y = res.harmonics[i][mesh.coord]
        mode = dominant_floquet_mode(ss, red.nonlinearities, res.harmonics[i], w)
        kinds.add(mode.kind)
        # the same dominant modulus as the sweep's default Floquet method
        top = np.max(np.abs(floquet_multipliers(ss, red.nonlinearities, res.harmonics[i], w)))
        assert abs(mode.multiplier) == pytest.approx(top, rel=1e-6)
        assert abs(mode.multiplier) > 1
        end = _propagate(ss, mesh, y, w, mode.vector)
        assert np.linalg.norm(end - mode.multiplier * mode.vector) <= 1e-6 * abs(mode.multiplier)
    assert kinds <= {"real > 1", "real < -1", "complex"}


def test_a_wrong_monodromy_is_caught(unstable_points):
    """The check can fail: the dominant eigenvector of Φᵀ (a left eigenvector, what a
    transposed or reversed product would give) does not come back as μ v."""
    model, res, rows = unstable_points
    red = model.reduced
    i = rows[0]
    w = float(res.omega[i])
    ss = red.linear_state_space(w).full()
    mode = dominant_floquet_mode(ss, red.nonlinearities, res.harmonics[i], w)
    lam, V = np.linalg.eig(mode.monodromy.T)
    j = int(np.argmax(np.abs(lam)))
    v = V[:, j] / np.linalg.norm(V[:, j])
    end = _propagate(ss, red.metrics.mesh, res.harmonics[i][red.metrics.mesh.coord], w, v)
    assert np.linalg.norm(end - lam[j] * v) > 1e-3
