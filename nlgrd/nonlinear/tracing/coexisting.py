"""Branches that coexist with a sweep's and that no stable-seeking sweep visits (issue 35
item 1).

A sweep up and a sweep down follow the stable branches each reaches from its start and
leave them only at a fold or a bifurcation. A branch that is stable only where another one
is stable too is never met: the preloaded stiff-stop chain of tests/test_folds.py has a
lifted-off period-1 branch, stable between a Neimark-Sacker point and a period doubling,
where the closed-stop branch is stable as well; both sweeps stay on the closed stop there.

Hysteresis and coexisting orbits live where a sweep jumps, so :func:`coexisting_branches`
searches there: at the rows on either side of each jump (at most :data:`MAX_JUMPS` jumps)
it runs the library's default period-1 orbit search
(:func:`~nlgrd.nonlinear.tracing.orbit_search.search_orbits`, starts scaled from the model),
drops the orbits the sweep already has at that frequency and those on a branch already
followed (the same motion:
:func:`~nlgrd.nonlinear.tracing.orbit_search.same_motion`), follows each new orbit over the
sweep's grid, up and down, stable or not
(:func:`~nlgrd.nonlinear.tracing.orbit_search.follow_orbit`), and settles its verdicts as a
converged sweep does (:func:`~nlgrd.nonlinear.tracing.harmonic_convergence.check_harmonics`
at the next rung, then :func:`~nlgrd.nonlinear.stability.verdicts.converge_verdicts`).

The search and the branches use the rung above the sweep's H' (``H``): the sweep's H was
chosen on its own rows, and an orbit off them has more harmonic content. On the preloaded
chain the sweep settles at H = 7 (its rows are the linear closed-stop orbits and the upper
branch); the orbits a search finds there at H = 7 or 9 have no exact orbit near them (max
|μ| 8-60, shooting finds none), at H = 13 the lifted-off orbit is among them (a real
multiplier -9.3 at 1.382 rad/s) and its branch below settles on the exact flow.
Each branch is returned as a SweepResult of its own; the sweep is not changed.
:func:`~nlgrd.nonlinear.stability.verdicts.locate_bifurcations` on each branch then finds
its folds and its changes of stability.

Only the :class:`~nlgrd.nonlinear.hb.harmonic_balance.ReducedModel` contract is used: any
model, any law.

Limits. A branch is followed by natural continuation in ω
(:func:`~nlgrd.nonlinear.tracing.subharmonic.follow_period`): past a fold Newton may land on
another branch and keep following it (on the preloaded chain the lifted-off branch followed
up from 1.382 rad/s goes on over 1.43-1.45 rad/s on other orbits), so a branch's rows are
not always one branch; locate_bifurcations bisects from each stable row on the exact flow
and reports nothing where that row's own branch stays stable. Cost (the preloaded chain,
the default sweep both ways, load 3 on two cores): the three jumps with a settled row, five
searches at H = 13 and eight branches, 60 s of CPU; locate_bifurcations on the eight
branches 160 s more. There, besides the lifted-off branch's fold, Neimark-Sacker point and
period doubling (within 3.2e-7 rad/s of the exact flow's) and the upper branch's fold, it
reports folds at 1.39524, 1.41767, 1.42588, 1.44537, 1.44803, 1.45063 and period doublings
at 1.43107, 1.43229, 1.43496 rad/s that no exact-flow reference has checked (2026-12-07):
the function is not called by any default flow until they are.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.results.sweep_results import SweepResult
from nlgrd.nonlinear.stability.verdicts import converge_verdicts
from nlgrd.nonlinear.tracing.harmonic_convergence import (
    OUTPUT_RTOL,
    check_harmonics,
    next_harmonics,
    pad_harmonics,
    with_harmonic_error,
)
from nlgrd.nonlinear.tracing.orbit_search import follow_orbit, same_motion, search_orbits

#: Jumps searched beside, at most, in the order the sweep meets them (up, then down). A
#: sweep both ways over a band with one hysteresis loop has two jumps (one each way); the
#: preloaded chain's default sweep has three (the closed stop's fold, the upper branch's
#: two folds). Each jump costs two searches and the following of what they find (on the
#: preloaded chain ~12 s of CPU a jump, locate_bifurcations on its branches ~30-90 s).
MAX_JUMPS = 4
#: Perturbed starts of each search [-]: the orbit search's own default
#: (:data:`~nlgrd.nonlinear.tracing.orbit_search.N_STARTS`, 40), so that what it finds is
#: what ``nlgrd sweep --search-at`` finds there. At H = 13 on the two-DOF preloaded chain a
#: search costs 3.4 s of CPU (H = 7: 3.1 s).
N_STARTS = 40


def search_frequencies(result: SweepResult, max_jumps: int = MAX_JUMPS) -> list[float]:
    """The rows beside the sweep's first ``max_jumps`` jumps that leave a real branch end:
    each jump's last frequency on the branch it leaves and its first on the branch it lands
    on, each once.

    A jump leaves a branch end when the row it leaves is converged and, with verdicts, its
    verdict settled (:func:`~nlgrd.nonlinear.stability.verdicts.converge_verdicts`: where
    the exact flow is known, its orbit is an exact one). Rows whose verdict did not settle
    are harmonic-balance orbits with no exact orbit near them (the preloaded chain at H = 7,
    1.386-1.426 rad/s: eight jumps between them); the jumps between them are not searched.

    Parameters
    ----------
    result : SweepResult
        A sweep (:meth:`~nlgrd.nonlinear.results.sweep_results.SweepResult.jumps`).
    max_jumps : int
        Jumps taken, at most [-].

    Returns
    -------
    list of float
        Frequencies [rad/s], in the order met.
    """
    out: list[float] = []
    settled = result.converged & result.verdict_converged
    taken = 0
    for jump in result.jumps():
        if taken >= max_jumps:
            break
        rows = np.nonzero(result.direction == jump.direction)[0]
        i = rows[np.argmin(np.abs(result.omega[rows] - jump.omega_from))]
        if not settled[i]:
            continue
        taken += 1
        for w in (float(jump.omega_from), float(jump.omega_to)):
            if not any(np.isclose(w, v, rtol=1e-12) for v in out):
                out.append(w)
    return out


def _known(harmonics: np.ndarray, omega: float, results: list[SweepResult]) -> bool:
    """Whether a converged row of one of ``results`` at ``omega`` has the same motion."""
    for res in results:
        rows = np.nonzero(np.isclose(res.omega, omega, rtol=1e-12) & res.converged)[0]
        for i in rows:
            H = min(np.shape(res.harmonics[i])[-1], harmonics.shape[-1]) // 2  # the harmonics both have
            z = pad_harmonics(res.harmonics[i], H)
            if same_motion(z, pad_harmonics(harmonics, H), 1):
                return True
    return False


def coexisting_branches(
    model: ReducedModel,
    result: SweepResult,
    *,
    H: int | None = None,
    max_jumps: int = MAX_JUMPS,
    n_starts: int = N_STARTS,
    rtol: float = OUTPUT_RTOL,
    tol: float = 1e-10,
) -> list[SweepResult]:
    """Period-1 branches found beside the sweep's jumps that the sweep does not visit
    (module notes), each followed over the sweep's grid with settled verdicts.

    Parameters
    ----------
    model : ReducedModel
        The model of the sweep.
    result : SweepResult
        A period-1 sweep with stability (e.g. from
        :func:`~nlgrd.nonlinear.tracing.harmonic_convergence.converged_sweep`).
    H : int, optional
        Harmonics of the search and the branches [-]; default the rung above the sweep's
        H' (module notes). The branches' outputs are checked at the next rung.
    max_jumps : int
        Jumps searched beside, at most [-] (:data:`MAX_JUMPS`).
    n_starts : int
        Perturbed starts of each search [-] (:data:`N_STARTS`).
    rtol : float
        Largest accepted estimated relative error of the branches' outputs [-].
    tol : float
        Newton's tolerance (relative residual).

    Returns
    -------
    list of SweepResult
        One per new branch, in the order found: directions "up" and "down" from the orbit
        found, converged where the branch exists, ``verdict_converged`` where its verdict
        is settled; ``source`` names where it was found.
    """
    if H is None:
        H = next_harmonics(next_harmonics(int(result.H)))
    H_check = next_harmonics(H)
    omegas = np.unique(np.asarray(result.omega, dtype=float))

    def model_of(nu: int) -> ReducedModel:
        return model

    branches: list[SweepResult] = []
    for w in search_frequencies(result, max_jumps):
        for orbit in search_orbits(model_of, w, H, (1,), n_starts=n_starts, tol=tol):
            z = np.asarray(orbit.harmonics)
            if _known(z, w, [result, *branches]):
                continue
            branch = follow_orbit(model_of, orbit, omegas, H)
            check = check_harmonics(model, branch, H_check, tol=tol, rtol=rtol, jumps=False)
            branch = with_harmonic_error(branch, check, rtol)
            branch = converge_verdicts(model, branch, check.solutions, tol=tol)
            state = "stable" if orbit.stable else "unstable"
            branches.append(replace(branch, source=f"{branch.source}; found at {w:.6g} rad/s ({state})"))
    return branches
