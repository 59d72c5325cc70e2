"""``index.html`` of a report folder: every figure, what it compares, the settings, the version.

No matplotlib here: this module only reads and writes files (and is imported by
:mod:`nlgrd.studies.reports` at start-up, which should stay quick).

Reads what the report parts leave in each top-level folder: PNG figures, their captions
in ``figures.json`` (:func:`nlgrd.plotting.save_figure`), and ``settings.json``
(:func:`nlgrd.studies.index_page.record_settings`: the run mode, the settings a part used and, for
notebooks, their parameters as run). The page holds no time and no absolute path, so a
rerun of the same code writes the same bytes; it names the git commit instead.
"""

from __future__ import annotations

import html
import json
import numbers
import os
import platform
import subprocess
from collections.abc import Mapping
from importlib import metadata
from pathlib import Path
from typing import Any
from urllib.parse import quote

INDEX = "index.html"
FIGURES_FILE, SETTINGS_FILE = "figures.json", "settings.json"
NO_CAPTION = "(no description recorded)"
_TITLES = {
    "models": "Linear models: modes and Campbell diagrams (data/models/)",
    "gears": "Gears: loaded static transmission error and tip relief",
}
_CONVENTIONS = (
    "How to read the sweep figures: up sweeps ▲ and down sweeps ▼ in different colours; stable "
    "points filled and joined by solid lines, unstable points open and joined by dashed lines, "
    "points whose stability was not computed half-filled (the legend says so); points without a "
    "converged solution are crosses on the bottom edge, counted in the legend; values beyond the "
    "scale are carets on the edge, counted with their extreme value in the legend. Continuation "
    "curves have no marker per point: stable parts solid, unstable dashed, stability not computed "
    "dotted. Long legends sit to the right of the axes. Campbell "
    "diagrams join a mode's points only where its whirl and kind stay the same and no other mode "
    "comes near (no lines across veerings or crossings)."
)
#: What the index says about measured curves (none is shipped) and how to add one.
MEASURED = (
    "Measured curves: none is shipped. The figures the paper compared with measurements "
    "(Kubo's rig, Fig. 5 of Maliha et al. 2004, in 01_kubo_dynamic_factor; Kahraman & "
    "Blankenship's rig, Fig. 8, in 02_kahraman_blankenship_dte) say so on the figure. To add "
    "one: digitise the curve into a CSV file in data/experimental/ with the header keys and "
    "columns of data/experimental/README.md (case kubo or kahraman_blankenship); check it with "
    "nlgrd.studies.experimental.load_experimental, which names the file, key, column and line of "
    "every problem; then rebuild the notebook reports. The notebook overlays every data set of "
    "its case on the figure and writes the scores to experimental_scores.csv."
)
_STYLE = """body{font-family:sans-serif;max-width:1100px;margin:1em auto;padding:0 1em;line-height:1.4}
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:2px 6px;text-align:left;
vertical-align:top}figure{margin:1em 0;border-top:1px solid #eee;padding-top:.5em}img{max-width:100%}
figcaption{font-size:.95em}code{font-size:.95em}"""


def _esc(value) -> str:
    return html.escape(str(value), quote=True)


def _href(rel: str) -> str:
    return quote(rel, safe="/")


def _fmt(value) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def read_json(path: Path) -> dict:
    """The JSON object in ``path`` ({} when missing or unreadable).

    Parameters
    ----------
    path : pathlib.Path
        The JSON file (UTF-8).

    Returns
    -------
    dict
        The parsed object; ``{}`` when the file is missing, unreadable or not JSON.
    """
    try:
        return json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}


