"""The jump criterion at a sweep's end (:func:`nlgrd.nonlinear.results.jumps.find_jumps`):
notebook 01's FE up sweep (Kubo, data/case_studies/kubo.toml, 80 points 2000-16000 rpm,
H chosen = 17) listed an up jump 2000 -> 2177 rpm, DTE RMS 6.78 -> 3.15 µm. The first
step has no left neighbour, which counted as a step of 0, and its right neighbour spans
the unconverged 2354 rpm point (skipped as NaN) to 2532 rpm: 0.008 µm, so a steep flank
passed "ratio times both neighbours".

It is no jump: 2000-2177 rpm is the falling flank of a superharmonic resonance of the
mesh (contact loss 7.8 % at 2000 rpm, none from 2040 rpm), one branch. Independent checks
(below): the up and the down harmonic-balance sweep at 20 rpm steps are equal there (no
hysteresis, so no fold between the two points), and the HHT-α integration of the full FE
model, swept up and down, gives the same DTE RMS at 2000 and 2177 rpm in both directions,
within 0.5 % of the harmonic balance (measured 0.27 % at 2000 rpm with 2048 steps per mesh
period; 2.2 % at 512 and 0.51 % at 1024: the step error shrinks as h², so 0.5 % bounds it).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import nlgrd
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.results.jumps import find_jumps

KUBO = Path(__file__).resolve().parent.parent / "data" / "case_studies" / "kubo.toml"
# notebook 01's up sweep, its first 8 points (pinion rpm, mesh0.dte_rms [um]; NaN: not converged)
RPM = np.array([2000.0, 2177.21519, 2354.43038, 2531.64557, 2708.86076, 2886.07595, 3063.29114, 3240.50633])
DTE = np.array([6.782296, 3.148454, np.nan, 3.156512, 3.293146, 8.521595, 5.250667, 3.313513])


def test_a_steep_first_step_is_no_jump():
    """The first step of the finite points has one neighbour: not judged a jump (nor the
    last, the data reversed as a down sweep ending on the flank); a step of the same size
    between two flat neighbours still is (the criterion itself unchanged inside)."""
    assert find_jumps(RPM, DTE, "up", rtol=0.1, ratio=3.0) == []
    assert find_jumps(RPM[::-1], DTE[::-1], "down", rtol=0.1, ratio=3.0) == []
    flat = np.array([3.15, 3.16, 6.78, 6.79, 6.80])  # the same 3.6 um step, inside
    jumps = find_jumps(RPM[:5], flat, "up", rtol=0.1, ratio=3.0)
    assert [(j.omega_from, j.omega_to) for j in jumps] == [(RPM[1], RPM[2])]


def test_the_first_step_is_one_branch():
    """The checks of the module notes: up = down harmonic balance at 20 rpm steps over
    2000-2180 rpm (to 1e-6: the same orbit), and time integration both ways at 2000 and
    2177 rpm within 0.5 % of it."""
    system = load_model(KUBO)
    rpm = np.linspace(2000.0, 2180.0, 10)
    hb = nlgrd.sweep(system, rpm=rpm, H=17, directions="both", time_domain=False).to_frame()
    up = hb[hb["direction"] == "up"]["mesh0.dte_rms [um]"].to_numpy()
    down = hb[hb["direction"] == "down"]["mesh0.dte_rms [um]"].to_numpy()[::-1]
    assert np.all(np.isfinite(up)) and np.allclose(up, down, rtol=1e-6, atol=0)
    assert up[0] > 6.5 and up[-1] < 3.2  # the flank the notebook's first step spans
    ends = [RPM[0], RPM[1]]
    ref = nlgrd.sweep(system, rpm=ends, H=17, directions="up", time_domain=False).to_frame()
    td = nlgrd.time_sweep(
        system, rpm=ends, directions="both", H=17, steps_per_period=2048, tol=1e-6
    ).to_frame()
    for d in ("up", "down"):
        got = td[td["direction"] == d].sort_values("shaft_speed [rpm]")["mesh0.dte_rms [um]"].to_numpy()
        np.testing.assert_allclose(got, ref["mesh0.dte_rms [um]"].to_numpy(), rtol=5e-3)
