"""Model files: a :class:`~nlgrd.rotor.system.RotorSystem` read from and written to TOML.

The reader and the writer are generic: they walk ``dataclasses.fields`` and the
type hints of the model classes, recursively, so a model class added later (a gear
mesh with a nested geometry table, say) needs no new code here. Keys are the
dataclass field names, values are SI, as everywhere in nlgrd (ROSS ``Rotor.save``
and ``Rotor.load`` use the same layout).

Format, version 1::

    version = 1                      # required; other versions are refused
    name = "test rig"

    [materials.steel]                # Material fields; the name is the table key
    density = 7850.0
    young_modulus = 2.1e11

    [[shafts]]                       # Shaft fields
    name = "pinion"
    speed_ratio = 1.0

    [[shafts.elements]]              # ShaftElement fields, one entry per element ...
    length = 0.05
    outer_diameter = 0.045
    material = "steel"               # a key of [materials]; omitted: nlgrd.rotor.materials.STEEL

    [[shafts.elements]]              # ... or one entry for a run of identical elements:
    count = 6                        # six elements like this one
    length = 0.05
    outer_diameter = 0.045
    material = "steel"

    [[disks]]                        # Disk fields
    shaft = 0
    node = 3
    mass = 0.92
    diametral_inertia = 5.9e-4
    polar_inertia = 1.16e-3

    [[bearings]]                     # Bearing fields; coefficients may be tables over speeds
    shaft = 0
    node = 0
    kyy = 1.0e8

    [[couplings]]                    # Coupling fields; no shaft_b/node_b: to ground
    shaft_a = 0
    c_torsion = 0.2

    [[gear_pairs]]                   # nlgrd.gear.mesh.GearMesh fields, nested tables as
    ...                              # [gear_pairs.geometry] and so on; any number of them

    [[bearing_clearances]]           # nlgrd.nonlinear.links.contract.BearingClearance fields
    name = "B1"                      # a radial clearance, a nonlinear link
    shaft = 0
    node = 8
    clearance = 20e-6
    stiffness = 1.0e10
    exponent = 1.5

    [[unbalance]]                    # nlgrd.rotor.loads.Unbalance: m e [kg m] >= 0 turning
    shaft = 1                        # with its shaft, a load of the link analyses
    node = 4
    amount = 1.0e-4                  # phase [rad]: its angle from y at t = 0; default 0

Rules:

- Element entries may carry ``count = N`` (1 <= N <= 100 000): N identical
  consecutive elements. It is the only key that is not a dataclass field. Errors
  in such an entry name the entry, ``shafts[0].elements[1]``, not the element.
- A field typed :class:`~nlgrd.rotor.materials.Material` holds the name of a
  ``[materials.<name>]`` table, or an inline table with all Material fields
  (the writer uses the latter only when two different materials share a name).
- Integers are accepted where a float is wanted; booleans, strings, arrays and
  tables are not accepted in place of numbers; every float must be finite (TOML
  allows ``nan`` and ``inf``).
- Fields left out take the dataclass default. TOML has no null: a field that may
  be None is None by leaving it out.

Every bad input raises one :class:`~nlgrd.errors.ModelError` whose one-line message
names the file and the key path, e.g.
``two_shaft.toml: shafts[1].elements[3].outer_diameter: must be positive, got -0.02``.
"""

from __future__ import annotations

import collections.abc
import dataclasses
import difflib
import enum
import importlib
import math
import os
import sys
import tomllib
import types
import typing
from collections.abc import Mapping
from typing import Any

import numpy as np

from nlgrd.errors import ModelError
from nlgrd.io.model_checks import check_gear_files, check_model
from nlgrd.io.toml_format import ARRAY, toml_key, toml_value
from nlgrd.rotor.materials import Material
from nlgrd.rotor.shaft import Shaft
from nlgrd.rotor.system import RotorSystem

__all__ = ["FORMAT_VERSION", "load_model", "model_from_dict", "model_from_file_data"]

#: Version of the file format this module reads and writes.
FORMAT_VERSION = 1

#: The extra key of compact element entries.
COUNT_KEY = "count"
MAX_COUNT = 100_000

#: Fields typed ``Any`` whose entries are built from a class in a module that may
#: not exist yet: (owner, field) -> (module, class). Imported on first use.
_LATE_TYPES: dict[tuple[type, str], tuple[str, str]] = {
    (RotorSystem, "gear_pairs"): ("nlgrd.gear.mesh", "GearMesh"),
    (RotorSystem, "bearing_clearances"): ("nlgrd.nonlinear.links.contract", "BearingClearance"),
}

