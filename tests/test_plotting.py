"""Figures a reader can trust at a glance: the artists of the sweep and Campbell plots.

Small synthetic result tables, checked on the artists (on the rendered pixels only where
the question is whether a marker can be seen): up and down sweeps get different colours;
unstable points open markers and dashed lines; unknown stability (NaN, None, or False
without Floquet multipliers) half-filled markers and the words "stability not computed"
in the legend; non-converged points (NaN values, as the sweeps write them) crosses on the
bottom edge counted in the legend; values beyond the scale carets at the axis limit with
a note; Campbell curves broken where the whirl or kind changes or two modes come close;
up and down answers at one speed both visible; legends naming only what is drawn.
"""

from __future__ import annotations

import json
from types import SimpleNamespace

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402

from nlgrd.plotting import save_figure  # noqa: E402
from nlgrd.plotting.common import (  # noqa: E402
    LEGEND_INSIDE,
    LEGEND_MARKER_MIN,
    NC_HEIGHT,
    NC_ROW,
    NO_MEASUREMENT_TEXT,
    SERIES_COLOURS,
    axis_label,
    drawn_entries,
    mark_not_converged,
    note_no_measurement,
    place_legend,
    plot_counted,
    stability_codes,
)
from nlgrd.plotting.nonlinear import plot_continuation, plot_sweep, plot_sweep_frame  # noqa: E402
from nlgrd.plotting.rotor import campbell_breaks, plot_campbell  # noqa: E402
from nlgrd.plotting.studies import study_curves, study_distribution, study_map  # noqa: E402
from nlgrd.studies.index_page import NO_CAPTION, index_html  # noqa: E402

X, Y = "base_frequency [Hz]", "dte_rms [um]"


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def sweep_frame(n=8, stable=True, floquet=1.0):
    """Up and down sweeps over the same n frequencies, all converged."""
    f = np.linspace(100.0, 800.0, n)
    up = pd.DataFrame({X: f, "direction": "up", "converged": True, Y: 1 + f / 100})
    down = pd.DataFrame({X: f[::-1], "direction": "down", "converged": True, Y: 2 + f[::-1] / 100})
    frame = pd.concat([up, down], ignore_index=True)
    frame["stable"] = pd.Series([stable] * len(frame), dtype=object)
    frame["floquet_max [-]"] = floquet
    return frame


def data_lines(ax):
    """Lines drawn in data coordinates with finite points (no crosses, no proxies)."""
    return [ln for ln in ax.get_lines() if ln.get_transform() == ax.transData]


def by_label(ax, text):
    found = [ln for ln in ax.get_lines() if text in ln.get_label()]
    assert found, f"no artist labelled with {text!r}: {[ln.get_label() for ln in ax.get_lines()]}"
    return found


def colour_of(line):
    return to_rgba(line.get_color())


def test_up_and_down_get_different_colours_not_only_markers():
    ax = plot_sweep_frame(sweep_frame(), X, Y, label="FE")
    up = {colour_of(ln) for ln in by_label(ax, "FE up")}
    down = {colour_of(ln) for ln in by_label(ax, "FE down")}
    assert len(up) == 1 and len(down) == 1 and up != down
    # every drawn line (markers and segments) has one of the two colours: two colours in all
    assert {colour_of(ln) for ln in data_lines(ax)} == up | down
    assert by_label(ax, "FE up")[0].get_marker() != by_label(ax, "FE down")[0].get_marker()


def test_two_series_use_four_colours():
    ax = plot_sweep_frame(sweep_frame(), X, Y, label="FE", series=0)
    plot_sweep_frame(sweep_frame(), X, Y, ax=ax, label="SDOF", series=1)
    assert len({colour_of(ln) for ln in data_lines(ax)}) == 4


def test_stable_points_are_filled_and_solid():
    ax = plot_sweep_frame(sweep_frame(stable=True), X, Y, label="FE")
    (mk,) = [ln for ln in by_label(ax, "FE up") if ln.get_marker() not in ("None", None, "")]
    assert mk.get_fillstyle() == "full" and mk.get_markerfacecolor() != "none"
    styles = {ln.get_linestyle() for ln in data_lines(ax) if ln.get_label().startswith("_")}
    assert styles == {"-"}
    assert not any("unstable" in ln.get_label() or "not computed" in ln.get_label() for ln in ax.get_lines())


def test_unstable_points_are_open_and_joined_dashed():
    frame = sweep_frame()
    unstable = (frame["direction"] == "up") & frame[X].between(300, 600)
    frame.loc[unstable, "stable"] = False
    frame.loc[unstable, "floquet_max [-]"] = 1.3
    ax = plot_sweep_frame(frame, X, Y, label="FE")
    (open_,) = by_label(ax, "FE up, unstable")
    assert open_.get_markerfacecolor() == "none"
    np.testing.assert_allclose(np.sort(open_.get_xdata()), np.sort(frame.loc[unstable, X]))
    up_colour = colour_of(open_)
    dashed = [ln for ln in data_lines(ax) if ln.get_linestyle() == "--"]
    assert dashed and all(colour_of(ln) == up_colour for ln in dashed)
    # the dashed pieces join exactly the segments with an unstable end
    xs = np.asarray(dashed[0].get_xdata(), dtype=float)
    assert np.nanmin(xs) < 300 and np.nanmax(xs) > 600
    filled = [ln for ln in by_label(ax, "FE up") if ln.get_label() == "FE up"]
    assert filled[0].get_markerfacecolor() != "none"


