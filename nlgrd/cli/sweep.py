"""The ``nlgrd sweep`` command: a harmonic-balance sweep (or continuation) of any model file,
written as a CSV table and a figure, with a summary; one flow for every model: its link
model (:func:`nlgrd.analyses.model`, one mesh too) behind the link view
(:class:`~nlgrd.nonlinear.models.model_views.LinkView`). The columns are
``<link>.<quantity> [unit]`` (:func:`link_quantity` reads ``--quantity``). A gear pair
whose errors repeat every N mesh periods (teeth that differ, runout) takes the same flow:
its plan's base is the mesh frequency / N, H counts harmonics of that base, ``--period``
counts mesh periods (auto, or a multiple of N up to 6), and the DTE and bearing-force spectra of the point
with the largest RMS DTE are drawn (:func:`_spectra`)."""

from __future__ import annotations

import math
import sys

from nlgrd.errors import ModelError
from nlgrd.io.command_line import (
    Outputs,
    ProgressBar,
    harmonics_line,
    output_file,
    parse_range,
    parse_span,
    pyplot,
    snap_to_grid,
)
from nlgrd.io.model_checks import check_harmonics_memory, check_speed_range
from nlgrd.nonlinear.results.response_kinds import QUASI_PERIODIC
from nlgrd.nonlinear.tracing.period_branches import PERIOD_HARMONICS
from nlgrd.units import floor_rounding, written_frame, written_name


class _Unit:
    """Mesh frequencies [rad/s] to and from the unit the range was given in (rpm or Hz)."""

    def __init__(
        self, rpm: bool, mesh_per_pinion: float, grid=None, *, speed="pinion speed", base="mesh frequency"
    ):
        self.name = "rpm" if rpm else "Hz"
        self.speed, self.base = speed, base
        self.column = f"{speed.replace(' ', '_')} [rpm]" if rpm else f"{base.replace(' ', '_')} [Hz]"
        self.grid = grid  # the values as given, written in place of their round trip
        # base (mesh) frequency [rad/s] per reference (pinion) speed [rad/s]: N_p |s_p|
        self.per_speed = mesh_per_pinion
        self.scale = mesh_per_pinion * math.pi / 30 if rpm else 2 * math.pi

    def omega(self, value):
        return value * self.scale

    def __call__(self, omega, digits: int = 1) -> str:
        return f"{omega / self.scale:.{digits}f}"

    @property
    def axis(self) -> tuple[str, float]:
        """The figures' abscissa: (label, value per mesh frequency [Hz])."""
        what = self.speed if self.name == "rpm" else self.base
        return f"{what} [{self.name}]", 2 * math.pi / self.scale


def _title(system, args) -> str:
    """The figures' title: the model's name (its file's when it has none)."""
    from pathlib import Path

    return (getattr(system, "name", None) or Path(args.model).stem)[:80]


