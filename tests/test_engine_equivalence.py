"""Guard rail of issue 33: today's single-mesh path equals the link path on one system.

The single-mesh path (``build_geared_model``: ``MeshReceptance``, ``bearing_harmonics``,
``geared_sweep``) and the link path (``build_link_model``: ``LinkReceptance`` with the
mesh as a ``GearMeshLink``, ``link_sweep``) reduce the same FE equations onto the same
mesh coordinate δ, so everything they compute must agree to the rounding of two
factorisations (κ_k, F_k, their ω-derivatives, recovered displacements) or of the
solver's tolerance (sweeps, tol = 1e-10). Floquet multipliers are the exception: the
single path takes them on the modes below 3x the highest mesh frequency
(``build_geared_model``) at every point, the link path on that basis where the orbit's
tangent is constant over the period and, where it varies (a contact change), on twice that
cut-off or the whole dense model (docs/conventions.md), so |μ| agree only to the single
path's truncation and the verdicts must agree.

Models: ``data/models/two_shaft.toml`` and ``data/case_studies/kubo.toml``, as loaded
and modified in memory (:func:`system`). The link path's default reduction is the one the
single path would take (issue 33 item 3): its banded LU on two_shaft (110 DOFs coupled to
the mesh) and on every tabulated or loss-factor variant, the pole-residue form on kubo's
base and cross variants (54 DOFs):

- ``cross``: every bearing cross-coupled, k_yz = 0.2 k_yy = -k_zy, c_yz = 0.1 c_yy = -c_zy;
- ``tabulated``: one more bearing, tabulated against speed (at 100 and 3000 rad/s:
  k_yy 0.5 -> 2 k, k_zz 0.6 -> 1.5 k, k_yz 0 -> 0.3 k, k the first bearing's k_yy), at a
  node with no bearing (two_shaft: pinion shaft node 3; kubo: shaft 0 node 0), so the
  others still hold every shaft;
- ``loss``: a hysteretic loss factor η = 0.01 in every material.

Known differences are strict xfails whose reasons carry the figures measured. One named
in issue 33 is not measurable here: the single path takes dκ_0/dω = 0, but on both models
a free torsional rigid-body mode leaves κ_0 at rounding (~1e-8 N/m), and with a torsional
brake added (k_tt = 2e3 N m/rad) and the tabulated bearing, dκ_0/dω by differences was
2.5e-4 N s/m against max |dκ_k/dω| ~5e6: 5e-11, below any tolerance that is not rounding.
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
from nlgrd.nonlinear.fourier.harmonics import complex_to_real, real_to_complex
from nlgrd.nonlinear.models.geared import build_geared_model, geared_sweep
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.nonlinear.results.bearing_loads import bearing_harmonics

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
    """(single-mesh GearedModel, LinkModel) of one system, H = 5, up to 6 kHz."""
    s = system(name, variant)
    return build_geared_model(s, 2 * np.pi * 6000.0, H), build_link_model(s)


def _flat(a) -> np.ndarray:
    return np.asarray(a, dtype=complex).reshape(H + 1, -1)


def _rel(a, b, scale) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / scale)


# ----------------------------------------------------------------------------- κ and F


@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("name", FILES)
def test_kappa_and_force_agree(name, variant):
    """κ_k and F_k, k = 0..5, at three mesh frequencies: REDUCTION_RTOL of their largest
    entry (κ_0 is rounding, ~1e-8 N/m, where a free torsional mode leaves the mean mesh
    compliance unbounded; it is compared against the scale of κ_1..κ_5)."""
    g, lk = models(name, variant)
    worst = 0.0
    for w in 2 * np.pi * np.array(POINTS_HZ[name]):
        kg, kl = _flat(g.reduced.kappa(w, H)), _flat(lk.reduced.kappa(w, H))
        fg, fl = _flat(g.reduced.force(w, H)), _flat(lk.reduced.force(w, H))
        worst = max(worst, _rel(kg, kl, np.max(np.abs(kl[1:]))), _rel(fg, fl, np.max(np.abs(fl))))
    print(f"{name} {variant}: kappa, F max rel diff {worst:.1e}")
    assert worst <= REDUCTION_RTOL


@pytest.mark.parametrize("variant", ("base", "cross"))
@pytest.mark.parametrize("name", FILES)
def test_analytic_derivatives_agree(name, variant):
    """dκ_k/dω and dF_k/dω where both paths have them analytically (no tabulated bearing,
    no loss factor): dκ to REDUCTION_RTOL of max |dκ|; dF to 1e-8 max|F|/ω, the rounding of
    the link path's central difference of F_0 (a step ~1e-6 ω on |F_0| ~ 2.3 kN: ~1e-10
    |F|/ω), the single path's dF_0 being 0 exactly (F_0 = the static mesh load)."""
    g, lk = models(name, variant)
    worst_k = worst_f = 0.0
    for w in 2 * np.pi * np.array(POINTS_HZ[name]):
        dkg, dkl = _flat(g.reduced.kappa_derivative(w, H)), _flat(lk.reduced.kappa_derivative(w, H))
        dfg, dfl = _flat(g.reduced.force_derivative(w, H)), _flat(lk.reduced.force_derivative(w, H))
        worst_k = max(worst_k, _rel(dkg, dkl, np.max(np.abs(dkl))))
        worst_f = max(worst_f, _rel(dfg, dfl, np.max(np.abs(lk.reduced.force(w, H))) / w))
    print(f"{name} {variant}: dkappa {worst_k:.1e} (of max), dF {worst_f:.1e} (of max|F|/omega)")
    assert worst_k <= REDUCTION_RTOL and worst_f <= 1e-8


