"""Reference for the quasi-periodic harmonic balance on Kubo's rig: time integration of the
full FE model (HHT-α, :class:`nlgrd.timedomain.links.LinkIntegrator` on every DOF of the
one-mesh link model, 512 steps per mesh period) at constant speed in the quasi-periodic
band 13 750-14 000 rpm (the up sweep, H = 13; tests/test_beyond_period_one.py), against the
torus of :func:`nlgrd.nonlinear.tracing.torus_sweep.torus_sweep` (the link torus,
:class:`nlgrd.nonlinear.tracing.link_torus.LinkTorus`, as every sweep answers).

Each run starts on the unstable periodic orbit, integrates ``TRANSIENT`` mesh periods
(discarded), then ``BLOCKS`` blocks of ``SPACING`` periods. The last period of each block
is kept (the torus is sampled at ``BLOCKS`` different phases of its second angle) for the
RMS of δ (alternating part) and the largest mesh force W; δ at the start of every period
(the Poincaré section θ₁ = 0, ``BLOCKS`` x ``SPACING`` samples) gives the rotation number ρ
per mesh period: the peak of its Hann-windowed spectrum, refined by a parabola through the
log-amplitudes, and the secondary frequency ρ f_mesh (folded into (0, f_mesh/2]).

Run (one at a time, one thread): ``OPENBLAS_NUM_THREADS=1 python benchmarks/torus_kubo_reference.py``
(``... high``: the high branch's band 8460-8790 rpm of the down sweep on notebook 01's grid;
``... check RPM ...``: those speeds of the stored band integrated again and printed against
the CSV's ``ti_*`` columns, nothing written).
Writes benchmarks/torus_kubo_reference.csv (``_high.csv``) (speeds, time-domain and torus figures, their
relative differences, the cost of each torus point and of the periodic point).

The stored CSVs were made by the single-mesh engine (since deleted: its model builder,
sweep, torus and HHT-α time response; see benchmarks/README.md), whose integrator is this
one (``LinkIntegrator.of_mesh``); ``check`` shows that this script's integration gives
their ``ti_*`` figures again. Their torus columns are that engine's torus, not the link
torus this script now computes, under that engine's names (``mesh_frequency [Hz]``,
``dte_rms [um]``, ``floquet_multiplier_abs [-]``, ...); a new run writes the torus table's
current names (``mesh0.dte_rms [um]``, ...: docs/conventions.md, "Column names") beside
this script's own ``pinion_speed [rpm]`` and ``ti_*``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.fourier.harmonics import differentiate, sample
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.nonlinear.results.bearing_loads import bearing_node_dofs
from nlgrd.nonlinear.tracing.torus_sweep import torus_sweep
from nlgrd.timedomain.links import LinkIntegrator, start_from_harmonics

ROOT = Path(__file__).resolve().parent.parent
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
TRANSIENT, BLOCKS, SPACING, STEPS = 3000, 500, 6, 512
H = 13


def rotation_number(x: np.ndarray) -> float:
    """Rotation per sample of the Poincaré samples ``x`` in (0, 1/2] [-]."""
    x = x - np.mean(x)
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))
    j = 2 + int(np.argmax(spec[2:-1]))
    a, b, c = np.log(spec[j - 1 : j + 2])
    return float((j + 0.5 * (a - c) / (a - 2 * b + c)) / x.size)


def reference(model, omega: float, harmonics: np.ndarray) -> dict:
    """The integration's statistics from the orbit ``harmonics`` (d, 2H+1) at ``omega``."""
    integ = LinkIntegrator(model, omega, steps_per_period=STEPS)
    state = integ.start(start_from_harmonics(model, omega, H, harmonics))
    for _ in range(TRANSIENT):
        _, state = integ.period(state)
    mesh = model.reduced.metrics.mesh
    e_dot = omega * sample(differentiate(mesh.lste), integ.ns)[: integ.ns]
    b0 = model.system.bearings[0]
    dofs = bearing_node_dofs(model.system)[:2]
    speed = model.receptance.plan.speed(omega)
    kb, cb = b0.stiffness(speed), b0.damping(speed)
    dt = 2 * np.pi / omega / STEPS
    d, w, p, fb = [], [], [], []
    for _ in range(BLOCKS):
        for _ in range(SPACING - 1):
            y, state = integ.period(state)
            p.append(y[0, 0])
        rec = integ.record(state, dofs)  # the block's last period, bearing 0's (y, z) too
        p.append(rec.y[0, 0])
        state = rec.end
        d.append(rec.y[0])
        w.append(rec.g[0] + mesh.damping * (rec.ydot[0] - e_dot))
        f = -(kb @ rec.q + cb @ np.gradient(rec.q, dt, axis=1))
        fb.append(np.hypot(f[0], f[1]))
    d, w, p, fb = np.concatenate(d), np.concatenate(w), np.asarray(p), np.concatenate(fb)
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


