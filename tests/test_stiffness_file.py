"""Mesh stiffness k(θ) from a file: the ``stiffness_file`` of a gear pair
(:mod:`nlgrd.gear.stiffness_file`), against the inputs it must reproduce.

References, each independent of the file reader:

- (a) a band-limited shape ρ(θ) = 1 + 0.15 cos θ - 0.05 sin θ + 0.04 cos 2θ + 0.03 sin 2θ,
  the ``stiffness_variation`` harmonics written out. Sampled at n >= 2H + 1 equal steps,
  the discrete Fourier transform returns these harmonics exactly and zeros above (the
  sampled cosines and sines below n/2 are orthogonal), so the file must give them to
  rounding (1e-14). At unequal steps the periodic cubic spline's error is at most
  (5/384) h⁴ max|ρ''''| (Hall & Meyer 1976, J. Approx. Theory 16:105; h the largest step
  in θ), and a harmonic's coefficient at most twice the largest pointwise error.
- (b) nlgrd's own load-sharing stiffness (``stiffness_variation = "load_sharing"``): its
  256 samples written to the file must give the same harmonics (FFT against least squares
  on the same samples: rounding, 1e-14) and so the same harmonic-balance sweep (Newton to
  1e-10 from the same starts: outputs within 1e-9, against a 1 % or larger change when ρ
  is left out).
- (c) the command line with the file and with the equivalent series writes the same CSV.
- (d) every bad file is one ModelError / one line naming the key and the file, exit 2.
"""

from __future__ import annotations

import dataclasses as dc
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from nlgrd.cli import main
from nlgrd.errors import ModelError
from nlgrd.gear.stiffness_file import read_stiffness_file
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.laws.mesh_law import mesh_law
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.timedomain.links import link_time_response

ROOT = Path(__file__).resolve().parent.parent
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
SERIES = (1.0, 0.15, -0.05, 0.04, 0.03)  # [1, a1, b1, a2, b2] of ρ
H = 30  # harmonics of ρ the analysis takes from samples (GearMesh.stiffness_harmonics default)
TWO_PI = 2 * np.pi


def rho_of(phase) -> np.ndarray:
    th = TWO_PI * np.asarray(phase)
    return 1 + 0.15 * np.cos(th) - 0.05 * np.sin(th) + 0.04 * np.cos(2 * th) + 0.03 * np.sin(2 * th)


def write_samples(path: Path, phase, values, header: str = "phase,stiffness_n_per_m") -> Path:
    rows = [f"{float(p)!r},{float(v)!r}" for p, v in zip(phase, values, strict=True)]
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def kubo(**mesh):
    s = load_model(KUBO)
    return dc.replace(s, gear_pairs=(dc.replace(s.gear_pairs[0], **mesh),))


def padded(rho, size: int) -> np.ndarray:
    out = np.zeros(size)
    out[: len(rho)] = rho
    return out


# ------------------------------------------------------------------------------ (a)
def test_band_limited_samples_give_the_series(tmp_path):
    k_h = 2.587e8
    n = 64  # >= 2 H + 1 = 61
    phase = np.arange(n) / n
    series = kubo(stiffness_variation=SERIES).gear_pairs[0]
    ref = series.stiffness_harmonics(H)
    assert ref.size == 5
    files = {
        "equal steps, N/m": write_samples(tmp_path / "k.csv", phase, k_h * rho_of(phase)),
        "rho, endpoint included": write_samples(
            tmp_path / "rho.csv", np.append(phase, 1.0), rho_of(np.append(phase, 1.0)), "phase,rho"
        ),
        "roll angle, offset start": write_samples(
            tmp_path / "roll.csv",
            TWO_PI * (phase + 0.25) / series.geometry.teeth_pinion,  # 2π/z1 per mesh cycle
            1e8 * rho_of(phase + 0.25),
            "roll_angle,stiffness_n_per_m",
        ),
    }
    for name, path in files.items():
        got = dc.replace(series, stiffness_variation=None, stiffness_file=str(path)).stiffness_harmonics(H)
        assert got.size == 2 * H + 1, name
        np.testing.assert_allclose(got, padded(ref, got.size), rtol=0, atol=1e-14, err_msg=name)
    mean = read_stiffness_file(files["equal steps, N/m"], H).mean
    assert (
        mean == pytest.approx(k_h, rel=1e-14)
        and read_stiffness_file(files["rho, endpoint included"]).mean is None
    )
    # the unloaded error of the parametric law follows from ρ: the same too
    e_file, _ = mesh_law(
        dc.replace(series, stiffness_variation=None, stiffness_file=str(files["equal steps, N/m"]))
    )
    e_series, _ = mesh_law(series)
    np.testing.assert_allclose(e_file, e_series, rtol=0, atol=1e-14 * np.max(np.abs(e_series)))


