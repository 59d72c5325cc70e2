"""`nlgrd sweep` on models with several meshes or a bearing clearance (issue 11, item 7):
the link sweep's CSV (every link's outputs as ``<link>.<quantity>``), the PNG of a chosen
link's quantity, and one-line errors for bad [[bearing_clearances]] entries."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from nlgrd.cli import main

ROOT = Path(__file__).resolve().parent.parent
IDLER = ROOT / "data" / "models" / "idler_train.toml"
TWO_SHAFT = ROOT / "data" / "models" / "two_shaft.toml"

CLEARANCE = """
[[bearing_clearances]]
name = "B1"
shaft = 0
node = 8
clearance = 20e-6
stiffness = 1.0e10
exponent = 1.5
damping = 1.0e3
"""


def clearance_model(tmp_path: Path, entry: str = CLEARANCE) -> Path:
    """two_shaft.toml with its pinion free-end bearing replaced by a radial clearance."""
    text = TWO_SHAFT.read_text()
    a = text.index('[[bearings]]\nname = "pinion, free end"')
    b = text.index('[[bearings]]\nname = "gear, left (locating)"')
    path = tmp_path / "clearance.toml"
    path.write_text(text[:a] + text[b:] + entry)
    return path


@pytest.mark.slow
def test_idler_train_sweep_writes_both_meshes(tmp_path, capsys):
    """Two meshes: columns of both, the base frequency (= mesh frequency) and the shaft
    speed base x 60 / 25 (25 input teeth, by hand); H chosen by the error estimate (on the
    ladder, within 0.5 % at every stable point); points without a stable periodic
    response have empty link columns; the PNG is written; progress is shown."""
    out = tmp_path / "idler.csv"
    argv = ["sweep", str(IDLER), "--hz", "1000:1200:2", "--direction", "up", "--out", str(out)]
    assert main([*argv, "--quantity", "mesh1.dslr"]) == 0
    captured = capsys.readouterr()
    text = captured.out
    assert "sweep: 2/2" in captured.err  # progress once per point, as on one mesh
    assert "links mesh0, mesh1" in text and "base frequency = mesh (25 x the shaft speed)" in text
    assert "(chosen; largest estimated error" in text  # the default: H by the estimate
    df = pd.read_csv(out)
    stable = df["stable"].eq(True)
    assert df.loc[stable, "H"].isin([5, 7, 9, 13, 17, 25]).all()
    assert df.loc[stable, "harmonic_error [-]"].le(5e-3).all()
    assert len(df) == 2 and (df["direction"] == "up").all()
    assert np.allclose(df["shaft_speed [rpm]"], df["base_frequency [Hz]"] * 60 / 25, rtol=1e-12)
    for q in ("dte_rms [um]", "force_max [N]", "dslr [-]", "contact_loss_fraction [-]"):
        for mesh in ("mesh0", "mesh1"):
            col = df[f"{mesh}.{q}"]
            assert col.notna().equals(df["stable"].eq(True)), (mesh, q)
    assert out.with_suffix(".png").stat().st_size > 0


def test_clearance_model_sweep_writes_the_bearing_link(tmp_path, capsys):
    """A [[bearing_clearances]] entry makes `nlgrd sweep` a link sweep with B1 columns; the
    journal runs on its clearance (the mesh load pushes it out): contact fraction 1 and a
    radial displacement beyond the 20 µm clearance."""
    out = tmp_path / "cl.csv"
    argv = ["sweep", str(clearance_model(tmp_path)), "--rpm", "2000:3000:3", "--direction", "up"]
    assert main([*argv, "--out", str(out), "--quantity", "B1.force_max", "--harmonics", "9"]) == 0
    text = capsys.readouterr().out
    assert "links B1, mesh0" in text and ", H = 9, " in text
    df = pd.read_csv(out)
    ok = df["stable"].eq(True)  # empty (not converged) is not stable
    assert ok.any()
    assert (df.loc[ok, "B1.contact_fraction [-]"] == 1).all()
    assert (df.loc[ok, "B1.displacement_max [um]"] > 20.0).all()


@pytest.mark.parametrize(
    "change, key",
    [
        (("exponent = 1.5", "exponent = 2.0"), "bearing_clearances[0].exponent"),
        (("node = 8\nclearance", "node = 80\nclearance"), "bearing_clearances[0].node"),
        (("clearance = 20e-6", "clearance = -1e-6"), "bearing_clearances[0].clearance"),
        (("damping = 1.0e3", "damping = 1.0e3\ncolour = 1"), "colour"),
    ],
)
def test_bad_clearance_entry_is_one_line(change, key, tmp_path, capsys):
    """Exit 2 and one line naming the file and the key."""
    path = clearance_model(tmp_path, CLEARANCE.replace(*change))
    assert main(["sweep", str(path), "--hz", "1000:1200:3", "--out", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and key in err and "clearance.toml" in err, err


def test_unknown_link_quantity_is_one_line(tmp_path, capsys):
    argv = ["sweep", str(IDLER), "--hz", "1000:1200:3", "--out", str(tmp_path / "x.csv")]
    assert main([*argv, "--quantity", "mesh7.dslr"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "mesh7" in err and "mesh0, mesh1" in err, err


def test_clearance_entries_survive_a_write_and_read(tmp_path):
    """save_model writes [[bearing_clearances]] and load_model reads back the same system."""
    from nlgrd.io.model_file import load_model
    from nlgrd.io.model_writer import save_model

    system = load_model(clearance_model(tmp_path))
    save_model(system, tmp_path / "again.toml")
    again = load_model(tmp_path / "again.toml")
    assert again == system and again.bearing_clearances[0].exponent == 1.5
