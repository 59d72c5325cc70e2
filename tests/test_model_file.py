"""Model files: the shipped examples, exact save/load round trips, and one clear error per bad input."""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import pytest

from nlgrd.errors import ModelError
from nlgrd.io import model_file, model_writer
from nlgrd.io.model_file import load_model, model_from_dict
from nlgrd.io.model_writer import model_to_dict, save_model
from nlgrd.rotor.assembly import assemble
from nlgrd.rotor.bearing import Bearing
from nlgrd.rotor.coupling import Coupling
from nlgrd.rotor.disk import Disk
from nlgrd.rotor.materials import Material
from nlgrd.rotor.shaft import Shaft, ShaftElement
from nlgrd.rotor.system import RotorSystem

MODELS = Path(__file__).resolve().parents[1] / "data" / "models"
EXAMPLES = ["single_shaft.toml", "two_shaft.toml"]

# A small valid model; each bad-input case below changes one spot of it.
BASE = """\
version = 1
name = "base"

[materials.steel]
density = 7850.0
young_modulus = 2.1e11
poisson_ratio = 0.3

[materials.bronze]
density = 8800.0
young_modulus = 1.1e11
poisson_ratio = 0.34

[[shafts]]
name = "s0"

[[shafts.elements]]
count = 3
length = 0.1
outer_diameter = 0.05
material = "steel"

[[shafts]]
name = "s1"
y = 0.1
speed_ratio = -1.0

[[shafts.elements]]
count = 2
length = 0.1
outer_diameter = 0.04
material = "steel"

[[shafts.elements]]
length = 0.1
outer_diameter = 0.045
material = "steel"

[[shafts.elements]]
length = 0.1
outer_diameter = 0.045
inner_diameter = 0.01
material = "bronze"

[[shafts.elements]]
length = 0.1
outer_diameter = 0.041
material = "steel"

[[disks]]
shaft = 0
node = 1
mass = 5.0
diametral_inertia = 0.01
polar_inertia = 0.02

[[bearings]]
shaft = 0
node = 0
kyy = 1.0e7
kyz = 1.0e5
kzz = 1.0e7
kxx = 1.0e7

[[bearings]]
shaft = 1
node = 5
kyy = 1.0e7
kzz = 1.0e7
speeds = [0.0, 100.0]
cyy = [100.0, 200.0]

[[couplings]]
shaft_a = 0
node_a = 3
shaft_b = 1
node_b = 0
k_torsion = 1.0e4
"""


def _edit(old: str, new: str) -> str:
    """BASE with the one occurrence of ``old`` replaced by ``new``."""
    assert BASE.count(old) == 1, f"case text {old!r} is not unique in BASE"
    return BASE.replace(old, new)


def _bad(tmp_path: Path, text: str) -> ModelError:
    path = tmp_path / "bad_model.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ModelError) as info:
        load_model(path)
    return info.value


def test_base_model_is_valid(tmp_path):
    """The base of the bad-input cases loads, so each case fails for its own edit only."""
    path = tmp_path / "base.toml"
    path.write_text(BASE)
    system = load_model(path)
    assert [s.n_nodes for s in system.shafts] == [4, 6]
    assert system.shafts[1].elements[3].material.name == "bronze"
    assert system.bearings[1].cyy == (100.0, 200.0)
    assert system.couplings[0].node_b == 0


# ---------------------------------------------------------------------------------- examples


def test_single_shaft_example():
    """single_shaft.toml: 1.2 m stepped 50/60/50 mm shaft, 12 elements, disk at midspan, two bearings."""
    system = load_model(MODELS / "single_shaft.toml")
    (shaft,) = system.shafts
    assert len(shaft.elements) == 12
    assert shaft.length == pytest.approx(1.2)
    assert [e.outer_diameter for e in shaft.elements] == [0.05] * 3 + [0.06] * 6 + [0.05] * 3
    assert len(system.disks) == 1 and system.disks[0].node == 6
    assert len(system.bearings) == 2
    for b in system.bearings:
        k = b.stiffness()
        assert k[0, 1] != 0 and k[1, 0] != 0 and abs(k[0, 1]) < 0.1 * k[0, 0]
        assert b.damping()[0, 1] != 0
    assert system.n_dofs == 78