def _richardson(f, w: float, h: float) -> np.ndarray:
    """Central difference of ``f(ω, H)`` with one Richardson step (error O(h^4))."""

    def cd(s):
        return (_flat(f(w + s, H)) - _flat(f(w - s, H))) / (2 * s)

    return (4 * cd(h / 2) - cd(h)) / 3


def _derivatives_against_differences(name, variant, which=("kappa", "force")):
    """Worst |single-path analytic - differences of the link path's κ, F| over the points,
    relative to max |dκ| (max |dF|), and the bound it must stay under: 1e-9 plus ten times
    the differences' own error (two Richardson steps h = 2e-5 ω and 1e-5 ω compared);
    ``which`` of the two."""
    g, lk = models(name, variant)
    pairs = {
        "kappa": (g.reduced.kappa_derivative, lk.reduced.kappa),
        "force": (g.reduced.force_derivative, lk.reduced.force),
    }
    excess = 0.0
    for w in 2 * np.pi * np.array(POINTS_HZ[name]):
        for k in which:
            analytic, f = pairs[k]
            a, d1, d2 = _flat(analytic(w, H)), _richardson(f, w, 2e-5 * w), _richardson(f, w, 1e-5 * w)
            parts = [np.arange(a.size)]
            if k == "force":  # dF_0/dω on the scale of F_0 itself, max|F|/ω (below)
                mean = np.arange(0, a.size, 2 * H + 1)
                parts = [np.setdiff1d(parts[0], mean), mean]
            for i, part in enumerate(parts):
                scale = np.max(np.abs(d2[part])) if i == 0 else np.max(np.abs(_flat(f(w, H)))) / w
                bound = 1e-9 + 10 * _rel(d1[part], d2[part], scale)
                excess = max(excess, _rel(a[part], d2[part], scale) / bound)
    return excess


@pytest.mark.parametrize("name", FILES)
def test_derivatives_with_a_loss_factor_against_differences(name):
    """With a loss factor the link path has no analytic derivative: the single path's
    dκ_k/dω and dF_k/dω equal central differences (Richardson) of the link path's κ_k and
    F_k within 1e-9 of their scale plus ten times the differences' own error."""
    assert _derivatives_against_differences(name, "loss") <= 1.0


