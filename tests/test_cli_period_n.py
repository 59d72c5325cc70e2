"""``nlgrd sweep --period N`` for N >= 3: period-N orbits searched for, followed over the grid
and written as the sweep (nlgrd.nonlinear.models.model_views.period_branches).

Model: the single-DOF gear pair of tests/test_orbit_search.py built as an FE model file: two
20-tooth gears (module 5 mm, base radius r_b = 46.985 mm) with polar inertias I = 2 m r_b²,
so that m_eq = 0.1 kg, k_h = 1e8 N/m, backlash 100 µm (b = 50 µm), W_0 = 1000 N
(torque W_0 r_b), LSTE 30 µm cos θ, ζ = 0.01, on short shafts of negligible mass whose
bearings (1e12 N/m) sit at the gears. Its mesh mode is 1e-4 below the single-DOF ω_n (the
bearings in series with k_h, the rounded inertias). Near 2.6 ω_n the pair has a stable
period-3 orbit (the 1/3 subharmonic resonance) with an unstable twin, on an isolated branch
no sweep reaches.

Independent reference: time integration of the single-DOF equation
(:func:`nlgrd.timedomain.sdof.integrate`, DOP853 with event-located contact changes) from
an arbitrary state, which settles on the period-3 orbit (tests/test_orbit_search.py's first
state). The FE orbit is compared at the same ω/ω_n: the ω/3 amplitude within 0.5 % and
the ω amplitude within 1 % (measured 1.5e-4 and 1.5e-3, the order of the FE's 1e-4
difference in the mesh mode, amplified near the resonance; the unstable twin's ω/3
amplitude is 1.5 % off, so the check tells the two apart).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from nlgrd.cli import main
from nlgrd.errors import ModelError
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.fourier.periods import amplitudes
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.nonlinear.models.sdof import SDOFGearPair
from nlgrd.rotor.modal import modal_analysis
from nlgrd.timedomain.sdof import integrate

MODEL = """version = 1
name = "the single-DOF pair of tests/test_orbit_search.py as an FE model"

[materials.light]
density = 0.785
young_modulus = 2.06e11
poisson_ratio = 0.3

[[shafts]]
name = "pinion"
speed_ratio = 1.0
[[shafts.elements]]
length = 0.05
outer_diameter = 0.05
material = "light"

[[shafts]]
name = "gear"
y = 0.1
speed_ratio = -1.0
[[shafts.elements]]
length = 0.05
outer_diameter = 0.05
material = "light"

[[disks]]
shaft = 0
node = 0
mass = 1.0
diametral_inertia = 2.2e-4
polar_inertia = 4.41511e-4

[[disks]]
shaft = 1
node = 0
mass = 1.0
diametral_inertia = 2.2e-4
polar_inertia = 4.41511e-4

[[bearings]]
shaft = 0
node = 0
kyy = 1e12
kzz = 1e12
kxx = 1e10
[[bearings]]
shaft = 0
node = 1
kyy = 1e12
kzz = 1e12
[[bearings]]
shaft = 1
node = 0
kyy = 1e12
kzz = 1e12
kxx = 1e10
[[bearings]]
shaft = 1
node = 1
kyy = 1e12
kzz = 1e12

[[gear_pairs]]
pinion_shaft = 0
pinion_node = 0
gear_shaft = 1
gear_node = 0
torque = 46.98463
mesh_stiffness = 1e8
damping_ratio = 0.01
lste_file = "lste.csv"

[gear_pairs.geometry]
teeth_pinion = 20
teeth_gear = 20
module = 0.005
face_width = 0.02
backlash = 0.0001
"""
K, M, B = 1e8, 0.1, 50e-6
WN = np.sqrt(K / M)


def write_model(folder: Path, torque: float = 46.98463) -> Path:
    (folder / "lste.csv").write_text("harmonic,a_um,b_um\n1,30.0,0.0\n")
    path = folder / "pair.toml"
    path.write_text(MODEL.replace("torque = 46.98463", f"torque = {torque!r}"))
    return path


def mesh_mode_hz(path: Path) -> float:
    """The FE model's mesh (first torsional) natural frequency [Hz]."""
    df = modal_analysis(load_model(path), speed=0.0, n_modes=4).to_frame()
    return float(df.loc[df["kind"] == "torsional", "natural_frequency [Hz]"].iloc[0])


