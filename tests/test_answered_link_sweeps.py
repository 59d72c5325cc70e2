"""The reports' answered sweeps (nlgrd.studies.answered_sweeps) on the link engine
(``nlgrd.sweep``, what notebooks 01 and 03 run): the gaps answered on two processes give
the same numbers as one, every column of the table; the table of a link sweep (its
``base_frequency [Hz]`` and ``mesh0.<quantity>`` columns) marks every point without a
value "not found"."""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import nlgrd
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.nonlinear.results.link_results import LinkSweepResult
from nlgrd.studies.answered_sweeps import (
    HB_RESPONSE,
    NOT_FOUND,
    answer_gaps_in_parallel,
    answered_table,
    gap_rows,
    response_counts,
    torus_answers_in_parallel,
)
from nlgrd.timedomain.sweep_answers import with_time_answers, with_torus_answers

ROOT = Path(__file__).resolve().parent.parent
#: The shortest record time_answer accepts (4 x its 20 batches): 80 periods a point.
PERIODS = {"periods": 80, "max_periods": 80}
DTE = "mesh0.dte_rms [um]"


def with_speed_of(result: LinkSweepResult, like: LinkSweepResult) -> LinkSweepResult:
    """``result`` with the speed settings of ``like`` (the serial answers build a new result
    without them; nlgrd.sweep adds them after answering)."""
    return dc.replace(result, speed_per_base=like.speed_per_base, speed_unit=like.speed_unit)


@pytest.fixture(scope="module")
def kb_sweep():
    """Three points of K&B's rig as given, low on its range (1100 Hz stable, period 1), each
    then marked as a gap: the time domain answers them from their orbit, deterministic work
    whose numbers must not depend on the process that did it. (1100-1300 Hz: all three
    converge under the Haswell, Sandybridge, Prescott and SkylakeX kernels; a sweep started
    at 1000 Hz does not converge there under Haswell, on either engine.)"""
    system = nlgrd.load(ROOT / "data" / "case_studies" / "kahraman_blankenship.toml")
    res = nlgrd.sweep(system, hz=[1100.0, 1200.0, 1300.0], directions="up", time_domain=False)
    assert isinstance(res, LinkSweepResult)
    assert res.result.converged.all() and not res.result.no_stable[0]
    gaps = dc.replace(res, result=dc.replace(res.result, no_stable=np.ones(3, bool)))
    return res, gaps, system


def test_two_processes_give_the_numbers_of_one_on_a_link_sweep(kb_sweep):
    """Each point's answer depends on that point only: the rows answered on two processes
    and put back are bit for bit those of the serial with_time_answers, every column (the
    mesh's values and uncertainties, kinds, the linear bearings' columns)."""
    _, gaps, system = kb_sweep
    assert gap_rows(gaps).tolist() == [0, 1, 2]
    serial = with_speed_of(with_time_answers(gaps, build_link_model(system), **PERIODS), gaps).to_frame()
    parallel = answer_gaps_in_parallel(gaps, system, workers=2, torus=False, **PERIODS).to_frame()
    # answered in the time domain, with uncertainties: not vacuous (measured: 1100 and 1200 Hz;
    # 1300 Hz, a stable orbit marked as a gap, is left unanswered by its 80-period record)
    assert serial["response"].isin(["time domain", "chaotic"]).sum() >= 1
    assert "mesh0.dte_rms_uncertainty [um]" in parallel
    assert "shaft_speed [rpm]" in parallel  # the speed settings survive the answers
    bearing = [c for c in parallel if c.startswith("bearing ") and c.endswith(".force_max [N]")]
    assert bearing and np.isfinite(parallel[bearing].to_numpy(float)).all()  # the bearings put back too
    pd.testing.assert_frame_equal(parallel, serial, check_exact=True)


def test_link_table_marks_points_without_a_value_and_counts_them(kb_sweep):
    """On a link table's names: a point whose harmonic balance did not converge, and one
    left without a value, read "not found"; the harmonic balance's kind stays beside it."""
    res, _, _ = kb_sweep
    hb = res.to_frame()
    answered = hb.copy()
    assert hb.loc[0, "response"] == "periodic"
    answered.loc[1, "converged"] = False
    answered.loc[2, DTE] = np.nan
    table = answered_table(hb, answered, DTE)
    assert table["response"].tolist() == ["periodic", NOT_FOUND, NOT_FOUND]
    assert table[HB_RESPONSE].tolist() == hb["response"].tolist()
    counts = response_counts(table).set_index("direction")
    assert counts.loc["up", NOT_FOUND] == 2 and counts.loc["up", "periodic"] == 1
    assert counts.loc["both", "points"] == 3
    with pytest.raises(ValueError, match="same sweep"):
        answered_table(hb, answered.iloc[:2], DTE)


def test_link_tori_of_each_direction_on_their_own_process_give_the_numbers_of_one():
    """Each direction's tori are followed along that direction only, so the up and down
    rows answered on two processes and put back are bit for bit those of one process.
    Kubo's rig at 13 750 and 13 800 rpm, up and down: Neimark-Sacker points whose torus
    converges (tests/test_torus_answers.py). About 10 s CPU each way (2.3 s a torus), 2 s
    more to spawn."""
    system = nlgrd.load(ROOT / "data" / "case_studies" / "kubo.toml")
    res = nlgrd.sweep(system, rpm=[13750.0, 13800.0], directions="both", time_domain=False)
    serial = with_speed_of(with_torus_answers(res, system), res).to_frame()
    parallel = torus_answers_in_parallel(res, system, workers=2).to_frame()
    assert (serial["response"] == "quasi-periodic").sum() == 4  # every point a torus: not vacuous
    assert (serial["verdict"] == "not computed").all()
    assert "shaft_speed [rpm]" in parallel
    pd.testing.assert_frame_equal(parallel, serial, check_exact=True)
