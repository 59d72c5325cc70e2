"""Receptance reduction onto the mesh coordinate against full-model solves.

Independent references: dense solves of the full dynamic stiffness (numpy.linalg), and
statics of a drive train whose only torsional support is the mesh (the mean mesh force
must equal the static load W_0 = T_p / r_bp).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.reduction.receptance import MeshReceptance

MODEL = Path(__file__).resolve().parent.parent / "data" / "models" / "two_shaft.toml"


def dense_reference(system, omega: float, H: int):
    """h_k = Wᵀ Z_k⁻¹ W, k = 1..H, by dense solves of the full dynamic stiffness (numpy)."""
    mr = MeshReceptance(system, method="direct")
    Zs = [mr.model.dynamic_stiffness(k * omega, mr.speed(omega)).toarray() for k in range(1, H + 1)]
    return np.array([mr.W.T @ sla.solve(Z, mr.W) for Z in Zs])


@pytest.fixture(scope="module")
def system():
    return load_model(MODEL)


def test_direct_equals_dense_solve(system):
    """Sparse-LU receptances equal dense solves to 1e-10 relative (both exact)."""
    mr = MeshReceptance(system, method="direct")
    for f in (300.0, 2500.0, 5200.0):
        om = 2 * np.pi * f
        h = mr.receptance(om, 5)
        ref = dense_reference(system, om, 5)
        assert np.max(np.abs(h - ref) / np.abs(ref)) < 1e-10


def test_modal_basis_matches_direct_in_band(system):
    """Modal basis with modes to 1.5x the top excitation frequency plus attachment vectors:
    h_k within 1e-3 relative of the direct receptance over the whole band (modal
    truncation with static and dynamic residual vectors; the residual error scales with
    (ω / ω_cut)², about 1e-1 at the top without the attachment vectors)."""
    top = 2 * np.pi * 6000.0
    H = 3
    direct = MeshReceptance(system, method="direct")
    modal = MeshReceptance(system, method="modal", max_frequency=H * top, cutoff_factor=1.5)
    assert modal.basis.shape[1] < system.n_dofs
    worst = 0.0
    for om in np.linspace(2 * np.pi * 200, top, 25):
        worst = max(worst, np.max(np.abs(modal.receptance(om, H) / direct.receptance(om, H) - 1)))
    assert worst < 1e-3, worst


def test_mean_of_free_drive_train_is_the_static_load(system):
    """The example's drive train is held in torsion only by the mesh: κ_0 = 0 (to 1e-9
    k_h) and F_0 = W_0 = T_p / r_bp to 1e-9 relative."""
    mr = MeshReceptance(system)
    mt = mr.mean_terms(0.0)
    W0 = system.gear_pairs[0].static_load
    assert abs(mt.kappa[0, 0]) < 1e-9 * mr.k_h[0]
    assert abs(mt.force[0] / W0 - 1) < 1e-9


def test_recovered_mean_deflection_matches_linear_static(system):
    """With the mesh in full contact (G_0 = k_h (Y_0 - b)), the recovered mean deflection of
    every DOF equals the linear static solution of the full model with the mesh spring
    preloaded by b, to 1e-9 relative."""
    from nlgrd.rotor.assembly import assemble
    from nlgrd.rotor.frequency_response import static_deflection

    mr = MeshReceptance(system)
    mesh = system.gear_pairs[0]
    b = mesh.half_backlash
    kh = mr.k_h[0]
    mt = mr.mean_terms(0.0)
    # mean equation κ0 Y0 + k_h (Y0 - b) = F0
    Y0 = (mt.force[0] + kh * b) / (mt.kappa[0, 0] + kh)
    G0 = kh * (Y0 - b)
    dofs = np.arange(system.n_dofs)
    Q = mr.recover(0.0, np.array([[Y0]]), np.array([[G0]]), np.array([[mt.force[0]]]), dofs)
    full = assemble(system)
    f = mesh.static_torques(system) + kh * b * mr.W[:, 0]
    ref = static_deflection(full, f).q
    # both are determined up to the free rolling motion only through the mesh: compare δ and
    # deflections relative to it
    assert abs(mr.W[:, 0] @ Q[0].real - mr.W[:, 0] @ ref) < 1e-9 * abs(mr.W[:, 0] @ ref)
    lateral = system.dofs.kind_mask("lateral")
    assert np.max(np.abs(Q[0].real[lateral] - ref[lateral])) < 1e-9 * np.max(np.abs(ref[lateral]))


def test_pole_residue_form_equals_direct_solves(system):
    """Modal method (pole-residue form): with the modal basis spanning the whole model
    (132 DOFs, modes to 3 x the top excitation frequency cover them all), h_k, the
    recovered output DOFs and dh_k/dω equal the direct sparse-LU results to 1e-6
    relative (the eigenvector matrix of the companion form is not orthogonal; the observed
    agreement is 5e-10). dh_k/dω is also checked against a fourth-order central finite
    difference of the direct receptance (step 3e-7 ω: a sharp mode near 30 kHz needs it;
    agreement 1e-9, rounding ~3e-10)."""
    top = 2 * np.pi * 6000.0
    H = 5
    direct = MeshReceptance(system, method="direct")
    modal = MeshReceptance(system, method="modal", max_frequency=H * top)
    assert modal.basis.shape[1] >= system.n_dofs - 2
    dofs = np.arange(0, system.n_dofs, 7)
    direct.set_output_dofs(dofs)
    modal.set_output_dofs(dofs)
    for om in 2 * np.pi * np.array([700.0, 2300.0, 4100.0, 6000.0]):
        hd, Ud, dd = direct._solve(om, H, derivative=True)
        hm, Um, dm = modal._solve(om, H, derivative=True)
        assert np.max(np.abs(hm - hd) / np.abs(hd)) < 1e-6
        assert np.max(np.abs(Um - Ud)) < 1e-6 * np.max(np.abs(Ud))
        assert np.max(np.abs(dm - dd) / np.abs(dd)) < 1e-6
        eps = 3e-7 * om
        r = [direct.receptance(om + j * eps, H) for j in (-2, -1, 1, 2)]
        fd = (r[0] - 8 * r[1] + 8 * r[2] - r[3]) / (12 * eps)
        assert np.max(np.abs(dd - fd) / np.abs(fd)) < 1e-6


def test_direct_solves_only_the_components_that_reach_the_mesh(system):
    """The direct method leaves out DOFs whose sparsity-graph component holds neither a
    mesh nor an output DOF (here the axial bars); the result is still the dense solve of
    the whole model (test_direct_equals_dense_solve), and the dropped DOFs are exactly
    those decoupled from every mesh DOF in Z."""
    import scipy.sparse.csgraph as csg

    mr = MeshReceptance(system, method="direct")
    keep = mr._direct().keep
    assert 0 < len(keep) < system.n_dofs
    Z = abs(mr.model.dynamic_stiffness(2 * np.pi * 1000.0, 10.0))
    dist = csg.shortest_path(Z, unweighted=True, indices=np.flatnonzero(mr.W[:, 0]))
    reachable = np.flatnonzero(np.isfinite(dist).any(axis=0))
    np.testing.assert_array_equal(np.sort(keep), reachable)


@pytest.mark.parametrize(
    "path",
    [
        "data/case_studies/kubo.toml",
        "data/case_studies/kahraman_blankenship.toml",
        "data/models/two_shaft.toml",
        "data/models/idler_train.toml",
    ],
)
def test_default_pole_form_of_the_whole_model_equals_dense_solves(path):
    """The default for small models ("poles": the shifted pole-residue form of the part
    of the model a mesh reaches, rigid-body modes that move no mesh left out; also
    asked for on the larger shipped models, at H = 6) against dense solves of the full
    dynamic stiffness (dense_reference) at H = 25, from 0.2 to 3 x the gear-pair
    frequencies of the shipped models, and its dh_k/dω (at 2300 Hz) against a
    fourth-order central difference of those dense solves. 1e-7 relative: the form is exact but for rounding
    in the companion eigenvectors (2e-9 seen on Kubo's rig, whose eigenvector matrix is
    the worst conditioned) and its check admits 1e-8 per harmonic; a missing shift or a
    wrong back-transformation errs at O(1)."""
    system = load_model(Path(__file__).resolve().parent.parent / path)
    mr = MeshReceptance(system, method="poles")
    small = len(mr._mesh_component()) <= 100  # the default for Kubo's and K & B's rigs
    assert MeshReceptance(system).method == ("poles" if small else "direct")
    H = 25 if small else 6
    dofs = np.arange(0, system.n_dofs, 5)
    mr.set_output_dofs(dofs)
    for f in (700.0, 2300.0, 4100.0, 9000.0):
        om = 2 * np.pi * f
        h, U, dh = mr._solve(om, H, derivative=True)
        ref = dense_reference(system, om, H)
        assert np.max(np.abs(h - ref) / np.abs(ref)) < 1e-7
        if f != 2300.0:
            continue
        eps = 1e-6 * om
        r = [dense_reference(system, om + j * eps, H) for j in (-2, -1, 1, 2)]
        fd = (r[0] - 8 * r[1] + 8 * r[2] - r[3]) / (12 * eps)
        assert np.max(np.abs(dh - fd)) < 1e-5 * np.max(np.abs(fd), axis=(1, 2), keepdims=True).max()
    direct = MeshReceptance(system, method="direct")
    direct.set_output_dofs(dofs)
    Ud = direct._solve(2 * np.pi * 9000.0, H)[1]
    U = mr._solve(2 * np.pi * 9000.0, H)[1]
    assert np.max(np.abs(U - Ud)) < 1e-7 * np.max(np.abs(Ud))
    assert max(mr.pole_check.values()) < 1e-8 and all(mr._poles[k] is not None for k in range(1, H + 1))
