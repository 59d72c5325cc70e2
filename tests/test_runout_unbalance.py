"""Runout of a gear and unbalance of a disk with the mesh (issue 12, item 4), on the
two-shaft example (data/models/two_shaft.toml, 25/25 teeth, one revolution = 25 mesh
cycles).

Runout (:class:`nlgrd.gear.modifications.GearRunout`) adds e_m cos(θ/z_m + φ_m) to the
LSTE; the analysis is then over a revolution in harmonics of the shaft frequency. Both go
through the link model (:func:`nlgrd.nonlinear.models.link_model.build_link_model`, base =
the shaft speed from :meth:`FrequencyPlan.for_system`, the mesh at harmonic 25), as every
model does (issue 33, stage C). Each check is against an
independent reference: a direct solve of the assembled FE model (linear case) or the
HHT-α integration of the same equations over revolutions (contact loss).
"""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest

from nlgrd.errors import ModelError
from nlgrd.gear.mesh import GearMesh
from nlgrd.gear.modifications import GearErrors, GearRunout
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.links.contract import GearMeshLink
from nlgrd.nonlinear.links.frequency_plan import FrequencyPlan
from nlgrd.nonlinear.models.link_model import Unbalance, build_link_model, link_sweep
from nlgrd.nonlinear.models.shaft_orders import link_spectra
from nlgrd.rotor.assembly import assemble

TWO_SHAFT = Path(__file__).resolve().parent.parent / "data" / "models" / "two_shaft.toml"
N = 25
RUNOUT = GearRunout(pinion=(3e-6, 0.5), gear=(2e-6, -1.0))


def with_pair(**changes):
    s = load_model(TWO_SHAFT)
    return dc.replace(s, gear_pairs=(dc.replace(s.gear_pairs[0], **changes),))


def lines(a_hb, a_ref, big):
    """Largest |ref/HB - 1| over the lines ``big``."""
    return float(np.max(np.abs(a_ref[big] / a_hb[big] - 1)))


def test_runout_lste_and_period():
    gp = with_pair(runout=RUNOUT).gear_pairs[0]
    assert gp.error_period == N and gp.tooth_period == 1
    e, e0 = gp.lste_harmonics(5), with_pair().gear_pairs[0].lste_harmonics(5)
    # the pinion and the gear turn once per 25 mesh cycles: both at shaft order 1
    want = sum(m * np.exp(1j * p) for m, p in (RUNOUT.pinion, RUNOUT.gear))
    assert complex(e[1], -e[2]) == pytest.approx(want, abs=1e-18)
    np.testing.assert_allclose(e[2 * N - 1 :: 2 * N], e0[1::2], atol=1e-18)  # mesh harmonics kept
    e[[1, 2]] = 0.0
    e[2 * N - 1 :: 2 * N] = e[2 * N :: 2 * N] = 0.0
    assert np.all(e == 0.0)
    # runout on the pinion with per-tooth errors on the gear of a 20/30 pair: the hunting period
    g = with_pair().gear_pairs[0].geometry
    assert GearRunout(pinion=(1e-6, 0)).cycles(g) == 25 and GearRunout().cycles(g) == 1
    spacing = np.zeros(25)
    spacing[3] = 2e-6
    both = with_pair(runout=GearRunout(pinion=(1e-6, 0.0)), errors=GearErrors(spacing_gear=spacing))
    assert both.gear_pairs[0].error_period == 25


