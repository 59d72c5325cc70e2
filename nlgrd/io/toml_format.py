"""TOML text: the writer of model files (tables, arrays of tables, values) and the
quoting of keys and values in messages (TOML 1.0; tomllib reads it back).
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

#: TOML arrays; tuples too for dictionaries built in Python.
ARRAY = (list, tuple)
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def dumps(data: dict[str, Any], header: str | None = None) -> str:
    """TOML text of ``data``: the subset nlgrd needs (tables, arrays of tables, scalars, arrays).

    Parameters
    ----------
    data : dict of str to Any
        The document: nested dictionaries are tables, lists (or tuples) of dictionaries
        arrays of tables, other values are written by :func:`toml_value`.
    header : str or None
        Text written first as comment lines (``# ...``), one per line; None for none.

    Returns
    -------
    str
        The TOML text, ending with a newline.

    Raises
    ------
    TypeError
        When an array mixes tables and other values, or a value has no TOML form.
    """
    lines: list[str] = []
    if header:
        lines.extend(f"# {line}".rstrip() for line in header.splitlines())
        lines.append("")
    _write_table(lines, [], data)
    while lines and not lines[0]:
        lines.pop(0)
    return "\n".join(lines) + "\n"


def _is_table_array(value: Any) -> bool:
    if isinstance(value, ARRAY) and value and all(isinstance(v, dict) for v in value):
        return True
    if isinstance(value, ARRAY) and any(isinstance(v, dict) for v in value):
        raise TypeError("an array mixes tables and other values")
    return False


def _write_table(lines: list[str], path: list[str], table: dict[str, Any]) -> None:
    inline = [(k, v) for k, v in table.items() if not isinstance(v, dict) and not _is_table_array(v)]
    tables = [(k, v) for k, v in table.items() if isinstance(v, dict)]
    arrays = [(k, v) for k, v in table.items() if _is_table_array(v)]
    for key, value in inline:
        lines.append(f"{toml_key(key)} = {toml_value(value)}")
    for key, value in tables:
        sub = [*path, toml_key(key)]
        has_inline = any(not isinstance(v, dict) and not _is_table_array(v) for v in value.values())
        if has_inline or not value:
            lines.extend(["", f"[{'.'.join(sub)}]"])
        _write_table(lines, sub, value)
    for key, value in arrays:
        sub = [*path, toml_key(key)]
        for item in value:
            lines.extend(["", f"[[{'.'.join(sub)}]]"])
            _write_table(lines, sub, item)


def toml_key(key: str) -> str:
    """A key in TOML syntax: bare when it may be, else a quoted string.

    Parameters
    ----------
    key : str
        The key.

    Returns
    -------
    str
        ``key`` itself when it is made of ``A-Za-z0-9_-`` only, else quoted and escaped.
    """
    return key if _BARE_KEY.fullmatch(key) else _toml_string(key)


_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r"}


def _toml_string(text: str) -> str:
    out = []
    for ch in text:
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def toml_value(value: Any) -> str:
    """One value in TOML syntax; floats keep ``repr`` precision, so they read back exactly.

    Parameters
    ----------
    value : Any
        A boolean, integer, float (NaN and infinities too), string, list or tuple of such
        values, or a dictionary (written as an inline table); numpy scalars too.

    Returns
    -------
    str
        The TOML text of the value.

    Raises
    ------
    TypeError
        When the value (or an item of it) has no TOML form.
    """
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        value = float(value)
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        if value != 0 and not 1e-4 <= abs(value) < 1e6:
            return np.format_float_scientific(value, unique=True, trim="0")
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write a {type(value).__name__} as TOML")
