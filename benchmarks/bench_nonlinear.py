"""Benchmark of the nonlinear geared-rotor analysis against the issue's acceptance targets.

Run from the repository root::

    .venv/bin/python benchmarks/bench_nonlinear.py            # full size
    .venv/bin/python benchmarks/bench_nonlinear.py --quick    # smoke run
    .venv/bin/python benchmarks/bench_nonlinear.py --cases 4  # the link engine's case-4 runs

Everything runs on the link engine (:func:`~nlgrd.nonlinear.models.link_model.build_link_model`,
:func:`~nlgrd.nonlinear.models.link_model.link_sweep`, what ``nlgrd.sweep`` runs;
:func:`nlgrd.timedomain.links.link_time_response`). The single-mesh engine these cases were
first measured with (its sweep, the mesh receptance, its HHT-α time response) is
deleted: its figures in ``benchmarks/README.md`` are recorded history, and nothing here
compares against it. Four cases, each printed as a table (figures and machine in
``benchmarks/README.md``):

1. A full up-and-down sweep (2 x 500 points, H = 5) of ``data/models/two_shaft.toml``
   with every shaft element split in two (252 DOFs), split into model build,
   receptances, Newton solves, jumps (points with ``branch_switch``), failed points and
   bearing recovery; ``stability=False`` on the full grid, ``stability=True`` on a
   2 x 15-point subsample with the full sweep extrapolated (``--full-stability`` also
   runs the full grid with stability, twice, as the library builds it: its state spaces
   share one Floquet cache; ``--before FILE`` also runs it, interleaved, with the
   ``floquet_multipliers`` of another version of ``nlgrd/nonlinear/stability/floquet.py``,
   e.g. ``git show main:nlgrd/nonlinear/stability/floquet.py > /tmp/floquet_before.py``,
   and compares the verdicts). Target: under 2 s. Then Floquet per point side
   by side on the sweep's harmonics: the reference ``method="expm"`` (the method before
   issue 10) against the default, verdicts compared. Target: <= 1 ms per point.
2. Time integration (HHT-α, :func:`nlgrd.timedomain.links.link_time_response`) against
   harmonic balance at the same points and equal accuracy (DTE RMS within 0.5 % of
   HB with H = 9), both as sweeps (each point starts from the previous one).
   Target: TI / HB per point >= 1000.
3. Per-point cost from 132 to 9 972 DOFs (more elements per shaft) with the link
   reduction's ``method="modal"`` (a truncated modal basis) and ``"direct"``, the one-off
   cost apart. Target: at most 2x.
4. (``--cases 4``) The single mesh on the link engine, best of ``--repeats``: case 1's sweep
   (H = 5, without and with stability) and the default sweep of
   ``data/models/two_shaft.toml`` at 40 base frequencies 1000-2900 Hz both ways (H chosen,
   stability, period "auto", without the time-domain answers), with CPU and wall time,
   corrector evaluations of the landing searches, sweeps per ladder and Floquet calls. Issue
   33's target (link / old <= 1.10) against the deleted single-mesh engine is measured by
   ``bench_against_deleted.py --case a`` and ``--case b``, both engines side by side
   (figures in benchmarks/README.md); ``--before FILE`` compares with a table
   this case printed before (another library version's run), row by row.

How it measures
---------------
- The split of a sweep into phases comes from wrapping library functions for the
  duration of one run (exclusive wall time per phase; the wrappers are removed
  afterwards; overhead about 0.5 µs per call, about 10 calls per point). The library is not modified.
- BLAS threads: the machine has 2 cores shared with other users. OpenBLAS's default
  (one thread per core) makes the small dense LAPACK calls of the stability analysis
  and of the modal receptances 1.5x to 40x slower whenever another process is busy,
  so the primary figures are taken with one BLAS thread (set for numpy's and scipy's
  OpenBLAS through their ``*_set_num_threads``, via ctypes as threadpoolctl does);
  the default thread count is measured side by side in the same run where it matters
  (``--blas-default`` makes the default the primary setting).
- Wall times vary with the load of the machine (printed at the start of every case);
  the results themselves (points, iterations, branch switches, errors) are
  deterministic for a given library version: the frequency grid is built from the
  gear-pair mode rounded to 1 Hz, because a 1e-13 change of the grid (the
  eigensolver's last digits) can turn a grazing point into a branch switch.
"""

from __future__ import annotations

import argparse
import ctypes
import dataclasses
import datetime
import importlib.util
import os
import platform
import re
import subprocess
import sys
import time
from collections import defaultdict
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import scipy
import scipy.linalg  # noqa: F401  (loads scipy's OpenBLAS so that its threads can be set)
import scipy.sparse.linalg  # noqa: F401

import nlgrd.nonlinear.hb.harmonic_balance as nl_hb
import nlgrd.nonlinear.models.link_model as nl_link_model
import nlgrd.nonlinear.reduction.link_reduction as nl_link_reduction
import nlgrd.nonlinear.reduction.state_space as nl_state_space
import nlgrd.nonlinear.results.metrics as nl_metrics
import nlgrd.nonlinear.stability.floquet as nl_floquet
import nlgrd.nonlinear.tracing.arclength as nl_arclength
import nlgrd.nonlinear.tracing.harmonic_convergence as nl_harmonics
import nlgrd.nonlinear.tracing.landing as nl_landing
import nlgrd.nonlinear.tracing.sweep as nl_sweep
from nlgrd.cache import BoundedCache
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.nonlinear.reduction.state_space import LinearStateSpace
from nlgrd.nonlinear.stability.tangent import tangent_pieces
from nlgrd.rotor.modal import gear_pair_mode
from nlgrd.rotor.system import refined
from nlgrd.timedomain.links import link_time_response

ROOT = Path(__file__).resolve().parents[1]
MODEL_FILE = ROOT / "data" / "models" / "two_shaft.toml"
TWO_PI = 2 * np.pi
#: Case 2: the cap of a time integration's periods (the deleted engine's default, as recorded).
TI_MAX_PERIODS = 3000


# --------------------------------------------------------------------------------------
# Machine and BLAS threads
# --------------------------------------------------------------------------------------


def load_average() -> str:
    try:
        a, b, c = os.getloadavg()
    except OSError:
        return "unknown"
    return f"{a:.2f} {b:.2f} {c:.2f} (1, 5, 15 min)"


