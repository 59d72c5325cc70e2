"""The cost ceiling of the landing search at a point without a stable orbit (issue 34,
item 2), on the idler train (data/models/idler_train.toml, H = 9) at 1600 Hz up from
1550 Hz: the point benchmarks/README.md measured, where the uncapped search walked 601
arc-length steps (22 folds, 4237 corrector evaluations; its one unstable crossing at the
568th) without a stable crossing.

Checked: the search stops at :data:`LANDING_EVALUATIONS` corrector evaluations (counted
on the tracer, so the check cannot depend on the machine's speed); the sweep still
reports the orbit the uncapped search reported there (same orbit to SAME_ORBIT_RTOL,
with max |μ| > 1 from the reference monodromy ``method="expm"``, and a converged
harmonic-balance residual); a failed search is not walked again from the same start, and
a walk from the same start to another target is replayed with a fresh walk's result.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import nlgrd.nonlinear.tracing.arclength as arclength
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.tracing.arclength import LANDING_EVALUATIONS, jump_to_branch
from nlgrd.nonlinear.tracing.landing import same_orbit
from nlgrd.nonlinear.tracing.sweep import FailedSearches

IDLER = Path(__file__).resolve().parent.parent / "data" / "models" / "idler_train.toml"
W = 2 * np.pi * np.array([1550.0, 1600.0])
H = 9


@pytest.fixture(scope="module")
def idler():
    model = build_link_model(load_model(IDLER))
    res = link_sweep(model, W, H=H, directions="up").result
    return model, res


@pytest.fixture
def counted(monkeypatch):
    """Corrector evaluations of every Tracer, counted by wrapping Tracer.system."""
    n = {"evals": 0}
    original = arclength.Tracer.system

    def system(self, u):
        n["evals"] += 1
        return original(self, u)

    monkeypatch.setattr(arclength.Tracer, "system", system)
    return n


def test_search_stops_at_the_ceiling(idler, counted):
    model, res = idler
    exhausted: list = []
    z, steps, folds, unstable = jump_to_branch(
        model.reduced, H, res.harmonics[0], W[0], W[1], tol=1e-10, exhausted=exhausted
    )
    assert z is None and exhausted == [True]
    # the check precedes each corrector call, which evaluates at most 13 times (12 updates)
    assert LANDING_EVALUATIONS <= counted["evals"] <= LANDING_EVALUATIONS + 13


def test_sweep_reports_the_uncapped_searchs_orbit(idler):
    model, res = idler
    assert bool(res.converged[1]) and bool(res.no_stable[1]) and bool(res.branch_switch[1])
    assert res.residual[1] < 1e-10
    mu = floquet_multipliers(
        model.reduced.linear_state_space(W[1]),
        model.reduced.nonlinearities,
        res.harmonics[1],
        W[1],
        method="expm",
    )
    assert np.max(np.abs(mu)) > 1.4  # 1.4246 measured; a real multiplier, far from 1


@pytest.mark.slow
def test_uncapped_search_finds_the_same_orbit(idler):
    """The search without a ceiling (the algorithm before issue 34, 4237 evaluations)."""
    model, res = idler
    z, _, folds, unstable = jump_to_branch(
        model.reduced, H, res.harmonics[0], W[0], W[1], tol=1e-10, max_evaluations=None
    )
    assert z is None and unstable is not None and folds > 0
    assert same_orbit(unstable, res.harmonics[1])


def test_failed_search_is_not_walked_again(idler, counted):
    model, res = idler
    searches = FailedSearches()
    first: list = []
    kw = dict(tol=1e-10, max_evaluations=60)  # a short search: the memo does not depend on its length
    out1 = searches.jump(model.reduced, H, res.harmonics[0], W[0], W[1], exhausted=first, **kw)
    walked = counted["evals"]
    again: list = []
    out2 = searches.jump(model.reduced, H, res.harmonics[0].copy(), W[0], W[1], exhausted=again, **kw)
    assert (
        out1[0] is None and first == [True] and out2 is out1 and again == first and counted["evals"] == walked
    )
    # the same start to another target: the stored walk is replayed (no evaluation), with
    # the result of a fresh walk (its crossings of the new target checked the same way)
    w2 = 2 * np.pi * 1590.0
    replayed = searches.jump(model.reduced, H, res.harmonics[0], W[0], w2, exhausted=[], **kw)
    assert counted["evals"] == walked
    fresh = jump_to_branch(model.reduced, H, res.harmonics[0], W[0], w2, **kw)
    assert counted["evals"] > walked
    assert replayed[1:3] == fresh[1:3] and (replayed[0] is None) == (fresh[0] is None)
    assert (replayed[3] is None) == (fresh[3] is None)
    if fresh[3] is not None:
        assert np.array_equal(replayed[3], fresh[3])
    # another start is walked afresh
    before = counted["evals"]
    searches.jump(model.reduced, H, res.harmonics[0] * (1 + 1e-9), W[0], w2, exhausted=[], **kw)
    assert counted["evals"] > before
