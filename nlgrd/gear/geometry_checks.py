"""Checks of a spur gear pair's geometry (:class:`nlgrd.gear.geometry.GearGeometry`): the
cutter, the radii, the mesh (clearances, interference, contact ratio) and undercut.
Each failure is one :class:`~nlgrd.errors.ModelError` naming the field to change.
"""

from __future__ import annotations

import math
import warnings
from typing import TYPE_CHECKING

from nlgrd.errors import ModelError

if TYPE_CHECKING:  # pragma: no cover
    from nlgrd.gear.geometry import GearGeometry

_MEMBERS = ("pinion", "gear")


def check_cutter(g: GearGeometry) -> None:
    """The cutter tip round fits on the cutter tooth (its flat half-width u_c >= 0).

    Parameters
    ----------
    g : GearGeometry
        The gear pair being validated.

    Raises
    ------
    ModelError
        Naming ``root_radius_coefficient`` when the tip round does not fit.
    """
    a = g.pressure_angle
    h_f, rho = g.dedendum_coefficient, g.root_radius_coefficient
    if h_f <= rho * (1.0 - math.sin(a)):
        raise ModelError(
            "root_radius_coefficient",
            f"cutter tip radius {rho!r} m_n does not fit in the dedendum {h_f!r} m_n",
        )
    if g.cutter_tip_half_flat < 0:
        raise ModelError(
            "root_radius_coefficient",
            f"cutter tip radius {rho!r} m_n is too large for the cutter tooth (tip flat < 0)",
        )


def check_radii(g: GearGeometry) -> None:
    """Tip outside base and root circles, teeth not pointed, some involute left.

    Parameters
    ----------
    g : GearGeometry
        The gear pair being validated.

    Raises
    ------
    ModelError
        Naming ``profile_shift_*``, ``tip_diameter_*`` or ``tip_rounding``, the field
        to change.
    """
    for i, member in enumerate(_MEMBERS):
        key = f"tip_diameter_{member}"
        ra, rb, rf = g.tip_radii[i], g.base_radii[i], g.root_radii[i]
        if rf <= 0:
            raise ModelError(f"profile_shift_{member}", f"{member} root radius {rf!r} m is not positive")
        if ra <= rb:
            raise ModelError(key, f"{member} tip radius {ra!r} m lies inside the base circle {rb!r} m")
        if ra <= rf:
            raise ModelError(key, f"{member} tip radius {ra!r} m lies inside the root circle {rf!r} m")
        if g.tip_thicknesses[i] <= 0:
            raise ModelError(
                key,
                f"pointed {member} teeth: tooth thickness at the tip circle is "
                f"{g.tip_thicknesses[i]!r} m (<= 0); reduce the tip diameter or the profile shift",
            )
        if g.active_tip_radii[i] <= rb:
            raise ModelError(
                "tip_rounding",
                f"tip rounding {g.tip_rounding!r} m removes the whole {member} involute",
            )


def check_mesh(g: GearGeometry) -> None:
    """Centre distance, tip clearance, no involute interference, contact ratio >= 1;
    warns of contact below the form circle.

    Parameters
    ----------
    g : GearGeometry
        The gear pair being validated.

    Raises
    ------
    ModelError
        Naming ``centre_distance``, ``tip_diameter_*`` or ``contact_ratio`` (ε_α < 1).

    Warns
    -----
    UserWarning
        When a tip contacts the mating flank below its form circle (trochoid interference).
    """
    a = g.operating_centre_distance
    rb1, rb2 = g.base_radii
    if a <= rb1 + rb2:
        raise ModelError("centre_distance", f"{a!r} m must exceed r_b1 + r_b2 = {rb1 + rb2!r} m")
    if g.centre_distance is not None and a < g.tight_mesh_centre_distance * (1 - 1e-12):
        raise ModelError(
            "centre_distance",
            f"{a!r} m is below the tight-mesh centre distance "
            f"{g.tight_mesh_centre_distance!r} m of these tooth thicknesses: the teeth would jam",
        )
    # each tip must clear the mating root circle
    for i, member in enumerate(_MEMBERS):
        other = _MEMBERS[1 - i]
        clearance = a - g.tip_radii[i] - g.root_radii[1 - i]
        if clearance <= 0:
            raise ModelError(
                f"tip_diameter_{member}",
                f"{member} tip circle reaches the {other} root circle (tip clearance {clearance!r} m)",
            )
    t1t2 = g.line_of_action_length
    e, s_a = g.end_of_contact, g.start_of_contact
    if e > t1t2:
        raise ModelError(
            "tip_diameter_pinion",
            "pinion tip circle reaches past the gear base-circle tangency point T2 on the line "
            f"of action ({e!r} m > T1T2 = {t1t2!r} m): involute interference with the gear",
        )
    if s_a < 0:
        raise ModelError(
            "tip_diameter_gear",
            "gear tip circle reaches past the pinion base-circle tangency point T1 on the line "
            f"of action ({t1t2 - s_a!r} m > T1T2 = {t1t2!r} m): involute interference with the pinion",
        )
    eps = g.contact_ratio
    if eps < 1.0:
        raise ModelError(
            "contact_ratio", f"transverse contact ratio {eps!r} is below 1: the mesh is not continuous"
        )
    # contact below the form circle (fillet / trochoid interference): warn
    form = g.form_roll_distances
    if s_a < form[0] * (1 - 1e-9):
        warnings.warn(
            f"gear tip contacts the pinion below its form circle (s_A = {s_a:.6g} m < {form[0]:.6g} m): "
            "trochoid interference on the pinion",
            UserWarning,
            stacklevel=4,
        )
    if t1t2 - e < form[1] * (1 - 1e-9):
        warnings.warn(
            "pinion tip contacts the gear below its form circle: trochoid interference on the gear",
            UserWarning,
            stacklevel=4,
        )


def warn_undercut(g: GearGeometry) -> None:
    """Warns when a gear is undercut, z < 2 (h_a* - x) / sin² α.

    Parameters
    ----------
    g : GearGeometry
        The gear pair being validated.

    Warns
    -----
    UserWarning
        For each undercut member.
    """
    s2 = math.sin(g.pressure_angle) ** 2
    for i, member in enumerate(_MEMBERS):
        z = g.teeth[i]
        x = g.profile_shifts[i]
        z_min = 2.0 * (g.addendum_coefficient - x) / s2
        if z < z_min:
            warnings.warn(
                f"{member} is undercut: z = {z} < 2 (h_a* - x) / sin² α = {z_min:.3g}",
                UserWarning,
                stacklevel=4,
            )
