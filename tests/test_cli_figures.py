"""The figures `nlgrd sweep` writes: abscissa in the unit the range was given in, the model's
name as title (a sweep's with its H, issue 36 item 1), readable axis labels (issue 36, item 3).

The figures are captured where the command stages them (``Outputs.figure``), before they
are written; the numbers drawn are checked against the CSV the same run writes.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from nlgrd.cli import main  # noqa: E402
from nlgrd.io.command_line import Outputs  # noqa: E402
from nlgrd.io.model_file import load_model  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
IDLER = ROOT / "data" / "models" / "idler_train.toml"


@pytest.fixture
def staged(monkeypatch):
    """The axes of every figure the command stages: (x label, y label, title, lines)."""
    seen = []
    original = Outputs.figure

    def figure(self, fig, path):
        ax = fig.axes[0]
        lines = {ln.get_label(): np.asarray(ln.get_xdata(), float) for ln in ax.get_lines()}
        seen.append((ax.get_xlabel(), ax.get_ylabel(), ax.get_title(), lines))
        return original(self, fig, path)

    monkeypatch.setattr(Outputs, "figure", figure)
    return seen


def _raw(label: str) -> bool:
    return "_" in label or "[um]" in label


def test_rpm_sweep_is_drawn_in_rpm_with_the_model_name(tmp_path, staged):
    """--rpm: the up points sit at the CSV's reference shaft (pinion) speeds (rtol 1e-12:
    the same numbers through mesh Hz and back)."""
    out = tmp_path / "k.csv"
    argv = [
        "sweep",
        str(KUBO),
        "--rpm",
        "9000:12000:4",
        "--no-stability",
        "--harmonics",
        "5",
        "--out",
        str(out),
    ]
    assert main(argv) == 0
    (xlabel, ylabel, title, lines) = staged[0]
    assert xlabel == "shaft speed [rpm]" and not _raw(ylabel)
    assert title.splitlines() == [load_model(KUBO).name, "base frequency: mesh, H = 5"]
    df = pd.read_csv(out)
    up = df[df["direction"] == "up"]["shaft_speed [rpm]"].to_numpy(float)
    drawn = next(x for k, x in lines.items() if k.startswith("sweep up"))
    np.testing.assert_allclose(np.sort(drawn), np.sort(up), rtol=1e-12)
    np.testing.assert_allclose(np.sort(drawn), [9000, 10000, 11000, 12000], rtol=1e-12)


def test_hz_sweep_and_continuation_are_drawn_in_mesh_hz(tmp_path, staged):
    base = ["--no-stability", "--harmonics", "5", "--direction", "up"]
    assert main(["sweep", str(KUBO), "--hz", "3000:3200:3", *base, "--out", str(tmp_path / "a.csv")]) == 0
    argv = [
        "sweep",
        str(KUBO),
        "--hz",
        "3000:3100:3",
        "--continuation",
        *base,
        "--out",
        str(tmp_path / "b.csv"),
    ]
    assert main(argv) in (0, 1)
    assert len(staged) == 2
    for xlabel, ylabel, title, _ in staged:
        assert xlabel == "base frequency [Hz]" and not _raw(ylabel)
        assert title.splitlines()[0] == load_model(KUBO).name


def test_link_sweep_labels_are_readable(tmp_path, staged):
    argv = [
        "sweep",
        str(IDLER),
        "--hz",
        "1000:1200:2",
        "--direction",
        "up",
        "--no-stability",
        "--harmonics",
        "5",
    ]
    assert main([*argv, "--quantity", "mesh1.dslr", "--out", str(tmp_path / "i.csv")]) == 0
    (xlabel, ylabel, title, _) = staged[0]
    assert xlabel == "base frequency [Hz]" and ylabel == "mesh1: DSLR [-]"
    assert title.startswith(load_model(IDLER).name[:60])
