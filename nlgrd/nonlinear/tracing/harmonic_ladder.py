"""The ladder of harmonic counts H climbs (issue 35): the first rungs, then 1.5 x per rung up
to what memory holds for the model, estimated from its size (also the bound of
``--harmonics``), not a constant."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel

#: The first harmonic counts tried, in order (each checked against the next); above the
#: last, :func:`ladder_for` climbs by 1.5 x up to what memory holds
#: (:func:`max_harmonics`).
LADDER = (5, 7, 9, 13, 17, 25)
#: The share of the available memory the arrays of one harmonic-balance point may take.
MEMORY_SHARE = 0.25
#: Bytes assumed available where the system does not say.
DEFAULT_MEMORY = 2**32


def available_memory() -> int:
    """Bytes of physical memory available now (:data:`DEFAULT_MEMORY` where unknown).

    Returns
    -------
    int
    """
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return DEFAULT_MEMORY


def harmonics_memory(H: int, n_dofs: int, n_coords: int) -> float:
    """Bytes the largest arrays of one point take at H harmonics (an estimate).

    Per harmonic the receptance columns of the link coordinates, complex N x n; one dense
    dynamic stiffness, complex N x N, factored; the harmonic-balance Jacobian of the n link
    coordinates, real (n (2H + 1))², four copies (the Jacobian, its factor, Newton's and
    hybr's).

    Parameters
    ----------
    H : int
        Number of harmonics.
    n_dofs : int
        DOFs N of the model's state space [-].
    n_coords : int
        Nonlinear (link) coordinates n [-].

    Returns
    -------
    float
        Bytes.
    """
    return 16.0 * ((H + 1) * n_dofs * n_coords + 2 * n_dofs**2) + 4 * 8.0 * (n_coords * (2 * H + 1)) ** 2


def max_harmonics(n_dofs: int, n_coords: int, memory: float | None = None) -> int:
    """The largest H whose :func:`harmonics_memory` fits in :data:`MEMORY_SHARE` of ``memory``.

    Parameters
    ----------
    n_dofs : int
        DOFs N of the model's state space [-].
    n_coords : int
        Nonlinear (link) coordinates n [-].
    memory : float, optional
        Bytes available (default :func:`available_memory`).

    Returns
    -------
    int
        At least 1.
    """
    budget = MEMORY_SHARE * (available_memory() if memory is None else float(memory))
    lo, hi = 1, 2
    while harmonics_memory(hi, n_dofs, n_coords) <= budget and hi < 2**31:
        lo, hi = hi, 2 * hi
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if harmonics_memory(mid, n_dofs, n_coords) <= budget else (lo, mid)
    return lo


def ladder_for(model: ReducedModel, memory: float | None = None) -> tuple[int, ...]:
    """:data:`LADDER`, then 1.5 x per rung, up to :func:`max_harmonics` of the model.

    Parameters
    ----------
    model : ReducedModel
        The model (its state space's size and its nonlinear coordinates).
    memory : float, optional
        Bytes available (default :func:`available_memory`).

    Returns
    -------
    tuple of int
    """
    ss = model.state_space if model.state_space is not None else None
    n_dofs = 0 if ss is None else ss.M.shape[0]
    n_coords = max((max(nl.coords) + 1 for nl in model.nonlinearities), default=1)
    top = max(max_harmonics(n_dofs, n_coords, memory), LADDER[1])
    ladder = [h for h in LADDER if h <= top]
    while True:
        h = int(np.ceil(1.5 * ladder[-1]))
        if h > top:
            return tuple(ladder)
        ladder.append(h)
