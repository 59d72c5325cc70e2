"""Nonlinear links: what a local nonlinearity of a rotor model supplies to the analysis.

A link joins DOFs of the finite-element model through a force law in d local
coordinates y = Pᵀ q (like an element of ROSS, Timbó et al. 2020, supplies its matrices).
The contract (:class:`NonlinearLink`):

- ``projection(system)``: P, the n x d map from the model's DOFs to the local coordinates;
- ``law(coords)``: the force law g(y, θ) on the solver's coordinates ``coords`` (the
  harmonic-balance protocol :class:`~nlgrd.nonlinear.laws.force_laws.LocalNonlinearity`:
  harmonics with their analytic Jacobian, exact piecewise where the law allows, AFT
  otherwise; tangent segments for Floquet; samples in time);
- ``pointwise(y, theta)``: g and ∂g/∂y at one instant, for the time-domain reference;
- ``linear_stiffness()``, ``linear_damping()``: the d x d stiffness the link stands for in
  a linear (modal) analysis and in the mean problem's regularisation, and the viscous
  damping it adds to the linear system;
- ``forcing(omega, H)``: excitation on the local coordinates (a mesh's LSTE through its
  damping), harmonics 0..H;
- ``metrics(harmonics, omega)``: its per-point outputs, named ``<link name>.<quantity>``;
  ``converged_outputs``, the names of those whose change with the number of harmonics
  estimates the truncation error (:mod:`nlgrd.nonlinear.tracing.harmonic_convergence`; all of
  them when a link has none); ``contact_outputs``, those that are fractions of the period
  in a contact state (the branch signature that tells one branch from another).
- ``subharmonic(nu)`` (optional): the same link on the base ω/ν of a period-ν model
  (:func:`nlgrd.nonlinear.models.link_model.period_model`): whatever it holds in harmonics of
  the base moves from harmonic k to νk. A link without it must not depend on the base
  (a clearance: its law is the same at every instant) and is used as it is.

The gear mesh with backlash (:class:`GearMeshLink`) and the bearing with radial clearance
(:class:`BearingClearance`) are the two kinds; the solver treats them alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from nlgrd.cache import BoundedCache
from nlgrd.errors import ModelError, check_positive
from nlgrd.nonlinear.fourier.harmonics import evaluate, real_to_complex, sample
from nlgrd.nonlinear.fourier.periods import spread
from nlgrd.nonlinear.laws.clearance import RadialClearanceLaw
from nlgrd.nonlinear.laws.force_laws import BacklashMesh, ParametricMesh
from nlgrd.nonlinear.laws.mesh_law import gear_mesh_force
from nlgrd.nonlinear.results.metrics import metrics_of_points
from nlgrd.rotor.system import RotorSystem

_UY, _UZ = 1, 2  # translational DOFs of a node in the y-z plane


@runtime_checkable
class NonlinearLink(Protocol):
    """What the analysis asks of a nonlinear link (see the module docstring).

    Attributes
    ----------
    name : str
        Unique in a model; the prefix of the link's output columns.
    kind : str
        What it is, as its outputs are described (:class:`nlgrd.units.OutputColumn`):
        "gear mesh", "bearing clearance", ...
    n_coords : int
        d, the number of local coordinates.
    contact_outputs : tuple of str
        The names of its ``metrics`` that are fractions of the period in a contact state.
    """

    name: str
    kind: str
    n_coords: int
    contact_outputs: tuple[str, ...]

    def projection(self, system: RotorSystem) -> NDArray:
        """P (n_dofs, d): y = Pᵀ q."""
        ...

    def law(self, coords: tuple[int, ...]):
        """The force law acting on the solver's coordinates ``coords``."""
        ...

    def pointwise(self, y: NDArray, theta: float) -> tuple[NDArray, NDArray]:
        """g (d,) [N] and ∂g/∂y (d, d) [N/m] at local coordinates ``y`` [m] and angle θ."""
        ...

    def linear_stiffness(self) -> NDArray:
        """The d x d stiffness of the link in a linear analysis [N/m]."""
        ...

    def linear_damping(self) -> NDArray:
        """The d x d viscous damping the link adds to the linear system [N s/m]."""
        ...

    def forcing(self, omega: float, H: int) -> NDArray:
        """Complex forcing harmonics (H+1, d) on the local coordinates [N]."""
        ...

    def metrics(self, harmonics: NDArray, omega: float) -> dict[str, float]:
        """Per-point outputs from the local harmonics (d, 2H+1) [m]."""
        ...