def cmd_sweep(args) -> int:
    """Nonlinear harmonic-balance sweep (or continuation) of any model: CSV, PNG, summary.

    One flow for every model: the link model and its view
    (:class:`~nlgrd.nonlinear.models.model_views.LinkView`) do the work; the command
    parses, writes and prints.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options of ``nlgrd sweep`` (:func:`build_parser`).

    Returns
    -------
    int
        The exit status: 0 when done, 1 when a continuation did not cover the range.

    Raises
    ------
    ModelError
        For a bad option or model (:func:`main` prints it and exits with status 2).
    """
    import numpy as np

    from nlgrd.io.model_file import load_model

    if (args.rpm is None) == (args.hz is None):
        raise ModelError(
            "--rpm", "give the range as --rpm START:STOP:COUNT (pinion speed) or --hz (mesh frequency)"
        )
    option, text = ("--rpm", args.rpm) if args.rpm is not None else ("--hz", args.hz)
    if args.harmonics is not None and args.harmonics < 1:
        raise ModelError("--harmonics", f"must be at least 1, got {args.harmonics}")
    if args.continuation:
        start, stop, count = parse_span(text, option)
        values = np.array([start, stop])
    else:
        values, count = parse_range(text, option), None
    if np.any(values <= 0):
        raise ModelError(option, f"speeds and frequencies must be positive, got {text!r}")
    out = output_file("--out", args.out, "sweep.csv")
    png = output_file("--plot", args.plot, "sweep.png") if args.plot else out.with_suffix(".png")
    if png.resolve() == out.resolve():
        raise ModelError("--plot", f"the plot would overwrite the CSV {out}; give --out a .csv name")
    from nlgrd.cli.orbits import MAX_PERIOD, default_search, parse_period, parse_search

    period, search = parse_period(args.period), None
    if args.search_at is not None:
        if args.continuation:
            raise ModelError("--search-at", "searches beside a sweep, not a --continuation")
        search = parse_search(args, values)
    system = load_model(args.model)
    try:
        check_harmonics_memory(system, args.harmonics, "--harmonics")
    except ModelError as err:
        raise err.within(file=str(args.model)) from None
    if not system.gear_pairs and not system.bearing_clearances:
        raise ModelError("gear_pairs", "the model has no gear pair and no clearance", args.model)
    revolution = _revolution(system)
    if revolution > 1 and period != "auto":  # --period counts mesh periods: base periods here
        if period % revolution:
            multiple = "" if revolution > MAX_PERIOD else f" or a multiple of {revolution}"
            raise ModelError(
                "--period",
                f"the gear errors repeat every {revolution} mesh periods (the base frequency is the "
                f"mesh frequency / {revolution}): give auto{multiple}",
                args.model,
            )
        period //= revolution
    if search is not None and revolution > 1:
        raise ModelError(
            "--search-at",
            f"the orbit search is not offered where the errors repeat every {revolution} mesh "
            "periods (each start solves the whole revolution); sweep with --period auto",
            args.model,
        )
    if getattr(args, "coexisting", False):
        _check_coexisting_options(args, period)
    if period != "auto" and period >= 3:
        _check_period_options(args, period)
        search = (search[0] if search is not None else default_search(values), (period,))
    grid = None if args.continuation else values  # the values as typed, written in the CSV
    nu = period if period != "auto" and period >= 3 else 1  # --period N: searched and followed
    top, in_rpm = float(max(values)), args.rpm is not None
    check_speed_range(system, top, in_rpm, option, repr(text))
    pyplot()
    from types import SimpleNamespace

    from nlgrd.analyses import model as link_model
    from nlgrd.nonlinear.models.link_model import model_links
    from nlgrd.nonlinear.models.model_views import LinkView

    column = link_quantity(args.quantity, SimpleNamespace(system=system, links=model_links(system)))[0]
    model = link_model(system)
    per_base = model.receptance.plan.speed_per_base
    unit = _Unit(args.rpm is not None, 1 / per_base, grid, speed="shaft speed", base="base frequency")
    view = LinkView(model, column)
    quantity = view.column
    omegas = unit.omega(values)
    if not args.continuation:  # the grid as nlgrd.analyses.sweep makes it
        omegas = values * math.pi / 30 / per_base if args.rpm is not None else 2 * math.pi * values
    if nu > 1:
        return _period_command(args, system, view, omegas, unit, quantity, out, png, search)
    if args.continuation:
        return _continuation(args, system, view, unit, omegas, count, quantity, out, png)
    res = view.sweep(
        omegas, args.harmonics, args.direction, not args.no_stability, period, ProgressBar("sweep")
    )
    beside = _coexisting(model, res) if getattr(args, "coexisting", False) else None
    res = time_answers(args, system, res, period, view.time_model())
    if beside is not None:  # the branches beside the harmonic-balance sweep's jumps
        import dataclasses

        res = dataclasses.replace(res, coexisting=beside.coexisting, coexisting_note=beside.coexisting_note)
    found = None
    if search is not None:
        from nlgrd.nonlinear.models.model_views import search_beside

        found = search_beside(view, res, omegas, *search, unit, print)
    extra, more = (
        (_spectra(model, res, quantity, unit, out), _sidebands(model, res))
        if revolution > 1
        else (None, None)
    )
    _write_sweep(
        view, res, quantity, out, png, extra, found=found, unit=unit, title=_title(system, args), more=more
    )
    if extra is not None:
        print(f"wrote {extra[1]}")
    if res.coexisting is not None:
        _coexisting_summary(res, unit, out)
    return _summary(args, view, res, unit, out, png, found is not None)


