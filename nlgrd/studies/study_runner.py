"""Running a study: its tasks on Dask (or in-process), results kept per task, tables at the end.

- **Executors.** ``"local"`` (default) starts a :class:`distributed.LocalCluster` sized
  to the machine (one single-threaded worker process per core) whose scheduler,
  workers, nannies and dashboard listen on 127.0.0.1 only; ``scheduler="tls://..."``
  (or ``tcp://``) uses an existing cluster with the certificates of the user's Dask
  configuration (``distributed.comm.tls.*``); ``"serial"`` runs in this process, for
  debugging. One task per sweep: a sweep's continuity stays inside its task.
- **Failures.** A task that raises is recorded with its error and the study goes on.
  A worker that dies takes its running task with it; the scheduler runs it again
  elsewhere (Dask's ``allowed-failures``), so the study completes with the same
  results. Ctrl-C cancels what is running and keeps what is finished.
- **Results** (:class:`ResultStore`): each finished task is written atomically to
  ``tasks/<key>.parquet`` and ``tasks/<key>.json`` (the JSON last: it marks the task
  done). A rerun skips every task whose key is stored, so it resumes after a crash or
  an interrupt; keys name the model, the analysis and the nlgrd version, so results of
  another model or library version are never picked up. Failed tasks are tried again.
- **Tables**, written atomically once every task is done: ``summary.csv`` and
  ``summary.parquet`` (one row per task: the parameters, status, error and the summary
  of :func:`~nlgrd.studies.study_tasks.summarise`), ``points.parquet`` (one row per
  sweep point, the parameters as columns) and ``grid.parquet``: the summary indexed by
  the axes (and the draw), which ``xarray.Dataset.from_dataframe`` turns into arrays
  over the axes. Rerunning a finished study rewrites them byte-identically.
"""

from __future__ import annotations

import json
import logging
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from nlgrd.errors import ModelError
from nlgrd.studies.index_page import write_json, write_text
from nlgrd.studies.study_file import Study
from nlgrd.studies.study_tasks import TaskSpec, run_task, task_specs

__all__ = [
    "CONNECT_TIMEOUT",
    "ResultStore",
    "StudyRun",
    "check_scheduler",
    "connect",
    "local_cluster",
    "run_study",
]

#: Seconds allowed to reach an existing scheduler (``--connect-timeout``). Dask's own
#: default (30 s) retries a closed port for half a minute; a scheduler that answers does
#: so in milliseconds on a LAN.
CONNECT_TIMEOUT = 10.0

_TLS_HELP = (
    "set distributed.comm.tls.ca-file, distributed.comm.tls.client.cert and "
    "distributed.comm.tls.client.key in your Dask configuration (e.g. ~/.config/dask/distributed.yaml, "
    "or the environment variables DASK_DISTRIBUTED__COMM__TLS__CA_FILE, ..._CLIENT__CERT, ..._CLIENT__KEY)"
)


def check_scheduler(scheduler: str | None) -> None:
    """Refuse a scheduler address that cannot work, before anything runs.

    Parameters
    ----------
    scheduler : str or None
        ``tcp://HOST:PORT`` or ``tls://HOST:PORT``; None: nothing to check.

    Raises
    ------
    ModelError
        Naming ``--scheduler``: another scheme, or ``tls://`` without the TLS files of the
        Dask configuration (the message says which keys to set).
    """
    if scheduler is None:
        return
    scheme, sep, rest = scheduler.partition("://")
    if not sep or scheme not in ("tcp", "tls") or not rest:
        raise ModelError("--scheduler", f"expected tcp://HOST:PORT or tls://HOST:PORT, got {scheduler!r}")
    if scheme == "tls":
        from distributed.security import Security

        sec = Security()
        if not (sec.tls_ca_file and sec.tls_client_cert):
            raise ModelError("--scheduler", f"{scheduler} needs the client's TLS certificates: {_TLS_HELP}")


def connect(scheduler: str, timeout: float | None = None):
    """A Dask client of the scheduler at ``scheduler``, or one line saying why not.

    Parameters
    ----------
    scheduler : str
        Its address (checked by :func:`check_scheduler`).
    timeout : float or None
        Seconds allowed to connect [s]; None: :data:`CONNECT_TIMEOUT`.

    Returns
    -------
    distributed.Client

    Raises
    ------
    ModelError
        Naming ``--scheduler`` when the address is refused or nothing answers in time.
    """
    from distributed import Client
    from distributed.security import Security

    check_scheduler(scheduler)
    timeout = CONNECT_TIMEOUT if timeout is None else timeout
    try:
        return Client(scheduler, security=Security(), timeout=timeout)
    except (OSError, TimeoutError) as err:
        raise ModelError(
            "--scheduler",
            f"no Dask scheduler answered at {scheduler} within {timeout:g} s ({type(err).__name__}); "
            "is it running? (--connect-timeout sets the wait)",
        ) from None


EXECUTORS = ("local", "serial")