@pytest.mark.parametrize(
    "stable, floquet",
    [(np.nan, 1.0), (None, 1.0), (pd.NA, 1.0), (False, np.nan)],
    ids=["NaN", "None", "NA", "False without Floquet"],
)
def test_unknown_stability_is_half_filled_and_stated(stable, floquet):
    ax = plot_sweep_frame(sweep_frame(stable=stable, floquet=floquet), X, Y, label="FE")
    ax.legend()
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "FE up, stability not computed" in texts and "FE down, stability not computed" in texts
    for ln in by_label(ax, "stability not computed"):
        assert ln.get_fillstyle() == "bottom"
    assert not any("unstable" in t for t in texts)
    # the lines between them are not dashed: unknown is not unstable
    assert {ln.get_linestyle() for ln in data_lines(ax) if ln.get_label().startswith("_")} == {"-"}


def test_nullable_boolean_column_as_the_sweep_tables_write_it():
    """``SweepResult.to_frame`` writes ``stable`` as pandas' nullable "boolean" (NA: unknown)."""
    frame = sweep_frame()
    frame["stable"] = pd.array([True, False, None, True] * (len(frame) // 4), dtype="boolean")
    ax = plot_sweep_frame(frame, X, Y, label="FE")
    labels = {ln.get_label() for ln in ax.get_lines()}
    assert {"FE up", "FE up, unstable", "FE up, stability not computed"} <= labels


def test_stable_column_missing_means_unknown():
    frame = sweep_frame().drop(columns=["stable", "floquet_max [-]"])
    ax = plot_sweep_frame(frame, X, Y, label="FE")
    assert by_label(ax, "FE up, stability not computed")


def test_non_converged_points_are_crosses_at_the_bottom_counted_in_the_legend():
    frame = sweep_frame()
    bad = (frame["direction"] == "down") & frame[X].isin(frame[X].unique()[[1, 4, 5]])
    # as the sweeps will write them: NaN in every numeric and flag column
    frame.loc[bad, [Y, "floquet_max [-]"]] = np.nan
    frame["stable"] = frame["stable"].astype(object)
    frame.loc[bad, "stable"] = None
    frame["converged"] = frame["converged"].astype(object)
    frame.loc[bad, "converged"] = False
    ax = plot_sweep_frame(frame, X, Y, label="FE")
    ax.legend()
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "FE down: not converged (3)" in texts
    assert not any("FE up: not converged" in t for t in texts)
    (cross,) = by_label(ax, "not converged")
    assert cross.get_marker() == "x"
    assert cross.get_transform() != ax.transData  # y in axes coordinates: the bottom edge
    np.testing.assert_allclose(cross.get_ydata(), NC_HEIGHT)
    np.testing.assert_allclose(np.sort(cross.get_xdata()), np.sort(frame.loc[bad, X]))
    down = colour_of(by_label(ax, "FE down")[0])
    assert colour_of(cross) == down
    # no down-sweep value is drawn at those frequencies
    for ln in data_lines(ax):
        if colour_of(ln) == down:
            x, y = np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float)
            assert not np.isin(x[np.isfinite(y)], frame.loc[bad, X].to_numpy()).any()


def test_stale_values_of_non_converged_points_are_not_drawn():
    """A table that keeps the last iterate's value of a failed point still shows only a cross."""
    frame = sweep_frame()
    frame.loc[3, "converged"] = False
    frame.loc[3, Y] = 99.0
    ax = plot_sweep_frame(frame, X, Y, label="FE")
    for ln in data_lines(ax):
        assert 99.0 not in np.asarray(ln.get_ydata(), float)
    assert by_label(ax, "FE up: not converged (1)")


def test_values_off_the_scale_are_clipped_to_the_axis_limit_with_a_note():
    frame = sweep_frame()
    up = frame.index[frame["direction"] == "up"]
    frame.loc[up[4], Y] = 30.0
    frame.loc[up[5], Y] = 12.0
    ax = plot_sweep_frame(frame, X, Y, label="SDOF", ylim=(0, 10))
    assert ax.get_ylim() == (0, 10)
    (caret,) = by_label(ax, "above the scale")
    np.testing.assert_allclose(caret.get_ydata(), 10.0)  # at the axis limit
    np.testing.assert_allclose(np.sort(caret.get_xdata()), np.sort(frame.loc[up[4:6], X]))
    assert caret.get_label().startswith("SDOF up: 2 above the scale (max 30")
    assert not caret.get_clip_on()
    # no line runs off the top: every other vertex lies within the scale
    for ln in data_lines(ax):
        if ln is not caret:
            y = np.asarray(ln.get_ydata(), float)
            assert np.all(y[np.isfinite(y)] <= 10.0)


def sweep_result(n=6):
    """A SweepResult-like object (the attributes plot_sweep reads), stability partly unknown."""
    omega = 2 * np.pi * np.concatenate([np.linspace(100, 600, n), np.linspace(600, 100, n)])
    direction = np.array(["up"] * n + ["down"] * n)
    converged = np.ones(2 * n, dtype=bool)
    converged[2] = False
    stable = np.array([True, False, None, True, True, True] + [None] * n, dtype=object)
    floquet = np.array([0.9, 1.2, np.nan, 0.9, 0.9, 0.9] + [np.nan] * n)
    rms = np.linspace(1e-6, 3e-6, 2 * n)
    rms[2] = np.nan
    return SimpleNamespace(
        omega=omega,
        direction=direction,
        converged=converged,
        stable=stable,
        floquet_max=floquet,
        metrics={"dte_rms": rms},
    )


def test_plot_sweep_of_a_result_states_everything_in_its_legend():
    ax = plot_sweep(sweep_result(), "dte_rms")
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert {"up", "up, unstable", "up: not converged (1)", "down, stability not computed"} <= set(texts)
    assert ax.get_xlabel() == "mesh frequency [Hz]"
    res = sweep_result()
    (up,) = [ln for ln in ax.get_lines() if ln.get_label() == "up"]
    np.testing.assert_allclose(up.get_ydata(), res.metrics["dte_rms"][[0, 3, 4, 5]] * 1e6)  # in µm


def test_every_plot_function_takes_and_returns_the_axes():
    _, ax = plt.subplots()
    assert plot_sweep_frame(sweep_frame(), X, Y, ax=ax) is ax
    assert plot_sweep(sweep_result(), ax=ax) is ax
    assert plot_campbell(campbell_result(), ax=ax) is ax
    assert plot_continuation(continuation_result(), ax=ax) is ax
    assert plot_sweep(sweep_result()) is not ax  # ax=None: a new figure


def continuation_result():
    """An S-shaped curve in arc-length order: stable, unstable middle branch, stable."""
    s = np.linspace(-1.2, 1.2, 25)
    f = 500 + 100 * (s**3 - s)  # folds back between the turning points
    y = 1e-6 * (3 + s)
    stable = np.abs(s) > 0.577
    curve = SimpleNamespace(
        omega=2 * np.pi * f,
        direction=np.array(["curve"] * s.size),
        converged=np.ones(s.size, dtype=bool),
        stable=stable,
        floquet_max=np.where(stable, 0.9, 1.5),
        metrics={"dte_rms": y},
    )
    return SimpleNamespace(curve=curve, turning_indices=np.array([7, 17]))


def test_continuation_keeps_the_arc_order_and_dashes_the_unstable_branch():
    ax = plot_continuation(continuation_result(), color="k", label="HB")
    dashed = [ln for ln in data_lines(ax) if ln.get_linestyle() == "--"]
    assert len(dashed) == 1
    xs = np.asarray(dashed[0].get_xdata(), float)
    xs = xs[np.isfinite(xs)]
    assert np.any(np.diff(xs) < 0)  # not re-sorted by frequency: it runs back along the fold
    assert by_label(ax, "HB curve, unstable")[0] is dashed[0]
    assert by_label(ax, "HB turning points")


def test_continuation_tells_stability_by_line_style_not_by_a_marker_per_point():
    """Issue 36, item 6: a continuation of 1200 points drew 1200 overlapping markers. Now
    the stable parts are one solid line, the unstable ones one dashed line, each in the
    legend once, and the only markers are the turning points' stars."""
    s = np.linspace(-1.2, 1.2, 1200)
    res = continuation_result()
    stable = np.abs(s) > 0.577
    res.curve = SimpleNamespace(
        omega=2 * np.pi * (500 + 100 * (s**3 - s)),
        direction=np.array(["curve"] * s.size),
        converged=np.ones(s.size, dtype=bool),
        stable=stable,
        floquet_max=np.where(stable, 0.9, 1.5),
        metrics={"dte_rms": 1e-6 * (3 + s)},
    )
    ax = plot_continuation(res, color="k", label="HB")
    styles = {ln.get_label(): ln.get_linestyle() for ln in data_lines(ax)}
    assert styles["HB curve"] == "-" and styles["HB curve, unstable"] == "--"
    markers = [ln for ln in ax.get_lines() if ln.get_marker() not in ("None", "none", "", None)]
    assert [ln.get_label() for ln in markers] == ["HB turning points"]
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert texts == ["HB curve", "HB curve, unstable", "HB turning points"]


def test_continuation_without_stability_is_dotted_and_says_so():
    res = continuation_result()
    res.curve.stable = np.full(res.curve.omega.size, np.nan, dtype=object)
    res.curve.floquet_max = np.full(res.curve.omega.size, np.nan)
    ax = plot_continuation(res, color="k", label="HB")
    (line,) = by_label(ax, "HB curve, stability not computed")
    assert line.get_linestyle() == ":"


def campbell_result(ns=11):
    """Three mode slots over speed: slot 0 changes whirl at index 5, slots 1 and 2 touch at
    index 8 (ordering may swap), slot 2 turns unstable (negative damping) from index 9."""
    speeds = np.linspace(0, 1000, ns)
    F = np.column_stack([100 + 0.01 * speeds, 200 + 0.05 * speeds, 300 - 0.01 * speeds])
    F[8, 2] = F[8, 1] * 1.005
    Z = np.full(F.shape, 0.02)
    Z[9:, 2] = -0.01
    whirl = np.array([["forward", "-", "backward"]] * ns, dtype=object)
    whirl[5:, 0] = "backward"
    kinds = np.array([["lateral", "torsional", "lateral"]] * ns, dtype=object)
    crit = [{"order": "1x", "mode": 1, "speed [rpm]": 6000.0, "frequency [Hz]": 100.0}]
    return SimpleNamespace(
        speeds=speeds,
        frequencies=F,
        damping_ratios=Z,
        whirl=whirl,
        kinds=kinds,
        orders={"1x": 1.0},
        critical_speeds=crit,
    )


def joined(ax, x0, x1, y0, y1):
    """Whether any line of ``ax`` has a segment from (x0, y0) to (x1, y1)."""
    for ln in ax.get_lines():
        x, y = np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float)
        if x.size < 2 or ln.get_linestyle() in ("None", "none", ""):
            continue
        hit = np.isclose(x[:-1], x0) & np.isclose(x[1:], x1) & np.isclose(y[:-1], y0) & np.isclose(y[1:], y1)
        if np.any(hit):
            return True
    return False