@pytest.mark.parametrize("name", FILES)
def test_kappa_derivative_with_a_tabulated_bearing_against_differences(name):
    """As the loss-factor test, dκ_k/dω with the speed-tabulated bearing. (The single path
    held the bearing's coefficients at the current speed: 3.3e-4 of max|dκ| off on two_shaft
    at 1500 Hz, 2e-6 on kubo; now 2e-11 and 1e-10, the differences good to 4e-11 and 7e-11.)"""
    assert _derivatives_against_differences(name, "tabulated", ("kappa",)) <= 1.0


@pytest.mark.parametrize("name", FILES)
def test_force_derivative_with_a_tabulated_bearing_against_differences(name):
    """As the loss-factor test, dF_k/dω with the speed-tabulated bearing. The mean term is
    measured on its own scale, max|F|/ω: the single path's dF_0/dω is 0 exactly (F_0 the
    static mesh load), the link path's F_0 = 2.3 kN on two_shaft varies with the tabulated
    bearing's speed by rounding only (differences 2.4e-11 N s at 1500 Hz, 1e-10 of max|F|/ω);
    on the scale of max|dF_k| (2.2e-4 N s) that noise was 1.1e-7, above or below the bound
    as the BLAS kernel rounded (a strict xfail under one kernel, a pass under Sandybridge)."""
    assert _derivatives_against_differences(name, "tabulated", ("force",)) <= 1.0


# ------------------------------------------------ the link path's banded strategy (issue 33)


@cache
def banded(name: str, variant: str = "base"):
    """The link model of :func:`system` with ``method="banded"``."""
    return build_link_model(system(name, variant), method="banded")


def _banded_worst(a, b, w: float) -> dict:
    """Worst differences of κ_k, F_k (against max|F| and, k >= 1, max|F_k>=1|) and, where
    both have them, dκ_k/dω and dF_k/dω (k >= 1) of two link receptances ``a`` (the banded)
    and ``b``, or of the single path's reduced model ``b``, at ``w``."""
    single = not hasattr(b, "terms")
    (ka, fa), da = a.terms(w, H), a.derivatives(w, H) if a.has_derivatives else None
    if single:
        kb, fb = _flat(b.kappa(w, H)), _flat(b.force(w, H))
        db = (_flat(b.kappa_derivative(w, H)), _flat(b.force_derivative(w, H))) if da is not None else None
    else:
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


@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("name", FILES)
def test_banded_link_strategy_equals_the_single_path(name, variant):
    """The link path's ``"banded"`` strategy (the single path's banded LU and Woodbury
    identity on the links' coordinates) against the single path (two_shaft: its banded
    direct solver; kubo: its pole-residue form) at three mesh frequencies: κ_k, F_k (also
    F_1..F_5 on their own scale), dκ_k/dω and dF_k/dω (k >= 1; analytic on both paths, with
    the tabulated bearing and the loss factor too) to REDUCTION_RTOL; every harmonic solved
    by band (none by the sparse fallback)."""
    g, _ = models(name, variant)
    lb = banded(name, variant)
    worst: dict = {}
    for w in 2 * np.pi * np.array(POINTS_HZ[name]):
        worst = _merge(worst, _banded_worst(lb.receptance, g.reduced, w))
    solver = lb.receptance._band_solver()
    print(f"{name} {variant}: banded link vs single " + ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))
    assert lb.receptance.method == "banded" and solver.banded and solver.n_sparse == 0 and solver.n_band > 0
    assert "dkappa" in worst and "dF_k" in worst  # analytic on every variant
    assert max(worst.values()) <= REDUCTION_RTOL


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


