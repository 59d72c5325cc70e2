"""Orbits no sweep reaches: an isolated period-3 branch of the single-DOF gear pair
(issue 12, item 2: the search for isolated branches from perturbed or time-integrated starts).

Model: m = 0.1 kg, k_h = 1e8 N/m (ω_n = 31.6 krad/s), half backlash 50 µm, static load
k_h x 10 µm, LSTE 30 µm cos θ, ζ = 0.01. At 2.3-2.7 ω_n its mesh-periodic orbit is stable
(largest multiplier 0.98, a complex pair: no period doubling), so a sweep, with
``period="auto"`` too, stays on it. Beside it lives a stable period-3 orbit (the 1/3
subharmonic resonance of an impact oscillator, ω/3 near ω_n: Shaw & Holmes 1983, J. Sound
Vib. 90:129; Kahraman & Singh 1990, J. Sound Vib. 142:49), born with an unstable twin in a
saddle-node: a branch connected to period 1 by no bifurcation.

Independent reference: time integration of the same equation
(:func:`nlgrd.timedomain.sdof.integrate`, event-located contact changes, DOP853 at rtol
1e-10) over cycles of three mesh periods. From random initial states it settles on the
period-3 orbit (Poincaré sampling: δ(t + T) and δ(t) differ by more than 1e-3 of the range,
δ(t + 3T) = δ(t)); from the static state on the mesh-periodic one. Started on the harmonic
balance's orbits along the branch it stays on them; the amplitudes of the ω/3 and ω
components agree within 1 % (the issue's tolerance; measured about 1e-6: H = 27 of the base
and the integrator's tolerance).
"""

from __future__ import annotations

import numpy as np
import pytest

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import differentiate, evaluate
from nlgrd.nonlinear.fourier.periods import amplitudes
from nlgrd.nonlinear.models.sdof import SDOFGearPair
from nlgrd.nonlinear.tracing.orbit_search import follow_orbit, same_motion, search_orbits, shifted
from nlgrd.nonlinear.tracing.sweep import sweep
from nlgrd.timedomain.sdof import integrate

K, M, B = 1e8, 0.1, 50e-6
WN = np.sqrt(K / M)
PAIR = SDOFGearPair(M, K, B, K * 10e-6, np.array([0.0, 30e-6, 0.0]), 0.01)
W0 = 2.6 * WN
GRID = WN * np.round(np.arange(2.3, 2.705, 0.02), 2)
H = 9


def model_of(nu):
    return PAIR.subharmonic(nu).reduced_model()


@pytest.fixture(scope="module")
def found():
    return search_orbits(model_of, W0, H, (1, 2, 3))


def test_search_finds_the_coexisting_orbits(found):
    """At 2.6 ω_n: the stable mesh-periodic orbit (the one the sweep gives), a stable
    period-3 orbit a hundred times larger and its unstable twin (a real multiplier > 1:
    the saddle of the saddle-node), each once although several starts reach them."""
    kinds = [(o.period, o.stable) for o in found]
    assert kinds == [(1, True), (3, False), (3, True)] or kinds == [(1, True), (3, True), (3, False)]
    p1 = sweep(PAIR.reduced_model(), GRID, H, "up", jump="auto")
    assert p1.converged.all() and p1.stable.all()  # no flip, no fold: nothing leads off period 1
    i = int(np.argmin(np.abs(GRID - W0)))
    np.testing.assert_allclose(
        found[0].harmonics, p1.harmonics[i], rtol=0, atol=1e-9 * np.abs(p1.harmonics[i]).max()
    )
    saddle = next(o for o in found if o.period == 3 and not o.stable)
    assert abs(saddle.dominant_multiplier.imag) < 1e-9 and saddle.dominant_multiplier.real > 1
    stable3 = next(o for o in found if o.period == 3 and o.stable)
    assert stable3.amplitude > 50 * found[0].amplitude
    assert not any(o.period == 2 for o in found)


def mesh_harmonics(z):
    """Harmonics of ω of a mesh-periodic signal given in harmonics of ω/3 (base harmonic 3k)."""
    k = 3 * np.arange(1, H + 1)
    return np.concatenate([[z[0]], np.column_stack([z[2 * k - 1], z[2 * k]]).reshape(-1)])


#: Initial states [δ µm, δ'/ω_n µm] (drawn uniformly from ±300 µm): the first two settle on
#: the period-3 orbit, the third on the mesh-periodic one (3 of 12 such draws reach period 3).
STATES = ((-12.57, -204.16), (140.75, -231.80), (-248.61, -157.91))


