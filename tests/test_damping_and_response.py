"""Frequency response and internal (rotating) damping against closed forms.

Sources: 2-DOF receptance by Cramer's rule (any vibration text, e.g. Inman, Engineering
Vibration, §4.6); Jeffcott rotor with internal viscous damping: whirl instability above
Ω_th = ω_n (1 + c_e / c_i) (Genta, Dynamics of Rotating Systems, 2005, §6.3; Friswell et al.,
Dynamics of Rotating Machines, 2010, §3.4).
"""

from __future__ import annotations

import numpy as np

from nlgrd import Bearing, Coupling, Disk, LinearModel, Material, RotorSystem, Shaft, ShaftElement, assemble
from nlgrd.rotor.frequency_response import frequency_response
from nlgrd.rotor.modal import modal_analysis


def test_two_dof_receptance_closed_form():
    """Damped 2-DOF chain: H = adj(Z)/det(Z) written out by hand; equal to 1e-10 relative
    (both are exact; only round-off differs)."""
    m1, m2, k1, k2, c1, c2 = 2.0, 1.0, 4e5, 2e5, 30.0, 10.0
    M = np.diag([m1, m2])
    K = np.array([[k1 + k2, -k2], [-k2, k2]])
    C = np.array([[c1 + c2, -c2], [-c2, c2]])
    model = LinearModel.from_matrices(M, K, C)
    w = np.linspace(1.0, 1500.0, 300)
    res = frequency_response(model, w, inputs=[0, 1], outputs=[0, 1])
    s = 1j * w
    z11 = m1 * s**2 + (c1 + c2) * s + k1 + k2
    z22 = m2 * s**2 + c2 * s + k2
    z12 = -(c2 * s + k2)
    det = z11 * z22 - z12**2
    ref = np.stack([np.stack([z22, -z12], -1), np.stack([-z12, z11], -1)], -2) / det[:, None, None]
    assert np.max(np.abs(res.H - ref) / np.abs(ref)) < 1e-10
    df = res.to_frame()
    assert len(df) == 300 * 4 and "magnitude [m/N]" in df


def _midspan_jeffcott(eta_v=0.0, loss=0.0, c_ext=0.0):
    light = Material("light", density=7850e-9, young_modulus=2.1e11, viscous_damping=eta_v, loss_factor=loss)
    L, D = 0.6, 0.02
    el = ShaftElement(L / 4, D, 0.0, light, shear=False)
    disk = Disk(0, 2, mass=10.0, diametral_inertia=0.0, polar_inertia=0.0)
    sys_ = RotorSystem(
        (Shaft((el,) * 4),),
        disks=(disk,),
        bearings=(Bearing(0, 0, kyy=1e12, kzz=1e12, kxx=1e9, ktt=1e6), Bearing(0, 4, kyy=1e12, kzz=1e12)),
        couplings=(Coupling(0, 2, c_lateral=c_ext),),
    )
    k = 48 * 2.1e11 * np.pi * D**4 / 64 / L**3
    return sys_, k, disk.mass


def test_internal_viscous_damping_instability_threshold():
    """Forward whirl damping changes sign at Ω_th = ω_n (1 + c_e/c_i), c_i = η_v k (the
    rotating damping force is η_v times the elastic force of the massless shaft). Bisection
    on the modal damping ratio; 1 % covers the pin springs and the bisection width."""
    eta_v, c_e = 2e-4, 50.0
    sys_, k, m = _midspan_jeffcott(eta_v=eta_v, c_ext=c_e)
    wn = np.sqrt(k / m)
    ref = wn * (1 + c_e / (eta_v * k))
    model = assemble(sys_)

    def forward_damping(speed):
        r = modal_analysis(model, speed=speed, n_modes=4)
        fwd = [i for i, w in enumerate(r.whirl) if w == "forward"]
        return r.damping_ratios[fwd[0]]

    lo, hi = 0.5 * ref, 2.0 * ref
    assert forward_damping(lo) > 0 > forward_damping(hi)
    for _ in range(30):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if forward_damping(mid) > 0 else (lo, mid)
    assert abs(lo / ref - 1) < 1e-2, (lo, ref)


def test_hysteretic_equals_viscous_at_the_whirl_frequency():
    """For a forward (backward) whirling excitation the rotating hysteretic loss factor η acts
    like rotating viscous damping η_v = η / |ω - Ω| (η / |ω + Ω|), below and above the spin
    speed (the definition of hysteretic damping in the rotating frame). Responses equal to
    1e-9 relative."""
    eta, speed = 0.02, 300.0
    sys_h, _, _ = _midspan_jeffcott(loss=eta)
    node = sys_h.dofs.node_dofs(0, 2)
    f_fwd = np.zeros(sys_h.n_dofs, complex)
    f_fwd[node[1]], f_fwd[node[2]] = 1.0, -1.0j
    f_bwd = np.conj(f_fwd)
    mh = assemble(sys_h)
    for w in (100.0, 250.0, 500.0, 900.0):
        for f, rel in ((f_fwd, abs(w - speed)), (f_bwd, abs(w + speed))):
            sys_v, _, _ = _midspan_jeffcott(eta_v=eta / rel)
            mv = assemble(sys_v)
            from scipy.sparse.linalg import spsolve

            qh = spsolve(mh.dynamic_stiffness(w, speed), f)
            qv = spsolve(mv.dynamic_stiffness(w, speed), f)
            assert np.linalg.norm(qh - qv) < 1e-9 * np.linalg.norm(qv)
