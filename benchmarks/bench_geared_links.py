"""Per-point cost of geared link models (issue 11): one mesh on the link path, a mesh with
a bearing clearance, two meshes.

Run from the repository root (``--evaluations``: only the per-evaluation timing;
``--banded``: only the single mesh on the link path's strategies (banded, pole-residue,
dense LU) against each other;
``--hertz [--idler]``: one mesh against mesh + Hertzian clearance with stability, the
clearance's Floquet on the truncated basis and on the full state, and the idler train)::

    .venv/bin/python benchmarks/bench_geared_links.py [--evaluations | --banded | --hertz [--idler]]
        [--rounds N]

Up sweeps with Floquet stability, one BLAS thread, fixed H: the single mesh
(data/models/two_shaft.toml, 132 DOFs, H = 9, mesh frequency 1000-1700 Hz, 15 points) on
the link reduction (`nlgrd.nonlinear.models.link_model.link_sweep`); then two_shaft with
the pinion's free-end bearing replaced by a 20 µm radial clearance with Hertzian contact
(2 links, 3 coordinates), the idler train (2 meshes, 198 DOFs) and the two-stage reduction
(2 meshes, base = 5 x the input speed, H = 45), each on its own grid. The link path runs
with the pole-residue reduction (the default, but for the single mesh whose default is now
the banded LU, issue 33: forced here, the banded LU a row of its own) and, for the trains,
also with a direct LU of Z_k per point (``method="direct"``); the pole-residue set-up (one
eigendecomposition per harmonic) is timed apart, in the warm-up on two points. Figures and
machine in benchmarks/README.md; its rows of the single-mesh engine (the mesh-receptance
path, ``--banded``'s "single path") are recorded history: that engine is deleted and no
longer measured here.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.links.contract import BearingClearance
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep

MODELS = Path(__file__).resolve().parents[1] / "data" / "models"


def _timed(label: str, run, n: int) -> None:
    t0 = time.perf_counter()
    ok = run()
    per = 1e3 * (time.perf_counter() - t0) / n
    print(f"{label}: {per:.1f} ms per point ({ok}/{n} stable)", flush=True)


def evaluations() -> None:
    """Per evaluation of κ_k, F_k and their ω-derivatives, pole-residue against direct LU."""
    from nlgrd.nonlinear.reduction.link_reduction import LinkReceptance

    for name, H in (("idler_train", 9), ("two_stage", 45)):
        system = load_model(MODELS / f"{name}.toml")
        rec = build_link_model(system).receptance
        direct = LinkReceptance(
            system, rec.links, rec.plan, rec.static_force, rec.harmonic_force, method="direct"
        )
        t0 = time.perf_counter()
        rec.terms(2 * np.pi * 100.0, H)
        setup = time.perf_counter() - t0
        times = {"poles": [], "direct": []}
        for f in (200.0, 777.0, 1000.0, 1500.0, 3000.0):
            w = 2 * np.pi * f / (5 if name == "two_stage" else 1)
            for label, r in (("poles", rec), ("direct", direct)):
                t0 = time.perf_counter()
                r.terms(w, H)
                r.derivatives(w, H)
                times[label].append(1e3 * (time.perf_counter() - t0))
        print(
            f"{name}, H = {H}: set-up {setup:.1f} s; per evaluation poles "
            f"{min(times['poles']):.1f}-{max(times['poles']):.1f} ms, direct "
            f"{min(times['direct']):.1f}-{max(times['direct']):.1f} ms",
            flush=True,
        )


def main() -> None:
    two = load_model(MODELS / "two_shaft.toml")
    grid = 2 * np.pi * np.linspace(1000.0, 1700.0, 15)
    bearings = tuple(b for i, b in enumerate(two.bearings) if i != 1)
    clear = dataclasses.replace(
        two,
        bearings=bearings,
        bearing_clearances=(BearingClearance("B1", 0, 8, 20e-6, 1e10, exponent=1.5, damping=1e3),),
    )
    idler, stage = load_model(MODELS / "idler_train.toml"), load_model(MODELS / "two_stage.toml")
    cases = [
        ("two_shaft, 1 mesh, link path", build_link_model(two, method="poles"), grid, 9),
        ("two_shaft, 1 mesh, link path, direct LU", build_link_model(two, method="direct"), grid, 9),
        ("two_shaft, 1 mesh, link path, banded LU", build_link_model(two, method="banded"), grid, 9),
        ("two_shaft, mesh + clearance (2 links)", build_link_model(clear), grid, 9),
        ("idler_train, 2 meshes", build_link_model(idler), grid, 9),
        ("idler_train, 2 meshes, direct LU", build_link_model(idler, method="direct"), grid, 9),
        ("two_stage, 2 meshes, base 5 x shaft", build_link_model(stage), grid / 5, 45),
        ("two_stage, 2 meshes, direct LU", build_link_model(stage, method="direct"), grid / 5, 45),
    ]
    with threadpool_limits(1):
        res = {}
        for label, model, omegas, H in cases:
            t0 = time.perf_counter()
            link_sweep(model, omegas[:2], H=H, directions="up", period=1)  # warm-up, pole-residue set-up
            print(f"{label}: warm-up on 2 points {time.perf_counter() - t0:.2f} s", flush=True)

            def run(model=model, omegas=omegas, H=H, label=label):
                r = link_sweep(model, omegas, H=H, directions="up", period=1).result
                res[label] = r
                return int(np.sum(r.converged & r.stable.astype(bool)))

            _timed(label, run, omegas.size)
    a, b = res["two_shaft, 1 mesh, link path, banded LU"], res["two_shaft, 1 mesh, link path"]
    both = a.converged & b.converged
    diff = np.max(np.abs(a.harmonics[both] - b.harmonics[both])) / np.max(np.abs(a.harmonics[both]))
    print(f"single mesh, banded LU and pole-residue harmonics differ by {diff:.1e}", flush=True)


def banded(rounds: int = 2) -> None:
    """One mesh: ``link_sweep`` with the link path's banded LU (``method="banded"``), its
    pole-residue form (forced) and its dense LU, on two_shaft.toml and kubo.toml, H = 9, up
    sweeps of 15 mesh frequencies 1000-1700 Hz, stability on and off. Each model built and
    warmed up on two points (set-up timed apart); then ``rounds`` rounds of the three in
    turn, the fastest round of each reported (the machine is shared). Last, the largest
    difference of the pole-residue and dense-LU harmonics from the banded ones over the
    converged points. (The recorded rows of the single-mesh engine's sweep in
    benchmarks/README.md are history: that engine is deleted.)"""
    grid = 2 * np.pi * np.linspace(1000.0, 1700.0, 15)
    H = 9
    files = (("two_shaft", MODELS / "two_shaft.toml"), ("kubo", MODELS.parent / "case_studies" / "kubo.toml"))
    for name, path in files:
        system = load_model(path)
        for stability in (True, False):
            head, runs = f"{name}, stability {stability}", {}
            for method in ("banded", "poles", "direct"):
                t0 = time.perf_counter()
                model = build_link_model(system, method=method)
                link_sweep(model, grid[:2], H=H, directions="up", period=1, stability=stability)
                label = f"link_sweep ({model.receptance.method})"
                print(f"{head}, {label}: set-up, 2 points {time.perf_counter() - t0:.2f} s", flush=True)

                def link(model=model, stability=stability):
                    return link_sweep(model, grid, H=H, directions="up", period=1, stability=stability).result

                runs[method] = (label, link)
            best, out = {}, {}
            for _ in range(rounds):
                for key, (_, run) in runs.items():
                    t0 = time.perf_counter()
                    out[key] = run()
                    best[key] = min(best.get(key, np.inf), 1e3 * (time.perf_counter() - t0) / grid.size)
            for key, per in best.items():
                r = out[key]
                ok = int(np.sum(r.converged & (r.stable.astype(bool) | (not stability))))
                tag = "stable" if stability else "converged"
                print(f"{head}, {runs[key][0]}: {per:.1f} ms per point ({ok}/15 {tag})", flush=True)
            a = out["banded"]
            for other in ("poles", "direct"):
                b = out[other]
                both = a.converged & b.converged
                scale = np.max(np.abs(a.harmonics[both]))
                diff = np.max(np.abs(a.harmonics[both] - b.harmonics[both])) / scale
                print(f"{head}: banded and {other} harmonics differ by {diff:.1e} of the largest", flush=True)


def _clearance_model(system):
    """``system`` with the pinion's free-end bearing replaced by a 20 µm Hertzian clearance."""
    node = system.bearings[1].node
    return dataclasses.replace(
        system,
        bearings=tuple(b for i, b in enumerate(system.bearings) if i != 1),
        bearing_clearances=(BearingClearance("B1", 0, node, 20e-6, 1e10, exponent=1.5, damping=1e3),),
    )


