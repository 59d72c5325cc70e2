"""The direct receptances by banded LU of the link-free dynamic stiffness and the
Sherman-Morrison-Woodbury identity (nlgrd.nonlinear.reduction.direct_receptance), as the
link reduction's ``"banded"`` strategy builds them (``LinkReceptance._band_solver``).

Independent reference: dense solves (numpy/LAPACK ``gesv``) of the whole dynamic
stiffness Z_k with the links' damping in it, assembled by the model; and central finite
differences of h_k(ω) for dh_k/dω. Both direct paths are exact up to rounding, so the
tolerances are rounding bounds: Z_k's condition number here is below about 1e5, and
1e-10 relative leaves a margin of 10^6 over double precision times that. The finite
differences (4th order, step 3e-7 ω) are accurate to about 1e-8."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.nonlinear.reduction import direct_receptance as dr

MODELS = Path(__file__).resolve().parents[1] / "data" / "models"


class Banded:
    """The link reduction's banded solver of ``system`` with output DOFs ``out``: its h_k,
    Z_k⁻¹ P at ``out`` and dh_k/dω for k = 1..H (``solve``), and the dense reference."""

    def __init__(self, system, out=()):
        self.rec = build_link_model(system, method="banded").receptance
        self.out = np.asarray(out, dtype=int)
        self.solver = self.rec._band_solver(tuple(int(i) for i in self.out))

    def solve(self, omega: float, H: int, derivative: bool = False):
        return self.solver.solve(np.arange(1, H + 1), omega, derivative)

    def speed(self, omega: float) -> float:
        return self.rec.plan.speed(omega)


def dense(b: Banded, omega: float, H: int):
    """(h_k, Z_k⁻¹ P at the output DOFs), k = 1..H, by dense solves of the whole Z_k."""
    rec, hs, us = b.rec, [], []
    P = rec.P.astype(complex)
    for k in range(1, H + 1):
        Z = rec.model.dynamic_stiffness(k * omega, b.speed(omega)).toarray()
        Z = Z + 1j * k * omega * rec.C_link.toarray()
        X = sla.solve(Z, P)
        hs.append(P.T @ X)
        us.append(X[b.out])
    return np.array(hs), np.array(us)


def rel(a, b) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def undamped_mode_near(b: Banded, hz: float) -> float:
    """The natural frequency [rad/s] nearest ``hz`` of the model without the links (the
    band's Z') whose mode no damping but the links' reaches (φᵀ C φ = 0 to rounding)."""
    d = b.solver
    bare, keep = d.bare.model, d.keep
    K = bare.K.toarray()[np.ix_(keep, keep)]
    M = bare.M.toarray()[np.ix_(keep, keep)]
    C = (bare.C + bare.Ci).toarray()[np.ix_(keep, keep)]
    lam, V = sla.eigh(K, M)
    undamped = [
        np.sqrt(v) for v, x in zip(lam, V.T, strict=True) if v > 1.0 and abs(x @ C @ x) < 1e-12 * np.sqrt(v)
    ]
    return float(min(undamped, key=lambda x: abs(x - 2 * np.pi * hz)))


@pytest.mark.parametrize("name", ["two_shaft.toml", "idler_train.toml"])
def test_band_solves_equal_dense_solves_of_the_whole_model(name):
    """One mesh (two_shaft) and two (idler_train, the 2 x 2 Woodbury step): the band path
    is taken (half bandwidth far below Z's own) and gives h_k, the output responses and
    dh_k/dω of the dense solves and of finite differences."""
    system = load_model(MODELS / name)
    mr = Banded(system, np.arange(0, system.n_dofs, 5))
    d = mr.solver
    assert d.banded and d.band.half_width <= 12
    for f in (317.0, 2513.0, 5207.0):
        om = 2 * np.pi * f
        h, U, dh = mr.solve(om, 4, derivative=True)
        hr, Ur = dense(mr, om, 4)
        assert rel(h, hr) < 1e-10 and rel(U, Ur) < 1e-10
        eps = 3e-7 * om
        r = [mr.solve(om + j * eps, 4)[0] for j in (-2, -1, 1, 2)]
        fd = (r[0] - 8 * r[1] + 8 * r[2] - r[3]) / (12 * eps)
        assert rel(dh, fd) < 1e-6
    assert d.n_sparse == 0 and d.n_band > 0


def test_band_and_sparse_paths_agree(monkeypatch):
    """BAND_LIMIT below every band: sparse LU of Z (the path before the band) gives the same
    h_k, responses and derivatives to rounding."""
    system = load_model(MODELS / "idler_train.toml")
    out = np.arange(0, system.n_dofs, 7)
    band = Banded(system, out)
    assert band.solver.banded  # built before the limit is lowered
    monkeypatch.setattr(dr, "BAND_LIMIT", -1)
    sparse = Banded(system, out)
    assert not sparse.solver.banded
    for om in 2 * np.pi * np.array([450.0, 1800.0, 4100.0]):
        got, ref = band.solve(om, 5, derivative=True), sparse.solve(om, 5, derivative=True)
        for x, y in zip(got, ref, strict=True):
            assert rel(x, y) < 1e-10
    assert sparse.solver.n_band == 0