@pytest.mark.slow
def test_time_integration_from_arbitrary_states_settles_on_the_found_orbits(found):
    """From two initial states time integration settles on a period-3 cycle, from a third
    on a mesh-periodic one (Poincaré: max |δ(t + T) - δ(t)| over the last 3T against the
    range; 768 samples per 3T, so that T is whole samples). As user starts of the search
    the cycles give the orbits the perturbed starts found: the same motion up to a shift by
    whole mesh periods."""
    p3 = PAIR.subharmonic(3)
    by_period = {1: [], 3: []}
    for d0, v0 in STATES:
        tr = integrate(
            p3, W0 / 3, [d0 * 1e-6, v0 * 1e-6 * WN], tol=1e-8, max_periods=600, samples_per_period=768
        )
        d = tr.history.delta
        jump = np.max(np.abs(d[256:] - d[:-256])) / np.ptp(d)
        assert tr.converged and (jump > 1e-3 or jump < 1e-6)  # a clear period 3 or 1
        by_period[3 if jump > 1e-3 else 1].append(tr.harmonics(3 * H))
    assert len(by_period[3]) == 2 and len(by_period[1]) == 1
    starts = [(3, z) for z in by_period[3]] + [(1, mesh_harmonics(z)) for z in by_period[1]]
    mine = search_orbits(model_of, W0, H, (1, 3), starts=starts, n_starts=0)
    assert [(o.period, o.stable, o.start) for o in mine] == [
        (1, True, "user start 2"),
        (3, True, "user start 0"),
    ]
    for o in mine:
        ref = next(f for f in found if f.period == o.period and f.stable)
        assert same_motion(o.harmonics, ref.harmonics, o.period)


@pytest.mark.slow
def test_followed_branch_against_time_integration(found):
    """The period-3 branch followed over 2.3-2.7 ω_n: stable throughout, it folds just
    above 2.70 ω_n (Newton from 2.70 finds nothing at 2.72 and beyond); at every other
    grid point (11 frequencies) time integration started on the HB orbit stays on it, its
    ω/3 and ω components within 1 %."""
    stable3 = next(o for o in found if o.period == 3 and o.stable)
    br = follow_orbit(model_of, stable3, np.append(GRID, 2.72 * WN), H)
    on = br.converged & (br.omega <= GRID[-1] * (1 + 1e-12))
    assert on.sum() == len(GRID) + 1  # W0 in both directions
    assert br.stable[on].all() and not br.converged[br.omega > GRID[-1] * 1.001].any()
    assert (br.period == 3).all() and (br.subharmonic_amplitude[on] > 0.5 * stable3.amplitude).all()
    assert set(br.to_frame()["response"].dropna()) == {"period 3"}
    worst = 0.0
    p3 = PAIR.subharmonic(3)
    for i in np.nonzero(on & (br.direction == "down"))[0][::2]:
        z, w = br.harmonics[i][0], br.omega[i]
        t0 = np.array([0.0])
        state = [evaluate(z, t0)[0], evaluate(differentiate(z), t0)[0] * w / 3]
        tr = integrate(p3, w / 3, state, tol=1e-9, max_periods=600)
        a_hb, a_td = amplitudes(z), amplitudes(tr.harmonics(3 * H))
        assert tr.converged
        worst = max(worst, *(abs(a_td[j] - a_hb[j]) / a_hb[j] for j in (0, 2)))
    print(f"period-3 branch vs time integration: worst amplitude difference {worst:.1e}")
    assert worst < 0.01


def test_shift_by_a_mesh_period_is_the_same_motion():
    """shifted(z, ν, s) is x(t + sT), T = 2π/ω the mesh period: checked by evaluating z at
    shifted times (harmonics of the base ω/ν, so the shift is 2π s/ν in base phase)."""
    rng = np.random.default_rng(0)
    z = rng.normal(size=13)
    t = np.linspace(0, 2 * np.pi, 17)
    for s in range(3):
        np.testing.assert_allclose(
            evaluate(shifted(z, 3, s), t), evaluate(z, t + 2 * np.pi * s / 3), atol=1e-12
        )
    assert same_motion(z[None], shifted(z, 3, 2)[None], 3)
    assert not same_motion(z[None], shifted(z, 3, 1)[None] * 1.01, 3)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(periods=(0,)), "periods"),
        (dict(periods=(1.5,)), "periods"),
        (dict(periods=()), "periods"),
        (dict(n_starts=-1), "n_starts"),
        (dict(periods=(1,), starts=[(2, np.zeros((1, 5)))]), "starts"),
    ],
)
def test_bad_search_input_names_the_field(kwargs, field):
    with pytest.raises(ModelError, match=field):
        search_orbits(model_of, W0, H, **kwargs)


