"""Issue 33's acceptance side by side: the single-mesh sweep on the link engine against the
deleted single-mesh engine, in one run.

Run from the repository root, with a worktree of the last commit that had the old engine::

    git worktree add ../wt-old bbfba76
    .venv/bin/python benchmarks/bench_against_deleted.py --old ../wt-old --repeats 3

``--case b`` (the default), case (b) of ``benchmarks/bench_nonlinear.py --cases 4``:
``data/models/two_shaft.toml`` as in the file (each tree's own copy; whether the two are
the same bytes is printed), 40 base frequencies 1000-2900 Hz both ways, H chosen,
stability, period "auto" (the link engine; the old ``geared_sweep`` has no period option),
model built inside the timing. ``--case a``, case (a): the same rotor with every shaft
element split in two (252 DOFs), mesh damping ratio 0.1, 2 x 500 mesh frequencies 0.5-1.5
x the gear pair's mode, H = 5, no stability, model built before the clock. Each run is
a fresh subprocess (``PYTHONPATH`` set to the tree measured, one BLAS thread), old and
link alternating, so both see the same load; the best of ``--repeats`` by CPU time is kept
per engine and the ratio link / old printed (target <= 1.10), with the load average
before each run, the corrector evaluations of the landing searches (``Tracer.system``
calls; both engines have it), the process time inside the landing searches
(``jump_to_branch``) and inside the Floquet analyses (``floquet_analysis``, every
caller's), and the points converged / stable / without a stable response. Figures and
machine in benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODEL = Path("data") / "models" / "two_shaft.toml"


def child(engine: str, case: str = "b") -> None:
    """Run case ``case`` in this process on the ``nlgrd`` of ``PYTHONPATH``; print one JSON line."""
    import numpy as np

    import nlgrd
    import nlgrd.nonlinear.tracing.arclength as arclength
    from nlgrd.io.model_file import load_model

    evals = {"n": 0}
    original = arclength.Tracer.system

    def system(self, *args, **kwargs):
        evals["n"] += 1
        return original(self, *args, **kwargs)

    arclength.Tracer.system = system
    spent = {"landing": 0.0, "floquet": 0.0}
    _timed(arclength, "jump_to_branch", spent, "landing", ("sweep", "landing"))
    import nlgrd.nonlinear.stability.floquet as floquet

    _timed(floquet, "floquet_analysis", spent, "floquet", ())
    tree = Path(nlgrd.__file__).resolve().parents[1]
    if case == "a":
        return _child_a(engine, tree, evals)
    grid = 2 * np.pi * np.linspace(1000.0, 2900.0, 40)
    w0, c0 = time.perf_counter(), time.process_time()
    base = load_model(tree / MODEL)
    if engine == "old":
        from nlgrd.nonlinear.models.geared import geared_sweep

        res = geared_sweep(base, omegas=grid, H=None, model=None, stability=True).mesh
    else:
        from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep

        res = link_sweep(build_link_model(base), grid, None, stability=True, period="auto").result
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    _emit(tree, cpu, wall, res, evals["n"], spent, stable=int(np.sum(res.stable)))


def _emit(tree: Path, cpu: float, wall: float, res, evaluations: int, spent: dict, **extra) -> None:
    """Print one run's JSON line: times, H, counts of points, landing evaluations and the
    time inside the landing searches and the Floquet analyses (``extra``: case-specific)."""
    import numpy as np

    out = {
        "tree": str(tree),
        "cpu": cpu,
        "wall": wall,
        "H": int(res.H),
        "converged": int(np.sum(res.converged)),
        "no_stable": int(np.sum(res.no_stable)),
        "evaluations": evaluations,
        "landing": spent["landing"],
        "floquet": spent["floquet"],
        **extra,
    }
    print(json.dumps(out))


def _child_a(engine: str, tree: Path, evals: dict) -> None:
    """Case (a) of ``bench_nonlinear.py --cases 4``: two_shaft with every shaft element split
    in two (252 DOFs), mesh damping ratio 0.1, 2 x 500 mesh frequencies 0.5-1.5 x the gear
    pair's mode, H = 5, no stability; the model built before the clock (both engines)."""
    import dataclasses

    import numpy as np

    from nlgrd.io.model_file import load_model
    from nlgrd.rotor.modal import gear_pair_mode
    from nlgrd.rotor.system import refined

    system = refined(load_model(tree / MODEL), 2)
    gears = tuple(dataclasses.replace(g, damping_ratio=0.1) for g in system.gear_pairs)
    system = dataclasses.replace(system, gear_pairs=gears)
    f_mode = float(round(gear_pair_mode(system)[0]))
    grid = 2 * np.pi * np.linspace(0.5 * f_mode, 1.5 * f_mode, 500)
    if engine == "old":
        from nlgrd.nonlinear.models.geared import build_geared_model, geared_sweep

        model = build_geared_model(system, 5 * float(grid.max()), H=5)
        w0, c0 = time.perf_counter(), time.process_time()
        res = geared_sweep(system, omegas=grid, H=5, model=model, stability=False, period=1).mesh
    else:
        from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep

        model = build_link_model(system)
        model.receptance.prepare(5 * float(grid.max()))
        w0, c0 = time.perf_counter(), time.process_time()
        res = link_sweep(model, grid, 5, stability=False, period=1).result
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    _emit(tree, cpu, wall, res, evals["n"], {"landing": 0.0, "floquet": 0.0}, stable=-1, dofs=system.n_dofs)


