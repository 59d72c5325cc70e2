"""Measured response curves (digitised from the literature) and their comparison with sweeps.

A data set is a CSV file in ``data/experimental/`` whose format is defined in
``data/experimental/README.md``: ``# key: value`` header lines (source figure,
digitisation, axis calibration, uncertainty, case, quantity), then the columns
``pinion_speed_rpm`` or ``mesh_frequency_hz``, ``value`` and ``direction`` (up, down or
unknown). :func:`load_experimental` reads and checks one file; bad data raise
:class:`~nlgrd.errors.ModelError` naming the file, the column and the line.

:func:`compare` scores a sweep table (``nlgrd.sweep(...).to_frame()`` or
``SweepResult.to_frame()``) against a data set, per sweep direction: resonance
location (x of the largest value), peak value, jump location (largest jump) and the RMS
difference on the measured points. :func:`curve_landmarks` and
:func:`hysteresis_bands` extract the same landmarks from any curve, computed or measured.

No measured curve is shipped: the digitised curves of Kubo et al. (1972) and Kahraman &
Blankenship (1997) compared in Maliha, Doğruer & Özgüven (2004), Figs. 5 and 8, are not
available to the project.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.results.jumps import Jump, find_jumps

#: Abscissa columns of a data file and the matching sweep-table column (docs/conventions.md,
#: "Column names": the reference shaft's speed, the pinion's on a one-mesh model, and the
#: base frequency, its mesh frequency).
X_COLUMNS = {
    "pinion_speed_rpm": "shaft_speed [rpm]",
    "mesh_frequency_hz": "base_frequency [Hz]",
}
#: Units of the abscissa columns.
X_UNITS = {"pinion_speed_rpm": "rpm", "mesh_frequency_hz": "Hz"}
#: Quantities a data set may hold, the sweep-table column each is compared with, and its unit.
#: Kubo's "dynamic factor" is a ratio of tooth stresses; it is compared with the DSLR, as in
#: Maliha et al. (2004), §4.1, which explains why the two need not agree in value.
QUANTITIES = {
    "dslr": ("dslr [-]", "-"),
    "dynamic_factor": ("dslr [-]", "-"),
    "dte_rms": ("dte_rms [um]", "um"),
}
DIRECTIONS = ("up", "down", "unknown")
#: Header keys every data file must state.
REQUIRED_HEADER = ("source", "figure", "digitisation", "calibration", "uncertainty", "case", "quantity")


@dataclass(frozen=True)
class ExperimentalSet:
    """One measured curve (or several sweep directions of it).

    Attributes
    ----------
    path : str
        The file it was read from.
    case : str
        Case-study name, e.g. ``"kubo"`` or ``"kahraman_blankenship"`` (the model file stem).
    quantity : str
        A key of :data:`QUANTITIES`.
    x_column : str
        A key of :data:`X_COLUMNS`.
    x : ndarray
        Pinion speed [rpm] or mesh frequency [Hz], as the column says.
    value : ndarray
        The measured quantity, in the unit of :data:`QUANTITIES`.
    direction : ndarray of str
        "up", "down" or "unknown" per point.
    header : dict
        All ``# key: value`` header entries (lower-case keys).
    """

    path: str
    case: str
    quantity: str
    x_column: str
    x: NDArray
    value: NDArray
    direction: NDArray
    header: dict = field(default_factory=dict)

    @property
    def frame_x_column(self) -> str:
        """Column of a sweep table holding the same abscissa."""
        return X_COLUMNS[self.x_column]

    @property
    def frame_column(self) -> str:
        """Column of a sweep table holding the quantity."""
        return QUANTITIES[self.quantity][0]

    @property
    def label(self) -> str:
        """Short label for plot legends: the file name and its source."""
        return f"{Path(self.path).name} ({self.header.get('source', '?')})"

    def directions(self) -> list[str]:
        """The sweep directions present, in file order."""
        return list(dict.fromkeys(self.direction.tolist()))

    def select(self, direction: str) -> tuple[NDArray, NDArray]:
        """(x, value) of one direction, sorted by x."""
        keep = self.direction == direction
        order = np.argsort(self.x[keep], kind="stable")
        return self.x[keep][order], self.value[keep][order]

    def to_frame(self) -> pd.DataFrame:
        """Tidy table with the sweep-table column names."""
        return pd.DataFrame(
            {self.frame_x_column: self.x, self.frame_column: self.value, "direction": self.direction}
        )


def _number(text: str, column: str, line: int, file: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise ModelError(column, f"line {line}: {text!r} is not a number", file) from None
    if not math.isfinite(v):
        raise ModelError(column, f"line {line}: must be finite, got {text!r}", file)
    return v


def _raise(problems: list[tuple[str, str]], file: str) -> None:
    """Raise one :class:`ModelError` listing every problem found (none: return)."""
    if not problems:
        return
    (key, message), rest = problems[0], problems[1:]
    if rest:
        others = "; ".join(f"{k}: {m}" if k else m for k, m in rest)
        message = f"{message}; and {len(rest)} more problem(s): {others}"
    raise ModelError(key, message, file)


def load_experimental(path: str | os.PathLike) -> ExperimentalSet:
    """Read and check one data file (format: ``data/experimental/README.md``).

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.

    Returns
    -------
    ExperimentalSet
        The data set: abscissa in the file's unit (pinion speed [rpm] or mesh frequency
        [Hz]), values in the unit of :data:`QUANTITIES`, and the header.

    Raises
    ------
    ModelError
        Naming the file and the header key or column (with the line) that is wrong: a
        missing header key, an unknown quantity or column, a value that is not a finite
        number, a non-positive abscissa, an unknown direction, fewer than two points.
    """
    path = Path(path)
    file = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ModelError("", "no such file", file) from None
    except UnicodeDecodeError as err:
        raise ModelError("", f"not UTF-8 text ({err.reason})", file) from None
    problems: list[tuple[str, str]] = []  # every one is listed, not only the first
    header: dict[str, str] = {}
    body: list[tuple[int, str]] = []
    for n, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            if body:
                problems.append(("header", f"line {n}: comment lines must come before the table"))
                continue
            entry = line[1:].strip()
            if ":" in entry:
                key, value = entry.split(":", 1)
                key = key.strip().lower()
                header[key] = (header[key] + " " if key in header else "") + value.strip()
            continue
        body.append((n, raw))
    for key in REQUIRED_HEADER:
        if not header.get(key):
            problems.append((f"header.{key}", f"missing: add a line '# {key}: ...'"))
    quantity = header.get("quantity", "")
    if quantity and quantity not in QUANTITIES:
        problems.append(("header.quantity", f"unknown quantity {quantity!r}; one of {sorted(QUANTITIES)}"))
    if not body:
        problems.append(("", "no table after the header"))
        _raise(problems, file)
    rows = list(csv.reader([r for _, r in body]))
    columns = [c.strip() for c in rows[0]]
    xs = [c for c in columns if c in X_COLUMNS]
    if len(xs) != 1:
        problems.append(
            ("columns", f"need exactly one of {sorted(X_COLUMNS)} as abscissa, got columns {columns}")
        )
        _raise(problems, file)
    unknown = [c for c in columns if c not in (*X_COLUMNS, "value", "direction")]
    problems += [(c, f"unknown column; allowed: {xs[0]}, value, direction") for c in unknown]
    missing = [c for c in ("value", "direction") if c not in columns]
    problems += [(c, "missing column") for c in missing]
    if len(set(columns)) != len(columns):
        problems.append(("columns", f"repeated column name in {columns}"))
    if missing or len(set(columns)) != len(columns):
        _raise(problems, file)
    ix, iv, idr = columns.index(xs[0]), columns.index("value"), columns.index("direction")
    x, v, d = [], [], []
    for (n, _), row in zip(body[1:], rows[1:], strict=True):
        if len(row) != len(columns):
            problems.append(("columns", f"line {n}: {len(row)} fields, the header has {len(columns)}"))
            continue
        try:
            xv = _number(row[ix].strip(), xs[0], n, file)
            if xv <= 0:
                raise ModelError(xs[0], f"line {n}: must be positive, got {row[ix].strip()!r}", file)
            x.append(xv)
        except ModelError as err:
            problems.append((err.key, err.message))
        try:
            v.append(_number(row[iv].strip(), "value", n, file))
        except ModelError as err:
            problems.append((err.key, err.message))
        dv = row[idr].strip().lower()
        if dv not in DIRECTIONS:
            problems.append(("direction", f"line {n}: {row[idr].strip()!r} is not one of {DIRECTIONS}"))
        d.append(dv)
    if len(body) - 1 < 2:
        problems.append(("value", f"need at least two points, got {len(body) - 1}"))
    _raise(problems, file)
    return ExperimentalSet(
        path=file,
        case=header["case"],
        quantity=quantity,
        x_column=xs[0],
        x=np.asarray(x, dtype=float),
        value=np.asarray(v, dtype=float),
        direction=np.asarray(d, dtype=str),
        header=header,
    )


def find_experimental(directory: str | os.PathLike, case: str) -> list[ExperimentalSet]:
    """All data sets of ``case`` among the ``*.csv`` files of ``directory`` (sorted by name).

    A missing directory gives an empty list; a bad file raises :class:`ModelError`.

    Parameters
    ----------
    directory : str or os.PathLike
        The folder searched (not its sub-folders), e.g. ``data/experimental``.
    case : str
        The case-study name the header's ``case`` must equal, e.g. ``"kubo"``.

    Returns
    -------
    list of ExperimentalSet
        The data sets of ``case``, in file-name order; empty when there is none.

    Raises
    ------
    ModelError
        When any ``*.csv`` file of the folder is bad (:func:`load_experimental`).
    """
    directory = Path(directory)
    if not directory.is_dir():
        return []
    sets = [load_experimental(p) for p in sorted(directory.glob("*.csv"))]
    return [s for s in sets if s.case == case]


# --------------------------------------------------------------------------------------
# Landmarks of a curve
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CurveLandmarks:
    """Landmarks of one curve y(x) (one sweep direction).

    Attributes
    ----------
    peak_x, peak_value : float
        Location and value of the largest y (the resonance location and peak).
    jump_x : float
        Midpoint of the largest jump (:func:`nlgrd.nonlinear.results.jumps.find_jumps`); NaN if none.
    jump_from, jump_to : float
        The two points between which it lies (in sweep order); NaN if none.
    """

    peak_x: float
    peak_value: float
    jump_x: float
    jump_from: float
    jump_to: float


def _finite(x: ArrayLike, y: ArrayLike) -> tuple[NDArray, NDArray]:
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y)
    return x[ok], y[ok]


def _sweep_order(x: ArrayLike, y: ArrayLike, direction: str) -> tuple[NDArray, NDArray]:
    """Finite points of a curve in sweep order ("down": decreasing x, else increasing)."""
    x, y = _finite(x, y)
    order = np.argsort(x, kind="stable")
    if direction == "down":
        order = order[::-1]
    return x[order], y[order]


def curve_landmarks(
    x: ArrayLike, y: ArrayLike, direction: str = "up", rtol: float = 0.15, ratio: float = 3.0
) -> CurveLandmarks:
    """Peak and largest jump of a curve; NaN points are skipped.

    ``direction`` gives the sweep order ("down": decreasing x) for the jump; a jump is a
    step larger than ``rtol`` times the range of y and ``ratio`` times its neighbours.

    Parameters
    ----------
    x : array_like
        Abscissa of the curve, in any unit (pinion speed [rpm], mesh frequency [Hz] or
        [rad/s]); the landmarks' locations come in the same unit.
    y : array_like
        The curve's values, in any unit (the peak value comes in the same unit).
    direction : str
        Sweep order for the jump: "down" for decreasing x, anything else for increasing x.
    rtol : float
        Smallest jump as a fraction of the range of y [-].
    ratio : float
        Smallest ratio of a jump to each of its neighbouring steps [-].

    Returns
    -------
    CurveLandmarks
        Peak and largest jump; all NaN when no finite point is left, the jump fields NaN
        when there is no jump.
    """
    x, y = _sweep_order(x, y, direction)
    nan = float("nan")
    if x.size == 0:
        return CurveLandmarks(nan, nan, nan, nan, nan)
    i = int(np.argmax(y))
    jumps = find_jumps(x, y, direction, rtol, ratio)
    if not jumps:
        return CurveLandmarks(float(x[i]), float(y[i]), nan, nan, nan)
    j = max(jumps, key=lambda jp: abs(jp.value_to - jp.value_from))
    # Jump.omega_* carry the abscissa here, whatever its unit
    return CurveLandmarks(float(x[i]), float(y[i]), j.omega, j.omega_from, j.omega_to)


def largest_jump(
    x: ArrayLike,
    y: ArrayLike,
    direction: str,
    lo: float = -np.inf,
    hi: float = np.inf,
    sign: int = 0,
    rtol: float = 0.1,
    ratio: float = 3.0,
) -> Jump | None:
    """The largest jump of one sweep direction with its midpoint in [lo, hi].

    ``x`` and ``y`` are sorted here into sweep order (``direction`` "down": decreasing x);
    jumps are found by :func:`nlgrd.nonlinear.results.jumps.find_jumps` (``rtol``, ``ratio``). ``sign``
    +1 keeps only rises of y in sweep order (the up sweep landing on the upper branch),
    -1 only drops (the down sweep falling off it), 0 both. Returns None when there is none;
    the returned :class:`~nlgrd.nonlinear.results.sweep_results.Jump` holds values of ``x`` (whatever their
    unit) in
    its ``omega_from``, ``omega_to`` and ``omega``.

    Parameters
    ----------
    x : array_like
        Abscissa of the curve, in any unit; ``lo``, ``hi`` and the returned jump use the same.
    y : array_like
        The curve's values, in any unit; non-finite points are skipped.
    direction : str
        The sweep direction: "down" for decreasing x, anything else for increasing x.
    lo, hi : float
        The range of x the jump's midpoint must lie in, in the unit of ``x``.
    sign : int
        +1 for rises of y only, -1 for drops only, 0 for both.
    rtol : float
        Smallest jump as a fraction of the range of y [-].
    ratio : float
        Smallest ratio of a jump to each of its neighbouring steps [-].

    Returns
    -------
    Jump or None
        The jump with the largest change of y, or None.
    """
    x, y = _sweep_order(x, y, direction)
    found = [
        j
        for j in find_jumps(x, y, direction, rtol, ratio)
        if lo <= j.omega <= hi and (sign == 0 or np.sign(j.value_to - j.value_from) == sign)
    ]
    return max(found, key=lambda j: abs(j.value_to - j.value_from), default=None)


def resonance_jumps(
    up: tuple[ArrayLike, ArrayLike],
    down: tuple[ArrayLike, ArrayLike],
    resonance: float,
    window: tuple[float, float] = (0.7, 1.05),
    rtol: float = 0.02,
) -> tuple[Jump | None, Jump | None]:
    """The up and the down jump of a softening main resonance (backlash, contact loss).

    ``up`` and ``down`` are the (x, y) curves of the two sweeps on the same x points
    (y: e.g. the DTE RMS), ``resonance`` the linear resonance on the x axis. Non-finite
    points are skipped.

    - Up jump: where the up sweep lands on the branch the down sweep follows, i.e. at the
      high end of a hysteresis band (:func:`hysteresis_bands`, ``rtol``): of the bands
      ending within ``window`` x ``resonance``, the one ending highest (backlash bends the
      resonance to lower x, so its band ends just below the linear resonance). The jump
      lies between the band's last point and the next converged up-sweep point.
    - Down jump: where the down sweep falls off that branch, the first step below the up
      jump (in down-sweep order) to less than half the value before it.

    Either is None when not found. The returned jumps hold x values in ``omega_*``.

    Parameters
    ----------
    up : tuple of array_like
        (x, y) of the up sweep; x in any unit, the same for every argument.
    down : tuple of array_like
        (x, y) of the down sweep; only the x points it shares with the up sweep form bands.
    resonance : float
        The linear resonance, in the unit of x.
    window : tuple of float
        (low, high) factors of ``resonance`` [-] between which a band must end.
    rtol : float
        Relative difference of the two sweeps that makes a point part of a band [-].

    Returns
    -------
    up_jump, down_jump : Jump or None
        The up and the down jump, each None when not found.
    """
    xu, yu = _sweep_order(*up, "up")
    xd, yd = _sweep_order(*down, "down")
    common, iu, idn = np.intersect1d(xu, xd, return_indices=True)
    bands = [
        b
        for b in hysteresis_bands(common, yu[iu], yd[idn], rtol)
        if window[0] * resonance <= b[1] <= window[1] * resonance
    ]
    if not bands:
        return None, None
    hi = max(b[1] for b in bands)
    i = int(np.nonzero(xu == hi)[0][0])
    if i + 1 >= len(xu):
        return None, None
    up_jump = Jump("up", float(xu[i]), float(xu[i + 1]), float(yu[i]), float(yu[i + 1]))
    for k in range(len(xd) - 1):
        if xd[k] <= up_jump.omega and yd[k + 1] < 0.5 * yd[k]:
            return up_jump, Jump("down", float(xd[k]), float(xd[k + 1]), float(yd[k]), float(yd[k + 1]))
    return up_jump, None


def local_peak(x: ArrayLike, y: ArrayLike, lo: float, hi: float) -> tuple[float, float]:
    """(x, y) of the largest y with lo <= x <= hi; (NaN, NaN) when no finite point lies there.

    Parameters
    ----------
    x : array_like
        Abscissa of the curve, in any unit.
    y : array_like
        The curve's values, in any unit; non-finite points are skipped.
    lo, hi : float
        The range of x searched (ends included), in the unit of ``x``.

    Returns
    -------
    x_peak, y_peak : float
        Location and value of the largest y in the range, or NaN.
    """
    x, y = _finite(x, y)
    keep = (x >= lo) & (x <= hi)
    if not np.any(keep):
        return float("nan"), float("nan")
    i = int(np.argmax(y[keep]))
    return float(x[keep][i]), float(y[keep][i])


def hysteresis_bands(
    x: ArrayLike, up: ArrayLike, down: ArrayLike, rtol: float = 0.02
) -> list[tuple[float, float]]:
    """Ranges of x where the up and the down sweep differ (two coexisting branches).

    ``x`` is shared by both curves (sorted here). A point differs when
    |up - down| > rtol · max(|up|, |down|); consecutive differing points form a band
    (x_first, x_last). Points where either sweep failed (NaN) neither start nor break a band.

    Parameters
    ----------
    x : array_like
        Abscissa shared by both curves, in any unit.
    up : array_like
        Values of the up sweep at ``x``, in any unit.
    down : array_like
        Values of the down sweep at ``x``, in the unit of ``up``.
    rtol : float
        Relative difference that makes a point differ [-].

    Returns
    -------
    list of tuple of float
        The bands (x_first, x_last) in increasing x, in the unit of ``x``.
    """
    x = np.asarray(x, dtype=float)
    up, down = np.asarray(up, dtype=float), np.asarray(down, dtype=float)
    order = np.argsort(x, kind="stable")
    x, up, down = x[order], up[order], down[order]
    ok = np.isfinite(up) & np.isfinite(down)
    x, up, down = x[ok], up[ok], down[ok]
    differs = np.abs(up - down) > rtol * np.maximum(np.abs(up), np.abs(down))
    bands: list[tuple[float, float]] = []
    start = None
    for i, d in enumerate(differs):
        if d and start is None:
            start = i
        if start is not None and (not d or i == len(differs) - 1):
            end = i if d else i - 1
            bands.append((float(x[start]), float(x[end])))
            start = None
    return bands


def directions_of(frame: pd.DataFrame, x_col: str, y_col: str) -> dict[str, tuple[NDArray, NDArray]]:
    """{direction: (x, y)} of a sweep table, each sorted by x.

    Parameters
    ----------
    frame : pandas.DataFrame
        A sweep table (``to_frame()`` of a sweep result) with a ``direction`` column.
    x_col : str
        Column of the abscissa, e.g. ``"shaft_speed [rpm]"``.
    y_col : str
        Column of the values, e.g. ``"dslr [-]"``.

    Returns
    -------
    dict of str to tuple of ndarray
        (x, y) per direction, in the units of the columns, in table order of the directions.

    Raises
    ------
    ModelError
        When a column is not in the table.
    """
    for c in (x_col, y_col, "direction"):
        if c not in frame.columns:
            raise ModelError(c, f"not a column of the sweep table (columns: {list(frame.columns)[:8]} ...)")
    out = {}
    for d, part in frame.groupby("direction", sort=False):
        part = part.sort_values(x_col, kind="stable")
        out[str(d)] = (part[x_col].to_numpy(float), part[y_col].to_numpy(float))
    return out