#: Sequence fields whose entries may carry ``count = N``.
REPEATABLE: set[tuple[type, str]] = {(Shaft, "elements")}

#: Classes kept in a top-level table and referred to by name: class -> table.
NAMED_TABLES: dict[type, str] = {Material: "materials"}

_SEQUENCE_ORIGINS = (tuple, list, collections.abc.Sequence)


# ----------------------------------------------------------------------------------
# reading


@dataclasses.dataclass
class _Reader:
    """State of one read: the file name for messages and the named tables."""

    file: str | None
    named: dict[type, dict[str, Any]] = dataclasses.field(default_factory=dict)

    def error(self, key: str, message: str) -> ModelError:
        return ModelError(key, message, self.file)


def load_model(path: str | os.PathLike) -> RotorSystem:
    """Read a rotor system from a TOML model file.

    Parameters
    ----------
    path : str or path-like
        The model file (format: see the module docstring).

    Returns
    -------
    RotorSystem

    Raises
    ------
    ModelError
        For any bad input (unreadable file, TOML syntax, unknown or missing keys, wrong types,
        values the model classes refuse, a physically absurd model, an unreadable or implausible
        ``lste_file`` or ``stiffness_file``; see :mod:`nlgrd.io.model_checks`), naming the file and the key.
    """
    name = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ModelError("", f"TOML syntax error: {_one_line(str(exc))}", name) from None
    except UnicodeDecodeError as exc:
        raise ModelError("", f"not UTF-8 text: {exc.reason} at byte {exc.start}", name) from None
    except OSError as exc:
        raise ModelError("", f"cannot read the file: {exc.strerror or exc}", name) from None
    return model_from_file_data(data, name)


def model_from_file_data(data: Mapping[str, Any], file: str) -> RotorSystem:
    """:func:`model_from_dict`, with the gear pairs' file paths relative to ``file`` and checked.

    Parameters
    ----------
    data : mapping
        The parsed model file.
    file : str
        The model file the data came from (paths and error messages).

    Returns
    -------
    RotorSystem
    """
    system = model_from_dict(data, file=file)
    system = _resolve_lste_files(system, os.path.dirname(os.path.abspath(file)))
    try:
        check_gear_files(system)
    except ModelError as exc:
        raise ModelError(_one_line(exc.key), _one_line(exc.message), file) from None
    return system


def _resolve_lste_files(system: RotorSystem, base: str) -> RotorSystem:
    """Make relative ``lste_file`` and ``stiffness_file`` paths relative to the model file's folder."""
    pairs = []
    changed = False
    for g in system.gear_pairs:
        paths = {k: p for k in ("lste_file", "stiffness_file") if (p := getattr(g, k, None))}
        if paths := {k: os.path.join(base, p) for k, p in paths.items() if not os.path.isabs(p)}:
            g = dataclasses.replace(g, **paths)
            changed = True
        pairs.append(g)
    return dataclasses.replace(system, gear_pairs=tuple(pairs)) if changed else system


def model_from_dict(data: Mapping[str, Any], file: str | None = None) -> RotorSystem:
    """Build a rotor system from the dictionary of a parsed model file.

    Parameters
    ----------
    data : mapping
        What ``tomllib`` returns for a model file, or what :func:`model_to_dict` gives.
    file : str, optional
        File name used in error messages.

    Returns
    -------
    RotorSystem

    Raises
    ------
    ModelError
        For bad input, and for a model that :func:`nlgrd.io.model_checks.check_model`
        finds absurd (an unsupported shaft, a mesh deflection beyond the tooth depth, ...).
    """
    try:
        system = _read_top(data, _Reader(file))
        check_model(system)
        return system
    except ModelError as exc:
        raise ModelError(_one_line(exc.key), _one_line(exc.message), exc.file or file) from None


def _read_top(data: Mapping[str, Any], rd: _Reader) -> RotorSystem:
    if not isinstance(data, Mapping):
        raise rd.error("", f"a model must be a table, got {_show(data)}")
    data = dict(data)
    if "version" not in data:
        raise rd.error("version", f"missing; a model file starts with 'version = {FORMAT_VERSION}'")
    version = data.pop("version")
    if isinstance(version, bool) or not isinstance(version, int):
        raise rd.error("version", f"must be an integer, got {_show(version)}")
    if version != FORMAT_VERSION:
        raise rd.error(
            "version", f"unsupported model file version {version}; this nlgrd reads version {FORMAT_VERSION}"
        )
    for cls, table in NAMED_TABLES.items():
        rd.named[cls] = _read_named(cls, data.pop(table, {}), table, rd)
    return _build(RotorSystem, data, "", rd, extra=("version", *NAMED_TABLES.values()))


