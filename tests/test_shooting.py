"""nlgrd.nonlinear.stability.shooting against the brute-force reference of tests/piecewise_reference.py
(issue 35, part 1): the two-DOF chain with a stiff one-sided spring, built with the library
(``ReducedModel.from_matrices`` and ``ContactStop``), its orbits polished by shooting.

The reference is independent code: the augmented linear system through scipy's expm, its
own event search and Newton. The module shoots on the modal form of the state space of
the library's model (particular solution plus exponentials) and finds the contact changes
on that flow. Both are exact up to the event location (1e-13 T) and rounding, so the
multipliers must agree to 1e-6 (the issue's multipliers; measured ~1e-10). The start is
the reference orbit's x₂ truncated to H = 9 harmonics: its contact times are off (the
point of the module), the polished orbit must not be.
"""

from __future__ import annotations

import time

import numpy as np
import piecewise_reference as pr
import pytest

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import analyse
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.laws.force_laws import ContactStop, ParametricMesh
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.stability.shooting import shoot_orbit


def chain() -> ReducedModel:
    stop = ContactStop(pr.KC, pr.GAP, np.array([0.0, pr.SEAT, 0.0]))
    return ReducedModel.from_matrices(pr.M, pr.D, pr.K, pr.W, np.zeros(2), (stop,))


def reference_orbit(omega: float):
    """(s₀, multipliers, x₂ sampled at 512 points over the period) of the reference orbit."""
    f, s = pr.Flow(omega), np.zeros(4)
    for _ in range(300):
        s = f.advance(s, 1, jacobian=False)[0]
    s0, Phi, ok = pr.shoot(s, omega)
    assert ok
    flow, n = pr.Flow(omega), 256
    x2 = [s0[1]] + [flow.advance(s0, jacobian=False, t_end=j * flow.T / n)[0][1] for j in range(1, n)]
    return s0, np.linalg.eigvals(Phi), np.array(x2)


@pytest.mark.parametrize("omega", [1.35, 1.40, 1.55, 1.64])  # stable, NS band, stable, flip
def test_polished_multipliers_against_reference(omega):
    s0, mu_ref, x2 = reference_orbit(omega)
    model = chain()
    y = analyse(x2, 9)[None, :]  # a truncated orbit as the start
    t0 = time.perf_counter()
    orbit = shoot_orbit(model.linear_state_space(omega), model.nonlinearities, y, omega)
    cost = time.perf_counter() - t0
    t0 = time.perf_counter()
    mu_hb = floquet_multipliers(model.linear_state_space(omega), model.nonlinearities, y, omega)
    floquet = time.perf_counter() - t0
    assert orbit.converged, orbit.residual
    np.testing.assert_allclose(orbit.state, s0, rtol=0, atol=1e-9 * np.max(np.abs(s0)))
    a, b = np.sort_complex(orbit.multipliers), np.sort_complex(mu_ref)
    err = np.max(np.abs(a - b))
    print(
        f"omega {omega}: |mu| max {np.max(np.abs(b)):.4f}, shooting vs reference {err:.1e}, "
        f"H = 9 Floquet max |mu| {np.max(np.abs(mu_hb)):.4f}; {orbit.iterations} Newton steps, "
        f"{cost * 1e3:.0f} ms against one Floquet evaluation {floquet * 1e3:.2f} ms"
    )
    assert err < 1e-6


def test_refuses_a_law_it_cannot_shoot():
    model = chain()
    law = ParametricMesh(1.0, 0.0, np.zeros(1), stiffness_variation=np.array([1.0, 0.1, 0.0]))
    with pytest.raises(ModelError, match="nonlinearities"):
        shoot_orbit(model.linear_state_space(1.5), (law,), np.zeros((1, 3)), 1.5)