def _check_coexisting_options(args, period) -> None:
    """``--coexisting`` searches period-1 orbits beside a sweep's jumps: a sweep with stability."""
    if args.continuation:
        raise ModelError("--coexisting", "searches beside a sweep's jumps, not a --continuation")
    if args.no_stability:
        raise ModelError(
            "--coexisting", "the coexisting branches need their Floquet stability: drop --no-stability"
        )
    if period not in ("auto", 1):
        raise ModelError(
            "--coexisting", f"searches mesh-periodic orbits: give --period auto or 1, got {period}"
        )


def _coexisting(model, res):
    """``res`` with its coexisting branches
    (:func:`~nlgrd.nonlinear.models.link_coexisting.with_coexisting`)."""
    from nlgrd.nonlinear.models.link_coexisting import with_coexisting
    from nlgrd.nonlinear.tracing.harmonic_convergence import LADDER

    return with_coexisting(
        res,
        model.reduced,
        model=model,
        ladder=[h * model.top_order for h in LADDER],
        jumps=res.jumps(),
        progress=ProgressBar("coexisting: searches"),
        locate_progress=ProgressBar("coexisting: bifurcations"),
    )


def _coexisting_summary(res, unit, out) -> None:
    """One line on the coexisting branches (how many, their ranges, their bifurcations), the
    note where the model cannot be shot, and the bifurcations' table written."""
    parts = []
    for b in res.coexisting:
        span = b.span()
        where = f"{unit(span[0])}-{unit(span[1])} {unit.name}" if span else "no converged point"
        n, sure = len(b.bifurcations), sum(f.confirmed for f in b.bifurcations)
        parts.append(f"{b.name} {where} ({n} bifurcations, {sure} confirmed)")
    jumps = "" if res.jumps() else " (the sweep has no jump to search beside)"
    print(f"coexisting: {len(res.coexisting)} branches{jumps}" + (": " + "; ".join(parts) if parts else ""))
    if res.coexisting_note and res.coexisting:
        print(res.coexisting_note)


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
    res : LinkSweepResult
        The sweep.
    period : int or str
        The parsed ``--period``.
    model : LinkModel, optional
        The link model (built from ``system`` when None).

    Returns
    -------
    LinkSweepResult

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
        torus_progress=ProgressBar("tori"),
        **periods,
    )


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


def _revolution(system) -> int:
    """N of one gear pair, nothing else nonlinear, whose errors repeat every N mesh periods
    (1 otherwise): ``--period`` counts its mesh periods and the spectra are drawn."""
    if len(system.gear_pairs) == 1 and not system.bearing_clearances and not system.unbalance:
        return system.gear_pairs[0].error_period
    return 1


def _check_period_options(args, period: int) -> None:
    """``--period N`` (N >= 3) searches and follows: no continuation, stability needed."""
    if args.continuation:
        raise ModelError(
            "--period", f"period-{period} orbits are searched and followed, not traced by --continuation"
        )
    if args.no_stability:
        raise ModelError(
            "--period", f"period-{period} orbits need their Floquet stability: drop --no-stability"
        )
    if args.search_periods is not None:
        raise ModelError("--search-periods", f"--period {period} searches period {period} only")


def _period_command(args, system, view, omegas, unit, quantity, out, png, search) -> int:
    """``--period N``, N >= 3: the period-N orbits searched for, followed over the grid and
    written as the sweep (:func:`nlgrd.nonlinear.models.model_views.period_branches`); exit 1
    when none is found."""
    import numpy as np

    from nlgrd.nonlinear.models.model_views import period_branches
    from nlgrd.nonlinear.tracing.harmonic_convergence import OUTPUT_RTOL

    at, (nu,) = search
    H = args.harmonics or PERIOD_HARMONICS
    where = ", ".join(f"{v:g}" for v in at) + f" {unit.name}"
    res, orbits, branches = period_branches(view, omegas, at, nu, H, args.direction, unit, print)
    if res is None:
        print(
            f"nlgrd: error: no period-{nu} orbit found at {where} (H = {H}); nothing written: try other "
            "--search-at speeds",
            file=sys.stderr,
        )
        return 1
    _write_sweep(
        view, res, quantity, out, png, found=(orbits, branches), unit=unit, title=_title(system, args)
    )
    m = view.points(res)
    ok = m.converged & ~m.no_stable
    print(
        f"period {nu}: {len(m)} points ({args.direction}), {view.words()}H = {H}, "
        f"a stable period-{nu} orbit at {int(ok.sum())}"
    )
    for label, mask in (
        (f"no stable period-{nu} orbit (unstable only; NaN outputs)", m.converged & m.no_stable),
        (f"no period-{nu} branch reaches (not converged)", ~m.converged),
    ):
        if np.any(mask):
            print(f"{label} at {unit.name}: " + ", ".join(unit(w) for w in np.atleast_1d(m.omega[mask])))
    worst = np.nanmax(m.harmonic_error[ok], initial=0.0)
    print(
        f"estimated harmonic error at most {worst:.2g} (against H = {m.H_check})"
        + (f": above {OUTPUT_RTOL:g}, raise --harmonics" if worst > OUTPUT_RTOL else "")
    )
    print(f"wrote {out}, {png}, {_beside(out, 'orbits')} and {_beside(out, 'branches')}")
    return 0


