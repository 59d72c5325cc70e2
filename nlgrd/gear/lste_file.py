"""Mesh excitation e(t) from files: sampled LSTE or Fourier coefficients.

Convention (Özgüven & Houser 1988, J. Sound Vib. 125:71; model.md §2)::

    e(t) = e0 + Σ_{m=1..H} [a_m cos(m ω t) + b_m sin(m ω t)]
         = Re Σ_{m=0..H} E_m exp(i m ω t),   E_0 = e0,  E_m = a_m - i b_m

with ω the mesh frequency; the mesh phase is φ = ω t / 2π in mesh cycles, so that
e is 1-periodic in φ. All amplitudes are in m along the line of action.

File formats
------------
Samples (CSV, one header row, ``#`` starts a comment): a phase column and a value
column, names case-insensitive:

- ``phase``: mesh phase in cycles, one period (e.g. 0 .. 1); or ``roll_angle``: pinion
  roll (rotation) angle in rad, one mesh cycle being 2π / z1 (``teeth_pinion`` needed);
- ``ste_m`` (metres) or ``ste_um`` (micrometres): the static transmission error.

The phase must increase strictly. If the last sample lies one period after the first
(the file includes the endpoint) the two values must agree (to ``periodic_rtol``
times the peak-to-peak value) and the last sample is dropped; otherwise the samples
must fill one period, the gap from the last sample to the first plus one period
being no longer than 1.5 times the largest spacing inside the file.

Fourier coefficients, CSV: columns ``harmonic`` (integers m >= 0, m = 0 holding e0),
``a_m`` and ``b_m`` in metres, or ``a_um`` and ``b_um`` in micrometres; harmonics not
listed are zero. TOML: keys ``version = 1``, ``e0``, ``a``, ``b`` (arrays, harmonics
1 .. H) and optional ``unit = "m"`` or ``"um"`` — the field names of
:class:`MeshExcitation`.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError

TOML_VERSION = 1
_UNIT_SCALE = {"m": 1.0, "um": 1e-6}


def _frozen(a: ArrayLike) -> NDArray:
    arr = np.array(a, dtype=float).reshape(-1)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class MeshExcitation:
    """Periodic mesh excitation e(φ), φ the mesh phase in cycles; SI units.

    e(φ) = e0 + Σ_{m=1..H} a_m cos(2π m φ) + b_m sin(2π m φ), equivalently
    Re Σ_{m=0..H} E_m exp(2π i m φ) with E_0 = e0 and E_m = a_m - i b_m.

    Parameters
    ----------
    e0 : float
        Mean value [m].
    a, b : array_like
        Cosine and sine coefficients a_m, b_m of harmonics m = 1 .. H [m].
    """

    e0: float = 0.0
    a: NDArray = ()
    b: NDArray = ()

    def __post_init__(self):
        a, b = _frozen(self.a), _frozen(self.b)
        if a.shape != b.shape:
            raise ModelError("b", f"needs as many coefficients as a ({a.size}), got {b.size}")
        if not math.isfinite(float(self.e0)):
            raise ModelError("e0", f"must be finite, got {self.e0!r}")
        for key, arr in (("a", a), ("b", b)):
            if not np.all(np.isfinite(arr)):
                raise ModelError(key, "coefficients must be finite")
        object.__setattr__(self, "e0", float(self.e0))
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "b", b)

    def __eq__(self, other) -> bool:
        if not isinstance(other, MeshExcitation):
            return NotImplemented
        return self.e0 == other.e0 and np.array_equal(self.a, other.a) and np.array_equal(self.b, other.b)

    __hash__ = None

    @property
    def n_harmonics(self) -> int:
        """Number H of harmonics held."""
        return int(self.a.size)

    def harmonics(self, H: int | None = None) -> NDArray:
        """Complex coefficients E_m, m = 0 .. H, with e = Re Σ E_m exp(i m ω t) [m].

        E_0 = e0, E_m = a_m - i b_m; zero beyond the harmonics held, truncated below.
        """
        H = self.n_harmonics if H is None else int(H)
        if H < 0:
            raise ValueError("H must be >= 0")
        out = np.zeros(H + 1, dtype=complex)
        out[0] = self.e0
        n = min(H, self.n_harmonics)
        out[1 : n + 1] = self.a[:n] - 1j * self.b[:n]
        return out

    def value(self, phase: ArrayLike) -> NDArray | float:
        """e at mesh phase φ [cycles] (φ = ω t / 2π) [m]."""
        ph = np.asarray(phase, dtype=float)
        m = np.arange(1, self.n_harmonics + 1)
        arg = 2 * np.pi * ph[..., None] * m
        out = self.e0 + np.sum(self.a * np.cos(arg) + self.b * np.sin(arg), axis=-1)
        return float(out) if np.ndim(out) == 0 else out

    def derivative(self, phase: ArrayLike) -> NDArray | float:
        """de/dφ at mesh phase φ [m per cycle]; de/dt = ω / (2π) de/dφ."""
        ph = np.asarray(phase, dtype=float)
        m = np.arange(1, self.n_harmonics + 1)
        arg = 2 * np.pi * ph[..., None] * m
        out = np.sum(2 * np.pi * m * (-self.a * np.sin(arg) + self.b * np.cos(arg)), axis=-1)
        return float(out) if np.ndim(out) == 0 else out

    def without_mean(self) -> MeshExcitation:
        """Copy with e0 = 0."""
        return MeshExcitation(0.0, self.a, self.b)

    def truncated(self, H: int) -> MeshExcitation:
        """Copy keeping harmonics 1 .. ``H`` (zero-padded if more than held)."""
        E = self.harmonics(H)
        return MeshExcitation(self.e0, np.real(E[1:]), -np.imag(E[1:]))

    @property
    def peak_to_peak(self) -> float:
        """Peak-to-peak value of e over a period, sampled at 64 (H + 1) points [m]."""
        phase = np.arange(64 * (self.n_harmonics + 1)) / (64 * (self.n_harmonics + 1))
        return float(np.ptp(self.value(phase)))

    @classmethod
    def fit(cls, phase: ArrayLike, values: ArrayLike, H: int) -> MeshExcitation:
        """Least-squares Fourier fit of samples over one period (see :func:`fourier_fit`)."""
        return fourier_fit(phase, values, H)

    def to_frame(self):
        """Coefficients as a tidy :class:`pandas.DataFrame` (µm), harmonic 0 holding e0."""
        import pandas as pd

        m = np.arange(self.n_harmonics + 1)
        a = np.concatenate([[self.e0], self.a])
        b = np.concatenate([[0.0], self.b])
        return pd.DataFrame(
            {"harmonic [-]": m, "a [um]": a * 1e6, "b [um]": b * 1e6, "amplitude [um]": np.hypot(a, b) * 1e6}
        )

    def save(self, path: str | Path) -> None:
        """Write the coefficients as TOML (``version``, ``unit = "m"``, ``e0``, ``a``, ``b``)."""

        def fmt(v: NDArray) -> str:
            return "[" + ", ".join(repr(float(x)) for x in v) + "]"

        text = (
            f"version = {TOML_VERSION}\n"
            'unit = "m"\n'
            f"e0 = {float(self.e0)!r}\n"
            f"a = {fmt(self.a)}\n"
            f"b = {fmt(self.b)}\n"
        )
        Path(path).write_text(text, encoding="utf-8")


def fourier_fit(phase: ArrayLike, values: ArrayLike, H: int) -> MeshExcitation:
    """Fit e0, a_m, b_m (m = 1 .. H) to samples of one period by linear least squares.

    Parameters
    ----------
    phase : array_like
        Sample phases in cycles [-] (any spacing; one period, endpoint excluded).
    values : array_like
        Sample values [m].
    H : int
        Number of harmonics H [-]; needs at least 2 H + 1 samples.

    Returns
    -------
    MeshExcitation
        e0, a_m, b_m [m].

    Raises
    ------
    ModelError
        When H < 0, the arrays differ in length or there are fewer than 2 H + 1 samples.

    Notes
    -----
    For uniform samples of a band-limited signal with H below the Nyquist limit the
    fit is exact (the basis is orthogonal on the grid), i.e. it equals the DFT.
    """
    ph = np.asarray(phase, dtype=float).reshape(-1)
    v = np.asarray(values, dtype=float).reshape(-1)
    H = int(H)
    if H < 0:
        raise ModelError("H", f"must be >= 0, got {H!r}")
    if ph.shape != v.shape:
        raise ModelError("values", f"needs one value per phase ({ph.size}), got {v.size}")
    if v.size < 2 * H + 1:
        raise ModelError("H", f"{H} harmonics need at least {2 * H + 1} samples, got {v.size}")
    m = np.arange(1, H + 1)
    arg = 2 * np.pi * ph[:, None] * m
    basis = np.hstack([np.ones((ph.size, 1)), np.cos(arg), np.sin(arg)])
    coef, *_ = np.linalg.lstsq(basis, v, rcond=None)
    return MeshExcitation(coef[0], coef[1 : H + 1], coef[H + 1 :])


def resample(
    phase: ArrayLike, values: ArrayLike, n_samples: int, kind: str = "cubic"
) -> tuple[NDArray, NDArray]:
    """Resample one period of samples onto n uniform phases 0, 1/n, .. (n-1)/n.

    ``kind="cubic"`` uses a periodic cubic spline, ``"linear"`` periodic linear
    interpolation. The input phases must increase strictly within one period
    (endpoint excluded).

    Parameters
    ----------
    phase : array_like
        Sample phases in cycles [-].
    values : array_like
        Sample values, one per phase (STE [m]; returned in the same unit).
    n_samples : int
        Number n of uniform phases, >= 2.
    kind : {"cubic", "linear"}
        Periodic interpolation.

    Returns
    -------
    phase : ndarray, shape (n,)
        Uniform phases k / n [-].
    values : ndarray, shape (n,)
        Interpolated values.

    Raises
    ------
    ModelError
        When n < 2, the phases are not strictly increasing within one period or
        ``kind`` is unknown.
    """
    ph = np.asarray(phase, dtype=float).reshape(-1)
    v = np.asarray(values, dtype=float).reshape(-1)
    if n_samples < 2:
        raise ModelError("n_samples", f"must be at least 2, got {n_samples!r}")
    if np.any(np.diff(ph) <= 0) or ph[-1] - ph[0] >= 1:
        raise ModelError("phase", "must increase strictly within one period")
    new = np.arange(int(n_samples)) / int(n_samples)
    xp = np.concatenate([ph, [ph[0] + 1.0]])
    fp = np.concatenate([v, [v[0]]])
    shifted = ph[0] + np.mod(new - ph[0], 1.0)
    if kind == "linear":
        out = np.interp(shifted, xp, fp)
    elif kind == "cubic":
        from scipy.interpolate import CubicSpline

        out = CubicSpline(xp, fp, bc_type="periodic")(shifted)
    else:
        raise ModelError("kind", f"must be 'linear' or 'cubic', got {kind!r}")
    return new, out


# --------------------------------------------------------------------------- reading
def _read_csv(path: Path):
    import pandas as pd

    try:
        frame = pd.read_csv(path, comment="#", skipinitialspace=True)
    except FileNotFoundError:
        raise
    except Exception as exc:  # pandas raises several parser errors
        raise ModelError("", f"cannot read CSV: {exc}", file=str(path)) from exc
    frame.columns = [str(c).strip().lower() for c in frame.columns]
    return frame


def _column(frame, name: str, path: Path) -> NDArray:
    raw = frame[name]
    values = np.asarray(raw.to_numpy(), dtype=object)
    out = np.empty(values.size)
    for i, x in enumerate(values):
        try:
            out[i] = float(x)
        except (TypeError, ValueError):
            raise ModelError(name, f"row {i + 1}: not a number ({x!r})", file=str(path)) from None
    bad = ~np.isfinite(out)
    if np.any(bad):
        rows = (np.flatnonzero(bad) + 1).tolist()[:5]
        raise ModelError(name, f"non-finite values (NaN, inf or empty) in data rows {rows}", file=str(path))
    return out


def _pick(frame, options: tuple[str, ...], what: str, path: Path) -> str:
    found = [c for c in options if c in frame.columns]
    if not found:
        raise ModelError(
            " or ".join(options),
            f"missing {what} column: need one of {list(options)}, found {list(frame.columns)}",
            file=str(path),
        )
    if len(found) > 1:
        raise ModelError(found[1], f"give one {what} column, found {found}", file=str(path))
    return found[0]


def read_lste_samples(
    path: str | Path, teeth_pinion: int | None = None, periodic_rtol: float = 1e-3
) -> tuple[NDArray, NDArray]:
    """Read sampled STE from a CSV file and check it covers one period.

    Parameters
    ----------
    path : str or Path
        CSV file (see the module notes for columns).
    teeth_pinion : int, optional
        z1, required with a ``roll_angle`` column.
    periodic_rtol : float
        Allowed mismatch of the endpoint values, relative to the peak-to-peak value [-].

    Returns
    -------
    phase : ndarray
        Phases in cycles [-], starting at the first sample, endpoint excluded.
    ste : ndarray
        STE [m].

    Raises
    ------
    ModelError
        When the file, its columns or its samples break the rules of the module notes.
    """
    path = Path(path)
    frame = _read_csv(path)
    pcol = _pick(frame, ("phase", "roll_angle"), "phase", path)
    vcol = _pick(frame, ("ste_m", "ste_um"), "STE", path)
    if len(frame) < 3:
        raise ModelError(pcol, f"needs at least 3 samples, got {len(frame)}", file=str(path))
    phase = _column(frame, pcol, path)
    ste = _column(frame, vcol, path) * (1e-6 if vcol == "ste_um" else 1.0)
    if pcol == "roll_angle":
        if teeth_pinion is None:
            raise ModelError(
                "teeth_pinion", "a roll_angle column needs the pinion tooth count", file=str(path)
            )
        phase = phase * int(teeth_pinion) / (2 * np.pi)
    step = np.diff(phase)
    if np.any(step <= 0):
        row = int(np.flatnonzero(step <= 0)[0]) + 2
        raise ModelError(
            pcol, f"must increase strictly (unsorted or repeated at data row {row})", file=str(path)
        )
    span = phase[-1] - phase[0]
    tol = 1e-9
    if abs(span - 1.0) <= tol:
        ptp = np.ptp(ste)
        if abs(ste[-1] - ste[0]) > periodic_rtol * ptp + 1e-300:
            raise ModelError(
                vcol,
                f"not periodic: the last sample (one period after the first) is {ste[-1]!r}, "
                f"the first {ste[0]!r}",
                file=str(path),
            )
        phase, ste = phase[:-1], ste[:-1]
    elif span > 1.0 + tol:
        raise ModelError(pcol, f"spans {span:.6g} cycles: must cover exactly one mesh period", file=str(path))
    else:
        gap = phase[0] + 1.0 - phase[-1]
        if gap > 1.5 * np.max(step):
            raise ModelError(
                pcol,
                f"spans {span:.6g} cycles: the samples do not fill one mesh period "
                f"(gap {gap:.3g} to the next period, largest step {np.max(step):.3g})",
                file=str(path),
            )
    return phase - phase[0] + np.mod(phase[0], 1.0), ste


def read_lste_csv(
    path: str | Path,
    H: int | None = None,
    teeth_pinion: int | None = None,
    resample_points: int | None = None,
    periodic_rtol: float = 1e-3,
) -> MeshExcitation:
    """Mesh excitation fitted to sampled STE in a CSV file.

    Parameters
    ----------
    path : str or Path
        CSV file of samples (module notes).
    H : int, optional
        Harmonics to fit; default the most the samples allow, (n - 1) // 2.
    teeth_pinion : int, optional
        z1, for a ``roll_angle`` column.
    resample_points : int, optional
        Resample onto this many uniform phases (periodic cubic spline) before fitting.
    periodic_rtol : float
        See :func:`read_lste_samples` [-].

    Returns
    -------
    MeshExcitation
        The Fourier fit, mean e0 kept [m].

    Raises
    ------
    ModelError
        When the samples are invalid or too few for H harmonics.
    """
    phase, ste = read_lste_samples(path, teeth_pinion=teeth_pinion, periodic_rtol=periodic_rtol)
    if resample_points is not None:
        phase, ste = resample(phase, ste, resample_points)
    H = (len(ste) - 1) // 2 if H is None else H
    try:
        return fourier_fit(phase, ste, H)
    except ModelError as exc:
        raise exc.within(file=str(path)) from None


def read_fourier_csv(path: str | Path) -> MeshExcitation:
    """Mesh excitation from a CSV table of Fourier coefficients (module notes).

    Parameters
    ----------
    path : str or Path
        CSV file with columns ``harmonic``, ``a_m``/``b_m`` or ``a_um``/``b_um``.

    Returns
    -------
    MeshExcitation
        Coefficients in m; harmonics not listed are zero.

    Raises
    ------
    ModelError
        On a missing column, mixed units, invalid or repeated harmonics, or a sine
        coefficient for harmonic 0.
    """
    path = Path(path)
    frame = _read_csv(path)
    if "harmonic" not in frame.columns:
        raise ModelError("harmonic", f"missing harmonic column, found {list(frame.columns)}", file=str(path))
    acol = _pick(frame, ("a_m", "a_um"), "cosine-coefficient", path)
    bcol = _pick(frame, ("b_m", "b_um"), "sine-coefficient", path)
    if (acol == "a_um") != (bcol == "b_um"):
        raise ModelError(bcol, f"units of {acol} and {bcol} differ", file=str(path))
    scale = 1e-6 if acol == "a_um" else 1.0
    harm = _column(frame, "harmonic", path)
    if np.any(harm < 0) or np.any(harm != np.round(harm)):
        raise ModelError("harmonic", "must hold integers >= 0", file=str(path))
    harm = harm.astype(int)
    if len(np.unique(harm)) != harm.size:
        raise ModelError("harmonic", "repeated harmonic numbers", file=str(path))
    a = _column(frame, acol, path) * scale
    b = _column(frame, bcol, path) * scale
    H = int(harm.max()) if harm.size else 0
    aa, bb = np.zeros(H + 1), np.zeros(H + 1)
    aa[harm], bb[harm] = a, b
    if bb[0] != 0:
        raise ModelError(bcol, "harmonic 0 (the mean) cannot have a sine coefficient", file=str(path))
    return MeshExcitation(aa[0], aa[1:], bb[1:])


def read_fourier_toml(path: str | Path) -> MeshExcitation:
    """Mesh excitation from a TOML file with ``version``, ``e0``, ``a``, ``b`` (``unit``).

    Parameters
    ----------
    path : str or Path
        TOML file (module notes).

    Returns
    -------
    MeshExcitation
        Coefficients in m.

    Raises
    ------
    ModelError
        On a parse error, a wrong version or unit, an unknown key or missing or
        non-numeric coefficients.
    """
    path = Path(path)
    with open(path, "rb") as fh:
        try:
            data = tomllib.load(fh)
        except tomllib.TOMLDecodeError as exc:
            raise ModelError("", f"cannot parse TOML: {exc}", file=str(path)) from exc
    version = data.get("version")
    if version != TOML_VERSION:
        raise ModelError("version", f"expected {TOML_VERSION}, got {version!r}", file=str(path))
    unit = data.get("unit", "m")
    if unit not in _UNIT_SCALE:
        raise ModelError("unit", f"must be 'm' or 'um', got {unit!r}", file=str(path))
    unknown = set(data) - {"version", "unit", "e0", "a", "b"}
    if unknown:
        raise ModelError(sorted(unknown)[0], "unknown key", file=str(path))
    for key in ("a", "b"):
        if key not in data:
            raise ModelError(key, "missing coefficient array", file=str(path))
    scale = _UNIT_SCALE[unit]
    try:
        e0 = float(data.get("e0", 0.0)) * scale
        a = np.asarray(data["a"], dtype=float) * scale
        b = np.asarray(data["b"], dtype=float) * scale
        return MeshExcitation(e0, a, b)
    except ModelError as exc:
        raise exc.within(file=str(path)) from None
    except (TypeError, ValueError) as exc:
        raise ModelError("a", f"coefficients must be numbers: {exc}", file=str(path)) from None


def read_excitation(path: str | Path, **kwargs) -> MeshExcitation:
    """Read a mesh excitation from any supported file.

    ``.toml``: coefficients; ``.csv`` with a ``harmonic`` column: coefficients; other
    ``.csv``: samples, fitted by :func:`read_lste_csv` (``kwargs`` passed on).

    Parameters
    ----------
    path : str or Path
        The file.
    **kwargs
        Options of :func:`read_lste_csv` (``H``, ``teeth_pinion``, ...), used for
        sample files only.

    Returns
    -------
    MeshExcitation
        The excitation [m], mean kept.
    """
    path = Path(path)
    if path.suffix.lower() == ".toml":
        return read_fourier_toml(path)
    frame = _read_csv(path)
    if "harmonic" in frame.columns:
        return read_fourier_csv(path)
    return read_lste_csv(path, **kwargs)


def write_lste_csv(path: str | Path, phase: ArrayLike, ste: ArrayLike, unit: str = "um") -> None:
    """Write samples in the CSV sample format (columns ``phase`` and ``ste_um``/``ste_m``).

    Parameters
    ----------
    path : str or Path
        File written.
    phase : array_like
        Mesh phases in cycles [-].
    ste : array_like
        STE [m], one value per phase.
    unit : {"um", "m"}
        Unit of the values in the file.

    Raises
    ------
    ModelError
        When ``unit`` is not "um" or "m".
    """
    if unit not in _UNIT_SCALE:
        raise ModelError("unit", f"must be 'm' or 'um', got {unit!r}")
    ph = np.asarray(phase, dtype=float).reshape(-1)
    v = np.asarray(ste, dtype=float).reshape(-1) / _UNIT_SCALE[unit]
    lines = [f"phase,ste_{unit}"] + [f"{p!r},{x!r}" for p, x in zip(ph.tolist(), v.tolist(), strict=True)]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
