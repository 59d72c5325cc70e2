"""The link reduction's strategies against each other, their derivatives against
differences, its stability basis against the full state, and its refusals.

(The file began as issue 33's guard rail between the former single-mesh path and the link
path; with that path deleted, the checks that compared the two are answered by
independent references elsewhere: κ_k, F_k and recovery against dense solves in
tests/test_link_receptance.py and tests/test_direct_receptance.py, the sweeps' verdicts
against time integration in tests/test_moved_verdicts.py.)

Models: ``data/models/two_shaft.toml`` and ``data/case_studies/kubo.toml``, as loaded
and modified in memory (:func:`system`). The default reduction ("auto"): the banded LU on
two_shaft (110 DOFs coupled to the mesh) and on every tabulated or loss-factor variant, the
pole-residue form on kubo's base and cross variants (54 DOFs):

- ``cross``: every bearing cross-coupled, k_yz = 0.2 k_yy = -k_zy, c_yz = 0.1 c_yy = -c_zy;
- ``tabulated``: one more bearing, tabulated against speed (at 100 and 3000 rad/s:
  k_yy 0.5 -> 2 k, k_zz 0.6 -> 1.5 k, k_yz 0 -> 0.3 k, k the first bearing's k_yy), at a
  node with no bearing (two_shaft: pinion shaft node 3; kubo: shaft 0 node 0), so the
  others still hold every shaft;
- ``loss``: a hysteretic loss factor η = 0.01 in every material.
"""

from __future__ import annotations

import dataclasses
import tomllib
from functools import cache
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from nlgrd.errors import ModelError
from nlgrd.io.model_file import model_from_file_data
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep

ROOT = Path(__file__).resolve().parents[1]
FILES = {
    "two_shaft": ROOT / "data" / "models" / "two_shaft.toml",
    "kubo": ROOT / "data" / "case_studies" / "kubo.toml",
}
#: Mesh frequencies [Hz] of the pointwise checks: below, near and above the gear-pair
#: mode (two_shaft 3662 Hz, kubo 4915 Hz).
POINTS_HZ = {"two_shaft": (1500.0, 3600.0, 5200.0), "kubo": (2000.0, 3400.0, 4500.0)}
H = 5
#: κ_k, F_k, dκ_k/dω and recovery: two factorisations of matrices with condition up to
#: ~1e6 (dense LU or pole-residue against sparse LU), rounding ~1e-10 measured.
REDUCTION_RTOL = 1e-9
VARIANTS = ("base", "cross", "tabulated", "loss")


@cache
def system(name: str, variant: str = "base"):
    """The model ``name`` with the modification ``variant`` (module docstring)."""
    path = FILES[name]
    data = tomllib.loads(path.read_text())
    if variant == "cross":
        for b in data["bearings"]:
            k, c = b.get("kyy", 0.0), b.get("cyy", 0.0)
            b.update(kyz=0.2 * k, kzy=-0.2 * k, cyz=0.1 * c, czy=-0.1 * c)
    elif variant == "tabulated":
        first = data["bearings"][0]
        k = first["kyy"]
        node = 3 if name == "two_shaft" else 0
        extra = {"shaft": 0, "node": node, "cyy": first["cyy"], "czz": first["czz"]}
        extra.update(speeds=[100.0, 3000.0], kyy=[0.5 * k, 2 * k], kzz=[0.6 * k, 1.5 * k], kyz=[0.0, 0.3 * k])
        data["bearings"].append(extra)
    elif variant == "loss":
        for m in data["materials"].values():
            m["loss_factor"] = 0.01
    return model_from_file_data(data, str(path))


@cache
def models(name: str, variant: str = "base"):
    """The link model of one system (default reduction)."""
    return build_link_model(system(name, variant))


def _flat(a) -> np.ndarray:
    return np.asarray(a, dtype=complex).reshape(H + 1, -1)


def _rel(a, b, scale) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / scale)


# ----------------------------------------------------------------------------- κ and F