def _beside(out, name: str):
    return out.with_name(f"{out.stem}_{name}.csv")


def _write_sweep(
    view, res, quantity, out, png, extra=None, found=None, unit=None, title=None, more=None
) -> None:
    """The sweep's CSV (the range's column as typed, ``more`` columns appended), its figure,
    and the orbit tables."""
    frame = view.table(res)
    for name, values in (more or {}).items():
        frame[name] = values
    if unit.grid is not None:
        snap_to_grid(frame, unit.column, unit.grid)
    for table in found if found is not None and unit.grid is not None else ():
        snap_to_grid(table, unit.column, unit.grid)
    figure = view.figure(
        res, frame, quantity, unit.column, unit.axis, title, None if found is None else found[1]
    )
    with Outputs() as files:
        files.csv(frame, out)
        if getattr(res, "coexisting", None) is not None:
            files.csv(res.bifurcations(), _beside(out, "bifurcations"))
        if found is not None:
            files.csv(floor_rounding(written_frame(found[0])), _beside(out, "orbits"))
            files.csv(found[1], _beside(out, "branches"))
        files.figure(figure, png)
        if extra is not None:
            files.figure(*extra)
        files.commit()


def _sidebands(model, res) -> dict:
    """``<mesh>.sideband_max [um]``: the largest DTE line between the mesh harmonics
    (:func:`~nlgrd.nonlinear.models.shaft_orders.sideband_amplitudes`), NaN where the table
    has no values."""
    import numpy as np

    from nlgrd.nonlinear.links.contract import GearMeshLink
    from nlgrd.nonlinear.models.shaft_orders import sideband_amplitudes

    mesh = next(lk for lk in model.links if isinstance(lk, GearMeshLink))
    r = res.result
    a = sideband_amplitudes(model, r, mesh.name, mesh.order)
    usable = np.isfinite(res.links[f"{mesh.name}.dte_rms [m]"].to_numpy(float))
    return {f"{mesh.name}.sideband_max [um]": np.where(usable, 1e6 * a, np.nan)}


def _spectra(model, res, quantity: str, unit, out):
    """The DTE and bearing-force spectra of the stable point with the largest RMS DTE of
    the mesh (:func:`~nlgrd.nonlinear.models.shaft_orders.link_spectra`): (figure, file),
    or None when no point is stable and periodic."""
    import numpy as np

    from nlgrd.nonlinear.links.contract import GearMeshLink
    from nlgrd.nonlinear.models.shaft_orders import link_spectra
    from nlgrd.plotting.sweep_figures import plot_spectra

    mesh = next(lk for lk in model.links if isinstance(lk, GearMeshLink))
    r = res.result
    rms = res.links[f"{mesh.name}.dte_rms [m]"].to_numpy(float)
    ok = np.asarray(r.converged, dtype=bool) & ~np.asarray(r.no_stable, dtype=bool) & np.isfinite(rms)
    if not ok.any():
        return None
    i = int(np.argmax(np.where(ok, rms, -np.inf)))
    fr, dte, force, names = link_spectra(model, r, i, mesh.name)
    title = f"spectra at {unit(r.omega[i])} {unit.name} (the largest RMS DTE)"
    bearing = (fr, np.zeros_like(fr), "no bearing")
    if force.shape[1]:
        j = int(np.argmax(force.max(axis=0)))
        bearing = (fr, force[:, j], names[j])
    fig = plot_spectra((fr, dte), bearing, float(r.omega[i]) * mesh.order, title)[0].figure
    return fig, out.with_name(out.stem + "_spectrum.png")