def test_coefficient_files_give_the_series(tmp_path):
    """``harmonic, a_rho, b_rho`` (harmonic 0 left out: 1) and ``a_n_per_m`` (divided by harmonic 0)."""
    rho = tmp_path / "rho_coef.csv"
    rho.write_text("harmonic,a_rho,b_rho\n1,0.15,-0.05\n2,0.04,0.03\n")
    k = tmp_path / "k_coef.csv"
    k.write_text("harmonic,a_n_per_m,b_n_per_m\n0,2e8,0\n2,8e6,6e6\n1,3e7,-1e7\n")
    for path in (rho, k):
        np.testing.assert_allclose(read_stiffness_file(path).rho, SERIES, rtol=0, atol=1e-16)
    assert read_stiffness_file(k).mean == 2e8


def test_unequal_steps_within_the_spline_bound(tmp_path):
    n = 64
    rng = np.random.default_rng(1)
    phase = np.sort(np.mod(np.arange(n) / n + rng.uniform(-0.3, 0.3, n) / n, 1.0))
    path = write_samples(tmp_path / "uneven.csv", phase, 3e8 * rho_of(phase))
    got = np.asarray(read_stiffness_file(path, H).rho)
    h = TWO_PI * np.max(np.diff(np.append(phase, phase[0] + 1)))
    d4 = 0.15 + 0.05 + 16 * (0.04 + 0.03)  # bound on max|ρ''''|: Σ k⁴ (|a_k| + |b_k|)
    bound = 2 * 5 / 384 * h**4 * d4
    err = np.max(np.abs(got - padded(SERIES, got.size)))
    # taken as equal steps, the same samples would be far off: the bound tells the two apart
    naive = read_stiffness_file(
        write_samples(tmp_path / "even.csv", np.arange(n) / n, 3e8 * rho_of(phase)), H
    )
    naive_err = np.max(np.abs(np.asarray(naive.rho) - padded(SERIES, got.size)))
    print(
        f"unequal steps: largest harmonic error {err:.2e}, bound {bound:.2e}, as equal steps {naive_err:.2e}"
    )
    assert err <= bound < naive_err / 10


# ------------------------------------------------------------------------------ (b)
@pytest.fixture(scope="module")
def load_sharing_file(tmp_path_factory):
    """Kubo's load-sharing stiffness samples (256 over the mesh cycle) in a file."""
    res = kubo().gear_pairs[0].lste_result()
    return write_samples(tmp_path_factory.mktemp("ls") / "k_theta.csv", res.phase, res.mesh_stiffness)


def test_load_sharing_samples_reproduce_load_sharing(load_sharing_file):
    ls = kubo(stiffness_variation="load_sharing").gear_pairs[0]
    gf = kubo(stiffness_file=str(load_sharing_file)).gear_pairs[0]
    a, b = ls.stiffness_harmonics(H), gf.stiffness_harmonics(H)
    print(f"load-sharing harmonics: largest difference {np.max(np.abs(a - b)):.2e}")
    np.testing.assert_allclose(b, a, rtol=0, atol=1e-14)
    assert gf.stiffness_shape().mean == pytest.approx(ls.lste_result().k_mean, rel=1e-14)


def test_load_sharing_sweep_from_the_file(load_sharing_file):
    """Kubo's rig at 2500-4000 Hz up and down, H = 9: the file's sweep is the load sharing's
    (the link engine, ``nlgrd.sweep``'s path)."""
    omegas = TWO_PI * np.array([2500.0, 3000.0, 3500.0, 4000.0])
    cols = ["mesh0.dte_rms [um]", "mesh0.force_max [N]", "floquet_max [-]"]
    frames = {}
    for name, mesh in {
        "load_sharing": {"stiffness_variation": "load_sharing"},
        "file": {"stiffness_file": str(load_sharing_file)},
        "constant": {},
    }.items():
        system = kubo(**mesh)
        frames[name] = link_sweep(build_link_model(system), omegas, H=9, directions="both").to_frame()
    ls, f, const = (frames[k][cols].to_numpy(float) for k in ("load_sharing", "file", "constant"))
    assert (
        frames["file"]["converged"].all()
        and (frames["file"]["stable"] == frames["load_sharing"]["stable"]).all()
    )
    rel = np.max(np.abs(f / ls - 1))
    print(f"file against load sharing: largest relative difference {rel:.2e}")
    assert rel < 1e-9
    assert np.max(np.abs(const / ls - 1)) > 0.01  # ρ matters here: the comparison can fail


