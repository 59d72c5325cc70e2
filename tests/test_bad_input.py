"""Bad input, table-driven (issue 36, items 7-9): each case is one line on stderr naming
the file and key (or the option) and exit status 2, or a correct run; never a traceback,
never exit 0 on nonsense.

Model-file cases edit a shipped model (data/models/two_shaft.toml) in one place and run
``nlgrd modes`` in-process: the model is read and checked before any computation, so a
case costs milliseconds. Option cases run the sub-command in-process with the
computation forbidden where the option must be refused first; a few run as a subprocess
to prove the exit status of the real command.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
import tomllib
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

import nlgrd.nonlinear.models.link_model
import nlgrd.rotor.modal
from nlgrd.cli import main

ROOT = Path(__file__).resolve().parents[1]
TWO = ROOT / "data" / "models" / "two_shaft.toml"
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
IDLER = ROOT / "data" / "models" / "idler_train.toml"
TWO_STAGE = ROOT / "data" / "models" / "two_stage.toml"
NLGRD = [sys.executable, "-m", "nlgrd.cli"]

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
UNBALANCE = """
[[unbalance]]
shaft = 0
node = 5
amount = 1e-4
phase = 0.0
"""
PAIR = TWO.read_text()[TWO.read_text().index("[[gear_pairs]]") :]


def _edit(old: str, new: str):
    return ("edit", old, new)


def _add(text: str):
    return ("add", text, "")


def _after(anchor: str, line: str):
    """Insert ``line`` after the first occurrence of ``anchor``."""
    return ("edit", anchor, anchor + "\n" + line)


def model_variant(tmp_path: Path, change) -> Path:
    """two_shaft.toml with one change: the first occurrence of a text replaced, or a text
    appended."""
    kind, a, b = change
    text = TWO.read_text(encoding="utf-8")
    if kind == "edit":
        assert a in text, a
        text = text.replace(a, b, 1)
    else:
        text += a
    path = tmp_path / "case.toml"
    path.write_text(text, encoding="utf-8")
    return path


def run(capsys, *argv) -> tuple[int, str, str]:
    """``nlgrd ARGV`` in-process: (status, stdout, stderr); argparse's exit is a status."""
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as stop:
        rc = stop.code
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith("nlgrd: error: "), lines[0]
    return lines[0]


@pytest.fixture
def no_computation(monkeypatch):
    """Any computation fails the test: the input must be refused before."""

    def forbidden(*args, **kwargs):
        raise AssertionError("computation started before the input was checked")

    for name in ("build_link_model", "link_sweep", "link_continuation"):
        monkeypatch.setattr(nlgrd.nonlinear.models.link_model, name, forbidden)
    for name in ("modal_analysis", "campbell"):
        monkeypatch.setattr(nlgrd.rotor.modal, name, forbidden)


# ----------------------------------------------------------------------- model file