def _node_dofs(system: RotorSystem, shaft: int, node: int, key: str) -> NDArray:
    try:
        return system.dofs.node_dofs(shaft, node)
    except (IndexError, KeyError, ValueError, ModelError) as err:
        raise ModelError(key, f"no node {node} on shaft {shaft!r}") from err


@dataclass(frozen=True)
class BearingClearance:
    """A bearing with radial clearance c in the y-z plane of a node (or between two nodes).

    Beyond the clearance the contact pushes back with k (r - c)^p (p = 1 linear, 1.5
    Hertzian; :mod:`nlgrd.nonlinear.laws.clearance`); a viscous damping in the plane acts
    always (the lubricant or a squeeze film). Relative to ground, or to node
    (``other_shaft``, ``other_node``) of a housing or another shaft.

    Parameters
    ----------
    name : str
        The link's name, the prefix of its output columns.
    shaft, node : int
        The journal's node.
    clearance : float
        Radial clearance c [m].
    stiffness : float
        Contact stiffness k [N/m] (``exponent`` 1) or [N/m^1.5] (1.5).
    exponent : float
        p: 1 or 1.5.
    damping : float
        Viscous damping in the plane [N s/m].
    other_shaft, other_node : int, optional
        The housing's node; ground when None.
    n_samples : int
        AFT samples per period [-].
    """

    name: str
    shaft: int
    node: int
    clearance: float
    stiffness: float
    exponent: float = 1.0
    damping: float = 0.0
    other_shaft: int | None = None
    other_node: int | None = None
    n_samples: int = 256

    def __post_init__(self):
        check_positive("damping", self.damping, allow_zero=True)
        if (self.other_shaft is None) != (self.other_node is None):
            raise ModelError("other_node", "give both other_shaft and other_node, or neither")
        RadialClearanceLaw(self.stiffness, self.clearance, self.exponent, n_samples=self.n_samples)

    n_coords = 2
    #: The names of its coordinates: the journal's (u_y, u_z) less the housing's.
    coordinates = ("y", "z")
    #: What it is (:class:`nlgrd.units.OutputColumn`).
    kind = "bearing clearance"
    #: The outputs the harmonic-count estimate compares.
    converged_outputs = ("force_max [N]", "displacement_max [m]")
    contact_outputs = ("contact_fraction [-]",)

    @property
    def output_scales(self) -> dict[str, float]:
        """The physical scale of an output the H estimate compares: the displacement's is
        the clearance."""
        return {"displacement_max [m]": self.clearance}

    def projection(self, system: RotorSystem) -> NDArray:
        """P (n_dofs, 2): the journal's (u_y, u_z) less the housing's.

        Parameters
        ----------
        system : RotorSystem
            The model.

        Returns
        -------
        ndarray (n_dofs, 2)
        """
        P = np.zeros((system.n_dofs, 2))
        d = _node_dofs(system, self.shaft, self.node, "node")
        P[d[_UY], 0] = P[d[_UZ], 1] = 1.0
        if self.other_node is not None:
            o = _node_dofs(system, self.other_shaft, self.other_node, "other_node")
            P[o[_UY], 0] = P[o[_UZ], 1] = -1.0
        return P

    def law(self, coords: tuple[int, ...]) -> RadialClearanceLaw:
        """The contact law on the solver's coordinates ``coords`` (two of them).

        Parameters
        ----------
        coords : tuple of int
            The two solver coordinates of this link.

        Returns
        -------
        RadialClearanceLaw
        """
        return RadialClearanceLaw(
            self.stiffness, self.clearance, self.exponent, tuple(coords), self.n_samples
        )

    @cached_property
    def _law(self) -> RadialClearanceLaw:
        return self.law((0, 1))

    def pointwise(self, y: NDArray, theta: float) -> tuple[NDArray, NDArray]:
        """Contact force and tangent at one instant.

        Parameters
        ----------
        y : ndarray (2,)
            (u_y, u_z) relative to the housing [m].
        theta : float
            Angle [rad] (unused: the law does not depend on time).

        Returns
        -------
        tuple of ndarray
            g (2,) [N] and ∂g/∂y (2, 2) [N/m].
        """
        uy, uz = (float(v) for v in np.asarray(y, dtype=float).reshape(2))
        k, c, p = self.stiffness, self.clearance, self.exponent
        if c == 0 and p == 1.0:
            return np.array([k * uy, k * uz]), k * np.eye(2)
        r = math.hypot(uy, uz)
        if r <= c:  # inside the clearance (the laws' force_at and tangent_at, one sample)
            return np.zeros(2), np.zeros((2, 2))
        pen = r - c
        ny, nz = uy / r, uz / r
        radial, hoop = k * p * pen ** (p - 1.0), k * pen**p / r
        nn = np.array([[ny * ny, ny * nz], [ny * nz, nz * nz]])
        return np.array([hoop * uy, hoop * uz]), radial * nn + hoop * (np.eye(2) - nn)

    def linear_stiffness(self) -> NDArray:
        """k I for a linear contact; for Hertz the tangent at a penetration of one clearance
        (at least 10 µm): the stiffness of the linear analysis in contact [N/m].

        Returns
        -------
        ndarray (2, 2)
        """
        if self.exponent == 1.0:
            return self.stiffness * np.eye(2)
        delta = max(self.clearance, 1e-5)
        return self.exponent * self.stiffness * delta ** (self.exponent - 1.0) * np.eye(2)

    def linear_damping(self) -> NDArray:
        """The viscous damping in the plane, c I [N s/m].

        Returns
        -------
        ndarray (2, 2)
        """
        return self.damping * np.eye(2)

    def forcing(self, omega: float, H: int) -> NDArray:
        """No excitation of its own: zeros (H+1, 2) [N].

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].
        H : int
            Number of harmonics [-].

        Returns
        -------
        ndarray (H+1, 2) of complex
        """
        return np.zeros((H + 1, 2), dtype=complex)

    def subharmonic(self, nu: int) -> BearingClearance:
        """The link on the base ω/ν: the same (its law does not depend on the angle).

        Parameters
        ----------
        nu : int
            Base periods of the new base [-].

        Returns
        -------
        BearingClearance
            ``self``.
        """
        return self

    def orbit(self, harmonics: NDArray, n_samples: int = 512) -> NDArray:
        """(u_y, u_z) over one period, (2, n_samples) [m].

        Parameters
        ----------
        harmonics : ndarray (2, 2H+1)
            Real harmonics of the local coordinates [m].
        n_samples : int
            Samples per period [-].

        Returns
        -------
        ndarray (2, n_samples)
        """
        return sample(np.asarray(harmonics, dtype=float).reshape(2, -1), n_samples)

    def metrics(self, harmonics: NDArray, omega: float) -> dict[str, float]:
        """Contact fraction, largest contact force and radial displacement over the period.

        Parameters
        ----------
        harmonics : ndarray (2, 2H+1)
            Real harmonics of the local coordinates [m].
        omega : float
            Base frequency [rad/s] (unused).

        Returns
        -------
        dict
            ``contact_fraction [-]``, ``force_max [N]``, ``displacement_max [m]``.
        """
        u = self.orbit(harmonics, 4 * self.n_samples)
        r = np.hypot(u[0], u[1])
        f = self._law.force_at(u)
        return {
            "contact_fraction [-]": float(np.mean(r > self.clearance)),
            "force_max [N]": float(np.max(np.hypot(f[0], f[1]))),
            "displacement_max [m]": float(np.max(r)),
        }


