"""Option checks and output files of the ``nlgrd`` command line (:mod:`nlgrd.cli`).

- The option checks run before any computation: ranges (``START:STOP:COUNT``), counts,
  orders, quantities, and that the output paths can be written. Each raises one
  :class:`~nlgrd.errors.ModelError` naming the option, e.g. ``--rpm``.
- :class:`Outputs` writes the output files atomically and together: each goes to a
  temporary file in its own folder, which then replaces the output (``os.replace``);
  an exception or Ctrl-C removes the temporary files, so the previous outputs stay.
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import tempfile
from fractions import Fraction
from pathlib import Path

from nlgrd.errors import ModelError

#: Largest COUNT of a range. A sweep point costs milliseconds to a second: 1e5 points
#: are hours of computing; a larger COUNT is a typing slip.
MAX_POINTS = 100_000

_RANGE = f"START:STOP:COUNT (START < STOP, COUNT from 2 to {MAX_POINTS}) or one number"
_SPAN = "START:STOP or START:STOP:COUNT (START != STOP)"


# ---------------------------------------------------------------------------- options


def _split(text: str, name: str, forms: tuple[int, ...], expected: str) -> tuple[list[float], int | None]:
    """Numbers of ``START[:STOP[:COUNT]]`` with as many parts as ``forms`` allows."""
    parts = text.split(":")
    if len(parts) not in forms:
        raise ModelError(name, f"expected {expected}, got {text!r}")
    try:
        values = [float(p) for p in parts[:2]]
    except ValueError:
        raise ModelError(name, f"expected {expected}, got {text!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise ModelError(name, f"speeds and frequencies must be finite, got {text!r}")
    count = None
    if len(parts) == 3:
        try:
            count = int(parts[2])
        except ValueError:
            raise ModelError(name, f"COUNT must be an integer, got {parts[2]!r} in {text!r}") from None
        if not 2 <= count <= MAX_POINTS:
            raise ModelError(name, f"COUNT must be from 2 to {MAX_POINTS}, got {count}")
    return values, count


def parse_range(text: str, name: str = "--rpm"):
    """Parse ``START:STOP:COUNT`` (or a single value) into an array; all finite.

    Parameters
    ----------
    text : str
        The option's text: ``START:STOP:COUNT`` (COUNT from 2 to :data:`MAX_POINTS`) or one
        number, in the option's unit (rpm for ``--rpm``).
    name : str
        The option's name, used in the error message.

    Returns
    -------
    numpy.ndarray
        The COUNT values START + i (STOP - START) / (COUNT - 1), or the one value. Each is
        the float nearest the exact decimal value (computed in rational arithmetic from
        the text as typed), so ``4000:16000:241`` gives 10600.0, not
        ``numpy.linspace``'s 10600.000000000004, and the tables print the grid as typed.

    Raises
    ------
    ModelError
        When the text is not of that form, a number is not finite, START >= STOP (a
        range goes up; the sweep's ``--direction`` chooses the sense) or COUNT is out of
        range.
    """
    import numpy as np

    values, count = _split(text, name, (1, 3), _RANGE)
    if count is None:
        return np.array(values)
    if values[0] >= values[1]:
        raise ModelError(
            name,
            f"START must be below STOP, got {text!r} (a range goes up; a sweep's --direction sets the sense)",
        )
    try:
        start, stop = (Fraction(p.strip()) for p in text.split(":")[:2])
    except ValueError:  # a form float() reads and Fraction() does not
        start, stop = (Fraction(v) for v in values)
    step = (stop - start) / (count - 1)
    return np.array([float(start + i * step) for i in range(count)])


def snap_to_grid(frame, column: str, grid) -> None:
    """Write the grid values as given in place of their round trip through rad/s.

    A speed converted to a frequency [rad/s] and back differs from the typed one by a few
    ulps (``10600.000000000004``); each value of ``frame[column]`` within 1e-9 of the grid's
    span of a grid value is replaced by it, in place. Others (a fold's landing, a
    continuation) are kept.

    Parameters
    ----------
    frame : pandas.DataFrame
        A result table; nothing happens when it has no ``column``.
    column : str
        The column in the range's unit, e.g. ``"shaft_speed [rpm]"``.
    grid : array_like
        The values of the range (:func:`parse_range`), in that unit.
    """
    import numpy as np

    if column not in frame.columns:
        return
    grid = np.sort(np.asarray(grid, dtype=float))
    values = frame[column].to_numpy(dtype=float)
    i = np.clip(np.searchsorted(grid, values), 1, max(len(grid) - 1, 1))
    lo, hi = grid[np.minimum(i - 1, len(grid) - 1)], grid[np.minimum(i, len(grid) - 1)]
    near = np.where(np.abs(values - lo) <= np.abs(values - hi), lo, hi)
    scale = max(float(np.ptp(grid)), float(np.max(np.abs(grid))))
    close = np.abs(values - near) <= 1e-9 * scale
    frame[column] = np.where(close, near, values)


def parse_span(text: str, name: str) -> tuple[float, float, int | None]:
    """Parse ``START:STOP`` or ``START:STOP:COUNT`` (a continuation's range) into (start, stop, count).

    Parameters
    ----------
    text : str
        The option's text, in the option's unit.
    name : str
        The option's name, used in the error message.

    Returns
    -------
    start, stop : float
        The ends of the range (different from each other).
    count : int or None
        COUNT when given, else None.

    Raises
    ------
    ModelError
        When the text is not of that form, a number is not finite, START equals STOP or
        COUNT is out of range.
    """
    values, count = _split(text, name, (2, 3), _SPAN)
    if values[0] == values[1]:
        raise ModelError(name, f"a continuation needs {_SPAN}, got {text!r}")
    return values[0], values[1], count


def check_at_least(name: str, value: int, low: int) -> None:
    """Raise unless the integer option ``name`` is at least ``low``.

    Parameters
    ----------
    name : str
        The option's name, used in the error message.
    value : int
        The option's value.
    low : int
        The smallest value allowed.

    Raises
    ------
    ModelError
        When ``value`` is less than ``low``.
    """
    if value < low:
        raise ModelError(name, f"must be at least {low}, got {value}")


def parse_speed(text: str) -> float:
    """The one speed of ``--rpm`` (a range is an error).

    Parameters
    ----------
    text : str
        The text of ``--rpm``: one number [rpm].

    Returns
    -------
    float
        The speed [rpm].

    Raises
    ------
    ModelError
        When the text is not a finite number or is a range.
    """
    values = parse_range(text, "--rpm")
    if len(values) != 1:
        raise ModelError("--rpm", f"give one speed for modal analysis, got the range {text!r}")
    return float(values[0])


def parse_orders(text: str) -> dict[str, float]:
    """``--orders`` (comma-separated positive numbers) as ``{"25x": 25.0, ...}``.

    Parameters
    ----------
    text : str
        The text of ``--orders``: comma-separated engine orders [-].

    Returns
    -------
    dict of str to float
        Each order [-] under its label (``"25x"``), in the order given.

    Raises
    ------
    ModelError
        When an order is not a number, not finite or not positive.
    """
    try:
        values = [float(o) for o in text.split(",")]
    except ValueError:
        raise ModelError("--orders", f"expected comma-separated numbers, got {text!r}") from None
    if not all(math.isfinite(v) and v > 0 for v in values):
        raise ModelError("--orders", f"orders must be positive finite numbers, got {text!r}")
    return {f"{v:g}x": v for v in values}


def check_quantity(name: str) -> str:
    """``--quantity``: one of :data:`nlgrd.nonlinear.results.metrics.METRIC_NAMES`.

    Parameters
    ----------
    name : str
        The text of ``--quantity``.

    Returns
    -------
    str
        ``name``, checked.

    Raises
    ------
    ModelError
        When ``name`` is not a metric name.
    """
    from nlgrd.nonlinear.results.metrics import METRIC_NAMES

    if name not in METRIC_NAMES:
        raise ModelError("--quantity", f"unknown quantity {name!r}; use one of {', '.join(METRIC_NAMES)}")
    return name


def _writable_folder(option: str, folder: Path) -> None:
    """Raise unless files can be made in ``folder`` or in the folder it would be made in."""
    probe = folder
    with contextlib.suppress(OSError):
        while not probe.exists() and probe.parent != probe:
            probe = probe.parent
    if not probe.is_dir():
        raise ModelError(option, f"cannot write in {folder}: {probe} is not a folder")
    try:
        with tempfile.TemporaryFile(dir=probe):
            pass
    except OSError as exc:
        raise ModelError(option, f"cannot write in {probe}: {exc.strerror or exc}") from None


def output_folder(option: str, text: str) -> Path:
    """An output folder: existing or to be made (nothing is made now).

    Parameters
    ----------
    option : str
        The option's name, used in the error message.
    text : str
        The folder given on the command line.

    Returns
    -------
    pathlib.Path
        The folder.

    Raises
    ------
    ModelError
        When ``text`` is a file, or files cannot be made in the folder (or in the existing
        folder it would be made in).
    """
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise ModelError(option, f"{text} is a file, not a folder")
    _writable_folder(option, path)
    return path


def output_file(option: str, text: str, example: str) -> Path:
    """An output file (not a folder) in a folder where files can be made.

    Parameters
    ----------
    option : str
        The option's name, used in the error message.
    text : str
        The file given on the command line.
    example : str
        A file name suggested in the message when ``text`` is a folder.

    Returns
    -------
    pathlib.Path
        The file.

    Raises
    ------
    ModelError
        When ``text`` is a folder, or files cannot be made in its folder.
    """
    path = Path(text)
    if path.is_dir() or text.endswith(("/", os.sep)):
        raise ModelError(option, f"{text} is a folder; give a file name, e.g. {path / example}")
    _writable_folder(option, path.parent)
    return path


# ---------------------------------------------------------------------------- outputs


class Outputs:
    """Output files written atomically and together.

    Each file is written to a temporary file in its own folder; :meth:`commit` renames
    them into place (``os.replace``). An exception or Ctrl-C before or during the
    commit removes the temporary files: the previous outputs stay as they were.

    Used as a context manager: ``with Outputs() as out: out.csv(frame, path); ...;
    out.commit()``. It takes no parameters.

    Attributes
    ----------
    _staged : list of (str, pathlib.Path)
        The temporary files written so far, each with the output it will replace (private).
    """

    def __init__(self):
        self._staged: list[tuple[str, Path]] = []

    def __enter__(self) -> Outputs:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        for tmp, _ in self._staged:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
        self._staged.clear()

    def _add(self, path: Path, write) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
        os.close(fd)
        self._staged.append((tmp, path))
        write(tmp)

    def csv(self, frame, path: Path) -> None:
        """Stage the table ``frame`` (a pandas DataFrame) as the CSV file ``path``, without its index."""
        self._add(path, lambda tmp: frame.to_csv(tmp, index=False))

    def figure(self, fig, path: Path) -> None:
        """Stage the matplotlib figure ``fig`` as the PNG file ``path`` (100 dpi), then close it."""
        import matplotlib.pyplot as plt

        try:
            self._add(path, lambda tmp: fig.savefig(tmp, dpi=100, format="png"))
        finally:
            plt.close(fig)

    def commit(self) -> None:
        """Move the staged files into place (``os.replace``), keeping an existing output's mode."""
        umask = os.umask(0)
        os.umask(umask)
        for tmp, path in self._staged:
            try:
                mode = path.stat().st_mode & 0o777
            except FileNotFoundError:
                mode = 0o666 & ~umask
            os.chmod(tmp, mode)
            os.replace(tmp, path)
        self._staged.clear()


def harmonics_line(res) -> str:
    """'H = 13 (chosen; largest estimated error 0.12 % against H = 17)', or 'H = 5' when H
    was given ('given; ...' when some points were estimated all the same, e.g. period-2
    branches): H of docs/conventions.md (harmonics of the sweep's frequency, whatever the
    period of the points), the error the largest over the accepted points.

    Parameters
    ----------
    res : SweepResult
        A sweep.

    Returns
    -------
    str
    """
    if res.H_check is None:
        return f"H = {res.H}"
    worst = res.max_harmonic_error
    text = f"{100 * worst:.2g} %" if math.isfinite(worst) else "n/a"
    how = "chosen" if "H chosen" in res.source else "given"
    return f"H = {res.H} ({how}; largest estimated error {text} against H = {res.H_check})"


def pyplot():
    """``matplotlib.pyplot`` on the file-only Agg backend.

    Returns
    -------
    module
        ``matplotlib.pyplot``, after selecting the Agg backend.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


class ProgressBar:
    """``progress(i, n)`` of a sweep drawn on stderr: a tqdm bar on a terminal, else a line
    at every tenth of the points (logs stay readable). ``label`` may change between runs
    (the rung of harmonics); a count that starts again from 1 starts a new bar.

    Parameters
    ----------
    label : str
        What is running, shown before the bar.
    """

    def __init__(self, label: str):
        self.label = label
        self._bar = None

    def __call__(self, i: int, n: int) -> None:
        if not sys.stderr.isatty():
            if i == n or i % max(1, n // 10) == 0:
                print(f"{self.label}: {i}/{n}", file=sys.stderr, flush=True)
            return
        from tqdm import tqdm

        if self._bar is None or self._bar.total != n or i < self._bar.n:
            self.close()
            self._bar = tqdm(total=n, desc=self.label, file=sys.stderr, leave=True, dynamic_ncols=True)
        self._bar.set_description(self.label, refresh=False)
        self._bar.update(i - self._bar.n)
        if i >= n:
            self.close()

    def close(self) -> None:
        """End the bar on the terminal (a run that stops early)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