def default_workers() -> int:
    """Worker processes of the embedded cluster: the cores this process may use.

    Returns
    -------
    int
    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def local_cluster(workers: int | None = None):
    """The embedded cluster: ``workers`` single-threaded processes, all on the loopback.

    Parameters
    ----------
    workers : int or None
        Worker processes; None: :func:`default_workers`.

    Returns
    -------
    distributed.LocalCluster
    """
    import dask

    # Dask's nannies set MALLOC_TRIM_THRESHOLD_ in their workers, which turns off glibc's
    # dynamic mmap threshold: every large numpy array is then a fresh mmap, and a sweep
    # ran 29 % slower (benchmarks/README.md). None unsets it for the embedded cluster.
    with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}):
        return _local_cluster(workers)


def _local_cluster(workers: int | None):
    from distributed import LocalCluster

    return LocalCluster(
        n_workers=workers or default_workers(),
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address="127.0.0.1:0",
        silence_logs=logging.ERROR,
        preload=["nlgrd.studies.study_tasks"],  # the library is imported as a worker starts
    )


class ResultStore:
    """Per-task results in ``out/tasks/``, written atomically (see the module docstring).

    Parameters
    ----------
    out : pathlib.Path
        The study's output folder.
    """

    def __init__(self, out: Path):
        self.out = Path(out)
        self.tasks = self.out / "tasks"

    def done(self, key: str) -> bool:
        """Whether the task ``key`` finished without error."""
        record = self.read(key)
        return record is not None and record.get("error") is None

    def read(self, key: str) -> dict | None:
        """The stored record of ``key`` (None when there is none)."""
        try:
            return json.loads((self.tasks / f"{key}.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None

    def write(self, result: dict) -> None:
        """Store one task's result (points first, the record last)."""
        self.tasks.mkdir(parents=True, exist_ok=True)
        key = result["key"]
        if result["points"] is not None:
            tmp = self.tasks / f".{key}.parquet.tmp"
            result["points"].to_parquet(tmp, index=False)
            os.replace(tmp, self.tasks / f"{key}.parquet")
        record = {k: result[k] for k in ("key", "error", "warnings", "summary")}
        record["seconds"] = round(float(result["seconds"]), 3)
        write_json(self.tasks / f"{key}.json", record)

    def points(self, key: str) -> pd.DataFrame | None:
        """The stored per-point table of ``key``."""
        path = self.tasks / f"{key}.parquet"
        return pd.read_parquet(path) if path.exists() else None


@dataclass
class StudyRun:
    """What a run did: task counts and where the tables are.

    Attributes
    ----------
    tasks : int
        Tasks of the study.
    skipped : int
        Found finished in the store (not recomputed).
    computed : int
        Run now.
    failed : int
        Tasks whose record holds an error.
    interrupted : bool
        Stopped by Ctrl-C (the tables are not written).
    out : pathlib.Path
        The output folder.
    cancelled : int
        Tasks with no record: cancelled (Ctrl-C, a lost client) before they finished; a
        rerun runs them.
    """

    tasks: int
    skipped: int
    computed: int
    failed: int
    interrupted: bool
    out: Path
    cancelled: int = 0


