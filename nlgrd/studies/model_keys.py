"""Model keys: addressing a value of a model file's data by path, as study axes do.

A key is the path a model-file error names: table keys joined by dots and list
entries by index, ``gear_pairs[0].geometry.backlash``; ``[*]`` stands for every entry
of a list, ``bearings[*].kyy``. Setting a key creates the tables on its way that the
file left out (``gear_pairs[0].modifications.tip_relief_pinion`` on a mesh without
modifications), so that the model reader checks the result like any model file.
"""

from __future__ import annotations

import re
from typing import Any

from nlgrd.errors import ModelError

__all__ = ["UNITS", "apply_value", "key_paths"]

#: Units of the model fields a study usually varies, for the results' column names
#: (SI, as in the model files; an axis may give its own ``unit``).
UNITS = {
    "torque": "N m",
    "backlash": "m",
    "mesh_stiffness": "N/m",
    "mesh_damping": "N s/m",
    "damping_ratio": "-",
    "tip_relief_pinion": "m",
    "tip_relief_gear": "m",
    "start_diameter_pinion": "m",
    "start_diameter_gear": "m",
    "start_roll_angle_pinion": "rad",
    "start_roll_angle_gear": "rad",
    "shape": "-",
    "profile_slope_pinion": "m",
    "profile_slope_gear": "m",
    "face_width": "m",
    "module": "m",
    "pressure_angle": "rad",
    "clearance": "m",
    "stiffness": "N/m",
    "exponent": "-",
    "kyy": "N/m",
    "kzz": "N/m",
    "kxx": "N/m",
    "kyz": "N/m",
    "kzy": "N/m",
    "cyy": "N s/m",
    "czz": "N s/m",
    "cxx": "N s/m",
    "k_torsion": "N m/rad",
    "c_torsion": "N m s/rad",
    "mass": "kg",
    "diametral_inertia": "kg m^2",
    "polar_inertia": "kg m^2",
    "outer_diameter": "m",
    "inner_diameter": "m",
    "length": "m",
    "unbalance": "kg m",
    "amount": "kg m",  # unbalance[i].amount
    "phase": "rad",  # unbalance[i].phase
    "modal_floor": "-",  # damping.modal_floor
    "rayleigh_alpha": "1/s",
    "rayleigh_beta": "s",
}

_PART = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[(?:\d+|\*)\])*)")
_INDEX = re.compile(r"\[(\d+|\*)\]")


def key_paths(key: str) -> list[str | int]:
    """The steps of ``key``: table keys (str), list indices (int) and ``"*"`` for all entries.

    Parameters
    ----------
    key : str
        E.g. ``"gear_pairs[0].geometry.backlash"``.

    Returns
    -------
    list
        E.g. ``["gear_pairs", 0, "geometry", "backlash"]``.

    Raises
    ------
    ModelError
        When ``key`` is not such a path, or does not end in a table key.
    """
    steps: list[str | int] = []
    for part in key.split("."):
        m = _PART.fullmatch(part)
        if not m:
            raise ModelError("key", f'{key!r} is not a model key like "gear_pairs[0].geometry.backlash"')
        steps.append(m.group(1))
        for idx in _INDEX.findall(m.group(2)):
            steps.append("*" if idx == "*" else int(idx))
    if not isinstance(steps[-1], str):
        raise ModelError("key", f"{key!r} must end in a field name, not an index")
    return steps


def _walk(node: Any, steps: list, done: str, key: str, value: Any, scaled: bool) -> None:
    step, rest = steps[0], steps[1:]
    if isinstance(step, str):
        if not isinstance(node, dict):
            raise ModelError(key, f"{done or 'the model'} is not a table")
        if not rest:
            if scaled:
                old = node.get(step)
                if isinstance(old, bool) or not isinstance(old, int | float):
                    raise ModelError(key, f"a scaled axis needs a number in the model file, found {old!r}")
                node[step] = old * value
            else:
                node[step] = value
            return
        if step not in node:
            if isinstance(rest[0], str):
                node[step] = {}
            else:
                raise ModelError(key, f"the model file has no list {done + '.' if done else ''}{step}")
        _walk(node[step], rest, f"{done}.{step}" if done else step, key, value, scaled)
        return
    if not isinstance(node, list):
        raise ModelError(key, f"{done} is not a list")
    if step == "*":
        if not node:
            raise ModelError(key, f"{done} is empty")
        for i, item in enumerate(node):
            _walk(item, rest, f"{done}[{i}]", key, value, scaled)
        return
    if step >= len(node):
        raise ModelError(key, f"{done} has {len(node)} entries; there is no [{step}]")
    _walk(node[step], rest, f"{done}[{step}]", key, value, scaled)


def apply_value(data: dict, key: str, value: Any, scaled: bool = False) -> None:
    """Set (or, ``scaled``, multiply) the value at ``key`` of model data ``data``, in place.

    Parameters
    ----------
    data : dict
        A model file's parsed TOML.
    key : str
        The model key (:func:`key_paths`).
    value : float or str
        The value set, or the scale factor.
    scaled : bool
        Multiply the file's value (which must be there) instead of replacing it.

    Raises
    ------
    ModelError
        Naming ``key``, when its path does not exist in ``data`` (a list entry out of
        range, a list or table missing) or a scaled value is not a number.
    """
    if "count" in key_paths(key)[-1:]:
        raise ModelError(key, "the element count is not a parameter")
    _walk(data, key_paths(key), "", key, value, scaled)
