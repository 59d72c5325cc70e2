"""Isotropic shaft materials."""

from __future__ import annotations

from dataclasses import dataclass

from nlgrd.errors import ModelError, check_positive, check_real


@dataclass(frozen=True)
class Material:
    """Linear-elastic isotropic material, SI units.

    Parameters
    ----------
    name : str
        Label used to refer to the material in model files.
    density : float
        Mass density [kg/m^3].
    young_modulus : float
        Young's modulus E [Pa].
    poisson_ratio : float
        Poisson's ratio nu [-], in (-1, 0.5).
    viscous_damping : float
        Internal (rotating) viscous damping coefficient eta_v [s]: the internal damping
        matrix is eta_v K_bending (Özgüven & Özkan 1984).
    loss_factor : float
        Internal (rotating) hysteretic loss factor eta_h [-] (Özgüven & Özkan 1984).
    """

    name: str = "steel"
    density: float = 7850.0
    young_modulus: float = 2.1e11
    poisson_ratio: float = 0.3
    viscous_damping: float = 0.0
    loss_factor: float = 0.0

    def __post_init__(self):
        check_positive("density", self.density)
        check_positive("young_modulus", self.young_modulus)
        check_positive("viscous_damping", self.viscous_damping, allow_zero=True)
        check_positive("loss_factor", self.loss_factor, allow_zero=True)
        check_real("poisson_ratio", self.poisson_ratio)
        if not (-1.0 < self.poisson_ratio < 0.5):
            raise ModelError("poisson_ratio", f"must lie in (-1, 0.5), got {self.poisson_ratio!r}")

    @property
    def shear_modulus(self) -> float:
        """Shear modulus G = E / (2 (1 + nu)) [Pa]."""
        return self.young_modulus / (2.0 * (1.0 + self.poisson_ratio))


STEEL = Material()
