"""Linear finite-element rotor model against analytic solutions.

Sources: Euler-Bernoulli and Timoshenko beam theory (Timoshenko 1921; Han, Benaroya & Wei,
J. Sound Vib. 225 (1999) 935, eq. for the pinned-pinned beam), uniform torsion bar
(Rao, Mechanical Vibrations, 5th ed., §8.4), Jeffcott/Stodola-Green rotor with disk
gyroscopics (Genta, Dynamics of Rotating Systems, 2005, §4.4; influence coefficients from
Roark's Formulas for Stress and Strain, table 8.1 case 1e/3e).
"""

from __future__ import annotations

import numpy as np
import pytest

from nlgrd import Bearing, Coupling, Disk, Material, RotorSystem, Shaft, ShaftElement, assemble
from nlgrd.rotor.frequency_response import static_deflection
from nlgrd.rotor.modal import campbell, modal_analysis

STEEL = Material("steel", density=7850.0, young_modulus=2.1e11, poisson_ratio=0.3)
K_PIN = 1e13  # pin supports for the Jeffcott rotor: 1e9 x its shaft's EI/L³


def pinned_shaft(length, diameter, n_el, material=STEEL, **el_kwargs):
    """Pinned-pinned shaft. The pins are springs of 1e9 EI/L³: their flexibility changes
    mode n by about 2 EI k_n² / (k_pin L) < 1e-6, and the stiffness spread stays small
    enough for the dense eigensolver."""
    el = ShaftElement(length / n_el, diameter, 0.0, material, **el_kwargs)
    k_pin = 1e9 * material.young_modulus * np.pi * diameter**4 / 64 / length**3
    k_axial = 1e6 * material.young_modulus * np.pi * diameter**2 / 4 / length
    k_torsion = 1e6 * material.shear_modulus * np.pi * diameter**4 / 32 / length
    shaft = Shaft((el,) * n_el)
    bearings = (
        Bearing(0, 0, kyy=k_pin, kzz=k_pin, kxx=k_axial, ktt=k_torsion),
        Bearing(0, n_el, kyy=k_pin, kzz=k_pin),
    )
    return RotorSystem((shaft,), bearings=bearings)


def bending_frequencies(system, n):
    """First n distinct bending frequencies [Hz] (each appears twice, y and z)."""
    res = modal_analysis(system, n_modes=4 * n + 6, damped=False)
    f = res.natural_frequencies[np.array(res.kinds) == "lateral"]
    return f[::2][:n]


def euler_bernoulli_ss(length, diameter, n, material=STEEL):
    I = np.pi * diameter**4 / 64
    A = np.pi * diameter**2 / 4
    k = np.arange(1, n + 1) * np.pi / length
    return k**2 * np.sqrt(material.young_modulus * I / (material.density * A)) / (2 * np.pi)


def timoshenko_ss(length, diameter, n, material=STEEL):
    """Pinned-pinned Timoshenko beam: for mode sin(kx) the two-field equations give
    det([[κGA k² - ρAω², κGA k], [κGA k, EI k² + κGA - ρIω²]]) = 0; the lower root."""
    E, G, rho, nu = material.young_modulus, material.shear_modulus, material.density, material.poisson_ratio
    I = np.pi * diameter**4 / 64
    A = np.pi * diameter**2 / 4
    kappa = 6 * (1 + nu) / (7 + 6 * nu)  # Cowper (1966), solid circle
    out = []
    for j in range(1, n + 1):
        k = j * np.pi / length
        # (κGAk² - ρAx)(EIk² + κGA - ρIx) - (κGAk)² = 0, x = ω²
        a = rho * A * rho * I
        b = -(kappa * G * A * k**2 * rho * I + rho * A * (E * I * k**2 + kappa * G * A))
        c = kappa * G * A * k**2 * (E * I * k**2 + kappa * G * A) - (kappa * G * A * k) ** 2
        x = np.min(np.roots([a, b, c]).real)
        out.append(np.sqrt(x) / (2 * np.pi))
    return np.array(out)


def test_slender_shaft_matches_euler_bernoulli():
    """L/D = 300: shear and rotary inertia change mode 4 by < 0.02 %, so Euler-Bernoulli is
    the exact reference; 20 cubic elements must be within 0.1 % for the first four modes."""
    L, D = 3.0, 0.01
    f = bending_frequencies(pinned_shaft(L, D, 20), 4)
    ref = euler_bernoulli_ss(L, D, 4)
    err = np.abs(f / ref - 1)
    assert np.all(err < 1e-3), err


