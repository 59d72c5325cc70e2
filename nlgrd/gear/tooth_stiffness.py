"""Tooth-pair compliance of spur gears by the potential-energy method.

Each tooth is a non-uniform cantilever on the tooth centre line, clamped at the root
circle, loaded at the contact point by the mesh force F along the line of action. F
makes the angle α1 with the normal to the tooth centre line; its components
F cos α1 (bending, shear) and F sin α1 (axial compression) store the energies of
Yang & Lin (1987, J. Mech. Trans. Autom. Des. 109:189) and Tian (2004, MSc thesis,
U. Alberta, ch. 2), written here over the centre-line coordinate y of the
actual tooth (Chen & Shao 2011, Eng. Fail. Anal. 18:2149, who extend the
tooth below the base circle; Ma et al. 2014, Eng. Fail. Anal. 44:179, who use the
generated fillet as done here)::

    1/k_b = ∫ [cos α1 (y_c - y) - x_c sin α1]² / (E I_y) dy,   I_y = 2 x³ L / 3
    1/k_s = ∫ 1.2 cos² α1 / (G A_y) dy,                          A_y = 2 x L
    1/k_a = ∫ sin² α1 / (E A_y) dy

with (x_c, y_c) the contact point (x the half thickness), G = E / (2 (1 + ν)) and the
integrals running from the root circle through the rack-generated trochoidal fillet
and the involute up to y_c. On the involute, with the parameter
τ = tan α_y - θ_b (θ_b the half tooth angle at the base circle, α_y the pressure angle
at radius y), x = r_b[(τ + θ_b) cos τ - sin τ], y = r_b[(τ + θ_b) sin τ + cos τ]
and α1 = τ_c at the contact point (Tian 2004, ch. 2).

The gear body (fillet foundation) follows Sainsot, Velex & Duverger (2004, J. Mech.
Des. 126:748, with its Table 1 coefficients)::

    1/k_f = cos² α1 / (E L) [L* (u_f/S_f)² + M* (u_f/S_f) + P* (1 + Q* tan² α1)]
    X* = A/θ_f² + B h_f² + C h_f/θ_f + D/θ_f + E h_f + F  (X = L, M, P, Q)

with u_f the distance along the centre line from the root circle to the point where
the line of action crosses it, S_f = 2 r_f θ_f the arc tooth thickness at the root
circle, θ_f its half angle and h_f = r_f / r_int (r_int the bore radius).

The Hertzian contact stiffness is the load-independent one of Yang & Sun (1985, "A
rotary model for spur gear dynamics", J. Mech. Trans. Autom. Des. 107):
k_h = π E L / (4 (1 - ν²)).

A tooth pair's compliance along the line of action is the sum (Tian 2004, ch. 2)
1/k_t = 1/k_h + Σ_{pinion, gear} (1/k_b + 1/k_s + 1/k_a + 1/k_f).

All functions take contact positions ``s`` [m] measured from the pinion base-circle
tangency point T1 along the line of action (see :mod:`nlgrd.gear.geometry`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.gear.geometry import GearGeometry

#: Sainsot, Velex & Duverger (2004) Table 1: rows L*, M*, P*, Q*; columns A_i .. F_i.
SAINSOT_COEFFICIENTS = np.array(
    [
        [-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045],
        [60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086],
        [-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236],
        [-6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904],
    ]
)

#: Timoshenko shear correction factor of a rectangular section used by Yang & Lin (1987).
SHEAR_FACTOR = 1.2

_N_FILLET = 801  # points on the generated fillet (composite Simpson, odd)
_N_GAUSS = 48  # Gauss-Legendre nodes on the involute part, per contact position


@dataclass(frozen=True, eq=False)
class ToothProfile:
    """Tooth flank of one member in tooth coordinates, from the root circle to the tip.

    ``x`` is the half thickness (normal to the tooth centre line) and ``y`` the distance
    along the centre line from the gear centre, both in m. The first point lies on the
    root circle, the last on the tip circle.

    Parameters
    ----------
    x_fillet, y_fillet : ndarray
        Rack-generated trochoidal fillet from the root circle to the form circle [m].
    base_radius : float
        r_b [m].
    base_half_angle : float
        θ_b [rad].
    form_tau, tip_tau : float
        Involute parameter τ = tan α_y - θ_b at the form circle and at the tip [rad].
    root_radius : float
        r_f [m].
    root_half_angle : float
        θ_f, half angle of the tooth at the root circle [rad].
    """

    x_fillet: NDArray
    y_fillet: NDArray
    base_radius: float
    base_half_angle: float
    form_tau: float
    tip_tau: float
    root_radius: float
    root_half_angle: float

    def involute_point(self, tau: ArrayLike) -> tuple[NDArray, NDArray]:
        """Half thickness x and centre-line coordinate y [m] of the involute at τ [rad]."""
        t = np.asarray(tau, dtype=float)
        rb, tb = self.base_radius, self.base_half_angle
        return rb * ((t + tb) * np.cos(t) - np.sin(t)), rb * ((t + tb) * np.sin(t) + np.cos(t))

    def points(self, n_involute: int = 200) -> tuple[NDArray, NDArray]:
        """Whole flank (fillet then involute) as arrays (x, y) [m]."""
        xi, yi = self.involute_point(np.linspace(self.form_tau, self.tip_tau, n_involute))
        return np.concatenate([self.x_fillet, xi[1:]]), np.concatenate([self.y_fillet, yi[1:]])


def _generated_fillet(
    teeth: int, module: float, alpha: float, shift: float, dedendum: float, rho_coefficient: float, n: int
) -> tuple[NDArray, NDArray]:
    """Fillet cut by the tip round of a rack cutter (Litvin & Fuentes 2004, sec. 10.5).

    Fixed frame: gear centre at the origin, the rack rolls on the reference circle at
    the pitch point I = (0, r). When the gear has turned by φ (clockwise) the rack has
    moved by r φ; the tip-round centre is C = (u_c + r φ, r + v_c) and, by the law of
    gearing, the cutting point lies on the line I C, at P = C + ρ (C - I) / |C - I|.
    φ runs from the root (C - I vertical) to the tangency of the round with the
    straight flank, whose normal is (cos α, -sin α) (C - I at α below the horizontal).
    Rotating P back by φ gives the fillet in the gear frame; the result is in tooth
    coordinates (x, y).
    """
    m = module
    r = 0.5 * m * teeth
    rho = rho_coefficient * m
    u_c = math.pi * m / 4 - (dedendum * m - rho) * math.tan(alpha) - rho / math.cos(alpha)
    v_c = shift * m - dedendum * m + rho  # negative: below the rolling line
    # parameter: horizontal offset w = u_c + r φ of the centre from I, from 0 to -v_c / tan α
    w = np.linspace(0.0, -v_c / math.tan(alpha), n)
    phi = (w - u_c) / r
    d = np.hypot(w, v_c)
    px = w + rho * w / d
    py = r + v_c + rho * v_c / d
    c, s = np.cos(phi), np.sin(phi)
    gx = px * c - py * s
    gy = px * s + py * c
    radius = np.hypot(gx, gy)
    polar = np.arctan2(gx, gy)  # angle from the tooth-space centre line
    psi = math.pi / teeth - polar  # half angle from the tooth centre line
    return radius * np.sin(psi), radius * np.cos(psi)


def _profile(geometry: GearGeometry, index: int) -> ToothProfile:
    """The tooth profile of member ``index``, kept in the geometry's cache."""
    return geometry.cache.get(("tooth profile", index), lambda: _make_profile(geometry, index))


