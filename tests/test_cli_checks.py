"""The command line never prints a traceback (issue 9, item 4).

Ctrl-C exits 130 with one line and leaves the previous outputs (written atomically);
options are checked before any computation; an incomplete continuation says how far
it got and exits 1; jumps are printed in the unit of the range; ``nlgrd lste`` uses the
model's ``lste_file`` and states the k_h of the dynamics; unexpected errors are one line
(the traceback only with NLGRD_DEBUG=1).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import nlgrd.nonlinear.models.link_model
import nlgrd.rotor.modal
from nlgrd.cli import main
from nlgrd.errors import ModelError
from nlgrd.gear.lste_file import write_lste_csv

ROOT = Path(__file__).resolve().parents[1]
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
KB = ROOT / "data" / "case_studies" / "kahraman_blankenship.toml"
TWO = ROOT / "data" / "models" / "two_shaft.toml"


def run(capsys, *argv) -> tuple[int, str, str]:
    rc = main([str(a) for a in argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


#: A progress line of the command off a terminal ("continuation up: 32/324"), not a message.
PROGRESS = re.compile(r"^\s*[^:]+: \d+/\d+$")


def one_line(err: str) -> str:
    """The one line stderr holds besides progress lines (the error)."""
    lines = [ln for ln in err.strip().splitlines() if not PROGRESS.match(ln)]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.fixture
def no_computation(monkeypatch):
    """Any computation fails the test: the options must be refused before."""

    def forbidden(*args, **kwargs):
        raise AssertionError("computation started before the options were checked")

    for name in ("build_link_model", "link_sweep", "link_continuation"):
        monkeypatch.setattr(nlgrd.nonlinear.models.link_model, name, forbidden)
    for name in ("modal_analysis", "campbell"):
        monkeypatch.setattr(nlgrd.rotor.modal, name, forbidden)


# ------------------------------------------------------------------------- Ctrl-C


def test_interrupted_sweep_keeps_the_previous_outputs(tmp_path, capsys, monkeypatch):
    out, png = tmp_path / "kubo.csv", tmp_path / "kubo.png"
    out.write_text("previous\n")
    png.write_bytes(b"previous png")

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(nlgrd.nonlinear.models.link_model, "link_sweep", interrupted)
    rc, _, err = run(capsys, "sweep", KUBO, "--hz", "3000:4000:3", "--out", out)
    assert rc == 130 and "interrupted" in one_line(err)
    assert out.read_text() == "previous\n" and png.read_bytes() == b"previous png"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kubo.csv", "kubo.png"]


def test_interrupt_while_writing_leaves_no_partial_file(tmp_path, capsys, monkeypatch):
    """Ctrl-C in the middle of writing the CSV: no half-written file, no temporary file."""
    original = pd.DataFrame.to_csv

    def half_then_interrupt(self, path, *args, **kwargs):
        original(self.iloc[:1], path, *args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(pd.DataFrame, "to_csv", half_then_interrupt)
    (tmp_path / "two_shaft_modes.csv").write_text("previous\n")
    rc, _, err = run(capsys, "modes", TWO, "--out", tmp_path)
    assert rc == 130 and "interrupted" in one_line(err)
    assert [p.name for p in tmp_path.iterdir()] == ["two_shaft_modes.csv"]
    assert (tmp_path / "two_shaft_modes.csv").read_text() == "previous\n"


def test_real_ctrl_c_in_a_running_sweep(tmp_path):
    """SIGINT to the running process: exit 130, one line, the previous CSV untouched."""
    out = tmp_path / "sweep.csv"
    out.write_text("previous\n")
    cmd = [sys.executable, "-m", "nlgrd.cli", "sweep", str(KUBO), "--hz", "3000:5000:200"]
    proc = subprocess.Popen(
        [*cmd, "--no-stability", "--out", str(out)], stderr=subprocess.PIPE, text=True, cwd=tmp_path
    )
    try:
        first = proc.stderr.readline()  # the first progress line: the sweep is running
        assert first.startswith("sweep"), first + proc.stderr.read()
        proc.send_signal(signal.SIGINT)
        err = proc.stderr.read()
        assert proc.wait(timeout=120) == 130
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert "Traceback" not in err and err.strip().splitlines()[-1] == "nlgrd: interrupted", err
    assert out.read_text() == "previous\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sweep.csv"]


# ------------------------------------------------------------------------- output paths


@pytest.mark.usefixtures("no_computation")
@pytest.mark.parametrize("where", [".", "folder"])
def test_sweep_out_that_is_a_folder(tmp_path, capsys, monkeypatch, where):
    """`--out .` or an existing folder where a CSV file is wanted."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "folder").mkdir()
    rc, _, err = run(capsys, "sweep", KUBO, "--hz", "3000:4000:3", "--out", where)
    line = one_line(err)
    assert rc == 2 and "--out" in line and "folder" in line, line


