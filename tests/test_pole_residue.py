"""The pole-residue form of the link reduction (issue 11, item 3) against direct solves.

- :class:`PoleResidue` on a random damped gyroscopic quadratic Z(ω) = A0 + ω A1 + ω² A2
  against numpy's dense solve, and its ω-derivative -X diag(1/(ω-λ)²) L b against
  central differences of that solve;
- :class:`LinkReceptance` with ``method="poles"`` (the default for the shipped trains)
  against ``method="direct"`` (one LU of Z_k per point): κ_k, F_k, their
  ω-derivatives and the recovery of every DOF.

Tolerances: the companion eigenvectors of these models have condition numbers ~1e3-1e5
(after the frequency scaling), so the form carries ~1e-16 x that x the distance-to-pole
amplification; 1e-8 is the acceptance of the form (POLE_CHECK_RTOL, checked per
harmonic), and the differences seen are 1e-12 to 6e-10.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nlgrd.errors import ModelError
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.nonlinear.reduction.link_reduction import LinkReceptance
from nlgrd.nonlinear.reduction.pole_residue import POLE_CHECK_RTOL, PoleResidue

MODELS = Path(__file__).resolve().parents[1] / "data" / "models"


def _random_quadratic(n: int, seed: int):
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((n, n))
    K = a @ a.T + n * np.eye(n)  # SPD stiffness
    b = rng.standard_normal((n, n))
    M = b @ b.T / n + np.eye(n)
    c = rng.standard_normal((n, n))
    C = 0.05 * (c @ c.T) / n
    g = rng.standard_normal((n, n))
    G = 0.1 * (g - g.T)  # skew: gyroscopic
    k, s = 2, 0.3  # harmonic and speed per base frequency
    return K.astype(complex), 1j * k * C, -(k * k) * M + 1j * k * s * G


def test_pole_residue_solve_and_derivative_against_dense_solves():
    """Z⁻¹ b and d(Z⁻¹ b)/dω at six frequencies around the poles, to 1e-10 relative (the
    second-order central difference with h = 1e-6 ω: truncation ~1e-12, rounding 1e-10)."""
    A0, A1, A2 = _random_quadratic(12, 1)
    pr = PoleResidue.of(A0, A1, A2)
    assert pr.poles.shape == (24,)
    b = np.random.default_rng(2).standard_normal((12, 3))
    for w in np.linspace(0.2, 3.0, 6) * np.median(np.abs(pr.poles)):
        ref = np.linalg.solve(A0 + w * A1 + w * w * A2, b)
        got = pr.solve(w, b)
        assert np.max(np.abs(got - ref)) <= 1e-10 * np.max(np.abs(ref))
        h = 1e-6 * w
        fd = (
            np.linalg.solve(A0 + (w + h) * A1 + (w + h) ** 2 * A2, b)
            - np.linalg.solve(A0 + (w - h) * A1 + (w - h) ** 2 * A2, b)
        ) / (2 * h)
        dz = pr.X_top @ (-pr.weights(w, 2)[:, None] * (pr.L @ b))
        assert np.max(np.abs(dz - fd)) <= 1e-6 * np.max(np.abs(fd))
    assert pr.check(A0, A1, A2, b, [1.0, 2.0]) < 1e-12


@pytest.mark.parametrize("name", ["idler_train", pytest.param("two_stage", marks=pytest.mark.slow)])
def test_poles_equal_direct_solves_of_the_link_reduction(name):
    """κ_k, F_k, dκ_k/dω, dF_k/dω and every DOF's recovery: poles against direct LU at
    five base frequencies, 1e-8 of each array's largest entry."""
    system = load_model(MODELS / f"{name}.toml")
    model = build_link_model(system)
    rec = model.receptance
    assert rec.method == "poles"
    direct = LinkReceptance(
        system, rec.links, rec.plan, rec.static_force, rec.harmonic_force, method="direct"
    )
    H = 3 * max(lk.order for lk in model.links)
    rng = np.random.default_rng(0)
    for f in (150.0, 480.0, 1000.0, 2300.0, 4100.0):
        w = 2 * np.pi * f / max(lk.order for lk in model.links)
        got = rec.terms(w, H) + rec.derivatives(w, H)
        ref = direct.terms(w, H) + direct.derivatives(w, H)
        for a, b in zip(got, ref, strict=True):
            assert np.max(np.abs(a - b)) <= 1e-8 * np.max(np.abs(b)), f
        z = 1e-6 * rng.standard_normal((rec.n_coords, 2 * H + 1))
        G = 1e3 * rng.standard_normal((rec.n_coords, 2 * H + 1))
        dofs = np.arange(system.n_dofs)
        qa, qb = rec.recover(w, H, z, G, dofs), direct.recover(w, H, z, G, dofs)
        assert np.max(np.abs(qa - qb)) <= 1e-8 * np.max(np.abs(qb)), f
    assert max(rec.pole_check.values()) <= POLE_CHECK_RTOL


def test_poles_refused_where_they_do_not_apply():
    system = load_model(MODELS / "idler_train.toml")
    rec = build_link_model(system).receptance
    with pytest.raises(ModelError, match="method"):
        LinkReceptance(system, rec.links, rec.plan, method="modal")


def test_check_frequencies_stay_off_undamped_poles():
    """An undamped Z (real poles ±ω_n): the check frequencies lie strictly between pole
    moduli (at least 1e-3 relative away from each), so the direct solve of the check is
    regular and the form passes it (1e-10)."""
    A0, _, A2 = _random_quadratic(10, 3)
    A2 = A2.real.astype(complex)  # no gyroscopic, no damping
    pr = PoleResidue.of(A0, np.zeros_like(A0), A2)
    w = pr.check_frequencies()
    mods = np.abs(pr.poles)
    gap = np.min(np.abs(w[:, None] - mods[None, :]) / mods[None, :], axis=1)
    assert w.size >= 3 and np.all(gap > 1e-3), gap
    assert pr.check(A0, np.zeros_like(A0), A2, np.eye(10)[:, :2], w) < 1e-10
