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
model, any law. The default flows offer it as an option (``nlgrd.sweep(...,
coexisting=True)``, ``nlgrd sweep --coexisting``:
:func:`nlgrd.nonlinear.models.link_coexisting.with_coexisting`, which also locates and
flags the branches' bifurcations).

Hops. A branch is followed by natural continuation in ω
(:func:`~nlgrd.nonlinear.tracing.subharmonic.follow_period`): past a fold Newton may land
on another orbit, and at H = 13 the truncated branches themselves run smoothly from one
exact branch onto another (the preloaded chain from the orbit at 1.430 rad/s with max |μ|
6.8: the rows above it are, shot on the exact flow, the stable orbit of the branch beside
it). Where the exact flow is known each branch is cut at its first hop on the exact flow
(:func:`cut_at_first_hop`), so every bifurcation
:func:`~nlgrd.nonlinear.stability.verdicts.locate_bifurcations` reports on it lies on one
continuous exact branch. On the preloaded chain (the default sweep both ways, all three
jumps with a settled row; nine branches) it reports, besides the lifted-off branch's
fold, Neimark-Sacker point and period doubling and the upper branch's fold 1.4297823:
the lifted-off branch's second period doubling 1.4310718 and fold 1.4506266 (above
1.43 rad/s it regains stability), folds at 1.4176731, 1.4258797, 1.4453670 and 1.4480325,
period doublings at 1.4322925 and 1.4349624, each within 1e-3 of a march on the
reference's exact flow (tests/piecewise_reference.py; folds to 1e-7, period doublings
inside its 5e-4 rad/s step) from the branch's last row before it, and the end of the
branch through the orbit at 1.394 rad/s at 1.3952356, where the reference's orbits end
between 1.3952 and 1.3953 (a grazing touch; its event search does not return closer).
Not checked: the fold 1.4453670 as the end of the branch through the orbit at 1.430 rad/s
with max |μ| 6.8 (the reference's march hangs at a grazing on the way; the same fold is
confirmed on the stable branch that meets it there). tests/test_folds.py holds those of
the first jump's branches. Not cut: a branch through a grazing (the orbit's slope jumps, the
harmonic-balance rows there have no exact orbit near them) when the exact flow continues
it, as at 1.421 rad/s on the branch that folds at 1.4176731.

