"""Period doubling on the link path (issue "Beyond mesh-periodic motion"): ``link_sweep``
with ``period="auto"`` (``nlgrd sweep``'s default) lands on the stable period-2 orbit
where a period-1 orbit has lost stability by period doubling, in both sweep directions,
and ``nlgrd sweep --period`` does the same for a link model.

The model (``MODEL`` below): a spur drive after data/models/two_shaft.toml (Kubo's 25/25
gears, k_h = 0.2587e9 N/m, 108 N m, 0.1 mm backlash, the same steel, bearings and motor
damping), cut down to what the test can afford: two 0.2 m shafts of two elements each
(36 DOFs), the gear blanks at mid-span, no motor or load inertia (a torsional damper of
0.2 N m s/rad at each shaft's free end instead: without one the gear shaft's ends twist
against each other undamped), and the pinion's free-end bearing replaced by a 20 µm
radial clearance with Hertzian contact (1e10 N/m^1.5, 1e3 N s/m): the mesh load holds the
journal on it, in nonlinear contact throughout. So that period doubling happens, the
teeth carry 40 µm of linear tip relief: an over-relieved pair whose LSTE (first harmonic
8.5 µm) is as large as the static mesh deflection (8.9 µm), like the single-DOF pair of
tests/test_period_doubling.py (Kahraman & Singh 1990). Mesh damping ratio 0.06: with
0.03 the period-2 orbits themselves lose stability over much of the band (a torus near
5400-6000 Hz, period 4 near 7100-7700 Hz); 0.06, within the 0.01-0.1 usually quoted
for spur gears, leaves one clean period-2 branch.

Harmonic balance at H = 9 (period 1) and 18 harmonics of ω/2 (period 2, each point's
estimated truncation error against 26 harmonics at most 6.5e-5). On the 50 Hz grid
5375-6425 Hz the mesh loses contact over 25-39 % of the period; the period-1 orbit loses
stability by period doubling between 5475 and 5525 Hz (its real multiplier passes -1
near 5490 Hz) and the stable period-2 orbit runs from there to 6425 Hz (19 grid points),
its ω/2 content 5.7 µm at 5525 Hz, 15.6 µm at 6425 Hz.

Independent reference: the HHT-α integration of the full FE equations with every link
pointwise (:func:`nlgrd.timedomain.links.link_time_response`) on the period-2 model, in
cycles of two mesh periods, its period read from the Poincaré sections once per mesh
period (at every phase): period 2 when δ(t + T) differs from δ(t) over the last cycle by
more than 1e-2 of δ's range, period 1 when by less than 1e-4.

- The branch (19 frequencies): a converged time-domain sweep at each of them would cost
  minutes, so each integration starts on the harmonic-balance orbit with its ω/2 content
  cut by 5 % and runs 20 cycles (40 mesh periods, 1024 steps per cycle); it must come
  back to the orbit (a wrong or unstable orbit would not be returned to) and stay period
  2, its last cycle changing by less than 5e-3 (measured at most 2.9e-3). The amplitudes
  of the ω/2 and ω components of the mesh DTE agree within 1 %: measured at most 0.35 %
  (5925 Hz, the perturbation's last trace), 1e-4 to 1e-3 elsewhere. The time step alone
  accounts for about 2e-4 (1024 against 2048 steps per cycle at 5600 Hz: 2.1e-4 and
  1.4e-4); near the doubling it grows, as the ω/2 amplitude grows like the square root
  of the distance to it and the step shifts the doubling by about 1 Hz: 10 Hz above it
  (5500 Hz) 0.8 % (2.5 % with 512 steps); the grid keeps 35 Hz from it.
- The doubling: a time-domain up sweep over 5425-5575 Hz, each frequency continuing from
  the last (started on the harmonic-balance period-1 orbit with a 1 % seed at ω/2, 512
  steps per cycle, to a period change below 1e-5), settles on period 1 at 5425 and 5475
  Hz (half-cycle difference 3e-6) and on period 2 from 5525 Hz (0.33): the same grid
  interval as the harmonic balance (the issue allows one grid step).
"""

from __future__ import annotations

import tomllib

import numpy as np
import pandas as pd
import pytest

