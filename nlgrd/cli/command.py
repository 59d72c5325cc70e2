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
  continuation that did not cover the range; the part computed is written; ``sweep
  --period N`` that found no period-N orbit: nothing is written), 2 on bad
  input (one line ``nlgrd: error: FILE: KEY: message``), 130 on Ctrl-C (one line);
- any unexpected exception is one line ``nlgrd: error: TYPE: message``; with the
  environment variable ``NLGRD_DEBUG=1`` its traceback is printed first.

The option checks, the range parsing and the atomic output writer are in
:mod:`nlgrd.io.command_line`; this module has the parser and :func:`main`, which hands each
sub-command to its module: :mod:`nlgrd.cli.linear` (``modes``, ``campbell``, ``lste``),
:mod:`nlgrd.cli.sweep` (``sweep``) and :mod:`nlgrd.cli.study` (``study``, ``report``).
"""

from __future__ import annotations

import argparse
import os
import sys
import traceback
import warnings

from nlgrd.cli.linear import cmd_campbell, cmd_lste, cmd_modes
from nlgrd.cli.orbits import DEFAULT_PERIODS
from nlgrd.cli.study import add_parsers as add_study_parsers
from nlgrd.cli.sweep import cmd_sweep
from nlgrd.errors import ModelError
from nlgrd.io.command_line import MAX_POINTS, parse_range, parse_span

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


class _Parser(argparse.ArgumentParser):
    """An option the parser refuses is one line too (no usage block), exit status 2."""

    def error(self, message):
        self.exit(2, f"nlgrd: error: {_one_line(message)} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``nlgrd``.

    Returns
    -------
    argparse.ArgumentParser
        The parser, one sub-command each for ``modes``, ``campbell``, ``lste``, ``sweep``,
        ``study`` and ``report``;
        each sets ``func`` to its ``cmd_*`` function.
    """
    p = _Parser(
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
        "--rpm",
        default="0:10000:51",
        help="speed range START:STOP:COUNT [rpm], START < STOP (default 0:10000:51)",
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
    sw.add_argument(
        "model",
        help="model file (TOML); several [[gear_pairs]], [[bearing_clearances]] or [[unbalance]] make "
        "it a link sweep (base frequency of the common period, columns <link>.<quantity>)",
    )
    rng = sw.add_mutually_exclusive_group()
    rng.add_argument(
        "--rpm",
        help="pinion speed range START:STOP:COUNT [rpm], START < STOP (--direction sets up or down; a "
        "range written down, 5:1:10, is refused); the grid is START + i (STOP - START) / (COUNT - 1) "
        "written as given; pitch-line velocity at most 300 m/s; with --continuation START:STOP[:COUNT]",
    )
    rng.add_argument(
        "--hz",
        help="base frequency range START:STOP:COUNT [Hz], START < STOP: the mesh frequency of one mesh, "
        "the mesh frequency / N where its errors repeat every N mesh periods (teeth that differ, "
        "runout), the common period of several meshes or an unbalance; with --continuation "
        "START:STOP[:COUNT]",
    )
    sw.add_argument(
        "--harmonics",
        type=int,
        default=None,
        help="number of harmonics H of the base frequency (--hz; N H for H mesh harmonics where the "
        "errors repeat every N mesh periods), at least 1, at most what memory holds for the model "
        "(default: chosen so that RMS DTE and maximum mesh force, "
        "and a clearance's force and displacement, are within 0.5 %% of the converged answer; "
        "5 is the paper's choice)",
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
        default=None,
        help="plotted quantity: dte_mean, dte_rms, dte_p2p, force_max, force_min, dslr (default), "
        "contact_loss_fraction or back_contact; for a link sweep LINK.QUANTITY, e.g. mesh1.dslr or "
        "B1.force_max (default: the first mesh's dslr, or the first link's largest force)",
    )
    sw.add_argument(
        "--period",
        default="auto",
        metavar="{auto,1,2,...,6}",
        help="orbits of how many mesh periods: auto (default) gives the mesh-periodic response where it "
        "is stable and the period-doubled one where it has lost stability by period doubling; 1 the "
        "mesh-periodic orbits only; 2 the period-2 branches alone; N = 3 to 6 the period-N orbits "
        "(no sweep reaches them) searched for at the --search-at speeds (default 5 grid speeds "
        "evenly spread over the range), each followed over the grid (H mesh harmonics: --harmonics, "
        "default 9); exit status 1, nothing written, when none is found. The CSV has each point's "
        "period, its ω/ν content and, where a complex pair of Floquet multipliers left the unit "
        "circle (quasi-periodic), the secondary frequency. Gear errors repeating every N mesh "
        "periods: auto, or a multiple of N up to 6 (the CSV's period then counts base periods, "
        "N mesh periods each); the DTE and bearing-force spectra of the largest RMS DTE are drawn "
        "(<out>_spectrum.png)",
    )
    sw.add_argument(
        "--search-at",
        default=None,
        help="comma-separated speeds (the range's unit) at which to search, from many starts, for "
        "orbits the sweep does not reach (isolated branches, subharmonics); each stable one found is "
        "followed over the grid. Writes <out>_orbits.csv and <out>_branches.csv, drawn on the PNG",
    )
    sw.add_argument(
        "--search-periods",
        default=None,
        help=f"periods sought by --search-at, in mesh periods (default {DEFAULT_PERIODS}; at most 6)",
    )
    sw.add_argument(
        "--coexisting",
        action="store_true",
        help="also search beside the sweep's jumps (at most 4) for the mesh-periodic branches that "
        "coexist with its own and that no sweep visits, and follow them over the grid, stable or "
        "not (minutes): their rows are appended to the CSV (column branch: 'sweep', 'coexisting k'), "
        "drawn on the PNG, and their bifurcations written to <out>_bifurcations.csv, each confirmed "
        "on the exact flow or flagged unconfirmed",
    )
    sw.add_argument("--no-stability", action="store_true", help="skip the Floquet stability of each point")
    sw.add_argument(
        "--no-time-domain",
        action="store_true",
        help="with --period auto, leave the points without a stable periodic response unanswered "
        "(default: each is integrated in time from its unstable orbit; response 'time domain' or "
        "'chaotic', values with their sampling uncertainty)",
    )
    sw.add_argument(
        "--time-periods",
        type=int,
        default=4096,
        help=(
            "base periods integrated per time-domain point before the last doubling (default 4096;"
            " at least 80); a decision within noise of its threshold doubles it once"
        ),
    )
    sw.add_argument("--out", default="sweep.csv", help="CSV file (default sweep.csv)")
    sw.add_argument("--plot", default=None, help="PNG file (default: the CSV's name with .png)")
    sw.set_defaults(func=cmd_sweep)
    add_study_parsers(sub)
    return p


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"nlgrd: warning: {_one_line(message)}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit status (0 done, 1 failed, 2 bad input, 130 interrupted).

    Parameters
    ----------
    argv : list of str or None
        The command-line arguments after the program name; None for ``sys.argv[1:]``.

    Returns
    -------
    int
        The exit status: 0 done, 1 the computation failed or fell short, 2 bad input (or no
        sub-command: the help is printed), 130 interrupted (Ctrl-C).
    """
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
            model = getattr(args, "model", None)
            if err.file is None and model and err.key and not err.key.startswith("-"):
                err = err.within(file=model)  # raised by an analysis: the model is the culprit
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
