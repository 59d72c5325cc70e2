"""Disk unbalance in the model file and `nlgrd sweep` (issue 12, item 4): the
``[[unbalance]]`` table (validation, round trip), the link model taking the system's
unbalance by default, and the CLI link sweep against calling
:func:`nlgrd.nonlinear.models.link_model.link_sweep` directly."""

from __future__ import annotations

import dataclasses as dc
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from nlgrd.cli import main
from nlgrd.errors import ModelError
from nlgrd.io.model_file import load_model
from nlgrd.io.model_writer import model_to_dict, save_model
from nlgrd.nonlinear.models.link_model import Unbalance, build_link_model, link_sweep, needs_links
from nlgrd.rotor.loads import Unbalance as RotorUnbalance
from nlgrd.rotor.system import refined

ROOT = Path(__file__).resolve().parent.parent
TWO_SHAFT = ROOT / "data" / "models" / "two_shaft.toml"
SINGLE = ROOT / "data" / "models" / "single_shaft.toml"

ENTRY = """
[[unbalance]]
shaft = 1
node = 4
amount = 1.0e-2
phase = 0.3
"""
RPM = (6000.0, 7000.0)  # mesh at 2500 and 2917 Hz: teeth in contact throughout
H = 25  # base = the shaft speed: the mesh at harmonic 25


def unbalance_model(
    tmp_path: Path, entry: str = ENTRY, base: Path = TWO_SHAFT, name: str = "unbalance"
) -> Path:
    """``base`` with ``entry`` appended, in tmp_path."""
    path = tmp_path / f"{name}.toml"
    path.write_text(base.read_text() + entry)
    return path


def test_the_library_record_is_the_rotor_one():
    assert Unbalance is RotorUnbalance
    assert Unbalance(1, 4, 1e-4) == Unbalance(shaft=1, node=4, amount=1e-4, phase=0.0)


def test_round_trip_and_refinement(tmp_path):
    system = load_model(unbalance_model(tmp_path, ENTRY + ENTRY.replace("node = 4", "node = 10")))
    assert system.unbalance == (Unbalance(1, 4, 1e-2, 0.3), Unbalance(1, 10, 1e-2, 0.3))
    assert needs_links(system) and not needs_links(load_model(TWO_SHAFT))
    data = model_to_dict(system)
    assert data["unbalance"][0] == {"shaft": 1, "node": 4, "amount": 1e-2, "phase": 0.3}
    save_model(system, tmp_path / "again.toml")
    assert "[[unbalance]]" in (tmp_path / "again.toml").read_text()
    assert load_model(tmp_path / "again.toml") == system
    # phase defaults to 0; refining keeps the unbalance at its place
    one = load_model(unbalance_model(tmp_path, ENTRY.replace("phase = 0.3\n", "")))
    assert one.unbalance == (Unbalance(1, 4, 1e-2, 0.0),)
    assert refined(one, 2).unbalance == (Unbalance(1, 8, 1e-2, 0.0),)
    assert load_model(TWO_SHAFT).unbalance == ()


@pytest.mark.parametrize(
    "change, key, words",
    [
        (("phase = 0.3", "phase = 0.3\ncolour = 1"), "unbalance[0].colour", "unknown key"),
        (("amount = 1.0e-2", "amount = -1.0e-4"), "unbalance[0].amount", "zero or positive"),
        (("amount = 1.0e-2", "amount = nan"), "unbalance[0].amount", "finite"),
        (("amount = 1.0e-2", 'amount = "1e-2"'), "unbalance[0].amount", "must be a number"),
        (("amount = 1.0e-2\n", ""), "unbalance[0].amount", "missing required key"),
        (("phase = 0.3", "phase = inf"), "unbalance[0].phase", "finite"),
        (("node = 4", "node = 11"), "unbalance[0].node", "out of range 0..10"),
        (("node = 4", "node = -1"), "unbalance[0].node", "non-negative integer"),
        (("shaft = 1", "shaft = 2"), "unbalance[0].shaft", "out of range 0..1"),
        (("shaft = 1", 'shaft = "gear"'), "unbalance[0].shaft", "must be an integer"),
        (("shaft = 1", "shaft = 1.0"), "unbalance[0].shaft", "must be an integer"),
    ],
)
def test_bad_entry_names_the_key_and_the_file(change, key, words, tmp_path):
    path = unbalance_model(tmp_path, ENTRY.replace(*change))
    with pytest.raises(ModelError) as err:
        load_model(path)
    assert err.value.key == key and words in err.value.message, str(err.value)
    assert err.value.file == str(path) and "\n" not in str(err.value)


