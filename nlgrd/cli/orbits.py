"""``nlgrd sweep --search-at`` and ``--period N``: orbits the sweep does not reach, searched
for at chosen speeds (:func:`nlgrd.nonlinear.tracing.orbit_search.search_orbits`) and followed over
the sweep's grid (:func:`~nlgrd.nonlinear.tracing.orbit_search.follow_orbit`).

``--search-at``: outputs beside the sweep's CSV, ``<out>_orbits.csv`` (every orbit found, one
row each, with whether the sweep has it) and ``<out>_branches.csv`` (the branch of each stable
orbit the sweep does not have, followed up and down over the grid), drawn on the sweep's
figure.

``--period N``, N >= 3 (orbits no sweep reaches: nothing branches onto them from period 1):
no period-1 sweep; the period-N orbits (of no shorter period) are searched for at the
``--search-at`` speeds, or at :data:`DEFAULT_SEARCH_POINTS` speeds of the grid evenly spread
over the range, with ``--harmonics`` (default :data:`PERIOD_HARMONICS`) mesh harmonics, N H
of ω/N. Each one found and not on a branch already followed is followed over the grid
(``<out>_branches.csv``; the orbits file's "on the sweep" then says "on a branch already
followed"), and :func:`merge_branches` makes them the sweep's CSV, one row per grid point
and direction: period N, the ω/N content, stability per point, an unstable orbit flagged as
no stable response (not drawn as the response), a point without a period-N orbit as not
converged; the harmonic error is estimated against the next H of the ladder. When no
period-N orbit is found at all, nothing is written and the command exits with status 1.
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pandas as pd

from nlgrd.errors import ModelError

#: Periods searched by default [mesh periods].
DEFAULT_PERIODS = "1,2,3"
#: Longest period searched [mesh periods]: the period-ν model has ν H harmonics.
MAX_PERIOD = 6
#: ``--period N`` without ``--search-at``: search at this many grid speeds, evenly spread.
DEFAULT_SEARCH_POINTS = 5
#: ``--period N`` without ``--harmonics``: mesh harmonics (N H of the base ω/N) [-]; the
#: single-DOF pair's period-3 orbit agrees with time integration to 1e-6 at 9
#: (tests/test_orbit_search.py).
PERIOD_HARMONICS = 9
#: Columns of ``<out>_orbits.csv``.
ORBIT_COLUMNS = (
    "search at",
    "mesh_frequency [Hz]",
    "pinion_speed [rpm]",
    "period",
    "stable",
    "floquet_max [-]",
    "on the sweep",
    "dte_rms [um]",
    "force_max [N]",
    "dslr [-]",
    "amplitude [um]",
    "start",
)


def parse_search(args, values: np.ndarray) -> tuple[np.ndarray, tuple[int, ...]]:
    """``--search-at`` speeds (the unit of the range) and ``--search-periods``, checked.

    Parameters
    ----------
    args : argparse.Namespace
        ``search_at`` (comma-separated numbers) and ``search_periods``.
    values : ndarray
        The sweep's grid, in the same unit.

    Returns
    -------
    (ndarray, tuple of int)
        The speeds and the periods.

    Raises
    ------
    ModelError
        Not numbers, outside the sweep's range, or periods not whole numbers 1-6.
    """
    try:
        at = np.array([float(t) for t in str(args.search_at).split(",")])
    except ValueError:
        raise ModelError("--search-at", f"comma-separated numbers, got {args.search_at!r}") from None
    lo, hi = float(np.min(values)), float(np.max(values))
    if not np.all(np.isfinite(at)) or np.any(at < lo) or np.any(at > hi):
        raise ModelError(
            "--search-at", f"speeds within the sweep's range {lo:g}-{hi:g}, got {args.search_at!r}"
        )
    text = DEFAULT_PERIODS if args.search_periods is None else args.search_periods
    try:
        periods = tuple(int(t) for t in str(text).split(","))
    except ValueError:
        raise ModelError("--search-periods", f"comma-separated whole numbers, got {text!r}") from None
    if any(not 1 <= p <= MAX_PERIOD for p in periods):
        raise ModelError("--search-periods", f"periods from 1 to {MAX_PERIOD}, got {text!r}")
    return at, periods


def search_command(model, res, omegas, at, periods, unit) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Search at each speed, print what was found, follow the new stable orbits.

    Parameters
    ----------
    model : GearedModel
        The sweep's model.
    res : GearedSweepResult
        The sweep.
    omegas : ndarray
        The sweep's mesh frequencies [rad/s].
    at : ndarray
        Search speeds, in the unit of ``unit``.
    periods : tuple of int
        Periods sought [mesh periods].
    unit : callable
        Mesh frequency [rad/s] to text in the range's unit; ``unit.omega`` the inverse.

    Returns
    -------
    (DataFrame, DataFrame)
        The orbits found, and the followed branches (columns of
        :meth:`SweepResult.to_frame` with "branch" and the pinion speed).
    """
    from nlgrd.nonlinear.models.geared import geared_model_of

    H = res.mesh.H

    def on_sweep(o, w: float, branches) -> bool:
        here = np.nonzero(
            np.isclose(res.mesh.omega, w, rtol=1e-12) & res.mesh.converged & ~res.mesh.no_stable
        )[0]
        return o.metrics is not None and any(
            int(res.mesh.period[i]) == o.period
            and np.isclose(res.mesh.metrics["dte_rms"][i], o.metrics.dte_rms, rtol=1e-6)
            and np.isclose(res.mesh.metrics["force_max"][i], o.metrics.force_max, rtol=1e-6)
            for i in here
        )

    orbits, branches, _ = search_and_follow(
        geared_model_of(model),
        omegas,
        at,
        periods,
        H,
        unit,
        on_sweep,
        "the sweep's",
        GearOrbits(model.pinion_rpm),
    )
    if orbits.empty:
        print("orbit search: nothing converged at the speeds given")
    return orbits, branches


