"""Several gear meshes as links (issue 11, item 5): the shipped idler train (three gears,
two meshes at one mesh frequency) and two-stage reduction (meshes at 25 Ω and 10 Ω,
solved at their common period, base 5 Ω), against independent calculations:

- the frequency plan against the tooth counts by hand;
- the link model linearised (every mesh at k_h, c_m) against the assembled FE model
  with its meshes (matrices and modal analysis);
- the harmonic balance with contact never lost against the linear frequency response
  of the assembled model (one sparse LU per harmonic, no reduction);
- the reduction's analytic frequency derivatives against finite differences.

The harmonic balance against time integration with both meshes losing contact is in
tests/test_link_time_domain.py.
"""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from nlgrd.errors import ModelError
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.fourier.harmonics import real_to_complex
from nlgrd.nonlinear.links.frequency_plan import FrequencyPlan
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.rotor.assembly import assemble
from nlgrd.rotor.modal import modal_analysis

MODELS = Path(__file__).resolve().parents[1] / "data" / "models"


@pytest.fixture(scope="module", params=["idler_train", "two_stage"])
def train(request):
    return request.param, load_model(MODELS / f"{request.param}.toml")


def test_frequency_plan_from_tooth_counts(train):
    """Idler: both meshes at 25 Ω (25 x 1 = 30 x 25/30), base = mesh frequency, harmonic 1
    each. Two-stage: 25 x 1 = 25 Ω and 20 x 0.5 = 10 Ω, gcd 5 Ω: harmonics 5 and 2. The
    shaft speed is then 1/25 resp. 1/5 of the base; an unbalance on the input shaft
    (order 1) on the idler plan is not a harmonic and is refused."""
    name, system = train
    model = build_link_model(system)
    plan = model.receptance.plan
    if name == "idler_train":
        assert (plan.name, plan.speed_per_base) == ("mesh", 1 / 25)
        assert [lk.order for lk in model.links] == [1, 1]
        with pytest.raises(ModelError, match="not a harmonic"):
            plan.order(1.0, "an unbalance")
    else:
        assert plan.name == "common" and abs(plan.speed_per_base - 1 / 5) < 1e-15
        assert [lk.order for lk in model.links] == [5, 2]
    assert FrequencyPlan.for_system(system, [1.0]).speed_per_base == 1.0


def test_linearised_link_model_is_the_assembled_model(train):
    """The link contract's linear stiffness and damping put back (LinkReceptance.linearised)
    give the matrices of the FE assembly with the meshes at k_h and c_m (to rounding,
    1e-14 of the largest entry) and so its modes: the undamped natural frequencies of the
    20 lowest modes agree to 1e-10 (the eigensolver's rounding on matrices equal to 1e-17)."""
    _, system = train
    lin = build_link_model(system).receptance.linearised()
    ref = assemble(system)
    for a, b in ((lin.K, ref.K), (lin.C, ref.C), (lin.M, ref.M)):
        assert abs(a - b).max() <= 1e-14 * abs(b).max()
    fa = modal_analysis(lin, n_modes=20, damped=False).natural_frequencies
    fb = modal_analysis(ref, n_modes=20, damped=False).natural_frequencies
    print(f"worst natural-frequency difference {np.max(np.abs(fa - fb) / fb):.1e}")
    assert np.max(np.abs(fa - fb) / fb) < 1e-10


@pytest.fixture(scope="module")
def heavy(train, tmp_path_factory):
    """The train at 100x its torques with each mesh's LSTE of the nominal load (from a
    file): no mesh ever opens."""
    name, system = train
    d = tmp_path_factory.mktemp(f"lste_{name}")
    pairs = []
    for i, g in enumerate(system.gear_pairs):
        path = d / f"mesh{i}.toml"
        g.excitation(20).save(path)
        pairs.append(dc.replace(g, torque=100 * g.torque, lste_file=str(path)))
    return name, dc.replace(system, gear_pairs=tuple(pairs))


def test_contact_never_lost_equals_linear_frequency_response(heavy):
    """With every mesh in contact throughout, the harmonic balance is linear: each mesh's
    δ harmonics equal Y_jk = w_jᵀ Z(kω)⁻¹ Σ_i w_i (k_i + i kω c_i) E_ik of the assembled
    model (meshes at k_h, c_m; E_ik the LSTE of mesh i at base harmonic k), to 1e-8
    (two factorisations of matrices with condition ~1e7, rounding ~1e-10)."""
    name, system = heavy
    model = build_link_model(system)
    H = 5 if name == "idler_train" else 10
    base = np.linspace(500.0, 6000.0, 12) / (1 if name == "idler_train" else 5)
    res = link_sweep(model, 2 * np.pi * base, H=H, directions="up", stability=False)
    assert res.result.converged.all()
    for lk in model.links:
        assert np.all(res.links[f"{lk.name}.contact_loss_fraction [-]"] == 0)
    lin = assemble(system)
    W = model.receptance.P
    E = np.stack([real_to_complex(lk.mesh.offset(H)[0]) for lk in model.links])  # (m, H+1)
    kh = np.array([lk.mesh.stiffness for lk in model.links])
    cm = np.array([lk.mesh.damping for lk in model.links])
    worst = 0.0
    for i, om in enumerate(res.result.omega):
        speed = model.receptance.plan.speed(om)
        Y = real_to_complex(res.result.harmonics[i])  # (m, H+1)
        for k in range(1, H + 1):
            f = W @ ((kh + 1j * k * om * cm) * E[:, k])
            if not np.any(f):
                assert np.max(np.abs(Y[:, k])) < 1e-12 * np.max(np.abs(Y[:, 1:]))
                continue
            ref = W.T @ spla.splu(lin.dynamic_stiffness(k * om, speed)).solve(f)
            worst = max(worst, float(np.max(np.abs(Y[:, k] - ref)) / np.max(np.abs(ref))))
    print(f"{name}: worst |Y - Y_lin| / |Y_lin| = {worst:.1e}")
    assert worst < 1e-8, worst


def test_analytic_frequency_derivatives_against_central_differences(train):
    """dκ_k/dω and dF_k/dω of the link reduction (used by the arc-length corrector) equal
    fourth-order central differences of κ_k, F_k with step h = 1e-5 ω (truncation
    ~(h/Δω)⁴ with Δω the distance to the nearest resonance, 2e-10 at 4 x 2300 Hz of the
    two-stage train, where h = 1e-4 ω leaves 2e-6; rounding ~1e-13/1e-5 ~ 1e-8): 1e-6
    of the largest entry of each harmonic."""
    _, system = train
    rec = build_link_model(system).receptance
    for w in 2 * np.pi * np.array([700.0, 2300.0]):
        dk, dfr = rec.derivatives(w, 4)
        h = 1e-5 * w
        t = [rec.terms(w + j * h, 4) for j in (-2, -1, 1, 2)]
        for i, got in enumerate((dk, dfr)):
            ref = (t[0][i] - 8 * t[1][i] + 8 * t[2][i] - t[3][i]) / (12 * h)
            for k in range(1, 5):
                assert np.max(np.abs(got[k] - ref[k])) <= 1e-6 * np.max(np.abs(ref[k])), (i, k)
            assert not np.any(got[0])  # no speed-dependent stiffness: κ_0, F_0 fixed