def check(rpm: list[float]) -> int:
    """The stored band's speeds ``rpm`` integrated again against the CSV's ``ti_*``."""
    model = build_link_model(load_model(KUBO))
    omegas = np.asarray(rpm, dtype=float) * 2 * np.pi / 60 * 25
    sw = link_sweep(model, omegas, H=H, directions="up", period=1).result
    ref = pd.read_csv(Path(__file__).with_suffix(".csv"))
    ref = ref.set_index(ref["pinion_speed [rpm]"].round(3))
    for r, w, z in zip(rpm, sw.omega, sw.harmonics, strict=True):
        t = time.perf_counter()
        new = reference(model, float(w), z)
        cost = time.perf_counter() - t
        for k, v in new.items():
            stored = ref.loc[r, k] if k in ref.columns else float("nan")  # older CSVs lack some
            diff = v / stored - 1
            print(f"{r:8.1f} rpm {k:32s} now {v:14.6f} stored {stored:14.6f} ({diff:+.2e}) {cost:.0f} s")
    return 0


def main(argv: list[str]) -> int:
    """``high``: the band 8460-8790 rpm of the high branch on notebook 01's grid (300 speeds
    over 2000-16 000 rpm, swept down from 16 000 rpm, H 13), every second point; ``check
    RPM ...``: :func:`check`; otherwise the up sweep's band 13 750-14 000 rpm in steps of
    25 rpm."""
    if len(argv) > 2 and argv[1] == "check":
        return check([float(x) for x in argv[2:]])
    model = build_link_model(load_model(KUBO))
    if len(argv) > 1 and argv[1] == "high":
        grid = np.linspace(2000.0, 16000.0, 300)
        grid = grid[grid > 8400]
        t = time.perf_counter()
        sw = link_sweep(model, grid * 2 * np.pi / 60 * 25, H=H, directions="down", period=1).result
        periodic_cost = (time.perf_counter() - t) / grid.size
        rpm = np.asarray(sw.omega) * 60 / (2 * np.pi * 25)
        marked = (sw.direction == "down") & np.isfinite(sw.secondary_frequency) & (rpm < 8800)
        keep = np.nonzero(marked)[0][::2]
        out_path = Path(__file__).with_name("torus_kubo_reference_high.csv")
    else:
        grid = np.arange(13750.0, 14001.0, 25.0)
        t = time.perf_counter()
        sw = link_sweep(model, grid * 2 * np.pi / 60 * 25, H=H, directions="up", period=1).result
        periodic_cost = (time.perf_counter() - t) / grid.size
        rpm = np.asarray(sw.omega) * 60 / (2 * np.pi * 25)
        keep = np.arange(grid.size)
        out_path = Path(__file__).with_suffix(".csv")
    tor = torus_sweep(model, sw.omega[keep], H=H, periodic=sw.harmonics[keep])
    frame = tor.to_frame()
    rows = []
    for i, j in enumerate(keep):
        row = {"pinion_speed [rpm]": float(rpm[j]), "periodic point [s]": periodic_cost}
        row.update(frame.iloc[i].to_dict())
        if tor.converged[i]:
            t = time.perf_counter()
            row.update(reference(model, float(sw.omega[j]), sw.harmonics[j]))
            row["time integration [s]"] = time.perf_counter() - t
            for ours, q in (
                ("mesh0.dte_rms [um]", "dte_rms [um]"),
                ("mesh0.force_max [N]", "force_max [N]"),
                ("secondary_frequency [Hz]", "secondary_frequency [Hz]"),
            ):  # the table's names (docs/conventions.md, "Column names"), the CSV's own
                row["diff " + q] = row[ours] / row["ti_" + q] - 1
        rows.append(row)
        print({k: v for k, v in row.items() if "diff" in k or "rpm" in k or "[s]" in k}, flush=True)
    out = pd.DataFrame(rows)
    out.to_csv(out_path, index=False)
    print(out.to_string())
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
