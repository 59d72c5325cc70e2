"""The gear mesh coupling: projection vector, static load path and gear-pair mode.

Independent checks: rigid-body statics of a spur pair (the mesh force lies on the line
tangent to both base circles; it resists the driver's rotation and drives the driven
member, with torques W r_b; it pushes the gears apart by W sin α_w), and the gear-pair
torsional natural frequency sqrt(k_h / m_eq) of two inertias coupled through the base
radii (Özgüven & Houser 1988, J. Sound Vib. 121:383, eq. 2).
"""

from __future__ import annotations

import numpy as np
import pytest

from nlgrd import Bearing, Disk, Material, RotorSystem, Shaft, ShaftElement, assemble
from nlgrd.errors import ModelError
from nlgrd.gear.geometry import GearGeometry
from nlgrd.gear.mesh import GearMesh
from nlgrd.rotor.frequency_response import static_deflection
from nlgrd.rotor.modal import modal_analysis

KUBO = GearGeometry(teeth_pinion=25, teeth_gear=25, module=4e-3, face_width=15e-3, backlash=0.1e-3)


def two_shafts(angle, spin=1.0, driver="pinion", torque=100.0, kh=2e8, stiff=False, disks=True):
    a = KUBO.operating_centre_distance
    mat = Material(
        "stiff", density=7850 * (1e-6 if stiff else 1), young_modulus=2.1e11 * (1e4 if stiff else 1)
    )
    el = ShaftElement(0.05, 0.04, 0.0, mat)
    s0 = Shaft((el, el), name="pinion", speed_ratio=spin)
    s1 = Shaft((el, el), name="gear", y=a * np.cos(angle), z=a * np.sin(angle), speed_ratio=-spin)
    kb = 1e13 if stiff else 1e9
    bearings = tuple(Bearing(s, n, kyy=kb, kzz=kb, kxx=kb) for s in (0, 1) for n in (0, 2))
    dks = (Disk(0, 1, 2.0, 0.5e-3, 1.152e-3), Disk(1, 1, 2.0, 0.5e-3, 1.152e-3)) if disks else ()
    mesh = GearMesh(0, 1, 1, 1, KUBO, torque=torque, mesh_stiffness=kh, driver=driver)
    return RotorSystem((s0, s1), disks=dks, bearings=bearings, gear_pairs=(mesh,)), mesh


@pytest.mark.parametrize("angle", [0.0, np.radians(130.0)])
@pytest.mark.parametrize("spin", [1.0, -1.0])
@pytest.mark.parametrize("driver", ["pinion", "gear"])
def test_line_of_action_statics(angle, spin, driver):
    """Mesh-force direction, torques and separating force against rigid-body statics."""
    sys_, mesh = two_shafts(angle, spin, driver)
    n = mesh.line_of_action(sys_)
    rbp, rbg = mesh.base_radii
    alpha = KUBO.operating_pressure_angle
    P = np.array([sys_.shafts[0].y, sys_.shafts[0].z])
    G = np.array([sys_.shafts[1].y, sys_.shafts[1].z])
    c = (G - P) / np.linalg.norm(G - P)
    pitch = P + KUBO.operating_pitch_radius_pinion * c

    def moment(point, centre, force):
        r = point - centre
        return r[0] * force[1] - r[1] * force[0]

    # tangent to both base circles: distance of each centre from the line equals r_b
    assert abs(abs(moment(pitch, P, n)) - rbp) < 1e-12
    assert abs(abs(moment(pitch, G, n)) - rbg) < 1e-12
    # separating component of the force on the gear
    assert abs(n @ c - np.sin(alpha)) < 1e-12
    W = 1000.0
    tq_pinion = moment(pitch, P, -W * n)  # force on the pinion is -W n
    tq_gear = moment(pitch, G, W * n)
    pinion_driven = driver == "gear"
    # the driver's mesh torque opposes its spin, the driven member's follows it;
    # the gear spins as -spin
    gear_spin = -spin
    assert np.sign(tq_pinion) == (spin if pinion_driven else -spin)
    assert np.sign(tq_gear) == (gear_spin if not pinion_driven else -gear_spin)
    assert abs(abs(tq_pinion) - W * rbp) < 1e-9 and abs(abs(tq_gear) - W * rbg) < 1e-9
    # w reproduces the same generalised forces: -W w
    w = mesh.projection(sys_)
    f = -W * w
    dm = sys_.dofs
    assert np.allclose(f[dm.node_dofs(0, 1)[1:3]], -W * n, atol=1e-12)
    assert np.allclose(f[dm.node_dofs(1, 1)[1:3]], W * n, atol=1e-12)
    assert abs(f[dm.index(0, 1, "θx")] - tq_pinion) < 1e-9
    assert abs(f[dm.index(1, 1, "θx")] - tq_gear) < 1e-9