def test_unbalance_on_a_shaft_that_does_not_turn(tmp_path):
    text = SINGLE.read_text().replace("speed_ratio = 1.0", "speed_ratio = 0.0", 1)
    (tmp_path / "base.toml").write_text(text)
    entry = ENTRY.replace("shaft = 1", "shaft = 0")
    with pytest.raises(ModelError) as err:
        load_model(unbalance_model(tmp_path, entry, tmp_path / "base.toml"))
    assert err.value.key == "unbalance[0].shaft" and "does not turn" in err.value.message


def test_bad_entry_through_the_cli_is_one_line(tmp_path, capsys):
    path = unbalance_model(tmp_path, ENTRY.replace("amount = 1.0e-2", "amount = -1.0"))
    assert main(["sweep", str(path), "--rpm", "6000:7000:2", "--out", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "unbalance[0].amount" in err and "unbalance.toml" in err, err


def test_library_default_is_the_systems_unbalance():
    """build_link_model(system) takes system.unbalance (base = the shaft speed); an explicit
    ``unbalance=()`` wins (base = the mesh frequency, as without unbalance)."""
    system = dc.replace(load_model(TWO_SHAFT), unbalance=(Unbalance(1, 4, 1e-2, 0.3),))
    assert build_link_model(system).receptance.plan.speed_per_base == 1.0
    assert build_link_model(system, unbalance=()).receptance.plan.speed_per_base == pytest.approx(1 / 25)


def cli_sweep(path: Path, tmp_path: Path, capsys) -> pd.DataFrame:
    out = tmp_path / f"{path.stem}.csv"
    argv = ["sweep", str(path), "--rpm", f"{RPM[0]}:{RPM[1]}:{len(RPM)}", "--direction", "up"]
    argv += ["--harmonics", str(H), "--no-stability", "--out", str(out), "--quantity", "mesh0.dte_rms"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "links mesh0" in text and "base frequency = shaft (1 x the shaft speed)" in text, text
    df = pd.read_csv(out)
    np.testing.assert_allclose(df["shaft_speed [rpm]"], RPM, rtol=1e-12)  # --rpm: the pinion speed
    np.testing.assert_allclose(df["base_frequency [Hz]"], np.array(RPM) / 60, rtol=1e-12)
    assert df["converged"].all()
    return df


def mesh_columns(frame: pd.DataFrame) -> pd.DataFrame:
    """The mesh's outputs over the period; its harmonic amplitudes (``dte_amp_<k>``, per
    harmonic of the table's own base) are compared apart."""
    cols = [c for c in frame.columns if c.startswith("mesh0.") and ".dte_amp_" not in c]
    return frame[cols].astype(float)


def test_cli_sweep_with_unbalance_is_the_link_sweep(tmp_path, capsys):
    """The CSV of `nlgrd sweep` on a model file with [[unbalance]] holds the numbers of
    build_link_model + link_sweep with the same Unbalance on the model without it; with a
    zero amount, those of the model without unbalance (its own mesh-frequency base, H = 1
    mesh harmonic = 25 shaft harmonics)."""
    base = load_model(TWO_SHAFT)
    omegas = np.array(RPM) * math.pi / 30
    df = cli_sweep(unbalance_model(tmp_path), tmp_path, capsys)
    model = build_link_model(base, unbalance=[Unbalance(1, 4, 1e-2, 0.3)])
    direct = link_sweep(model, omegas, H=H, directions="up", stability=False).to_frame()
    np.testing.assert_allclose(mesh_columns(df), mesh_columns(direct), rtol=1e-9, atol=0)

    zero = cli_sweep(unbalance_model(tmp_path, ENTRY.replace("1.0e-2", "0.0"), name="zero"), tmp_path, capsys)
    plain = build_link_model(base)
    assert plain.receptance.plan.speed_per_base == pytest.approx(1 / 25)
    ref = link_sweep(plain, omegas * 25, H=1, directions="up", stability=False).to_frame()
    np.testing.assert_allclose(mesh_columns(zero), mesh_columns(ref), rtol=1e-9, atol=0)
    # the same mesh harmonic in both bases: the 25th shaft harmonic is the 1st mesh harmonic
    np.testing.assert_allclose(zero["mesh0.dte_amp_25 [um]"], ref["mesh0.dte_amp_1 [um]"], rtol=1e-9, atol=0)
    # the unbalance (1e-2 kg m on the gear blank) moves the DTE
    change = mesh_columns(df)["mesh0.dte_rms [um]"] / mesh_columns(zero)["mesh0.dte_rms [um]"] - 1
    assert (change.abs() > 1e-4).all(), change
