"""Units of the written tables and figures: the one place for their conversions and for
the column names that carry them.

Inside nlgrd everything is SI (m, N, s, rad/s); a table or a figure writes lengths in µm,
frequencies in Hz and speeds in rpm. The conversions below are the expressions the
tables have always used (``x * 1e6``, ``ω / (2π)``, ``Ω · 30 / π``), so the numbers
written are unchanged to the last bit. A column is named by :func:`column`:
``<quantity> [unit]``, or ``<link>.<quantity> [unit]`` for one link's or bearing's output
(docs/conventions.md, "Column names").
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
