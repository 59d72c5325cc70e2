"""The main job: build every report into ``reports/`` (``python -m nlgrd.studies.reports``).

Parts: the modes and Campbell diagram of each model in ``data/models/``; the LSTE and
tip-relief figures of the gears; every notebook of ``notebooks/`` executed by papermill
into ``reports/<name>/`` (the notebook, its HTML, its PNG figures and CSV curves); and
``reports/index.html`` (every figure, what it compares, the settings, the version).

Complete or clearly not: a run builds into ``.reports.staging-<pid>`` beside
``reports/`` and replaces it only when every part succeeded, by two renames with SIGINT
and SIGTERM held until both are done, carrying over the files git tracks there. An
interrupted or failed run leaves the previous complete set (or nothing) and says so in
one line; staging folders of killed runs are removed at the next start. CSV files and
the index are byte-identical on a rerun (no times; the index names the git commit);
papermill's timestamps and absolute paths are removed from the executed notebooks.

Options: ``--fast`` (the notebooks' quick mode, fewer Campbell speeds), ``--only PART``
and ``--notebook NAME`` (rebuild some, keep the rest), ``-p NAME VALUE`` (a notebook
parameter, checked against every notebook run before anything is built), ``--out DIR``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import sys
import threading
import time
import traceback
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from nlgrd.errors import ModelError
from nlgrd.studies.index_page import SETTINGS_FILE, read_json, record_settings, write_json
from nlgrd.studies.notebooks import (
    NOTEBOOKS,
    check_parameters,
    export_html,
    make_deterministic,
    notebook_names,
    parameter_rows,
    relative_path,
    run_notebook,
)
from nlgrd.studies.publishing import (
    PARTS,
    Build,
    ReportError,
    carry_over,
    clean_stale,
    raise_interrupt,
    say,
    signals_held,
    staging_dir,
    summary,
)

__all__ = ["build_reports", "main"]

ROOT = Path(__file__).resolve().parents[2]
#: Where ``make reports`` publishes.
REPORTS = ROOT / "reports"
#: Campbell speed range [rpm] START:STOP:COUNT, full and fast mode.
CAMPBELL_RPM = {False: "0:15000:61", True: "0:15000:16"}
#: Exit status of an interrupted run (128 + SIGINT).
INTERRUPTED = 130


# --------------------------------------------------------------------------------------
# Parts
# --------------------------------------------------------------------------------------


def _captions(folder: Path, captions: Mapping[str, str]) -> None:
    from nlgrd.plotting import record_caption

    for name, text in captions.items():
        record_caption(folder / name, text)


def _wrote(build: Build, *paths: Path) -> None:
    """Name the files written where they will be once published (``build.out``), not in
    the stage, which is gone when the run ends."""
    shown = [str(build.out / p.relative_to(build.stage)) for p in paths]
    print(f"wrote {', '.join(shown[:-1])} and {shown[-1]}", flush=True)


def build_model_reports(build: Build) -> None:
    """Modes and Campbell diagram of each model in data/models/.

    Parameters
    ----------
    build : Build
        The run: its stage (the part writes into ``build.stage / "models"``) and mode.

    Raises
    ------
    ModelError
        When a model file cannot be read.
    """
    from nlgrd.analyses import campbell, load, modes
    from nlgrd.io.analysis_files import write_campbell, write_modes
    from nlgrd.io.command_line import parse_orders, parse_range

    models = sorted((ROOT / "data" / "models").glob("*.toml"))
    target = build.stage / "models"
    rpm = CAMPBELL_RPM[build.fast]
    captions = {}
    for i, model in enumerate(models, 1):
        print(f"[{i}/{len(models)}] {model.name}: modes and Campbell diagram", flush=True)
        system = load(model)
        _wrote(build, *write_modes(modes(system, 0.0, n_modes=12), target, model.stem))
        diagram = campbell(system, parse_range(rpm), n_modes=10, orders=parse_orders("1"))
        _wrote(build, *write_campbell(diagram, target, model.stem))
        captions[f"{model.stem}_modes.png"] = (
            f"The first six modes of {model.name} at standstill: amplitude along each shaft of each "
            "DOF family (lateral, torsional, axial) holding at least 5 % of the mode's kinetic "
            "energy, with frequency, damping ratio (stability), kind and whirl in each title."
        )
        captions[f"{model.stem}_campbell.png"] = (
            f"Damped natural frequencies of {model.name} against speed, coloured by whirl "
            "(forward, backward, planar, no lateral motion), against the 1x order line, with the "
            "critical speeds where they cross."
        )
    _captions(target, captions)
    start, stop, count = rpm.split(":")
    record_settings(target, {"mode": build.mode}, key="run")
    record_settings(
        target,
        {
            "models": ", ".join(m.name for m in models) + " (data/models/)",
            "modes": "damped complex modes with gyroscopics at 0 rpm; 12 listed, 6 shapes drawn",
            "Campbell diagram": f"{start}-{stop} rpm, {count} speeds, 10 modes, excitation order 1x",
            "damping": "as in each model file (bearings, couplings, internal damping)",
        },
    )


def build_gear_reports(build: Build) -> None:
    """LSTE of the geared example and the tip-relief sweep of Kubo's gears.

    Parameters
    ----------
    build : Build
        The run: its stage (the part writes into ``build.stage / "gears"``) and mode.

    Raises
    ------
    ModelError
        When a model file cannot be read.
    """
    import numpy as np

    from nlgrd.analyses import load
    from nlgrd.gear.geometry import GearGeometry
    from nlgrd.gear.transmission_error import single_pair_deflection, tip_relief_sweep
    from nlgrd.io.analysis_files import write_lste
    from nlgrd.plotting import headless, save_figure

    headless()
    target = build.stage / "gears"
    target.mkdir(parents=True, exist_ok=True)
    captions, geared = {}, []
    for model in sorted((ROOT / "data" / "models").glob("*.toml")):
        if "[[gear_pairs]]" in model.read_text():
            print(f"{model.name}: loaded static transmission error", flush=True)
            files = write_lste(load(model).gear_pairs[0], target, model.stem)
            _wrote(build, files.csv, files.png)
            geared.append(model.name)
            captions[f"{model.stem}_lste.png"] = (
                f"The gear pair of {model.name} at its static load over two mesh cycles: loaded static "
                "transmission error against the unloaded one, mesh stiffness k(t) against its mean, "
                "and the load of each tooth pair along the path of contact."
            )
    print("Kubo's gears: tip-relief sweep", flush=True)
    teeth, module, face, load, n = 25, 4e-3, 15e-3, 2295.0, 41
    geo = GearGeometry(teeth, teeth, module, face)
    deflection = single_pair_deflection(geo, load)
    sweep = tip_relief_sweep(geo, load, np.linspace(0, 2 * deflection, n))
    ax = sweep.plot(design_deflection=deflection)
    save_figure(
        ax.figure,
        target / "kubo_tip_relief_sweep.png",
        "Peak-to-peak loaded static transmission error of Kubo's gears against the amount of "
        "linear tip relief, with its minimum and the single-pair deflection W / k_pair.",
        dpi=100,
    )
    ax.figure.clf()
    sweep.to_frame().to_csv(target / "kubo_tip_relief_sweep.csv", index=False)
    _captions(target, captions)
    record_settings(target, {"mode": build.mode}, key="run")
    record_settings(
        target,
        {
            "LSTE": f"gear pair 0 of {', '.join(geared) or 'no model'} (data/models/) at its static load",
            "tip-relief sweep": (
                f"Kubo's gears: {teeth}/{teeth} teeth, module {module * 1e3:g} mm, face width "
                f"{face * 1e3:g} mm, W = {load:g} N; {n} amounts from 0 to 2 x the single-pair "
                f"deflection ({deflection * 1e6:.2f} µm)"
            ),
        },
    )


def build_notebook_reports(build: Build) -> list[Path]:
    """Run the notebooks into ``stage/<name>/``; returns the directories.

    The notebooks' printed progress goes to ``build.stream`` (default: standard output).

    Parameters
    ----------
    build : Build
        The run: its stage, mode, notebooks, stream and notebook parameters.

    Returns
    -------
    list of pathlib.Path
        The notebooks' folders in the stage, in the order run.

    Raises
    ------
    ModelError
        For an unknown notebook name or parameter.
    papermill.PapermillExecutionError
        When a notebook cell raised.
    """
    stream = build.stream or sys.stdout
    names = notebook_names(build.notebooks)
    done = []
    for i, name in enumerate(names, 1):
        nb = NOTEBOOKS / f"{name}.ipynb"
        target = build.stage / name
        print(
            f"[{i}/{len(names)}] notebooks/{nb.name} -> {build.out.name}/{name}/ ({build.mode})", flush=True
        )
        t0 = time.perf_counter()
        log = build.stage / f".{name}.kernel.log"
        params = {"fast": build.fast, **(build.parameters or {})}
        executed = run_notebook(nb, target, params, stream=stream, kernel_log=log)
        log.unlink(missing_ok=True)
        make_deterministic(executed, out_dir=relative_path(build.out / name, NOTEBOOKS))
        export_html(executed)
        record_settings(target, {"mode": build.mode}, key="run")
        data = read_json(target / SETTINGS_FILE)
        data["parameters"] = parameter_rows(nb, executed)
        write_json(target / SETTINGS_FILE, data)
        files = sorted(p.name for p in target.iterdir())
        print(
            f"    {len(files)} files ({sum(f.endswith('.png') for f in files)} PNG, "
            f"{sum(f.endswith('.csv') for f in files)} CSV) in {time.perf_counter() - t0:.0f} s",
            flush=True,
        )
        done.append(target)
    return done


BUILDERS = {"models": build_model_reports, "gears": build_gear_reports, "notebooks": build_notebook_reports}


def build_reports(
    out: Path = REPORTS,
    parts: tuple[str, ...] = PARTS,
    fast: bool = False,
    notebooks: tuple[str, ...] | None = None,
    stream=None,
    parameters: Mapping[str, Any] | None = None,
) -> int:
    """Build ``parts`` into a stage and publish it to ``out``; returns the exit status.

    0 when published; 1 when a part failed and 130 when interrupted (SIGINT or SIGTERM),
    both leaving ``out`` as it was, with one line on standard error saying what it holds.
    Publishing renames ``out`` to ``.<name>.old-<pid>`` and the stage to ``out`` with the
    signals held, so an interrupt lands before both renames or after both.

    Parameters
    ----------
    out : pathlib.Path
        The folder published to.
    parts : tuple of str
        The parts rebuilt (of :data:`PARTS`); the others are carried over from ``out``.
    fast : bool
        Fast mode: the notebooks' quick mode and fewer Campbell speeds.
    notebooks : tuple of str or None
        The notebooks to run; None for all.
    stream : file-like or None
        Receives the notebooks' printed output; None for standard output.
    parameters : Mapping of str to Any or None
        Parameters passed to every notebook; None for none.

    Returns
    -------
    int
        The exit status: 0 published, 1 a part failed, 130 interrupted.
    """
    out = Path(out).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    clean_stale(out)
    build = Build(out, staging_dir(out), fast, notebooks, stream, parameters)
    name = out.name + "/"
    previous = (
        f"{name} keeps the previous complete set"
        if (out / "index.html").is_file()
        else f"{name} has no complete set (nothing was published)"
    )
    published = False
    main_thread = threading.current_thread() is threading.main_thread()
    old_term = signal.signal(signal.SIGTERM, raise_interrupt) if main_thread else None
    t0 = time.perf_counter()
    try:
        build.stage.mkdir()
        for part in PARTS:
            if part in parts:
                try:
                    BUILDERS[part](build)
                except (Exception, SystemExit) as err:
                    raise ReportError(f"{part}: {err}") from err
        carry_over(build, parts)
        from nlgrd.studies.index_page import write_index

        write_index(build.stage, fast=fast, parts=parts, root=ROOT)
        old = staging_dir(out, "old")
        with signals_held():  # the swap: two renames, not interruptible between them
            if out.exists():
                os.rename(out, old)
            os.rename(build.stage, out)
            published = True
        shutil.rmtree(old, ignore_errors=True)
        print(f"reports written to {out} in {time.perf_counter() - t0:.1f} s", flush=True)
        return 0
    except KeyboardInterrupt:
        with signals_held(reraise=False):  # a second Ctrl-C does not cut the clean-up short
            shutil.rmtree(build.stage, ignore_errors=True)
            if published:
                say(f"interrupted after publishing: {name} holds this run's complete set")
            else:
                say(f"interrupted: {previous}; this run's partial output was removed")
        return INTERRUPTED
    except Exception as err:
        traceback.print_exc()
        say(
            f"failed: {summary(err)}; {previous}; this run's output is in {build.stage} "
            "(removed at the next run)"
        )
        return 1
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, old_term)


def _literal(text: str) -> Any:
    """A ``-p`` value: a Python literal (number, bool, None, list ...) or else the text."""
    import ast

    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def main(argv: list[str] | None = None) -> int:
    """Build all reports; returns the exit status.

    Parameters
    ----------
    argv : list of str or None
        The command-line arguments (``--fast``, ``--only``, ``--notebook``, ``--out``,
        ``-p NAME VALUE``); None for ``sys.argv[1:]``.

    Returns
    -------
    int
        The exit status: that of :func:`build_reports`, 2 for an unknown notebook name or
        parameter, 130 when interrupted before the build started.
    """
    parser = argparse.ArgumentParser(
        prog="python -m nlgrd.studies.reports", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--fast", action="store_true", help="run the notebooks in their quick mode")
    parser.add_argument("--only", choices=PARTS, action="append", help="build only these parts")
    parser.add_argument("--notebook", action="append", help="run only this notebook (name without .ipynb)")
    parser.add_argument("--out", default=str(REPORTS), help="folder to publish to (default: reports/)")
    parser.add_argument(
        "-p",
        "--parameter",
        nargs=2,
        action="append",
        metavar=("NAME", "VALUE"),
        help="a notebook parameter for every notebook run (VALUE read as a Python literal, else text)",
    )
    args = parser.parse_args(argv)
    parts = tuple(args.only or PARTS)
    try:
        selected = tuple(args.notebook) if args.notebook else None
        names = notebook_names(selected)  # fail early on a misspelt name
        params = {name: _literal(value) for name, value in args.parameter or ()}
        if params and "notebooks" in parts:
            for name in names:  # fail early on a misspelt parameter
                check_parameters(NOTEBOOKS / f"{name}.ipynb", params)
        return build_reports(Path(args.out), parts, args.fast, selected, parameters=params)
    except KeyboardInterrupt:  # before the build started: nothing was touched
        say(f"interrupted before the build started: {Path(args.out).name}/ is unchanged")
        return INTERRUPTED
    except ModelError as err:
        say(f"python -m nlgrd.studies.reports: error: {err}")
        return 2


if __name__ == "__main__":
    status = main()
    if status == INTERRUPTED:  # its line is the last word: no shutdown noise of the abandoned kernel client
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(os.open(os.devnull, os.O_WRONLY), 2)
    sys.exit(status)
