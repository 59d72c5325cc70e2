"""docs/conventions.md, "Column names": the rename table lists every column the package's
result tables write, and every writer it names (the link sweeps and curves, ``nlgrd
sweep``'s CSV, tori, orbit search, time responses, static deflection, speed ramp, LSTE, the
single-DOF pair's table, ...; issue 33 item 5) writes only the current names of its rows;
each new name follows the schema of :func:`nlgrd.units.column`."""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import pandas as pd  # noqa: E402
import pytest  # noqa: E402
import test_result_family as family  # noqa: E402

from nlgrd.units import column, parse_column  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "conventions.md"
#: What a placeholder of the table stands for.
PLACEHOLDERS = {
    "<mesh>": r"[^.\[]+",
    "<bearing>": r".+",
    "<link>": r"[^.\[]+",
    "<k>": r"\d+",
    "<j>": r"\d+",
    "<metric>": r"[a-z][a-z0-9_]*",
    "<quantity>": r"[a-z][a-z0-9_]*",
    "<coordinate>": r"[a-z]+",
    "[unit]": r"\[[^\]]+\]",
}


def _rows() -> list[tuple[str, list[str], list[str]]]:
    text = DOC.read_text(encoding="utf-8").split("<!-- column-rename-table -->", 1)[1]
    rows = []
    for line in text.splitlines()[3:]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line.strip().strip("|"))]
        rows.append((cells[0], re.findall(r"`([^`]+)`", cells[1]), re.findall(r"`([^`]+)`", cells[2])))
    return rows


def _pattern(name: str) -> re.Pattern:
    out = re.escape(name)
    for key, rx in PLACEHOLDERS.items():
        out = out.replace(re.escape(key), rx)
    return re.compile(out + r"\Z")


OLD = [_pattern(n) for _, olds, _ in _rows() for n in olds]
NEW = [_pattern(n) for _, _, news in _rows() for n in news]
#: The writers of the table (its first cell's words before the bracket), per result class
#: of tests/test_result_family.py: each table may write only the current names of its rows
#: (the new name, or the old one where the row says "unchanged").
WRITERS = {
    "nlgrd.gear.transmission_error.LSTEResult": ("LSTE",),
    "nlgrd.nonlinear.results.link_results.LinkSweepResult": ("sweep", "curve"),
    "nlgrd.nonlinear.results.link_results.LinkContinuationResult": ("sweep", "curve", "continuation"),
    "nlgrd.nonlinear.results.sweep_results.SweepResult": ("single-DOF sweep",),
    "nlgrd.nonlinear.results.sweep_results.ContinuationResult": ("single-DOF sweep",),
    "nlgrd.nonlinear.stability.floquet.FloquetResult": ("Floquet multipliers",),
    "nlgrd.nonlinear.tracing.orbit_search.OrbitSearchResult": ("orbit search",),
    "nlgrd.nonlinear.tracing.torus_sweep.TorusResult": ("tori",),
    "nlgrd.rotor.frequency_response.FrequencyResponse": ("frequency response",),
    "nlgrd.rotor.frequency_response.StaticResult": ("static deflection",),
    "nlgrd.rotor.modal.ModalResult": ("modes",),
    "nlgrd.rotor.modal.CampbellResult": ("Campbell",),
    "nlgrd.timedomain.link_response.LinkTimeResponse": ("time response",),
    "nlgrd.timedomain.run_down.RampResult": ("speed ramp",),
    "nlgrd.timedomain.sdof.TimeResponse": ("time response",),
}


def _group(writers: tuple[str, ...]) -> list[tuple[str, list[str], list[str]]]:
    return [r for r in _rows() if r[0].split(" (")[0].startswith(writers)]


def _current(writers: tuple[str, ...]) -> list[re.Pattern]:
    """The names a table of these writers may write: each row's new names, its old ones
    where it has none ("unchanged")."""
    return [_pattern(n) for _, olds, news in _group(writers) for n in (news or olds)]


def _renamed(writers: tuple[str, ...]) -> list[re.Pattern]:
    return [_pattern(n) for _, olds, news in _group(writers) if news for n in olds]


def _unlisted(columns) -> list[str]:
    """Columns in neither the old nor the new names of the table."""
    return [c for c in columns if not any(p.match(c) for p in OLD + NEW)]


def _stale(columns, writers: tuple[str, ...] = ("sweep", "curve", "continuation")) -> list[str]:
    """Columns still under an old name the table renames for these writers (no new or
    unchanged name of theirs fits)."""
    current, renamed = _current(writers), _renamed(writers)
    return [c for c in columns if any(p.match(c) for p in renamed) and not any(p.match(c) for p in current)]


def _foreign(columns, writers: tuple[str, ...]) -> list[str]:
    """Columns that are no current name of these writers' rows."""
    current = _current(writers)
    return [c for c in columns if not any(p.match(c) for p in current)]


def test_the_table_is_there():
    rows = _rows()
    assert len(rows) >= 30
    assert all(olds for _, olds, _ in rows)


