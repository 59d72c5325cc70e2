"""The landing search at points without a stable orbit, with and without its ceiling
(issue 34, item 2).

Run from the repository root::

    .venv/bin/python benchmarks/bench_landing.py

idler_train.toml, up sweep (``link_sweep``, H = 9, 15 mesh frequencies 1000-1700 Hz, one
BLAS thread), warmed up on 2 points, run twice side by side in one process: with
``jump_to_branch``'s ceiling :data:`~nlgrd.nonlinear.tracing.arclength.LANDING_EVALUATIONS`
(the default) and without it (``max_evaluations=None``, the search before issue 34).
Prints the time per point, the corrector evaluations of each search, and whether every
point's answer (convergence, stability, no-stable flag, branch switch, harmonics to
1e-8 relative) is the same. Figures in benchmarks/README.md.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

import nlgrd.nonlinear.tracing.arclength as arclength
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep

IDLER = Path(__file__).resolve().parents[1] / "data" / "models" / "idler_train.toml"
_EVALS = {"n": 0}


def _count() -> None:
    """Count corrector evaluations (Tracer.system calls)."""
    original = arclength.Tracer.system

    def system(self, u):
        _EVALS["n"] += 1
        return original(self, u)

    arclength.Tracer.system = system


def run(model, grid, ceiling):
    arclength.jump_to_branch.__kwdefaults__["max_evaluations"] = ceiling
    _EVALS["n"] = 0
    stamps, evals = [time.perf_counter()], [0]

    def progress(i, n):
        stamps.append(time.perf_counter())
        evals.append(_EVALS["n"])

    r = link_sweep(model, grid, H=9, directions="up", period=1, progress=progress).result
    return r, np.diff(stamps), np.diff(evals)


def main() -> None:
    _count()
    model = build_link_model(load_model(IDLER))
    grid = 2 * np.pi * np.linspace(1000.0, 1700.0, 15)
    with threadpool_limits(1):
        link_sweep(model, grid[:2], H=9, directions="up", period=1)  # warm-up, pole-residue set-up
        out = {}
        for label, ceiling in (("no ceiling", None), ("ceiling", arclength.LANDING_EVALUATIONS)):
            out[label] = run(model, grid, ceiling)
            r, dt, ev = out[label]
            print(f"{label}: {dt.sum():.2f} s in total, {ev.sum()} corrector evaluations", flush=True)
    (a, ta, ea), (b, tb, eb) = out["no ceiling"], out["ceiling"]
    same_all = True
    for i, w in enumerate(grid):
        za, zb = np.ravel(a.harmonics[i]), np.ravel(b.harmonics[i])
        rel = float(np.linalg.norm(za - zb) / max(np.linalg.norm(za), 1e-300))
        flags = ("converged", "stable", "no_stable", "branch_switch")
        differ = [f for f in flags if bool(getattr(a, f)[i]) != bool(getattr(b, f)[i])]
        same = not differ and rel <= 1e-8
        same_all &= same
        kind = "no stable" if a.no_stable[i] else ("stable" if a.stable[i] else "unstable")
        print(
            f"{w / 2 / np.pi:7.1f} Hz {kind:9s}: {1e3 * ta[i]:8.0f} ms ({ea[i]:4d} evals) -> "
            f"{1e3 * tb[i]:6.0f} ms ({eb[i]:4d} evals), same answer {same} (harmonics {rel:.0e})"
            + (f", differ: {', '.join(differ)}" if differ else ""),
            flush=True,
        )
    print(f"every point the same: {same_all}; total {ta.sum():.2f} s -> {tb.sum():.2f} s", flush=True)


if __name__ == "__main__":
    main()