def test_two_shaft_example():
    """two_shaft.toml: two parallel shafts 0.1 m apart, >= 100 DOFs, gear shaft at -1 x pinion speed."""
    system = load_model(MODELS / "two_shaft.toml")
    pinion, gear = system.shafts
    assert system.n_dofs >= 100
    assert gear.y - pinion.y == pytest.approx(0.1)
    assert gear.speed_ratio == -1.0
    assert len(system.bearings) == 4
    for s in (0, 1):
        on_shaft = [b for b in system.bearings if b.shaft == s]
        assert len(on_shaft) == 2
        assert sum(b.kxx > 0 for b in on_shaft) == 1
    assert {d.name for d in system.disks} >= {"motor", "pinion blank", "gear blank", "load"}
    assert len(system.gear_pairs) == 1 and system.gear_pairs[0].geometry.teeth_pinion == 25


@pytest.mark.parametrize("name", EXAMPLES)
def test_examples_have_no_axial_rigid_body_mode(name):
    """The thrust bearings make the axial stiffness matrix positive definite (no axial rigid-body mode)."""
    system = load_model(MODELS / name)
    K = assemble(system).K.toarray()
    axial = system.dofs.kind_mask("axial")
    assert np.linalg.eigvalsh(K[np.ix_(axial, axial)]).min() > 0


# ---------------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("name", EXAMPLES)
def test_example_round_trip(tmp_path, name):
    """save -> load gives an equal system, and saving that again gives the same text."""
    system = load_model(MODELS / name)
    first, second = tmp_path / "first.toml", tmp_path / "second.toml"
    save_model(system, first)
    again = load_model(first)
    assert again == system
    save_model(again, second)
    assert first.read_text() == second.read_text()


def _awkward_system() -> RotorSystem:
    """A system with everything the writer must get right."""
    steel = Material("steel", density=7850.0, young_modulus=2.1e11, poisson_ratio=0.3)
    other_steel = Material(
        "steel", density=7800.0, young_modulus=2.0e11, poisson_ratio=0.29, loss_factor=0.002
    )
    odd = Material('odd "name"\\ with\ttab', density=1.0e3 + 0.1 + 0.2, young_modulus=1.2345678901234567e9)
    e1 = ShaftElement(0.1 + 0.2, 0.05, 0.0, steel)
    e2 = ShaftElement(
        1e-3 / 3, 0.05, 0.02, other_steel, axial_force=-1.5e3, shear=False, rotary_inertia=False
    )
    e3 = ShaftElement(0.07, 0.03, 0.0, odd)
    shaft0 = Shaft((e1, e1, e2, e1, e3, e3, e3), name="pinion ✓", x_start=-0.25, y=1e-17, speed_ratio=1.0)
    shaft1 = Shaft.uniform(0.6, 0.04, 5, material=steel, name="gear", y=0.1, speed_ratio=-25 / 31)
    speeds = (0.0, 50.0, 2.0 / 3.0 * 1e3)
    return RotorSystem(
        shafts=(shaft0, shaft1),
        disks=(Disk(0, 2, 5, 0.01, 0.02), Disk.from_dimensions(1, 3, 0.2, 0.02, 0.04, name="blank")),
        bearings=(
            Bearing(0, 0, kyy=1e8, kyz=-3e5, kzy=5e-324, kzz=2e8, cyy=1e3, ktt=7.0),
            Bearing(
                1, 5, kyy=(1e7, 2e7, 3e7), kzz=1e7, cyz=(0.0, -1.0, math.pi), speeds=speeds, name="table"
            ),
        ),
        couplings=(Coupling(0, 7, 1, 0, k_torsion=1e4, ratio=-31 / 25), Coupling(0, 0, c_torsion=0.2)),
        name='line one\nline "two"',
    )


def test_round_trip_awkward_values(tmp_path):
    """Exact round trip of floats at repr precision, name clashes, escapes, tables over speed, None fields."""
    system = _awkward_system()
    path = tmp_path / "awkward.toml"
    save_model(system, path)
    again = load_model(path)
    assert again == system
    assert again.shafts[0].elements[2].material.density == 7800.0
    assert again.couplings[1].shaft_b is None
    assert model_to_dict(again) == model_to_dict(system)
    written = tomllib.loads(path.read_text())["disks"][0]["mass"]
    assert type(written) is float  # Disk(mass=5) is written 5.0: the field is a float


