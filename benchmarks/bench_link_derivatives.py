"""One dκ_k/dω + dF_k/dω evaluation of the banded link path.

`.venv/bin/python benchmarks/bench_link_derivatives.py [--sweep]` (about 15 s; with
``--sweep`` one more minute). two_shaft.toml, one BLAS thread: the per-call time of
``LinkReceptance.derivatives`` (κ_k and F_k included: each call at a new frequency), then
of one frequency's dκ_k/dω, dF_k/dω, κ_k and F_k on the link model's reduced model (what
the arc-length corrector asks), at H = 7 and 17 over 200 frequencies 1000-2900 Hz, the
best of three rounds; with ``--sweep`` the CPU time of
``nlgrd.sweep(two_shaft, hz=np.linspace(1000, 2900, 40), time_domain=False)``.

The single-mesh engine's side (its mesh receptance's ``kappa_derivative`` and its reduced
model) is deleted: its figures stay in benchmarks/README.md as recorded history.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

import nlgrd
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model

MODEL = Path(__file__).resolve().parents[1] / "data" / "models" / "two_shaft.toml"


def per_call(run, omegas, rounds: int = 3, first: int = 1) -> float:
    """Best over ``rounds`` of the mean time [ms] of ``run(ω)``, each round at frequencies
    shifted by a new offset (rounds ``first``, ``first`` + 1, ...: no cache hit)."""
    best = np.inf
    for r in range(rounds):
        ws = omegas * (1 + 1e-7 * (r + first))
        t0 = time.perf_counter()
        for w in ws:
            run(float(w))
        best = min(best, 1e3 * (time.perf_counter() - t0) / ws.size)
    return best


def main() -> None:
    system = load_model(MODEL)
    omegas = 2 * np.pi * np.linspace(1000.0, 2900.0, 200)
    with threadpool_limits(1):
        for H in (7, 17):
            lm = build_link_model(system)
            rec = lm.receptance
            rec.derivatives(omegas[0], H)  # warm-up: solver set-up
            link = per_call(lambda w, rec=rec, H=H: rec.derivatives(w, H), omegas)
            print(f"H={H}: link ({rec.method}) derivatives {link:.3f} ms per call", flush=True)
            # what the corrector asks at one frequency: dκ, dF, then κ, F
            r = lm.reduced

            def run(w, r=r, H=H):
                r.kappa_derivative(w, H), r.force_derivative(w, H), r.kappa(w, H), r.force(w, H)

            run(omegas[0] * 1.01)
            each = per_call(run, omegas, first=10)
            print(f"H={H}: dκ, dF, κ, F per frequency: link {each:.3f} ms", flush=True)
        if "--sweep" in sys.argv:
            t0, c0 = time.perf_counter(), time.process_time()
            res = nlgrd.sweep(system, hz=np.linspace(1000, 2900, 40), time_domain=False)
            print(
                f"nlgrd.sweep two_shaft 40 points: {time.process_time() - c0:.1f} s CPU, "
                f"{time.perf_counter() - t0:.1f} s wall",
                flush=True,
            )
            print(f"  {type(res).__name__}", flush=True)


if __name__ == "__main__":
    main()
