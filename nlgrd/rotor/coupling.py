"""Couplings: springs and dampers between two shaft nodes, or a node and ground."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError, check_positive, check_real


@dataclass(frozen=True)
class Coupling:
    """Linear spring-damper between node a and node b (or ground when ``shaft_b`` is None).

    Lateral, tilt and axial terms act on the differences of like DOFs. The torsional
    term acts on the twist ``θx_a - ratio θx_b``: ``ratio = 1`` is an ordinary shaft
    coupling, ``ratio = -N_a/N_b`` closes a loop through an (ideal) external gear pair,
    as the slave side of a four-square rig.

    Parameters
    ----------
    shaft_a, node_a : int
        First node.
    shaft_b, node_b : int or None
        Second node, or None for ground.
    k_torsion, c_torsion : float
        Torsional stiffness [N m/rad] and damping [N m s/rad].
    k_lateral, c_lateral : float
        Lateral stiffness [N/m] and damping [N s/m], same in y and z.
    k_tilt, c_tilt : float
        Bending (tilt) stiffness [N m/rad] and damping [N m s/rad].
    k_axial, c_axial : float
        Axial stiffness [N/m] and damping [N s/m].
    ratio : float
        Torsional ratio, see above [-].
    name : str
        Label.
    """

    shaft_a: int
    node_a: int
    shaft_b: int | None = None
    node_b: int | None = None
    k_torsion: float = 0.0
    c_torsion: float = 0.0
    k_lateral: float = 0.0
    c_lateral: float = 0.0
    k_tilt: float = 0.0
    c_tilt: float = 0.0
    k_axial: float = 0.0
    c_axial: float = 0.0
    ratio: float = 1.0
    name: str = ""

    def __post_init__(self):
        for key in ("shaft_a", "node_a", "shaft_b", "node_b"):
            v = getattr(self, key)
            if v is None and key.endswith("_b"):
                continue
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ModelError(key, f"must be a non-negative integer, got {v!r}")
        if (self.shaft_b is None) != (self.node_b is None):
            raise ModelError("node_b", "give both shaft_b and node_b, or neither (ground)")
        for key in (
            "k_torsion",
            "c_torsion",
            "k_lateral",
            "c_lateral",
            "k_tilt",
            "c_tilt",
            "k_axial",
            "c_axial",
        ):
            check_positive(key, getattr(self, key), allow_zero=True)
        check_real("ratio", self.ratio)

    @property
    def grounded(self) -> bool:
        """True when the coupling ties node a to the ground."""
        return self.shaft_b is None

    def _matrix(self, stiff: bool) -> NDArray:
        """12x12 matrix on (node a DOFs, node b DOFs); the b half is unused when grounded."""
        p = "k" if stiff else "c"
        diag = np.array(
            [getattr(self, f"{p}_{n}") for n in ("axial", "lateral", "lateral", "torsion", "tilt", "tilt")]
        )
        out = np.zeros((12, 12))
        for i in range(6):
            r = self.ratio if i == 3 else 1.0
            v = np.array([1.0, -r])
            idx = [i, 6 + i]
            out[np.ix_(idx, idx)] += diag[i] * np.outer(v, v)
        return out

    def K(self) -> NDArray:
        """12x12 stiffness on (a, b) node DOFs."""
        return self._matrix(True)

    def C(self) -> NDArray:
        """12x12 damping on (a, b) node DOFs."""
        return self._matrix(False)