from nlgrd.cli import main
from nlgrd.errors import ModelError
from nlgrd.io.model_file import model_from_dict
from nlgrd.nonlinear.fourier.harmonics import analyse
from nlgrd.nonlinear.fourier.periods import amplitudes, spread, subharmonic_mask
from nlgrd.nonlinear.links.contract import GearMeshLink
from nlgrd.nonlinear.links.frequency_plan import FrequencyPlan
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep, period_model
from nlgrd.nonlinear.results.metrics import NO_STABLE
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.tracing.auto_period import transitions
from nlgrd.timedomain.links import link_time_response, start_from_harmonics

MODEL = """
version = 1
name = "spur drive with a bearing clearance, over-relieved teeth"

[materials.steel]
density = 7850.0
young_modulus = 2.1e11
poisson_ratio = 0.3

[[shafts]]
name = "pinion"
speed_ratio = 1.0
[[shafts.elements]]
count = 2
length = 0.1
outer_diameter = 0.045
material = "steel"

[[shafts]]
name = "gear"
y = 0.1
speed_ratio = -1.0
[[shafts.elements]]
count = 2
length = 0.1
outer_diameter = 0.045
material = "steel"

[[disks]]
name = "pinion blank"
shaft = 0
node = 1
mass = 0.9248
diametral_inertia = 5.953e-4
polar_inertia = 1.156e-3

[[disks]]
name = "gear blank"
shaft = 1
node = 1
mass = 0.9248
diametral_inertia = 5.953e-4
polar_inertia = 1.156e-3

[[bearings]]
name = "pinion, motor side (locating)"
shaft = 0
node = 0
kyy = 1.5e8
kzz = 1.5e8
cyy = 1.0e3
czz = 1.0e3
kxx = 5.0e7
cxx = 5.0e2

[[bearings]]
name = "gear, left (locating)"
shaft = 1
node = 0
kyy = 1.5e8
kzz = 1.5e8
cyy = 1.0e3
czz = 1.0e3
kxx = 5.0e7
cxx = 5.0e2

[[bearings]]
name = "gear, load side"
shaft = 1
node = 2
kyy = 1.5e8
kzz = 1.5e8
cyy = 1.0e3
czz = 1.0e3

[[bearing_clearances]]
name = "B1"
shaft = 0
node = 2
clearance = 20e-6
stiffness = 1.0e10
exponent = 1.5
damping = 1.0e3

[[couplings]]
name = "motor electromagnetic damping"
shaft_a = 0
node_a = 0
c_torsion = 0.2

[[couplings]]
name = "brake"
shaft_a = 1
node_a = 2
c_torsion = 0.2

[[gear_pairs]]
pinion_shaft = 0
pinion_node = 1
gear_shaft = 1
gear_node = 1
torque = 108.0
mesh_stiffness = 0.2587e9
damping_ratio = 0.06
input_node = 0
output_node = 2

[gear_pairs.geometry]
teeth_pinion = 25
teeth_gear = 25
module = 0.004
face_width = 0.015
backlash = 0.0001

[gear_pairs.modifications]
tip_relief_pinion = 40e-6
tip_relief_gear = 40e-6
"""

#: base (= mesh) frequencies [Hz]: 50 Hz steps, 35 Hz clear of the doubling near 5490 Hz
GRID = np.arange(5375.0, 6426.0, 50.0)
H = 9
#: the period-2 points of the harmonic balance (both directions), and the first of them
BRANCH = GRID[GRID >= 5525.0]
#: time steps per cycle of two mesh periods, cycles integrated from the perturbed orbit
STEPS, CYCLES = 1024, 20


def system():
    return model_from_dict(tomllib.loads(MODEL))


@pytest.fixture(scope="module")
def swept():
    model = build_link_model(system())
    # link_sweep's default period is "auto" (it was 1): the period-2 branch without asking
    return model, link_sweep(model, 2 * np.pi * GRID, H=H, directions="both")


def half_difference(d):
    """max |δ(t) - δ(t + T)| over a cycle of two mesh periods, relative to δ's range: the
    Poincaré sections once per mesh period, at every phase."""
    n = d.size // 2
    return float(np.max(np.abs(d[:n] - d[n:])) / np.ptp(d))


