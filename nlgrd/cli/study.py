"""``nlgrd study`` (a parametric or tolerance study from a study file, on Dask) and
``nlgrd report`` (a notebook run by papermill once per parameter set)."""

from __future__ import annotations

import ast
import sys
from pathlib import Path
from typing import Any

from nlgrd.errors import ModelError

EXECUTOR_HELP = (
    "where the tasks run: 'local' (default) an embedded Dask cluster of one worker process per core "
    "on 127.0.0.1, 'serial' this process (debugging)"
)
SCHEDULER_HELP = (
    "address of an existing Dask scheduler, e.g. tcp://10.0.0.5:8786 or tls://host:8786 (TLS with "
    "the certificates of your Dask configuration, distributed.comm.tls.*); overrides --executor"
)

TIMEOUT_HELP = "seconds to wait for --scheduler to answer (default 10)"


def _check_connection(args) -> None:
    from nlgrd.studies.study_runner import check_scheduler

    t = args.connect_timeout
    if t is not None and not (t > 0 and t < float("inf")):
        raise ModelError("--connect-timeout", f"must be a positive number of seconds, got {t}")
    check_scheduler(args.scheduler)


def _literal(text: str) -> Any:
    """A ``-p`` value: a Python literal (number, bool, None, list ...) or else the text."""
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def add_parsers(sub) -> None:
    """Add the ``study`` and ``report`` sub-commands to ``sub`` (argparse sub-parsers).

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The sub-parsers of ``nlgrd``.
    """
    st = sub.add_parser(
        "study",
        help="parametric or tolerance study: many sweeps of one model, on Dask",
        description="Runs every task (one sweep each) of a study file on Dask; writes OUT/summary.csv "
        "(one row per task), OUT/summary.parquet, OUT/grid.parquet (indexed by the axes), "
        "OUT/points.parquet (every sweep point) and OUT/tasks/ (one result per task). A rerun skips "
        "finished tasks: an interrupted study resumes. Exit status 1 when a task failed.",
    )
    st.add_argument("study", help="study file (TOML)")
    st.add_argument(
        "--out",
        default=None,
        help="output folder (default: STUDY's file name without .toml, in the current directory)",
    )
    st.add_argument("--executor", choices=["local", "serial"], default="local", help=EXECUTOR_HELP)
    st.add_argument("--scheduler", default=None, help=SCHEDULER_HELP)
    st.add_argument(
        "--workers", type=int, default=None, help="workers of the embedded cluster (default: cores)"
    )
    st.add_argument("--connect-timeout", type=float, default=None, help=TIMEOUT_HELP)
    st.add_argument("--no-progress", action="store_true", help="no progress bar")
    st.set_defaults(func=cmd_study)
    rp = sub.add_parser(
        "report",
        help="run a notebook by papermill once per parameter set (batch reports)",
        description="Executes NOTEBOOK (a file, or the name of one in notebooks/) with the parameters "
        "given by -p, or once per [[runs]] table of --batch FILE, each into OUT/<run>/ (notebook, "
        "HTML, figures, CSV files), and writes OUT/index.html. Parameter names are checked against "
        "the notebook before anything runs.",
    )
    rp.add_argument("notebook", help="notebook file, or a name of notebooks/ (e.g. 01_kubo_dynamic_factor)")
    rp.add_argument(
        "-p", nargs=2, action="append", default=[], metavar=("NAME", "VALUE"), help="a notebook parameter"
    )
    rp.add_argument("--batch", default=None, help="TOML file of [[runs]] tables (parameters, optional name)")
    rp.add_argument(
        "--out",
        default=None,
        help="output folder (default: reports/batch-<notebook> in the current directory)",
    )
    rp.add_argument("--executor", choices=["local", "serial"], default="local", help=EXECUTOR_HELP)
    rp.add_argument("--scheduler", default=None, help=SCHEDULER_HELP)
    rp.add_argument(
        "--workers", type=int, default=None, help="workers of the embedded cluster (default: cores)"
    )
    rp.add_argument("--connect-timeout", type=float, default=None, help=TIMEOUT_HELP)
    rp.set_defaults(func=cmd_report)


def cmd_study(args) -> int:
    """Run a study file (``nlgrd study``).

    Parameters
    ----------
    args : argparse.Namespace
        The options of ``nlgrd study``.

    Returns
    -------
    int
        0 when every task is done, 1 when some failed, 130 when interrupted.

    Raises
    ------
    ModelError
        For a bad study file or option.
    """
    from nlgrd.studies.study_file import load_study
    from nlgrd.studies.study_runner import run_study

    args.model = args.study  # errors without a file name are the study file's
    _check_connection(args)
    study = load_study(args.study)
    out = Path(args.out) if args.out else Path(Path(args.study).stem)  # the current directory
    if out.exists() and not out.is_dir():
        raise ModelError("--out", f"{out} exists and is not a folder")
    where = f"scheduler {args.scheduler}" if args.scheduler else f"executor {args.executor}"
    print(f"study {study.name!r}: {len(study.parameter_sets())} tasks, {where}", flush=True)
    run = run_study(
        study,
        out,
        executor=args.executor,
        scheduler=args.scheduler,
        workers=args.workers,
        progress=not args.no_progress,
        connect_timeout=args.connect_timeout,
    )
    print(
        f"tasks: {run.tasks}, computed {run.computed}, skipped (finished before) {run.skipped}, "
        f"failed {run.failed}" + (f", cancelled {run.cancelled} (rerun to resume)" if run.cancelled else "")
    )
    if run.interrupted:
        print(f"nlgrd: interrupted; finished tasks are kept in {out}/tasks: rerun to resume", file=sys.stderr)
        return 130
    print(f"wrote {out}/summary.csv, summary.parquet, grid.parquet, points.parquet")
    return 1 if run.failed or run.cancelled else 0


def cmd_report(args) -> int:
    """Run a notebook once per parameter set (``nlgrd report``).

    Parameters
    ----------
    args : argparse.Namespace
        The options of ``nlgrd report``.

    Returns
    -------
    int
        0 when every run succeeded, 1 otherwise.

    Raises
    ------
    ModelError
        For an unknown notebook or parameter, or a bad batch file.
    """
    from nlgrd.studies.batch_reports import read_batch, run_batch
    from nlgrd.studies.notebooks import NOTEBOOKS

    nb = Path(args.notebook)
    if not nb.suffix and not nb.exists():
        nb = NOTEBOOKS / f"{args.notebook}.ipynb"
    if not nb.is_file():
        raise ModelError("notebook", f"no notebook {args.notebook!r} (a file, or a name in {NOTEBOOKS})")
    args.model = str(nb)
    if args.workers is not None and args.workers < 1:
        raise ModelError("--workers", f"must be at least 1, got {args.workers}")
    _check_connection(args)
    common = {name: _literal(value) for name, value in args.p}
    if "out_dir" in common:
        raise ModelError("-p out_dir", "the batch sets out_dir; give --out")
    runs = read_batch(args.batch, common)
    out = Path(args.out) if args.out else Path("reports") / f"batch-{nb.stem}"  # the current directory
    print(f"report {nb.name}: {len(runs)} run(s) into {out}", flush=True)
    records = run_batch(
        nb,
        runs,
        out,
        executor=args.executor,
        scheduler=args.scheduler,
        workers=args.workers,
        connect_timeout=args.connect_timeout,
        progress=sys.stderr.isatty(),
    )
    for name, rec in records.items():
        print(f"  {name}: {'done' if rec['error'] is None else 'failed: ' + rec['error']}")
    print(f"wrote {out}/index.html")
    return 0 if all(r["error"] is None for r in records.values()) else 1
