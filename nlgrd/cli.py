"""The ``nlgrd`` command line.

Every sub-command reads a TOML model file (see :mod:`nlgrd.io.model_file`) and writes
CSV tables and PNG figures next to each other in ``--out`` (default: the current
directory).

The command line never prints a traceback:

- the options are checked before any computation (ranges, counts, quantities, and that
  the output paths can be written), the model when it is read;
- outputs are written atomically and together, at the end: each goes to a temporary
  file in its own folder, which then replaces the output (``os.replace``), so Ctrl-C or
  a failure leaves the previous files or none, never a partial one;
- exit status 0 on success, 1 when the computation failed or fell short (e.g. a
  continuation that did not cover the range; the part computed is written), 2 on bad
  input (one line ``nlgrd: error: FILE: KEY: message``), 130 on Ctrl-C (one line);
- any unexpected exception is one line ``nlgrd: error: TYPE: message``; with the
  environment variable ``NLGRD_DEBUG=1`` its traceback is printed first.

The option checks, the range parsing and the atomic output writer are in
:mod:`nlgrd.io.command_line`; this module has the sub-commands, the parser and :func:`main`.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import traceback
import warnings
from pathlib import Path

from nlgrd.errors import ModelError
from nlgrd.io.command_line import (
    MAX_POINTS,
    Outputs,
    check_at_least,
    check_quantity,
    output_file,
    output_folder,
    parse_orders,
    parse_range,
    parse_span,
    parse_speed,
    pyplot,
)

__all__ = [
    "EPILOG",
    "MAX_POINTS",
    "build_parser",
    "cmd_campbell",
    "cmd_lste",
    "cmd_modes",
    "cmd_sweep",
    "main",
    "parse_range",
    "parse_span",
]

EPILOG = """\
examples:
  nlgrd modes data/models/two_shaft.toml
  nlgrd modes data/models/two_shaft.toml --rpm 3000 --n-modes 12 --out reports/two_shaft
  nlgrd campbell data/models/two_shaft.toml --rpm 0:10000:101 --orders 1,25
  nlgrd lste data/models/two_shaft.toml
  nlgrd sweep data/case_studies/kubo.toml --rpm 4000:16000:241 --out kubo.csv
  nlgrd sweep data/case_studies/kubo.toml --hz 3000:5000:101 --continuation --out curve.csv

Units: speeds in rpm on the command line, everything in the model file in SI
(m, kg, N, s, rad). Shafts, nodes and DOFs are numbered from 0.