def _richardson(f, w: float, h: float) -> np.ndarray:
    """Central difference of ``f(ω, H)`` with one Richardson step (error O(h^4))."""

    def cd(s):
        return (_flat(f(w + s, H)) - _flat(f(w - s, H))) / (2 * s)

    return (4 * cd(h / 2) - cd(h)) / 3


# ------------------------------------------------ the link path's banded strategy (issue 33)


@cache
def banded(name: str, variant: str = "base"):
    """The link model of :func:`system` with ``method="banded"``."""
    return build_link_model(system(name, variant), method="banded")


def _banded_worst(a, b, w: float) -> dict:
    """Worst differences of κ_k, F_k (against max|F| and, k >= 1, max|F_k>=1|) and, where
    both have them, dκ_k/dω and dF_k/dω (k >= 1) of two link receptances ``a`` (the banded)
    and ``b`` at ``w``."""
    (ka, fa), da = a.terms(w, H), a.derivatives(w, H) if a.has_derivatives else None
    (kb, fb), db = b.terms(w, H), b.derivatives(w, H) if da is not None else None
    ka, fa, kb, fb = _flat(ka), _flat(fa), _flat(kb), _flat(fb)
    out = {
        "kappa": _rel(ka, kb, np.max(np.abs(ka[1:]))),
        "F": _rel(fa, fb, np.max(np.abs(fa))),
        "F_k": _rel(fa[1:], fb[1:], np.max(np.abs(fa[1:]))),
    }
    if db is not None:
        dka, dfa = _flat(da[0]), _flat(da[1])
        dkb, dfb = _flat(db[0]), _flat(db[1])
        out["dkappa"] = _rel(dka, dkb, np.max(np.abs(dka)))
        out["dF_k"] = _rel(dfa[1:], dfb[1:], np.max(np.abs(dfa[1:])))
    return out


def _merge(worst: dict, new: dict) -> dict:
    return {k: max(worst.get(k, 0.0), new.get(k, 0.0)) for k in {**worst, **new}}


def _clearance_system(unbalance: bool):
    from nlgrd.io.model_file import load_model
    from nlgrd.rotor.system import Unbalance

    s = load_model(ROOT / "data" / "models" / "two_shaft_clearance.toml")
    if unbalance:
        s = dataclasses.replace(s, unbalance=(Unbalance(0, 4, 1e-4, 0.3), Unbalance(1, 2, 2e-4, 1.0)))
    return s


@pytest.mark.parametrize(
    "case", ["two_shaft", "kubo", "two_shaft_clearance", "two_shaft_clearance_unbalance"]
)
def test_banded_link_strategy_equals_the_other_link_strategies(case):
    """``"banded"`` against the link path's pole-residue form and its
    dense LU (``"direct"``) at three frequencies, with the bearing clearance of
    data/models/two_shaft_clearance.toml (3 link coordinates, the Woodbury matrix 3 x 3)
    and with two unbalances besides (forces off the links): κ_k, F_k, dκ_k/dω, dF_k/dω as
    above and the recovery of every third DOF from random (Y, G), its mean and alternating
    harmonics each on its own scale, to REDUCTION_RTOL."""
    if case in FILES:
        s, pts = system(case), POINTS_HZ[case]
    else:
        s, pts = _clearance_system(case.endswith("unbalance")), POINTS_HZ["two_shaft"]
    b, poles, direct = (build_link_model(s, method=m).receptance for m in ("banded", "poles", "direct"))
    assert b.method == "banded" and poles.method == "poles" and direct.method == "direct"
    d = b.n_coords
    rng = np.random.default_rng(1)
    worst: dict = {}
    dofs = np.arange(0, s.n_dofs, 3)
    for w in 2 * np.pi * np.array(pts):
        Y, G = 1e-6 * rng.standard_normal((d, 2 * H + 1)), 1e2 * rng.standard_normal((d, 2 * H + 1))
        qb = b.recover(w, H, Y, G, dofs)
        for other in (poles, direct):
            worst = _merge(worst, _banded_worst(b, other, w))
            q = other.recover(w, H, Y, G, dofs)
            rec = max(
                _rel(qb[:, p], q[:, p], np.max(np.abs(qb[:, p]))) for p in (slice(0, 1), slice(1, None))
            )
            worst = _merge(worst, {"recover": rec})
    print(f"{case} (d = {d}): banded vs poles, direct " + ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))
    assert b._band_solver().n_sparse == 0 and len(worst) == 6
    assert max(worst.values()) <= REDUCTION_RTOL


