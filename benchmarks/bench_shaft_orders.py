"""Per-point cost of a shaft-order sweep (issue 12, item 4) against the mesh-periodic one.

Run from the repository root::

    .venv/bin/python benchmarks/bench_shaft_orders.py

data/models/two_shaft.toml (132 DOFs) with and without one gear tooth's 5 µm spacing
error, up sweeps of 2600-2640 Hz (21 points, no fold; brief contact loss at the error
tooth), one BLAS thread, side by side in one run: the mesh-periodic sweep at H = 5, and
the sweep over the gear revolution (period 25) with H = 5 mesh harmonics, i.e. 125
harmonics of the shaft frequency (mesh harmonic 5 and every sideband up to it), each with
and without Floquet stability. Figures and machine in benchmarks/README.md.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
from bench_nonlinear import machine_lines
from threadpoolctl import threadpool_limits

from nlgrd.gear.modifications import GearErrors
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.geared import build_geared_model, geared_sweep
from nlgrd.nonlinear.models.shaft_orders import shaft_order_model, shaft_order_sweep

MODELS = Path(__file__).resolve().parents[1] / "data" / "models"


def main() -> None:
    for line in machine_lines():
        print(line)
    plain = load_model(MODELS / "two_shaft.toml")
    g = plain.gear_pairs[0]
    spacing = np.zeros(g.geometry.teeth_gear)
    spacing[0] = 5e-6
    tooth = dataclasses.replace(
        plain, gear_pairs=(dataclasses.replace(g, errors=GearErrors(spacing_gear=spacing)),)
    )
    omegas = 2 * np.pi * np.linspace(2600.0, 2640.0, 21)
    m1 = build_geared_model(plain, omegas.max(), H=5)
    mN = shaft_order_model(tooth, omegas.max(), H=5)
    # warm-up: modal bases, state spaces and caches out of the timing
    geared_sweep(plain, omegas[:2], H=5, model=m1, directions="up", period=1)
    shaft_order_sweep(tooth, omegas[:2], H=5, model=mN, directions="up")
    rows = []
    with threadpool_limits(1):
        for stability in (False, True):
            t0 = time.perf_counter()
            r1 = geared_sweep(plain, omegas, H=5, model=m1, directions="up", stability=stability, period=1)
            t1 = time.perf_counter()
            stamps = []
            rN = shaft_order_sweep(
                tooth,
                omegas,
                H=5,
                model=mN,
                directions="up",
                stability=stability,
                progress=lambda i, n, stamps=stamps: stamps.append(time.perf_counter()),
            )
            t2 = time.perf_counter()
            n = omegas.size
            each = np.diff([t1, *stamps[1:], t2])  # a point's work ends when the next begins
            rows.append((stability, 1e3 * (t1 - t0) / n, 1e3 * (t2 - t1) / n, r1.mesh, rN.mesh, each))
    print(
        "| stability | mesh-periodic, H = 5 | revolution, H = 5 (125 of the shaft frequency): mean "
        "| median point | slowest point | ratio of means |"
    )
    print("|---|---|---|---|---|---|")
    for stability, a, b, r1, rN, each in rows:
        ok1, okN = int(np.sum(r1.converged)), int(np.sum(rN.converged))
        print(
            f"| {stability} | {a:.1f} ms ({ok1}/21) | {b:.1f} ms ({okN}/21) | {1e3 * np.median(each):.0f} ms "
            f"| {each.max():.1f} s | {b / a:.0f}x |"
        )


if __name__ == "__main__":
    main()
