"""The one-mesh closed-form step of :class:`nlgrd.timedomain.links.LinkIntegrator` against
the general link step it short-cuts.

Reference: the same integrator with the step solved by Newton on the link's own pointwise
law (:meth:`GearMeshLink.pointwise <nlgrd.nonlinear.links.contract.GearMeshLink.pointwise>`,
the dead zone written independently of the closed form), the path every other link takes.
Problems: the SDOF gear pair as a one-DOF FE model (Kubo-like: k_h = 0.2587 GN/m, 50 µm
backlash, an LSTE of three harmonics, ζ = 0.02) at resonance, where the teeth separate;
with 5 µm backlash and a light load (300 N), where they hit the back flanks; and with a varying
mesh stiffness ρ(θ) (a parametric mesh); 30 periods of 256 steps from the static state
(from the back flank at 0.8 ω_n, where the pair stays in back contact) on the period
map, 10 step by step (``MAX_STATE`` = 0).

Tolerance 1e-10 of the largest |δ| and |W|: Newton stops at a residual of 1e-13
relative, so the two differ by that at every step, and the lightly damped resonance
(ζ = 0.02: a perturbation decays by e over ~8 periods) carries a few hundred steps of it
(measured: at most 3.4e-13 on δ, 1.7e-12 on W); a wrong branch or constant in the
closed form differs at O(b).
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pytest

import nlgrd.timedomain.links as td_links
from nlgrd.nonlinear.laws.force_laws import ParametricMesh
from nlgrd.nonlinear.models.sdof import SDOFGearPair
from nlgrd.timedomain.links import LinkIntegrator, settle

LSTE = np.array([0.0, 1.24e-6, 0.0, 0.50e-6, 0.30e-6, 0.10e-6, -0.05e-6])


def _one_dof(backlash, load, parametric):
    sd = SDOFGearPair(0.261, 0.2587e9, backlash, load, LSTE, damping_ratio=0.02)
    mesh = sd.mesh()
    if parametric:
        fields = {f.name: getattr(mesh, f.name) for f in dc.fields(mesh)}
        mesh = ParametricMesh(**fields, stiffness_variation=np.array([1.0, 0.2, 0.05, 0.03, 0.0]))
    matrices = (np.array([[sd.mass]]), np.array([[sd.mesh_damping]]), np.zeros((1, 1)))
    return matrices + (np.ones(1), mesh, np.array([sd.static_load])), sd.natural_frequency


CASES = {  # backlash [m], load [N], parametric, ω/ω_n, start δ [m] (None: static)
    "contact loss": (50e-6, 2295.0, False, 1.0, None),
    "back-side contact": (5e-6, 300.0, False, 0.8, -30e-6),
    "parametric mesh": (50e-6, 2295.0, True, 0.6, None),
}


@pytest.mark.parametrize("stepped", [False, True])
@pytest.mark.parametrize("case", list(CASES))
def test_closed_form_step_equals_newton_on_the_pointwise_law(case, stepped, monkeypatch):
    """δ, the mesh force and the end state of both, the regime checked on the forces."""
    backlash, load, parametric, ratio, delta0 = CASES[case]
    state0 = None if delta0 is None else (np.array([delta0]), np.zeros(1))
    args, wn = _one_dof(backlash, load, parametric)
    if stepped:
        monkeypatch.setattr(td_links, "MAX_STATE", 0)
    runs, periods = [], 10 if stepped else 30
    for newton in (False, True):
        integ = LinkIntegrator.of_mesh(*args, ratio * wn, steps_per_period=256)
        assert (integ.pmap is None) == stepped
        if newton:
            integ._solve_link = integ._newton_link
        run = settle(integ, integ.start(state0), tol=0.0, max_periods=periods, min_periods=periods)
        runs.append(integ.record(run.start))
    fast, slow = runs
    g = slow.g[0]
    if case == "contact loss":
        assert np.mean(g == 0) > 0.1  # the teeth separate
    if case == "back-side contact":
        assert np.any(g < 0)  # back flanks in contact
    dy = np.max(np.abs(fast.y - slow.y)) / np.max(np.abs(slow.y))
    dg = np.max(np.abs(fast.g - slow.g)) / np.max(np.abs(g))
    print(f"{case}: δ {dy:.1e}, W {dg:.1e}")
    assert dy < 1e-10 and dg < 1e-10
    assert abs(fast.end[0] - slow.end[0]) < 1e-10 * np.max(np.abs(slow.y))
