"""The tables renamed by issue 33 item 5 (docs/conventions.md, "Column names") carry the
same numbers under their new names, every mesh's: the link sweep's per-mesh DTE harmonic
amplitudes ``<mesh>.dte_amp_<k> [um]``, the tori's per-mesh columns, the orbit search's
link columns and the static deflection in µm."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import nlgrd
from nlgrd.nonlinear.fourier.harmonics import real_to_complex
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep

ROOT = Path(__file__).resolve().parent.parent
TWO_STAGE = ROOT / "data" / "models" / "two_stage.toml"
CLEARANCE = ROOT / "data" / "models" / "two_shaft_clearance.toml"
#: Two-stage reduction: base 5 Ω, mesh0 at base harmonic 5 and mesh1 at 2 (its model file).
OMEGA = 2 * np.pi * 200.0
H = 15


@pytest.fixture(scope="module")
def two_stage():
    """The two-stage model and its sweep at one base frequency (a stable periodic point)."""
    model = build_link_model(nlgrd.load(str(TWO_STAGE)))
    res = link_sweep(model, np.array([OMEGA]), H=H, directions="up")
    assert res.result.converged[0] and res.result.stable[0]
    return model, res


def _fft_amplitudes(z: np.ndarray, n: int = 256) -> np.ndarray:
    """|δ_k|, k = 0..H, by numpy's FFT of δ(θ) = z₀ + Σ a_k cos kθ + b_k sin kθ sampled at
    ``n`` points (written out here, not by the package's Fourier helpers)."""
    hmax = (z.size - 1) // 2
    theta = 2 * np.pi * np.arange(n) / n
    k = np.arange(1, hmax + 1)
    d = z[0] + np.cos(np.outer(theta, k)) @ z[1::2] + np.sin(np.outer(theta, k)) @ z[2::2]
    f = np.abs(np.fft.rfft(d)) / n
    return np.concatenate([[f[0]], 2 * f[1 : hmax + 1]])


def test_every_mesh_has_its_dte_harmonic_amplitudes(two_stage):
    """``<mesh>.dte_amp_<k> [um]``, k = 0..H, for both meshes of the two-stage reduction.
    Reference: numpy's FFT of each mesh's DTE sampled from its harmonics (256 samples of a
    signal of 15 harmonics: exact to rounding, so 1e-9 of the largest amplitude; the
    table writes 0 for rounding below 1e-8 of the row's largest µm value:
    ``units.floor_rounding``). The first mesh's equal the mesh result's own
    ``amplitudes`` (its metrics, another code path) to rounding. The two meshes differ
    (mesh0 has its content at multiples of 5, mesh1 at multiples of 2): a column of the
    wrong mesh fails."""
    model, res = two_stage
    frame = res.to_frame()
    coords = {lk.name: sl.start for lk, sl in zip(model.links, model.receptance.slices, strict=True)}
    largest = 0.0
    for name in ("mesh0", "mesh1"):
        cols = [f"{name}.dte_amp_{k} [um]" for k in range(H + 1)]
        assert [c for c in frame.columns if c.startswith(f"{name}.dte_amp_")] == cols
        ours = frame[cols].to_numpy(float)[0]
        theirs = _fft_amplitudes(res.result.harmonics[0, coords[name]]) * 1e6
        largest = max(largest, float(np.max(theirs)))
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-8 * float(np.max(theirs)), err_msg=name)
    first = frame[[f"mesh0.dte_amp_{k} [um]" for k in range(H + 1)]].to_numpy(float)[0]
    np.testing.assert_allclose(first, res.result.amplitudes[0] * 1e6, rtol=0, atol=1e-8 * largest)
    a0 = frame[[f"mesh0.dte_amp_{k} [um]" for k in (2, 5)]].to_numpy(float)[0]
    a1 = frame[[f"mesh1.dte_amp_{k} [um]" for k in (2, 5)]].to_numpy(float)[0]
    assert a0[1] > 1.0 and a1[0] > 1.0 and a0[0] < 0.1 and a1[1] < 0.1  # [um]


