"""Fourier coefficients of the backlash law: closed form, quadrature, AFT, Jacobian."""

import numpy as np
import pytest

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import (
    analyse,
    complex_to_real,
    differentiate,
    evaluate,
    real_to_complex,
    sample,
)
from nlgrd.nonlinear.laws.describing_functions import (
    aft_convergence,
    contact_intervals,
    deadzone,
    describing_gains,
    fourier_aft,
    fourier_exact,
    one_sided_describing_function,
)
from nlgrd.nonlinear.laws.force_laws import AFTNonlinearity, BacklashMesh


def _random_signal(rng, H, scale=1.0, mean=0.0):
    k = np.repeat(np.arange(1, H + 1), 2)
    return np.concatenate([[mean], scale * rng.normal(size=2 * H) / k])


def test_single_harmonic_closed_form():
    """Exact piecewise integration equals the one-sided describing function to 1e-10.

    Independent check: for x = x0 + A cos θ without back-side contact (x0 - A >= -b), f
    equals max(0, x - b), whose mean (A/π)(sin α - α cos α) and first cosine harmonic
    (A/π)(α - sin α cos α), cos α = (b - x0)/A, follow by integrating over |θ| < α
    (derivation in :func:`one_sided_describing_function`; model.md §3). The exact
    method only adds rounding and crossing-polish errors, quadratic in the crossing
    error, so 1e-10 (relative to A) is a loose bound on ~1e-15 errors.
    """
    b = 1.0
    for x0, A in [(1.5, 1.0), (0.3, 1.2), (0.9, 0.2), (1.0, 0.7), (0.0, 1.0), (-0.4, 0.6), (2.5, 1.0)]:
        assert x0 - A >= -b
        G = fourier_exact([x0, A, 0.0, 0.0, 0.0], b, 2)
        mean, first = one_sided_describing_function(x0, A, b)
        assert abs(G[0] - mean) <= 1e-10 * A
        assert abs(G[1] - first) <= 1e-10 * A
        assert abs(G[2]) <= 1e-10 * A  # no sine part for an even signal


def test_closed_form_rejects_non_positive_amplitude():
    """The closed form needs A > 0 (a ModelError names the argument)."""
    with pytest.raises(ModelError):
        one_sided_describing_function(0.0, 0.0, 1.0)


def test_exact_matches_dense_quadrature_with_back_contact():
    """Exact harmonics equal trapezoidal quadrature with 2^18 samples, back contact included.

    Independent check: brute-force sampling of k_h f(x(θ)). The trapezoidal rule on a
    periodic integrand with kinks errs by O(h²) ≈ (2π/2^18)² · max|x''| ≈ 1e-9 here,
    so 1e-8 relative to k_h max|x| is the justified bound.
    """
    rng = np.random.default_rng(1)
    b, kh = 0.7, 3.0
    for _ in range(20):
        x = _random_signal(rng, 6, 1.5, rng.normal())
        th = 2 * np.pi * np.arange(2**18) / 2**18
        ref = analyse(kh * deadzone(evaluate(x, th), b), 6)
        G = fourier_exact(x, b, 6, kh)
        assert np.max(np.abs(G - ref)) <= 1e-8 * kh * np.max(np.abs(x))


def test_crossing_methods_agree_including_near_tangency():
    """Grid crossings with certificate and companion-matrix roots give the same intervals.

    Independent check: two root finders. A near-tangent signal (max x = b + 1e-9)
    forces the certified sampling path to fall back; contact fractions must agree to
    1e-10 (polished simple roots err ~1e-15 rad; the near-double root of the grazing
    case only to eps/slope ~ 1e-12 rad, where the force it bounds is 1e-9 deep).
    """
    rng = np.random.default_rng(2)
    b = 1.0
    cases = [_random_signal(rng, 5, 1.0, rng.normal()) for _ in range(50)]
    cases.append(np.array([b + 1e-9 - 0.5, 0.5, 0.0, 0.0, 0.0]))  # grazing from below
    for x in cases:
        a = contact_intervals(x, b)
        c = contact_intervals(x, b, crossings="companion")
        assert abs(a.contact_fraction - c.contact_fraction) < 1e-10
        assert a.back_contact == c.back_contact
        np.testing.assert_allclose(np.sum(a.end - a.start), 2 * np.pi, rtol=1e-14)


def test_single_state_shortcuts_against_dense_sampling():
    """The one-state certificates (harmonic bound, then 64 samples with the chord bound
    Σ k² |X_k| h² / 8) never declare one contact state where the signal crosses ±b.

    Independent check: 2^18 samples of x(θ) (FFT). Signals with 30 decaying harmonics (as
    δ - e with a tooth-profile LSTE) whose minimum sits within a few percent above or
    below b: where dense sampling sees a crossing, the intervals must have more than one
    piece; where they have one piece, its state must hold at every sample.
    """
    rng = np.random.default_rng(11)
    b = 1.0
    checked = 0
    for _ in range(300):
        x = _random_signal(rng, 30, 0.3)
        x[0] += b - sample(x, 2**18).min() + rng.uniform(-0.03, 0.03)  # min(x) within ±0.03 of b
        xs = sample(x, 2**18)
        iv = contact_intervals(x, b)
        if iv.state.size == 1:
            checked += 1
            assert iv.state[0] == 1 and xs.min() > b
        else:
            assert xs.min() < b + 1e-9
    assert checked > 20


