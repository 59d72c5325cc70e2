"""Floquet stability (:mod:`nlgrd.nonlinear.stability.floquet`): the fast default against the reference
monodromy.

The reference is ``method="expm"``, the library's method before issue 10: scipy's
``expm`` of the unscaled state matrix per contact interval and every eigenvalue of the
product (exp(λ T) in full contact). The default (``"auto"``) returns the dominant
multipliers only: the exact neutral μ = 1 of the free, damped drive-train rotation when
an energy argument certifies a time-invariant state stable, else the Ritz values of the
monodromy on its dominant invariant subspace (isolated by repeated squaring) with a
backward-error check.

Tolerances on max |μ|. Stable points: max |μ| = 1 exactly, the free rotation damped by
the motor ([φ; 0] is an exact eigenvector of every contact state), which both methods
reproduce to rounding: |max|μ| - 1| <= 1e-9 (observed 1e-12). Unstable points: the
Ritz values are exact eigenvalues of a matrix within ‖R‖ <= RITZ_RTOL ‖Φ‖_F of the
monodromy Φ, so to first order |Δμ| <= κ(μ) RITZ_RTOL ‖Φ‖_F, κ(μ) = ‖x‖‖y‖/|yᴴx| the
condition number of the dominant multiplier (right and left eigenvectors of Φ, computed
here by a dense solve; 1e-12 is added for the reference's own rounding); a revisited
frequency (shared cache) adds REVISIT_RTOL ‖Φ‖₁. On this sweep (measured on the former
mesh-coordinate engine's basis; now the link model's stability basis) κ = 23-260, bounds
3e-6-4e-5 (all far from deciding a verdict: the least unstable point has max |μ| =
1.0004); observed 2e-12 and 2e-11 (33 of the 72 contact-loss points reuse the other
sweep direction's multipliers).
"""

from __future__ import annotations

import dataclasses as dc
from collections import OrderedDict
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
from threadpoolctl import threadpool_limits

import nlgrd.nonlinear.hb.harmonic_balance as hb
import nlgrd.nonlinear.hb.solvers as hb_solvers
import nlgrd.nonlinear.reduction.linear_algebra as la
import nlgrd.nonlinear.reduction.state_space as hb_state_space
import nlgrd.nonlinear.stability.floquet as fl
from nlgrd.errors import ModelError
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.nonlinear.reduction.state_space import LinearStateSpace
from nlgrd.nonlinear.stability.tangent import tangent_pieces
from nlgrd.rotor.modal import gear_pair_mode
from nlgrd.rotor.rigid_body import rigid_body_modes

TWO_SHAFT = Path(__file__).resolve().parent.parent / "data" / "models" / "two_shaft.toml"
STABLE = 1 + 1e-6


@pytest.fixture(scope="module")
def swept():
    """two_shaft.toml with mesh damping ratio 0.02 (file: 0.005): an up-and-down sweep of
    2 x 110 points over 0.7..1.3 x the gear-pair mode, H = 5, stability=False (about 2 s).
    About a third of the points lose contact and most of those are unstable."""
    with threadpool_limits(limits=1):
        s = load_model(TWO_SHAFT)
        s = dc.replace(s, gear_pairs=(dc.replace(s.gear_pairs[0], damping_ratio=0.02),))
        f0 = float(round(gear_pair_mode(s)[0]))
        om = 2 * np.pi * np.linspace(0.7 * f0, 1.3 * f0, 110)
        model = build_link_model(s)
        res = link_sweep(model, om, H=5, stability=False, period=1).result
    assert np.all(res.converged)
    return model, res


def _points(swept):
    model, res = swept
    return model, list(zip(res.omega, res.harmonics, strict=True))


def _mats(model, w):
    """(M, D, K, W) of the link model's stability basis at ``w`` (the sweep's, sized for
    its top frequency), as plain matrices: every method below runs on the same ones."""
    ss = model.reduced.linear_state_space(w)
    return ss.M, ss.D, ss.K, ss.W


def _state_space(model, w):
    """The stability basis at ``w`` without its larger and full states (the methods are
    compared on one state space)."""
    return LinearStateSpace(*_mats(model, w))