def test_every_new_name_follows_the_schema():
    """A new name (not "unchanged") is ``[<owner>.]<quantity>[ [unit]]`` with a snake_case
    quantity (its placeholders read as words)."""
    words = {"<k>": "1", "<j>": "1", "<metric>": "dte_rms", "<quantity>": "force_max", "<coordinate>": "y"}
    for _, _, news in _rows():
        for name in news:
            concrete = name
            for key in ("<mesh>", "<bearing>", "<link>"):
                concrete = concrete.replace(key, "owner")
            for key, word in words.items():
                concrete = concrete.replace(key, word)
            concrete = concrete.replace("[unit]", "[N]")
            owner, quantity, unit = parse_column(concrete)
            assert re.fullmatch(r"[a-z][a-z0-9_]*", quantity), name
            assert column(quantity, unit, owner) == concrete, name


@pytest.mark.parametrize("name", sorted(family.CASES))
def test_every_result_table_column_is_listed(name):
    """Each result family member's table (the small cases of tests/test_result_family.py)."""
    cls = family.result_classes().get(name)
    if cls is None:
        pytest.fail(f"{name} is gone: remove its case from CASES")
    assert _unlisted(family.CASES[name]().to_frame().columns) == []


def test_the_command_line_tables_are_listed(tmp_path):
    """``nlgrd sweep`` of a one-mesh model with named bearings, of a link model with a
    clearance, and a continuation: every CSV column is in the table."""
    from nlgrd.cli.command import main

    runs = {
        "one": ["data/models/two_shaft.toml", "--hz", "1000:1700:2", "--harmonics", "5", "--no-time-domain"],
        "link": ["data/models/two_shaft_clearance.toml", "--hz", "1000:1700:2", "--harmonics", "5"],
        "curve": ["data/models/two_shaft.toml", "--hz", "1000:1050:2", "--harmonics", "5", "--continuation"],
    }
    for key, args in runs.items():
        out = tmp_path / f"{key}.csv"
        args = [str(ROOT / args[0]), *args[1:]]
        assert main(["sweep", *args, "--out", str(out)]) == 0
        columns = pd.read_csv(out).columns
        assert _unlisted(columns) == [], key
        assert _stale(columns) == [], key  # the rename applied (issue 33 item 5)


def test_a_column_not_in_the_table_is_caught():
    assert _unlisted(["dte_rms [um]", "mesh0.dte_rms [m]", "not_a_column [m]"]) == ["not_a_column [m]"]


def test_a_column_under_its_old_name_is_caught():
    """The link tables' old names (lengths in m, ``subharmonic_amp``) are stale; their new
    names and the unchanged ones are not."""
    old = ["mesh0.dte_rms [m]", "B1.displacement_max [m]", "subharmonic_amp [um]", "mesh_frequency [Hz]"]
    new = ["mesh0.dte_rms [um]", "B1.displacement_max [um]", "subharmonic_amplitude [um]"]
    assert _stale(old) == old
    assert _stale([*new, "base_frequency [Hz]", "mesh0.force_max [N]", "B1.force_mean [N]"]) == []


def test_the_link_result_tables_use_the_new_names():
    """``nlgrd.sweep`` and ``nlgrd.continuation`` tables (the link engine, every model):
    no column under a renamed old name."""
    for name in ("LinkSweepResult", "LinkContinuationResult"):
        key = f"nlgrd.nonlinear.results.link_results.{name}"
        assert _stale(family.CASES[key]().to_frame().columns) == [], name


def test_every_writer_of_the_table_is_checked():
    """Each result class has its writer rows in the table, and each writer named in WRITERS
    has rows."""
    assert sorted(set(family.CASES) - set(WRITERS)) == []
    for name, writers in WRITERS.items():
        assert _group(writers), (name, writers)


@pytest.mark.parametrize("name", sorted(WRITERS))
def test_every_table_writes_only_the_current_names_of_its_rows(name):
    """The rename applied to every writer of the table (issue 33 item 5): each column of
    the small case's table is a new name of its rows or an unchanged one, none an old
    name the table renames (``mesh_frequency [Hz]`` of a torus table, ``dte [um]`` of a
    time response, ``ux [m]`` of a static deflection)."""
    columns = family.CASES[name]().to_frame().columns
    writers = WRITERS[name]
    assert _stale(columns, writers) == [], name
    assert _foreign(columns, writers) == [], name


@pytest.mark.parametrize(
    ("writers", "old"),
    [
        (("tori",), ["mesh_frequency [Hz]", "pinion_speed [rpm]", "dte_rms [um]", "force_max [N]"]),
        (("tori",), ["dte_rms_change [-]", "B1 force_max [N]", "floquet_multiplier_abs [-]"]),
        (("orbit search",), ["mesh_frequency [Hz]", "dte_rms [um]", "back_contact"]),
        (("single-DOF sweep",), ["mesh_frequency [Hz]"]),
        (("time response",), ["dte [um]", "lste [um]", "mesh_deflection [um]", "mesh_force [N]"]),
        (("static deflection",), ["ux [m]", "uy [m]", "uz [m]"]),
    ],
)
def test_an_old_name_of_another_writer_is_caught(writers, old):
    """The check can fail: each table's old names are stale and foreign to it."""
    assert _stale(old, writers) == old
    assert _foreign(old, writers) == old
