"""The "auto" receptance of a mid-size model whose dynamic stiffness has a wide band:
direct sparse solves for a short sweep, the pole-residue form once a sweep has solved
``POLES_AFTER`` new frequencies (issue 10); with a narrow band, direct solves throughout.

Reference: the same sweep with ``receptance="direct"`` (exact sparse LU per frequency).
The pole-residue form is exact up to rounding of one eigendecomposition per harmonic
(test_receptance: h_k within 2e-9 of dense solves); the tolerance 1e-8 on the sweep's
outputs leaves room for the Newton tolerance (1e-10) acting on slightly different
receptances, and is far below any physical difference (a 1e-3 change of the mesh damping
moves the DTE RMS by ~1e-4)."""

import dataclasses
from pathlib import Path

import numpy as np

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.geared import build_geared_model, gear_pair_mode, geared_sweep
from nlgrd.nonlinear.reduction import direct_receptance as dr
from nlgrd.nonlinear.reduction import receptance as rc

MODEL = Path(__file__).resolve().parents[1] / "data" / "models" / "two_shaft.toml"


def test_auto_turns_to_poles_after_a_short_sweep_with_the_direct_answers(monkeypatch):
    """Where Z's band is wide (sparse LU per frequency; here forced by lowering
    BAND_LIMIT, as a model with many cross-couplings would have it)."""
    monkeypatch.setattr(dr, "BAND_LIMIT", -1)
    system = load_model(MODEL)
    f = float(round(gear_pair_mode(system)[0]))
    omegas = 2 * np.pi * np.linspace(0.6 * f, 1.4 * f, rc.POLES_AFTER + 40)
    auto = build_geared_model(system, float(omegas.max()), H=5)
    n_mesh = len(auto.receptance._mesh_component())
    assert rc.POLES_LIMIT < n_mesh <= rc.POLES_LATE_LIMIT  # the case this test is about
    assert auto.receptance.method == "direct"
    direct = build_geared_model(system, float(omegas.max()), H=5, receptance="direct")
    probe = build_geared_model(system, float(omegas.max()), H=5).receptance
    for w in omegas[: rc.POLES_AFTER]:  # POLES_AFTER new frequencies, each asked twice
        probe.kappa(float(w), 5)
        probe.kappa_derivative(float(w), 5)
    assert probe.method == "direct" and probe.n_direct == rc.POLES_AFTER
    probe.kappa(float(omegas[-1]), 5)  # the next new one: pole-residue form
    assert probe.method == "poles" and probe.n_direct == rc.POLES_AFTER
    assert probe.requested_method == "auto"
    kw = dict(H=5, stability=False, directions="up")
    a = geared_sweep(system, omegas, model=auto, **kw).mesh
    assert auto.receptance.method == "poles" and auto.receptance.n_direct == rc.POLES_AFTER
    assert max(auto.receptance.pole_check.values()) < 1e-8
    d = geared_sweep(system, omegas, model=direct, **kw).mesh
    assert direct.receptance.n_direct >= omegas.size and direct.receptance.method == "direct"
    assert np.array_equal(a.converged, d.converged) and a.converged.all()
    fa, fd = a.to_frame(), d.to_frame()
    assert np.sum(fd["contact_loss_fraction [-]"] > 0) >= 20  # nonlinear points compared
    for col in ("dte_rms [um]", "force_max [N]", "dslr [-]"):
        ref = fd[col].to_numpy()
        assert np.max(np.abs(fa[col].to_numpy() - ref)) <= 1e-8 * np.max(np.abs(ref)), col


def test_auto_stays_direct_with_a_narrow_band():
    """With a narrow band (two_shaft: half bandwidth 7 without the mesh damping) a direct
    solve costs less than a twentieth of the pole-residue set-up per harmonic, and "auto"
    stays direct however long the sweep."""
    system = load_model(MODEL)
    m = build_geared_model(system, 2 * np.pi * 6000.0, H=2)
    assert m.receptance.method == "direct" and m.receptance._poles_after is None
    assert m.receptance._direct().banded


def test_auto_stays_direct_with_tabulated_bearings():
    """Bearings tabulated against speed keep the dense per-frequency path (the pole-residue
    form needs Z_k quadratic in ω): "auto" must not turn to it."""
    system = load_model(MODEL)
    b = system.bearings[0]
    tab = dataclasses.replace(
        b,
        kyy=(b.kyy, 1.01 * b.kyy),
        kzz=(b.kzz, 1.01 * b.kzz),
        speeds=(0.0, 1e4),
    )
    system = dataclasses.replace(system, bearings=(tab, *system.bearings[1:]))
    m = build_geared_model(system, 2 * np.pi * 3000.0, H=2)
    assert m.receptance.method == "direct" and m.receptance._poles_after is None
    for w in 2 * np.pi * np.linspace(1000.0, 3000.0, rc.POLES_AFTER + 5):
        m.receptance.kappa(float(w), 2)
    assert m.receptance.method == "direct" and m.receptance.n_direct == rc.POLES_AFTER + 5