MODEL_CASES = {
    # materials
    "density negative": (_edit("density = 7850.0", "density = -7850.0"), "materials.steel.density"),
    "density above osmium": (_edit("density = 7850.0", "density = 7.85e5"), "materials.steel.density"),
    "density a string": (_edit("density = 7850.0", 'density = "7850"'), "materials.steel.density"),
    "E 2.1e30 (issue)": (
        _edit("young_modulus = 2.1e11", "young_modulus = 2.1e30"),
        "materials.steel.young_modulus",
    ),
    "E in GPa": (_edit("young_modulus = 2.1e11", "young_modulus = 210.0"), "materials.steel.young_modulus"),
    "E in MPa": (_edit("young_modulus = 2.1e11", "young_modulus = 2.1e5"), "materials.steel.young_modulus"),
    "E zero": (_edit("young_modulus = 2.1e11", "young_modulus = 0.0"), "materials.steel.young_modulus"),
    "E nan": (_edit("young_modulus = 2.1e11", "young_modulus = nan"), "materials.steel.young_modulus"),
    "nu 0.5": (_edit("poisson_ratio = 0.3", "poisson_ratio = 0.5"), "materials.steel.poisson_ratio"),
    "nu negative": (_edit("poisson_ratio = 0.3", "poisson_ratio = -0.2"), "materials.steel.poisson_ratio"),
    "nu 3 (percent?)": (
        _edit("poisson_ratio = 0.3", "poisson_ratio = 30.0"),
        "materials.steel.poisson_ratio",
    ),
    "viscous damping negative": (
        _edit("viscous_damping = 0.0", "viscous_damping = -1e-5"),
        "materials.steel.viscous_damping",
    ),
    "loss factor above 2": (_edit("loss_factor = 0.0", "loss_factor = 3.0"), "materials.steel.loss_factor"),
    "material key misspelt": (_edit("loss_factor = 0.0", "los_factor = 0.0"), "materials.steel.los_factor"),
    "unknown material": (_edit('material = "steel"', 'material = "stell"'), "shafts[0].elements[0].material"),
    # shafts
    "element length negative": (_edit("length = 0.06", "length = -0.06"), "shafts[0].elements[0].length"),
    "element length zero": (_edit("length = 0.06", "length = 0.0"), "shafts[0].elements[0].length"),
    "outer diameter zero": (
        _edit("outer_diameter = 0.035", "outer_diameter = 0.0"),
        "shafts[0].elements[0].outer_diameter",
    ),
    "outer diameter inf": (
        _edit("outer_diameter = 0.035", "outer_diameter = inf"),
        "shafts[0].elements[0].outer_diameter",
    ),
    "bore above outer diameter": (
        _after("outer_diameter = 0.035", "inner_diameter = 0.05"),
        "shafts[0].elements[0].inner_diameter",
    ),
    "element count zero": (_edit("count = 2", "count = 0"), "shafts[0].elements[0].count"),
    "element count fractional": (_edit("count = 2", "count = 2.5"), "shafts[0].elements[0].count"),
    "element key misspelt": (
        _edit("outer_diameter = 0.035", "outer_diametre = 0.035"),
        "shafts[0].elements[0].outer_diametre",
    ),
    "speed ratio a word": (_edit("speed_ratio = 1.0", 'speed_ratio = "fast"'), "shafts[0].speed_ratio"),
    "x_start inf": (_edit("x_start = 0.0", "x_start = inf"), "shafts[0].x_start"),
    "shaft names repeated": (_edit('name = "gear"\n', 'name = "pinion"\n'), "shafts[1].name"),
    "shaft without elements": (
        _edit("[[shafts.elements]]\ncount = 2", "[[shafts.elementz]]\ncount = 2"),
        "shafts[0].elementz",
    ),
    # disks
    "disk mass negative": (_edit("mass = 5.057", "mass = -5.057"), "disks[0].mass"),
    "disk node beyond the shaft": (
        _edit("shaft = 0\nnode = 0\nmass = 5.057", "shaft = 0\nnode = 99\nmass = 5.057"),
        "disks[0].node",
    ),
    "disk shaft missing": (
        _edit("shaft = 0\nnode = 0\nmass = 5.057", "shaft = 7\nnode = 0\nmass = 5.057"),
        "disks[0].shaft",
    ),
    "disk inertia negative": (
        _edit("diametral_inertia = 6.295e-3", "diametral_inertia = -6.295e-3"),
        "disks[0].diametral_inertia",
    ),
    "disk polar inertia nan": (
        _edit("polar_inertia = 5.762e-3", "polar_inertia = nan"),
        "disks[0].polar_inertia",
    ),
    "disk key misspelt": (_edit("mass = 5.057", "mas = 5.057"), "disks[0].mas"),
    # bearings
    "bearing kyy negative": (_edit("kyy = 1.5e8", "kyy = -1.5e8"), "bearings[0].kyy"),
    "bearing cyy nan": (_edit("cyy = 1.0e3", "cyy = nan"), "bearings[0].cyy"),
    "bearing kxx a word": (_edit("kxx = 5.0e7", 'kxx = "stiff"'), "bearings[0].kxx"),
    "bearing node beyond the shaft": (
        _edit("shaft = 0\nnode = 2\nkyy", "shaft = 0\nnode = 99\nkyy"),
        "bearings[0].node",
    ),
    "bearing shaft missing": (
        _edit("shaft = 0\nnode = 2\nkyy", "shaft = 5\nnode = 2\nkyy"),
        "bearings[0].shaft",
    ),
    "bearing key misspelt": (_edit("kyy = 1.5e8", "kyyy = 1.5e8"), "bearings[0].kyyy"),
    # couplings
    "coupling damping negative": (_edit("c_torsion = 0.2", "c_torsion = -0.2"), "couplings[0].c_torsion"),
    "coupling node beyond the shaft": (_edit("node_a = 0", "node_a = 77"), "couplings[0].node_a"),
    "coupling shaft missing": (_edit("shaft_a = 0", "shaft_a = 9"), "couplings[0].shaft_a"),
    # gear pairs
    "torque nan": (_edit("torque = 108.0", "torque = nan"), "gear_pairs[0].torque"),
    "torque a word": (_edit("torque = 108.0", 'torque = "high"'), "gear_pairs[0].torque"),
    "mesh stiffness negative": (
        _edit("mesh_stiffness = 0.2587e9", "mesh_stiffness = -0.2587e9"),
        "gear_pairs[0].mesh_stiffness",
    ),
    "mesh damping ratio negative": (
        _edit("damping_ratio = 0.005", "damping_ratio = -0.005"),
        "gear_pairs[0].damping_ratio",
    ),
    "pinion node beyond the shaft": (
        _edit("pinion_node = 5", "pinion_node = 50"),
        "gear_pairs[0].pinion_node",
    ),
    "gear shaft missing": (_edit("gear_shaft = 1", "gear_shaft = 4"), "gear_pairs[0].gear_shaft"),
    "input node beyond the shaft": (_edit("input_node = 0", "input_node = 99"), "gear_pairs[0].input_node"),
    "driver unknown": (_after("torque = 108.0", 'driver = "wheel"'), "gear_pairs[0].driver"),
    "gear pair key misspelt": (_edit("torque = 108.0", "torqe = 108.0"), "gear_pairs[0].torqe"),
    "same gear pair twice (issue)": (_add("\n" + PAIR), "gear_pairs[1]"),
    "too few pinion teeth": (
        _edit("teeth_pinion = 25", "teeth_pinion = 3"),
        "gear_pairs[0].geometry.teeth_pinion",
    ),
    "fractional teeth": (
        _edit("teeth_pinion = 25", "teeth_pinion = 25.5"),
        "gear_pairs[0].geometry.teeth_pinion",
    ),
    "module zero": (_edit("module = 0.004", "module = 0.0"), "gear_pairs[0].geometry.module"),
    "module in mm": (_edit("module = 0.004", "module = 4.0"), "gear_pairs[0].gear_shaft: shaft centres"),
    "face width negative": (
        _edit("face_width = 0.015", "face_width = -0.015"),
        "gear_pairs[0].geometry.face_width",
    ),
    "backlash negative": (
        _edit("backlash = 0.0001", "backlash = -0.0001"),
        "gear_pairs[0].geometry.backlash",
    ),
    "gear E 2.1e30": (
        _after("backlash = 0.0001", "young_modulus = 2.1e30"),
        "gear_pairs[0].geometry.young_modulus",
    ),
    "gear nu 0.6": (
        _after("backlash = 0.0001", "poisson_ratio = 0.6"),
        "gear_pairs[0].geometry.poisson_ratio",
    ),
    "geometry key misspelt": (
        _edit("face_width = 0.015", "facewidth = 0.015"),
        "gear_pairs[0].geometry.facewidth",
    ),
    "missing LSTE file": (
        _after("torque = 108.0", 'lste_file = "no_such_lste.csv"'),
        "gear_pairs[0].lste_file",
    ),
    "missing stiffness file": (
        _after("torque = 108.0", 'stiffness_file = "no_such_k.csv"'),
        "gear_pairs[0].stiffness_file",
    ),
    "stiffness variation unknown": (
        _after("torque = 108.0", 'stiffness_variation = "wobbly"'),
        "gear_pairs[0].stiffness_variation",
    ),
    # bearing clearances
    "clearance negative": (
        _add(CLEARANCE.replace("clearance = 20e-6", "clearance = -20e-6")),
        "bearing_clearances[0].clearance",
    ),
    "clearance stiffness zero": (
        _add(CLEARANCE.replace("stiffness = 1.0e10", "stiffness = 0.0")),
        "bearing_clearances[0].stiffness",
    ),
    "clearance exponent negative": (
        _add(CLEARANCE.replace("exponent = 1.5", "exponent = -1.5")),
        "bearing_clearances[0].exponent",
    ),
    "clearance damping negative": (
        _add(CLEARANCE.replace("damping = 1.0e3", "damping = -1.0e3")),
        "bearing_clearances[0].damping",
    ),
    "clearance node beyond the shaft": (
        _add(CLEARANCE.replace("node = 8", "node = 99")),
        "bearing_clearances[0].node",
    ),
    "clearance shaft missing": (
        _add(CLEARANCE.replace("shaft = 0", "shaft = 9")),
        "bearing_clearances[0].shaft",
    ),
    "clearance key misspelt": (
        _add(CLEARANCE.replace("clearance = 20e-6", "clearence = 20e-6")),
        "bearing_clearances[0].clearence",
    ),
    # unbalance
    "unbalance amount negative": (
        _add(UNBALANCE.replace("amount = 1e-4", "amount = -1e-4")),
        "unbalance[0].amount",
    ),
    "unbalance node beyond the shaft": (
        _add(UNBALANCE.replace("node = 5", "node = 99")),
        "unbalance[0].node",
    ),
    "unbalance shaft missing": (_add(UNBALANCE.replace("shaft = 0", "shaft = 9")), "unbalance[0].shaft"),
    "unbalance phase nan": (_add(UNBALANCE.replace("phase = 0.0", "phase = nan")), "unbalance[0].phase"),
    # the whole rotor's damping
    "damping floor negative": (_add("\n[damping]\nmodal_floor = -0.01\n"), "damping.modal_floor"),
    "damping floor critical": (_add("\n[damping]\nmodal_floor = 1.0\n"), "damping.modal_floor"),
    "damping floor a string": (_add('\n[damping]\nmodal_floor = "1%"\n'), "damping.modal_floor"),
    "Rayleigh alpha negative": (_add("\n[damping]\nrayleigh_alpha = -5.0\n"), "damping.rayleigh_alpha"),
    "Rayleigh beta inf": (_add("\n[damping]\nrayleigh_beta = inf\n"), "damping.rayleigh_beta"),
    "damping key misspelt": (_add("\n[damping]\nmodal_flor = 0.01\n"), "damping.modal_flor"),
    # the file as a whole
    "format version 2": (_edit("version = 1", "version = 2"), "version"),
    "unknown section": (_add("\n[[bearing]]\nshaft = 0\nnode = 2\n"), "bearing: unknown key"),
    "not TOML": (_add("\nthis is = = not toml\n"), "TOML syntax error"),
}


