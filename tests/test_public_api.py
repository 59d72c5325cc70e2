"""The analyses ``import nlgrd`` gives (issue 33, item 9), on models with one mesh, a mesh
and a bearing clearance, and a clearance without a mesh.

Each check is against something the façade does not compute itself: the speed
conversion against the tooth count of the model file, a continuation curve against
Newton solves at its own frequencies and its fold against the sign of the Jacobian's
determinant, an orbit search against the sweep's orbit, a time-domain sweep against
the harmonic balance, and the README's quick start run as written.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import nlgrd
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.nonlinear.tracing.orbit_search import same_motion

ROOT = Path(__file__).resolve().parents[1]
CLEARANCE = ROOT / "data" / "models" / "two_shaft_clearance.toml"
RUB = ROOT / "data" / "models" / "rub_rotor.toml"


@pytest.fixture(scope="module")
def clearance_model():
    return nlgrd.load(CLEARANCE)


def test_import_nlgrd_gives_the_analyses_and_the_model_classes():
    for name in ("load", "modes", "campbell", "sweep", "continuation", "search_orbits", "time_sweep"):
        assert callable(getattr(nlgrd, name)), name
    for name in ("RotorSystem", "Shaft", "Disk", "Bearing", "GearMesh", "BearingClearance", "Unbalance"):
        assert isinstance(getattr(nlgrd, name), type), name


def test_speeds_in_rpm_are_the_mesh_frequency_of_the_model_files_tooth_count(clearance_model):
    """rpm of the reference shaft x pinion teeth / 60 is the mesh frequency [Hz]: the same
    points either way (the pinion shaft turns at speed ratio 1 in this file)."""
    gp = clearance_model.gear_pairs[0]
    assert clearance_model.shafts[gp.pinion_shaft].speed_ratio == 1.0
    teeth = gp.geometry.teeth_pinion
    rpm = np.array([2600.0, 2800.0])
    a = nlgrd.sweep(clearance_model, rpm=rpm, H=5, directions="up", period=1, stability=False)
    b = nlgrd.sweep(clearance_model, hz=rpm * teeth / 60, H=5, directions="up", period=1, stability=False)
    np.testing.assert_allclose(a.result.omega, 2 * np.pi * rpm * teeth / 60, rtol=1e-14)
    np.testing.assert_allclose(
        a.result.harmonics, b.result.harmonics, rtol=0, atol=1e-12 * np.abs(b.result.harmonics).max()
    )


def test_continuation_of_a_clearance_model_is_the_newton_solution_and_finds_the_fold(clearance_model):
    """Continuation was refused for link models; now the curve of the mesh + Hertzian
    clearance model (H 5) is checked two ways. Up to its first turning point every curve
    point is the solution Newton finds from the linear response at the same frequency
    (1e-7 of the orbit: the corrector's and Newton's tolerances are 1e-9 and 1e-10 on the
    residual). And the turning point is a fold of the harmonic-balance equations: the
    determinant of their Jacobian dR/dz (the residual's own, not the tracer's tangent) has
    one sign on every point before the turn and the other on every point after it (a real
    eigenvalue crossed zero; the smallest singular value stays above 2e-3 of the largest at
    every point, so the signs are far from rounding)."""
    c = nlgrd.continuation(clearance_model, hz=(1190.0, 1215.0), H=5, stability=False)
    assert len(c.curve.turning_omegas) >= 1
    first = c.curve.turning_indices[0]
    frame = c.to_frame()
    assert {"base_frequency [Hz]", "stable", "B1.force_max [N]", "mesh0.dslr [-]"} <= set(frame.columns)
    assert frame["B1.force_max [N]"].notna().all()
    reduced = build_link_model(clearance_model).reduced
    signs = []
    for i in range(len(c.omega)):
        problem = reduced.at(float(c.omega[i]), 5)
        z = np.asarray(c.curve.curve.harmonics[i])
        _, J, _ = problem.residual_jacobian(z.reshape(-1))
        sv = np.linalg.svd(J, compute_uv=False)
        assert sv[-1] > 2e-3 * sv[0]
        signs.append(np.linalg.slogdet(J)[0])
        if i <= first:
            sol = solve(problem, None)
            assert sol.converged
            assert np.max(np.abs(np.asarray(sol.harmonics) - z)) < 1e-7 * np.max(np.abs(z))
    assert len(set(signs[: first + 1])) == 1 and set(signs[first + 1 :]) == {-signs[0]}


def test_orbit_search_on_a_clearance_model_finds_the_sweeps_orbit(clearance_model):
    """search_orbits raised on several nonlinear coordinates; the link model's period-1
    search at 1250 Hz finds the (stable) orbit the sweep reaches, and no other."""
    found = nlgrd.search_orbits(clearance_model, hz=1250.0, periods=(1,), H=5)
    sweep = nlgrd.sweep(clearance_model, hz=[1250.0], H=5, directions="up", period=1)
    assert bool(sweep.result.stable[0])
    assert [same_motion(o.harmonics, sweep.result.harmonics[0], 1) for o in found] == [True]
    assert found[0].stable


def test_time_sweep_of_a_rotor_with_a_rub_ring_agrees_with_the_harmonic_balance():
    """The rub rotor (no gear: base = shaft speed, so rpm / 60 Hz) well below its
    critical speed, inside the clearance: the HHT-α steady state (its periodicity
    tolerance 1e-4) and the harmonic balance give the same unbalance orbit, to 1e-4."""
    system = nlgrd.load(RUB)
    hb = nlgrd.sweep(system, rpm=[1000.0], H=3, directions="up", period=1)
    np.testing.assert_allclose(hb.result.omega, [2 * np.pi * 1000.0 / 60], rtol=1e-14)
    td = nlgrd.time_sweep(system, rpm=[1000.0], directions="up", H=3)
    z_hb, z_td = np.asarray(hb.result.harmonics[0]), np.asarray(td.result.harmonics[0])
    assert np.max(np.abs(z_td - z_hb)) < 1e-4 * np.max(np.abs(z_hb))


def test_speeds_given_both_ways_or_neither_are_refused(clearance_model):
    with pytest.raises(nlgrd.ModelError, match="rpm"):
        nlgrd.sweep(clearance_model, rpm=[1000.0], hz=[1000.0])
    with pytest.raises(nlgrd.ModelError, match="rpm"):
        nlgrd.sweep(clearance_model)
    with pytest.raises(nlgrd.ModelError, match="hz"):
        nlgrd.sweep(clearance_model, hz=[-5.0])


def test_a_misspelt_sweep_option_is_named_not_a_type_error(clearance_model):
    """An option no sweep function takes (``harmonics=`` for ``H=``) is one ModelError
    naming it and listing the options, before any computation (it was a TypeError from
    deep inside the tracing); a real option (``tol``) still passes."""
    with pytest.raises(nlgrd.ModelError, match=r"harmonics: is not an option of nlgrd.sweep .*\btol\b"):
        nlgrd.sweep(clearance_model, hz=[1000.0, 1100.0], harmonics=5)
    res = nlgrd.sweep(clearance_model, hz=[1000.0], H=5, directions="up", time_domain=False, tol=1e-9)
    assert bool(res.result.converged[0])


def test_the_readme_quick_start_runs_as_written(tmp_path, monkeypatch):
    """The README's five-line quick start, executed as it stands (from the clone's root)."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## Quick start.*?```python\n(.*?)```", text, re.S)
    assert block, "README has no '## Quick start' python block"
    code = block.group(1)
    lines = [ln for ln in code.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    assert len(lines) <= 5
    monkeypatch.chdir(tmp_path)  # the figure is written here, not into the clone
    monkeypatch.setenv("MPLBACKEND", "Agg")
    code = code.replace('"data/', f'"{ROOT.as_posix()}/data/')
    scope: dict = {}
    exec(compile(code, "README quick start", "exec"), scope)  # noqa: S102 - the README's own code
    frame = scope["result"].to_frame()
    assert frame["converged"].all()
    assert (tmp_path / "two_shaft_sweep.png").stat().st_size > 0


def test_cli_continuation_of_a_link_model(tmp_path, capsys):
    """``nlgrd sweep --continuation`` was refused for link models. The mesh + clearance
    model's curve, with every link's outputs, turns where the API's curve does (its
    Jacobian's determinant changes sign between curve points at 1205.2 and 1206.9 Hz: the
    test above), and the down trace from 1215 Hz covers the range."""
    from nlgrd.cli import main

    out = tmp_path / "curve.csv"
    argv = ["sweep", str(CLEARANCE), "--hz", "1190:1215", "--continuation", "--harmonics", "5"]
    assert main([*argv, "--no-stability", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    turn = float(re.search(r"turning points at ([0-9.]+)", text).group(1))
    assert 1205.2 < turn < 1206.9
    import pandas as pd

    frame = pd.read_csv(out)
    assert {"base_frequency [Hz]", "shaft_speed [rpm]", "B1.force_max [N]", "mesh0.dslr [-]"} <= set(
        frame.columns
    )
    teeth = nlgrd.load(CLEARANCE).gear_pairs[0].geometry.teeth_pinion
    np.testing.assert_allclose(
        frame["shaft_speed [rpm]"], frame["base_frequency [Hz]"] * 60 / teeth, rtol=1e-12
    )
    assert set(frame["trace"]) == {"up", "down"}
    assert (tmp_path / "curve.png").stat().st_size > 0


def test_time_sweep_of_a_link_model_has_every_links_outputs():
    """``nlgrd.time_sweep`` of a link model gives every link's and linear bearing's outputs
    (it gave a SweepResult whose only output columns were a gear mesh's, NaN on a rotor
    without one). The rub rotor at 1000 rpm (inside the clearance, from rest) and at 4000
    rpm (on the ring all round, rub force 84 N; started on the harmonic-balance orbit, which
    the integration must keep as a periodic steady state): each output of the HHT-α
    integration (512 steps per period: second-order error measured 4e-4 at 4000 rpm from
    rest) equals the harmonic balance's (H = 7) to 1e-3 (a zero mean force to 1e-3 of the
    bearing's largest force)."""
    from nlgrd.nonlinear.models.link_model import build_link_model
    from nlgrd.timedomain.links import start_from_harmonics

    system = nlgrd.load(RUB)
    rpm = [1000.0, 4000.0]
    hb = nlgrd.sweep(system, rpm=np.linspace(1000.0, 4000.0, 10), H=7, directions="up", period=1)
    frame = hb.to_frame().iloc[[0, -1]].reset_index(drop=True)
    assert frame["rub.force_max [N]"].iloc[0] == 0.0 and frame["rub.force_max [N]"].iloc[1] > 50.0
    w = float(hb.result.omega[-1])
    start = start_from_harmonics(build_link_model(system), w, 7, hb.result.harmonics[-1])
    td = pd.concat(
        [
            nlgrd.time_sweep(system, rpm=rpm[:1], directions="up", H=7).to_frame(),
            nlgrd.time_sweep(system, rpm=rpm[1:], directions="up", H=7, state0=start).to_frame(),
        ],
        ignore_index=True,
    )
    assert "dte_rms [um]" not in td and td["converged"].all()
    np.testing.assert_allclose(td["base_frequency [Hz]"], frame["base_frequency [Hz]"], rtol=1e-14)
    columns = [c for c in frame.columns if c.startswith(("rub.", "bearing "))]
    assert len(columns) == 3 + 2 * 6  # the rub's, and two bearings' (BEARING_OUTPUTS)
    for column in columns:
        # a mean force is 0 (no gravity, no static load): 1e-3 of that bearing's largest force
        scale = frame[column.replace("force_mean", "force_max")] if "force_mean" in column else 0.0
        np.testing.assert_allclose(
            td[column], frame[column], rtol=1e-3, atol=1e-3 * np.max(scale), err_msg=column
        )


def test_a_one_point_sweep_of_the_rub_rotor_lands_on_the_run_up_orbit():
    """``nlgrd.sweep(rub_rotor, rpm=[4000])`` did not converge: Newton from the linear
    response fails there (the disk rubs all round) and a one-point sweep had no next
    frequency to approach from. Now its first point is approached from 0.9 x the speed
    below (``landing.APPROACH_FRACTIONS``) and lands on the orbit a 21-point run-up from
    2000 rpm reaches (rub force 84.04 N at H = 5): the same orbit to the solver's
    tolerance (1e-8 relative, both Newton solutions to 1e-10 of the same equations).
    Independent check of that orbit: ``nlgrd.time_sweep(rub_rotor, rpm=[4000],
    directions="up", H=7)`` from rest (HHT-α, 512 steps per period) settles on 84.075 N,
    contact all round (measured, 175 s; the 4e-4 difference is the integration's
    second-order error, tests/test_public_api.py's time-sweep test above)."""
    system = nlgrd.load(RUB)
    one = nlgrd.sweep(system, rpm=[4000.0], H=5, time_domain=False).to_frame()
    run_up = nlgrd.sweep(system, rpm=np.linspace(2000.0, 4000.0, 21), H=5, directions="up", time_domain=False)
    ref = run_up.to_frame().iloc[-1]
    assert one["converged"].all() and one["stable"].all() and list(one["direction"]) == ["up", "down"]
    assert ref["rub.contact_fraction [-]"] == 1.0 and 80.0 < ref["rub.force_max [N]"] < 90.0
    np.testing.assert_allclose(one["rub.force_max [N]"], ref["rub.force_max [N]"], rtol=1e-8)
    np.testing.assert_allclose(one["rub.displacement_max [um]"], ref["rub.displacement_max [um]"], rtol=1e-8)


def test_stability_with_a_loss_factor_is_refused_naming_the_material_and_the_file(tmp_path, capsys):
    """A loss factor has no time-domain form, so no Floquet stability: the refusal names the
    field (``materials.steel.loss_factor``), and the file on the command line and in a
    study's task (it said ``loss_factor: ...`` with neither). Without stability the sweep runs."""
    from nlgrd.cli import main

    path = tmp_path / "clearance_loss.toml"
    path.write_text(CLEARANCE.read_text().replace("loss_factor = 0.0", "loss_factor = 0.01"))
    system = nlgrd.load(path)
    with pytest.raises(nlgrd.ModelError) as err:
        nlgrd.sweep(system, hz=[1000.0], H=3, directions="up")
    assert err.value.key == "materials.steel.loss_factor"
    assert nlgrd.sweep(system, hz=[1000.0], H=3, directions="up", stability=False).result.converged.all()
    out = tmp_path / "s.csv"
    assert main(["sweep", str(path), "--hz", "1000:1010:2", "--harmonics", "3", "--out", str(out)]) == 2
    lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("nlgrd:")]
    assert len(lines) == 1 and str(path) in lines[0] and "materials.steel.loss_factor" in lines[0]
    # a study's task records the one line with the file (the study goes on)
    import tomllib

    from nlgrd.studies.study_file import Analysis
    from nlgrd.studies.study_tasks import TaskSpec, run_task

    analysis = Analysis(unit="hz", start=1000.0, stop=1010.0, count=2, harmonics=3).as_dict()
    task = run_task(TaskSpec(0, {}, tomllib.loads(path.read_text()), str(path), analysis))
    assert task["summary"] is None
    assert str(path) in task["error"] and "materials.steel.loss_factor" in task["error"]
