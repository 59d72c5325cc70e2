"""Tests of nlgrd.gear.lste_file: Fourier convention, file round trips and file errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nlgrd.errors import ModelError
from nlgrd.gear.lste_file import (
    MeshExcitation,
    fourier_fit,
    read_excitation,
    read_fourier_csv,
    read_fourier_toml,
    read_lste_csv,
    read_lste_samples,
    resample,
    write_lste_csv,
)

# a band-limited test signal [µm]: mean and 5 harmonics
E0_UM = 8.3
A_UM = np.array([1.2, -0.45, 0.3, 0.0, -0.07])
B_UM = np.array([-0.8, 0.25, 0.0, 0.11, 0.02])


def signal_um(phase):
    m = np.arange(1, 6)
    arg = 2 * np.pi * np.asarray(phase)[:, None] * m
    return E0_UM + (A_UM * np.cos(arg) + B_UM * np.sin(arg)).sum(axis=1)


def test_convention_complex_coefficients():
    """e = e0 + Σ a_m cos(mωt) + b_m sin(mωt) = Re Σ_{m>=0} E_m e^{imωt} with E_m = a_m - i b_m.

    Checked by direct evaluation on 97 phases; tolerance 1e-15 m (rounding).
    """
    ex = MeshExcitation(E0_UM * 1e-6, A_UM * 1e-6, B_UM * 1e-6)
    E = ex.harmonics(5)
    assert E[0] == E0_UM * 1e-6
    assert np.allclose(E[1:], (A_UM - 1j * B_UM) * 1e-6, rtol=0, atol=1e-20)
    phase = np.linspace(0, 1, 97)
    direct = np.real(np.sum(E[None, :] * np.exp(2j * np.pi * np.outer(phase, np.arange(6))), axis=1))
    assert np.allclose(ex.value(phase), direct, rtol=0, atol=1e-15)
    assert np.allclose(ex.value(phase), signal_um(phase) * 1e-6, rtol=0, atol=1e-15)
    # derivative by central differences (step 1e-6 cycles: error ~1e-12 relative)
    h = 1e-6
    fd = (ex.value(phase + h) - ex.value(phase - h)) / (2 * h)
    assert np.allclose(ex.derivative(phase), fd, rtol=1e-6, atol=1e-12)
    # padding and truncation
    assert ex.harmonics(8)[6:].tolist() == [0, 0, 0]
    assert ex.truncated(2).n_harmonics == 2 and ex.without_mean().e0 == 0.0


@pytest.mark.parametrize("endpoint", [False, True])
@pytest.mark.parametrize("unit", ["um", "m"])
def test_round_trip_recovers_coefficients(tmp_path, endpoint, unit):
    """A band-limited periodic signal written as CSV is fitted back to its coefficients within 1e-12 µm.

    Independent source: the coefficients the signal was built from. 64 uniform
    samples, 5 harmonics: the least-squares basis is orthogonal on the grid, so the
    fit is exact up to rounding (~1e-15 µm); repr() keeps all digits in the file.
    """
    n = 64
    phase = np.arange(n + 1 if endpoint else n) / n
    path = tmp_path / "ste.csv"
    values = signal_um(phase) * (1.0 if unit == "um" else 1e-6)
    write_lste_csv(path, phase, values * (1e-6 if unit == "um" else 1.0), unit=unit)
    ex = read_lste_csv(path, H=5)
    assert abs(ex.e0 * 1e6 - E0_UM) < 1e-12
    assert np.max(np.abs(ex.a * 1e6 - A_UM)) < 1e-12
    assert np.max(np.abs(ex.b * 1e6 - B_UM)) < 1e-12
    # and through read_excitation with the default (maximum) number of harmonics
    ex_all = read_excitation(path)
    assert ex_all.n_harmonics == (n - 1) // 2
    assert np.max(np.abs(ex_all.a[5:])) < 1e-18


def test_roll_angle_column_and_offset_phase(tmp_path):
    """A roll_angle column [rad] maps to phase = angle z1 / 2π; the period may start anywhere."""
    z1 = 25
    phase = 0.25 + np.arange(48) / 48
    angle = phase * 2 * np.pi / z1
    path = tmp_path / "roll.csv"
    lines = ["# LSTE from a load distribution program", "roll_angle, ste_um"]
    lines += [f"{a!r}, {v!r}" for a, v in zip(angle.tolist(), signal_um(phase).tolist(), strict=True)]
    path.write_text("\n".join(lines) + "\n")
    ex = read_lste_csv(path, H=5, teeth_pinion=z1)
    assert np.max(np.abs(ex.a * 1e6 - A_UM)) < 1e-10
    assert np.max(np.abs(ex.b * 1e6 - B_UM)) < 1e-10
    with pytest.raises(ModelError) as exc:
        read_lste_csv(path)
    assert exc.value.key == "teeth_pinion" and exc.value.file == str(path)


def test_resample_and_nonuniform_fit():
    """Non-uniform samples: the least-squares fit is still exact for a band-limited signal (1e-10 µm);
    periodic cubic resampling onto 256 points keeps the harmonics to 2e-3 µm (spline error)."""
    rng = np.random.default_rng(3)
    phase = np.sort(rng.uniform(0, 1, 80))
    values = signal_um(phase)
    ex = fourier_fit(phase, values, 5)
    assert np.max(np.abs(ex.a - A_UM)) < 1e-10
    new_phase, new_values = resample(phase, values, 256)
    assert new_phase[1] == pytest.approx(1 / 256)
    ex2 = fourier_fit(new_phase, new_values, 5)
    assert np.max(np.abs(ex2.a - A_UM)) < 2e-3
    assert np.max(np.abs(ex2.b - B_UM)) < 2e-3
    lin_phase, lin_values = resample(phase, values, 64, kind="linear")
    assert np.all(np.isfinite(lin_values)) and len(lin_phase) == 64
    with pytest.raises(ModelError):
        fourier_fit(phase[:9], values[:9], 5)


def test_toml_and_coefficient_csv_round_trip(tmp_path):
    """MeshExcitation.save writes TOML that reads back exactly; a coefficient CSV table reads too."""
    ex = MeshExcitation(E0_UM * 1e-6, A_UM * 1e-6, B_UM * 1e-6)
    path = tmp_path / "lste.toml"
    ex.save(path)
    assert read_fourier_toml(path) == ex
    assert read_excitation(path) == ex
    um = tmp_path / "um.toml"
    um.write_text('version = 1\nunit = "um"\ne0 = 1.5\na = [1.0, 2.0]\nb = [0.5, 0.0]\n')
    got = read_excitation(um)
    assert got.e0 == pytest.approx(1.5e-6) and np.allclose(got.a, [1e-6, 2e-6], rtol=1e-15, atol=0)
    csv = tmp_path / "coef.csv"
    csv.write_text("harmonic,a_um,b_um\n0,8.3,0\n2,-0.45,0.25\n1,1.2,-0.8\n")
    got = read_fourier_csv(csv)
    assert got.e0 == pytest.approx(8.3e-6)
    assert np.allclose(got.a, [1.2e-6, -0.45e-6], rtol=1e-14, atol=0)
    assert np.allclose(got.b, [-0.8e-6, 0.25e-6], rtol=1e-14, atol=0)
    assert read_excitation(csv) == got
    frame = got.to_frame()
    assert list(frame.columns) == ["harmonic [-]", "a [um]", "b [um]", "amplitude [um]"]


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def _samples(header: str, rows) -> str:
    return header + "\n" + "\n".join(f"{p},{v}" for p, v in rows) + "\n"


GOOD = [(i / 8, float(np.sin(2 * np.pi * i / 8))) for i in range(8)]


@pytest.mark.parametrize(
    ("name", "text", "key", "match"),
    [
        (
            "unsorted",
            _samples("phase,ste_um", GOOD[:3] + [GOOD[4], GOOD[3]] + GOOD[5:]),
            "phase",
            "increase strictly",
        ),
        ("repeated", _samples("phase,ste_um", GOOD[:3] + [GOOD[2]] + GOOD[3:]), "phase", "increase strictly"),
        ("endpoint", _samples("phase,ste_um", [*GOOD, (1.0, 0.7)]), "ste_um", "not periodic"),
        ("too_long", _samples("phase,ste_um", [*GOOD, (1.125, 0.7)]), "phase", "one mesh period"),
        ("too_short", _samples("phase,ste_um", GOOD[:5]), "phase", "do not fill one mesh period"),
        ("nan", _samples("phase,ste_um", GOOD[:3] + [(0.375, "nan")] + GOOD[4:]), "ste_um", "non-finite"),
        ("inf", _samples("phase,ste_m", GOOD[:3] + [(0.375, "inf")] + GOOD[4:]), "ste_m", "non-finite"),
        ("empty", _samples("phase,ste_um", GOOD[:3] + [(0.375, "")] + GOOD[4:]), "ste_um", "non-finite"),
        ("nan_phase", _samples("phase,ste_um", GOOD[:3] + [("nan", 0.1)] + GOOD[4:]), "phase", "non-finite"),
        ("text", _samples("phase,ste_um", GOOD[:3] + [(0.375, "abc")] + GOOD[4:]), "ste_um", "not a number"),
        ("no_value", _samples("phase,te", GOOD), "ste_m or ste_um", "missing STE column"),
        ("no_phase", _samples("angle,ste_um", GOOD), "phase or roll_angle", "missing phase column"),
        (
            "two_values",
            "phase,ste_m,ste_um\n" + "\n".join(f"{p},{v},{v}" for p, v in GOOD),
            "ste_um",
            "one STE",
        ),
    ],
)
def test_sample_file_errors_name_file_and_column(tmp_path, name, text, key, match):
    """Bad sample files raise ModelError naming the file and the column, with the cause in words."""
    path = _write(tmp_path / f"{name}.csv", text)
    with pytest.raises(ModelError, match=match) as exc:
        read_lste_samples(path)
    assert exc.value.file == str(path)
    assert exc.value.key == key
    assert str(path) in str(exc.value) and key in str(exc.value)


def test_endpoint_within_tolerance_is_accepted(tmp_path):
    """An endpoint equal to the first value (to 1e-3 of peak-to-peak) is dropped, not an error."""
    path = _write(tmp_path / "ok.csv", _samples("phase,ste_um", [*GOOD, (1.0, GOOD[0][1] + 1e-5)]))
    phase, ste = read_lste_samples(path)
    assert len(phase) == 8 and ste[0] == pytest.approx(0.0, abs=1e-20)


def test_coefficient_file_errors(tmp_path):
    """Coefficient tables: missing columns, bad harmonics, version and unit keys are named."""
    cases = [
        ("harmonic,a_um\n1,1.0\n", "b_m or b_um"),
        ("a_um,b_um\n1.0,0.0\n", "harmonic"),
        ("harmonic,a_um,b_um\n1,1.0,0\n1,2.0,0\n", "harmonic"),
        ("harmonic,a_um,b_um\n-1,1.0,0\n", "harmonic"),
        ("harmonic,a_um,b_um\n0,1.0,2.0\n", "b_um"),
        ("harmonic,a_um,b_m\n1,1.0,2.0\n", "b_m"),
        ("harmonic,a_um,b_um\n1,nan,0\n", "a_um"),
    ]
    for i, (text, key) in enumerate(cases):
        path = _write(tmp_path / f"c{i}.csv", text)
        with pytest.raises(ModelError) as exc:
            read_fourier_csv(path)
        assert exc.value.key == key and exc.value.file == str(path), text
    tomls = [
        ("version = 2\na = [1.0]\nb = [0.0]\n", "version"),
        ('version = 1\nunit = "mm"\na = [1.0]\nb = [0.0]\n', "unit"),
        ("version = 1\na = [1.0, 2.0]\nb = [0.0]\n", "b"),
        ("version = 1\na = [1.0]\n", "b"),
        ("version = 1\na = [1.0]\nb = [0.0]\nc = 3\n", "c"),
        ("version = 1\na = [nan]\nb = [0.0]\n", "a"),
    ]
    for i, (text, key) in enumerate(tomls):
        path = _write(tmp_path / f"t{i}.toml", text)
        with pytest.raises(ModelError) as exc:
            read_fourier_toml(path)
        assert exc.value.key == key and exc.value.file == str(path), text
