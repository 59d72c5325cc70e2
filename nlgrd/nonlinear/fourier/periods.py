"""Orbits of period ν written on the base ω/ν: harmonic k of ω moves to νk of the base
(:func:`spread`); the base harmonics that are not multiples of ν are the subharmonic content
(:func:`subharmonic_mask`, :func:`amplitudes`), and an orbit's period is the shortest ν
whose subharmonic content is above rounding (:func:`period_of`). The bookkeeping of
:mod:`nlgrd.nonlinear.tracing.subharmonic` (period-ν sweeps and branch-off), of the force
laws and of the models that solve on the base.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import n_harmonics

#: Subharmonic content below this fraction of the largest alternating amplitude is rounding:
#: the orbit has the shorter period.
SUBHARMONIC_RTOL = 1e-6


def _check_period(nu: int) -> int:
    if int(nu) != nu or nu < 1:
        raise ModelError("period", f"a whole number of mesh periods >= 1, got {nu!r}")
    return int(nu)


def spread(z: ArrayLike, nu: int) -> NDArray[np.float64]:
    """Harmonics of ω written as harmonics of ω / ν: harmonic k moves to νk.

    Parameters
    ----------
    z : array_like (..., 2H+1)
        Real harmonics [x_0, a_1, b_1, ...] of a mesh-periodic signal (any unit).
    nu : int
        Mesh periods per base period [-].

    Returns
    -------
    ndarray (..., 2νH+1)
        The same signal in harmonics of the base ω / ν (zeros between).
    """
    nu = _check_period(nu)
    z = np.asarray(z, dtype=float)
    H = n_harmonics(z)
    out = np.zeros((*z.shape[:-1], 2 * nu * H + 1))
    out[..., 0] = z[..., 0]
    k = np.arange(1, H + 1)
    out[..., 2 * nu * k - 1] = z[..., 1::2]
    out[..., 2 * nu * k] = z[..., 2::2]
    return out


def subharmonic_mask(H: int, nu: int) -> NDArray[np.bool_]:
    """Positions in real harmonics [x_0, a_1, b_1, ...] of H base harmonics whose harmonic
    is not a multiple of ν (the subharmonic part).

    Parameters
    ----------
    H : int
        Number of base harmonics.
    nu : int
        Mesh periods per base period.

    Returns
    -------
    ndarray of bool (2H+1,)
    """
    nu = _check_period(nu)
    j = np.concatenate([[0], np.repeat(np.arange(1, H + 1), 2)])
    return j % nu != 0


def amplitudes(z: ArrayLike) -> NDArray[np.float64]:
    """|X_j| of every base harmonic j = 1..H, per coordinate.

    Parameters
    ----------
    z : array_like (..., 2H+1)
        Real harmonics [x_0, a_1, b_1, ...] (any unit).

    Returns
    -------
    ndarray (..., H)
        sqrt(a_j² + b_j²), the amplitude of the component at j times the base (unit of z).
    """
    z = np.asarray(z, dtype=float)
    return np.hypot(z[..., 1::2], z[..., 2::2])


def period_of(z: ArrayLike, nu: int, rtol: float = SUBHARMONIC_RTOL, size: float = 0.0) -> int:
    """The period of an orbit of period ν (in mesh periods): the smallest divisor p of ν
    such that every base harmonic that is not a multiple of ν / p is below ``rtol`` times
    the orbit's size: its largest alternating amplitude, or ``size`` if larger.

    Parameters
    ----------
    z : array_like (n, 2H+1) or (2H+1,)
        Real harmonics of the base ω / ν.
    nu : int
        Mesh periods of the base period.
    rtol : float
        Relative amplitude below which a component counts as absent [-].
    size : float
        A floor of the orbit's size, in the unit of ``z`` (e.g. its mean or the model's
        own lengths): an orbit that hardly moves is then not judged against the noise of
        its own alternating part.

    Returns
    -------
    int
        p in mesh periods (1 for a mesh-periodic orbit).
    """
    nu = _check_period(nu)
    a = np.atleast_2d(amplitudes(z))
    top = max(float(np.max(a)) if a.size else 0.0, float(size))
    j = np.arange(1, a.shape[-1] + 1)
    for p in (d for d in range(1, nu + 1) if nu % d == 0):
        other = j % (nu // p) != 0
        if top == 0 or not np.any(a[:, other] > rtol * top):
            return p
    return nu


def on_shorter_period(z: ArrayLike, nu: int, p: int) -> NDArray[np.float64]:
    """Harmonics of ω/ν of an orbit of period p (p divides ν) written on the base ω/p: the
    base harmonics that are multiples of ν/p, renumbered (the inverse of :func:`spread`
    from p to ν).

    Parameters
    ----------
    z : array_like (..., 2νH+1)
        Real harmonics of the base ω/ν (any unit).
    nu, p : int
        Mesh periods of the two bases [-]; p divides ν.

    Returns
    -------
    ndarray (..., 2pH+1)
        The same signal on the base ω/p, without the components of other harmonics.

    Raises
    ------
    ModelError
        p not a divisor of ν.
    """
    nu, p = _check_period(nu), _check_period(p)
    if nu % p:
        raise ModelError("period", f"{p} does not divide {nu}")
    z = np.asarray(z, dtype=float)
    q = nu // p
    k = np.arange(1, n_harmonics(z) // q + 1)
    out = np.zeros((*z.shape[:-1], 2 * k.size + 1))
    out[..., 0] = z[..., 0]
    out[..., 1::2] = z[..., 2 * q * k - 1]
    out[..., 2::2] = z[..., 2 * q * k]
    return out