def machine_lines() -> list[str]:
    """nproc, lscpu head, versions, date and load: the machine the figures belong to."""

    def run(cmd):
        try:
            return subprocess.run(cmd, capture_output=True, text=True, check=False).stdout.strip()
        except OSError:
            return "(unavailable)"

    lines = [f"date: {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}"]
    lines.append(f"nproc: {run(['nproc'])}")
    lines += ["lscpu | head:"] + ["  " + s for s in run(["lscpu"]).splitlines()[:10]]
    lines.append(f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}")
    lines.append(f"OpenBLAS threads by default: {BLAS.describe()}")
    lines.append(f"load average at start: {load_average()}")
    return lines


class _Blas:
    """Thread count of the OpenBLAS copies loaded by numpy and scipy (ctypes, as threadpoolctl)."""

    def __init__(self):
        self.libs = []
        try:
            with open("/proc/self/maps") as fh:
                paths = sorted({ln.split()[-1] for ln in fh if "openblas" in ln.lower()})
        except OSError:
            paths = []
        for p in paths:
            try:
                lib = ctypes.CDLL(p)
            except OSError:
                continue
            names = [
                (f"{a}get_num_threads{b}", f"{a}set_num_threads{b}")
                for a in ("scipy_openblas_", "openblas_")
                for b in ("64_", "")
            ]
            for get, put in names:
                if hasattr(lib, get) and hasattr(lib, put):
                    self.libs.append((Path(p).name, getattr(lib, get), getattr(lib, put)))
                    break
        self.default = self.get()

    @property
    def available(self) -> bool:
        return bool(self.libs)

    def get(self) -> list[int]:
        return [int(g()) for _, g, _ in self.libs]

    def describe(self) -> str:
        if not self.libs:
            return "unknown (no OpenBLAS found; thread control off)"
        return ", ".join(f"{n}: {g()}" for n, g, _ in self.libs)

    def set(self, n: int | list[int]) -> None:
        ns = n if isinstance(n, list) else [n] * len(self.libs)
        for (_, _, put), k in zip(self.libs, ns, strict=True):
            put(int(k))

    @contextmanager
    def threads(self, n: int | list[int] | None):
        """Run a block with ``n`` BLAS threads (a list: per library; None: as is)."""
        if n is None or not self.libs:
            yield
            return
        old = self.get()
        self.set(n)
        try:
            yield
        finally:
            self.set(old)


BLAS = _Blas()


# --------------------------------------------------------------------------------------
# Models
# --------------------------------------------------------------------------------------


def refine(system, factor: int, damping_ratio: float | None = None):
    """``system`` with every shaft element split into ``factor`` equal elements
    (:func:`nlgrd.rotor.system.refined`), the gear pairs' mesh damping ratio replaced
    when ``damping_ratio`` is given."""
    out = refined(system, factor)
    if damping_ratio is None:
        return out
    gears = tuple(dataclasses.replace(g, damping_ratio=float(damping_ratio)) for g in out.gear_pairs)
    return dataclasses.replace(out, gear_pairs=gears)


# --------------------------------------------------------------------------------------
# Phase timing of a sweep
# --------------------------------------------------------------------------------------


class Probe:
    """Exclusive wall time per phase, by wrapping library functions for one run.

    A wrapped call charges its own time (minus nested wrapped calls) to its phase. A
    "sticky" phase (jumps, bearing recovery) takes everything inside it. The sweep's
    placeholder metrics of each point (MeshMetrics.nan) mark its end, so every point's time is known
    by phase; points that needed a branch switch or failed are then booked as a whole.
    """

    def __init__(self):
        self.acc = defaultdict(float)
        self.stack: list[tuple[str, bool]] = []
        self.seg = 0.0
        self.points: list[dict[str, float]] = []
        self._snap: dict[str, float] = {}
        self._patched = []

    def _charge(self, now: float) -> None:
        if self.stack:
            self.acc[self.stack[-1][0]] += now - self.seg
        self.seg = now

    def wrap(self, owner, name: str, phase: str, sticky: bool = False, boundary: bool = False) -> None:
        orig = getattr(owner, name)
        raw = vars(owner).get(name, orig)  # a classmethod is restored as itself
        probe = self

        def wrapper(*args, **kwargs):
            if probe.stack and (probe.stack[-1][1] or (boundary and probe.stack[-1][0] == phase)):
                return orig(*args, **kwargs)  # inside a sticky phase, or a boundary call nested in one
            probe._charge(time.perf_counter())
            probe.stack.append((phase, sticky))
            try:
                return orig(*args, **kwargs)
            finally:
                probe._charge(time.perf_counter())
                probe.stack.pop()
                if boundary:
                    cur = dict(probe.acc)
                    probe.points.append({k: v - probe._snap.get(k, 0.0) for k, v in cur.items()})
                    probe._snap = cur

        setattr(owner, name, wrapper)
        self._patched.append((owner, name, raw))

    def __enter__(self):
        w = self.wrap
        w(nl_link_reduction.LinkReceptance, "terms", "receptances")
        w(nl_link_reduction.LinkReceptance, "derivatives", "receptances")
        w(nl_hb.ReducedModel, "at", "problem setup")
        w(nl_hb.ReducedModel, "linear_state_space", "stability")
        w(nl_sweep, "solve", "Newton")
        w(nl_sweep, "floquet_multipliers", "stability")
        # every point starts with placeholder metrics: the end of the point
        w(nl_sweep.MeshMetrics, "nan", "output metrics", boundary=True)
        w(nl_metrics, "metrics_of_points", "output metrics")  # all points at once, after the last
        w(nl_sweep, "jump_to_branch", "jump", sticky=True)
        for name in ("restart", "follow_branch", "pool_candidates", "approach"):  # landings
            w(nl_landing, name, "jump", sticky=True)
        w(nl_link_model, "points_outputs", "bearing recovery", sticky=True)  # links' and bearings' outputs
        self.stack = [("other", False)]
        self.seg = time.perf_counter()
        return self

    def __exit__(self, *exc):
        self._charge(time.perf_counter())
        self.stack = []
        for owner, name, orig in reversed(self._patched):
            setattr(owner, name, orig)
        self._patched = []


POINT_PHASES = ("receptances", "problem setup", "Newton", "stability", "output metrics", "other")


@dataclasses.dataclass
class SweepTiming:
    """Wall time of one instrumented sweep, by phase [s]."""

    total: float
    phases: dict
    n_points: int
    n_regular: int
    n_switch: int
    n_failed: int
    n_no_stable: int
    newton_iterations: int
    point_times: np.ndarray  # per point [s], in sweep order
    point_phases: list  # per point: {phase: s}
    result: object

    @property
    def regular_mean(self) -> float:
        return sum(self.phases[p] for p in POINT_PHASES) / max(self.n_regular, 1)