def _make_profile(geometry: GearGeometry, index: int) -> ToothProfile:
    z = geometry.teeth[index]
    x_shift = geometry.profile_shifts[index]
    xf, yf = _generated_fillet(
        z,
        geometry.module,
        geometry.pressure_angle,
        x_shift,
        geometry.dedendum_coefficient,
        geometry.root_radius_coefficient,
        _N_FILLET,
    )
    rb, tb = geometry.base_radii[index], geometry.base_half_angles[index]
    r_form = geometry.form_radii[index]
    form_tau = math.sqrt(max(r_form**2 / rb**2 - 1, 0.0)) - tb
    tip_tau = math.sqrt(geometry.active_tip_radii[index] ** 2 / rb**2 - 1) - tb
    # keep the fillet up to the form circle (it meets the involute there); an undercut
    # gear has its form circle on the base circle and the trochoid reaches above it
    keep = np.hypot(xf, yf) <= r_form * (1 + 1e-12)
    keep[0] = True
    root_radius = float(np.hypot(xf[0], yf[0]))
    return ToothProfile(
        x_fillet=xf[keep],
        y_fillet=yf[keep],
        base_radius=rb,
        base_half_angle=tb,
        form_tau=form_tau,
        tip_tau=tip_tau,
        root_radius=root_radius,
        root_half_angle=float(math.atan2(xf[0], yf[0])),
    )


