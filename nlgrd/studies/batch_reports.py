"""Batch reports: one notebook executed by papermill once per parameter set.

``nlgrd report NOTEBOOK -p NAME VALUE ...`` runs one set; ``--batch FILE`` runs every
``[[runs]]`` table of a TOML file (its keys are notebook parameters, plus an optional
``name`` for the run's folder; ``-p`` values apply to every run)::

    [[runs]]
    name = "H5"
    fast = true
    H = 5

Every parameter name of every set is checked against the notebook's parameters cell
before anything runs (papermill alone would warn and run the defaults). The runs go to
the same executors as studies (:mod:`nlgrd.studies.study_runner`): the embedded Dask
cluster, an existing one, or this process. Each run is executed in a staging folder
and renamed into ``OUT/<name>/`` (the executed notebook, its HTML, its figures and CSV
files) only when it succeeded; ``OUT/index.html`` lists the runs with their parameters,
figures and status.
"""

from __future__ import annotations

import html
import os
import re
import shutil
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import quote

from nlgrd.errors import ModelError
from nlgrd.studies.index_page import write_json, write_text
from nlgrd.studies.notebooks import (
    check_parameters,
    export_html,
    make_deterministic,
    relative_path,
    run_notebook,
)

__all__ = ["ReportRun", "read_batch", "run_batch"]

_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")


@dataclass(frozen=True)
class ReportRun:
    """One run of a batch: its folder name and parameters.

    Parameters
    ----------
    name : str
        Folder name under the batch's output folder.
    parameters : dict
        Notebook parameters by name.
    """

    name: str
    parameters: dict


def read_batch(path: str | os.PathLike | None, common: dict[str, Any]) -> list[ReportRun]:
    """The runs of a batch file (or one run of ``common`` alone when ``path`` is None).

    Parameters
    ----------
    path : str or os.PathLike or None
        The batch file (TOML, ``[[runs]]`` tables).
    common : dict
        Parameters given on the command line (``-p``), applied to every run.

    Returns
    -------
    list of ReportRun

    Raises
    ------
    ModelError
        Naming the file and key, for an unreadable file, a run that is not a table, a
        bad or repeated ``name``.
    """
    if path is None:
        return [ReportRun("run", dict(common))]
    file = str(path)
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as err:
        raise ModelError("", f"cannot read the batch file: {err.strerror or err}", file) from None
    except tomllib.TOMLDecodeError as err:
        raise ModelError("", f"not valid TOML: {err}", file) from None
    for k in sorted(set(data) - {"runs"}):
        raise ModelError(k, "unknown key; a batch file holds [[runs]] tables", file)
    runs = data.get("runs")
    if not isinstance(runs, list) or not runs:
        raise ModelError("runs", "give at least one [[runs]] table", file)
    out, seen = [], set()
    for i, raw in enumerate(runs):
        if not isinstance(raw, dict):
            raise ModelError(f"runs[{i}]", "must be a table", file)
        params = dict(raw)
        name = params.pop("name", f"run-{i + 1:02d}")
        if not isinstance(name, str) or not _NAME.fullmatch(name):
            raise ModelError(
                f"runs[{i}].name", f"must be a folder name of letters, digits, _ . -, got {name!r}", file
            )
        if name in seen:
            raise ModelError(f"runs[{i}].name", f"{name!r} is used twice", file)
        seen.add(name)
        out.append(ReportRun(name, {**common, **params}))
    return out


def run_report(notebook: str, target: str, parameters: dict, progress: bool = False) -> dict[str, Any]:
    """Execute one run into ``target`` (via a staging folder); returns its record.

    Parameters
    ----------
    notebook : str
        The notebook file.
    target : str
        The run's folder (replaced when the run succeeds).
    parameters : dict
        Notebook parameters (``out_dir`` is set to the staging folder).
    progress : bool
        A tqdm bar over the notebook's cells on standard error.

    Returns
    -------
    dict
        ``error`` (one line or None), ``files`` (names written).
    """
    target_path = Path(target)
    stage = target_path.with_name(f".{target_path.name}.partial")
    shutil.rmtree(stage, ignore_errors=True)
    try:
        executed = run_notebook(notebook, stage, parameters, progress_bar=progress)
        make_deterministic(executed, out_dir=relative_path(target_path, Path(notebook).parent))
        export_html(executed)
    except Exception as err:  # recorded in the index; the batch goes on
        shutil.rmtree(stage, ignore_errors=True)
        return {"error": f"{type(err).__name__}: {' '.join(str(err).split())[:300]}", "files": []}
    old = target_path.with_name(f".{target_path.name}.old")
    shutil.rmtree(old, ignore_errors=True)
    if target_path.exists():
        os.replace(target_path, old)
    os.replace(stage, target_path)
    shutil.rmtree(old, ignore_errors=True)
    return {"error": None, "files": sorted(p.name for p in target_path.iterdir())}