def test_period_three_by_default_search_against_time_integration(tmp_path, capsys):
    model = write_model(tmp_path)
    fn = mesh_mode_hz(model)
    assert abs(fn * 2 * np.pi / WN - 1) < 2e-4  # the FE pair is the single-DOF one
    lo, hi = 2.45 * fn, 2.65 * fn  # 5 points, 2.6 fn among them; the branch runs 2.3-2.7
    out = tmp_path / "p3.csv"
    assert main(["sweep", str(model), "--hz", f"{lo!r}:{hi!r}:5", "--period", "3", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "period 3: searching at" in text and "(40 starts each, H = 9)" in text
    df = pd.read_csv(out)
    assert len(df) == 10 and list(df["direction"]) == ["up"] * 5 + ["down"] * 5
    assert df["converged"].all() and df["stable"].all() and (df["period"] == 3).all()
    assert set(df["response"]) == {"period 3"} and (df["harmonic_error [-]"] < 5e-3).all()
    assert df.filter(like="bearing 0").notna().all().all()
    at = df[np.isclose(df["base_frequency [Hz]"], 2.6 * fn, rtol=1e-9)]
    assert len(at) == 2
    # the reference: the single-DOF pair integrated from an arbitrary state at 2.6 ω_n
    pair = SDOFGearPair(M, K, B, K * 10e-6, np.array([0.0, 30e-6, 0.0]), 0.01).subharmonic(3)
    tr = integrate(pair, 2.6 * WN / 3, [-12.57e-6, -204.16e-6 * WN], tol=1e-8, max_periods=600)
    d = tr.history.delta
    assert tr.converged and np.max(np.abs(d[256:] - d[:-256])) / np.ptp(d) > 1e-3  # not period 1
    ref = amplitudes(tr.harmonics(27)) * 1e6  # ω/3, 2ω/3, ω, ... [µm]
    # the link table's DTE: its RMS over the orbit (the alternating part of the 27 harmonics)
    sub, rms = at["subharmonic_amplitude [um]"].to_numpy(), at["mesh0.dte_rms [um]"].to_numpy()
    ref_rms = np.sqrt(np.sum(ref**2) / 2)
    with capsys.disabled():
        print(
            f"omega/3: {sub[0]:.4f} um against {ref[0]:.4f}; RMS DTE: {rms[0]:.5f} um against {ref_rms:.5f}"
        )
    assert np.all(np.abs(sub / ref[0] - 1) < 5e-3) and np.all(np.abs(rms / ref_rms - 1) < 1e-2)
    # at each of the 5 grid speeds the search finds the saddle-node pair; the first is followed
    orbits = pd.read_csv(tmp_path / "p3_orbits.csv")
    assert len(orbits) == 10 and (orbits["period"] == 3).all()
    assert sorted(orbits.groupby("search at")["stable"].sum()) == [1] * 5
    assert (orbits["floquet_max [-]"][~orbits["stable"]] > 1.1).all()
    first = orbits["search at"] == orbits["search at"].min()
    assert not orbits.loc[first, "on the sweep"].any() and orbits.loc[~first, "on the sweep"].all()
    branches = pd.read_csv(tmp_path / "p3_branches.csv")
    labels = sorted(set(branches["branch"]))
    assert len(labels) == 2 and labels[0].endswith("stable there") and labels[1].endswith("unstable there")
    unstable = branches[branches["branch"] == labels[1]]
    assert unstable["converged"].all() and not unstable["stable"].any()
    assert (tmp_path / "p3.png").stat().st_size > 0


#: A radial clearance of 1 mm at the gear's free-end bearing, never touched (that bearing
#: carries ~1e-11 m): the same equations, but a model with links (issue 33: ``--period N``
#: works on every model).
FAR_CLEARANCE = """
[[bearing_clearances]]
name = "far"
shaft = 1
node = 1
clearance = 1e-3
stiffness = 1e8
"""


def test_period_three_on_a_link_model_against_time_integration(tmp_path, capsys):
    """The pair above with an untouched bearing clearance goes through the link path (every
    link's outputs in ``<link>.<quantity>`` columns): the same search, the same period-3
    response, against the same single-DOF time integration: the ω/3 amplitude and the mesh's
    RMS DTE (about its mean, all 27 harmonics of ω/3 of the reference) within 0.5 % (the
    FE-vs-single-DOF difference of the test above). Its harmonic error is judged by the
    mesh: the clearance's displacement, 1e-8 of its clearance, is measured against 1 % of
    the clearance (``ReducedModel.output_scales``; without that floor it gave 40 %)."""
    model = write_model(tmp_path)
    model.write_text(model.read_text() + FAR_CLEARANCE)
    fn = mesh_mode_hz(model)
    lo, hi = 2.45 * fn, 2.65 * fn
    out = tmp_path / "p3.csv"
    assert main(["sweep", str(model), "--hz", f"{lo!r}:{hi!r}:5", "--period", "3", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "period 3: searching at" in text and "links far, mesh0" in text
    df = pd.read_csv(out)
    assert len(df) == 10 and df["converged"].all() and df["stable"].all() and (df["period"] == 3).all()
    assert set(df["response"]) == {"period 3"} and (df["harmonic_error [-]"] < 5e-3).all()
    assert (df["far.force_max [N]"] == 0).all()  # never touched
    at = df[np.isclose(df["base_frequency [Hz]"], 2.6 * fn, rtol=1e-9)]
    assert len(at) == 2
    pair = SDOFGearPair(M, K, B, K * 10e-6, np.array([0.0, 30e-6, 0.0]), 0.01).subharmonic(3)
    tr = integrate(pair, 2.6 * WN / 3, [-12.57e-6, -204.16e-6 * WN], tol=1e-8, max_periods=600)
    ref = amplitudes(tr.harmonics(27))  # ω/3, 2ω/3, ω, ... [m]
    rms = np.sqrt(np.sum(ref**2) / 2)
    sub, dte = at["subharmonic_amplitude [um]"].to_numpy() * 1e-6, at["mesh0.dte_rms [um]"].to_numpy() * 1e-6
    with capsys.disabled():
        print(f"omega/3: {sub[0] * 1e6:.4f} um against {ref[0] * 1e6:.4f}; RMS DTE {dte[0]:.5e} vs {rms:.5e}")
    assert np.all(np.abs(sub / ref[0] - 1) < 5e-3) and np.all(np.abs(dte / rms - 1) < 5e-3)
    assert (tmp_path / "p3_orbits.csv").exists() and (tmp_path / "p3_branches.csv").exists()


def test_no_orbit_found_exits_1_and_writes_nothing(tmp_path, capsys):
    """At 100 times the load the teeth never separate (static deflection 1 mm against an LSTE
    of 30 µm): the law is linear and its only periodic orbit is the mesh-periodic one."""
    model = write_model(tmp_path, torque=4698.463)
    fn = mesh_mode_hz(model)
    out = tmp_path / "none.csv"
    argv = ["sweep", str(model), "--hz", f"{2.5 * fn!r}:{2.7 * fn!r}:2", "--period", "3"]
    assert main([*argv, "--search-at", f"{2.6 * fn!r}", "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("nlgrd: error: no period-3 orbit found"), err
    assert not list(tmp_path.glob("none*"))


@pytest.mark.parametrize(
    "argv, key",
    [
        (["--period", "7"], "--period"),
        (["--period", "x"], "--period"),
        (["--period", "3.0"], "--period"),
        (["--period", "3", "--continuation", "--rpm", "9000:9100"], "--period"),
        (["--period", "3", "--no-stability"], "--period"),
        (["--period", "3", "--search-periods", "3"], "--search-periods"),
        (["--period", "3", "--search-at", "20000"], "--search-at"),
    ],
)
def test_bad_period_options_are_one_line(argv, key, tmp_path, capsys):
    model = write_model(tmp_path)
    rng = [] if "--rpm" in argv else ["--rpm", "9000:9100:2"]
    assert main(["sweep", str(model), *rng, *argv, "--out", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and key in err, err


def test_link_sweep_points_to_the_orbit_search(tmp_path):
    """A sweep asked for period 3 refuses (ModelError 'period') and names the orbit search."""
    model = build_link_model(load_model(write_model(tmp_path)))
    with pytest.raises(ModelError, match="orbit_search.search_orbits") as err:
        link_sweep(model, [2 * np.pi * 13000.0], H=5, period=3)
    assert err.value.key == "period"
