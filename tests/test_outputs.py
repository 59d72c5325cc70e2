"""Outputs say what is known: unconverged and unknown values are NA, residuals mean one
thing, reruns are byte-identical, and out-of-range or misspelt requests are errors.

Each test here failed on the code before issue 9 ("The same answer on every machine"):
unconverged points wrote ``stable = False`` and ``back_contact = True`` (NaN cast to
bool), sweeps without stability wrote ``stable = False``, continuation residuals were
scaled by the starting point's force and ``converged`` was set to True, the iterative
eigensolvers started from random vectors (and, on the former one-mesh engine, a reused
model accepted frequencies past the ones its bases were built for and the stability
basis kept the cut-off of its first call).
"""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest

from nlgrd.errors import ModelError
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model, link_continuation, link_sweep
from nlgrd.nonlinear.models.sdof import SDOFGearPair
from nlgrd.nonlinear.reduction.modal_basis import ModeCapWarning, lowest_modes
from nlgrd.nonlinear.tracing.continuation import continuation
from nlgrd.nonlinear.tracing.sweep import sweep
from nlgrd.rotor.modal import gear_pair_mode

DATA = Path(__file__).resolve().parent.parent / "data"
LSTE = np.array([0.0, 3e-6, 0.0, 1e-6, 0.0])
KUBO_SDOF = SDOFGearPair(0.261, 0.2587e9, 50e-6, 2295.0, LSTE, damping_ratio=0.02)


def _two_shaft(zeta=0.03):
    s = load_model(DATA / "models" / "two_shaft.toml")
    return dc.replace(s, gear_pairs=(dc.replace(s.gear_pairs[0], damping_ratio=zeta),))


def test_unconverged_points_are_na_in_every_numeric_and_flag_column():
    """With one Newton iteration and no fallback most points cannot converge; every
    column but frequency, direction and the converged flag is NA on those rows, and
    ``stable`` / ``back_contact`` are nullable booleans, never a False/True guess."""
    rm = KUBO_SDOF.reduced_model()
    om = KUBO_SDOF.natural_frequency * np.linspace(0.8, 1.2, 9)
    res = sweep(rm, om, H=3, max_iter=1, fallback=False, jump="none", stability=True)
    df = res.to_frame()
    bad = ~df["converged"].to_numpy(bool)
    assert bad.sum() >= 3 and (~bad).sum() >= 1
    meta = {"base_frequency [Hz]", "direction", "converged"}
    for col in df.columns:
        if col not in meta:
            assert df.loc[bad, col].isna().all(), col
    assert str(df["stable"].dtype) == "boolean" and str(df["back_contact"].dtype) == "boolean"
    assert df.loc[~bad, "stable"].notna().all()


def test_sweep_without_stability_writes_stability_as_unknown():
    """No Floquet multipliers computed: ``stable`` is NA at every point, not False."""
    rm = KUBO_SDOF.reduced_model()
    om = KUBO_SDOF.natural_frequency * np.linspace(0.5, 0.7, 5)
    df = sweep(rm, om, H=3, stability=False).to_frame()
    assert df["converged"].all()
    assert df["stable"].isna().all() and df["floquet_max [-]"].isna().all()


def test_time_integration_is_the_same_result_family_with_its_residual_named():
    """A time-integration sweep is a SweepResult like a harmonic-balance sweep: the same
    table, but its residual column names what it is (the period-to-period difference, not
    a harmonic-balance residual) and ``stable`` is NA (not computed), never True/False."""
    from nlgrd.nonlinear.results.sweep_results import RESIDUAL_COLUMNS, SweepResult
    from nlgrd.timedomain.sdof import time_sweep

    om = KUBO_SDOF.natural_frequency * np.array([0.5, 0.55])
    td = time_sweep(KUBO_SDOF, om, "up")
    hb = sweep(KUBO_SDOF.reduced_model(), om, H=5, directions="up", stability=True)
    assert isinstance(td, SweepResult) and td.residual_kind == "period difference"
    f_td, f_hb = td.to_frame(), hb.to_frame()
    assert "period_difference [-]" in f_td and "residual [-]" not in f_td
    assert "residual [-]" in f_hb and "period_difference [-]" not in f_hb

    def named(frame, residual):  # the amplitude columns follow each result's H
        return {c for c in frame.columns if not c.startswith("dte_amp_")} - {residual}

    assert named(f_td, "period_difference [-]") == named(f_hb, "residual [-]")
    assert f_td["converged"].all() and f_td["stable"].isna().all() and f_hb["stable"].all()
    assert str(f_td["stable"].dtype) == "boolean" == str(f_hb["stable"].dtype)
    assert set(RESIDUAL_COLUMNS) == {"relative residual", "period difference"}
    with pytest.raises(ModelError, match="residual_kind"):
        dc.replace(hb, residual_kind="error")


