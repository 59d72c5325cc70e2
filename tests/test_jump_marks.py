"""Issue 33 item 5: a sweep's jumps drawn one way on every sweep figure (a one-mesh
sweep's ``plot``, a link sweep's ``plot`` and ``nlgrd sweep``'s link figure): dotted
vertical arrows (gid ``jump``) at the midpoint of the jump's two points, from the value
left to the value reached, counted in the legend."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from nlgrd.nonlinear.models.sdof import SDOFGearPair  # noqa: E402
from nlgrd.nonlinear.results.link_results import LinkSweepResult  # noqa: E402
from nlgrd.nonlinear.tracing.sweep import sweep  # noqa: E402
from nlgrd.plotting.common import JUMP_GID, mark_jumps  # noqa: E402

# the single-DOF pair of tests/test_continuation.py: its curve folds twice between 0.66 and
# 1.0 ω_n, so the up sweep jumps up near the upper fold and the down sweep down near the lower
LSTE = np.array([0.0, 1.24e-6, 0.0, 0.50e-6, 0.30e-6, 0.10e-6, -0.05e-6])
PAIR = SDOFGearPair(0.261, 0.2587e9, 50e-6, 2295.0, LSTE, damping_ratio=0.02)
GRID = np.arange(0.66, 1.0, 0.02) * PAIR.natural_frequency


@pytest.fixture(scope="module")
def swept():
    return sweep(PAIR.reduced_model(), GRID, 5)


def _jump_lines(ax):
    shafts = [ln for ln in ax.get_lines() if ln.get_gid() == JUMP_GID and not ln.get_label().startswith("_")]
    heads = [ln for ln in ax.get_lines() if ln.get_gid() == JUMP_GID and ln.get_label().startswith("_")]
    return shafts, heads


def _check_arrows(ax, jumps, table, x, y, series=""):
    """One labelled shaft per direction, at the midpoints of the jumps, from the table's
    value at the point left to the value at the point reached; its head at the latter."""
    shafts, heads = _jump_lines(ax)
    assert sorted(s.get_label() for s in shafts) == [f"{series}down: jump (1)", f"{series}up: jump (1)"]
    for j in jumps:
        f0, f1 = j.omega_from / (2 * np.pi), j.omega_to / (2 * np.pi)
        part = table[table["direction"] == j.direction]
        v0 = part.loc[np.isclose(part[x], f0, rtol=1e-12), y].item()
        v1 = part.loc[np.isclose(part[x], f1, rtol=1e-12), y].item()
        shaft = next(s for s in shafts if s.get_label().startswith(series + j.direction))
        np.testing.assert_allclose(shaft.get_xdata()[:2], (f0 + f1) / 2, rtol=1e-12)
        np.testing.assert_allclose(shaft.get_ydata()[:2], [v0, v1], rtol=1e-12)
        assert any(np.isclose(h.get_ydata(), v1, rtol=1e-12).any() for h in heads)


def test_one_mesh_sweep_draws_its_jumps(swept):
    """The fold's jumps: up 4609.8 -> 4710.1 Hz (5.56 -> 9.74 µm RMS), down 3607.7 ->
    3507.5 Hz (20.4 -> 1.77 µm), as the sweep's ``jumps()`` finds them."""
    jumps = swept.jumps()
    assert sorted(j.direction for j in jumps) == ["down", "up"]
    ax = swept.plot("dte_rms")
    _check_arrows(ax, jumps, swept.to_frame(), "base_frequency [Hz]", "dte_rms [um]")
    plt.close(ax.figure)


def test_link_sweep_draws_its_jumps_the_same_way(swept):
    """The same points as a link sweep (the pair's RMS DTE as a link column): the same
    arrows, from ``LinkSweepResult.jumps()`` (the jumps the command line lists)."""
    links = pd.DataFrame({"mesh.dte_rms [um]": swept.dte_rms * 1e6})
    res = LinkSweepResult(swept, links)
    ax = res.plot("mesh.dte_rms")
    _check_arrows(ax, res.jumps(), res.to_frame(), "base_frequency [Hz]", "mesh.dte_rms [um]", "sweep ")
    plt.close(ax.figure)


def test_a_jump_off_the_drawn_values_is_left_out():
    """A jump whose end is not drawn as a value (NaN: not converged, no stable response)
    gets no arrow, and the legend counts only the arrows drawn."""
    fig, ax = plt.subplots()
    assert mark_jumps(ax, [1.0], [2.0], [np.nan], "C0", "up") == []
    drawn = mark_jumps(ax, [1.0, 2.0, 3.0], [1.0, 5.0, np.nan], [4.0, 2.0, 1.0], "C0", "up")
    assert drawn[0].get_label() == "up: jump (2)"
    assert [h.get_marker() for h in drawn[1:]] == ["^", "v"]
    plt.close(fig)
