"""Mesh excitation e(t) from files: sampled LSTE or Fourier coefficients.

Convention (Özgüven & Houser 1988, J. Sound Vib. 125:71; model.md §2)::

    e(t) = e0 + Σ_{m=1..H} [a_m cos(m ω t) + b_m sin(m ω t)]
         = Re Σ_{m=0..H} E_m exp(i m ω t),   E_0 = e0,  E_m = a_m - i b_m

with ω the mesh frequency; the mesh phase is φ = ω t / 2π in mesh cycles, so that
e is 1-periodic in φ. All amplitudes are in m along the line of action.

File formats
------------
(Read by :mod:`nlgrd.gear.sample_tables`, which the mesh-stiffness files share.)
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
from nlgrd.gear.sample_tables import read_harmonic_table, read_periodic_samples, read_table

TOML_VERSION = 1
_UNIT_SCALE = {"m": 1.0, "um": 1e-6}
_STE_COLUMNS = {"ste_m": 1.0, "ste_um": 1e-6}


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
    phase, ste, _ = read_periodic_samples(path, _STE_COLUMNS, "STE", teeth_pinion, periodic_rtol)
    return phase, ste


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
    a, b, _ = read_harmonic_table(path, _UNIT_SCALE)
    return MeshExcitation(a[0], a[1:], b[1:])


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
    if "harmonic" in read_table(path).columns:
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