@pytest.mark.usefixtures("no_computation")
@pytest.mark.parametrize(
    "argv",
    [
        ["sweep", KUBO, "--hz", "3000:4000:3", "--out", "{tmp}/file.txt/x.csv"],
        ["sweep", KUBO, "--hz", "3000:4000:3", "--out", "{tmp}/x.csv", "--plot", "{tmp}/file.txt/x.png"],
        ["sweep", KUBO, "--hz", "3000:4000:3", "--out", "{tmp}/x.csv", "--plot", "{tmp}/x.csv"],
        ["modes", TWO, "--out", "{tmp}/file.txt"],
        ["campbell", TWO, "--out", "{tmp}/file.txt/sub"],
        ["lste", TWO, "--out", "{tmp}/file.txt"],
    ],
    ids=["sweep-out", "sweep-plot", "plot-is-out", "modes", "campbell", "lste"],
)
def test_output_paths_that_cannot_be_written(tmp_path, capsys, argv):
    (tmp_path / "file.txt").write_text("a file, not a folder")
    argv = [str(a).format(tmp=tmp_path) for a in argv]
    option = "--plot" if "--plot" in argv else "--out"
    rc, _, err = run(capsys, *argv)
    line = one_line(err)
    assert rc == 2 and option in line, line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt"]


@pytest.mark.usefixtures("no_computation")
@pytest.mark.skipif(not os.path.isdir("/sys") or os.access("/sys", os.W_OK) is False, reason="needs /sys")
def test_folder_that_refuses_files(capsys):
    """/sys refuses new files even to root: the probe finds out before the computation."""
    rc, _, err = run(capsys, "sweep", KUBO, "--hz", "3000:4000:3", "--out", "/sys/nlgrd_test.csv")
    line = one_line(err)
    assert rc == 2 and "--out" in line and "/sys" in line, line