def marker_colour(ax, x, y):
    """Colour of the marker drawn at (x, y)."""
    for ln in ax.get_lines():
        if ln.get_linestyle() in ("None", "none", ""):
            xs, ys = np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float)
            if np.any(np.isclose(xs, x) & np.isclose(ys, y)):
                return colour_of(ln)
    raise AssertionError(f"no marker at {(x, y)}")


def test_campbell_curves_break_at_whirl_changes_and_near_crossings():
    res = campbell_result()
    br = campbell_breaks(res)
    assert br[4, 0] and not br[3, 0] and not br[5, 0]  # slot 0: forward up to speed 4, backward from 5
    assert br[7, 1] and br[8, 1] and br[7, 2] and br[8, 2]  # slots 1, 2 touch at speed 8
    ax = plot_campbell(res)
    rpm = res.speeds * 30 / np.pi
    F = res.frequencies
    assert joined(ax, rpm[3], rpm[4], F[3, 0], F[4, 0])
    assert not joined(ax, rpm[4], rpm[5], F[4, 0], F[5, 0])
    assert not joined(ax, rpm[7], rpm[8], F[7, 1], F[8, 1])
    assert not joined(ax, rpm[8], rpm[9], F[8, 2], F[9, 2])
    # the points on either side of the change carry their whirl's colour
    assert marker_colour(ax, rpm[4], F[4, 0]) == to_rgba("C0")  # forward
    assert marker_colour(ax, rpm[5], F[5, 0]) == to_rgba("C3")  # backward


