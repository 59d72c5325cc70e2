"""The orbit's tangent stiffness over one period, for Floquet analysis
(:mod:`nlgrd.nonlinear.stability.floquet`): its pieces between the laws' contact changes,
piecewise constant (:func:`tangent_pieces`) or smooth (:func:`smooth_pieces`), and the
cyclic sequence of distinct states (:func:`state_sequence`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray


def tangent_pieces(nonlinearities: Sequence, harmonics: NDArray, n: int) -> tuple[NDArray, NDArray]:
    """Common breaks over [0, 2π] and the n x n tangent stiffness on each piece.

    Parameters
    ----------
    nonlinearities : sequence
        The laws (each with ``coords`` and ``tangent_segments``).
    harmonics : ndarray
        The orbit's harmonics, one row per link coordinate.
    n : int
        Link coordinates [-].

    Returns
    -------
    breaks : ndarray
        The pieces' bounds [rad], from 0 to 2π.
    Kt : ndarray
        The tangent stiffness on each piece, shape (pieces, n, n).
    """
    segs = []
    for nl in nonlinearities:
        idx = list(nl.coords)
        br, kt = nl.tangent_segments(harmonics[idx])
        segs.append((idx, br, kt))
    if all(kt.shape[0] == 1 for _, _, kt in segs):  # one state all period: no breaks inside
        Kt = np.zeros((1, n, n))
        for idx, _, kt in segs:
            Kt[np.ix_([0], idx, idx)] += kt[:1]
        return np.array([0.0, 2 * np.pi]), Kt
    breaks, mids = _union_breaks([br for _, br, _ in segs])
    Kt = np.zeros((mids.size, n, n))
    for idx, br, kt in segs:
        Kt[np.ix_(np.arange(mids.size), idx, idx)] += kt[_segments_at(mids, br, kt.shape[0])]
    return breaks, Kt


def smooth_pieces(nonlinearities: Sequence, harmonics: NDArray, n: int):
    """Union breaks over one period of every law's exact breaks (contact changes), the
    constant part of the n x n tangent per piece, and per piece the laws whose tangent
    varies there: [(coords, tangent function)], or None when no law has a smooth tangent.

    Parameters
    ----------
    nonlinearities : sequence
        The laws (each with ``coords`` and ``tangent_segments`` or ``tangent_function``).
    harmonics : ndarray
        The orbit's harmonics, one row per link coordinate.
    n : int
        Link coordinates [-].

    Returns
    -------
    tuple or None
        (breaks [rad], constant tangent per piece (pieces, n, n), varying laws per piece).
    """
    if not any(hasattr(nl, "tangent_function") for nl in nonlinearities):
        return None
    parts, smooth = [], False
    for nl in nonlinearities:
        idx = list(nl.coords)
        f = getattr(nl, "tangent_function", None)
        if f is not None:
            br, fn, var = f(harmonics[idx])
            smooth |= bool(np.any(var))
            parts.append((idx, np.asarray(br, dtype=float), None, fn, np.asarray(var, dtype=bool)))
        else:
            br, kt = nl.tangent_segments(harmonics[idx])
            parts.append((idx, np.asarray(br, dtype=float), kt, None, None))
    if not smooth:
        return None
    breaks, mids = _union_breaks([br for _, br, *_ in parts])
    K0 = np.zeros((mids.size, n, n))
    active: list[list] = [[] for _ in mids]
    for idx, br, kt, fn, var in parts:
        seg = _segments_at(mids, br, br.size - 1)
        if fn is None:
            K0[np.ix_(np.arange(mids.size), idx, idx)] += kt[seg]
            continue
        v = var[seg]
        if np.any(~v):
            K0[np.ix_(np.flatnonzero(~v), idx, idx)] += fn(mids[~v])
        for i in np.flatnonzero(v):
            active[i].append((idx, fn))
    return breaks, K0, active


def state_sequence(breaks: NDArray, Kt: NDArray) -> tuple[list[NDArray], list[tuple[int, float]]]:
    """Distinct tangents and the cyclic sequence (state, angle) with equal neighbours merged.

    The last piece is merged into the first when both have the same tangent: the
    monodromy matrices of cyclic shifts of the period are similar.

    Parameters
    ----------
    breaks : ndarray
        The pieces' bounds [rad].
    Kt : ndarray
        The tangent stiffness on each piece, shape (pieces, n, n).

    Returns
    -------
    states : list of ndarray
        The distinct tangents.
    seq : list of (int, float)
        The cyclic sequence: index into ``states`` and the angle it lasts [rad].
    """
    states: list[NDArray] = []
    keys: dict[bytes, int] = {}
    seq: list[tuple[int, float]] = []
    for i in range(Kt.shape[0]):
        key = Kt[i].tobytes()
        if key not in keys:
            keys[key] = len(states)
            states.append(Kt[i])
        s, dth = keys[key], float(breaks[i + 1] - breaks[i])
        if seq and seq[-1][0] == s:
            seq[-1] = (s, seq[-1][1] + dth)
        else:
            seq.append((s, dth))
    if len(seq) > 1 and seq[0][0] == seq[-1][0]:
        seq[0] = (seq[0][0], seq[0][1] + seq[-1][1])
        seq.pop()
    return states, seq


def time_invariant(nonlinearities: Sequence, Y: NDArray, n: int) -> bool:
    """Whether the orbit's tangent is one constant over the period (no contact change).

    Parameters
    ----------
    nonlinearities : sequence
        The laws (each with ``coords`` and ``tangent_segments``).
    Y : ndarray
        The orbit's harmonics, one row per link coordinate.
    n : int
        Link coordinates [-].

    Returns
    -------
    bool
    """
    if smooth_pieces(nonlinearities, Y, n) is not None:
        return False
    return len(state_sequence(*tangent_pieces(nonlinearities, Y, n))[0]) == 1


def _union_breaks(brs: Sequence[NDArray]) -> tuple[NDArray, NDArray]:
    """The union over [0, 2π] of the laws' breaks (each law's last break is its first
    plus 2π), breaks closer than 1e-14 merged, and the pieces' mid-angles."""
    allb = [np.mod(br[:-1], 2 * np.pi) for br in brs]
    breaks = np.unique(np.concatenate([[0.0, 2 * np.pi], *allb]))
    breaks = breaks[np.append(True, np.diff(breaks) > 1e-14)]
    return breaks, 0.5 * (breaks[:-1] + breaks[1:])


def _segments_at(mids: NDArray, br: NDArray, nseg: int) -> NDArray:
    """The index of one law's segment (breaks ``br``, ``nseg`` segments) at each angle."""
    rel = np.mod(mids - br[0], 2 * np.pi) + br[0]
    return np.clip(np.searchsorted(br, rel, side="right") - 1, 0, nseg - 1)