def test_runout_linear_against_the_fe_frequency_response():
    """Teeth in contact throughout: the model is linear and time-invariant, so each DTE line
    j is T(j Ω) e_j, T = k_m wᵀ Z(jΩ)⁻¹ w with k_m = k_h + i jΩ c_m and Z the dynamic
    stiffness of the assembled FE model with the mesh spring, solved directly (the HB goes
    through the receptance reduction instead). No sidebands: those need contact loss (or a
    varying stiffness). Tolerance 1e-6: two exact solutions of the same linear equations,
    differing by the pole-residue receptance (2e-9, docs/verification.md) and the solver
    tolerance."""
    system = with_pair(runout=RUNOUT)
    w = 2 * np.pi * 2600.0
    model = build_link_model(system)
    res = link_sweep(model, np.array([w / N]), H=5 * N, directions="up", stability=False)
    assert res.result.converged[0] and res.to_frame()["mesh0.contact_loss_fraction [-]"].iloc[0] == 0.0
    fr, a_hb, _, _ = link_spectra(model, res.result, 0, "mesh0")
    e = system.gear_pairs[0].lste_harmonics(5)
    lm = assemble(system)
    mesh, speed = lm.meshes[0], w / N  # pinion speed ratio 1
    ref = np.empty(fr.size)
    for j, om in enumerate(fr, start=1):
        x = np.linalg.solve(lm.dynamic_stiffness(om, speed).toarray(), mesh.w)
        T = (mesh.stiffness + 1j * om * mesh.damping) * (mesh.w @ x)
        ref[j - 1] = abs(T * complex(e[2 * j - 1], -e[2 * j]))
    big = a_hb > 1e-6 * a_hb.max()
    assert set(np.nonzero(big)[0] + 1) == {1, 25, 50, 75, 100, 125}  # shaft order 1, mesh lines
    err = lines(a_hb, ref, big)
    print(f"linear runout: worst {err:.1e}; 1x {a_hb[0] * 1e6:.3f} um")
    assert err < 1e-6


@pytest.mark.slow  # about 12 s: 60 revolutions of 12 800 steps
def test_runout_with_contact_loss_against_time_integration():
    """6900 Hz mesh, contact lost 12 % of the time: the contact loss mixes the runout's
    shaft order into sidebands of the mesh harmonics. HB with H = 7 mesh harmonics (175 of
    the shaft frequency, period 1), reached by a down sweep from 7000 Hz; link HHT-α over revolutions,
    512 steps per mesh period, 60 revolutions from the HB orbit (a lightly damped mode near
    6700 Hz settles slowly). Lines above 4 % of the largest sideband up to the 5th mesh
    harmonic (beyond it the truncation at H = 7 shows, 5 %): within 2 % (the issue's); the
    8 lines (2 sidebands) measured 0.79 % on the link engine (0.8 % on the single-mesh one)."""
    from nlgrd.timedomain.links import link_time_response, start_from_harmonics

    system = with_pair(runout=RUNOUT)
    w = 2 * np.pi * np.array([6900.0, 7000.0]) / N  # the base: the shaft frequency
    model = build_link_model(system)
    res = link_sweep(model, w, H=7 * N, directions="down", period=1)
    df = res.to_frame()
    assert df["stable"].all() and df["mesh0.contact_loss_fraction [-]"].iloc[1] > 0.1
    fr, a_hb, _, _ = link_spectra(model, res.result, 1, "mesh0")
    start = start_from_harmonics(model, w[0], 7 * N, res.result.harmonics[1])
    tr = link_time_response(model, w[0], steps_per_period=512 * N, tol=1e-6, state0=start, max_periods=60)
    d = tr.y[0]
    a_td = 2 * np.abs(np.fft.rfft(d)[1 : a_hb.size + 1]) / d.size
    j = np.arange(1, a_hb.size + 1)
    side = (j % N != 0) & (j > 1)
    big = (a_hb >= 0.04 * a_hb[side].max()) & (j <= 5 * N)
    err = lines(a_hb, a_td, big)
    print(f"runout, contact loss: {big.sum()} lines ({(big & side).sum()} sidebands), worst {err:.2e}")
    assert (big & side).sum() >= 2 and err < 0.02