def test_campbell_draws_stability_and_counts_critical_speeds():
    ax = plot_campbell(campbell_result())
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(t.startswith("unstable (ζ < 0)") and "(2 points)" in t for t in texts)
    assert any(t.startswith("stable (ζ ≥ 0)") for t in texts)
    assert "critical speeds (1)" in texts
    rpm = campbell_result().speeds * 30 / np.pi
    F = campbell_result().frequencies
    open_ = [ln for ln in ax.get_lines() if ln.get_markerfacecolor() == "none" and ln.get_marker() == "o"]
    assert open_ and np.allclose(np.sort(open_[0].get_xdata()), rpm[9:])
    assert joined(ax, rpm[9], rpm[10], F[9, 2], F[10, 2])
    dashed = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
    assert dashed


def test_stability_codes_read_csv_strings_and_missing_values():
    codes = stability_codes(np.array(["True", "False", "", None, np.nan, True, 0], dtype=object))
    assert codes.tolist() == [1, 0, -1, -1, -1, 1, 0]
    assert stability_codes([True, True], known=[True, False]).tolist() == [1, -1]


def test_save_figure_records_its_caption(tmp_path):
    _, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    save_figure(ax.figure, tmp_path / "b.png", "Second   figure,\n one line.")
    save_figure(ax.figure, tmp_path / "a.png", "First figure.")
    assert (tmp_path / "a.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    captions = json.loads((tmp_path / "figures.json").read_text())
    assert list(captions) == ["a.png", "b.png"]
    assert captions["b.png"] == "Second figure, one line."
    assert not list(tmp_path.glob(".*"))  # no temporary files left


def test_index_page_lists_every_figure_with_its_caption_and_settings(tmp_path):
    from nlgrd.studies.index_page import record_settings
    from nlgrd.studies.reports import ROOT

    part = tmp_path / "models"
    part.mkdir()
    for name in ("x_campbell.png", "x_modes.png"):
        (part / name).write_bytes(b"\x89PNG")
    (part / "x_campbell.csv").write_text("a\n1\n")
    (part / "figures.json").write_text(json.dumps({"x_campbell.png": "Frequencies against speed."}))
    record_settings(part, {"mode": "fast"}, key="run")
    record_settings(part, {"harmonics H": 5, "mesh damping ratio": 0.005})
    page = index_html(tmp_path, fast=True, parts=("models",), root=ROOT)
    assert '<img src="models/x_campbell.png"' in page and '<img src="models/x_modes.png"' in page
    assert "Frequencies against speed." in page and NO_CAPTION in page
    assert '<a href="models/x_campbell.csv">' in page
    assert "<td>harmonics H</td><td>5</td>" in page and "<td>mesh damping ratio</td><td>0.005</td>" in page
    assert "built in fast mode" in page and "<td>nlgrd</td>" in page
    assert str(tmp_path) not in page
    assert page == index_html(tmp_path, fast=True, parts=("models",), root=ROOT)


def test_index_page_says_no_measured_curve_is_shipped_and_how_to_add_one(tmp_path):
    """Issue 36, item 5: the index names the loader and the format file, both of which exist."""
    import nlgrd.studies.experimental as experimental
    from nlgrd.studies.reports import ROOT

    page = index_html(tmp_path, fast=True, parts=(), root=ROOT)
    assert "Measured curves: none is shipped." in page
    assert "data/experimental/README.md" in page and "load_experimental" in page
    assert (ROOT / "data" / "experimental" / "README.md").is_file()
    assert callable(experimental.load_experimental)


def test_period_two_points_are_drawn_ringed_and_lost_points_marked_by_kind():
    """The response kinds a ``period="auto"`` sweep writes: a period-2 orbit is a response
    (drawn at its value, ringed, counted), a quasi-periodic point and one without a stable
    response are not (bottom-edge marks of their own, counted; their value is NaN as
    SweepResult.to_frame writes it)."""
    frame = sweep_frame(n=6)
    kinds = [
        "periodic",
        "period 2",
        "period 2",
        "quasi-periodic",
        "no stable mesh-periodic response",
        "periodic",
    ]
    frame["response"] = pd.array(kinds + ["periodic"] * 6, dtype="string")
    lost = frame.index[:6][[3, 4]]
    frame.loc[lost, Y] = np.nan
    ax = plot_sweep_frame(frame, X, Y, label="FE")
    (ring,) = by_label(ax, "FE up: period 2 (2)")
    assert ring.get_transform() == ax.transData
    np.testing.assert_allclose(ring.get_ydata(), frame.loc[[1, 2], Y])
    (quasi,) = by_label(ax, "FE up: quasi-periodic (1)")
    (none,) = by_label(ax, "FE up: no stable periodic response (1)")
    np.testing.assert_allclose(quasi.get_xdata(), frame.loc[[3], X])
    np.testing.assert_allclose(none.get_xdata(), frame.loc[[4], X])
    for mark in (quasi, none):
        assert mark.get_transform() != ax.transData
    assert not any("period 2" in ln.get_label() and "down" in ln.get_label() for ln in ax.get_lines())


def test_sweep_axis_is_in_the_unit_the_range_was_given_in_with_the_title():
    """Issue 36, item 3: ``--rpm`` drew mesh frequency [Hz]. With ``xaxis`` (label, value per
    mesh Hz) the points sit at the speeds the user gave: 600 Hz of a 20-tooth pinion is
    600 * 60 / 20 = 1800 rpm (exact arithmetic, so a 1e-12 tolerance)."""
    res = sweep_result()
    ax = plot_sweep(res, "dte_rms", xaxis=("pinion speed [rpm]", 60 / 20), title="kubo.toml")
    assert ax.get_xlabel() == "pinion speed [rpm]"
    assert ax.get_title() == "kubo.toml"
    (up,) = [ln for ln in ax.get_lines() if ln.get_label() == "up"]
    np.testing.assert_allclose(up.get_xdata(), res.omega[[0, 3, 4, 5]] / (2 * np.pi) * 3, rtol=1e-12)


@pytest.mark.parametrize(
    ("column", "label"),
    [
        ("base_frequency [Hz]", "base frequency [Hz]"),
        ("gear_pairs[0].damping_ratio [-]", "mesh damping ratio ζ [-]"),
        ("gear_pairs[1].geometry.backlash [m]", "mesh 2 backlash 2b [m]"),
        ("mesh1.dte_rms [um]", "mesh1: RMS of alternating DTE [µm]"),
        ("dte_rms [um]", "RMS of alternating DTE [µm]"),
    ],
)
def test_raw_column_names_become_readable_axis_labels(column, label):
    assert axis_label(column) == label


def test_no_figure_labels_an_axis_with_a_raw_column_name():
    """Sweep frames and study figures label their axes through axis_label: no underscore,
    no model-key path, no "um"."""
    ax = plot_sweep_frame(sweep_frame(), X, Y)
    summary = pd.DataFrame(
        {
            "gear_pairs[0].damping_ratio [-]": [0.01, 0.01, 0.05, 0.05],
            "gear_pairs[0].geometry.backlash [m]": [1e-4, 2e-4, 1e-4, 2e-4],
            "dte_rms_max [um]": [1.0, 2.0, 3.0, 4.0],
        }
    )
    maps = study_map(summary, "gear_pairs[0].damping_ratio [-]", "gear_pairs[0].geometry.backlash [m]",
                     "dte_rms_max [um]")  # fmt: skip
    curves = study_curves(summary, "gear_pairs[0].damping_ratio [-]", "dte_rms_max [um]",
                          "gear_pairs[0].geometry.backlash [m]")  # fmt: skip
    dist = study_distribution(summary, "dte_rms_max [um]")
    labels = [a.get_xlabel() for a in (ax, maps, curves, dist)] + [a.get_ylabel() for a in (ax, maps, curves)]
    labels += [t.get_text() for t in curves.get_legend().get_texts()]
    assert labels[0] == "base frequency [Hz]" and labels[1] == "mesh damping ratio ζ [-]"
    for text in labels:
        assert "_" not in text and "[um]" not in text and "gear_pairs" not in text, text


def _extent(artist, fig):
    return artist.get_window_extent(fig.canvas.get_renderer())


def test_a_long_legend_goes_outside_the_axes_and_a_short_one_stays_inside():
    """Issue 36, item 6: legends of 17-21 entries covered the curves. Five series of up and
    down sweeps with unstable and unknown points give more than LEGEND_INSIDE entries: the
    legend's box must not overlap the axes' box (renderer extents, in pixels)."""
    ax = None
    for k in range(5):
        ax = plot_sweep(sweep_result(), ax=ax, label=f"s{k}", series=k)
    fig = ax.figure
    fig.tight_layout()
    legend = ax.get_legend()
    assert len(legend.get_texts()) > LEGEND_INSIDE
    assert _extent(legend, fig).x0 >= _extent(ax, fig).x1 - 1e-6
    assert _extent(legend, fig).x1 <= fig.bbox.x1 + 1  # and within the figure
    # the figure grew by the legend's width: the axes keep more than half of the
    # default 6.4 in (fig. 6 of notebook 01 had its axes squeezed to a third)
    assert fig.get_figwidth() > 6.4 and _extent(ax, fig).width / fig.dpi > 0.5 * 6.4
    _, ax2 = plt.subplots()
    plot_sweep_frame(sweep_frame(), X, Y, ax=ax2)
    place_legend(ax2)
    ax2.figure.canvas.draw()
    assert _extent(ax2, ax2.figure).contains(*_extent(ax2.get_legend(), ax2.figure).p0)


def test_campbell_order_labels_stay_inside_the_axes():
    """Issue 36, item 6: the order labels were written at the last speed, right of the axes,
    or above it where an order line leaves through the top. Every label's extent must lie
    within the axes' extent (1 px of slack for rounding of the text box)."""
    res = campbell_result()
    res.orders = {"1x": 1.0, "2x": 2.0, "0.5x": 0.5, "10x": 10.0}
    ax = plot_campbell(res)
    fig = ax.figure
    fig.canvas.draw()
    box = _extent(ax, fig)
    names = [t for t in ax.texts if t.get_text() in res.orders]
    assert len(names) == 4
    for t in names:
        e = _extent(t, fig)
        assert box.x0 - 1 <= e.x0 and e.x1 <= box.x1 + 1 and box.y0 - 1 <= e.y0 and e.y1 <= box.y1 + 1, (
            t.get_text()
        )


def test_the_note_that_no_measurement_is_shipped_is_a_legend_entry_on_the_figure():
    _, ax = plt.subplots()
    note_no_measurement(ax)
    ax = plot_sweep(sweep_result(), ax=ax)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert texts[0] == NO_MEASUREMENT_TEXT and "no measured curve shipped" in texts[0]


def test_a_short_legend_that_would_cover_points_goes_outside():
    """Issue 36, item 6: K&B Fig. 8 (fast run) had a 6-entry legend over two sweep points.
    Points on a 30 x 30 grid fill the axes, so no inside place is free: the legend goes to
    the right of the axes (renderer extents, in pixels)."""
    _, ax = plt.subplots()
    g = np.linspace(0.0, 1.0, 30)
    xx, yy = np.meshgrid(g, g)
    ax.plot(xx.ravel(), yy.ravel(), ".", ls="none", label="points")
    legend = place_legend(ax)
    ax.figure.tight_layout()
    ax.figure.canvas.draw()
    assert len(legend.get_texts()) == 1
    assert _extent(legend, ax.figure).x0 >= _extent(ax, ax.figure).x1 - 1e-6


# Issue 35, item 4: every figure of the answered sweeps legible (the reports and `nlgrd sweep`
# share these helpers). The first test looks at pixels: whether a marker can be seen is a
# property of the rendered image, not of one artist.

UP_RGB, DOWN_RGB = (to_rgba(c)[:3] for c in SERIES_COLOURS[0])


def answered_frame(kinds, ms_y=1.0):
    """Up and down rows at the same speeds, one per kind, with the same value in both
    directions (the coincidence a report shows where both sweeps reach the same attractor).
    Torus rows carry the verdict "not computed", as SweepResult.to_frame writes it."""
    f = 1000.0 + 100.0 * np.arange(len(kinds))
    rows = []
    for d in ("up", "down"):
        for x, kind in zip(f, kinds, strict=True):
            torus = kind == "torus"
            rows.append(
                {X: x, "direction": d, "converged": True, "stable": pd.NA, "floquet_max [-]": np.nan,
                 Y: ms_y + x / 1000, "response": "quasi-periodic" if torus else kind,
                 "verdict": "not computed" if torus else "unstable"}
            )  # fmt: skip
    return pd.DataFrame(rows)


def colour_pixels(fig, ax, x, y, rgb, half=25, tol=0.12):
    """Pixels within ``half`` px of the data point (x, y) whose colour is within ``tol`` of
    ``rgb`` in every channel (antialiased edges blend with white, so they do not count)."""
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba(), dtype=float)[..., :3] / 255
    px, py = ax.transData.transform((x, y))
    row, col = int(round(img.shape[0] - py)), int(round(px))
    patch = img[max(row - half, 0) : row + half, max(col - half, 0) : col + half]
    return int(np.all(np.abs(patch - np.asarray(rgb)) < tol, axis=-1).sum())


