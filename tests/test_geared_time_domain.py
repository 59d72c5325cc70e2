"""Harmonic balance of the geared FE model (the link engine, ``nlgrd.sweep``'s path:
``build_link_model``, ``link_sweep``) against direct time integration.

The independent reference is the HHT-α integration of the same equations of motion of
the full finite-element model (:func:`nlgrd.timedomain.links.link_time_sweep`), run to a
periodic steady state at every frequency and swept up and down with each point starting
from the previous state, exactly like the harmonic-balance sweep. Model: Kubo's rig
(data/case_studies/kubo.toml) with every element split in two (144 DOFs) and mesh damping
ratio 0.02, so that transients die within some tens of periods.

Regimes: the main resonance with tooth separation (hysteresis between ~3300 and ~4300 Hz),
the 1/2 superharmonic resonance (~2400 Hz) and, with the backlash reduced to 4 µm, the
back-side contact regime. H = 9 harmonics; 512 (1024 near the superharmonic) time steps per
mesh period, which keeps the integration error below 0.3 % (checked against 4096 steps).

Tolerances: RMS DTE and maximum mesh force within 1 % (the issue's target; the measured
worst case is printed) at every point where the harmonic-balance solution is stable
(Floquet) and the integration reaches a periodic state; where it does not, Floquet must
flag the HB solution unstable. Jumps must fall in the same grid interval in both methods,
and the grid step is below 1 % of the jump frequency.
"""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.timedomain.links import link_time_sweep

KUBO = Path(__file__).resolve().parent.parent / "data" / "case_studies" / "kubo.toml"


def refined_kubo(backlash: float | None = None):
    s = load_model(KUBO)

    def refine(shaft):
        els = tuple(dc.replace(e, length=e.length / 2) for e in shaft.elements for _ in range(2))
        return dc.replace(shaft, elements=els)

    g = s.gear_pairs[0]
    geo = g.geometry if backlash is None else dc.replace(g.geometry, backlash=backlash)
    return dc.replace(
        s,
        shafts=tuple(refine(sh) for sh in s.shafts),
        disks=tuple(dc.replace(d, node=2 * d.node) for d in s.disks),
        bearings=tuple(dc.replace(b, node=2 * b.node) for b in s.bearings),
        couplings=tuple(dc.replace(c, node_a=2 * c.node_a, node_b=2 * c.node_b) for c in s.couplings),
        gear_pairs=(
            dc.replace(
                g, pinion_node=2 * g.pinion_node, gear_node=2 * g.gear_node, damping_ratio=0.02, geometry=geo
            ),
        ),
    )


def jump_intervals(frame, column="dte_rms [um]", ratio=1.25):
    """Grid intervals where a sweep's value changes by more than ``ratio`` between neighbours."""
    out = set()
    for d in ("up", "down"):
        x = frame[frame.direction == d].sort_values("base_frequency [Hz]")
        f, v = x["base_frequency [Hz]"].to_numpy(), x[column].to_numpy()
        for i in range(len(f) - 1):
            r = v[i + 1] / v[i]
            if r > ratio or r < 1 / ratio:
                out.add((d, round(f[i], 6), round(f[i + 1], 6)))
    return out


CASES = {
    "main resonance": (None, np.arange(3250, 4351, 25.0), 512),
    "superharmonic": (None, np.arange(2300, 2501, 20.0), 1024),
    "back-side contact": (4e-6, np.arange(3900, 5201, 50.0), 512),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", ["main resonance"])
def test_harmonic_balance_matches_time_integration(case):
    """The main resonance; the other regimes: tests/test_geared_time_domain_regimes.py (a
    file of their own, so that ``make test``'s workers run them beside this one)."""
    check_case(case)


def check_case(case):
    """The checks of the module docstring for one regime of :data:`CASES`."""
    backlash, freqs, steps = CASES[case]
    system = refined_kubo(backlash)
    assert system.n_dofs >= 100
    omegas = 2 * np.pi * freqs
    model = build_link_model(system)
    hb = link_sweep(model, omegas, H=9, stability=True).to_frame()
    td = link_time_sweep(model, omegas, steps_per_period=steps, tol=1e-5).to_frame()

    def names(frame):
        """The mesh's columns without their prefix (one mesh: base frequency = mesh frequency)."""
        return frame.rename(columns=lambda c: c.removeprefix("mesh0."))

    hb, td = names(hb), names(td)
    assert hb["converged"].all(), hb[~hb["converged"]]
    key = ["direction", "base_frequency [Hz]"]
    hb, td = hb.sort_values(key).reset_index(drop=True), td.sort_values(key).reset_index(drop=True)
    # an unstable periodic solution is no steady state of the time integration: where the
    # integration finds no periodic state, Floquet must call the HB solution unstable
    assert not np.any(~td["converged"] & hb["stable"]), td[~td["converged"]]
    ok = td["converged"] & hb["stable"]
    assert ok.sum() >= 20
    print(
        f"{case}: {int((~hb['stable']).sum())} HB points unstable, "
        f"{int((~td['converged']).sum())} not periodic in time"
    )
    err_rms = np.abs(hb["dte_rms [um]"] / td["dte_rms [um]"] - 1)[ok]
    err_force = np.abs(hb["dslr [-]"] / td["dslr [-]"] - 1)[ok]
    print(
        f"{case}: {len(hb)} points, worst RMS DTE error {err_rms.max():.2e}, "
        f"max mesh force {err_force.max():.2e}"
    )
    assert err_rms.max() < 0.01 and err_force.max() < 0.01
    if case == "back-side contact":
        assert td["back_contact"].sum() >= 10 and hb["back_contact"].sum() == td["back_contact"].sum()
    else:
        assert (td["contact_loss_fraction [-]"] > 0).sum() >= 5
        jumps_hb, jumps_td = jump_intervals(hb), jump_intervals(td)
        print(f"{case}: jumps HB {sorted(jumps_hb)}, time integration {sorted(jumps_td)}")
        assert jumps_hb and jumps_hb == jumps_td
        step = np.diff(freqs).min()
        assert all(step < 0.01 * f0 for _, f0, _ in jumps_hb)