def empty_caches(model) -> None:
    """The link reduction's per-frequency caches emptied (factors, κ_k / F_k terms,
    recoveries); its one-off forms (pole-residue, basis) kept."""
    rec = model.receptance
    rec._factors, rec._terms = BoundedCache(64), BoundedCache(4096)
    rec._band_sols, rec._recovery = BoundedCache(64), BoundedCache(4096)


def timed_sweep(model, omegas, H, directions="both", stability=False) -> SweepTiming:
    """link_sweep (period 1) with a phase split (points with branch_switch / failures
    booked whole)."""
    with Probe() as probe:
        t0 = time.perf_counter()
        res = link_sweep(model, omegas, H, directions=directions, stability=stability, period=1)
        total = time.perf_counter() - t0
    m = res.result
    n = len(m.omega)
    if len(probe.points) != n:
        raise RuntimeError(f"probe saw {len(probe.points)} points, the sweep has {n}")
    switch = np.asarray(m.branch_switch, bool)
    failed = ~np.asarray(m.converged, bool) & ~switch
    lost = np.asarray(m.no_stable, bool) & ~switch & ~failed  # unstable, no stable response found
    regular = ~switch & ~failed & ~lost
    per_point = np.array([sum(p.values()) for p in probe.points])
    phases = {p: sum(probe.points[i].get(p, 0.0) for i in np.nonzero(regular)[0]) for p in POINT_PHASES}
    # the metrics of all points, computed after the last one (booked to the regular points)
    phases["output metrics"] += probe.acc.get("output metrics", 0.0) - sum(
        p.get("output metrics", 0.0) for p in probe.points
    )
    phases["jumps"] = float(per_point[switch].sum())
    phases["failed points"] = float(per_point[failed].sum())
    phases["no stable response"] = float(per_point[lost].sum())
    phases["bearing recovery"] = probe.acc.get("bearing recovery", 0.0)
    phases["other"] += total - sum(probe.acc.values())  # link_sweep outside any wrapped call
    return SweepTiming(
        total,
        phases,
        n,
        int(regular.sum()),
        int(switch.sum()),
        int(failed.sum()),
        int(lost.sum()),
        int(np.sum(m.iterations[regular])),
        per_point,
        probe.points,
        res,
    )


# --------------------------------------------------------------------------------------
# Printing
# --------------------------------------------------------------------------------------


def table(header: list[str], rows: list[list[str]]) -> str:
    """Plain-text table, first column left-aligned, the others right-aligned."""
    cols = list(zip(header, *rows, strict=True))
    width = [max(len(str(c)) for c in col) for col in cols]

    def line(cells):
        return "  ".join(
            str(c).ljust(w) if i == 0 else str(c).rjust(w)
            for i, (c, w) in enumerate(zip(cells, width, strict=True))
        )

    return "\n".join([line(header), "  ".join("-" * w for w in width)] + [line(r) for r in rows])


def verdict(ok: bool) -> str:
    return "MET" if ok else "MISSED"


def section(title: str) -> None:
    print()
    print("=" * len(title))
    print(title)
    print("=" * len(title))
    print(f"load average: {load_average()}", flush=True)


# --------------------------------------------------------------------------------------
# Case 1: full up-and-down sweep
# --------------------------------------------------------------------------------------