def scaling(factors=(1, 8, 25, 83), only: str | None = None) -> None:
    """Per-point cost against model size: two_shaft.toml with every element split in
    ``factors`` (132 to 9 972 DOFs), one mesh (with and without stability) and mesh +
    clearance, the default method (pole-residue up to 300 DOFs, modal basis above; since
    issue 33 the banded LU for the single mesh at 132 DOFs) and,
    at the smallest size, the modal basis too. Set-up (basis, pole-residue forms, mean
    factor, two warm-up points) timed apart."""
    from nlgrd.rotor.system import refined

    two = load_model(MODELS / "two_shaft.toml")
    grid = 2 * np.pi * np.linspace(1000.0, 1700.0, 15)
    H = 9
    cases = (("1 mesh", two, True), ("1 mesh", two, False), ("mesh + clearance", _clearance_model(two), True))
    cases = tuple(c for c in cases if only is None or c[0] == only)
    for factor in factors:
        for label, base, stability in cases:
            system = refined(base, factor)
            for method in ("auto", "modal") if system.n_dofs <= 300 else ("auto",):
                t0 = time.perf_counter()
                model = build_link_model(system, method=method, max_frequency=H * grid[-1])
                link_sweep(model, grid[:2], H=H, directions="up", period=1, stability=stability)
                setup = time.perf_counter() - t0
                t0 = time.perf_counter()
                r = link_sweep(model, grid, H=H, directions="up", period=1, stability=stability).result
                per = 1e3 * (time.perf_counter() - t0) / grid.size
                rec = model.receptance
                basis = (
                    ""
                    if rec.basis is None
                    else f", basis {rec.basis.shape[1]} / {rec._stability[1].shape[0]}"
                )
                ok = int(np.sum(r.converged & (r.stable.astype(bool) | (not stability))))
                print(
                    f"{system.n_dofs} DOFs, {label}, stability {stability}, {method} ({rec.method}{basis}): "
                    f"set-up {setup:.2f} s, {per:.1f} ms per point ({ok}/{grid.size} converged"
                    f"{' and stable' if stability else ''})",
                    flush=True,
                )