class GearOrbits:
    """What :func:`search_and_follow` writes of a geared model's orbits: the mesh frequency,
    the pinion speed and the first mesh's outputs (:data:`ORBIT_COLUMNS`).

    Parameters
    ----------
    pinion_rpm : callable
        Mesh frequency [rad/s] to pinion speed [rpm] (``GearedModel.pinion_rpm``).
    """

    columns = ORBIT_COLUMNS

    def __init__(self, pinion_rpm):
        self.pinion_rpm = pinion_rpm

    def row(self, o) -> dict:
        m = o.metrics
        return {
            "mesh_frequency [Hz]": o.omega / (2 * np.pi),
            "pinion_speed [rpm]": float(self.pinion_rpm(o.omega)),
            "dte_rms [um]": np.nan if m is None else m.dte_rms * 1e6,
            "force_max [N]": np.nan if m is None else m.force_max,
            "dslr [-]": np.nan if m is None else m.dslr,
        }

    def text(self, row: dict) -> str:
        return f"RMS DTE {row['dte_rms [um]']:.4g} um"

    def frame(self, branch) -> pd.DataFrame:
        f = branch.to_frame()
        f.insert(0, "pinion_speed [rpm]", self.pinion_rpm(branch.omega))
        return f


def search_and_follow(model_of, omegas, at, periods, H, unit, known, words, view, every=False):
    """Search at each speed, print each orbit, follow the stable ones (``every``: all) that
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
        Frequency [rad/s] to text in the range's unit; ``unit.omega`` the inverse.
    known : callable
        ``known(orbit, omega, followed)``: whether the sweep (or a branch already followed) has it.
    words : str
        How a known orbit is described in the printed line.
    view : GearOrbits or nlgrd.cli.link_sweep.LinkOrbits
        Each orbit's and branch's columns.
    every : bool
        The ``--period N`` search: follow unstable orbits too, period-N orbits only (one of a
        shorter minimal period is dropped: ``model_of`` gives the period-N model alone).

    Returns
    -------
    (DataFrame, DataFrame, list)
        The orbits found, the followed branches, and (label, result) per branch.
    """
    from nlgrd.nonlinear.tracing.orbit_search import follow_orbit, search_orbits

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
            print(
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
                print(f"  followed: period {o.period} {reach}, {int(branch.stable.sum())} stable points")
    orbits = pd.DataFrame(rows, columns=list(view.columns))
    branches = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=["branch"])
    return orbits, branches, followed


