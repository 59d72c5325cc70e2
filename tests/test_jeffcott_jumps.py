"""Jump speeds of a Jeffcott rotor with a bearing clearance (issue 11, item 4): the
harmonic-balance sweep's jumps up and down against a quasi-static time-integration sweep.

The rotor: a steel shaft (0.6 m, 40 mm, four Timoshenko elements) with a central disk
(200 mm x 30 mm), a stiff bearing at one end and, at the other, a soft centring spring
with a damper in parallel with a radial clearance of 30 µm beyond which a Hertzian
contact acts: the model of a rotor in a bearing clearance with an elastic support of
Ehrich 1988 (J. Vib. Acoust. 110:9), with the Hertz law of rolling-element contact
(Villa, Sinou & Thouverez 2007, J. Braz. Soc. Mech. Sci. Eng. 29:14, who solve a rotor
with bearing clearance and Hertz contact by harmonic balance and check it by time
integration). Unbalance at the disk; the base frequency is the shaft speed.

Free of the clearance the rotor's first forward whirl is at 35 Hz (damping ratio 0.2);
once the journal rides on the contact its stiffness grows with the penetration and the
resonance bends to higher speeds: a hardening curve. A run-up stays on the upper
(contact) branch to 73.45 Hz, where it folds and the response drops onto the
lower branch (journal inside or just grazing the clearance); a run-down stays on the
lower branch until the journal grazes the clearance at 53.05 Hz and jumps up onto the
contact branch. Between the two the response is two-valued, both branches stable (no
torus, no period doubling: the rotor is isotropic and whirls on a circle). Floquet: the
largest lateral multiplier is 0.92 (real) on the contact branch 0.2 Hz below its fold
(0.81 a step before), 0.48 on the lower branch 0.2 Hz above its end (the Hertz tangent
grows as the square root of the penetration, so the grazing orbit folds abruptly). The
axial and torsional degrees of freedom are undamped and keep 18 multipliers on the unit
circle (|μ| - 1 ~ 5e-14, within the sweep's stability margin of 1e-6).

What is compared with what: the speeds of the two jumps of the harmonic-balance sweep
(:func:`link_sweep`, default jump handling) on a uniform grid against those of an HHT-α
integration of the same FE equations swept quasi-statically over the same grid (each
speed started from the state at the end of the one before), and the disk orbit
amplitude of the two on both branches.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from nlgrd.nonlinear.fourier.harmonics import sample
from nlgrd.nonlinear.links.contract import BearingClearance
from nlgrd.nonlinear.models.link_model import Unbalance, build_link_model, link_sweep
from nlgrd.nonlinear.results.sweep_results import find_jumps
from nlgrd.rotor.bearing import Bearing
from nlgrd.rotor.disk import Disk
from nlgrd.rotor.materials import Material
from nlgrd.rotor.shaft import Shaft, ShaftElement
from nlgrd.rotor.system import RotorSystem

STEEL = Material("steel", density=7850.0, young_modulus=2.1e11, poisson_ratio=0.3)
DISK = Disk.from_dimensions(0, 2, outer_diameter=0.2, width=0.03)
#: centring spring [N/m] and damper [N s/m] of the clearance bearing: with the 40 mm shaft
#: (bending stiffness at the disk 48EI/L³ = 5.9e6 N/m) the support sets the first whirl,
#: 35 Hz with damping ratio 0.2, so the lower branch is well damped and settles fast.
K_SOFT, C_SOFT = 2e5, 400.0
#: radial clearance [m] and Hertzian contact stiffness [N/m^1.5]: the tangent
#: 1.5 k δ^0.5 is 1e6 N/m at a penetration of one clearance, five times the centring
#: spring and of the order of the shaft's; it hardens with the penetration, so the upper
#: branch bends far (to twice the free whirl speed) and folds at a finite amplitude.
CLEARANCE, K_HERTZ = 30e-6, 1.2e8
#: unbalance m e = disk mass x 20 µm: the free peak (37 Hz) would take the journal to
#: 1.6 clearances, and above the resonance the free journal orbit (26 µm at 70 Hz) stays
#: inside the clearance, so the lower branch exists next to the upper one.
ECCENTRICITY = 20e-6
H = 3
#: The speed grid [Hz]: 0.5 Hz steps, offset by a quarter step so that the two folds
#: (73.45 and 53.05 Hz, found with a 0.1 Hz sweep) lie 0.2 Hz from the nearest grid
#: speed, not on one: which grid speed is the last on a branch is then not decided by
#: rounding.
STEP_HZ = 0.5
SPEEDS_HZ = np.arange(30.25, 85.0, STEP_HZ)
#: The time-domain windows: start BACK steps before the harmonic balance's last point on
#: the branch followed, go at most AHEAD steps past its first point on the new branch,
#: and stop AFTER points past the time integration's own jump.
BACK, AHEAD, AFTER = 4, 4, 2


def jeffcott() -> RotorSystem:
    """The rotor with its linear bearings (the clearance is the link of :func:`jumps_model`)."""
    el = ShaftElement(0.6 / 4, 0.04, 0.0, STEEL)
    bearings = (
        Bearing(0, 0, kyy=1e7, kzz=1e7, cyy=300.0, czz=300.0, kxx=1e8),
        Bearing(0, 4, kyy=K_SOFT, kzz=K_SOFT, cyy=C_SOFT, czz=C_SOFT),
    )
    return RotorSystem((Shaft((el,) * 4),), disks=(DISK,), bearings=bearings)


def jumps_model():
    link = BearingClearance("B", 0, 4, clearance=CLEARANCE, stiffness=K_HERTZ, exponent=1.5)
    return build_link_model(jeffcott(), [link], unbalance=[Unbalance(0, 2, DISK.mass * ECCENTRICITY)])


def disk_dofs(system):
    d = system.dofs.node_dofs(0, 2)
    return [d[1], d[2]]


def disk_amplitude(model, omega, z) -> float:
    """Largest radius of the disk orbit [m] of the harmonic-balance point ``z`` at ``omega``."""
    G = model.reduced.at(omega, H).nonlinear_forces(z.ravel(), jacobian=False)[0].reshape(z.shape)
    q = sample(model.receptance.recover(omega, H, z, G, disk_dofs(model.system)), 512)
    return float(np.max(np.hypot(q[0], q[1])))


def single_jump(omegas, values, direction):
    """The one jump of a sweep in sweep order, as (index from, index to)."""
    jumps = find_jumps(omegas, values, direction)
    assert len(jumps) == 1, (direction, [(j.omega_from, j.omega_to) for j in jumps])
    (j,) = jumps
    return int(np.nonzero(omegas == j.omega_from)[0][0]), int(np.nonzero(omegas == j.omega_to)[0][0])


@pytest.fixture(scope="module")
def hb():
    """The harmonic-balance sweep up and down over SPEEDS_HZ: (model, sweep, per direction
    the speeds [Hz] and disk amplitudes [m] in sweep order and the jump's grid indices)."""
    t0 = time.process_time()
    model = jumps_model()
    sw = link_sweep(model, 2 * np.pi * SPEEDS_HZ, H=H, directions="both")
    res = sw.result
    journal = sw.links["B.displacement_max [m]"].to_numpy()
    out = {}
    for d in ("up", "down"):
        keep = res.direction == d
        w, z = res.omega[keep], res.harmonics[keep]
        amp = np.array([disk_amplitude(model, wi, zi) for wi, zi in zip(w, z, strict=True)])
        out[d] = dict(f=w / (2 * np.pi), amp=amp, z=z, jump=single_jump(w, journal[keep], d))
    print(f"\nharmonic balance, {res.omega.size} points: {time.process_time() - t0:.1f} s CPU")
    return model, sw, out


def test_harmonic_balance_hysteresis(hb):
    """The harmonic balance (H = 3) on the 0.5 Hz grid: every point converged and Floquet
    stable, none without a stable periodic response; one jump per direction (of the
    journal's largest displacement, :func:`find_jumps`), down from the contact branch on
    the way up, up onto it on the way down at a lower speed, more than 2 grid steps apart
    (42 measured: 73.75 and 52.75 Hz); the sweep flags both as branch switches
    (``result.jumps()``); the orbits are circles (mean, 2x and 3x below 1e-8 of the 1x harmonic: an isotropic
    rotor under unbalance, so the truncation to H = 3 costs nothing)."""
    _, sw, out = hb
    res = sw.result
    assert res.converged.all() and res.stable.all() and not res.no_stable.any()
    up, down = out["up"], out["down"]
    f_up = up["f"][up["jump"][1]]  # first speed off the contact branch, sweeping up
    f_down = down["f"][down["jump"][1]]  # first speed on it, sweeping down
    print(
        f"harmonic balance: sweeping up, jumps down {up['f'][up['jump'][0]]:.2f} -> {f_up:.2f} Hz; "
        f"sweeping down, jumps up {down['f'][down['jump'][0]]:.2f} -> {f_down:.2f} Hz"
    )
    assert up["amp"][up["jump"][0]] > 5 * up["amp"][up["jump"][1]]
    assert down["amp"][down["jump"][1]] > 2 * down["amp"][down["jump"][0]]
    assert f_up - f_down > 2 * STEP_HZ
    flagged = {(j.direction, round(j.omega_from / (2 * np.pi), 6)) for j in res.jumps()}
    assert flagged == {
        ("up", round(up["f"][up["jump"][0]], 6)),
        ("down", round(down["f"][down["jump"][0]], 6)),
    }
    z = res.harmonics
    first = np.max(np.abs(z[:, :, 1:3]))
    assert np.max(np.abs(z[:, :, [0, 3, 4, 5, 6]])) <= 1e-8 * first


def td_window(model, direction, branch, other):
    """Quasi-static time-integration sweep over the grid around the harmonic balance's
    jump in ``direction``: from the harmonic-balance orbit BACK steps before its last
    point on the branch, each speed started from the end state of the one before.

    Returns (speeds [Hz], disk amplitudes [m], converged, harmonic-balance amplitude of
    the nearer branch at each speed [m], index of the first speed past a step larger than
    half the harmonic balance's jump, or None)."""
    from nlgrd.timedomain.links import link_time_response, start_from_harmonics

    i_from, i_to = branch["jump"]
    start, stop = i_from - BACK, min(i_to + AHEAD, branch["f"].size - 1)
    assert start >= 0
    f_other = list(np.round(other["f"], 9))
    state = start_from_harmonics(model, 2 * np.pi * branch["f"][start], H, branch["z"][start])
    f, amp, conv, ref = [], [], [], []
    jumped_at = None
    hb_jump = abs(branch["amp"][i_from] - branch["amp"][i_to])
    for i in range(start, stop + 1):
        w = 2 * np.pi * branch["f"][i]
        tr = link_time_response(
            model, w, state0=state, steps_per_period=256, tol=1e-4, output_dofs=disk_dofs(model.system)
        )
        state = tr.state
        a = float(np.max(np.hypot(tr.q[0], tr.q[1])))
        # the harmonic-balance orbit of the branch the integration is on (nearer of the two)
        both = (branch["amp"][i], other["amp"][f_other.index(round(branch["f"][i], 9))])
        f.append(branch["f"][i])
        amp.append(a)
        conv.append(tr.converged)
        ref.append(min(both, key=lambda b: abs(b - a)))
        if jumped_at is None and len(amp) > 1 and abs(a - amp[-2]) > 0.5 * hb_jump:
            jumped_at = len(amp) - 1
        if jumped_at is not None and len(amp) - 1 - jumped_at >= AFTER:
            break
    return np.array(f), np.array(amp), np.array(conv), np.array(ref), jumped_at


@pytest.mark.slow
def test_jump_speeds_against_time_integration(hb):
    """The jump speeds of the harmonic-balance sweep within one grid step (0.5 Hz) of
    those of HHT-α time integration swept quasi-statically over the same grid, in both
    directions; the disk orbit amplitude of the two within 1 % at every speed of the
    windows, on both branches.

    The integration runs over a window of the grid from BACK = 4 steps before the
    harmonic balance's last point on the branch (started there from its orbit) to at most
    AHEAD = 4 steps past its jump, each speed from the previous one's end state (a slow
    run-up or run-down: the orbit is kept until it ceases to attract), so it is free to
    jump up to 4 steps earlier or later. A jump of the integration is a step between
    speeds larger than half the harmonic balance's jump there, and the test asks for one
    in each window (:func:`find_jumps` on the window agrees).

    Tolerances. One grid step: both methods can only place a jump between two grid
    speeds, and near a fold the integration may leave a branch whose basin of attraction
    has shrunk below the step's disturbance one step before its end (the folds lie 0.2
    Hz from a grid speed; measured: the same grid step both ways, 73.75 Hz up and 52.75
    Hz down). 1 %: the differences measured are 5.5e-4 at most (256 steps per period;
    1.4e-4 on most points, the HHT-α period error, which falls to ~5e-5 with 512 steps as
    (ω Δt)²; the larger ones, 4-5e-4 next to the folds, are the transient left by the
    1e-4 period-to-period criterion where the orbit attracts slowly, 3e-4 with 512
    steps); the truncation to H = 3 costs nothing (circular orbits,
    :func:`test_harmonic_balance_hysteresis`). CPU: 7 s for the 16 speeds."""
    model, _, out = hb
    t0 = time.process_time()
    worst, n_points, td_jump = 0.0, 0, {}
    for direction, other in (("up", "down"), ("down", "up")):
        branch = out[direction]
        f, amp, conv, ref, jumped_at = td_window(model, direction, branch, out[other])
        assert conv.all(), f[~conv]
        assert jumped_at is not None, (direction, f, amp)
        i_from, i_to = single_jump(2 * np.pi * f, amp, direction)
        assert i_to == jumped_at
        f_hb, f_td = branch["f"][branch["jump"][1]], f[i_to]
        err = np.abs(amp / ref - 1)
        worst, n_points = max(worst, float(err.max())), n_points + f.size
        td_jump[direction] = f_td
        print(
            f"{direction:>4}: harmonic balance jumps to {f_hb:.2f} Hz, time integration to {f_td:.2f} Hz "
            f"(window {f[0]:.2f} -> {f[-1]:.2f} Hz, {f.size} speeds, worst |HB/TD - 1| = {err.max():.1e})"
        )
        assert abs(f_td - f_hb) <= STEP_HZ * (1 + 1e-9)
        assert f[0] < f_hb - 2 * STEP_HZ if direction == "up" else f[0] > f_hb + 2 * STEP_HZ
        assert worst < 0.01
    assert td_jump["up"] - td_jump["down"] > 2 * STEP_HZ
    print(
        f"worst |HB/TD - 1| = {worst:.1e} at {n_points} speeds; "
        f"time integration {time.process_time() - t0:.1f} s CPU"
    )


@pytest.mark.slow
def test_linear_contact_sweep_lands_where_the_lower_branch_ends():
    """The same rotor with a linear contact law beyond the clearance (p = 1, 1e6 N/m, the
    Hertz tangent at one clearance of penetration): sweeping down, the lower branch ends
    where the journal grazes the clearance, a non-smooth end at which neither the
    arc-length continuation nor Newton restarts from the last orbit find the contact branch
    (before the second pass tried the up sweep's orbits there, 18 down points from 55.75 to
    47.25 Hz were left unsolved). Every point converges and is stable; the down sweep lands
    on the up sweep's orbit at the same speed (harmonics within 1e-8 of their largest: the
    same Newton solution); one jump per direction (``result.jumps()``). Independent check of one landed orbit:
    HHT-α integration of the FE model started on it keeps it (period-to-period change
    below 1e-4 and disk amplitude within 1 % of the harmonic balance's; the tolerance of
    the Hertz comparison above)."""
    from nlgrd.timedomain.links import link_time_response, start_from_harmonics

    link = BearingClearance("B", 0, 4, clearance=CLEARANCE, stiffness=1e6, exponent=1.0)
    model = build_link_model(jeffcott(), [link], unbalance=[Unbalance(0, 2, DISK.mass * ECCENTRICITY)])
    sw = link_sweep(model, 2 * np.pi * SPEEDS_HZ, H=H, directions="both")
    res = sw.result
    assert res.converged.all() and res.stable.all() and not res.no_stable.any()
    up, down = res.direction == "up", res.direction == "down"
    by_speed = {round(float(w), 9): z for w, z in zip(res.omega[up], res.harmonics[up], strict=True)}
    landed = [i for i in np.nonzero(down & res.branch_switch)[0]]
    assert landed, "the down sweep switches branch"
    scale = np.max(np.abs(res.harmonics))
    for i in landed:
        assert np.max(np.abs(res.harmonics[i] - by_speed[round(float(res.omega[i]), 9)])) <= 1e-8 * scale
    assert sorted(j.direction for j in res.jumps()) == ["down", "up"]
    i = landed[0]
    w, z = float(res.omega[i]), res.harmonics[i]
    state = start_from_harmonics(model, w, H, z)
    tr = link_time_response(
        model, w, state0=state, steps_per_period=256, tol=1e-4, output_dofs=disk_dofs(model.system)
    )
    a_td = float(np.max(np.hypot(tr.q[0], tr.q[1])))
    a_hb = disk_amplitude(model, w, z)
    print(
        f"linear contact: lands at {w / (2 * np.pi):.2f} Hz sweeping down; TD/HB - 1 = {a_td / a_hb - 1:.1e}"
    )
    assert tr.converged
    assert abs(a_td / a_hb - 1) <= 1e-2