def _summary(args, view, res, unit, out, png, orbits: bool = False) -> int:
    """Print what the sweep found, point by point in the range's unit; 1 when no point converged."""
    import numpy as np

    from nlgrd.cli.orbits import none_of
    from nlgrd.nonlinear.tracing.auto_period import transitions

    m = view.points(res)
    bad = np.atleast_1d(m.omega[~m.converged])
    timed = m.time_answered
    kinds = np.asarray(m.time_kind, dtype=object)
    solved = timed & (kinds == QUASI_PERIODIC)
    lost = int(np.sum(np.asarray(m.no_stable, dtype=bool))) - int(np.sum(timed))
    print(
        f"sweep: {len(m)} points ({args.direction}), {view.words()}{harmonics_line(m)}, "
        f"{len(bad)} not converged, {lost} without a stable periodic response, {int(np.sum(solved))} "
        f"answered by the torus harmonic balance, {int(np.sum(timed & ~solved))} answered in the time domain"
    )
    wrote = f"wrote {out} and {png}" + (
        f", {_beside(out, 'orbits')} and {_beside(out, 'branches')}" if orbits else ""
    )
    if getattr(res, "coexisting", None) is not None:
        wrote += f"; the coexisting branches' bifurcations {_beside(out, 'bifurcations')}"
    if len(bad):
        print(
            f"not converged (NaN in the CSV, flagged converged = False) at {unit.name}: "
            + ", ".join(unit(w) for w in bad)
        )
    if len(bad) == len(m):
        print(wrote)
        print(f"nlgrd: error: no point of the sweep converged{none_of(args.period)}", file=sys.stderr)
        return 1
    torus = np.isfinite(m.secondary_frequency) & ~timed
    lost = np.atleast_1d(m.omega[m.no_stable & ~torus & ~timed])
    if len(lost):
        print(
            f"no stable periodic response (response column; NaN outputs) at {unit.name}: "
            + ", ".join(unit(w) for w in lost)
        )
    if np.any(torus):
        print(
            f"quasi-periodic (a complex pair of multipliers left the unit circle; NaN outputs) at "
            f"{unit.name} (secondary frequency Hz): "
            + ", ".join(
                f"{unit(w)} ({f / (2 * np.pi):.0f})"
                for w, f in zip(m.omega[torus], m.secondary_frequency[torus], strict=True)
            )
        )
    if np.any(solved):
        print(
            f"quasi-periodic, answered by the torus harmonic balance (values; its stability not computed) at "
            f"{unit.name} (secondary frequency Hz): "
            + ", ".join(
                f"{unit(w)} ({f / (2 * np.pi):.0f})"
                for w, f in zip(m.omega[solved], m.secondary_frequency[solved], strict=True)
            )
        )
    for kind in ("time domain", "chaotic"):
        at = timed & (kinds == kind)
        if np.any(at):
            print(
                f"{kind} (no stable periodic orbit; integrated in time, values ± their uncertainty) at "
                f"{unit.name}: " + ", ".join(unit(w) for w in m.omega[at])
            )
    two = np.atleast_1d(m.omega[(m.period == 2) & m.converged & ~m.no_stable])
    if len(two):
        print(f"period 2 (period doubled) at {unit.name}: " + ", ".join(unit(w) for w in two))
    jumps = res.jumps()
    for j in jumps:
        print(f"jump ({j.direction}): {unit(j.omega_from)} -> {unit(j.omega_to)} {unit.name}")
    torus_dirs = set(np.asarray(m.direction)[np.isfinite(m.secondary_frequency)].astype(str))
    if any(j.direction in torus_dirs for j in jumps):
        print(
            "note: this sweep has quasi-periodic points, so where it leaves a branch depends on the "
            "grid: harmonic balance cannot tell whether the motion stays near an unstable branch "
            "there. A slow run-down in the time domain decides (nlgrd.timedomain.run_down; Kubo's "
            "case in docs/verification.md, 'Kubo's main down jump')"
        )
    for t in transitions(m):
        print(
            f"{t.kind} ({t.direction}): {unit(t.omega_from)} -> {unit(t.omega_to)} {unit.name}, "
            f"{t.response_from} -> {t.response_to}"
        )
    print(wrote)
    return 0


