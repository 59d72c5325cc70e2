"""The cost of a torus try where no torus exists, before and after the stall stop and the
one-factorisation κ derivative (issue 35 item 2, issue 34 item 4), side by side in one
process.

Kahraman & Blankenship's rig (data/case_studies/kahraman_blankenship.toml) at Neimark-Sacker
points of its fast report, each tried as a sweep tries it (``converged_tori``'s settings:
H₁ 13, H₂ 4, 25 iterations, two start sizes, no check) on its link model (one mesh, the
torus every sweep tries: :class:`~nlgrd.nonlinear.tracing.link_torus.LinkTorus`), the
periodic orbit solved afresh:
"before" with the stall stop off and dR/dω₂ by central differences of κ (the former solve),
"after" as the code runs now. Printed per point: CPU time, Newton iterations, sparse LUs of
the full model (κ frequencies) and whether a torus converged (with its ω₂ and RMS DTE, the
same before and after).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_torus_fail.py [Hz ...]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.hb import quasi_periodic as qp
from nlgrd.nonlinear.models.link_model import build_link_model
from nlgrd.nonlinear.tracing import torus_sweep as ts
from nlgrd.nonlinear.tracing.link_torus import LinkTorus

ROOT = Path(__file__).resolve().parent.parent
#: Neimark-Sacker points of the fast report (60 points, 800-6000 Hz) where the periodic
#: solve from rest lands on the unstable orbit: five chaotic gaps and two tori.
POINTS_HZ = (2386.4, 3620.3, 4942.4, 5118.6, 5559.3, 1593.2, 5471.2)


def _target(model, before: bool, count: dict) -> LinkTorus:
    target = LinkTorus(model)
    tm = target.torus_model
    plain, slope = tm.kappa_at, tm.kappa_slope_at

    def kappa_at(freqs, omega):
        count["lu"] += len(freqs)
        return plain(freqs, omega)

    def kappa_slope_at(freqs, omega):
        count["lu"] += len(freqs)
        return slope(freqs, omega)

    tm.kappa_at = kappa_at
    tm.kappa_slope_at = None if before else kappa_slope_at
    return target


def one(model, w: float, before: bool) -> dict:
    """One point tried as a sweep tries it; CPU seconds, iterations, LUs, the torus."""
    count = {"lu": 0, "newton": 0}
    target = _target(model, before, count)
    original = qp.solve_torus

    def solve(*args, **kwargs):
        sol = original(*args, **({**kwargs, "stall": False} if before else kwargs))
        count["newton"] += sol.iterations
        return sol

    qp.solve_torus = solve
    try:
        c0 = time.process_time()
        res = ts.torus_sweep(
            model,
            [w],
            H=13,
            H2=4,
            check=False,
            tol=ts.ANSWER_TOL,
            max_iter=ts.ANSWER_MAX_ITER,
            start_sizes=ts.ANSWER_START_SIZES,
            target=target,
        )
        cpu = time.process_time() - c0
    finally:
        qp.solve_torus = original
    return {
        "cpu": cpu,
        **count,
        "torus": bool(res.converged[0]),
        "w2": res.output("secondary_frequency")[0],
        "dte_rms": res.output("dte_rms")[0],
    }


def main(points_hz=POINTS_HZ) -> None:
    system = load_model(ROOT / "data" / "case_studies" / "kahraman_blankenship.toml")
    model = build_link_model(system)  # one mesh: the link torus every sweep tries
    head = f"{'f [Hz]':>8} | {'before: CPU s, its, LUs':>26} | {'after: CPU s, its, LUs':>26}"
    print(head + " | torus (ω₂ [Hz], RMS DTE [um])")
    for f in points_hz:
        w = 2 * np.pi * f
        b, a = one(model, w, True), one(model, w, False)
        same = b["torus"] == a["torus"]
        torus = "none" if not a["torus"] else f"{a['w2'] / 2 / np.pi:.6f} Hz, {1e6 * a['dte_rms']:.6f} um"
        if a["torus"] and b["torus"]:
            same = abs(a["w2"] / b["w2"] - 1) < 1e-8 and abs(a["dte_rms"] / b["dte_rms"] - 1) < 1e-8
        cols = [f"{r['cpu']:7.2f} {r['newton']:4d} {r['lu']:8d}" for r in (b, a)]
        print(f"{f:8.1f} | {cols[0]:>26} | {cols[1]:>26} | {torus}{'' if same else ' (DIFFERS from before)'}")


if __name__ == "__main__":
    main(tuple(float(x) for x in sys.argv[1:]) or POINTS_HZ)
