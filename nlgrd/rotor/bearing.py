"""Linear bearings between a shaft node and the ground."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError, check_finite, check_positive, check_real

_COEFFS = ("kyy", "kyz", "kzy", "kzz", "cyy", "cyz", "czy", "czz")


def _numbers(key: str, values) -> tuple[float, ...]:
    if not isinstance(values, (list, tuple, np.ndarray)):
        raise ModelError(key, f"must be a list of numbers, got {values!r}")
    for i, x in enumerate(values):
        check_real(f"{key}[{i}]", x)
    return tuple(float(x) for x in values)


@dataclass(frozen=True)
class Bearing:
    """Linear bearing with full 2x2 stiffness and damping on (uy, uz).

    The force on the journal is ``-[C] (y', z') - [K] (y, z)``. Cross-coupled terms
    (fluid-film bearings) are allowed. Each coefficient is a number or, with
    ``speeds`` given, a sequence tabulated at those speeds and interpolated linearly
    (held constant outside the table).

    Parameters
    ----------
    shaft, node : int
        Where the bearing sits.
    kyy, kyz, kzy, kzz : float or sequence
        Stiffness coefficients [N/m].
    cyy, cyz, czy, czz : float or sequence
        Damping coefficients [N s/m].
    kxx, cxx : float
        Axial stiffness [N/m] and damping [N s/m] (thrust); 0 by default.
    ktt : float
        Torsional stiffness to ground [N m/rad] (e.g. a brake); 0 by default.
    speeds : sequence of float, optional
        Shaft spin speeds of the table [rad/s], strictly increasing.
    name : str
        Label.
    """

    shaft: int
    node: int
    kyy: float | tuple[float, ...] = 0.0
    kyz: float | tuple[float, ...] = 0.0
    kzy: float | tuple[float, ...] = 0.0
    kzz: float | tuple[float, ...] = 0.0
    cyy: float | tuple[float, ...] = 0.0
    cyz: float | tuple[float, ...] = 0.0
    czy: float | tuple[float, ...] = 0.0
    czz: float | tuple[float, ...] = 0.0
    kxx: float = 0.0
    cxx: float = 0.0
    ktt: float = 0.0
    speeds: tuple[float, ...] | None = None
    name: str = ""

    def __post_init__(self):
        for key in ("shaft", "node"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ModelError(key, f"must be a non-negative integer, got {v!r}")
        for key in ("kxx", "cxx", "ktt"):
            check_positive(key, getattr(self, key), allow_zero=True)
        n = None
        if self.speeds is not None:
            object.__setattr__(self, "speeds", _numbers("speeds", self.speeds))
            check_finite("speeds", self.speeds)
            n = len(self.speeds)
            if n < 2 or np.any(np.diff(self.speeds) <= 0):
                raise ModelError("speeds", "must hold at least two strictly increasing speeds [rad/s]")
        for key in _COEFFS:
            v = getattr(self, key)
            if isinstance(v, (list, tuple, np.ndarray)):
                if n is None:
                    raise ModelError(key, "is a table but the bearing has no 'speeds'")
                if len(v) != n:
                    raise ModelError(key, f"has {len(v)} values but 'speeds' has {n}")
                object.__setattr__(self, key, _numbers(key, v))
            elif isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)):
                raise ModelError(key, f"must be a number or a list of numbers, got {v!r}")
            check_finite(key, getattr(self, key))
        for key in ("kyy", "kzz", "cyy", "czz"):
            if np.any(np.asarray(getattr(self, key)) < 0):
                raise ModelError(key, "direct coefficients must not be negative")

    def _at(self, key: str, speed: float) -> float:
        v = getattr(self, key)
        if isinstance(v, tuple):
            return float(np.interp(abs(speed), self.speeds, v))
        return float(v)

    def _slope(self, key: str, speed: float) -> float:
        """d(coefficient)/d(speed) of the linear interpolation at ``speed`` (0 outside the
        table and for a constant; at a table speed the slope of the segment above it)."""
        v = getattr(self, key)
        s = abs(speed)
        if not isinstance(v, tuple) or s < self.speeds[0] or s >= self.speeds[-1]:
            return 0.0
        i = int(np.searchsorted(self.speeds, s, side="right")) - 1
        return float(np.sign(speed) * (v[i + 1] - v[i]) / (self.speeds[i + 1] - self.speeds[i]))

    def _slope_matrix(self, kind: str, speed: float) -> NDArray:
        """The 6x6 slope of the "k" or "c" coefficients: the (uy, uz) block, zero elsewhere."""
        m = np.zeros((6, 6))
        m[1:3, 1:3] = [[self._slope(f"{kind}{a}{b}", speed) for b in "yz"] for a in "yz"]
        return m

    def K_slope(self, speed: float = 0.0) -> NDArray:
        """dK/dΩ: the change of the 6x6 stiffness with shaft speed [N s/m].

        Parameters
        ----------
        speed : float
            Shaft spin speed [rad/s].

        Returns
        -------
        ndarray (6, 6)
            Zero but for the tabulated (uy, uz) coefficients.
        """
        return self._slope_matrix("k", speed)

    def C_slope(self, speed: float = 0.0) -> NDArray:
        """dC/dΩ: the change of the 6x6 damping with shaft speed [N s²/m].

        Parameters
        ----------
        speed : float
            Shaft spin speed [rad/s].

        Returns
        -------
        ndarray (6, 6)
            Zero but for the tabulated (uy, uz) coefficients.
        """
        return self._slope_matrix("c", speed)

    def stiffness(self, speed: float = 0.0) -> NDArray:
        """2x2 stiffness on (uy, uz) [N/m] at shaft speed ``speed`` [rad/s]."""
        return np.array(
            [
                [self._at("kyy", speed), self._at("kyz", speed)],
                [self._at("kzy", speed), self._at("kzz", speed)],
            ]
        )

    def damping(self, speed: float = 0.0) -> NDArray:
        """2x2 damping on (uy, uz) [N s/m] at shaft speed ``speed`` [rad/s]."""
        return np.array(
            [
                [self._at("cyy", speed), self._at("cyz", speed)],
                [self._at("czy", speed), self._at("czz", speed)],
            ]
        )

    @property
    def speed_dependent(self) -> bool:
        """Whether any coefficient is tabulated against speed."""
        return self.speeds is not None

    def K(self, speed: float = 0.0) -> NDArray:
        """6x6 stiffness on the node DOFs."""
        k = np.zeros((6, 6))
        k[1:3, 1:3] = self.stiffness(speed)
        k[0, 0] = self.kxx
        k[3, 3] = self.ktt
        return k

    def C(self, speed: float = 0.0) -> NDArray:
        """6x6 damping on the node DOFs."""
        c = np.zeros((6, 6))
        c[1:3, 1:3] = self.damping(speed)
        c[0, 0] = self.cxx
        return c
