"""The command line: outputs of `modes` and `campbell`, and one-line errors (exit 2)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from nlgrd.cli import main

ROOT = Path(__file__).resolve().parent.parent
TWO_SHAFT = ROOT / "data" / "models" / "two_shaft.toml"

GOOD_HEAD = """version = 1
[[shafts]]
name = "s"
[[shafts.elements]]
count = 4
length = 0.1
outer_diameter = 0.05
"""

BAD = {
    "missing field": ("version = 1\n[[shafts]]\n[[shafts.elements]]\nlength = 0.1\n", "outer_diameter"),
    "unknown key": (GOOD_HEAD + "colour = 1\n", "colour"),
    "wrong type": (GOOD_HEAD.replace("0.05", '"thick"'), "outer_diameter"),
    "negative diameter": (GOOD_HEAD.replace("0.05", "-0.05"), "outer_diameter"),
    "inner >= outer": (GOOD_HEAD + "inner_diameter = 0.06\n", "inner_diameter"),
    "negative mass": (
        GOOD_HEAD
        + "[[disks]]\nshaft = 0\nnode = 1\nmass = -1.0\ndiametral_inertia = 0.1\npolar_inertia = 0.1\n",
        "mass",
    ),
    "nan": (GOOD_HEAD.replace("0.05", "nan"), "outer_diameter"),
    "node out of range": (GOOD_HEAD + "[[bearings]]\nshaft = 0\nnode = 9\nkyy = 1e8\n", "node"),
    "bearing not finite": (GOOD_HEAD + "[[bearings]]\nshaft = 0\nnode = 0\nkyz = inf\n", "kyz"),
    "toml syntax": (GOOD_HEAD + "[[bearings\n", "line"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_prints_one_line_and_exits_2(case, tmp_path, capsys):
    """Every bad-input case: exit status 2, one line on stderr naming file and key."""
    text, key = BAD[case]
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["modes", str(path), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert err.startswith("nlgrd: error:") and "bad.toml" in err and key in err, err


def test_no_traceback_from_the_installed_command(tmp_path):
    """The real process: exit 2, no 'Traceback' on stderr."""
    path = tmp_path / "bad.toml"
    path.write_text(GOOD_HEAD.replace("0.05", "-1"))
    proc = subprocess.run(
        [sys.executable, "-m", "nlgrd.cli", "modes", str(path)], capture_output=True, text=True, cwd=tmp_path
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1


def test_the_console_script_is_the_command():
    """pyproject's ``nlgrd`` script names the ``main`` that ``python -m nlgrd.cli`` runs."""
    import importlib
    import tomllib

    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    module, _, name = scripts["nlgrd"].partition(":")
    assert getattr(importlib.import_module(module), name) is main
    assert "main()" in (ROOT / "nlgrd" / "cli" / "__main__.py").read_text()


def test_bad_range_is_one_line(capsys, tmp_path):
    """A malformed --rpm range is a one-line error too."""
    assert main(["campbell", str(TWO_SHAFT), "--rpm", "0:10", "--out", str(tmp_path)]) == 2
    assert "--rpm" in capsys.readouterr().err