def test_period_two_link_model_holds_the_period_one_orbits():
    """:func:`period_model` puts every excitation at even harmonics of ω/2: a stable
    period-1 orbit (5375 Hz, contact lost 32 % of the period) spread onto ω/2 solves its
    harmonic balance to rounding, and its Floquet multipliers over 2T are the squares of
    those over T (the monodromy over two periods is the square of that over one)."""
    model = build_link_model(system())
    two = period_model(model, 2)
    assert two is period_model(model, 2) and two.period == 2 and two.top_order == 2
    assert [lk.order for lk in two.links if isinstance(lk, GearMeshLink)] == [2]
    w = 2 * np.pi * GRID[0]
    r = link_sweep(model, [w], H=H, directions="up", period=1).result
    z1 = r.harmonics[0]
    assert r.stable[0] and res_contact_loss(model, z1, w) > 0.3
    R, _, scale = two.reduced.at(w / 2, 2 * H).residual_jacobian(spread(z1, 2).reshape(-1))
    assert np.max(np.abs(R)) / scale < 1e-9
    r1, r2 = model.reduced, two.reduced
    mu1 = floquet_multipliers(r1.linear_state_space(w), r1.nonlinearities, z1, w, method="dense")
    mu2 = floquet_multipliers(
        r2.linear_state_space(w / 2), r2.nonlinearities, spread(z1, 2), w / 2, method="dense"
    )
    top1, top2 = np.sort(np.abs(mu1))[::-1], np.sort(np.abs(mu2))[::-1]
    np.testing.assert_allclose(top2[:8], top1[:8] ** 2, rtol=1e-6)


def res_contact_loss(model, z, w) -> float:
    mesh = next(lk for lk in model.links if isinstance(lk, GearMeshLink))
    sl = model.receptance.slices[model.links.index(mesh)]
    return mesh.metrics(z[sl], w)["contact_loss_fraction [-]"]


def test_period_two_model_is_the_model_at_even_harmonics():
    """With an unbalance on the gear blank the base is the shaft speed (the mesh at its
    25th harmonic, the unbalance at the 1st): on the period-2 model, at half the base,
    harmonic 2k of κ and of the forcing (LSTE through the mesh damping, unbalance, static
    loads) equals harmonic k of the model's (both are Z(kω) at the same shaft speed:
    measured equal to the last bit, the halving of ω and the doubling of k being exact in
    binary; the tolerance 1e-7 is the pole-residue forms' own check, 1e-8), and every odd
    harmonic is unforced."""
    text = MODEL + "\n[[unbalance]]\nshaft = 1\nnode = 1\namount = 1.0e-4\nphase = 0.3\n"
    model = build_link_model(model_from_dict(tomllib.loads(text)))
    assert model.receptance.plan.speed_per_base == 1.0 and model.top_order == 25
    two = period_model(model, 2)
    assert two.receptance.plan.speed_per_base == 2.0 and two.top_order == 50
    w, Hk = 2 * np.pi * 200.0, 50  # two mesh harmonics and the sidebands between them
    k1, f1 = model.receptance.terms(w, Hk)
    k2, f2 = two.receptance.terms(w / 2, 2 * Hk)
    np.testing.assert_allclose(k2[::2], k1, rtol=1e-7, atol=1e-7 * np.max(np.abs(k1)))
    np.testing.assert_allclose(f2[::2], f1, rtol=1e-7, atol=1e-7 * np.max(np.abs(f1)))
    assert np.max(np.abs(f2[1::2])) <= 1e-12 * np.max(np.abs(f1))
    assert np.max(np.abs(f1[1])) > 0 and np.max(np.abs(f1[25])) > 0  # unbalance, mesh


def test_subharmonic_plan_and_links():
    """The plan of base ω/2 doubles every order; a mesh link moved onto it is the link
    built at twice the order (its LSTE harmonic k at 2k); a clearance does not change."""
    s = system()
    plan = FrequencyPlan.for_system(s)
    half = plan.subharmonic(2)
    assert half.speed(1.0) == 2 * plan.speed(1.0) and half.order(25.0) == 2 * plan.order(25.0) == 2
    mesh = GearMeshLink.from_system(s, 0, order=1)
    moved = mesh.subharmonic(2)
    again = GearMeshLink.from_system(s, 0, order=2)
    assert moved.order == 2
    np.testing.assert_array_equal(moved.mesh.lste, again.mesh.lste)
    assert s.bearing_clearances[0].subharmonic(2) is s.bearing_clearances[0]
    with pytest.raises(ModelError, match="period"):
        plan.subharmonic(0)
    model = build_link_model(s)
    with pytest.raises(ModelError, match="period"):
        link_sweep(model, [1000.0], H=3, period=2, stability=False)
    with pytest.raises(ModelError, match="period"):
        link_sweep(model, [1000.0], H=3, period=3)