@pytest.mark.parametrize("kind", ["time domain", "chaotic", "torus"])
def test_up_and_down_answers_at_one_speed_are_both_visible(kind):
    """Issue 35, item 4: where the up and down sweeps are answered at the same speed with the
    same value, the down marker used to be drawn over the up one, the same open shape: the
    up answer disappeared. Now the up marker is open and large, the down one filled, smaller
    and above it: at the point the rendered image must show both colours, each over at least
    15 px (the up outline of a 1.4 x 10 pt diamond at 100 dpi is ~80 px; a hidden one leaves
    only antialiased fringes, which the colour tolerance excludes). A point where only the
    down answer lies must show no up colour (the check can fail)."""
    frame = answered_frame([kind, kind])
    frame = frame[~((frame["direction"] == "up") & (frame[X] == 1100.0))]  # down alone at 1100 Hz
    fig, ax = plt.subplots(figsize=(4, 3), dpi=100)
    plot_sweep_frame(frame, X, Y, ax=ax, label="FE", ms=10)
    ax.set_xlim(900, 1200)
    ax.set_ylim(1.8, 2.3)
    assert colour_pixels(fig, ax, 1000.0, 2.0, UP_RGB) >= 15
    assert colour_pixels(fig, ax, 1000.0, 2.0, DOWN_RGB) >= 15
    assert colour_pixels(fig, ax, 1100.0, 2.1, UP_RGB) == 0
    assert colour_pixels(fig, ax, 1100.0, 2.1, DOWN_RGB) >= 15