def test_search_on_two_nonlinear_coordinates_and_with_user_starts_only():
    """The search on a model with two nonlinear coordinates (it raised ValueError on the
    linear response's flat harmonics) and with ``n_starts=0`` (only the user's starts):
    tests/test_period_doubling.py's two-DOF oscillator with its stop on the second mass,
    both masses nonlinear coordinates, a second stop on the first one far beyond its
    motion (1 mm gap). At 0.9 x the first in-contact natural frequency the period-1 orbit
    found from perturbed starts is the one a sweep to that frequency reaches (the same
    Newton solution to 1e-7 relative; both are converged to 1e-10 of the residual), and
    with no perturbed starts the user's start alone gives it again."""
    from test_period_doubling import K2, KC, LOAD, M2, SEAT, two_dof

    from nlgrd.nonlinear.fourier.periods import spread
    from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
    from nlgrd.nonlinear.laws.force_laws import ContactStop

    D, wn = two_dof()

    def model_of(nu: int) -> ReducedModel:
        stops = (
            ContactStop(KC, 0.0, spread(np.array([0.0, SEAT, 0.0]), nu), coord=1),
            ContactStop(KC, 1e-3, np.zeros(1), coord=0),
        )
        return ReducedModel.from_matrices(M2, D, K2, np.eye(2), LOAD, stops, metrics=None)

    w = 0.9 * wn
    ref = sweep(model_of(1), np.linspace(0.5 * wn, w, 9), 9, "up")
    assert ref.converged[-1] and ref.stable[-1]
    found = search_orbits(model_of, w, 9, periods=(1,), n_starts=6)
    assert len(found) == 1 and found[0].harmonics.shape == (2, 19)
    np.testing.assert_allclose(found[0].harmonics, ref.harmonics[-1], rtol=1e-7, atol=1e-7 * SEAT)
    again = search_orbits(model_of, w, 9, periods=(1,), n_starts=0, starts=[(1, ref.harmonics[-1])])
    assert len(again) == 1 and again[0].start == "user start 0"
    assert search_orbits(model_of, w, 9, periods=(1,), n_starts=0) == []


def test_search_finds_the_period_two_orbit_from_the_flip():
    """The single-DOF pair of tests/test_period_doubling.py (LSTE 10 µm, ζ 0.03) at 1.30 ω_n:
    its period-1 orbit is flip-unstable (real multiplier -1.32) and a stable period-2 orbit
    lives beside it. With no perturbed starts (``n_starts=0``) and the linear response as
    the one user start of period 1, the search finds the period-1 orbit and, from its
    critical Floquet mode, the period-2 orbit; without ``stability`` there are no
    multipliers, so no flip, and period 1 alone; with period 2 alone sought, from the
    linear response spread onto ω/2, the period-1 orbit Newton reaches there is flipped
    too. Reference: time integration from the static
    state (:func:`nlgrd.timedomain.sdof.integrate`, DOP853 at rtol 1e-10, steady to 1e-8
    per cycle of two mesh periods) settles on the same orbit: all 37 harmonics of ω/2
    within 1e-4 of their norm for one of the two shifts by a mesh period (measured 6e-7;
    1e-4 is the worst amplitude difference along this period-2 branch in
    tests/test_period_doubling.py, from H = 18 of the base and the integrator), the other
    shift 0.4 off."""
    from test_period_doubling import PAIR as FLIP_PAIR
    from test_period_doubling import WN as FLIP_WN

    from nlgrd.nonlinear.fourier.periods import spread

    def flip_model(nu):
        return FLIP_PAIR.subharmonic(nu).reduced_model()

    w = 1.30 * FLIP_WN
    z_lin = flip_model(1).at(w, 9).linear_solution().reshape(1, -1)
    found = search_orbits(flip_model, w, 9, (1, 2), n_starts=0, starts=[(1, z_lin)])
    # the critical mode's sign is LAPACK's: the first size that reaches period 2 is 0.2 of
    # the orbit, on the + or - side
    assert [(o.period, o.stable, o.start.replace("-0.2", "+0.2")) for o in found] == [
        (1, False, "user start 0"),
        (2, True, "flip of the period-1 orbit from user start 0, start +0.2 x its size"),
    ]
    mu = found[0].dominant_multiplier
    assert abs(mu.imag) < 1e-9 and mu.real < -1.3
    tr = integrate(FLIP_PAIR.subharmonic(2), w / 2, None, tol=1e-8, max_periods=600)
    td = tr.harmonics(18)
    off = [np.linalg.norm(shifted(found[1].harmonics[0], 2, s) - td) / np.linalg.norm(td) for s in (0, 1)]
    assert tr.converged and min(off) < 1e-4 < 0.1 < max(off), off
    no_flip = search_orbits(flip_model, w, 9, (1, 2), n_starts=0, starts=[(1, z_lin)], stability=False)
    assert [(o.period, o.start) for o in no_flip] == [(1, "user start 0")]
    # period 1 not sought: the period-1 orbit Newton reaches on the period-2 model is listed
    # as period 1 and flipped as well
    alone = search_orbits(flip_model, w, 9, (2,), n_starts=0, starts=[(2, spread(z_lin, 2))])
    assert [(o.period, o.start.split(",")[0]) for o in alone] == [
        (1, "user start 0"),
        (2, "flip of the period-1 orbit from user start 0"),
    ]
    assert same_motion(alone[1].harmonics, found[1].harmonics, 2)