@pytest.mark.slow  # the fixture: sweeps up and down with their period-2 branches, about 8 s
def test_sweeps_land_on_the_stable_period_two_branch(swept):
    """Up and down, the sweep answers with period 1 below 5525 Hz and with the stable
    period-2 orbit from there to 6425 Hz, where period 1 is flip-unstable; both directions
    find the same period-2 orbit (amplitudes, which do not depend on the half-cycle
    shift), and the table has the one-mesh path's columns."""
    model, res = swept
    r, df = res.result, res.to_frame()
    assert r.converged.all() and not r.no_stable.any() and r.stable.all()
    one = link_sweep(model, 2 * np.pi * GRID, H=H, directions="up", period=1).result
    for d in ("up", "down"):
        part = df[df["direction"] == d].sort_values("base_frequency [Hz]")
        expected = np.where(GRID >= BRANCH[0], 2, 1)
        np.testing.assert_array_equal(part["period"].to_numpy(dtype=int), expected)
        assert (part.loc[part["period"] == 2, "response"] == "period 2").all()
        assert (part.loc[part["period"] == 2, "subharmonic_amplitude [um]"] > 1.0).all()
        assert (part.loc[part["period"] == 1, "subharmonic_amplitude [um]"] == 0).all()
        assert part["mesh0.dte_rms [um]"].notna().all() and part["B1.force_max [N]"].notna().all()
    assert (df["B1.contact_fraction [-]"] == 1).all()  # the journal on its clearance throughout
    assert df.loc[df["period"] == 2, "harmonic_error [-]"].le(1e-3).all()
    # where period 2 is reported, the period-1 orbit is flip-unstable
    flip = (one.dominant_multiplier.real < -1) & (np.abs(one.dominant_multiplier.imag) < 1e-9)
    np.testing.assert_array_equal(flip, GRID >= BRANCH[0])
    sl = model.receptance.slices[[lk.name for lk in model.links].index("mesh0")]
    up, down = (r.direction == "up"), (r.direction == "down")
    a_up = np.array([amplitudes(z[sl])[0][:2] for z in r.harmonics[up]])
    a_down = np.array([amplitudes(z[sl])[0][:2] for z in r.harmonics[down]])[::-1]
    np.testing.assert_allclose(a_down, a_up, rtol=1e-6)
    kinds = [(t.direction, t.kind) for t in transitions(r)]
    assert kinds == [("up", "period doubling"), ("down", "period-2 branch ends")]


@pytest.mark.slow  # 19 integrations of 40 mesh periods, about 20 s
def test_period_two_branch_against_time_integration(swept):
    """The 19 period-2 points of the up sweep against the integration started on each
    with its ω/2 content cut by 5 % (module docstring): period 2 kept, settled, the ω/2
    and ω amplitudes of the mesh DTE within 1 %."""
    model, res = swept
    r = res.result
    two = period_model(model, 2)
    sl = model.receptance.slices[[lk.name for lk in model.links].index("mesh0")]
    rows = np.nonzero((r.direction == "up") & (r.period == 2))[0]
    np.testing.assert_allclose(r.omega[rows] / (2 * np.pi), BRANCH, rtol=1e-12)
    assert len(rows) >= 15
    odd = np.tile(subharmonic_mask(r.H_stored, 2), (r.harmonics.shape[1], 1))
    worst, drift = 0.0, 0.0
    for i in rows:
        w, z = float(r.omega[i]) / 2, r.harmonics[i]
        start = start_from_harmonics(two, w, r.H_stored, np.where(odd, 0.95 * z, z))  # ω/2 content -5 %
        tr = link_time_response(
            two, w, state0=start, steps_per_period=STEPS, tol=0, max_periods=CYCLES, min_periods=CYCLES
        )
        d = tr.y[sl][0]
        a_td = amplitudes(analyse(d, 2))[:2]  # |δ| at ω/2 and ω
        a_hb = amplitudes(z[sl])[0][:2]
        err = float(np.max(np.abs(a_td / a_hb - 1)))
        print(f"{r.omega[i] / (2 * np.pi):.0f} Hz: HB {a_hb * 1e6} um, TD {a_td * 1e6} um, {err:.1e}")
        assert half_difference(d) > 1e-2  # still period 2
        worst, drift = max(worst, err), max(drift, tr.difference)
    print(f"period-2 branch: {len(rows)} points, worst {worst:.2e}, largest period change {drift:.1e}")
    assert worst < 1e-2
    assert drift < 5e-3  # settled: the perturbation has died away


