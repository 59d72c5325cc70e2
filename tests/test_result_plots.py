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
    ``rub.displacement_max [um]`` column (every one of them: all points converged, stable)."""
    frame = rub_sweep.to_frame()
    assert frame["converged"].all() and frame["stable"].all()
    fig, ax = plt.subplots()
    assert rub_sweep.plot("rub.displacement_max", ax=ax) is ax
    drawn = _drawn_y(ax)
    for v in frame["rub.displacement_max [um]"].to_numpy(float):
        assert np.any(np.isclose(drawn, v, rtol=1e-12, atol=0))
    assert ax.get_ylabel() == "rub: displacement max [µm]"
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


def _points(ax, gid: str, markers: bool = True) -> int:
    """Points drawn by the artists of ``gid`` (markers only, or every finite vertex)."""
    lines = [ln for ln in ax.get_lines() if ln.get_gid() == gid]
    if markers:
        lines = [ln for ln in lines if ln.get_linestyle() == "None"]
    return sum(int(np.isfinite(np.asarray(ln.get_ydata(), dtype=float)).sum()) for ln in lines)


def test_link_sweep_figure_marks_stability_gaps_and_jumps():
    """Kubo's rig over its main resonance (3-6 kHz, H = 5, no time answers: quasi-periodic
    points stay gaps): ``nlgrd.sweep(...).plot()`` draws the marks of stable points, of
    points without a stable periodic response and of jumps (gids of
    :mod:`nlgrd.plotting.common`), each as many as its table says: a filled marker per
    stable point, an edge mark per point without a stable periodic response, one arrow per
    jump whose two ends are drawn."""
    from nlgrd.plotting.common import JUMP_GID, NO_RESPONSE_GID, STABILITY_GIDS, STABLE

    system = nlgrd.load(ROOT / "data" / "case_studies" / "kubo.toml")
    hz = np.linspace(3000.0, 6000.0, 16)
    res = nlgrd.sweep(system, hz=hz, H=5, time_domain=False)
    ax = res.plot("dte_rms")
    kinds = {ln.get_gid() for ln in ax.get_lines()} - {None}
    assert {STABILITY_GIDS[STABLE], NO_RESPONSE_GID, JUMP_GID} <= kinds
    frame = res.to_frame()
    assert _points(ax, STABILITY_GIDS[STABLE]) == int(frame["stable"].eq(True).sum())
    gaps = frame["converged"].astype(bool) & ~frame["response"].isin(["periodic"])
    assert _points(ax, NO_RESPONSE_GID) == int(gaps.sum()) > 0
    drawn = [j for j in res.jumps() if np.isfinite([j.value_from, j.value_to]).all()]
    shafts = [ln for ln in ax.get_lines() if ln.get_gid() == JUMP_GID and ln.get_linestyle() != "None"]
    assert sum(int(ln.get_label().rsplit("(", 1)[1].rstrip(")")) for ln in shafts) == len(drawn) > 0
    plt.close(ax.figure)


# ----------------------------------------------------------------------------- time responses

#: Kubo's single-DOF pair (tests/test_sdof.py), ζ = 0.02, LSTE of three harmonics.
LSTE = np.array([0.0, 1.24e-6, 0.0, 0.50e-6, 0.30e-6, 0.10e-6, -0.05e-6])


def _sdof():
    from nlgrd.nonlinear.models.sdof import SDOFGearPair

    return SDOFGearPair(0.261, 0.2587e9, 50e-6, 2295.0, LSTE, damping_ratio=0.02)


def _history_checks(res, frame):
    """The table of a mesh time response: its last period's δ, e and W in µm and N."""
    h = res.history
    assert list(frame.columns) == [
        "time [s]",
        "mesh0.delta [um]",
        "mesh0.lste [um]",
        "mesh0.deflection [um]",
        "mesh0.force [N]",
    ]
    np.testing.assert_array_equal(frame["time [s]"], h.t)
    np.testing.assert_allclose(frame["mesh0.delta [um]"], h.delta * 1e6, rtol=1e-15)
    np.testing.assert_allclose(frame["mesh0.lste [um]"], h.lste * 1e6, rtol=1e-15)
    np.testing.assert_allclose(
        frame["mesh0.deflection [um]"], (h.delta - h.lste) * 1e6, rtol=1e-12, atol=1e-12
    )
    np.testing.assert_allclose(frame["mesh0.force [N]"], h.force, rtol=1e-15)


def test_sdof_time_response_table_and_plot():
    """``nlgrd.timedomain.sdof.integrate``'s TimeResponse: ``to_frame()`` in µm and N, and
    ``plot(ax=ax)`` draws δ in µm against time in ms on ``ax``."""
    from nlgrd.timedomain.sdof import integrate

    sd = _sdof()
    res = integrate(sd, 0.8 * sd.natural_frequency, tol=1e-6)
    frame = res.to_frame()
    _history_checks(res, frame)
    fig, ax = plt.subplots()
    assert res.plot(ax=ax) is ax
    np.testing.assert_allclose(ax.get_lines()[0].get_ydata(), frame["mesh0.delta [um]"], rtol=1e-15)
    plt.close(fig)
    plt.close(res.plot(quantity="force").figure)


def test_link_time_response_table_and_plot():
    """``link_time_response`` of rub_rotor: one column per link coordinate, named
    ``<link>.<coordinate> [um]``, over one period in time [s]; ``plot(ax=ax)`` draws them."""
    from nlgrd.nonlinear.models.link_model import build_link_model
    from nlgrd.timedomain.links import link_time_response

    model = build_link_model(nlgrd.load(RUB))
    omega = 2 * np.pi * 40.0
    res = link_time_response(model, omega, steps_per_period=64, tol=1e-4, max_periods=200)
    frame = res.to_frame()
    assert list(frame.columns) == ["time [s]", "rub.y [um]", "rub.z [um]"]
    ns = res.y.shape[1]
    np.testing.assert_allclose(frame["time [s]"], np.arange(ns) * 2 * np.pi / omega / ns, rtol=1e-15)
    np.testing.assert_allclose(frame["rub.y [um]"], res.y[0] * 1e6, rtol=1e-15)
    np.testing.assert_allclose(frame["rub.z [um]"], res.y[1] * 1e6, rtol=1e-15)
    fig, ax = plt.subplots()
    assert res.plot(ax=ax) is ax
    drawn = [np.asarray(line.get_ydata(), dtype=float) for line in ax.get_lines()]
    assert len(drawn) == 2
    np.testing.assert_allclose(drawn[1], frame["rub.z [um]"], rtol=1e-15)
    plt.close(fig)
