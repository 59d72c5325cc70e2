"""A study on 2 Dask workers against the same study run serially (issue 13).

Run from the repository root::

    .venv/bin/python benchmarks/bench_studies.py              # 16 tasks, about 2 min
    .venv/bin/python benchmarks/bench_studies.py --tasks 32

The study: Kubo's rig (data/case_studies/kubo.toml) at mesh damping ratio 0.05, the
pinion torque on ``--tasks`` values from 50 to 200 N m, each task a sweep of 31 speeds
from 4000 to 14000 rpm up and down, H by the error estimate, Floquet stability on: the
defaults of ``nlgrd study``. Side by side in one run:

1. serially, in this process (``--executor serial``);
2. on a 2-worker ``LocalCluster`` started beforehand (its start-up time is printed
   separately), through its scheduler address, as ``nlgrd study --scheduler`` would.

Speed-up = serial wall time / cluster wall time. Scheduler overhead per task, from
Dask's task stream: on each worker, the idle gaps between the end of one task's
computation and the start of the next (the scheduler's round trip, the result's
transfer, the next task's arguments), summed over the workers and divided by the
number of tasks, against the mean task computation time. The idle tail after a
worker's last task (load imbalance: nothing left to run) is not overhead and is
reported on its own. Both runs' summary tables are compared byte for byte.
Figures and machine in benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def study_text(tasks: int) -> str:
    torques = [50.0 + 150.0 * i / (tasks - 1) for i in range(tasks)]
    return f"""version = 1
name = "benchmark: Kubo, {tasks} torques"
model = "{(ROOT / "data" / "case_studies" / "kubo.toml").as_posix()}"
[analysis]
rpm = [4000.0, 14000.0, 31]
direction = "both"
[[axes]]
key = "gear_pairs[0].damping_ratio"
values = [0.05]
[[axes]]
key = "gear_pairs[0].torque"
values = [{", ".join(repr(t) for t in torques)}]
"""


def gaps(stream: list[dict], t_end: float) -> tuple[float, float, int]:
    """(sum of idle gaps between computations, idle tails, tasks) over the workers."""
    by_worker: dict[str, list[tuple[float, float]]] = {}
    for rec in stream:
        for ss in rec["startstops"]:
            if ss["action"] == "compute":
                by_worker.setdefault(rec["worker"], []).append((ss["start"], ss["stop"]))
    gap = tail = 0.0
    n = 0
    for spans in by_worker.values():
        spans.sort()
        n += len(spans)
        gap += sum(b[0] - a[1] for a, b in zip(spans, spans[1:], strict=False))
        tail += t_end - spans[-1][1]
    return gap, tail, n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", type=int, default=16)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()

    from distributed import Client, get_task_stream

    from nlgrd.studies.study_file import load_study
    from nlgrd.studies.study_runner import local_cluster, run_study

    tmp = Path(tempfile.mkdtemp(prefix="bench-study-"))
    try:
        path = tmp / "study.toml"
        path.write_text(study_text(args.tasks))
        study = load_study(path)
        t0 = time.perf_counter()
        run_study(study, tmp / "serial", executor="serial", progress=False)
        t_serial = time.perf_counter() - t0

        t0 = time.perf_counter()
        with local_cluster(args.workers) as cluster, Client(cluster) as client:
            t_start = time.perf_counter() - t0
            client.run(lambda: None)
            with get_task_stream(client) as ts:
                t0 = time.perf_counter()
                run_study(study, tmp / "cluster", scheduler=cluster.scheduler_address, progress=False)
                t_cluster = time.perf_counter() - t0
                t_end = time.time()
            stream = [r for r in ts.data if str(r.get("key", "")).startswith("nlgrd-task-")]
        compute = sum(
            ss["stop"] - ss["start"]
            for rec in stream
            for ss in rec["startstops"]
            if ss["action"] == "compute"
        )
        gap, tail, n = gaps(stream, t_end)
        same = (tmp / "serial" / "summary.csv").read_bytes() == (tmp / "cluster" / "summary.csv").read_bytes()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    mean = compute / n
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}")
    print(f"study: {args.tasks} tasks (sweeps of Kubo's rig), {args.workers} workers")
    print(f"serial:  {t_serial:.1f} s")
    print(f"cluster: {t_cluster:.1f} s (start-up of the LocalCluster, not counted: {t_start:.1f} s)")
    print(f"speed-up: {t_serial / t_cluster:.2f}x")
    print(f"tasks in the task stream: {n}, mean computation {mean:.2f} s")
    print(
        f"scheduler overhead per task: {gap / n * 1e3:.1f} ms = {100 * gap / n / mean:.2f} %"
        " of the mean task; "
        f"idle tails (nothing left to run): {tail:.1f} s over the workers"
    )
    print(f"summary tables byte-identical: {same}")


if __name__ == "__main__":
    main()