@pytest.mark.parametrize("angle", [0.0, np.radians(130.0)])
@pytest.mark.parametrize("spin", [1.0, -1.0])
def test_static_torque_loads_mesh_and_bearings(angle, spin):
    """Static torques T_p and T_p r_bg / r_bp: the mesh carries W_0 = T_p / r_bp in
    compression and the bearings of each shaft react the mesh force (±W_0 n), to 1e-9
    relative (a linear solve)."""
    torque = 120.0
    sys_, mesh = two_shafts(angle, spin, torque=torque)
    model = assemble(sys_)
    res = static_deflection(model, mesh.static_torques(sys_))
    w = mesh.projection(sys_)
    W = mesh.stiffness() * (w @ res.q)
    W0 = torque / mesh.base_radii[0]
    assert abs(W / W0 - 1) < 1e-9
    n = mesh.line_of_action(sys_)
    for shaft, sign in ((0, 1.0), (1, -1.0)):
        react = np.zeros(2)
        for b in sys_.bearings:
            if b.shaft == shaft:
                u = res.q[sys_.dofs.node_dofs(shaft, b.node)[1:3]]
                react += -b.stiffness() @ u
        assert np.allclose(react, sign * W0 * n, rtol=0, atol=1e-9 * W0)


def test_gear_pair_torsional_mode():
    """Very stiff shafts and bearings, light shafts: the torsional mode with the mesh equals
    sqrt(k_h / m_eq) within 1 % (the residual shaft compliance and inertia are < 1e-3)."""
    sys_, mesh = two_shafts(0.3, stiff=True, kh=2.587e8)
    res = modal_analysis(sys_, n_modes=30, damped=False)
    meq = mesh.equivalent_mass(sys_)
    ref = np.sqrt(2.587e8 / meq) / (2 * np.pi)
    tors = res.natural_frequencies[np.array(res.kinds) != "lateral"]
    assert np.min(np.abs(tors / ref - 1)) < 1e-2, (tors[:5], ref)
    assert abs(meq - 0.2607) < 1e-3  # model.md §5: m_eq ≈ 0.261 kg for Kubo's rig


def test_damping_ratio_gives_coefficient():
    """c_m = 2 ζ sqrt(k_h m_eq) (paper §2.2)."""
    sys_, mesh = two_shafts(0.0)
    m = GearMesh(0, 1, 1, 1, KUBO, torque=10.0, mesh_stiffness=2e8, damping_ratio=0.05)
    assert abs(m.damping_coefficient(sys_) - 0.1 * np.sqrt(2e8 * mesh.equivalent_mass(sys_))) < 1e-9


def test_wrong_centre_distance_is_an_error():
    """Shafts not the operating centre distance apart: a ModelError naming gear_pairs[0]."""
    sys_, mesh = two_shafts(0.0)
    s1 = Shaft(sys_.shafts[1].elements, y=0.2, speed_ratio=-1.0)
    with pytest.raises(ModelError, match=r"gear_pairs\[0\].*centre"):
        RotorSystem((sys_.shafts[0], s1), bearings=sys_.bearings, gear_pairs=(mesh,))
