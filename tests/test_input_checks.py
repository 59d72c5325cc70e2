"""Physically absurd model input: one ModelError naming the file and the key (issue 9, item 5).

Every case starts from a shipped model (data/), copied to tmp_path and changed in one
spot, and checks both the library (load_model raises ModelError with the key) and the
command line (one line ``nlgrd: error: FILE: KEY: message``, exit status 2).
"""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np
import pytest

from nlgrd.cli import main
from nlgrd.errors import ModelError
from nlgrd.gear.lste_file import write_lste_csv
from nlgrd.io.model_file import load_model, model_from_dict
from nlgrd.io.model_writer import save_model

ROOT = Path(__file__).resolve().parents[1]
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
KB = ROOT / "data" / "case_studies" / "kahraman_blankenship.toml"
TWO = ROOT / "data" / "models" / "two_shaft.toml"
SINGLE = ROOT / "data" / "models" / "single_shaft.toml"
SHIPPED = [KUBO, KB, TWO, SINGLE]

# kubo.toml: the radial stiffness lines of its first two bearings (shaft 0, nodes 1 and 3)
KUBO_B0 = "shaft = 0\nnode = 1\nkyy = 0.3503e13\nkzz = 0.3503e13"
KUBO_B1 = "shaft = 0\nnode = 3\nkyy = 0.3503e13\nkzz = 0.3503e13"


def variant(tmp_path: Path, source: Path, *edits: tuple[str, str], name: str = "case.toml") -> Path:
    """``source`` copied to tmp_path with each (old, new) edit applied to its one occurrence."""
    text = source.read_text(encoding="utf-8")
    for old, new in edits:
        assert text.count(old) == 1, f"{old!r} is not unique in {source.name}"
        text = text.replace(old, new)
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def load_error(path: Path) -> ModelError:
    with pytest.raises(ModelError) as info:
        load_model(path)
    err = info.value
    assert "\n" not in str(err)
    assert err.file == str(path) and str(err).startswith(f"{path}: {err.key}: ")
    return err


