"""Study files: a parametric or tolerance study of a model file, read from TOML.

A study is many sweeps of one base model, each with some model values changed. Its
file names the model, the sweep every task runs, and the parameter axes::

    version = 1
    name = "Kubo: jump band against backlash and mesh damping"
    model = "../data/case_studies/kubo.toml"   # relative to this file

    [analysis]
    rpm = [6000.0, 12000.0, 31]     # START, STOP, COUNT of pinion speeds; or hz = [...]
    direction = "both"              # "up", "down" or "both"
    harmonics = 9                   # left out: chosen by the error estimate (tolerance)
    tolerance = 0.005               # output tolerance of that estimate [-]
    stability = true                # Floquet stability (on by default)
    time_domain = true              # points with no stable periodic orbit answered by time
                                    # integration (needs stability; on by default)

    [[axes]]                        # one parameter axis
    key = "gear_pairs[0].geometry.backlash"
    values = [50e-6, 100e-6, 200e-6]

    [[axes]]
    key = "gear_pairs[0].damping_ratio"
    range = [0.005, 0.05, 4]        # START, STOP, COUNT
    spacing = "log"                 # "linear" (default) or "log"

    [[axes]]
    key = "bearings[*].kyy"         # [*]: every entry of the list
    scale = [0.5, 1.0, 2.0]         # multiplies the model file's value

    [[axes]]                        # a tolerance: sampled, not gridded
    key = ["gear_pairs[0].modifications.tip_relief_pinion",
           "gear_pairs[0].modifications.tip_relief_gear"]   # one value set at both keys
    distribution = "normal"         # "normal" (mean, std) or "uniform" (low, high)
    mean = 10e-6
    std = 1e-6
    unit = "m"

    [sampling]                      # for the sampled axes only
    method = "latin_hypercube"      # or "random"
    samples = 20
    seed = 1

The tasks are the full grid of the gridded axes (``values``, ``range``, ``scale``),
each combined with every one of the ``samples`` draws of the sampled axes (the same
draws at every grid point: common random numbers, so that designs are compared on the
same errors). Latin hypercube draws are stratified per axis (McKay, Beckman & Conover
1979; :class:`scipy.stats.qmc.LatinHypercube`), random ones plain Monte Carlo, both
from the seed, so a study file always means the same tasks.

Every axis value is applied to the base model and the model is checked before any
work starts: a bad key or value raises one :class:`~nlgrd.errors.ModelError` naming
the study file and the key, e.g. ``study.toml: axes[1].values[2]: gear_pairs[0].geometry.backlash:
must be non-negative, got -1e-05``.
"""

from __future__ import annotations

import copy
import itertools
import math
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from nlgrd.errors import ModelError
from nlgrd.studies.model_keys import UNITS, apply_value, key_paths

__all__ = ["Analysis", "Axis", "Study", "load_study"]

SAMPLING = ("latin_hypercube", "random")
DISTRIBUTIONS = {"normal": ("mean", "std"), "uniform": ("low", "high")}
_NO_UNIT = "?"  # a field of no known unit: the study file must give it (checked last)
#: Most tasks one study may hold (a typing slip beyond that).
MAX_TASKS = 1_000_000


@dataclass(frozen=True)
class Analysis:
    """The sweep every task of a study runs.

    Parameters
    ----------
    unit : {"rpm", "hz"}
        Whether the range is of pinion (reference shaft) speeds [rpm] or base (mesh)
        frequencies [Hz].
    start, stop : float
        Ends of the range, in ``unit``.
    count : int
        Points of the range.
    direction : {"up", "down", "both"}
        Sweep directions.
    harmonics : int or None
        Number of harmonics; None chooses it by the error estimate.
    tolerance : float
        Output tolerance of that estimate [-].
    stability : bool
        Floquet stability of every point.
    time_domain : bool
        Points without a stable periodic orbit answered by time integration
        (:func:`nlgrd.timedomain.sweep_answers.with_time_answers`; needs ``stability``).
    """

    unit: str
    start: float
    stop: float
    count: int
    direction: str = "both"
    harmonics: int | None = None
    tolerance: float = 0.005
    stability: bool = True
    time_domain: bool = True

    def values(self) -> np.ndarray:
        """The swept speeds [rpm] or frequencies [Hz]."""
        return np.linspace(self.start, self.stop, self.count)

    def as_dict(self) -> dict[str, Any]:
        """The analysis as plain data (for task keys and records)."""
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


