"""Per-point cost of a shaft-order sweep (issue 12, item 4) against the mesh-periodic one.

Run from the repository root::

    .venv/bin/python benchmarks/bench_shaft_orders.py [--points 21]

data/models/two_shaft.toml (132 DOFs) with and without one gear tooth's 5 µm spacing
error, up sweeps of 2600-2640 Hz (21 points, no fold; brief contact loss at the error
tooth), one BLAS thread, side by side in one run: the mesh-periodic sweep at H = 5, and
the sweep over the gear revolution (period 25) with H = 5 mesh harmonics, i.e. 125
harmonics of the shaft frequency (mesh harmonic 5 and every sideband up to it), each with
and without Floquet stability. Both on the link engine
(:func:`~nlgrd.nonlinear.models.link_model.link_sweep`, ``period=1``): the plain model's
plan base is the mesh frequency, the tooth error's the gear revolution (mesh/25,
``top_order`` 25), so its sweep runs at ω_mesh/25 with 5 x 25 harmonics. Figures and
machine in benchmarks/README.md (the recorded table was measured with the single-mesh
engine's mesh-periodic and shaft-order sweeps, since deleted).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np
from bench_nonlinear import machine_lines
from threadpoolctl import threadpool_limits

from nlgrd.gear.modifications import GearErrors
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep

MODELS = Path(__file__).resolve().parents[1] / "data" / "models"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=21, help="sweep points (default 21; 3 for a smoke run)")
    args = ap.parse_args()
    for line in machine_lines():
        print(line)
    plain = load_model(MODELS / "two_shaft.toml")
    g = plain.gear_pairs[0]
    spacing = np.zeros(g.geometry.teeth_gear)
    spacing[0] = 5e-6
    tooth = dataclasses.replace(
        plain, gear_pairs=(dataclasses.replace(g, errors=GearErrors(spacing_gear=spacing)),)
    )
    omegas = 2 * np.pi * np.linspace(2600.0, 2640.0, args.points)
    m1 = build_link_model(plain)
    mN = build_link_model(tooth)  # plan base: the gear revolution, mesh/N
    N = mN.top_order
    HN = 5 * N  # H = 5 mesh harmonics on the revolution's base
    # warm-up: modal bases, state spaces and caches out of the timing
    link_sweep(m1, omegas[:2], H=5, directions="up", period=1)
    link_sweep(mN, omegas[:2] / N, H=HN, directions="up", period=1)
    rows = []
    with threadpool_limits(1):
        for stability in (False, True):
            t0 = time.perf_counter()
            r1 = link_sweep(m1, omegas, H=5, directions="up", stability=stability, period=1).result
            t1 = time.perf_counter()
            stamps = []
            rN = link_sweep(
                mN,
                omegas / N,
                H=HN,
                directions="up",
                stability=stability,
                period=1,
                progress=lambda i, n, stamps=stamps: stamps.append(time.perf_counter()),
            ).result
            t2 = time.perf_counter()
            n = omegas.size
            each = np.diff([t1, *stamps[1:], t2])  # a point's work ends when the next begins
            rows.append((stability, 1e3 * (t1 - t0) / n, 1e3 * (t2 - t1) / n, r1, rN, each))
    print(
        "| stability | mesh-periodic, H = 5 | revolution, H = 5 (125 of the shaft frequency): mean "
        "| median point | slowest point | ratio of means |"
    )
    print("|---|---|---|---|---|---|")
    for stability, a, b, r1, rN, each in rows:
        ok1 = f"{int(np.sum(r1.converged))}/{r1.omega.size}"
        okN = f"{int(np.sum(rN.converged))}/{rN.omega.size}"
        print(
            f"| {stability} | {a:.1f} ms ({ok1}) | {b:.1f} ms ({okN}) | {1e3 * np.median(each):.0f} ms "
            f"| {each.max():.1f} s | {b / a:.0f}x |"
        )


if __name__ == "__main__":
    main()