def test_stocky_shaft_matches_timoshenko():
    """L/D = 5: shear lowers mode 4 by ~30 % from Euler-Bernoulli. On this bare shaft
    pinned at both ends the blended mass is fourth order (docs/verification.md, case (a)):
    20 elements within 0.1 % of the analytic Timoshenko values. The default consistent
    mass is second order here (elements of L/D = 0.25): within 1 % (measured 0.76 % on
    mode 4, 20 elements), an upper bound on every mode (Rayleigh-Ritz)."""
    L, D = 0.5, 0.1
    ref = timoshenko_ss(L, D, 4)
    f = bending_frequencies(pinned_shaft(L, D, 20, mass_matrix="blended"), 4)
    assert np.all(np.abs(f / ref - 1) < 1e-3), f / ref - 1
    fc = bending_frequencies(pinned_shaft(L, D, 20), 4)
    assert np.all((fc / ref - 1 > 0) & (fc / ref - 1 < 1e-2)), fc / ref - 1
    eb = euler_bernoulli_ss(L, D, 4)
    assert eb[3] / ref[3] > 1.2  # the case really tests shear and rotary inertia


@pytest.mark.parametrize("mass", ["blended", "consistent"])
@pytest.mark.parametrize("geometry", [(3.0, 0.01), (0.5, 0.1)])
def test_bending_convergence_table(geometry, mass):
    """Refining the mesh gives monotonically shrinking errors (no jumps). At the finest
    levels mode 4 (>= 2 elements per half wave from 8 elements on) converges at the
    rate of cubic elements, h^4, for slender elements (L/D = 300, Phi << 1: the two
    masses coincide) and for the blended mass on the stocky shaft; the consistent mass
    on the stocky shaft (Phi = 9-35 at 8-16 elements) at h^2 (docs/verification.md,
    case (a): 2.00-2.03). Each within a factor 2 of its rate."""
    L, D = geometry
    ref = timoshenko_ss(L, D, 4)
    counts = [4, 8, 16, 20]
    errs = np.array(
        [np.abs(bending_frequencies(pinned_shaft(L, D, n, mass_matrix=mass), 4) / ref - 1) for n in counts]
    )
    print("elements  " + "  ".join(f"mode {m + 1} error" for m in range(4)))
    for n, e in zip(counts, errs, strict=True):
        print(f"{n:8d}  " + "  ".join(f"{x:12.2e}" for x in e))
    for m in range(4):
        assert np.all(np.diff(errs[:, m]) < 0), (m, errs[:, m])
    rate = np.log(errs[2, 3] / errs[1, 3]) / np.log(2.0)
    if mass == "consistent" and L / D < 10:
        assert -3.0 < rate < -1.5, rate
    else:
        assert -5.0 < rate < -3.0, rate


def test_torsion_free_free_and_fixed_free():
    """Uniform bar: free-free f_n = n c / 2L, fixed-free f_n = (2n-1) c / 4L, c = sqrt(G/ρ).
    Linear elements with consistent mass err by about (nπh/L)²/24; 100 elements keep the
    first three modes below 0.05 %, under the 0.1 % target."""
    L, D, n_el = 1.0, 0.05, 100
    c = np.sqrt(STEEL.shear_modulus / STEEL.density)
    shaft = Shaft.uniform(L, D, n_el, STEEL)
    lateral = tuple(Bearing(0, i, kyy=K_PIN, kzz=K_PIN, kxx=K_PIN) for i in (0, n_el))
    free = modal_analysis(RotorSystem((shaft,), bearings=lateral), n_modes=60, damped=False)
    f_free = free.natural_frequencies[np.array(free.kinds) == "torsional"][:3]
    ref_free = np.arange(1, 4) * c / (2 * L)
    assert free.n_rigid_body == 1  # the free torsional rotation
    assert np.all(np.abs(f_free / ref_free - 1) < 1e-3), f_free / ref_free - 1
    clamp = Coupling(0, 0, k_torsion=1e6 * STEEL.shear_modulus * np.pi * D**4 / 32 / L)
    fixed = modal_analysis(
        RotorSystem((shaft,), bearings=lateral, couplings=(clamp,)), n_modes=60, damped=False
    )
    f_fixed = fixed.natural_frequencies[np.array(fixed.kinds) == "torsional"][:3]
    ref_fixed = (2 * np.arange(1, 4) - 1) * c / (4 * L)
    assert np.all(np.abs(f_fixed / ref_fixed - 1) < 1e-3), f_fixed / ref_fixed - 1


