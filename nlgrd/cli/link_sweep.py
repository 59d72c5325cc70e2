"""``nlgrd sweep`` of a model with several gear meshes, bearing clearances or unbalance: a link sweep
(:func:`nlgrd.nonlinear.models.link_model.link_sweep`), every link's outputs in columns
``<link>.<quantity>``, each point's period, ω/2 content and bifurcations as on the one-mesh
path (``--period``), and a figure of one of them."""

from __future__ import annotations

import math
import sys

import numpy as np
import pandas as pd

from nlgrd.errors import ModelError
from nlgrd.io.command_line import Outputs, harmonics_line, snap_to_grid
from nlgrd.nonlinear.models.link_model import needs_links

__all__ = [
    "LinkOrbits",
    "link_period_response",
    "link_quantity",
    "link_search",
    "link_sweep_command",
    "needs_links",
    "time_answers",
]


def link_quantity(text: str | None, model) -> tuple[str, str]:
    """``--quantity`` for a link model: ``LINK.QUANTITY`` or a bare quantity of the first
    link that has it (None: a mesh's DSLR, else the first link's largest force).

    Parameters
    ----------
    text : str or None
        The option as given.
    model : LinkModel
        The model whose links are asked.

    Returns
    -------
    (str, str)
        The column ``<link>.<quantity> [unit]`` and its label.
    """
    from nlgrd.nonlinear.links.contract import GearMeshLink
    from nlgrd.nonlinear.results.link_results import output_names

    keys: dict[str, list[str]] = {}  # every link's and linear bearing's outputs, by name
    for column in output_names(model):
        name, _, q = column.partition(".")
        keys.setdefault(name, []).append(q)
    if text is None:  # the default: a mesh's DSLR, else the first link's largest force
        has_dslr = any(isinstance(lk, GearMeshLink) for lk in model.links)
        text = "dslr" if has_dslr else f"{model.links[0].name}.force_max"
    name, _, q = text.rpartition(".")
    if not name:
        meshes = [lk.name for lk in model.links if isinstance(lk, GearMeshLink)]
        order = meshes + [lk.name for lk in model.links if lk.name not in meshes]
        name = next((n for n in order if any(k.split(" ")[0] == q for k in keys[n])), "")
    if name not in keys:
        raise ModelError("--quantity", f"no link {name or text!r}; links: {', '.join(keys)}")
    match = [k for k in keys[name] if k.split(" ")[0] == q]
    if not match:
        quantities = ", ".join(k.split(" ")[0] for k in keys[name])
        raise ModelError("--quantity", f"link {name!r} has no {q!r}; it has {quantities}")
    return f"{name}.{match[0]}", f"{name}: {match[0]}"


def time_answers(args, system, res, period, model=None):
    """``res`` with its points without a stable periodic response answered in the time
    domain (:func:`nlgrd.timedomain.sweep_answers.answer_sweep`), unless
    ``--no-time-domain``, ``--no-stability`` or a ``--period`` other than auto.

    Parameters
    ----------
    args : argparse.Namespace
        The options of ``nlgrd sweep``.
    system : RotorSystem
        The model.
    res : GearedSweepResult or LinkSweepResult
        The sweep.
    period : int or str
        The parsed ``--period``.
    model : LinkModel, optional
        The link model (built from ``system`` when None).

    Returns
    -------
    GearedSweepResult or LinkSweepResult

    Raises
    ------
    ModelError
        ``--time-periods`` below 80 (also where the rule does not apply).
    """
    cap = getattr(args, "time_periods", None)
    if cap is not None and cap < 80:  # a bad value is reported even where unused
        raise ModelError("--time-periods", f"must be at least 80, got {cap}")
    from nlgrd.io.command_line import ProgressBar
    from nlgrd.timedomain.sweep_answers import answer_sweep

    periods = {} if cap is None else {"periods": min(512, int(cap)), "max_periods": int(cap)}
    return answer_sweep(
        res,
        system=system,
        model=model,
        period=period,
        stability=not args.no_stability,
        time_domain=not args.no_time_domain,
        progress=ProgressBar("time domain"),
        **periods,
    )