def _read_named(cls: type, raw: Any, table: str, rd: _Reader) -> dict[str, Any]:
    """Build the entries of a top-level table of named objects, e.g. ``[materials.steel]``."""
    if not isinstance(raw, dict):
        raise rd.error(table, f"must be a table of named tables [{table}.<name>], got {_show(raw)}")
    out = {}
    for key, entry in raw.items():
        path = _join(table, key)
        if not isinstance(entry, dict):
            raise rd.error(path, f"must be a table, got {_show(entry)}")
        if "name" in entry:
            raise rd.error(_join(path, "name"), f"is given by the table key [{path}]; remove it")
        out[key] = _build(cls, {**entry, "name": key}, path, rd)
    return out


def field_hints(cls: type) -> dict[str, Any]:
    """Resolved type hints of a dataclass, also when its module imports types lazily.

    Parameters
    ----------
    cls : type
        The dataclass.

    Returns
    -------
    dict of str to Any
        Each field's type hint, by field name (``typing.get_type_hints``); names the module
        cannot resolve are looked up among the classes of the loaded ``nlgrd`` modules.
    """
    try:
        return typing.get_type_hints(cls)
    except NameError:
        ns: dict[str, Any] = {}
        for mod_name, mod in list(sys.modules.items()):
            if mod_name == "nlgrd" or mod_name.startswith("nlgrd."):
                ns.update({k: v for k, v in vars(mod).items() if isinstance(v, type)})
        return typing.get_type_hints(cls, localns=ns)


def _build(cls: type, table: Any, path: str, rd: _Reader, extra: tuple[str, ...] = ()) -> Any:
    """Build dataclass ``cls`` from a TOML table, checking keys and types first."""
    if not isinstance(table, dict):
        raise rd.error(path, f"must be a table, got {_show(table)}")
    fields = [f for f in dataclasses.fields(cls) if f.init]
    names = [f.name for f in fields]
    for key in table:
        if key not in names:
            raise _unknown_key(path, key, [*names, *extra], rd)
    hints = field_hints(cls)
    kwargs = {}
    for f in fields:
        sub = _join(path, f.name)
        if f.name in table:
            value = table[f.name]
            hint = _late_hint(cls, f.name, hints[f.name], value, sub, rd)
            if (cls, f.name) in REPEATABLE:
                kwargs[f.name] = _convert_repeated(hint, value, sub, rd)
            else:
                kwargs[f.name] = _convert(hint, value, sub, rd)
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise rd.error(sub, f"missing required key ({_describe(hints[f.name])})")
    try:
        return cls(**kwargs)
    except ModelError as exc:
        raise exc.within(path, rd.file) from None
    except (TypeError, ValueError, ArithmeticError, AttributeError, LookupError) as exc:
        where = path or "model"
        raise rd.error(where, f"invalid {cls.__name__}: {type(exc).__name__}: {_one_line(str(exc))}") from exc


def _unknown_key(path: str, key: str, valid: list[str], rd: _Reader) -> ModelError:
    close = difflib.get_close_matches(key, valid, n=1, cutoff=0.6)
    hint = f"did you mean {close[0]!r}?" if close else f"valid keys are {', '.join(valid)}"
    return rd.error(_join(path, key), f"unknown key; {hint}")


def _late_hint(cls: type, name: str, hint: Any, value: Any, path: str, rd: _Reader) -> Any:
    """Replace an ``Any`` item type by its late-imported class when entries are present."""
    if (cls, name) not in _LATE_TYPES or not isinstance(value, ARRAY) or not value:
        return hint
    module_name, class_name = _LATE_TYPES[(cls, name)]
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name is None or not (module_name == exc.name or module_name.startswith(exc.name + ".")):
            raise  # the module exists but imports something missing: not a model-file problem
        raise rd.error(
            path, f"needs the module {module_name}, which this version of nlgrd does not have"
        ) from None
    item = getattr(module, class_name, None)
    if item is None:
        raise rd.error(path, f"needs {module_name}.{class_name}, which this version of nlgrd does not have")
    return tuple[item, ...]


