"""The frequency plan of a gear pair whose excitation repeats only every N mesh cycles
(tooth errors that differ, runout; :attr:`~nlgrd.gear.mesh.GearMesh.error_period`), and
the speed check that reads ``hz`` as that plan's base (issue 33 closing note, items 1-2).

Model: the two-shaft example (data/models/two_shaft.toml, 25/25 teeth, operating pitch
radius 50 mm) with one gear tooth's spacing error 5 µm (as tests/test_shaft_orders.py):
the LSTE repeats every 25 mesh cycles, one revolution, so the base is the mesh frequency
/ 25 = the shaft frequency. Independent references: the plan's base against the hand count
N_p |s_p| / N of the mesh order, and the pitch-line velocity limit against v = 2π f r by
hand (f the shaft frequency, r = 50 mm): 300 m/s at f = 954.93 Hz.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import nlgrd
from nlgrd.errors import ModelError
from nlgrd.io.model_checks import MAX_PITCH_LINE_VELOCITY
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.links.frequency_plan import FrequencyPlan
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.nonlinear.models.model_views import LinkView

TWO_SHAFT = Path(__file__).resolve().parent.parent / "data" / "models" / "two_shaft.toml"
SPACING = "\n[gear_pairs.errors]\nspacing_gear = [5e-6" + ", 0.0" * 24 + "]\n"
RUNOUT = "\n[gear_pairs.runout]\npinion = [3e-6, 0.5]\n"


def _model(tmp_path, extra: str):
    path = tmp_path / "two_shaft_errors.toml"
    path.write_text(TWO_SHAFT.read_text() + extra)
    return load_model(path)


@pytest.mark.parametrize("extra, n", [("", 1), (SPACING, 25), (RUNOUT, 25)])
def test_the_plan_is_named_after_its_base(tmp_path, extra, n):
    """Without errors the base is the mesh frequency ("mesh"); with one tooth's spacing
    error or a pinion runout it is the mesh frequency / 25 ("mesh/25", formerly "mesh"):
    1 / speed_per_base = N_p |s_p| / N by hand, and the sweep summary prints the name."""
    system = _model(tmp_path, extra)
    gp = system.gear_pairs[0]
    assert gp.error_period == n
    plan = FrequencyPlan.of_model(system)
    order = gp.geometry.teeth_pinion * abs(system.shafts[gp.pinion_shaft].speed_ratio) / n
    assert abs(1 / plan.speed_per_base - order) < 1e-12 * order
    assert plan.name == ("mesh" if n == 1 else f"mesh/{n}")
    words = LinkView(build_link_model(system), None).words()
    assert f"base frequency = {plan.name} ({order:.6g} x the shaft speed)" in words


def test_hz_is_checked_as_the_plans_base_through_the_api(tmp_path):
    """``nlgrd.sweep(hz=...)`` on the mesh/25 model: hz is the shaft frequency here, so
    2 % below the hand limit (936 Hz: 294 m/s) is swept and 2 % above (974 Hz: 306 m/s) is
    refused with one ModelError naming ``hz``; read as a mesh frequency (the former
    one-mesh reading) both would pass at 12 m/s. The same limit in rpm of the shaft."""
    system = _model(tmp_path, SPACING)
    r = system.gear_pairs[0].geometry.operating_pitch_radius_pinion
    assert r == pytest.approx(0.05)
    limit = MAX_PITCH_LINE_VELOCITY / (2 * math.pi * r)  # [Hz] of the shaft = the base here
    res = nlgrd.sweep(system, hz=[0.98 * limit], H=25, directions="up", stability=False, time_domain=False)
    assert bool(res.result.converged[0])
    with pytest.raises(ModelError) as err:
        nlgrd.sweep(system, hz=[0.5 * limit, 1.02 * limit], H=25)
    assert err.value.key == "hz" and "pitch-line velocity of 306 m/s" in err.value.message
    with pytest.raises(ModelError) as err:
        nlgrd.sweep(system, rpm=[1.02 * limit * 60], H=25)
    assert err.value.key == "rpm" and "306 m/s" in err.value.message
    model = build_link_model(system)
    np.testing.assert_allclose(model.receptance.plan.speed_per_base, 1.0, rtol=1e-12)
