"""The main job: build every report into ``reports/`` (``python -m nlgrd.reports``).

For each example model in ``data/models/``: the table and shapes of its modes and its
Campbell diagram; the LSTE and tip-relief figures of the gears. Then every notebook in
``notebooks/`` (the case studies) is executed with papermill into
``reports/<notebook name>/``: the executed notebook, its HTML (nbconvert), and the PNG
figures and CSV curves the notebook writes.

Notebook runs are staged: each builds into ``reports/.<name>.partial/`` and replaces
``reports/<name>/`` only when it has run through, so a failed or interrupted run never
leaves a half-written report behind (the staging directory is kept for inspection).
Outputs are deterministic: papermill's timestamps and durations and the random id of the
injected-parameters cell are removed from the executed notebook, paths in it are
relative, and no notebook prints times.

``python -m nlgrd.reports --fast`` runs the notebooks in their quick mode;
``--only notebooks`` (or ``models``, ``gears``) builds one part.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from nlgrd.cli import main as cli_main
from nlgrd.errors import ModelError

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = ROOT / "notebooks"
#: Jupyter kernel the notebooks run in.
KERNEL = "python3"
#: Longest time one notebook cell may run [s] (papermill ``execution_timeout``).
CELL_TIMEOUT = 1800


def build_model_reports(out: Path) -> None:
    """Modes and Campbell diagram of each model in data/models/."""
    models = sorted((ROOT / "data" / "models").glob("*.toml"))
    for i, model in enumerate(models, 1):
        print(f"[{i}/{len(models)}] {model.name}: modes and Campbell diagram", flush=True)
        target = out / "models"
        for argv in (
            ["modes", str(model), "--out", str(target)],
            ["campbell", str(model), "--rpm", "0:15000:61", "--orders", "1", "--out", str(target)],
        ):
            status = cli_main(argv)
            if status:
                raise SystemExit(status)


def build_gear_reports(out: Path) -> None:
    """LSTE of the geared example and the tip-relief sweep of Kubo's gears."""
    import matplotlib

    matplotlib.use("Agg")
    import numpy as np

    from nlgrd.gear_geometry import GearGeometry
    from nlgrd.transmission_error import single_pair_deflection, tip_relief_sweep

    target = out / "gears"
    for model in sorted((ROOT / "data" / "models").glob("*.toml")):
        text = model.read_text()
        if "[[gear_pairs]]" in text:
            print(f"{model.name}: loaded static transmission error", flush=True)
            if cli_main(["lste", str(model), "--out", str(target)]):
                raise SystemExit(2)
    print("Kubo's gears: tip-relief sweep", flush=True)
    geo = GearGeometry(25, 25, 4e-3, 15e-3)
    load = 2295.0
    deflection = single_pair_deflection(geo, load)
    sweep = tip_relief_sweep(geo, load, np.linspace(0, 2 * deflection, 41))
    ax = sweep.plot(design_deflection=deflection)
    ax.figure.tight_layout()
    ax.figure.savefig(target / "kubo_tip_relief_sweep.png", dpi=100)
    sweep.to_frame().to_csv(target / "kubo_tip_relief_sweep.csv", index=False)


# --------------------------------------------------------------------------------------
# Notebooks
# --------------------------------------------------------------------------------------


def notebook_parameters(notebook: str | os.PathLike) -> dict[str, Any]:
    """The parameters a notebook declares in its cell tagged ``parameters`` (name -> info).

    From :func:`papermill.inspect_notebook`; raises :class:`ModelError` when the notebook
    has no such cell.
    """
    import papermill as pm

    declared = pm.inspect_notebook(str(notebook))
    if not declared:
        raise ModelError("parameters", "the notebook has no cell tagged 'parameters'", str(notebook))
    return declared


def check_parameters(notebook: str | os.PathLike, parameters: Mapping[str, Any]) -> None:
    """Raise :class:`ModelError` if any name in ``parameters`` is not a notebook parameter.

    papermill itself only warns and then runs the notebook with its defaults, so a misspelt
    parameter would silently be ignored.
    """
    declared = notebook_parameters(notebook)
    unknown = sorted(set(parameters) - set(declared))
    if unknown:
        raise ModelError(
            f"parameters.{unknown[0]}",
            f"not a parameter of the notebook (misspelt?); it declares {', '.join(sorted(declared))}",
            str(notebook),
        )


def _relative(path: Path, start: Path) -> str:
    """``path`` relative to ``start`` when both lie in the repository, else absolute."""
    path, start = path.resolve(), start.resolve()
    if path.is_relative_to(ROOT) and start.is_relative_to(ROOT):
        return os.path.relpath(path, start)
    return str(path)