def test_period_two_rings_of_up_and_down_are_concentric():
    """Up and down period-2 rings at one speed: the up ring is the larger, so that the down
    ring (drawn on top) lies inside it instead of over it; both open (the orbit's marker
    shows through)."""
    frame = sweep_frame(n=4)
    frame["response"] = "period 2"
    ax = plot_sweep_frame(frame, X, Y, label="FE")
    (up,) = by_label(ax, "FE up: period 2 (4)")
    (down,) = by_label(ax, "FE down: period 2 (4)")
    assert up.get_markersize() > down.get_markersize() + 1.0  # pt: the down ring clear inside
    assert up.get_markerfacecolor() == "none" and down.get_markerfacecolor() == "none"


def test_chaotic_stars_are_larger_than_the_other_answers():
    """Issue 35, item 4: the chaotic stars read too small at the default size (1.3 ms, as the
    diamonds); a star's ink is thin, so it is drawn at 1.8 x the marker size of the stable
    points, the up star (the open, outer one) at exactly that size."""
    frame = answered_frame(["chaotic", "time domain"])
    for ms in (3.5, 5.0):
        _, ax = plt.subplots()
        plot_sweep_frame(frame, X, Y, ax=ax, label="FE", ms=ms)
        bars = {c.get_label(): c[0] for c in ax.containers}  # error bars: (data line, caps, bars)
        star, diamond = bars["FE up: chaotic (1; ±2σ)"], bars["FE up: time domain (1; ±2σ)"]
        assert star.get_marker() == "*" and diamond.get_marker() == "D"
        assert star.get_markersize() == pytest.approx(1.8 * ms)
        assert star.get_markersize() > diamond.get_markersize()


