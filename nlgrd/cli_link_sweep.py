"""``nlgrd sweep`` of a model with several gear meshes, bearing clearances or unbalance: a link sweep
(:func:`nlgrd.nonlinear.link_model.link_sweep`), every link's outputs in columns
``<link>.<quantity>``, each point's period, ω/2 content and bifurcations as on the one-mesh
path (``--period``), and a figure of one of them."""

from __future__ import annotations

import math
import sys

from nlgrd.errors import ModelError
from nlgrd.io.command_line import Outputs, harmonics_line
from nlgrd.nonlinear.link_model import needs_links

__all__ = ["link_quantity", "link_sweep_command", "needs_links"]


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
    from nlgrd.nonlinear.link_model import metric_names
    from nlgrd.nonlinear.links import GearMeshLink

    keys = {lk.name: metric_names(lk) for lk in model.links}
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


def link_sweep_command(args, system, values, out, png) -> int:
    """Run ``nlgrd sweep`` on a link model; write the CSV and PNG; print a summary.

    Parameters
    ----------
    args : argparse.Namespace
        The options of ``nlgrd sweep``.
    system : RotorSystem
        The model (several meshes, a bearing clearance or an unbalance, which
        :func:`~nlgrd.nonlinear.link_model.build_link_model` takes from it).
    values : ndarray
        The range: shaft speeds [rpm] (``--rpm``) or base frequencies [Hz] (``--hz``).
    out, png : Path
        The output files.

    Returns
    -------
    int
        0.
    """
    import numpy as np

    from nlgrd.cli_orbits import parse_period
    from nlgrd.io.command_line import ProgressBar, pyplot
    from nlgrd.nonlinear.link_model import build_link_model, link_sweep

    model = build_link_model(system)
    plan = model.receptance.plan
    if args.rpm is not None:
        omegas = np.asarray(values, dtype=float) * math.pi / 30 / plan.speed_per_base
    else:
        omegas = 2 * math.pi * np.asarray(values, dtype=float)
    column, label = link_quantity(args.quantity, model)
    res = link_sweep(
        model,
        omegas,
        H=args.harmonics,
        directions=args.direction,
        stability=not args.no_stability,
        period=parse_period(args.period),
        progress=ProgressBar("sweep"),
    )
    H = res.result.H  # of the base frequency, whatever the period of the points (as the CSV's H)
    frame = res.to_frame()
    frame.insert(1, "shaft_speed [rpm]", frame["base_frequency [Hz]"] * plan.speed_per_base * 60)
    x_col = "shaft_speed [rpm]" if args.rpm is not None else "base_frequency [Hz]"
    plt = pyplot()
    from nlgrd.plotting.common import axis_label, place_legend

    fig, ax = plt.subplots(figsize=(7, 4))
    for direction, part in frame.groupby("direction", sort=False):
        ax.plot(part[x_col], part[column], ".-", label=f"sweep {direction}")
    ax.set_xlabel(axis_label(x_col))
    ax.set_ylabel(axis_label(column))
    ax.set_title(f"{(system.name or 'model')[:60]}\nbase frequency: {plan.name}, H = {H}", fontsize=9)
    place_legend(ax)
    fig.tight_layout()
    with Outputs() as files:
        files.csv(frame, out)
        files.figure(fig, png)
        files.commit()
    r = res.result
    bad = int(np.sum(~r.converged))
    lost = int(np.sum(np.asarray(r.no_stable, dtype=bool)))
    print(
        f"sweep: {len(r)} points ({args.direction}), links {', '.join(lk.name for lk in model.links)}, "
        f"base frequency = {plan.name} ({1 / plan.speed_per_base:.6g} x the shaft speed), "
        f"{harmonics_line(r)}, "
        f"{bad} not converged, {lost} without a stable periodic response"
    )
    _periods(r, unit=(60 * plan.speed_per_base, "rpm") if args.rpm is not None else (1.0, "Hz"))
    print(f"wrote {out} and {png}")
    if bad == len(r):
        print("nlgrd: error: no point of the sweep converged", file=sys.stderr)
        return 1
    return 0


def _periods(r, unit: tuple[float, str]) -> None:
    """Print the period-2 points, the quasi-periodic ones and the bifurcations along each
    sweep (:func:`nlgrd.nonlinear.auto_period.transitions`), in the range's unit."""
    import numpy as np

    from nlgrd.nonlinear.auto_period import transitions

    scale, name = unit

    def show(w) -> str:
        return f"{w / (2 * np.pi) * scale:.1f}"

    two = r.omega[(r.period == 2) & ~r.no_stable & r.converged]
    if two.size:
        print(f"period 2 (period doubled) at {name}: " + ", ".join(show(w) for w in two))
    torus = np.isfinite(r.secondary_frequency)
    if np.any(torus):
        print(
            f"quasi-periodic (a complex pair of multipliers left the unit circle; NaN outputs) at {name} "
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
