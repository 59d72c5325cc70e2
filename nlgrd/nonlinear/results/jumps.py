"""Jumps of swept branches: where a sweep leaves one branch for another between two
consecutive points (a fold, the end of a branch, the loss of stability).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class Jump:
    """A jump of a swept branch between two consecutive points.

    Attributes
    ----------
    direction : str
        "up" or "down".
    omega_from : float
        The last point on the branch left [rad/s].
    omega_to : float
        The first point on the new branch [rad/s]; the fold lies between the two, their
        midpoint is :attr:`omega`.
    value_from, value_to : float
        The quantity tested at the two points (SI).
    """

    direction: str
    omega_from: float
    omega_to: float
    value_from: float
    value_to: float

    @property
    def omega(self) -> float:
        """Midpoint estimate of the jump frequency [rad/s]."""
        return 0.5 * (self.omega_from + self.omega_to)


def find_jumps(
    omegas: NDArray, value: NDArray, direction: str, rtol: float = 0.15, ratio: float = 4.0
) -> list[Jump]:
    """Jumps in one sweep direction: steps much larger than their neighbours.

    A step i -> i+1 (in sweep order) is a jump when |Δv| exceeds ``rtol`` times the
    range of v over the sweep and ``ratio`` times both neighbouring steps. The first and
    the last step (of the finite points) have one neighbour only and are never a jump
    here: a steep flank at the sweep's end cannot be told from a jump (notebook 01's up
    sweep from 2000 rpm, tests/test_jump_criterion.py); a solver that left its branch
    there says so itself (:meth:`~nlgrd.nonlinear.results.sweep_results.SweepResult.jumps`).

    Parameters
    ----------
    omegas : ndarray
        Frequencies in sweep order [rad/s].
    value : ndarray
        The quantity per point (NaN points are skipped).
    direction : str
        Sweep direction written into the jumps.
    rtol : float
        Smallest jump relative to the range of ``value`` [-].
    ratio : float
        How much larger than both neighbouring steps a jump must be [-].

    Returns
    -------
    list of Jump
    """
    v = np.asarray(value, dtype=float)
    ok = np.isfinite(v)
    w, v = np.asarray(omegas, dtype=float)[ok], v[ok]
    if v.size < 2:
        return []
    dv = np.abs(np.diff(v))
    rng = np.ptp(v) + 1e-300
    out = []
    for i in range(1, dv.size - 1):  # a step with a neighbour on each side
        step, left, right = dv[i], dv[i - 1], dv[i + 1]
        if step > rtol * rng and step > ratio * left and step > ratio * right:
            out.append(Jump(direction, float(w[i]), float(w[i + 1]), float(v[i]), float(v[i + 1])))
    return out
