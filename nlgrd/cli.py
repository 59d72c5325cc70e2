"""The ``nlgrd`` command line.

Every sub-command reads a TOML model file (see :mod:`nlgrd.model_file`) and writes
CSV tables and PNG figures next to each other in ``--out`` (default: the current
directory). Bad input prints one line ``nlgrd: error: FILE: KEY: message`` and exits
with status 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from nlgrd.errors import ModelError

EPILOG = """\
examples:
  nlgrd modes data/models/two_shaft.toml
  nlgrd modes data/models/two_shaft.toml --rpm 3000 --n-modes 12 --out reports/two_shaft
  nlgrd campbell data/models/two_shaft.toml --rpm 0:10000:101 --orders 1,25
  nlgrd lste data/models/two_shaft.toml
  nlgrd sweep data/case_studies/kubo.toml --rpm 4000:16000:241 --out kubo.csv

Units: speeds in rpm on the command line, everything in the model file in SI
(m, kg, N, s, rad). Shafts, nodes and DOFs are numbered from 0.
"""


def parse_range(text: str, name: str = "--rpm") -> np.ndarray:
    """Parse ``START:STOP:COUNT`` (or a single value) into an array."""
    parts = text.split(":")
    try:
        if len(parts) == 1:
            return np.array([float(parts[0])])
        if len(parts) == 3:
            start, stop, count = float(parts[0]), float(parts[1]), int(parts[2])
            if count < 2:
                raise ValueError
            return np.linspace(start, stop, count)
    except ValueError:
        pass
    raise ModelError(name, f"expected START:STOP:COUNT (COUNT >= 2) or one number, got {text!r}")


def _out_path(args, model_path: str, suffix: str) -> Path:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    return out / f"{Path(model_path).stem}_{suffix}"


def _save_figure(fig, path: Path) -> None:
    tmp = path.with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=100)
    tmp.replace(path)


def _write_csv(frame, path: Path) -> None:
    tmp = path.with_suffix(".tmp.csv")
    frame.to_csv(tmp, index=False)
    tmp.replace(path)


def cmd_modes(args) -> int:
    """Modal analysis: table on screen, CSV and mode-shape PNG."""
    from nlgrd.modal import modal_analysis
    from nlgrd.model_file import load_model

    system = load_model(args.model)
    rpm = parse_range(args.rpm)[0]
    res = modal_analysis(system, speed=rpm * np.pi / 30, n_modes=args.n_modes, damped=not args.undamped)
    df = res.to_frame()
    print(
        f"{args.model}: {system.n_dofs} DOFs, speed {rpm:g} rpm, "
        f"{res.n_rigid_body} rigid-body mode(s) not listed"
    )
    cols = ["mode", "natural_frequency [Hz]", "damping_ratio [-]", "kind", "whirl"]
    print(df[cols].to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    csv = _out_path(args, args.model, "modes.csv")
    _write_csv(df, csv)
    png = _out_path(args, args.model, "modes.png")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = min(6, len(res.eigenvalues))
    fig, axes = plt.subplots((n + 1) // 2, 2, figsize=(11, 3 * ((n + 1) // 2)), squeeze=False)
    for i, ax in enumerate(axes.ravel()):
        if i < n:
            res.plot(i, ax=ax)
        else:
            ax.set_visible(False)
    fig.tight_layout()
    _save_figure(fig, png)
    print(f"wrote {csv} and {png}")
    return 0


def cmd_campbell(args) -> int:
    """Campbell diagram: CSV of frequencies, CSV of critical speeds, PNG."""
    from nlgrd.modal import campbell
    from nlgrd.model_file import load_model

    system = load_model(args.model)
    rpm = parse_range(args.rpm)
    try:
        orders = {f"{float(o):g}x": float(o) for o in args.orders.split(",")}
    except ValueError:
        raise ModelError("--orders", f"expected comma-separated numbers, got {args.orders!r}") from None

    def progress(i, n):
        if sys.stderr.isatty() or i == n:
            print(f"\rcampbell: {i}/{n} speeds", end="\n" if i == n else "", file=sys.stderr, flush=True)

    res = campbell(system, rpm * np.pi / 30, n_modes=args.n_modes, orders=orders, progress=progress)
    csv = _out_path(args, args.model, "campbell.csv")
    _write_csv(res.to_frame(), csv)
    crit = _out_path(args, args.model, "critical_speeds.csv")
    _write_csv(res.critical_frame(), crit)
    import matplotlib

    matplotlib.use("Agg")
    ax = res.plot()
    png = _out_path(args, args.model, "campbell.png")
    ax.figure.tight_layout()
    _save_figure(ax.figure, png)
    print(res.critical_frame().to_string(index=False, float_format=lambda v: f"{v:.5g}"))
    print(f"wrote {csv}, {crit} and {png}")
    return 0


def cmd_lste(args) -> int:
    """Loaded static transmission error of a gear pair: CSV and a three-panel PNG."""
    from nlgrd.model_file import load_model

    system = load_model(args.model)
    if not system.gear_pairs:
        raise ModelError("gear_pairs", f"{args.model} has no gear pair")
    if not 0 <= args.pair < len(system.gear_pairs):
        raise ModelError("--pair", f"gear pair {args.pair} out of range 0..{len(system.gear_pairs) - 1}")
    mesh = system.gear_pairs[args.pair]
    res = mesh.lste_result()
    csv = _out_path(args, args.model, "lste.csv")
    _write_csv(res.to_frame(), csv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(7, 9))
    res.plot(axes[0], kind="lste")
    res.plot(axes[1], kind="stiffness")
    res.plot(axes[2], kind="load_sharing")
    fig.tight_layout()
    png = _out_path(args, args.model, "lste.png")
    _save_figure(fig, png)
    print(
        f"gear pair {args.pair}: W_0 = {mesh.static_load:.1f} N, "
        f"contact ratio {mesh.geometry.contact_ratio:.4f}, "
        f"mean mesh stiffness {res.k_mean:.4g} N/m, LSTE peak-to-peak {res.fluctuation_pp * 1e6:.3f} um"
    )
    print(f"wrote {csv} and {png}")
    return 0


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


def cmd_sweep(args) -> int:
    """Nonlinear harmonic-balance sweep of the geared model: CSV, PNG, summary."""
    from nlgrd.geared_response import build_geared_model, geared_continuation, geared_sweep
    from nlgrd.model_file import load_model

    system = load_model(args.model)
    if (args.rpm is None) == (args.hz is None):
        raise ModelError(
            "--rpm", "give the range as --rpm START:STOP:COUNT (pinion speed) or --hz (mesh frequency)"
        )
    if args.harmonics < 1 or args.harmonics > 50:
        raise ModelError("--harmonics", f"must be between 1 and 50, got {args.harmonics}")
    if not system.gear_pairs:
        raise ModelError("gear_pairs", f"{args.model} has no gear pair: nothing nonlinear to sweep")
    probe = build_geared_model(system, 1.0, H=1) if args.rpm is not None else None
    if args.rpm is not None:
        omegas = probe.mesh_frequency(parse_range(args.rpm, "--rpm"))
    else:
        omegas = 2 * np.pi * parse_range(args.hz, "--hz")
    if np.any(omegas <= 0):
        raise ModelError("--rpm" if args.rpm else "--hz", "speeds and frequencies must be positive")
    model = build_geared_model(system, float(omegas.max()), H=args.harmonics)
    out = Path(args.out)
    png = Path(args.plot) if args.plot else out.with_suffix(".png")
    for p in (out, png):
        p.parent.mkdir(parents=True, exist_ok=True)
    import matplotlib

    matplotlib.use("Agg")
    if args.continuation:
        res = geared_continuation(
            system, float(omegas.min()), float(omegas.max()), H=args.harmonics, model=model
        )
        frame = res.to_frame()
        _write_csv(frame, out)
        ax = res.plot(quantity=args.quantity)
        n_bad = 0 if res.complete else 1
        print(
            f"continuation: {len(frame)} points, turning points at "
            + ", ".join(f"{w / 2 / np.pi:.1f} Hz" for w in res.turning_omegas)
            + ("" if res.complete else " (INCOMPLETE: the curve could not be followed to the end)")
        )
    else:
        res = geared_sweep(
            system,
            mesh_frequencies=omegas,
            H=args.harmonics,
            directions=args.direction,
            model=model,
            stability=not args.no_stability,
            progress=_Progress("sweep"),
        )
        frame = res.to_frame()
        _write_csv(frame, out)
        ax = res.plot(quantity=args.quantity)
        bad = res.failures()
        n_bad = len(bad)
        print(f"sweep: {len(frame)} points ({args.direction}), H = {args.harmonics}, {n_bad} not converged")
        if n_bad:
            print(
                "not converged (NaN in the CSV, flagged converged = False) at mesh frequency [Hz]: "
                + ", ".join(
                    f"{w / 2 / np.pi:.1f}" for w in np.atleast_1d(res.mesh.omega[~res.mesh.converged])
                )
            )
        for j in res.jumps():
            print(f"jump ({j.direction}): {j.omega_from / 2 / np.pi:.1f} -> {j.omega_to / 2 / np.pi:.1f} Hz")
    ax.figure.tight_layout()
    _save_figure(ax.figure, png)
    print(f"wrote {out} and {png}")
    return 0


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
    m.add_argument("--n-modes", type=int, default=12, help="number of modes to list (default 12)")
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
    c.add_argument("--n-modes", type=int, default=10, help="modes to follow (default 10)")
    c.add_argument(
        "--orders", default="1", help="excitation orders per pinion revolution, e.g. 1,25 (default 1)"
    )
    c.add_argument("--out", default=".", help="output folder (default: current directory)")
    c.set_defaults(func=cmd_campbell)
    ls = sub.add_parser(
        "lste",
        help="loaded static transmission error, mesh stiffness and load sharing of a gear pair",
        description="Computes, from the gear geometry, tip relief and the static torque, the "
        "loaded static transmission error over a mesh cycle, the mesh stiffness k(t) and the "
        "load carried by each tooth pair. Writes MODEL_lste.csv and MODEL_lste.png.",
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
        "show; or the whole response curve by arc-length continuation. Writes a CSV (mesh "
        "and bearing results per point, units in the column names) and a PNG.",
    )
    sw.add_argument("model", help="model file (TOML) with one [[gear_pairs]] entry")
    rng = sw.add_mutually_exclusive_group()
    rng.add_argument("--rpm", help="pinion speed range START:STOP:COUNT [rpm]")
    rng.add_argument("--hz", help="mesh frequency range START:STOP:COUNT [Hz]")
    sw.add_argument("--harmonics", type=int, default=5, help="number of harmonics H (default 5)")
    sw.add_argument("--direction", choices=["up", "down", "both"], default="both", help="sweep direction")
    sw.add_argument("--continuation", action="store_true", help="arc-length continuation instead of sweeps")
    sw.add_argument("--quantity", default="dslr", help="plotted quantity: dslr, dte_rms, ... (default dslr)")
    sw.add_argument("--no-stability", action="store_true", help="skip the Floquet stability of each point")
    sw.add_argument("--out", default="sweep.csv", help="CSV file (default sweep.csv)")
    sw.add_argument("--plot", default=None, help="PNG file (default: next to the CSV)")
    sw.set_defaults(func=cmd_sweep)
    return p


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit status (2 on bad input)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return args.func(args)
    except ModelError as err:
        print(f"nlgrd: error: {err}", file=sys.stderr)
        return 2
    except OSError as err:
        print(f"nlgrd: error: {err.filename or ''}: {err.strerror or err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
