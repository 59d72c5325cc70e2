"""Decisions of rank type do not depend on what differs between machines.

What a different CPU or BLAS kernel changes is rounding: the order of summation, the
last bits of every product. These tests make that difference on purpose and many
orders of magnitude larger (DOFs permuted, matrices scaled by 1e±6, relative
perturbations of 1e-13, one or two BLAS threads) and require the same decisions:
the rigid-body modes (count and subspace), the balanced-load verdict, and along a
sweep the convergence, contact state, Floquet verdict and branch of every point.

Independent reference for the rigid-body count: the model's topology. A shaft train
(shafts joined by meshes and torsional couplings) with no torsional ground has one
free rotation; every shipped model is supported laterally and axially.
"""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
from test_geared_time_domain import refined_kubo
from threadpoolctl import threadpool_limits

from nlgrd.errors import ModelError
from nlgrd.io.model_file import load_model
from nlgrd.rotor.assembly import LinearModel, assemble
from nlgrd.rotor.modal import modal_analysis
from nlgrd.rotor.rigid_body import check_balanced, rigid_body_modes

DATA = Path(__file__).resolve().parent.parent / "data"
MODELS = sorted(p for p in DATA.glob("**/*.toml") if p.parent.name != "studies")  # study files are not models


def free_rotations(system) -> int:
    """Rigid-body modes from the topology alone: torsionally ungrounded shaft trains
    (union-find) and :func:`lateral_pivots`."""
    parent = list(range(len(system.shafts)))

    def root(i):
        while parent[i] != i:
            i = parent[i]
        return i

    grounded = set()
    for c in system.couplings:
        if c.k_torsion > 0:
            if c.grounded:
                grounded.add(c.shaft_a)
            else:
                parent[root(c.shaft_a)] = root(c.shaft_b)
    for g in system.gear_pairs:
        parent[root(g.pinion_shaft)] = root(g.gear_shaft)
    for b in system.bearings:
        if b.ktt > 0:
            grounded.add(b.shaft)
    grounded_roots = {root(s) for s in grounded}
    return len({root(s) for s in range(len(system.shafts))} - grounded_roots) + lateral_pivots(system)


def lateral_pivots(system) -> int:
    """Lateral rigid-body modes, from the topology: a shaft held laterally at one node only
    (its other bearing a clearance, which a linear analysis leaves out: no stiffness at
    rest) pivots about it in both planes, 2 modes (a gear mesh ties one combination of
    them to the drive train's rotation, it does not remove one). Shafts held at two
    nodes or more by bearings or lateral couplings have none."""
    held: dict[int, set] = {i: set() for i in range(len(system.shafts))}
    for b in system.bearings:
        held[b.shaft].add(b.node)
    for c in system.couplings:
        if c.k_lateral > 0 and c.shaft_b is None:
            held[c.shaft_a].add(c.node_a)
    return sum(2 for nodes in held.values() if len(nodes) == 1)


def _systems():
    out = [(p.stem, load_model(p)) for p in MODELS]
    out.append(("kubo refined", refined_kubo()))
    return out


SYSTEMS = _systems()


def _relative_perturbation(A, rng, eps=1e-13):
    """A + eps * (A ∘ X), X uniform in [-1, 1], symmetric, on A's sparsity pattern."""
    A = sp.csc_matrix(A)
    X = sp.csc_matrix((rng.uniform(-1, 1, A.nnz), A.indices, A.indptr), shape=A.shape)
    X = (X + X.T) / 2
    return (A + eps * A.multiply(X)).tocsc()


def _same_subspace(R, R0, M0):
    """Largest distance of span(R) from span(R0) (R0 M0-orthonormal), relative."""
    if R.shape[1] != R0.shape[1]:
        return np.inf
    if R.shape[1] == 0:
        return 0.0
    proj = R0 @ (R0.T @ (M0 @ R))
    return np.linalg.norm(R - proj) / np.linalg.norm(R)