@dataclass(frozen=True)
class GearMeshLink:
    """The spur gear mesh with backlash of ``system.gear_pairs[index]`` as a link (d = 1).

    Parameters
    ----------
    name : str
        The link's name, the prefix of its output columns.
    mesh : BacklashMesh
        k_h, b, c_m and the LSTE in harmonics of the base frequency: a mesh at harmonic
        m of the base has its LSTE harmonic k at base harmonic m k.
    w : ndarray (n_dofs,)
        The projection vector: δ = wᵀ q along the line of action [-].
    index : int, optional
        Which gear pair of the system it is.
    order : int
        m, the base harmonic of the mesh frequency [-].
    """

    name: str
    mesh: BacklashMesh
    w: NDArray
    index: int | None = None
    order: int = 1

    n_coords = 1
    #: What it is (:class:`nlgrd.units.OutputColumn`).
    kind = "gear mesh"
    #: The name of its coordinate: δ along the line of action.
    coordinates = ("delta",)
    #: The outputs the harmonic-count estimate compares (those of the single-mesh path).
    converged_outputs = ("dte_rms [m]", "force_max [N]")
    contact_outputs = ("contact_loss_fraction [-]",)

    @classmethod
    def from_system(
        cls, system: RotorSystem, index: int = 0, name: str | None = None, order: int = 1
    ) -> GearMeshLink:
        """The link of gear pair ``index`` of ``system``.

        Parameters
        ----------
        system : RotorSystem
            The model.
        index : int
            Which gear pair.
        name : str, optional
            Default ``mesh<index>``.
        order : int
            The base harmonic of its mesh frequency (:meth:`FrequencyPlan.order`) [-].

        Returns
        -------
        GearMeshLink

        Raises
        ------
        ModelError
            ``plan`` when ``order`` is not a multiple of the gear pair's
            :attr:`~nlgrd.gear.mesh.GearMesh.error_period`.
        """
        from nlgrd.rotor.assembly import assemble

        if not 0 <= index < len(system.gear_pairs):
            raise ModelError("gear_pairs", f"no gear pair {index} (the model has {len(system.gear_pairs)})")
        if int(order) != order or order < 1:
            raise ModelError("order", f"a positive integer, got {order!r}")
        order = int(order)
        gp = system.gear_pairs[index]
        N = gp.error_period
        if order % N:
            raise ModelError(
                "plan",
                f"the excitation of gear_pairs[{index}] (tooth errors that differ or runout) repeats "
                f"every {N} mesh cycles, so the mesh must sit at a multiple of harmonic {N} of the "
                f"base frequency; it sits at {order} (take the base from FrequencyPlan.for_system)",
            )
        link = assemble(system).meshes[index]
        mesh = gear_mesh_force(gp, link.stiffness, link.damping, 30, order=order)
        return cls(name or f"mesh{index}", mesh, np.asarray(link.w, dtype=float), index, order)

    def subharmonic(self, nu: int) -> GearMeshLink:
        """The link on the base ω/ν of a period-ν model: the mesh at harmonic ν m, its LSTE
        (and a varying stiffness) harmonic k moved to νk (:func:`~nlgrd.nonlinear.fourier.periods.spread`).

        Parameters
        ----------
        nu : int
            Base periods of the new base [-], >= 1.

        Returns
        -------
        GearMeshLink
            The same mesh force law in time, in harmonics of ω/ν.
        """
        if int(nu) != nu or nu < 1:
            raise ModelError("period", f"a whole number of base periods >= 1, got {nu!r}")
        nu = int(nu)
        mesh = replace(self.mesh, lste=spread(self.mesh.lste, nu))
        if isinstance(mesh, ParametricMesh):
            mesh = replace(mesh, stiffness_variation=spread(mesh.stiffness_variation, nu))
        return replace(self, mesh=mesh, order=self.order * nu)

    @property
    def excitation_harmonics(self) -> int:
        """The highest base harmonic of its LSTE [-]."""
        return (self.mesh.lste.size - 1) // 2

    def projection(self, system: RotorSystem) -> NDArray:
        """P = w as one column, (n_dofs, 1).

        Parameters
        ----------
        system : RotorSystem
            The model (its DOF count must match w).

        Returns
        -------
        ndarray (n_dofs, 1)
        """
        if self.w.size != system.n_dofs:
            raise ModelError("w", f"has {self.w.size} entries, the model {system.n_dofs} DOFs")
        return self.w[:, None]

    def law(self, coords: tuple[int, ...]) -> BacklashMesh:
        """The backlash law on solver coordinate ``coords[0]``.

        Parameters
        ----------
        coords : tuple of int
            One solver coordinate.

        Returns
        -------
        BacklashMesh
        """
        return replace(self.mesh, coord=int(coords[0]))

    def pointwise(self, y: NDArray, theta: float) -> tuple[NDArray, NDArray]:
        """k_h f(δ - e(θ)) (k_h ρ(θ) f of a parametric mesh) and its slope at one instant.

        Parameters
        ----------
        y : ndarray (1,)
            δ [m].
        theta : float
            Base angle ω t [rad].

        Returns
        -------
        tuple of ndarray
            g (1,) [N] and ∂g/∂δ (1, 1) [N/m].
        """

        def at():
            th = np.array([theta], dtype=float)
            return float(evaluate(self.mesh.lste, th)[0]), float(self.mesh.stiffness_time(th)[0])

        e, k = self._lste_at.get((float(theta),), at)
        x = float(np.asarray(y).reshape(-1)[0]) - e
        b = self.mesh.half_backlash
        g = k * (x - b) if x > b else (k * (x + b) if x < -b else 0.0)  # the dead zone
        return np.array([g]), np.array([[k if abs(x) > b else 0.0]])

    @cached_property
    def _lste_at(self) -> BoundedCache:
        """e(θ) and the stiffness at the angles of a time integration's steps (they repeat every period)."""
        return BoundedCache(16384)

    def linear_stiffness(self) -> NDArray:
        """k_h, (1, 1) [N/m].

        Returns
        -------
        ndarray (1, 1)
        """
        return np.array([[self.mesh.stiffness]])

    def linear_damping(self) -> NDArray:
        """c_m, (1, 1) [N s/m].

        Returns
        -------
        ndarray (1, 1)
        """
        return np.array([[self.mesh.damping]])

    def forcing(self, omega: float, H: int) -> NDArray:
        """The LSTE through the mesh damping, i k ω c_m E_k, (H+1, 1) [N].

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].
        H : int
            Number of harmonics [-].

        Returns
        -------
        ndarray (H+1, 1) of complex
        """
        E = real_to_complex(self.mesh.offset(H)[0])
        return (1j * np.arange(H + 1) * omega * self.mesh.damping * E)[:, None]

    def metrics(self, harmonics: NDArray, omega: float) -> dict[str, float]:
        """DTE mean, RMS and peak-to-peak, the mesh force's extremes, DSLR and contact loss
        of the mesh (:class:`~nlgrd.nonlinear.results.metrics.MeshMetrics`).

        Parameters
        ----------
        harmonics : ndarray (1, 2H+1)
            Real harmonics of δ [m].
        omega : float
            Base frequency [rad/s].

        Returns
        -------
        dict
            ``dte_mean [m]``, ``dte_rms [m]``, ``dte_p2p [m]``, ``force_max [N]``,
            ``force_min [N]``, ``dslr [-]``, ``contact_loss_fraction [-]``, ``back_contact``.
        """
        return self.metrics_of_points(np.asarray(harmonics).reshape(1, -1), [omega])[0]

    def metrics_of_points(self, harmonics: NDArray, omegas) -> list[dict[str, float]]:
        """:meth:`metrics` of many points with the same H at once (one FFT of all of them:
        :func:`~nlgrd.nonlinear.results.metrics.metrics_of_points`).

        Parameters
        ----------
        harmonics : ndarray (P, 2H+1)
            Real harmonics of δ per point [m].
        omegas : array_like (P,)
            Base frequency of each point [rad/s].

        Returns
        -------
        list of dict
            One per point, as :meth:`metrics`.
        """
        Z = np.asarray(harmonics, dtype=float).reshape(len(omegas), -1)
        ms = metrics_of_points(Z, np.asarray(omegas, dtype=float), self.mesh)
        return [
            {
                "dte_mean [m]": m.dte_mean,
                "dte_rms [m]": m.dte_rms,
                "dte_p2p [m]": m.dte_p2p,
                "force_max [N]": m.force_max,
                "force_min [N]": m.force_min,
                "dslr [-]": m.dslr,
                "contact_loss_fraction [-]": m.contact_loss_fraction,
                "back_contact": float(m.back_contact),
            }
            for m in ms
        ]

    @staticmethod
    def metric_row(metrics: dict, i: int) -> dict[str, float]:
        """:meth:`metrics` of point ``i`` from a sweep's own metrics of this mesh
        (``SweepResult.metrics``: per name an array over the points).

        Parameters
        ----------
        metrics : dict of str -> ndarray
            ``SweepResult.metrics``.
        i : int
            The point.

        Returns
        -------
        dict
            As :meth:`metrics`.
        """
        return {
            "dte_mean [m]": float(metrics["dte_mean"][i]),
            "dte_rms [m]": float(metrics["dte_rms"][i]),
            "dte_p2p [m]": float(metrics["dte_p2p"][i]),
            "force_max [N]": float(metrics["force_max"][i]),
            "force_min [N]": float(metrics["force_min"][i]),
            "dslr [-]": float(metrics["dslr"][i]),
            "contact_loss_fraction [-]": float(metrics["contact_loss_fraction"][i]),
            "back_contact": float(metrics["back_contact"][i]),
        }