def _convert_repeated(hint: Any, value: Any, path: str, rd: _Reader) -> Any:
    """Convert a sequence of tables whose entries may carry ``count = N``."""
    if not isinstance(value, ARRAY) or not all(isinstance(v, dict) for v in value):
        raise rd.error(path, f"must be {_describe(hint)}, got {_show(value)}")
    item_hint = _sequence_item(hint)
    out = []
    for i, entry in enumerate(value):
        sub = f"{path}[{i}]"
        entry = dict(entry)
        count = entry.pop(COUNT_KEY, 1)
        if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_COUNT:
            raise rd.error(
                _join(sub, COUNT_KEY), f"must be an integer from 1 to {MAX_COUNT}, got {_show(count)}"
            )
        if dataclasses.is_dataclass(item_hint):
            item = _build(item_hint, entry, sub, rd, extra=(COUNT_KEY,))
        else:
            item = _convert(item_hint, entry, sub, rd)
        out.extend([item] * count)
    return list(out) if typing.get_origin(hint) is list else tuple(out)


def _sequence_item(hint: Any) -> Any:
    for member in union_members(hint):
        if typing.get_origin(member) in _SEQUENCE_ORIGINS:
            args = typing.get_args(member)
            return args[0] if args else Any
    return Any


def union_members(hint: Any) -> list[Any]:
    """The members of a union type hint other than None (``X | None`` gives ``[X]``).

    Parameters
    ----------
    hint : Any
        A type hint.

    Returns
    -------
    list
        The members of the union without ``NoneType``; ``[hint]`` when it is not a union.
    """
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        return [a for a in typing.get_args(hint) if a is not type(None)]
    return [hint]


def _kind_fits(hint: Any, value: Any, strict: bool) -> bool:
    """Whether ``value`` is of the TOML kind that ``hint`` takes (for picking a union member)."""
    origin = typing.get_origin(hint)
    if hint is Any:
        return True
    if origin is typing.Literal:
        return value in typing.get_args(hint)
    if origin in _SEQUENCE_ORIGINS or hint in (tuple, list) or _is_ndarray(hint):
        return isinstance(value, ARRAY)
    if dataclasses.is_dataclass(hint):
        return isinstance(value, dict) or (hint in NAMED_TABLES and isinstance(value, str))
    if isinstance(hint, type) and issubclass(hint, enum.Enum):
        return any(value == m.value for m in hint)
    if hint is bool:
        return isinstance(value, bool)
    if isinstance(value, bool):
        return False
    if hint is int:
        return isinstance(value, int)
    if hint is float:
        return isinstance(value, float) or (not strict and isinstance(value, int))
    if hint is str:
        return isinstance(value, str)
    return False


def _is_ndarray(hint: Any) -> bool:
    return hint is np.ndarray or typing.get_origin(hint) is np.ndarray


def _convert(hint: Any, value: Any, path: str, rd: _Reader) -> Any:
    """Convert one TOML value to the Python value of type ``hint``, or raise ModelError."""
    if hint is Any or hint is object:
        return value
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        members = union_members(hint)
        if len(members) == 1:
            return _convert(members[0], value, path, rd)
        for strict in (True, False):
            for member in members:
                if _kind_fits(member, value, strict):
                    return _convert(member, value, path, rd)
        raise rd.error(path, f"must be {_describe(hint)}, got {_show(value)}")
    if origin is typing.Literal:
        if value in typing.get_args(hint) and type(value) in {type(a) for a in typing.get_args(hint)}:
            return value
        raise rd.error(path, f"must be {_describe(hint)}, got {_show(value)}")
    if origin in _SEQUENCE_ORIGINS or hint in (tuple, list):
        return _convert_sequence(hint, value, path, rd)
    if _is_ndarray(hint):
        return _convert_ndarray(value, path, rd)
    if dataclasses.is_dataclass(hint):
        if hint in NAMED_TABLES and isinstance(value, str):
            return _lookup(hint, value, path, rd)
        if not isinstance(value, dict):
            raise rd.error(path, f"must be {_describe(hint)}, got {_show(value)}")
        return _build(hint, value, path, rd)
    if isinstance(hint, type) and issubclass(hint, enum.Enum):
        for member in hint:
            if value == member.value and type(value) is type(member.value):
                return member
        raise rd.error(path, f"must be {_describe(hint)}, got {_show(value)}")
    if hint is bool:
        if not isinstance(value, bool):
            raise rd.error(path, f"must be true or false, got {_show(value)}")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise rd.error(path, f"must be an integer, got {_show(value)}")
        return value
    if hint is float:
        return _to_float(value, path, rd)
    if hint is str:
        if not isinstance(value, str):
            raise rd.error(path, f"must be a string, got {_show(value)}")
        return value
    raise rd.error(path, f"cannot be set in a model file (type {hint!r})")


