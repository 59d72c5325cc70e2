"""Single-DOF gear pair with backlash (Özgüven & Houser 1988; the paper's DYTE model).

    m_eq δ'' + c_m (δ' - e') + k_h f(δ - e) = W_0

δ the relative displacement along the line of action [m], e(t) the LSTE, f the
backlash function (total backlash 2b), m_eq = I_p I_g / (I_p r_bg² + I_g r_bp²). The
model gives the reduced harmonic-balance problem directly,

    κ_k = -m_eq (kω)² + i kω c_m,   F_k = W_0 [k = 0] + i kω c_m E_k,

and is integrated in time (:func:`nlgrd.timedomain.sdof.integrate`,
:func:`nlgrd.timedomain.sdof.time_sweep`) as the independent reference. The LSTE mean
e_0 is kept as given (it only shifts δ by e_0).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError, check_finite, check_positive
from nlgrd.nonlinear.fourier.harmonics import real_to_complex, resize_harmonics
from nlgrd.nonlinear.fourier.periods import spread
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.laws.force_laws import BacklashMesh, ParametricMesh
from nlgrd.nonlinear.laws.mesh_law import mesh_law
from nlgrd.nonlinear.reduction.state_space import LinearStateSpace
from nlgrd.nonlinear.results.metrics import PointMetrics
from nlgrd.rotor.system import RotorSystem


@dataclass(frozen=True)
class SDOFGearPair:
    """Single-DOF gear pair model (SI units).

    Parameters
    ----------
    mass : float
        Equivalent mass m_eq [kg].
    mesh_stiffness : float
        Average mesh stiffness k_h [N/m].
    half_backlash : float
        b [m] (total backlash 2b).
    static_load : float
        W_0 [N].
    lste : array_like
        Real harmonics [e_0, a_1, b_1, ...] of e(θ), θ = ω t [m].
    damping_ratio : float
        ζ, giving c_m = 2 ζ sqrt(k_h m_eq) unless ``damping`` is set.
    damping : float, optional
        Mesh damping c_m [N s/m].
    stiffness_variation : array_like, optional
        Real harmonics [1, a_1, b_1, ...] of k(θ)/k_h: the parametric mesh of
        :class:`~nlgrd.nonlinear.laws.force_laws.ParametricMesh` (``lste`` is then the unloaded
        transmission error); default constant stiffness, the paper's model.
    """

    mass: float
    mesh_stiffness: float
    half_backlash: float
    static_load: float
    lste: NDArray = field(default_factory=lambda: np.zeros(1))
    damping_ratio: float = 0.0
    damping: float | None = None
    stiffness_variation: NDArray = field(default_factory=lambda: np.ones(1))

    def __post_init__(self):
        check_positive("mass", self.mass)
        check_positive("mesh_stiffness", self.mesh_stiffness)
        check_positive("half_backlash", self.half_backlash, allow_zero=True)
        check_positive("damping_ratio", self.damping_ratio, allow_zero=True)
        check_finite("static_load", self.static_load)
        lste = np.atleast_1d(np.asarray(self.lste, dtype=float))
        check_finite("lste", lste)
        if lste.size % 2 != 1:
            raise ModelError("lste", "real harmonics [e0, a1, b1, ...] of odd length")
        object.__setattr__(self, "lste", lste)
        if self.damping is not None:
            check_positive("damping", self.damping, allow_zero=True)
        rho = np.atleast_1d(np.asarray(self.stiffness_variation, dtype=float))
        check_finite("stiffness_variation", rho)
        if rho.ndim != 1 or rho.size % 2 != 1 or abs(rho[0] - 1) > 1e-12:
            raise ModelError(
                "stiffness_variation",
                f"real harmonics [1, a1, b1, ...] of k(θ)/k_h (mean 1: k_h is the mean), got {rho}",
            )
        object.__setattr__(self, "stiffness_variation", rho)

    @classmethod
    def from_gears(
        cls,
        pinion_inertia: float,
        gear_inertia: float,
        pinion_base_radius: float,
        gear_base_radius: float,
        mesh_stiffness: float,
        half_backlash: float,
        static_load: float,
        lste: ArrayLike,
        damping_ratio: float = 0.0,
    ) -> SDOFGearPair:
        """From I_p, I_g [kg m²] and base radii [m]: m_eq = I_p I_g / (I_p r_bg² + I_g r_bp²)."""
        m = (
            pinion_inertia
            * gear_inertia
            / (pinion_inertia * gear_base_radius**2 + gear_inertia * pinion_base_radius**2)
        )
        return cls(m, mesh_stiffness, half_backlash, static_load, np.asarray(lste), damping_ratio)

    def subharmonic(self, nu: int) -> SDOFGearPair:
        """The same gear pair described on the base ω / ν: the LSTE moved to harmonics νk
        (:func:`nlgrd.nonlinear.fourier.periods.spread`), for orbits of period ν mesh periods.
        Solve and integrate it at ω / ν.

        Parameters
        ----------
        nu : int
            Mesh periods per base period [-].

        Returns
        -------
        SDOFGearPair
        """
        rho = spread(self.stiffness_variation, nu)
        return replace(self, lste=spread(self.lste, nu), stiffness_variation=rho)

    @property
    def mesh_damping(self) -> float:
        """c_m [N s/m]."""
        if self.damping is not None:
            return float(self.damping)
        return 2 * self.damping_ratio * np.sqrt(self.mesh_stiffness * self.mass)

    @property
    def natural_frequency(self) -> float:
        """ω_n = sqrt(k_h / m_eq) [rad/s]."""
        return float(np.sqrt(self.mesh_stiffness / self.mass))

    def mesh(self, method: str = "exact", n_samples: int | None = None) -> BacklashMesh:
        """The mesh nonlinearity (acting on coordinate 0, δ): :class:`ParametricMesh` when
        the stiffness varies, else :class:`BacklashMesh`."""
        args = (self.mesh_stiffness, self.half_backlash, self.lste, self.mesh_damping, self.static_load, 0)
        rho = self.stiffness_variation
        if rho.size > 1 and np.any(rho[1:]):
            return ParametricMesh(*args, method, n_samples, stiffness_variation=rho)
        return BacklashMesh(*args, method, n_samples)

    def kappa(self, omega: float, H: int) -> NDArray[np.complex128]:
        """κ_k = -m (kω)² + i kω c_m, k = 0..H [N/m]."""
        w = np.arange(H + 1) * omega
        return -self.mass * w**2 + 1j * w * self.mesh_damping

    def force(self, omega: float, H: int) -> NDArray[np.complex128]:
        """F_k = W_0 [k=0] + i kω c_m E_k [N]."""
        w = np.arange(H + 1) * omega
        F = 1j * w * self.mesh_damping * real_to_complex(resize_harmonics(self.lste, H))
        F[0] = self.static_load
        return F

    def state_space(self) -> LinearStateSpace:
        """M = [[m]], D = [[c_m]], K = [[0]], W = [[1]] for Floquet stability."""
        return LinearStateSpace([[self.mass]], [[self.mesh_damping]], [[0.0]], [[1.0]])

    def reduced_model(self, method: str = "exact", n_samples: int | None = None) -> ReducedModel:
        """The reduced harmonic-balance model with analytic ω-derivatives."""
        m, c = self.mass, self.mesh_damping

        def dkappa(omega: float, H: int) -> NDArray:
            k = np.arange(H + 1)
            return -2 * m * k**2 * omega + 1j * k * c

        def dforce(omega: float, H: int) -> NDArray:
            k = np.arange(H + 1)
            return 1j * k * c * real_to_complex(resize_harmonics(self.lste, H))

        mesh = self.mesh(method, n_samples)
        metrics = PointMetrics(mesh)
        return ReducedModel(
            self.kappa,
            self.force,
            (mesh,),
            state_space=self.state_space(),
            kappa_derivative=dkappa,
            force_derivative=dforce,
            outputs=metrics.outputs,
            branch_signature=metrics.signature,
            metrics=metrics,
        )

    def linear_response(self, omega: float, H: int) -> NDArray[np.float64]:
        """Real harmonics of δ with the mesh always in drive-side contact (linear response).

        (κ_k + k_h) δ_k = F_k + k_h E_k + k_h b [k = 0].
        """
        k_h = self.mesh_stiffness
        E = real_to_complex(resize_harmonics(self.lste, H))
        rhs = self.force(omega, H) + k_h * E
        rhs[0] += k_h * self.half_backlash
        Y = rhs / (self.kappa(omega, H) + k_h)
        out = np.empty(2 * H + 1)
        out[0] = Y[0].real
        out[1::2], out[2::2] = Y[1:].real, -Y[1:].imag
        return out


def sdof_model(system: RotorSystem):
    """The single-DOF gear pair of ``system``'s mesh (Özgüven & Houser 1988; the paper's DYTE).

    m_eq from the disks at the gear nodes, k_h, c_m, b, W_0 and the LSTE of the gear pair
    (mean removed): the model the paper compares NLGRD with. Returns
    :class:`nlgrd.nonlinear.models.sdof.SDOFGearPair`.

    Parameters
    ----------
    system : RotorSystem
        With exactly one gear pair.

    Returns
    -------
    SDOFGearPair
        m_eq [kg], k_h [N/m], b [m], W_0 [N], c_m [N s/m] and 30 LSTE harmonics [m]; with a
        varying mesh stiffness its ρ(θ) and the effective unloaded error of
        :func:`~nlgrd.nonlinear.laws.mesh_law.mesh_law`.

    Raises
    ------
    ModelError
        Not exactly one gear pair, or a varying mesh stiffness with errors that differ from
        tooth to tooth (the single-DOF model is mesh-periodic).
    """
    if len(system.gear_pairs) != 1:
        raise ModelError("gear_pairs", "the single-DOF model needs exactly one gear pair")
    gp = system.gear_pairs[0]
    ex = gp.excitation(30)
    lste = np.empty(2 * len(ex.a) + 1)
    lste[0] = ex.e0
    lste[1::2], lste[2::2] = ex.a, ex.b
    rho = np.ones(1)
    if gp.stiffness_harmonics() is not None:
        if gp.error_period != 1:
            raise ModelError(
                "stiffness_file" if gp.stiffness_file is not None else "stiffness_variation",
                "the single-DOF model is mesh-periodic: a varying mesh stiffness with errors that "
                f"repeat every {gp.error_period} mesh cycles needs the FE model (nlgrd.sweep)",
            )
        lste, rho = mesh_law(gp, 30)  # the effective unloaded error with k_h ρ(θ)
    return SDOFGearPair(
        mass=gp.equivalent_mass(system),
        mesh_stiffness=gp.stiffness(),
        half_backlash=gp.half_backlash,
        static_load=gp.static_load,
        lste=lste,
        damping=gp.damping_coefficient(system),
        stiffness_variation=rho,
    )