def test_time_domain_takes_the_same_law(tmp_path):
    """The HHT-α integration reads the force law of the model: with the file it is the series'
    (8 mesh periods at 3000 Hz, 256 steps each: the same histories to rounding)."""
    n = 64
    phase = np.arange(n) / n
    path = write_samples(tmp_path / "k.csv", phase, 2.6e8 * rho_of(phase))
    om = TWO_PI * 3000.0
    runs = []
    for mesh in ({"stiffness_variation": SERIES}, {"stiffness_file": str(path)}):
        model = build_link_model(kubo(**mesh))
        tr = link_time_response(model, om, steps_per_period=256, max_periods=8, min_periods=8)
        runs.append(tr.y[0])
    scale = np.ptp(runs[0])
    print(f"time domain, file against series: {np.max(np.abs(runs[1] - runs[0])) / scale:.1e} of the range")
    assert scale > 0
    np.testing.assert_allclose(runs[1], runs[0], rtol=0, atol=1e-9 * scale)


# ------------------------------------------------------------------------------ (c)
def kubo_file(tmp_path: Path, line: str, name: str = "kubo") -> Path:
    """Kubo's model file with ``line`` added to its gear pair, in tmp_path."""
    text = KUBO.read_text()
    assert "damping_ratio = 0.005\n" in text
    path = tmp_path / f"{name}.toml"
    path.write_text(text.replace("damping_ratio = 0.005\n", f"damping_ratio = 0.005\n{line}\n", 1))
    return path


