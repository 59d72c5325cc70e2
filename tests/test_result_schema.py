"""Issue 33 item 5, one result schema: the link engine's tables (``nlgrd.sweep(...).to_frame()``,
``nlgrd sweep``'s CSV) write every output in the units of docs/conventions.md ("Column
names"), converted in one place (:mod:`nlgrd.units`), and give a one-mesh model every output
of its mesh and bearings."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

import nlgrd  # noqa: E402
from nlgrd.nonlinear.results.bearing_loads import bearing_names  # noqa: E402
from nlgrd.nonlinear.results.metrics import METRIC_UNITS  # noqa: E402
from nlgrd.units import (  # noqa: E402
    ROUNDING_FLOOR,
    WRITTEN,
    floor_rounding,
    parse_column,
    written_frame,
    written_name,
)

ROOT = Path(__file__).resolve().parent.parent
TWO_SHAFT = ROOT / "data" / "models" / "two_shaft.toml"
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
#: two_shaft's mesh frequencies: stable, period 1, no jump in either direction (the
#: fold-free band of tests/test_engine_equivalence.py is 2200-2900 Hz; these 6 points too).
HZ = np.linspace(1000.0, 2900.0, 6)
H = 13


@pytest.fixture(scope="module")
def two_shaft():
    system = nlgrd.load(TWO_SHAFT)
    return system, nlgrd.sweep(system, hz=HZ, H=H, directions="up", time_domain=False)


def test_written_names():
    """Lengths m -> µm with the unit; forces, ratios, flags and point columns unchanged."""
    assert written_name("mesh0.dte_rms [m]") == "mesh0.dte_rms [um]"
    assert written_name("B1.displacement_rms_uncertainty [m]") == "B1.displacement_rms_uncertainty [um]"
    for same in ("mesh0.force_max [N]", "mesh0.dslr [-]", "mesh0.back_contact", "base_frequency [Hz]"):
        assert written_name(same) == same


def test_every_written_column_is_the_si_value_times_its_factor(two_shaft):
    """Each link and bearing column of the table is the engine's SI value (``links``) times
    the factor of :data:`nlgrd.units.WRITTEN` (1e6 for m -> µm, 1 else), to the last bit:
    no other change (no value of this model is near the rounding floor)."""
    _, res = two_shaft
    frame = res.to_frame()
    assert not [c for c in frame.columns if c.endswith(" [m]")]
    converted = 0
    for c in res.links.columns:
        unit = parse_column(c)[2]
        factor = WRITTEN[unit][1] if unit in WRITTEN else 1.0
        converted += factor != 1.0
        np.testing.assert_array_equal(
            frame[written_name(c)].to_numpy(float), res.links[c].to_numpy(float) * factor
        )
    amps = [c for c in res.links.columns if parse_column(c)[1].startswith("dte_amp_")]
    assert len(amps) == res.result.H + 1  # the mesh's DTE harmonic amplitudes, k = 0..H
    assert converted == 3 + 2 * 4 + len(amps)  # the mesh's DTE mean, RMS, p2p; 4 bearings' 2 displacements
    assert sum(parse_column(c)[2] == "um" for c in frame.columns) == converted + 1  # + subharmonic


#: The bearing outputs a one-mesh table writes per bearing (no mean displacement).
BEARING_OUTPUTS = (
    "displacement_max",
    "displacement_rms",
    "force_mean",
    "force_rms",
    "force_max",
    "force_amplitude",
)


def test_one_mesh_table_has_every_mesh_and_bearing_output(two_shaft):
    """Every mesh output (``METRIC_UNITS``) under ``mesh0.`` and every bearing's outputs
    (:data:`BEARING_OUTPUTS`) under ``<bearing>.``, in the written units and finite at the
    stable period-1 points; the frequency column is the frequencies asked and the shaft
    speed the pinion's (25 teeth: 60/25 rpm per Hz of mesh frequency)."""
    system, res = two_shaft
    fn = res.to_frame()
    assert fn["stable"].all() and (fn["period"] == 1).all() and res.jumps() == []
    np.testing.assert_allclose(fn["base_frequency [Hz]"], HZ, rtol=1e-15)
    np.testing.assert_allclose(fn["shaft_speed [rpm]"], HZ * 60 / 25, rtol=1e-13)
    names = []
    for q, si in METRIC_UNITS.items():
        names.append(f"mesh0.{q}" + (f" [{WRITTEN[si][0]}]" if si else ""))
    for b in bearing_names(system):
        for q in BEARING_OUTPUTS:
            names.append(f"{b}.{q} [{'um' if q.startswith('displacement') else 'N'}]")
    assert not sorted(set(names) - set(fn.columns))
    numeric = [c for c in names if fn[c].dtype != object and str(fn[c].dtype) != "boolean"]
    assert np.isfinite(fn[numeric].to_numpy(float)).all()