@pytest.mark.parametrize("change, key", list(MODEL_CASES.values()), ids=list(MODEL_CASES))
def test_bad_model_file(tmp_path, capsys, change, key):
    path = model_variant(tmp_path, change)
    rc, _, err = run(capsys, "modes", path, "--out", tmp_path / "out")
    line = one_line(err)
    assert rc == 2 and line.startswith(f"nlgrd: error: {path}: {key}"), line
    assert not (tmp_path / "out").exists()


ACCEPTED = {
    "near-massless shaft (Kubo's idealisation)": _edit("density = 7850.0", "density = 7.85"),
    "Poisson ratio 0": _edit("poisson_ratio = 0.3", "poisson_ratio = 0.0"),
    "diamond's modulus": _edit("young_modulus = 2.1e11", "young_modulus = 1.2e12"),
    "damping floor and Rayleigh": _add(
        "\n[damping]\nmodal_floor = 0.02\nrayleigh_alpha = 1.0\nrayleigh_beta = 1e-7\n"
    ),
}


@pytest.mark.parametrize("change", list(ACCEPTED.values()), ids=list(ACCEPTED))
def test_edge_of_the_ranges_runs(tmp_path, capsys, change):
    """The ends of the material ranges are legal models: ``modes`` runs and writes."""
    path = model_variant(tmp_path, change)
    rc, out, err = run(capsys, "modes", path, "--out", tmp_path / "out")
    assert rc == 0 and err == "", err
    assert (tmp_path / "out" / "case_modes.csv").is_file()