def test_verdicts_and_max_modulus_equal_the_reference_monodromy(swept):
    """At every point of the sweep (220, >= 50 unstable, >= 50 in full contact): the same
    verdict |μ|max < 1 + 1e-6 as the reference and max |μ| within the tolerances of the
    module docstring; in full contact the certified μ = 1 exactly. The same with a cache
    shared by the state spaces of the sweep (the down sweep reuses the up sweep's)."""
    model, pts = _points(swept)
    nl = model.reduced.nonlinearities
    shared = hb_state_space.FloquetCache(maxsize=4096)
    old, new, reuse, lti = [], [], [], []
    with threadpool_limits(limits=1):
        for w, z in pts:
            mats = _mats(model, w)
            ref = fl.floquet_multipliers(LinearStateSpace(*mats), nl, z, w, method="expm")
            old.append(np.max(np.abs(ref)))
            mu = fl.floquet_multipliers(LinearStateSpace(*mats), nl, z, w)
            new.append(np.max(np.abs(mu)))
            again = fl.floquet_multipliers(LinearStateSpace(*mats, cache=shared), nl, z, w)
            reuse.append(np.max(np.abs(again)))
            lti.append(tangent_pieces(nl, z, 1)[0].size == 2)
            if lti[-1]:
                np.testing.assert_array_equal(mu, np.ones(1))
    old, new, reuse, lti = map(np.array, (old, new, reuse, lti))
    assert old.size >= 200
    unstable = old >= STABLE
    assert np.sum(unstable) >= 50
    assert np.sum(lti) >= 50 and np.all(old[lti] < STABLE)
    np.testing.assert_array_equal(new < STABLE, old < STABLE)
    np.testing.assert_array_equal(reuse < STABLE, old < STABLE)
    for mu in (old, new, reuse):
        assert np.max(np.abs(mu[~unstable] - 1)) <= 1e-9
    with threadpool_limits(limits=1):
        for i in np.nonzero(unstable)[0]:
            w, z = pts[i]
            Phi = fl.monodromy(_state_space(model, w), nl, z, w)
            lam, vl, vr = sla.eig(Phi, left=True, right=True)
            j = int(np.argmax(np.abs(lam)))
            kappa = np.linalg.norm(vl[:, j]) * np.linalg.norm(vr[:, j]) / abs(vl[:, j].conj() @ vr[:, j])
            assert abs(abs(lam[j]) - old[i]) <= 1e-10 * old[i]  # the reference's monodromy, another expm
            bound = kappa * fl.RITZ_RTOL * np.linalg.norm(Phi) + 1e-12
            assert abs(new[i] - old[i]) <= bound
            assert abs(reuse[i] - old[i]) <= bound + kappa * fl.REVISIT_RTOL * np.linalg.norm(Phi, 1)
    hits = sum(1 for k in shared._data if k[0] == "monodromy")
    assert hits < np.sum(~lti)  # the down sweep found the up sweep's entries


def test_dense_method_gives_every_multiplier_of_the_reference(swept):
    """method="dense" (scaled state, own Padé expm, merged cyclic intervals) returns the
    same 2N multipliers as the reference, at a full-contact and a contact-loss point:
    sorted moduli within 1e-10 (both dense and backward stable; |μ| <= ~1.1)."""
    model, pts = _points(swept)
    nl = model.reduced.nonlinearities
    kinds = {}
    for w, z in pts:
        kinds.setdefault(tangent_pieces(nl, z, 1)[0].size > 2, (w, z))
    assert len(kinds) == 2
    with threadpool_limits(limits=1):
        for w, z in kinds.values():
            ss = _state_space(model, w)
            ref = np.sort(np.abs(fl.floquet_multipliers(ss, nl, z, w, method="expm")))
            got = np.sort(np.abs(fl.floquet_multipliers(ss, nl, z, w, method="dense")))
            assert got.size == ref.size == 2 * ss.deflated.M.shape[0]
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-10)