def link_sweep_command(args, system, values, out, png, search=None, unit_of=None) -> int:
    """Run ``nlgrd sweep`` on a link model; write the CSV and PNG; print a summary.

    Parameters
    ----------
    args : argparse.Namespace
        The options of ``nlgrd sweep``.
    system : RotorSystem
        The model (several meshes, a bearing clearance or an unbalance, which
        :func:`~nlgrd.nonlinear.models.link_model.build_link_model` takes from it).
    values : ndarray
        The range: shaft speeds [rpm] (``--rpm``) or base frequencies [Hz] (``--hz``).
    out, png : Path
        The output files.
    search : (ndarray, tuple of int), optional
        ``--search-at`` speeds (the range's unit) and periods: :func:`link_search`.
    unit_of : callable, optional
        The frequency plan -> the range's unit (``omega``, ``name``, called for text); needed
        with ``search``.

    Returns
    -------
    int
        0, or 1 when no point converged.
    """
    from nlgrd.cli.orbits import none_of, parse_period
    from nlgrd.io.command_line import ProgressBar, pyplot
    from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep

    model = build_link_model(system)
    plan = model.receptance.plan
    if args.rpm is not None:
        omegas = np.asarray(values, dtype=float) * math.pi / 30 / plan.speed_per_base
    else:
        omegas = 2 * math.pi * np.asarray(values, dtype=float)
    column, label = link_quantity(args.quantity, model)
    period, found = parse_period(args.period), None
    if period != "auto" and period >= 3:  # searched, followed and merged (search: its speeds)
        res, found = link_period_response(
            model, omegas, search[0], period, args.harmonics, args.direction, unit_of(plan), column
        )
        if res is None:
            where = ", ".join(f"{v:g}" for v in search[0]) + f" {unit_of(plan).name}"
            print(
                f"nlgrd: error: no period-{period} orbit found at {where}; nothing written: try other "
                "--search-at speeds",
                file=sys.stderr,
            )
            return 1
        search = None  # the period-N orbits are the response
    else:
        res = link_sweep(
            model,
            omegas,
            H=args.harmonics,
            directions=args.direction,
            stability=not args.no_stability,
            period=period,
            progress=ProgressBar("sweep"),
        )
        res = time_answers(args, system, res, period, model)
    H = res.result.H  # of the base frequency, whatever the period of the points (as the CSV's H)
    frame = res.to_frame()
    frame.insert(1, "shaft_speed [rpm]", frame["base_frequency [Hz]"] * plan.speed_per_base * 60)
    x_col = "shaft_speed [rpm]" if args.rpm is not None else "base_frequency [Hz]"
    snap_to_grid(frame, x_col, values)  # the speeds as typed, not their round trip through rad/s
    if search is not None:
        found = link_search(model, res, omegas, *search, unit_of(plan), column)
    pyplot()
    from nlgrd.plotting.sweep_figures import plot_link_sweep

    title = f"{(system.name or 'model')[:60]}\nbase frequency: {plan.name}, H = {H}"
    fig = plot_link_sweep(frame, x_col, column, title, None if found is None else found[1]).figure
    names = ("orbits", "branches") if found is not None else ()
    beside = [(out.with_name(f"{out.stem}_{n}.csv"), f) for n, f in zip(names, found or (), strict=True)]
    with Outputs() as files:
        files.csv(frame, out)
        for path, table in beside:
            snap_to_grid(table, x_col, values)
            files.csv(table, path)
        files.figure(fig, png)
        files.commit()
    r = res.result
    bad = int(np.sum(~r.converged))
    answered = int(np.sum(r.time_answered))
    tori = int(np.sum(r.time_answered & (np.asarray(r.time_kind, dtype=object) == "quasi-periodic")))
    lost = int(np.sum(np.asarray(r.no_stable, dtype=bool))) - answered
    print(
        f"sweep: {len(r)} points ({args.direction}), links {', '.join(lk.name for lk in model.links)}, "
        f"base frequency = {plan.name} ({1 / plan.speed_per_base:.6g} x the shaft speed), "
        f"{harmonics_line(r)}, "
        f"{bad} not converged, {lost} without a stable periodic response, {tori} answered by the "
        f"torus harmonic balance, {answered - tori} answered in the time domain"
    )
    _periods(r, unit=(60 * plan.speed_per_base, "rpm") if args.rpm is not None else (1.0, "Hz"))
    print(f"wrote {out} and {png}" + "".join(f", {path}" for path, _ in beside))
    if bad == len(r):
        print(f"nlgrd: error: no point of the sweep converged{none_of(args.period)}", file=sys.stderr)
        return 1
    return 0