def test_jacobian_matches_finite_differences():
    """Analytic dG/dx (Toeplitz of the contact indicator) equals central differences.

    Independent check: central differences with step 1e-7 on a signal with 6 crossings;
    truncation O(h² |G'''|) is tiny, but the kinks make G only piecewise smooth, so the
    bound 1e-6 relative to k_h allows the rounding error (1e-16/1e-7 ~ 1e-9) with margin.
    """
    rng = np.random.default_rng(3)
    b, kh, H = 0.5, 2.0, 5
    x = _random_signal(rng, H, 1.0, 0.2)
    G, J = fourier_exact(x, b, H, kh, jacobian=True)
    Jfd = np.empty_like(J)
    for j in range(2 * H + 1):
        dx = np.zeros(2 * H + 1)
        dx[j] = 1e-7
        Jfd[:, j] = (fourier_exact(x + dx, b, H, kh) - fourier_exact(x - dx, b, H, kh)) / 2e-7
    assert np.max(np.abs(J - Jfd)) < 1e-6 * kh


def test_full_contact_is_linear():
    """With x > b throughout, G = k_h (x - b) exactly and dG/dx = k_h I (both methods).

    Independent check: the law is linear there; rounding-level tolerance 1e-12.
    """
    x = np.array([3.0, 0.5, -0.3, 0.2, 0.1, 0.0, 0.05])
    for fun in (fourier_exact, fourier_aft):
        G, J = fun(x, 1.0, 3, 2.0, jacobian=True)
        expected = 2.0 * x
        expected[0] -= 2.0
        np.testing.assert_allclose(G, expected, atol=1e-12)
        np.testing.assert_allclose(J, 2.0 * np.eye(7), atol=1e-12)


def test_aft_converges_at_second_order():
    """AFT error against the exact harmonics decays like N^-2 (convergence study in N).

    Independent check: the exact method. f has kinks, so the sampled transform errs by
    O(N^-2); the least-squares slope over N = 64..4096 must lie in [-2.6, -1.5] (the
    error oscillates with where crossings fall between samples) and the error at
    N = 4096 must be below 1e-5 of the signal amplitude.
    """
    rng = np.random.default_rng(4)
    x = _random_signal(rng, 5, 1.0, 0.3)
    study = aft_convergence(x, 0.6, 5, n_samples=(64, 128, 256, 512, 1024, 2048, 4096))
    slope = np.polyfit(np.log(study["n_samples"]), np.log(study["error"]), 1)[0]
    assert -2.6 <= slope <= -1.5
    assert study["error"][-1] < 1e-5 * np.max(np.abs(x))


def test_aft_jacobian_tends_to_exact():
    """The AFT Jacobian (DFT of the sampled indicator) tends to the exact one.

    Independent check: exact Toeplitz Jacobian; with 8192 samples the indicator's
    crossing positions are off by at most half a cell, error O(1/N) ≈ 1e-3.
    """
    rng = np.random.default_rng(5)
    x = _random_signal(rng, 4, 1.0, 0.1)
    _, Je = fourier_exact(x, 0.5, 4, jacobian=True)
    _, Ja = fourier_aft(x, 0.5, 4, n_samples=8192, jacobian=True)
    assert np.max(np.abs(Je - Ja)) < 1e-3


def test_harmonic_conversions_round_trip():
    """Real/complex conversions, sampling and analysis invert each other (rounding level)."""
    rng = np.random.default_rng(6)
    z = rng.normal(size=9)
    np.testing.assert_allclose(complex_to_real(real_to_complex(z)), z)
    np.testing.assert_allclose(analyse(sample(z, 64), 4), z, atol=1e-14)
    th = np.linspace(0, 2 * np.pi, 7)
    # d/dθ of the trig polynomial against a centred difference (h = 1e-6: error 1e-11)
    dz = differentiate(z)
    fd = (evaluate(z, th + 1e-6) - evaluate(z, th - 1e-6)) / 2e-6
    np.testing.assert_allclose(evaluate(dz, th), fd, atol=1e-8)


def test_describing_gains_of_one_sided_case():
    """The paper's ν_1 = G_1 / X_1 equals (α - sin α cos α)/π for x = x0 + A cos θ.

    Independent check: the closed form of test_single_harmonic_closed_form divided by A.
    """
    x0, A, b = 0.8, 1.0, 1.0
    nu = describing_gains([x0, A, 0.0], b, 1)
    _, first = one_sided_describing_function(x0, A, b)
    assert abs(nu[1] - first / A) < 1e-12


def test_backlash_mesh_and_generic_aft_plugin_agree():
    """A dead zone plugged in through AFTNonlinearity reproduces BacklashMesh harmonics.

    Independent check: the generic AFT element knows nothing of the exact method; with
    4096 samples its O(N^-2) error is ~1e-7 of k_h · amplitude, bound 1e-5.
    """
    lste = np.array([0.0, 0.3, 0.1])
    mesh = BacklashMesh(2.0, 0.5, lste)
    aft = AFTNonlinearity(
        lambda u: 2.0 * deadzone(u, 0.5), lambda u: 2.0 * (np.abs(u) > 0.5), 0, lste, n_samples=4096
    )
    y = np.array([[0.4, 0.9, -0.2, 0.1, 0.05]])
    G1, J1 = mesh.harmonics(y, jacobian=True)
    G2, J2 = aft.harmonics(y, jacobian=True)
    assert np.max(np.abs(G1 - G2)) < 1e-5 * 2.0
    assert np.max(np.abs(J1 - J2)) < 5e-3


def test_mesh_input_validation():
    """Bad mesh input raises ModelError naming the field."""
    with pytest.raises(ModelError, match="lste"):
        BacklashMesh(1.0, 0.1, np.zeros(2))
    with pytest.raises(ModelError, match="stiffness"):
        BacklashMesh(-1.0, 0.1)