def test_neutral_mode_is_an_exact_multiplier_of_every_state(swept):
    """The certificate's μ = 1: two_shaft.toml keeps a free torsional rotation damped by
    the motor (K φ = 0, Wᵀ φ = 0, D φ ≠ 0), so [φ; 0] is in the kernel of the state
    matrix in contact and in separation; it is not a free rigid-body mode (not deflated)."""
    model, pts = _points(swept)
    w, z = pts[0]
    ss = _state_space(model, w)
    assert ss.rigid_body_modes().shape[1] == 0
    ok, Z = la.psd_null_space(ss.K + model.links[0].mesh.stiffness * ss.W @ ss.W.T)
    assert ok and Z.shape[1] == 1
    phi = Z[:, 0]
    assert np.linalg.norm(ss.K @ phi) <= 1e-9 * np.linalg.norm(ss.K)
    assert np.linalg.norm(ss.W.T @ phi) <= 1e-9 * np.linalg.norm(ss.W)
    assert np.linalg.norm(ss.D @ phi) > 1e-6 * np.linalg.norm(ss.D)
    assert la.psd_to_tolerance(ss.D) and fl._spd(ss.M)


def test_certificate_refuses_circulatory_stiffness(swept):
    """A skew (circulatory) part of K breaks the energy argument: no certificate, and the
    dominant multipliers come from the monodromy: max |μ| equal to the reference's within
    1e-8 relative (a small random skew part, 1e-9 of the largest stiffness)."""
    model, pts = _points(swept)
    nl = model.reduced.nonlinearities
    w, z = next((w, z) for w, z in pts if tangent_pieces(nl, z, 1)[0].size == 2)
    ss = _state_space(model, w)
    rng = np.random.default_rng(1)
    S = rng.standard_normal(ss.K.shape)
    Kc = ss.K + 1e-9 * np.max(np.abs(ss.K)) * (S - S.T)
    bent = LinearStateSpace(ss.M, ss.D, Kc, ss.W)
    kt = np.full((1, 1), model.links[0].mesh.stiffness)
    assert fl._neutral_count(ss, kt, True) == 1
    assert fl._neutral_count(bent, kt, True) is None
    with threadpool_limits(limits=1):
        got = fl.floquet_multipliers(bent, nl, z, w)
        ref = fl.floquet_multipliers(bent, nl, z, w, method="expm")
    assert got.size < ref.size
    top = np.max(np.abs(ref))
    assert abs(np.max(np.abs(got)) - top) <= 1e-8 * top


def _state_matrix(ss, kh):
    n = ss.M.shape[0]
    lower = -np.linalg.solve(ss.M, np.column_stack([ss.K + kh * ss.W @ ss.W.T, ss.D]))
    return np.block([[np.zeros((n, n)), np.eye(n)], [lower]])


def test_free_modes_agree_with_rigid_body_modes(swept):
    """The fast free-mode test of the deflation finds what rigid_body_modes finds on the
    benchmark model (a damped free rotation: none), a grounded chain (none) and a free,
    undamped two-inertia gear pair (one)."""
    model, pts = _points(swept)
    ss = _state_space(model, pts[0][0])
    cases = [(ss.K, ss.D, ss.W, ss.M)]
    k = 1e6 * np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    cases.append((k, 1e-3 * k, np.array([[0.0], [1.0], [-1.0]]), np.diag([1.0, 2.0, 3.0])))
    w2 = np.array([0.05, 0.06])
    cases.append((np.zeros((2, 2)), 10.0 * np.outer(w2, w2), w2[:, None], np.diag([1e-3, 2e-3])))
    for (K, D, W, M), expect in zip(cases, (0, 0, 1), strict=True):
        F = la.free_modes(K, D, W)
        assert F is not None and F.shape[1] == expect
        assert rigid_body_modes((K + K.T) / 2, M, constraints=(K, D, W.T)).shape[1] == expect