def _periods(r, unit: tuple[float, str]) -> None:
    """Print the period-2 points, the quasi-periodic ones and the bifurcations along each
    sweep (:func:`nlgrd.nonlinear.tracing.auto_period.transitions`), in the range's unit."""
    import numpy as np

    from nlgrd.nonlinear.tracing.auto_period import transitions

    scale, name = unit

    def show(w) -> str:
        return f"{w / (2 * np.pi) * scale:.1f}"

    two = r.omega[(r.period == 2) & ~r.no_stable & r.converged]
    if two.size:
        print(f"period 2 (period doubled) at {name}: " + ", ".join(show(w) for w in two))
    solved = r.time_answered & (np.asarray(r.time_kind, dtype=object) == "quasi-periodic")
    for torus, what in (
        (np.isfinite(r.secondary_frequency) & ~solved, "NaN outputs"),
        (solved, "answered by the torus harmonic balance"),
    ):
        if np.any(torus):
            print(
                f"quasi-periodic (a complex pair of multipliers left the unit circle; {what}) at {name} "
                "(secondary frequency Hz): "
                + ", ".join(
                    f"{show(w)} ({f / (2 * np.pi):.0f})"
                    for w, f in zip(r.omega[torus], r.secondary_frequency[torus], strict=True)
                )
            )
    for t in transitions(r):
        print(
            f"{t.kind} ({t.direction}): {show(t.omega_from)} -> {show(t.omega_to)} {name}, "
            f"{t.response_from} -> {t.response_to}"
        )


class LinkOrbits:
    """What :func:`nlgrd.cli.orbits.search_and_follow` writes of a link model's orbits: the
    base frequency, the reference shaft speed and every link's outputs over the orbit's
    whole period (as :func:`~nlgrd.nonlinear.models.link_model.link_sweep`'s columns).

    Parameters
    ----------
    model : LinkModel
        The sweep's model.
    column : str
        The ``--quantity`` column drawn.
    """

    def __init__(self, model, column: str):
        from nlgrd.nonlinear.results.link_results import output_names

        self.model, self.column = model, column
        self.per_base = model.receptance.plan.speed_per_base * 60  # [rpm per Hz of the base]
        self.outputs = output_names(model)
        self.columns = (
            "search at",
            "base_frequency [Hz]",
            "shaft_speed [rpm]",
            "period",
            "stable",
            "floquet_max [-]",
            "on the sweep",
            *self.outputs,
            "amplitude [um]",
            "start",
        )

    def period(self, nu: int):
        """The period-ν model (:func:`~nlgrd.nonlinear.models.link_model.period_model`)."""
        from nlgrd.nonlinear.models.link_model import period_model

        return period_model(self.model, nu)

    def values(self, harmonics, omega: float, nu: int) -> dict:
        """Every link's and bearing's outputs of an orbit of ν base periods at the base
        frequency ω [rad/s]."""
        from nlgrd.nonlinear.results.link_results import point_outputs

        return point_outputs(self.period(nu), harmonics, omega / nu)

    def row(self, o) -> dict:
        hz = o.omega / (2 * np.pi)
        return {
            "base_frequency [Hz]": hz,
            "shaft_speed [rpm]": hz * self.per_base,
            **self.values(o.harmonics, o.omega, o.period),
        }

    def text(self, row: dict) -> str:
        return f"{self.column} {row[self.column]:.4g}"

    def result(self, branch):
        """``branch`` (one period) with every link's outputs where it is the response: a
        :class:`~nlgrd.nonlinear.results.link_results.LinkSweepResult`."""
        from nlgrd.nonlinear.results.link_results import LinkSweepResult, bearing_columns

        nu = int(branch.period[0]) if len(branch) else 1
        usable = branch.converged & ~np.asarray(branch.no_stable, dtype=bool)
        blank = dict.fromkeys(self.outputs, np.nan)
        rows = [
            self.values(branch.harmonics[i], float(branch.omega[i]), nu) if usable[i] else blank
            for i in range(len(branch))
        ]
        return LinkSweepResult(branch, pd.DataFrame(rows, columns=self.outputs), bearing_columns(self.model))

    def frame(self, branch) -> pd.DataFrame:
        f = self.result(branch).to_frame()
        f.insert(0, "shaft_speed [rpm]", f["base_frequency [Hz]"] * self.per_base)
        return f

    def model_of(self, H: int, top: float):
        """``model_of(nu)`` for :func:`nlgrd.cli.orbits.search_and_follow`: the period-ν
        reduced model, its basis serving H harmonics of the base up to ``top`` [rad/s]."""

        def model_of(nu: int):
            m = self.period(nu)
            m.receptance.prepare(H * top)  # a modal basis (large models) serving νH harmonics of ω/ν
            return m.reduced

        return model_of