def test_mode_only_the_mesh_damps():
    """two_shaft's gear shaft twists without damping but the mesh's: Z' is singular to
    rounding at that mode's frequency (1406 Hz, found here from K and M), Z is not. With one
    mesh the identity keeps the band path as accurate as a solve of Z."""
    system = load_model(MODELS / "two_shaft.toml")
    mr = Banded(system)
    d = mr.solver
    w = undamped_mode_near(mr, 1406.0)
    assert abs(w / (2 * np.pi) - 1406.4) < 1.0
    keep = d.keep
    Zb = d.bare.model.dynamic_stiffness(w, mr.speed(w)).toarray()[np.ix_(keep, keep)]
    assert 1 / np.linalg.cond(Zb) < 1e-12  # Z' singular to rounding
    h, _, dh = mr.solve(w, 1, derivative=True)
    hr, _ = dense(mr, w, 1)
    assert rel(h, hr) < 1e-10
    assert d.n_band == 1 and d.n_sparse == 0


def test_speed_tabulated_bearings_take_the_model_data_path(monkeypatch):
    """With a bearing tabulated against speed the band's non-zeros come from the model per
    frequency (no precomputed parts): the band path still equals sparse LU of Z and dense
    solves, h_k, responses and dh_k/dω (both hold the tabulated coefficients at the current
    speed in dh/dω, and keep the i kω of its damping)."""
    import dataclasses

    system = load_model(MODELS / "two_shaft.toml")
    b = system.bearings[0]
    tab = dataclasses.replace(
        b, kyy=(b.kyy, 1.3 * b.kyy), kzz=(b.kzz, 1.2 * b.kzz), cyy=(b.cyy, 2 * b.cyy), speeds=(0.0, 1e3)
    )
    system = dataclasses.replace(system, bearings=(tab, *system.bearings[1:]))
    out = np.arange(0, system.n_dofs, 9)
    band = Banded(system, out)
    assert band.solver.banded and band.solver._parts is None
    monkeypatch.setattr(dr, "BAND_LIMIT", -1)
    sparse = Banded(system, out)
    for om in 2 * np.pi * np.array([700.0, 2500.0, 4800.0]):
        got, ref = band.solve(om, 4, derivative=True), sparse.solve(om, 4, derivative=True)
        for x, y in zip(got, ref, strict=True):
            assert rel(x, y) < 1e-10
        hr, Ur = dense(band, om, 4)
        assert rel(got[0], hr) < 1e-10 and rel(got[1], Ur) < 1e-10


@pytest.mark.parametrize("banded", [True, False])
def test_speed_tabulated_bearing_derivative_keeps_its_damping(monkeypatch, banded):
    """A bearing "tabulated" with the same coefficients at every speed is the plain bearing:
    dh_k/dω must equal the finite differences of h_k, the i k C_b term of its damping
    included (it was left out before 2026-12-05: 5.7e-3 off at 317 Hz)."""
    import dataclasses

    if not banded:
        monkeypatch.setattr(dr, "BAND_LIMIT", -1)
    system = load_model(MODELS / "two_shaft.toml")
    b = system.bearings[0]
    tab = dataclasses.replace(
        b, kyy=(b.kyy, b.kyy), kzz=(b.kzz, b.kzz), cyy=(b.cyy, b.cyy), czz=(b.czz, b.czz), speeds=(0.0, 1e4)
    )
    system = dataclasses.replace(system, bearings=(tab, *system.bearings[1:]))
    mr = Banded(system)
    assert mr.solver.banded == banded
    for f in (317.0, 2513.0):
        om = 2 * np.pi * f
        dh = mr.solve(om, 3, derivative=True)[2]
        eps = 3e-7 * om
        r = [mr.solve(om + j * eps, 3)[0] for j in (-2, -1, 1, 2)]
        fd = (r[0] - 8 * r[1] + 8 * r[2] - r[3]) / (12 * eps)
        assert rel(dh, fd) < 1e-6


def test_two_meshes_near_a_mode_only_the_meshes_damp():
    """The idler train near a mode of its shafts that only the mesh damping reaches: the
    2 x 2 Woodbury step is ill-conditioned there (its rounding in dh/dω grows as the square
    of cond(I + D h')), so the solver hands such harmonics to sparse LU of Z. h_k within
    1e-9 of dense solves and dh_k/dω within 1e-6 of finite differences at 1e-4 .. 1e-6 from
    the mode (the band path alone gave 2e-5 at cond 2e5)."""
    system = load_model(MODELS / "idler_train.toml")
    mr = Banded(system)
    d = mr.solver
    w0 = undamped_mode_near(mr, 3905.0)
    assert abs(w0 / (2 * np.pi) - 3905.0) < 5.0
    for off in (1e-4, 1e-5, 1e-6):
        om = w0 * (1 + off)
        h, _, dh = mr.solve(om, 1, derivative=True)
        hr, _ = dense(mr, om, 1)
        assert rel(h, hr) < 1e-9
        eps = 3e-7 * om
        r = [dense(mr, om + j * eps, 1)[0] for j in (-2, -1, 1, 2)]
        fd = (r[0] - 8 * r[1] + 8 * r[2] - r[3]) / (12 * eps)
        assert rel(dh, fd) < 1e-6
    assert d.n_sparse > 0


def test_no_dof_reached_gives_zero_receptances():
    """A link that reaches no DOF (its projection zeroed): h_k = 0, no error."""
    import dataclasses

    system = load_model(MODELS / "two_shaft.toml")
    rec = build_link_model(system, method="banded").receptance
    m = rec.model
    full = dataclasses.replace(m, C=(m.C + rec.C_link).tocsc())
    W, none = np.zeros_like(rec.P), np.zeros(0, dtype=int)
    keep = dr.coupled_dofs(full, W, none)
    solver = dr.DirectSolver(full, m, W, rec.c_link, keep, none, rec.plan.speed_per_base)
    h, U, dh = solver.solve(np.arange(1, 4), 2 * np.pi * 1000.0, True)
    assert not np.any(h) and not np.any(dh) and U.shape[0] == 3