def test_continuation_residual_is_the_sweep_residual_and_converged_is_computed():
    """Each curve point's residual equals max|R| / max(|L z|, |G|, |F|) recomputed at that
    point (the measure sweeps converge on), to 1e-6 relative or 1e-15 absolute, and
    ``converged`` is that residual against the tolerance."""
    rm = KUBO_SDOF.reduced_model()
    wn = KUBO_SDOF.natural_frequency
    c = continuation(rm, 1.05 * wn, 0.85 * wn, 3, ds_max=0.05, tol=1e-9)
    curve = c.curve
    assert len(curve) >= 8
    for w, z, r in zip(curve.omega, curve.harmonics, curve.residual, strict=True):
        p = rm.at(float(w), 3)
        R, _, scale = p.residual_jacobian(z.reshape(-1))
        expect = np.max(np.abs(R)) / scale
        assert r == pytest.approx(expect, rel=1e-6, abs=1e-15)
    np.testing.assert_array_equal(curve.converged, curve.residual <= 1e-9)


@pytest.mark.slow  # about 40 s: the inner loop (-m "not slow") leaves it to make test
def test_modal_receptances_and_floquet_are_byte_identical_in_one_process():
    """Two link models on a modal basis built one after the other in one process (the
    iterative eigensolvers' state differs between them) give byte-identical sweep outputs,
    floquet_max included."""
    s = _two_shaft()
    f0 = gear_pair_mode(s)[0]
    om = 2 * np.pi * np.linspace(0.8 * f0, 1.2 * f0, 12)
    frames = []
    for _ in range(2):
        m = build_link_model(s, method="modal", max_frequency=3 * float(om.max()))
        frames.append(link_sweep(m, om, H=3).to_frame())
    a, b = (f.to_csv(index=False) for f in frames)
    assert a == b
    ok = frames[0]["converged"].to_numpy(bool)
    assert ok.sum() >= 10 and frames[0].loc[ok, "floquet_max [-]"].notna().all()


def test_mode_basis_cap_is_reported():
    """A basis that stops doubling at its cap short of the cut-off warns (ModeCapWarning)."""
    n = 60
    k = 1e6 * (2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1))
    import scipy.sparse as sp

    K, M = sp.csc_matrix(k), sp.identity(n, format="csc")
    with pytest.warns(ModeCapWarning, match="cap 8"):
        lam, _ = lowest_modes(K, M, cutoff=1e9, start=4, cap=8, what="test basis")
    assert lam.size >= 8


@pytest.mark.parametrize(
    "call, key",
    [
        (lambda rm, om: sweep(rm, om, H=3, jump="sideways"), "jump"),
        (lambda rm, om: sweep(rm, om, H=3, directions="sideways"), "directions"),
        (lambda rm, om: sweep(rm, om, H=3, stability=False).plot("dslrr"), "quantity"),
        (lambda rm, om: build_link_model(_two_shaft(), method="fast"), "method"),
    ],
    ids=["jump", "direction", "quantity", "receptance"],
)
def test_option_strings_are_validated_with_the_allowed_values(call, key):
    """A misspelt option raises ModelError naming the option and listing what is allowed."""
    rm = KUBO_SDOF.reduced_model()
    om = KUBO_SDOF.natural_frequency * np.array([0.5, 0.6])
    with pytest.raises(ModelError) as err:
        call(rm, om)
    assert err.value.key == key
    assert "'" in str(err.value)  # the allowed values are quoted in the message


def test_continuation_that_turns_back_is_not_complete():
    """Kubo's rig from 3000 to 5000 Hz: the curve folds back at the main resonance's
    turning point (near 4273 Hz) and leaves the range below 3000 Hz; that is not a
    complete curve (it was flagged complete before). From 1000 to 1400 Hz (no fold)
    it is."""
    model = build_link_model(load_model(DATA / "case_studies" / "kubo.toml"))  # the link engine
    c = link_continuation(model, 2 * np.pi * 3000, 2 * np.pi * 5000, 5)
    assert not c.curve.complete
    assert c.curve.omega.max() < 2 * np.pi * 4500 and c.curve.omega.min() < 2 * np.pi * 3000
    assert link_continuation(model, 2 * np.pi * 1000, 2 * np.pi * 1400, 5).curve.complete
