"""Time answers under four OpenBLAS kernels and against 4x longer records (issue 35,
items 3-4): how often two standard uncertainties cover another record's value, and
whether a point's kind ("chaotic", "time domain" or "not found") depends on the kernel.

Kahraman & Blankenship's rig (data/case_studies/kahraman_blankenship.toml) swept as
notebook 02 sweeps it (800-6000 Hz, 300 points each way, H by the error estimate, landing
by arc length); the converged points without a stable orbit are the gaps, each started
from its unstable orbit as the sweep's time answer starts (velocities x 1.001). A record
is one integration with its Lyapunov twin (``time_answer._Run``); the answer's rule
(``time_answer._settle``) is replayed on its prefixes, which are what ``time_answer``
would have integrated (the integration is deterministic within a process). So one long
record per point and kernel gives the report's answer (256 -> 1024 periods) and, for the
default kernel, the 4x record (a prefix four times the answer's length).

Steps (OUT defaults to /tmp/time_answer_kernels)::

    python benchmarks/bench_time_answer_kernels.py starts        # [points], 300 by default
    python benchmarks/bench_time_answer_kernels.py record default 4096 sample
    python benchmarks/bench_time_answer_kernels.py record default 2048 screen
    OPENBLAS_CORETYPE=Haswell python benchmarks/bench_time_answer_kernels.py record Haswell 2048 sample
    OPENBLAS_CORETYPE=Haswell python benchmarks/bench_time_answer_kernels.py record Haswell 2048 near
    (the same for Sandybridge and Prescott)
    python benchmarks/bench_time_answer_kernels.py judge current current.json
    python benchmarks/bench_time_answer_kernels.py judge former former.json   # the rule of 5a1d1ae
    python benchmarks/bench_time_answer_kernels.py compare former.json current.json

``former`` replays the estimator and rule before this change (20 batch means with the
lag-1 gate at 2/√20; no extension beyond ``max_periods``), copied here to judge the same
records. Figures: benchmarks/README.md.

``starts`` sweeps with the link engine (:func:`~nlgrd.nonlinear.models.link_model.link_sweep`,
``period=1``, ``jump="auto"``): the row numbers of SAMPLE, SCREEN, NEAR and NEAR2 are
indices into the link engine's gap list. The recorded figures were made from the
single-mesh engine's sweep (deleted), whose gap list may differ: rerun
``starts`` and check the rows before comparing with them.
"""

from __future__ import annotations

import glob
import json
import math
import os
import pickle
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
OUT = Path(os.environ.get("OUT", "/tmp/time_answer_kernels"))
KB = ROOT / "data/case_studies/kahraman_blankenship.toml"
KERNELS = ("default", "Haswell", "Sandybridge", "Prescott")
#: Gap rows of the sweep sampled (up: 0-122, down: 123-317): 2000 Hz up (intermittent),
#: 5183 up and 4278, 4087, 3948, 3565, 3443 down (docs/verification.md, issue 35), and
#: nine more spread over both directions and the bands.
SAMPLE = (13, 90, 195, 206, 214, 223, 230, 46, 28, 60, 100, 144, 180, 250, 290, 6)
#: 32 more gaps screened at the default kernel (2048 periods) ...
SCREEN = (3, 11, 17, 24, 33, 41, 44, 52, 56, 66, 72, 80, 86, 95, 99, 106, 115, 121, 127, 135)
SCREEN += (143, 150, 160, 170, 186, 200, 212, 240, 262, 280, 300, 310)
#: ... and the 10 of them near a threshold, recorded under the other kernels (2048 periods).
NEAR = (44, 56, 80, 86, 106, 121, 127, 135, 52, 66)
#: ... and 8 more, chosen after the first judging (the same criteria).
NEAR2 = (143, 160, 200, 262, 240, 212, 300, 170)
#: The report's settings (notebook 02: the cap 1024, the first record a quarter of it).
PERIODS, MAX_PERIODS = 256, 1024


def starts(points: int = 300) -> None:
    """The sweep's gaps and their unstable orbits -> OUT/starts.npz (``points`` per
    direction: 300 as recorded, fewer for a smoke run)."""
    from nlgrd.io.model_file import load_model
    from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
    from nlgrd.timedomain.sweep_answers import base_harmonics

    system = load_model(KB)
    omegas = 2 * np.pi * np.linspace(800.0, 6000.0, points)
    model = build_link_model(system)  # one mesh: the plan base is the mesh frequency
    m = link_sweep(model, omegas, H=None, directions="both", jump="auto", period=1).result
    gaps = np.nonzero(np.asarray(m.converged, bool) & np.asarray(m.no_stable, bool))[0]
    z = np.empty(gaps.size, dtype=object)
    z[:] = [base_harmonics(m.harmonics[i], int(m.base)) for i in gaps]
    OUT.mkdir(parents=True, exist_ok=True)
    np.savez(
        OUT / "starts.npz",
        omega=np.asarray(m.omega)[gaps],
        direction=np.asarray(m.direction)[gaps].astype(str),
        z=z,
    )
    print(f"{gaps.size} gaps")