def test_dict_round_trip():
    """model_from_dict(model_to_dict(s)) == s, without going through text."""
    system = _awkward_system()
    assert model_from_dict(model_to_dict(system)) == system


def test_floats_round_trip_exactly(tmp_path):
    """Random floats over 600 decades read back bit for bit (written with repr precision)."""
    rng = np.random.default_rng(1)
    values = np.sort(10.0 ** rng.uniform(-300, 300, 200) * rng.uniform(1, 10, 200))
    shaft = Shaft.uniform(1.0, 0.05, 2)
    bearing = Bearing(0, 0, kyy=tuple(values), kzz=1e8, speeds=tuple(values))  # kzz: held in z
    system = RotorSystem((shaft,), bearings=(bearing,))
    path = tmp_path / "floats.toml"
    save_model(system, path)
    assert load_model(path).bearings[0].kyy == tuple(float(v) for v in values)


def test_count_equals_explicit_elements(tmp_path):
    """An element entry with count = 3 gives the same shaft as three explicit entries."""
    element = 'length = 0.1\nouter_diameter = 0.05\nmaterial = "steel"\n'
    head = "version = 1\n[materials.steel]\n[[shafts]]\n"
    compact = head + "[[shafts.elements]]\ncount = 3\n" + element
    explicit = head + ("[[shafts.elements]]\n" + element) * 3
    (tmp_path / "a.toml").write_text(compact)
    (tmp_path / "b.toml").write_text(explicit)
    a, b = load_model(tmp_path / "a.toml"), load_model(tmp_path / "b.toml")
    assert a == b and len(a.shafts[0].elements) == 3


def test_saved_file_uses_count(tmp_path):
    """The writer folds runs of identical elements into one entry with count."""
    path = tmp_path / "uniform.toml"
    save_model(RotorSystem((Shaft.uniform(1.0, 0.05, 10),)), path)
    data = tomllib.loads(path.read_text())
    assert [e["count"] for e in data["shafts"][0]["elements"]] == [10]
    assert data["version"] == 1


def test_int_where_float_is_wanted(tmp_path):
    """Integers are accepted for float fields and stored as floats."""
    path = tmp_path / "ints.toml"
    path.write_text("version = 1\n[[shafts]]\n[[shafts.elements]]\nlength = 1\nouter_diameter = 1\n")
    el = load_model(path).shafts[0].elements[0]
    assert type(el.length) is float and el.length == 1.0


def test_header_written_as_comments(tmp_path):
    """save_model(header=...) puts comment lines at the top and the file still loads."""
    path = tmp_path / "h.toml"
    save_model(_awkward_system(), path, header="what it is\nwhere the numbers come from")
    lines = path.read_text().splitlines()
    assert lines[:2] == ["# what it is", "# where the numbers come from"]
    assert load_model(path) == _awkward_system()