Period 2. :func:`period_two_branches` starts the period-2 branches born at the located
period doublings of these branches from the exact flow (the exact orbit at the period
doubling kicked along its flip eigenvector), follows and settles them: on the preloaded
chain the subcritical branch born at 1.3648667 rad/s and its fold 1.3517440 (the
reference's 1.3517439).

Cost (the preloaded chain, the default sweep both ways, load 6 on two cores,
2026-12-07): all three jumps, five searches at H = 13 and nine branches with their hop
cuts, 181 s of CPU (49 s without the cuts at load 3; the cuts alone, on the eight
branches found without them, 137 s at load 2-3: 52 s on the lifted-off branch, each
grid step marched in steps of about 5e-4 rad/s); locate_bifurcations on the nine
branches 161 s more; the first jump alone 123 s.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from nlgrd.nonlinear.fourier.periods import period_of
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.results.sweep_results import SweepResult, dominant_multiplier, without_rows
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.nonlinear.stability.shooting import orbit_harmonics, polish, shoot_orbit, shootable
from nlgrd.nonlinear.stability.verdicts import (
    KEPT_HARMONICS,
    converge_verdicts,
    locate_bifurcations,
    same_orbit,
)
from nlgrd.nonlinear.tracing.auto_period import period_only
from nlgrd.nonlinear.tracing.harmonic_convergence import (
    OUTPUT_RTOL,
    check_harmonics,
    next_harmonics,
    pad_harmonics,
    with_harmonic_error,
)
from nlgrd.nonlinear.tracing.orbit_search import FoundOrbit, follow_orbit, same_motion, search_orbits
from nlgrd.nonlinear.tracing.subharmonic import follow_period

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
#: A row stays on its branch when its exact orbit lies within this fraction of the
#: state's size of the previous exact row's orbit continued to it on the exact flow
#: (:func:`cut_at_first_hop`) [-]: both converge to 1e-11; on the preloaded chain the
#: rows of the lifted-off branch (29 steps) agree to 1e-14 - 1.4e-11, the rows on the
#: branch beside the one followed differ by 0.046-0.12 (tests/test_folds.py,
#: test_a_followed_branch_stops_at_its_first_hop).
HOP_RTOL = 1e-6
#: Each step of that continuation is kept when the shot orbit lies within this fraction of
#: the state's size of its secant predictor (halved otherwise) [-]: on the preloaded chain
#: a step of 4e-4 rad/s moves the state by about 2e-2 of its size, the secant predictor's
#: error is far below that, and the branch beside it is 0.046-0.12 away.
MARCH_RTOL = 1e-2
#: Halvings of a step of that continuation before the branch counts as ended [-].
MARCH_HALVINGS = 12
#: Period-2 orbits born at a period doubling are sought this fraction of ω on either side
#: of it (a subcritical branch lies on the stable side, a supercritical one on the other)
#: [-]: the reference's period-2 orbit of tests/test_folds.py, P2_START, 1.5e-3 below its
#: period doubling.
PD_OFFSET = 1.5e-3
#: Kicks along the flip eigenvector v (max |v| = 1) of the exact orbit at the period
#: doubling, as fractions of its state's largest component [-] (P2_START: 0.05 of a unit
#: eigenvector, 0.04 of the state).
PD_KICKS = (0.05, 0.2)


def search_frequencies(result: SweepResult, max_jumps: int = MAX_JUMPS, jumps=None) -> list[float]:
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
    jumps : list of Jump, optional
        The sweep's jumps; default ``result.jumps()`` (a link sweep gives its links' own,
        :meth:`~nlgrd.nonlinear.results.link_results.LinkSweepResult.jumps`).

    Returns
    -------
    list of float
        Frequencies [rad/s], in the order met.
    """
    out: list[float] = []
    settled = result.converged & result.verdict_converged
    taken = 0
    for jump in result.jumps() if jumps is None else jumps:
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
    ladder=None,
    jumps=None,
    progress=None,
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
    ladder : sequence of int, optional
        The rungs of H (:func:`~nlgrd.nonlinear.tracing.harmonic_convergence.next_harmonics`;
        a link model's: the ladder times its ``top_order``); default the library's.
    jumps : list of Jump, optional
        The sweep's jumps (:func:`search_frequencies`).
    progress : callable, optional
        ``progress(i, n)`` after each of the n frequencies searched at.

    Returns
    -------
    list of SweepResult
        One per new branch, in the order found: directions "up" and "down" from the orbit
        found, converged where the branch exists, ``verdict_converged`` where its verdict
        is settled; ``source`` names where it was found.
    """
    rungs = {} if ladder is None else {"ladder": ladder}
    if H is None:
        H = next_harmonics(next_harmonics(int(result.H), **rungs), **rungs)
    H_check = next_harmonics(H, **rungs)
    omegas = np.unique(np.asarray(result.omega, dtype=float))

    def model_of(nu: int) -> ReducedModel:
        return model

    branches: list[SweepResult] = []
    at = search_frequencies(result, max_jumps, jumps)
    for k, w in enumerate(at):
        if progress is not None:
            progress(k, len(at))
        for orbit in search_orbits(model_of, w, H, (1,), n_starts=n_starts, tol=tol):
            z = np.asarray(orbit.harmonics)
            if _known(z, w, [result, *branches]):
                continue
            branch = follow_orbit(model_of, orbit, omegas, H)
            check = check_harmonics(model, branch, H_check, tol=tol, rtol=rtol, jumps=False)
            branch = with_harmonic_error(branch, check, rtol)
            branch = converge_verdicts(model, branch, check.solutions, tol=tol)
            branch = cut_at_first_hop(model, branch)
            state = "stable" if orbit.stable else "unstable"
            branches.append(replace(branch, source=f"{branch.source}; found at {w:.6g} rad/s ({state})"))
    if progress is not None and at:
        progress(len(at), len(at))
    return branches


