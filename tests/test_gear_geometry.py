"""Tests of nlgrd.gear.geometry against textbook closed forms and input validation."""

from __future__ import annotations

import math
import warnings

import pytest

from nlgrd.errors import ModelError
from nlgrd.gear.geometry import GearGeometry, involute

ALPHA = math.radians(20.0)


def _inv(a: float) -> float:
    return math.tan(a) - a


def _solve_inv(value: float) -> float:
    """Bisection on tan a - a = value (independent of the library's solver)."""
    lo, hi = 0.0, 1.5
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if _inv(mid) < value:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _closed_form(z1, z2, m, x1=0.0, x2=0.0, ha=1.0, alpha=ALPHA):
    """Textbook spur-pair formulas (e.g. Niemann & Winter vol. II, ISO 21771).

    inv α' = inv α + 2 tan α (x1 + x2)/(z1 + z2); a' = (r1 + r2) cos α / cos α';
    r_a = r + (h_a + x) m; g_α = sqrt(ra1² - rb1²) + sqrt(ra2² - rb2²) - a' sin α';
    p_b = π m cos α; ε_α = g_α / p_b.
    """
    r1, r2 = m * z1 / 2, m * z2 / 2
    rb1, rb2 = r1 * math.cos(alpha), r2 * math.cos(alpha)
    aw = _solve_inv(_inv(alpha) + 2 * math.tan(alpha) * (x1 + x2) / (z1 + z2))
    a = (r1 + r2) * math.cos(alpha) / math.cos(aw)
    ra1, ra2 = r1 + (ha + x1) * m, r2 + (ha + x2) * m
    g = math.sqrt(ra1**2 - rb1**2) + math.sqrt(ra2**2 - rb2**2) - a * math.sin(aw)
    pb = math.pi * m * math.cos(alpha)
    return {"aw": aw, "a": a, "g": g, "pb": pb, "eps": g / pb, "ra1": ra1, "ra2": ra2}


@pytest.mark.parametrize(
    ("z1", "z2", "m", "x1", "x2"),
    [
        (25, 25, 4e-3, 0.0, 0.0),  # Kubo et al. (1972), model.md §5
        (20, 40, 3e-3, 0.0, 0.0),
        (18, 40, 3e-3, 0.3, 0.1),  # profile-shifted, x1 + x2 != 0
        (30, 60, 2e-3, 0.2, -0.2),  # shifted, x1 + x2 = 0
    ],
)
def test_contact_ratio_base_pitch_path_match_closed_form(z1, z2, m, x1, x2):
    """Contact ratio, base pitch and path of contact equal the textbook closed forms.

    Source: the involute-pair formulas of ISO 21771 / any gear textbook, re-derived in
    ``_closed_form`` with its own bisection for inv α'. Tolerance 1e-9 relative: both
    sides are closed forms in double precision (bisection converged to ~1e-16).
    """
    g = GearGeometry(z1, z2, m, 0.02, profile_shift_pinion=x1, profile_shift_gear=x2)
    ref = _closed_form(z1, z2, m, x1, x2)
    assert g.operating_pressure_angle == pytest.approx(ref["aw"], rel=1e-9)
    assert g.operating_centre_distance == pytest.approx(ref["a"], rel=1e-9)
    assert g.tip_radius_pinion == pytest.approx(ref["ra1"], rel=1e-12)
    assert g.tip_radius_gear == pytest.approx(ref["ra2"], rel=1e-12)
    assert g.base_pitch == pytest.approx(ref["pb"], rel=1e-12)
    assert g.path_of_contact == pytest.approx(ref["g"], rel=1e-9)
    assert g.contact_ratio == pytest.approx(ref["eps"], rel=1e-9)
    # the operating pressure angle satisfies the meshing equation it was solved from
    lhs = involute(g.operating_pressure_angle)
    rhs = involute(ALPHA) + 2 * math.tan(ALPHA) * (x1 + x2) / (z1 + z2)
    assert lhs == pytest.approx(rhs, rel=1e-12, abs=1e-15)


