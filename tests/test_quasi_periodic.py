"""Two-frequency harmonic balance (nlgrd.nonlinear.quasi_periodic) against time integration.

The reference is independent: scipy's DOP853 integration of the single-DOF gear pair with
backlash, m δ'' + c (δ' - e') + k f(δ - e) = W_0 + F₂ cos ω₂ t, e = e₁ cos ω₁ t, ω₂/ω₁
irrational, from rest to t = 150 T₂ (the transient, decaying as e^{-ζ t}: e^{-0.05 · 150 · 11} ≈ 1e-36,
so only the torus is left), then compared over 60 T₂. A forced torus has its phases fixed
by the forcing (θ₁ = ω₁ t, θ₂ = ω₂ t), so the harmonic balance gives δ(t) itself.
The contact is lost 11 % of the time: the law is non-smooth on the torus.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nlgrd.errors import ModelError
from nlgrd.nonlinear import quasi_periodic as qp
from nlgrd.nonlinear import torus_grid as tg
from nlgrd.nonlinear.force_laws import BacklashMesh
from nlgrd.nonlinear.harmonic_balance import ReducedModel

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
    t0, t1 = 150 * T2, 210 * T2
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
    ts = np.linspace(t0, t1, 60001)
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
    # the torus average (grid) against the window's: the 60 T₂ window itself is off by 3e-4
    assert abs(np.std(g.samples(sol.Y)) - np.std(y)) < 2e-3 * np.std(y)


def test_grid_too_coarse_is_refused():
    with pytest.raises(ModelError, match="does not resolve"):
        tg.TorusGrid(8, 4, 16, 9)
