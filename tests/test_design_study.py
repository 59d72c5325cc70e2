"""The design-study notebook (notebooks/04_design_study.ipynb) in fast mode, on a 2-worker
embedded Dask cluster, and batch reports of notebook 01 (``nlgrd report``).

Design study, checked against things other than the code that made them:

- the unmodified gears' peak dynamic factor is the same at every load (the model is
  homogeneous in the load while the backlash stays open: LSTE, deflection and dynamic
  load all scale with it), to 1e-3 (seen 5e-15: the same dimensionless problem at the
  same speeds);
- two tasks with the torque and the relief in the same ratio have the same peak, to
  1e-6 (the same homogeneity; seen 1e-15);
- the relief with the lowest peak never moves to smaller amounts as the load rises
  (Lin, Oswald & Townsend 1994);
- one cell of the map recomputed here by ``nlgrd.sweep`` on a model changed through the
  model classes (``dataclasses.replace``), not through the study's model keys: the same
  peak to 1e-9 (the same solver on the same model, so only the plumbing can differ).

Batch reports: 4 parameter sets of notebook 01 in fast mode on the embedded cluster, into
4 report folders and an index; a misspelt parameter in one set fails before any runs.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from nlgrd.studies.notebooks import NOTEBOOKS, run_notebook

ROOT = Path(__file__).resolve().parents[1]
NLGRD = [sys.executable, "-m", "nlgrd.cli"]


@pytest.fixture(scope="module")
def design(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("design") / "out"
    run_notebook(NOTEBOOKS / "04_design_study.ipynb", out, {"fast": True, "workers": 2}, timeout=900)
    return out


@pytest.mark.notebook
def test_unmodified_dynamic_factor_does_not_depend_on_load(design):
    summary = pd.read_csv(design / "relief_load_summary.csv")
    assert (summary["status"] == "done").all()
    bare = summary[summary["gear_pairs[0].modifications.tip_relief_pinion [m]"] == 0]["dslr_peak [-]"]
    assert len(bare) >= 4 and bare.max() / bare.min() - 1 < 1e-3
    checks = pd.read_csv(design / "checks.csv")
    assert checks["value"].iloc[0] < 1e-3
    # torque and relief in the same ratio: the same dynamic factor (homogeneity)
    pairs = pd.read_csv(design / "scaled_pairs.csv")
    assert len(pairs) >= 2 and (pairs["difference [-]"] < 1e-6).all()


@pytest.mark.notebook
def test_best_relief_moves_up_with_load_and_relief_helps_at_high_load(design):
    best = pd.read_csv(design / "best_relief.csv")
    for _, part in best.groupby("shape"):
        b = part.sort_values("torque [N m]")["best relief [um]"].to_numpy()
        assert np.all(np.diff(b) >= 0)
    summary = pd.read_csv(design / "relief_load_summary.csv")
    high = summary[summary["gear_pairs[0].torque [N m]"] == summary["gear_pairs[0].torque [N m]"].max()]
    bare = high[high["gear_pairs[0].modifications.tip_relief_pinion [m]"] == 0]["dslr_peak [-]"].min()
    assert high["dslr_peak [-]"].min() < 0.8 * bare  # a relief designed near this load lowers the peak


@pytest.mark.notebook
def test_one_map_cell_equals_a_direct_sweep_of_the_same_model(design):
    from nlgrd.analyses import sweep
    from nlgrd.gear.modifications import ProfileModification
    from nlgrd.io.model_file import load_model

    summary = pd.read_csv(design / "relief_load_summary.csv")
    row = summary[(summary["gear_pairs[0].modifications.shape [-]"] == "parabolic")].iloc[-1]
    analysis = tomllib.loads((design / "relief_load.study.toml").read_text())["analysis"]
    system = load_model(ROOT / "data" / "case_studies" / "kubo.toml")
    relief = float(row["gear_pairs[0].modifications.tip_relief_pinion [m]"])
    gp = dataclasses.replace(
        system.gear_pairs[0],
        torque=float(row["gear_pairs[0].torque [N m]"]),
        damping_ratio=float(row["gear_pairs[0].damping_ratio [-]"]),
        modifications=ProfileModification(
            tip_relief_pinion=relief, tip_relief_gear=relief, shape="parabolic"
        ),
    )
    system = dataclasses.replace(system, gear_pairs=(gp,))
    res = sweep(system, rpm=np.linspace(*analysis["rpm"]))
    frame = res.to_frame()
    peak = float(np.nanmax(frame["mesh0.dslr [-]"].astype(float)))
    assert peak == pytest.approx(row["dslr_peak [-]"], rel=1e-9)


@pytest.mark.notebook
def test_design_study_figures_are_captioned_and_study_files_rerun(design, tmp_path):
    captions = json.loads((design / "figures.json").read_text())
    assert (
        {p.name for p in design.glob("*.png")}
        == set(captions)
        == {
            "relief_map.png",
            "relief_curves.png",
            "jump_band.png",
            "tolerance_distribution.png",
        }
    )
    # the study file written beside the results runs from the command line as it is
    study = design / "jump_band.study.toml"
    r = subprocess.run(
        [
            *NLGRD,
            "study",
            str(study),
            "--out",
            str(tmp_path / "rerun"),
            "--executor",
            "serial",
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr
    rerun = pd.read_csv(tmp_path / "rerun" / "summary.csv").drop(columns=["key"])
    notebook = pd.read_csv(design / "jump_band_summary.csv").drop(columns=["backlash [um]"])
    pd.testing.assert_frame_equal(rerun, notebook, check_exact=False, check_dtype=False, rtol=1e-9)


#: Four sets of notebook 01 in fast mode, cut to the bone (12 points, no extra damping
#: sweep, time integration at one point): about 25 s each.
BATCH = "".join(
    f"""