@pytest.mark.parametrize("case", ["two_shaft", "two_shaft_clearance_unbalance"])
def test_banded_link_evaluation_factorises_once(monkeypatch, case):
    """One corrector evaluation on ``"banded"`` (dκ_k/dω and dF_k/dω, then κ_k and F_k at
    the same frequency) factorises each Z'_k once (it did twice), as in the other order, and
    gives what a receptance asked κ_k first (its plain solve, then the derivatives on the same
    LUs) gives, bit for bit: with one link coordinate (two_shaft) κ_k takes the derivative
    solve's h_k, with three (the bearing clearance, unbalance forces off the links) its own
    plain solve."""
    from nlgrd.nonlinear.reduction import direct_receptance as dr

    s = system(case) if case in FILES else _clearance_system(True)
    first, plain_first = (build_link_model(s, method="banded").receptance for _ in range(2))
    assert first.method == "banded" and first.n_coords == (1 if case in FILES else 3)
    factor, calls = dr._Band.factor, []
    monkeypatch.setattr(dr._Band, "factor", lambda band, data: calls.append(1) or factor(band, data))
    for w in 2 * np.pi * np.array(POINTS_HZ["two_shaft"]):
        n = len(calls)
        d = first.derivatives(w, H)
        t = first.terms(w, H)
        assert len(calls) - n == H
        n = len(calls)
        t_ref = plain_first.terms(w, H)
        d_ref = plain_first.derivatives(w, H)
        assert len(calls) - n == H
        for a, b in zip((*d, *t), (*d_ref, *t_ref), strict=True):
            np.testing.assert_array_equal(a, b)
    assert first._band_solver().n_sparse == 0


@pytest.mark.parametrize("variant", ("tabulated", "loss"))
@pytest.mark.parametrize("name", FILES)
def test_banded_link_derivatives_against_differences(name, variant):
    """With a tabulated bearing or a loss factor only the banded LU gives the link path
    analytic derivatives: dκ_k/dω (k = 0..5) and dF_k/dω (k = 1..5; dF_0 is the same central
    difference of the mean on every strategy) against Richardson differences of the banded
    κ_k, F_k, within 1e-9 of their scale plus ten times the differences' own error."""
    lb = banded(name, variant)
    rec = lb.receptance
    assert rec.has_derivatives and lb.reduced.kappa_derivative is not None
    excess = 0.0
    for w in 2 * np.pi * np.array(POINTS_HZ[name]):
        analytic = [_flat(a) for a in rec.derivatives(w, H)]
        for i, rows in ((0, slice(None)), (1, slice(1, None))):

            def f(x, h_, i=i):
                return rec.terms(x, h_)[i]

            a, d1, d2 = (
                x[rows] for x in (analytic[i], _richardson(f, w, 2e-5 * w), _richardson(f, w, 1e-5 * w))
            )
            scale = np.max(np.abs(d2))
            excess = max(excess, _rel(a, d2, scale) / (1e-9 + 10 * _rel(d1, d2, scale)))
    print(f"{name} {variant}: banded analytic vs differences, excess {excess:.2f}")
    assert excess <= 1.0


def test_auto_chooses_the_strategy_by_size_and_bearings():
    """``method="auto"``: the pole-residue form up to 100 DOFs coupled to the mesh (kubo:
    54), the banded LU above (two_shaft: 110) and with a tabulated bearing or a loss factor
    (where the pole-residue form does not apply); several link coordinates (the clearance
    model) keep the pole-residue form."""
    for name, variant, method in (
        ("kubo", "base", "poles"),
        ("kubo", "tabulated", "banded"),
        ("kubo", "loss", "banded"),
        ("two_shaft", "base", "banded"),
        ("two_shaft", "tabulated", "banded"),
    ):
        lk = models(name, variant)
        assert lk.receptance.method == method, (name, variant)
        if method == "banded":
            assert lk.receptance._band_solver().banded
    assert build_link_model(_clearance_system(False)).receptance.method == "poles"