def test_link_path_chooses_as_the_single_path():
    """``method="auto"`` on the link path as on the single path (``MeshReceptance``): the
    pole-residue form up to 100 DOFs coupled to the mesh (kubo: 54), the banded LU above
    (two_shaft: 110) and with a tabulated bearing or a loss factor (where the link path's
    pole-residue form does not apply: it took dense or sparse LU); several link coordinates
    (the clearance model) keep the pole-residue form."""
    for name, variant, method in (
        ("kubo", "base", "poles"),
        ("kubo", "tabulated", "banded"),
        ("kubo", "loss", "banded"),
        ("two_shaft", "base", "banded"),
        ("two_shaft", "tabulated", "banded"),
    ):
        g, lk = models(name, variant)
        assert lk.receptance.method == method, (name, variant)
        if variant == "base":
            assert g.receptance.method == ("poles" if method == "poles" else "direct")
            assert g.receptance._direct().banded
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


# ----------------------------------------------------------------------------- recovery


_POLE_RECOVERY = pytest.mark.xfail(
    strict=True,
    reason="link path's pole-residue recovery (LinkReceptance.recover, method 'poles') of the "
    "bearing DOFs of kubo (bearings 3.5e12 N/m: harmonics ~1e-11 m) differs from a direct solve "
    "by 3.6e-6 of the alternating harmonics at 2000 Hz (2.4e-7 at 4500 Hz); the single path's "
    "poles agree with a direct solve to 9e-10",
)
RECOVERY_CASES = [
    pytest.param(n, v, marks=_POLE_RECOVERY if (n, v) in {("kubo", "base"), ("kubo", "cross")} else ())
    for n in FILES
    for v in VARIANTS
]


@pytest.mark.parametrize(("name", "variant"), RECOVERY_CASES)
def test_bearing_displacements_recovered_alike(name, variant):
    """Harmonics of every bearing node's (u_y, u_z) from the same δ harmonics: the single
    path's ``bearing_harmonics`` (G = F - κ Y) against the link path's ``recover`` given
    that same G. Recovery is linear in (Y, G), so any δ serves: a static offset with
    1 µm at the first harmonic and 0.3 µm at the second. The mean and the alternating
    harmonics each to REDUCTION_RTOL of their largest (the mean, the static deflection, is
    30x the alternating part on kubo's stiff bearings)."""
    g, lk = models(name, variant)
    z = np.zeros(2 * H + 1)
    z[0], z[1], z[4] = 5e-6, 1e-6, 0.3e-6
    worst = 0.0
    for w in 2 * np.pi * np.array(POINTS_HZ[name]):
        Q, _ = bearing_harmonics(g, w, z)
        Y = real_to_complex(z)
        G = _flat(lk.reduced.force(w, H))[:, 0] - _flat(lk.reduced.kappa(w, H))[:, 0] * Y
        q = lk.receptance.recover(w, H, z[None, :], complex_to_real(G)[None, :], g.bearing_dofs)
        Ql = real_to_complex(q).T
        for part in (slice(0, 1), slice(1, None)):
            worst = max(worst, _rel(Q[part], Ql[part], np.max(np.abs(Ql[part]))))
    print(f"{name} {variant}: bearing recovery {worst:.1e}")
    assert worst <= REDUCTION_RTOL


def test_a_tabulated_bearing_in_place_of_a_linear_one_builds_on_both_paths():
    """two_shaft with its first bearing tabulated against speed (k_yy 0.5 -> 2 x, k_zz
    0.6 -> 1.5 x over 100-3000 rad/s): both paths build and give the same κ_k, F_k. (The
    link path refused it: it checked the static loads against the rigid-body modes of
    ``LinearModel.K``, which leaves tabulated bearings out: a net load of 2.0e-1 on a free
    mode; both now take the stiffness at rest, ``stiffness(0)``.)"""
    data = tomllib.loads(FILES["two_shaft"].read_text())
    b = data["bearings"][0]
    k = b["kyy"]
    b.update(speeds=[100.0, 3000.0], kyy=[0.5 * k, 2 * k], kzz=[0.6 * k, 1.5 * k])
    s = model_from_file_data(data, str(FILES["two_shaft"]))
    g = build_geared_model(s, 2 * np.pi * 6000.0, H)
    lk = build_link_model(s)
    worst = 0.0
    for w in 2 * np.pi * np.array(POINTS_HZ["two_shaft"]):
        kg, kl = _flat(g.reduced.kappa(w, H)), _flat(lk.reduced.kappa(w, H))
        fg, fl = _flat(g.reduced.force(w, H)), _flat(lk.reduced.force(w, H))
        worst = max(worst, _rel(kg, kl, np.max(np.abs(kl[1:]))), _rel(fg, fl, np.max(np.abs(fl))))
    print(f"two_shaft, first bearing tabulated: kappa, F max rel diff {worst:.1e}")
    assert worst <= REDUCTION_RTOL