def _p2_orbits(model, model_two, z, omega_pd: float, H: int, tol: float) -> list[FoundOrbit]:
    """Period-2 harmonic-balance orbits started from the exact flow at a period doubling:
    the exact period-1 orbit there (shot from ``z``) kicked along its flip eigenvector,
    shot over two periods at ω_pd (1 ± :data:`PD_OFFSET`), then solved with 2H harmonics
    of ω/2 from the exact orbit's harmonics."""
    first = polish(model, z, omega_pd)
    if first is None:
        return []
    mu, vectors = np.linalg.eig(first.monodromy)
    v = np.real(vectors[:, int(np.argmin(np.abs(mu + 1)))])
    v /= np.max(np.abs(v))
    size = float(np.max(np.abs(first.state)))
    found: list[FoundOrbit] = []
    for w in (omega_pd * (1 - PD_OFFSET), omega_pd * (1 + PD_OFFSET)):
        ss = model_two.linear_state_space(w / 2)
        for kick in (k * sign for k in PD_KICKS for sign in (1.0, -1.0)):
            shot = shoot_orbit(
                ss,
                model_two.nonlinearities,
                None,
                w / 2,
                model_two.static_force,
                state=first.state + kick * size * v,
            )
            if not shot.converged:
                continue
            sol = solve(
                model_two.at(w / 2, 2 * H),
                orbit_harmonics(model_two, shot, w / 2, 2 * H),
                tol=tol,
                fallback=False,
            )
            if not (sol.converged and period_of(sol.harmonics, 2) == 2):
                continue
            fmax, dom = dominant_multiplier(
                floquet_multipliers(ss, model_two.nonlinearities, sol.harmonics, w / 2)
            )
            met = model_two.metrics.of(sol.harmonics, w / 2)
            found.append(
                FoundOrbit(
                    w,
                    2,
                    sol.harmonics,
                    float(fmax),
                    complex(dom),
                    f"beside the period doubling at {omega_pd:.6g} rad/s",
                    met,
                )
            )
            break
    return found


def period_two_branches(
    model: ReducedModel,
    model_two: ReducedModel,
    branches: list[SweepResult],
    *,
    H: int | None = None,
    rtol: float = OUTPUT_RTOL,
    tol: float = 1e-10,
) -> list[SweepResult]:
    """The period-2 branches born at the period doublings of followed period-1 branches.

    Each period doubling between two rows with settled verdicts (one stable, one with a
    real multiplier < -1) is located on the exact flow
    (:func:`~nlgrd.nonlinear.stability.verdicts.locate_bifurcations`); the period-2 orbits
    beside it (:func:`_p2_orbits`) are followed over the branch's grid
    (:func:`~nlgrd.nonlinear.tracing.subharmonic.follow_period`, stopped at its first hop),
    their outputs checked at the next rung and their verdicts settled on the period-2
    model, as :func:`~nlgrd.nonlinear.tracing.auto_period.beyond_period_one` does. A start
    from the harmonic-balance critical mode (``branch_off``) does not reach a subcritical
    branch: it exists on the stable side only, where the truncated orbit's multipliers are
    wrong (the preloaded chain at H = 13, 1.362 rad/s: 2.4 where the exact orbit has
    |μ| = 0.96), and on the flip-unstable side it finds orbits with no exact orbit near them.

    Parameters
    ----------
    model : ReducedModel
        The period-1 model (a :func:`~nlgrd.nonlinear.stability.shooting.shootable` one;
        otherwise nothing is found).
    model_two : ReducedModel
        The same model on the base ω/2 (every excitation at even harmonics).
    branches : list of SweepResult
        Period-1 branches with settled verdicts (:func:`coexisting_branches`).
    H : int, optional
        Harmonics of ω [-] (2H of ω/2); default each branch's.
    rtol : float
        Largest accepted estimated relative error of the outputs [-].
    tol : float
        Newton's tolerance (relative residual).

    Returns
    -------
    list of SweepResult
        One per period-2 branch found (``period`` 2, frequencies ω, harmonics of ω/2).
    """
    out: list[SweepResult] = []
    for branch in branches:
        Hb = int(branch.H) if H is None else int(H)
        omegas = np.unique(np.asarray(branch.omega, dtype=float))
        flips = [f for f in locate_bifurcations(model, branch, folds=False) if f[1] == "period doubling"]
        for d, _, w_pd in flips:
            rows = np.nonzero((branch.direction == d) & branch.converged & branch.stable)[0]
            if not rows.size:
                continue
            i = rows[np.argmin(np.abs(branch.omega[rows] - w_pd))]
            for orbit in _p2_orbits(model, model_two, branch.harmonics[i], w_pd, Hb, tol):
                p2 = follow_period(model_two, omegas, 2 * Hb, 2, orbit.omega, orbit.harmonics, tol=tol)
                on_base = replace(p2, omega=p2.omega / 2)
                check = check_harmonics(
                    model_two, on_base, next_harmonics(2 * Hb), tol=tol, rtol=rtol, jumps=False
                )
                on_base = with_harmonic_error(on_base, check, rtol)
                on_base = converge_verdicts(model_two, on_base, check.solutions, tol=tol)
                on_base = cut_at_first_hop(model_two, on_base)
                p2 = period_only(replace(on_base, omega=p2.omega), 2)
                state = "stable" if orbit.stable else "unstable"
                out.append(replace(p2, source=f"{p2.source}; {orbit.start} ({state})"))
    return out