def test_banded_link_strategy_sparse_fallback(monkeypatch):
    """With no band allowed (``BAND_LIMIT`` below every band) the banded strategy falls
    back to sparse LU of Z_k for every harmonic, forcing and derivatives included, and
    agrees with the band to REDUCTION_RTOL (two_shaft with the clearance and unbalances)."""
    from nlgrd.nonlinear.reduction import direct_receptance as dr

    s = _clearance_system(True)
    band = build_link_model(s, method="banded").receptance
    assert band._band_solver().banded  # built before the limit is lowered
    monkeypatch.setattr(dr, "BAND_LIMIT", -1)
    sparse = build_link_model(s, method="banded").receptance
    worst: dict = {}
    for w in 2 * np.pi * np.array(POINTS_HZ["two_shaft"]):
        worst = _merge(worst, _banded_worst(band, sparse, w))
    print("banded vs its sparse fallback " + ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))
    assert not sparse._band_solver().banded and sparse._band_solver().n_sparse > 0
    assert len(worst) == 5 and max(worst.values()) <= REDUCTION_RTOL


# ----------------------------------------------------------------------------- outputs


def test_link_outputs_of_many_points_equal_each_point():
    """``points_outputs`` (a link sweep's outputs of all points at once: the meshes' metrics
    in one FFT, the bearings' maxima of all points together) of points with two different
    H equal each point's own ``point_outputs`` to 1e-12 of each column's largest, and the
    mesh's columns equal ``metrics_from_harmonics`` of each point (the mesh law's metrics
    from one point's harmonics)."""
    from nlgrd.nonlinear.results.link_results import point_outputs, points_outputs
    from nlgrd.nonlinear.results.metrics import metrics_from_harmonics

    lk = models("two_shaft")
    pts = []
    for h, hz in ((H, 1500.0), (H, 2500.0), (3, 2000.0)):
        r = link_sweep(lk, 2 * np.pi * np.array([hz]), H=h, directions="up", period=1, stability=False)
        pts.append((r.result.harmonics[0], float(r.result.omega[0])))
    many = pd.DataFrame(points_outputs(lk, [z for z, _ in pts], [w for _, w in pts]))
    each = pd.DataFrame([point_outputs(lk, z, w) for z, w in pts])
    assert list(many.columns) == list(each.columns) and many.shape == (3, len(each.columns))
    scale = np.maximum(np.max(np.abs(each.to_numpy(float)), axis=0), 1e-300)
    assert np.max(np.abs(many.to_numpy(float) - each.to_numpy(float)) / scale) <= 1e-12
    mesh = lk.links[0]
    for (z, w), (_, row) in zip(pts, many.iterrows(), strict=True):
        m = metrics_from_harmonics(np.asarray(z).reshape(-1), w, mesh.mesh)
        assert np.isclose(row["mesh0.dte_rms [m]"], m.dte_rms, rtol=1e-12, atol=0)
        assert np.isclose(row["mesh0.force_max [N]"], m.force_max, rtol=1e-12, atol=0)


# ----------------------------------------------------------------------------- Floquet

#: two_shaft mesh frequencies [Hz] solved from rest: 3400 Hz on an unstable period-1
#: orbit (|μ| = 1.186), 5000 and 5500 Hz stable (|μ| = 1, the free torsional mode).
FLOQUET_HZ = (3400.0, 5000.0, 5500.0)


def _point_sweeps():
    """two_shaft's FLOQUET_HZ, each a one-point link sweep from rest, H 5, period 1."""
    lk = models("two_shaft")
    return [
        link_sweep(lk, 2 * np.pi * np.array([hz]), H=H, directions="up", period=1, stability=True).result
        for hz in FLOQUET_HZ
    ]


