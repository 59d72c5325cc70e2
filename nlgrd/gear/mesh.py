"""The spur gear mesh as a coupling between two shaft nodes along the line of action.

Geometry of the projection (derived in ``docs/gear_mesh.md``): with pinion centre P,
gear centre G, c = (G - P)/|G - P| and t = e_x × c, the pinion spinning with sign
s_p about +x and σ = +1 when the pinion drives (-1 when the gear drives), the unit
vector of the force that the pinion exerts on the gear is

    n = σ s_p cos α_w t + sin α_w c

and the compression of the mesh along the line of action is

    δ = wᵀ q = n · (u_p - u_g) + σ s_p (r_bp θx_p + r_bg θx_g),

so the mesh force W adds -W w to the generalised forces: bearing reactions come from
the lateral entries, torques from the torsional ones (Maliha et al. 2004, §2.2;
model.md §2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError, check_positive
from nlgrd.gear.geometry import GearGeometry
from nlgrd.gear.modifications import GearErrors, GearRunout, ProfileModification
from nlgrd.gear.stiffness_file import read_stiffness_file, rho_samples


@dataclass(frozen=True)
class GearMesh:
    """A spur gear pair meshing between a pinion node and a gear node.

    Parameters
    ----------
    pinion_shaft, pinion_node, gear_shaft, gear_node : int
        Where the pinion and the gear sit. The centre-line orientation in the y-z plane
        comes from the two shafts' centre positions, whose distance must equal the
        operating centre distance of ``geometry``.
    geometry : GearGeometry
        Tooth geometry, backlash (total, along the line of action) and material.
    torque : float
        Static torque transmitted by the pinion [N m], >= 0; the mean mesh force is
        W_0 = torque / r_bp.
    mesh_stiffness : float, optional
        Average mesh stiffness k_h [N/m]; None computes it from the geometry (mean of the
        loaded mesh stiffness over a mesh cycle at W_0).
    damping_ratio : float
        Mesh damping ratio ζ [-] of the gear-pair torsional mode: c_m = 2 ζ sqrt(k_h m_eq),
        m_eq = I_p I_g / (I_p r_bg² + I_g r_bp²) from the disks at the two nodes.
    mesh_damping : float, optional
        Mesh damping coefficient c_m [N s/m]; overrides ``damping_ratio`` when given.
    driver : {"pinion", "gear"}
        Which member drives (decides the loaded flank and the line of action).
    input_node, output_node : int, optional
        Nodes of the pinion shaft and the gear shaft where the driving and the load
        torque enter; default the pinion and gear nodes.
    lste_file : str, optional
        File of the loaded static transmission error (CSV of samples or of Fourier
        coefficients, or TOML; see :mod:`nlgrd.gear.lste_file`), relative to the model file;
        None computes it from the geometry and ``modifications`` at W_0.
    modifications : ProfileModification, optional
        Tip relief of pinion and gear, used when the LSTE is computed.
    lste_points : int
        Samples per mesh cycle of the computed LSTE, >= 16.
    errors : GearErrors, optional
        Spacing and profile-slope errors, used when the LSTE is computed. Errors that
        differ from tooth to tooth repeat only after :attr:`error_period` mesh cycles (a
        revolution, or the hunting period): they excite shaft orders and the sidebands of
        the mesh harmonics, and the analysis is then solved over that period.
    stiffness_variation : {None, "load_sharing"} or sequence of float
        How the mesh stiffness varies over the mesh cycle. None (default): the paper's
        constant k_h with the LSTE as excitation. "load_sharing": k(θ) = k_h ρ(θ) with ρ
        the shape of the tangent mesh stiffness of nlgrd's load-sharing calculation at W_0
        (:func:`~nlgrd.gear.transmission_error.loaded_static_transmission_error`). A
        sequence: the real Fourier harmonics [1, a_1, b_1, ...] of ρ(θ) in the mesh angle,
        ρ_0 = 1, ρ > 0 throughout. See :meth:`mesh_law`.
    stiffness_file : str, optional
        File of k(θ) over one mesh cycle (CSV of samples in N/m or of ρ, or of Fourier
        coefficients; :mod:`nlgrd.gear.stiffness_file`), relative to the model file: its
        shape ρ = k / mean(k) times the model's k_h, as a ``stiffness_variation`` of the same
        harmonics (H of them from samples, as from the load sharing); the mean of a file in
        N/m is checked against k_h, not used. The phase is the LSTE's mesh phase. Excludes
        ``stiffness_variation``.
    runout : GearRunout, optional
        Eccentricity and phase of the pinion and of the gear (``[gear_pairs.runout]`` in a
        model file): adds e_m cos(θ / z_m + φ_m) to the LSTE, so the excitation repeats
        once per revolution of the member (:attr:`error_period`); see
        :class:`~nlgrd.gear.modifications.GearRunout` for the model and its conventions.

    Notes
    -----
    The mean of the LSTE is removed (e_0 = 0): the static deflection of the mesh comes
    from the mean load acting on k_h and is not counted twice.
    """

    pinion_shaft: int
    pinion_node: int
    gear_shaft: int
    gear_node: int
    geometry: GearGeometry
    torque: float = 0.0
    mesh_stiffness: float | None = None
    damping_ratio: float = 0.0
    mesh_damping: float | None = None
    driver: str = "pinion"
    input_node: int | None = None
    output_node: int | None = None
    lste_file: str | None = None
    modifications: ProfileModification | None = None
    lste_points: int = 256
    errors: GearErrors | None = None
    stiffness_variation: str | tuple[float, ...] | None = None
    runout: GearRunout | None = None
    stiffness_file: str | None = None

    def __post_init__(self):
        for key in ("pinion_shaft", "pinion_node", "gear_shaft", "gear_node", "input_node", "output_node"):
            v = getattr(self, key)
            if v is None and key in ("input_node", "output_node"):
                continue
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ModelError(key, f"must be a non-negative integer, got {v!r}")
        if self.pinion_shaft == self.gear_shaft:
            raise ModelError("gear_shaft", "pinion and gear must sit on different shafts")
        if not isinstance(self.geometry, GearGeometry):
            raise ModelError("geometry", f"must be a GearGeometry, got {type(self.geometry).__name__}")
        check_positive("torque", self.torque, allow_zero=True)
        check_positive("damping_ratio", self.damping_ratio, allow_zero=True)
        if self.mesh_stiffness is not None:
            check_positive("mesh_stiffness", self.mesh_stiffness)
        if self.mesh_damping is not None:
            check_positive("mesh_damping", self.mesh_damping, allow_zero=True)
        if (
            isinstance(self.lste_points, bool)
            or not isinstance(self.lste_points, int)
            or self.lste_points < 16
        ):
            raise ModelError("lste_points", f"must be an integer >= 16, got {self.lste_points!r}")
        if self.driver not in ("pinion", "gear"):
            raise ModelError("driver", f"must be 'pinion' or 'gear', got {self.driver!r}")
        if self.runout is not None and not isinstance(self.runout, GearRunout):
            raise ModelError("runout", f"must be a GearRunout, got {type(self.runout).__name__}")
        self._check_stiffness_variation()

    def _check_stiffness_variation(self) -> None:
        v = self.stiffness_variation
        if self.stiffness_file is not None:
            if not isinstance(self.stiffness_file, str) or not self.stiffness_file.strip():
                raise ModelError("stiffness_file", f"must name a file, got {self.stiffness_file!r}")
            if v is not None:
                raise ModelError(
                    "stiffness_file",
                    f"give stiffness_file ({self.stiffness_file}) or stiffness_variation ({v!r}), not both",
                )
        if v is None or v == "load_sharing":
            return
        if isinstance(v, str) or not np.iterable(v):
            raise ModelError(
                "stiffness_variation", f"'load_sharing' or Fourier harmonics [1, a1, b1, ...], got {v!r}"
            )
        try:
            rho = np.asarray(v, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise ModelError("stiffness_variation", f"must be numbers, got {v!r}") from None
        if rho.size % 2 != 1 or not np.all(np.isfinite(rho)) or abs(rho[0] - 1.0) > 1e-9:
            raise ModelError(
                "stiffness_variation",
                f"real harmonics [1, a1, b1, ...]: odd length, finite, mean 1; got {list(rho)}",
            )
        if np.min(rho_samples(rho)) <= 0:
            raise ModelError("stiffness_variation", "k_h ρ(θ) must stay positive over the mesh cycle")
        object.__setattr__(self, "stiffness_variation", tuple(float(r) for r in rho))

    # geometry in the system
    @property
    def base_radii(self) -> tuple[float, float]:
        """Base radii (pinion, gear) [m]."""
        return self.geometry.base_radius_pinion, self.geometry.base_radius_gear

    @property
    def half_backlash(self) -> float:
        """b, half the total backlash along the line of action [m]."""
        return self.geometry.backlash / 2

    @property
    def static_load(self) -> float:
        """Mean mesh force W_0 = T_p / r_bp [N]."""
        return self.torque / self.geometry.base_radius_pinion

    def check(self, system) -> None:
        """Raise ModelError unless the shafts' centres are the operating centre distance apart."""
        sp_, sg = system.shafts[self.pinion_shaft], system.shafts[self.gear_shaft]
        dist = float(np.hypot(sg.y - sp_.y, sg.z - sp_.z))
        a = self.geometry.operating_centre_distance
        if abs(dist - a) > 1e-6 * a:
            raise ModelError(
                "gear_shaft",
                f"shaft centres are {dist:.6g} m apart but the gears' operating centre distance is {a:.6g} m",
            )
        if sp_.speed_ratio == 0 or sg.speed_ratio == 0:
            raise ModelError("pinion_shaft", "meshing shafts need non-zero speed ratios")
        ratio = -self.geometry.teeth_pinion / self.geometry.teeth_gear
        if abs(sg.speed_ratio / sp_.speed_ratio - ratio) > 1e-9 * abs(ratio):
            raise ModelError(
                "gear_shaft",
                f"speed ratio of the gear shaft over the pinion shaft must be -N_p/N_g = {ratio:.6g}, "
                f"got {sg.speed_ratio / sp_.speed_ratio:.6g}",
            )

    def line_of_action(self, system) -> NDArray:
        """Unit vector (n_y, n_z) of the force the pinion exerts on the gear."""
        sp_, sg = system.shafts[self.pinion_shaft], system.shafts[self.gear_shaft]
        c = np.array([sg.y - sp_.y, sg.z - sp_.z])
        c = c / np.linalg.norm(c)
        t = np.array([-c[1], c[0]])
        alpha = self.geometry.operating_pressure_angle
        return self._sense(system) * np.cos(alpha) * t + np.sin(alpha) * c

    def _sense(self, system) -> float:
        s_p = np.sign(system.shafts[self.pinion_shaft].speed_ratio)
        return (1.0 if self.driver == "pinion" else -1.0) * s_p

    def projection(self, system) -> NDArray:
        """Projection vector w (n_dofs) with δ = wᵀ q, the mesh compression [m]."""
        self.check(system)
        dm = system.dofs
        w = np.zeros(dm.n_dofs)
        n = self.line_of_action(system)
        sense = self._sense(system)
        rbp, rbg = self.base_radii
        p = dm.node_dofs(self.pinion_shaft, self.pinion_node)
        g = dm.node_dofs(self.gear_shaft, self.gear_node)
        w[p[1:3]] += n
        w[g[1:3]] -= n
        w[p[3]] += sense * rbp
        w[g[3]] += sense * rbg
        return w

    def static_torques(self, system) -> NDArray:
        """Generalised force vector of the static driving and load torques (n_dofs) [N m].

        Driving torque T_p on the pinion shaft at ``input_node`` and load torque
        T_p r_bg / r_bp on the gear shaft at ``output_node``, signed so that the mesh
        carries W_0 = T_p / r_bp in compression.
        """
        dm = system.dofs
        f = np.zeros(dm.n_dofs)
        sense = self._sense(system)
        rbp, rbg = self.base_radii
        W0 = self.static_load
        pin = self.pinion_node if self.input_node is None else self.input_node
        out = self.gear_node if self.output_node is None else self.output_node
        f[dm.index(self.pinion_shaft, pin, "θx")] += sense * W0 * rbp
        f[dm.index(self.gear_shaft, out, "θx")] += sense * W0 * rbg
        return f

    def equivalent_mass(self, system) -> float:
        """m_eq = I_p I_g / (I_p r_bg² + I_g r_bp²) [kg] from the disks at the gear nodes."""
        ip = sum(
            d.polar_inertia
            for d in system.disks
            if (d.shaft, d.node) == (self.pinion_shaft, self.pinion_node)
        )
        ig = sum(
            d.polar_inertia for d in system.disks if (d.shaft, d.node) == (self.gear_shaft, self.gear_node)
        )
        if ip <= 0 or ig <= 0:
            raise ModelError(
                "damping_ratio",
                "needs a disk with polar inertia at both the pinion and the gear node (for m_eq)",
            )
        rbp, rbg = self.base_radii
        return ip * ig / (ip * rbg**2 + ig * rbp**2)

    def stiffness(self) -> float:
        """Average mesh stiffness k_h [N/m]: given, or from the geometry at W_0."""
        if self.mesh_stiffness is not None:
            return float(self.mesh_stiffness)
        return float(_computed_stiffness(self.geometry, self.static_load))

    def lste_result(self):
        """The loaded static transmission error computed from the geometry at W_0 (LSTEResult)."""
        if self.static_load <= 0:
            raise ModelError("torque", "a positive torque is needed to compute the LSTE from the geometry")
        return _lste_cached(
            self.geometry, self.static_load, self.modifications, self.lste_points, self.errors
        )

    def excitation(self, H: int = 30):
        """The LSTE as a :class:`~nlgrd.gear.lste_file.MeshExcitation`, mean removed [m].

        From ``lste_file`` when given, else computed from the geometry. With errors that
        differ from tooth to tooth, the mesh harmonics alone (:meth:`lste_harmonics` has
        the revolution's).
        """
        from nlgrd.gear.lste_file import read_excitation

        if self.lste_file:
            ex = read_excitation(self.lste_file, teeth_pinion=self.geometry.teeth_pinion)
            return ex.without_mean()
        return self.lste_result().excitation(H)

    @property
    def tooth_period(self) -> int:
        """Mesh cycles after which the tooth errors repeat [-]: 1, or with errors that differ
        from tooth to tooth z_1, z_2 or the hunting period (:meth:`GearErrors.hunting_cycles`);
        1 with an ``lste_file`` (a mesh cycle's LSTE)."""
        if self.errors is None or self.lste_file:
            return 1
        return self.errors.hunting_cycles(self.geometry)

    @property
    def error_period(self) -> int:
        """Mesh cycles after which the excitation repeats [-]: the lcm of
        :attr:`tooth_period` and the runout's (z_m of each member with runout,
        :meth:`GearRunout.cycles`)."""
        n = self.tooth_period
        return n if self.runout is None else math.lcm(n, self.runout.cycles(self.geometry))

    def lste_harmonics(self, H: int = 30) -> NDArray:
        """Real harmonics [0, a_1, b_1, ...] of the LSTE, mean removed, runout included, over
        :attr:`error_period` N mesh cycles: N H harmonics of ω/N (the mesh harmonics at
        multiples of N, shaft orders and sidebands between) [m]."""
        N, n = self.error_period, self.tooth_period
        if n == 1:
            ex = self.excitation(H)
            out = np.zeros(2 * N * ex.a.size + 1)
            out[2 * N - 1 :: 2 * N], out[2 * N :: 2 * N] = ex.a, ex.b
        else:
            out = _real_harmonics(np.tile(self.lste_result().lste, N // n), N * H, "lste_points")
            out[0] = 0.0
        if self.runout is not None:
            out += self.runout.harmonics(self.geometry, N, (out.size - 1) // 2)
        return out

    def stiffness_shape(self, H: int = 30):
        """The shape ρ = k / mean(k) of the ``stiffness_file`` (read anew each call).

        Parameters
        ----------
        H : int
            Harmonics taken from a file of samples [-].

        Returns
        -------
        StiffnessShape or None
            :class:`~nlgrd.gear.stiffness_file.StiffnessShape`; None without a file.

        Raises
        ------
        ModelError
            For an unusable file, naming its column and the file.
        """
        if not self.stiffness_file:
            return None
        return read_stiffness_file(self.stiffness_file, H, teeth_pinion=self.geometry.teeth_pinion)

    def stiffness_harmonics(self, H: int = 30) -> NDArray | None:
        """Real harmonics [1, a_1, b_1, ...] of ρ(θ) = k(θ)/k_h over :attr:`error_period` N
        mesh cycles, in harmonics of ω/N as :meth:`lste_harmonics`: N H from the load
        sharing, H mesh harmonics from a ``stiffness_file`` of samples, all that were given
        otherwise (the given harmonic k of the mesh frequency at k N); None for the
        constant k_h."""
        v = self.stiffness_variation if not self.stiffness_file else self.stiffness_shape(H).rho
        N = self.error_period
        if v is None:
            return None
        if v == "load_sharing":
            k = np.tile(self.lste_result().mesh_stiffness, N // self.tooth_period)
            out = _real_harmonics(k / np.mean(k), N * H, "lste_points")
            out[0] = 1.0
            return out
        out = np.zeros(N * (len(v) - 1) + 1)
        out[0], out[2 * N - 1 :: 2 * N], out[2 * N :: 2 * N] = v[0], v[1::2], v[2::2]
        return out

    def damping_coefficient(self, system) -> float:
        """Mesh damping coefficient c_m [N s/m]."""
        if self.mesh_damping is not None:
            return float(self.mesh_damping)
        if self.damping_ratio == 0:
            return 0.0
        return 2 * self.damping_ratio * float(np.sqrt(self.stiffness() * self.equivalent_mass(system)))


def _real_harmonics(samples: NDArray, H: int, key: str) -> NDArray:
    """Real harmonics [c_0, a_1, b_1, ...] of equally spaced samples over one period."""
    n = samples.size
    if 2 * H >= n:
        raise ModelError(key, f"{H} harmonics need more than {2 * H} samples over the period, got {n}")
    c = np.fft.rfft(samples)[: H + 1] / n
    out = np.empty(2 * H + 1)
    out[0], out[1::2], out[2::2] = c[0].real, 2 * c[1:].real, -2 * c[1:].imag
    return out


def _computed_stiffness(geometry: GearGeometry, load: float) -> float:
    if load <= 0:
        raise ModelError(
            "torque", "a positive torque is needed to compute the mesh stiffness from the geometry"
        )
    return _lste_cached(geometry, load, None, 256).k_mean


def _lste_cached(geometry, load, modifications, points, errors=None):
    """LSTE results are costly (tooth compliance integrals); models are frozen, so they
    are kept in the geometry's cache."""
    from nlgrd.gear.transmission_error import loaded_static_transmission_error

    return geometry.cache.get(
        ("lste", load, modifications, points, errors),
        lambda: loaded_static_transmission_error(
            geometry, load, modifications=modifications, errors=errors, points_per_cycle=points
        ),
    )
