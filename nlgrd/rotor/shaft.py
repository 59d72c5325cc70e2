"""Timoshenko shaft elements and shafts.

Element matrices follow Nelson (1980), "A finite rotating shaft element using
Timoshenko beam theory", J. Mech. Des. 102:793-803, with the consistent shape
functions of Friedman & Kosmatka (1993), Comput. Struct. 47:473-481, which give the
closed-form mass, rotary inertia and gyroscopic terms in the shear parameter Phi.
Internal viscous damping and its circulatory term follow Özgüven & Özkan (1984),
J. Vib. Acoust. 106:72-79. Torsion and axial motion are two-node bars with
consistent mass.

Node DOF order is (ux, uy, uz, θx, θy, θz); the shaft axis is x. Bending in the
x-y plane uses (uy, θz) with θz = duy/dx; bending in the x-z plane uses (uz, -θy).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError, check_positive, check_real
from nlgrd.rotor.materials import STEEL, Material

#: Map from the element's 12 node DOFs to the 8 bending "plane" coordinates
#: (uy1, φy1, uy2, φy2, uz1, φz1, uz2, φz2) with φy = θz and φz = -θy.
_T_PLANE = np.zeros((8, 12))
for _row, (_col, _sign) in enumerate([(1, 1), (5, 1), (7, 1), (11, 1), (2, 1), (4, -1), (8, 1), (10, -1)]):
    _T_PLANE[_row, _col] = _sign


def _planes(k4: NDArray, cross: bool = False) -> NDArray:
    """Put a 4x4 single-plane matrix into both bending planes, in node DOFs.

    With ``cross=True`` the result couples the planes as [[0, k4], [-k4, 0]], the
    form of the gyroscopic and circulatory matrices.
    """
    p = np.zeros((8, 8))
    if cross:
        p[:4, 4:] = k4
        p[4:, :4] = -k4
    else:
        p[:4, :4] = k4
        p[4:, 4:] = k4
    return _T_PLANE.T @ p @ _T_PLANE


def _bar(value: float) -> NDArray:
    return value * np.array([[1.0, -1.0], [-1.0, 1.0]])


def _bar_mass(value: float) -> NDArray:
    return value / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])


def _put_bar(m12: NDArray, bar: NDArray, dof: int) -> None:
    idx = [dof, 6 + dof]
    m12[np.ix_(idx, idx)] += bar


@dataclass(frozen=True)
class ShaftElement:
    """Hollow or solid circular Timoshenko shaft element between two nodes.

    Parameters
    ----------
    length : float
        Element length [m].
    outer_diameter : float
        Outer diameter [m].
    inner_diameter : float
        Inner (bore) diameter [m]; 0 for a solid shaft.
    material : Material
        Shaft material.
    axial_force : float
        Constant axial force [N], tension positive; adds the geometric stiffness of
        Przemieniecki (1968), eq. 15.12 (Euler-Bernoulli form).
    shear : bool
        Include shear deformation (Timoshenko); False gives Rayleigh beam.
    rotary_inertia : bool
        Include rotary inertia and gyroscopic terms of the shaft itself.
    mass_matrix : {"consistent", "blended"}
        "consistent" (default): Nelson's (1980) consistent matrices, from the shape
        functions of the stiffness (without axial force a Rayleigh-Ritz
        discretisation: natural frequencies converge from above). "blended": the
        consistent matrices blended with the lumped ones by beta = Phi / (2 (1 + Phi));
        for slender elements (Phi << 1) beta -> 0 and the two coincide. A model file
        sets it per element (``mass_matrix = "blended"``).

        Convergence in the element length h (tests/element_study.py, table in
        docs/verification.md): slender elements converge as h^4 with either mass.
        Elements about as short as the shaft is thick (the shipped models: Phi =
        0.2-13) converge as h^2 with the consistent mass. The blend cancels the
        opposite h^2 errors of lumped and consistent mass (Krieg & Key 1973) only on a
        uniform shaft pinned at both ends; with disks, elastic bearings or overhangs it
        converges as h^2 too, with errors of either sign and, on every shipped model
        at its own element count and twice it, a largest error per group of modes
        1.6-22 x the consistent one. Hence the default.
    """

    length: float
    outer_diameter: float
    inner_diameter: float = 0.0
    material: Material = field(default=STEEL)
    axial_force: float = 0.0
    shear: bool = True
    rotary_inertia: bool = True
    mass_matrix: str = "consistent"

    def __post_init__(self):
        for key in ("shear", "rotary_inertia"):
            if not isinstance(getattr(self, key), bool):
                raise ModelError(key, f"must be true or false, got {getattr(self, key)!r}")
        if self.mass_matrix not in ("blended", "consistent"):
            raise ModelError("mass_matrix", f"must be 'consistent' or 'blended', got {self.mass_matrix!r}")
        check_positive("length", self.length)
        check_positive("outer_diameter", self.outer_diameter)
        check_positive("inner_diameter", self.inner_diameter, allow_zero=True)
        check_real("axial_force", self.axial_force)
        if self.inner_diameter >= self.outer_diameter:
            raise ModelError(
                "inner_diameter",
                f"must be smaller than outer_diameter ({self.inner_diameter!r} >= {self.outer_diameter!r})",
            )
        if not isinstance(self.material, Material):
            raise ModelError("material", f"must be a Material, got {self.material!r}")

    # section properties
    @property
    def area(self) -> float:
        """Cross-section area [m^2]."""
        return np.pi / 4.0 * (self.outer_diameter**2 - self.inner_diameter**2)

    @property
    def second_moment(self) -> float:
        """Diametral second moment of area I [m^4]."""
        return np.pi / 64.0 * (self.outer_diameter**4 - self.inner_diameter**4)

    @property
    def polar_moment(self) -> float:
        """Polar second moment of area J = 2 I [m^4]."""
        return 2.0 * self.second_moment

    @property
    def shear_coefficient(self) -> float:
        """Timoshenko shear coefficient of a hollow circle, Cowper (1966) Table 1."""
        nu = self.material.poisson_ratio
        m2 = (self.inner_diameter / self.outer_diameter) ** 2
        return 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)

    @property
    def phi(self) -> float:
        """Shear parameter Phi = 12 E I / (kappa G A L^2) [-]; 0 without shear."""
        if not self.shear:
            return 0.0
        mat = self.material
        return (
            12.0
            * mat.young_modulus
            * self.second_moment
            / (self.shear_coefficient * mat.shear_modulus * self.area * self.length**2)
        )

    @property
    def mass(self) -> float:
        """Element mass [kg]."""
        return self.material.density * self.area * self.length

    # single-plane 4x4 matrices, DOFs (u1, φ1, u2, φ2)
    def _k4(self) -> NDArray:
        L, P = self.length, self.phi
        EI = self.material.young_modulus * self.second_moment
        return (
            EI
            / ((1 + P) * L**3)
            * np.array(
                [
                    [12, 6 * L, -12, 6 * L],
                    [6 * L, (4 + P) * L**2, -6 * L, (2 - P) * L**2],
                    [-12, -6 * L, 12, -6 * L],
                    [6 * L, (2 - P) * L**2, -6 * L, (4 + P) * L**2],
                ]
            )
        )

    def _k4_axial_load(self) -> NDArray:
        L = self.length
        return (
            self.axial_force
            / (30 * L)
            * np.array(
                [
                    [36, 3 * L, -36, 3 * L],
                    [3 * L, 4 * L**2, -3 * L, -(L**2)],
                    [-36, -3 * L, 36, -3 * L],
                    [3 * L, -(L**2), -3 * L, 4 * L**2],
                ]
            )
        )

    def _m4_translation(self) -> NDArray:
        L, P = self.length, self.phi
        a = 13 / 35 + 7 * P / 10 + P**2 / 3
        b = (11 / 210 + 11 * P / 120 + P**2 / 24) * L
        c = 9 / 70 + 3 * P / 10 + P**2 / 6
        d = (13 / 420 + 3 * P / 40 + P**2 / 24) * L
        e = (1 / 105 + P / 60 + P**2 / 120) * L**2
        f = (1 / 140 + P / 60 + P**2 / 120) * L**2
        m = np.array([[a, b, c, -d], [b, e, d, -f], [c, d, a, -b], [-d, -f, -b, e]])
        return self._blend(self.mass / (1 + P) ** 2 * m, np.diag([1.0, 0.0, 1.0, 0.0]) * self.mass / 2)

    def _blend(self, consistent: NDArray, lumped: NDArray) -> NDArray:
        if self.mass_matrix == "consistent":
            return consistent
        beta = self.phi / (2 * (1 + self.phi))
        return (1 - beta) * consistent + beta * lumped

    def _m4_rotary(self) -> NDArray:
        if not self.rotary_inertia:
            return np.zeros((4, 4))
        L, P = self.length, self.phi
        a = 6 / 5
        b = (1 / 10 - P / 2) * L
        e = (2 / 15 + P / 6 + P**2 / 3) * L**2
        f = (-1 / 30 - P / 6 + P**2 / 6) * L**2
        m = np.array([[a, b, -a, b], [b, e, -b, f], [-a, -b, a, -b], [b, f, -b, e]])
        rho_i = self.material.density * self.second_moment
        return self._blend(rho_i / ((1 + P) ** 2 * L) * m, np.diag([0.0, 1.0, 0.0, 1.0]) * rho_i * L / 2)

    # 12x12 matrices in node DOFs
    @cached_property
    def _cache(self) -> dict[str, NDArray]:
        mat, L = self.material, self.length
        k = _planes(self._k4() + self._k4_axial_load())
        _put_bar(k, _bar(mat.shear_modulus * self.polar_moment / L), 3)
        _put_bar(k, _bar(mat.young_modulus * self.area / L), 0)
        m = _planes(self._m4_translation() + self._m4_rotary())
        _put_bar(m, _bar_mass(mat.density * self.polar_moment * L), 3)
        _put_bar(m, _bar_mass(self.mass), 0)
        return {
            "M": m,
            "K": k,
            "G": _planes(2.0 * self._m4_rotary(), cross=True),
            "Kb": _planes(self._k4()),
            "Kx": _planes(self._k4(), cross=True),
        }

    def M(self) -> NDArray:
        """Mass matrix (translational, rotary, torsional and axial inertia) [kg, kg m^2]."""
        return self._cache["M"].copy()

    def K(self) -> NDArray:
        """Stiffness matrix: bending (with shear and axial load), torsion, axial [N/m, N m/rad]."""
        return self._cache["K"].copy()

    def G(self) -> NDArray:
        """Gyroscopic matrix per unit spin speed [kg m^2]; enters as Ω G q'."""
        return self._cache["G"].copy()

    def Kb(self) -> NDArray:
        """Bending stiffness alone, the base of the internal damping matrices [N/m]."""
        return self._cache["Kb"].copy()

    def Kx(self) -> NDArray:
        """Bending stiffness cross-coupled between planes, [[0, Kb], [-Kb, 0]] in plane form.

        The circulatory stiffness of internal viscous damping is Ω eta_v Kx
        (Özgüven & Özkan 1984).
        """
        return self._cache["Kx"].copy()


