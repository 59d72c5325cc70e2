"""Issue 33 item 7, "one sweep flow for every model": ``nlgrd sweep`` writes and summarises a
sweep of one gear pair (its mesh coordinate) and of a link model (a bearing clearance) by
one path (:mod:`nlgrd.cli.sweep`), and the period-ν models of the orbit search are built
once (:class:`nlgrd.nonlinear.models.model_views.LinkView`).

The numbers are checked elsewhere (tests/test_cli*.py, tests/test_capability_matrix.py);
these are checks of the flow: the same summary on both, the speeds as typed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from nlgrd.cli import main

ROOT = Path(__file__).resolve().parent.parent
#: model -> (range option, range, the speed column of the CSV); 3 points each, H = 5,
#: below the first strong resonance (tests/test_capability_matrix.py's ranges): about 1 s.
CASES = {
    "two_shaft": ("--rpm", "1800:2000:3", "shaft_speed [rpm]"),
    "two_shaft_clearance": ("--rpm", "2000:3000:3", "shaft_speed [rpm]"),
}
#: The summary's first line: the same fields on every model, in this order.
FIELDS = (
    "points (up)",
    "H = 5",
    "not converged",
    "without a stable periodic response",
    "answered by the torus harmonic balance",
    "answered in the time domain",
)


@pytest.mark.parametrize("name", list(CASES))
def test_one_summary_and_the_typed_speeds_on_every_model(name, tmp_path, capsys):
    """One summary for both kinds of model: its first line has every field of FIELDS in
    order (the one-mesh line had only the first three before the two paths were merged);
    the CSV's speed column is the typed grid exactly (snapped; rtol 0)."""
    option, span, column = CASES[name]
    out = tmp_path / "s.csv"
    argv = ["sweep", str(ROOT / "data" / "models" / f"{name}.toml"), option, span]
    assert main([*argv, "--harmonics", "5", "--direction", "up", "--out", str(out)]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    at = [first.find(f) for f in FIELDS]
    assert min(at) >= 0 and at == sorted(at), first
    df = pd.read_csv(out)
    np.testing.assert_array_equal(
        df[column].to_numpy(), [2000.0, 2500.0, 3000.0] if "clearance" in name else [1800.0, 1900.0, 2000.0]
    )


def test_period_models_are_built_once():
    """LinkView.period: the view's own model for period 1 (no rebuild); another period is
    built once (the same object on the second call, from the model's cache), on the base
    ω/ν with the mesh at ν times its harmonic (the shaft speed per base ν times the model's)."""
    from nlgrd import load
    from nlgrd.analyses import model as link_model
    from nlgrd.nonlinear.models.model_views import LinkView

    model = link_model(load(ROOT / "data" / "models" / "two_shaft.toml"))
    view = LinkView(model, None)
    assert view.period(1) is model
    two = view.period(2)
    assert view.period(2) is two and two.period == 2 and two.links[0].order == 2 * model.links[0].order
    assert two.receptance.plan.speed_per_base == 2 * model.receptance.plan.speed_per_base


def test_an_orbit_is_on_the_sweep_to_the_scale_of_its_unit():
    """``same_outputs`` (the "on the sweep" flag of a link model): the unloaded bearing's
    rounding (Kubo's stub bearings: force_mean 1e-66 N beside 1e3 N, BLAS-dependent) is no
    difference; a change of 1e-5 of the largest force in any force column is, and so is a
    change of 1e-5 of a dimensionless output. Sweep row: Kubo at 3100 Hz, H = 5, rounded."""
    from nlgrd.nonlinear.models.model_views import same_outputs

    sweep = {
        "mesh0.dte_rms [m]": 3.342128e-06,
        "mesh0.force_max [N]": 3.226900e03,
        "mesh0.dslr [-]": 1.406053,
        "mesh0.contact_loss_fraction [-]": 0.0,
        "mesh0.back_contact": False,
        "bearing 0.force_mean [N]": 1.147503e03,
        "bearing 4.force_mean [N]": 9.272896e-67,
        "bearing 4.force_max [N]": 4.441572e-08,
        "bearing 4.displacement_max [m]": 4.441572e-17,
    }
    rounding = dict(sweep)
    rounding["bearing 4.force_mean [N]"] = 1.090370e-66  # the search's own orbit
    rounding["bearing 4.force_max [N]"] = 3.967392e-08
    rounding["bearing 4.displacement_max [m]"] = 3.967392e-16
    assert same_outputs(sweep, rounding)
    # the comparison before (each column to 1e-6 of itself) fails on the rounding alone
    assert not all(np.isclose(sweep[k], v, rtol=1e-6, atol=0) for k, v in rounding.items())
    for key, step in (
        ("bearing 4.force_max [N]", 1e-5 * 3.2269e03),
        ("bearing 0.force_mean [N]", 1e-5 * 3.2269e03),
        ("mesh0.contact_loss_fraction [-]", 1e-5 * 1.406053),
        ("mesh0.dte_rms [m]", 1e-5 * 3.342128e-06),
    ):
        other = dict(sweep)
        other[key] = sweep[key] + step
        assert not same_outputs(sweep, other), key
    assert not same_outputs(sweep, {**sweep, "mesh0.back_contact": True})