#: Points of the bearing-output check, away from the gear-pair mode (a coarse sweep through
#: two_shaft's 3662 Hz mode fails to converge at 3600 Hz on both paths, and Newton from the
#: linear solution at kubo's 4500 Hz).
BEARING_POINTS_HZ = {"two_shaft": (1500.0, 2500.0, 5200.0), "kubo": (2000.0, 3000.0, 3400.0)}
#: The bearing columns of the two tables: single path (unit, factor to SI), link path.
BEARING_COLUMNS = {
    "displacement_max": ("[um]", 1.0, "[um]"),
    "displacement_rms": ("[um]", 1.0, "[um]"),
    "force_mean": ("[N]", 1.0, "[N]"),
    "force_rms": ("[N]", 1.0, "[N]"),
    "force_max": ("[N]", 1.0, "[N]"),
    "force_amplitude": ("[N]", 1.0, "[N]"),
}


@pytest.mark.parametrize(
    ("name", "variant"), [*(("two_shaft", v) for v in VARIANTS), ("kubo", "loss"), ("kubo", "tabulated")]
)
def test_link_sweep_bearing_outputs_equal_the_single_path(name, variant):
    """Every linear bearing's force and displacement columns of a link sweep (issue 33:
    linear bearings are outputs on every model; ``bearing_loads.link_bearing_outputs``)
    against the single path's ``<name> <quantity>`` columns at three points, H = 5,
    period 1: each quantity to REDUCTION_RTOL of its largest over bearings and points (both
    sweeps solve to a relative residual of 1e-10). Kubo's base and cross variants are left
    to the recovery test above (the link path's pole-residue recovery: xfail, 3.8e-7 here)."""
    s, lk = system(name, variant), None
    single, link = [], []
    for w in 2 * np.pi * np.array(BEARING_POINTS_HZ[name]):  # each from its linear solution
        single.append(geared_sweep(s, omegas=[w], H=H, directions="up", period=1, stability=False).to_frame())
        lk = lk or build_link_model(s)
        link.append(link_sweep(lk, [w], H=H, directions="up", period=1, stability=False).to_frame())
    single, link = pd.concat(single, ignore_index=True), pd.concat(link, ignore_index=True)
    assert single["converged"].all() and link["converged"].all()
    names = [b.name or f"bearing {j} (shaft {b.shaft}, node {b.node})" for j, b in enumerate(s.bearings)]
    worst = 0.0
    for q, (unit, factor, si) in BEARING_COLUMNS.items():
        a = np.array([single[f"{n} {q} {unit}"].to_numpy() * factor for n in names])
        b = np.array([link[f"{n}.{q} {si}"].to_numpy() for n in names])
        assert np.isfinite(a).all() and np.isfinite(b).all() and np.max(np.abs(a)) > 0
        worst = max(worst, _rel(a, b, np.max(np.abs(a))))
    print(f"{name} {variant}: bearing outputs {worst:.1e}")
    assert worst <= REDUCTION_RTOL


