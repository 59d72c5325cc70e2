"""Issue 33 item 5: every result the public analyses return has ``to_frame()`` and
``plot(ax=None)``, drawn by ``nlgrd.plotting`` (the same stability and missing-point marks
for every model). Here the results of link models (``nlgrd.sweep`` and
``nlgrd.continuation`` of a model with a clearance) and the time responses."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import nlgrd  # noqa: E402
from nlgrd.errors import ModelError  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
RUB = ROOT / "data" / "models" / "rub_rotor.toml"


def _drawn_y(ax) -> np.ndarray:
    """Every finite y value of the lines drawn on ``ax``."""
    ys = [np.asarray(line.get_ydata(), dtype=float) for line in ax.get_lines()]
    ys = np.concatenate(ys) if ys else np.zeros(0)
    return ys[np.isfinite(ys)]


@pytest.fixture(scope="module")
def rub_sweep():
    """rub_rotor (a disk in a rub ring, no gear), 3 speeds up, H = 5, with stability."""
    return nlgrd.sweep(nlgrd.load(RUB), rpm=np.linspace(2000.0, 3000.0, 3), H=5, directions="up")


def test_link_sweep_plot_draws_its_column_on_the_given_axes(rub_sweep):
    """``plot(ax=ax)`` draws on ``ax``, returns it, and the values drawn are the table's
    ``rub.displacement_max [m]`` column (every one of them: all points converged, stable)."""
    frame = rub_sweep.to_frame()
    assert frame["converged"].all() and frame["stable"].all()
    fig, ax = plt.subplots()
    assert rub_sweep.plot("rub.displacement_max", ax=ax) is ax
    drawn = _drawn_y(ax)
    for v in frame["rub.displacement_max [m]"].to_numpy(float):
        assert np.any(np.isclose(drawn, v, rtol=1e-12, atol=0))
    assert ax.get_ylabel() == "rub: displacement max [m]"
    plt.close(fig)


def test_link_sweep_plot_default_quantity_and_new_figure(rub_sweep):
    """Without ``ax`` a new figure; without a quantity the CLI's default: a mesh's DSLR,
    else the first link's largest force (here ``rub.force_max [N]``)."""
    ax = rub_sweep.plot()
    drawn = _drawn_y(ax)
    for v in rub_sweep.to_frame()["rub.force_max [N]"].to_numpy(float):
        assert np.any(np.isclose(drawn, v, rtol=1e-12, atol=0))
    plt.close(ax.figure)


def test_link_sweep_plot_of_an_unknown_quantity_names_the_columns(rub_sweep):
    with pytest.raises(ModelError, match=r"quantity.*rub\.force_max"):
        rub_sweep.plot("dslr")


def test_link_continuation_plot_draws_its_curve():
    """``nlgrd.continuation`` of rub_rotor: ``plot(ax=ax)`` draws the link column along the
    curve on ``ax``."""
    res = nlgrd.continuation(nlgrd.load(RUB), rpm=(2000.0, 2100.0), H=5)
    frame = res.to_frame()
    fig, ax = plt.subplots()
    assert res.plot("rub.force_max", ax=ax) is ax
    drawn = _drawn_y(ax)
    values = frame["rub.force_max [N]"].to_numpy(float)
    assert values.size >= 2
    for v in values:
        assert np.any(np.isclose(drawn, v, rtol=1e-12, atol=0))
    plt.close(fig)