@pytest.mark.parametrize("name, system", SYSTEMS, ids=[s[0] for s in SYSTEMS])
def test_rigid_body_modes_survive_permutation_scaling_and_perturbation(name, system):
    """Same rigid-body count (= the topology's free rotations) and subspace (to 1e-8:
    the null vectors are exact to ~1e-13 and the rest of the spectrum lies >= 1e5 x
    higher on the scaled stiffness) under: DOFs permuted, K and M scaled by 1e6 and
    1e-6 (together and K alone), relative perturbations of 1e-13 of K and M."""
    lm = assemble(system)
    K, M = lm.K.tocsc(), lm.M.tocsc()
    expected = free_rotations(system)
    R0 = rigid_body_modes(K, M)
    assert R0.shape[1] == expected
    rng = np.random.default_rng(7)
    n = K.shape[0]
    p = rng.permutation(n)
    inv = np.argsort(p)
    variants = {
        "permuted": (K[p][:, p], M[p][:, p], lambda R: R[inv]),
        "scaled 1e6": (1e6 * K, 1e6 * M, lambda R: R * 1e3),
        "scaled 1e-6": (1e-6 * K, 1e-6 * M, lambda R: R * 1e-3),
        "K scaled 1e6": (1e6 * K, M, lambda R: R),
    }
    for i in range(3):
        variants[f"perturbed {i}"] = (_relative_perturbation(K, rng), _relative_perturbation(M, rng), None)
    for label, (Kv, Mv, back) in variants.items():
        R = rigid_body_modes(Kv, Mv)
        assert R.shape[1] == expected, label
        R = back(R) if back else R
        assert _same_subspace(R, R0, M) < 1e-8, label


@pytest.mark.parametrize("name, system", SYSTEMS, ids=[s[0] for s in SYSTEMS])
def test_rigid_body_mode_survives_projection_onto_a_modal_basis(name, system):
    """K and M projected onto their 12 lowest modes (as the stability basis does): the
    free rotation's diagonal entry is then rounding noise (~1e-15 of the largest, any
    sign) and must count as zero stiffness, not be Jacobi-scaled up to look stiff.
    Reference: the topology's count of free rotations."""
    lm = assemble(system)
    K, M = lm.K.toarray(), lm.M.toarray()
    _, Phi = sla.eigh(K, M, subset_by_index=[0, 11])
    Kr, Mr = Phi.T @ K @ Phi, Phi.T @ M @ Phi
    R = rigid_body_modes((Kr + Kr.T) / 2, (Mr + Mr.T) / 2)
    assert R.shape[1] == free_rotations(system)
    assert abs(np.diag(Kr)[0]) < 1e-12 * np.abs(np.diag(Kr)).max()  # the case is the noisy one


