"""Writing model files: :func:`save_model` (atomic) and :func:`model_to_dict`.

The inverse of :mod:`nlgrd.io.model_file`: every field is written, defaults included,
so that a file means the same to a later version; ``load_model(save_model(s))``
equals ``s``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import enum
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from nlgrd.io.model_file import (
    COUNT_KEY,
    FORMAT_VERSION,
    MAX_COUNT,
    NAMED_TABLES,
    REPEATABLE,
    field_hints,
    union_members,
)
from nlgrd.io.toml_format import dumps
from nlgrd.rotor.system import RotorSystem


@dataclasses.dataclass
class _Writer:
    """State of one write: the named objects met so far, by table."""

    named: dict[type, dict[str, Any]] = dataclasses.field(default_factory=dict)


def model_to_dict(system: RotorSystem) -> dict[str, Any]:
    """The dictionary of a model file for ``system``: TOML-ready values only.

    Every field is written, defaults included, so that a file means the same to a
    later nlgrd whose defaults differ. Runs of identical shaft elements are written
    as one entry with ``count``. ``model_from_dict(model_to_dict(s)) == s``.

    Parameters
    ----------
    system : RotorSystem
        The model.

    Returns
    -------
    dict
    """
    if not isinstance(system, RotorSystem):
        raise TypeError(f"expected a RotorSystem, got {type(system).__name__}")
    wr = _Writer()
    body = _dump_dataclass(system, wr)
    out: dict[str, Any] = {"version": FORMAT_VERSION}
    if "name" in body:
        out["name"] = body.pop("name")
    for cls, table in NAMED_TABLES.items():
        entries = wr.named.get(cls, {})
        if entries:
            out[table] = {
                k: {n: v for n, v in _dump_dataclass(obj, wr).items() if n != "name"}
                for k, obj in entries.items()
            }
    out.update(body)
    return out


def save_model(system: RotorSystem, path: str | os.PathLike, header: str | None = None) -> None:
    """Write ``system`` to a TOML model file, atomically.

    The text goes to a temporary file in the same directory, which then replaces
    ``path`` (``os.replace``): a reader never sees a half-written file, and a failed
    write leaves an existing file as it was. ``load_model`` gives back an equal system.

    Parameters
    ----------
    system : RotorSystem
        The model.
    path : str or path-like
        Destination file.
    header : str, optional
        Text written as ``#`` comment lines at the top of the file.
    """
    text = dumps(model_to_dict(system), header)
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        try:
            mode = path.stat().st_mode & 0o777
        except FileNotFoundError:
            mode = 0o644
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def _dump_dataclass(obj: Any, wr: _Writer) -> dict[str, Any]:
    out: dict[str, Any] = {}
    hints = field_hints(type(obj))
    for f in dataclasses.fields(obj):
        if not f.init:
            continue
        value = getattr(obj, f.name)
        if value is None:
            if f.default is not None:
                raise ValueError(f"{type(obj).__name__}.{f.name} is None, which a model file cannot hold")
            continue
        if (type(obj), f.name) in REPEATABLE and isinstance(value, (tuple, list)):
            out[f.name] = _dump_runs(value, wr)
        else:
            out[f.name] = _dump_value(value, wr)
        if _wants_float(hints.get(f.name)) and type(out[f.name]) is int:
            out[f.name] = float(out[f.name])  # 5 -> 5.0 for a float field; it reads back equal
    if "name" in out:
        out = {"name": out.pop("name"), **out}
    return out


def _wants_float(hint: Any) -> bool:
    members = union_members(hint)
    return float in members and int not in members


def _dump_runs(items: Any, wr: _Writer) -> list[dict[str, Any]]:
    """Entries for a repeatable sequence: runs of equal items as one entry with ``count``."""
    out: list[dict[str, Any]] = []
    i = 0
    while i < len(items):
        j = i + 1
        while j < len(items) and j - i < MAX_COUNT and items[j] == items[i]:
            j += 1
        entry = _dump_dataclass(items[i], wr)
        out.append({COUNT_KEY: j - i, **entry} if j - i > 1 else entry)
        i = j
    return out


def _dump_value(value: Any, wr: _Writer) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        cls = type(value)
        if cls in NAMED_TABLES:
            known = wr.named.setdefault(cls, {})
            name = value.name
            if name not in known:
                known[name] = value
            if known[name] == value:
                return name
        return _dump_dataclass(value, wr)
    if isinstance(value, enum.Enum):
        return _dump_value(value.value, wr)
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    if isinstance(value, str):
        return value
    if isinstance(value, np.ndarray):
        return _dump_value(value.tolist(), wr)
    if isinstance(value, (list, tuple)):
        if any(v is None for v in value):
            raise ValueError("a model file cannot hold None inside an array")
        return [_dump_value(v, wr) for v in value]
    raise TypeError(f"a model file cannot hold a {type(value).__name__}: {value!r}")