def test_free_basis_vector_of_kubo_rig_is_deflated():
    """Kubo's rig: the stability basis holds the free (undamped) rotation of the drive
    train as one of its vectors, with a stiffness diagonal of rounding (~1e-20 of the
    largest). Both rigid_body_modes (which counts a rounding-level diagonal as zero) and
    the fast test find it, and it is real: undeflated, the full-contact state
    matrix has a pair of eigenvalues within 1e-2 of 0 (the Jordan block at 0 split by
    rounding, which in a product of exponentials becomes 1 ± 1e-4 and a false
    instability); deflated, none."""
    kubo = load_model(TWO_SHAFT.parent.parent / "case_studies" / "kubo.toml")
    om = 2 * np.pi * gear_pair_mode(kubo)[0]
    model = build_link_model(kubo)
    model.receptance.prepare_stability(om)
    ss = _state_space(model, om)
    assert rigid_body_modes((ss.K + ss.K.T) / 2, ss.M, constraints=(ss.K, ss.D, ss.W.T)).shape[1] == 1
    R = ss.rigid_body_modes()
    assert R.shape[1] == 1
    np.testing.assert_allclose(R.T @ ss.M @ R, np.eye(1), atol=1e-12)
    for A in (ss.K, ss.D, ss.W.T):
        assert np.linalg.norm(A @ R) <= 1e-8 * np.linalg.norm(A) * np.linalg.norm(R)
    kh = model.links[0].mesh.stiffness
    near = [np.sum(np.abs(np.linalg.eigvals(_state_matrix(x, kh))) < 1e-2) for x in (ss, ss.deflated)]
    assert near == [2, 0]


def test_psd_helpers():
    """psd_null_space: a rank-deficient PSD matrix (diagonal over 8 decades, as an FE
    stiffness with translations and rotations) gives its null space; an indefinite one
    is refused; psd_to_tolerance agrees."""
    rng = np.random.default_rng(0)
    B = rng.standard_normal((12, 9))
    s = np.logspace(0, 4, 12)
    A = (B @ B.T) * np.outer(s, s)
    ok, Z = la.psd_null_space(A)
    assert ok and Z.shape == (12, 3)
    d = np.sqrt(np.diag(A))
    Zs = Z * d[:, None]  # the null vectors of the Jacobi-scaled matrix
    assert np.linalg.norm((A / np.outer(d, d)) @ Zs) <= 1e-10 * np.linalg.norm(Zs)
    assert la.psd_to_tolerance(A)
    C = A.copy()
    C[0, 0] = -1e-3 * A[0, 0]
    assert la.psd_null_space(C) == (False, None)
    assert not la.psd_to_tolerance(C)
    E = np.diag([1.0, -1.0])
    assert not la.psd_null_space(E)[0] and not la.psd_to_tolerance(E)
    assert la.psd_null_space(np.zeros((2, 2)))[1].shape == (2, 2)


def test_expm_matches_scipy():
    """Padé [13/13] with scaling and squaring equals scipy's expm to 1e-12 relative, for
    ‖X‖₁ from 1e-3 to 1e2 (oscillatory, lightly damped spectra as in the state matrices)."""
    rng = np.random.default_rng(2)
    n = 20
    S = rng.standard_normal((n, n))
    base = (S - S.T) - 0.05 * np.eye(n)
    for scale in (1e-3, 0.3, 5.0, 40.0, 120.0):
        X = scale * base / np.linalg.norm(base, 1)
        ref = sla.expm(X)
        assert np.linalg.norm(la.expm(X) - ref) <= 1e-12 * np.linalg.norm(ref)


def test_small_systems_return_every_multiplier():
    """Up to DENSE_STATE_LIMIT the default is the dense method: the 2 x 2 single-DOF gear
    pair gets both multipliers, equal to the reference."""
    from nlgrd.nonlinear.models.sdof import SDOFGearPair

    LSTE = np.array([0.0, 2e-6, 1e-6])
    sd = SDOFGearPair(4.7e-2, 0.2587e9, 50e-6, 2295.0, LSTE, damping_ratio=0.02)
    rm = sd.reduced_model()
    om = 0.8 * sd.natural_frequency
    sol = hb_solvers.solve(rm.at(om, 5))
    mu = fl.floquet_multipliers(rm.state_space, rm.nonlinearities, sol.harmonics, om)
    ref = fl.floquet_multipliers(rm.state_space, rm.nonlinearities, sol.harmonics, om, method="expm")
    assert mu.size == ref.size == 2
    np.testing.assert_allclose(np.sort(np.abs(mu)), np.sort(np.abs(ref)), rtol=1e-12)