@pytest.mark.parametrize("name, system", SYSTEMS, ids=[s[0] for s in SYSTEMS])
def test_modal_analysis_and_balance_verdict_survive_perturbation(name, system):
    """The modes listed (count of rigid-body modes, 8 lowest damped frequencies to 1e-6
    relative: (near-)double eigenvalues of the non-normal gyroscopic pencil move by
    ~sqrt(1e-13) = 3e-7 under a 1e-13 perturbation, simple ones by ~1e-13; or to the
    eigensolver's accuracy ~1e3 ε λ_max / ω² where that is larger) and the
    balanced-load verdict on the static torques are the same for the model and for its
    permuted and 1e-13-perturbed copies; an imbalance of 1e-6 of the torque on a free
    train is still rejected."""
    lm = assemble(system)
    rng = np.random.default_rng(11)
    n = lm.n_dofs
    p = rng.permutation(n)
    base = LinearModel.from_matrices(lm.M, lm.K, lm.C, lm.G)
    copies = [
        LinearModel.from_matrices(lm.M[p][:, p], lm.K[p][:, p], lm.C[p][:, p], lm.G[p][:, p]),
        LinearModel.from_matrices(
            _relative_perturbation(lm.M, rng),
            _relative_perturbation(lm.K, rng),
            _relative_perturbation(lm.C, rng) if lm.C.nnz else lm.C,
            lm.G,
        ),
    ]
    ref = modal_analysis(base, speed=300.0, n_modes=8)
    # a backward-stable eigensolver perturbs ω² by ~ε λ_max (absolute): δω/ω ~ ε λ_max / ω²,
    # with a factor up to ~1e3 for the non-normal first-order form; Kubo's axial bars reach
    # λ_max ~ 8e15 (rad/s)², which bounds its 565 Hz mode at 1.4e-4 (seen: 3.6e-6)
    lam_max = sla.eigh(lm.K.toarray(), lm.M.toarray(), eigvals_only=True, subset_by_index=[n - 1, n - 1])[0]
    w = 2 * np.pi * ref.damped_frequencies
    rtol = np.maximum(1e-6, 1e3 * np.finfo(float).eps * lam_max / w**2)
    assert ref.n_rigid_body == free_rotations(system)
    assert np.all(ref.natural_frequencies > 1.0)  # no pseudo-mode of the free rotation
    for c in copies:
        res = modal_analysis(c, speed=300.0, n_modes=8)
        assert res.n_rigid_body == ref.n_rigid_body
        err = np.abs(res.damped_frequencies - ref.damped_frequencies) / ref.damped_frequencies
        assert np.all(err <= rtol), (err, rtol)
    if system.gear_pairs and ref.n_rigid_body and lateral_pivots(system):
        # the mesh load pushes a shaft that pivots in the linear model (its clearance holds
        # it only in contact): rejected by the linear balance check, on every copy
        f = sum(g.static_torques(system) for g in system.gear_pairs)
        for model, load in zip((base, *copies), (f, f[p], f), strict=True):
            with pytest.raises(ModelError, match="not balanced"):
                check_balanced(rigid_body_modes(model.K, model.M), load, "torque")
    elif system.gear_pairs and ref.n_rigid_body:
        f = sum(g.static_torques(system) for g in system.gear_pairs)
        R = rigid_body_modes(lm.K, lm.M)
        check_balanced(R, f * (1 + 1e-13 * rng.uniform(-1, 1, n)), "torque")
        unbalanced = f.copy()
        unbalanced[np.argmax(np.abs(f))] *= 1 + 1e-6
        with pytest.raises(ModelError, match="not balanced"):
            check_balanced(R, unbalanced, "torque")


def _permute_shafts(system, order):
    """The same physical model with its shafts listed in ``order`` (DOFs permuted)."""
    new = {old: i for i, old in enumerate(order)}
    gp = tuple(
        dc.replace(g, pinion_shaft=new[g.pinion_shaft], gear_shaft=new[g.gear_shaft])
        for g in system.gear_pairs
    )
    return dc.replace(
        system,
        shafts=tuple(system.shafts[i] for i in order),
        disks=tuple(dc.replace(d, shaft=new[d.shaft]) for d in system.disks),
        bearings=tuple(dc.replace(b, shaft=new[b.shaft]) for b in system.bearings),
        couplings=tuple(
            dc.replace(c, shaft_a=new[c.shaft_a], shaft_b=None if c.shaft_b is None else new[c.shaft_b])
            for c in system.couplings
        ),
        gear_pairs=gp,
    )


def _perturb_system(system, rng, eps=1e-13):
    """Material, bearing and torque values changed by relative amounts of eps."""

    def r():
        return 1 + eps * rng.uniform(-1, 1)

    def element(e):
        mat = dc.replace(
            e.material, density=e.material.density * r(), young_modulus=e.material.young_modulus * r()
        )
        return dc.replace(e, material=mat)

    shafts = tuple(dc.replace(s, elements=tuple(element(e) for e in s.elements)) for s in system.shafts)
    bearings = tuple(
        dc.replace(b, kyy=b.kyy * r(), kzz=b.kzz * r()) if not isinstance(b.kyy, tuple) else b
        for b in system.bearings
    )
    gp = tuple(dc.replace(g, torque=g.torque * r()) for g in system.gear_pairs)
    return dc.replace(system, shafts=shafts, bearings=bearings, gear_pairs=gp)