def test_kubo_diameters_and_contact_ratio():
    """Kubo's gears (model.md §5, Table 1 of Maliha et al. 2004): m 4 mm, 25/25 teeth.

    Table: pitch 100 mm, base 94 mm (rounded: 100 cos 20° = 93.97), outside 108 mm,
    root 90 mm. The geometric contact ratio of these diameters is 1.612 (the table's
    1.56 is LDP's, with tip rounding); checked against the closed form to 1e-9.
    """
    g = GearGeometry(25, 25, 4e-3, 15e-3, tip_diameter_pinion=0.108, tip_diameter_gear=0.108)
    assert 2 * g.pitch_radius_pinion == pytest.approx(0.100, rel=1e-12)
    assert 2 * g.base_radius_gear == pytest.approx(0.094, abs=0.5e-3)
    assert 2 * g.root_radius_pinion == pytest.approx(0.090, rel=1e-12)
    assert 2 * g.tip_radius_gear == pytest.approx(0.108, rel=1e-12)
    assert g.contact_ratio == pytest.approx(_closed_form(25, 25, 4e-3)["eps"], rel=1e-9)
    assert g.contact_ratio == pytest.approx(1.6117, abs=1e-4)
    assert g.gear_ratio == 1.0


def test_given_centre_distance_sets_operating_pressure_angle():
    """cos α' = (r_b1 + r_b2) / a' for a given centre distance (a' cos α' = a cos α)."""
    g0 = GearGeometry(20, 40, 3e-3, 0.02)
    a = g0.operating_centre_distance + 0.2e-3
    g = GearGeometry(20, 40, 3e-3, 0.02, centre_distance=a)
    assert math.cos(g.operating_pressure_angle) == pytest.approx(
        (g.base_radius_pinion + g.base_radius_gear) / a, rel=1e-14
    )
    assert g.operating_pitch_radius_pinion + g.operating_pitch_radius_gear == pytest.approx(a, rel=1e-14)
    assert g.operating_pitch_radius_gear / g.operating_pitch_radius_pinion == pytest.approx(2.0, rel=1e-14)


def test_position_helpers_are_consistent():
    """The pitch point lies on the operating pitch circles; roll angles invert."""
    g = GearGeometry(18, 40, 3e-3, 0.02, profile_shift_pinion=0.3, profile_shift_gear=0.1)
    c = g.pitch_point
    assert g.contact_radius(c, "pinion") == pytest.approx(g.operating_pitch_radius_pinion, rel=1e-13)
    assert g.contact_radius(c, "gear") == pytest.approx(g.operating_pitch_radius_gear, rel=1e-13)
    assert g.contact_radius(g.end_of_contact, "pinion") == pytest.approx(g.tip_radius_pinion, rel=1e-13)
    assert g.contact_radius(g.start_of_contact, "gear") == pytest.approx(g.tip_radius_gear, rel=1e-13)
    for member in ("pinion", "gear"):
        xi = g.roll_angle(0.01, member)
        assert g.position_from_roll_angle(xi, member) == pytest.approx(0.01, rel=1e-14)
        d = 2 * g.contact_radius(0.011, member)
        assert g.position_from_diameter(d, member) == pytest.approx(0.011, rel=1e-12)
    assert g.lowest_single_contact < g.pitch_point < g.highest_single_contact


def test_backlash_conversion():
    """Backlash along the LOA = circumferential backlash on the operating pitch circle × cos α'."""
    g = GearGeometry(18, 40, 3e-3, 0.02, profile_shift_pinion=0.3, profile_shift_gear=0.1)
    b = GearGeometry.backlash_from_circumferential(1e-4, g.operating_pressure_angle)
    assert b == pytest.approx(1e-4 * math.cos(g.operating_pressure_angle), rel=1e-15)
    g2 = g.with_circumferential_backlash(1e-4)
    assert g2.backlash == pytest.approx(b, rel=1e-15)
    assert g2.circumferential_backlash == pytest.approx(1e-4, rel=1e-14)
    assert g2.half_backlash == pytest.approx(b / 2, rel=1e-15)