def test_missing_empty_binary_and_folder_model_files(tmp_path, capsys):
    empty, binary = tmp_path / "empty.toml", tmp_path / "binary.toml"
    empty.write_text("")
    binary.write_bytes(b"\xff\xfe\x00version = 1")
    for path in (tmp_path / "nothing.toml", empty, binary, tmp_path):
        rc, _, err = run(capsys, "modes", path, "--out", tmp_path / "out")
        line = one_line(err)
        assert rc == 2 and str(path) in line, line


# ----------------------------------------------------------------------- options

OPTION_CASES = {
    "rpm down (issue)": (["sweep", KUBO, "--rpm", "5:1:10"], "--rpm", "START must be below STOP"),
    "hz down": (["sweep", KUBO, "--hz", "5000:3000:11"], "--hz", "START must be below STOP"),
    "campbell rpm down": (["campbell", TWO, "--rpm", "100:0:5"], "--rpm", "below STOP"),
    "rpm equal ends": (["sweep", KUBO, "--rpm", "4000:4000:3"], "--rpm", "below STOP"),
    "rpm 1e9 (issue)": (["sweep", KUBO, "--rpm", "1e9:2e9:3"], "--rpm", "pitch-line velocity"),
    "hz far beyond": (["sweep", KUBO, "--hz", "1e6:2e6:3"], "--hz", "pitch-line velocity"),
    "rpm 1e9, two meshes": (["sweep", IDLER, "--rpm", "1e9:2e9:3"], "--rpm", "pitch-line velocity"),
    "hz far beyond, two meshes": (["sweep", IDLER, "--hz", "1e6:2e6:3"], "--hz", "pitch-line velocity"),
    "continuation beyond": (["sweep", KUBO, "--rpm", "1e5:1e6", "--continuation"], "--rpm", "pitch-line"),
    "rpm a word": (["sweep", KUBO, "--rpm", "fast"], "--rpm", "START:STOP:COUNT"),
    "rpm four parts": (["sweep", KUBO, "--rpm", "1:2:3:4"], "--rpm", "START:STOP:COUNT"),
    "rpm two parts": (["sweep", KUBO, "--rpm", "1000:2000"], "--rpm", "START:STOP:COUNT"),
    "count fractional": (["sweep", KUBO, "--rpm", "1000:2000:2.5"], "--rpm", "COUNT"),
    "no range": (["sweep", KUBO], "--rpm", "--hz"),
    "rpm and hz": (["sweep", KUBO, "--rpm", "1000:2000:3", "--hz", "400:800:3"], "--rpm", "--hz"),
    "harmonics 0": (["sweep", KUBO, "--rpm", "4000:5000:3", "--harmonics", "0"], "--harmonics", "at least 1"),
    "harmonics beyond memory": (
        ["sweep", KUBO, "--rpm", "4000:5000:3", "--harmonics", "100000000"],
        "--harmonics",
        "more memory than available",
    ),
    "harmonics a word": (
        ["sweep", KUBO, "--rpm", "4000:5000:3", "--harmonics", "many"],
        "--harmonics",
        "int",
    ),
    "direction sideways": (
        ["sweep", KUBO, "--rpm", "4000:5000:3", "--direction", "sideways"],
        "--direction",
        "up",
    ),
    "period 7": (["sweep", KUBO, "--rpm", "4000:5000:3", "--period", "7"], "--period", "1 to 6"),
    "period a word": (["sweep", KUBO, "--rpm", "4000:5000:3", "--period", "x"], "--period", "1 to 6"),
    "search beside continuation": (
        ["sweep", KUBO, "--rpm", "4000:5000", "--continuation", "--search-at", "4500"],
        "--search-at",
        "continuation",
    ),
    "search at a word": (
        ["sweep", KUBO, "--rpm", "4000:5000:3", "--search-at", "abc"],
        "--search-at",
        "comma-separated",
    ),
    "search periods 9": (
        ["sweep", KUBO, "--rpm", "4000:5000:3", "--search-at", "4500", "--search-periods", "9"],
        "--search-periods",
        "1 to 6",
    ),
    "link quantity on a gear model": (
        ["sweep", KUBO, "--rpm", "4000:5000:3", "--quantity", "mesh9.dslr"],
        "--quantity",
        "no link 'mesh9'",
    ),
    "modes rpm range": (["modes", TWO, "--rpm", "1:2:3"], "--rpm", "one speed"),
    "modes n-modes a word": (["modes", TWO, "--n-modes", "six"], "--n-modes", "int"),
    "campbell orders a word": (["campbell", TWO, "--orders", "one"], "--orders", "numbers"),
    "lste pair a word": (["lste", TWO, "--pair", "first"], "--pair", "int"),
    "unknown option": (["modes", TWO, "--speed", "3"], "unrecognized arguments", "--speed"),
    "unknown command": (["modal", TWO], "argument COMMAND", "modal"),
}