def case_sweep(cfg) -> dict:
    section(f"Case 1: up-and-down sweep, 2 x {cfg.n_points} points, H = 5")
    base = load_model(MODEL_FILE)
    system = refine(base, 2, cfg.zeta)
    f_exact, _ = gear_pair_mode(system)
    # rounded, so that the grid does not depend on the eigensolver's last digits (ARPACK's
    # start vector, BLAS threads): a 1e-13 change of the grid can turn a grazing point
    # into a branch switch and back
    f_mode = float(round(f_exact))
    lo, hi = 0.5 * f_mode, 1.5 * f_mode
    omegas = TWO_PI * np.linspace(lo, hi, cfg.n_points)
    sub = TWO_PI * np.linspace(lo, hi, cfg.n_stability)
    print(
        f"model: {MODEL_FILE.relative_to(ROOT)}, every shaft element split in 2 -> {system.n_dofs} DOFs;\n"
        f"gear pair kept, mesh damping ratio {cfg.zeta} (file: {base.gear_pairs[0].damping_ratio}), "
        f"bearings as in the file.\n"
        f"Mesh frequency {lo:.1f} .. {hi:.1f} Hz (0.5 .. 1.5 x {f_mode:.0f} Hz, the gear-pair mode at "
        f"{f_exact:.1f} Hz rounded), "
        f"{cfg.n_points} points each way;\n"
        f"link_sweep (period 1; newton, jump='auto', tol 1e-10), reduction method 'auto'."
    )

    def build():
        t0 = time.perf_counter()
        model = build_link_model(system)
        model.receptance.prepare(5 * float(omegas.max()))  # a modal basis, where the model takes one
        return model, time.perf_counter() - t0

    # (label, stability, grid, BLAS threads); column labels kept short, legend printed below
    nsub = f"2x{cfg.n_stability}"
    plan = [("stability=False", False, omegas, cfg.primary)]
    if cfg.secondary is not None:
        plan.append(("stability=False [2]", False, omegas, cfg.secondary))
    plan.append((f"stability=True {nsub}", True, sub, cfg.primary))
    if cfg.secondary is not None:
        plan.append((f"stability=True {nsub} [2]", True, sub, cfg.secondary))
    if cfg.full_stability:
        plan.append(("stability=True full", True, omegas, cfg.primary))
        if cfg.before:
            plan.append(("stability=True full, before", True, omegas, cfg.primary))
        plan.append(("stability=True full, again", True, omegas, cfg.primary))
        if cfg.before:
            plan.append(("stability=True full, before again", True, omegas, cfg.primary))
            plan.append(("stability=False, again", False, omegas, cfg.primary))
    before = _floquet_before(cfg.before) if cfg.before and cfg.full_stability else None
    runs = {}
    for label, stab, grid, threads in plan:
        with BLAS.threads(threads), _floquet_swapped(before if "before" in label else None):
            model, t_build = build()
            t_basis = None
            if stab:
                t0 = time.perf_counter()
                # the one-off basis, built as state_space_at would build it at the first point
                model.reduced.linear_state_space(float(grid[0]))
                t_basis = time.perf_counter() - t0
            st = timed_sweep(model, grid, 5, stability=stab)
        runs[label] = (st, t_build, t_basis)
        print(f"  {label} ({2 * len(grid)} points): {st.total:.2f} s", flush=True)

    def ms_per(x, n):
        return f"{1e3 * x / max(n, 1):.2f}"

    spec = [
        (
            "points: regular / branch switch / failed / no stable",
            lambda s, b, t: f"{s.n_regular}/{s.n_switch}/{s.n_failed}/{s.n_no_stable}",
        ),
        ("model build, one-off [s]", lambda s, b, t: f"{b:.3f}"),
        ("stability basis, one-off [s]", lambda s, b, t: "-" if t is None else f"{t:.3f}"),
        ("receptances [s]", lambda s, b, t: f"{s.phases['receptances']:.3f}"),
        ("problem setup [s]", lambda s, b, t: f"{s.phases['problem setup']:.3f}"),
        ("Newton solves [s]", lambda s, b, t: f"{s.phases['Newton']:.3f}"),
        ("  Newton iterations, regular points", lambda s, b, t: f"{s.newton_iterations}"),
        ("Floquet stability [s]", lambda s, b, t: f"{s.phases['stability']:.3f}"),
        ("output metrics [s]", lambda s, b, t: f"{s.phases['output metrics']:.3f}"),
        ("jumps: points with branch_switch [s]", lambda s, b, t: f"{s.phases['jumps']:.3f}"),
        ("failed points [s]", lambda s, b, t: f"{s.phases['failed points']:.3f}"),
        ("no stable response: restarts [s]", lambda s, b, t: f"{s.phases['no stable response']:.3f}"),
        ("link and bearing outputs [s]", lambda s, b, t: f"{s.phases['bearing recovery']:.3f}"),
        ("other [s]", lambda s, b, t: f"{s.phases['other']:.3f}"),
        ("sweep total [s]", lambda s, b, t: f"{s.total:.3f}"),
        ("regular point: all phases [ms]", lambda s, b, t: f"{1e3 * s.regular_mean:.2f}"),
        ("  receptances [ms]", lambda s, b, t: ms_per(s.phases["receptances"], s.n_regular)),
        ("  Newton [ms]", lambda s, b, t: ms_per(s.phases["Newton"], s.n_regular)),
        ("  Floquet [ms]", lambda s, b, t: ms_per(s.phases["stability"], s.n_regular)),
        ("  link and bearing outputs [ms]", lambda s, b, t: ms_per(s.phases["bearing recovery"], s.n_points)),
    ]
    cols = list(runs)
    rows = [[name] + [fn(*runs[c]) for c in cols] for name, fn in spec]
    print()
    print(table(["phase"] + cols, rows))
    print(f"columns: {cfg.primary_label}; [2]: {cfg.secondary_label}; {nsub}: the subsample grid")

    st0, tb0, _ = runs["stability=False"]
    n_full = 2 * cfg.n_points
    print()
    total0 = st0.total + tb0
    print(
        f"stability=False: {st0.total:.2f} s sweep + {tb0:.2f} s build for {n_full} points -> target < 2 s: "
        f"{verdict(total0 < 2)} ({total0 / 2:.1f}x the target)"
    )
    m0 = st0.result.result
    for i in np.nonzero(np.asarray(m0.branch_switch) | ~np.asarray(m0.converged))[0]:
        kind = "branch switch" if m0.branch_switch[i] else "failed"
        print(
            f"  {kind} at {m0.omega[i] / TWO_PI:.0f} Hz ({m0.direction[i]} sweep): {st0.point_times[i]:.2f} s"
        )
    print(
        f"  without them: {st0.total - st0.phases['jumps'] - st0.phases['failed points']:.2f} s; "
        f"receptances are computed for {cfg.n_points} distinct frequencies (the down sweep reuses them)"
    )
    sst, _, t_basis = runs[f"stability=True {nsub}"]
    per = sst.phases["stability"] / max(sst.n_regular, 1)
    est = st0.total + tb0 + n_full * per + t_basis
    print(
        f"stability=True: Floquet {1e3 * per:.0f} ms per point on the {sst.n_points}-point subsample -> "
        f"estimated {est:.0f} s for {n_full} points\n  (stability=False sweep + build + {n_full} x Floquet "
        f"+ basis) -> target < 2 s: {verdict(est < 2)} ({est / 2:.0f}x the target)"
    )
    if "stability=True full" in runs:
        sf, tbf, tsf = runs["stability=True full"]
        tot = sf.total + tbf + tsf
        print(
            f"stability=True, full grid, measured: {tot:.2f} s (sweep {sf.total:.2f} + build {tbf:.2f} "
            f"+ basis {tsf:.2f}) -> target < 2 s: {verdict(tot < 2)}; "
            f"stability=False in the same run: {total0:.2f} s"
        )
        ss_, tbs, tss = runs["stability=True full, again"]
        tot = ss_.total + tbs + tss
        print(f"  the same again: {tot:.2f} s -> {verdict(tot < 2)}")
        if cfg.before:
            compare_before(runs, total0)
    if cfg.secondary is not None:
        for a in ("stability=False", f"stability=True {nsub}"):
            s2 = runs[f"{a} [2]"][0]
            r = s2.total / runs[a][0].total
            print(f"side by side, {a}: {cfg.secondary_label} / {cfg.primary_label} = {r:.2f}x")
    with BLAS.threads(cfg.primary):
        floquet_side_by_side(build()[0], st0.result, cfg)
    return {"system": system, "omegas": omegas, "f_mode": f_mode, "sweep": st0, "build": tb0}