@dataclass(frozen=True)
class Axis:
    """One parameter axis of a study.

    Parameters
    ----------
    keys : tuple of str
        Model keys set by the axis (each may hold ``[*]``); all get the same value.
    name : str
        The axis' column name in the results, with its unit, e.g. ``"torque [N m]"``.
    values : tuple
        The gridded values (numbers or strings), or scale factors when ``scaled``;
        empty for a sampled axis.
    scaled : bool
        Whether the values multiply the model file's values.
    distribution : str or None
        ``"normal"`` or ``"uniform"`` for a sampled axis.
    parameters : tuple of float
        Its parameters: (mean, std) or (low, high).
    """

    keys: tuple[str, ...]
    name: str
    values: tuple = ()
    scaled: bool = False
    distribution: str | None = None
    parameters: tuple[float, ...] = ()

    @property
    def sampled(self) -> bool:
        """Whether the axis is drawn from a distribution rather than gridded."""
        return self.distribution is not None

    def from_unit(self, u: np.ndarray) -> np.ndarray:
        """Values of a sampled axis at probabilities ``u`` in (0, 1) (inverse CDF)."""
        from scipy import stats

        a, b = self.parameters
        if self.distribution == "normal":
            return stats.norm.ppf(u, loc=a, scale=b)
        return a + (b - a) * u


@dataclass(frozen=True)
class Study:
    """A study: base model (as read from its file), analysis, axes and sampling.

    Parameters
    ----------
    file : str
        The study file.
    name : str
        Its title.
    model_file : str
        The base model file (absolute).
    model : dict
        The base model file's content (parsed TOML).
    analysis : Analysis
        The sweep of every task.
    axes : tuple of Axis
        The parameter axes, in file order.
    method : str
        ``"latin_hypercube"`` or ``"random"`` (sampled axes).
    samples : int
        Draws of the sampled axes (1 when there are none).
    seed : int
        Seed of the draws.
    """

    file: str
    name: str
    model_file: str
    model: dict
    analysis: Analysis
    axes: tuple[Axis, ...]
    method: str = "latin_hypercube"
    samples: int = 1
    seed: int = 0

    @property
    def grid_axes(self) -> tuple[Axis, ...]:
        """The gridded axes, in file order."""
        return tuple(a for a in self.axes if not a.sampled)

    def draws(self) -> np.ndarray:
        """The sampled axes' values, one row per draw (shape samples x sampled axes)."""
        sampled = [a for a in self.axes if a.sampled]
        if not sampled:
            return np.zeros((1, 0))
        rng = np.random.default_rng(self.seed)
        if self.method == "latin_hypercube":
            from scipy.stats import qmc

            u = qmc.LatinHypercube(d=len(sampled), rng=rng).random(self.samples)
        else:
            u = rng.random((self.samples, len(sampled)))
        return np.column_stack([a.from_unit(u[:, i]) for i, a in enumerate(sampled)])

    def parameter_sets(self) -> list[dict[str, Any]]:
        """Every task's parameters: axis name -> value, grid order (last axis fastest),
        each grid point with every draw."""
        grid = self.grid_axes
        sampled = [a for a in self.axes if a.sampled]
        draws = self.draws()
        out = []
        for combo in itertools.product(*(a.values for a in grid)):
            for row in draws:
                p = {a.name: v for a, v in zip(grid, combo, strict=True)}
                p.update({a.name: float(v) for a, v in zip(sampled, row, strict=True)})
                out.append({a.name: p[a.name] for a in self.axes})
        return out

    def model_data(self, parameters: dict[str, Any]) -> dict:
        """The base model's data with ``parameters`` (:meth:`parameter_sets`) applied."""
        data = copy.deepcopy(self.model)
        for axis in self.axes:
            for key in axis.keys:
                apply_value(data, key, parameters[axis.name], axis.scaled)
        return data


# ------------------------------------------------------------------------- reading


class _Where:
    """The study file, for error messages."""

    def __init__(self, file: str):
        self.file = file

    def error(self, key: str, message: str) -> ModelError:
        return ModelError(key, message, self.file)


