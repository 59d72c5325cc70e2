"""CSV tables of one mesh cycle, shared by the LSTE files (:mod:`nlgrd.gear.lste_file`) and the
mesh-stiffness files (:mod:`nlgrd.gear.stiffness_file`).

Two layouts, one header row, ``#`` starting a comment, column names case-insensitive:

- samples: a phase column, ``phase`` (mesh phase in cycles) or ``roll_angle`` (pinion roll
  angle in rad, one mesh cycle being 2π / z1), and one value column; the phases increase
  strictly and fill one period (:func:`read_periodic_samples` states the rules);
- Fourier coefficients: ``harmonic`` (integers m >= 0, m = 0 the mean) with ``a_<unit>`` and
  ``b_<unit>`` (:func:`read_harmonic_table`).

Every bad input raises one :class:`~nlgrd.errors.ModelError` naming the column and the file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError

#: Phase columns of a sample table.
PHASE_COLUMNS = ("phase", "roll_angle")


def read_table(path: str | Path):
    """Read a CSV table, column names stripped and lower-cased.

    Parameters
    ----------
    path : str or Path
        The CSV file.

    Returns
    -------
    pandas.DataFrame
        Its columns.

    Raises
    ------
    FileNotFoundError
        When the file does not exist.
    ModelError
        When pandas cannot parse it.
    """
    import pandas as pd

    path = Path(path)
    try:
        frame = pd.read_csv(path, comment="#", skipinitialspace=True)
    except FileNotFoundError:
        raise
    except Exception as exc:  # pandas raises several parser errors
        raise ModelError("", f"cannot read CSV: {exc}", file=str(path)) from exc
    frame.columns = [str(c).strip().lower() for c in frame.columns]
    return frame


def number_column(frame, name: str, path: str | Path) -> NDArray:
    """A column as finite floats.

    Parameters
    ----------
    frame : pandas.DataFrame
        From :func:`read_table`.
    name : str
        The column.
    path : str or Path
        The file, for messages.

    Returns
    -------
    ndarray
        The values, in the file's unit.

    Raises
    ------
    ModelError
        At the first entry that is not a number, or when any is NaN, infinite or empty.
    """
    values = np.asarray(frame[name].to_numpy(), dtype=object)
    out = np.empty(values.size)
    for i, x in enumerate(values):
        try:
            out[i] = float(x)
        except (TypeError, ValueError):
            raise ModelError(name, f"row {i + 1}: not a number ({x!r})", file=str(path)) from None
    bad = ~np.isfinite(out)
    if np.any(bad):
        rows = (np.flatnonzero(bad) + 1).tolist()[:5]
        raise ModelError(name, f"non-finite values (NaN, inf or empty) in data rows {rows}", file=str(path))
    return out


def pick_column(frame, options: tuple[str, ...], what: str, path: str | Path) -> str:
    """The one column of ``options`` that the table has.

    Parameters
    ----------
    frame : pandas.DataFrame
        From :func:`read_table`.
    options : tuple of str
        Acceptable names.
    what : str
        What the column holds, for messages.
    path : str or Path
        The file, for messages.

    Returns
    -------
    str
        The name found.

    Raises
    ------
    ModelError
        When none or more than one of ``options`` is present.
    """
    found = [c for c in options if c in frame.columns]
    if not found:
        raise ModelError(
            " or ".join(options),
            f"missing {what} column: need one of {list(options)}, found {list(frame.columns)}",
            file=str(path),
        )
    if len(found) > 1:
        raise ModelError(found[1], f"give one {what} column, found {found}", file=str(path))
    return found[0]


def read_periodic_samples(
    path: str | Path,
    values: dict[str, float],
    what: str,
    teeth_pinion: int | None = None,
    periodic_rtol: float = 1e-3,
) -> tuple[NDArray, NDArray, str]:
    """Samples of one mesh cycle from a CSV table, checked to cover one period.

    The phase must increase strictly. If the last sample lies one period after the first
    (the file includes the endpoint) the two values must agree (to ``periodic_rtol`` times
    the peak-to-peak value) and the last sample is dropped; otherwise the samples must
    fill one period, the gap from the last sample to the first plus one period being no
    longer than 1.5 times the largest spacing inside the file.

    Parameters
    ----------
    path : str or Path
        CSV file with a phase column (:data:`PHASE_COLUMNS`) and one value column.
    values : dict of str to float
        Acceptable value columns and the factor from each column's unit to SI.
    what : str
        What the values are, for messages ("STE", "stiffness").
    teeth_pinion : int, optional
        z1, required with a ``roll_angle`` column.
    periodic_rtol : float
        Allowed mismatch of the endpoint values, relative to the peak-to-peak value [-].

    Returns
    -------
    phase : ndarray
        Phases in cycles [-], starting at the first sample, endpoint excluded.
    samples : ndarray
        The values in SI.
    column : str
        The value column read.

    Raises
    ------
    ModelError
        When the file, its columns or its samples break these rules, naming the column.
    """
    path = Path(path)
    frame = read_table(path)
    pcol = pick_column(frame, PHASE_COLUMNS, "phase", path)
    vcol = pick_column(frame, tuple(values), what, path)
    if len(frame) < 3:
        raise ModelError(pcol, f"needs at least 3 samples, got {len(frame)}", file=str(path))
    phase = number_column(frame, pcol, path)
    v = number_column(frame, vcol, path) * values[vcol]
    if pcol == "roll_angle":
        if teeth_pinion is None:
            raise ModelError(
                "teeth_pinion", "a roll_angle column needs the pinion tooth count", file=str(path)
            )
        phase = phase * int(teeth_pinion) / (2 * np.pi)
    step = np.diff(phase)
    if np.any(step <= 0):
        row = int(np.flatnonzero(step <= 0)[0]) + 2
        raise ModelError(
            pcol, f"must increase strictly (unsorted or repeated at data row {row})", file=str(path)
        )
    span = phase[-1] - phase[0]
    tol = 1e-9
    if abs(span - 1.0) <= tol:
        if abs(v[-1] - v[0]) > periodic_rtol * np.ptp(v) + 1e-300:
            raise ModelError(
                vcol,
                f"not periodic: the last sample (one period after the first) is {v[-1]!r}, "
                f"the first {v[0]!r}",
                file=str(path),
            )
        phase, v = phase[:-1], v[:-1]
    elif span > 1.0 + tol:
        raise ModelError(pcol, f"spans {span:.6g} cycles: must cover exactly one mesh period", file=str(path))
    else:
        gap = phase[0] + 1.0 - phase[-1]
        if gap > 1.5 * np.max(step):
            raise ModelError(
                pcol,
                f"spans {span:.6g} cycles: the samples do not fill one mesh period "
                f"(gap {gap:.3g} to the next period, largest step {np.max(step):.3g})",
                file=str(path),
            )
    return phase - phase[0] + np.mod(phase[0], 1.0), v, vcol


def read_harmonic_table(path: str | Path, units: dict[str, float]) -> tuple[NDArray, NDArray, str]:
    """Fourier coefficients from a CSV table with columns ``harmonic``, ``a_<unit>``, ``b_<unit>``.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    units : dict of str to float
        Acceptable units (column suffixes) and the factor from each to SI.

    Returns
    -------
    a : ndarray (H+1,)
        Cosine coefficients of harmonics 0 .. H, a[0] the mean (SI); harmonics not listed
        are zero.
    b : ndarray (H+1,)
        Sine coefficients, b[0] = 0 (SI).
    unit : str
        The unit read.

    Raises
    ------
    ModelError
        On a missing column, mixed units, invalid or repeated harmonics, or a sine
        coefficient for harmonic 0.
    """
    path = Path(path)
    frame = read_table(path)
    if "harmonic" not in frame.columns:
        raise ModelError("harmonic", f"missing harmonic column, found {list(frame.columns)}", file=str(path))
    acol = pick_column(frame, tuple(f"a_{u}" for u in units), "cosine-coefficient", path)
    bcol = pick_column(frame, tuple(f"b_{u}" for u in units), "sine-coefficient", path)
    if acol[2:] != bcol[2:]:
        raise ModelError(bcol, f"units of {acol} and {bcol} differ", file=str(path))
    scale = units[acol[2:]]
    harm = number_column(frame, "harmonic", path)
    if np.any(harm < 0) or np.any(harm != np.round(harm)):
        raise ModelError("harmonic", "must hold integers >= 0", file=str(path))
    harm = harm.astype(int)
    if len(np.unique(harm)) != harm.size:
        raise ModelError("harmonic", "repeated harmonic numbers", file=str(path))
    H = int(harm.max()) if harm.size else 0
    a, b = np.zeros(H + 1), np.zeros(H + 1)
    a[harm] = number_column(frame, acol, path) * scale
    b[harm] = number_column(frame, bcol, path) * scale
    if b[0] != 0:
        raise ModelError(bcol, "harmonic 0 (the mean) cannot have a sine coefficient", file=str(path))
    return a, b, acol[2:]