def test_link_outputs_of_many_points_equal_each_point():
    """``points_outputs`` (a link sweep's outputs of all points at once: the meshes' metrics
    in one FFT, the bearings' maxima of all points together) of points with two different
    H equal each point's own ``point_outputs`` to 1e-12 of each column's largest, and the
    mesh's columns equal the single path's ``metrics_from_harmonics`` of each point."""
    from nlgrd.nonlinear.results.link_results import point_outputs, points_outputs
    from nlgrd.nonlinear.results.metrics import metrics_from_harmonics

    lk = models("two_shaft")[1]
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

#: Floquet multipliers: the single path's state space holds the modes below 3x the
#: highest mesh frequency its model was built for; the link path's is the dense model.
#: That truncation moves |μ| by up to 3e-3 (measured on two_shaft's 1-6 kHz sweep, 5000
#: Hz down: 1.04822 against 1.05134); built for 20 kHz instead, the single path gives
#: 1.18599215 at 3400 Hz against the link path's 1.18599217.
FLOQUET_RTOL = 5e-3
#: |μ| of a single-path model built for 60 kHz (modes to 180 kHz) against the link path:
#: the truncation gone, what remains is the eigenvalue rounding of two state spaces.
FLOQUET_FULL_RTOL = 1e-6
#: two_shaft mesh frequencies [Hz] solved from rest: 3400 Hz on an unstable period-1
#: orbit (|μ| = 1.186), 5000 and 5500 Hz stable (|μ| = 1, the free torsional mode).
FLOQUET_HZ = (3400.0, 5000.0, 5500.0)


def _point_sweeps(variant: str = "base", fine: bool = False):
    s = system("two_shaft", variant)
    g = build_geared_model(s, 2 * np.pi * 60e3, H) if fine else models("two_shaft", variant)[0]
    lk = models("two_shaft", variant)[1]
    out = []
    for hz in FLOQUET_HZ:
        ws = 2 * np.pi * np.array([hz])
        rg = geared_sweep(s, ws, H=H, directions="up", model=g, period=1, stability=True).mesh
        rl = link_sweep(lk, ws, H=H, directions="up", period=1, stability=True).result
        out.append((rg, rl))
    return out


def _floquet_agree(pairs, rtol: float) -> float:
    """Worst relative |μ| difference; asserts the points converged alike and the verdicts agree."""
    worst = 0.0
    for rg, rl in pairs:
        assert np.array_equal(rg.converged, rl.converged) and np.all(rg.converged)
        assert np.array_equal(rg.stable, rl.stable)
        worst = max(worst, float(np.max(np.abs(rg.floquet_max / rl.floquet_max - 1))))
    assert worst <= rtol
    return worst


def test_floquet_verdicts_agree_at_hb_points():
    """Stable flag equal and largest |μ| to FLOQUET_RTOL at the two_shaft points of
    FLOQUET_HZ (one unstable); with the single path's truncation removed, to
    FLOQUET_FULL_RTOL."""
    pairs = _point_sweeps()
    assert [bool(rg.stable[0]) for rg, _ in pairs] == [False, True, True]
    print(f"floquet |mu| default {_floquet_agree(pairs, FLOQUET_RTOL):.1e}", end=" ")
    print(f"60 kHz model {_floquet_agree(_point_sweeps(fine=True), FLOQUET_FULL_RTOL):.1e}")


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
    pts = [rl for _, rl in _point_sweeps()]
    lk = models("two_shaft")[1]
    worst, const, vary = 0.0, 0, 0
    for rl in pts:
        w_, c_, v_ = _against_full_state(lk, rl)
        worst, const, vary = max(worst, w_), const + c_, vary + v_
    _, _, rl = kubo_sweeps
    wk, ck, vk = _against_full_state(models("kubo")[1], rl.result)
    print(
        f"two_shaft: {const} points with a constant tangent, {vary} varying, |d max mu| {worst:.1e}; "
        f"kubo: {ck} / {vk}, {wk:.1e}"
    )
    assert ck > 0 and vk > 0 and const + vary == 3
    assert max(worst, wk) <= FULL_STATE_ATOL