@pytest.mark.slow  # a time-domain sweep of 4 frequencies, about 10 s
def test_doubling_where_time_integration_doubles(swept):
    """The time-domain up sweep across the doubling (module docstring) doubles in the grid
    interval where the harmonic balance does."""
    model, res = swept
    r = res.result
    two = period_model(model, 2)
    sl = model.receptance.slices[[lk.name for lk in model.links].index("mesh0")]
    up = np.nonzero(r.direction == "up")[0]
    i_hb = int(np.argmax(r.period[up] == 2))  # the first period-2 point of the up sweep
    first = up[i_hb - 2]  # two grid steps below the doubling: period 1, spread onto ω/2
    hz = GRID[i_hb - 2 : i_hb + 2]
    assert r.period[first] == r.period[up][i_hb - 1] == 1
    z = r.harmonics[first]
    seed = np.zeros_like(z)
    seed[:, 1] = 1e-2 * float(np.max(amplitudes(z)))  # 1 % at ω/2
    state = start_from_harmonics(two, float(r.omega[first]) / 2, r.H_stored, z + seed)
    kinds = []
    for f in hz:
        tr = link_time_response(
            two, np.pi * f, state0=state, steps_per_period=512, tol=1e-5, max_periods=400, min_periods=10
        )
        state, h = tr.state, half_difference(tr.y[sl][0])
        print(f"{f:.0f} Hz: {tr.periods} cycles, converged {tr.converged}, half-cycle difference {h:.1e}")
        assert tr.converged
        kinds.append(2 if h > 1e-2 else (1 if h < 1e-4 else 0))
    # time integration doubles in the same grid interval as HB (GRID[i_hb - 1], GRID[i_hb]):
    # stricter than the one grid step of the acceptance
    assert kinds == [1, 1, 2, 2], (kinds, GRID[i_hb])


def test_cli_link_sweep_period_auto(tmp_path, capsys):
    """``nlgrd sweep --period auto`` on the link model: the one-mesh path's columns
    (period, ω/2 content, secondary frequency, instability), period 1 at 5475 Hz and the
    stable period-2 orbit at 5525 and 5575 Hz, the doubling in the summary; with
    ``--period 1`` the same points have no stable response and a real multiplier < -1."""
    path = tmp_path / "drive.toml"
    path.write_text(MODEL)
    out = tmp_path / "sweep.csv"
    argv = ["sweep", str(path), "--hz", "5475:5575:3", "--direction", "up", "--harmonics", "9"]
    assert main([*argv, "--out", str(out), "--quantity", "mesh0.dte_rms"]) == 0
    text = capsys.readouterr().out
    assert "period 2 (period doubled) at Hz: 5525.0, 5575.0" in text
    assert "period doubling (up): 5475.0 -> 5525.0 Hz, periodic -> period 2" in text
    df = pd.read_csv(out)
    columns = ("period", "response", "subharmonic_amplitude [um]", "secondary_frequency [Hz]", "instability")
    for col in columns:
        assert col in df.columns, col
    assert list(df["period"]) == [1, 2, 2] and list(df["response"]) == ["periodic", "period 2", "period 2"]
    assert df["stable"].all() and (df["subharmonic_amplitude [um]"].iloc[1:] > 1.0).all()
    assert df["mesh0.dte_rms [um]"].notna().all()
    assert main([*argv, "--out", str(out), "--period", "1"]) == 0
    capsys.readouterr()
    df = pd.read_csv(out)
    assert list(df["response"].iloc[1:]) == [NO_STABLE] * 2
    assert list(df["instability"].iloc[1:]) == ["real < -1"] * 2
    assert df["mesh0.dte_rms [um]"].iloc[1:].isna().all()