def cli_error(path: Path, tmp_path: Path, capsys) -> str:
    """The one stderr line of ``nlgrd modes PATH`` (exit status 2)."""
    assert main(["modes", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    return err


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_shipped_models_pass_the_checks(path):
    """No false alarm on the shipped models."""
    load_model(path)


# ---------------------------------------------------------------------------- torque


def test_torque_giving_a_deflection_beyond_the_tooth_depth(tmp_path, capsys):
    """1e9 N m on Kubo's gears: W_0 / k_h = 82 m against a 9 mm tooth depth."""
    path = variant(tmp_path, KUBO, ("torque = 107.83", "torque = 1e9"))
    err = load_error(path)
    assert err.key == "gear_pairs[0].torque"
    assert "tooth depth" in err.message
    line = cli_error(path, tmp_path, capsys)
    assert line.startswith(f"nlgrd: error: {path}: gear_pairs[0].torque: "), line


def test_torque_check_with_computed_mesh_stiffness(tmp_path):
    """Kahraman & Blankenship's model has no mesh_stiffness: k_h from the geometry is used."""
    path = variant(tmp_path, KB, ("torque = 50.0", "torque = 1e9"))
    assert load_error(path).key == "gear_pairs[0].torque"


def test_large_but_possible_torque_loads(tmp_path):
    """Ten times Kubo's torque (a 89 um static deflection) is not an error."""
    load_model(variant(tmp_path, KUBO, ("torque = 107.83", "torque = 1078.3")))


# ---------------------------------------------------------------------------- damping


def test_mesh_damping_ratio_above_one(tmp_path, capsys):
    path = variant(tmp_path, KUBO, ("damping_ratio = 0.005", "damping_ratio = 5.0"))
    err = load_error(path)
    assert err.key == "gear_pairs[0].damping_ratio" and "above 1" in err.message
    assert f"{path}: gear_pairs[0].damping_ratio: " in cli_error(path, tmp_path, capsys)


def test_mesh_damping_ratio_of_one_is_allowed(tmp_path):
    """Critical damping is the limit, not an error."""
    load_model(variant(tmp_path, KUBO, ("damping_ratio = 0.005", "damping_ratio = 1.0")))


def test_material_loss_factor_above_two(tmp_path):
    """A hysteretic loss factor eta > 2 is an equivalent damping ratio eta / 2 above 1."""
    path = variant(tmp_path, KUBO, ("density = 7850.0\n", "density = 7850.0\nloss_factor = 3.0\n"))
    assert load_error(path).key == "materials.steel.loss_factor"


# ---------------------------------------------------------------------------- names


def test_duplicate_shaft_names(tmp_path, capsys):
    path = variant(tmp_path, KUBO, ('[[shafts]]\nname = "load"', '[[shafts]]\nname = "gear"'))
    err = load_error(path)
    assert err.key == "shafts[3].name" and "shafts[1]" in err.message
    assert f"{path}: shafts[3].name: " in cli_error(path, tmp_path, capsys)


def test_unnamed_shafts_are_not_duplicates(tmp_path):
    """Shafts left without a name (the default "") do not clash."""
    system = load_model(TWO)
    shafts = tuple(dataclasses.replace(s, name="") for s in system.shafts)
    path = tmp_path / "unnamed.toml"
    save_model(dataclasses.replace(system, shafts=shafts), path)
    load_model(path)


# ---------------------------------------------------------------------------- support


def _zero(text: str, keys: str = "yz") -> str:
    for k in keys:
        text = text.replace(f"k{k}{k} = 0.3503e13", f"k{k}{k} = 0.0")
    return text


def test_zero_bearings_leave_a_shaft_floating(tmp_path, capsys):
    """Both radial bearings of the pinion shaft at zero stiffness: the first one is named."""
    path = variant(tmp_path, KUBO, (KUBO_B0, _zero(KUBO_B0)), (KUBO_B1, _zero(KUBO_B1)))
    err = load_error(path)
    assert err.key == "bearings[0]" and "shaft 0" in err.message
    line = cli_error(path, tmp_path, capsys)
    assert line.startswith(f"nlgrd: error: {path}: bearings[0]: ") and "loads are not balanced" not in line


def test_one_zero_bearing_leaves_a_shaft_pivoting(tmp_path):
    """One of the two bearings of the pinion shaft at zero: the shaft pivots about the other."""
    path = variant(tmp_path, KUBO, (KUBO_B1, _zero(KUBO_B1)))
    err = load_error(path)
    assert err.key == "bearings[1]" and "pivot" in err.message


def test_zero_stiffness_in_one_direction(tmp_path):
    """kzz = 0 on both bearings of the motor stub: unsupported in z, the kzz key is named."""
    text = KUBO.read_text()
    stub = "shaft = 2\nnode = {}\nkyy = 1e9\nkzz = 1e9"
    edits = [(stub.format(n), stub.format(n).replace("kzz = 1e9", "kzz = 0.0")) for n in (0, 1)]
    assert all(text.count(old) == 1 for old, _ in edits)
    err = load_error(variant(tmp_path, KUBO, *edits))
    assert err.key == "bearings[4].kzz"


def test_free_free_rotor_is_legal(tmp_path):
    """No bearings at all, no gears: a free-free rotor (e.g. for an impact test), not an error."""
    system = load_model(SINGLE)
    path = tmp_path / "free.toml"
    save_model(dataclasses.replace(system, bearings=()), path)
    load_model(path)


def _without_bearings(tmp_path: Path, source: Path, drop: set[int]) -> Path:
    system = load_model(source)
    kept = tuple(b for j, b in enumerate(system.bearings) if j not in drop)
    path = tmp_path / "dropped.toml"
    save_model(dataclasses.replace(system, bearings=kept), path)
    return path


def test_loaded_gear_shaft_without_bearings(tmp_path, capsys):
    """Kubo's gear shaft with no bearing: the mesh load cannot be balanced (today's "loads are
    not balanced" at the sweep, without the file)."""
    path = _without_bearings(tmp_path, KUBO, {2, 3})
    err = load_error(path)
    assert err.key == "shafts[1]" and "gear_pairs[0]" in err.message
    line = cli_error(path, tmp_path, capsys)
    assert line.startswith(f"nlgrd: error: {path}: shafts[1]: "), line


def test_loaded_gear_shaft_on_one_bearing(tmp_path):
    """Kubo's gear shaft on its node-1 bearing only: it pivots, the mesh force at node 2 is off the pivot."""
    err = load_error(_without_bearings(tmp_path, KUBO, {3}))
    assert err.key == "shafts[1]" and "pivots about node 1" in err.message


def test_unloaded_stub_without_bearings_is_legal(tmp_path):
    """Kubo's load stub without bearings carries no gear and no zero bearing: legal."""
    load_model(_without_bearings(tmp_path, KUBO, {6, 7}))


def test_supports_other_than_bearings_count(tmp_path):
    """A shaft held by grounded couplings, or coupled to a supported shaft, is supported."""
    data = tomllib.loads(SINGLE.read_text())
    bearings = data.pop("bearings")
    grounded = [{"shaft_a": 0, "node_a": b["node"], "k_lateral": 1e8, "k_axial": 1e8} for b in bearings]
    model_from_dict({**data, "couplings": grounded})
    # a second, bearing-less shaft hanging on the first by a stiff coupling
    stub = {"name": "stub", "elements": [{"length": 0.1, "outer_diameter": 0.05}], "x_start": 1.2}
    coupled = {"shaft_a": 0, "node_a": 12, "shaft_b": 1, "node_b": 0, "k_lateral": 1e9, "k_tilt": 1e6}
    model_from_dict({**data, "bearings": bearings, "shafts": [*data["shafts"], stub], "couplings": [coupled]})


# ---------------------------------------------------------------------------- LSTE file


def _lste(path: Path, pp: float, column: str = "ste_um") -> None:
    """A sinusoidal LSTE of peak-to-peak ``pp`` [m], written as ``column``."""
    phase = np.arange(64) / 64
    ste = 0.5 * pp * np.cos(2 * np.pi * phase)
    if column == "ste_m":
        write_lste_csv(path, phase, ste, unit="m")
    else:
        write_lste_csv(path, phase, ste, unit="um")


def test_lste_file_in_micrometres_read_as_metres(tmp_path, capsys):
    """Values in um under a ste_m header: a 5 m fluctuation, named by the lste_file key."""
    lines = ["phase,ste_m"] + [f"{i / 64},{2.4 * np.cos(2 * np.pi * i / 64)}" for i in range(64)]
    (tmp_path / "lste.csv").write_text("\n".join(lines) + "\n")
    path = variant(tmp_path, KUBO, ("damping_ratio = 0.005", 'damping_ratio = 0.005\nlste_file = "lste.csv"'))
    err = load_error(path)
    assert err.key == "gear_pairs[0].lste_file" and "backlash" in err.message
    assert f"{path}: gear_pairs[0].lste_file: " in cli_error(path, tmp_path, capsys)


def test_lste_file_hundreds_of_times_the_backlash(tmp_path):
    """Kahraman & Blankenship's 15 um backlash against a 3 mm LSTE: below the tooth depth, still absurd."""
    _lste(tmp_path / "lste.csv", 3e-3)
    path = variant(tmp_path, KB, ("damping_ratio = 0.01", 'damping_ratio = 0.01\nlste_file = "lste.csv"'))
    err = load_error(path)
    assert err.key == "gear_pairs[0].lste_file" and "200" in err.message


def test_lste_file_beyond_the_tooth_depth_without_backlash(tmp_path):
    """Zero backlash: the tooth depth is still a bound."""
    _lste(tmp_path / "lste.csv", 0.02, column="ste_m")
    path = variant(
        tmp_path,
        KUBO,
        ("damping_ratio = 0.005", 'damping_ratio = 0.005\nlste_file = "lste.csv"'),
        ("backlash = 0.0001", "backlash = 0.0"),
    )
    assert load_error(path).key == "gear_pairs[0].lste_file"


@pytest.mark.parametrize("pp", [5e-6, 1e-4])
def test_plausible_lste_files_load(tmp_path, pp):
    """A few um, and even 7 x the backlash (100 um on Kahraman's 15 um), are accepted."""
    _lste(tmp_path / "lste.csv", pp)
    load_model(
        variant(tmp_path, KB, ("damping_ratio = 0.01", 'damping_ratio = 0.01\nlste_file = "lste.csv"'))
    )


def test_missing_lste_file_is_named_at_load(tmp_path):
    path = variant(
        tmp_path, KUBO, ("damping_ratio = 0.005", 'damping_ratio = 0.005\nlste_file = "nowhere.csv"')
    )
    err = load_error(path)
    assert err.key == "gear_pairs[0].lste_file" and "nowhere.csv" in err.message


# ---------------------------------------------------------------------------- robustness


def _gear_leaves(data):
    for key, value in data["gear_pairs"][0].items():
        if isinstance(value, dict):
            for sub in value:
                yield (key, sub)
        else:
            yield (key,)


@pytest.mark.parametrize("value", [0, -1.0, 1e300, 1e-300, True, "x"])
def test_gear_pair_values_give_model_errors_only(value):
    """Every gear-pair leaf of Kubo's model set to an odd value: a ModelError or a model, nothing else."""
    base = tomllib.loads(KUBO.read_text())
    for leaf in _gear_leaves(base):
        data = tomllib.loads(KUBO.read_text())
        target = data["gear_pairs"][0]
        for k in leaf[:-1]:
            target = target[k]
        target[leaf[-1]] = value
        try:
            model_from_dict(data, file="fuzz.toml")
        except ModelError as err:
            assert str(err).startswith("fuzz.toml: ") and "\n" not in str(err)