def test_the_amplitudes_are_not_jumps_and_not_mesh_outputs(two_stage):
    """The default jumps and the orbits' comparison ignore the amplitude columns."""
    _, res = two_stage
    assert "mesh1.dte_amp_2 [m]" in res.links.columns
    from nlgrd.nonlinear.results.link_results import _jumps_on

    assert not _jumps_on("mesh1.dte_amp_2 [m]") and _jumps_on("mesh1.dte_rms [m]")


@pytest.mark.slow
def test_the_dte_amplitudes_against_the_time_integration(two_stage):
    """The same point integrated in time (HHT-α, 512 steps per base period, the full FE
    model to a periodic steady state: nlgrd.timedomain.links.link_time_response), the FFT
    of each mesh's DTE over its last period against ``<mesh>.dte_amp_<k>``, k = 0..10.
    Tolerance: 3e-3 of the mesh's largest alternating amplitude, for the truncation to
    H = 15 and the integration's step (measured 1.5e-3 at mesh0's harmonic 5 and 10, its
    mesh harmonics). The top harmonics are not compared: the balance truncated at H = 15
    misses the content beyond it that feeds them (measured 16 % at mesh0's harmonic 15,
    its third mesh harmonic). About 70 s."""
    from nlgrd.timedomain.links import link_time_response

    model, res = two_stage
    frame = res.to_frame()
    tr = link_time_response(model, OMEGA)
    assert tr.converged
    Z = tr.harmonics(H)
    for j, name in enumerate(tr.names):
        mesh = name.split(".")[0]
        ours = frame[[f"{mesh}.dte_amp_{k} [um]" for k in range(11)]].to_numpy(float)[0]
        theirs = np.abs(real_to_complex(Z[j]))[:11] * 1e6
        scale = float(np.max(theirs[1:]))
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=3e-3 * scale, err_msg=mesh)


def _periodic_torus(z: np.ndarray, omega: float):
    """A periodic orbit written as a torus (every harmonic on k₂ = 0, ω₂ arbitrary): its
    outputs over the torus are the orbit's own."""
    from nlgrd.nonlinear.hb import quasi_periodic as qp
    from nlgrd.nonlinear.hb import torus_grid as tg

    hmax = (z.shape[1] - 1) // 2
    grid = tg.TorusGrid(hmax, 2, *tg.default_grid(hmax, 2))
    Y = np.zeros((z.shape[0], grid.n_terms), dtype=complex)
    Y[:, : hmax + 1] = real_to_complex(z)
    return qp.TorusSolution(omega, 0.37 * omega, Y, grid, True, 0.0, 0, 0.0)