def _to_float(value: Any, path: str, rd: _Reader) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise rd.error(path, f"must be a number, got {_show(value)}")
    try:
        out = float(value)
    except OverflowError:
        raise rd.error(path, f"must be finite, got an integer of {len(str(abs(value)))} digits") from None
    if not math.isfinite(out):
        raise rd.error(path, f"must be finite, got {toml_value(out)}")
    return out


def _convert_sequence(hint: Any, value: Any, path: str, rd: _Reader) -> Any:
    if not isinstance(value, ARRAY):
        raise rd.error(path, f"must be {_describe(hint)}, got {_show(value)}")
    origin = typing.get_origin(hint) or hint
    args = typing.get_args(hint)
    if origin is tuple and args and args[-1] is not Ellipsis:
        if len(value) != len(args):
            raise rd.error(path, f"must have {len(args)} entries, got {len(value)}")
        items = [_convert(a, v, f"{path}[{i}]", rd) for i, (a, v) in enumerate(zip(args, value, strict=True))]
    else:
        item = args[0] if args else Any
        items = [_convert(item, v, f"{path}[{i}]", rd) for i, v in enumerate(value)]
    return items if origin is list else tuple(items)


def _convert_ndarray(value: Any, path: str, rd: _Reader) -> np.ndarray:
    def leaves(v: Any, p: str) -> Any:
        if isinstance(v, ARRAY):
            return [leaves(x, f"{p}[{i}]") for i, x in enumerate(v)]
        return _to_float(v, p, rd)

    if not isinstance(value, ARRAY):
        raise rd.error(path, f"must be an array of numbers, got {_show(value)}")
    nested = leaves(value, path)
    try:
        return np.array(nested, dtype=float)
    except ValueError:
        raise rd.error(path, "must be a rectangular array of numbers") from None


def _lookup(cls: type, name: str, path: str, rd: _Reader) -> Any:
    table = NAMED_TABLES[cls]
    known = rd.named.get(cls, {})
    if name in known:
        return known[name]
    if not known:
        raise rd.error(path, f"unknown {cls.__name__.lower()} {name!r}: the file has no [{table}] tables")
    close = difflib.get_close_matches(name, list(known), n=1, cutoff=0.6)
    hint = f"did you mean {close[0]!r}?" if close else f"defined: {', '.join(map(repr, known))}"
    raise rd.error(path, f"unknown {cls.__name__.lower()} {name!r} (not in [{table}]); {hint}")


def _describe(hint: Any) -> str:
    """Words for what a type hint accepts, for error messages."""
    if hint is Any or hint is object:
        return "a value"
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_describe(m) for m in union_members(hint))
    if origin is typing.Literal:
        return "one of " + ", ".join(toml_value(a) for a in typing.get_args(hint))
    if origin in _SEQUENCE_ORIGINS or hint in (tuple, list):
        args = [a for a in typing.get_args(hint) if a is not Ellipsis]
        kinds = {_plural(a) for a in args} or {"values"}
        return f"an array of {' or '.join(sorted(kinds))}"
    if _is_ndarray(hint):
        return "an array of numbers"
    if dataclasses.is_dataclass(hint):
        if hint in NAMED_TABLES:
            return f"the name of a [{NAMED_TABLES[hint]}] table or a table"
        return "a table"
    if isinstance(hint, type) and issubclass(hint, enum.Enum):
        return "one of " + ", ".join(toml_value(m.value) for m in hint)
    return {bool: "true or false", int: "an integer", float: "a number", str: "a string"}.get(
        hint, repr(hint)
    )


def _plural(hint: Any) -> str:
    if dataclasses.is_dataclass(hint):
        return "tables"
    return {bool: "booleans", int: "integers", float: "numbers", str: "strings"}.get(hint, "values")


def _toml_type(value: Any) -> str:
    if isinstance(value, bool):
        return "boolean"
    kinds = ((int, "integer"), (float, "float"), (str, "string"), (ARRAY, "array"), (dict, "table"))
    for kind, name in kinds:
        if isinstance(value, kind):
            return name
    return "datetime" if hasattr(value, "isoformat") else type(value).__name__


def _show(value: Any, limit: int = 60) -> str:
    """A value as TOML spells it, with its TOML type, shortened: ``string "0.05"``."""
    try:
        text = toml_value(value)
    except TypeError:
        text = value.isoformat() if hasattr(value, "isoformat") else repr(value)
    if len(text) > limit:
        text = text[: limit - 3] + "..."
    return f"{_toml_type(value)} {text}"


def _one_line(text: str) -> str:
    return " ".join(text.split()) if "\n" in text or "\r" in text else text


def _join(path: str, key: str) -> str:
    key = toml_key(key)
    return f"{path}.{key}" if path else key