def _progress(total: int, initial: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(
        total=total, initial=initial, disable=not enabled, unit="task", file=sys.stderr, dynamic_ncols=True
    )


def _serial(specs: list[TaskSpec], handle: Callable[[dict], None], on_result) -> None:
    for spec in specs:
        handle(run_task(spec))
        if on_result is not None:
            on_result(None)


def _on_dask(client, specs: list[TaskSpec], handle: Callable[[dict], None], on_result) -> None:
    from distributed import as_completed

    futures = {client.submit(run_task, s, key=f"nlgrd-task-{s.key}", pure=False): s for s in specs}
    try:
        for future in as_completed(futures):
            spec = futures[future]
            if future.status == "cancelled":  # no record: a rerun runs it again
                continue
            if future.status == "finished":
                result = future.result()
            else:  # raised outside run_task: a worker lost too often, a pickling error
                err = future.exception()
                result = {
                    "key": spec.key,
                    "index": spec.index,
                    "points": None,
                    "summary": None,
                    "error": f"{type(err).__name__}: {' '.join(str(err).split())}",
                    "warnings": [],
                    "seconds": 0.0,
                }
            handle(result)
            if on_result is not None:
                on_result(client)
    finally:
        client.cancel(list(futures))


def run_study(
    study: Study,
    out: str | os.PathLike,
    *,
    executor: str = "local",
    scheduler: str | None = None,
    workers: int | None = None,
    progress: bool = True,
    on_result: Callable[[Any], None] | None = None,
    connect_timeout: float | None = None,
) -> StudyRun:
    """Run every unfinished task of ``study`` and write its tables into ``out``.

    Parameters
    ----------
    study : Study
        The study (:func:`~nlgrd.studies.study_file.load_study`).
    out : str or os.PathLike
        Output folder (made when missing).
    executor : {"local", "serial"}
        The embedded Dask cluster, or this process.
    scheduler : str or None
        Address of an existing Dask scheduler (``tcp://`` or ``tls://``); overrides
        ``executor``.
    workers : int or None
        Worker processes of the embedded cluster (default: one per core).
    progress : bool
        A progress bar with ETA on standard error.
    on_result : callable or None
        Called with the Dask client (None when serial) after each finished task (tests).
    connect_timeout : float or None
        Seconds allowed to reach ``scheduler`` [s] (:func:`connect`).

    Returns
    -------
    StudyRun

    Raises
    ------
    ModelError
        For an unknown executor (``--executor``) or a bad worker count (``--workers``).
    """
    if executor not in EXECUTORS:
        raise ModelError("--executor", f"must be one of {', '.join(EXECUTORS)}, got {executor!r}")
    if workers is not None and workers < 1:
        raise ModelError("--workers", f"must be at least 1, got {workers}")
    check_scheduler(scheduler)
    out = Path(out)
    store = ResultStore(out)
    specs = task_specs(study)
    unique = list({s.key: s for s in specs}.values())
    todo = [s for s in unique if not store.done(s.key)]
    skipped = len(unique) - len(todo)
    client = connect(scheduler, connect_timeout) if scheduler is not None and todo else None
    bar = _progress(len(unique), skipped, progress)
    computed = 0

    def handle(result: dict) -> None:
        nonlocal computed
        store.write(result)
        computed += 1
        bar.update(1)
        if result["error"] is not None:
            bar.write(f"task {result['index']}: {result['error']}")

    interrupted = False
    try:
        if not todo:
            pass
        elif scheduler is None and executor == "serial":
            _serial(todo, handle, on_result)
        else:
            _run_on_cluster(todo, handle, client, workers, on_result)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        bar.close()
    records = [store.read(s.key) for s in unique]
    failed = sum(r is not None and r.get("error") is not None for r in records)
    cancelled = sum(r is None for r in records)
    if not interrupted:
        write_tables(study, specs, store)
    return StudyRun(len(unique), skipped, computed, failed, interrupted, out, cancelled)


def _run_on_cluster(todo, handle, client, workers, on_result) -> None:
    """On ``client`` (an existing scheduler's, closed at the end) or an embedded cluster."""
    from distributed import Client

    if client is not None:
        with client:
            _on_dask(client, todo, handle, on_result)
        return
    with local_cluster(workers) as cluster, Client(cluster) as client:
        _on_dask(client, todo, handle, on_result)


# ------------------------------------------------------------------------------ tables


def _atomic_parquet(frame: pd.DataFrame, path: Path, index: bool) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    frame.to_parquet(tmp, index=index)
    os.replace(tmp, path)


def summary_table(study: Study, specs: list[TaskSpec], store: ResultStore) -> pd.DataFrame:
    """One row per task: index, parameters, status, error and summary (:func:`summarise`).

    Parameters
    ----------
    study : Study
    specs : list of TaskSpec
        The study's tasks.
    store : ResultStore
        Where their results are.

    Returns
    -------
    pandas.DataFrame
    """
    rows = []
    sampled = study.samples if any(a.sampled for a in study.axes) else 0
    for s in specs:
        record = store.read(s.key)
        row: dict[str, Any] = {"task": s.index}
        if sampled:
            row["sample"] = s.index % sampled
        row.update(s.parameters)
        if record is None:
            row["status"], row["error"], record = "cancelled", "cancelled (rerun to resume)", {}
        else:
            row["status"] = "failed" if record.get("error") else "done"
            row["error"] = record.get("error") or ""
        row.update(record.get("summary") or {})
        row["key"] = s.key
        rows.append(row)
    frame = pd.DataFrame(rows)
    head = [c for c in frame if c not in ("key",)]
    return frame[head + ["key"]]


def write_tables(study: Study, specs: list[TaskSpec], store: ResultStore) -> None:
    """Write ``summary.csv``, ``summary.parquet``, ``grid.parquet`` and ``points.parquet``.

    Parameters
    ----------
    study : Study
    specs : list of TaskSpec
    store : ResultStore
    """
    summary = summary_table(study, specs, store)
    write_text(store.out / "summary.csv", summary.to_csv(index=False, lineterminator="\n"))
    _atomic_parquet(summary, store.out / "summary.parquet", index=False)
    dims = [a.name for a in study.grid_axes] + (["sample"] if "sample" in summary else [])
    if dims:
        numeric = summary.drop(columns=["task", "status", "error", "key"])  # drawn values stay as variables
        _atomic_parquet(numeric.set_index(dims), store.out / "grid.parquet", index=True)
    parts = []
    for s in specs:
        pts = store.points(s.key)
        if pts is None:
            continue
        params = pd.DataFrame({"task": np.full(len(pts), s.index)})
        for name, value in s.parameters.items():
            params[name] = value
        parts.append(pd.concat([params, pts.reset_index(drop=True)], axis=1))
    if parts:
        _atomic_parquet(pd.concat(parts, ignore_index=True), store.out / "points.parquet", index=False)
    write_json(
        store.out / "study.json",
        {
            "name": study.name,
            "study_file": os.path.basename(study.file),
            "model_file": os.path.basename(study.model_file),
            "analysis": study.analysis.as_dict(),
            "axes": [a.name for a in study.axes],
            "tasks": len(specs),
            "failed": int((summary["status"] != "done").sum()),
        },
    )
