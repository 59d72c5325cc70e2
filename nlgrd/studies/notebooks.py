"""The notebooks of ``notebooks/`` as reports: their parameters (checked before a run),
execution by papermill with a per-cell timeout and the kernel's log kept, the executed
notebook made deterministic (no timestamps or absolute paths) and exported to HTML.
"""

from __future__ import annotations

import ast
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from nlgrd.errors import ModelError
from nlgrd.studies.index_page import write_text

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = ROOT / "notebooks"
#: Jupyter kernel the notebooks run in.
KERNEL = "python3"
#: Longest time one notebook cell may run [s] (papermill ``execution_timeout``).
CELL_TIMEOUT = 1800


def notebook_parameters(notebook: str | os.PathLike) -> dict[str, Any]:
    """The parameters a notebook declares in its cell tagged ``parameters`` (name -> info).

    From :func:`papermill.inspect_notebook`; raises :class:`ModelError` when the notebook
    has no such cell.

    Parameters
    ----------
    notebook : str or os.PathLike
        The notebook file.

    Returns
    -------
    dict of str to Any
        Each parameter's papermill information (``default``, ``help``, ...) by name.

    Raises
    ------
    ModelError
        When the notebook has no cell tagged ``parameters``.
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

    Parameters
    ----------
    notebook : str or os.PathLike
        The notebook file.
    parameters : Mapping of str to Any
        The parameters a run would pass, by name (only the names are checked).

    Raises
    ------
    ModelError
        For the first unknown name (in sorted order), or when the notebook declares no
        parameters.
    """
    declared = notebook_parameters(notebook)
    unknown = sorted(set(parameters) - set(declared))
    if unknown:
        raise ModelError(
            f"parameters.{unknown[0]}",
            f"not a parameter of the notebook (misspelt?); it declares {', '.join(sorted(declared))}",
            str(notebook),
        )
    for name in sorted(parameters):
        kind, optional = _declared_type(declared[name])
        value = parameters[name]
        if kind is None or (optional and value is None) or _is(value, kind):
            continue
        raise ModelError(
            f"parameters.{name}",
            f"the notebook expects {kind}{' or None' if optional else ''} (its parameters cell), "
            f"got {type(value).__name__} {value!r}",
            str(notebook),
        )


_TYPE_NAMES = ("bool", "int", "float", "str", "list", "dict")


def _declared_type(info: Mapping[str, Any]) -> tuple[str | None, bool]:
    """(type name, None allowed) of a parameter: its annotation (``points: "int" = None``,
    meaning int or None), else the type of its default; (None, True) when unknown."""
    try:
        default = ast.literal_eval(info.get("default", "None"))
    except (ValueError, SyntaxError):
        return None, True
    annotation = (info.get("inferred_type_name") or "").strip("\"' ")
    if annotation in _TYPE_NAMES:
        return annotation, default is None
    kind = type(default).__name__
    if default is None or kind not in _TYPE_NAMES:
        return None, True
    return ("list" if kind == "tuple" else kind), False


def _is(value: Any, kind: str) -> bool:
    if kind in ("int", "float") and isinstance(value, bool):
        return False
    allowed = {"int": int, "float": (int, float), "bool": bool, "str": str, "list": (list, tuple)}
    return isinstance(value, allowed.get(kind, dict))


def relative_path(path: Path, start: Path) -> str:
    """``path`` relative to ``start`` when both lie in the repository, else absolute.

    Parameters
    ----------
    path : pathlib.Path
        The path written.
    start : pathlib.Path
        The folder it is taken relative to.

    Returns
    -------
    str
        The relative path (``os.path.relpath`` of the resolved paths), or the resolved
        absolute ``path`` when either lies outside the repository.
    """
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
    kernel_log: str | os.PathLike | None = None,
    progress_bar: bool = False,
) -> Path:
    """Execute ``notebook`` with papermill; returns the executed notebook in ``out_dir``.

    The parameter names are checked first (:func:`check_parameters`); ``out_dir`` is
    created and passed as the notebook's ``out_dir`` parameter, where it writes its
    figures and CSV files. The notebook runs in its own directory, so its default paths
    (``../data/...``) hold. Each cell may run ``timeout`` seconds. ``stream`` (e.g.
    ``sys.stdout``) receives the notebook's printed output as it runs: its progress.
    With ``kernel_log``, the kernel process writes its own standard error (start-up
    warnings, shutdown noise after an interrupt) to that file instead of ours. Raises
    :class:`ModelError` for a parameter the notebook does not declare, and
    ``papermill.PapermillExecutionError`` when a cell raised (the notebook executed up to
    that cell is in ``out_dir``).

    Parameters
    ----------
    notebook : str or os.PathLike
        The notebook file.
    out_dir : str or os.PathLike
        The folder the executed notebook and its outputs go to (made when missing).
    parameters : Mapping of str to Any or None
        Notebook parameters, by name; ``out_dir`` is added unless given.
    kernel_name : str
        The Jupyter kernel.
    timeout : float
        Longest time one cell may run [s].
    stream : file-like or None
        Receives the notebook's printed output as it runs; None for none.
    kernel_log : str or os.PathLike or None
        File the kernel process appends its standard error to; None to leave it on ours.
    progress_bar : bool
        Papermill's tqdm bar over the cells on standard error.

    Returns
    -------
    pathlib.Path
        The executed notebook, ``out_dir / notebook's name``.

    Raises
    ------
    ModelError
        For a parameter the notebook does not declare.
    papermill.PapermillExecutionError
        When a cell raised.
    """
    import papermill as pm

    notebook = Path(notebook).resolve()
    out = Path(out_dir)
    params = dict(parameters or {})
    params.setdefault("out_dir", relative_path(out, notebook.parent))
    check_parameters(notebook, params)
    out.mkdir(parents=True, exist_ok=True)
    target = out / notebook.name
    extra = {"kernel_manager_class": _logged_kernel_manager(Path(kernel_log))} if kernel_log else {}
    pm.execute_notebook(
        str(notebook),
        str(target),
        parameters=params,
        kernel_name=kernel_name,
        cwd=str(notebook.parent),
        progress_bar=progress_bar,
        stdout_file=stream,
        stderr_file=None,
        execution_timeout=timeout,
        **extra,
    )
    return target


