"""The link integrator's one-mesh fast path against the single-mesh loop it replaces
(issue 33 item 6): ``nlgrd.timedomain.integrator.integrate_fe`` (old) and
``nlgrd.timedomain.geared.integrate_fe`` (``LinkIntegrator.of_mesh``) on the same problems,
fixed numbers of periods from the same start, every output sample compared.

Both evaluate the same HHT-α recurrence with the same closed-form mesh step; they differ
only in the order of floating-point operations (the forcing sum, e(θ) by a direct sum
instead of an FFT). The issue's figure: 1e-12 relative to each output's largest value.
"""

from __future__ import annotations

import dataclasses as dc
import time
from pathlib import Path

import numpy as np
import pytest
from test_geared_time_domain import refined_kubo

import nlgrd.timedomain.integrator as old_mod
import nlgrd.timedomain.links as links_mod
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.laws.force_laws import ParametricMesh
from nlgrd.nonlinear.models.geared import build_geared_model
from nlgrd.nonlinear.models.sdof import SDOFGearPair
from nlgrd.timedomain.geared import integrate_fe as new_fe

ROOT = Path(__file__).resolve().parent.parent
LSTE = np.array([0.0, 1.24e-6, 0.0, 0.50e-6, 0.30e-6, 0.10e-6, -0.05e-6])


def sdof_problem(parametric=False, backlash=50e-6, load=2295.0):
    sd = SDOFGearPair(0.261, 0.2587e9, backlash, load, LSTE, damping_ratio=0.02)
    mesh = sd.mesh()
    if parametric:
        rho = np.array([1.0, 0.2, 0.05, 0.03, 0.0])
        mesh = ParametricMesh(
            **{f.name: getattr(mesh, f.name) for f in dc.fields(mesh)}, stiffness_variation=rho
        )
    M, D, K = np.array([[sd.mass]]), np.array([[sd.mesh_damping]]), np.zeros((1, 1))
    return (M, D, K, np.ones(1), mesh, np.array([sd.static_load])), sd.natural_frequency


def fe_problem(system, hz):
    w = 2 * np.pi * hz
    model = build_geared_model(system, w, H=9)
    lm, rec = model.receptance.model, model.receptance
    speed = rec.speed(w)
    return (lm.M, lm.damping(speed), lm.stiffness(speed), rec.W[:, 0], model.mesh, rec.static_force), w


def problems():
    sd, wn = sdof_problem()
    sdp, _ = sdof_problem(parametric=True)
    back, _ = sdof_problem(backlash=5e-6, load=300.0)
    two = load_model(ROOT / "data" / "models" / "two_shaft.toml")
    return {
        "sdof Kubo-like, contact loss": (sd, 1.0 * wn, 512, 40),
        "sdof back-side contact": (back, 1.0 * wn, 512, 40),
        "sdof parametric stiffness": (sdp, 0.95 * wn, 512, 40),
        "two_shaft.toml FE": fe_problem(two, 1500.0) + (512, 20),
        "Kubo FE 4300 Hz, contact loss": fe_problem(refined_kubo(), 4300.0) + (512, 20),
    }


def _rel(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / (np.max(np.abs(np.asarray(b))) + 1e-300))


def _compare(args, w, steps, periods, **kw):
    opts = dict(steps_per_period=steps, tol=0.0, max_periods=periods, min_periods=periods, **kw)
    t0 = time.perf_counter()
    a = old_mod.integrate_fe(*args, w, **opts)
    t1 = time.perf_counter()
    b = new_fe(*args, w, **opts)
    t2 = time.perf_counter()
    assert a.periods == b.periods == periods
    h, g = a.history, b.history
    worst = {
        "delta": _rel(g.delta, h.delta),
        "delta_dot": _rel(g.delta_dot, h.delta_dot),
        "force": _rel(g.force, h.force),
        "q": _rel(b.q, a.q),
        "state": max(_rel(x, y) for x, y in zip(b.state, a.state, strict=True)),
        "poincare": _rel(b.poincare, a.poincare),
        "difference": abs(b.difference / a.difference - 1),
    }
    return worst, t1 - t0, t2 - t1, h


@pytest.mark.parametrize("case", list(problems()))
@pytest.mark.parametrize("stepped", [False, True])
def test_new_path_equals_old_loop(case, stepped, monkeypatch):
    """Every sample of δ, δ', W, q, the end state and the Poincaré section to 1e-12
    relative (the period map, and with ``MAX_STATE`` = 0 the step-by-step form of both)."""
    args, w, steps, periods = problems()[case]
    if stepped:
        monkeypatch.setattr(old_mod, "MAX_STATE", 0)
        monkeypatch.setattr(links_mod, "MAX_STATE", 0)
        periods = min(periods, 6)
    worst, t_old, t_new, h = _compare(args, w, steps, periods)
    sep = np.mean(np.abs(h.delta - h.lste) < args[4].half_backlash)
    print(f"\n{case} ({'stepped' if stepped else 'period map'}): old {t_old:.3f} s, new {t_new:.3f} s, "
          f"separated {sep:.2f}, " + ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))  # fmt: skip
    assert max(worst.values()) < 1e-12, worst


def test_converged_runs_agree():
    """To steady state with the default criterion: the same periods and samples."""
    args, w, steps, _ = problems()["sdof Kubo-like, contact loss"]
    a = old_mod.integrate_fe(*args, w, steps_per_period=steps, tol=1e-8)
    b = new_fe(*args, w, steps_per_period=steps, tol=1e-8)
    assert a.converged and b.converged and a.periods == b.periods
    print(f"\nconverged after {a.periods} periods: delta {_rel(b.history.delta, a.history.delta):.1e}")
    assert _rel(b.history.delta, a.history.delta) < 1e-12 and _rel(b.history.force, a.history.force) < 1e-12
