"""Reference for the quasi-periodic harmonic balance on Kubo's rig: time integration of the
full FE model (HHT-α, :func:`nlgrd.timedomain.geared.time_response`, 512 steps per mesh
period) at constant speed in the quasi-periodic band 13 750-14 000 rpm (the up sweep,
H = 13; tests/test_beyond_period_one.py), against the torus of
:func:`nlgrd.nonlinear.tracing.torus_sweep.torus_sweep`.

Each run starts on the unstable periodic orbit, integrates ``TRANSIENT`` mesh periods
(discarded), then ``BLOCKS`` blocks of ``SPACING`` periods. The last period of each block
is kept (the torus is sampled at ``BLOCKS`` different phases of its second angle) for the
RMS of δ (alternating part) and the largest mesh force W; δ at the start of every period
(the Poincaré section θ₁ = 0, ``BLOCKS`` x ``SPACING`` samples) gives the rotation number ρ
per mesh period: the peak of its Hann-windowed spectrum, refined by a parabola through the
log-amplitudes, and the secondary frequency ρ f_mesh (folded into (0, f_mesh/2]).

Run (one at a time, one thread): ``OPENBLAS_NUM_THREADS=1 python benchmarks/torus_kubo_reference.py``
(``... high``: the high branch's band 8460-8790 rpm of the down sweep on notebook 01's grid).
Writes benchmarks/torus_kubo_reference.csv (``_high.csv``) (speeds, time-domain and torus figures, their
relative differences, the cost of each torus point and of the periodic point).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.geared import build_geared_model, geared_sweep
from nlgrd.nonlinear.tracing.torus_sweep import torus_sweep
from nlgrd.timedomain.geared import start_from_harmonics, time_response

ROOT = Path(__file__).resolve().parent.parent
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
TOP = 2 * np.pi * 14500 / 60 * 25 * 1.0001
TRANSIENT, BLOCKS, SPACING, STEPS = 3000, 500, 6, 512


def rotation_number(x: np.ndarray) -> float:
    """Rotation per sample of the Poincaré samples ``x`` in (0, 1/2] [-]."""
    x = x - np.mean(x)
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))
    j = 2 + int(np.argmax(spec[2:-1]))
    a, b, c = np.log(spec[j - 1 : j + 2])
    return float((j + 0.5 * (a - c) / (a - 2 * b + c)) / x.size)


def reference(model, omega: float, harmonics: np.ndarray) -> dict:
    state = start_from_harmonics(model, omega, harmonics)
    tr = time_response(model, omega, state0=state, tol=0, min_periods=TRANSIENT, max_periods=TRANSIENT)
    state = tr.state
    d, w, p, fb = [], [], [], []
    b0 = model.system.bearings[0]
    dofs = model.bearing_dofs[:2]
    speed = model.receptance.speed(omega)
    kb, cb = b0.stiffness(speed), b0.damping(speed)
    dt = 2 * np.pi / omega / STEPS
    for _ in range(BLOCKS):
        tr = time_response(
            model, omega, state0=state, tol=0, min_periods=SPACING, max_periods=SPACING, store_dofs=True
        )
        state = tr.state
        d.append(tr.history.delta)
        w.append(tr.history.force)
        p.append(tr.poincare)
        q = tr.q[dofs]  # bearing 0's (y, z) over the block's last period
        f = -(kb @ q + cb @ np.gradient(q, dt, axis=1))
        fb.append(np.hypot(f[0], f[1]))
    d, w, p, fb = np.concatenate(d), np.concatenate(w), np.concatenate(p), np.concatenate(fb)
    f1 = omega / (2 * np.pi)
    half = d.size // 2
    return {
        "ti_dte_rms [um]": float(np.std(d)) * 1e6,
        "ti_force_max [N]": float(np.max(w)),
        "ti_secondary_frequency [Hz]": rotation_number(p) * f1,
        "ti_bearing_0_force_max [N]": float(np.max(fb)),
        # the spread of the statistics between the two halves of the record
        "ti_dte_rms halves [-]": float(np.std(d[:half]) / np.std(d[half:]) - 1),
        "ti_force_max halves [-]": float(np.max(w[:half]) / np.max(w[half:]) - 1),
    }


def main(argv: list[str]) -> int:
    """``high``: the band 8460-8790 rpm of the high branch on notebook 01's grid (300 speeds
    over 2000-16 000 rpm, swept down from 16 000 rpm, H 13), every second point; otherwise
    the up sweep's band 13 750-14 000 rpm in steps of 25 rpm."""
    system = load_model(KUBO)
    if len(argv) > 1 and argv[1] == "high":
        grid = np.linspace(2000.0, 16000.0, 300)
        grid = grid[grid > 8400]
        model = build_geared_model(system, 2 * np.pi * 16000 / 60 * 25, H=25)
        t = time.perf_counter()
        sw = geared_sweep(system, rpm=grid, H=13, model=model, directions="down", period=1)
        periodic_cost = (time.perf_counter() - t) / grid.size
        m = sw.mesh
        keep = np.nonzero((m.direction == "down") & np.isfinite(m.secondary_frequency) & (sw.rpm < 8800))[0][
            ::2
        ]
        out_path = Path(__file__).with_name("torus_kubo_reference_high.csv")
    else:
        rpm = np.arange(13750.0, 14001.0, 25.0)
        model = build_geared_model(system, TOP, H=17)
        t = time.perf_counter()
        sw = geared_sweep(system, rpm=rpm, H=13, model=model, directions="up", period=1)
        periodic_cost = (time.perf_counter() - t) / rpm.size
        keep = np.arange(rpm.size)
        out_path = Path(__file__).with_suffix(".csv")
    m = sw.mesh
    tor = torus_sweep(model, m.omega[keep], H=13, periodic=m.harmonics[keep])
    frame = tor.to_frame()
    rows = []
    for i, j in enumerate(keep):
        row = {"pinion_speed [rpm]": float(sw.rpm[j]), "periodic point [s]": periodic_cost}
        row.update(frame.iloc[i].to_dict())
        if tor.converged[i]:
            t = time.perf_counter()
            row.update(reference(model, float(m.omega[j]), m.harmonics[j]))
            row["time integration [s]"] = time.perf_counter() - t
            for q in ("dte_rms [um]", "force_max [N]", "secondary_frequency [Hz]"):
                row["diff " + q] = row[q] / row["ti_" + q] - 1
        rows.append(row)
        print({k: v for k, v in row.items() if "diff" in k or "rpm" in k or "[s]" in k}, flush=True)
    out = pd.DataFrame(rows)
    out.to_csv(out_path, index=False)
    print(out.to_string())
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
