"""Arc-length continuation (unstable branch, turning points) and FE time integration."""

from pathlib import Path

import numpy as np
import pytest

from nlgrd.nonlinear.fourier.harmonics import differentiate, sample
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.laws.force_laws import BacklashMesh
from nlgrd.nonlinear.models.sdof import SDOFGearPair
from nlgrd.nonlinear.results.metrics import TimeHistory, metrics_from_harmonics, metrics_from_history
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.tracing.continuation import continuation
from nlgrd.nonlinear.tracing.sweep import sweep
from nlgrd.timedomain.integrator import static_solution
from nlgrd.timedomain.links import LinkIntegrator, settle

LSTE = np.array([0.0, 1.24e-6, 0.0, 0.50e-6, 0.30e-6, 0.10e-6, -0.05e-6])
MAIN = SDOFGearPair(0.261, 0.2587e9, 50e-6, 2295.0, LSTE, damping_ratio=0.02)
WN = MAIN.natural_frequency


def integrate(M, D, K, w, mesh, F0, om, steps):
    """HHT-α integration of the FE matrices with one mesh (:meth:`LinkIntegrator.of_mesh`)
    from the static solution to a periodic steady state (period-to-period change of δ
    below 1e-6 of its range plus the static mesh deflection): (converged, the last
    period's mesh metrics, every DOF over the last period)."""
    integ = LinkIntegrator.of_mesh(M, D, K, w, mesh, F0, om, steps_per_period=steps)
    floor = abs(F0 @ w) / (mesh.stiffness * (w @ w))
    run = settle(integ, integ.start(), tol=1e-6, max_periods=3000, min_periods=5, floor=floor)
    last = integ.record(run.start, np.arange(integ.N))
    e, edot = sample(mesh.lste, steps), om * sample(differentiate(mesh.lste), steps)
    force = last.g[0] + mesh.damping * (last.ydot[0] - edot)
    history = TimeHistory(integ.dt * np.arange(steps), last.y[0], last.ydot[0], e, edot, force)
    return run.converged, metrics_from_history(history, mesh), last.q


def test_unstable_branch_between_stable_branches_and_folds_at_sweep_jumps():
    """The continuation curve folds twice; the middle branch is unstable and lies between.

    Independent checks: (1) the up/down HB sweeps on a 0.5 % grid, whose jumps must
    bracket the turning points within one grid step; (2) Floquet stability changes
    exactly at the turning points (a fold is a μ = 1 bifurcation); (3) on the common
    frequency range the unstable branch's RMS DTE lies strictly between the two stable
    branches' (interpolated) values.
    """
    rm = MAIN.reduced_model()
    c = continuation(rm, 1.2 * WN, 0.6 * WN, 5)
    assert c.complete
    assert c.turning_omegas.size == 2
    w_lo, w_hi = np.sort(c.turning_omegas)
    step = 0.005 * WN
    grid = np.arange(0.66, 1.0, 0.005) * WN
    sw = sweep(rm, grid, 5, stability=False)
    jumps = {j.direction: j for j in sw.jumps()}
    assert set(jumps) == {"up", "down"}
    assert jumps["up"].omega_from - 1e-9 <= w_hi <= jumps["up"].omega_to + step
    assert jumps["down"].omega_to - step <= w_lo <= jumps["down"].omega_from + 1e-9
    i1, i2 = np.sort(c.turning_indices)
    st = c.stable
    assert np.all(st[: i1 - 1]) and not np.any(st[i1 + 2 : i2 - 1]) and np.all(st[i2 + 2 :])
    # stability per point is known everywhere and the middle is between the outer branches
    assert np.all(c.curve.stability_known)
    rms = c.curve.dte_rms
    w = c.omega
    first, middle, last = slice(0, i1 + 1), slice(i1 + 1, i2 + 1), slice(i2 + 1, None)
    for wm, rm_mid in zip(w[middle][2:-2], rms[middle][2:-2], strict=True):
        a = np.interp(wm, w[first][::-1], rms[first][::-1])
        b = np.interp(wm, w[last], rms[last])
        assert min(a, b) < rm_mid < max(a, b)
    frame = c.to_frame()
    assert "arclength [-]" in frame and str(frame["stable"].dtype) == "boolean"
    assert frame["stable"].notna().all()  # stability computed at every point
    # an unstable orbit is never written as "periodic" (issue 33): its response says unstable
    assert set(frame.loc[~frame["stable"], "response"]) == {"unstable periodic"}
    assert set(frame.loc[frame["stable"], "response"]) == {"periodic"}


