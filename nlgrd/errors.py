"""Errors raised for bad model input."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np


class ModelError(ValueError):
    """Bad model input: names the offending key and, when known, the file.

    Parameters
    ----------
    key : str
        Dotted path of the offending field, e.g. ``"shafts[0].elements[2].outer_diameter"``.
    message : str
        What is wrong, in words a user understands.
    file : str, optional
        The model file the value came from.
    """

    def __init__(self, key: str, message: str, file: str | None = None):
        self.key = key
        self.message = message
        self.file = file
        super().__init__(str(self))

    def __reduce__(self):
        return (ModelError, (self.key, self.message, self.file))

    def __str__(self) -> str:
        where = f"{self.file}: " if self.file else ""
        return f"{where}{self.key}: {self.message}" if self.key else f"{where}{self.message}"

    def within(self, prefix: str = "", file: str | None = None) -> ModelError:
        """Return a copy with ``prefix`` prepended to the key and ``file`` set."""
        key = f"{prefix}.{self.key}" if prefix and self.key else (prefix or self.key)
        return ModelError(key, self.message, file or self.file)


def check_finite(key: str, value: float | Iterable) -> None:
    """Raise :class:`ModelError` if ``value`` (scalar or array) is not all finite.

    Parameters
    ----------
    key : str
        Dotted path of the field, named in the error.
    value : float or array_like
        The value (in its own unit), a scalar or anything ``numpy.asarray`` makes floats of.

    Raises
    ------
    ModelError
        When an element of ``value`` is NaN or infinite.
    """
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ModelError(key, f"must be finite, got {value!r}")


def check_positive(key: str, value: float, allow_zero: bool = False) -> None:
    """Raise :class:`ModelError` unless ``value`` is a finite number > 0 (or >= 0).

    Parameters
    ----------
    key : str
        Dotted path of the field, named in the error.
    value : float
        The value (in its own unit); an int or a numpy number, not a bool.
    allow_zero : bool
        Whether zero is accepted (``value >= 0``) instead of ``value > 0``.

    Raises
    ------
    ModelError
        When ``value`` is not a number, not finite, or not positive (negative when
        ``allow_zero``).
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ModelError(key, f"must be a number, got {type(value).__name__} {value!r}")
    if not math.isfinite(value):
        raise ModelError(key, f"must be finite, got {value!r}")
    if allow_zero and value < 0:
        raise ModelError(key, f"must be zero or positive, got {value!r}")
    if not allow_zero and value <= 0:
        raise ModelError(key, f"must be positive, got {value!r}")


def check_real(key: str, value: float) -> None:
    """Raise :class:`ModelError` unless ``value`` is a finite real number.

    Parameters
    ----------
    key : str
        Dotted path of the field, named in the error.
    value : float
        The value (in its own unit); an int or a numpy number, not a bool.

    Raises
    ------
    ModelError
        When ``value`` is not a number or not finite.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ModelError(key, f"must be a number, got {type(value).__name__} {value!r}")
    if not math.isfinite(value):
        raise ModelError(key, f"must be finite, got {value!r}")