@pytest.fixture(scope="module")
def kubo_sweeps():
    """Kubo's rig, 3000-6000 Hz in 16 points (200 Hz steps), up and down, H = 5, with
    stability: across the main resonance (gear-pair mode 4915 Hz) and its jumps."""
    ws = 2 * np.pi * np.linspace(3000.0, 6000.0, 16)
    return link_sweep(models("kubo"), ws, H=H, directions="both", period=1, stability=True)


def _against_full_state(lk, res) -> tuple[float, int, int]:
    """Worst |max|μ| - max|μ| of the full state| over the converged points of the link sweep
    ``res`` (its multipliers on the link model ``lk``'s stability state spaces), asserting
    equal verdicts; and how many points had a constant tangent (on the basis) and how many
    a varying one (on the full state)."""
    from nlgrd.nonlinear.results.sweep_results import STABLE_RTOL
    from nlgrd.nonlinear.stability.floquet import floquet_multipliers
    from nlgrd.nonlinear.stability.tangent import time_invariant

    rec, laws = lk.receptance, lk.reduced.nonlinearities
    worst, constant, varying = 0.0, 0, 0
    for i in np.flatnonzero(res.converged):
        w, z = float(res.omega[i]), np.atleast_2d(res.harmonics[i])
        ss = lk.reduced.linear_state_space(w)
        assert ss.full is not None and ss.M.shape[0] < rec.model.n_dofs  # on the basis
        mu = floquet_multipliers(rec.stability.full_state(rec.plan.speed(w)), laws, z, w)
        top = float(np.max(np.abs(mu)))
        worst = max(worst, abs(top - float(res.floquet_max[i])))
        assert (top < 1 + STABLE_RTOL) == bool(res.stable[i])
        if time_invariant(laws, z, rec.n_coords):
            constant += 1
        else:
            varying += 1
    return worst, constant, varying


#: The link path's multipliers against the full state's, below the verdict's band: on the
#: basis where the tangent is constant, on twice the cut-off where it varies and max |μ|
#: moved by at most 1e-7, else the full state itself (measured 0 on two_shaft, 3.1e-11 to
#: 3.9e-11 on kubo under three BLAS kernels).
FULL_STATE_ATOL = 1e-6


def test_link_stability_basis_against_the_full_state(kubo_sweeps):
    """The link path's stability rule (``LinkReceptance.state_space``: a model whose links
    are all gear meshes on the modes below 3x the highest mesh frequency and the static
    attachment vectors; where the orbit's tangent varies over the period, on twice that
    cut-off when max |μ| moves by at most 1e-7, else on the full state):
    at every converged point of two_shaft's FLOQUET_HZ (one unstable) and of Kubo's sweep
    (up and down, some unstable, some with contact loss) max |μ| within FULL_STATE_ATOL of
    the full state space's and the same verdicts. (Before, every point took the full state:
    two_shaft 264 states where the basis has 74.)"""
    pts = _point_sweeps()
    assert [bool(r.stable[0]) for r in pts] == [False, True, True]
    lk = models("two_shaft")
    worst, const, vary = 0.0, 0, 0
    for rl in pts:
        w_, c_, v_ = _against_full_state(lk, rl)
        worst, const, vary = max(worst, w_), const + c_, vary + v_
    wk, ck, vk = _against_full_state(models("kubo"), kubo_sweeps.result)
    print(
        f"two_shaft: {const} points with a constant tangent, {vary} varying, |d max mu| {worst:.1e}; "
        f"kubo: {ck} / {vk}, {wk:.1e}"
    )
    assert ck > 0 and vk > 0 and const + vary == 3
    assert max(worst, wk) <= FULL_STATE_ATOL