def _number(value: Any, key: str, w: _Where, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise w.error(key, f"must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise w.error(key, f"must be positive, got {value!r}")
    return float(value)


def _integer(value: Any, key: str, w: _Where, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise w.error(key, f"must be an integer from {low} to {high}, got {value!r}")
    return int(value)


def _table(data: dict, key: str, allowed: set[str], w: _Where, required: set[str] = frozenset()) -> dict:
    table = data.get(key, {})
    if not isinstance(table, dict):
        raise w.error(key, f"must be a table, got {type(table).__name__}")
    for k in sorted(set(table) - allowed):
        raise w.error(f"{key}.{k}", f"unknown key; valid keys: {', '.join(sorted(allowed))}")
    for k in sorted(required - set(table)):
        raise w.error(f"{key}.{k}", "is required")
    return table


def _analysis(data: dict, w: _Where) -> Analysis:
    allowed = {"rpm", "hz", "direction", "harmonics", "tolerance", "stability", "time_domain"}
    t = _table(data, "analysis", allowed, w)
    if ("rpm" in t) == ("hz" in t):
        raise w.error("analysis.rpm", "give the range as rpm = [START, STOP, COUNT] or hz = [...]")
    unit = "rpm" if "rpm" in t else "hz"
    r = t[unit]
    key = f"analysis.{unit}"
    if not isinstance(r, list) or len(r) != 3:
        raise w.error(key, f"must be [START, STOP, COUNT], got {r!r}")
    start = _number(r[0], f"{key}[0]", w, positive=True)
    stop = _number(r[1], f"{key}[1]", w, positive=True)
    count = _integer(r[2], f"{key}[2]", w, 1, 100_000)
    if (count > 1 and start >= stop) or (count == 1 and start != stop):
        raise w.error(key, f"must go up, START < STOP (one speed: START = STOP and COUNT 1), got {r!r}")
    direction = t.get("direction", "both")
    if direction not in ("up", "down", "both"):
        raise w.error("analysis.direction", f"must be 'up', 'down' or 'both', got {direction!r}")
    harmonics = t.get("harmonics")
    if harmonics is not None:
        harmonics = _integer(harmonics, "analysis.harmonics", w, 1, 10**9)  # memory: _check_speeds
    tolerance = _number(t.get("tolerance", 0.005), "analysis.tolerance", w, positive=True)
    stability = t.get("stability", True)
    if not isinstance(stability, bool):
        raise w.error("analysis.stability", f"must be true or false, got {stability!r}")
    time_domain = t.get("time_domain", True)
    if not isinstance(time_domain, bool):
        raise w.error("analysis.time_domain", f"must be true or false, got {time_domain!r}")
    return Analysis(unit, start, stop, count, direction, harmonics, tolerance, stability, time_domain)


def _check_speeds(system, analysis: Analysis, w: _Where) -> None:
    """The sweep's top speed within every gear pair's pitch-line velocity limit, and its
    harmonics within memory (the bound of ``--harmonics``)."""
    from nlgrd.io.model_checks import check_harmonics_memory, check_speed_range

    try:
        key, given = f"analysis.{analysis.unit}", f"{analysis.stop:g} {analysis.unit}"
        check_speed_range(system, analysis.stop, analysis.unit == "rpm", key, given)
        check_harmonics_memory(system, analysis.harmonics, "analysis.harmonics")
    except ModelError as err:
        raise w.error(err.key, err.message) from None


def _axis_name(keys: tuple[str, ...], raw: dict, scaled: bool, key: str, w: _Where) -> str:
    if "name" in raw and not isinstance(raw["name"], str):
        raise w.error(f"{key}.name", f"must be a string, got {raw['name']!r}")
    base = raw.get("name", keys[0])
    if scaled:
        return f"{base} scale [-]"
    unit = raw.get("unit", UNITS.get(keys[0].rsplit(".", 1)[-1], _NO_UNIT))
    if not isinstance(unit, str):
        raise w.error(f"{key}.unit", f"must be a string, got {unit!r}")
    return f"{base} [{unit}]"


def _axis(raw: Any, i: int, w: _Where) -> Axis:
    key = f"axes[{i}]"
    if not isinstance(raw, dict):
        raise w.error(key, f"must be a table, got {type(raw).__name__}")
    kinds = [k for k in ("values", "range", "scale", "distribution") if k in raw]
    if len(kinds) != 1:
        raise w.error(key, "give exactly one of values, range, scale or distribution")
    kind = kinds[0]
    allowed = {"key", "name", "unit", kind}
    if kind == "range":
        allowed.add("spacing")
    if kind == "distribution":
        dist = raw["distribution"]
        if not isinstance(dist, str) or dist not in DISTRIBUTIONS:
            raise w.error(f"{key}.distribution", f"must be one of {', '.join(DISTRIBUTIONS)}, got {dist!r}")
        allowed |= set(DISTRIBUTIONS[dist])
    for k in sorted(set(raw) - allowed):
        raise w.error(f"{key}.{k}", f"unknown key; valid keys here: {', '.join(sorted(allowed))}")
    keys = raw.get("key")
    keys = [keys] if isinstance(keys, str) else keys
    if not keys or not isinstance(keys, list) or not all(isinstance(k, str) and k for k in keys):
        raise w.error(f"{key}.key", 'must be a model key, e.g. "gear_pairs[0].torque", or a list of them')
    for k in keys:
        try:
            key_paths(k)
        except ModelError as err:
            raise w.error(f"{key}.key", err.message) from None
    keys = tuple(keys)
    name = _axis_name(keys, raw, kind == "scale", key, w)
    if kind == "distribution":
        dist = raw["distribution"]
        if dist not in DISTRIBUTIONS:
            raise w.error(f"{key}.distribution", f"must be one of {', '.join(DISTRIBUTIONS)}, got {dist!r}")
        names = DISTRIBUTIONS[dist]
        for p in names:
            if p not in raw:
                raise w.error(f"{key}.{p}", f"is required for a {dist} distribution")
        a, b = (_number(raw[p], f"{key}.{p}", w) for p in names)
        if b <= (a if dist == "uniform" else 0):
            raise w.error(f"{key}.{names[1]}", f"must be above {a if dist == 'uniform' else 0}, got {b!r}")
        return Axis(keys, name, distribution=dist, parameters=(a, b))
    if kind == "range":
        r = raw["range"]
        if not isinstance(r, list) or len(r) != 3:
            raise w.error(f"{key}.range", f"must be [START, STOP, COUNT], got {r!r}")
        a, b = (_number(v, f"{key}.range[{j}]", w) for j, v in enumerate(r[:2]))
        n = _integer(r[2], f"{key}.range[2]", w, 1, 100_000)
        spacing = raw.get("spacing", "linear")
        if spacing not in ("linear", "log"):
            raise w.error(f"{key}.spacing", f"must be 'linear' or 'log', got {spacing!r}")
        if spacing == "log" and (a <= 0 or b <= 0):
            raise w.error(f"{key}.range", "a log range needs positive ends")
        vals = np.geomspace(a, b, n) if spacing == "log" else np.linspace(a, b, n)
        return Axis(keys, name, tuple(float(v) for v in vals))
    vals = raw[kind]
    if not isinstance(vals, list) or not vals:
        raise w.error(f"{key}.{kind}", f"must be a non-empty list, got {vals!r}")
    out = []
    for j, v in enumerate(vals):
        if isinstance(v, str) and kind == "values":
            out.append(v)
        else:
            out.append(_number(v, f"{key}.{kind}[{j}]", w, positive=kind == "scale"))
    if len(set(out)) != len(out):
        raise w.error(f"{key}.{kind}", "holds a value twice")
    return Axis(keys, name, tuple(out), scaled=kind == "scale")


def _sampling(data: dict, axes: list[Axis], w: _Where) -> tuple[str, int, int]:
    t = _table(data, "sampling", {"method", "samples", "seed"}, w)
    if not any(a.sampled for a in axes):
        if t:
            raise w.error("sampling", "there is no sampled axis (one with a distribution)")
        return "latin_hypercube", 1, 0
    for k in ("samples", "seed"):
        if k not in t:
            raise w.error(f"sampling.{k}", "is required with sampled axes")
    method = t.get("method", "latin_hypercube")
    if method not in SAMPLING:
        raise w.error("sampling.method", f"must be one of {', '.join(SAMPLING)}, got {method!r}")
    samples = _integer(t["samples"], "sampling.samples", w, 1, MAX_TASKS)
    seed = _integer(t["seed"], "sampling.seed", w, 0, 2**63 - 1)
    return method, samples, seed


def load_study(path: str | os.PathLike) -> Study:
    """Read and check a study file; every axis value is tried on the model.

    Parameters
    ----------
    path : str or os.PathLike
        The study file (TOML).

    Returns
    -------
    Study

    Raises
    ------
    ModelError
        One line naming the file and the key, for a missing or unreadable file, an
        unknown or bad key, or an axis value the model does not accept.
    """
    from nlgrd.io.model_file import model_from_file_data

    path = Path(path)
    w = _Where(str(path))
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as err:
        raise ModelError("", f"cannot read the study file: {err.strerror or err}", str(path)) from None
    except tomllib.TOMLDecodeError as err:
        raise ModelError("", f"not valid TOML: {err}", str(path)) from None
    allowed = {"version", "name", "model", "analysis", "axes", "sampling"}
    for k in sorted(set(data) - allowed):
        raise w.error(k, f"unknown key; valid keys: {', '.join(sorted(allowed))}")
    if data.get("version") != 1:
        raise w.error("version", f"must be 1, got {data.get('version')!r}")
    name = data.get("name", path.stem)
    if not isinstance(name, str):
        raise w.error("name", f"must be a string, got {name!r}")
    if not isinstance(data.get("model"), str):
        raise w.error("model", "must name the base model file (relative to the study file)")
    model_file = (path.parent / data["model"]).resolve()
    try:
        model = tomllib.loads(model_file.read_text(encoding="utf-8"))
    except OSError as err:
        raise w.error("model", f"cannot read {data['model']!r}: {err.strerror or err}") from None
    except tomllib.TOMLDecodeError as err:
        raise w.error("model", f"{data['model']!r} is not valid TOML: {err}") from None
    try:
        system = model_from_file_data(model, str(model_file))
    except ModelError as err:
        raise w.error("model", str(err)) from None
    analysis = _analysis(data, w)
    _check_speeds(system, analysis, w)
    raw_axes = data.get("axes", [])
    if not isinstance(raw_axes, list):
        raise w.error("axes", "must be an array of tables ([[axes]])")
    axes = [_axis(a, i, w) for i, a in enumerate(raw_axes)]
    names = [a.name for a in axes]
    for n in names:
        if names.count(n) > 1:
            raise w.error("axes", f"two axes have the column name {n!r}; give one a name")
    method, samples, seed = _sampling(data, axes, w)
    study = Study(str(path), name, str(model_file), model, analysis, tuple(axes), method, samples, seed)
    total = math.prod(len(a.values) for a in study.grid_axes) * samples
    if total > MAX_TASKS:
        raise w.error("axes", f"{total} tasks; at most {MAX_TASKS}")
    _check_values(study, w)
    for i, a in enumerate(axes):
        if a.name.endswith(f"[{_NO_UNIT}]"):
            raise w.error(
                f"axes[{i}].unit", f'give the unit of {a.keys[0]!r} (e.g. unit = "m") for its column'
            )
    return study


def _check_values(study: Study, w: _Where) -> None:
    """Apply each axis value alone (sampled axes: their extreme draws) and build the model."""
    from nlgrd.io.model_file import model_from_file_data

    draws = study.draws()
    sampled = [a for a in study.axes if a.sampled]
    for i, axis in enumerate(study.axes):
        if axis.sampled:
            col = draws[:, sampled.index(axis)]
            trials = [(f"axes[{i}] (draw {int(j)})", float(col[j])) for j in (np.argmin(col), np.argmax(col))]
        else:
            kind = "scale" if axis.scaled else "values"
            trials = [(f"axes[{i}].{kind}[{j}]", v) for j, v in enumerate(axis.values)]
        for where, value in trials:
            data = copy.deepcopy(study.model)
            try:
                for key in axis.keys:
                    apply_value(data, key, value, axis.scaled)
                model_from_file_data(data, study.model_file)
            except ModelError as err:
                raise w.error(where, f"{err.key}: {err.message}" if err.key else err.message) from None
