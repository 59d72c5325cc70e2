"""One H in every output (issue 36, item 1; docs/conventions.md, "H, the number of
harmonics"): H counts the harmonics of the sweep's base frequency, and a period-2 orbit,
solved with 2 H harmonics of ω/2, is still reported as H. The CSV's ``H`` column,
``SweepResult.H``, the command's summary line and the figure's title must say the same H,
on one gear pair and on a link model; the largest estimated harmonic error is over the
accepted points only.

Before this, a sweep with a period-2 point had ``SweepResult.H`` = 2 H (notebook 01's
legends and the report index said 34 where the CSV said 17), and the link sweep's title
said "H = 18" for ``--harmonics 9``: each test below fails on that code.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402
from test_link_period_doubling import MODEL as DRIVE  # noqa: E402

import nlgrd.cli.sweep as cli_sweep  # noqa: E402
from nlgrd.cli import main  # noqa: E402
from nlgrd.io.command_line import Outputs, harmonics_line  # noqa: E402
from nlgrd.nonlinear.results.sweep_results import SweepResult  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
#: Kubo's down sweep from 14 500 rpm lands on the stable period-2 orbit at 9800 rpm
#: (tests/test_beyond_period_one.py, H = 13): 111 points, about 4 s
KUBO_DOWN = ["--rpm", "9000:14500:111", "--direction", "down", "--harmonics", "13"]


@pytest.fixture
def captured(monkeypatch):
    """The figure titles the command stages and the result it writes (the same run)."""
    seen = {"titles": [], "results": []}
    figure, write = Outputs.figure, cli_sweep._write_sweep

    def staged(self, fig, path):
        seen["titles"].append(fig.axes[0].get_title())
        return figure(self, fig, path)

    def written(view, res, *args, **kwargs):
        seen["results"].append(res)
        return write(view, res, *args, **kwargs)

    monkeypatch.setattr(Outputs, "figure", staged)
    monkeypatch.setattr(cli_sweep, "_write_sweep", written)
    return seen


def _summary(text: str) -> str:
    return next(line for line in text.splitlines() if line.startswith("sweep: "))


def test_kubo_period_two_point_reports_one_H(tmp_path, captured, capsys):
    """--harmonics 13 with a period-2 point (26 harmonics of ω/2 in the arrays): 13 in the
    CSV column, SweepResult.H, the summary line and the title."""
    out = tmp_path / "kubo.csv"
    assert main(["sweep", str(KUBO), *KUBO_DOWN, "--out", str(out)]) == 0
    text = capsys.readouterr().out
    df = pd.read_csv(out)
    assert (df["period"] == 2).sum() >= 1  # the case this test is about
    assert set(df["H"].dropna().astype(int)) == {13}
    (res,) = captured["results"]
    assert res.result.base == 2 and res.result.H_stored == 26  # what the arrays hold
    assert res.result.H == 13
    assert "H = 13," in _summary(text) and "26" not in _summary(text)
    (title,) = captured["titles"]
    assert title.splitlines()[1] == "base frequency: mesh, H = 13"


def test_period_two_alone_checks_against_H_of_the_mesh(tmp_path, captured, capsys):
    """--period 2: the period-2 branch's own estimate is against the next rung of the
    ladder after 13, 17 mesh harmonics (34 of ω/2, which the summary said before); H is
    given, not chosen; the error shown is over the accepted points, within 0.5 %; the
    period-2 points listed are the converged ones (the list held every grid point)."""
    out = tmp_path / "kubo2.csv"
    assert main(["sweep", str(KUBO), *KUBO_DOWN, "--period", "2", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    line = _summary(text)
    # the one stable period-2 point, not the 110 grid points no period-2 branch reaches
    assert "period 2 (period doubled) at rpm: 9800.0\n" in text
    (res,) = captured["results"]
    assert res.result.H == 13 and res.result.H_check == 17
    assert "H = 13 (given; largest estimated error " in line and line.split(" against H = ")[1].startswith(
        "17)"
    )
    assert set(pd.read_csv(out)["H"].dropna().astype(int)) == {13}
    assert res.result.max_harmonic_error <= 0.005


def test_link_sweep_harmonics_9_is_H_9_everywhere(tmp_path, captured, capsys):
    """A link sweep with --harmonics 9 and two period-2 points (18 harmonics of ω/2 in the
    arrays; the drive of tests/test_link_period_doubling.py): 9 in the CSV, the summary
    and the title (which said "H = 18")."""
    path = tmp_path / "drive.toml"
    path.write_text(DRIVE)
    out = tmp_path / "link.csv"
    argv = ["sweep", str(path), "--hz", "5475:5575:3", "--direction", "up", "--harmonics", "9"]
    assert main([*argv, "--out", str(out), "--quantity", "mesh0.dte_rms"]) == 0
    line = _summary(capsys.readouterr().out)
    df = pd.read_csv(out)
    assert list(df["period"]) == [1, 2, 2]
    assert set(df["H"].astype(int)) == {9}
    assert "H = 9," in line and "18" not in line
    (title,) = captured["titles"]
    assert title.endswith("H = 9") and "18" not in title


def _result(error, converged, no_stable, source="harmonic balance (H=5, exact); H chosen by error estimate"):
    n = len(error)
    return SweepResult(
        omega=np.arange(1.0, n + 1),
        direction=np.array(["up"] * n),
        harmonics=np.zeros((n, 1, 2 * 10 + 1)),  # 10 of ω/2: H = 5 of ω
        converged=np.array(converged),
        residual=np.zeros(n),
        iterations=np.ones(n, dtype=int),
        stable=np.array(converged),
        floquet_max=np.full(n, 0.5),
        metrics={},
        amplitudes=np.zeros((n, 6)),
        source=source,
        harmonic_error=np.array(error),
        H_check=7,
        no_stable=np.array(no_stable),
        period=np.array([1, 2, 1, 1][:n]),
        base=2,
    )


def test_largest_error_is_over_the_accepted_points():
    """A point rejected by the estimate (3.9 %, not converged) and an unstable orbit's
    estimate do not count: the largest over the accepted ones is 0.2 %, not 3.9 %."""
    res = _result([0.001, 0.039, 0.004, 0.002], [True, False, True, True], [False, False, True, False])
    assert res.H == 5 and res.H_stored == 10
    assert res.max_harmonic_error == 0.002
    assert harmonics_line(res) == "H = 5 (chosen; largest estimated error 0.2 % against H = 7)"
    none = _result([np.nan, 0.039], [True, False], [False, False])
    assert math.isnan(none.max_harmonic_error)
    assert harmonics_line(none) == "H = 5 (chosen; largest estimated error n/a against H = 7)"