def link_search(model, res, omegas, at, periods, unit, column: str):
    """``--search-at`` on a link model: search at each speed, print what was found, follow
    the stable orbits the sweep does not have over its grid
    (:func:`nlgrd.cli.orbits.search_and_follow` with :class:`LinkOrbits`).

    Parameters
    ----------
    model : LinkModel
        The sweep's model.
    res : LinkSweepResult
        The sweep.
    omegas : ndarray
        The sweep's base frequencies [rad/s].
    at : ndarray
        Search speeds, in the unit of ``unit``.
    periods : tuple of int
        Periods sought [base periods].
    unit : callable
        Base frequency [rad/s] to text in the range's unit; ``unit.omega`` the inverse.
    column : str
        The ``--quantity`` column, printed for each orbit.

    Returns
    -------
    (DataFrame, DataFrame)
        The orbits found and the followed branches.
    """
    from nlgrd.cli.orbits import search_and_follow

    r, view = res.result, LinkOrbits(model, column)
    H = r.H
    model_of = view.model_of(H, float(np.max(omegas)))

    def on_sweep(o, w: float, branches) -> bool:
        here = np.nonzero(
            np.isclose(r.omega, w, rtol=1e-12) & r.converged & ~np.asarray(r.no_stable, dtype=bool)
        )[0]
        mine = view.values(o.harmonics, o.omega, o.period)
        return any(
            int(r.period[i]) == o.period
            and all(np.isclose(res.links[k].iloc[i], v, rtol=1e-6, atol=0) for k, v in mine.items())
            for i in here
        )

    orbits, branches, _ = search_and_follow(
        model_of, omegas, at, periods, H, unit, on_sweep, "the sweep's", view
    )
    if orbits.empty:
        print("orbit search: nothing converged at the speeds given")
    return orbits, branches


def link_period_response(model, omegas, at, nu: int, H: int | None, directions: str, unit, column: str):
    """``--period N`` (N >= 3) on a link model: period-N orbits searched at ``at``, each new
    one followed over the grid, the branches merged into one response per grid point and
    direction (:func:`nlgrd.cli.orbits.merge_branches`), its harmonic error estimated at
    the next rung, as :func:`nlgrd.cli.orbits.period_search` does for one mesh.

    Parameters
    ----------
    model : LinkModel
        The sweep's model.
    omegas : ndarray
        The grid's base frequencies [rad/s].
    at : ndarray
        Search speeds, in the unit of ``unit``.
    nu : int
        The period sought [base periods].
    H : int or None
        Harmonics of the base (ν H of ω/ν); None: :data:`nlgrd.cli.orbits.PERIOD_HARMONICS`.
    directions : {"both", "up", "down"}
        Sweep directions of the response.
    unit : callable
        Base frequency [rad/s] to text in the range's unit; ``unit.omega`` the inverse.
    column : str
        The ``--quantity`` column, printed for each orbit.

    Returns
    -------
    (LinkSweepResult or None, (DataFrame, DataFrame))
        The response (None when no period-ν orbit was found), the orbits found and the
        followed branches.
    """
    from nlgrd.cli.orbits import PERIOD_HARMONICS, period_response
    from nlgrd.nonlinear.tracing.orbit_search import N_STARTS

    H = H or PERIOD_HARMONICS
    view, top = LinkOrbits(model, column), float(np.max(omegas))
    where = ", ".join(f"{v:g}" for v in at) + f" {unit.name}"
    print(f"period {nu}: searching at {where} ({N_STARTS} starts each, H = {H})")
    res, orbits, frames = period_response(
        view.model_of(H, top),
        lambda H_check: view.model_of(H_check, top)(nu),
        omegas,
        at,
        nu,
        H,
        unit,
        directions,
        view,
    )
    return (None if res is None else view.result(res)), (orbits, frames)
