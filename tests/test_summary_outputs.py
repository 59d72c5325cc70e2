"""Issue 33 item 5: a study's summary reads the result's typed outputs
(:class:`nlgrd.units.OutputColumn`: quantity, unit, owner, kind), not column-name
patterns or hand-written unit factors; checked on a link model (a mesh and a journal
clearance) and a one-mesh model with named bearings against the static load."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import nlgrd
from nlgrd.studies.study_tasks import SummaryColumns, _sweep_frame, summarise
from nlgrd.units import OutputColumn

ROOT = Path(__file__).resolve().parent.parent
ANALYSIS = dict(
    start=1000.0,
    stop=1700.0,
    count=8,
    unit="hz",
    direction="both",
    stability=True,
    harmonics=5,
    tolerance=0.005,
    time_domain=False,
)


def test_the_dte_factor_comes_from_the_unit():
    """A mesh's RMS DTE in [m] is scaled by 1e6 to the summary's µm, one in [um] by 1: the
    same summary before and after the columns' planned rename to µm."""
    for unit, factor in (("m", 1e6), ("um", 1.0)):
        cols = SummaryColumns.of(
            [
                OutputColumn("dte_rms", unit, "drive", "gear mesh"),
                OutputColumn("force_max", "N", "drive", "gear mesh"),
                OutputColumn("force_max", "N", "journal", "bearing clearance"),
                OutputColumn("force_max", "N", "B2", "bearing"),
                OutputColumn("force_max", "N", "rub", "rub"),  # another link: not a bearing
            ]
        )
        assert cols.dte_rms == [(f"drive.dte_rms [{unit}]", factor)]
        assert cols.mesh_force == ["drive.force_max [N]"]
        assert cols.bearing_force == ["journal.force_max [N]", "B2.force_max [N]"]


@pytest.mark.parametrize("model", ["two_shaft_clearance", "two_shaft"])
def test_summary_units_and_forces_by_hand(model):
    """two_shaft (4 named bearings, one mesh) and two_shaft_clearance (its pinion's free
    end in a journal clearance B1: a link model), 1000-1700 Hz up and down. By hand from
    the table: the RMS DTE peak in µm (x 1e6 of the link's [m] column), the largest
    bearing or clearance force; and the mesh force peak over the DSLR peak is the static
    load W0 = 2298.62 N of the gear pair (DSLR = W/W0 at the same point, so to rounding:
    rtol 1e-12). Measured: DTE peak 4.987 / 5.241 µm, bearing force 1292.6 / 1408.3 N."""
    system = nlgrd.load(ROOT / "data" / "models" / f"{model}.toml")
    frame, jumps, x, per, cols = _sweep_frame(system, ANALYSIS)
    s = summarise(frame, jumps, x, per, cols)
    w0 = system.gear_pairs[0].static_load
    w0 = w0() if callable(w0) else w0
    assert s["mesh_force_peak [N]"] / s["dslr_peak [-]"] == pytest.approx(w0, rel=1e-12)
    dte = frame["mesh0.dte_rms [um]"].max()
    forces = [c for c in frame.columns if c.endswith(".force_max [N]") and not c.startswith("mesh0.")]
    assert len(forces) == 4
    if model == "two_shaft":
        # each shaft symmetric about its gear: the mean mesh force W0 splits in halves
        means = frame[[c for c in frame.columns if c.endswith(".force_mean [N]")]].to_numpy(float)
        assert means.shape[1] == 4
        np.testing.assert_allclose(means, w0 / 2, rtol=1e-9)
    else:
        assert "B1.force_max [N]" in forces
    assert s["dte_rms_peak [um]"] == pytest.approx(dte, rel=1e-15)
    assert 1.0 < s["dte_rms_peak [um]"] < 10.0  # µm, not m
    assert s["bearing_force_max [N]"] == frame[forces].to_numpy(float).max()
