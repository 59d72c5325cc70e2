"""The reports' answered sweeps (nlgrd.studies.answered_sweeps): the gaps answered on two
processes give the same numbers as one; the table marks every point without a value
"not found" and the counts are those of the table."""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.geared import geared_sweep
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.studies.answered_sweeps import (
    HB_RESPONSE,
    NOT_FOUND,
    answer_gaps_in_parallel,
    answered_table,
    response_counts,
    torus_answers_in_parallel,
)
from nlgrd.timedomain.sweep_answers import with_time_answers, with_torus_answers

ROOT = Path(__file__).resolve().parent.parent
#: The shortest record time_answer accepts (4 x its 20 batches): 80 periods a point.
PERIODS = {"periods": 80, "max_periods": 80}


@pytest.fixture(scope="module")
def kb_sweep():
    """Three points of K&B's rig as given, low on its range (1100 Hz stable, period 1; the
    others without a stable periodic response), each then marked as a gap: the time domain
    answers them from their orbit, deterministic work whose numbers must not depend on the
    process that did it."""
    system = load_model(ROOT / "data" / "case_studies" / "kahraman_blankenship.toml")
    res = geared_sweep(system, omegas=2 * np.pi * np.array([1000.0, 1100.0, 1200.0]), directions="up")
    assert res.mesh.converged.all() and not res.mesh.no_stable[1]
    gaps = dc.replace(res, mesh=dc.replace(res.mesh, no_stable=np.ones(3, bool)))
    return res, gaps, system


def test_two_processes_give_the_numbers_of_one(kb_sweep):
    """Each point's answer depends on that point only (its start, the seeded twin, one BLAS
    thread): the rows answered on two processes and put back must be bit for bit those of
    the serial with_time_answers, every column of the table (values, uncertainties, kinds,
    the linear bearings' columns)."""
    _, gaps, system = kb_sweep
    serial = with_time_answers(gaps, build_link_model(system), **PERIODS).to_frame()
    parallel = answer_gaps_in_parallel(gaps, system, workers=2, torus=False, **PERIODS).to_frame()
    assert serial["response"].isin(["time domain", "chaotic"]).sum() == 3  # answered: not vacuous
    assert "dte_rms_uncertainty [um]" in parallel
    bearing = [c for c in parallel if c.endswith("force_max [N]") and "uncertainty" not in c]
    assert bearing and np.isfinite(parallel[bearing].to_numpy(float)).all()  # the bearings put back too
    pd.testing.assert_frame_equal(parallel, serial, check_exact=True)


def test_table_marks_points_without_a_value_and_counts_them(kb_sweep):
    """A point whose harmonic balance did not converge, and one left without a value, read
    "not found"; the others keep their kind; the harmonic balance's kind stays beside it;
    the counts are the table's per direction."""
    res, _, _ = kb_sweep
    hb = res.to_frame()
    answered = hb.copy()
    assert hb.loc[1, "response"] == "periodic"
    answered.loc[0, "converged"] = False
    answered.loc[2, "dte_rms [um]"] = np.nan
    table = answered_table(hb, answered)
    assert table["response"].tolist() == [NOT_FOUND, "periodic", NOT_FOUND]
    assert table[HB_RESPONSE].tolist() == hb["response"].tolist()
    counts = response_counts(table).set_index("direction")
    assert counts.loc["up", NOT_FOUND] == 2 and counts.loc["up", "periodic"] == 1
    assert counts.loc["both", "points"] == 3
    with pytest.raises(ValueError, match="same sweep"):
        answered_table(hb, answered.iloc[:2])


def test_tori_of_each_direction_on_their_own_process_give_the_numbers_of_one():
    """Each direction's tori are followed along that direction only (with_torus_answers), so
    the up and down rows answered on two processes and put back must be bit for bit those of
    one process, every column (values, kinds, ω₂, estimates, bearings). Kubo's rig at
    13 750 and 13 800 rpm, up and down: Neimark-Sacker points whose torus converges
    (tests/test_torus_answers.py: within 1 % of the FE integration there). About 10 s CPU
    each way (2.3 s a torus), 2 s more to spawn."""
    system = load_model(ROOT / "data" / "case_studies" / "kubo.toml")
    res = geared_sweep(system, rpm=np.array([13750.0, 13800.0]), directions="both")
    serial = with_torus_answers(res, system).to_frame()
    parallel = torus_answers_in_parallel(res, system, workers=2).to_frame()
    assert (serial["response"] == "quasi-periodic").sum() == 4  # every point a torus: not vacuous
    assert (serial["verdict"] == "not computed").all()
    pd.testing.assert_frame_equal(parallel, serial, check_exact=True)
