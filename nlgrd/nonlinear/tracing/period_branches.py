"""Orbits found at chosen speeds, followed over a grid and merged into one response: the
orbit search of ``nlgrd sweep --search-at`` and ``--period N``, for any model.

:func:`search_and_follow` searches at each speed
(:func:`nlgrd.nonlinear.tracing.orbit_search.search_orbits`) and follows over the grid
(:func:`~nlgrd.nonlinear.tracing.orbit_search.follow_orbit`) the stable orbits that a test
``known`` does not already have (``every``: the unstable ones too). What is written of each
orbit and branch is the model's (a *view*: ``columns``, ``row(orbit)``, ``text(row)``,
``frame(branch)``; :mod:`nlgrd.nonlinear.models.model_views`).

``--period N``, N >= 3 (orbits no sweep reaches: nothing branches onto them from period 1):
:func:`period_response` searches for period-N orbits (of no shorter period), follows each
one found and not on a branch already followed (:func:`on_followed_branch`), and
:func:`merge_branches` makes them one response per grid point and direction: period N, the
ω/N content, stability per point, an unstable orbit flagged as no stable response (not
drawn as the response), a point without a period-N orbit as not converged; the harmonic
error is estimated against the next H of the ladder.

Progress lines go to ``report`` (the command line passes :func:`print`; None: silent).
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np

#: ``--period N`` without ``--harmonics``: mesh harmonics (N H of the base ω/N) [-]; the
#: single-DOF pair's period-3 orbit agrees with time integration to 1e-6 at 9
#: (tests/test_orbit_search.py).
PERIOD_HARMONICS = 9


def _silent(line: str) -> None:
    """The default ``report``: no output."""


def search_and_follow(model_of, omegas, at, periods, H, unit, known, words, view, every=False, report=None):
    """Search at each speed, report each orbit, follow the stable ones (``every``: all) that
    ``known`` does not have.

    Parameters
    ----------
    model_of : callable
        ``model_of(nu)``: the period-ν reduced model
        (:func:`~nlgrd.nonlinear.tracing.orbit_search.search_orbits`).
    omegas : ndarray
        The grid over which orbits are followed [rad/s].
    at : ndarray
        Search speeds, in the unit of ``unit``.
    periods : tuple of int
        Periods sought [base periods].
    H : int
        Harmonics of the base [-].
    unit : callable
        Frequency [rad/s] to text in the range's unit; ``unit.omega`` the inverse, ``unit.name``
        its name (the branches' labels are written in it).
    known : callable
        ``known(orbit, omega, followed)``: whether the sweep (or a branch already followed) has it.
    words : str
        How a known orbit is described in the reported line.
    view : LinkView
        Each orbit's and branch's columns (:mod:`nlgrd.nonlinear.models.model_views`); only
        its ``row``, ``text``, ``frame`` and ``columns`` are used.
    every : bool
        The ``--period N`` search: follow unstable orbits too, period-N orbits only (one of a
        shorter minimal period is dropped: ``model_of`` gives the period-N model alone).
    report : callable, optional
        Takes each progress line (None: silent).

    Returns
    -------
    (DataFrame, DataFrame, list)
        The orbits found, the followed branches, and (label, result) per branch.
    """
    import pandas as pd

    from nlgrd.nonlinear.tracing.orbit_search import follow_orbit, search_orbits

    report = report or _silent
    rows, frames, followed = [], [], []
    for value in at:
        w = float(unit.omega(value))
        for o in search_orbits(model_of, w, H, periods, shorter_periods=not every):
            seen = known(o, w, followed)
            out = view.row(o)
            rows.append(
                {
                    "search at": value,
                    "period": o.period,
                    "stable": o.stable,
                    "floquet_max [-]": o.floquet_max,
                    "on the sweep": seen,
                    "amplitude [um]": o.amplitude * 1e6,
                    "start": o.start,
                    **out,
                }
            )
            state = "stable" if o.stable else f"unstable, max |mu| {o.floquet_max:.3g}"
            report(
                f"orbit at {unit(w)} {unit.name}: period {o.period}, {state}, "
                + view.text(out)
                + ("" if not seen else f" ({words})")
            )
            if (o.stable or every) and not seen:
                branch = follow_orbit(model_of, o, omegas, H)
                label = f"period {o.period} from {unit(w)} {unit.name}"
                if every:  # unstable ones too: say which
                    label += ", stable there" if o.stable else ", unstable there"
                same = sum(lb.split(" (")[0] == label for lb, _ in followed)
                label += f" ({same + 1})" if same else ""
                f = view.frame(branch)
                f.insert(0, "branch", label)
                frames.append(f)
                followed.append((label, branch))
                span = branch.omega[branch.converged]
                reach = (
                    f"from {unit(span.min())} to {unit(span.max())} {unit.name}" if span.size else "nowhere"
                )
                report(f"  followed: period {o.period} {reach}, {int(branch.stable.sum())} stable points")
    orbits = pd.DataFrame(rows, columns=list(view.columns))
    branches = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=["branch"])
    return orbits, branches, followed


def on_followed_branch(nu: int):
    """The ``known`` test of a ``--period N`` search: an orbit is known when a branch
    already followed has the same motion at its speed (a shift by whole base periods is
    the same orbit).

    Parameters
    ----------
    nu : int
        The period sought [base periods].

    Returns
    -------
    callable
        ``known(orbit, omega, followed)`` for :func:`search_and_follow`.
    """
    from nlgrd.nonlinear.tracing.orbit_search import same_motion

    def on_branch(o, w: float, followed) -> bool:
        return any(
            same_motion(b.harmonics[i], o.harmonics, nu)
            for _, b in followed
            for i in np.nonzero(np.isclose(b.omega, w, rtol=1e-12) & b.converged)[0]
        )

    return on_branch


def period_response(model_of, fine_of, omegas, at, nu: int, H: int, unit, directions: str, view, report=None):
    """``--period N`` on any model: search at ``at`` for period-ν orbits, follow each new one
    over the grid (unstable ones too), merge the branches into one response per grid point
    and direction (:func:`merge_branches`) and estimate its harmonic error at the next rung.

    Parameters
    ----------
    model_of : callable
        ``model_of(nu)``: the period-ν reduced model at H.
    fine_of : callable
        ``fine_of(H')``: the period-ν reduced model serving ν H' harmonics of ω/ν.
    omegas : ndarray
        The grid's base frequencies [rad/s].
    at : ndarray
        Search speeds, in the unit of ``unit``.
    nu : int
        The period sought [base periods].
    H : int
        Harmonics of the base (ν H of ω/ν) [-].
    unit : callable
        Frequency [rad/s] to text in the range's unit; ``unit.omega`` the inverse.
    directions : {"both", "up", "down"}
        Sweep directions of the response.
    view : LinkView
        Each orbit's and branch's columns (as :func:`search_and_follow`).
    report : callable, optional
        Takes each progress line (None: silent).

    Returns
    -------
    (SweepResult or None, DataFrame, DataFrame)
        The response with its harmonic error (None when no period-ν orbit was found), the
        orbits found and the followed branches.
    """
    from nlgrd.nonlinear.tracing.harmonic_convergence import check_harmonics, next_harmonics

    orbits, frames, followed = search_and_follow(
        model_of,
        omegas,
        at,
        (nu,),
        H,
        unit,
        on_followed_branch(nu),
        "on a branch already followed",
        view,
        every=True,
        report=report,
    )
    if not followed:
        return None, orbits, frames
    res = merge_branches([b for _, b in followed], omegas, directions)
    on_base = dc.replace(res, omega=res.omega / nu)  # the frequencies the model's receptances take
    H_check = next_harmonics(H)
    check = check_harmonics(fine_of(H_check), on_base, nu * H_check, jumps=False)
    return dc.replace(res, harmonic_error=check.error, H_check=H_check), orbits, frames  # of ω, as H


def merge_branches(branches: list, omegas, directions: str = "both"):
    """One response per grid point and sweep direction from followed branches of one period.

    Each direction is walked like a slow sweep: it stays on the branch of the previous point
    while that branch has a stable orbit here, else takes the first branch with one; where
    none is stable, an unstable orbit (``no_stable``: kept, not the response); where no
    branch reaches, the point is not converged.

    Parameters
    ----------
    branches : list of SweepResult
        From :func:`~nlgrd.nonlinear.tracing.orbit_search.follow_orbit`, one period, one H.
    omegas : array_like
        The grid [rad/s].
    directions : {"both", "up", "down"}
        "up": the grid ascending; "down": descending; "both": up, then down.

    Returns
    -------
    SweepResult
        One row per grid point and direction; ``branch_switch`` where the branch changes.
    """
    blank = _take(branches[0], [0])
    blank = dc.replace(
        blank,
        harmonics=np.full_like(blank.harmonics, np.nan),
        converged=np.zeros(1, bool),
        stable=np.zeros(1, bool),
        no_stable=np.zeros(1, bool),
    )
    pool = _concat([*branches, blank])
    owner = np.concatenate([np.full(len(b), k) for k, b in enumerate(branches)] + [[-1]])
    grid = np.unique(np.asarray(omegas, dtype=float))
    rows, names, at, switch = [], [], [], []
    for d in ("up", "down") if directions == "both" else (directions,):
        cur = None
        for w in grid if d == "up" else grid[::-1]:
            here = np.nonzero(np.isclose(pool.omega, w, rtol=1e-12) & pool.converged)[0]
            stable = [int(i) for i in here if pool.stable[i]]
            mine = [i for i in (stable or here.tolist()) if owner[i] == cur]
            pick = mine[0] if mine else (stable or here.tolist() or [len(pool) - 1])[0]
            switch.append(cur is not None and owner[pick] not in (-1, cur))
            cur = owner[pick] if owner[pick] >= 0 else cur
            rows.append(pick)
            names.append(d)
            at.append(w)
    out = _take(pool, rows)
    return dc.replace(out, omega=np.array(at), direction=np.array(names), branch_switch=np.array(switch))


def _take(res, index):
    """The rows ``index`` of a SweepResult (every per-point array and metric)."""
    n = len(res)

    def pick(v):
        if isinstance(v, dict):
            return {k: pick(x) for k, x in v.items()}
        return v[index] if isinstance(v, np.ndarray) and v.ndim and v.shape[0] == n else v

    return dc.replace(res, **{f.name: pick(getattr(res, f.name)) for f in dc.fields(res)})


def _concat(results: list):
    """SweepResults of one kind and H, one after the other."""

    def cat(values):
        if isinstance(values[0], dict):
            return {k: np.concatenate([v[k] for v in values]) for k in values[0]}
        return np.concatenate(values) if isinstance(values[0], np.ndarray) else values[0]

    return dc.replace(
        results[0], **{f.name: cat([getattr(r, f.name) for r in results]) for f in dc.fields(results[0])}
    )
