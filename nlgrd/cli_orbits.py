"""``nlgrd sweep --search-at``: orbits the sweep does not reach, searched for at chosen speeds
(:func:`nlgrd.nonlinear.orbit_search.search_orbits`) and followed over the sweep's grid.

Outputs beside the sweep's CSV: ``<out>_orbits.csv`` (every orbit found, one row each, with
whether the sweep has it) and ``<out>_branches.csv`` (the branch of each stable orbit the
sweep does not have, followed up and down over the grid), drawn on the sweep's figure.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from nlgrd.errors import ModelError

#: Periods searched by default [mesh periods].
DEFAULT_PERIODS = "1,2,3"
#: Longest period searched [mesh periods]: the period-ν model has ν H harmonics.
MAX_PERIOD = 6
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
    try:
        periods = tuple(int(t) for t in str(args.search_periods).split(","))
    except ValueError:
        raise ModelError(
            "--search-periods", f"comma-separated whole numbers, got {args.search_periods!r}"
        ) from None
    if any(not 1 <= p <= MAX_PERIOD for p in periods):
        raise ModelError("--search-periods", f"periods from 1 to {MAX_PERIOD}, got {args.search_periods!r}")
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
    from nlgrd.nonlinear.orbit_search import follow_orbit, geared_model_of, search_orbits

    H = int(np.max(res.mesh.H)) // int(res.mesh.base)
    model_of = geared_model_of(model)
    rows, frames = [], []
    for value in at:
        w = float(unit.omega(value))
        found = search_orbits(model_of, w, H, periods)
        here = np.nonzero(
            np.isclose(res.mesh.omega, w, rtol=1e-12) & res.mesh.converged & ~res.mesh.no_stable
        )[0]
        for o in found:
            on_sweep = o.metrics is not None and any(
                int(res.mesh.period[i]) == o.period
                and np.isclose(res.mesh.metrics["dte_rms"][i], o.metrics.dte_rms, rtol=1e-6)
                and np.isclose(res.mesh.metrics["force_max"][i], o.metrics.force_max, rtol=1e-6)
                for i in here
            )
            m = o.metrics
            rows.append(
                {
                    "search at": value,
                    "mesh_frequency [Hz]": w / (2 * np.pi),
                    "pinion_speed [rpm]": float(model.pinion_rpm(w)),
                    "period": o.period,
                    "stable": o.stable,
                    "floquet_max [-]": o.floquet_max,
                    "on the sweep": on_sweep,
                    "dte_rms [um]": np.nan if m is None else m.dte_rms * 1e6,
                    "force_max [N]": np.nan if m is None else m.force_max,
                    "dslr [-]": np.nan if m is None else m.dslr,
                    "amplitude [um]": o.amplitude * 1e6,
                    "start": o.start,
                }
            )
            state = "stable" if o.stable else f"unstable, max |mu| {o.floquet_max:.3g}"
            print(
                f"orbit at {unit(w)} {unit.name}: period {o.period}, {state}, "
                f"RMS DTE {rows[-1]['dte_rms [um]']:.4g} um" + ("" if not on_sweep else " (the sweep's)")
            )
            if o.stable and not on_sweep:
                branch = follow_orbit(model_of, o, omegas, H)
                f = branch.to_frame()
                f.insert(0, "branch", f"period {o.period} from {unit(w)} {unit.name}")
                f.insert(1, "pinion_speed [rpm]", model.pinion_rpm(branch.omega))
                frames.append(f)
                span = branch.omega[branch.converged]
                print(
                    f"  followed: period {o.period} from {unit(span.min())} to {unit(span.max())} "
                    f"{unit.name}, {int(branch.stable.sum())} stable points"
                )
    if not rows:
        print("orbit search: nothing converged at the speeds given")
    orbits = pd.DataFrame(rows, columns=list(ORBIT_COLUMNS))
    branches = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=["branch"])
    return orbits, branches


def draw_branches(ax, branches: pd.DataFrame, x: str, quantity: str) -> None:
    """The followed branches on the sweep's axes (one colour pair per branch).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The sweep's axes.
    branches : DataFrame
        From :func:`search_command`.
    x : str
        Abscissa column ("mesh_frequency [Hz]" or "pinion_speed [rpm]").
    quantity : str
        The plotted metric (its column is named "<quantity> [unit]").
    """
    from nlgrd.plotting.nonlinear import plot_sweep_frame

    column = next((c for c in branches.columns if c.split(" [")[0] == quantity), None)
    if column is None:
        return
    for k, (name, part) in enumerate(branches.groupby("branch", sort=False)):
        plot_sweep_frame(part, x, column, ax=ax, label=name, series=2 + k % 3)