def write_text(path: Path, text: str) -> None:
    """Write ``text`` to a temporary file beside ``path``, then rename it over ``path``.

    Parameters
    ----------
    path : pathlib.Path
        The file written (its folder must exist).
    text : str
        The text, written as UTF-8.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


def write_json(path: Path, data: dict) -> None:
    """``data`` as indented JSON (keys in their order), written atomically.

    Parameters
    ----------
    path : pathlib.Path
        The file written (:func:`write_text`).
    data : dict
        The object written; non-ASCII text is kept as it is.
    """
    write_text(path, json.dumps(data, indent=1, ensure_ascii=False) + "\n")


def _plain(value: Any) -> Any:
    """A JSON value for a setting: numbers as Python numbers, anything else as text."""
    if isinstance(value, bool | str) or value is None:
        return value
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value)
    return str(value)


def record_settings(out_dir: str | os.PathLike, settings: Mapping[str, Any], key: str = "settings") -> None:
    """Record the settings a report part used in ``out_dir/settings.json`` (shown in the index).

    ``settings`` maps a label (e.g. "harmonics H") to its value; labels already recorded
    are replaced, new ones appended in order. Notebooks call this (as
    ``nlgrd.studies.index_page.record_settings``) with the values they actually use, after their
    defaults are resolved. ``key="run"`` holds the run mode.

    Parameters
    ----------
    out_dir : str or os.PathLike
        The report part's folder (made when missing).
    settings : Mapping of str to Any
        Label -> value; numbers are stored as numbers, booleans, strings and None as they
        are, anything else as its text.
    key : str
        The entry of ``settings.json`` recorded: ``"settings"`` (the settings table of the
        index) or ``"run"`` (the run mode).
    """
    path = Path(out_dir) / SETTINGS_FILE
    path.parent.mkdir(parents=True, exist_ok=True)
    data = read_json(path)
    rows = dict((k, v) for k, v in data.get(key, []))
    rows.update({str(k): _plain(v) for k, v in settings.items()})
    data[key] = [[k, v] for k, v in rows.items()]
    write_json(path, data)


def _git(root: Path, *args: str) -> str | None:
    try:
        res = subprocess.run(["git", *args], cwd=root, capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        return None
    return res.stdout.strip()


def version_rows(root: Path) -> list[tuple[str, str]]:
    """(label, text) rows: the library version, the git commit, Python and key packages.

    Parameters
    ----------
    root : pathlib.Path
        The repository the git commit is read from (no row when git or the repository is missing).

    Returns
    -------
    list of tuple of str
        (label, text) rows: nlgrd, git commit, Python, then numpy, scipy, pandas, matplotlib
        and papermill where installed.
    """
    import nlgrd

    version = nlgrd.__version__
    try:
        installed = metadata.version("nlgrd")
    except metadata.PackageNotFoundError:
        installed = None
    if installed and installed != version:
        version += f" (installed metadata: {installed})"
    rows = [("nlgrd", version)]
    commit = _git(root, "rev-parse", "HEAD")
    if commit:
        dirty = _git(root, "status", "--porcelain", "--untracked-files=no")
        rows.append(("git commit", commit + (" with uncommitted changes to tracked files" if dirty else "")))
    rows.append(("Python", platform.python_version()))
    for pkg in ("numpy", "scipy", "pandas", "matplotlib", "papermill"):
        try:
            rows.append((pkg, metadata.version(pkg)))
        except metadata.PackageNotFoundError:
            pass
    return rows


def _title(folder: Path) -> str:
    if folder.name in _TITLES:
        return _TITLES[folder.name]
    nb = folder / f"{folder.name}.ipynb"
    if nb.is_file():
        cells = read_json(nb).get("cells", [])
        for cell in cells:
            if cell.get("cell_type") == "markdown":
                src = "".join(cell.get("source", []))
                for line in src.splitlines():
                    if line.startswith("# "):
                        return f"{folder.name}: {line[2:].strip()}"
                break
    return folder.name


def _table(rows, head=None) -> list[str]:
    out = ["<table>"]
    if head:
        out.append("<tr>" + "".join(f"<th>{_esc(h)}</th>" for h in head) + "</tr>")
    for row in rows:
        out.append("<tr>" + "".join(f"<td>{_esc(_fmt(c))}</td>" for c in row) + "</tr>")
    out.append("</table>")
    return out


def _section(stage: Path, folder: Path) -> list[str]:
    rel = folder.relative_to(stage).as_posix()
    out = [f'<h2 id="{_esc(rel)}">{_esc(_title(folder))}</h2>']
    settings = read_json(folder / SETTINGS_FILE)
    run = dict((k, v) for k, v in settings.get("run", []))
    out.append(f"<p>Folder <code>{_esc(rel)}/</code>, built in {_esc(run.get('mode', 'unknown'))} mode.</p>")
    if settings.get("settings"):
        out.append("<h3>Settings</h3>")
        out += _table(settings["settings"], ("setting", "value"))
    if settings.get("parameters"):
        out.append("<h3>Notebook parameters as run</h3>")
        out += _table(settings["parameters"], ("parameter", "value", "the notebook's note"))
    files = sorted(p for p in folder.rglob("*") if p.is_file() and not p.name.startswith("."))
    docs = [p for p in files if p.suffix in (".ipynb", ".html")]
    tables = [p for p in files if p.suffix == ".csv"]
    for label, group in (("Notebook", docs), ("Tables (CSV)", tables)):
        if group:
            links = ", ".join(
                f'<a href="{_href(p.relative_to(stage).as_posix())}">'
                f"{_esc(p.relative_to(folder).as_posix())}</a>"
                for p in group
            )
            out.append(f"<p>{label}: {links}</p>")
    captions = read_json(folder / FIGURES_FILE)
    for png in (p for p in files if p.suffix == ".png"):
        src = png.relative_to(stage).as_posix()
        text = captions.get(png.name, NO_CAPTION)
        out += [
            f'<figure id="{_esc(src)}">',
            f'<a href="{_href(src)}"><img src="{_href(src)}" alt="{_esc(text)}" loading="lazy"></a>',
            f'<figcaption><a href="{_href(src)}"><code>{_esc(src)}</code></a>: {_esc(text)}</figcaption>',
            "</figure>",
        ]
    return out


def _order(folder: Path) -> tuple[int, str]:
    return (list(_TITLES).index(folder.name) if folder.name in _TITLES else len(_TITLES), folder.name)


def index_html(stage: Path, *, fast: bool, parts, root: Path) -> str:
    """The text of ``index.html`` for the report folder ``stage``.

    Parameters
    ----------
    stage : pathlib.Path
        The report folder; each of its top-level folders (not hidden) is one section.
    fast : bool
        Whether this run was in fast mode (stated on the page).
    parts : iterable of str
        The report parts rebuilt by this run (stated on the page).
    root : pathlib.Path
        The repository, for the version rows (:func:`version_rows`).

    Returns
    -------
    str
        The HTML text; it holds no time and no absolute path.
    """
    stage = Path(stage)
    folders = sorted((p for p in stage.iterdir() if p.is_dir() and not p.name.startswith(".")), key=_order)
    mode = "fast" if fast else "full"
    out = [
        "<!DOCTYPE html>",
        '<html lang="en">',
        '<head><meta charset="utf-8"><title>nlgrd reports</title>',
        f"<style>{_STYLE}</style></head>",
        "<body>",
        "<h1>nlgrd reports</h1>",
        "<p>This run: <code>python -m nlgrd.studies.reports"
        f"{' --fast' if fast else ''}</code> ({mode} mode), "
        f"parts rebuilt: {_esc(', '.join(parts))}. Each section states the mode it was built in.</p>",
        f"<p>{_esc(_CONVENTIONS)}</p>",
        f"<p>{_esc(MEASURED)}</p>",
        "<h2>Version</h2>",
    ]
    out += _table(version_rows(root))
    out.append("<h2>Contents</h2><ul>")
    for folder in folders:
        n = sum(1 for _ in folder.rglob("*.png"))
        out.append(f'<li><a href="#{_esc(folder.name)}">{_esc(_title(folder))}</a> ({n} figures)</li>')
    out.append("</ul>")
    for folder in folders:
        out += _section(stage, folder)
    out += ["</body>", "</html>", ""]
    return "\n".join(out)


def write_index(stage: Path, *, fast: bool, parts, root: Path) -> Path:
    """Write ``stage/index.html`` (:func:`index_html`); returns its path.

    Parameters
    ----------
    stage : pathlib.Path
        The report folder.
    fast : bool
        Whether this run was in fast mode.
    parts : iterable of str
        The report parts rebuilt by this run.
    root : pathlib.Path
        The repository, for the version rows.

    Returns
    -------
    pathlib.Path
        The path of the written ``index.html``.
    """
    path = Path(stage) / INDEX
    write_text(path, index_html(stage, fast=fast, parts=parts, root=root))
    return path
