"""Harmonic balance of the reduced problem: linear limit, solvers, flags, vector form, stability."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nlgrd.nonlinear.fourier.harmonics import evaluate
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel, ReducedProblem
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.laws.describing_functions import deadzone
from nlgrd.nonlinear.laws.force_laws import AFTNonlinearity, BacklashMesh
from nlgrd.nonlinear.models.sdof import SDOFGearPair
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.stability.hill import hill_multipliers
from nlgrd.nonlinear.tracing.sweep import sweep

# Kubo et al. (1972) single-DOF data as decoded in model.md §5, with an LSTE of three
# harmonics (first-harmonic amplitude 1.24 µm = half the 2.479 µm STE amplitude).
LSTE = np.array([0.0, 1.24e-6, 0.0, 0.50e-6, 0.30e-6, 0.10e-6, -0.05e-6])


def kubo(zeta=0.02, W0=2295.0, b=50e-6):
    return SDOFGearPair(0.261, 0.2587e9, b, W0, LSTE, damping_ratio=zeta)


def test_contact_never_lost_equals_linear_response():
    """With a large static load the HB solution is the linear frequency response to 1e-8.

    Independent check: (κ_k + k_h) δ_k = F_k + k_h E_k + k_h b [k=0] solved directly
    (:meth:`SDOFGearPair.linear_response`), here at W_0 = 200 kN so |δ - e| > b always,
    including at resonance (ζ = 0.005). Newton lands on the piecewise-linear law's
    linear piece, so only rounding remains; 1e-8 relative is the acceptance bound.
    """
    model = kubo(zeta=0.005, W0=2e5)
    rm = model.reduced_model()
    wn = model.natural_frequency
    for f in (0.3, 0.5, 0.9, 1.0, 1.1, 2.0):
        sol = solve(rm.at(f * wn, 5))
        lin = model.linear_response(f * wn, 5)
        assert sol.converged
        assert np.max(np.abs(sol.harmonics[0] - lin)) <= 1e-8 * np.max(np.abs(lin))
        assert rm.metrics.mesh.intervals(sol.harmonics[0]).contact_fraction == 1.0


def test_residual_jacobian_matches_finite_differences():
    """dR/dz of the reduced problem equals central differences (contact loss present).

    Independent check: finite differences, step 1e-12 m on δ ~ 1e-5 m; bound 1e-6
    relative to max|J| covers rounding (1e-16 · 1e3 N / 1e-12 m ≈ 1e-1 N/m vs 1e8).
    """
    model = kubo()
    wn = model.natural_frequency
    p = model.reduced_model().at(1.0 * wn, 5)
    z = solve(p).harmonics.reshape(-1) * 1.01
    _, J, _ = p.residual_jacobian(z)
    Jfd = np.empty_like(J)
    for j in range(z.size):
        dz = np.zeros_like(z)
        dz[j] = 1e-12
        Jfd[:, j] = (p.residual(z + dz) - p.residual(z - dz)) / 2e-12
    assert np.max(np.abs(J - Jfd)) < 1e-6 * np.max(np.abs(J))


def test_quasi_linear_iteration_reaches_newton_solution():
    """The paper's quasi-linear receptance iteration converges to the Newton solution.

    Independent check: a different algorithm on the same equations. At 1.05 ω_n with
    16 % contact loss it converges linearly (tens of iterations, Newton needs ~5);
    both stop at relative residual 1e-10, so the harmonics agree to ~1e-8 relative.
    """
    model = kubo()
    p = model.reduced_model().at(1.05 * model.natural_frequency, 5)
    newton = solve(p)
    ql = solve(p, method="quasi-linear", max_iter=2000, fallback=False)
    assert newton.converged and ql.converged
    assert ql.iterations > newton.iterations
    assert np.max(np.abs(ql.harmonics - newton.harmonics)) < 1e-7 * np.max(np.abs(newton.harmonics))


def test_non_convergence_is_flagged():
    """max_iter = 1 without fallback cannot converge: flagged, harmonics NaN, listed by sweeps.

    Independent check: none needed; this is the bookkeeping contract (never report a
    non-converged iterate as an answer).
    """
    model = kubo()
    rm = model.reduced_model()
    wn = model.natural_frequency
    sol = solve(rm.at(1.0 * wn, 5), max_iter=1, fallback=False)
    assert not sol.converged
    assert np.all(np.isnan(sol.harmonics))
    assert np.all(np.isfinite(sol.iterate))
    assert sol.residual > 1e-10
    res = sweep(rm, np.array([0.97, 1.0, 1.03]) * wn, 5, "up", max_iter=1, fallback=False, jump="none")
    assert not np.all(res.converged)
    failed = res.failures()
    assert failed.size == np.sum(~res.converged) > 0
    assert np.all(np.isnan(res.dte_rms[~res.converged]))
    assert not np.any(res.stable[~res.converged])
    frame = res.to_frame()
    assert list(frame["converged"]) == list(res.converged)


def test_a_failed_point_leaves_the_next_start_alone(monkeypatch):
    """After a point that did not converge, the sweep starts the next from the last
    converged orbit (a failed point's harmonics are NaN and must not become the start).

    One Newton iteration solves a full-contact (linear) point from any start but not a
    point with contact loss: swept from 0.5 to 2 ω_n, the points around the resonance fail
    and those far above it, in full contact again, must converge to the linear answer
    (independent reference: Newton with its default iterations at each of them). Every
    start the sweep hands to Newton is recorded: all finite."""
    import nlgrd.nonlinear.tracing.sweep as sweep_module

    starts = []

    def recording(problem, z=None, **kw):
        starts.append(None if z is None else np.asarray(z, dtype=float).copy())
        return solve(problem, z, **kw)

    monkeypatch.setattr(sweep_module, "solve", recording)
    model = kubo()
    rm = model.reduced_model()
    wn = model.natural_frequency
    om = np.linspace(0.5, 2.0, 31) * wn
    res = sweep(rm, om, 5, "up", max_iter=1, fallback=False, jump="none", stability=False)
    assert len(starts) == om.size and all(s is None or np.all(np.isfinite(s)) for s in starts)
    bad = np.flatnonzero(~res.converged)
    assert bad.size > 0 and bad[-1] < om.size - 3
    after = np.arange(bad[-1] + 1, om.size)
    assert np.all(res.converged[after])
    for i in after:
        ref = solve(rm.at(om[i], 5))
        assert np.max(np.abs(res.harmonics[i] - ref.harmonics)) <= 1e-9 * np.max(np.abs(ref.harmonics))


def test_two_decoupled_coordinates_equal_two_scalar_problems():
    """An n_nl = 2 problem with diagonal κ equals the two scalar problems solved apart.

    Independent check: the scalar path. The second coordinate carries a different
    mesh (other backlash and LSTE) through ``coord=1``; 1e-10 relative (both converge
    to 1e-10 residual).
    """
    a, b = kubo(), kubo(W0=500.0, b=10e-6)
    w = 1.05 * a.natural_frequency
    H = 5
    kap = np.zeros((H + 1, 2, 2), complex)
    kap[:, 0, 0], kap[:, 1, 1] = a.kappa(w, H), b.kappa(w, H)
    frc = np.column_stack([a.force(w, H), b.force(w, H)])
    mb = b.mesh()
    mesh_b = BacklashMesh(mb.stiffness, mb.half_backlash, mb.lste, mb.damping, mb.static_load, coord=1)
    joint = solve(ReducedProblem(w, kap, frc, (a.mesh(), mesh_b)))
    sa = solve(a.reduced_model().at(w, H))
    sb = solve(b.reduced_model().at(w, H))
    assert joint.converged and sa.converged and sb.converged
    np.testing.assert_allclose(joint.harmonics[0], sa.harmonics[0], rtol=1e-10, atol=1e-10 * 1e-4)
    np.testing.assert_allclose(joint.harmonics[1], sb.harmonics[0], rtol=1e-10, atol=1e-10 * 1e-4)


def test_receptance_form_equals_stiffness_form():
    """Y_k + h_k G_k = h_k F_k (receptance form, mean in stiffness form) gives the same solution.

    Independent check: the stiffness form; 1e-10 relative.
    """
    model = kubo()
    w, H = 1.0 * model.natural_frequency, 5
    kap, frc = model.kappa(w, H), model.force(w, H)
    h = np.zeros(H + 1, complex)
    h[1:] = 1 / kap[1:]
    ylin = h * frc
    p = ReducedProblem.from_receptance(w, h, ylin, (model.mesh(),), mean_kappa=0.0, mean_force=frc[0])
    s1 = solve(p)
    s2 = solve(model.reduced_model().at(w, H))
    assert s1.converged and s2.converged
    np.testing.assert_allclose(s1.harmonics, s2.harmonics, rtol=1e-9, atol=1e-15)


def test_from_matrices_reproduces_sdof_for_two_inertias():
    """Dense reduction of the 2-DOF torsional gear pair gives the SDOF κ_k and F_k.

    Independent check: Özgüven & Houser's SDOF reduction, m_eq = I_p I_g/(I_p r_g² +
    I_g r_p²). The drive train is free (κ_0 = 0, F_0 = W_0): the mean comes from the
    regularised least-squares route, exact up to rounding of k_h (1e-6 N/m of 1e8).
    """
    Ip, Ig, rp, rg = 1.152e-3, 2.0e-3, 0.047, 0.06
    meq = Ip * Ig / (Ip * rg**2 + Ig * rp**2)
    sd = SDOFGearPair(meq, 0.2587e9, 50e-6, 2295.0, LSTE, damping_ratio=0.02)
    w = np.array([rp, rg])
    M, D, K = np.diag([Ip, Ig]), sd.mesh_damping * np.outer(w, w), np.zeros((2, 2))
    rm = ReducedModel.from_matrices(M, D, K, w, sd.static_load * w, [sd.mesh()])
    om, H = 0.9 * sd.natural_frequency, 5
    p = rm.at(om, H)
    assert abs(p.kappa[0, 0, 0]) < 1e-6
    np.testing.assert_allclose(p.kappa[1:, 0, 0], sd.kappa(om, H)[1:], rtol=1e-10)
    np.testing.assert_allclose(p.force[:, 0], sd.force(om, H), rtol=1e-10, atol=1e-9)
    # the rigid-body rotation is removed before Floquet: stable solution, |μ| < 1
    sol = solve(p)
    mu = floquet_multipliers(rm.state_space, rm.nonlinearities, sol.harmonics, om)
    assert mu.size == 2 and np.max(np.abs(mu)) < 1


def _monodromy_by_integration(model, z, omega):
    """Monodromy of the variational equation by finite differences of solve_ivp flows."""
    mesh = model.mesh()
    T = 2 * np.pi / omega
    m, c, kh, b = model.mass, model.mesh_damping, model.mesh_stiffness, model.half_backlash

    def rhs(t, y):
        th = omega * t
        x = evaluate(z, th) - evaluate(mesh.lste, th)
        # variational equation: tangent stiffness k_h where |x| > b
        ks = kh * (abs(x) > b)
        return [y[1], -(c * y[1] + ks * y[0]) / m]

    cols = []
    for y0 in ([1.0, 0.0], [0.0, omega]):
        sol = solve_ivp(rhs, (0, T), y0, method="DOP853", rtol=1e-11, atol=1e-13, max_step=T / 400)
        cols.append(sol.y[:, -1] / (1.0 if y0[0] else omega))
    return np.column_stack(cols)


def test_floquet_monodromy_matches_integrated_variational_equation():
    """Exact piecewise monodromy equals the integrated variational equation (unstable point).

    Independent check: solve_ivp of η'' = -(c η' + k_t(t) η)/m over one period with the
    contact indicator from the HB solution, at a point of the unstable middle branch
    (μ_max > 1). The integrator steps over the kinks with max_step T/400 at rtol 1e-11:
    multipliers agree to 1e-4 relative.
    """
    model = kubo()
    wn = model.natural_frequency
    rm = model.reduced_model()
    from nlgrd.nonlinear.tracing.continuation import continuation

    c = continuation(rm, 1.1 * wn, 0.7 * wn, 5, stability=True)
    i = int(np.argmax(c.curve.floquet_max))
    z, om = c.curve.harmonics[i, 0], c.omega[i]
    mu = np.sort(np.abs(floquet_multipliers(rm.state_space, rm.nonlinearities, z[None], om)))
    assert mu[-1] > 1.05
    Phi = _monodromy_by_integration(model, z, om)
    mu_ref = np.sort(np.abs(np.linalg.eigvals(Phi)))
    np.testing.assert_allclose(mu, mu_ref, rtol=1e-4)
    # Hill's method on the same point (truncation 60 harmonics)
    mu_hill = np.sort(np.abs(hill_multipliers(rm.state_space, rm.nonlinearities, z[None], om, 60)))
    np.testing.assert_allclose(mu_hill, mu, rtol=1e-3)


def test_floquet_in_full_contact_equals_matrix_exponential():
    """With one contact state all period the monodromy is exp(A T), and the shortcut
    μ = exp(λ(A) T) must give its eigenvalues. Independent check: scipy's expm of the
    state matrix built here from the state space, then eigvals; 1e-10 relative (both are
    accurate to rounding for this well-conditioned 2 x 2 case; μ ~ 0.5-0.9)."""
    from scipy.linalg import expm

    model = kubo(W0=20 * 2295.0)  # 20x the load: the mesh never opens
    rm = model.reduced_model()
    om = 0.6 * model.natural_frequency
    sol = solve(rm.at(om, 5))
    assert sol.converged and model.mesh().intervals(sol.harmonics[0]).state.size == 1
    mu = np.sort(np.abs(floquet_multipliers(rm.state_space, rm.nonlinearities, sol.harmonics, om)))
    ss = rm.state_space
    Minv = np.linalg.inv(ss.M)
    A = np.block(
        [
            [np.zeros_like(ss.M), np.eye(len(ss.M))],
            [-Minv @ (ss.K + model.mesh().stiffness * ss.W @ ss.W.T), -Minv @ ss.D],
        ]
    )
    ref = np.sort(np.abs(np.linalg.eigvals(expm(A * 2 * np.pi / om))))
    np.testing.assert_allclose(mu, ref, rtol=1e-10)
    assert mu[-1] < 1


def test_generic_aft_nonlinearity_in_the_solver():
    """A dead zone supplied as AFTNonlinearity gives the BacklashMesh solution.

    Independent check: the exact describing function; AFT with 2048 samples errs by
    ~1e-6 relative (N^-2), bound 1e-4 on the harmonics.
    """
    model = kubo()
    w, H = 1.0 * model.natural_frequency, 5
    kh, b = model.mesh_stiffness, model.half_backlash
    aft = AFTNonlinearity(
        lambda u: kh * deadzone(u, b), lambda u: kh * (np.abs(u) > b), 0, model.lste, n_samples=2048
    )
    exact = solve(model.reduced_model().at(w, H))
    plug = solve(ReducedProblem(w, model.kappa(w, H), model.force(w, H), (aft,)), exact.harmonics * 1.02)
    assert plug.converged
    assert np.max(np.abs(plug.harmonics - exact.harmonics)) < 1e-4 * np.max(np.abs(exact.harmonics))


def test_bad_problem_shapes_raise():
    """Inconsistent shapes are reported, not broadcast silently."""
    from nlgrd.errors import ModelError

    with pytest.raises(ModelError):
        ReducedProblem(1.0, np.ones(3), np.ones(4), ())
