"""Issue 33 item 7: every ``nlgrd sweep`` option on every shipped model (data/models and
data/case_studies), at a small size (3 grid points, few harmonics, one direction, a range
inside each model's validity). Each cell either runs (exit 0, its files written) or is
refused in one line on stderr (exit 2) for a reason of physics listed in REFUSALS. A
refusal that exists only because of the code path is an ``xfail(strict=True)`` in
PATH_ONLY, so that it fails the day it is fixed and is then moved out of the table.

``--coexisting`` at this size finds no jump to search beside (3 points below the first
strong resonance): the cell checks the flow (the ``branch`` column, the bifurcations'
table, no refusal); the branches themselves: tests/test_coexisting_flow.py.

The numbers themselves are checked elsewhere (tests/test_cli*.py, tests/test_link_*.py,
tests/test_orbit_search.py ...); this is the coverage of options by models."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from nlgrd.cli import main

ROOT = Path(__file__).resolve().parent.parent

#: model file -> (range option, START:STOP:COUNT, mid speed, --harmonics, a --quantity other
#: than the default). Ranges below each model's first strong resonance (fast, converging
#: everywhere); two_stage at a tiny H (its base is 5 x the shaft speed, the meshes at base
#: harmonics 5 and 2).
MODELS = {
    "models/idler_train.toml": ("--hz", "400:500:3", "450", "5", "mesh1.force_max"),
    "models/rub_rotor.toml": ("--rpm", "2000:3000:3", "2500", "5", "rub.displacement_max"),
    "models/single_shaft.toml": ("--rpm", "2000:3000:3", "2500", "5", "dte_rms"),
    "models/two_shaft.toml": ("--hz", "3000:3200:3", "3100", "5", "force_max"),
    "models/two_shaft_clearance.toml": ("--rpm", "2000:3000:3", "2500", "5", "B1.force_max"),
    "models/two_stage.toml": ("--rpm", "2000:3000:3", "2500", "10", "mesh1.dslr"),
    "case_studies/kahraman_blankenship.toml": ("--hz", "400:500:3", "450", "5", "force_max"),
    "case_studies/kubo.toml": ("--hz", "3000:3200:3", "3100", "5", "force_max"),
}
#: --continuation spans where the one above costs minutes (many small steps: two_stage
#: 2000-3000 rpm > 2 min; two_shaft_clearance turns back near 2050 rpm at H = 5, 3 min).
CONTINUATION = {
    "models/two_stage.toml": "2000:2040:3",
    "models/two_shaft_clearance.toml": "2100:2140:3",
}


def _options(model: str) -> dict[str, list[str]]:
    _, _, mid, _, quantity = MODELS[model]
    return {
        "plain": [],
        "continuation": ["--continuation"],
        "period 1": ["--period", "1"],
        "period 2": ["--period", "2"],
        "quantity": ["--quantity", quantity],
        "search-at": ["--search-at", mid, "--search-periods", "1"],
        "period 3": ["--period", "3", "--search-at", mid],
        "no-stability": ["--no-stability"],
        "coexisting": ["--coexisting"],
    }


OPTIONS = list(_options(next(iter(MODELS))))

#: (model, option or "*") -> what the one-line refusal says, and why it is physics.
REFUSALS = {
    # a linear rotor (no mesh, no clearance): nothing nonlinear to solve; its response is
    # `nlgrd unbalance` / `modes` / `campbell`
    ("models/single_shaft.toml", "*"): "the model has no gear pair and no clearance",
}

#: (model, option) -> why the refusal is only the code path's (xfail, strict). None left:
#: ``--period N >= 3`` on link models came last (tests/test_cli_period_n.py).
PATH_ONLY: dict[tuple[str, str], str] = {}


#: option -> the one line of exit 1 when the range holds no orbit of that period (a
#: result: the period-2 branches exist only beyond a period doubling; period 3 is searched)
NONE_THERE = {
    "period 2": "no period-2 orbit in the range",
    "period 3": "no period-3 orbit found",
}


def _cells():
    for model in MODELS:
        for option in OPTIONS:
            marks = []
            if (model, option) in PATH_ONLY:
                marks = [pytest.mark.xfail(strict=True, reason=PATH_ONLY[model, option])]
            yield pytest.param(model, option, marks=marks, id=f"{Path(model).stem}-{option.replace(' ', '')}")


def _refusal(model: str, option: str) -> str | None:
    return REFUSALS.get((model, option), REFUSALS.get((model, "*")))


@pytest.mark.parametrize(("model", "option"), list(_cells()))
def test_every_sweep_option_on_every_shipped_model(model, option, tmp_path, capsys):
    """The option runs (exit 0: the CSV and PNG written, and the orbit tables with
    --search-at), finds no orbit of the period asked for (exit 1, the one line of
    NONE_THERE: a result, not a refusal), or
    is refused in one line for the reason listed in REFUSALS."""
    unit, span, _, harmonics, _ = MODELS[model]
    if option == "continuation":
        span = CONTINUATION.get(model, span)
    out = tmp_path / "s.csv"
    argv = ["sweep", str(ROOT / "data" / model), unit, span, "--harmonics", harmonics, "--direction", "up"]
    status = main([*argv, *_options(model)[option], "--out", str(out)])
    err = [line for line in capsys.readouterr().err.splitlines() if line.startswith("nlgrd:")]
    reason = _refusal(model, option)
    if reason is not None:
        assert status == 2 and len(err) == 1 and reason in err[0], (status, err)
        return
    if status == 1 and option in NONE_THERE:  # no orbit of that period in the range
        assert len(err) == 1 and NONE_THERE[option] in err[0], err
        return
    assert status == 0, err
    assert out.stat().st_size > 0 and out.with_suffix(".png").stat().st_size > 0
    if option in ("search-at", "period 3"):
        for name in ("orbits", "branches"):
            assert (tmp_path / f"s_{name}.csv").exists()
    if option == "search-at":
        _check_search(out, tmp_path / "s_orbits.csv")
    if option == "coexisting":  # the branches' rows (none without a jump) and bifurcations
        assert "branch" in pd.read_csv(out).columns and (tmp_path / "s_bifurcations.csv").exists()


def _check_search(sweep_csv: Path, orbits_csv: Path) -> None:
    """The search at a grid speed where the sweep is stable and periodic finds the sweep's
    orbit again, from its own starts (two procedures, one orbit): a stable row flagged "on
    the sweep" whose written outputs equal the sweep's at that speed. 1e-6 of the value or
    of the largest output in its unit: the flag's own criterion; both are Newton solutions to
    1e-10 of the same equations."""
    sweep, orbits = pd.read_csv(sweep_csv), pd.read_csv(orbits_csv)
    freq = "base_frequency [Hz]"
    mine = orbits[orbits["on the sweep"].astype(bool)]
    assert len(mine) >= 1 and mine["stable"].astype(bool).all(), orbits
    skip = {freq, "period", "stable", "floquet_max [-]", "pinion_speed [rpm]", "shaft_speed [rpm]"}
    outputs = [c for c in orbits.columns if c in sweep.columns and c not in skip]
    assert outputs, (list(orbits.columns), list(sweep.columns))
    for _, o in mine.iterrows():
        at = sweep[np.isclose(sweep[freq], o[freq], rtol=1e-9) & (sweep["period"] == o["period"])]
        assert len(at) >= 1
        a, b = at[outputs].iloc[0].to_numpy(float), o[outputs].to_numpy(float)
        # atol: 1e-6 of the largest output in the column's unit, the rounding of a bearing the
        # mesh does not load (1e-66 to 1e-8 N beside 1e3 N on Kubo's rig) being no output
        units = np.array([c.rsplit("[", 1)[-1] for c in outputs])
        scale = np.array([np.max(np.abs(a[units == u])) for u in units])
        np.testing.assert_array_less(np.abs(a - b), 1e-6 * scale + 1e-300)  # + 1e-300: 0 against 0
