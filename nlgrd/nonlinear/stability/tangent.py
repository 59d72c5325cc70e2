"""The orbit's tangent stiffness over one period, for Floquet analysis
(:mod:`nlgrd.nonlinear.stability.floquet`): its pieces between the laws' contact changes,
piecewise constant (:func:`_tangent_pieces`) or smooth (:func:`_smooth_pieces`), and the
cyclic sequence of distinct states (:func:`_state_sequence`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray


def _tangent_pieces(nonlinearities: Sequence, harmonics: NDArray, n: int) -> tuple[NDArray, NDArray]:
    """Common breaks over [0, 2π] and the n x n tangent stiffness on each piece."""
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
    allb = [np.mod(br[:-1], 2 * np.pi) for _, br, _ in segs]
    breaks = np.unique(np.concatenate([[0.0, 2 * np.pi], *allb])) if allb else np.array([0.0, 2 * np.pi])
    breaks = breaks[np.append(True, np.diff(breaks) > 1e-14)]
    mids = 0.5 * (breaks[:-1] + breaks[1:])
    Kt = np.zeros((mids.size, n, n))
    for idx, br, kt in segs:
        rel = np.mod(mids - br[0], 2 * np.pi) + br[0]
        seg = np.clip(np.searchsorted(br, rel, side="right") - 1, 0, kt.shape[0] - 1)
        Kt[np.ix_(np.arange(mids.size), idx, idx)] += kt[seg]
    return breaks, Kt


def _smooth_pieces(nonlinearities: Sequence, harmonics: NDArray, n: int):
    """Union breaks over one period of every law's exact breaks (contact changes), the
    constant part of the n x n tangent per piece, and per piece the laws whose tangent
    varies there: [(coords, tangent function)], or None when no law has a smooth tangent."""
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
    allb = [np.mod(br[:-1], 2 * np.pi) for _, br, *_ in parts]
    breaks = np.unique(np.concatenate([[0.0, 2 * np.pi], *allb]))
    breaks = breaks[np.append(True, np.diff(breaks) > 1e-14)]
    mids = 0.5 * (breaks[:-1] + breaks[1:])
    K0 = np.zeros((mids.size, n, n))
    active: list[list] = [[] for _ in mids]
    for idx, br, kt, fn, var in parts:
        rel = np.mod(mids - br[0], 2 * np.pi) + br[0]
        nseg = br.size - 1
        seg = np.clip(np.searchsorted(br, rel, side="right") - 1, 0, nseg - 1)
        if fn is None:
            K0[np.ix_(np.arange(mids.size), idx, idx)] += kt[seg]
            continue
        v = var[seg]
        if np.any(~v):
            K0[np.ix_(np.flatnonzero(~v), idx, idx)] += fn(mids[~v])
        for i in np.flatnonzero(v):
            active[i].append((idx, fn))
    return breaks, K0, active


def _state_sequence(breaks: NDArray, Kt: NDArray) -> tuple[list[NDArray], list[tuple[int, float]]]:
    """Distinct tangents and the cyclic sequence (state, angle) with equal neighbours merged.

    The last piece is merged into the first when both have the same tangent: the
    monodromy matrices of cyclic shifts of the period are similar.
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


def _time_invariant(nonlinearities: Sequence, Y: NDArray, n: int) -> bool:
    """Whether the orbit's tangent is one constant over the period (no contact change)."""
    if _smooth_pieces(nonlinearities, Y, n) is not None:
        return False
    return len(_state_sequence(*_tangent_pieces(nonlinearities, Y, n))[0]) == 1