Exit status: 0 done, 1 computation failed or incomplete, 2 bad input, 130 Ctrl-C.
NLGRD_DEBUG=1 prints the traceback of an unexpected error.
"""


def _stem(model: str) -> str:
    return Path(model).stem


# ---------------------------------------------------------------------------- commands


def cmd_modes(args) -> int:
    """Modal analysis: table on screen, CSV and mode-shape PNG."""
    import numpy as np

    from nlgrd.io.model_file import load_model
    from nlgrd.rotor.modal import modal_analysis

    rpm = parse_speed(args.rpm)
    check_at_least("--n-modes", args.n_modes, 1)
    folder = output_folder("--out", args.out)
    system = load_model(args.model)
    res = modal_analysis(system, speed=rpm * np.pi / 30, n_modes=args.n_modes, damped=not args.undamped)
    df = res.to_frame()
    print(
        f"{args.model}: {system.n_dofs} DOFs, speed {rpm:g} rpm, "
        f"{res.n_rigid_body} rigid-body mode(s) not listed"
    )
    cols = ["mode", "natural_frequency [Hz]", "damping_ratio [-]", "kind", "whirl"]
    print(df[cols].to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    csv, png = folder / f"{_stem(args.model)}_modes.csv", folder / f"{_stem(args.model)}_modes.png"
    plt = pyplot()
    with Outputs() as out:
        out.csv(df, csv)
        n = min(6, len(res.eigenvalues))
        fig, axes = plt.subplots((n + 1) // 2, 2, figsize=(11, 3 * ((n + 1) // 2)), squeeze=False)
        for i, ax in enumerate(axes.ravel()):
            if i < n:
                res.plot(i, ax=ax)
            else:
                ax.set_visible(False)
        fig.tight_layout()
        out.figure(fig, png)
        out.commit()
    print(f"wrote {csv} and {png}")
    return 0


def cmd_campbell(args) -> int:
    """Campbell diagram: CSV of frequencies, CSV of critical speeds, PNG."""
    import numpy as np

    from nlgrd.io.model_file import load_model
    from nlgrd.rotor.modal import campbell

    rpm = parse_range(args.rpm, "--rpm")
    orders = parse_orders(args.orders)
    check_at_least("--n-modes", args.n_modes, 1)
    folder = output_folder("--out", args.out)
    system = load_model(args.model)

    def progress(i, n):
        if sys.stderr.isatty() or i == n:
            print(f"\rcampbell: {i}/{n} speeds", end="\n" if i == n else "", file=sys.stderr, flush=True)

    res = campbell(system, rpm * np.pi / 30, n_modes=args.n_modes, orders=orders, progress=progress)
    stem = _stem(args.model)
    csv, crit, png = (folder / f"{stem}_{s}" for s in ("campbell.csv", "critical_speeds.csv", "campbell.png"))
    pyplot()
    with Outputs() as out:
        out.csv(res.to_frame(), csv)
        out.csv(res.critical_frame(), crit)
        ax = res.plot()
        ax.figure.tight_layout()
        out.figure(ax.figure, png)
        out.commit()
    print(res.critical_frame().to_string(index=False, float_format=lambda v: f"{v:.5g}"))
    print(f"wrote {csv}, {crit} and {png}")
    return 0


def cmd_lste(args) -> int:
    """Loaded static transmission error of a gear pair: CSV and PNG; the k_h of the dynamics."""
    from nlgrd.io.model_file import load_model

    folder = output_folder("--out", args.out)
    system = load_model(args.model)
    if not system.gear_pairs:
        raise ModelError("gear_pairs", "the model has no gear pair", args.model)
    if not 0 <= args.pair < len(system.gear_pairs):
        raise ModelError("--pair", f"gear pair {args.pair} out of range 0..{len(system.gear_pairs) - 1}")
    mesh = system.gear_pairs[args.pair]
    k_h = mesh.stiffness()
    stem = _stem(args.model)
    csv, png = folder / f"{stem}_lste.csv", folder / f"{stem}_lste.png"
    plt = pyplot()
    with Outputs() as out:
        if mesh.lste_file:
            summary, computed = _lste_from_file(mesh, out, csv, png, plt)
        else:
            res = mesh.lste_result()
            computed = res.k_mean
            out.csv(res.to_frame(), csv)
            fig, axes = plt.subplots(3, 1, figsize=(7, 9))
            res.plot(axes[0], kind="lste")
            res.plot(axes[1], kind="stiffness")
            res.plot(axes[2], kind="load_sharing")
            fig.tight_layout()
            out.figure(fig, png)
            summary = (
                f"LSTE computed from the geometry, peak-to-peak {res.fluctuation_pp * 1e6:.3f} um, "
                f"mean mesh stiffness {res.k_mean:.4g} N/m"
            )
        out.commit()
    print(
        f"gear pair {args.pair}: W_0 = {mesh.static_load:.1f} N, "
        f"contact ratio {mesh.geometry.contact_ratio:.4f}, {summary}"
    )
    if mesh.mesh_stiffness is not None:
        note = f"; the geometry gives {computed:.4g} N/m" if computed is not None else ""
        print(f"the dynamics use k_h = {k_h:.4g} N/m (the model's mesh_stiffness{note})")
    else:
        print(f"the dynamics use k_h = {k_h:.4g} N/m (computed from the geometry at W_0)")
    print(f"wrote {csv} and {png}")
    return 0


def _lste_from_file(mesh, out: Outputs, csv: Path, png: Path, plt) -> tuple[str, float | None]:
    """CSV and plot of the LSTE of the gear pair's ``lste_file`` (the one the dynamics use)."""
    import numpy as np
    import pandas as pd

    from nlgrd.gear.lste_file import read_excitation

    ex = read_excitation(mesh.lste_file, teeth_pinion=mesh.geometry.teeth_pinion)
    phase = np.arange(mesh.lste_points) / mesh.lste_points
    lste = np.asarray(ex.value(phase))
    out.csv(
        pd.DataFrame(
            {
                "phase [cycles]": phase,
                "pinion rotation [rad]": 2 * np.pi * phase / mesh.geometry.teeth_pinion,
                "lste [um]": lste * 1e6,
            }
        ),
        csv,
    )
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.plot(phase, lste * 1e6, "k-", label=f"lste_file {Path(mesh.lste_file).name} (used)")
    computed = None
    if mesh.static_load > 0:
        res = mesh.lste_result()
        computed = res.k_mean
        ax.plot(res.phase, res.lste * 1e6, "C0--", lw=1, label="computed from the geometry (not used)")
    ax.set_xlabel("mesh phase [cycles]")
    ax.set_ylabel("LSTE [um]")
    ax.legend(fontsize=8)
    fig.tight_layout()
    out.figure(fig, png)
    summary = (
        f"LSTE from the lste_file {mesh.lste_file} (the dynamics remove its mean), "
        f"peak-to-peak {ex.peak_to_peak * 1e6:.3f} um"
    )
    return summary, computed