@pytest.mark.usefixtures("no_computation")
@pytest.mark.parametrize(("argv", "option", "fragment"), list(OPTION_CASES.values()), ids=list(OPTION_CASES))
def test_bad_option(tmp_path, capsys, argv, option, fragment):
    out = tmp_path / "x.csv" if argv[0] == "sweep" else tmp_path / "out"
    rc, _, err = run(capsys, *argv, "--out", out)
    line = one_line(err)
    assert rc == 2 and option in line and fragment in line, line
    assert not out.exists()


# ----------------------------------------------------------------------- study files

STUDY = f"""version = 1
name = "bad input"
model = "{KUBO.as_posix()}"
[analysis]
rpm = [6000.0, 12000.0, 7]
direction = "up"
harmonics = 5
stability = false
[[axes]]
key = "gear_pairs[0].geometry.backlash"
values = [50e-6, 100e-6]
[[axes]]
key = "gear_pairs[0].damping_ratio"
range = [0.02, 0.08, 4]
"""

STUDY_CASES = {
    "rpm down": (("rpm = [6000.0, 12000.0, 7]", "rpm = [12000.0, 6000.0, 7]"), "analysis.rpm"),
    "rpm count 1": (("rpm = [6000.0, 12000.0, 7]", "rpm = [6000.0, 12000.0, 1]"), "analysis.rpm"),
    "rpm words": (("rpm = [6000.0, 12000.0, 7]", 'rpm = ["slow", "fast", 7]'), "analysis.rpm"),
    "rpm 1e9": (("rpm = [6000.0, 12000.0, 7]", "rpm = [1e9, 2e9, 3]"), "analysis.rpm"),
    "rpm and hz": (("rpm = [6000.0, 12000.0, 7]", "rpm = [6000.0, 12000.0, 7]\nhz = [1, 2, 3]"), "analysis"),
    "harmonics 0": (("harmonics = 5", "harmonics = 0"), "analysis.harmonics"),
    "harmonics beyond memory": (("harmonics = 5", "harmonics = 100000000"), "analysis.harmonics"),
    "stability a word": (("stability = false", 'stability = "no"'), "analysis.stability"),
    "time_domain a word": (
        ("stability = false", 'stability = false\ntime_domain = "no"'),
        "analysis.time_domain",
    ),
    "analysis key misspelt": (("harmonics = 5", "harmonic = 5"), "analysis.harmonic"),
    "tolerance negative": (("harmonics = 5", "tolerance = -0.01"), "analysis.tolerance"),
    "model missing": ((f'model = "{KUBO.as_posix()}"', 'model = "no_such_model.toml"'), "model"),
    "version 3": (("version = 1", "version = 3"), "version"),
    "top-level key misspelt": (('name = "bad input"', 'nme = "bad input"'), "nme"),
    "axis key unknown": (
        ('key = "gear_pairs[0].geometry.backlash"', 'key = "gear_pairs[0].geometry.backlsh"'),
        "axes[0]",
    ),
    "axis value negative": (("values = [50e-6, 100e-6]", "values = [50e-6, -100e-6]"), "axes[0].values[1]"),
    "axis values empty": (("values = [50e-6, 100e-6]", "values = []"), "axes[0].values"),
    "axis range count 0": (("range = [0.02, 0.08, 4]", "range = [0.02, 0.08, 0]"), "axes[1].range"),
    "axis log spacing from 0": (
        ("range = [0.02, 0.08, 4]", 'range = [0.0, 0.08, 4]\nspacing = "log"'),
        "axes[1]",
    ),
    "axis spacing unknown": (
        ("range = [0.02, 0.08, 4]", 'range = [0.02, 0.08, 4]\nspacing = "cubic"'),
        "axes[1].spacing",
    ),
    "axis values and range": (
        ("range = [0.02, 0.08, 4]", "range = [0.02, 0.08, 4]\nvalues = [0.1]"),
        "axes[1]",
    ),
    "axis same key twice": (
        ('key = "gear_pairs[0].damping_ratio"', 'key = "gear_pairs[0].geometry.backlash"'),
        "axes: two axes",
    ),
    "distribution unknown": (
        ("range = [0.02, 0.08, 4]", 'distribution = "cauchy"\nmean = 0.05\nstd = 0.01'),
        "axes[1].distribution: must be one of normal, uniform",
    ),
    "std negative": (
        (
            "range = [0.02, 0.08, 4]",
            'distribution = "normal"\nmean = 0.05\nstd = -0.01\n[sampling]\nsamples = 4\nseed = 1',
        ),
        "axes[1].std",
    ),
    "sampling method unknown": (
        (
            "range = [0.02, 0.08, 4]",
            'distribution = "normal"\nmean = 0.05\nstd = 0.01\n'
            '[sampling]\nsamples = 4\nseed = 1\nmethod = "sobel"',
        ),
        "sampling.method",
    ),
    "samples zero": (
        (
            "range = [0.02, 0.08, 4]",
            'distribution = "normal"\nmean = 0.05\nstd = 0.01\n[sampling]\nsamples = 0\nseed = 1',
        ),
        "sampling.samples",
    ),
}