def parse_period(text: str) -> str | int:
    """The ``--period`` option: "auto" or a whole number of mesh periods from 1 to :data:`MAX_PERIOD`.

    Parameters
    ----------
    text : str
        The option's value.

    Returns
    -------
    str or int
        "auto", or the period [mesh periods].

    Raises
    ------
    ModelError
        Anything else.
    """
    if text == "auto":
        return text
    try:
        nu = int(text)
    except ValueError:
        nu = 0
    if not 1 <= nu <= MAX_PERIOD or str(nu) != str(text).strip():
        raise ModelError(
            "--period", f"auto or a whole number of mesh periods 1 to {MAX_PERIOD}, got {text!r}"
        )
    return nu


def none_of(period: str) -> str:
    """What a sweep where no point converged means for ``--period`` (appended to its line).

    Parameters
    ----------
    period : str
        The ``--period`` option as given.

    Returns
    -------
    str
        The explanation, or "".
    """
    if str(period).strip() == "2":
        return ": no period-2 orbit in the range (period-2 branches exist only beyond a period doubling)"
    return ""


def default_search(values: np.ndarray, count: int = DEFAULT_SEARCH_POINTS) -> np.ndarray:
    """Speeds of the grid at which ``--period N`` searches without ``--search-at``.

    Parameters
    ----------
    values : ndarray
        The sweep's grid (the range's unit).
    count : int
        How many, evenly spread from the lowest to the highest [-].

    Returns
    -------
    ndarray
        ``count`` grid values (all when the grid has fewer), ascending.
    """
    grid = np.unique(np.asarray(values, dtype=float))
    return grid[np.unique(np.round(np.linspace(0, grid.size - 1, min(count, grid.size))).astype(int))]


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


def period_search(model, omegas, at, nu: int, H: int, unit, directions: str):
    """``--period N``: search at ``at`` for period-ν orbits, follow each new one over the grid
    and merge the branches into one response per grid point and direction (module notes).

    Parameters
    ----------
    model : GearedModel
        The period-ν model (``build_geared_model(..., period=nu)`` with ν H harmonics).
    omegas : ndarray
        The grid's mesh frequencies [rad/s].
    at : ndarray
        Search speeds, in the unit of ``unit``.
    nu : int
        The period ν [mesh periods].
    H : int
        Mesh harmonics (ν H of the base) [-].
    unit : callable
        Mesh frequency [rad/s] to text in the range's unit; ``unit.omega`` the inverse.
    directions : {"both", "up", "down"}
        Sweep directions of the response.

    Returns
    -------
    (GearedSweepResult or None, DataFrame, DataFrame)
        The response (None when no period-ν orbit was found), the orbits found and the
        followed branches (as :func:`search_command`'s).
    """
    from nlgrd.nonlinear.models.geared import GearedSweepResult, build_geared_model
    from nlgrd.nonlinear.results.bearing_loads import bearing_names, bearing_response

    def fine_of(H_check: int):
        return model.cache.get(
            ("period", nu, nu * H_check),
            lambda: build_geared_model(
                model.system,
                model.max_mesh_frequency,
                nu * H_check,
                model.receptance.requested_method,
                period=nu,
            ),
        ).reduced

    res, orbits, frames = period_response(
        lambda _: model.reduced, fine_of, omegas, at, nu, H, unit, directions, GearOrbits(model.pinion_rpm)
    )
    if res is None:
        return None, orbits, frames
    on_base = dc.replace(res, omega=res.omega / nu)  # the frequencies the model's receptances take
    names = bearing_names(model.system)
    out = GearedSweepResult(res, bearing_response(model, on_base), model.pinion_rpm(res.omega), names, H)
    return out, orbits, frames


def period_response(model_of, fine_of, omegas, at, nu: int, H: int, unit, directions: str, view):
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
    view : GearOrbits or nlgrd.cli.link_sweep.LinkOrbits
        Each orbit's and branch's columns.

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