def record(kernel: str, periods: int, rows=SAMPLE) -> None:
    """One record of ``periods`` periods per gap of ``rows`` under this process's kernel."""
    import nlgrd
    from nlgrd.nonlinear.models.link_model import build_link_model
    from nlgrd.threads import single_blas_thread
    from nlgrd.timedomain.links import start_from_harmonics
    from nlgrd.timedomain.time_answer import _Run, answer_steps

    d = np.load(OUT / "starts.npz", allow_pickle=True)
    model = build_link_model(nlgrd.load(str(KB)))
    (OUT / "rec").mkdir(parents=True, exist_ok=True)

    @single_blas_thread
    def one(i: int) -> None:
        out = OUT / "rec" / f"{kernel}_{i}_{periods}.pkl"
        if out.exists():
            return
        t0 = time.perf_counter()
        omega, z = float(d["omega"][i]), np.asarray(d["z"][i], float)
        q0, v0 = start_from_harmonics(model, omega, (z.shape[-1] - 1) // 2, z)
        run = _Run(model, omega, (q0, 1.001 * v0), answer_steps(model), -0.05)
        run.extend(periods)
        rows = {k: np.array([r[k] for r in run.rec.rows]) for k in run.rec.rows[0]}
        with open(out, "wb") as f:
            pickle.dump({"rows": rows, "logs": np.array(run.logs), "omega": omega}, f)
        print(kernel, i, f"{omega / 2 / np.pi:.0f} Hz", f"{time.perf_counter() - t0:.1f} s", flush=True)

    for i in rows:
        one(i)


def _former(ta):
    """The estimator and rule of 5a1d1ae, installed in ``ta`` (time_answer)."""
    from nlgrd.timedomain.record_statistics import Estimate

    def batch_mean(x):
        x = np.asarray(x, dtype=float)
        size = max(x.size // 20, 1)
        b = x[x.size - size * min(20, x.size) :].reshape(-1, size).mean(axis=1)
        if b.size < 3:
            return Estimate(float(np.mean(x)), math.inf)
        dev = b - b.mean()
        den = float(dev @ dev)
        r = float(dev[1:] @ dev[:-1]) / den if den > 0 else 0.0
        r = min(r, 0.9) if r > 2 / math.sqrt(b.size) else 0.0
        return Estimate(float(np.mean(x)), math.sqrt(den / (b.size - 1) / b.size * (1 + r) / (1 - r)))

    def settle(run, periods, max_periods, rtol, progress=None):
        target = periods
        while True:
            run.extend(target, progress)
            cut, cuts_ok, links, mesh, bearings, drift, lam = ta._judge(run.rec, run.logs)
            undecided = ta.LYAPUNOV_FLOOR < lam.value <= 3 * lam.uncertainty
            settled = cuts_ok and ta._targets_met(links, rtol) and not (undecided or drift)
            if settled or target >= max_periods:
                break
            target = min(2 * target, max_periods)
        kind = ta.CHAOTIC if lam.value > max(3 * lam.uncertainty, ta.LYAPUNOV_FLOOR) else ta.TIME_DOMAIN
        return ta._Verdict(cut, cuts_ok, links, mesh, bearings, lam, bool(settled), kind)

    ta.sample_mean, ta._settle = batch_mean, settle


class _Prefix:
    """A stored record seen by ``_settle`` as a run: ``extend`` shows a longer prefix."""

    def __init__(self, d, model, recorder, clamp=False):
        from nlgrd.timedomain.bearing_record import bearing_names, bearing_node_dofs

        class Rec:
            cut_series = recorder.cut_series

            def __init__(self):
                self.n, self.all = 0, d["rows"]
                self.integ = type("I", (), {"model": model})()
                self.bearings = type(
                    "B", (), {"names": bearing_names(model.system), "dofs": bearing_node_dofs(model.system)}
                )()

            @property
            def rows(self):
                return range(self.n)

            def series(self, key, cut=0, stop=None):
                return self.all[key][: self.n][cut:stop]

        self.rec, self._logs, self.logs, self.clamp = Rec(), d["logs"], [], clamp

    def extend(self, target, progress=None):
        if target > self._logs.size:
            if not self.clamp:
                raise RuntimeError(f"the record holds {self._logs.size} periods, {target} asked")
            target = self._logs.size
        self.rec.n, self.logs = target, list(self._logs[:target])


def judge(which: str, out: str) -> None:
    """Every stored record judged by the ``which`` rule ("former" or "current")."""
    import nlgrd
    import nlgrd.timedomain.time_answer as ta
    from nlgrd.nonlinear.models.link_model import build_link_model

    if which == "former":
        _former(ta)
    model = build_link_model(nlgrd.load(str(KB)))

    def verdict(d, periods, max_periods, clamp=False):
        run = _Prefix(d, model, ta._Recorder, clamp)
        v = ta._settle(run, periods, max_periods, 0.01)
        stats = {k: [e.value, e.uncertainty] for k, e in {**v.links, **v.bearings}.items()}
        return {
            "n": run.rec.n,
            "cut": v.cut,
            "ok": v.cuts_ok,
            "kind": v.kind,
            "lam": [v.lam.value, v.lam.uncertainty],
            "stats": stats,
        }

    res = {}
    for f in sorted(glob.glob(str(OUT / "rec" / "*.pkl"))):
        kernel, i, _ = Path(f).stem.split("_")
        with open(f, "rb") as fh:
            d = pickle.load(fh)
        r = {"hz": d["omega"] / 2 / np.pi, "answer": verdict(d, PERIODS, MAX_PERIODS)}
        n = 4 * r["answer"]["n"]
        if kernel == "default" and n <= d["logs"].size:  # the 4x record: a prefix
            r["x4"] = verdict(d, n, n, clamp=True)
        res[f"{kernel}_{i}"] = r
    with open(out, "w") as fh:
        json.dump(res, fh)


def _extreme(key: str) -> bool:
    return any(s in key for s in ("_max", "dslr", "p2p"))


def _z(a: dict, b: dict) -> dict:
    """|a - b| / sqrt(u_a² + u_b²) of every statistic but back contact."""
    out = {}
    for k, (va, ua) in a["stats"].items():
        if k.endswith("back_contact"):
            continue
        vb, ub = b["stats"][k]
        den = math.hypot(ua, ub)
        out[k] = abs(va - vb) / den if den > 0 else (0.0 if va == vb else math.inf)
    return out


def compare(files: list[str]) -> None:
    """Kinds per kernel, "not found" and coverage of each judged file."""
    for fn in files:
        with open(fn) as fh:
            r = json.load(fh)
        points = sorted({k.split("_")[1] for k in r}, key=int)
        flips = lost = full = 0
        cover: dict[str, list] = {
            "4x, means": [],
            "4x, extremes": [],
            "kernels, means": [],
            "kernels, extremes": [],
            "kernels, means, both chaotic": [],
        }
        print(fn)
        for p in points:
            got = [r.get(f"{k}_{p}") for k in KERNELS]
            d = got[0]
            kinds = [(v["answer"]["kind"] if v["answer"]["ok"] else "not found") for v in got if v]
            flips += len(set(kinds)) > 1
            full += len(kinds) == len(KERNELS)
            lost += kinds.count("not found")
            a = d["answer"]

            def pm(e, scale=1.0):
                return f"{e[0] * scale:.4g}±{e[1] * scale:.2g}"

            dte = " ".join(pm(v["answer"]["stats"]["mesh0.dte_rms [m]"], 1e6) for v in got if v)
            x4 = pm(d["x4"]["stats"]["mesh0.dte_rms [m]"], 1e6) if "x4" in d else "-"
            lam = " ".join(pm(v["answer"]["lam"]) for v in got if v)
            print(f"  {d['hz']:6.0f} Hz  {'/'.join(kinds)}  n {a['n']} cut {a['cut']}")
            print(f"      λT {lam}  DTE µm {dte}  4x {x4}")
            if "x4" in d and a["ok"] and d["x4"]["ok"]:
                for k, v in _z(a, d["x4"]).items():
                    cover["4x, extremes" if _extreme(k) else "4x, means"].append(v)
            for v in got[1:]:
                if v and a["ok"] and v["answer"]["ok"]:
                    for k, w in _z(a, v["answer"]).items():
                        cover["kernels, extremes" if _extreme(k) else "kernels, means"].append(w)
                        if not _extreme(k) and a["kind"] == v["answer"]["kind"] == "chaotic":
                            cover["kernels, means, both chaotic"].append(w)
        ns = [v["answer"]["n"] for v in r.values()]
        print(f"  {len(points)} points ({full} under all kernels): kernel-dependent kinds {flips}")
        print(f"  'not found' {lost} of {len(r)} answers")
        print(f"  periods: {sum(ns)} in {len(ns)} answers, {sum(n > MAX_PERIODS for n in ns)} beyond the cap")
        for k, v in cover.items():
            v = np.array(v)
            if v.size:
                within = f"within 2σ {np.mean(v <= 2):.3f}, within 3σ {np.mean(v <= 3):.3f}"
                print(f"  {k}: {v.size} pairs, {within}, largest {v.max():.1f}σ")


if __name__ == "__main__":
    step, args = sys.argv[1], sys.argv[2:]
    if step == "starts":
        starts(*map(int, args[:1]))
    elif step == "record":
        record(args[0], int(args[1]), {"sample": SAMPLE, "screen": SCREEN, "near": NEAR + NEAR2}[args[2]])
    elif step == "judge":
        judge(args[0], args[1])
    else:
        compare(args)
