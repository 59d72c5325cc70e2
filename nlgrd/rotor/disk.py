"""Rigid disks attached to shaft nodes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError, check_positive


@dataclass(frozen=True)
class Disk:
    """Rigid disk on a shaft node (gear blank, coupling hub, motor or load inertia).

    Parameters
    ----------
    shaft : int
        Index of the shaft carrying the disk.
    node : int
        Node of that shaft.
    mass : float
        Mass [kg].
    diametral_inertia : float
        Moment of inertia about a diameter, I_d [kg m^2].
    polar_inertia : float
        Moment of inertia about the spin axis, I_p [kg m^2].
    name : str
        Label.
    """

    shaft: int
    node: int
    mass: float
    diametral_inertia: float
    polar_inertia: float
    name: str = ""

    def __post_init__(self):
        for key in ("shaft", "node"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ModelError(key, f"must be a non-negative integer, got {v!r}")
        check_positive("mass", self.mass, allow_zero=True)
        check_positive("diametral_inertia", self.diametral_inertia, allow_zero=True)
        check_positive("polar_inertia", self.polar_inertia, allow_zero=True)

    @classmethod
    def from_dimensions(
        cls,
        shaft: int,
        node: int,
        outer_diameter: float,
        width: float,
        inner_diameter: float = 0.0,
        density: float = 7850.0,
        name: str = "",
    ) -> Disk:
        """Solid or annular cylindrical disk of uniform density.

        Parameters
        ----------
        shaft, node : int
            Where the disk sits.
        outer_diameter, inner_diameter, width : float
            Dimensions [m].
        density : float
            Density [kg/m^3], steel by default.
        name : str
            Label.

        Returns
        -------
        Disk
            With the mass [kg] and inertias [kg m^2] of the cylinder.
        """
        check_positive("outer_diameter", outer_diameter)
        check_positive("width", width)
        check_positive("inner_diameter", inner_diameter, allow_zero=True)
        check_positive("density", density)
        if inner_diameter >= outer_diameter:
            raise ModelError("inner_diameter", "must be smaller than outer_diameter")
        m = density * np.pi / 4 * (outer_diameter**2 - inner_diameter**2) * width
        ip = m / 8 * (outer_diameter**2 + inner_diameter**2)
        idiam = ip / 2 + m * width**2 / 12
        return cls(shaft, node, float(m), float(idiam), float(ip), name)

    def M(self) -> NDArray:
        """6x6 mass matrix on the node DOFs (ux, uy, uz, θx, θy, θz)."""
        m, d, p = self.mass, self.diametral_inertia, self.polar_inertia
        return np.diag([m, m, m, p, d, d])

    def G(self) -> NDArray:
        """6x6 gyroscopic matrix per unit spin speed: I_p [[0, 1], [-1, 0]] on (θy, θz)."""
        g = np.zeros((6, 6))
        g[4, 5] = self.polar_inertia
        g[5, 4] = -self.polar_inertia
        return g