def _timed(module, name: str, spent: dict, key: str, users: tuple[str, ...]) -> None:
    """Add the process time of ``module.name`` (outermost calls only) to ``spent[key]``, also
    where the modules ``nlgrd.nonlinear.tracing.<users>`` imported it by name."""
    import importlib

    original = getattr(module, name)
    depth = {"n": 0}

    def wrapper(*args, **kwargs):
        depth["n"] += 1
        c0 = time.process_time()
        try:
            return original(*args, **kwargs)
        finally:
            depth["n"] -= 1
            if not depth["n"]:
                spent[key] += time.process_time() - c0

    setattr(module, name, wrapper)
    for user in users:
        mod = importlib.import_module(f"nlgrd.nonlinear.tracing.{user}")
        if getattr(mod, name, None) is original:
            setattr(mod, name, wrapper)


def load() -> str:
    """The 1, 5 and 15 min load averages."""
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def cpu_model() -> str:
    """The processor's name (Linux), else platform.processor()."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def run(engine: str, tree: Path, case: str = "b") -> dict:
    """One subprocess run of ``engine`` on ``tree`` (case ``case``); its JSON result with the load before."""
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    before = load()
    out = subprocess.run(
        [sys.executable, str(Path(__file__).resolve()), "--child", engine, "--case", case],
        env=env,
        cwd=str(tree),
        capture_output=True,
        text=True,
        check=False,
    )
    if out.returncode != 0:
        sys.exit(f"{engine} run failed:\n{out.stderr[-3000:]}")
    res = json.loads(out.stdout.strip().splitlines()[-1])
    if Path(res["tree"]) != tree.resolve():
        sys.exit(f"{engine} imported nlgrd from {res['tree']}, not {tree}")
    res["load"] = before
    return res


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", help="worktree of the deleted engine (commit bbfba76)")
    ap.add_argument("--repeats", type=int, default=2, help="runs per engine, alternating (best kept)")
    ap.add_argument("--case", choices=("a", "b"), default="b", help="case of bench_nonlinear.py --cases 4")
    ap.add_argument("--child", choices=("old", "link"), help=argparse.SUPPRESS)
    cfg = ap.parse_args(argv)
    if cfg.child:
        child(cfg.child, cfg.case)
        return
    if not cfg.old:
        ap.error("--old is required (a worktree of commit bbfba76)")
    old = Path(cfg.old).resolve()
    same = (old / MODEL).read_bytes() == (ROOT / MODEL).read_bytes()
    print(f"machine: {cpu_model()}, {os.cpu_count()} CPUs; Python {platform.python_version()}")
    what = "2 x 40 points" if cfg.case == "b" else "elements split in two, 2 x 500 points, H 5, no stability"
    print(f"case ({cfg.case}): {MODEL} (the two trees' copies {'identical' if same else 'DIFFER'}), {what}")
    best: dict[str, dict] = {}
    for i in range(cfg.repeats):
        for engine, tree in (("old", old), ("link", ROOT)):
            r = run(engine, tree, cfg.case)
            print(
                f"run {i + 1} {engine:4s}: CPU {r['cpu']:6.2f} s, wall {r['wall']:6.2f} s, H {r['H']}, "
                f"conv/stable/no stable {r['converged']}/{r['stable']}/{r['no_stable']}, "
                f"corrector evaluations {r['evaluations']}, in landing searches {r['landing']:.2f} s, "
                f"in Floquet analyses {r['floquet']:.2f} s, load before {r['load']}",
                flush=True,
            )
            if engine not in best or r["cpu"] < best[engine]["cpu"]:
                best[engine] = r
    o, n = best["old"], best["link"]
    print(
        f"best of {cfg.repeats} by CPU: old {o['cpu']:.2f} s, link {n['cpu']:.2f} s, "
        f"link / old = {n['cpu'] / o['cpu']:.2f} (target <= 1.10); load at end {load()}"
    )
    print(
        f"of them: landing searches old {o['landing']:.2f} s, link {n['landing']:.2f} s; "
        f"Floquet analyses old {o['floquet']:.2f} s, link {n['floquet']:.2f} s; "
        f"the rest old {o['cpu'] - o['landing'] - o['floquet']:.2f} s, "
        f"link {n['cpu'] - n['landing'] - n['floquet']:.2f} s (Floquet at the searches' crossings "
        "counted in both)"
    )


if __name__ == "__main__":
    main()
