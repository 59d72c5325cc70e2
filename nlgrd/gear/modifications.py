"""Deviations of spur-gear flanks from the ideal involute: tip relief (linear or
parabolic, Lin, Oswald & Townsend 1994) and gear errors (pitch spacing and profile
slope per tooth); both enter the load sharing of :mod:`nlgrd.gear.transmission_error`
as initial separations of the tooth pairs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError, check_finite, check_positive
from nlgrd.gear.geometry import GearGeometry

_SHAPES = {"linear": 1.0, "parabolic": 2.0}


@dataclass(frozen=True)
class ProfileModification:
    """Tip relief of the pinion and of the gear (Lin, Oswald & Townsend 1994).

    The relief is measured normal to the profile, i.e. along the line of action, and
    grows from zero at the start of relief to its amount at the active tip:
    C (ξ - ξ_s)^p / (ξ_a - ξ_s)^p with p = 1 (``"linear"``) or 2 (``"parabolic"``), ξ
    the member's roll angle, ξ_s its value at the start and ξ_a at the tip.

    Parameters
    ----------
    tip_relief_pinion, tip_relief_gear : float
        Relief amounts C at the tips [m].
    start_roll_angle_pinion, start_roll_angle_gear : float or None
        Roll angle of the member where the relief starts [rad].
    start_diameter_pinion, start_diameter_gear : float or None
        Or the diameter where it starts [m] (give at most one of angle and diameter).
        With neither, the relief starts at the member's highest point of single tooth
        contact ("short" relief): s_A + p_b for the pinion, s_E - p_b for the gear.
    shape : {"linear", "parabolic"}
        Relief shape for both members.
    """

    tip_relief_pinion: float = 0.0
    tip_relief_gear: float = 0.0
    start_roll_angle_pinion: float | None = None
    start_roll_angle_gear: float | None = None
    start_diameter_pinion: float | None = None
    start_diameter_gear: float | None = None
    shape: Literal["linear", "parabolic"] = "linear"

    def __post_init__(self):
        for member in ("pinion", "gear"):
            check_positive(f"tip_relief_{member}", getattr(self, f"tip_relief_{member}"), allow_zero=True)
            angle = getattr(self, f"start_roll_angle_{member}")
            diameter = getattr(self, f"start_diameter_{member}")
            if angle is not None:
                check_positive(f"start_roll_angle_{member}", angle)
            if diameter is not None:
                check_positive(f"start_diameter_{member}", diameter)
            if angle is not None and diameter is not None:
                raise ModelError(
                    f"start_diameter_{member}",
                    "give the start of relief as a roll angle or a diameter, not both",
                )
        if self.shape not in _SHAPES:
            raise ModelError("shape", f"must be one of {sorted(_SHAPES)}, got {self.shape!r}")

    def start_position(self, geometry: GearGeometry, member: str) -> float:
        """Position s from T1 [m] where the relief of ``member`` starts."""
        i = geometry.member_index(member)
        angle = getattr(self, f"start_roll_angle_{member}")
        diameter = getattr(self, f"start_diameter_{member}")
        if angle is not None:
            return float(geometry.position_from_roll_angle(angle, member))
        if diameter is not None:
            return float(geometry.position_from_diameter(diameter, member))
        return geometry.highest_single_contact if i == 0 else geometry.lowest_single_contact

    def relief(self, geometry: GearGeometry, position: ArrayLike, member: str) -> NDArray:
        """Relief of ``member`` [m] at contact positions ``s`` from T1 [m]."""
        s = np.asarray(position, dtype=float)
        i = geometry.member_index(member)
        amount = self.tip_relief_pinion if i == 0 else self.tip_relief_gear
        if amount == 0:
            return np.zeros_like(s)
        start = self.start_position(geometry, member)
        tip = geometry.end_of_contact if i == 0 else geometry.start_of_contact
        length = (tip - start) if i == 0 else (start - tip)
        if length <= 0:
            key = "roll_angle" if getattr(self, f"start_roll_angle_{member}") is not None else "diameter"
            raise ModelError(
                f"start_{key}_{member}",
                f"the {member} relief starts at or beyond its active tip (position {start!r} m)",
            )
        # roll angle is linear in s, so the fraction along the relief is too
        frac = (s - start) / length if i == 0 else (start - s) / length
        frac = np.clip(frac, 0.0, None)
        return amount * frac ** _SHAPES[self.shape]

    def total_relief(self, geometry: GearGeometry, position: ArrayLike) -> NDArray:
        """Sum of pinion and gear relief [m] at positions ``s`` [m]."""
        return self.relief(geometry, position, "pinion") + self.relief(geometry, position, "gear")


def _per_tooth(key: str, value, teeth: int) -> NDArray:
    arr = np.asarray(0.0 if value is None else value, dtype=float)
    if arr.ndim == 0:
        arr = np.full(teeth, float(arr))
    if arr.ndim != 1 or arr.size != teeth:
        raise ModelError(key, f"needs one value per tooth ({teeth}), got shape {np.shape(value)}")
    check_finite(key, arr)
    arr = arr.copy()
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class GearErrors:
    """Manufacturing errors of the pinion and gear flanks, along the line of action [m].

    Positive values mean excess material on the loaded flank: that tooth meets its
    mate earlier, which lowers the separation of its pairs.

    Parameters
    ----------
    spacing_pinion, spacing_gear : array_like or None
        Position deviation of each tooth's loaded flank along the LOA [m] (the
        cumulative pitch deviation times cos α), tooth k = 0 .. z - 1 in the order the
        teeth enter the mesh; None for none.
    profile_slope_pinion, profile_slope_gear : float or array_like
        Profile slope deviation f_Hα [m]: material added at the tip relative to the
        start of active profile, linear in roll angle over the active profile and zero
        at the pitch point; a scalar for every tooth or one value per tooth.
    """

    spacing_pinion: NDArray | None = None
    spacing_gear: NDArray | None = None
    profile_slope_pinion: float | NDArray = 0.0
    profile_slope_gear: float | NDArray = 0.0

    def __post_init__(self):
        for key in ("spacing_pinion", "spacing_gear", "profile_slope_pinion", "profile_slope_gear"):
            value = getattr(self, key)
            if value is not None:
                arr = np.asarray(value, dtype=float)
                check_finite(key, arr)
                if arr.ndim > 1:
                    raise ModelError(key, f"must be a scalar or a 1-D array, got shape {arr.shape}")

    @classmethod
    def from_single_pitch_deviations(
        cls, pinion: ArrayLike | None = None, gear: ArrayLike | None = None, **kwargs
    ) -> GearErrors:
        """Errors from single pitch deviations f_pt along the LOA [m] (their cumulative sums).

        The cumulative sums of a closed tooth sequence must come back to zero; the mean
        f_pt is removed first so that they do.
        """

        def cum(v):
            if v is None:
                return None
            a = np.asarray(v, dtype=float)
            return np.concatenate([[0.0], np.cumsum(a - a.mean())[:-1]])

        return cls(spacing_pinion=cum(pinion), spacing_gear=cum(gear), **kwargs)

    def arrays(self, geometry: GearGeometry) -> dict[str, NDArray]:
        """Per-tooth arrays of the four errors for this pair [m]."""
        z1, z2 = geometry.teeth
        return {
            "spacing_pinion": _per_tooth("spacing_pinion", self.spacing_pinion, z1),
            "spacing_gear": _per_tooth("spacing_gear", self.spacing_gear, z2),
            "profile_slope_pinion": _per_tooth("profile_slope_pinion", self.profile_slope_pinion, z1),
            "profile_slope_gear": _per_tooth("profile_slope_gear", self.profile_slope_gear, z2),
        }

    def hunting_cycles(self, geometry: GearGeometry) -> int:
        """Mesh cycles after which the error pattern repeats [-].

        1 if every tooth of a member has the same errors; z1 (one pinion revolution)
        when only the pinion teeth differ, z2 when only the gear's, lcm(z1, z2) (the
        hunting period) when both.
        """
        arr = self.arrays(geometry)
        z1, z2 = geometry.teeth
        p = np.ptp(arr["spacing_pinion"]) > 0 or np.ptp(arr["profile_slope_pinion"]) > 0
        g = np.ptp(arr["spacing_gear"]) > 0 or np.ptp(arr["profile_slope_gear"]) > 0
        return math.lcm(z1 if p else 1, z2 if g else 1)


@dataclass(frozen=True)
class GearRunout:
    """Runout of the pinion and of the gear: each member's geometric centre (that of its
    base circle) turns about its shaft axis at a distance e: a once-per-revolution
    transmission error, whose modulation of the mesh gives sidebands at the mesh
    harmonics ± the member's shaft order (Smith 2003, "Gear Noise and Vibration", 2nd ed.,
    Marcel Dekker; the projection on the line of action after Velex & Maatar 1996, J.
    Sound Vib. 191:629).

    The offset's component along the line of action moves the member's flanks towards or
    away from its mate, the same for every tooth pair in contact, so it adds

        e_r(θ) = e_p cos(θ_p + φ_p) + e_g cos(θ_g + φ_g)

    to the LSTE e (the approach δ of the shaft centres at which the mesh carries W_0; see
    :mod:`nlgrd.gear.transmission_error`), θ_m = θ / z_m the member's rotation since
    mesh phase θ = 0 [rad]. The phase φ_m is counted in the member's sense of rotation
    from β_m, the direction along the line of action pointing away from the mate (the
    direction in which a shift of the member's centre opens the mesh), to the offset at
    θ = 0: at θ_m + φ_m = 0 the member is offset furthest from its mate, the teeth meet
    latest and e_r = e_m is largest. The change of backlash with the runout's component
    along the line of centres (2 sin α_w times it) and the phase modulation by its
    component across the line of action are neglected (first order in e / r_b).

    Parameters
    ----------
    pinion, gear : tuple of float
        (e, φ) of the member: eccentricity e >= 0 [m] and phase φ [rad].
    """

    pinion: tuple[float, float] = (0.0, 0.0)
    gear: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self):
        for key in ("pinion", "gear"):
            value = getattr(self, key)
            try:
                arr = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                raise ModelError(key, f"must be [eccentricity, phase], got {value!r}") from None
            if arr.shape != (2,):
                raise ModelError(
                    key, f"must be [eccentricity, phase] (2 numbers), got shape {np.shape(value)}"
                )
            check_finite(key, arr)
            if arr[0] < 0:
                raise ModelError(key, f"the eccentricity must be >= 0 m, got {arr[0]!r}")
            object.__setattr__(self, key, (float(arr[0]), float(arr[1])))

    def cycles(self, geometry: GearGeometry) -> int:
        """Mesh cycles after which the runout repeats [-]: lcm of z_m over the members
        with e_m > 0 (1 for none).

        Parameters
        ----------
        geometry : GearGeometry
            The pair (its tooth counts).

        Returns
        -------
        int
        """
        z1, z2 = geometry.teeth
        return math.lcm(z1 if self.pinion[0] > 0 else 1, z2 if self.gear[0] > 0 else 1)

    def harmonics(self, geometry: GearGeometry, N: int, H: int) -> NDArray:
        """Real harmonics [0, a_1, b_1, ...] of e_r over N mesh cycles, H of θ / N [m].

        Parameters
        ----------
        geometry : GearGeometry
            The pair (its tooth counts).
        N : int
            Mesh cycles of the period, a multiple of :meth:`cycles` [-].
        H : int
            Number of harmonics of θ / N [-].

        Returns
        -------
        ndarray (2H+1,)
        """
        out = np.zeros(2 * H + 1)
        for (e, phi), z in ((self.pinion, geometry.teeth_pinion), (self.gear, geometry.teeth_gear)):
            if e == 0:
                continue
            if N % z:
                raise ModelError("runout", f"a period of {N} mesh cycles is no whole revolution of {z} teeth")
            j = N // z  # θ_m = θ / z = j θ / N
            if j <= H:  # e cos(j ϑ + φ) = e cos φ cos jϑ - e sin φ sin jϑ
                out[2 * j - 1] += e * np.cos(phi)
                out[2 * j] -= e * np.sin(phi)
        return out