def _floquet_before(path: str):
    """The module of another version of ``floquet.py`` (``--before``)."""
    spec = importlib.util.spec_from_file_location("floquet_before", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up there
    spec.loader.exec_module(mod)
    return mod


@contextmanager
def _floquet_swapped(before):
    """Every library module's ``floquet_multipliers`` replaced by ``before``'s for a block."""
    if before is None:
        yield
        return
    swapped = [
        (mod, mod.floquet_multipliers)
        for name, mod in list(sys.modules.items())
        if name.startswith("nlgrd") and mod is not nl_floquet and hasattr(mod, "floquet_multipliers")
    ]
    for mod, _ in swapped:
        mod.floquet_multipliers = before.floquet_multipliers
    try:
        yield
    finally:
        for mod, fn in swapped:
            mod.floquet_multipliers = fn


def compare_before(runs, total0: float) -> None:
    """Before/after of ``--before``: best of two each, against the best stability=False run
    of the same process, and the answers compared point by point."""

    def total(label):
        s, b, t = runs[label]
        return s.total + b + (t or 0.0)

    off = min(total0, total("stability=False, again"))
    aft = min(total("stability=True full"), total("stability=True full, again"))
    bef = min(total("stability=True full, before"), total("stability=True full, before again"))
    print(
        f"side by side (best of two each): stability=False {off:.2f} s; with stability: before "
        f"{bef:.2f} s ({bef / off:.2f}x), after {aft:.2f} s ({aft / off:.2f}x) -> target <= 1.3x: "
        f"{verdict(aft / off <= 1.3)}"
    )
    a, b = runs["stability=True full, before"][0].result.result, runs["stability=True full"][0].result.result
    same = all(
        np.array_equal(np.asarray(getattr(a, k)), np.asarray(getattr(b, k)))
        for k in ("omega", "converged", "stable", "no_stable", "branch_switch")
    )
    za, zb = np.asarray(a.harmonics), np.asarray(b.harmonics)
    dz = float(np.nanmax(np.abs(za - zb)) / np.nanmax(np.abs(za))) if za.shape == zb.shape else np.inf
    dmu = float(np.nanmax(np.abs(np.abs(a.dominant_multiplier) - np.abs(b.dominant_multiplier))))
    print(
        f"  before/after: convergence, stability, no-stable and branch switches identical at every "
        f"point: {same}; harmonics within {dz:.1e} (relative); largest change of |dominant "
        f"multiplier| {dmu:.1e}"
    )


def floquet_side_by_side(model, result, cfg) -> None:
    """Floquet per point on the harmonics of the stability=False sweep, in sweep order:
    the reference ``method="expm"`` (the method before issue 10), the default, and the
    default with a cache shared by the state spaces; each on a new state space per point,
    as ``state_space_at`` builds them (its build, the projection of the FE matrices on the
    stability basis, is timed apart)."""
    print()
    print("Floquet per point, side by side (harmonics of the stability=False sweep, sweep order):")
    m = result.result
    nl = model.reduced.nonlinearities
    shared = nl_state_space.FloquetCache(maxsize=4096)
    fm = nl_floquet.floquet_multipliers
    model.reduced.linear_state_space(float(m.omega[0]))  # the one-off stability basis
    rec = defaultdict(list)
    for w, z, ok in zip(m.omega, m.harmonics, m.converged, strict=True):
        if not ok:
            continue
        # the contact intervals of these harmonics, cached as after the sweep's last Newton step
        rec["loss"].append(tangent_pieces(nl, z, 1)[0].size > 2)
        t0 = time.perf_counter()
        ss = model.reduced.linear_state_space(float(w))
        t1 = time.perf_counter()
        mats = (ss.M, ss.D, ss.K, ss.W)
        extra = dict(larger=ss.larger, full=ss.full, dropped=ss.dropped)
        old = fm(LinearStateSpace(*mats, **extra), nl, z, w, method="expm")
        t2 = time.perf_counter()
        new = fm(LinearStateSpace(*mats, **extra), nl, z, w)
        t3 = time.perf_counter()
        shr = fm(LinearStateSpace(*mats, cache=shared, **extra), nl, z, w)
        t4 = time.perf_counter()
        for k, v in (("build", t1 - t0), ("expm", t2 - t1), ("auto", t3 - t2), ("shared", t4 - t3)):
            rec[k].append(v)
        for k, v in (("mu_expm", old), ("mu_auto", new), ("mu_shared", shr)):
            rec[k].append(float(np.max(np.abs(v))))
    r = {k: np.asarray(v) for k, v in rec.items()}
    loss = r["loss"]
    groups = [("full contact", ~loss), ("contact loss", loss), ("all points", np.ones_like(loss))]
    rows = []
    for name, sel in groups:
        rows.append(
            [name, f"{sel.sum()}"]
            + [f"{1e3 * r[k][sel].mean():.2f}" for k in ("expm", "auto", "shared", "build")]
            + [f"{np.sum(r['mu_expm'][sel] >= 1 + 1e-6)}"]
        )
    print(
        table(
            [
                "points",
                "n",
                "expm (old) [ms]",
                "auto [ms]",
                "auto, shared cache [ms]",
                "state-space build [ms]",
                "unstable (expm)",
            ],
            rows,
        )
    )
    stable = r["mu_expm"] < 1 + 1e-6
    for k in ("mu_auto", "mu_shared"):
        diff = int(np.sum((r[k] < 1 + 1e-6) != stable))
        print(
            f"  {k[3:]}: verdicts differing from expm: {diff} of {stable.size}; "
            f"max |Δ max|μ|| = {np.max(np.abs(r[k] - r['mu_expm'])):.1e}"
        )
    per_old, per_new = r["expm"].mean(), r["auto"].mean()
    print(
        f"  per point: expm {1e3 * per_old:.2f} ms, auto {1e3 * per_new:.2f} ms ({per_old / per_new:.1f}x), "
        f"shared {1e3 * r['shared'].mean():.2f} ms -> target <= 1 ms: auto {verdict(per_new <= 1e-3)}, "
        f"shared {verdict(r['shared'].mean() <= 1e-3)} (state-space build {1e3 * r['build'].mean():.2f} ms "
        f"apart, the same for all)"
    )


# --------------------------------------------------------------------------------------
# Case 2: time integration against harmonic balance
# --------------------------------------------------------------------------------------


def hb_point_cost(model, w_prev, w, H, repeats=3) -> tuple[float, SweepTiming]:
    """Wall time of the second point of an up sweep [w_prev, w] (median of ``repeats``).

    Receptances, problem setup, Newton from the previous point, metrics and the point's
    share of the link and bearing outputs; the reduction's caches are emptied before each repeat.
    """
    times, st = [], None
    for _ in range(repeats):
        empty_caches(model)
        st = timed_sweep(model, np.array([w_prev, w]), H, directions="up")
        times.append(st.point_times[1] + st.phases["bearing recovery"] / 2)
    return float(np.median(times)), st


def case_time_domain(cfg, c1) -> None:
    section("Case 2: time integration (HHT-α) / harmonic balance, per point, equal accuracy")
    system, omegas = c1["system"], c1["omegas"]
    dw = float(omegas[1] - omegas[0])  # the sweep step of case 1
    S, tol = cfg.ti_steps, cfg.ti_tol
    print(
        f"{system.n_dofs} DOFs (the case-1 model). Reference: HB with H = 9. Both methods as sweeps,\n"
        f"one step (the case-1 step, {dw / TWO_PI:.2f} Hz) from f - step to f:\n"
        f"- HB per point: the point at f of an up sweep [f - step, f] (receptances, Newton from the point\n"
        f"  at f - step, metrics, half the link and bearing outputs), median of 3 runs;\n"
        f"- TI: link_time_response(steps_per_period={S}, tol={tol:g}, max_periods={TI_MAX_PERIODS})\n"
        f"  at f - step from rest (its default start),\n"
        f"  then at f from that end state (a time sweep, as time_sweep does). TI per point = the run at f.\n"
        + (
            "  --quick: a coarse setting, not the tuned one."
            if cfg.quick
            else f"  {S} steps per period is the cheapest setting found within 0.5 % at every point\n"
            f"  (128 steps: -1.3 % at 3700 Hz; the error is the HHT-α discretisation, not tol)."
        )
    )
    m9 = build_link_model(system)
    m9.receptance.prepare(9 * float(omegas.max()))
    m5 = build_link_model(system)
    m5.receptance.prepare(5 * float(omegas.max()))
    rows, hb9s, hb5s, rests, warms, errs, rest_errs, errs5 = [], [], [], [], [], [], [], []
    for fz in cfg.ti_frequencies:
        w = TWO_PI * fz
        hb9, st9 = hb_point_cost(m9, w - dw, w, 9)
        hb5, st5 = hb_point_cost(m5, w - dw, w, 5)
        ref_prev, ref = (float(v) for v in st9.result.result.metrics["dte_rms"])
        h5 = float(st5.result.result.metrics["dte_rms"][1])
        opts = dict(steps_per_period=S, tol=tol, max_periods=TI_MAX_PERIODS)
        t0 = time.perf_counter()
        tr0 = link_time_response(m5, w - dw, **opts)
        t_rest = time.perf_counter() - t0
        t0 = time.perf_counter()
        tr1 = link_time_response(m5, w, state0=tr0.state, **opts)
        t_warm = time.perf_counter() - t0
        # the mesh's δ is the one-mesh model's link coordinate 0: RMS of its alternating part
        e_rest = float(np.std(tr0.y[0])) / ref_prev - 1
        e_warm = float(np.std(tr1.y[0])) / ref - 1
        hb9s.append(hb9)
        hb5s.append(hb5)
        rests.append(t_rest)
        warms.append(t_warm)
        errs.append(e_warm)
        errs5.append(h5 / ref - 1)
        rest_errs.append(e_rest)
        cl = float(st9.result.result.metrics["contact_loss_fraction"][1])
        rows.append(
            [
                f"{fz:.0f}",
                f"{ref * 1e6:.3f}",
                f"{cl:.2f}",
                f"{100 * (h5 / ref - 1):+.2f}",
                f"{1e3 * hb5:.1f}",
                f"{1e3 * hb9:.1f}",
                f"{tr1.periods}{'' if tr1.converged else '*'}",
                f"{t_warm:.2f}",
                f"{100 * e_warm:+.2f}",
                f"{t_warm / hb9:.0f}",
                f"{tr0.periods}{'' if tr0.converged else '*'}",
                f"{t_rest:.1f}",
                f"{100 * e_rest:+.2f}",
            ]
        )
        print(f"  {fz:.0f} Hz done", flush=True)
    print()
    header = [
        "f [Hz]",
        "HB9 DTE rms [um]",
        "contact loss [-]",
        "HB5 err [%]",
        "HB5 [ms]",
        "HB9 [ms]",
        "TI periods",
        "TI [s]",
        "TI err [%]",
        "TI/HB9",
        "from rest: periods",
        "[s]",
        "err [%]",
    ]
    print(table(header, rows))
    print(f"  * stopped at max_periods = {TI_MAX_PERIODS} without meeting tol")
    hb9m, hb5m, warm, rest = (float(np.sum(x)) for x in (hb9s, hb5s, warms, rests))
    n = len(warms)
    ok = all(abs(e) <= 0.005 for e in errs)
    print()
    print(f"equal accuracy: TI (time sweep) within 0.5 % of HB H=9 at every point: {'yes' if ok else 'NO'}")
    bad = [
        f"{f:.0f} Hz ({100 * e:+.2f} %)"
        for f, e in zip(cfg.ti_frequencies, rest_errs, strict=True)
        if abs(e) > 0.005
    ]
    if bad:
        print(f"  from rest, {TI_MAX_PERIODS} periods are not enough for 0.5 % at: {', '.join(bad)}")
    sweep_avg = (c1["sweep"].total + c1["build"]) / c1["sweep"].n_points
    print(
        f"per point, mean over the {n} points: TI {warm / n:.2f} s (from rest {rest / n:.1f} s); "
        f"HB H=9 {1e3 * hb9m / n:.1f} ms, H=5 {1e3 * hb5m / n:.1f} ms;\n"
        f"  case-1 sweep average, jumps included: {1e3 * sweep_avg:.1f} ms"
    )
    ratio = warm / hb9m
    med = float(np.median(np.array(warms) / np.array(hb9s)))
    print(
        f"ratio TI / HB (H=9), total time over the {n} points: {ratio:.0f}x "
        f"-> target >= 1000x: {verdict(ratio >= 1000)}"
    )
    print(f"  median of the per-point ratios: {med:.0f}x -> {verdict(med >= 1000)}")
    ok5 = all(abs(e) <= 0.005 for e in errs)
    worst5 = max(errs5, key=abs)
    med5 = float(np.median(np.array(warms) / np.array(hb5s)))
    print(
        f"HB with H = 5 (the paper's) is within {100 * abs(worst5):.3f} % of H = 9 "
        f"(worst {100 * worst5:+.3f} %), TI within 0.5 %: {'yes' if ok5 else 'NO'};\n"
        f"  at that accuracy, median of the per-point ratios TI / HB H=5: {med5:.0f}x "
        f"-> {verdict(med5 >= 1000)}"
    )
    print(
        f"  other ratios (totals): TI / HB H=5 {warm / hb5m:.0f}x; TI from rest / HB H=9 {rest / hb9m:.0f}x; "
        f"TI / case-1 sweep average {warm / n / sweep_avg:.0f}x"
    )


# --------------------------------------------------------------------------------------
# Case 3: per-point cost against model size
# --------------------------------------------------------------------------------------


def case_scaling(cfg, c1) -> None:
    section("Case 3: per-point cost against model size (one-off cost apart)")
    base = load_model(MODEL_FILE)
    f_mode = c1["f_mode"]
    omegas = TWO_PI * np.linspace(0.55 * f_mode, 0.68 * f_mode, cfg.n_scaling)
    top = float(c1["omegas"].max())
    print(
        f"two_shaft.toml with each element split in {', '.join(map(str, cfg.factors))}; mesh damping ratio "
        f"{cfg.zeta}. Up sweep of {cfg.n_scaling} points,\n"
        f"{omegas[0] / TWO_PI:.0f} .. {omegas[-1] / TWO_PI:.0f} Hz (full contact, no jumps), H = 5; "
        f"models built for the case-1 range\n"
        f"(modal: the link reduction's truncated modal basis for 5 x {top / TWO_PI:.0f} Hz). "
        f"Per point: median over points 2..n\n"
        f"(the first carries the one-off mean-load factorisation) plus link and bearing outputs / n.\n"
        f"The one-off cost (the build, with the modal basis; then receptance.prepare) is timed apart."
    )
    rows, per = [], {}
    for factor in cfg.factors:
        system = refine(base, factor, cfg.zeta)
        for method in ("modal", "direct"):
            with BLAS.threads(cfg.primary):
                t0 = time.perf_counter()
                model = build_link_model(system, method=method, max_frequency=5 * top)  # with its basis
                t_build = time.perf_counter() - t0
            variants = [(cfg.primary, cfg.primary_label)]
            if method == "modal" and cfg.secondary is not None:
                variants.append((cfg.secondary, cfg.secondary_label))
            for threads, tlabel in variants:
                empty_caches(model)
                with BLAS.threads(threads):
                    t0 = time.perf_counter()
                    model.receptance.prepare(5 * top)  # nothing left to do if the build made the basis
                    t_poles = time.perf_counter() - t0
                    st = timed_sweep(model, omegas, 5, directions="up")
                br = st.phases["bearing recovery"] / st.n_points
                pp = float(np.median(st.point_times[1:])) + br
                rec = float(np.median([p.get("receptances", 0.0) for p in st.point_phases[1:]]))
                newton = float(np.median([p.get("Newton", 0.0) for p in st.point_phases[1:]]))
                per[(system.n_dofs, method, tlabel)] = pp
                rows.append(
                    [
                        f"{system.n_dofs}",
                        method,
                        tlabel,
                        f"{t_build:.2f} + {t_poles:.2f}" if tlabel == cfg.primary_label else "(same)",
                        "-" if model.receptance.basis is None else f"{model.receptance.basis.shape[1]}",
                        f"{1e3 * pp:.1f}",
                        f"{1e3 * rec:.1f}",
                        f"{1e3 * newton:.2f}",
                        f"{st.n_failed + st.n_switch}",
                    ]
                )
            print(f"  {system.n_dofs} DOFs, {method} done", flush=True)
    print()
    header = [
        "DOFs",
        "receptance",
        "BLAS",
        "one-off: build + prepare [s]",
        "basis size",
        "per point [ms]",
        "  receptances [ms]",
        "  Newton [ms]",
        "switch+failed",
    ]
    print(table(header, rows))
    n_small = 12 * (10 * min(cfg.factors) + 1)
    n_large = 12 * (10 * max(cfg.factors) + 1)
    print()
    for method, tlabel in (("modal", cfg.primary_label), ("direct", cfg.primary_label)):
        a, b = per.get((n_small, method, tlabel)), per.get((n_large, method, tlabel))
        if a and b:
            print(
                f"per-point growth {n_small} -> {n_large} DOFs, {method} ({tlabel}): {b / a:.2f}x "
                f"-> target <= 2x: {verdict(b / a <= 2)}"
            )
    a, b = per.get((n_small, "modal", cfg.secondary_label)), per.get((n_large, "modal", cfg.secondary_label))
    if a and b:
        print(
            f"  modal with {cfg.secondary_label}: {b / a:.2f}x (no verdict: these times follow the other "
            f"processes' load)"
        )
    a, b = per.get((n_small, "direct", cfg.primary_label)), per.get((n_large, "modal", cfg.primary_label))
    if a and b:
        print(
            f"per-point growth with receptance='auto' (direct at {n_small}, modal at {n_large} DOFs): "
            f"{b / a:.2f}x -> {verdict(b / a <= 2)}"
        )
    mids = sorted({k[0] for k in per if k[0] != n_small})
    if len(mids) > 1:
        a = per.get((mids[0], "modal", cfg.primary_label))
        b = per.get((n_large, "modal", cfg.primary_label))
        if a and b:
            print(f"  modal, {mids[0]} -> {n_large} DOFs (basis size saturated): {b / a:.2f}x")


# --------------------------------------------------------------------------------------


# --------------------------------------------------------------------------------------
# Case 4: the single mesh on the link engine
# --------------------------------------------------------------------------------------


class Counts:
    """Corrector evaluations of the landing searches, sweeps per ladder, lifts refused and
    Floquet calls of one run (wrapping library functions for its duration, as :class:`Probe`)."""

    def __init__(self):
        self.n = defaultdict(int)
        self._patched = []

    def _wrap(self, owner, name, key, refused=False):
        orig = vars(owner)[name]
        counts = self.n

        def wrapper(*args, **kwargs):
            counts[key] += 1
            out = orig(*args, **kwargs)
            if refused and out is None:
                counts["lifts refused"] += 1
            return out

        setattr(owner, name, wrapper)
        self._patched.append((owner, name, orig))

    def __enter__(self):
        self._wrap(nl_arclength.Tracer, "system", "corrector evaluations")
        self._wrap(nl_harmonics, "sweep", "sweeps")
        self._wrap(nl_harmonics, "lift", "lifts", refused=True)
        self._wrap(nl_floquet, "floquet_analysis", "Floquet calls")  # every caller's
        return self

    def __exit__(self, *exc):
        for owner, name, orig in reversed(self._patched):
            setattr(owner, name, orig)


def _engines_run(run, *args) -> tuple[float, float, dict, object]:
    """(wall, CPU, counts, result) of ``run(*args)``."""
    with Counts() as counts:
        w0, c0 = time.perf_counter(), time.process_time()
        res = run(*args)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    return wall, cpu, dict(counts.n), res


def _verdicts(sweep_result) -> tuple[int, int, int]:
    """(converged, stable, no stable response) points."""
    r = sweep_result
    return int(np.sum(r.converged)), int(np.sum(r.stable)), int(np.sum(r.no_stable))


def case_engines(cfg) -> None:
    section("Case 4: single mesh on the link engine (link_sweep)")
    base = load_model(MODEL_FILE)
    system = refine(base, 2, cfg.zeta)
    f_mode = float(round(gear_pair_mode(system)[0]))
    omegas = TWO_PI * np.linspace(0.5 * f_mode, 1.5 * f_mode, cfg.n_points)
    sub = TWO_PI * np.linspace(0.5 * f_mode, 1.5 * f_mode, cfg.n_stability)
    hz40 = np.linspace(1000.0, 2900.0, cfg.n_default)
    print(
        f"(a) case 1's sweep: {system.n_dofs} DOFs, 2 x {cfg.n_points} points H = 5 without stability, "
        f"2 x {cfg.n_stability} with; the model built once, outside the timing.\n"
        f"(b) {MODEL_FILE.relative_to(ROOT)} as in the file, {hz40.size} base frequencies 1000-2900 Hz "
        f"both ways, H chosen, stability, period 'auto', no time-domain answers; each run builds its model.\n"
        f"Best of {cfg.repeats} by CPU time; load at start {load_average()}.\n"
        f"The single-mesh engine's rows (issue 33's link / old ratio) are recorded history in\n"
        f"benchmarks/README.md: that engine is deleted (bench_against_deleted.py runs it from a worktree)."
    )
    link_model = build_link_model(system)
    link_model.receptance.prepare(5 * float(omegas.max()))

    def run(grid, stab, H, sys_):
        model = link_model if H else build_link_model(sys_)
        return link_sweep(model, grid, H, stability=stab, period="auto" if stab else 1).result

    cases = [
        (f"(a) H = 5, 2 x {cfg.n_points}, stability=False", omegas, False, 5, system),
        (f"(a) H = 5, 2 x {cfg.n_stability}, stability=True", sub, True, 5, system),
        (f"(b) two_shaft 2 x {hz40.size}, H chosen, stability", TWO_PI * hz40, True, None, base),
    ]
    before = _case4_before(cfg.before) if cfg.before else {}
    rows = []
    for label, grid, stab, H, sys_ in cases:
        best = None
        for _ in range(cfg.repeats):
            out = _engines_run(run, grid, stab, H, sys_)
            if best is None or out[1] < best[1]:
                best = out
        wall, cpu, counts, res = best
        conv, stable, lost = _verdicts(res)
        rows.append(
            [
                label,
                f"{cpu:.2f}",
                f"{wall:.2f}",
                f"{1e3 * cpu / len(grid) / 2:.1f}",
                str(res.H),
                f"{conv}/{stable}/{lost}",
                str(counts.get("corrector evaluations", 0)),
                str(counts.get("sweeps", 1 if H else 0)),
                str(counts.get("lifts refused", 0)),
                str(counts.get("Floquet calls", 0)),
            ]
        )
        if label in before:
            print(f"{label}: CPU {cpu:.2f} s, before {before[label]:.2f} s -> {cpu / before[label]:.2f}x")
    header = ["case", "CPU s", "wall s", "CPU ms/pt", "H", "conv/stable/no stable"]
    header += ["corrector evals", "sweeps", "lifts refused", "Floquet calls"]
    print(table(header, rows))
    print(f"load average at end of case 4: {load_average()}")


def _case4_before(path: str) -> dict[str, float]:
    """CPU seconds per case label from the printed case-4 table of an earlier run
    (``--cases 4 --before FILE``; a link engine's table: a case's first cells, then CPU s)."""
    out = {}
    for line in Path(path).read_text().splitlines():
        parts = re.split(r"\s{2,}", line.strip())
        if len(parts) >= 2 and parts[0].startswith(("(a)", "(b)")):
            try:
                out[parts[0]] = float(parts[1])
            except ValueError:
                continue
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small grids and models (smoke run, about 1 min)")
    ap.add_argument(
        "--full-stability",
        action="store_true",
        help="also the 2 x 500 sweep with stability (about 4 more min)",
    )
    ap.add_argument("--zeta", type=float, default=0.1, help="mesh damping ratio (file: 0.005), default 0.1")
    ap.add_argument(
        "--before",
        help="with --full-stability: another floquet.py run side by side (module docstring); "
        "with --cases 4: the output of an earlier --cases 4 run, compared per case by CPU time",
    )
    ap.add_argument(
        "--cases", default="123", help="which cases to run, e.g. 13 (case 1 runs with 2 or 3), 4 alone"
    )
    ap.add_argument("--repeats", type=int, default=2, help="case 4: runs per case (the best reported)")
    ap.add_argument(
        "--blas-default", action="store_true", help="primary figures with the default BLAS threads, not 1"
    )
    cfg = ap.parse_args(argv)
    if cfg.quick:
        cfg.n_points, cfg.n_stability, cfg.n_scaling, cfg.n_default = 100, 4, 8, 10
        cfg.ti_frequencies, cfg.ti_steps, cfg.ti_tol = [2000.0], 128, 1e-4
        cfg.factors = [1, 8]
    else:
        cfg.n_points, cfg.n_stability, cfg.n_scaling, cfg.n_default = 500, 15, 15, 40
        cfg.ti_frequencies, cfg.ti_steps, cfg.ti_tol = [2000.0, 2800.0, 3300.0, 3700.0, 4300.0], 256, 1e-4
        cfg.factors = [1, 8, 25, 83]
    one = "1 BLAS thread"
    dflt = (
        "default BLAS threads (" + "/".join(map(str, BLAS.default)) + ")"
        if BLAS.available
        else "default BLAS"
    )
    if not BLAS.available:
        cfg.primary, cfg.primary_label, cfg.secondary, cfg.secondary_label = None, dflt, None, None
    elif cfg.blas_default:
        cfg.primary, cfg.primary_label, cfg.secondary, cfg.secondary_label = None, dflt, 1, one
    else:
        cfg.primary, cfg.primary_label, cfg.secondary, cfg.secondary_label = 1, one, list(BLAS.default), dflt
    t_all = time.perf_counter()
    print("nlgrd nonlinear benchmark" + (" (--quick)" if cfg.quick else ""))
    if cfg.quick:
        print(
            "--quick: small grids and models (a smoke run); its MET/MISSED lines are not acceptance figures"
        )
    print("\n".join(machine_lines()))
    print(f"primary setting: {cfg.primary_label}; side by side: {cfg.secondary_label or 'none'}")
    with BLAS.threads(cfg.primary):
        if "4" in cfg.cases:
            case_engines(cfg)
        if not set(cfg.cases) & set("123"):
            print(f"\nload average at end: {load_average()}")
            return
        c1 = case_sweep(cfg)
        if "2" in cfg.cases:
            case_time_domain(cfg, c1)
        if "3" in cfg.cases:
            case_scaling(cfg, c1)
    print(f"\nload average at end: {load_average()}")
    print(f"benchmark wall time: {time.perf_counter() - t_all:.0f} s")


if __name__ == "__main__":
    sys.exit(main())
