"""Staging and publishing of the reports: a run builds beside ``reports/`` and replaces
it by two renames with SIGINT and SIGTERM held, carrying over the files git tracks there;
staging folders of killed runs are removed at the next start."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
import threading
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from nlgrd.studies.notebooks import (
    notebook_names,
)

#: The parts of a report build.
PARTS = ("models", "gears", "notebooks")


@dataclass(frozen=True)
class Build:
    """One run: where it publishes (``out``), where it builds (``stage``), in which mode.

    Attributes
    ----------
    out : pathlib.Path
        The folder the run publishes to (``reports/``).
    stage : pathlib.Path
        The staging folder the run builds in (:func:`staging_dir`).
    fast : bool
        Fast mode: the notebooks' quick mode and fewer Campbell speeds.
    notebooks : tuple of str or None
        The notebooks to run (``--notebook``); None for all.
    stream : file-like or None
        Receives the notebooks' printed output; None for standard output.
    parameters : Mapping of str to Any or None
        Parameters passed to every notebook (``-p NAME VALUE``); None for none.
    """

    out: Path
    stage: Path
    fast: bool = False
    notebooks: tuple[str, ...] | None = None
    stream: Any = None
    parameters: Mapping[str, Any] | None = None  # passed to every notebook (``-p NAME VALUE``)

    @property
    def mode(self) -> str:
        """The run mode: "fast" or "full"."""
        return "fast" if self.fast else "full"


class ReportError(RuntimeError):
    """A part of the report build failed."""


def staging_dir(out: Path, kind: str = "staging", pid: int | None = None) -> Path:
    """``.<out name>.<kind>-<pid>`` beside ``out`` (same file system, so renames are atomic).

    Parameters
    ----------
    out : pathlib.Path
        The folder published to.
    kind : str
        ``"staging"`` (the folder a run builds in) or ``"old"`` (the previous set while it is
        replaced).
    pid : int or None
        The process id in the name; None for this process.

    Returns
    -------
    pathlib.Path
        The folder's path (nothing is made).
    """
    return out.parent / f".{out.name}.{kind}-{os.getpid() if pid is None else pid}"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process
        pass
    return True


def clean_stale(out: Path) -> list[Path]:
    """Remove staging and old folders of runs that are no longer running; returns them.

    A run killed between its two renames leaves no ``out`` and its previous set in
    ``.<name>.old-<pid>``: that folder is renamed back to ``out``.

    Parameters
    ----------
    out : pathlib.Path
        The folder published to.

    Returns
    -------
    list of pathlib.Path
        The folders removed (not the one renamed back).
    """
    removed = []
    for kind in ("old", "staging"):
        for path in sorted(out.parent.glob(f".{out.name}.{kind}-*")):
            pid = path.name.rpartition("-")[2]
            if pid.isdigit() and int(pid) != os.getpid() and _alive(int(pid)):
                continue
            if kind == "old" and not out.exists():
                os.rename(path, out)
                print(f"restored the previous complete set of {out.name}/ from {path.name}", flush=True)
                continue
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed


def tracked_files(out: Path) -> list[str]:
    """Paths (relative to ``out``) of the files git tracks there; README.md without git.

    Parameters
    ----------
    out : pathlib.Path
        The folder published to (an existing folder).

    Returns
    -------
    list of str
        The tracked files, sorted; without git, ``["README.md"]`` when it exists, else [].
    """
    try:
        res = subprocess.run(
            ["git", "ls-files", "-z", "--", "."], cwd=out, capture_output=True, text=True, check=True
        )
        return sorted(p for p in res.stdout.split("\0") if p)
    except (OSError, subprocess.CalledProcessError):
        return ["README.md"] if (out / "README.md").is_file() else []


def _link_tree(src: Path, dst: Path) -> None:
    """Copy ``src`` to ``dst`` by hard links (files are never rewritten in place), else copies."""

    def link(a, b):
        try:
            os.link(a, b)
        except OSError:
            shutil.copy2(a, b)

    if src.is_dir():
        shutil.copytree(src, dst, copy_function=link)
    else:
        dst.parent.mkdir(parents=True, exist_ok=True)
        link(src, dst)


@contextlib.contextmanager
def signals_held(reraise: bool = True):
    """SIGINT and SIGTERM wait until the block is left, then interrupt (``reraise``) or not.

    Their handlers only note them meanwhile (a signal mask would hold them in this thread
    only: another thread, e.g. zmq's, would take them and interrupt the main thread).

    Parameters
    ----------
    reraise : bool
        Raise KeyboardInterrupt on leaving the block when a signal came meanwhile.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending: list[int] = []
    old = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(sig) not in (signal.SIG_IGN, None):
            old[sig] = signal.signal(sig, lambda signum, frame: pending.append(signum))
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
        if pending and reraise:
            raise KeyboardInterrupt(signal.Signals(pending[0]).name)


def carry_over(build: Build, parts: tuple[str, ...]) -> None:
    """Copy into the stage what this run keeps from the published set.

    Always the files git tracks there (``reports/README.md``); for a partial run
    (``--only``, ``--notebook``) also the folders of the parts it does not rebuild.

    Files are hard-linked where possible (else copied); nothing already in the stage is
    replaced.

    Parameters
    ----------
    build : Build
        The run: its published folder ``out``, its ``stage`` and its ``notebooks``.
    parts : tuple of str
        The parts this run rebuilds (of :data:`PARTS`).
    """
    out, stage = build.out, build.stage
    if not out.is_dir():
        return
    for rel in tracked_files(out):
        if (out / rel).is_file() and not (stage / rel).exists():
            _link_tree(out / rel, stage / rel)
    if set(parts) == set(PARTS) and build.notebooks is None:
        return
    rebuilt = {"models", "gears"} & set(parts)
    if "notebooks" in parts:
        rebuilt |= set(notebook_names(build.notebooks))
    for entry in sorted(out.iterdir()):
        if entry.is_dir() and not entry.name.startswith(".") and entry.name not in rebuilt:
            if not (stage / entry.name).exists():
                _link_tree(entry, stage / entry.name)


def raise_interrupt(signum, frame):
    """Signal handler: raise KeyboardInterrupt named after the signal.

    Parameters
    ----------
    signum : int
        The signal.
    frame : frame
        Unused.
    """
    raise KeyboardInterrupt(signal.Signals(signum).name)


def summary(err: BaseException) -> str:
    """One line on an error: a notebook cell's exception, else the first line of the message.

    Parameters
    ----------
    err : BaseException
        The error.

    Returns
    -------
    str
    """
    cause = err.__cause__ or err
    if hasattr(cause, "ename"):  # papermill.PapermillExecutionError
        text = f"{cause.ename}: {cause.evalue} (cell {cause.exec_count})"
    else:
        text = next((line for line in str(cause).splitlines() if line.strip()), type(cause).__name__)
    part = str(err).partition(":")[0] if isinstance(err, ReportError) else ""
    return f"{part}: {text}" if part else text


def say(text: str) -> None:
    """Print ``text`` to standard error at once.

    Parameters
    ----------
    text : str
        One line.
    """
    print(text, file=sys.stderr, flush=True)