def test_cache_is_bounded_and_on_objects():
    """FloquetCache drops its oldest entry when full; no Floquet cache is a module global
    (the reference's eigenvalue cache lives on the state space now)."""
    c = hb_state_space.FloquetCache(maxsize=3)
    for i in range(5):
        assert c.get(i, lambda i=i: i * i) == i * i
    assert len(c) == 3 and c.peek(0) is None and c.peek(4) == 16
    assert not hasattr(hb, "_EIG_CACHE")
    for mod in (fl, hb, hb_state_space):
        globals_ = [
            k for k, v in vars(mod).items() if isinstance(v, dict | OrderedDict | hb_state_space.FloquetCache)
        ]
        assert [k for k in globals_ if not k.startswith("__")] == []
    ss = LinearStateSpace([[1.0]], [[0.1]], [[0.0]], [[1.0]])
    assert ss.floquet_cache is ss.floquet_cache and LinearStateSpace([[1.0]], [[0.1]], [[0.0]], [[1.0]]) == ss


def test_unknown_method_is_a_model_error():
    """An unknown Floquet method is a ModelError naming the method."""
    ss = LinearStateSpace([[1.0]], [[0.1]], [[0.0]], [[1.0]])
    with pytest.raises(ModelError):
        fl.floquet_multipliers(ss, (), np.zeros((1, 3)), 1.0, method="fast")


def test_mesh_block_splits_off_only_what_the_model_decouples(swept):
    """The axial modes of the spur-gear drive move neither the mesh nor anything coupled to
    it: mesh_block leaves them out (their couplings are rounding of the basis projection,
    <= 1e-11), and the dense method with the split equals the reference (previous test).
    A coupling of 1e-9 of the largest mass entry joins that coordinate (and its axial
    neighbours) to the block; one
    between GAP_RTOL and BLOCK_RTOL (neither rounding nor clearly physical) keeps all."""
    model, pts = _points(swept)
    ss = _state_space(model, pts[0][0])
    block = la.mesh_block(ss.M, ss.D, ss.K, ss.W)
    side = np.nonzero(~block)[0]
    assert 0 < side.size < block.size // 4
    for A in (ss.M, ss.D, ss.K):
        assert np.max(np.abs(A[np.ix_(block, ~block)])) <= la.GAP_RTOL * np.max(np.abs(A))
    M = ss.M.copy()
    i, j = side[0], np.nonzero(block)[0][0]
    M[i, j] = M[j, i] = 1e-9 * np.max(np.abs(M))
    grown = la.mesh_block(M, ss.D, ss.K, ss.W)
    assert grown[i] and 0 < np.sum(~grown) < side.size  # i and what it couples to
    M[i, j] = M[j, i] = 3e-11 * np.max(np.abs(M))
    assert la.mesh_block(M, ss.D, ss.K, ss.W).all()
    lam = fl._prepared(ss).side
    assert lam.size == 2 * side.size and np.all(lam.real <= 1e-9 * np.abs(lam).max())


def test_kubo_rig_verdicts_equal_the_reference_with_and_without_deflation():
    """Kubo's rig (free, undamped drive-train rotation, undamped modes off the mesh, so
    max |μ| = 1 at stable points), an up-and-down sweep of 2 x 20 points over its range
    (27 of the 40 lose contact, one is unstable): the default's verdict equals the
    reference's at every point, with the deflation and without it (the dense reference is
    not thrown by the undeflated Jordan block at μ = 1: it splits it by ~1e-8 at most).
    Before the free basis vector was deflated, the default's Ritz values split it by
    1.2e-4 (the square root of their backward error) and called stable points unstable
    (109 of 122 in a 61-speed sweep)."""
    kubo = load_model(TWO_SHAFT.parent.parent / "case_studies" / "kubo.toml")
    with threadpool_limits(limits=1):
        model = build_link_model(kubo)
        om = np.linspace(4000, 16000, 20) * np.pi / 30 / model.receptance.plan.speed_per_base
        res = link_sweep(model, om, H=5, stability=False, period=1).result
        nl = model.reduced.nonlinearities
        verdicts = []
        for w, z, ok in zip(res.omega, res.harmonics, res.converged, strict=True):
            if not ok:
                continue
            ss = _state_space(model, w)
            got = [fl.floquet_multipliers(ss, nl, z, w)]
            got.append(fl.floquet_multipliers(ss, nl, z, w, method="expm"))
            got.append(fl.floquet_multipliers(ss, nl, z, w, method="expm", deflate=False))
            verdicts.append([np.max(np.abs(mu)) < STABLE for mu in got])
    v = np.array(verdicts)
    assert v.shape[0] >= 30 and 0 < np.sum(~v[:, 1]) < v.shape[0]
    np.testing.assert_array_equal(v[:, 0], v[:, 1])
    np.testing.assert_array_equal(v[:, 0], v[:, 2])


