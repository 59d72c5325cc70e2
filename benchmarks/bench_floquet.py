"""Per-point cost with Floquet stability of geared link models, and the Floquet share
(issue 34, item 1 and 5).

Run from the repository root::

    .venv/bin/python benchmarks/bench_floquet.py [--stage-points 3]
    git show <commit>:nlgrd/nonlinear/stability/floquet.py > /tmp/floquet_before.py
    .venv/bin/python benchmarks/bench_floquet.py --before /tmp/floquet_before.py --models 3

``--before FILE``: the same sweeps side by side in this process with the
``floquet_multipliers`` of another version of ``nlgrd/nonlinear/stability/floquet.py`` (before,
after, before, after; the best of two each; the idler on its stable points only), with
the verdicts and dominant multipliers of both compared.

Up sweeps (``link_sweep``, fixed H, one BLAS thread) side by side in one process:
two_shaft.toml (one mesh), the same rotor with the pinion's free-end bearing replaced by
a 20 µm Hertzian clearance (1e10 N/m^1.5, 1e3 N s/m), idler_train.toml (two meshes), 15
mesh frequencies 1000-1700 Hz at H = 9, and two_stage.toml (base 5 x input speed, H =
45) on fewer points. Each model is warmed up on 2 points first (pole-residue set-up).
The time inside ``floquet_multipliers`` is measured by wrapping it where the sweep
modules imported it; the points without a stable orbit are counted apart, since their
cost is the landing search, not Floquet. Figures in benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

import nlgrd.nonlinear.stability.floquet as floquet
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.links.contract import BearingClearance
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep

MODELS = Path(__file__).resolve().parents[1] / "data" / "models"
_SPENT = {"t": 0.0, "n": 0}


def _wrap(original=None) -> None:
    """Time every call of ``original`` (default floquet_multipliers), installed wherever a
    module imported floquet_multipliers."""
    original = floquet.floquet_multipliers if original is None else original

    def timed(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            _SPENT["t"] += time.perf_counter() - t0
            _SPENT["n"] += 1

    for name, mod in list(sys.modules.items()):
        if name.startswith("nlgrd") and mod is not floquet and hasattr(mod, "floquet_multipliers"):
            mod.floquet_multipliers = timed


def side_by_side(before_file: str, n_models: int) -> None:
    """Before/after in one process (module docstring)."""
    spec = importlib.util.spec_from_file_location("floquet_before", before_file)
    before = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = before  # dataclasses look their module up there
    spec.loader.exec_module(before)
    print(subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip(), flush=True)
    best, answers = {}, {}
    with threadpool_limits(1):
        for _, (label, model, omegas, H) in zip(range(n_models), cases(0), strict=False):
            if label.startswith("idler"):  # its stable points: the others cost the landing search
                _wrap()
                r = link_sweep(model, omegas, H=H, directions="up", period=1).result
                omegas = omegas[r.converged & r.stable.astype(bool)]
                label = f"{label}, its {omegas.size} stable points"
            for tag, fn in (
                ("before", before.floquet_multipliers),
                ("after", floquet.floquet_multipliers),
            ) * 2:
                _wrap(fn)
                link_sweep(model, omegas[:2], H=H, directions="up", period=1)
                _SPENT.update(t=0.0, n=0)
                t0 = time.perf_counter()
                r = link_sweep(model, omegas, H=H, directions="up", period=1).result
                total = time.perf_counter() - t0
                per, fl = 1e3 * total / omegas.size, 1e3 * _SPENT["t"] / omegas.size
                print(
                    f"{label} [{tag}]: {per:.1f} ms per point, "
                    f"Floquet {fl:.1f} ms ({100 * _SPENT['t'] / total:.0f} %)"
                )
                if per < best.get((label, tag), (np.inf,))[0]:
                    best[label, tag] = (per, fl)
                answers.setdefault(label, {})[tag] = r
    print(subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip(), flush=True)
    one = next(iter(answers))
    for (label, tag), (per, fl) in best.items():
        print(
            f"best {label} [{tag}]: {per:.1f} ms per point (Floquet {fl:.1f}), "
            f"{per / best[one, tag][0]:.1f}x one mesh"
        )
    for label, d in answers.items():
        a, b = d["before"], d["after"]
        same = np.array_equal(a.stable, b.stable) and np.array_equal(a.converged, b.converged)
        diff = float(np.nanmax(np.abs(np.abs(a.dominant_multiplier) - np.abs(b.dominant_multiplier))))
        print(f"{label}: verdicts identical {same}, largest change of |dominant multiplier| {diff:.1e}")


def cases(stage_points: int):
    two = load_model(MODELS / "two_shaft.toml")
    grid = 2 * np.pi * np.linspace(1000.0, 1700.0, 15)
    bearings = tuple(b for i, b in enumerate(two.bearings) if i != 1)
    clear = dataclasses.replace(
        two,
        bearings=bearings,
        bearing_clearances=(BearingClearance("B1", 0, 8, 20e-6, 1e10, exponent=1.5, damping=1e3),),
    )
    yield "two_shaft, 1 mesh", build_link_model(two), grid, 9
    yield "two_shaft, mesh + 20 µm Hertzian clearance", build_link_model(clear), grid, 9
    yield "idler_train, 2 meshes", build_link_model(load_model(MODELS / "idler_train.toml")), grid, 9
    if stage_points:
        stage = build_link_model(load_model(MODELS / "two_stage.toml"))
        yield (
            "two_stage, 2 meshes, base 5 x shaft",
            stage,
            np.linspace(grid[0], grid[-1], stage_points) / 5,
            45,
        )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--stage-points", type=int, default=3)
    ap.add_argument("--models", type=int, default=4, help="the first this many models only")
    ap.add_argument("--before", help="another floquet.py to run side by side (module docstring)")
    args = ap.parse_args()
    if args.before:
        side_by_side(args.before, min(args.models, 3))
        return
    _wrap()
    rows = []
    with threadpool_limits(1):
        for _, (label, model, omegas, H) in zip(range(args.models), cases(args.stage_points), strict=False):
            link_sweep(model, omegas[:2], H=H, directions="up", period=1)  # warm-up, pole-residue set-up
            _SPENT.update(t=0.0, n=0)
            t0 = time.perf_counter()
            r = link_sweep(model, omegas, H=H, directions="up", period=1).result
            total = time.perf_counter() - t0
            stable = r.converged & r.stable.astype(bool)
            per, fl = 1e3 * total / omegas.size, 1e3 * _SPENT["t"] / omegas.size
            rows.append((label, per))
            print(
                f"{label}: {per:.1f} ms per point, Floquet {fl:.1f} ms per point "
                f"({_SPENT['n']} calls, {100 * _SPENT['t'] / total:.0f} %), "
                f"{int(stable.sum())}/{omegas.size} stable",
                flush=True,
            )
            if not stable.all() and stable.any():  # the stable points alone: no landing search
                _SPENT.update(t=0.0, n=0)
                t0 = time.perf_counter()
                link_sweep(model, omegas[stable], H=H, directions="up", period=1)
                t = time.perf_counter() - t0
                print(
                    f"  the {int(stable.sum())} stable points alone: "
                    f"{1e3 * t / stable.sum():.1f} ms per point, "
                    f"Floquet {1e3 * _SPENT['t'] / stable.sum():.1f} ms per point",
                    flush=True,
                )
    base = rows[0][1]
    for label, per in rows[1:]:
        print(f"{label}: {per / base:.1f}x one mesh", flush=True)


if __name__ == "__main__":
    main()