def _kubo(**kw):
    base = dict(teeth_pinion=25, teeth_gear=25, module=4e-3, face_width=15e-3)
    base.update(kw)
    return GearGeometry(**base)


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"teeth_pinion": 3}, "teeth_pinion"),
        ({"teeth_gear": 25.0}, "teeth_gear"),
        ({"module": 0.0}, "module"),
        ({"module": -1e-3}, "module"),
        ({"face_width": 0.0}, "face_width"),
        ({"face_width": float("nan")}, "face_width"),
        ({"module": float("inf")}, "module"),
        ({"profile_shift_pinion": float("nan")}, "profile_shift_pinion"),
        ({"backlash": -1e-5}, "backlash"),
        ({"young_modulus": float("inf")}, "young_modulus"),
        ({"poisson_ratio": 0.6}, "poisson_ratio"),
        ({"tip_diameter_pinion": 0.104, "tip_diameter_gear": 0.104}, "contact_ratio"),
        ({"centre_distance": 0.0999}, "centre_distance"),
        ({"root_radius_coefficient": 0.6}, "root_radius_coefficient"),
    ],
)
def test_invalid_input_names_the_field(kwargs, key):
    """Each invalid input raises ModelError whose key names the field (``contact_ratio`` for ε < 1).

    Tip diameters of 104 mm on Kubo's pair give ε = 0.88 (closed form), below 1.
    """
    with pytest.raises(ModelError) as exc:
        _kubo(**kwargs)
    assert exc.value.key == key


def test_interference_says_which_gear():
    """A large pinion with a small gear: the pinion tip reaches past T2 (the gear's base tangency).

    z1 = 60, z2 = 8, m = 1: sqrt(r_a1² - r_b1²) = 12.90 mm > a sin α = 11.63 mm.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the 8-tooth gear is undercut
        with pytest.raises(ModelError, match="pinion tip circle reaches past the gear") as exc:
            GearGeometry(60, 8, 1e-3, 0.01)
        assert exc.value.key == "tip_diameter_pinion"
        with pytest.raises(ModelError, match="gear tip circle reaches past the pinion") as exc:
            GearGeometry(8, 60, 1e-3, 0.01)
        assert exc.value.key == "tip_diameter_gear"


def test_pointed_teeth_are_refused():
    """z = 10, x = 0.8: θ_b = 0.2302 rad < inv α_a = 0.238 rad, so s_a < 0 (pointed)."""
    with pytest.raises(ModelError, match="pointed pinion") as exc:
        GearGeometry(10, 30, 1e-3, 0.01, profile_shift_pinion=0.8)
    assert exc.value.key == "tip_diameter_pinion"


def test_undercut_warns():
    """z = 14 < 2 h_a / sin² 20° = 17.1: undercut warning (UserWarning)."""
    with pytest.warns(UserWarning) as record:
        GearGeometry(14, 14, 1e-3, 0.01)
    messages = [str(w.message) for w in record]
    assert any("pinion is undercut" in m for m in messages)
    assert any("gear is undercut" in m for m in messages)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        GearGeometry(18, 40, 1e-3, 0.01)  # z = 18 > 17.1: no warning


def test_tip_rounding_shortens_the_path_of_contact():
    """A tip round moves the end of the involute below the tip circle; ε falls accordingly.

    Kubo's table lists ε = 1.56; a 0.3 mm tip round on the 108 mm tips gives about that.
    """
    g0 = _kubo(tip_diameter_pinion=0.108, tip_diameter_gear=0.108)
    g = _kubo(tip_diameter_pinion=0.108, tip_diameter_gear=0.108, tip_rounding=0.3e-3)
    assert g.active_tip_radius_pinion < g.tip_radius_pinion
    assert g.contact_ratio < g0.contact_ratio
    assert g.contact_ratio == pytest.approx(1.56, abs=0.01)