[[runs]]
name = "{name}"
fast = true
H = {h}
points = 12
td_points = 1
damping_band = [0.05]
rpm_max = {rpm_max}
"""
    for name, h, rpm_max in (
        ("H5", 5, 16000.0),
        ("H7", 7, 16000.0),
        ("to13k", 5, 13000.0),
        ("to14k", 5, 14000.0),
    )
)


@pytest.mark.notebook
def test_batch_of_four_sets_of_notebook_01_on_the_local_cluster(tmp_path):
    batch = tmp_path / "batch.toml"
    batch.write_text(BATCH)
    out = tmp_path / "batch"
    r = subprocess.run(
        [
            *NLGRD,
            "report",
            "01_kubo_dynamic_factor",
            "--batch",
            str(batch),
            "--out",
            str(out),
            "--workers",
            "2",
        ],
        capture_output=True,
        text=True,
        timeout=1200,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    index = (out / "index.html").read_text()
    for name in ("H5", "H7", "to13k", "to14k"):
        folder = out / name
        assert (folder / "01_kubo_dynamic_factor.ipynb").exists() and (
            folder / "01_kubo_dynamic_factor.html"
        ).exists()
        assert list(folder.glob("*.png")) and list(folder.glob("*.csv"))
        assert f'href="{name}/01_kubo_dynamic_factor.html"' in index
    # each run got its own parameters
    for name, h, top in (("H5", 5, 16000), ("H7", 7, 16000), ("to13k", 5, 13000), ("to14k", 5, 14000)):
        sweep = pd.read_csv(out / name / "dslr_fe.csv")
        assert set(sweep["H"].dropna().astype(int)) == {h}
        assert sweep["shaft_speed [rpm]"].max() == pytest.approx(top)
    record = json.loads((out / "batch.json").read_text())
    assert [record[n]["parameters"]["H"] for n in ("H5", "H7")] == [5, 7]
    assert all(record[n]["error"] is None for n in record)


@pytest.mark.notebook
def test_a_misspelt_parameter_in_a_batch_fails_before_anything_runs(tmp_path):
    batch = tmp_path / "batch.toml"
    batch.write_text(BATCH.replace("rpm_max = 14000.0", "rpm_mx = 14000.0"))
    out = tmp_path / "batch"
    r = subprocess.run(
        [*NLGRD, "report", "01_kubo_dynamic_factor", "--batch", str(batch), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 2
    assert r.stderr.strip().startswith("nlgrd: error: ") and "to14k: parameters.rpm_mx" in r.stderr
    assert "\n" not in r.stderr.strip()
    assert not out.exists()


@pytest.mark.notebook
def test_tolerance_study_ran_the_study_files_draws(design):
    """The tolerance section's rows are the shipped study file's first Latin-hypercube
    draws (seed 2026, 6 in fast mode), every one a finished sweep with a peak above 1."""
    from nlgrd.studies.study_file import load_study

    study = dataclasses.replace(
        load_study(ROOT / "data" / "studies" / "kubo_relief_tolerance.toml"), samples=6
    )
    expected = pd.DataFrame(study.parameter_sets())
    tol = pd.read_csv(design / "tolerance_summary.csv")
    assert (tol["status"] == "done").all() and (tol["dslr_peak [-]"] > 1).all()
    for column in expected:
        assert np.allclose(tol[column], expected[column], rtol=1e-9, atol=0)