@dataclass(frozen=True)
class Shaft:
    """A shaft: a chain of elements along x, with its place and speed in the system.

    Parameters
    ----------
    elements : tuple of ShaftElement
        Elements from the first node to the last; element i joins nodes i and i+1.
    name : str
        Label used in DOF names and model files.
    x_start : float
        Axial position of node 0 [m].
    y, z : float
        Position of the shaft centre line in the y-z plane [m].
    speed_ratio : float
        Spin speed of this shaft divided by the reference (pinion) speed [-], signed:
        a gear meshing externally with the pinion has -N_p / N_g.
    """

    elements: tuple[ShaftElement, ...]
    name: str = "shaft"
    x_start: float = 0.0
    y: float = 0.0
    z: float = 0.0
    speed_ratio: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "elements", tuple(self.elements))
        if not self.elements:
            raise ModelError("elements", "a shaft needs at least one element")
        for i, e in enumerate(self.elements):
            if not isinstance(e, ShaftElement):
                raise ModelError(f"elements[{i}]", f"must be a ShaftElement, got {type(e).__name__}")
        for key in ("x_start", "y", "z", "speed_ratio"):
            check_real(key, getattr(self, key))

    @classmethod
    def uniform(
        cls,
        length: float,
        outer_diameter: float,
        n_elements: int,
        material: Material = STEEL,
        inner_diameter: float = 0.0,
        **kwargs,
    ) -> Shaft:
        """A uniform shaft of ``n_elements`` equal elements; ``kwargs`` go to :class:`Shaft`."""
        if isinstance(n_elements, bool) or not isinstance(n_elements, (int, np.integer)) or n_elements < 1:
            raise ModelError("n_elements", f"must be a whole number >= 1, got {n_elements!r}")
        el = ShaftElement(length / n_elements, outer_diameter, inner_diameter, material)
        return cls(elements=(el,) * n_elements, **kwargs)

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return len(self.elements) + 1

    @property
    def node_positions(self) -> NDArray:
        """Axial positions of the nodes [m]."""
        return self.x_start + np.concatenate([[0.0], np.cumsum([e.length for e in self.elements])])

    @property
    def length(self) -> float:
        """Total length [m]."""
        return float(sum(e.length for e in self.elements))