@pytest.mark.parametrize(("edit", "key"), list(STUDY_CASES.values()), ids=list(STUDY_CASES))
def test_bad_study_file(tmp_path, capsys, monkeypatch, edit, key):
    monkeypatch.chdir(tmp_path)
    text = STUDY.replace(*edit)
    assert text != STUDY
    path = tmp_path / "s.toml"
    path.write_text(text)
    rc, _, err = run(capsys, "study", path, "--executor", "serial", "--no-progress")
    line = one_line(err)
    assert rc == 2 and line.startswith(f"nlgrd: error: {path}: {key}"), line
    assert not (tmp_path / "s").exists()  # nothing ran


def test_study_speeds_read_as_the_base_frequency_of_a_link_model(tmp_path, capsys, monkeypatch):
    """A study's ``hz`` is the base frequency, as in ``nlgrd sweep --hz``: on two_stage.toml
    (base = 5 x the input shaft's speed, input pinion 25 teeth) 10 kHz is 120,000 rpm of the
    input shaft, 628 m/s at its pinion's pitch line (limit 300 m/s at 57,296 rpm). Read as the
    first pair's mesh frequency (the old reading) it was 24,000 rpm and passed."""
    monkeypatch.chdir(tmp_path)
    text = STUDY.replace(f'model = "{KUBO.as_posix()}"', f'model = "{TWO_STAGE.as_posix()}"')
    text = text.replace("rpm = [6000.0, 12000.0, 7]", "hz = [1000.0, 10000.0, 3]")
    path = tmp_path / "s.toml"
    path.write_text(text)
    rc, _, err = run(capsys, "study", path, "--executor", "serial", "--no-progress")
    line = one_line(err)
    assert rc == 2 and line.startswith(f"nlgrd: error: {path}: analysis.hz") and "pitch-line" in line, line
    assert not (tmp_path / "s").exists()


def test_study_harmonics_bounded_by_memory_as_the_command_line(tmp_path):
    """A study's ``analysis.harmonics`` has the bound of ``--harmonics`` (memory, issue 35
    item 1), not the old constant 50: 75 (what a stiff contact needs) loads on Kubo's model;
    a number beyond memory is refused by STUDY_CASES."""
    from nlgrd.io.model_checks import check_harmonics_memory
    from nlgrd.io.model_file import load_model
    from nlgrd.studies.study_file import load_study

    path = tmp_path / "s.toml"
    path.write_text(STUDY.replace("harmonics = 5", "harmonics = 75"))
    study = load_study(path)
    assert study.analysis.harmonics == 75
    check_harmonics_memory(load_model(KUBO), 75, "--harmonics")  # the CLI's bound accepts it too


# ----------------------------------------------------------------------- reports, schedulers

NB = "01_kubo_dynamic_factor"
NB_FILE = ROOT / "notebooks" / f"{NB}.ipynb"
REPORT_CASES = {
    "no such notebook (issue)": (["report", "99_nothing"], "notebook: no notebook '99_nothing'"),
    "points a word (issue)": (
        ["report", NB, "-p", "points", "abc"],
        "parameters.points: the notebook expects int",
    ),
    "H fractional": (["report", NB, "-p", "H", "2.5"], "parameters.H: the notebook expects int or None"),
    "fast a word": (["report", NB, "-p", "fast", "maybe"], "parameters.fast: the notebook expects bool"),
    "fast a number": (["report", NB, "-p", "fast", "1"], "parameters.fast: the notebook expects bool"),
    "rpm_min a word": (
        ["report", NB, "-p", "rpm_min", "low"],
        "parameters.rpm_min: the notebook expects float",
    ),
    "damping band a number": (
        ["report", NB, "-p", "damping_band", "0.1"],
        "parameters.damping_band: the notebook",
    ),
    "model file a number": (
        ["report", NB, "-p", "model_file", "3"],
        "parameters.model_file: the notebook expects str",
    ),
    "unknown parameter": (["report", NB, "-p", "pionts", "3"], "parameters.pionts: not a parameter"),
    "out_dir given": (["report", NB, "-p", "out_dir", "x"], "-p out_dir"),
    "workers 0": (["report", NB, "--workers", "0"], "--workers"),
    "batch file missing": (["report", NB, "--batch", "no_such_batch.toml"], "no_such_batch.toml"),
    "executor unknown": (["report", NB, "--executor", "threads"], "--executor"),
    "report tls without certificates (issue)": (
        ["report", NB, "--scheduler", "tls://127.0.0.1:8786"],
        "--scheduler: tls://127.0.0.1:8786 needs the client's TLS certificates: set "
        "distributed.comm.tls.ca-file",
    ),
    "report scheduler without scheme": (
        ["report", NB, "--scheduler", "head:8786"],
        "--scheduler: expected tcp://",
    ),
    "report timeout negative": (["report", NB, "--connect-timeout", "-1"], "--connect-timeout"),
    "study tls without certificates (issue)": (
        ["study", ROOT / "data" / "studies" / "kubo_jump_band.toml", "--scheduler", "tls://head:8786"],
        "--scheduler: tls://head:8786 needs the client's TLS certificates",
    ),
    "study scheduler http": (
        ["study", ROOT / "data" / "studies" / "kubo_jump_band.toml", "--scheduler", "http://head:8786"],
        "--scheduler: expected tcp://",
    ),
    "study timeout zero": (
        ["study", ROOT / "data" / "studies" / "kubo_jump_band.toml", "--connect-timeout", "0"],
        "--connect-timeout",
    ),
    "study timeout a word": (
        ["study", ROOT / "data" / "studies" / "kubo_jump_band.toml", "--connect-timeout", "soon"],
        "--connect-timeout",
    ),
    "study workers 0": (
        ["study", ROOT / "data" / "studies" / "kubo_jump_band.toml", "--workers", "0"],
        "--workers",
    ),
    "study file missing": (["study", "no_such_study.toml"], "no_such_study.toml"),
}