def _continuation(args, system, view, unit, omegas, count, quantity, out, png) -> int:
    """``--continuation``: trace the curve up from START, down from STOP, or both; check the coverage.

    ``view.continuation`` gives the curve (a ContinuationResult whose metrics hold
    ``quantity``) and its table. COUNT, when given, sets the largest step so
    that successive points lie at most about (STOP - START) / (COUNT - 1) apart in
    frequency (never coarser than the default).
    """
    import inspect

    import pandas as pd

    from nlgrd.nonlinear.tracing.continuation import continuation
    from nlgrd.plotting.nonlinear import plot_continuation

    lo, hi = float(omegas.min()), float(omegas.max())
    tol = 1e-9 * (hi - lo)  # the continuation's own range tolerance
    defaults = {k: p.default for k, p in inspect.signature(continuation).parameters.items()}
    names = ["up", "down"] if args.direction == "both" else [args.direction]
    traces, frames = {}, []
    for name in names:
        begin, end = (lo, hi) if name == "up" else (hi, lo)
        kwargs = {}
        if count is not None:
            # the tracer scales ω by its start value: a scaled step ds moves ω by at most ds * begin
            ds_max = min(defaults["ds_max"], (hi - lo) / (count - 1) / begin)
            kwargs = {
                "ds": min(defaults["ds"], ds_max),
                "ds_max": ds_max,
                "max_steps": max(defaults["max_steps"], 10 * count),
            }
        kwargs["progress"] = ProgressBar(f"continuation {name}")
        res, frame = view.continuation(begin, end, args.harmonics, quantity, not args.no_stability, **kwargs)
        traces[name] = res
        frame.insert(1, "trace", name)
        frame.insert(2, f"{unit.speed.replace(' ', '_')} [rpm]", res.omega / unit.per_speed * 30 / math.pi)
        frames.append(frame)
        w = res.omega
        reached = w.max() >= hi - tol if name == "up" else w.min() <= lo + tol
        if reached:
            how = f"reached {unit(end)} {unit.name}"
        elif (w[-1] - begin) * (1 if end > begin else -1) < 0:  # left the range behind its start
            how = f"turned back and left the range at {unit(w[-1])}, short of {unit(end)} {unit.name}"
        else:
            how = f"stopped at {unit(w[-1])} {unit.name} (the step size collapsed or the step limit was met)"
        turns = ", ".join(unit(t) for t in res.turning_omegas)
        print(
            f"continuation {name} from {unit(begin)} {unit.name}: {len(w)} points spanning "
            f"{unit(w.min())}-{unit(w.max())} {unit.name}, "
            + (f"turning points at {turns} {unit.name}" if turns else "no turning point")
            + f"; {how}; {harmonics_line(res.curve)}"
        )
    with Outputs() as files:
        files.csv(pd.concat(frames, ignore_index=True), out)
        ax = None
        for name, res in traces.items():
            ax = plot_continuation(
                res,
                quantity=written_name(quantity),
                ax=ax,
                color="k" if name == "up" else "C3",
                label=name,
                xaxis=unit.axis,
                title=_title(system, args),
            )
        ax.figure.tight_layout()
        files.figure(ax.figure, png)
        files.commit()
    print(f"wrote {out} and {png}")
    top = min(hi, traces["up"].omega.max()) if "up" in traces else lo
    bottom = max(lo, traces["down"].omega.min()) if "down" in traces else hi
    requested = f"{unit(lo, 0)}-{unit(hi, 0)} {unit.name}"
    if top >= bottom - tol:
        print(f"continuation: covered the requested {requested}")
        return 0
    parts = [f"{unit(lo, 0)}-{unit(top, 0)}"] if "up" in traces else []
    parts += [f"{unit(bottom, 0)}-{unit(hi, 0)}"] if "down" in traces else []
    hint = "" if args.direction == "both" else "; try --direction both"
    print(
        f"nlgrd: error: continuation INCOMPLETE: covered {' and '.join(parts)} {unit.name} of the "
        f"requested {requested}, nothing between {unit(top, 0)} and {unit(bottom, 0)} {unit.name} "
        f"(the CSV and the plot hold the part computed){hint}",
        file=sys.stderr,
    )
    return 1
