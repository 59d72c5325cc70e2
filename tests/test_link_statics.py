"""The static position of a journal on its bearing clearance under the mesh load and
gravity (issue 11, item 4): the mean problem of the link reduction (k = 0, solved by
damped Newton from the linear guess moved into contact) against a direct Newton solve of
the full FE statics K q + P g(Pᵀ q) = f, with the drive line's torsional rigid-body mode
held by the constraint Rᵀ M q = 0 (bordered system) — no reduction, no harmonics."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.links.contract import BearingClearance
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.rotor.assembly import assemble
from nlgrd.rotor.rigid_body import rigid_body_modes

TWO_SHAFT = Path(__file__).resolve().parents[1] / "data" / "models" / "two_shaft.toml"


def clearance_system(exponent: float):
    s = load_model(TWO_SHAFT)
    link = BearingClearance(
        "B1", 0, 8, clearance=20e-6, stiffness=1e10 if exponent == 1.5 else 5e7, exponent=exponent
    )
    return dataclasses.replace(
        s, bearings=tuple(b for i, b in enumerate(s.bearings) if i != 1), bearing_clearances=(link,)
    )


def full_static(system, gravity):
    """Newton on the full FE statics: clearance force pointwise, mesh in full contact."""
    lin = assemble(system, mesh_stiffness=False, mesh_damping=False)
    K, M = lin.K.toarray(), lin.M.toarray()
    n = K.shape[0]
    model = build_link_model(system, gravity=gravity)  # only for P, the loads, the laws
    rec = model.receptance
    P, f = rec.P, rec.static_force
    clear, mesh = model.links
    law = clear.law((0, 1))
    kh, b, e0 = mesh.mesh.stiffness, mesh.mesh.half_backlash, mesh.mesh.lste[0]
    R = rigid_body_modes(lin.K + rec.K_link, lin.M)
    r = R.shape[1]
    q = np.zeros(n)
    q += np.linalg.lstsq(K + P @ rec.k_link @ P.T, f, rcond=None)[0]
    u = P[:, :2].T @ q
    q += P[:, :2] @ (u * 20e-6 / np.linalg.norm(u))  # start in contact
    for _ in range(100):
        y = P.T @ q
        g = np.concatenate([law.force_at(y[:2, None])[:, 0], [kh * (y[2] - e0 - b)]])
        T = np.zeros((3, 3))
        T[:2, :2] = law.tangent_at(y[:2, None])[0]
        T[2, 2] = kh
        res = K @ q + P @ g - f
        if np.max(np.abs(res)) < 1e-11 * np.max(np.abs(f)):
            return y
        A = np.block([[K + P @ T @ P.T, M @ R], [(M @ R).T, np.zeros((r, r))]])
        q = q - np.linalg.solve(A, np.concatenate([res, R.T @ M @ q]))[:n]
    raise AssertionError("the full static Newton did not converge")


@pytest.mark.parametrize("exponent", [1.0, 1.5])
@pytest.mark.parametrize("gravity", [None, (-9.81, 0.0)])
def test_static_position_on_the_clearance_equals_the_full_static_solve(exponent, gravity):
    """The mean of the harmonic balance's first guess (its static state) equals the full
    static solution: journal (u_y, u_z) and mesh deflection δ to 1e-9 of the journal's
    radial displacement (two Newton solves to 1e-11 residual on matrices of condition
    ~1e6); the journal sits beyond its clearance (in contact)."""
    system = clearance_system(exponent)
    model = build_link_model(system, gravity=gravity)
    problem = model.reduced.at(2 * np.pi * 1000.0, 3)
    z = problem.linear_solution().reshape(3, -1)
    ref = full_static(system, gravity)
    r = float(np.hypot(ref[0], ref[1]))
    print(
        f"p = {exponent}, gravity {gravity}: journal at {1e6 * r:.3f} µm, "
        f"difference {np.max(np.abs(z[:, 0] - ref)) / r:.1e}"
    )
    assert r > 20e-6
    assert np.max(np.abs(z[:, 0] - ref)) <= 1e-9 * r, (z[:, 0], ref)


def test_a_mean_external_force_enters_like_a_static_load():
    """The reduction keeps Pᵀ K_r⁻¹ P and Pᵀ K_r⁻¹ f_s per speed and adds the links' own and
    the external mean forces by linearity: a constant force given as the mean harmonic of
    the external forces gives the same F_0 as the same force among the static loads, and
    both equal (Pᵀ K_r⁻¹ P)⁻¹ Pᵀ K_r⁻¹ f_0 from one bordered solve of the whole f_0
    (1e-10: the same factorisation, d = 3 coordinates)."""
    from nlgrd.nonlinear.reduction.link_reduction import LinkReceptance

    system = clearance_system(1.5)
    rec = build_link_model(system, gravity=(-9.81, 0.0)).receptance
    extra = np.zeros(system.n_dofs)
    extra[system.dofs.index(0, 4, "uy")] = -150.0
    extra[system.dofs.index(1, 3, "uz")] = 80.0
    H, w = 3, 2 * np.pi * 1000.0

    def mean_only(omega, H):
        f = np.zeros((H + 1, system.n_dofs), dtype=complex)
        f[0] = extra
        return f

    as_static = LinkReceptance(system, rec.links, rec.plan, rec.static_force + extra)
    as_mean = LinkReceptance(system, rec.links, rec.plan, rec.static_force, mean_only)
    kap, F = as_static.terms(w, H)
    kap2, F2 = as_mean.terms(w, H)
    d = rec.n_coords
    f0 = as_static.forces(w, H)[0].real
    x = as_static.mean.solve(0.0, np.column_stack([rec.P, f0]))
    ref = np.linalg.solve(rec.P.T @ x[:, :d], rec.P.T @ x[:, d])
    scale = np.max(np.abs(ref))
    assert np.max(np.abs(F[0] - ref)) <= 1e-10 * scale
    assert np.max(np.abs(F2[0] - ref)) <= 1e-10 * scale
    assert np.array_equal(kap[0], kap2[0])
    assert np.max(np.abs(F[0] - rec.terms(w, H)[1][0])) > 1e-3 * scale  # the load matters
