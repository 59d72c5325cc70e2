"""Quasi-periodic answers of link models (issue 35, item 2 on any model:
nlgrd.nonlinear.tracing.link_torus and the link branch of
nlgrd.timedomain.sweep_answers.with_torus_answers).

References, independent of the link path:

- Kubo's rig (data/case_studies/kubo.toml) with a bearing clearance of 1 mm that is never
  touched (its bearing moves by ~1e-9 m) is a link model of the same equations as the
  one-mesh model: its torus must solve the one-mesh torus balance, and both must match
  the HHT-α integration of the full FE model in benchmarks/torus_kubo_reference.csv
  (RMS DTE and largest mesh force within the issue's 1 %, ω₂ within 0.5 %; the
  bearing force against the integration of tests/test_quasi_periodic.py, 1 %).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import nlgrd
from nlgrd.nonlinear.hb import quasi_periodic as qp
from nlgrd.nonlinear.models.geared import build_geared_model
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.nonlinear.results.response_kinds import QUASI_PERIODIC
from nlgrd.nonlinear.tracing.link_torus import LinkTorus, torus_link_columns
from nlgrd.nonlinear.tracing.torus_outputs import TORUS_OUTPUTS, geared_torus_model
from nlgrd.nonlinear.tracing.torus_sweep import torus_sweep

ROOT = Path(__file__).resolve().parent.parent
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
REFERENCE = ROOT / "benchmarks" / "torus_kubo_reference.csv"
#: A radial clearance of 1 mm at the gear shaft's far bearing: never touched.
FAR_CLEARANCE = """
[[bearing_clearances]]
name = "far"
shaft = 1
node = 3
clearance = 1e-3
stiffness = 1e8
"""
#: Bearing 0's largest force on the torus at 13 850 rpm by time integration
#: (tests/test_quasi_periodic.py) [N].
BEARING_0_TI = 5520.880924


@pytest.fixture(scope="module")
def kubo_far(tmp_path_factory):
    path = tmp_path_factory.mktemp("kubo") / "kubo_far.toml"
    path.write_text(KUBO.read_text() + FAR_CLEARANCE)
    return nlgrd.load(str(path))


def _reference(rpm):
    ref = pd.read_csv(REFERENCE)
    return ref.set_index(ref["pinion_speed [rpm]"].round(3)).loc[rpm]


def test_kubo_as_a_link_model_gives_the_one_mesh_torus(kubo_far):
    """The torus of the link model (clearance + mesh, three coordinates) at two speeds of
    the reference band, H₁ 13, H₂ 4, against (i) the one-mesh balance: its mesh
    coordinate solves the one-mesh torus balance to a relative residual of 1e-9 (the
    reductions agree to 4e-11, tests/test_engine_equivalence.py); (ii) the one-mesh torus's
    outputs within 1e-3: the balance of a piecewise-linear law sampled on the AFT grid
    has neighbouring solutions (measured at 13 750 rpm: ω₂ 8136.058 and 8137.006 rad/s, both
    at residual 1e-16 of the same one-mesh balance), 1.2e-4 apart, the size of the
    torus's own convergence estimate (1.3e-4; benchmarks/torus_kubo_reference.csv);
    (iii) the time integration: RMS DTE and largest mesh force within 1 %, ω₂ within
    0.5 % (measured: +0.001 %/-0.01 % and +0.15 %), the bearing force at 13 850 rpm within
    1 %; (iv) the clearance: never in contact, no force. About 7 s CPU for the two link
    points against 5 s on one mesh."""
    rpm = [13750.0, 13850.0]
    system = nlgrd.load(str(KUBO))
    geared = build_geared_model(system, 2 * np.pi * 14500 / 60 * 25 * 1.0001, H=17)
    one = torus_sweep(geared, rpm=rpm, H=13, H2=4, check=False)
    model = build_link_model(kubo_far)
    target = LinkTorus(model)
    links = torus_sweep(model, rpm=rpm, H=13, H2=4, check=False, target=target)
    assert one.converged.all() and links.converged.all()
    np.testing.assert_allclose(links.omega, one.omega, rtol=1e-12)
    coord = next(
        sl.start for lk, sl in zip(model.links, model.receptance.slices, strict=True) if lk.name == "mesh0"
    )
    tm = geared_torus_model(geared)
    for sol in links.solutions:
        prob = qp.TorusProblem(tm, sol.omega, sol.grid)
        R, _, _, scale = prob.residual(
            sol.grid.to_real(sol.Y[coord : coord + 1]), sol.secondary, jacobian=False
        )
        assert np.max(np.abs(R)) / scale < 1e-9
    names = list(TORUS_OUTPUTS)
    ref = _reference(rpm)
    for column, rtol in (("dte_rms", 0.01), ("force_max", 0.01), ("secondary_frequency", 0.005)):
        j = names.index(column)
        np.testing.assert_allclose(links.outputs[:, j], one.outputs[:, j], rtol=1e-3, err_msg=column)
        theirs = ref[[c for c in ref.columns if c.startswith(f"ti_{column} [")][0]].to_numpy(float)
        factor = TORUS_OUTPUTS[column][1]
        for res in (one, links):
            np.testing.assert_allclose(res.outputs[:, j] * factor, theirs, rtol=rtol, err_msg=column)
    assert abs(links.bearing_force_max[1, 0] / BEARING_0_TI - 1) < 0.01
    cols = torus_link_columns(model, links.solutions[1])
    assert cols["far.contact_fraction [-]"] == 0 and cols["far.force_max [N]"] == 0
    assert 0 < cols["far.displacement_max [m]"] < 1e-6  # it moves, far from its 1 mm
    j = names.index("force_max")
    assert cols["mesh0.force_max [N]"] == pytest.approx(links.outputs[1, j], rel=1e-12)


@pytest.mark.slow
def test_a_link_sweep_answers_kubo_tori(kubo_far):
    """``nlgrd.sweep`` on the link model with its defaults (period "auto", time domain
    on): its Neimark-Sacker points are answered by the torus first, as on one mesh
    (tests/test_torus_answers.py), every link's columns and the linear bearings' written,
    against the time integration (1 %, 0.5 %). About 20 s for the two points (the link
    sweep's choice of H and its torus ladder included)."""
    rpm = [13750.0, 13800.0]
    res = nlgrd.sweep(kubo_far, rpm=rpm, directions="up")
    frame = res.to_frame()
    assert (frame["response"] == QUASI_PERIODIC).all()
    assert (frame["verdict"] == "not computed").all()
    assert (frame["harmonic_error [-]"] <= 5e-3).all()
    ref = _reference(rpm)
    for ours, theirs, scale, rtol in (
        ("mesh0.dte_rms [m]", "ti_dte_rms [um]", 1e6, 0.01),
        ("mesh0.force_max [N]", "ti_force_max [N]", 1.0, 0.01),
        ("secondary_frequency [Hz]", "ti_secondary_frequency [Hz]", 1.0, 0.005),
    ):
        np.testing.assert_allclose(
            frame[ours].to_numpy(float) * scale, ref[theirs].to_numpy(float), rtol=rtol
        )
    assert (frame["far.force_max [N]"] == 0).all()
    bearings = [c for c in frame.columns if c.startswith("bearing ")]
    assert np.all(np.isfinite(frame[bearings].to_numpy(float)))
    assert frame["bearing 0 (shaft 0, node 1).force_max [N]"].iloc[0] > 0