def test_link_stability_basis_for_gear_meshes_and_clearances():
    """Gear meshes and bearing clearances take the truncated basis (docs/conventions.md,
    "Stability state space"): for the gear-mesh model the modes below 3x the highest mesh
    frequency (of the link model at that top, counted here from the undamped eigenvalues)
    with the static attachment vector, sized by the sweep's top frequency."""
    lk = build_link_model(system("two_shaft"))
    rec = lk.receptance
    rec.prepare_stability(2 * np.pi * 6000.0)
    ss = rec.state_space(2 * np.pi * 3000.0)
    assert rec.truncates_stability and ss.M.shape[0] < rec.model.n_dofs
    import scipy.linalg as sla

    K = (rec.model.stiffness(rec.plan.speed(2 * np.pi * 3000.0)) + rec.K_link).toarray()
    lam = sla.eigh(K, rec.model.M.toarray(), eigvals_only=True)
    below = int(np.sum(np.sqrt(np.maximum(lam, 0.0)) < 3 * 2 * np.pi * 6000.0))
    assert ss.M.shape[0] == below + rec.n_coords  # the modes and one attachment vector per link
    clear = build_link_model(_clearance_system(False)).receptance
    assert clear.truncates_stability
    ss = clear.state_space(2 * np.pi * 3000.0)
    assert ss.full is not None and ss.M.shape[0] < clear.model.n_dofs


def _max_mu(state_space, laws, z, w) -> float:
    from nlgrd.nonlinear.stability.floquet import _analysis

    return float(np.max(np.abs(_analysis(state_space, laws, z, w, True, "auto").multipliers)))


def test_clearance_floquet_on_the_truncated_basis_against_the_full_state():
    """data/models/two_shaft_clearance.toml (mesh + 20 µm Hertzian clearance, a smooth law:
    every point is checked on twice the cut-off) at 1000, 1125 and 1250 Hz, H = 9: at the
    two stable points the basis with twice the cut-off (what ``floquet_analysis`` returns
    there) gives max |μ| within TRUNCATION_ATOL = 1e-7 of the full state (measured 4e-11
    over 41 points 1-6 kHz, benchmarks/README.md: the tolerance is the rule's own, a tenth
    of the verdict's band); at the unstable 1125 Hz the cut-off basis is off by far more
    (1.75 against 1.0010: its parametric instability is not the full state's), the check
    sees it and the result is the full state's. data/models/rub_rotor.toml: its torsion is
    undamped and above the cut-off, so the dropped modes' first-order multiplier is 1, the
    kept basis's max |μ| (0.99) is not the full state's (1) and the full state decides."""
    from nlgrd.io.model_file import load_model
    from nlgrd.nonlinear.results.sweep_results import STABLE_RTOL
    from nlgrd.nonlinear.stability.floquet import TRUNCATION_ATOL, floquet_analysis

    lk = build_link_model(_clearance_system(False))
    laws = lk.reduced.nonlinearities
    grid = 2 * np.pi * np.array([1000.0, 1125.0, 1250.0])
    res = link_sweep(lk, grid, H=9, directions="up", period=1, stability=False).result
    assert res.converged.all()
    verdicts = []
    for i, w in enumerate(grid):
        z = res.harmonics[i]
        ss = lk.reduced.linear_state_space(w)
        full = _max_mu(ss.full(), laws, z, w)
        got = float(np.max(np.abs(floquet_analysis(ss, laws, z, w).multipliers)))
        assert abs(got - full) <= TRUNCATION_ATOL
        verdicts.append(full < 1 + STABLE_RTOL)
        assert (got < 1 + STABLE_RTOL) == verdicts[-1]
        if verdicts[-1]:  # kept: the basis with twice the cut-off, its dropped modes below
            assert abs(_max_mu(ss.larger(), laws, z, w) - full) <= TRUNCATION_ATOL
            assert ss.larger().dropped <= full + TRUNCATION_ATOL
        else:  # the cut-off basis alone would be wrong here
            assert abs(_max_mu(ss, laws, z, w) - full) > 100 * TRUNCATION_ATOL
    assert verdicts == [True, False, True]
    rub = build_link_model(load_model(ROOT / "data" / "models" / "rub_rotor.toml"))
    w = 2 * np.pi * 33.3
    res = link_sweep(rub, np.array([w]), H=5, directions="up", period=1, stability=False).result
    z, laws = res.harmonics[0], rub.reduced.nonlinearities
    ss = rub.reduced.linear_state_space(w)
    assert ss.full is not None and ss.dropped == pytest.approx(1.0, abs=1e-12)
    full = _max_mu(ss.full(), laws, z, w)
    assert abs(_max_mu(ss, laws, z, w) - full) > 1e-3
    assert abs(float(np.max(np.abs(floquet_analysis(ss, laws, z, w).multipliers))) - full) <= TRUNCATION_ATOL