def tooth_profile(geometry: GearGeometry, member: str = "pinion") -> ToothProfile:
    """Rack-generated tooth flank (fillet and involute) of ``member``, tooth coordinates [m].

    Parameters
    ----------
    geometry : GearGeometry
        The gear pair.
    member : {"pinion", "gear"}
        Which member.

    Returns
    -------
    ToothProfile
        Kept in ``geometry.cache``.
    """
    return _profile(geometry, geometry.member_index(member))


@dataclass(frozen=True, eq=False)
class ToothCompliance:
    """Compliances of one tooth along the line of action [m/N], per contact position.

    Parameters
    ----------
    bending, shear, axial : ndarray
        1/k_b, 1/k_s, 1/k_a of the cantilever tooth [m/N] (Yang & Lin 1987; Tian 2004).
    fillet : ndarray
        1/k_f of the gear body [m/N] (Sainsot et al. 2004).
    """

    bending: NDArray
    shear: NDArray
    axial: NDArray
    fillet: NDArray

    @property
    def total(self) -> NDArray:
        """Sum of the four compliances [m/N]."""
        return self.bending + self.shear + self.axial + self.fillet


def _simpson_weights(n: int) -> NDArray:
    if n < 3 or n % 2 == 0:
        raise ValueError("composite Simpson needs an odd number >= 3 of points")
    w = np.ones(n)
    w[1:-1:2] = 4.0
    w[2:-1:2] = 2.0
    return w / 3.0


def _fillet_moments(profile: ToothProfile) -> tuple[NDArray, float, float]:
    """∫ y'^k / I dy (k = 0, 1, 2, per unit face width, E = 1) and ∫ 1/A dy over the fillet.

    y' = y - y_root; the fillet is integrated in its generating parameter (uniform)
    by composite Simpson on y(parameter), dy from the sampled derivative.
    """
    x, y = profile.x_fillet, profile.y_fillet
    n = len(x)
    if n < 3:
        return np.zeros(3), 0.0, float(y[0])
    if n % 2 == 0:
        x, y = x[:-1], y[:-1]
        n -= 1
    dy = np.gradient(y, edge_order=2)  # dy per unit parameter step
    w = _simpson_weights(n) * dy
    inv_i = 1.0 / (2.0 * x**3 / 3.0)
    inv_a = 1.0 / (2.0 * x)
    yr = y - y[0]
    moments = np.array([np.sum(w * inv_i), np.sum(w * yr * inv_i), np.sum(w * yr**2 * inv_i)])
    return moments, float(np.sum(w * inv_a)), float(y[0])