def _logged_kernel_manager(log: Path):
    """A jupyter kernel manager whose kernel process writes its standard error to ``log``."""
    from jupyter_client.manager import AsyncKernelManager

    class LoggedKernelManager(AsyncKernelManager):
        async def _async_launch_kernel(self, kernel_cmd, **kw):  # the documented override point
            with open(log, "ab") as fh:
                kw.setdefault("stderr", fh)
                await super()._async_launch_kernel(kernel_cmd, **kw)

    return LoggedKernelManager


_VOLATILE = ("start_time", "end_time", "duration", "input_path", "output_path")


def make_deterministic(executed: str | os.PathLike, out_dir: str | None = None) -> None:
    """Strip run-dependent metadata from an executed notebook, in place (atomically).

    Removes papermill's timestamps, durations and absolute paths and nbclient's
    per-cell execution times, and gives the injected-parameters cell a fixed id. With
    ``out_dir``, the injected ``out_dir`` parameter is rewritten to it: the directory the
    staged outputs are published to, so that the report reruns in place.

    Parameters
    ----------
    executed : str or os.PathLike
        The executed notebook, rewritten.
    out_dir : str or None
        The ``out_dir`` parameter written in its place; None to keep it.
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
    write_text(path, nbformat.writes(nb) + "\n")


def export_html(executed: str | os.PathLike) -> Path:
    """HTML of an executed notebook (nbconvert), next to it; returns its path.

    Parameters
    ----------
    executed : str or os.PathLike
        The executed notebook.

    Returns
    -------
    pathlib.Path
        The HTML file: the notebook's path with the suffix ``.html``.
    """
    import nbformat
    from nbconvert import HTMLExporter

    path = Path(executed)
    body, _ = HTMLExporter().from_notebook_node(nbformat.read(path, as_version=4))
    target = path.with_suffix(".html")
    write_text(target, body)
    return target


def parameter_rows(notebook: Path, executed: Path) -> list[list]:
    """[name, value as run, the notebook's comment] for each declared parameter.

    Parameters
    ----------
    notebook : pathlib.Path
        The notebook as written (its declared parameters).
    executed : pathlib.Path
        The executed notebook (its injected parameters).

    Returns
    -------
    list of list of str
        One row per declared parameter: its name, the ``repr`` of the value injected (else
        the declared default) and the notebook's comment on it ("" when none).
    """
    import nbformat

    injected = nbformat.read(executed, as_version=4).metadata.get("papermill", {}).get("parameters", {})
    rows = []
    for name, info in notebook_parameters(notebook).items():
        value = repr(injected[name]) if name in injected else str(info.get("default"))
        rows.append([name, value, str(info.get("help") or "")])
    return rows


def notebook_names(selected: tuple[str, ...] | None = None) -> list[str]:
    """Names (stems) of the notebooks to run: all of ``notebooks/`` or the ``selected`` ones.

    Parameters
    ----------
    selected : tuple of str or None
        The names chosen (``--notebook``); None for all.

    Returns
    -------
    list of str
        The names, in sorted order.

    Raises
    ------
    ModelError
        When a selected name is not a notebook of ``notebooks/`` (``--notebook``).
    """
    names = sorted(p.stem for p in NOTEBOOKS.glob("*.ipynb"))
    if selected is None:
        return names
    unknown = sorted(set(selected) - set(names))
    if unknown:
        raise ModelError(
            "--notebook", f"no notebook {unknown[0]!r} in notebooks/ (there are {', '.join(names)})"
        )
    return [n for n in names if n in selected]
