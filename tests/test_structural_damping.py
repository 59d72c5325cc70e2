"""The whole rotor's damping (model file ``[damping]``): Rayleigh damping and a modal floor.

Sources: for proportional damping C = α M + β K the undamped modes diagonalise C and each
complex pair is λ = -ζ ω ± i ω √(1 - ζ²) with ζ = α / (2 ω) + β ω / 2 exactly (Clough &
Penzien, Dynamics of Structures, 2003, §12.4, eq. 12-31); a modal damping matrix
M Φ diag(2 ζ_i ω_i) Φᵀ M gives each mode exactly ζ_i (same, §12.5). The damped modes come
from :func:`nlgrd.rotor.modal.modal_analysis` (first-order form, LAPACK eig), the
undamped ω from its real eigenproblem: two different solvers.

Tolerances: the shaft's axial bars put the largest eigenvalue ~1e8 times above the
lowest, so the low eigenvalues carry a rounding of ~1e-8 |λ|: the two bending planes'
frequencies, equal by symmetry, differ by up to 5e-8 relative (asserted below 1e-7). On a
ζ of 0.002 or more that is at most 5e-5 of ζ; ZETA_RTOL = 1e-4 covers it, while a wrong
formula (a factor 2, the ω of another mode, a floor leaking onto a mode above it) is off by
1e-2 or more.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from nlgrd import Bearing, Disk, Material, RotorSystem, Shaft, ShaftElement, assemble
from nlgrd.errors import ModelError
from nlgrd.io.model_file import load_model
from nlgrd.io.model_writer import save_model
from nlgrd.rotor.modal import modal_analysis
from nlgrd.rotor.rigid_body import rigid_body_modes
from nlgrd.rotor.structural_damping import StructuralDamping

STEEL = Material("steel", density=7850.0, young_modulus=2.1e11, poisson_ratio=0.3)
ZETA_RTOL = 1e-4
FREQ_RTOL = 1e-7


def _beam(damping: StructuralDamping | None = None, grounded: bool = False) -> RotorSystem:
    """A 0.6 m, 30 mm steel shaft on two undamped bearings with a disk: no damping of its
    own. Ungrounded it keeps two rigid-body modes (axial translation, free torsion)."""
    el = ShaftElement(0.05, 0.03, 0.0, STEEL)
    ground = {"kxx": 1e9, "ktt": 1e5} if grounded else {}
    return RotorSystem(
        (Shaft((el,) * 12),),
        disks=(Disk(0, 4, mass=3.0, diametral_inertia=4e-3, polar_inertia=8e-3),),
        bearings=(Bearing(0, 1, kyy=5e8, kzz=5e8, **ground), Bearing(0, 11, kyy=5e8, kzz=5e8)),
        damping=damping,
    )


def _low_modes(system: RotorSystem, n: int = 12):
    """Undamped ω [rad/s] and damped ζ of the n lowest flexible modes, paired by frequency."""
    und = modal_analysis(system, n_modes=n, damped=False)
    dmp = modal_analysis(system, n_modes=n, damped=True)
    omega = 2 * np.pi * und.natural_frequencies
    return omega, 2 * np.pi * dmp.natural_frequencies, dmp.damping_ratios


def test_rayleigh_damping_ratio_is_alpha_over_two_omega_plus_beta_omega_over_two():
    """ζ_i = α / (2 ω_i) + β ω_i / 2 for every low mode (Clough & Penzien eq. 12-31), with
    α and β chosen so that both terms matter (α: 2.5e-3 on mode 1; β: 0.48 on mode 12)."""
    alpha, beta = 30.0, 4e-6
    system = _beam(StructuralDamping(rayleigh_alpha=alpha, rayleigh_beta=beta), grounded=True)
    omega, omega_d, zeta = _low_modes(system)
    assert np.allclose(omega_d, omega, rtol=FREQ_RTOL)  # |λ| = ω: the modes are the undamped ones
    ref = alpha / (2 * omega) + beta * omega / 2
    assert ref.min() > 2e-3 and np.ptp(ref) > 0.01  # both terms visible
    assert np.max(np.abs(zeta / ref - 1)) < ZETA_RTOL


def test_modal_floor_gives_every_elastic_mode_the_floor_and_leaves_rigid_modes_free():
    """No other damping: C = C_F is a modal damping matrix, so every elastic mode has ζ = ζ_min
    exactly (Clough & Penzien §12.5), and the two rigid-body modes (axial, torsional) stay
    undamped: C_F R = 0 to rounding (1e-12 of ‖C_F‖ ‖R‖; a floor leaking onto them would be
    ~1)."""
    floor = 0.02
    system = _beam(StructuralDamping(modal_floor=floor))
    model = assemble(system)
    R = rigid_body_modes(model.K, model.M)
    assert R.shape[1] == 2
    C = model.C.toarray()
    assert np.linalg.norm(C @ R) < 1e-12 * np.linalg.norm(C) * np.linalg.norm(R)
    omega, omega_d, zeta = _low_modes(system, n=20)
    assert np.allclose(omega_d, omega, rtol=FREQ_RTOL)
    assert np.max(np.abs(zeta / floor - 1)) < ZETA_RTOL
    assert modal_analysis(system, n_modes=4).n_rigid_body == 2


def test_modal_floor_leaves_a_mode_already_above_it_unchanged():
    """α M alone gives ζ = α / (2 ω), above a floor of 0.01 on the first modes only; the floor
    keeps those exactly (α / 2ω) and lifts the rest exactly to 0.01 (C + C_F stays modal)."""
    alpha, floor = 60.0, 0.01
    system = _beam(StructuralDamping(modal_floor=floor, rayleigh_alpha=alpha), grounded=True)
    omega, _, zeta = _low_modes(system, n=12)
    own = alpha / (2 * omega)
    above = own > floor
    assert 0 < above.sum() < len(own)  # both kinds present
    ref = np.where(above, own, floor)
    assert np.max(np.abs(zeta / ref - 1)) < ZETA_RTOL


def test_the_same_damping_reaches_every_analysis():
    """The matrix added does not depend on which mesh terms an analysis assembles (the
    harmonic balance leaves k_h and c_m out, modal analysis keeps them): C with and without
    the option differ by one matrix in all four assemblies of Kahraman & Blankenship's rig."""
    kb = load_model("data/case_studies/kahraman_blankenship.toml")
    floored = dataclasses.replace(kb, damping=StructuralDamping(modal_floor=0.01, rayleigh_beta=1e-7))
    added = []
    for flags in ((True, True), (False, True), (False, False), (True, False)):
        added.append((assemble(floored, *flags).C - assemble(kb, *flags).C).toarray())
    scale = np.abs(added[0]).max()
    assert scale > 0
    for a in added[1:]:
        assert np.abs(a - added[0]).max() <= 1e-12 * scale