def test_a_legend_names_only_the_kinds_drawn_with_their_counts():
    """Issue 35, item 4: Kubo's fig5b listed "up: period-2 orbits" where no period-2 orbit
    was drawn. place_legend leaves out every artist without a finite point (keeping the
    text-only note that no measurement is shipped); plot_counted draws nothing for an empty
    kind and counts the points it draws; a period-2 kind wholly beyond the scale gets no
    ring entry (its carets say it)."""
    _, ax = plt.subplots()
    note_no_measurement(ax)
    ax.plot([], [], "^", label="up: period-2 orbits")  # what the notebook drew
    ax.plot([np.nan], [np.nan], "v", label="down: nothing finite")
    assert plot_counted(ax, [1.0, 2.0], [np.nan, np.nan], "^", "up: empty") is None
    plot_counted(ax, [1.0, 2.0, 3.0], [1.0, np.nan, 3.0], "v", "down: period-2 orbits")
    texts = [t.get_text() for t in place_legend(ax).get_texts()]
    assert texts == [NO_MEASUREMENT_TEXT, "down: period-2 orbits (2)"]
    assert drawn_entries(ax)[1] == texts
    frame = sweep_frame(n=4)
    frame["response"] = "period 2"
    ax = plot_sweep_frame(frame, X, Y, label="FE", ylim=(0, 1))  # every value above 1
    labels = [ln.get_label() for ln in ax.get_lines()]
    assert not any("period 2" in t for t in labels)
    assert any("above the scale" in t for t in labels)


def test_legend_lists_error_bar_kinds_in_drawing_order():
    """matplotlib lists error-bar containers after every line, so the time answers' entries
    came after the landmarks drawn later (fig5 of notebook 01): the legend follows the order
    in which the kinds were drawn."""
    ax = plot_sweep_frame(answered_frame(["time domain"]), X, Y, label="FE")
    ax.axvline(1000.0, label="gear-pair mode")
    texts = drawn_entries(ax)[1]
    assert texts.index("FE up: time domain (1; ±2σ)") < texts.index("gear-pair mode")
    assert texts.index("FE down: time domain (1; ±2σ)") < texts.index("gear-pair mode")


def test_legend_markers_are_readable_while_the_curve_keeps_its_dots():
    """The damping-band figures draw their thin curves with 1.5 pt markers, unreadable as
    legend keys: the legend's copies are drawn at LEGEND_MARKER_MIN at least, the axes'
    markers keep their size."""
    ax = plot_sweep_frame(sweep_frame(), X, Y, label="thin", ms=1.5)
    legend = place_legend(ax)
    sizes = [h.get_markersize() for h in legend.legend_handles if h.get_marker() not in ("", "None", None)]
    assert sizes and min(sizes) >= LEGEND_MARKER_MIN
    assert {ln.get_markersize() for ln in by_label(ax, "thin up")} == {1.5}


def test_outside_legends_of_stacked_panels_widen_the_figure_once():
    """A stacked figure (K&B's fig8 with the floor, two panels, each legend outside) was
    widened by every panel's legend: the axes shrank to make room for legends that share
    one column. The figure grows by the widest legend of the column only."""
    fig, axs = plt.subplots(2, 1, figsize=(6.0, 6.0))
    widths = []
    for k, ax in enumerate(axs):
        ax.plot([0, 1], [0, 1], "o-", label="a label of some length " + "x" * (10 * k))
        legend = place_legend(ax, inside=0)
        widths.append(legend.get_window_extent(fig.canvas.get_renderer()).width / fig.dpi)
    assert fig.get_figwidth() == pytest.approx(6.0 + max(widths) + 0.3, rel=1e-6)


