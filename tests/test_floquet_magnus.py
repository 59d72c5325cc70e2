"""Floquet products without per-cell exponentials (issue 34, item 1).

The references are the variational equations integrated by scipy's DOP853 (rtol 1e-12),
with the tangent evaluated pointwise from the force law at each instant: they share
neither the breaks nor the exponentials of :mod:`nlgrd.nonlinear.stability.floquet`.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from nlgrd.nonlinear.fourier.harmonics import evaluate
from nlgrd.nonlinear.laws.clearance import RadialClearanceLaw
from nlgrd.nonlinear.laws.force_laws import BacklashMesh, ParametricMesh
from nlgrd.nonlinear.reduction.state_space import LinearStateSpace
from nlgrd.nonlinear.stability.floquet import MAGNUS_ATOL, floquet_analysis, floquet_multipliers


def _reference(M, D, K, W, tangent, omega):
    """Eigenvalues of Φ from DOP853 on q'' = -M⁻¹(D q' + (K + W K_t(ωt) Wᵀ) q)."""
    N = M.shape[0]
    Minv = np.linalg.inv(M)

    def f(t, z):
        Z = z.reshape(2 * N, 2 * N)
        q, v = Z[:N], Z[N:]
        Kt = K + W @ tangent(omega * t) @ W.T
        return np.vstack([v, -Minv @ (D @ v + Kt @ q)]).ravel()

    sol = solve_ivp(
        f, (0.0, 2 * np.pi / omega), np.eye(2 * N).ravel(), method="DOP853", rtol=1e-12, atol=1e-13
    )
    return np.linalg.eigvals(sol.y[:, -1].reshape(2 * N, 2 * N))


KAPPA, ZETA = 0.3, 0.005


def _mathieu(omega):
    """x'' + 2ζ x' + (1 + κ cos ωt) x = 0 as a parametric mesh without backlash (always in contact)."""
    ss = LinearStateSpace([[1.0]], [[2 * ZETA]], [[0.0]], [[1.0]])
    law = ParametricMesh(stiffness=1.0, half_backlash=0.0, stiffness_variation=np.array([1.0, KAPPA, 0.0]))
    return ss, law, np.array([[1.0, 0.0, 0.0]])


def _mathieu_reference(omega):
    M, D, K, W = np.eye(1), np.array([[2 * ZETA]]), np.zeros((1, 1)), np.eye(1)
    return _reference(M, D, K, W, lambda th: np.array([[1.0 + KAPPA * np.cos(th)]]), omega)


def test_magnus_mathieu_tongue_edges_against_integration():
    """The principal tongue of the damped Mathieu equation (ω near 2): max |μ| at five
    frequencies and the two tongue edges (max |μ| = 1) against DOP853. Tolerance 1e-6 on
    |μ| (the Magnus refinement targets MAGNUS_ATOL = 1e-7 on its own estimate; the
    reference's own error is ~1e-11) and 1e-6 relative on the edges (issue 34: the
    256-cell product was 7.5e-5 off there)."""
    for w in (1.8, 1.95, 2.0, 2.1, 2.3):
        ss, law, y = _mathieu(w)
        r = floquet_analysis(ss, [law], y, w, deflate=False)
        ref = np.max(np.abs(_mathieu_reference(w)))
        assert r.converged and r.error <= MAGNUS_ATOL
        assert abs(np.max(np.abs(r.multipliers)) - ref) < 1e-6

    def new(w):
        ss, law, y = _mathieu(w)
        return np.max(np.abs(floquet_multipliers(ss, [law], y, w, deflate=False))) - 1

    def old(w):
        return np.max(np.abs(_mathieu_reference(w))) - 1

    for a, b in ((1.7, 1.95), (2.05, 2.4)):
        e_new, e_ref = brentq(new, a, b, xtol=1e-10), brentq(old, a, b, xtol=1e-10)
        assert abs(e_new - e_ref) < 1e-6 * e_ref


def test_magnus_hertzian_clearance_against_integration():
    """A journal (2 DOFs, 10 kg, centring spring 1e6 N/m, 200 N s/m) on a 20 µm Hertzian
    clearance (1e10 N/m^1.5) with an orbit that leaves and regains contact: every
    multiplier against DOP853 of the variational equation, within 1e-6 (the step-doubling
    target is 1e-7 on max |μ|; the others converge with it)."""
    law = RadialClearanceLaw(1e10, 20e-6, 1.5)
    y = np.zeros((2, 7))
    y[0, 1], y[1, 2] = 25e-6, 22e-6  # forward elliptic whirl, radius 22-25 µm
    y[0, 0], y[0, 3] = 1e-6, 4e-6  # mean and second harmonic: the contact is lost and regained
    M, D, K, W = 10 * np.eye(2), 200 * np.eye(2), 1e6 * np.eye(2), np.eye(2)
    omega = 2 * np.pi * 60.0
    breaks, _, varies = law.tangent_function(y)
    assert breaks.size > 2 and varies.any() and not varies.all()  # both states occur
    ss = LinearStateSpace(M, D, K, W)
    r = floquet_analysis(ss, [law], y, omega)
    tangent = lambda th: law.tangent_at(np.vstack([evaluate(y[0], [th]), evaluate(y[1], [th])]))[0]  # noqa: E731
    ref = _reference(M, D, K, W, tangent, omega)
    assert r.converged
    mu = np.sort_complex(r.multipliers)
    assert np.max(np.abs(mu - np.sort_complex(ref))) < 1e-6


def test_piecewise_links_switching_at_different_times_against_integration():
    """Two backlash laws on two coupled DOFs whose contacts change at different angles:
    one exponential per interval of the union of their exact crossings (no saltation),
    every multiplier against DOP853 with the pointwise tangent, within 1e-6 (the product
    is exact; the reference steps across the tangent's jumps, ~1e-8 here)."""
    meshes = [
        BacklashMesh(2e7, 5e-6, lste=np.array([0.0, 8e-6, 0.0]), coord=0),
        BacklashMesh(3e7, 4e-6, lste=np.array([0.0, 0.0, 7e-6, 2e-6, 0.0]), coord=1),
    ]
    y = np.array([[6e-6, 1e-6, 0.5e-6, 0, 0], [5e-6, 0.0, 0.0, 0, 0]])
    M = np.diag([0.2, 0.1])
    K = np.array([[3e7, -1e7], [-1e7, 2e7]])
    D = 2e-4 * K + np.diag([5.0, 5.0])
    W = np.eye(2)
    omega = 2 * np.pi * 1500.0
    ivs = [m.intervals(y[i]) for i, m in enumerate(meshes)]
    union = np.unique(np.round(np.mod(np.concatenate([iv.start for iv in ivs]), 2 * np.pi), 12))
    assert all(iv.start.size >= 2 for iv in ivs) and union.size >= 4
    ss = LinearStateSpace(M, D, K, W)
    r = floquet_analysis(ss, meshes, y, omega, method="dense")
    assert r.exponentials <= union.size and r.error == 0.0

    def tangent(th):
        out = np.zeros((2, 2))
        for i, m in enumerate(meshes):
            x = evaluate(y[i], th) - evaluate(m.lste, th)
            out[i, i] = m.stiffness if abs(x) > m.half_backlash else 0.0
        return out

    ref = _reference(M, D, K, W, tangent, omega)
    assert np.max(np.abs(np.sort_complex(r.multipliers) - np.sort_complex(ref))) < 1e-6


@pytest.mark.parametrize("law", [ParametricMesh(1.0, 0.0, stiffness_variation=np.array([1.0, 0.0, 0.0]))])
def test_magnus_constant_tangent_is_exact(law):
    """ρ = 1: a constant tangent; the Magnus product is exp(A T) and the estimate vanishes."""
    ss = LinearStateSpace([[1.0]], [[0.1]], [[0.0]], [[1.0]])
    r = floquet_analysis(ss, [law], np.array([[1.0, 0.0, 0.0]]), 1.3)
    lam = np.linalg.eigvals(np.array([[0.0, 1.0], [-1.0, -0.1]]))
    assert np.allclose(
        np.sort_complex(r.multipliers), np.sort_complex(np.exp(lam * 2 * np.pi / 1.3)), atol=1e-12
    )
    assert r.error < 1e-12