def test_modes_writes_table_csv_and_png(tmp_path, capsys):
    """`nlgrd modes` prints a table and writes CSV and PNG; CSV frequencies ascending."""
    assert main(["modes", str(TWO_SHAFT), "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "natural_frequency [Hz]" in out and "DOFs" in out
    df = pd.read_csv(tmp_path / "two_shaft_modes.csv")
    assert (df["damped_frequency [Hz]"].diff().dropna() >= 0).all()
    assert (tmp_path / "two_shaft_modes.png").stat().st_size > 10_000


@pytest.mark.slow
def test_campbell_writes_outputs(tmp_path):
    """`nlgrd campbell` writes the diagram, its CSV and the critical speeds."""
    assert main(["campbell", str(TWO_SHAFT), "--rpm", "0:20000:21", "--out", str(tmp_path)]) == 0
    df = pd.read_csv(tmp_path / "two_shaft_campbell.csv")
    assert df["speed [rpm]"].nunique() == 21
    crit = pd.read_csv(tmp_path / "two_shaft_critical_speeds.csv")
    assert len(crit) >= 1 and (tmp_path / "two_shaft_campbell.png").exists()


def test_lste_writes_csv_and_png(tmp_path, capsys):
    """`nlgrd lste` on the geared example: CSV with the LSTE and a PNG; summary printed."""
    assert main(["lste", str(TWO_SHAFT), "--out", str(tmp_path)]) == 0
    assert "mean mesh stiffness" in capsys.readouterr().out
    df = pd.read_csv(tmp_path / "two_shaft_lste.csv")
    assert len(df) >= 64 and any("lste" in c for c in df.columns)
    assert (tmp_path / "two_shaft_lste.png").stat().st_size > 10_000


def test_lste_without_gear_pair_is_one_line(capsys, tmp_path):
    """A model without gear pairs: one-line error, exit 2."""
    single = ROOT / "data" / "models" / "single_shaft.toml"
    assert main(["lste", str(single), "--out", str(tmp_path)]) == 2
    assert "gear_pairs" in capsys.readouterr().err


KUBO = ROOT / "data" / "case_studies" / "kubo.toml"


def test_sweep_writes_csv_png_and_summary(tmp_path, capsys):
    """`nlgrd sweep`: CSV with up and down points, PNG, summary with the converged count."""
    out = tmp_path / "kubo.csv"
    argv = ["sweep", str(KUBO), "--rpm", "9000:12000:7", "--no-stability", "--out", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "0 not converged" in text
    df = pd.read_csv(out)
    assert sorted(df["direction"].unique()) == ["down", "up"] and len(df) == 14
    assert {"shaft_speed [rpm]", "mesh0.dslr [-]", "mesh0.dte_rms [um]"} <= set(df.columns)
    assert out.with_suffix(".png").exists()


def test_sweep_period_auto_and_one(tmp_path, capsys):
    """`--period auto` (the default) writes each point's period, its ω/2 content and the
    secondary frequency of a torus, and lists the bifurcations with their kind; `--period
    1` leaves the flip-unstable point without a response (Kubo's rig down from 14 100 rpm,
    H = 13: tests/test_beyond_period_one.py checks these points)."""
    common = ["sweep", str(KUBO), "--rpm", "9700:14100:45", "--direction", "down", "--harmonics", "13"]
    common.append(
        "--no-time-domain"
    )  # the gaps as the harmonic balance leaves them (tests/test_time_answer.py)
    out = tmp_path / "auto.csv"
    assert main([*common, "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "period doubling (down): 9900.0 -> 9800.0 rpm, periodic -> period 2" in text
    assert (
        "Neimark-Sacker (down): 14100.0 -> 14000.0 rpm" in text
        and "period 2 (period doubled) at rpm: 9800.0" in text
    )
    df = pd.read_csv(out).round({"shaft_speed [rpm]": 6}).set_index("shaft_speed [rpm]")
    assert df.loc[9800.0, "period"] == 2 and df.loc[9800.0, "subharmonic_amplitude [um]"] > 1
    assert df.loc[9900.0, "period"] == 1 and df.loc[9900.0, "subharmonic_amplitude [um]"] == 0
    assert df.loc[14000.0, "response"] == "quasi-periodic" and df.loc[14000.0, "secondary_frequency [Hz]"] > 0
    assert np.isnan(df.loc[14000.0, "mesh0.dte_rms [um]"]) and np.isnan(
        df.loc[9900.0, "secondary_frequency [Hz]"]
    )
    one = tmp_path / "one.csv"
    assert main([*common, "--period", "1", "--out", str(one)]) == 0
    df1 = pd.read_csv(one).round({"shaft_speed [rpm]": 6}).set_index("shaft_speed [rpm]")
    assert df1.loc[9800.0, "response"] == "no stable mesh-periodic response" and np.isnan(
        df1.loc[9800.0, "period"]
    )
    assert (df1["period"].dropna() == 1).all()


@pytest.mark.slow  # a 3-point FE sweep, the search for periods 1 and 2 and a period-2 branch: about 30 s
def test_sweep_search_at_writes_the_orbits_the_sweep_does_not_reach(tmp_path, capsys):
    """`--search-at`: at 9800 rpm a down sweep started at 9900 rpm is on the branch without
    contact loss; the search finds that orbit (marked as the sweep's), the flip-unstable
    contact-loss orbit and the stable period-2 orbit of tests/test_period_doubling_fe.py's
    kind, which it follows and draws; the CSVs say which is which."""
    out = tmp_path / "s.csv"
    argv = ["sweep", str(KUBO), "--rpm", "9700:9900:3", "--direction", "down", "--harmonics", "13"]
    assert main([*argv, "--search-at", "9800", "--search-periods", "1,2", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "orbit at 9800.0 rpm: period 2, stable" in text and "(the sweep's)" in text
    orbits = pd.read_csv(tmp_path / "s_orbits.csv")
    mine = orbits[orbits["on the sweep"]]
    assert len(mine) == 1 and mine["period"].iloc[0] == 1 and mine["stable"].iloc[0]
    sweep = pd.read_csv(out).round({"shaft_speed [rpm]": 6}).set_index("shaft_speed [rpm]")
    assert mine["mesh0.dte_rms [um]"].iloc[0] == pytest.approx(
        sweep.loc[9800.0, "mesh0.dte_rms [um]"], rel=1e-6
    )
    two = orbits[(orbits["period"] == 2) & orbits["stable"]]
    assert len(two) == 1 and not two["on the sweep"].iloc[0]
    assert (orbits.loc[~orbits["stable"], "floquet_max [-]"] > 1).all()
    branches = pd.read_csv(tmp_path / "s_branches.csv")
    at = branches[branches["converged"] & np.isclose(branches["shaft_speed [rpm]"], 9800.0)]
    assert set(at["response"]) == {"period 2"} and set(branches["branch"]) == {"period 2 from 9800.0 rpm"}
    assert at["mesh0.dte_rms [um]"].iloc[0] == pytest.approx(two["mesh0.dte_rms [um]"].iloc[0], rel=1e-9)
    assert (tmp_path / "s.png").stat().st_size > 0


@pytest.mark.parametrize(
    "argv, key",
    [
        (["--rpm", "0:1000:5"], "--rpm"),
        (["--rpm", "1000:2000:5", "--harmonics", "0"], "--harmonics"),
        (["--hz", "a:b:c"], "--hz"),
        ([], "--rpm"),
        (["--rpm", "1000:2000:5", "--search-at", "2500"], "--search-at"),
        (["--rpm", "1000:2000:5", "--search-at", "1500,x"], "--search-at"),
        (["--rpm", "1000:2000:5", "--search-at", "1500", "--search-periods", "0,2"], "--search-periods"),
        (["--rpm", "1000:2000:5", "--search-at", "1500", "--search-periods", "1.5"], "--search-periods"),
        (["--rpm", "1000:2000", "--continuation", "--search-at", "1500"], "--search-at"),
    ],
)
def test_sweep_bad_options_are_one_line(argv, key, tmp_path, capsys):
    """Bad ranges and harmonics: exit 2 and one line naming the option."""
    assert main(["sweep", str(KUBO), "--out", str(tmp_path / "x.csv"), *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and key in err, err