@pytest.fixture
def no_run(monkeypatch):
    """Running a notebook or a study task fails the test: the input must be refused before."""
    import nlgrd.studies.batch_reports
    import nlgrd.studies.study_runner

    def forbidden(*args, **kwargs):
        raise AssertionError("a run started before the input was checked")

    monkeypatch.setattr(nlgrd.studies.batch_reports, "run_report", forbidden)
    monkeypatch.setattr(nlgrd.studies.study_runner, "run_task", forbidden)


@pytest.mark.usefixtures("no_run")
@pytest.mark.parametrize(("argv", "fragment"), list(REPORT_CASES.values()), ids=list(REPORT_CASES))
def test_bad_report_or_study_option(tmp_path, capsys, monkeypatch, argv, fragment):
    monkeypatch.chdir(tmp_path)
    for name in [k for k in os.environ if k.startswith("DASK_DISTRIBUTED__COMM__TLS")]:
        monkeypatch.delenv(name)
    rc, _, err = run(capsys, *argv)
    line = one_line(err)
    assert rc == 2 and fragment in line, line
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_closed_scheduler_port_fails_fast(tmp_path, capsys, monkeypatch):
    """A scheduler address where nothing listens (a loopback port just freed) is one line
    naming --scheduler within about the connect timeout (1 s here), not Dask's 30 s."""
    monkeypatch.chdir(tmp_path)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    study = ROOT / "data" / "studies" / "kubo_jump_band.toml"
    t0 = time.perf_counter()
    rc, _, err = run(
        capsys, "study", study, "--scheduler", f"tcp://127.0.0.1:{port}", "--connect-timeout", "1"
    )
    elapsed = time.perf_counter() - t0
    line = one_line(err)
    assert rc == 2 and line.startswith(
        f"nlgrd: error: --scheduler: no Dask scheduler answered at tcp://127.0.0.1:{port}"
    )
    assert elapsed < 10, elapsed  # loading the study takes a few s; Dask's default wait alone is 30 s


# ----------------------------------------------------------------------- faults and outputs