def tooth_compliance(geometry: GearGeometry, position: ArrayLike, member: str = "pinion") -> ToothCompliance:
    """Bending, shear, axial and fillet-foundation compliance of one tooth [m/N].

    Parameters
    ----------
    geometry : GearGeometry
        The gear pair.
    position : array_like
        Contact positions s along the line of action from T1 [m].
    member : {"pinion", "gear"}
        Which tooth.

    Returns
    -------
    ToothCompliance
        Arrays shaped like ``position``.

    Notes
    -----
    Contact points below the form circle (possible only with trochoid interference) are
    evaluated at the form circle.
    """
    i = geometry.member_index(member)
    s = np.asarray(position, dtype=float).reshape(-1)
    prof = _profile(geometry, i)
    E, nu, L = geometry.young_modulus, geometry.poisson_ratio, geometry.face_width
    G = E / (2.0 * (1.0 + nu))
    rb, tb = prof.base_radius, prof.base_half_angle

    r_c = np.asarray(geometry.contact_radius(s, member), dtype=float)
    tau_c = np.sqrt(np.maximum(r_c**2 / rb**2 - 1.0, 0.0)) - tb
    tau_c = np.clip(tau_c, prof.form_tau, None)
    alpha1 = tau_c
    ca, sa = np.cos(alpha1), np.sin(alpha1)
    x_c, y_c = prof.involute_point(tau_c)

    # fillet part: expand the squared moment arm about y_root
    mom, inv_a_f, y_root = _fillet_moments(prof)
    arm0 = ca * (y_c - y_root) - sa * x_c  # arm at y = y_root
    bend_f = (arm0**2 * mom[0] - 2.0 * arm0 * ca * mom[1] + ca**2 * mom[2]) / (E * L)
    shear_f = SHEAR_FACTOR * ca**2 * inv_a_f / (G * L)
    axial_f = sa**2 * inv_a_f / (E * L)

    # involute part: Gauss-Legendre in τ from the form circle to the contact point
    g, gw = np.polynomial.legendre.leggauss(_N_GAUSS)
    half = 0.5 * (tau_c - prof.form_tau)
    tau = prof.form_tau + half[:, None] * (g[None, :] + 1.0)
    wts = half[:, None] * gw[None, :]
    x, y = prof.involute_point(tau)
    dy = rb * (tau + tb) * np.cos(tau)  # dy/dτ
    inv_i = 1.0 / (2.0 * x**3 * L / 3.0)
    inv_a = 1.0 / (2.0 * x * L)
    arm = ca[:, None] * (y_c[:, None] - y) - (sa * x_c)[:, None]
    bend_i = np.sum(wts * dy * arm**2 * inv_i, axis=1) / E
    shear_i = SHEAR_FACTOR * ca**2 * np.sum(wts * dy * inv_a, axis=1) / G
    axial_i = sa**2 * np.sum(wts * dy * inv_a, axis=1) / E

    fillet = _fillet_foundation(geometry, i, prof, x_c, y_c, alpha1)
    shape = np.shape(position)
    return ToothCompliance(
        bending=(bend_f + bend_i).reshape(shape),
        shear=(shear_f + shear_i).reshape(shape),
        axial=(axial_f + axial_i).reshape(shape),
        fillet=fillet.reshape(shape),
    )


def sainsot_coefficients(root_half_angle: float, radius_ratio: float) -> tuple[float, float, float, float]:
    """L*, M*, P*, Q* of Sainsot, Velex & Duverger (2004), Table 1.

    Parameters
    ----------
    root_half_angle : float
        θ_f [rad].
    radius_ratio : float
        h_f = r_f / r_int [-].

    Returns
    -------
    L_star, M_star, P_star, Q_star : float
        The coefficients L*, M*, P*, Q* [-] of the fillet-foundation compliance.
    """
    t, h = root_half_angle, radius_ratio
    basis = np.array([1.0 / t**2, h**2, h / t, 1.0 / t, h, 1.0])
    L_, M_, P_, Q_ = SAINSOT_COEFFICIENTS @ basis
    return float(L_), float(M_), float(P_), float(Q_)