def jeffcott_closed_form(m, Id, Ip, EI, L, a, speed):
    """Whirl frequencies [rad/s] of a rigid disk at x = a on a massless pinned-pinned shaft.

    Flexibility at the disk (Roark): [[a²b², ab(b-a)], [ab(b-a), a²-ab+b²]] / (3EIL).
    With u = y + iz, φ = φy + iφz and e^{iωt}, the disk equations give
    (k11 - mω²)(k22 - Id ω² + Ip Ω ω) - k12² = 0; positive roots whirl forward,
    negative roots backward."""
    b = L - a
    F = np.array([[a**2 * b**2, a * b * (b - a)], [a * b * (b - a), a**2 - a * b + b**2]]) / (3 * EI * L)
    k = np.linalg.inv(F)
    # expand: (k11 - m w²)(k22 + IpΩ w - Id w²) - k12²
    p1 = np.array([-m, 0.0, k[0, 0]])
    p2 = np.array([-Id, Ip * speed, k[1, 1]])
    poly = np.polysub(np.polymul(p1, p2), [k[0, 1] ** 2])
    r = np.sort(np.roots(poly).real)
    return np.sort(r[r > 0]), np.sort(-r[r < 0])


def test_jeffcott_whirl_speeds_with_gyroscopic_disk():
    """Forward and backward whirl frequencies from 0 to 3x the first critical speed within
    0.5 % of the closed form. The shaft is made massless (density 1e-9 of steel) and
    Euler-Bernoulli (shear off) to match the closed form's assumptions."""
    L, D, a = 0.6, 0.02, 0.2
    light = Material("light", density=7850e-9, young_modulus=2.1e11, poisson_ratio=0.3)
    el = ShaftElement(L / 6, D, 0.0, light, shear=False)
    disk = Disk.from_dimensions(0, 2, outer_diameter=0.3, width=0.03)
    sys_ = RotorSystem(
        (Shaft((el,) * 6),),
        disks=(disk,),
        bearings=(Bearing(0, 0, kyy=K_PIN, kzz=K_PIN, kxx=1e9, ktt=1e6), Bearing(0, 6, kyy=K_PIN, kzz=K_PIN)),
    )
    EI = 2.1e11 * np.pi * D**4 / 64
    args = (disk.mass, disk.diametral_inertia, disk.polar_inertia, EI, L, a)
    # first forward critical speed: forward root equal to the speed
    grid = np.linspace(1, 2000, 4000)
    g = np.array([jeffcott_closed_form(*args, s)[0][0] - s for s in grid])
    crit = grid[np.argmax(g < 0)]
    model = assemble(sys_)
    worst = 0.0
    for speed in np.linspace(0, 3 * crit, 7):
        fwd, bwd = jeffcott_closed_form(*args, speed)
        res = modal_analysis(model, speed=speed, n_modes=8)
        lat = np.array(res.kinds) == "lateral"
        w = 2 * np.pi * res.damped_frequencies[lat]
        whirl = np.array(res.whirl)[lat]
        fe_fwd = np.sort(w[whirl == "forward"])[:2]
        fe_bwd = np.sort(w[whirl == "backward"])[:2]
        if speed == 0:
            fe_fwd = fe_bwd = np.sort(w)[[0, 2]]
        worst = max(worst, np.max(np.abs(fe_fwd / fwd - 1)), np.max(np.abs(fe_bwd / bwd - 1)))
    assert worst < 5e-3, worst


def test_campbell_finds_forward_critical_speed():
    """Campbell crossing of the 1x line with the first forward mode equals the closed-form
    synchronous critical speed within 0.5 % (linear interpolation between 41 speeds)."""
    L, D, a = 0.6, 0.02, 0.2
    light = Material("light", density=7850e-9, young_modulus=2.1e11, poisson_ratio=0.3)
    el = ShaftElement(L / 6, D, 0.0, light, shear=False)
    disk = Disk.from_dimensions(0, 2, outer_diameter=0.3, width=0.03)
    sys_ = RotorSystem(
        (Shaft((el,) * 6),),
        disks=(disk,),
        bearings=(Bearing(0, 0, kyy=K_PIN, kzz=K_PIN, kxx=1e9, ktt=1e6), Bearing(0, 6, kyy=K_PIN, kzz=K_PIN)),
    )
    EI = 2.1e11 * np.pi * D**4 / 64
    args = (disk.mass, disk.diametral_inertia, disk.polar_inertia, EI, L, a)
    grid = np.linspace(1, 2000, 20000)
    g = np.array([jeffcott_closed_form(*args, s)[0][0] - s for s in grid])
    crit = grid[np.argmax(g < 0)]
    res = campbell(sys_, np.linspace(0, 2 * crit, 41), n_modes=4)
    fwd = [
        c["speed [rpm]"] for c in res.critical_speeds if res.whirl[0, c["mode"] - 1] in ("forward", "planar")
    ]
    assert any(abs(s * np.pi / 30 / crit - 1) < 5e-3 for s in fwd), (fwd, crit * 30 / np.pi)