def _torsional_chain(n_motor_springs=1):
    """Motor inertia - torsion spring - pinion | mesh | gear - spring - load (free train)."""
    Im, Ip, Ig, Il = 5.762e-3, 1.152e-3, 1.152e-3, 1.152e-3
    kt = 2.0e4
    rp = rg = 0.047
    M = np.diag([Im, Ip, Ig, Il])
    K = np.zeros((4, 4))
    for a, b in ((0, 1), (2, 3)):
        K[np.ix_([a, b], [a, b])] += kt * np.array([[1, -1], [-1, 1]])
    w = np.array([0.0, rp, rg, 0.0])
    return M, K, w


def test_fe_time_domain_two_inertias_equals_sdof():
    """HHT-α integration of the 2-DOF torsional pair equals the SDOF harmonic balance.

    Independent check: Özgüven & Houser's exact reduction to δ = r_p θ_p + r_g θ_g with
    m_eq (the pair has a free rigid-body rotation; the static torques are balanced).
    HHT-α is second order: with 512 steps per period the RMS and max-force errors are
    ~1e-4 (measured 6e-5 at resonance), bound 1e-3; H = 15 HB is exact to 1e-5.
    """
    Ip, Ig, r = 1.152e-3, 1.152e-3, 0.047
    meq = Ip * Ig / (Ip * r**2 + Ig * r**2)
    sd = SDOFGearPair(meq, 0.2587e9, 50e-6, 2295.0, LSTE, damping_ratio=0.02)
    w = np.array([r, r])
    M, D, K = np.diag([Ip, Ig]), sd.mesh_damping * np.outer(w, w), np.zeros((2, 2))
    F0 = sd.static_load * w
    om = 1.0 * sd.natural_frequency
    converged, mt, q = integrate(M, D, K, w, sd.mesh(), F0, om, 512)
    assert converged
    hb = solve(sd.reduced_model().at(om, 15))
    ref = metrics_from_harmonics(hb.harmonics[0], om, sd.mesh())
    assert ref.contact_loss_fraction > 0.2
    assert mt.dte_rms == pytest.approx(ref.dte_rms, rel=1e-3)
    assert mt.force_max == pytest.approx(ref.force_max, rel=1e-3)
    assert q[0].shape == (512,)


def test_fe_time_domain_chain_equals_reduced_harmonic_balance():
    """A 4-DOF torsional chain: HHT-α time integration equals HB on the reduced problem.

    Independent checks: the dense receptance reduction (:meth:`ReducedModel.from_matrices`,
    κ_0 = 0 from the free rigid-body mode) with H = 15 against direct integration of the
    4 DOFs (256 steps per period, second-order error ~5e-4); the Floquet multipliers of
    the chain (rigid-body rotation deflated) show the HB solution is stable, as the
    time integration that converged to it requires.
    """
    M, K, w = _torsional_chain()
    meq = 1.152e-3 / (2 * 0.047**2)
    cm = 2 * 0.02 * np.sqrt(0.2587e9 * meq)
    mesh = BacklashMesh(0.2587e9, 50e-6, LSTE, cm, 2295.0)
    D = cm * np.outer(w, w) + 1e-4 * K
    F0 = 2295.0 * 0.047 * np.array([1.0, 0.0, 0.0, 1.0])  # motor drives, load resists
    qs = static_solution(K, w, mesh, F0)
    assert w @ qs == pytest.approx(50e-6 + 2295.0 / 0.2587e9, rel=1e-9)
    rm = ReducedModel.from_matrices(M, D, K, w, F0, [mesh])
    om = 1.05 * np.sqrt(0.2587e9 / meq)  # above the fold: a single, separated solution
    hb = sweep(rm, np.array([1.2, 1.1, 1.05]) * om / 1.05, 15, "down")
    assert hb.converged[-1] and hb.stable[-1] and hb.contact_loss_fraction[-1] > 0.1
    converged, mt, _ = integrate(M, D, K, w, mesh, F0, om, 256)
    assert converged
    assert mt.dte_rms == pytest.approx(hb.dte_rms[-1], rel=2e-3)
    assert mt.force_max == pytest.approx(hb.force_max[-1], rel=2e-3)
    mu = floquet_multipliers(rm.state_space, rm.nonlinearities, hb.harmonics[-1], om)
    assert mu.size == 6  # 4 DOFs minus the rigid-body rotation, times 2


def test_static_solution_rejects_unbalanced_load():
    """An unbalanced static torque on a free train has no static solution (ModelError),
    with or without the mass matrix."""
    from nlgrd.errors import ModelError

    M, K, w = _torsional_chain()
    mesh = BacklashMesh(0.2587e9, 50e-6, LSTE, 0.0, 2295.0)
    for mass in (M, None):
        with pytest.raises(ModelError, match="self-equilibrated"):
            static_solution(K, w, mesh, np.array([1.0, 0.0, 0.0, 0.0]), M=mass)