def _fillet_foundation(
    geometry: GearGeometry, index: int, prof: ToothProfile, x_c: NDArray, y_c: NDArray, alpha1: NDArray
) -> NDArray:
    E, L = geometry.young_modulus, geometry.face_width
    r_f = prof.root_radius
    bore = (geometry.bore_diameter_pinion, geometry.bore_diameter_gear)[index]
    r_int = 0.5 * bore if bore is not None else 0.5 * r_f
    if r_int >= r_f:
        member = ("pinion", "gear")[index]
        raise ModelError(
            f"bore_diameter_{member}", f"bore radius {r_int!r} m reaches the root circle {r_f!r} m"
        )
    theta_f = prof.root_half_angle
    L_, M_, P_, Q_ = sainsot_coefficients(theta_f, r_f / r_int)
    u_f = y_c - x_c * np.tan(alpha1) - r_f
    s_f = 2.0 * r_f * theta_f
    ratio = u_f / s_f
    return (
        np.cos(alpha1) ** 2 / (E * L) * (L_ * ratio**2 + M_ * ratio + P_ * (1.0 + Q_ * np.tan(alpha1) ** 2))
    )


def hertz_stiffness(geometry: GearGeometry) -> float:
    """Load-independent Hertzian contact stiffness k_h = π E L / (4 (1 - ν²)) [N/m].

    Yang & Sun (1985), as used by Tian (2004).

    Parameters
    ----------
    geometry : GearGeometry
        The gear pair.

    Returns
    -------
    float
        k_h [N/m].
    """
    E, nu, L = geometry.young_modulus, geometry.poisson_ratio, geometry.face_width
    return math.pi * E * L / (4.0 * (1.0 - nu**2))


@dataclass(frozen=True, eq=False)
class PairCompliance:
    """Compliance components of one tooth pair along the line of action [m/N].

    Parameters
    ----------
    position : ndarray
        Contact positions s from T1 [m].
    pinion, gear : ToothCompliance
        Tooth compliances.
    hertz : float
        1/k_h [m/N].
    """

    position: NDArray
    pinion: ToothCompliance
    gear: ToothCompliance
    hertz: float

    @property
    def total(self) -> NDArray:
        """Pair compliance 1/k_t [m/N]."""
        return self.hertz + self.pinion.total + self.gear.total

    @property
    def stiffness(self) -> NDArray:
        """Pair stiffness k_t [N/m]."""
        return 1.0 / self.total

    def components(self) -> dict[str, NDArray]:
        """Compliances by name [m/N]: ``bending_pinion``, ..., ``fillet_gear``, ``hertz``."""
        out = {}
        for member, tc in (("pinion", self.pinion), ("gear", self.gear)):
            for name in ("bending", "shear", "axial", "fillet"):
                out[f"{name}_{member}"] = getattr(tc, name)
        out["hertz"] = np.full(np.shape(self.position), self.hertz)
        return out


def pair_compliance(geometry: GearGeometry, position: ArrayLike) -> PairCompliance:
    """Compliance components of a tooth pair in contact at positions ``s`` from T1 [m].

    Parameters
    ----------
    geometry : GearGeometry
        The gear pair.
    position : array_like
        Contact positions s along the line of action from T1 [m].

    Returns
    -------
    PairCompliance
        Pinion and gear tooth compliances and the Hertzian one [m/N].
    """
    s = np.asarray(position, dtype=float)
    return PairCompliance(
        position=s,
        pinion=tooth_compliance(geometry, s, "pinion"),
        gear=tooth_compliance(geometry, s, "gear"),
        hertz=1.0 / hertz_stiffness(geometry),
    )


def pair_stiffness(geometry: GearGeometry, position: ArrayLike) -> NDArray:
    """Single tooth-pair stiffness k_t along the line of action [N/m] at positions ``s`` [m].

    Parameters
    ----------
    geometry : GearGeometry
        The gear pair.
    position : array_like
        Contact positions s along the line of action from T1 [m].

    Returns
    -------
    ndarray
        k_t [N/m], shaped like ``position``.
    """
    return pair_compliance(geometry, position).stiffness


def pitch_point_stiffness(geometry: GearGeometry) -> float:
    """Single tooth-pair stiffness at the pitch point [N/m].

    Parameters
    ----------
    geometry : GearGeometry
        The gear pair.

    Returns
    -------
    float
        k_t at the pitch point C [N/m].
    """
    return float(pair_stiffness(geometry, geometry.pitch_point))