def test_rounding_is_written_as_zero():
    """:func:`nlgrd.units.floor_rounding`: per row and unit, a magnitude at most
    ROUNDING_FLOOR x the row's largest is 0; NaN, dimensionless and point columns kept."""
    frame = pd.DataFrame(
        {
            "base_frequency [Hz]": [1e-30, 1.0],
            "mesh0.force_max [N]": [3.2e3, np.nan],
            "B4.force_mean [N]": [9.3e-67, 1.0],
            "B4.force_max [N]": [4.4e-8, 2.0],
            "B4.displacement_max [um]": [4.4e-11, 5.0],
            "B0.displacement_max [um]": [8.0, 1e-9],
            "mesh0.contact_loss_fraction [-]": [1e-20, 0.5],
        }
    )
    out = floor_rounding(frame)
    expected = frame.copy()
    expected.loc[0, ["B4.force_mean [N]", "B4.force_max [N]", "B4.displacement_max [um]"]] = 0.0
    expected.loc[1, "B0.displacement_max [um]"] = 0.0
    pd.testing.assert_frame_equal(out, expected)
    # just above the floor: kept
    above = frame.assign(**{"B4.force_max [N]": [3.2e3 * ROUNDING_FLOOR * 1.01, 2.0]})
    assert floor_rounding(above).loc[0, "B4.force_max [N]"] > 0


def test_unloaded_stub_bearings_are_written_as_zero():
    """Kubo's stub shafts (coupled in torsion only: bearings 4-7 carry no load) recover
    forces of 1e-66 to 1e-8 N beside the mesh's 3e3 N (``links``, BLAS-dependent); the
    table writes them 0 and every loaded bearing's value unchanged."""
    res = nlgrd.sweep(nlgrd.load(KUBO), hz=[3100.0], H=5, directions="up", time_domain=False)
    frame, links = res.to_frame(), written_frame(res.links)
    stubs = [c for c in links.columns if c.startswith(("bearing 4", "bearing 5", "bearing 6", "bearing 7"))]
    loaded = [c for c in links.columns if c.startswith(("bearing 0", "bearing 1", "bearing 2", "bearing 3"))]
    assert len(stubs) == len(loaded) == 4 * 6
    top = links.filter(like="[N]").abs().to_numpy().max()
    assert 0 < links[stubs].abs().to_numpy().max() <= 1e-9 * top  # rounding, not zero
    assert (frame[stubs].to_numpy(float) == 0).all()
    np.testing.assert_array_equal(frame[loaded].to_numpy(float), links[loaded].to_numpy(float))


def test_written_frame_is_idempotent(two_shaft):
    frame = two_shaft[1].to_frame()
    pd.testing.assert_frame_equal(written_frame(frame), frame)


def test_rpm_given_puts_the_shaft_speed_first():
    """``rpm=``: ``shaft_speed [rpm]`` first, the speeds as given (to rounding of the round
    trip through rad/s), ``base_frequency [Hz]`` beside it (the mesh frequency: 25 teeth)."""
    rpm = np.array([2400.0, 4800.0])
    res = nlgrd.sweep(nlgrd.load(TWO_SHAFT), rpm=rpm, H=5, directions="up", time_domain=False)
    frame = res.to_frame()
    assert list(frame.columns[:2]) == ["shaft_speed [rpm]", "base_frequency [Hz]"]
    np.testing.assert_allclose(frame["shaft_speed [rpm]"], rpm, rtol=1e-14)
    np.testing.assert_allclose(frame["base_frequency [Hz]"], rpm / 60 * 25, rtol=1e-14)
    plt.close("all")