DROPPED_CASES = [
    ("two_shaft_clearance", 1000.0),
    ("two_shaft", 1500.0),
    ("idler_train", 1000.0),
    ("rub_rotor", 50.0),
]


@pytest.mark.parametrize("name, hz", DROPPED_CASES)
def test_dropped_mode_multiplier_against_the_eigenvalues(name, hz):
    """``TruncatedStability.dropped`` (the modes above the cut-off, Rayleigh's first-order
    decay rate φᵀDφ/2) against the exact eigenvalues λ of the full linear state matrix
    (links at K_L, C_L, D with the gyroscopic terms at the point's speed): max |exp(λT)|
    over |Im λ| above the cut-off. Measured 2.4e-10 at most (second order in the light
    damping); tolerance a tenth of TRUNCATION_ATOL, so that the estimate's error cannot
    decide the rule that compares it with max |μ| to TRUNCATION_ATOL. An undamped dropped
    mode (idler_train, rub_rotor: torsion) gives 1 on both sides."""
    from nlgrd.io.model_file import load_model
    from nlgrd.nonlinear.stability.floquet import TRUNCATION_ATOL

    rec = build_link_model(load_model(ROOT / "data" / "models" / f"{name}.toml")).receptance
    st, w = rec.stability, 2 * np.pi * hz
    rec.prepare_stability(w)
    speed, cut = rec.plan.speed(w), 3 * st.top_order * st.top
    m = rec.model
    M, D = m.M.toarray(), (m.damping(speed) + rec.C_link).toarray()
    K = (m.stiffness(speed) + rec.K_link).toarray()
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, D)]])
    lam = np.linalg.eigvals(A)
    exact = float(np.max(np.abs(np.exp(lam[np.abs(lam.imag) > cut] * 2 * np.pi / w))))
    assert abs(st.dropped(cut, speed, w) - exact) <= TRUNCATION_ATOL / 10


def test_a_model_without_links_is_refused_in_one_line():
    """single_shaft.toml (no gear pair, no clearance): ``build_link_model`` refuses it with
    one line naming the reason (it raised numpy's matmul ValueError: block_diag of no link
    is (1, 0))."""
    from nlgrd.io.model_file import load_model

    with pytest.raises(ModelError, match="no gear pair and no clearance") as err:
        build_link_model(load_model(ROOT / "data" / "models" / "single_shaft.toml"))
    assert "\n" not in str(err.value) and err.value.key == "gear_pairs"


@pytest.mark.parametrize("name", FILES)
def test_floquet_with_a_loss_factor_refused(name):
    """A loss factor η = 0.01 (hysteretic damping, no time-domain form): Floquet stability is
    refused with one line under ``<material>.loss_factor``; the harmonic balance, where it
    is exact (tests/test_link_receptance.py), still solves."""
    from nlgrd.nonlinear.reduction.state_space import HYSTERETIC_REFUSAL

    lk = models(name, "loss")
    w = 2 * np.pi * np.array([POINTS_HZ[name][0]])
    with pytest.raises(ModelError) as err:
        link_sweep(lk, w, H=H, directions="up", period=1, stability=True)
    assert err.value.key.endswith(".loss_factor") and "\n" not in str(err.value)
    assert HYSTERETIC_REFUSAL in err.value.message
    assert np.all(link_sweep(lk, w, H=H, directions="up", period=1, stability=False).result.converged)
