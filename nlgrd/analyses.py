"""The analyses of any model, as ``import nlgrd`` gives them: load a model file, its modes
and Campbell diagram, and the nonlinear response (harmonic-balance sweeps, continuation,
orbit search, time-domain sweeps) of a model with one gear mesh or several, with or
without bearing clearances and unbalance.

Speeds are given once, in the unit the user has: ``rpm`` (the reference shaft, speed
ratio 1) or ``hz`` (the base frequency of the model's frequency plan: the mesh frequency
for one mesh, :class:`~nlgrd.nonlinear.links.frequency_plan.FrequencyPlan`). Each function
builds the link model (:func:`model`: every model, one mesh too, reduced onto all its
link coordinates) and calls the link engine's analysis; the result is the library's
result object, with ``to_frame()``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.tracing.period_branches import PERIOD_HARMONICS
from nlgrd.rotor.system import RotorSystem

__all__ = ["campbell", "continuation", "load", "model", "modes", "search_orbits", "sweep", "time_sweep"]

#: Mesh harmonics of an orbit search without ``H`` (the CLI's ``--period N`` default) [-].
SEARCH_HARMONICS = PERIOD_HARMONICS


def load(path: str | os.PathLike) -> RotorSystem:
    """Read a TOML model file (:func:`nlgrd.io.model_file.load_model`).

    Parameters
    ----------
    path : str or path-like
        The model file.

    Returns
    -------
    RotorSystem
    """
    from nlgrd.io.model_file import load_model

    return load_model(path)


def modes(system: RotorSystem, rpm: float = 0.0, n_modes: int = 20, damped: bool = True):
    """Modes at reference shaft speed ``rpm`` (:func:`nlgrd.rotor.modal.modal_analysis`).

    Parameters
    ----------
    system : RotorSystem
        The model; gear meshes at their average stiffness.
    rpm : float
        Reference shaft speed [rpm].
    n_modes : int
        Flexible modes returned [-].
    damped : bool
        Complex modes with damping and gyroscopics (True) or real undamped modes.

    Returns
    -------
    ModalResult
    """
    from nlgrd.rotor.modal import modal_analysis

    return modal_analysis(system, rpm * math.pi / 30, n_modes=n_modes, damped=damped)


def campbell(system: RotorSystem, rpm: ArrayLike, n_modes: int = 10, orders: dict[str, float] | None = None):
    """Campbell diagram over reference shaft speeds ``rpm`` (:func:`nlgrd.rotor.modal.campbell`).

    Parameters
    ----------
    system : RotorSystem
        The model.
    rpm : array_like
        Reference shaft speeds [rpm].
    n_modes : int
        Modes followed [-].
    orders : dict, optional
        Excitation orders per unit shaft speed, e.g. ``{"1x": 1, "mesh": 25}``.

    Returns
    -------
    CampbellResult
    """
    from nlgrd.rotor.modal import campbell as campbell_diagram

    speeds = np.asarray(rpm, dtype=float) * math.pi / 30
    return campbell_diagram(system, speeds, n_modes=n_modes, orders=orders)


def model(system: RotorSystem):
    """The reduced harmonic-balance model of ``system``: every model, one mesh or many, with
    or without clearances and unbalance, reduced onto all its link coordinates on its
    frequency plan (:func:`nlgrd.nonlinear.models.link_model.build_link_model`: the mesh
    frequency for one mesh excited at its mesh period, the error period's base when its
    teeth differ, the shaft speed without gears); its κ_k equal dense solves of the
    full model to 1e-9 (tests/test_link_receptance.py).

    Parameters
    ----------
    system : RotorSystem
        The model.

    Returns
    -------
    LinkModel
    """
    from nlgrd.nonlinear.models.link_model import build_link_model

    return build_link_model(system)


build_model = model


def _speed_per_base(system: RotorSystem) -> float:
    from nlgrd.nonlinear.links.frequency_plan import FrequencyPlan

    return FrequencyPlan.of_model(system).speed_per_base


def _with_speed(result, system: RotorSystem, rpm):
    """``result`` whose table has the reference shaft's speed [rpm] beside the base
    frequency, first when the speeds were given in rpm."""
    import dataclasses

    return dataclasses.replace(
        result, speed_per_base=_speed_per_base(system), speed_unit="Hz" if rpm is None else "rpm"
    )


def _omegas(system: RotorSystem, rpm, hz, name: str = "rpm") -> NDArray:
    """Base frequencies [rad/s] from reference shaft speeds [rpm] or base frequencies [Hz],
    their top checked (:func:`~nlgrd.io.model_checks.check_speed_range`)."""
    from nlgrd.io.model_checks import check_speed_range

    if (rpm is None) == (hz is None):
        raise ModelError(name, "give the speeds either as rpm (reference shaft) or as hz (base frequency)")
    if hz is not None:
        omegas = 2 * math.pi * np.atleast_1d(np.asarray(hz, dtype=float))
    else:
        omegas = np.atleast_1d(np.asarray(rpm, dtype=float)) * math.pi / 30 / _speed_per_base(system)
    key = name if rpm is not None else "hz"
    if omegas.ndim != 1 or omegas.size < 1 or not np.all(np.isfinite(omegas)) or np.any(omegas <= 0):
        raise ModelError(key, "must be positive finite speeds")
    top = float(np.max(rpm if rpm is not None else hz))  # as the CLI and a study check theirs
    check_speed_range(system, top, rpm is not None, key, f"{top:g} {'rpm' if rpm is not None else 'Hz'}")
    return omegas


def sweep(
    system: RotorSystem,
    *,
    rpm: ArrayLike | None = None,
    hz: ArrayLike | None = None,
    H: int | None = None,
    directions: str = "both",
    period: int | str = "auto",
    stability: bool = True,
    progress: Callable[[int, int], None] | None = None,
    time_domain: bool = True,
    time_options: dict | None = None,
    coexisting: bool = False,
    coexisting_progress: Callable[[int, int], None] | None = None,
    **options,
):
    """Up and/or down harmonic-balance sweep of any model.

    Parameters
    ----------
    system : RotorSystem or ReducedModel
        The model (one mesh or several, clearances, unbalance), or a model built from
        matrices (:class:`~nlgrd.nonlinear.hb.harmonic_balance.ReducedModel`: speeds as
        ``hz``, period 1, H chosen on the library's ladder, no time-domain answers; its
        outputs ``model.<quantity> [unit]``, its first law's).
    rpm, hz : array_like
        Reference shaft speeds [rpm] or base frequencies [Hz]; one of them.
    H : int, optional
        Harmonics of the base frequency [-]; default chosen by the error estimate.
    directions : {"both", "up", "down"}
    period : {"auto", 1, 2}
        "auto": period 1 where it is stable, the period-2 orbit where it lost stability
        by period doubling.
    stability : bool
        Floquet stability of each point.
    progress : callable, optional
        ``progress(i, n)`` once per point.
    time_domain : bool
        With ``period`` "auto" and stability: every point without a stable periodic
        response answered (:func:`nlgrd.timedomain.sweep_answers.answer_sweep`): a
        Neimark-Sacker point by the torus harmonic balance where it converges
        (``response`` "quasi-periodic"), the others by time integration (``response``
        "time domain" or "chaotic", values with their uncertainty).
    time_options : dict, optional
        Options of :func:`nlgrd.timedomain.time_answer.time_answer` (``max_periods``, ...).
    coexisting : bool
        Also search for the period-1 branches that coexist with the sweep's beside its
        jumps (at most 4) and follow them over the grid
        (:func:`nlgrd.nonlinear.models.link_coexisting.with_coexisting`: minutes; needs
        ``stability``). The result's table gains a ``branch`` column and their rows, its
        ``bifurcations()`` their bifurcations, each ``confirmed`` on the exact flow or not.
    coexisting_progress : callable, optional
        ``coexisting_progress(i, n)`` per frequency searched at.
    **options
        Further options of :func:`nlgrd.nonlinear.models.link_model.link_sweep` and
        :func:`nlgrd.nonlinear.tracing.sweep.sweep` (``tol``, ``jump``, ...;
        ``harmonic_rtol`` is the ``rtol`` of the choice of H).

    Returns
    -------
    LinkSweepResult
        Every link's and linear bearing's outputs per point, with ``to_frame()``,
        ``jumps()`` and ``plot()``.
    """
    from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
    from nlgrd.nonlinear.models.link_model import link_sweep
    from nlgrd.nonlinear.tracing.harmonic_convergence import LADDER
    from nlgrd.timedomain.sweep_answers import answer_sweep

    _known_options(options)
    if coexisting and not stability:
        raise ModelError("coexisting", "the coexisting branches need stability: drop stability=False")
    if coexisting and period not in ("auto", 1):
        raise ModelError(
            "coexisting", f"searches period-1 orbits beside the sweep: give period auto or 1, got {period!r}"
        )
    if isinstance(system, ReducedModel):
        if period not in ("auto", 1):
            raise ModelError("period", f"a model built from matrices is swept at period 1, got {period!r}")
        return _matrix_sweep(
            system, hz, rpm, H, directions, stability, progress, coexisting, coexisting_progress, options
        )
    omegas = _omegas(system, rpm, hz)
    m = model(system)
    rtol = {"rtol": options.pop("harmonic_rtol")} if "harmonic_rtol" in options else {}
    kw = dict(directions=directions, stability=stability, progress=progress, period=period)
    res = link_sweep(m, omegas, H, **kw, **rtol, **options)
    if coexisting:
        from nlgrd.nonlinear.models.link_coexisting import with_coexisting

        ladder = [h * m.top_order for h in LADDER]
        found = with_coexisting(
            res, m.reduced, model=m, ladder=ladder, jumps=res.jumps(), progress=coexisting_progress
        )
    res = answer_sweep(
        res,
        system=system,
        model=m,
        period=period,
        stability=stability,
        time_domain=time_domain,
        **rtol,
        **(time_options or {}),
    )
    if coexisting:  # the branches beside the harmonic-balance sweep's jumps, kept
        import dataclasses

        res = dataclasses.replace(res, coexisting=found.coexisting, coexisting_note=found.coexisting_note)
    return _with_speed(res, system, rpm)


def _known_options(options: dict) -> None:
    """Raise ModelError naming the first of :func:`sweep`'s ``**options`` that no sweep
    function takes (a misspelt option would otherwise fail deep inside as a TypeError)."""
    import inspect

    from nlgrd.nonlinear.models.link_model import link_sweep
    from nlgrd.nonlinear.tracing import sweep as tracing
    from nlgrd.nonlinear.tracing.harmonic_convergence import converged_sweep

    known = {"harmonic_rtol"}
    for f in (link_sweep, converged_sweep, tracing.sweep):
        for name, p in inspect.signature(f).parameters.items():
            if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD):
                known.add(name)
    known -= {"model", "omegas", "H", "directions", "rtol", "period", "stability", "progress"}
    for name in options:
        if name not in known:
            raise ModelError(name, f"is not an option of nlgrd.sweep (options: {', '.join(sorted(known))})")


def _matrix_sweep(m, hz, rpm, H, directions, stability, progress, coexisting, coexisting_progress, options):
    """:func:`sweep` of a model built from matrices (a ReducedModel): period 1, no links."""
    from nlgrd.nonlinear.models.link_coexisting import metric_links, with_coexisting
    from nlgrd.nonlinear.results.link_results import LinkSweepResult
    from nlgrd.nonlinear.tracing.harmonic_convergence import converged_sweep
    from nlgrd.nonlinear.tracing.sweep import sweep as hb_sweep

    if rpm is not None or hz is None:
        raise ModelError("hz", "a model built from matrices has no shaft: give its base frequencies as hz")
    omegas = 2 * math.pi * np.atleast_1d(np.asarray(hz, dtype=float))
    if omegas.ndim != 1 or not np.all(np.isfinite(omegas)) or np.any(omegas <= 0):
        raise ModelError("hz", "must be positive finite frequencies")
    if "harmonic_rtol" in options:
        options["rtol"] = options.pop("harmonic_rtol")
    kw = dict(stability=stability, progress=progress, **options)
    if H is None:
        res = converged_sweep(m, omegas, directions, **kw)
    else:
        kw.pop("rtol", None)
        res = hb_sweep(m, omegas, int(H), directions, **kw)
    out = LinkSweepResult(res, metric_links(res, res.converged & ~np.asarray(res.no_stable, dtype=bool)))
    return with_coexisting(out, m, progress=coexisting_progress) if coexisting else out


def continuation(
    system: RotorSystem,
    *,
    rpm: tuple[float, float] | None = None,
    hz: tuple[float, float] | None = None,
    H: int | None = None,
    stability: bool = True,
    **options,
):
    """Pseudo-arc-length continuation of any model's response, unstable parts included.

    Parameters
    ----------
    system : RotorSystem
        The model.
    rpm, hz : (float, float)
        Start and end: reference shaft speeds [rpm] or base frequencies [Hz].
    H : int, optional
        Harmonics of the base [-]; default chosen by the error estimate.
    stability : bool
        Floquet stability of each point.
    **options
        Further options of :func:`nlgrd.nonlinear.tracing.continuation.continuation`.

    Returns
    -------
    LinkContinuationResult
        The curve with every link's outputs along it.
    """
    ends = _omegas(system, rpm, hz)
    if ends.size != 2:
        raise ModelError("rpm" if rpm is not None else "hz", "a continuation takes (start, end)")
    w0, w1 = (float(w) for w in ends)
    from nlgrd.nonlinear.models.link_model import link_continuation

    curve = link_continuation(model(system), w0, w1, H, stability=stability, **options)
    return _with_speed(curve, system, rpm)


def search_orbits(
    system: RotorSystem,
    *,
    rpm: float | None = None,
    hz: float | None = None,
    periods: tuple[int, ...] = (1, 2, 3),
    H: int = SEARCH_HARMONICS,
    **options,
):
    """Periodic orbits of the given periods at one speed, from many starts (orbits that no
    sweep reaches: isolated branches, subharmonics).

    Parameters
    ----------
    system : RotorSystem
        The model.
    rpm, hz : float
        The speed: reference shaft [rpm] or base frequency [Hz].
    periods : tuple of int
        Periods sought, in base periods [-].
    H : int
        Harmonics of the base per orbit (ν H of ω/ν for period ν) [-].
    **options
        Further options of :func:`nlgrd.nonlinear.tracing.orbit_search.search_orbits`.

    Returns
    -------
    list of FoundOrbit
    """
    from nlgrd.nonlinear.models.model_views import LinkView
    from nlgrd.nonlinear.tracing.orbit_search import search_orbits as search

    omega = float(_omegas(system, rpm, hz)[0])
    view = LinkView(model(system), None)
    options.setdefault("outputs", view.values)  # every link's columns in the table
    return search(view.model_of(int(H), omega), omega, int(H), periods, **options)


def time_sweep(
    system: RotorSystem,
    *,
    rpm: ArrayLike | None = None,
    hz: ArrayLike | None = None,
    directions: str = "both",
    H: int = 15,
    **options,
):
    """Time-domain sweep of any model, each speed continuing from the last: the
    independent reference of :func:`sweep` (HHT-α integration of the full model).

    Parameters
    ----------
    system : RotorSystem
        The model.
    rpm, hz : array_like
        Reference shaft speeds [rpm] or base frequencies [Hz].
    directions : {"both", "up", "down"}
    H : int
        Harmonics kept from each steady state's last period [-].
    **options
        Further options of the integrator (``steps_per_period``, ``tol``, ...).

    Returns
    -------
    LinkSweepResult
        Every link's and linear bearing's outputs, as :func:`sweep` has them.
    """
    from nlgrd.timedomain.links import link_time_sweep

    omegas = _omegas(system, rpm, hz)
    return _with_speed(link_time_sweep(model(system), omegas, directions, H=H, **options), system, rpm)
