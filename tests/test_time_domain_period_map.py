"""The period map of the time integrators (nlgrd/timedomain/period_map.py) against their
step-by-step form.

The period map evaluates the same HHT-α recurrence in another order (the linear part of
a whole period precomputed, the link forces solved step by step), so it must give the
step-by-step histories to rounding. Reference: the same integrator with the period map
turned off (``MAX_STATE`` = 0: every step a sparse solve of all DOFs, the form the
time-domain tests were validated with). Fixed numbers of periods from the same start, in
regimes with contact loss at the mesh and with the journal on a Hertzian clearance, so
that every branch of the link laws is taken. Tolerance 1e-8 relative: over 30 periods
of ~500 steps the two orders of summation differ by rounding amplified by the lightly
damped modes (1e-11 seen on the link coordinates, 2.4e-8 on the angles of the free
rotation, which no damping bounds); a wrong kernel or forcing term differs at O(1).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_bearing_clearance import clearance_model, disk_dofs
from test_geared_time_domain import refined_kubo

import nlgrd.timedomain.links as td_links
from nlgrd.nonlinear.fourier.harmonics import differentiate, sample
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.timedomain.links import LinkIntegrator, link_time_response, settle, start_from_harmonics


def _both(monkeypatch, module, run):
    fast = run()
    with monkeypatch.context() as m:
        m.setattr(module, "MAX_STATE", 0)
        slow = run()
    return fast, slow


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def fe_periods(model, w: float, periods: int):
    """``periods`` periods of the link model's FE matrices with its one mesh
    (:meth:`LinkIntegrator.of_mesh`) from the static solution of the nonlinear mesh
    (:func:`nlgrd.timedomain.integrator.static_solution`), the last one recorded on every
    DOF: (periods, last period difference, δ, mesh force, LSTE, q, end state)."""
    rec, mesh = model.receptance, model.links[0].mesh
    speed = rec.plan.speed(w)
    D = rec.model.damping(speed) + rec.C_link  # with c_m w wᵀ
    integ = LinkIntegrator.of_mesh(
        rec.model.M,
        D,
        rec.model.stiffness(speed),
        rec.P[:, 0],
        mesh,
        rec.static_force,
        w,
        steps_per_period=512,
    )
    run = settle(integ, integ.start(), tol=0.0, max_periods=periods, min_periods=periods)
    last = integ.record(run.start, np.arange(integ.N))
    ns, N = integ.ns, integ.N
    e, edot = sample(mesh.lste, ns), w * sample(differentiate(mesh.lste), ns)
    force = last.g[0] + mesh.damping * (last.ydot[0] - edot)
    state = (last.end[:N], last.end[N : 2 * N], last.end[2 * N : 3 * N])
    return run.periods, run.differences[-1], last.y[0], force, e, last.q, state


@pytest.mark.parametrize("hz", [4300.0, 2400.0])
def test_geared_fe_period_map_equals_the_steps(monkeypatch, hz):
    """Kubo's rig (144 DOFs) in the tooth-separation regime of the main resonance and at
    the superharmonic, 30 periods from the static state of the nonlinear mesh (from the
    linear static rest the 2400 Hz case has no contact loss in the 30th period)."""
    model = build_link_model(refined_kubo())
    w = 2 * np.pi * hz
    mesh = model.links[0].mesh
    fast, slow = _both(monkeypatch, td_links, lambda: fe_periods(model, w, 30))
    (pf, df, yf, ff, _, qf, sf), (ps, ds, ys, fs, es, qs, ss) = fast, slow
    assert pf == ps == 30
    separated = np.abs(ys - es) < mesh.half_backlash
    assert separated.mean() > (0.3 if hz == 4300.0 else 0.0)  # the teeth separate in the last period
    assert _rel(yf, ys) < 1e-8 and _rel(ff, fs) < 1e-8
    # the DOFs carry the train's free rotation (a multiplier 1 of the step map), which
    # keeps the rounding of 15 000 steps undamped: 2.4e-8 of the largest angle seen
    assert _rel(qf, qs) < 1e-7
    for a, b in zip(sf, ss, strict=True):
        assert _rel(a, b) < 1e-7
    assert abs(df / ds - 1) < 1e-5


def test_link_period_map_equals_the_steps(monkeypatch):
    """The Jeffcott rotor with a 30 µm radial clearance (two link coordinates, Newton on
    the Hertzian law) at 27 Hz, where the journal runs on the clearance; 20 periods from
    the harmonic-balance orbit."""
    model = clearance_model(30e-6)
    w = 2 * np.pi * np.array([25.0, 27.0])
    hb = link_sweep(model, w, H=7, directions="up").result
    z = hb.harmonics[-1]
    assert np.max(np.hypot(*z[:, 1:3].T)) > 0  # an orbit, not rest
    start = start_from_harmonics(model, w[-1], 7, z)
    dofs = disk_dofs(model.system)

    def run():
        return link_time_response(
            model, w[-1], state0=start, steps_per_period=256, tol=0.0, max_periods=20, min_periods=20,
            output_dofs=dofs,
        )  # fmt: skip

    fast, slow = _both(monkeypatch, td_links, run)
    r = np.hypot(slow.y[0], slow.y[1])
    assert r.max() > 30e-6  # on the clearance
    assert _rel(fast.y, slow.y) < 1e-8 and _rel(fast.q, slow.q) < 1e-8
    for a, b in zip(fast.state, slow.state, strict=True):
        assert _rel(a, b) < 1e-8