def _index(title: str, runs: list[ReportRun], records: dict[str, dict]) -> str:
    esc = html.escape
    rows = []
    for run in runs:
        rec = records[run.name]
        params = ", ".join(f"{esc(k)} = {esc(repr(v))}" for k, v in sorted(run.parameters.items()))
        pages = [f for f in rec["files"] if f.endswith(".html")]
        link = (
            f'<a href="{quote(run.name)}/{quote(pages[0])}">{esc(run.name)}</a>' if pages else esc(run.name)
        )
        status = "done" if rec["error"] is None else f"failed: {esc(rec['error'])}"
        figs = "".join(
            f'<a href="{quote(run.name)}/{quote(f)}"><img src="{quote(run.name)}/{quote(f)}" width="220"></a>'
            for f in rec["files"]
            if f.endswith(".png")
        )
        rows.append(f"<tr><td>{link}</td><td><code>{params}</code></td><td>{status}</td><td>{figs}</td></tr>")
    return (
        f"<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>{esc(title)}</title></head><body>\n"
        f"<h1>{esc(title)}</h1>\n<table border='1' cellpadding='4'>\n"
        "<tr><th>run</th><th>parameters</th><th>status</th><th>figures</th></tr>\n"
        + "\n".join(rows)
        + "\n</table>\n</body></html>\n"
    )


def _runs_bar(total: int, enabled: bool):
    """A tqdm bar over the runs of a batch on standard error (disabled: counts nothing)."""
    from tqdm import tqdm

    return tqdm(total=total, disable=not enabled, unit="run", file=sys.stderr, dynamic_ncols=True)


def _gather(client, futures: list, bar) -> list:
    """The futures' results in their order, ``bar`` advanced as each finishes."""
    from distributed import as_completed

    for _ in as_completed(futures):
        bar.update()
    return client.gather(futures)


def run_batch(
    notebook: str | os.PathLike,
    runs: list[ReportRun],
    out: str | os.PathLike,
    *,
    executor: str = "local",
    scheduler: str | None = None,
    workers: int | None = None,
    connect_timeout: float | None = None,
    progress: bool = False,
) -> dict[str, dict]:
    """Run every run of a batch, then write ``out/index.html``; returns the records by name.

    Parameters
    ----------
    notebook : str or os.PathLike
        The notebook.
    runs : list of ReportRun
        The runs (:func:`read_batch`).
    out : str or os.PathLike
        The batch's output folder.
    executor : {"local", "serial"}
        As :func:`nlgrd.studies.study_runner.run_study`.
    scheduler : str or None
        Address of an existing Dask scheduler.
    workers : int or None
        Worker processes of the embedded cluster.
    connect_timeout : float or None
        Seconds allowed to reach ``scheduler`` [s].
    progress : bool
        A tqdm bar on standard error: over the cells of a batch of one run, else over the
        runs.

    Returns
    -------
    dict of str to dict
        Each run's record (``error``, ``files``).

    Raises
    ------
    ModelError
        For a parameter name the notebook does not declare (naming the run), before any
        run starts.
    """
    notebook = str(Path(notebook).resolve())
    for run in runs:
        try:
            check_parameters(notebook, run.parameters)
        except ModelError as err:
            raise ModelError(f"{run.name}: {err.key}", err.message, err.file) from None
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    cells = progress and len(runs) == 1  # one run: its cells; several: the runs
    jobs = [(notebook, str(out / r.name), r.parameters, cells) for r in runs]
    bar = _runs_bar(len(jobs), progress and not cells)
    if scheduler is None and executor == "serial":
        results = []
        for job in jobs:
            results.append(run_report(*job))
            bar.update()
    else:
        from distributed import Client

        from nlgrd.studies.study_runner import connect, default_workers, local_cluster

        if scheduler is not None:
            with connect(scheduler, connect_timeout) as client:
                results = _gather(client, [client.submit(run_report, *j, pure=False) for j in jobs], bar)
        else:
            with (
                local_cluster(workers or min(len(jobs), default_workers())) as cluster,
                Client(cluster) as client,
            ):
                results = _gather(client, [client.submit(run_report, *j, pure=False) for j in jobs], bar)
    bar.close()
    records = {r.name: rec for r, rec in zip(runs, results, strict=True)}
    write_text(out / "index.html", _index(f"{Path(notebook).stem}: batch of {len(runs)}", runs, records))
    write_json(out / "batch.json", {r.name: {"parameters": r.parameters, **records[r.name]} for r in runs})
    return records
