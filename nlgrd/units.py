"""Units of the written tables and figures: the one place for their conversions and for
the column names that carry them.

Inside nlgrd everything is SI (m, N, s, rad/s); a table or a figure writes lengths in µm,
frequencies in Hz and speeds in rpm. The conversions below are the expressions the
tables have always used (``x * 1e6``, ``ω / (2π)``, ``Ω · 30 / π``), so the numbers
written are unchanged to the last bit. A column is named by :func:`column`:
``<quantity> [unit]``, or ``<link>.<quantity> [unit]`` for one link's or bearing's output
(docs/conventions.md, "Column names"). A table of SI columns is written by
:func:`written_frame`; rounding beside the row's values is written 0 by
:func:`floor_rounding`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nlgrd.errors import ModelError

#: The unit a table writes for each SI unit of a value, and the factor from SI to it
#: (frequencies and speeds have their own functions: :func:`hz`, :func:`rpm`).
WRITTEN = {"m": ("um", 1e6), "N": ("N", 1.0), "-": ("-", 1.0), "s": ("s", 1.0)}


def um(metres):
    """A length written in µm: ``metres * 1e6``.

    Parameters
    ----------
    metres : float or ndarray
        Length [m].

    Returns
    -------
    float or ndarray
        [um].
    """
    return metres * 1e6


def hz(omega):
    """An angular frequency written in Hz: ω / (2π).

    Parameters
    ----------
    omega : float or array_like
        Angular frequency [rad/s].

    Returns
    -------
    float or ndarray
        [Hz].
    """
    return omega / (2 * np.pi)


def rpm(speed):
    """A shaft speed written in rpm: Ω · 30 / π.

    Parameters
    ----------
    speed : float or array_like
        Shaft speed [rad/s].

    Returns
    -------
    float or ndarray
        [rpm].
    """
    return speed * 30 / math.pi


def speed_of_rpm(values):
    """A speed in rpm as angular speed: n π / 30.

    Parameters
    ----------
    values : float or array_like
        Speed [rpm].

    Returns
    -------
    float or ndarray
        [rad/s].
    """
    return values * math.pi / 30


def omega_of_hz(values):
    """A frequency in Hz as angular frequency: 2π f.

    Parameters
    ----------
    values : float or array_like
        Frequency [Hz].

    Returns
    -------
    float or ndarray
        [rad/s].
    """
    return 2 * np.pi * values


def column(quantity: str, unit: str | None, link: str | None = None) -> str:
    """The name of a table column: ``<quantity> [unit]`` or ``<link>.<quantity> [unit]``
    (no brackets when ``unit`` is None: a flag, a count or a word).

    Parameters
    ----------
    quantity : str
        What the column holds, snake_case (``dte_rms``, ``force_max``).
    unit : str or None
        The written unit (``um``, ``N``, ``Hz``, ``rpm``, ``-``).
    link : str, optional
        The link or bearing whose output it is.

    Returns
    -------
    str

    Raises
    ------
    ModelError
        (``quantity``) Empty, or holding a space, a bracket or a dot.
    """
    if not quantity or any(c in quantity for c in " [].") or (link is not None and not link):
        raise ModelError(
            "quantity", f"a column's quantity is one word without '.', '[' or ' ', got {quantity!r}"
        )
    name = quantity if link is None else f"{link}.{quantity}"
    return name if unit is None else f"{name} [{unit}]"


#: Factors between the units of one quantity that tables write (value in ``to`` = value in
#: ``from`` x factor), keyed (from, to).
FACTORS = {("m", "um"): 1e6, ("um", "m"): 1e-6}


def factor(from_unit: str, to_unit: str) -> float:
    """The factor from one written unit to another of the same quantity (1 for the same).

    Parameters
    ----------
    from_unit, to_unit : str
        Units as written in column names ("m", "um", "N", "-").

    Returns
    -------
    float

    Raises
    ------
    ModelError
        (``unit``) Units of different quantities.
    """
    if from_unit == to_unit:
        return 1.0
    if (from_unit, to_unit) not in FACTORS:
        raise ModelError("unit", f"no conversion from [{from_unit}] to [{to_unit}]")
    return FACTORS[(from_unit, to_unit)]


@dataclass(frozen=True)
class OutputColumn:
    """One output column of a result's table, typed: what it holds, in which unit, whose.

    Attributes
    ----------
    quantity : str
        What it holds (``dte_rms``, ``force_max``, ``dslr``, ...).
    unit : str or None
        The written unit (None: a flag).
    owner : str or None
        The link or bearing whose output it is (None: the one mesh of a one-mesh table).
    kind : str
        What the owner is: "gear mesh", "bearing clearance", "bearing", or another link's kind.
    name : str
        The column as the table writes it, where that is not :func:`column`'s name
        (a one-mesh table's bearings: ``<bearing> <quantity> [unit]``); "" otherwise.
    """

    quantity: str
    unit: str | None
    owner: str | None = None
    kind: str = ""
    name: str = ""

    @property
    def column(self) -> str:
        """The column's name in the table."""
        return self.name or column(self.quantity, self.unit, self.owner)

    def factor_to(self, unit: str) -> float:
        """The factor from this column's unit to ``unit`` (:func:`factor`).

        Parameters
        ----------
        unit : str
            The unit wanted.

        Returns
        -------
        float
        """
        return factor(self.unit or "-", unit)

    def written(self) -> OutputColumn:
        """This column as a table writes it (an SI unit of :data:`WRITTEN` in its written
        unit: m -> µm), the rest unchanged.

        Returns
        -------
        OutputColumn
        """
        if self.name or self.unit not in WRITTEN:
            return self
        return OutputColumn(self.quantity, WRITTEN[self.unit][0], self.owner, self.kind)


def written(values, unit: str):
    """Values of SI unit ``unit`` as a table writes them, with the written unit.

    Parameters
    ----------
    values : float or ndarray
        The values, in ``unit``.
    unit : str
        Their SI unit, a key of :data:`WRITTEN` ("m", "N", "-", "s").

    Returns
    -------
    tuple of (str, float or ndarray)
        The written unit and the values in it.

    Raises
    ------
    ModelError
        (``unit``) Not a key of :data:`WRITTEN`.
    """
    if unit not in WRITTEN:
        raise ModelError("unit", f"one of {', '.join(WRITTEN)}, got {unit!r}")
    name, factor = WRITTEN[unit]
    return name, (values * factor if factor != 1.0 else values)


def parse_column(name: str) -> tuple[str | None, str, str | None]:
    """(link, quantity, unit) of a column named by :func:`column` (None where absent).

    Parameters
    ----------
    name : str
        A column name.

    Returns
    -------
    tuple of (str or None, str, str or None)
    """
    stem, sep, unit = name.partition(" [")
    link, dot, quantity = stem.rpartition(".")
    return (link if dot else None), quantity, (unit[:-1] if sep else None)


def written_name(name: str) -> str:
    """The name a table writes for a column of SI unit (``<link>.dte_rms [m]`` ->
    ``<link>.dte_rms [um]``; a column of another unit unchanged).

    Parameters
    ----------
    name : str
        A column name (:func:`column`).

    Returns
    -------
    str
    """
    owner, quantity, unit = parse_column(name)
    if unit not in WRITTEN or WRITTEN[unit][0] == unit:
        return name
    return column(quantity, WRITTEN[unit][0], owner)


def written_frame(frame):
    """A table with every column of SI unit in its written unit (:data:`WRITTEN`: m -> µm,
    x 1e6), renamed by :func:`written_name`; the other columns as they are.

    Parameters
    ----------
    frame : pandas.DataFrame
        The table.

    Returns
    -------
    pandas.DataFrame
        A new table, the columns in the same order.
    """
    out = frame.copy()
    names = {}
    for name in frame.columns:
        new = written_name(str(name))
        if new != name:
            out[name] = written(frame[name].to_numpy(dtype=float), parse_column(name)[2])[1]
            names[name] = new
    return out.rename(columns=names)


#: A link's or bearing's value is written as 0 when its magnitude is at most this times the
#: largest of the row's outputs in the same unit. The recovery of a bearing the load does
#: not reach (Kubo's stub shafts, coupled in torsion only) leaves rounding up to 7.2e-11
#: of the row's largest (1e-66 to 1e-8 N beside 3e3 N; BLAS-dependent); the smallest real
#: output of the shipped models measured 1.4e-6 of it (Kubo, 3-6 kHz; two_shaft 9e-4).
ROUNDING_FLOOR = 1e-8


def floor_rounding(frame, rtol: float = ROUNDING_FLOOR):
    """A table with each row's owner columns (``<owner>.<quantity> [unit]``, unit not ``-``)
    of magnitude at most ``rtol`` x the row's largest of that unit written as 0 (NaN kept).

    Parameters
    ----------
    frame : pandas.DataFrame
        The table, columns named by :func:`column`.
    rtol : float
        The floor relative to the row's largest value of the unit [-].

    Returns
    -------
    pandas.DataFrame
        A new table.
    """
    groups: dict[str, list] = {}
    for name in frame.columns:
        owner, _, unit = parse_column(str(name))
        if owner is not None and unit not in (None, "-"):
            groups.setdefault(unit, []).append(name)
    out = frame.copy()
    for cols in groups.values():
        v = out[cols].to_numpy(dtype=float)
        with np.errstate(invalid="ignore"):
            top = np.nanmax(np.abs(v), axis=1, initial=0.0, where=np.isfinite(v))[:, None]
            out[cols] = np.where(np.abs(v) <= rtol * top, 0.0, v)
    return out