def test_certificate_cache_sees_the_damping(swept):
    """The certificate with a shared cache (its null space of K_t kept per K_t and M, the
    same for all three state spaces here) answers as without one: a gyroscopic (skew)
    change of D keeps it, a negative damping direction refuses it, in whichever order the
    three state spaces meet the cache. A cache of the whole answer by K_t and M alone would
    return the first one's for all (the answers are exact integers: equality is the check)."""
    model, pts = _points(swept)
    w, _ = pts[0]
    ss = _state_space(model, w)
    kt = np.full((1, 1), model.links[0].mesh.stiffness)
    rng = np.random.default_rng(2)
    S = rng.standard_normal(ss.D.shape)
    v = np.linalg.eigh(ss.D + ss.D.T)[1][:, 0]  # the least damped direction
    big = np.max(np.abs(ss.D))
    spaces = [
        LinearStateSpace(ss.M, ss.D, ss.K, ss.W),
        LinearStateSpace(ss.M, ss.D + 0.1 * big * (S - S.T), ss.K, ss.W),  # gyroscopic: sym(D) kept
        LinearStateSpace(ss.M, ss.D - 0.1 * big * np.outer(v, v), ss.K, ss.W),  # an active direction
    ]
    plain = [fl._neutral_count(s, kt, True) for s in spaces]
    assert plain == [1, 1, None]
    for order in ((0, 1, 2), (2, 1, 0)):
        shared = hb_state_space.FloquetCache(maxsize=64)
        for i in order:
            s = spaces[i]
            cached = LinearStateSpace(s.M, s.D, s.K, s.W, cache=shared)
            assert fl._neutral_count(cached, kt, True) == plain[i]
            assert fl._neutral_count(cached, kt, True) == plain[i]  # the stored answer


def test_truncated_basis_analysis_is_kept_per_orbit(swept):
    """On a truncated basis (``full`` given) the result of an orbit is kept in the shared
    cache: the same orbit again takes no new analysis and returns equal multipliers (a
    copy: changing one leaves the kept one alone); another orbit, or the same numbers with
    other law objects, is analysed afresh; every result equals the full state's own."""
    model, pts = _points(swept)
    nl = tuple(model.reduced.nonlinearities)
    w, z = next((w, z) for w, z in pts if tangent_pieces(nl, z, 1)[0].size > 2)
    mats = _mats(model, w)
    built = []

    def full():
        built.append(LinearStateSpace(*mats))
        return built[-1]

    ss = LinearStateSpace(*mats, cache=hb_state_space.FloquetCache(16), full=full)
    with threadpool_limits(limits=1):
        ref = fl.floquet_multipliers(LinearStateSpace(*mats), nl, z, w)
        first = fl.floquet_multipliers(ss, nl, z, w)
        first[:] = np.nan
        again = fl.floquet_multipliers(ss, nl, z, w)
        assert len(built) == 1
        np.testing.assert_array_equal(again, ref)
        np.testing.assert_array_equal(fl.floquet_multipliers(ss, [dc.replace(n) for n in nl], z, w), ref)
        assert len(built) == 2
        z2 = z.copy()
        z2[..., 1] *= 1 + 1e-6
        fl.floquet_multipliers(ss, nl, z2, w)
        assert len(built) == 3