@pytest.mark.parametrize(
    "argv",
    [
        ["sweep", KUBO, "--rpm", "5:1:10"],
        ["sweep", KUBO, "--rpm", "1e9:2e9:3"],
        ["report", "99_nothing"],
        ["modes", TWO, "--rpm", "fast"],
    ],
    ids=["rpm down", "rpm 1e9", "no notebook", "modes rpm a word"],
)
def test_the_real_command_exits_2_with_one_line(tmp_path, argv):
    """The installed command as a user runs it: status 2, one line, nothing on stdout."""
    r = subprocess.run([*NLGRD, *map(str, argv)], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert r.stderr.startswith("nlgrd: error: ") and "Traceback" not in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_grid_values_are_the_decimal_values_of_the_range():
    """START + i (STOP - START) / (COUNT - 1) in exact rational arithmetic, then the nearest
    float: every value prints as the decimal number the user's range means (checked
    against integer arithmetic, independent of floats), where ``numpy.linspace`` gives
    e.g. 0.30000000000000004 for 0:1:11."""
    from nlgrd.io.command_line import parse_range

    grid = parse_range("4000:16000:241")
    assert [repr(float(v)) for v in grid] == [repr(float(4000 + 50 * i)) for i in range(241)]
    tenths = parse_range("0:1:11")
    assert [repr(float(v)) for v in tenths] == [repr(i / 10) for i in range(11)]  # i/10: correctly rounded
    assert repr(float(np.linspace(0, 1, 11)[3])) == "0.30000000000000004"  # what the old grid wrote


def test_speeds_written_as_given_after_their_round_trip():
    """rpm -> mesh frequency [rad/s] -> rpm differs from the typed value by ulps
    (10600.000000000004); the CSV's column is the typed grid again, and a value that is no
    grid point (a fold's landing) is kept."""
    from nlgrd.io.command_line import parse_range, snap_to_grid

    grid = parse_range("4000:16000:241")
    scale = 25 * np.pi / 30  # Kubo: 25 pinion teeth, mesh frequency per pinion rpm
    trip = (grid * scale) / scale
    assert np.any(trip != grid)  # the round trip does leave noise
    frame = pd.DataFrame({"shaft_speed [rpm]": np.append(trip, 10612.5)})
    snap_to_grid(frame, "shaft_speed [rpm]", grid)
    assert frame["shaft_speed [rpm]"].tolist() == [*grid.tolist(), 10612.5]


def test_a_sweep_whose_every_point_fails_exits_1(tmp_path, capsys, monkeypatch):
    """A run in which no point converged is a failure (exit 1, one error line), not a
    success: the real sweep is run on two points and its points marked not converged."""
    real = nlgrd.nonlinear.models.link_model.link_sweep

    def failing(*args, **kwargs):
        res = real(*args, **kwargs)
        res.result.converged[:] = False
        return res

    monkeypatch.setattr(nlgrd.nonlinear.models.link_model, "link_sweep", failing)
    out = tmp_path / "s.csv"
    argv = ["sweep", KUBO, "--rpm", "6000:7000:2", "--harmonics", "3", "--no-stability", "--direction", "up"]
    rc, stdout, err = run(capsys, *argv, "--out", out)
    assert rc == 1 and "2 not converged" in stdout, stdout
    assert (
        "Traceback" not in err
        and err.strip().splitlines()[-1] == "nlgrd: error: no point of the sweep converged"
    )


def test_outputs_go_to_the_current_directory(tmp_path, capsys, monkeypatch):
    """``nlgrd study data/studies/x.toml`` writes ./x/ and ``nlgrd report`` ./reports/,
    not into the source tree, when run from elsewhere."""
    import nlgrd.studies.batch_reports
    import nlgrd.studies.study_runner

    seen = {}

    def fake_study(study, out, **kwargs):
        seen["study"] = Path(out)
        return nlgrd.studies.study_runner.StudyRun(1, 1, 0, 0, False, Path(out))

    def fake_batch(notebook, runs, out, **kwargs):
        seen["report"] = Path(out)
        return {"run": {"error": None}}

    monkeypatch.setattr(nlgrd.studies.study_runner, "run_study", fake_study)
    monkeypatch.setattr(nlgrd.studies.batch_reports, "run_batch", fake_batch)
    monkeypatch.chdir(tmp_path)
    rc, _, _ = run(capsys, "study", ROOT / "data" / "studies" / "kubo_jump_band.toml")
    assert rc == 0 and seen["study"].resolve() == tmp_path / "kubo_jump_band"
    rc, out, _ = run(capsys, "report", NB, "-p", "fast", "True")
    assert rc == 0 and seen["report"].resolve() == tmp_path / "reports" / f"batch-{NB}"
    assert f"wrote reports/batch-{NB}/index.html" in out


def test_cancelled_task_is_counted_as_cancelled(tmp_path, capsys, monkeypatch):
    """A task with no record at the end (cancelled with the client) is 'cancelled (rerun to
    resume)' on screen and in the summary, not 'failed'; exit status 1."""
    import nlgrd.studies.study_runner as runner
    from nlgrd.studies.study_file import load_study

    study_text = STUDY.replace("values = [50e-6, 100e-6]", "values = [50e-6]").replace(
        "range = [0.02, 0.08, 4]", "values = [0.02, 0.08]"
    )
    path = tmp_path / "c.toml"
    path.write_text(study_text)

    def one_cancelled(todo, handle, on_result):  # the serial runner, the second task cancelled
        handle(runner.run_task(todo[0]))

    monkeypatch.setattr(runner, "_serial", one_cancelled)
    monkeypatch.chdir(tmp_path)
    rc, out, err = run(capsys, "study", path, "--executor", "serial", "--no-progress")
    assert rc == 1 and "failed 0, cancelled 1 (rerun to resume)" in out, out + err
    summary = pd.read_csv(tmp_path / "c" / "summary.csv")
    assert sorted(summary["status"]) == ["cancelled", "done"]
    assert load_study(path).name == "bad input"


def test_report_build_names_the_final_paths(tmp_path, capsys):
    """``make reports`` builds in a staging folder renamed at the end: its ``wrote`` lines
    name the published path."""
    from nlgrd.analyses import load, modes
    from nlgrd.io.analysis_files import write_modes
    from nlgrd.studies.reports import _wrote

    build = SimpleNamespace(stage=tmp_path / ".reports.staging-1", out=tmp_path / "reports")
    _wrote(build, *write_modes(modes(load(TWO), n_modes=2), build.stage / "models", "two_shaft"))
    out = capsys.readouterr().out
    assert f"wrote {build.out / 'models' / 'two_shaft_modes.csv'}" in out
    assert str(build.stage) not in out


def test_experimental_file_lists_every_problem(tmp_path):
    """Three independent faults (a missing header key, a word for a speed, an unknown
    direction) are all named in the one line."""
    from nlgrd.errors import ModelError
    from nlgrd.studies.experimental import load_experimental

    path = tmp_path / "x.csv"
    path.write_text(
        "# figure: 1\n# digitisation: by hand\n# calibration: axes\n# uncertainty: 1 %\n"
        "# case: kubo\n# quantity: dslr\npinion_speed_rpm,value,direction\n"
        "4000,1.1,up\nfast,1.2,up\n5000,1.3,sideways\n"
    )
    with pytest.raises(ModelError) as info:
        load_experimental(path)
    text = str(info.value)
    assert "\n" not in text and text.startswith(str(path))
    assert "header.source" in text and "line 9" in text and "'sideways'" in text and "2 more" in text


def test_licence_is_an_spdx_expression():
    """setuptools >= 77 reads ``license = "MIT"`` (PEP 639) without its deprecation warning
    for the table form."""
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert data["project"]["license"] == "MIT"
    assert "setuptools>=77" in data["build-system"]["requires"]