def test_link_stability_basis_for_gear_meshes_and_clearances():
    """Gear meshes and bearing clearances take the truncated basis (docs/conventions.md,
    "Stability state space"); the gear-mesh model's basis is the single path's: modes
    below 3x the highest mesh frequency with the static attachment vector, sized by the
    sweep's top frequency."""
    lk = build_link_model(system("two_shaft"))
    rec = lk.receptance
    rec.prepare_stability(2 * np.pi * 6000.0)
    ss = rec.state_space(2 * np.pi * 3000.0)
    g = models("two_shaft")[0]  # built for 6 kHz: the same basis size
    assert rec.truncates_stability and ss.M.shape == g.reduced.linear_state_space(2 * np.pi * 3000.0).M.shape
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
def test_floquet_with_a_loss_factor_refused_alike(name):
    """A loss factor η = 0.01 (hysteretic damping, no time-domain form): both paths refuse
    Floquet stability with the same one line under ``loss_factor`` (the single path left it
    out and gave the multipliers of the model without it, the link path refused in other
    words), and both still solve the harmonic balance, where it is exact (tested above)."""
    from nlgrd.nonlinear.reduction.state_space import HYSTERETIC_REFUSAL

    s = system(name, "loss")
    g, lk = models(name, "loss")
    w = 2 * np.pi * np.array([POINTS_HZ[name][0]])
    lines = []
    for run in (
        lambda: geared_sweep(s, w, H=H, directions="up", model=g, period=1, stability=True),
        lambda: link_sweep(lk, w, H=H, directions="up", period=1, stability=True),
    ):
        with pytest.raises(ModelError) as err:
            run()
        assert err.value.key.endswith(".loss_factor") and "\n" not in str(err.value)
        assert HYSTERETIC_REFUSAL in err.value.message
        lines.append((err.value.key, err.value.message))
    assert lines[0] == lines[1]
    for res in (
        geared_sweep(s, w, H=H, directions="up", model=g, period=1, stability=False).mesh,
        link_sweep(lk, w, H=H, directions="up", period=1, stability=False).result,
    ):
        assert np.all(res.converged)


# ----------------------------------------------------------------------------- sweeps

#: Sweep tolerance: both paths solve the same equations to tol = 1e-10 (relative
#: residual) from the same starts; outputs agree to the solver's tolerance times the
#: conditioning, measured 3e-13.
SWEEP_RTOL = 1e-8


def test_fold_free_sweep_agrees():
    """two_shaft, 2200-2900 Hz (8 points, up and down, H = 5, stability): below the
    superharmonic rise at 3000-3100 Hz, no fold, shown by both jump lists being empty.
    RMS DTE (single ``dte_rms [um]``, link ``mesh0.dte_rms [um]``), largest mesh force and
    DSLR from the two tables, to SWEEP_RTOL."""
    s = system("two_shaft")
    g, lk = models("two_shaft")
    ws = 2 * np.pi * np.linspace(2200.0, 2900.0, 8)
    rg = geared_sweep(s, ws, H=H, directions="both", model=g, period=1, stability=True)
    rl = link_sweep(lk, ws, H=H, directions="both", period=1, stability=True)
    assert rg.jumps() == [] and rl.jumps() == []
    fg, fl = rg.to_frame(), rl.to_frame()
    assert fg["converged"].all() and fl["converged"].all() and fg["stable"].all() and fl["stable"].all()
    assert np.allclose(fg["mesh_frequency [Hz]"], fl["base_frequency [Hz]"], rtol=1e-15)
    worst = 0.0
    for single, link, to_single in (
        ("dte_rms [um]", "mesh0.dte_rms [um]", 1.0),
        ("force_max [N]", "mesh0.force_max [N]", 1.0),
        ("dslr [-]", "mesh0.dslr [-]", 1.0),
    ):
        a, b = fg[single].to_numpy(float), fl[link].to_numpy(float) * to_single
        worst = max(worst, float(np.max(np.abs(a / b - 1))))
    print(f"fold-free sweep max rel diff {worst:.1e}")
    assert worst <= SWEEP_RTOL


