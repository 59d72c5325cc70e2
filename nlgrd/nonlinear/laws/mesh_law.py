"""The force law of a spur gear mesh: the paper's constant k_h with the LSTE, or the
parametric k_h ρ(θ) with the effective unloaded error (issue 12, item 3).

:func:`mesh_law` states how k(θ) and e(θ) combine; :func:`gear_mesh_force` builds the
:class:`~nlgrd.nonlinear.laws.force_laws.BacklashMesh` or
:class:`~nlgrd.nonlinear.laws.force_laws.ParametricMesh` of a gear pair for its link
(:class:`nlgrd.nonlinear.links.contract.GearMeshLink`) and the single-DOF model.
"""

from __future__ import annotations

from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.gear.mesh import GearMesh
from nlgrd.nonlinear.fourier.harmonics import analyse, sample
from nlgrd.nonlinear.fourier.periods import spread
from nlgrd.nonlinear.laws.force_laws import BacklashMesh, ParametricMesh


def mesh_law(gear_pair: GearMesh, H: int = 30) -> tuple[NDArray, NDArray | None]:
    """The excitation e(θ) and stiffness shape ρ(θ) of the mesh force k_h ρ f(δ - e).

    With the constant k_h (ρ None) e is the LSTE, mean removed (:meth:`GearMesh.excitation`).
    With a varying stiffness the force law k_h ρ(θ) f(δ - e_p) takes

        e_p(θ) = e(θ) + W_0 / k_h (1 - 1/ρ(θ)),

    so that its static solution under W_0 is the constant model's, δ_s = W_0/k_h + e:
    the LSTE is the loaded error, and e_p, the LSTE less the static tooth deflection
    W_0/k(θ) (a constant aside), the effective unloaded one (the two formulations of
    Özgüven & Houser 1988, J. Sound Vib. 121:383, §3). e_p is taken to ``H`` harmonics
    from 64 H samples of the truncated ρ.

    With errors that differ from tooth to tooth both are over the gear pair's
    :attr:`~nlgrd.gear.mesh.GearMesh.error_period` N mesh cycles, in harmonics of ω/N.

    Parameters
    ----------
    gear_pair : GearMesh
        The gear pair (its ``stiffness_variation`` decides).
    H : int
        Mesh harmonics of the LSTE (and of ρ from the load sharing): N H of ω/N.

    Returns
    -------
    lste : ndarray (2H+1,)
        Real harmonics [e_0, a_1, b_1, ...] of e or e_p [m].
    rho : ndarray or None
        Real harmonics of ρ; None for the constant k_h.
    """
    e = gear_pair.lste_harmonics(H)
    rho = gear_pair.stiffness_harmonics(H)
    if rho is None:
        return e, None
    n = 64 * max((e.size - 1) // 2, (rho.size - 1) // 2, 1)
    shift = gear_pair.static_load / gear_pair.stiffness() * (1.0 - 1.0 / sample(rho, n))
    return e + analyse(shift, (e.size - 1) // 2), rho


def gear_mesh_force(
    gear_pair: GearMesh,
    stiffness: float,
    damping: float,
    H: int = 30,
    order: int = 1,
    method: str = "exact",
) -> BacklashMesh:
    """The force law of ``gear_pair`` with its harmonics on a frequency plan.

    Parameters
    ----------
    gear_pair : GearMesh
        The gear pair.
    stiffness, damping : float
        k_h [N/m] and c_m [N s/m] (those of the assembled model).
    H : int
        Mesh harmonics of the LSTE and of ρ [-].
    order : int
        The mesh frequency's harmonic of the base frequency (ν of a period-ν model, or the
        mesh's order on a frequency plan): the harmonics k of the mesh land on νk [-]. A
        multiple of the gear pair's :attr:`~nlgrd.gear.mesh.GearMesh.error_period` N.
    method : {"exact", "aft"}
        Fourier coefficients of the constant-stiffness law (a parametric one is exact).

    Raises
    ------
    ModelError
        ``period`` when ``order`` is not a multiple of N.

    Returns
    -------
    BacklashMesh
        A :class:`~nlgrd.nonlinear.laws.force_laws.ParametricMesh` when the stiffness varies.
    """
    N = gear_pair.error_period
    if order % N:
        raise ModelError(
            "period",
            f"the gear errors differ from tooth to tooth and repeat every {N} mesh cycles: the "
            f"analysis period must be a multiple of {N} mesh periods, got {order}",
        )
    order //= N
    e, rho = mesh_law(gear_pair, H)
    args = dict(
        stiffness=float(stiffness),
        half_backlash=gear_pair.half_backlash,
        lste=spread(e, order),
        damping=float(damping),
        static_load=gear_pair.static_load,
    )
    if rho is None:
        return BacklashMesh(**args, method=method)
    return ParametricMesh(**args, stiffness_variation=spread(rho, order))