def _sweep_decisions(system, threads=None):
    """The sweep of the link engine (``nlgrd.sweep``, without time answers) and its decisions."""
    import types

    import nlgrd

    rpm = np.linspace(6000, 12500, 53)
    with threadpool_limits(limits=threads):
        res = nlgrd.sweep(system, rpm=rpm, H=5, stability=True, time_domain=False)
    r, links = res.result, res.links
    m = types.SimpleNamespace(
        converged=r.converged,
        stable=r.stable,
        branch_switch=r.branch_switch,
        contact_loss_fraction=links["mesh0.contact_loss_fraction [-]"].to_numpy(),
        dte_rms=links["mesh0.dte_rms [m]"].to_numpy(),
    )
    return res, m


@pytest.mark.slow
def test_sweep_decisions_survive_permutation_perturbation_and_threads():
    """Kubo's rig, up and down sweeps over the main resonance (two jumps, a hysteresis
    band, points of both Floquet verdicts): the shafts listed in reverse order (every
    DOF permuted), a 1e-13 relative perturbation of materials, bearings and torque, and
    one against two BLAS threads give the same convergence flags, Floquet verdicts,
    contact-loss pattern and jump points, and the same RMS DTE to 1e-7 relative (the
    Newton tolerance is 1e-10; a different branch would differ by tens of percent)."""
    kubo = load_model(DATA / "case_studies" / "kubo.toml")
    ref, mref = _sweep_decisions(kubo, threads=2)
    assert mref.converged.all()
    assert np.any(mref.branch_switch)
    order = list(range(len(kubo.shafts)))[::-1]
    variants = {
        "shafts reversed": _permute_shafts(kubo, order),
        "perturbed": _perturb_system(kubo, np.random.default_rng(3)),
    }
    runs = {k: _sweep_decisions(v, threads=2)[1] for k, v in variants.items()}
    runs["one thread"] = _sweep_decisions(kubo, threads=1)[1]
    for label, m in runs.items():
        np.testing.assert_array_equal(m.converged, mref.converged, err_msg=label)
        np.testing.assert_array_equal(m.stable, mref.stable, err_msg=label)
        np.testing.assert_array_equal(m.branch_switch, mref.branch_switch, err_msg=label)
        np.testing.assert_array_equal(
            m.contact_loss_fraction > 0, mref.contact_loss_fraction > 0, err_msg=label
        )
        np.testing.assert_allclose(m.dte_rms, mref.dte_rms, rtol=1e-7, err_msg=label)


def test_campbell_lists_no_pseudo_modes_of_the_free_rotation():
    """Kubo's rig, 0-10 000 rpm: the free rotation of the drive train is counted as a
    rigid-body mode, never listed; overdamped real eigenvalues (Im λ ~ 1e-9 |λ| from
    rounding) are not listed either. Reference: the lowest flexible mode is the
    torsional coupling mode at 290 Hz (17 400 rpm), so no 1x critical speed lies below
    10 000 rpm and no listed frequency lies below 200 Hz."""
    from nlgrd.rotor.modal import campbell

    kubo = load_model(DATA / "case_studies" / "kubo.toml")
    res = campbell(kubo, np.linspace(0, 10000, 11) * np.pi / 30, n_modes=6)
    assert np.nanmin(res.frequencies) > 200.0
    assert res.critical_speeds == []
    assert modal_analysis(kubo, speed=9000 * np.pi / 30).n_rigid_body == 1


@pytest.mark.slow
def test_cli_sweep_reruns_are_byte_identical(tmp_path):
    """The README's `nlgrd sweep` (Kubo, 4000-16000 rpm, up and down, default H chosen by
    the error estimate; 61 speeds instead of 241 for time) in two fresh processes writes
    byte-identical CSVs, Floquet and harmonic-error columns included: no random
    starts, no dependence on process state or memory alignment (floquet_max carried
    ~1e-13 noise that changed between runs before it was written to 10 digits)."""
    import subprocess
    import sys

    outs = []
    for i in range(2):
        out = tmp_path / f"run{i}.csv"
        cmd = [sys.executable, "-m", "nlgrd.cli", "sweep", str(DATA / "case_studies" / "kubo.toml")]
        cmd += ["--rpm", "4000:16000:61", "--out", str(out)]
        subprocess.run(cmd, check=True, capture_output=True, cwd=tmp_path)
        outs.append(out.read_bytes())
    assert outs[0] == outs[1] and len(outs[0]) > 1000