@pytest.fixture(scope="module")
def kubo_sweeps():
    """Kubo's rig, 3000-6000 Hz in 16 points (200 Hz steps), up and down, H = 5, with
    stability: across the main resonance (gear-pair mode 4915 Hz) and its jumps."""
    ws = 2 * np.pi * np.linspace(3000.0, 6000.0, 16)
    g, lk = models("kubo")
    rg = geared_sweep(system("kubo"), ws, H=H, directions="both", model=g, period=1, stability=True)
    rl = link_sweep(lk, ws, H=H, directions="both", period=1, stability=True)
    return ws, rg, rl


def test_jump_locations_agree(kubo_sweeps):
    """Every jump of one path has one of the other in the same direction within one grid
    step (200 Hz), and the counts are equal; the up sweep jumps off the resonance."""
    ws, rg, rl = kubo_sweeps
    step = ws[1] - ws[0]
    jg, jl = rg.jumps(), rl.jumps()
    assert len(jg) == len(jl) and any(j.direction == "up" for j in jg)
    worst = 0.0
    for a_list, b_list in ((jg, jl), (jl, jg)):
        for a in a_list:
            d = min(abs(a.omega - b.omega) for b in b_list if b.direction == a.direction)
            worst = max(worst, d / step)
    print(f"kubo: {len(jg)} jumps, largest shift {worst:.2f} grid steps")
    assert worst <= 1.0


def test_floquet_verdicts_agree_along_kubo_sweep(kubo_sweeps):
    """Stable flags equal and |μ| to FLOQUET_RTOL along Kubo's sweep (some points unstable)."""
    _, rg, rl = kubo_sweeps
    assert not np.all(rg.mesh.stable)
    print(f"kubo floquet |mu| {_floquet_agree([(rg.mesh, rl.result)], FLOQUET_RTOL):.1e}")


def test_the_api_sweeps_one_mesh_on_the_link_engine():
    """``nlgrd.sweep`` builds the link model of every model, one mesh too (issue 33 item
    4): on two_shaft's fold-free 2200-2900 Hz (8 points, up and down, H chosen, period
    "auto", stability, as the API's defaults) its link table equals the mesh-coordinate
    sweep's (``geared_sweep``, what ``nlgrd.sweep`` ran before) to SWEEP_RTOL: the same
    H, periods, verdicts, mesh outputs and bearing forces (these on the largest bearing
    force, as above)."""
    import nlgrd

    s = system("two_shaft")
    hz = np.linspace(2200.0, 2900.0, 8)
    new = nlgrd.sweep(s, hz=hz, directions="both")
    old = geared_sweep(s, 2 * np.pi * hz, directions="both")
    fo, fn = old.to_frame(), new.to_frame()
    assert new.result.H == old.mesh.H and np.array_equal(new.result.period, old.mesh.period)
    assert fn["converged"].all() and np.array_equal(fo["stable"], fn["stable"])
    worst = 0.0
    for single, link, to_single in (
        ("dte_rms [um]", "mesh0.dte_rms [um]", 1.0),
        ("force_max [N]", "mesh0.force_max [N]", 1.0),
        ("dslr [-]", "mesh0.dslr [-]", 1.0),
    ):
        worst = max(worst, float(np.max(np.abs(fo[single] / (fn[link] * to_single) - 1))))
    names = [b.name or f"bearing {j} (shaft {b.shaft}, node {b.node})" for j, b in enumerate(s.bearings)]
    a = np.array([fo[f"{n} force_max [N]"] for n in names])
    b = np.array([fn[f"{n}.force_max [N]"] for n in names])
    worst = max(worst, _rel(a, b, np.max(np.abs(a))))
    print(f"nlgrd.sweep on the link engine against geared_sweep: {worst:.1e}")
    assert worst <= SWEEP_RTOL