def hertz(rounds: int = 2, idler: bool = False) -> None:
    """One mesh against mesh + 20 µm Hertzian clearance (data/models/two_shaft_clearance.toml)
    with stability, equal H = 9, up sweeps of 15 mesh frequencies 1000-1700 Hz: the
    clearance's Floquet on the truncated basis (the default since issue 34 item 1) and on
    the full state (its stability basis's ``state_space`` replaced by ``full_state``). Each
    model built and warmed up on two points; ``rounds`` rounds of the three in turn, the
    fastest of each reported, with the time inside Floquet (``floquet_multipliers``) and,
    per state dimension, inside each basis's analysis (``floquet._analysis``). Last, the
    largest difference of max |μ| of the two clearance runs and their verdicts. With
    ``idler``, also idler_train.toml (2 meshes) on the points of the grid where one sweep
    found a stable orbit (the others take the landing search, issue 34 item 2)."""
    import sys

    from nlgrd.nonlinear.stability import floquet

    spent = {"floquet": 0.0}
    original, analysis = floquet.floquet_multipliers, floquet._analysis

    def timed(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            spent["floquet"] += time.perf_counter() - t0

    def timed_analysis(state_space, *args):
        t0 = time.perf_counter()
        try:
            return analysis(state_space, *args)
        finally:
            key = f"n={state_space.M.shape[0]}"
            spent[key] = spent.get(key, 0.0) + time.perf_counter() - t0

    floquet._analysis = timed_analysis
    for name, mod in list(sys.modules.items()):
        if name.startswith("nlgrd") and mod is not floquet and hasattr(mod, "floquet_multipliers"):
            mod.floquet_multipliers = timed
    grid = 2 * np.pi * np.linspace(1000.0, 1700.0, 15)
    H = 9
    one = build_link_model(load_model(MODELS / "two_shaft.toml"))
    clear = build_link_model(load_model(MODELS / "two_shaft_clearance.toml"))
    full = build_link_model(load_model(MODELS / "two_shaft_clearance.toml"))
    stab = full.receptance.stability
    stab.state_space = lambda omega, speed: stab.full_state(speed)
    runs = {
        "one mesh": one,
        "mesh + clearance, truncated basis": clear,
        "mesh + clearance, full state": full,
    }
    grids = dict.fromkeys(runs, grid)
    if idler:
        model = build_link_model(load_model(MODELS / "idler_train.toml"))
        r = link_sweep(model, grid, H=H, directions="up", period=1).result
        runs["idler_train, 2 meshes, its stable points"] = model
        grids["idler_train, 2 meshes, its stable points"] = grid[r.converged & r.stable.astype(bool)]
    for label, model in runs.items():
        t0 = time.perf_counter()
        link_sweep(model, grids[label][:2], H=H, directions="up", period=1)
        print(f"{label}: set-up, 2 points {time.perf_counter() - t0:.2f} s", flush=True)
    best, out = {}, {}
    for _ in range(rounds):
        for label, model in runs.items():
            for key in spent:
                spent[key] = 0.0
            t0 = time.perf_counter()
            out[label] = link_sweep(model, grids[label], H=H, directions="up", period=1).result
            n = grids[label].size
            per = 1e3 * (time.perf_counter() - t0) / n
            if per < best.get(label, (np.inf,))[0]:
                best[label] = (per, {k: 1e3 * v / n for k, v in spent.items() if v > 0})
    for label, (per, parts) in best.items():
        r = out[label]
        ok = int(np.sum(r.converged & r.stable.astype(bool)))
        split = ", ".join(f"{k} {v:.1f}" for k, v in parts.items())
        print(f"{label}: {per:.1f} ms per point ({ok}/{r.omega.size} stable; ms per point: {split})")
    ref = best["one mesh"][0]
    for label in list(runs)[1:]:
        print(f"{label} against one mesh: {best[label][0] / ref:.1f}x", flush=True)
    a, b = out["mesh + clearance, truncated basis"], out["mesh + clearance, full state"]
    both = a.converged & b.converged
    diff = np.max(np.abs(a.floquet_max[both] - b.floquet_max[both]))
    same = int(np.sum(a.stable[both] == b.stable[both]))
    print(f"clearance: max |μ| truncated - full state {diff:.1e}, verdicts equal {same}/{int(both.sum())}")


if __name__ == "__main__":
    import sys

    with threadpool_limits(1):
        if "--scaling" in sys.argv:
            scaling()
        elif "--scaling-clearance" in sys.argv:  # the mesh + clearance rows alone
            scaling(only="mesh + clearance")
        elif "--hertz" in sys.argv:  # --rounds N as --banded
            rounds = int(sys.argv[sys.argv.index("--rounds") + 1]) if "--rounds" in sys.argv else 2
            hertz(rounds, idler="--idler" in sys.argv)
        elif "--banded" in sys.argv:  # --rounds N: N rounds, the fastest reported (default 2)
            rounds = int(sys.argv[sys.argv.index("--rounds") + 1]) if "--rounds" in sys.argv else 2
            banded(rounds)
        else:
            evaluations()
            if "--evaluations" not in sys.argv:
                main()