def test_matrix_properties():
    """M, K symmetric positive semi-definite; G skew-symmetric; on a stepped two-shaft model
    with disks, bearings and couplings (round-off tolerance 1e-12 of the largest entry)."""
    s0 = Shaft(
        (ShaftElement(0.1, 0.05), ShaftElement(0.15, 0.06, 0.02), ShaftElement(0.1, 0.05)), speed_ratio=1
    )
    s1 = Shaft((ShaftElement(0.12, 0.04),) * 3, y=0.1, speed_ratio=-2.0)
    sys_ = RotorSystem(
        (s0, s1),
        disks=(Disk.from_dimensions(0, 1, 0.2, 0.03), Disk(1, 2, 3.0, 0.01, 0.02)),
        bearings=(Bearing(0, 0, kyy=1e8, kzz=2e8, kyz=1e7, kzy=1e7), Bearing(1, 3, kyy=1e8, kzz=1e8)),
        couplings=(Coupling(0, 3, 1, 0, k_torsion=1e4, k_lateral=1e6, ratio=-2.0),),
    )
    m = assemble(sys_)
    for name in ("M", "K"):
        A = getattr(m, name).toarray()
        assert np.max(np.abs(A - A.T)) <= 1e-12 * np.max(np.abs(A))
        assert np.min(np.linalg.eigvalsh(A)) >= -1e-9 * np.max(np.abs(A))
    G = m.G.toarray()
    assert np.max(np.abs(G + G.T)) <= 1e-12 * np.max(np.abs(G))
    assert np.max(np.abs(G)) > 0


def test_static_deflection_of_pinned_beam():
    """Central load on a pinned-pinned Euler-Bernoulli beam: δ = PL³/48EI (exact at the
    nodes of cubic elements) plus the pin springs' own deflection (P/2)/k_pin; so 1e-9
    relative, round-off."""
    L, D, P = 1.0, 0.03, 1000.0
    sys_ = pinned_shaft(L, D, 8, shear=False)
    res = static_deflection(sys_, {(0, 4, "uy"): P})
    EI = 2.1e11 * np.pi * D**4 / 64
    got = res.q[sys_.dofs.index(0, 4, "uy")]
    k_pin = 1e9 * EI / L**3
    assert abs(got / (P * L**3 / (48 * EI) + P / 2 / k_pin) - 1) < 1e-9
    assert len(res.to_frame()) == 9


def test_static_deflection_rejects_unbalanced_torque_on_free_train():
    """A torque on a free torsional rigid-body mode has no static solution: a ModelError."""
    from nlgrd.errors import ModelError

    shaft = Shaft.uniform(1.0, 0.05, 4)
    sys_ = RotorSystem(
        (shaft,), bearings=(Bearing(0, 0, kyy=1e9, kzz=1e9, kxx=1e9), Bearing(0, 4, kyy=1e9, kzz=1e9))
    )
    with pytest.raises(ModelError, match="rigid-body"):
        static_deflection(sys_, {(0, 2, "θx"): 10.0})


def test_bearing_slopes_are_those_of_the_table():
    """``Bearing.K_slope`` and ``C_slope``: the slopes of the linear interpolation of each
    tabulated coefficient, by differences of ``stiffness``/``damping`` inside a segment
    (either sign of the speed: the table is of |Ω|), 0 beyond the table and for constants."""
    b = Bearing(
        0,
        0,
        kyy=[1e8, 3e8, 2e8],
        kzz=5e7,
        kyz=[0.0, 1e7, 4e7],
        cyy=[100.0, 300.0, 50.0],
        speeds=[100.0, 200.0, 400.0],
        kxx=1e9,
        cxx=10.0,
    )
    h = 1e-3
    for s in (150.0, 250.0, -250.0, 399.0):
        dk = (b.stiffness(s + h) - b.stiffness(s - h)) / (2 * h)
        dc = (b.damping(s + h) - b.damping(s - h)) / (2 * h)
        np.testing.assert_allclose(b.K_slope(s)[1:3, 1:3], dk, rtol=1e-9, atol=1e-9 * np.abs(dk).max())
        np.testing.assert_allclose(b.C_slope(s)[1:3, 1:3], dc, rtol=1e-9, atol=1e-9 * np.abs(dc).max())
        assert b.K_slope(s)[0, 0] == 0.0 and b.C_slope(s)[0, 0] == 0.0
    assert b.K_slope(150.0)[1, 1] == 2e6 and b.K_slope(-250.0)[1, 1] == 5e5  # d/dΩ of |Ω|
    assert not b.K_slope(50.0).any() and not b.K_slope(500.0).any()
