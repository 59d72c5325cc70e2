"""The model's stores of stability and recovery work give what the uncached paths give.

- The full state space of a truncated basis's check (``TruncatedStability.full_state(speed,
  shared=True)``) shares the model's Floquet store: its multipliers equal, bit for bit,
  those of a full state space with no store, at a first visit of each frequency, at a
  revisited one and for another damping matrix (a store keyed without ω, the speed or D
  would return another frequency's or damping's multipliers, which differ).
- The bearing recovery after a sweep (``LinkReceptance.recover``) takes the rows the
  sweep's own banded solves kept per (ω, H): the same bits as a fresh solve.

The reference is the uncached computation of the same quantity, so the tolerance is 0
(``assert_array_equal``): the stores hold the results of the same arithmetic.
"""

from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.nonlinear.reduction.state_space import LinearStateSpace
from nlgrd.nonlinear.results.bearing_loads import bearing_node_dofs
from nlgrd.nonlinear.stability.floquet import floquet_analysis
from nlgrd.nonlinear.stability.tangent import tangent_pieces

TWO_SHAFT = Path(__file__).resolve().parents[1] / "data" / "models" / "two_shaft.toml"
#: A mesh orbit of two_shaft.toml that loses contact (half backlash 50 µm, static
#: deflection 8.9 µm beyond it): δ from 39 to 80 µm, three tangent pieces.
LOSS = np.array([5.89e-5, 2e-5, 0.0, 1e-6, 5e-7])
OMEGAS = 2 * np.pi * np.array([1300.0, 1700.0])


@pytest.fixture(scope="module")
def model():
    return build_link_model(load_model(TWO_SHAFT))


def test_the_orbit_loses_contact(model):
    """The orbit's tangent varies (the path that builds exponentials and the revisit store)."""
    _, Kt = tangent_pieces(model.reduced.nonlinearities, LOSS[None], 1)
    assert Kt.ravel().min() == 0 and Kt.ravel().max() > 0


def test_full_state_store_gives_the_plain_multipliers(model):
    laws, st = model.reduced.nonlinearities, model.receptance.stability
    speed = model.receptance.plan.speed
    plain = [floquet_analysis(st.full_state(speed(w)), laws, LOSS, w).multipliers for w in OMEGAS]
    assert not np.array_equal(np.sort_complex(plain[0]), np.sort_complex(plain[1]))
    for w, ref in zip([*OMEGAS, OMEGAS[0]], [*plain, plain[0]], strict=True):  # the last a revisit
        shared = st.full_state(speed(w), shared=True)
        assert shared.cache is st._floquet
        assert_array_equal(floquet_analysis(shared, laws, LOSS, w).multipliers, ref)
    assert sum(k[0] == "monodromy" for k in st._floquet._data) >= 2
    # another damping at the same frequency and speed, through the same store
    w = OMEGAS[1]
    ss = st.full_state(speed(w))
    other = LinearStateSpace(ss.M, 1.5 * ss.D, ss.K, ss.W)
    ref = floquet_analysis(other, laws, LOSS, w).multipliers
    assert not np.array_equal(np.sort_complex(ref), np.sort_complex(plain[1]))
    got = floquet_analysis(LinearStateSpace(ss.M, 1.5 * ss.D, ss.K, ss.W, cache=st._floquet), laws, LOSS, w)
    assert_array_equal(got.multipliers, ref)


def test_recovery_takes_the_sweeps_solves(model):
    rec = model.receptance
    assert rec.method == "banded"
    dofs = bearing_node_dofs(model.system)
    H = 3
    Y = np.array([[5.9e-5, 2e-6, -1e-6, 3e-7, 2e-7, -1e-7, 5e-8]])
    G = np.array([[2300.0, 40.0, -20.0, 5.0, 3.0, -1.0, 0.5]])
    fresh = build_link_model(load_model(TWO_SHAFT)).receptance
    refs = [fresh.recover(w, H, Y, G, dofs) for w in OMEGAS]  # a banded solve each
    assert not np.array_equal(refs[0], refs[1])
    for w in OMEGAS:
        rec.terms(w, H)  # the sweep's solve: it keeps the bearing rows
    for w, ref in zip(OMEGAS, refs, strict=True):
        assert rec._recovery.peek((float(w), H, tuple(int(i) for i in dofs))) is not None
        assert_array_equal(rec.recover(w, H, Y, G, dofs), ref)