def test_a_torus_table_has_every_mesh(two_stage):
    """``TorusResult.to_frame`` of a two-mesh model: ``<mesh>.<quantity>`` of both meshes.
    Reference: the link sweep's own columns of the same orbit, written as a torus on k₂ = 0:
    mean and RMS of the DTE are moments of the same harmonics (1e-9), and differ between
    the meshes (58.9 and 60.7 µm, 2.2 and 3.3 µm). The extremes are not compared: the
    torus samples 256 points of θ₁ against the sweep's 2048 (measured 4.8 % lower largest
    force of mesh0, whose contact peaks are narrow at base harmonic 5)."""
    from nlgrd.nonlinear.tracing.link_torus import LinkTorus
    from nlgrd.nonlinear.tracing.torus_outputs import CHECKED, TORUS_OUTPUTS
    from nlgrd.nonlinear.tracing.torus_sweep import TorusResult

    model, res = two_stage
    target = LinkTorus(model)
    assert target.mesh_names == ("mesh0", "mesh1")
    sol = _periodic_torus(res.result.harmonics[0], OMEGA)
    first = target.outputs(sol)
    both = target.mesh_outputs(sol, first)
    np.testing.assert_array_equal(both[0], first)
    np.testing.assert_allclose(target.mesh_outputs(sol)[0], first, rtol=1e-12)
    n = len(TORUS_OUTPUTS)
    tor = TorusResult(
        np.array([OMEGA]),
        np.array([1000.0]),
        np.array([True]),
        first[None, :],
        np.full((1, len(CHECKED)), 1e-4),
        np.array([1.01 + 0.2j]),
        np.array([1e-11]),
        np.array([5]),
        np.ones(1),
        H,
        2,
        np.zeros((1, 0)),
        [],
        [sol],
        meshes=target.mesh_names,
        mesh_outputs=both[None, :, :],
        mesh_change=np.array([[[1e-4, 2e-4, 3e-4], [4e-4, 5e-4, 3e-4]]]),
    )
    frame = tor.to_frame()
    sweep = res.to_frame()
    for name in ("mesh0", "mesh1"):
        for q in ("dte_mean [um]", "dte_rms [um]"):
            np.testing.assert_allclose(frame[f"{name}.{q}"], sweep[f"{name}.{q}"], rtol=1e-9, err_msg=q)
    assert frame["mesh1.force_max_change [-]"].iloc[0] == 5e-4
    assert frame["secondary_frequency [Hz]"].iloc[0] == pytest.approx(0.37 * OMEGA / (2 * np.pi), rel=1e-15)
    assert len([c for c in frame.columns if c.startswith("mesh1.")]) == n - 1 + 2
    with pytest.raises(nlgrd.ModelError, match="mesh_outputs"):
        TorusResult(
            *[getattr(tor, f) for f in ("omega", "rpm", "converged", "outputs", "change")],
            tor.multiplier,
            tor.residual,
            tor.iterations,
            tor.seconds,
            H,
            2,
            tor.bearing_force_max,
            [],
            [sol],
            meshes=("mesh0", "mesh1"),
        )


def test_the_orbit_search_writes_every_link():
    """``nlgrd.search_orbits`` on a model with a clearance and four bearings: every link's
    and bearing's columns, as the sweep writes them. Reference: the link sweep's point at
    the same speed, the same orbit (the search's smallest period-1 orbit), solved to 1e-10
    from another start: 1e-6 of each value or of the row's largest in its unit."""
    system = nlgrd.load(str(CLEARANCE))
    found = nlgrd.search_orbits(system, hz=1200.0, periods=(1,), H=5, n_starts=8)
    frame = found.to_frame()
    sweep = nlgrd.sweep(system, hz=[1200.0], H=5, directions="up").to_frame()
    links = [c for c in sweep.columns if "." in c and "dte_amp_" not in c]
    assert [c for c in frame.columns if "." in c] == links
    assert "base_frequency [Hz]" in frame.columns and "mesh_frequency [Hz]" not in frame.columns
    row = frame.iloc[0]
    for c in links:
        unit = c.rsplit("[", 1)[-1]
        scale = max(abs(float(sweep[k].iloc[0])) for k in links if k.endswith(unit))
        assert float(row[c]) == pytest.approx(float(sweep[c].iloc[0]), rel=1e-6, abs=1e-6 * scale), c


def test_the_static_deflection_is_in_micrometres():
    """``StaticResult.to_frame``: ``ux``, ``uy``, ``uz`` [um] are the solved DOFs x 1e6
    (the solution vector itself: exact to one rounding), ``x [m]`` the node positions."""
    from nlgrd.rotor.frequency_response import static_deflection

    system = nlgrd.load(str(ROOT / "data" / "models" / "two_shaft.toml"))
    res = static_deflection(system, {(0, 1, "uy"): 10.0})
    frame = res.to_frame()
    dm = system.dofs
    for i, (s, node) in enumerate(zip(frame["shaft"], frame["node"], strict=True)):
        q = res.q[dm.node_dofs(int(s), int(node))]
        assert frame["x [m]"].iloc[i] == system.shafts[int(s)].node_positions[int(node)]
        for j, c in enumerate(("ux [um]", "uy [um]", "uz [um]")):
            assert frame[c].iloc[i] == q[j] * 1e6
    assert np.max(np.abs(frame["uy [um]"])) > 1e-3  # a deflection, not zeros