def test_kb_weak_mode_is_lifted_to_the_floor():
    """Kahraman & Blankenship's rig as given has a mode near 741 Hz damped at ζ ≈ 1.75e-4
    (bearing damping only; the issue's independent check). With a 0.01 floor its ζ is
    0.01 within 2 %: the rest of C (bearings, mesh) is not modal, so the floor is exact only
    on the modal projection; the mode's frequency stays within 0.1 %."""
    kb = load_model("data/case_studies/kahraman_blankenship.toml")
    bare = modal_analysis(kb, n_modes=4)
    i = int(np.argmin(np.abs(bare.natural_frequencies - 741.0)))
    assert abs(bare.natural_frequencies[i] - 741.0) < 1
    assert bare.damping_ratios[i] == pytest.approx(1.75e-4, rel=0.01)
    fl = modal_analysis(dataclasses.replace(kb, damping=StructuralDamping(modal_floor=0.01)), n_modes=4)
    j = int(np.argmin(np.abs(fl.natural_frequencies - bare.natural_frequencies[i])))
    assert abs(fl.natural_frequencies[j] / bare.natural_frequencies[i] - 1) < 1e-3
    assert abs(fl.damping_ratios[j] / 0.01 - 1) < 0.02


def test_round_trip_through_the_model_writer(tmp_path):
    """save_model writes the [damping] table and load_model reads the same system back:
    equal options and the same assembled C to rounding."""
    kb = load_model("data/case_studies/kahraman_blankenship.toml")
    sys_ = dataclasses.replace(kb, damping=StructuralDamping(modal_floor=0.015, rayleigh_alpha=2.5))
    path = tmp_path / "kb.toml"
    save_model(sys_, path)
    assert "[damping]" in path.read_text()
    back = load_model(path)
    assert back.damping == sys_.damping
    a, b = assemble(sys_).C.toarray(), assemble(back).C.toarray()
    assert np.abs(a - b).max() <= 1e-12 * np.abs(a).max()


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"modal_floor": -0.01}, "modal_floor"),
        ({"modal_floor": 1.0}, "modal_floor"),
        ({"rayleigh_alpha": float("nan")}, "rayleigh_alpha"),
        ({"rayleigh_beta": -1e-6}, "rayleigh_beta"),
    ],
)
def test_bad_values_name_their_key(kwargs, key):
    with pytest.raises(ModelError) as err:
        StructuralDamping(**kwargs)
    assert err.value.key == key