@pytest.mark.usefixtures("no_computation")
@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0, reason="root writes anywhere")
def test_read_only_folder(tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        rc, _, err = run(capsys, "modes", TWO, "--out", ro)
    finally:
        ro.chmod(0o700)
    assert rc == 2 and "--out" in one_line(err)


# ------------------------------------------------------------------------- option values


@pytest.mark.usefixtures("no_computation")
@pytest.mark.parametrize(
    ("argv", "option", "fragment"),
    [
        (
            ["sweep", KUBO, "--hz", "3000:4000:3", "--quantity", "foo"],
            "--quantity",
            "links: mesh0",
        ),
        (["modes", TWO, "--n-modes", "0"], "--n-modes", "at least 1"),
        (["modes", TWO, "--n-modes", "-3"], "--n-modes", "at least 1"),
        (["campbell", TWO, "--n-modes", "0"], "--n-modes", "at least 1"),
        (["campbell", TWO, "--orders", "0"], "--orders", "positive"),
        (["campbell", TWO, "--orders", "1,-2"], "--orders", "positive"),
        (["campbell", TWO, "--orders", "nan"], "--orders", "positive"),
        (["campbell", TWO, "--rpm", "0:inf:5"], "--rpm", "finite"),
        (["campbell", TWO, "--rpm", "0:1000:0"], "--rpm", "COUNT"),
        (["campbell", TWO, "--rpm", "0:1000:-4"], "--rpm", "COUNT"),
        (["campbell", TWO, "--rpm", "0:1000:10000000"], "--rpm", "COUNT"),
        (["modes", TWO, "--rpm", "nan"], "--rpm", "finite"),
        (["modes", TWO, "--rpm", "0:1000:5"], "--rpm", "one speed"),
        (["lste", TWO, "--pair", "-1"], "--pair", "out of range"),
        (["lste", TWO, "--pair", "3"], "--pair", "out of range"),
        (["sweep", KUBO, "--hz", "3000:4000:3", "--harmonics", "-1"], "--harmonics", "at least 1"),
        (["sweep", KUBO, "--hz", "3000:4000:0"], "--hz", "COUNT"),
        (["sweep", KUBO, "--hz=-5:4000:3"], "--hz", "positive"),
        (["sweep", KUBO, "--rpm", "0:4000:3"], "--rpm", "positive"),
        (["sweep", KUBO, "--hz", "3000", "--continuation"], "--hz", "START:STOP"),
        (["sweep", KUBO, "--hz", "3000:3000", "--continuation"], "--hz", "START:STOP"),
        (["sweep", KUBO, "--hz", "3000:4000:1", "--continuation"], "--hz", "COUNT"),
    ],
)
def test_bad_option_values_before_any_computation(tmp_path, capsys, argv, option, fragment):
    out = tmp_path / "x.csv" if argv[0] == "sweep" else tmp_path
    rc, _, err = run(capsys, *argv, "--out", out)
    line = one_line(err)
    assert rc == 2 and line.startswith(f"nlgrd: error: {option}: ") and fragment in line, line


def test_harmonics_beyond_memory_is_one_line_naming_the_model(tmp_path, capsys):
    """--harmonics is bounded by memory, not by a constant (issue 35): 10^8 harmonics need
    a Jacobian of 3 x 10^17 bytes; the error names the option, the model file and the bound."""
    argv = ["sweep", KUBO, "--hz", "3000:4000:3", "--harmonics", "100000000", "--out", tmp_path / "x.csv"]
    rc, _, err = run(capsys, *argv)
    line = one_line(err)
    assert rc == 2 and "kubo.toml" in line and "--harmonics: " in line and "more memory" in line, line
    assert not (tmp_path / "x.csv").exists()


def test_model_errors_are_checked_before_output_folders_are_made(tmp_path, capsys):
    """A bad model creates no output folder."""
    bad = tmp_path / "bad.toml"
    bad.write_text("version = 1\n")
    rc, _, err = run(capsys, "modes", bad, "--out", tmp_path / "new" / "folder")
    assert rc == 2 and "bad.toml" in one_line(err)
    assert not (tmp_path / "new").exists()


# ------------------------------------------------------------------------- continuation


def test_continuation_that_turns_back_reports_its_span_and_fails(tmp_path, capsys):
    """Kubo upward from 3000 Hz: the curve folds back at about 4273 Hz and leaves the range
    at the low end; the CLI says it covered 3000-4273 Hz of 3000-5000 Hz and exits 1.

    The continuation tests fix H = 5 (--harmonics 5): they check how the command reports
    coverage, with figures of that H; the H chosen by default is tested in
    tests/test_harmonic_convergence.py."""
    out = tmp_path / "curve.csv"
    argv = ["sweep", KUBO, "--hz", "3000:5000:101", "--continuation", "--harmonics", "5", "--direction", "up"]
    rc, text, err = run(capsys, *argv, "--no-stability", "--out", out)
    assert rc == 1
    line = one_line(err)
    assert re.search(r"covered 3000-42\d\d Hz of the requested 3000-5000 Hz", line), line
    assert out.exists() and "INCOMPLETE" in line and "turned back" in text
    df = pd.read_csv(out)
    assert set(df["trace"]) == {"up"}


def test_continuation_both_ways_covers_the_range(tmp_path, capsys):
    """--direction both traces from each end: together they cover 3000-5000 Hz (exit 0)."""
    out = tmp_path / "curve.csv"
    argv = [
        "sweep",
        KUBO,
        "--hz",
        "3000:5000:101",
        "--continuation",
        "--harmonics",
        "5",
        "--direction",
        "both",
    ]
    rc, text, err = run(capsys, *argv, "--no-stability", "--out", out)
    assert rc == 0, err
    assert "covered the requested 3000-5000 Hz" in text
    df = pd.read_csv(out)
    assert set(df["trace"]) == {"up", "down"}
    down = df[df["trace"] == "down"]
    assert down["base_frequency [Hz]"].iloc[0] == pytest.approx(5000)


def test_continuation_count_sets_the_frequency_resolution(tmp_path, capsys):
    """COUNT = 101 over 3000-5000 Hz: successive curve points about 20 Hz apart at most."""
    out = tmp_path / "curve.csv"
    argv = [
        "sweep",
        KUBO,
        "--hz",
        "3000:5000:101",
        "--continuation",
        "--harmonics",
        "5",
        "--direction",
        "down",
    ]
    rc, _, err = run(capsys, *argv, "--no-stability", "--out", out)
    assert rc == 0, err
    f = pd.read_csv(out)["base_frequency [Hz]"].to_numpy()
    # the predictor moves at most (STOP - START) / (COUNT - 1); the corrector, at right
    # angles to the tangent, may add up to half a step (the tracer's acceptance test)
    assert np.max(np.abs(np.diff(f))) <= 1.5 * 20.0
    assert len(f) > 100


def test_continuation_turning_points_in_rpm(tmp_path, capsys):
    out = tmp_path / "curve.csv"
    argv = ["sweep", KUBO, "--rpm", "7200:12000", "--continuation", "--harmonics", "5", "--direction", "up"]
    rc, text, err = run(capsys, *argv, "--no-stability", "--out", out)
    assert rc == 1
    assert re.search(r"turning points at [\d., ]+ rpm", text), text
    assert re.search(r"covered 7200-10\d\d\d rpm of the requested 7200-12000 rpm", err), err


# ------------------------------------------------------------------------- jumps, lste


def test_jumps_in_the_unit_of_the_range(tmp_path, capsys):
    """--rpm: jumps and frequencies in rpm (the up jump between 10000 and 10500 rpm)."""
    argv = ["sweep", KUBO, "--rpm", "9000:12000:7", "--no-stability", "--out", tmp_path / "s.csv"]
    rc, text, _ = run(capsys, *argv)
    assert rc == 0
    jumps = [ln for ln in text.splitlines() if ln.startswith("jump")]
    assert jumps and all(ln.endswith(" rpm") for ln in jumps), text
    assert "jump (up): 10000.0 -> 10500.0 rpm" in jumps


def test_lste_states_the_mesh_stiffness_of_the_dynamics(tmp_path, capsys):
    """Kubo gives mesh_stiffness = 0.2587e9 N/m: that k_h is stated, not only the geometric mean."""
    rc, text, _ = run(capsys, "lste", KUBO, "--out", tmp_path)
    assert rc == 0
    assert "k_h = 2.587e+08 N/m" in text and "mesh_stiffness" in text


def test_lste_states_computed_mesh_stiffness(tmp_path, capsys):
    rc, text, _ = run(capsys, "lste", KB, "--out", tmp_path)
    assert rc == 0 and "computed from the geometry" in text


def test_lste_uses_the_models_lste_file(tmp_path, capsys):
    """With lste_file, the CSV and the summary show the file's LSTE (6 um peak to peak, not 4.9 um)."""
    phase = np.arange(128) / 128
    write_lste_csv(tmp_path / "measured.csv", phase, 3e-6 * np.cos(2 * np.pi * phase), unit="um")
    text = KUBO.read_text().replace(
        "damping_ratio = 0.005", 'damping_ratio = 0.005\nlste_file = "measured.csv"'
    )
    model = tmp_path / "kubo_file.toml"
    model.write_text(text)
    rc, out, err = run(capsys, "lste", model, "--out", tmp_path / "out")
    assert rc == 0, err
    assert "measured.csv" in out and "k_h = 2.587e+08 N/m" in out
    df = pd.read_csv(tmp_path / "out" / "kubo_file_lste.csv")
    assert np.ptp(df["lste [um]"]) == pytest.approx(6.0, rel=1e-3)
    assert (tmp_path / "out" / "kubo_file_lste.png").exists()


# ------------------------------------------------------------------------- unexpected errors


def _boom(*args, **kwargs):
    raise RuntimeError("boom\nsecond line")


def test_unexpected_error_is_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("NLGRD_DEBUG", raising=False)
    monkeypatch.setattr(nlgrd.rotor.modal, "modal_analysis", _boom)
    rc, _, err = run(capsys, "modes", TWO, "--out", tmp_path)
    assert rc == 1 and one_line(err) == "nlgrd: error: RuntimeError: boom second line"


def test_debug_shows_the_traceback(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("NLGRD_DEBUG", "1")
    monkeypatch.setattr(nlgrd.rotor.modal, "modal_analysis", _boom)
    rc, _, err = run(capsys, "modes", TWO, "--out", tmp_path)
    assert (
        rc == 1
        and "Traceback" in err
        and err.strip().endswith("nlgrd: error: RuntimeError: boom second line")
    )


def test_late_model_errors_name_the_file(tmp_path, capsys, monkeypatch):
    """A ModelError raised by an analysis (no file attached) is reported with the model file."""

    def unbalanced(*args, **kwargs):
        raise ModelError("torque", "the loads are not balanced")

    monkeypatch.setattr(nlgrd.rotor.modal, "modal_analysis", unbalanced)
    rc, _, err = run(capsys, "modes", TWO, "--out", tmp_path)
    assert rc == 2 and one_line(err) == f"nlgrd: error: {TWO}: torque: the loads are not balanced"