def run_notebook(
    notebook: str | os.PathLike,
    out_dir: str | os.PathLike,
    parameters: Mapping[str, Any] | None = None,
    *,
    kernel_name: str = KERNEL,
    timeout: float = CELL_TIMEOUT,
    stream=None,
) -> Path:
    """Execute ``notebook`` with papermill; returns the executed notebook in ``out_dir``.

    The parameter names are checked first (:func:`check_parameters`); ``out_dir`` is
    created and passed as the notebook's ``out_dir`` parameter, where it writes its
    figures and CSV files. The notebook runs in its own directory, so its default paths
    (``../data/...``) hold. Each cell may run ``timeout`` seconds. ``stream`` (e.g.
    ``sys.stdout``) receives the notebook's printed output as it runs: its progress.

    Raises
    ------
    ModelError
        A parameter the notebook does not declare.
    papermill.PapermillExecutionError
        A cell raised; the executed notebook up to that cell is in ``out_dir``.
    """
    import papermill as pm

    notebook = Path(notebook).resolve()
    out = Path(out_dir)
    params = dict(parameters or {})
    params.setdefault("out_dir", _relative(out, notebook.parent))
    check_parameters(notebook, params)
    out.mkdir(parents=True, exist_ok=True)
    target = out / notebook.name
    pm.execute_notebook(
        str(notebook),
        str(target),
        parameters=params,
        kernel_name=kernel_name,
        cwd=str(notebook.parent),
        progress_bar=False,
        stdout_file=stream,
        stderr_file=None,
        execution_timeout=timeout,
    )
    return target


_VOLATILE = ("start_time", "end_time", "duration", "input_path", "output_path")


def make_deterministic(executed: str | os.PathLike, out_dir: str | None = None) -> None:
    """Strip run-dependent metadata from an executed notebook, in place (atomically).

    Removes papermill's timestamps, durations and absolute paths and nbclient's
    per-cell execution times, and gives the injected-parameters cell a fixed id. With
    ``out_dir``, the injected ``out_dir`` parameter is rewritten to it: the directory the
    staged outputs were renamed to, so that the report reruns in place.
    """
    import nbformat

    path = Path(executed)
    nb = nbformat.read(path, as_version=4)
    meta = nb.metadata.get("papermill", {})
    for key in _VOLATILE:
        meta.pop(key, None)
    staged = meta.get("parameters", {}).get("out_dir")
    if out_dir is not None and staged is not None:
        meta["parameters"]["out_dir"] = out_dir
    for cell in nb.cells:
        cell.metadata.pop("execution", None)
        for key in _VOLATILE:
            cell.metadata.get("papermill", {}).pop(key, None)
        if "injected-parameters" in cell.metadata.get("tags", []):
            cell["id"] = "injected-parameters"
            if out_dir is not None and staged is not None:
                cell.source = cell.source.replace(repr(staged), repr(out_dir)).replace(
                    f'"{staged}"', f'"{out_dir}"'
                )
    _write_text(path, nbformat.writes(nb) + "\n")


def export_html(executed: str | os.PathLike) -> Path:
    """HTML of an executed notebook (nbconvert), next to it; returns its path."""
    import nbformat
    from nbconvert import HTMLExporter

    path = Path(executed)
    body, _ = HTMLExporter().from_notebook_node(nbformat.read(path, as_version=4))
    target = path.with_suffix(".html")
    _write_text(target, body)
    return target


def _write_text(path: Path, text: str) -> None:
    """Write ``text`` to a temporary file beside ``path``, then rename it over ``path``."""
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


def build_notebook_reports(out: Path, fast: bool = False, stream=None) -> list[Path]:
    """Run every notebook of ``notebooks/`` into ``out/<name>/``; returns the directories.

    The notebooks' printed progress goes to ``stream`` (default: standard output).
    """
    stream = stream or sys.stdout
    notebooks = sorted(NOTEBOOKS.glob("*.ipynb"))
    done = []
    for i, nb in enumerate(notebooks, 1):
        name = nb.stem
        final, stage = out / name, out / f".{name}.partial"
        mode = "fast" if fast else "full"
        print(f"[{i}/{len(notebooks)}] notebooks/{nb.name} -> reports/{name}/ ({mode})", flush=True)
        t0 = time.perf_counter()
        if stage.exists():
            shutil.rmtree(stage)
        try:
            executed = run_notebook(nb, stage, {"fast": fast}, stream=stream)
        except Exception:
            print(f"notebooks/{nb.name} failed; what it ran is in {stage}", file=sys.stderr, flush=True)
            raise
        make_deterministic(executed, out_dir=_relative(final, NOTEBOOKS))
        export_html(executed)
        old = out / f".{name}.old"
        if old.exists():
            shutil.rmtree(old)
        if final.exists():
            final.rename(old)
        stage.rename(final)
        if old.exists():
            shutil.rmtree(old)
        files = sorted(p.name for p in final.iterdir())
        print(
            f"    {len(files)} files ({sum(f.endswith('.png') for f in files)} PNG, "
            f"{sum(f.endswith('.csv') for f in files)} CSV) in {time.perf_counter() - t0:.0f} s",
            flush=True,
        )
        done.append(final)
    return done


def main(argv: list[str] | None = None) -> int:
    """Build all reports; returns the exit status."""
    parser = argparse.ArgumentParser(prog="python -m nlgrd.reports", description=__doc__.splitlines()[0])
    parser.add_argument("--fast", action="store_true", help="run the notebooks in their quick mode")
    parser.add_argument(
        "--only", choices=("models", "gears", "notebooks"), action="append", help="build only these parts"
    )
    args = parser.parse_args(argv)
    parts = args.only or ["models", "gears", "notebooks"]
    out = ROOT / "reports"
    out.mkdir(exist_ok=True)
    t0 = time.perf_counter()
    if "models" in parts:
        build_model_reports(out)
    if "gears" in parts:
        build_gear_reports(out)
    if "notebooks" in parts:
        build_notebook_reports(out, fast=args.fast)
    print(f"reports written to {out} in {time.perf_counter() - t0:.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