class _Progress:
    """A one-line progress bar on stderr (a final line only when stderr is not a terminal)."""

    def __init__(self, label: str):
        self.label = label

    def __call__(self, i: int, n: int) -> None:
        if sys.stderr.isatty():
            bar = "#" * int(30 * i / n)
            print(
                f"\r{self.label} [{bar:<30}] {i}/{n}", end="" if i < n else "\n", file=sys.stderr, flush=True
            )
        elif i == n or i % max(1, n // 10) == 0:
            print(f"{self.label}: {i}/{n}", file=sys.stderr, flush=True)


def _harmonics_line(res) -> str:
    """'H = 13 (estimated error 0.12 % against H = 17)' or 'H = 5' when H was given."""
    if res.H_check is None:
        return f"H = {res.H}"
    e = [float(x) for x in res.harmonic_error if math.isfinite(x)]
    worst = f"{100 * max(e):.2g} %" if e else "n/a"
    return f"H = {res.H} (chosen; largest estimated error {worst} against H = {res.H_check})"


class _Unit:
    """Mesh frequencies [rad/s] to and from the unit the range was given in (rpm or Hz)."""

    def __init__(self, rpm: bool, mesh_per_pinion: float):
        self.name = "rpm" if rpm else "Hz"
        # mesh frequency [rad/s] per pinion speed [rad/s]: N_p |s_p|
        self.scale = mesh_per_pinion * math.pi / 30 if rpm else 2 * math.pi

    def omega(self, value):
        return value * self.scale

    def __call__(self, omega, digits: int = 1) -> str:
        return f"{omega / self.scale:.{digits}f}"


def cmd_sweep(args) -> int:
    """Nonlinear harmonic-balance sweep (or continuation) of the geared model: CSV, PNG, summary."""
    import numpy as np

    from nlgrd.io.model_file import load_model
    from nlgrd.nonlinear.geared import build_geared_model
    from nlgrd.nonlinear.harmonic_convergence import LADDER

    if (args.rpm is None) == (args.hz is None):
        raise ModelError(
            "--rpm", "give the range as --rpm START:STOP:COUNT (pinion speed) or --hz (mesh frequency)"
        )
    option, text = ("--rpm", args.rpm) if args.rpm is not None else ("--hz", args.hz)
    if args.harmonics is not None and not 1 <= args.harmonics <= 50:
        raise ModelError("--harmonics", f"must be between 1 and 50, got {args.harmonics}")
    quantity = check_quantity(args.quantity)
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
    system = load_model(args.model)
    if len(system.gear_pairs) != 1:
        raise ModelError(
            "gear_pairs", f"the sweep needs exactly one gear pair, got {len(system.gear_pairs)}", args.model
        )
    gp = system.gear_pairs[0]
    unit = _Unit(
        args.rpm is not None, gp.geometry.teeth_pinion * abs(system.shafts[gp.pinion_shaft].speed_ratio)
    )
    omegas = unit.omega(values)
    model = build_geared_model(system, float(omegas.max()), H=args.harmonics or LADDER[-1])
    pyplot()
    if args.continuation:
        return _continuation(args, system, model, unit, omegas, count, quantity, out, png)
    from nlgrd.nonlinear.geared import geared_sweep

    res = geared_sweep(
        system,
        mesh_frequencies=omegas,
        H=args.harmonics,
        directions=args.direction,
        model=model,
        stability=not args.no_stability,
        progress=_Progress("sweep"),
    )
    with Outputs() as files:
        files.csv(res.to_frame(), out)
        ax = res.plot(quantity=quantity)
        ax.figure.tight_layout()
        files.figure(ax.figure, png)
        files.commit()
    bad = np.atleast_1d(res.mesh.omega[~res.mesh.converged])
    print(
        f"sweep: {len(res.mesh)} points ({args.direction}), {_harmonics_line(res.mesh)}, "
        f"{len(bad)} not converged"
    )
    if len(bad):
        print(
            f"not converged (NaN in the CSV, flagged converged = False) at {unit.name}: "
            + ", ".join(unit(w) for w in bad)
        )
    lost = np.atleast_1d(res.mesh.omega[res.mesh.no_stable])
    if len(lost):
        print(
            f"no stable mesh-periodic response (response column; NaN outputs) at {unit.name}: "
            + ", ".join(unit(w) for w in lost)
        )
    for j in res.jumps():
        print(f"jump ({j.direction}): {unit(j.omega_from)} -> {unit(j.omega_to)} {unit.name}")
    print(f"wrote {out} and {png}")
    return 0


def _continuation(args, system, model, unit, omegas, count, quantity, out, png) -> int:
    """``--continuation``: trace the curve up from START, down from STOP, or both; check the coverage.

    COUNT, when given, sets the largest step so that successive points lie at most about
    (STOP - START) / (COUNT - 1) apart in frequency (never coarser than the default).
    """
    import inspect

    import pandas as pd

    from nlgrd.nonlinear.continuation import continuation
    from nlgrd.nonlinear.geared import geared_continuation
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
        res = geared_continuation(
            system, begin, end, H=args.harmonics, model=model, stability=not args.no_stability, **kwargs
        )
        traces[name] = res
        frame = res.to_frame()
        frame.insert(1, "trace", name)
        frame.insert(2, "pinion_speed [rpm]", model.pinion_rpm(res.omega))
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
            + f"; {how}; {_harmonics_line(res.curve)}"
        )
    with Outputs() as files:
        files.csv(pd.concat(frames, ignore_index=True), out)
        ax = None
        for name, res in traces.items():
            ax = plot_continuation(
                res, quantity=quantity, ax=ax, color="k" if name == "up" else "C3", label=name
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


# ---------------------------------------------------------------------------- parser, main


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``nlgrd``."""
    p = argparse.ArgumentParser(
        prog="nlgrd",
        description="Nonlinear dynamics of geared rotor systems (finite-element shafts, "
        "spur gear mesh with backlash, harmonic balance).",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    m = sub.add_parser(
        "modes",
        help="natural frequencies, damping, whirl and mode shapes of the linear system",
        description="Modal analysis at one speed. Prints a table of modes and writes "
        "MODEL_modes.csv and MODEL_modes.png (first six mode shapes).",
    )
    m.add_argument("model", help="model file (TOML)")
    m.add_argument("--rpm", default="0", help="reference (pinion) speed [rpm], default 0")
    m.add_argument("--n-modes", type=int, default=12, help="number of modes to list, >= 1 (default 12)")
    m.add_argument(
        "--undamped", action="store_true", help="real modes of K and M only (no damping, no gyroscopics)"
    )
    m.add_argument("--out", default=".", help="output folder (default: current directory)")
    m.set_defaults(func=cmd_modes)
    c = sub.add_parser(
        "campbell",
        help="Campbell diagram and critical speeds over a speed range",
        description="Damped natural frequencies against speed, with critical speeds where "
        "a mode crosses an excitation order. Writes MODEL_campbell.csv, "
        "MODEL_critical_speeds.csv and MODEL_campbell.png.",
    )
    c.add_argument("model", help="model file (TOML)")
    c.add_argument(
        "--rpm", default="0:10000:51", help="speed range START:STOP:COUNT [rpm] (default 0:10000:51)"
    )
    c.add_argument("--n-modes", type=int, default=10, help="modes to follow, >= 1 (default 10)")
    c.add_argument(
        "--orders", default="1", help="excitation orders per pinion revolution, e.g. 1,25 (default 1)"
    )
    c.add_argument("--out", default=".", help="output folder (default: current directory)")
    c.set_defaults(func=cmd_campbell)
    ls = sub.add_parser(
        "lste",
        help="loaded static transmission error, mesh stiffness and load sharing of a gear pair",
        description="The loaded static transmission error over a mesh cycle that the dynamics "
        "use: from the gear pair's lste_file when the model gives one, else computed from the "
        "gear geometry, tip relief and the static torque (with the mesh stiffness k(t) and the "
        "load carried by each tooth pair). States the mean mesh stiffness k_h of the dynamics. "
        "Writes MODEL_lste.csv and MODEL_lste.png.",
    )
    ls.add_argument("model", help="model file (TOML) with a [[gear_pairs]] entry")
    ls.add_argument("--pair", type=int, default=0, help="index of the gear pair (default 0)")
    ls.add_argument("--out", default=".", help="output folder (default: current directory)")
    ls.set_defaults(func=cmd_lste)
    sw = sub.add_parser(
        "sweep",
        help="nonlinear response (harmonic balance) over speed or mesh frequency, up and down",
        description="Periodic steady-state response of the geared model with backlash by "
        "multi-harmonic balance, swept up and/or down so that jumps and double solutions "
        "show; or the whole response curve by arc-length continuation, traced up from START, "
        "down from STOP, or both (--direction). A continuation that does not cover the range "
        "says how far it got and exits with status 1. Writes a CSV (mesh and bearing results "
        "per point, units in the column names) and a PNG.",
    )
    sw.add_argument("model", help="model file (TOML) with one [[gear_pairs]] entry")
    rng = sw.add_mutually_exclusive_group()
    rng.add_argument(
        "--rpm", help="pinion speed range START:STOP:COUNT [rpm]; with --continuation START:STOP[:COUNT]"
    )
    rng.add_argument(
        "--hz", help="mesh frequency range START:STOP:COUNT [Hz]; with --continuation START:STOP[:COUNT]"
    )
    sw.add_argument(
        "--harmonics",
        type=int,
        default=None,
        help="number of harmonics H, 1 to 50 (default: chosen so that RMS DTE and maximum mesh force "
        "are within 0.5 %% of the converged answer; 5 is the paper's choice)",
    )
    sw.add_argument(
        "--direction",
        choices=["up", "down", "both"],
        default="both",
        help="sweep up, down or both (default); with --continuation: trace from START up, "
        "from STOP down, or both",
    )
    sw.add_argument(
        "--continuation",
        action="store_true",
        help="arc-length continuation instead of sweeps; COUNT, if given, bounds the frequency "
        "step to about (STOP - START) / (COUNT - 1)",
    )
    sw.add_argument(
        "--quantity",
        default="dslr",
        help="plotted quantity: dte_mean, dte_rms, dte_p2p, force_max, force_min, dslr (default), "
        "contact_loss_fraction or back_contact",
    )
    sw.add_argument("--no-stability", action="store_true", help="skip the Floquet stability of each point")
    sw.add_argument("--out", default="sweep.csv", help="CSV file (default sweep.csv)")
    sw.add_argument("--plot", default=None, help="PNG file (default: the CSV's name with .png)")
    sw.set_defaults(func=cmd_sweep)
    return p


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"nlgrd: warning: {_one_line(message)}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit status (0 done, 1 failed, 2 bad input, 130 interrupted)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    debug = os.environ.get("NLGRD_DEBUG", "").strip() not in ("", "0")
    with warnings.catch_warnings():
        if not debug:
            warnings.showwarning = _show_warning
        try:
            return args.func(args)
        except KeyboardInterrupt:
            if debug:
                traceback.print_exc()
            print("nlgrd: interrupted", file=sys.stderr)
            return 130
        except ModelError as err:
            if debug:
                traceback.print_exc()
            if err.file is None and err.key and not err.key.startswith("-"):
                err = err.within(file=args.model)  # raised by an analysis: the model is the culprit
            print(f"nlgrd: error: {_one_line(err)}", file=sys.stderr)
            return 2
        except Exception as err:  # noqa: BLE001 - the command line never shows a traceback
            if debug:
                traceback.print_exc()
            if isinstance(err, OSError) and err.filename:
                print(f"nlgrd: error: {err.filename}: {err.strerror or err}", file=sys.stderr)
            else:
                print(f"nlgrd: error: {type(err).__name__}: {_one_line(err)}", file=sys.stderr)
            return 1


if __name__ == "__main__":
    raise SystemExit(main())
