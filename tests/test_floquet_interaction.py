"""The Magnus product in the interaction picture of each piece's mean state matrix
(:func:`nlgrd.nonlinear.stability.magnus_steps.interaction_piece`) on systems of several DOFs, where the
stiff constant part is integrated exactly and only the tangent's variation through W
enters the Magnus term.

The reference is the variational equation integrated by scipy's DOP853 (rtol 1e-12) with
the tangent evaluated pointwise from the force law at each instant: it shares neither the
pieces, the Gauss points nor the exponentials of :mod:`nlgrd.nonlinear.stability.floquet`.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nlgrd.nonlinear.fourier.harmonics import evaluate
from nlgrd.nonlinear.laws.clearance import RadialClearanceLaw
from nlgrd.nonlinear.laws.force_laws import ParametricMesh
from nlgrd.nonlinear.reduction.state_space import LinearStateSpace
from nlgrd.nonlinear.stability.floquet import MAGNUS_ATOL, floquet_analysis


def _chain(n: int, stiffness: float, mass: float) -> tuple[np.ndarray, np.ndarray]:
    """Mass and stiffness of n masses in a line, the first tied to the ground."""
    K = np.zeros((n, n))
    K[0, 0] = stiffness
    for i in range(n - 1):
        K[i : i + 2, i : i + 2] += stiffness * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return mass * np.eye(n), K


def _reference(M, D, K, W, tangent, omega):
    """Eigenvalues of Φ from DOP853 on q'' = -M⁻¹(D q' + (K + W K_t(ωt) Wᵀ) q)."""
    N = M.shape[0]
    Minv = np.linalg.inv(M)

    def f(t, z):
        Z = z.reshape(2 * N, 2 * N)
        q, v = Z[:N], Z[N:]
        return np.vstack([v, -Minv @ (D @ v + (K + W @ tangent(omega * t) @ W.T) @ q)]).ravel()

    sol = solve_ivp(
        f, (0.0, 2 * np.pi / omega), np.eye(2 * N).ravel(), method="DOP853", rtol=1e-12, atol=1e-13
    )
    return np.linalg.eigvals(sol.y[:, -1].reshape(2 * N, 2 * N))


def _close(mu, ref):
    """Largest distance from a multiplier to the nearest reference one, both ways."""
    d = np.abs(mu[:, None] - ref[None, :])
    return max(d.min(axis=1).max(), d.min(axis=0).max())


@pytest.mark.parametrize("omega", [150.0, 260.0, 400.0])
def test_parametric_mesh_on_a_chain_against_integration(omega):
    """Eight masses (1 kg, 1e6 N/m springs, Rayleigh damping) with a mesh of k(θ) =
    3e6 (1 + 0.3 cos θ + 0.1 cos 2θ + 0.05 sin 2θ) N/m between masses 3 and 4, always in
    contact: modes 192-3024 rad/s at the mean mesh stiffness. Every multiplier against
    DOP853 within 1e-6 (measured 7e-8, 5e-9, 6e-10; the step doubling targets
    MAGNUS_ATOL = 1e-7 on max |μ|); the multipliers of the mean stiffness alone are
    0.07-0.17 away, so the check sees the parametric term."""
    M, K = _chain(8, 1e6, 1.0)
    D = 2e-6 * K + 0.5 * M
    W = np.zeros((8, 1))
    W[3, 0], W[4, 0] = 1.0, -1.0
    rho = np.array([1.0, 0.3, 0.0, 0.1, 0.05])
    law = ParametricMesh(3e6, 0.0, stiffness_variation=rho)
    y = np.array([[6e-6, 0.0, 0.0, 0.0, 0.0]])
    r = floquet_analysis(LinearStateSpace(M, D, K, W), [law], y, omega, method="dense", deflate=False)
    ref = _reference(M, D, K, W, lambda th: np.array([[3e6 * evaluate(rho, [th])[0]]]), omega)
    assert r.converged and r.error <= MAGNUS_ATOL
    assert r.exponentials >= 16  # the Magnus steps, not one exponential of the mean
    assert _close(r.multipliers, ref) < 1e-6


def test_hertzian_clearance_on_a_rotor_chain_against_integration():
    """A 2-D chain of six nodes (x and y, 2 kg, 5e6 N/m links, Rayleigh damping) whose
    last node whirls in a 20 µm Hertzian clearance (1e10 N/m^1.5) and loses and regains
    contact within the period: pieces in contact with a varying tangent, pieces without
    contact (one exact exponential). Every multiplier against DOP853 within 1e-6."""
    n = 6
    m1, k1 = _chain(n, 5e6, 2.0)
    M, K = np.kron(m1, np.eye(2)), np.kron(k1, np.eye(2))
    D = 1e-5 * K + 2.0 * M
    W = np.zeros((2 * n, 2))
    W[-2, 0], W[-1, 1] = 1.0, 1.0
    law = RadialClearanceLaw(1e10, 20e-6, 1.5)
    y = np.zeros((2, 7))
    y[0, 1], y[1, 2] = 25e-6, 22e-6
    y[0, 0], y[0, 3] = 1e-6, 4e-6
    breaks, _, varies = law.tangent_function(y)
    assert breaks.size > 2 and varies.any() and not varies.all()  # both states occur
    omega = 2 * np.pi * 60.0
    r = floquet_analysis(LinearStateSpace(M, D, K, W), [law], y, omega, method="dense", deflate=False)
    tangent = lambda th: law.tangent_at(np.vstack([evaluate(y[0], [th]), evaluate(y[1], [th])]))[0]  # noqa: E731
    ref = _reference(M, D, K, W, tangent, omega)
    assert r.converged and r.error <= MAGNUS_ATOL
    assert _close(r.multipliers, ref) < 1e-6


@pytest.mark.parametrize("damping, thin", [((1e-4, 5.0), True), ((1e-3, 50.0), False)])
def test_thin_updates_and_their_guard_against_integration(monkeypatch, damping, thin):
    """The steps of a piece multiplied as rank-2 n_nl updates (:func:`magnus_steps.thin_steps`)
    while E^{-j} amplifies little (light damping), and as full products when it amplifies
    beyond ``THIN_GROWTH`` (Rayleigh damping 1e-3 K + 50 M: the decaying modes lose
    e^{>10} per period): both paths taken as stated, every multiplier against DOP853
    within 1e-6 (measured 1.5e-9 and 7.7e-10)."""
    import nlgrd.nonlinear.stability.magnus_steps as steps

    taken = []
    original = steps.thin_steps

    def spy(*args):
        X = original(*args)
        taken.append(X is not None)
        return X

    monkeypatch.setattr(steps, "thin_steps", spy)
    M, K = _chain(8, 1e6, 1.0)
    D = damping[0] * K + damping[1] * M
    W = np.zeros((8, 1))
    W[3, 0], W[4, 0] = 1.0, -1.0
    rho = np.array([1.0, 0.3, 0.0, 0.1, 0.05])
    law = ParametricMesh(3e6, 0.0, stiffness_variation=rho)
    y = np.array([[6e-6, 0.0, 0.0, 0.0, 0.0]])
    r = floquet_analysis(LinearStateSpace(M, D, K, W), [law], y, 150.0, method="dense", deflate=False)
    ref = _reference(M, D, K, W, lambda th: np.array([[3e6 * evaluate(rho, [th])[0]]]), 150.0)
    assert taken and all(t == thin for t in taken)
    assert r.converged and _close(r.multipliers, ref) < 1e-6


def test_thin_steps_equal_the_plain_product():
    """E^m X of :func:`magnus_steps.thin_steps` against the plain product of the m factors
    E (I + L P_j Rᵀ), random 30 x 30 with rank-4 updates: equal to 1e-12 relative (rounding)."""
    from nlgrd.nonlinear.stability.magnus_steps import thin_steps

    rng = np.random.default_rng(3)
    n, k, m = 30, 4, 12
    E = np.eye(n) + 0.05 * rng.standard_normal((n, n))
    L, Rt = rng.standard_normal((n, k)), rng.standard_normal((k, n))
    P = 0.1 * rng.standard_normal((m, k, k))
    plain = np.eye(n)
    for j in range(m):
        plain = E @ (np.eye(n) + L @ P[j] @ Rt) @ plain
    X = thin_steps(E, L, Rt, P)
    assert X is not None
    got = np.linalg.matrix_power(E, m) @ X
    assert np.max(np.abs(got - plain)) < 1e-12 * np.max(np.abs(plain))


def _midpoint_reference(M, D, K, W, tangent, omega, cells):
    """Φ as the product of scipy's expm over ``cells`` equal cells, the tangent at each
    cell's midpoint (second order), Richardson-extrapolated from cells and 2 cells; and
    the distance of the extrapolated multipliers from those of 2 cells (its error bound)."""
    from scipy.linalg import expm as scipy_expm

    N = M.shape[0]
    Minv = np.linalg.inv(M)

    def product(n):
        dt = 2 * np.pi / omega / n
        Phi = np.eye(2 * N)
        for j in range(n):
            A = np.zeros((2 * N, 2 * N))
            A[:N, N:] = np.eye(N)
            A[N:, :N] = -Minv @ (K + W @ tangent((j + 0.5) * dt * omega) @ W.T)
            A[N:, N:] = -Minv @ D
            Phi = scipy_expm(A * dt) @ Phi
        return Phi

    coarse, fine = product(cells), product(2 * cells)
    ref = np.linalg.eigvals((4 * fine - coarse) / 3)
    return ref, _close(ref, np.linalg.eigvals(fine))


def test_a_stiff_decaying_mode_leaves_the_interaction_picture(monkeypatch):
    """The mesh chain of the first test plus a 1 g mass on mass 8 through a 1e6 N s/m
    damper and a 1e6 N/m spring: a real mode at -c/m = -1e9 1/s (Kubo's full link state
    has one at -1.07e9 1/s), where e^{-A₀ s} of a step overflowed (RuntimeWarnings, |μ|
    inf). The piece takes plain Magnus steps (:func:`magnus_steps.plain_steps`): no
    warning, every multiplier against scipy expm products over 4000 and 8000 midpoint cells,
    Richardson-extrapolated, within 1e-6 (the reference's own error is printed, below it)."""
    import warnings

    import nlgrd.nonlinear.stability.magnus_steps as steps

    taken = []
    original = getattr(steps, "plain_steps", None)
    if original is not None:  # spied on; absent before the fix (the test then fails below)
        monkeypatch.setattr(steps, "plain_steps", lambda *a: taken.append(1) or original(*a))
    M8, K8 = _chain(8, 1e6, 1.0)
    M, K, D = np.zeros((9, 9)), np.zeros((9, 9)), np.zeros((9, 9))
    M[:8, :8], K[:8, :8], D[:8, :8] = M8, K8, 2e-6 * K8 + 0.5 * M8
    M[8, 8] = 1e-3
    tie = np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[7:, 7:] += 1e6 * tie
    D[7:, 7:] += 1e6 * tie
    A = np.block([[np.zeros((9, 9)), np.eye(9)], [-np.linalg.solve(M, K), -np.linalg.solve(M, D)]])
    assert np.max(-np.linalg.eigvals(A).real) > 9e8  # the stiff mode is there
    W = np.zeros((9, 1))
    W[3, 0], W[4, 0] = 1.0, -1.0
    rho = np.array([1.0, 0.3, 0.0, 0.1, 0.05])
    law = ParametricMesh(3e6, 0.0, stiffness_variation=rho)
    y = np.array([[6e-6, 0.0, 0.0, 0.0, 0.0]])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = floquet_analysis(LinearStateSpace(M, D, K, W), [law], y, 150.0, method="dense", deflate=False)
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]
    tangent = lambda th: np.array([[3e6 * evaluate(rho, [th])[0]]])  # noqa: E731
    ref, ref_error = _midpoint_reference(M, D, K, W, tangent, 150.0, 4000)
    print(
        f"stiff mode: |mu| max {np.max(np.abs(r.multipliers)):.9f}, against the reference "
        f"{_close(r.multipliers, ref):.1e} (reference {ref_error:.1e})"
    )
    assert ref_error < 1e-7
    assert r.converged and np.all(np.isfinite(r.multipliers))
    assert _close(r.multipliers, ref) < 1e-6
    assert taken  # the plain steps, not the interaction picture
