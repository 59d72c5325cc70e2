"""``nlgrd modes``, ``nlgrd campbell`` and ``nlgrd lste``: the linear analyses of a model file
(:mod:`nlgrd.rotor.modal`, :mod:`nlgrd.gear`), their tables printed and their files written by
:mod:`nlgrd.io.analysis_files`."""

from __future__ import annotations

from pathlib import Path

from nlgrd.errors import ModelError
from nlgrd.io.analysis_files import write_campbell, write_lste, write_modes
from nlgrd.io.command_line import (
    ProgressBar,
    check_at_least,
    output_folder,
    parse_orders,
    parse_range,
    parse_speed,
)

__all__ = ["cmd_campbell", "cmd_lste", "cmd_modes"]


# ---------------------------------------------------------------------------- commands


def _stem(model: str) -> str:
    return Path(model).stem


# ---------------------------------------------------------------------------- commands


def cmd_modes(args) -> int:
    """Modal analysis: table on screen, CSV and mode-shape PNG.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options of ``nlgrd modes`` (:func:`build_parser`).

    Returns
    -------
    int
        The exit status: 0 when done.

    Raises
    ------
    ModelError
        For a bad option or model (:func:`main` prints it and exits with status 2).
    """
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
    csv, png = write_modes(res, folder, _stem(args.model))
    print(f"wrote {csv} and {png}")
    return 0


def cmd_campbell(args) -> int:
    """Campbell diagram: CSV of frequencies, CSV of critical speeds, PNG.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options of ``nlgrd campbell`` (:func:`build_parser`).

    Returns
    -------
    int
        The exit status: 0 when done.

    Raises
    ------
    ModelError
        For a bad option or model (:func:`main` prints it and exits with status 2).
    """
    import numpy as np

    from nlgrd.io.model_file import load_model
    from nlgrd.rotor.modal import campbell

    rpm = parse_range(args.rpm, "--rpm")
    orders = parse_orders(args.orders)
    check_at_least("--n-modes", args.n_modes, 1)
    folder = output_folder("--out", args.out)
    system = load_model(args.model)
    bar = ProgressBar("campbell")  # tqdm on a terminal
    res = campbell(system, rpm * np.pi / 30, n_modes=args.n_modes, orders=orders, progress=bar)
    csv, crit, png = write_campbell(res, folder, _stem(args.model))
    print(res.critical_frame().to_string(index=False, float_format=lambda v: f"{v:.5g}"))
    print(f"wrote {csv}, {crit} and {png}")
    return 0


def cmd_lste(args) -> int:
    """Loaded static transmission error of a gear pair: CSV and PNG; the k_h of the dynamics.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options of ``nlgrd lste`` (:func:`build_parser`).

    Returns
    -------
    int
        The exit status: 0 when done.

    Raises
    ------
    ModelError
        For a bad option or model (:func:`main` prints it and exits with status 2).
    """
    from nlgrd.io.model_file import load_model

    folder = output_folder("--out", args.out)
    system = load_model(args.model)
    if not system.gear_pairs:
        raise ModelError("gear_pairs", "the model has no gear pair", args.model)
    if not 0 <= args.pair < len(system.gear_pairs):
        raise ModelError("--pair", f"gear pair {args.pair} out of range 0..{len(system.gear_pairs) - 1}")
    mesh = system.gear_pairs[args.pair]
    k_h = mesh.stiffness()
    files = write_lste(mesh, folder, _stem(args.model))
    summary, computed = files.summary, files.computed
    print(
        f"gear pair {args.pair}: W_0 = {mesh.static_load:.1f} N, "
        f"contact ratio {mesh.geometry.contact_ratio:.4f}, {summary}"
    )
    if mesh.mesh_stiffness is not None:
        note = f"; the geometry gives {computed:.4g} N/m" if computed is not None else ""
        print(f"the dynamics use k_h = {k_h:.4g} N/m (the model's mesh_stiffness{note})")
    else:
        print(f"the dynamics use k_h = {k_h:.4g} N/m (computed from the geometry at W_0)")
    if mesh.stiffness_file:
        shape = mesh.stiffness_shape()
        lo, hi = shape.extremes
        mean = "" if shape.mean is None else f"; the file's mean {shape.mean:.4g} N/m is not used"
        print(
            f"and k(θ) = k_h ρ(θ), ρ {lo:.3f} to {hi:.3f} from the stiffness_file {mesh.stiffness_file}{mean}"
        )
    print(f"wrote {files.csv} and {files.png}")
    return 0