def test_save_is_atomic(tmp_path, monkeypatch):
    """A failed save leaves the old file untouched and no temporary file behind."""
    path = tmp_path / "model.toml"
    system = load_model(MODELS / "single_shaft.toml")
    save_model(system, path)
    before = path.read_bytes()

    def boom(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(model_writer.os, "replace", boom)
    with pytest.raises(OSError, match="disk full"):
        save_model(_awkward_system(), path)
    assert path.read_bytes() == before
    assert os.listdir(tmp_path) == ["model.toml"]


def test_save_replaces_existing_file(tmp_path):
    """Saving over an existing file replaces it and leaves only that file."""
    path = tmp_path / "model.toml"
    path.write_text("old contents")
    save_model(_awkward_system(), path)
    assert load_model(path) == _awkward_system()
    assert os.listdir(tmp_path) == ["model.toml"]


# ---------------------------------------------------------------------------------- generic nesting


@dataclass(frozen=True)
class FakeGeometry:
    """Stands in for nlgrd.gear.geometry.GearGeometry."""

    teeth_pinion: int
    teeth_gear: int
    module: float
    centre_distance: float | None = None
    kind: Literal["spur", "helical"] = "spur"

    def __post_init__(self):
        if self.module <= 0:
            raise ModelError("module", f"must be positive, got {self.module!r}")


@dataclass(frozen=True)
class FakeMesh:
    """Stands in for nlgrd.gear.mesh.GearMesh: node references and a nested geometry table."""

    pinion_shaft: int
    pinion_node: int
    gear_shaft: int
    gear_node: int
    geometry: FakeGeometry
    lste: tuple[float, ...] = ()
    mesh_stiffness: float = 2.0e8


MESH = """
[[gear_pairs]]
pinion_shaft = 0
pinion_node = 2
gear_shaft = 1
gear_node = 3
lste = [1.0e-6, -2.0e-7]

[gear_pairs.geometry]
teeth_pinion = 25
teeth_gear = 25
module = 0.004
kind = "spur"
"""


@pytest.fixture
def fake_gear_module(monkeypatch):
    """Point the reader's gear_pairs entries at FakeMesh of this test module."""
    monkeypatch.setitem(model_file._LATE_TYPES, (RotorSystem, "gear_pairs"), (__name__, "FakeMesh"))


def test_nested_dataclass_read_and_written_generically(tmp_path, fake_gear_module):
    """A gear_pairs class with a nested table needs no loader code: it loads and round-trips."""
    path = tmp_path / "mesh.toml"
    path.write_text(BASE + MESH)
    system = load_model(path)
    (mesh,) = system.gear_pairs
    assert mesh == FakeMesh(0, 2, 1, 3, FakeGeometry(25, 25, 0.004), lste=(1.0e-6, -2.0e-7))
    save_model(system, tmp_path / "again.toml")
    assert load_model(tmp_path / "again.toml") == system


@pytest.mark.parametrize(
    ("old", "new", "key", "fragment"),
    [
        ("module = 0.004", "module = -0.004", "gear_pairs[0].geometry.module", "must be positive"),
        ("module = 0.004", "modul = 0.004", "gear_pairs[0].geometry.modul", "did you mean 'module'"),
        ('kind = "spur"', 'kind = "bevel"', "gear_pairs[0].geometry.kind", 'one of "spur", "helical"'),
        ("gear_node = 3", "gear_node = 30", "gear_pairs[0].gear_node", "out of range"),
        ("lste = [1.0e-6, -2.0e-7]", "lste = [1.0e-6, nan]", "gear_pairs[0].lste[1]", "must be finite"),
    ],
)
def test_nested_errors_name_full_path(tmp_path, fake_gear_module, old, new, key, fragment):
    """Errors inside a nested table carry the whole key path."""
    err = _bad(tmp_path, BASE + MESH.replace(old, new))
    assert str(err).startswith(f"{tmp_path / 'bad_model.toml'}: {key}: ")
    assert fragment in str(err)


def test_gear_pairs_without_gear_module(tmp_path, monkeypatch):
    """gear_pairs entries when the gear-mesh module is missing give one clear ModelError."""
    monkeypatch.setitem(model_file._LATE_TYPES, (RotorSystem, "gear_pairs"), ("nlgrd._no_such_module", "X"))
    err = _bad(tmp_path, BASE + MESH)
    assert err.key == "gear_pairs"
    assert "nlgrd._no_such_module" in str(err)


# ---------------------------------------------------------------------------------- bad input

BAD_CASES = [
    # (id, text, key path, fragment of the message)
    ("toml-syntax", _edit('name = "base"', 'name = "base'), "", "TOML syntax error"),
    ("toml-duplicate-key", _edit("y = 0.1\n", "y = 0.1\ny = 0.2\n"), "", "TOML syntax error"),
    ("version-missing", _edit("version = 1\n", ""), "version", "missing"),
    ("version-unknown", _edit("version = 1", "version = 2"), "version", "unsupported model file version 2"),
    ("version-string", _edit("version = 1", 'version = "1"'), "version", "must be an integer"),
    (
        "missing-required-field",
        _edit("length = 0.1\nouter_diameter = 0.041", "length = 0.1"),
        "shafts[1].elements[3].outer_diameter",
        "missing required key",
    ),
    (
        "missing-required-disk-mass",
        _edit("mass = 5.0\n", ""),
        "disks[0].mass",
        "missing required key",
    ),
    (
        "unknown-key",
        _edit("outer_diameter = 0.041", "outer_diamter = 0.041"),
        "shafts[1].elements[3].outer_diamter",
        "did you mean 'outer_diameter'?",
    ),
    ("unknown-top-level-key", _edit("[[disks]]", "[[disk]]"), "disk", "did you mean 'disks'?"),
    (
        "unknown-key-count",
        _edit("count = 3", "cuont = 3"),
        "shafts[0].elements[0].cuont",
        "did you mean 'count'?",
    ),
    (
        "string-for-number",
        _edit("outer_diameter = 0.041", 'outer_diameter = "0.041"'),
        "shafts[1].elements[3].outer_diameter",
        'must be a number, got string "0.041"',
    ),
    (
        "list-for-scalar",
        _edit("outer_diameter = 0.041", "outer_diameter = [0.041, 0.05]"),
        "shafts[1].elements[3].outer_diameter",
        "must be a number, got array [0.041, 0.05]",
    ),
    (
        "scalar-for-list",
        _edit("speeds = [0.0, 100.0]", "speeds = 100.0"),
        "bearings[1].speeds",
        "must be an array of numbers, got float 100.0",
    ),
    (
        "table-for-number",
        _edit("mass = 5.0", "mass = {value = 5.0}"),
        "disks[0].mass",
        "must be a number, got table",
    ),
    ("bool-for-number", _edit("kyz = 1.0e5", "kyz = true"), "bearings[0].kyz", "got boolean true"),
    (
        "float-for-int",
        _edit("node = 1\n", "node = 1.0\n"),
        "disks[0].node",
        "must be an integer, got float 1.0",
    ),
    (
        "string-for-bool",
        _edit("inner_diameter = 0.01", 'shear = "yes"'),
        "shafts[1].elements[2].shear",
        "true",
    ),
    (
        "zero-diameter",
        _edit("outer_diameter = 0.041", "outer_diameter = 0.0"),
        "shafts[1].elements[3].outer_diameter",
        "must be positive, got 0.0",
    ),
    (
        "negative-diameter",
        _edit("outer_diameter = 0.041", "outer_diameter = -0.02"),
        "shafts[1].elements[3].outer_diameter",
        "must be positive, got -0.02",
    ),
    (
        "inner-not-below-outer",
        _edit("inner_diameter = 0.01", "inner_diameter = 0.045"),
        "shafts[1].elements[2].inner_diameter",
        "must be smaller than outer_diameter",
    ),
    ("negative-mass", _edit("mass = 5.0", "mass = -5.0"), "disks[0].mass", "must be zero or positive"),
    (
        "negative-inertia",
        _edit("polar_inertia = 0.02", "polar_inertia = -0.02"),
        "disks[0].polar_inertia",
        "must be zero or positive",
    ),
    (
        "nan",
        _edit("density = 8800.0", "density = nan"),
        "materials.bronze.density",
        "must be finite, got nan",
    ),
    ("inf", _edit("mass = 5.0", "mass = inf"), "disks[0].mass", "must be finite, got inf"),
    ("negative-inf", _edit("y = 0.1", "y = -inf"), "shafts[1].y", "must be finite, got -inf"),
    ("huge-integer", _edit("mass = 5.0", "mass = " + "9" * 400), "disks[0].mass", "must be finite"),
    ("node-out-of-range", _edit("node = 5\n", "node = 6\n"), "bearings[1].node", "node 6 out of range 0..5"),
    (
        "shaft-out-of-range",
        _edit("shaft = 0\nnode = 1", "shaft = 2\nnode = 1"),
        "disks[0].shaft",
        "out of range",
    ),
    ("coupling-node-out-of-range", _edit("node_b = 0", "node_b = 9"), "couplings[0].node_b", "out of range"),
    ("negative-node", _edit("node = 1\n", "node = -1\n"), "disks[0].node", "non-negative integer"),
    ("bearing-entry-nan", _edit("kyz = 1.0e5", "kyz = nan"), "bearings[0].kyz", "must be finite, got nan"),
    (
        "bearing-table-entry-inf",
        _edit("cyy = [100.0, 200.0]", "cyy = [100.0, inf]"),
        "bearings[1].cyy[1]",
        "must be finite, got inf",
    ),
    (
        "bearing-table-length",
        _edit("cyy = [100.0, 200.0]", "cyy = [100.0, 200.0, 300.0]"),
        "bearings[1].cyy",
        "has 3 values but 'speeds' has 2",
    ),
    (
        "bearing-negative-direct",
        _edit("kzz = 1.0e7\nkxx", "kzz = -1.0e7\nkxx"),
        "bearings[0].kzz",
        "negative",
    ),
    (
        "unknown-material",
        _edit('material = "bronze"', 'material = "bronz"'),
        "shafts[1].elements[2].material",
        "unknown material 'bronz' (not in [materials]); did you mean 'bronze'?",
    ),
    (
        "material-name-key",
        _edit("[materials.bronze]\n", '[materials.bronze]\nname = "brass"\n'),
        "materials.bronze.name",
        "is given by the table key",
    ),
    (
        "material-poisson",
        _edit("poisson_ratio = 0.34", "poisson_ratio = 0.5"),
        "materials.bronze.poisson_ratio",
        "must lie in (-1, 0.5)",
    ),
    ("count-zero", _edit("count = 3", "count = 0"), "shafts[0].elements[0].count", "from 1 to 100000"),
    ("count-float", _edit("count = 3", "count = 3.0"), "shafts[0].elements[0].count", "got float 3.0"),
    (
        "element-not-table",
        "version = 1\n[[shafts]]\nelements = [1.0]\n",
        "shafts[0].elements",
        "must be an array of tables, got array [1.0]",
    ),
    ("no-elements", "version = 1\n[[shafts]]\nelements = []\n", "shafts[0].elements", "at least one element"),
    ("shafts-table", "version = 1\n[shafts]\nname = 1\n", "shafts", "must be an array of tables, got table"),
    ("no-shafts", "version = 1\n", "shafts", "missing required key"),
]


@pytest.mark.parametrize(
    ("text", "key", "fragment"), [pytest.param(t, k, f, id=i) for i, t, k, f in BAD_CASES]
)
def test_bad_input(tmp_path, text, key, fragment):
    """One ModelError per bad input, on one line, naming the file and the key path."""
    err = _bad(tmp_path, text)
    message = str(err)
    file = str(tmp_path / "bad_model.toml")
    assert "\n" not in message
    assert err.file == file and message.startswith(f"{file}: ")
    assert err.key == key
    if key:
        assert message.startswith(f"{file}: {key}: ")
    assert fragment in message


def test_syntax_error_gives_line(tmp_path):
    """A TOML syntax error names the line."""
    err = _bad(tmp_path, _edit('name = "base"', 'name = "base'))
    assert "line 2" in str(err)


def test_unreadable_file(tmp_path):
    """A missing file is a ModelError naming it, not an OSError traceback."""
    with pytest.raises(ModelError, match="nowhere.toml: cannot read the file"):
        load_model(tmp_path / "nowhere.toml")


def test_not_utf8(tmp_path):
    """Bytes that are not UTF-8 give a ModelError naming the file."""
    path = tmp_path / "latin1.toml"
    path.write_bytes(b'version = 1\nname = "caf\xe9"\n')
    with pytest.raises(ModelError, match="latin1.toml: "):
        load_model(path)


def test_model_from_dict_names_key_without_file():
    """model_from_dict without a file name still names the key path."""
    data = tomllib.loads(BASE)
    data["disks"][0]["mass"] = -1.0
    with pytest.raises(ModelError) as info:
        model_from_dict(data)
    assert str(info.value).startswith("disks[0].mass: must be zero or positive")


def _leaves(obj, path=()):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(obj, list) and obj and isinstance(obj[0], dict):
        for i, v in enumerate(obj):
            yield from _leaves(v, (*path, i))
    else:
        yield path


def _set(obj, path, value):
    for p in path[:-1]:
        obj = obj[p]
    obj[path[-1]] = value


@pytest.mark.parametrize("value", ["x", True, [1.0], {"a": 1}, math.nan, math.inf, -1.0, 0, -1, 1e300, []])
def test_no_traceback_for_any_bad_value(value):
    """Every leaf of the base model set to a bad value gives a ModelError or a valid model, nothing else."""
    for path in _leaves(tomllib.loads(BASE)):
        data = tomllib.loads(BASE)
        _set(data, path, value)
        try:
            model_from_dict(data, file="fuzz.toml")
        except ModelError as err:
            assert str(err).startswith("fuzz.toml: ") and "\n" not in str(err)