def test_a_written_table_without_the_verdict_draws_its_torus_answers_apart(tmp_path):
    """The reports write their answered tables without the ``verdict`` column (dte_fe.csv,
    dslr_fe.csv). Read back and drawn, a quasi-periodic row with a value (a torus answer:
    an unanswered quasi-periodic row has none, docs/conventions.md) was drawn as a periodic
    point, joined to the lines. It must be a square of its own, counted, and on no line."""
    frame = answered_frame(["torus", "time domain"]).drop(columns="verdict")
    frame.to_csv(tmp_path / "t.csv", index=False)
    back = pd.read_csv(tmp_path / "t.csv")
    ax = plot_sweep_frame(back, X, Y, label="FE")
    (square,) = by_label(ax, "FE up: quasi-periodic (torus HB) (1)")
    assert square.get_marker() == "s" and list(square.get_xdata()) == [1000.0]
    joined = [ln for ln in data_lines(ax) if ln.get_linestyle() not in ("None", "none")]
    assert not any(np.isfinite(ln.get_ydata()).any() for ln in joined)  # no line: nothing periodic
    assert not any("stability not computed" in ln.get_label() for ln in ax.get_lines())


def test_a_legend_placed_before_the_first_draw_sees_the_data_where_it_is_drawn():
    """Kubo's fig5b (fast run) had its 8-entry legend over the curve: before the first draw
    matplotlib's axes still have their (0, 1) limits, so the data of a real sweep (speeds in
    rpm, DSLR 1-5) lay off the axes when place_legend asked whether the legend covers a
    point. Points filling the axes at such values, the legend must still leave the axes
    (renderer extents after the layout, in pixels)."""
    _, ax = plt.subplots()
    xx, yy = np.meshgrid(np.linspace(2000.0, 14000.0, 30), np.linspace(1.5, 4.5, 30))
    ax.plot(xx.ravel(), yy.ravel(), ".", ls="none", label="points")
    legend = place_legend(ax)
    ax.figure.tight_layout()
    ax.figure.canvas.draw()
    assert _extent(legend, ax.figure).x0 >= _extent(ax, ax.figure).x1 - 1e-6


def test_up_and_down_points_not_found_at_one_speed_both_show():
    """K&B's fig8 with the floor (fast run): the up and down sweeps' "not found" crosses at
    the same speeds lay on one another, the down's red over the up's blue, though the
    legend counted both. The down sweep's crosses lie a row (NC_ROW points) above; in the
    rendered image both colours show at that speed, each over at least 10 px (a 5 pt cross
    of 1.2 pt strokes at 100 dpi is ~40 px)."""
    frame = sweep_frame(n=4)
    frame["converged"] = [True, False, True, True, True, True, False, True]  # 333 Hz, both
    fig, ax = plt.subplots(figsize=(4, 3), dpi=100)
    plot_sweep_frame(frame, X, Y, ax=ax, label="FE", not_converged="not found")
    (up,) = by_label(ax, "FE up: not found (1)")
    (down,) = by_label(ax, "FE down: not found (1)")
    fig.canvas.draw()
    y_up, y_down = (ln.get_transform().transform((333.0, NC_HEIGHT))[1] for ln in (up, down))
    assert y_down - y_up == pytest.approx(NC_ROW * fig.dpi / 72)
    x_px = ax.transData.transform((frame.loc[1, X], 0.0))[0]
    img = np.asarray(fig.canvas.buffer_rgba(), dtype=float)[..., :3] / 255
    y_px = 0.5 * (y_up + y_down)
    patch = img[int(img.shape[0] - y_px) - 12 : int(img.shape[0] - y_px) + 12, int(x_px) - 8 : int(x_px) + 8]
    for rgb in (UP_RGB, DOWN_RGB):
        assert np.all(np.abs(patch - np.asarray(rgb)) < 0.12, axis=-1).sum() >= 10


@pytest.mark.parametrize("row", [0, 1])
def test_not_converged_marks_alone_set_the_speed_axis(row):
    """A sweep where no point converged draws only its crosses: the speed axis must span
    them in either row (the lifted row's transform hides the data branch from matplotlib's
    autoscaling; before the fix the axis stayed at (-0.05, 0.05), the crosses were drawn far
    outside it unclipped, and tight_layout refused the figure: the capability matrix's
    period-2 cells)."""
    fig, ax = plt.subplots()
    mark_not_converged(ax, [1000.0, 1050.0, 1100.0], "C0", "up", row=row)
    lo, hi = ax.get_xlim()
    assert lo <= 1000.0 and hi >= 1100.0 and hi - lo < 200.0
    plt.close(fig)


def test_error_bars_of_an_rms_stop_at_zero():
    """K&B's full report drew chaotic answers with ±2σ bars down to -7 µm of RMS DTE (an
    RMS cannot be negative; 2σ from a short record exceeds the value): the lower bar of a
    quantity that cannot be negative stops at zero, the upper one keeps 2σ. A signed
    quantity (the mean DTE) keeps both."""
    frame = answered_frame(["chaotic"])
    frame[Y] = 1.0
    frame["dte_rms_uncertainty [um]"] = 3.0
    ax = plot_sweep_frame(frame, X, Y, label="FE")
    segments = [seg for c in ax.collections for seg in c.get_segments()]
    assert segments and min(min(seg[:, 1]) for seg in segments) == 0.0
    assert max(max(seg[:, 1]) for seg in segments) == pytest.approx(7.0)
    signed = frame.rename(
        columns={Y: "dte_mean [um]", "dte_rms_uncertainty [um]": "dte_mean_uncertainty [um]"}
    )
    ax = plot_sweep_frame(signed, X, "dte_mean [um]", label="FE")
    segments = [seg for c in ax.collections for seg in c.get_segments()]
    assert min(min(seg[:, 1]) for seg in segments) == pytest.approx(-5.0)