@pytest.mark.slow  # about 40 s: the link HB at 175 harmonics and 30 revolutions of 12 800 steps
def test_unbalance_sidebands_link_model_against_time_integration():
    """The gear disk's unbalance (1e-4 kg m at node 4 of the gear shaft) with the mesh at
    6900 Hz, contact lost 12 % of the time: the unbalance moves the gear centre at the shaft
    order, which the contact loss mixes into sidebands k f_mesh ± f_shaft. Link model on
    the base = shaft speed (mesh at harmonic 25), H = 7 x 25; link HHT-α integration,
    512 steps per mesh period, started on the HB orbit. Sidebands and mesh lines above
    5 % of the largest sideband up to the 5th mesh harmonic within 2 % (the issue's)."""
    from nlgrd.timedomain.links import link_time_response, start_from_harmonics

    system = load_model(TWO_SHAFT)
    model = build_link_model(system, unbalance=[Unbalance(1, 4, 1e-4, 0.3)])
    assert model.receptance.plan.speed_per_base == 1.0 and model.links[0].order == N
    H = 7 * N
    w = 2 * np.pi * 6900.0 / N
    res = link_sweep(model, np.array([w]), H=H, directions="up", stability=False)
    assert res.links["mesh0.contact_loss_fraction [-]"].iloc[0] > 0.1
    z = model.link_harmonics(res.result.harmonics[0], "mesh0")[0]
    a_hb = np.hypot(z[1::2], z[2::2])
    start = start_from_harmonics(model, w, H, res.result.harmonics[0])
    tr = link_time_response(model, w, steps_per_period=512 * N, tol=1e-7, state0=start, max_periods=30)
    a_td = 2 * np.abs(np.fft.rfft(tr.y[0])[1 : a_hb.size + 1]) / tr.y.shape[1]
    j = np.arange(1, a_hb.size + 1)
    side = (j % N != 0) & (j > 1)
    big = (a_hb >= 0.05 * a_hb[side].max()) & (j <= 5 * N)
    err = lines(a_hb, a_td, big)
    print(f"unbalance: {big.sum()} lines ({(big & side).sum()} sidebands), worst {err:.2e}")
    assert (big & side).sum() >= 2 and err < 0.02


def test_link_path_takes_the_revolution():
    """With runout the mesh link must sit at a multiple of 25 base harmonics: the default
    plan does (base = shaft speed), an explicit mesh plan is refused naming ``plan``."""
    system = with_pair(runout=RUNOUT)
    plan = FrequencyPlan.for_system(system)
    assert plan.speed_per_base == 1.0
    link = GearMeshLink.from_system(system, 0, order=N)
    e = system.gear_pairs[0].lste_harmonics(30)
    np.testing.assert_allclose(link.mesh.lste[:3], e[:3])  # shaft order 1 at base harmonic 1
    with pytest.raises(ModelError, match="multiple of harmonic 25") as err:
        build_link_model(system, plan=FrequencyPlan(1 / N, "mesh"))
    assert err.value.key.endswith("plan")


@pytest.mark.parametrize(
    ("value", "match"),
    [((-1e-6, 0.0), "eccentricity must be >= 0"), ((1e-6,), "2 numbers"), ((1e-6, float("nan")), "finite")],
)
def test_runout_input_checks(value, match):
    with pytest.raises(ModelError, match=match) as err:
        GearRunout(pinion=value)
    assert err.value.key == "pinion"
    g = load_model(TWO_SHAFT).gear_pairs[0]
    with pytest.raises(ModelError) as err:
        dc.replace(g, runout=(1e-6, 0.0))
    assert err.value.key == "runout"
    assert isinstance(g, GearMesh)


def test_runout_in_the_model_file(tmp_path):
    from nlgrd.io.model_writer import save_model

    text = TWO_SHAFT.read_text()
    good = tmp_path / "runout.toml"
    good.write_text(text + "\n[gear_pairs.runout]\npinion = [3e-6, 0.5]\ngear = [2e-6, -1.0]\n")
    assert load_model(good).gear_pairs[0].runout == RUNOUT
    again = tmp_path / "again.toml"
    save_model(load_model(good), again)
    assert load_model(again).gear_pairs[0].runout == RUNOUT
    for body, msg in [
        ("pinion = [-3e-6, 0.5]", "eccentricity must be >= 0"),
        ("pinion = [3e-6]", "2 entries"),
    ]:
        bad = tmp_path / "bad.toml"
        bad.write_text(text + f"\n[gear_pairs.runout]\n{body}\n")
        with pytest.raises(ModelError, match=msg) as err:
            load_model(bad)
        assert err.value.key == "gear_pairs[0].runout.pinion" and err.value.file.endswith("bad.toml")
