"""Figure files: drawing without a display, saving a figure atomically with its caption
recorded in ``figures.json`` beside it (what the report index shows)."""

from __future__ import annotations

import json
import os
from pathlib import Path


def headless() -> None:
    """Draw without a display (the Agg backend): for scripts and report builds."""
    import matplotlib

    matplotlib.use("Agg")


FIGURES_FILE = "figures.json"


def _write_atomic(path: Path, data: bytes) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def record_caption(path: str | os.PathLike, caption: str) -> None:
    """Record ``caption`` for the figure file ``path`` in ``figures.json`` beside it.

    The file maps figure names to one-sentence descriptions (what the figure compares);
    the report index (:mod:`nlgrd.studies.reports`) shows them.

    Parameters
    ----------
    path : str or os.PathLike
        The figure file; its name is the key in ``figures.json``.
    caption : str
        One sentence; runs of whitespace are collapsed to single spaces.
    """
    path = Path(path)
    index = path.parent / FIGURES_FILE
    captions = json.loads(index.read_text(encoding="utf-8")) if index.exists() else {}
    captions[path.name] = " ".join(caption.split())
    text = json.dumps(dict(sorted(captions.items())), indent=1, ensure_ascii=False) + "\n"
    _write_atomic(index, text.encode("utf-8"))


def save_figure(fig, path: str | os.PathLike, caption: str | None = None, dpi: int = 110) -> Path:
    """Save ``fig`` as PNG at ``path`` (tight layout, written atomically); returns the path.

    With ``caption`` (one sentence: what the figure compares) it is recorded in
    ``figures.json`` beside the figure (:func:`record_caption`).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure to save.
    path : str or os.PathLike
        The output file (the format follows its suffix); missing parent directories are
        created.
    caption : str, optional
        One sentence recorded in ``figures.json`` (None or empty: none recorded).
    dpi : int
        Resolution [dots per inch].

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    fig.savefig(tmp, dpi=dpi)
    os.replace(tmp, path)
    if caption:
        record_caption(path, caption)
    return path