def test_sparse_static_solution_equals_dense_least_squares():
    """The bordered sparse LU of K + k_h w wᵀ with its rigid-body modes gives the
    minimum-norm solution of dense least squares (numpy lstsq, an SVD: independent of
    the rigid-body decision), to 1e-9 relative: on the two-shaft FE
    model (132 DOFs, a free rolling mode of the drive train), on the small torsional chain
    and on a 1600-DOF chain (rigid-body modes by the sparse eigensolver)."""
    from nlgrd.io.model_file import load_model
    from nlgrd.rotor.assembly import assemble

    s = load_model(Path(__file__).resolve().parent.parent / "data" / "models" / "two_shaft.toml")
    lm = assemble(s, mesh_stiffness=False)
    g = s.gear_pairs[0]
    mesh = BacklashMesh(lm.meshes[0].stiffness, g.half_backlash, LSTE, 0.0, g.static_load)
    cases = [(lm.M, lm.K, lm.meshes[0].w, g.static_torques(s))]
    M, K, w = _torsional_chain()
    cases.append((M, K, w, 2295.0 * 0.047 * np.array([1.0, 0.0, 0.0, 1.0])))
    # a 1600-inertia torsional chain, free at both ends, meshing at DOFs 0 and 1599: the
    # rigid-body modes come from the sparse eigensolver path (more than 1500 DOFs)
    n = 1600
    kc = 1e6 * np.ones(n - 1)
    K = np.diag(np.concatenate([kc, [0]]) + np.concatenate([[0], kc])) - np.diag(kc, 1) - np.diag(kc, -1)
    w = np.zeros(n)
    w[0], w[-1] = 0.047, -0.047
    cases.append((np.diag(np.linspace(1e-3, 2e-3, n)), K, w, 1e3 * (np.eye(n)[1] - np.eye(n)[-2])))
    for M, K, w, F0 in cases:
        Ks = (K.toarray() if hasattr(K, "toarray") else K) + mesh.stiffness * np.outer(w, w)
        rhs = F0 + mesh.stiffness * w * (mesh.lste[0] + mesh.half_backlash)
        dense = np.linalg.lstsq(Ks, rhs, rcond=None)[0]
        sparse = static_solution(K, w, mesh, F0, M=M)
        assert np.max(np.abs(sparse - dense)) < 1e-9 * np.max(np.abs(dense))


def test_plots_return_axes():
    """Sweep, continuation and time-history plots draw and return their axes (smoke test)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nlgrd.nonlinear.results.metrics import time_history

    rm = MAIN.reduced_model()
    sw = sweep(rm, np.linspace(0.85, 1.0, 7) * WN, 3)
    c = continuation(rm, 1.0 * WN, 0.9 * WN, 3, ds_max=0.05)
    ax = sw.plot("dslr")
    assert c.plot(ax=ax) is ax
    th = time_history(sw.harmonics[0, 0], sw.omega[0], rm.metrics.mesh)
    assert th.plot(quantity="force") is not None
    assert len(ax.lines) >= 3
    plt.close("all")


@pytest.mark.parametrize("zeta", [0.02, 0.005])
def test_jump_landing_without_floquet_matches_floquet_checked_landing(zeta):
    """After a fold, a sweep without stability accepts the first curve crossing past an
    even number of turning points (the determinant's sign); with stability, the first
    Floquet-stable crossing. On Kubo's single-DOF rig (131 frequencies 0.3-1.6 ωn, up and
    down, several jumps at ζ = 0.005) both land on the same solutions at every point,
    and the landing points are Floquet-stable. Independent check: Floquet multipliers of
    the exact monodromy. (``leave_unstable=False``: what is compared is the landing after
    a fold; at ζ = 0.005 some points lose stability without a fold, which only the sweep
    with stability can see and leave, tests/test_geared_response.py.)"""
    m = SDOFGearPair(0.261, 0.2587e9, 50e-6, 2295.0, LSTE, damping_ratio=zeta)
    rm = m.reduced_model()
    om = m.natural_frequency * np.linspace(0.3, 1.6, 131)
    with_f = sweep(rm, om, H=5, stability=True, leave_unstable=False)
    without = sweep(rm, om, H=5, stability=False)
    assert with_f.converged.all() and without.converged.all()
    assert np.sum(with_f.branch_switch) >= 3
    np.testing.assert_array_equal(with_f.branch_switch, without.branch_switch)
    np.testing.assert_allclose(
        without.harmonics, with_f.harmonics, rtol=0, atol=1e-9 * np.max(np.abs(with_f.harmonics))
    )
    assert np.all(with_f.floquet_max[with_f.branch_switch] < 1 + 1e-6)
    left = sweep(rm, om, H=5, stability=True)  # the default leaves unstable branches
    assert not np.any(left.converged & ~left.stable & ~left.no_stable)