def test_cli_sweep_with_the_file_writes_the_series_numbers(tmp_path, capsys):
    n = 64
    phase = np.arange(n) / n
    write_samples(tmp_path / "k_theta.csv", phase, 2.6e8 * rho_of(phase))
    models = {
        "series": kubo_file(tmp_path, f"stiffness_variation = {list(SERIES)}", "series"),
        "file": kubo_file(tmp_path, 'stiffness_file = "k_theta.csv"', "file"),
        "constant": kubo_file(tmp_path, "", "constant"),
    }
    frames = {}
    for name, model in models.items():
        out = tmp_path / f"{name}.csv"
        argv = ["sweep", str(model), "--rpm", "11000:13000:3", "--harmonics", "9", "--out", str(out)]
        assert main(argv) == 0, capsys.readouterr().err
        frames[name] = pd.read_csv(out)
    s, f = frames["series"], frames["file"]
    assert list(s.columns) == list(f.columns) and len(s) == 6 and s["converged"].all()
    # the outputs; the residual (below Newton's 1e-10) and the iteration count are the solver's
    num = s.select_dtypes("number").columns.drop(["residual [-]", "iterations"])
    s, f = s.drop(columns=["residual [-]", "iterations"]), f.drop(columns=["residual [-]", "iterations"])
    pd.testing.assert_frame_equal(s.drop(columns=num), f.drop(columns=num))
    # ρ's harmonics agree to 1e-14 (test above): the outputs to Newton's tolerance and rounding
    a, b = f[num].to_numpy(float), s[num].to_numpy(float)
    with np.errstate(invalid="ignore", divide="ignore"), capsys.disabled():
        print(f"CLI, file against series: largest relative difference {np.nanmax(np.abs(a / b - 1)):.1e}")
    np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)
    c = frames["constant"]["mesh0.dte_rms [um]"].to_numpy(float)
    change = np.max(np.abs(c / s["mesh0.dte_rms [um]"].to_numpy(float) - 1))
    with capsys.disabled():
        print(f"CLI, constant k_h against the series: RMS DTE differs by up to {change:.1%}")
    assert change > 1e-2  # the series matters: the comparison can fail
    capsys.readouterr()
    assert main(["lste", str(models["file"]), "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "from the stiffness_file" in text and "the file's mean 2.6e+08 N/m is not used" in text


# ------------------------------------------------------------------------------ (d)
GOOD = np.arange(64) / 64


def _rows(values, phases=GOOD) -> str:
    text = [v if isinstance(v, str) else repr(float(v)) for v in values]
    return "\n".join(f"{float(p)!r},{v}" for p, v in zip(phases, text, strict=True))


STEP = np.where(GOOD < 0.5, 0.02e8, 2e8)  # positive samples whose 30 harmonics dip below 0 (Gibbs)
BAD = {
    "missing file": (None, "no such file"),
    "missing column": ("phase,k\n" + _rows(2.6e8 * rho_of(GOOD)), "missing stiffness column"),
    "non-numeric": (
        "phase,stiffness_n_per_m\n" + _rows(["abc" if i == 4 else 2.6e8 for i in range(64)]),
        "stiffness_n_per_m: row 5: not a number ('abc')",
    ),
    "non-positive": (
        "phase,stiffness_n_per_m\n" + _rows(np.where(GOOD == 0.5, 0.0, 2.6e8)),
        "stiffness_n_per_m: row 33: must be positive",
    ),
    "non-monotonic phase": (
        "phase,stiffness_n_per_m\n" + _rows(np.full(64, 2.6e8), GOOD[[0, 2, 1, *range(3, 64)]]),
        "must increase strictly",
    ),
    "duplicate phase": (
        "phase,stiffness_n_per_m\n" + _rows(np.full(64, 2.6e8), np.append(GOOD[:32], GOOD[31:63])),
        "repeated at data row 33",
    ),
    "too few samples": (
        "phase,stiffness_n_per_m\n" + _rows(np.full(20, 2.6e8), np.arange(20) / 20),
        "give at least 61 samples",
    ),
    "rho mean not 1": ("phase,rho\n" + _rows(1.2 * rho_of(GOOD)), "the mean of rho over the cycle is 1.2"),
    "unit slip": ("phase,stiffness_n_per_m\n" + _rows(2.6e5 * rho_of(GOOD)), "check the unit (N/m)"),
    "dips below zero": ("phase,stiffness_n_per_m\n" + _rows(STEP), "must stay positive over the mesh cycle"),
    "no mean": ("harmonic,a_n_per_m,b_n_per_m\n1,1e7,0\n", "harmonic 0 (the mean stiffness) is needed"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_file_is_one_line_naming_key_and_file(case, tmp_path, capsys):
    text, fragment = BAD[case]
    csv = tmp_path / "k_theta.csv"
    if text is not None:
        csv.write_text(text + "\n")
    model = kubo_file(tmp_path, 'stiffness_file = "k_theta.csv"')
    with pytest.raises(ModelError) as exc:
        load_model(model)
    assert exc.value.key == "gear_pairs[0].stiffness_file" and exc.value.file == str(model)
    assert main(["sweep", str(model), "--rpm", "9000:9100:2", "--out", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err.strip()
    print(err)
    assert len(err.splitlines()) == 1 and err.startswith("nlgrd: error:"), err
    assert "kubo.toml" in err and "gear_pairs[0].stiffness_file" in err and "k_theta.csv" in err, err
    assert fragment in err, err


def test_both_keys_are_refused(tmp_path, capsys):
    write_samples(tmp_path / "k_theta.csv", GOOD, 2.6e8 * rho_of(GOOD))
    model = kubo_file(tmp_path, 'stiffness_file = "k_theta.csv"\nstiffness_variation = "load_sharing"')
    assert main(["sweep", str(model), "--rpm", "9000:9100:2", "--out", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "gear_pairs[0].stiffness_file" in err and "kubo.toml" in err
    assert "k_theta.csv" in err and "stiffness_variation" in err and "not both" in err, err


def test_no_traceback_from_the_installed_command(tmp_path):
    (tmp_path / "k_theta.csv").write_text(BAD["non-numeric"][0])
    model = kubo_file(tmp_path, 'stiffness_file = "k_theta.csv"')
    proc = subprocess.run(
        [sys.executable, "-m", "nlgrd.cli", "sweep", str(model), "--rpm", "9000:9100:2"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and "not a number" in proc.stderr


def test_study_key_follows_the_file_content(tmp_path):
    """A study's result key changes with the stiffness file's content, as with an LSTE file's:
    stored results of another k(θ) are never reused."""
    import tomllib

    from nlgrd.studies.study_tasks import task_key

    path = write_samples(tmp_path / "k_theta.csv", GOOD, 2.6e8 * rho_of(GOOD))
    model = kubo_file(tmp_path, 'stiffness_file = "k_theta.csv"')
    data = tomllib.loads(model.read_text())
    before = task_key(data, str(model), {"rpm": [9000.0, 9100.0, 2]})
    assert task_key(data, str(model), {"rpm": [9000.0, 9100.0, 2]}) == before
    write_samples(path, GOOD, 2.6e8 * rho_of(GOOD + 0.01))
    assert task_key(data, str(model), {"rpm": [9000.0, 9100.0, 2]}) != before