def _shoot_from(model: ReducedModel, state: np.ndarray, omega: float):
    """The exact orbit shot from a state (q, q') at base frequency ω, or None."""
    ss = model.linear_state_space(omega)
    orbit = shoot_orbit(ss, model.nonlinearities, None, omega, model.static_force, state=state)
    return orbit if orbit.converged else None


def _march(model: ReducedModel, state: np.ndarray, omega: float, omega_end: float) -> np.ndarray | None:
    """The exact orbit through ``state`` at ``omega`` continued in ω to ``omega_end``: each
    step shot from the secant predictor, kept within :data:`MARCH_RTOL` of it, halved
    otherwise; None where the branch ends (a fold) or leaves every predictor."""
    full = omega_end - omega
    h, pts = full, [(omega, state)]
    while (omega_end - pts[-1][0]) * np.sign(full) > 1e-12 * abs(omega_end):
        w, s = pts[-1]
        wn = omega_end if abs(h) >= abs(omega_end - w) else w + h
        pred = s if len(pts) < 2 else s + (s - pts[-2][1]) * (wn - w) / (w - pts[-2][0])
        orbit = _shoot_from(model, pred, wn)
        if orbit is not None and np.linalg.norm(orbit.state - pred) <= MARCH_RTOL * np.linalg.norm(s):
            pts.append((wn, orbit.state))
            h = min(abs(2 * h), abs(full)) * np.sign(full)
        else:
            h /= 2
            if abs(h) < abs(full) / 2**MARCH_HALVINGS:
                return None
    return pts[-1][1]


def cut_at_first_hop(model: ReducedModel, branch: SweepResult) -> SweepResult:
    """A followed branch without the rows past its first hop onto another orbit, judged on
    the exact flow (a :func:`~nlgrd.nonlinear.stability.shooting.shootable` model;
    otherwise the branch is returned as it is).

    Natural continuation of a harmonic-balance orbit can land on another branch past a
    fold, and at H = 13 on the preloaded chain of tests/test_folds.py the truncated
    branches themselves run smoothly from one exact branch onto another (from the orbit
    at 1.430 rad/s with max |μ| 6.8, the rows at 1.434 rad/s and above are, on the exact
    flow, the stable orbit of the branch beside it): no test on the harmonic-balance rows
    alone sees it. So, in each direction from the start, each row whose exact orbit is
    its harmonic-balance orbit (polished by shooting,
    :func:`~nlgrd.nonlinear.stability.verdicts.same_orbit`) is compared with the previous
    such row's exact orbit continued to it on the exact flow (:func:`_march`): where the
    two differ by more than :data:`HOP_RTOL` of the state, or the continuation ends, that
    row and every later one are dropped (not converged). Rows without an exact orbit in
    between are kept only up to the last row confirmed.

    Parameters
    ----------
    model : ReducedModel
        The model of the branch (its base frequency is ``branch.omega``).
    branch : SweepResult
        From :func:`~nlgrd.nonlinear.tracing.orbit_search.follow_orbit`: each direction
        starts at the found orbit.

    Returns
    -------
    SweepResult
        The branch with the rows past its first hop not converged.
    """
    if not shootable(model):
        return branch
    drop = np.zeros(len(branch), dtype=bool)
    for d in ("up", "down"):
        rows = np.nonzero((branch.direction == d) & branch.converged)[0]
        rows = rows[np.argsort(branch.omega[rows] * (1.0 if d == "up" else -1.0), kind="stable")]
        last, confirmed = None, 0
        for n, i in enumerate(rows):
            w = float(branch.omega[i])
            orbit = polish(model, branch.harmonics[i], w)
            if orbit is None or not same_orbit(
                orbit_harmonics(model, orbit, w, KEPT_HARMONICS), branch.harmonics[i]
            ):
                continue
            if last is not None:
                s = _march(model, last[1], last[0], w)
                if s is None or np.linalg.norm(s - orbit.state) > HOP_RTOL * np.linalg.norm(orbit.state):
                    drop[rows[confirmed + 1 :]] = True
                    break
            last, confirmed = (w, orbit.state), n
    return without_rows(branch, drop)
